"""What a commissioning run did, recorded for people (the HTML report, ``ecattool commission --report``).

The runner (:mod:`ecattool.commission.runner`) fills one :class:`DriveTrace` per drive as it goes, on any
target (the simulator or a real master): every startup write as sent with its result and read-back, the
``.sw`` blocks checked and written, the EtherCAT and CiA-402 state timeline over process-data cycles, and
samples of the commissioning move (the master's set-point, the drive's position demand, actual position and
velocity in user units, actual position in internal units). Recording never changes what the run does: an
object that cannot be sampled is dropped from the samples, not reported as a failure.
"""

from __future__ import annotations

import time
from collections.abc import Container
from dataclasses import dataclass, field
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Protocol

from ecattool.commission.cia402 import state_of
from ecattool.errors import EcatToolError
from ecattool.profiles.rules import interpolation_period_ns

if TYPE_CHECKING:
    from ecattool.findings import Finding
    from ecattool.pdo.layout import Layout
    from ecattool.project.slave import Slave
    from ecattool.startup.model import StartupCommand
    from ecattool.sw.apply import BlockCheck, DownloadReport

class ProcessImage(Protocol):
    """What the trace reads after a cycle (the runner's ``ProcessIo``): objects by (index, sub-index), from the
    input image where mapped, else by SDO."""

    @property
    def in_pos(self) -> Container[tuple[int, int]]: ...

    def has(self, index: int, sub: int = 0) -> bool: ...

    def read(self, index: int, sub: int) -> int: ...


#: at most this many move samples are kept: a long move is thinned (every 2nd, 4th … cycle), never cut
MAX_SAMPLES = 600


@dataclass(frozen=True, slots=True)
class Channel:
    """A quantity sampled during the move."""

    key: str
    index: int
    subindex: int
    label: str
    unit: str  # "user" (the position/velocity user unit) or "internal"
    kind: str  # "position" | "velocity"
    source: str  # "master" (the last value the master wrote) | "drive"


CHANNELS = (
    Channel("target", 0x607A, 0, "607Ah target position (sent)", "user", "position", "master"),
    Channel("demand", 0x6062, 0, "6062h position demand", "user", "position", "drive"),
    Channel("actual", 0x6064, 0, "6064h position actual", "user", "position", "drive"),
    Channel("velocity", 0x606C, 0, "606Ch velocity actual", "user", "velocity", "drive"),
    Channel("internal", 0x6063, 0, "6063h position actual (internal)", "internal", "position", "drive"),
    Channel("error", 0x60F4, 0, "60F4h following error actual", "user", "position", "drive"),
    Channel("torque", 0x6077, 0, "6077h torque actual", "per mille of rated torque", "torque", "drive"),
)


@dataclass(frozen=True, slots=True)
class MoveFigures:
    """What the move's trace shows about how the axis followed (issue 33): the largest following error (60F4h,
    else 6062h - 6064h; user units), the settling time (from the demand's end until the actual position stays
    on the final demand; s), the overshoot beyond the final demand in the direction of the move (user units),
    the peak speed (606Ch, user velocity units) and the peak torque (6077h, per mille of rated); ``window``:
    the drive's following-error window 6065h (None: none, or supervision off)."""

    following_error: int
    settling_s: float
    overshoot: int
    peak_speed: int | None
    peak_torque: int | None
    window: int | None

    @property
    def outside_window(self) -> bool:
        return self.window is not None and self.following_error > self.window

    def to_json(self) -> dict[str, Any]:
        return {"following_error_max": self.following_error, "following_error_window": self.window,
                "settling_time_s": round(self.settling_s, 6), "overshoot": self.overshoot,
                "peak_speed": self.peak_speed, "peak_torque_per_mille": self.peak_torque}

    def text(self) -> str:
        parts = [f"following error up to {self.following_error}"
                 + (f" (6065h window {self.window})" if self.window is not None else ""),
                 f"settled {self.settling_s * 1000:g} ms after the demand", f"overshoot {self.overshoot}"]
        if self.peak_speed is not None:
            parts.append(f"peak speed {self.peak_speed}")
        if self.peak_torque is not None:
            parts.append(f"peak torque {self.peak_torque / 10:g} % of rated")
        return "; ".join(parts)


def move_figures(samples: list[Sample], cycle_s: float, window: int | None) -> MoveFigures | None:
    """:class:`MoveFigures` of a move's samples (None: no position samples)."""
    pts = [s for s in samples if "actual" in s.values]
    if not pts:
        return None
    demand_key = "demand" if all("demand" in s.values for s in pts) else "actual"
    errors = [abs(s.values["error"]) if "error" in s.values else abs(s.values[demand_key] - s.values["actual"])
              for s in pts]
    final = pts[-1].values[demand_key]
    start = pts[0].values["actual"]
    direction = 1 if final >= start else -1
    demand_end = pts[0].cycle
    for a, b in zip(pts, pts[1:]):
        if b.values[demand_key] != a.values[demand_key]:
            demand_end = b.cycle
    settled = pts[-1].cycle
    for s in reversed(pts):
        if s.values["actual"] != final:
            break
        settled = s.cycle
    overshoot = max(0, max((s.values["actual"] - final) * direction for s in pts))
    speeds = [abs(s.values["velocity"]) for s in pts if "velocity" in s.values]
    torques = [abs(s.values["torque"]) for s in pts if "torque" in s.values]
    return MoveFigures(max(errors), max(0, settled - demand_end) * cycle_s, overshoot,
                       max(speeds) if speeds else None, max(torques) if torques else None, window)


@dataclass(slots=True)
class StartupWrite:
    """One startup-list write as sent, with what the drive answered and what it read back."""

    transition: str
    address: str
    comment: str
    data: bytes
    complete_access: bool
    ok: bool = True
    result: str = "ok"
    read_back: bytes | None = None
    verified: bool | None = None  # None: not read back (no reply expected, complete access, not readable)
    source: str = ""  # where the write comes from (project file:line), for people

    def to_json(self) -> dict[str, Any]:
        return {"transition": self.transition, "object": self.address, "comment": self.comment,
                "data": self.data.hex(), "complete_access": self.complete_access, "ok": self.ok,
                "result": self.result, "read_back": None if self.read_back is None else self.read_back.hex(),
                "verified": self.verified}


@dataclass(slots=True)
class SwBlock:
    """One block of a ``.sw`` image: the drive's checksum before, whether it was written, and after."""

    start: int
    end: int
    words: int
    expected: int
    before: int | None
    written: bool = False
    after: int | None = None
    error: str | None = None

    @property
    def ok(self) -> bool:
        final = self.after if self.written else self.before
        return self.error is None and final == self.expected


@dataclass(slots=True)
class StateEvent:
    """A point of the state timeline: an EtherCAT state reached, or a CiA-402 state the statusword showed."""

    cycle: int
    layer: str  # "ethercat" | "cia402"
    state: str
    statusword: int | None = None
    controlword: int | None = None


@dataclass(slots=True)
class Sample:
    cycle: int
    values: dict[str, int]


@dataclass(slots=True)
class DriveTrace:
    """Everything the report shows about one drive's run (filled by the runner; empty when it never ran)."""

    layout: Layout | None = None
    findings: list[Finding] = field(default_factory=list)
    units: dict[str, str] = field(default_factory=dict)  # "position"/"velocity" -> unit name
    counts_per_unit: Fraction | None = None
    cycle_s: float = 0.001  # one process-data cycle: the drive's 60C2h, else the project's DC cycle, else 1 ms
    startup: list[StartupWrite] = field(default_factory=list)
    sw_file: str = ""
    sw_blocks: list[SwBlock] = field(default_factory=list)
    events: list[StateEvent] = field(default_factory=list)
    samples: list[Sample] = field(default_factory=list)
    channels: list[Channel] = field(default_factory=list)
    move: str = ""  # "PP move of 1000 user units" once the move started
    move_cycles: tuple[int, int] | None = None
    #: the following-error window 6065h read when the move began (None: none, or FFFFFFFFh = off)
    error_window: int | None = None
    figures: MoveFigures | None = None
    #: the cycle the move reached its target (PP: statusword bit 10; CSP: the last set-point), before the axis
    #: settled: the end of :attr:`move_cycles` where set
    reached_cycle: int | None = None
    #: the move's duration by the master's clock (on a real bus the drive moves in real time, and a master that
    #: is late for a cycle counts fewer cycles than the drive ran)
    move_wall_s: float | None = None
    cycles: int = 0
    _written: dict[tuple[int, int], int] = field(default_factory=dict)
    _every: int = 1
    _sampling: bool = False
    _move_start: int = 0
    _move_start_wall: float = 0.0

    @classmethod
    def for_drive(cls, rd: Slave) -> DriveTrace:
        """The static context of a drive: its process image, lint findings and units."""
        trace = cls(findings=list(rd.findings), counts_per_unit=rd.counts_per_unit)
        if rd.device is not None and rd.mapping is not None:
            from ecattool import pdo

            try:
                trace.layout = pdo.layout(rd.device, rd.mapping)
            except EcatToolError:
                pass
        summary = getattr(rd.factor_group, "summary", {})
        for what in ("position", "velocity"):
            if summary.get(f"{what} unit"):
                trace.units[what] = str(summary[f"{what} unit"])
        if rd.dc is not None and rd.dc.cycle_ns:
            trace.cycle_s = rd.dc.cycle_ns / 1e9
        return trace

    # ------------------------------------------------------------------ startup list, .sw image
    def startup_write(self, cmd: StartupCommand) -> StartupWrite:
        w = StartupWrite(cmd.transition, cmd.address, cmd.comment, bytes(cmd.data), cmd.complete_access,
                         source=str(cmd.source) if cmd.source is not None else "")
        self.startup.append(w)
        return w

    def sw_checked(self, checks: list[BlockCheck], file: str) -> None:
        """The verify before any download (``sw.BlockCheck`` list)."""
        self.sw_file = file
        self.sw_blocks = [SwBlock(c.block.start, c.block.end, c.block.count, c.expected, c.actual, error=c.error)
                          for c in checks]

    def sw_downloaded(self, result: DownloadReport, after: list[BlockCheck]) -> None:
        """A download (``sw.DownloadReport``) and the verify after the drive's reset."""
        written = {b.start for b in result.written}
        final = {c.block.start: c for c in after}
        for b in self.sw_blocks:
            b.written = b.start in written
            c = final.get(b.start)
            if c is not None:
                b.after, b.error = c.actual, result.write_errors.get(b.start) or c.error

    # ------------------------------------------------------------------ states and process data
    def ec_state(self, state: str) -> None:
        self.events.append(StateEvent(self.cycles, "ethercat", state))

    def written(self, index: int, sub: int, value: int) -> None:
        """The master wrote ``value`` to an object (process data or SDO): the controlword and set-points."""
        self._written[(index, sub)] = value

    def on_cycle(self, io: ProcessImage) -> None:
        """After every process-data cycle: the CiA-402 state (when the statusword is mapped) and, during the
        move, a sample."""
        self.cycles += 1
        if (0x6041, 0) in io.in_pos:
            sw = io.read(0x6041, 0)
            state = state_of(sw)
            last = next((e for e in reversed(self.events) if e.layer == "cia402"), None)
            if last is None or last.state != state:
                self.events.append(StateEvent(self.cycles, "cia402", state, sw, self._written.get((0x6040, 0))))
        if self._sampling and (self.cycles - self._move_start) % self._every == 0:
            self._sample(io)

    def begin_move(self, io: ProcessImage, what: str) -> None:
        self.move = what
        self.channels = [c for c in CHANNELS if io.has(c.index, c.subindex)]
        self.cycle_s = self._drive_period(io) or self.cycle_s
        self.error_window = None
        if io.has(0x6065, 0) and io.has(0x6066, 0):  # the supervision needs both (window and time)
            try:
                window, time_out = io.read(0x6065, 0), io.read(0x6066, 0)
            except EcatToolError:
                window, time_out = 0xFFFFFFFF, 0
            # FFFFFFFFh: supervision off (CiA-402); 0 with a time of 0: a setup that set neither (Technosoft
            # §7.2.10: "Default value -", set by Drive Setup)
            self.error_window = None if window == 0xFFFFFFFF or (window == 0 and time_out == 0) else window
        self._move_start = self.cycles
        self.reached_cycle = None
        self._move_start_wall = time.monotonic()
        self._sampling = True
        self._sample(io)

    @staticmethod
    def _drive_period(io: ProcessImage) -> float | None:
        """The drive's interpolation period 60C2h in seconds (the time of one cycle as the drive counts it),
        None where it has none or will not tell."""
        if not io.has(0x60C2, 1):
            return None

        try:
            base, exponent = io.read(0x60C2, 1), io.read(0x60C2, 2)
        except EcatToolError:
            return None
        return float(interpolation_period_ns(base, exponent)) / 1e9 if base > 0 and -9 <= exponent <= 2 else None

    def reached(self) -> None:
        """The move has reached its target now (the axis may still settle)."""
        self.reached_cycle = self.cycles

    def end_move(self, io: ProcessImage) -> None:
        if self._sampling and (not self.samples or self.samples[-1].cycle != self.cycles):
            self._sample(io)
        self._sampling = False
        self.move_cycles = (self._move_start, self.reached_cycle if self.reached_cycle is not None else self.cycles)
        self.figures = move_figures(self.samples, self.cycle_s, self.error_window)
        self.move_wall_s = time.monotonic() - self._move_start_wall

    def _sample(self, io: ProcessImage) -> None:
        values: dict[str, int] = {}
        for c in list(self.channels):
            try:
                if c.source == "master":
                    if (c.index, c.subindex) in self._written:
                        values[c.key] = self._written[(c.index, c.subindex)]
                else:  # from the input image, or by SDO where it is not mapped
                    values[c.key] = io.read(c.index, c.subindex)
            except EcatToolError:
                self.channels.remove(c)  # the drive will not give it: not sampled, the run goes on
        self.samples.append(Sample(self.cycles, values))
        if len(self.samples) >= MAX_SAMPLES:  # thin out: keep every other sample, sample half as often
            self.samples = self.samples[::2]
            self._every *= 2
