"""``audit``: does what is on the drives still match the project? Every object the project's startup list
would write is read back (the last value written to each address is the one that must be there), the SII
identity is compared with the project's device, and, only when asked, a Technosoft drive's ``.sw`` blocks are
checksummed by the drive.

The audit reads; it never writes. The one exception is opt-in: the ``.sw`` checksum of a block is computed by
the drive after the master writes the block's address range to 2069h (a request object, not a setting; it
changes nothing the drive keeps), so ``sw_checksums=True`` sends those writes and nothing else.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, TypedDict, cast

from ecattool.abort import al_status_text
from ecattool.errors import Location, SdoAbort, TargetError
from ecattool.esi.model import Identity
from ecattool.findings import Finding, Severity
from ecattool.od.model import EcState
from ecattool.online.dictionary import decode
from ecattool.online.found import RUNNING, Found
from ecattool.online.live import LiveBus, describe_slave
from ecattool.online.objects import address
from ecattool.project.machine import Machine
from ecattool.project.slave import Slave
from ecattool.startup.model import StartupCommand
from ecattool.target.base import LiveSlave, entry_size
from ecattool.target.remote import MasterGone

if TYPE_CHECKING:
    from ecattool.target.base import SlaveTarget


class DriftJson(TypedDict):
    """A drift as ``audit --json`` prints it."""

    drive: str
    position: int
    kind: str
    address: str
    expected: object
    actual: object
    message: str
    location: str | None


class ProcessDataRow(TypedDict):
    """A value the project sets on an object mapped into an RxPDO, and what SDO read there (not compared)."""

    drive: str
    position: int
    address: str
    project: object
    read: object


class AuditJson(TypedDict):
    """The report as ``audit --json`` prints it."""

    project: str
    target: str
    ok: bool
    checked: int
    drifts: list[DriftJson]
    process_data: list[ProcessDataRow]


@dataclass
class Drift:
    """One difference between the project and a drive: ``kind`` is ``value``, ``identity``, ``abort``,
    ``unreadable``, ``sw`` or ``state``."""

    drive: str
    position: int
    kind: str
    address: str
    expected: object
    actual: object
    message: str
    location: Location | None = None

    def to_json(self) -> DriftJson:
        return {"drive": self.drive, "position": self.position, "kind": self.kind, "address": self.address,
                "expected": self.expected, "actual": self.actual, "message": self.message,
                "location": None if self.location is None else str(self.location)}

    def finding(self) -> Finding:
        return Finding(f"audit.{self.kind}", Severity.ERROR, f"{self.drive} (slave {self.position}): {self.message}",
                       self.location)


@dataclass
class AuditReport:
    project: str
    target: str
    drifts: list[Drift] = field(default_factory=list)
    checked: int = 0
    #: values the project sets on objects mapped into the drive's RxPDOs: the master writes them every cycle, so
    #: what SDO reads there is process data, not a setting (listed, not drift)
    process_data: list[ProcessDataRow] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.drifts

    def to_json(self) -> AuditJson:
        return {"project": self.project, "target": self.target, "ok": self.ok, "checked": self.checked,
                "drifts": [d.to_json() for d in self.drifts], "process_data": self.process_data}

    def findings(self) -> list[Finding]:
        return [d.finding() for d in self.drifts]


def _same(expected: bytes, actual: bytes) -> bool:
    """Equal values: the same bytes; a string or domain read back longer than written counts when the rest is
    padding (zero bytes)."""
    if actual == expected:
        return True
    n = len(expected)
    return len(actual) > n and actual[:n] == expected and not any(actual[n:])


def expected_values(rd: Slave) -> dict[tuple[int, int, bool], StartupCommand]:
    """The startup commands of a drive that leave a value to read back: the last write of each address that the
    drive answers and can read back (one-shot writes such as a Technosoft reset, and 2065h data streams, are
    left out)."""
    last: dict[tuple[int, int, bool], StartupCommand] = {}
    for cmd in rd.startup.commands:
        if not cmd.verify or not cmd.expect_reply:
            continue
        last[(cmd.index, cmd.subindex, cmd.complete_access)] = cmd
    return last


def identity_differences(rd: Slave, ident: Identity) -> list[tuple[str, int, int]]:
    """``(field, project's, slave's)`` for each identity field the project checks (``identity:`` of the drive:
    vendor, product, revision exact/at-least/ignore) where the slave's ``ident`` is not the project device's."""
    assert rd.device is not None  # a machine whose devices did not resolve is refused (Machine.refuse_errors)
    dev_ident = rd.device.identity
    check = rd.drive.identity
    fields = [f for f, on in (("vendor_id", check.vendor), ("product_code", check.product),
                              ("revision", check.revision != "ignore")) if on]
    out = []
    for f in fields:
        want, got = getattr(dev_ident, f), getattr(ident, f)
        if f == "revision" and (want == 0 or (check.revision == "at-least" and got >= want)):
            continue
        if want != got:
            out.append((f, int(want), int(got)))
    return out


def rx_objects(rd: Slave) -> set[tuple[int, int]]:
    """The objects mapped into the drive's RxPDOs (the project's mapping, else the device's default)."""
    mapping = rd.mapping
    if mapping is None:
        return set()
    return {(e.index, e.subindex) for pdo in mapping.rx for e in pdo.entries if e.index}


#: the AL status code a drive shows in SAFE-OP once its master stopped sending process data (the sync manager
#: watchdog): what every drive of a machine shows after its master went away, not a drift of the drive
WATCHDOG_CODE = 0x001B


def state_drift(rd: Slave, found: Found) -> Drift | None:
    """A drive found (before the master reset the bus) in INIT or BOOT, or with the AL error indication: the project
    expects every drive at least in PRE-OP with its mailbox running and no error (commissioning takes it on). A
    drive in SAFE-OP with the watchdog's code 0x001B is one whose master stopped: not drift."""
    state = found.state
    if state is EcState.PREOP or state in RUNNING:
        if not found.error or (state is EcState.SAFEOP and found.al_status_code == WATCHDOG_CODE):
            return None
    code = found.al_status_code
    why = f", AL status code 0x{code:04X} ({al_status_text(code)})" if found.error or code else ""
    return Drift(rd.drive.name, rd.position, "state", "AL status", "PRE-OP, SAFE-OP or OP without error",
                 str(found), f"found in {state.value if state else 'no state'}{' with an error' if found.error else ''}"
                             f"{why} before the bus was opened", None)


def audit_drive(rd: Slave, slave: LiveSlave, report: AuditReport, sw_checksums: bool = False,
                found: Found | None = None) -> None:
    name = rd.drive.name
    device = rd.device
    assert device is not None  # a machine whose devices did not resolve is refused (Machine.refuse_errors)
    if found is not None and (drift := state_drift(rd, found)) is not None:
        report.drifts.append(drift)
    in_pdos = rx_objects(rd)
    try:
        ident = slave.identity()
    except MasterGone:
        raise  # nothing more can be read: one line, not a drift report of everything
    except TargetError as exc:
        report.drifts.append(Drift(name, rd.position, "unreadable", "identity", None, None, f"identity: {exc}"))
        ident = None
    if ident is not None:
        for f, want, got in identity_differences(rd, ident):
            report.drifts.append(Drift(name, rd.position, "identity", f, f"0x{want:08X}", f"0x{got:08X}",
                                       f"{f} is 0x{got:08X} on the bus, the project's device has 0x{want:08X}"))
    # a slave without a CoE mailbox has no startup SDOs in a project that lints: audit sends it none
    for (index, sub, ca), cmd in expected_values(rd).items():
        where = address(index, sub) + (" (complete access)" if ca else "")
        report.checked += 1
        entry = device.dictionary.entry(index, sub)
        try:
            actual = slave.sdo_upload(index, sub, ca, size=None if ca else max(len(cmd.data), entry_size(entry) or 0))
        except SdoAbort as exc:
            report.drifts.append(Drift(name, rd.position, "abort", where, cmd.data.hex(), f"0x{exc.code:08X}",
                                       f"{where}: reading it back was refused: {exc}", cmd.source))
            continue
        except MasterGone:
            raise
        except TargetError as exc:
            report.drifts.append(Drift(name, rd.position, "unreadable", where, cmd.data.hex(), None,
                                       f"{where}: {describe_slave(slave)}: {exc}", cmd.source))
            continue
        if not _same(cmd.data, actual) and (index, sub) in in_pdos:
            report.process_data.append({"drive": name, "position": rd.position, "address": where,
                                        "project": decode(entry, cmd.data), "read": decode(entry, actual)})
        elif not _same(cmd.data, actual):
            want, got = decode(entry, cmd.data), decode(entry, actual)
            label = f" ({entry.name})" if entry is not None and entry.name else ""
            report.drifts.append(Drift(name, rd.position, "value", where, want, got,
                                       f"{where}{label} is {got!r} on the drive, the project sets {want!r}",
                                       cmd.source))
    if sw_checksums and rd.sw_image is not None:
        from ecattool.sw.apply import verify

        # every master's live slave also changes state (the .sw checksum needs the mailbox), which the
        # LiveSlave protocol does not list yet: one slave protocol for every master is issue 36's item 3
        for c in verify(rd.sw_image, cast("SlaveTarget", slave)):
            report.checked += 1
            if not c.ok:
                report.drifts.append(Drift(name, rd.position, "sw", f"0x{c.start:04X}-0x{c.end:04X}",
                                           f"0x{c.expected:04X}", None if c.actual is None else f"0x{c.actual:04X}",
                                           f".sw block {c.describe()}", None))


def audit(machine: Machine, bus: LiveBus, sw_checksums: bool = False, allow_errors: bool = False) -> AuditReport:
    """Compare every drive of ``machine`` (built once by the caller: :func:`ecattool.project.machine.load_machine`)
    with the slave at its position on ``bus``. A machine with lint errors is refused unless ``allow_errors``
    (:meth:`~ecattool.project.machine.Machine.refuse_errors`, as ``commission`` does)."""
    machine.refuse_errors("audit", allow_errors=allow_errors)
    report = AuditReport(machine.path, bus.spec)
    for rd in machine.in_bus_order():
        audit_drive(rd, bus.slave(rd.position), report, sw_checksums, bus.found_at(rd.position))
    return report
