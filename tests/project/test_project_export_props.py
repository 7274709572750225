"""Property: any lint-clean list of parameters written in a project comes out of every text exporter and back
through its importer unchanged (transition, address, bytes), encoded with the object's exact size."""

from __future__ import annotations

import tempfile
from functools import lru_cache
from pathlib import Path

from hypothesis import given, settings
from hypothesis import strategies as st

from ecattool import profiles
from ecattool.od.model import EcState
from ecattool.od.types import Kind
from ecattool.project.export import slave_configs
from ecattool.startup import export, import_bytes

RELATIONAL = {0x6046, 0x6060}  # see test_lint_sim_agree: judged by the drive from other values


@lru_cache(maxsize=None)
def writable() -> list:
    dev = profiles.load("hdt", product="tomcat")
    return [(o.index, e) for o in dev.dictionary for e in o.entries.values()
            if e.datatype is not None and e.datatype.kind in (Kind.SIGNED, Kind.UNSIGNED)
            and e.datatype.bits in (8, 16, 32) and e.access.writable(EcState.PREOP)
            and not (0x1600 <= o.index <= 0x1BFF or o.index in (0x1C12, 0x1C13)) and o.index not in RELATIONAL]


@st.composite
def parameter(draw) -> tuple[int, object, int]:
    index, e = draw(st.sampled_from(writable()))
    bits = e.datatype.bits
    lo, hi = (-(1 << (bits - 1)), (1 << (bits - 1)) - 1) if e.datatype.kind is Kind.SIGNED else (0, (1 << bits) - 1)
    lo = max(lo, e.minimum) if e.minimum is not None else lo
    hi = min(hi, e.maximum) if e.maximum is not None else hi
    if e.values:  # a printed value list (decision Profiles-2): only its values are valid
        value = draw(st.sampled_from(sorted(e.values)))
    else:
        value = draw(st.sampled_from(sorted(e.enum))) if e.enum else draw(st.integers(lo, hi))
    return index, e, value


def _text(v: int, style: int) -> str:
    return str(v) if style == 0 or v < 0 else f"0x{v:X}" if style == 1 else f'"#x{v:X}"'


@settings(max_examples=40)
@given(params=st.lists(parameter(), min_size=1, max_size=12), styles=st.lists(st.integers(0, 2), min_size=12, max_size=12),
       transitions=st.lists(st.sampled_from(["PS", "IP"]), min_size=12, max_size=12))
def test_parameters_survive_every_exporter(params, styles, transitions):
    lines = ["ecattool: 1", "drives:", "  - name: axis", "    device: {profile: hdt, product: tomcat}",
             "    disable_rules:", "      - {rule: PDO021, reason: generated values}",
             "      - {rule: PRJ016, reason: generated values}", "    parameters:"]
    for k, (index, e, value) in enumerate(params):
        lines.append(f'      - {{object: "0x{index:04X}:{e.subindex:02X}", value: {_text(value, styles[k])}, '
                     f"transition: {transitions[k]}}}")
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "project.yaml"
        p.write_text("\n".join(lines) + "\n")
        (cfg,) = slave_configs(p)
    want = [(transitions[k], index, e.subindex, e.encode(value)) for k, (index, e, value) in enumerate(params)]
    assert [(c.transition, c.index, c.subindex, c.data) for c in cfg.commands] == want
    for fmt in ("eni", "json", "csv", "twincat", "ecmc", "ros2"):
        (back,) = import_bytes(export(cfg, fmt, lossy=True).encode(), f"x.{fmt}", fmt)  # CSV/TwinCAT: no PDO tables
        got = [(c.index, c.subindex, c.data) for c in back.commands]
        assert got == [w[1:] for w in want], fmt
        if fmt in ("eni", "json", "csv", "twincat"):
            assert [c.transition for c in back.commands] == transitions[: len(params)], fmt
