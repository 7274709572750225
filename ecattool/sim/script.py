"""Scripts for the simulator: a JSON/YAML list of SDO reads/writes, state requests and process-data cycles.

Steps (one mapping each)::

    - state: PREOP                          # INIT, PREOP, SAFEOP, OP, BOOT
    - read: "6041:00"                       # optional expect: 0x0250 (value) or expect_data: "5002"
    - write: "6060:00"                      # value: 8 (encoded with the entry's type) or data: "08" (hex bytes)
      value: 8
    - write: "1C12:00"
      data: "0200001601"                    # complete_access: true for a complete-access download
      complete_access: true
    - write: "6041:00"
      value: 1
      expect_abort: 0x06010002              # this abort is expected: the step passes
    - state: OP
      expect_al_status: 0x0011
    - exchange: "0f00"                      # one process-data cycle with this output image (hex)
    - cycles: 100                           # advance the motion model
    - foe: FOESW_AXIS01.bin                 # data: hex, or file: path relative to the script
      file: setup.bin
    - inputs: {limit_positive: true}        # limit_negative, limit_positive (switch inputs), load_torque (N·m
                                            # on the motor shaft), obstacle (user position, or null)
    - plant: {position_bandwidth: 50}       # the plant's parameters (docs/simulator.md), or: plant: ideal

:func:`run_script` runs the steps and returns the transcript; it stops at the first unexpected result.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

from ecattool.errors import (
    EcatToolError,
    InputError,
    Location,
    SdoAbort,
    SdoTimeout,
    StateChangeError,
    TargetError,
)
from ecattool.od.model import EcState
from ecattool.od.numbers import format_address, parse_address, parse_int
from ecattool.sim.drive import Drive, FoeError
from ecattool.sim.drive.plant import PlantParams

_KINDS = ("state", "read", "write", "exchange", "cycles", "foe", "inputs", "plant")
#: what an ``inputs:`` step sets
_INPUTS = ("limit_negative", "limit_positive", "load_torque", "obstacle")
#: The keys each kind of step takes besides its own: anything else is refused, never silently ignored.
_KEYS: dict[str, frozenset[str]] = {
    "state": frozenset({"expect_al_status"}),
    "read": frozenset({"complete_access", "expect", "expect_data", "expect_abort", "expect_timeout"}),
    "write": frozenset({"value", "data", "complete_access", "expect_abort", "expect_reply", "expect_timeout"}),
    "exchange": frozenset(),
    "cycles": frozenset(),
    "foe": frozenset({"data", "file", "password", "expect_abort"}),
    "inputs": frozenset(),
    "plant": frozenset(),
}


@dataclass
class Line:
    step: int
    line: int | None
    op: str
    target: str
    result: str  # "ok", "abort", "timeout", "refused", "foe-error", "mismatch"
    detail: str = ""
    code: int | None = None
    expected: bool = True
    data: str | None = None
    value: Any = None

    def to_json(self) -> dict[str, Any]:
        return {k: v for k, v in self.__dict__.items() if v is not None}


@dataclass
class Transcript:
    source: str
    lines: list[Line] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return all(ln.expected for ln in self.lines)

    @property
    def failure(self) -> Line | None:
        return next((ln for ln in self.lines if not ln.expected), None)

    def to_json(self) -> dict[str, Any]:
        return {"source": self.source, "ok": self.ok, "steps": [ln.to_json() for ln in self.lines]}


def load_script(path: str | Path) -> tuple[list[dict[str, Any]], list[Location]]:
    """The steps of a JSON/YAML script file and the location of each step."""
    from ecattool.fileio import read_bytes
    from ecattool.yamlloc import MAX_YAML_BYTES, load_yaml

    doc = load_yaml(read_bytes(path, MAX_YAML_BYTES), str(path))
    return parse_steps(doc.data, [doc.locate((i,)) for i in range(len(doc.data or []))], str(path))


def parse_steps(data: Any, locations: list[Location], source: str = "<script>") -> tuple[list[dict[str, Any]], list[Location]]:
    if not isinstance(data, list):
        raise InputError("a simulator script is a list of steps (- read: \"6041:00\", - state: OP …)", Location(source, 1))
    for i, step in enumerate(data):
        loc = locations[i] if i < len(locations) else Location(source)
        if not isinstance(step, dict) or not any(k in step for k in _KINDS):
            raise InputError(f"step {i + 1} needs one of {', '.join(_KINDS)}", loc)
        kinds = [k for k in _KINDS if k in step]
        if len(kinds) > 1:
            raise InputError(f"step {i + 1} has {' and '.join(kinds)}: one operation a step", loc)
        allowed = _KEYS[kinds[0]]
        for key in step:
            if key != kinds[0] and key not in allowed:
                raise InputError(f"step {i + 1} ({kinds[0]}): unknown key {key!r}{_suggest(str(key), allowed)}"
                                 f" (a {kinds[0]} step takes {', '.join(sorted(allowed)) or 'nothing else'})", loc)
        _check_bounds(step, i + 1, loc)
    return data, locations


#: Most process-data cycles one ``cycles:`` step may run: 10^5 cycles are 100 s of motion at a 1 ms cycle (seconds
#: of simulation); a count from a typo (2^40) is refused where the script is read instead of running for days.
MAX_CYCLES = 100_000

#: (key, what, lowest, highest) of the counts and codes a step gives, checked when the script is read
_BOUNDS = (("cycles", "cycle count", 0, MAX_CYCLES), ("password", "FoE password", 0, 0xFFFFFFFF),
           ("expect_abort", "abort code", 0, 0xFFFFFFFF), ("expect_al_status", "AL status", 0, 0xFFFF))


def _check_bounds(step: dict[str, Any], n: int, loc: Location) -> None:
    for key, what, lo, hi in _BOUNDS:
        if key in step:
            v = _int(step[key], loc, what)
            if not lo <= v <= hi:
                raise InputError(f"step {n} ({key}): {what} {v} is out of range {lo}..{hi}", loc)


def _suggest(key: str, allowed: frozenset[str]) -> str:
    import difflib

    close = difflib.get_close_matches(key, sorted(allowed), n=1)
    return f", did you mean {close[0]!r}?" if close else ""


def _int(v: Any, loc: Location, what: str) -> int:
    if isinstance(v, bool):  # YAML true/false: never a number
        raise InputError(f"{what} must be a number, not {str(v).lower()}", loc)
    return parse_int(v if isinstance(v, (int, str)) else str(v), loc, what)


def run_script(drive: Drive, steps: list[dict[str, Any]], locations: list[Location], source: str = "<script>",
               base_dir: Path | None = None) -> Transcript:
    """Run ``steps`` against ``drive``; stops after the first unexpected result (see :class:`Transcript`)."""
    tr = Transcript(source)
    for i, step in enumerate(steps):
        loc = locations[i] if i < len(locations) else Location(source)
        line = _run_step(drive, step, i + 1, loc, base_dir)
        tr.lines.append(line)
        if not line.expected:
            break
    return tr


def _run_step(drive: Drive, step: dict[str, Any], n: int, loc: Location, base_dir: Path | None) -> Line:
    want_abort = _int(step["expect_abort"], loc, "abort code") if "expect_abort" in step else None
    want_al = _int(step["expect_al_status"], loc, "AL status") if "expect_al_status" in step else None
    ln = loc.line
    if "state" in step:
        try:
            state = EcState.parse(str(step["state"]))
        except ValueError:
            raise InputError(f"unknown state {step['state']!r} (INIT, PREOP, SAFEOP, OP, BOOT)", loc) from None
        try:
            drive.request_state(state)
        except StateChangeError as exc:
            return Line(n, ln, "state", state.value, "refused", str(exc), exc.al_status, want_al == exc.al_status)
        return Line(n, ln, "state", state.value, "ok", expected=want_al is None)
    if "cycles" in step:
        _check_bounds(step, n, loc)  # steps given to run_script directly are not parsed first
        drive.step(_int(step["cycles"], loc, "cycle count"))
        return Line(n, ln, "cycles", str(step["cycles"]), "ok")
    if "exchange" in step:
        try:
            outputs = bytes.fromhex(str(step["exchange"]).replace(" ", ""))
        except ValueError:
            raise InputError(f"exchange needs the output image as hex bytes, not {step['exchange']!r}", loc) from None
        try:
            inputs = drive.exchange(outputs)
        except EcatToolError as exc:
            return Line(n, ln, "exchange", outputs.hex(), "refused", str(exc), expected=False)
        return Line(n, ln, "exchange", outputs.hex(), "ok", data=inputs.hex())
    if "inputs" in step:
        return _inputs(drive, step["inputs"], n, loc)
    if "plant" in step:
        try:
            return _plant(drive, step["plant"], n, loc)
        except TargetError as exc:
            raise InputError(f"step {n} (plant): {exc}", loc) from None
    if "foe" in step:
        name = str(step["foe"])
        if "file" in step:
            from ecattool.fileio import read_bytes

            data = read_bytes((base_dir or Path(".")) / str(step["file"]))
        else:
            try:
                data = bytes.fromhex(str(step.get("data", "")).replace(" ", ""))
            except ValueError:
                raise InputError(f"foe data must be hex bytes (\"0800\"), not {step.get('data')!r}", loc) from None
        try:
            drive.foe_write(name, data, _int(step.get("password", 0), loc, "password"))
        except FoeError as exc:
            return Line(n, ln, "foe", name, "foe-error", str(exc), exc.code, want_abort == exc.code)
        return Line(n, ln, "foe", name, "ok", expected=want_abort is None)
    op = "read" if "read" in step else "write"
    index, sub = parse_address(str(step[op]), loc)
    addr = format_address(index, sub)
    ca = bool(step.get("complete_access", False))
    try:
        if op == "read":
            raw = drive.sdo_upload(index, sub, complete_access=ca)
            value = _decode(drive, index, sub, raw, ca)
            line = Line(n, ln, "read", addr, "ok", data=raw.hex(), value=value, expected=want_abort is None)
            if "expect" in step and value != _expected_value(step["expect"], loc):
                line.result, line.expected = "mismatch", False
                line.detail = f"read {value!r}, expected {step['expect']!r}"
            if "expect_data" in step and raw.hex() != str(step["expect_data"]).replace(" ", "").lower():
                line.result, line.expected = "mismatch", False
                line.detail = f"read {raw.hex()}, expected {step['expect_data']}"
            return line
        data = _encode(drive, index, sub, step, loc)
        drive.sdo_download(index, sub, data, complete_access=ca, expect_reply=bool(step.get("expect_reply", True)))
        return Line(n, ln, "write", addr, "ok", data=data.hex(), expected=want_abort is None)
    except SdoAbort as exc:
        return Line(n, ln, op, addr, "abort", exc.message.split(": ", 1)[-1], exc.code, want_abort == exc.code)
    except SdoTimeout:
        return Line(n, ln, op, addr, "timeout", "no reply", expected=bool(step.get("expect_timeout", False)))


def _number(v: Any, loc: Location, what: str) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise InputError(f"{what} must be a number, not {v!r}", loc)
    return float(v)


def _inputs(drive: Drive, data: Any, n: int, loc: Location) -> Line:
    """Switch inputs, a load torque or an obstacle (issue 33: what a script can do to the axis), or an I/O slave's
    input objects by address (``"6000:01": 1``)."""
    if not isinstance(data, dict) or not data:
        raise InputError(f"step {n} (inputs): a mapping of {', '.join(_INPUTS)} or input objects (\"6000:01\": 1)",
                         loc)
    objects: dict[tuple[int, int], int] = {}
    for key in data:
        if key not in _INPUTS:
            try:
                address = parse_address(str(key), loc)
            except InputError:
                raise InputError(f"step {n} (inputs): unknown input {key!r}{_suggest(str(key), frozenset(_INPUTS))} "
                                 f"(one of {', '.join(_INPUTS)}, or an input object \"6000:01\")", loc) from None
            objects[address] = _int(data[key], loc, f"input {key}")
    try:
        if objects:
            drive.set_inputs(objects)
        _axis_inputs(drive, data, n, loc)
    except TargetError as exc:
        raise InputError(f"step {n} (inputs): {exc}", loc) from None
    return Line(n, loc.line, "inputs", ", ".join(f"{k}={v}" for k, v in data.items()), "ok")


def _axis_inputs(drive: Drive, data: dict[str, Any], n: int, loc: Location) -> None:
    if "limit_negative" in data or "limit_positive" in data:
        neg, pos = drive.limit_switches
        for key in ("limit_negative", "limit_positive"):
            if key in data and not isinstance(data[key], bool):
                raise InputError(f"step {n} (inputs): {key} is true or false, not {data[key]!r}", loc)
        drive.set_limit_switches(negative=bool(data.get("limit_negative", neg)),
                                 positive=bool(data.get("limit_positive", pos)))
    if "load_torque" in data:
        drive.set_load_torque(_number(data["load_torque"], loc, "load_torque"))
    if "obstacle" in data:
        drive.set_obstacle(None if data["obstacle"] is None else _int(data["obstacle"], loc, "obstacle"))


def _plant(drive: Drive, data: Any, n: int, loc: Location) -> Line:
    """New plant parameters (or ``ideal``) for the drive."""
    if data == "ideal":
        drive.set_plant("ideal")
        return Line(n, loc.line, "plant", "ideal", "ok")
    names = {f.name for f in fields(PlantParams)} - {"delay"}
    if not isinstance(data, dict) or not data:
        raise InputError(f"step {n} (plant): 'ideal' or a mapping of {', '.join(sorted(names))}", loc)
    for key, value in data.items():
        if key not in names:
            raise InputError(f"step {n} (plant): unknown parameter {key!r}{_suggest(str(key), frozenset(names))}",
                             loc)
        if _number(value, loc, str(key)) < 0:
            raise InputError(f"step {n} (plant): {key} must not be negative", loc)
    base = drive.plant_params or PlantParams()
    drive.set_plant(base.with_(**{k: float(v) for k, v in data.items()}))
    return Line(n, loc.line, "plant", ", ".join(f"{k}={v}" for k, v in data.items()), "ok")


def _expected_value(v: Any, loc: Location) -> Any:
    if isinstance(v, str):
        try:
            return parse_int(v, loc)
        except InputError:
            return v
    return v


def _decode(drive: Drive, index: int, sub: int, raw: bytes, ca: bool) -> Any:
    e = drive.device.dictionary.entry(index, sub)
    if ca or e is None or e.datatype is None:
        return raw.hex()
    try:
        v = e.decode(raw)
    except EcatToolError:
        return raw.hex()
    return v.hex() if isinstance(v, bytes) else v


def _encode(drive: Drive, index: int, sub: int, step: dict[str, Any], loc: Location) -> bytes:
    if "data" in step:
        try:
            return bytes.fromhex(str(step["data"]).replace(" ", ""))
        except ValueError:
            raise InputError(f"data must be hex bytes (\"0800\"), not {step['data']!r}", loc) from None
    if "value" not in step:
        raise InputError("a write needs value: or data:", loc)
    e = drive.device.dictionary.entry(index, sub)
    if e is None:
        raise InputError(f"{format_address(index, sub)} is not in the dictionary; give data: as hex bytes", loc)
    value = step["value"]
    if isinstance(value, str):
        try:
            value = parse_int(value, loc)
        except InputError:
            pass
    try:
        return e.encode(value)
    except EcatToolError as exc:
        raise InputError(f"{format_address(index, sub)}: {exc.message}", loc) from None
