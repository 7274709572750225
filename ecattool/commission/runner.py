"""The commissioning run over a SlaveTarget (simulator or real master)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

from ecattool.commission import cia402
from ecattool.commission.trace import DriveTrace, StartupWrite
from ecattool.errors import EcatToolError, SdoAbort, StateChangeError, TargetError
from ecattool.findings import Finding, has_errors
from ecattool.od.model import EcState
from ecattool.project.machine import Machine, load_machine
from ecattool.project.resolve import TRANSITION_STATE
from ecattool.project.slave import Slave
from ecattool.startup.model import StartupCommand
from ecattool.target.base import SlaveTarget, Target, entry_size

if TYPE_CHECKING:
    from ecattool.od.model import Entry
    from ecattool.scaling.group import FactorObject

#: what an SDO step returns
_T = TypeVar("_T")

#: transitions whose commands are sent while the slave is in PRE-OP on the way up
_PREOP_TRANSITIONS = ("IP", "PS")
_SAFEOP_TRANSITIONS = ("SO",)


@dataclass(slots=True)
class Step:
    name: str
    ok: bool
    detail: str = ""
    abort_code: int | None = None
    al_status: int | None = None

    def to_json(self) -> dict[str, Any]:
        d: dict[str, Any] = {"name": self.name, "ok": self.ok, "detail": self.detail}
        if self.abort_code is not None:
            d["abort_code"] = f"0x{self.abort_code:08X}"
        if self.al_status is not None:
            d["al_status"] = f"0x{self.al_status:04X}"
        return d


@dataclass(slots=True)
class DriveReport:
    name: str
    position: int
    #: "axis" (CiA-402: enabled and moved) or "io" (states, mapping and process data proven)
    kind: str = "axis"
    ok: bool = False
    steps: list[Step] = field(default_factory=list)
    error: str | None = None
    final_state: str = ""
    #: what the run did, for the HTML report (not part of the JSON report)
    trace: DriveTrace = field(default_factory=DriveTrace)

    def to_json(self) -> dict[str, Any]:
        out = {"name": self.name, "position": self.position, "kind": self.kind, "ok": self.ok, "error": self.error,
               "final_state": self.final_state, "steps": [s.to_json() for s in self.steps]}
        if self.trace.figures is not None:
            out["move"] = self.trace.figures.to_json()
        return out


@dataclass(slots=True)
class CommissionReport:
    project: str
    target: str
    drives: list[DriveReport] = field(default_factory=list)
    #: the project's lint findings (file and line), for the HTML report (not part of the JSON report)
    findings: list[Finding] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return bool(self.drives) and all(d.ok for d in self.drives)

    def to_json(self) -> dict[str, Any]:
        return {"project": self.project, "target": self.target, "ok": self.ok,
                "drives": [d.to_json() for d in self.drives]}


class _Failed(Exception):
    def __init__(self, step: Step) -> None:
        super().__init__(step.detail)
        self.step = step


# --------------------------------------------------------------------------------------------
# process data access
# --------------------------------------------------------------------------------------------


#: outputs that start at 0 (or the startup value), never at what the drive holds: the controlword and the
#: set-points that move the axis as soon as it is enabled (vl 6042h, torque 6071h, velocity 60FFh, offsets
#: 60B1h/60B2h)
_NOT_SEEDED = frozenset({0x6040, 0x6042, 0x6071, 0x60FF, 0x60B1, 0x60B2})


class ProcessIo:
    """Objects in the process image by (index, sub); SDO for objects that are not mapped."""

    def __init__(self, slave: SlaveTarget, rd: Slave, trace: DriveTrace | None = None) -> None:
        from ecattool import pdo

        self.slave = slave
        self.rd = rd
        self.trace = trace
        assert rd.device is not None and rd.mapping is not None
        self.layout = pdo.layout(rd.device, rd.mapping)
        self.out_pos = {(v.index, v.subindex): v for v in self.layout.outputs.entries if not v.is_gap}
        self.in_pos = {(v.index, v.subindex): v for v in self.layout.inputs.entries if not v.is_gap}
        self.outputs = bytearray(self.layout.outputs.byte_size)
        self.inputs = bytes(self.layout.inputs.byte_size)
        # mapped outputs start from the values the startup list gives them (else the PDO would write 0
        # over them every cycle; lint warns about such objects with PDO021)
        for cmd in rd.startup:
            pos = self.out_pos.get((cmd.index, cmd.subindex))
            if pos is not None and not cmd.complete_access:
                _put_bits(self.outputs, pos.bit_offset, pos.bit_len, int.from_bytes(cmd.data, "little"))

    def seed_from_drive(self) -> None:
        """Start every mapped output except the controlword from the value the drive holds (read by SDO in
        SAFE-OP, after the startup list): the first cycles must not write 0 over a profile velocity or an
        acceleration that the drive's defaults or the startup list set (HDT maps 6081h/6083h/6084h in its
        default RxPDOs). The controlword starts at 0: the power stage stays off until the enable sequence;
        velocity and torque set-points (and their offsets) keep their startup value or 0, so that a value a
        drive still holds from an earlier run does not act the moment it is enabled in CSV/CST/PV/TQ (the
        target position is set to the actual position before enabling, see ``_hold_position``). An object
        the drive will not read out keeps its startup value (or 0)."""
        if not _speaks_coe(self.rd):
            return  # no mailbox: nothing to ask; the outputs start from the startup values or 0
        for (index, sub), pos in self.out_pos.items():
            if index in _NOT_SEEDED or pos.bit_len % 8:
                continue
            try:
                raw = self.slave.sdo_upload(index, sub, size=pos.bit_len // 8)
            except EcatToolError:
                continue
            if len(raw) * 8 == pos.bit_len:
                _put_bits(self.outputs, pos.bit_offset, pos.bit_len, int.from_bytes(raw, "little"))

    def _entry(self, index: int, sub: int) -> Entry:
        assert self.rd.device is not None
        e = self.rd.device.dictionary.entry(index, sub)
        if e is None:
            raise TargetError(f"0x{index:04X}:{sub:02X} is not in the device dictionary")
        return e

    def cycle(self) -> None:
        self.inputs = self.slave.exchange(bytes(self.outputs))
        if self.trace is not None:
            self.trace.on_cycle(self)

    def write(self, index: int, sub: int, value: int) -> None:
        if self.trace is not None:
            self.trace.written(index, sub, value)
        entry = self._entry(index, sub)
        raw = entry.encode(value)
        pos = self.out_pos.get((index, sub))
        if pos is None:
            self.slave.sdo_download(index, sub, raw)
            return
        _put_bits(self.outputs, pos.bit_offset, pos.bit_len, int.from_bytes(raw, "little"))

    def read(self, index: int, sub: int) -> int:
        entry = self._entry(index, sub)
        pos = self.in_pos.get((index, sub))
        if pos is None:
            value: int = entry.decode(self.slave.sdo_upload(index, sub, size=entry_size(entry)))
        else:
            raw = _get_bits(self.inputs, pos.bit_offset, pos.bit_len)
            value = entry.decode(raw.to_bytes(entry.byte_size, "little"))
        return value

    def has(self, index: int, sub: int = 0) -> bool:
        assert self.rd.device is not None
        return self.rd.device.dictionary.entry(index, sub) is not None


def _put_bits(buf: bytearray, bit_offset: int, bit_len: int, value: int) -> None:
    whole = int.from_bytes(buf, "little")
    mask = ((1 << bit_len) - 1) << bit_offset
    whole = (whole & ~mask) | ((value << bit_offset) & mask)
    buf[:] = whole.to_bytes(len(buf), "little")


def _get_bits(buf: bytes, bit_offset: int, bit_len: int) -> int:
    return (int.from_bytes(buf, "little") >> bit_offset) & ((1 << bit_len) - 1)


# --------------------------------------------------------------------------------------------
# one drive
# --------------------------------------------------------------------------------------------


def _sdo_step(name: str, fn: Callable[[], _T]) -> _T:
    try:
        return fn()
    except SdoAbort as exc:
        raise _Failed(Step(name, False, str(exc), abort_code=exc.code)) from None
    except StateChangeError as exc:
        raise _Failed(Step(name, False, str(exc), al_status=exc.al_status)) from None
    except EcatToolError as exc:
        raise _Failed(Step(name, False, exc.message)) from None


def _goto(slave: SlaveTarget, state: EcState, report: DriveReport) -> None:
    _sdo_step(f"state {state.value}", lambda: slave.request_state(state))
    report.steps.append(Step(f"state {state.value}", True, f"reached {state.value}"))
    report.trace.ec_state(state.value)


def _speaks_coe(rd: Slave) -> bool:
    """Whether the slave has a CoE mailbox: a slave without one (an EL2008, a fixed process image) is never sent
    an SDO; its identity is read from its EEPROM."""
    return rd.device is not None and rd.device.has_coe


def _check_identity(slave: SlaveTarget, rd: Slave, report: DriveReport) -> None:
    assert rd.device is not None
    want = rd.device.identity
    policy = rd.drive.identity
    try:
        if not _speaks_coe(rd):
            raise TargetError("no mailbox: the identity is the EEPROM's")
        vendor = int.from_bytes(slave.sdo_upload(0x1018, 1, size=4), "little")  # UDINTs (CiA-301)
        product = int.from_bytes(slave.sdo_upload(0x1018, 2, size=4), "little")
        revision = int.from_bytes(slave.sdo_upload(0x1018, 3, size=4), "little")
        how = "1018h"
    except EcatToolError:
        ident = slave.identity()
        vendor, product, revision, how = ident.vendor_id, ident.product_code, ident.revision, "EEPROM"
    problems = []
    if policy.vendor and vendor != want.vendor_id:
        problems.append(f"vendor 0x{vendor:08X} (expected 0x{want.vendor_id:08X})")
    if policy.product and product != want.product_code:
        problems.append(f"product 0x{product:08X} (expected 0x{want.product_code:08X})")
    if policy.revision == "exact" and revision != want.revision:
        problems.append(f"revision 0x{revision:08X} (expected exactly 0x{want.revision:08X})")
    if policy.revision == "at-least" and revision < want.revision:
        problems.append(f"revision 0x{revision:08X} (expected at least 0x{want.revision:08X})")
    if problems:
        raise _Failed(Step("identity", False, "wrong device: " + ", ".join(problems)))
    report.steps.append(Step("identity", True, f"vendor 0x{vendor:08X} product 0x{product:08X} "
                                                f"revision 0x{revision:08X} ({how})"))


def _send(slave: SlaveTarget, rd: Slave, cmd: StartupCommand, trace: DriveTrace) -> None:
    """Write one startup command and read it back, recording both in the trace."""
    sent = trace.startup_write(cmd)
    try:
        _send_verified(slave, rd, cmd, sent)
    except _Failed as exc:
        sent.ok, sent.result = False, exc.step.detail
        raise


def _send_verified(slave: SlaveTarget, rd: Slave, cmd: StartupCommand, sent: StartupWrite) -> None:
    assert rd.device is not None

    def write() -> None:
        slave.sdo_download(cmd.index, cmd.subindex, cmd.data, cmd.complete_access, cmd.expect_reply)

    _sdo_step(f"write {cmd.address}", write)
    if not (cmd.verify and cmd.expect_reply):
        return
    entry = rd.device.dictionary.entry(cmd.index, cmd.subindex)
    state = TRANSITION_STATE.get(cmd.transition, EcState.PREOP)
    if entry is None or not entry.access.readable(state) or cmd.complete_access:
        return
    bound = max(len(cmd.data), entry_size(entry) or 0)
    back = _sdo_step(f"read back {cmd.address}", lambda: slave.sdo_upload(cmd.index, cmd.subindex, size=bound))
    sent.read_back, sent.verified = bytes(back), bytes(back) == cmd.data
    if bytes(back) != cmd.data:
        raise _Failed(Step(f"verify {cmd.address}", False,
                           f"read back {bytes(back).hex()} after writing {cmd.data.hex()} ({cmd.comment})"))


def _startup(slave: SlaveTarget, rd: Slave, transitions: tuple[str, ...], report: DriveReport) -> None:
    cmds = [c for c in rd.startup if c.transition in transitions]
    for c in cmds:
        _send(slave, rd, c, report.trace)
    if cmds:
        report.steps.append(Step(f"startup {'/'.join(transitions)}", True, f"{len(cmds)} write(s) verified"))


def _sw(slave: SlaveTarget, rd: Slave, report: DriveReport) -> None:
    from ecattool import sw

    cfg = rd.drive.sw_config
    image = rd.sw_image
    if image is None or cfg is None:
        return
    diff = _sdo_step("sw verify", lambda: sw.verify(image, slave))
    report.trace.sw_checked(diff, cfg.file)
    bad = [b for b in diff if not b.ok]
    if not bad:
        report.steps.append(Step("sw verify", True, f"{len(diff)} block(s) match {cfg.file}"))
        return
    if not cfg.download:
        raise _Failed(Step("sw verify", False, f"{len(bad)} block(s) differ from {cfg.file}: "
                           + ", ".join(f"0x{b.start:04X}" for b in bad) + " (download disabled)"))
    result = _sdo_step("sw download", lambda: sw.download(image, slave, mode=cfg.mode))
    report.trace.sw_downloaded(result, result.after)
    if not result.ok:
        starts = dict.fromkeys([*(c.start for c in result.failed), *result.write_errors])
        why = [f"0x{k:04X}" + (f" ({result.write_errors[k]})" if k in result.write_errors else "") for k in starts]
        raise _Failed(Step("sw download", False, "after download, block(s) still differ: " + ", ".join(why)))
    # the drive resets after the download (2080h); bring it back to PRE-OP and check once more
    _sdo_step("sw reset", lambda: slave.request_state(EcState.INIT) if slave.state() is not EcState.INIT else None)
    _sdo_step("sw reset", lambda: slave.request_state(EcState.PREOP))
    report.trace.ec_state(EcState.INIT.value)  # the reset, as the timeline shows it
    report.trace.ec_state(EcState.PREOP.value)
    after = _sdo_step("sw verify", lambda: sw.verify(image, slave))
    report.trace.sw_downloaded(result, after)
    still = [b for b in after if not b.ok]
    if still:
        raise _Failed(Step("sw verify", False, "after reset, block(s) differ: "
                           + ", ".join(f"0x{b.start:04X}" for b in still)))
    report.steps.append(Step("sw download", True, f"{len(result.written)} block(s) written and verified from {cfg.file}"))


def _cycle_until(io: ProcessIo, done: Callable[[int], bool], max_cycles: int) -> bool:
    for _ in range(max_cycles):
        io.cycle()
        if done(io.read(0x6041, 0)):
            return True
    return False


def _set_mode(io: ProcessIo, mode: int) -> None:
    """Write 6060h and wait until the drive shows the mode in 6061h."""
    io.write(0x6060, 0, mode)
    for _ in range(100):
        io.cycle()
        if not io.has(0x6061) or io.read(0x6061, 0) == mode:
            return
    raise _Failed(Step("move", False, f"the drive did not switch to mode {mode} (6061h stays {io.read(0x6061, 0)})"))


def _preselect_mode(io: ProcessIo, rd: Slave) -> None:
    """Write the move's mode before the enable sequence: Control Techniques refuses a change of 6060h in
    OPERATION ENABLED (7.3.6, SDO abort 0800 0022h), so a mode chosen only for the move must be set first.
    A drive that shows the mode only once enabled (Technosoft) is checked by the move itself."""
    from ecattool.project.steps import MOVE_MODE_CODES, move_mode

    mode = move_mode(rd)
    if mode is None or not io.has(0x6060):
        return
    io.write(0x6060, 0, MOVE_MODE_CODES[mode])
    io.cycle()


def _hold_position(io: ProcessIo) -> None:
    """Set the mapped target position 607Ah to the actual position before the enable sequence: a drive in a
    cyclic position mode follows 607Ah from its first enabled cycle, and the value it held (0 after power-on)
    would make an axis that does not stand at 0 jump there."""
    if (0x607A, 0) in io.out_pos and io.has(0x6064):
        io.write(0x607A, 0, io.read(0x6064, 0))


def _zero_objects(io: ProcessIo, rd: Slave, mode: str) -> str:
    """Why a move failed, where the drive shows it: a PP move's profile velocity or acceleration at 0, or a
    zero part of the position factor (``steps.zero_factor_parts``), as the drive holds them (the process image
    for mapped outputs, else SDO)."""
    from ecattool.project.steps import PP_PROFILE, zero_factor_parts

    assert rd.device is not None
    device = rd.device

    def read(index: int, sub: int) -> int | None:
        pos = io.out_pos.get((index, sub))
        entry = device.dictionary.entry(index, sub)
        if entry is None:
            return None
        try:
            if pos is not None:
                return _get_bits(bytes(io.outputs), pos.bit_offset, pos.bit_len)
            return int.from_bytes(bytes(io.slave.sdo_upload(index, sub, size=entry_size(entry))), "little")
        except EcatToolError:
            return None

    zero = [(i, s) for i, s in (PP_PROFILE if mode == "pp" else ()) if read(i, s) == 0] + zero_factor_parts(read)
    names = [f"{i:04X}:{s:02X} ({getattr(device.dictionary.entry(i, s), 'name', '')})" for i, s in zero]
    return f": the drive holds 0 in {', '.join(names)}, which the move needs non-zero" if names else ""


def _move(io: ProcessIo, rd: Slave, report: DriveReport) -> None:
    from ecattool.commission.profiletime import check_move_time
    from ecattool.project.steps import MOVE_MODE_CODES, move_mode

    move = rd.drive.move
    mode = move_mode(rd)
    if move is None or mode is None:
        return
    dist = Fraction(move.distance).limit_denominator(1)
    internal = io.has(0x6063)
    p0 = io.read(0x6064, 0)
    i0 = io.read(0x6063, 0) if internal else None
    _set_mode(io, MOVE_MODE_CODES[mode])
    report.trace.begin_move(io, f"{mode.upper()} move of {dist} user units")
    try:
        _run_move(io, rd, mode, p0, dist, report.trace)
    finally:
        report.trace.end_move(io)
    figures = report.trace.figures
    if io.read(0x6041, 0) & 0x0008:
        raise _Failed(Step("move", False, "the drive faulted during the move (statusword bit 3)"
                                          + (f": {figures.text()}" if figures is not None else "")))
    if figures is not None and figures.outside_window:
        raise _Failed(Step("move", False, f"the following error reached {figures.following_error} user units, "
                                          f"beyond the window 6065h = {figures.window}: {figures.text()} (widen "
                                          "6065h, lower 6083h/6081h, or stiffen the drive's position loop)"))
    p1 = io.read(0x6064, 0)
    if p1 - p0 != dist:
        raise _Failed(Step("move", False, f"position moved {p1 - p0} user units, commanded {dist}"
                                          + _zero_objects(io, rd, mode)))
    detail = f"{mode.upper()} move of {dist} user units: position {p0} -> {p1}"
    if internal and i0 is not None:
        i1 = io.read(0x6063, 0)
        cpu = rd.counts_per_unit
        if cpu is not None:
            want = dist * cpu
            if abs(Fraction(i1 - i0) - want) > max(Fraction(1), abs(want) / 1_000_000):
                raise _Failed(Step("move", False, f"internal position moved {i1 - i0} counts, the factor group "
                                                  f"says {float(want):g} counts for {dist} user units"))
            detail += f"; internal {i0} -> {i1} = {i1 - i0} counts (factor group: {float(want):g})"
        else:
            detail += f"; internal {i0} -> {i1} counts"
    took_ok, took = check_move_time(io, rd, report.trace, mode, dist)  # the profile's time (issue 24)
    if not took_ok:
        raise _Failed(Step("move", False, took))
    if figures is not None:
        took += f"; {figures.text()}"
    report.steps.append(Step("move", True, detail + took))


def _run_move(io: ProcessIo, rd: Slave, mode: str, p0: int, dist: Fraction, trace: DriveTrace) -> None:
    """The motion: one profile-position set-point (pp), or 100 cyclic set-points then 50 cycles (csp)."""
    target = int(p0 + dist)
    if mode == "pp":
        io.write(0x607A, 0, target)
        io.write(0x6040, 0, cia402.ENABLE_OPERATION | cia402.NEW_SETPOINT)
        if not _cycle_until(io, lambda sw: bool(sw & 0x1000), 1000):
            raise _Failed(Step("move", False, "the drive did not acknowledge the new set-point (statusword bit 12)"
                                              + _zero_objects(io, rd, mode)))
        io.write(0x6040, 0, cia402.ENABLE_OPERATION)
        blocked = _zero_objects(io, rd, mode)
        if blocked:  # it would stand still: say why now rather than after the wait for target reached
            raise _Failed(Step("move", False, f"profile position move to {target} cannot happen{blocked}"))
        if not _cycle_until(io, lambda sw: bool(sw & 0x0400) and not sw & 0x1000, 200_000):
            raise _Failed(Step("move", False, f"profile position move to {target} did not reach its target "
                                              "(statusword bit 10)" + _zero_objects(io, rd, mode)))
        trace.reached()
        _settle(io)
    else:
        steps = 100
        for k in range(1, steps + 1):
            io.write(0x607A, 0, int(p0 + dist * k / steps))
            io.cycle()
        _cycle_until(io, lambda sw: False, 50)
        trace.reached()
        _settle(io, target)


def _settle(io: ProcessIo, target: int | None = None, cycles: int = 2000) -> None:
    """Cycle until the axis stands: 6064h on ``target`` (where given) and the actual position (6063h where the
    drive has it, else 6064h) the same for ten cycles; at most ``cycles`` (a drive's position loop settles
    after its demand has ended; bit 10 comes within the position window 6067h, which may be wider than a
    count). A fault (statusword bit 3) ends the wait."""
    key = 0x6063 if io.has(0x6063) else 0x6064
    last, same = None, 0
    for _ in range(cycles):
        now = io.read(key, 0)
        same = same + 1 if now == last else 0
        last = now
        if io.read(0x6041, 0) & 0x0008 or (same >= 10 and (target is None or io.read(0x6064, 0) == target)):
            return
        io.cycle()


def _prove_process_data(io: ProcessIo, rd: Slave, report: DriveReport) -> None:
    """An I/O slave in OP: one cycle with the output image (every output at its startup value or 0: nothing is
    switched on), its inputs read and decoded, and each mapped output read back by SDO where the slave's
    dictionary makes it readable in OP (the outputs arrived where the mapping says). A target raises on a
    working counter that is not full (pysoem) or an image of the wrong size (the simulator)."""
    assert rd.device is not None
    io.cycle()
    if len(io.inputs) != io.layout.inputs.byte_size:
        raise _Failed(Step("process data", False, f"the input image is {len(io.inputs)} byte(s), the mapping "
                                                  f"lays out {io.layout.inputs.byte_size}"))
    values = []
    for (index, sub), pos in io.in_pos.items():
        entry = rd.device.dictionary.entry(index, sub)
        if entry is not None and entry.datatype is not None and entry.datatype.bits:
            values.append(f"{index:04X}:{sub:02X}={_get_bits(io.inputs, pos.bit_offset, pos.bit_len)}")
    checked = 0
    for (index, sub), pos in io.out_pos.items() if _speaks_coe(rd) else ():
        entry = rd.device.dictionary.entry(index, sub)
        if entry is None or not entry.access.readable(EcState.OP) or pos.bit_len % 8:
            continue
        try:
            raw = bytes(io.slave.sdo_upload(index, sub, size=max(entry_size(entry) or 0, pos.bit_len // 8)))
        except EcatToolError:
            continue  # no mailbox, or an object the slave will not read out: the cycle itself is the proof
        sent = _get_bits(bytes(io.outputs), pos.bit_offset, pos.bit_len)
        if len(raw) * 8 == pos.bit_len and int.from_bytes(raw, "little") != sent:
            raise _Failed(Step("process data", False, f"output {index:04X}:{sub:02X} ({entry.name}) reads "
                                                      f"{int.from_bytes(raw, 'little')} by SDO after the cycle wrote {sent}"))
        checked += 1
    shown = ", ".join(values[:8]) + (f", … ({len(values)} inputs)" if len(values) > 8 else "")
    report.steps.append(Step("process data", True,
                             f"{len(io.outputs)} output byte(s) written ({len(io.out_pos)} object(s)"
                             + (f", {checked} read back by SDO" if checked else "") + f"), {len(io.inputs)} input "
                             f"byte(s) read ({len(io.in_pos)} object(s)" + (f": {shown}" if shown else "") + ")"))


def _expected_readbacks(rd: Slave) -> list[FactorObject]:
    """Factor objects the drive computes from its own hardware configuration (Control Techniques' read-only
    608Fh): the scaling is only right if the drive reports the value the project's feedback assumes."""
    group = rd.factor_group
    return [o for o in getattr(group, "objects", ()) if not o.write] if group is not None else []


def _check_readbacks(slave: SlaveTarget, rd: Slave, report: DriveReport) -> None:
    assert rd.device is not None
    expected = _expected_readbacks(rd)
    checked: list[str] = []
    for o in expected:
        entry = rd.device.dictionary.entry(o.index, o.subindex)
        if entry is None:
            continue
        address = f"0x{o.index:04X}:{o.subindex:02X}"
        raw = _sdo_step(f"read {address}", partial(slave.sdo_upload, o.index, o.subindex, size=entry_size(entry)))
        got = entry.decode(bytes(raw))
        if got != o.value:
            raise _Failed(Step("scaling", False, f"{address} ({o.name}: {o.part}) reads {got}, the project's scaling "
                                                 f"expects {o.value}; put the drive's value into the feedback section"))
        checked.append(f"{address} = {got}")
    if checked:
        report.steps.append(Step("scaling", True, "drive reports " + ", ".join(checked)))


def _dc(slave: SlaveTarget, rd: Slave, report: DriveReport) -> None:
    if rd.dc is None:
        return
    act = rd.dc.assign_activate
    cycle = rd.dc.cycle_ns or 0
    shift = rd.dc.shift_ns or 0
    _sdo_step("dc", lambda: slave.configure_dc(act, cycle, shift))
    what = f"SYNC0 cycle {cycle} ns" if cycle else "SYNC0 at the target's bus cycle (the project gives no cycle_ns)"
    report.steps.append(Step("dc", True, f"AssignActivate 0x{act:04X}, {what}" + (f", shift {shift} ns" if shift else "")))


def _safe_stop(slave: SlaveTarget, io: ProcessIo | None, report: DriveReport) -> None:
    """Leave the drive with its power stage off, in PRE-OP, whatever state it reached."""
    try:
        if io is not None:
            io.write(0x6040, 0, cia402.DISABLE_VOLTAGE)
            io.cycle()
    except EcatToolError:
        pass
    try:
        if slave.state() in (EcState.OP, EcState.SAFEOP):
            slave.request_state(EcState.PREOP)
    except EcatToolError:
        pass
    try:
        report.final_state = slave.state().value
    except EcatToolError:
        report.final_state = "unknown"


class _DriveRun:
    """One drive's commissioning in two phases, so that a master with one IO map for the whole bus
    (pysoem/SOEM ``config_map``) reads every drive's PDO mapping after all of them were written:
    :meth:`prepare` does everything in PRE-OP (identity, .sw, startup list, read-backs, DC), :meth:`finish`
    goes to SAFE-OP and OP, enables and moves. A failure in either stops the drive safely."""

    def __init__(self, slave: SlaveTarget, rd: Slave, allow_errors: bool = False) -> None:
        self.slave = slave
        self.rd = rd
        self.allow_errors = allow_errors
        self.report = DriveReport(rd.drive.name, rd.position, rd.kind, trace=DriveTrace.for_drive(rd))
        self.io: ProcessIo | None = None
        self.failed = False

    def _guarded(self, phase: Callable[[], None]) -> None:
        try:
            phase()
        except _Failed as exc:
            self._fail(exc.step)
        except EcatToolError as exc:  # anything a target or the device model raised outside a named step
            self._fail(Step("commission", False, str(exc)))

    def _fail(self, step: Step) -> None:
        self.report.steps.append(step)
        self.report.error = f"{step.name}: {step.detail}{_drive_error(self.slave, self.rd)}"
        self.failed = True
        _safe_stop(self.slave, self.io, self.report)

    def prepare(self) -> None:
        self._guarded(self._prepare)

    def finish(self) -> None:
        if not self.failed:
            self._guarded(self._finish)

    def _prepare(self) -> None:
        slave, rd, report = self.slave, self.rd, self.report
        if has_errors(rd.findings) and not self.allow_errors:
            first = next(f for f in rd.findings if f.severity.value == "error")
            raise _Failed(Step("lint", False, f"the project has errors for this drive, first: {first} "
                                              "(--allow-errors commissions it anyway)"))
        current = _sdo_step("state", slave.state)
        report.trace.ec_state(current.value)
        if current is not EcState.INIT:
            _sdo_step("state INIT", lambda: slave.request_state(EcState.INIT))
            report.trace.ec_state(EcState.INIT.value)
        _goto(slave, EcState.PREOP, report)
        _check_identity(slave, rd, report)
        _sw(slave, rd, report)
        _startup(slave, rd, _PREOP_TRANSITIONS, report)
        _check_readbacks(slave, rd, report)
        _dc(slave, rd, report)

    def _finish(self) -> None:
        slave, rd, report = self.slave, self.rd, self.report
        _goto(slave, EcState.SAFEOP, report)
        io = self.io = ProcessIo(slave, rd, report.trace)
        io.cycle()
        _startup(slave, rd, _SAFEOP_TRANSITIONS, report)
        io.seed_from_drive()
        io.cycle()  # the image a real master keeps sending while the drive goes to OP holds the seeded values
        _goto(slave, EcState.OP, report)
        if rd.kind == "io":
            _sdo_step("process data", lambda: _prove_process_data(io, rd, report))
        if rd.enables:
            _sdo_step("mode", lambda: _preselect_mode(io, rd))
            _sdo_step("hold position", lambda: _hold_position(io))
            try:
                passed = _sdo_step("enable", lambda: cia402.enable(lambda: io.read(0x6041, 0),
                                                                   lambda v: io.write(0x6040, 0, v), io.cycle))
            except _Failed as exc:  # name the project setting that commissions the slave without the enable
                exc.step.detail += " (enable: false in the project commissions it to OP without the CiA-402 enable)"
                raise
            report.steps.append(Step("enable", True, " -> ".join(passed)))
            _sdo_step("move", lambda: _move(io, rd, report))
        report.ok = True
        report.final_state = slave.state().value


def commission_drive(slave: SlaveTarget, rd: Slave) -> DriveReport:
    """Commission one drive on its own (both phases at once)."""
    run = _DriveRun(slave, rd)
    run.prepare()
    run.finish()
    return run.report


def op_handover(positions: Sequence[int]) -> str:
    """What the slaves put back in OP are told, once: ecattool's process data ends with the command."""
    one = len(positions) == 1
    which = f"slave {positions[0]} is" if one else f"slaves {', '.join(map(str, positions))} are"
    return (f"{which} in OP: the process data must now come from the machine's master (ecattool's stops as the "
            f"command ends; a drive's power stage is left disabled), else the sync manager watchdog takes "
            f"{'it' if one else 'them'} to SAFE-OP (AL status code 0x001B)")


def put_back(drives: Sequence[Slave], wanted: Sequence[tuple[SlaveTarget, EcState]]) -> list[str]:
    """Take each slave of ``wanted`` back to its state (SAFE-OP or OP, as it was found before a master reset the
    bus: :mod:`ecattool.online.bus_state`) the way commissioning configures it, from the project's ``drives`` at
    the same position: identity checked, the PRE-OP startup list (PDO assignment and mappings, the ESI's init
    commands, scaling, parameters) and DC, for every slave first (a master with one IO map for the bus, SOEM's
    ``config_map``, reads every slave's mapping once, at the first SAFE-OP request), then SAFE-OP with the SO
    commands, then OP where it was found in OP. Never the CiA-402 enable and no move: a drive put back in OP has
    its power stage disabled. A slave the project does not configure, or whose step fails, is left in PRE-OP.
    Returns one line per slave, what was done or why not, and one for the slaves put back in OP: who must send
    their process data now (:func:`op_handover`)."""
    by_position = {rd.position: rd for rd in drives}
    notes: list[str] = []
    runs: list[tuple[SlaveTarget, Slave, EcState, DriveReport]] = []

    def done(slave: SlaveTarget, state: EcState, phase: Callable[[], None], report: DriveReport | None = None) -> bool:
        """``phase`` ran; or it failed, as commissioning's run of a drive takes a failure (:meth:`_DriveRun._guarded`:
        a named step, or anything a target raised outside one), and the slave is left in PRE-OP with a note."""
        try:
            phase()
            return True
        except _Failed as exc:
            step = exc.step
        except EcatToolError as exc:
            step = Step("commission", False, str(exc))
        notes.append(f"slave {slave.position} ({state.value}) was left in PRE-OP: putting it back failed at "
                     f"{step.name}: {step.detail}")
        if report is not None:
            _safe_stop(slave, None, report)
        return False

    for slave, state in wanted:
        rd = by_position.get(slave.position)
        if rd is None or rd.device is None:
            notes.append(f"slave {slave.position} ({state.value}) was left in PRE-OP: the project configures no "
                         f"slave at position {slave.position}, ecattool cannot take it back to {state.value}")
            continue
        report = DriveReport(rd.drive.name, rd.position, rd.kind, trace=DriveTrace.for_drive(rd))

        def preop(slave: SlaveTarget = slave, rd: Slave = rd, report: DriveReport = report) -> None:
            _check_identity(slave, rd, report)
            _startup(slave, rd, _PREOP_TRANSITIONS, report)
            _dc(slave, rd, report)

        if done(slave, state, preop):
            runs.append((slave, rd, state, report))
    ready = []
    for slave, rd, state, report in runs:  # every slave's PRE-OP writes are done: SAFE-OP, slave by slave

        def safeop(slave: SlaveTarget = slave, rd: Slave = rd, report: DriveReport = report) -> None:
            _goto(slave, EcState.SAFEOP, report)
            _startup(slave, rd, _SAFEOP_TRANSITIONS, report)

        if done(slave, state, safeop, report):
            ready.append((slave, state, report))
    in_op = []
    for slave, state, report in ready:  # OP last: the master's cycles on the way keep the others' watchdogs fed
        if state is EcState.OP:
            if not done(slave, state, partial(_goto, slave, EcState.OP, report), report):
                continue
            in_op.append(slave.position)
        notes.append(f"slave {slave.position} was put back in {state.value} as the project configures it")
    if in_op:
        notes.append(op_handover(in_op))
    return notes


def _drive_error(slave: SlaveTarget, rd: Slave) -> str:
    """What the drive itself says went wrong, for a failure report: its error code 603Fh (the last EMCY), named
    from the family's table; "" where there is none, or it cannot be read (no mailbox, no 603Fh)."""
    from ecattool.od.emcy import error_text

    if rd.device is None or rd.device.dictionary.entry(0x603F, 0) is None:
        return ""
    try:
        if slave.state() not in (EcState.PREOP, EcState.SAFEOP, EcState.OP):
            return ""
        code = int.from_bytes(bytes(slave.sdo_upload(0x603F, 0, size=2))[:2], "little")  # UINT (CiA-402)
    except EcatToolError:
        return ""
    if not code:
        return ""
    return f"; the drive reports error 603Fh = 0x{code:04X} ({error_text(code, rd.rules.family if rd.rules is not None else None)})"


def open_target(spec: str, drives: Sequence[Slave], reset_bus: bool = False) -> tuple[Target, str]:
    """The target ``spec`` names (:func:`ecattool.online.targets.open_guarded`: a real bus with slaves in SAFE-OP
    or OP is refused unless ``reset_bus``) with the slaves' devices for a simulator; and the target's name for the
    report. A slave whose device did not resolve cannot be simulated: an InputError naming it and why (the file
    and line lint names); a real master takes the devices that resolved (their ESI timeouts bound its waits)."""
    from ecattool.online.targets import open_guarded
    from ecattool.target.opener import parse_target

    machine = Machine("", slaves=tuple(drives))
    devices = ([d for _, d in machine.devices()] if parse_target(spec).own_slaves
               else [s.device for s in machine.in_bus_order() if s.device is not None])
    return open_guarded(spec, devices, reset_bus), spec


def _set_plants(slaves: list[SlaveTarget], drives: Sequence[Slave]) -> None:
    """Put each simulated drive on the plant its project sets (``plant:``); a real slave has its own."""
    from ecattool.project.plant import plant_params

    for rd in drives:
        if rd.drive.plant is None or rd.position >= len(slaves):
            continue
        set_plant = getattr(slaves[rd.position], "set_plant", None)
        if set_plant is not None:
            set_plant(plant_params(rd))


def commission(path: str | Path | Machine, target: str | Target | None = None,
               on_drive: Callable[[DriveReport], None] | None = None, *,
               allow_errors: bool = False, reset_bus: bool = False) -> CommissionReport:
    """Commission every slave of the project at ``path`` (or of a :class:`Machine` already built) on ``target``.

    An axis goes to OP, is enabled through CiA-402 and makes the project's move; an I/O slave goes to OP and
    exchanges one cycle of process data (:func:`_prove_process_data`). A slave with lint errors is not touched
    (its report names the first error) unless ``allow_errors`` (the ``--allow-errors`` policy of every command).

    ``target`` is a spec string (``"sim"``, ``"pysoem:eth0"``; default: the project's, i.e. ``"sim"``) or a
    ready :class:`~ecattool.target.base.Target` object (e.g. a ``SimTarget`` of prepared simulated drives with
    faults scheduled); a target object passed in is not closed, its owner closes it. A real bus with a slave in
    SAFE-OP or OP is refused before it is touched, unless ``reset_bus`` (commissioning takes every slave through
    INIT: a running machine would stop).
    """
    machine = path if isinstance(path, Machine) else load_machine(path)
    machine.require_loaded()
    owned = target is None or isinstance(target, str)
    if target is None or isinstance(target, str):
        tgt, name = open_target(target or machine.target, machine.slaves, reset_bus)
    else:
        tgt, name = target, type(target).__name__
    report = CommissionReport(machine.path, name, findings=list(machine.findings))
    try:
        slaves = tgt.slaves()
        if owned:
            _set_plants(slaves, machine.slaves)
        ordered = machine.in_bus_order()
        runs: list[_DriveRun | DriveReport] = []
        for rd in ordered:  # every drive's PRE-OP work first, then SAFE-OP/OP drive by drive
            if rd.position >= len(slaves):
                dr = DriveReport(rd.drive.name, rd.position, rd.kind, error=f"no slave at bus position {rd.position}")
                dr.steps.append(Step("bus", False, dr.error or ""))
                runs.append(dr)
            else:
                run = _DriveRun(slaves[rd.position], rd, allow_errors)
                run.prepare()
                runs.append(run)
        for item in runs:
            if isinstance(item, _DriveRun):
                item.finish()
                item = item.report
            report.drives.append(item)
            if on_drive:
                on_drive(item)
    finally:
        if owned:
            tgt.close()
    return report
