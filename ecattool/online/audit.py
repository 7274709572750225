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
from pathlib import Path
from typing import Any

from ecattool.errors import InputError, SdoAbort, TargetError
from ecattool.findings import Finding, Severity
from ecattool.online.dictionary import decode
from ecattool.online.live import LiveBus, describe_slave
from ecattool.online.objects import address


@dataclass
class Drift:
    """One difference between the project and a drive: ``kind`` is ``value``, ``identity``, ``abort``,
    ``unreadable`` or ``sw``."""

    drive: str
    position: int
    kind: str
    address: str
    expected: Any
    actual: Any
    message: str
    location: Any = None

    def to_json(self) -> dict[str, Any]:
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

    @property
    def ok(self) -> bool:
        return not self.drifts

    def to_json(self) -> dict[str, Any]:
        return {"project": self.project, "target": self.target, "ok": self.ok, "checked": self.checked,
                "drifts": [d.to_json() for d in self.drifts]}

    def findings(self) -> list[Finding]:
        return [d.finding() for d in self.drifts]


def _same(expected: bytes, actual: bytes) -> bool:
    """Equal values: the same bytes; a string or domain read back longer than written counts when the rest is
    padding (zero bytes)."""
    if actual == expected:
        return True
    n = len(expected)
    return len(actual) > n and actual[:n] == expected and not any(actual[n:])


def expected_values(rd: Any) -> dict[tuple[int, int, bool], Any]:
    """The startup commands of a drive that leave a value to read back: the last write of each address that the
    drive answers and can read back (one-shot writes such as a Technosoft reset, and 2065h data streams, are
    left out)."""
    last: dict[tuple[int, int, bool], Any] = {}
    for cmd in rd.startup.commands:
        if not cmd.verify or not cmd.expect_reply:
            continue
        last[(cmd.index, cmd.subindex, cmd.complete_access)] = cmd
    return last


def audit_drive(rd: Any, slave: Any, report: AuditReport, sw_checksums: bool = False) -> None:
    name = rd.drive.name
    device = rd.device
    dev_ident = device.identity
    try:
        ident = slave.identity()
    except TargetError as exc:
        report.drifts.append(Drift(name, rd.position, "unreadable", "identity", None, None, f"identity: {exc}"))
        ident = None
    if ident is not None:
        check = rd.drive.identity  # what the project checks: vendor, product, revision exact/at-least/ignore
        fields = [f for f, on in (("vendor_id", check.vendor), ("product_code", check.product),
                                  ("revision", check.revision != "ignore")) if on]
        for f in fields:
            want, got = getattr(dev_ident, f), getattr(ident, f)
            if f == "revision" and (want == 0 or (check.revision == "at-least" and got >= want)):
                continue
            if want != got:
                report.drifts.append(Drift(name, rd.position, "identity", f, f"0x{want:08X}", f"0x{got:08X}",
                                           f"{f} is 0x{got:08X} on the bus, the project's device has 0x{want:08X}"))
    # a slave without a CoE mailbox has no startup SDOs in a project that lints: audit sends it none
    for (index, sub, ca), cmd in expected_values(rd).items():
        where = address(index, sub) + (" (complete access)" if ca else "")
        report.checked += 1
        entry = device.dictionary.entry(index, sub)
        try:
            actual = slave.sdo_upload(index, sub, ca)
        except SdoAbort as exc:
            report.drifts.append(Drift(name, rd.position, "abort", where, cmd.data.hex(), f"0x{exc.code:08X}",
                                       f"{where}: reading it back was refused: {exc}", cmd.source))
            continue
        except TargetError as exc:
            report.drifts.append(Drift(name, rd.position, "unreadable", where, cmd.data.hex(), None,
                                       f"{where}: {describe_slave(slave)}: {exc}", cmd.source))
            continue
        if not _same(cmd.data, actual):
            want, got = decode(entry, cmd.data), decode(entry, actual)
            label = f" ({entry.name})" if entry is not None and entry.name else ""
            report.drifts.append(Drift(name, rd.position, "value", where, want, got,
                                       f"{where}{label} is {got!r} on the drive, the project sets {want!r}",
                                       cmd.source))
    if sw_checksums and rd.sw_image is not None:
        from ecattool.sw.apply import verify

        for c in verify(rd.sw_image, slave):
            report.checked += 1
            if not c.ok:
                report.drifts.append(Drift(name, rd.position, "sw", f"0x{c.start:04X}-0x{c.end:04X}",
                                           f"0x{c.expected:04X}", None if c.actual is None else f"0x{c.actual:04X}",
                                           f".sw block {c.describe()}", None))


def audit(project: str | Path, bus: LiveBus, sw_checksums: bool = False) -> AuditReport:
    """Compare every drive of the project at ``project`` with the slave at its position on ``bus``."""
    from ecattool.project.export import refuse_errors
    from ecattool.project.lint import lint_project

    result = lint_project(project)
    if result.loaded is None:
        first = result.findings[0]
        raise InputError(first.message, first.location)
    refuse_errors(result, "audit")
    report = AuditReport(str(project), bus.spec)
    for rd in sorted(result.drives, key=lambda r: r.position):
        audit_drive(rd, bus.slave(rd.position), report, sw_checksums)
    return report
