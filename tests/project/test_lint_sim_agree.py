"""Lint and the simulator are independent witnesses: for generated single parameter writes (any integer
entry of the three families' dictionaries, values around the type, minimum and maximum limits), lint's
verdict (PRJ012/PRJ014 error or clean) must match whether the simulated drive accepts the SDO download.

The few objects where the drive decides from other objects' values or runs a command (relational checks
lint cannot see from one parameter) are listed with the reason. 6060h is judged by the family's supported modes
(PRJ017): an error where the drive aborts, a warning on Technosoft, which accepts it with an emergency."""

from __future__ import annotations

from functools import lru_cache

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ecattool import profiles
from ecattool.errors import EcatToolError, Location, SdoAbort
from ecattool.od.model import EcState
from ecattool.od.types import Kind
from ecattool.project.model import Parameter
from ecattool.project.resolve import encode_parameter
from ecattool.sim import Drive

FAMILIES = {"hdt": "tomcat", "technosoft-ipos": "ipos4808-bx-cat-sto", "controltechniques": "digitax-st"}
LOC = Location("p.yaml", 1, 1)

#: (family, index) -> why lint cannot judge a single write of it
RELATIONAL = {
    ("hdt", 0x6046): "min velocity must stay below max velocity (the other sub-index)",
    ("hdt", 0x1010): "a store command: only the signature 'save' (65766173h) is accepted",
    ("controltechniques", 0x604B): "0 is refused; negative numerators give the direction (scaling decisions)",
    ("controltechniques", 0x604C): "0 is refused; negative numerators give the direction",
    ("controltechniques", 0x60C2): "the period is sub1 x 10^sub2: valid or not with the other sub-index",
    ("technosoft-ipos", 0x2069): "a checksum command over an address range",
    ("technosoft-ipos", 0x2080): "a reset command: the drive does not reply",
}


@lru_cache(maxsize=None)
def device(family: str):
    return profiles.load(family, product=FAMILIES[family])


@lru_cache(maxsize=None)
def rules(family: str):
    return profiles.rules_for(device(family))


@lru_cache(maxsize=None)
def entries(family: str) -> list:
    dev = device(family)
    return [(o.index, e) for o in dev.dictionary for e in o.entries.values()
            if e.datatype is not None and e.datatype.kind in (Kind.SIGNED, Kind.UNSIGNED)
            and e.datatype.bits in (8, 16, 32)
            and not (0x1600 <= o.index <= 0x1BFF or o.index in (0x1C12, 0x1C13))  # PDO programming: pdo/ rules
            and (family, o.index) not in RELATIONAL]


def _values(e) -> st.SearchStrategy[int]:
    bits = e.datatype.bits
    lo, hi = (-(1 << (bits - 1)), (1 << (bits - 1)) - 1) if e.datatype.kind is Kind.SIGNED else (0, (1 << bits) - 1)
    edges = [lo, hi, 0, 1]
    for b in (e.minimum, e.maximum, *sorted(e.values or ())):
        if b is not None:
            edges += [b - 1, b, b + 1]
    return st.one_of(st.sampled_from([v for v in edges if lo <= v <= hi]), st.integers(lo, hi))


def _sim_verdict(family: str, index: int, sub: int, data: bytes) -> str:
    drive = Drive.from_device(device(family))
    drive.request_state(EcState.PREOP)
    try:
        drive.sdo_download(index, sub, data)
    except SdoAbort as exc:
        return f"abort 0x{exc.code:08X}"
    except EcatToolError as exc:  # pragma: no cover - a timeout would be a relational object to list
        return type(exc).__name__
    return "ok"


def _check(family: str, index: int, entry, value: int) -> None:
    param = Parameter(object=f"{index:04X}:{entry.subindex:02X}", value=value)
    cmd, findings = encode_parameter(device(family), param, LOC, LOC, rules(family))
    errors = [f.rule for f in findings if f.severity.value == "error"]
    # what lint refused is sent anyway, as the bit pattern of the value in the entry's size
    raw = cmd.data if cmd is not None else (value % (1 << entry.datatype.bits)).to_bytes(entry.byte_size, "little")
    sim = _sim_verdict(family, index, entry.subindex, raw)
    lint = errors[0] if errors else "ok"
    assert (lint == "ok") == (sim == "ok"), (family, f"0x{index:04X}:{entry.subindex:02X}", entry.name, value, lint, sim)


@pytest.mark.parametrize("family", sorted(FAMILIES))
def test_every_entry_written_with_its_default(family):
    """Each integer entry once, with its default value (or 0): lint and drive agree on access rules."""
    for index, entry in entries(family):
        default = entry.decode(entry.default) if entry.default else 0
        _check(family, index, entry, default)


@pytest.mark.parametrize("family", sorted(FAMILIES))
@settings(max_examples=250)
@given(data=st.data())
def test_lint_and_the_simulated_drive_agree_on_parameter_writes(family, data):
    index, entry = data.draw(st.sampled_from(entries(family)), label="entry")
    _check(family, index, entry, data.draw(_values(entry), label="value"))


@pytest.mark.parametrize("mode", [2, 8])
@pytest.mark.parametrize("cycle_ns", [None, 0, 125_000, 250_000, 1_000_000, 1_100_000, 15_000_000, 15_250_000])
def test_lint_and_the_simulated_drive_agree_on_distributed_clocks(tmp_path, mode, cycle_ns):
    """Control Techniques 7.4/8.1.1: CSP needs DC, SYNC0 = n x 250 us (n = 1..60). Lint's PRJ041/PRJ042 error
    must be exactly what makes the simulated drive refuse OP (commissioned with the rules disabled)."""
    from ecattool.commission import commission
    from ecattool.project.machine import load_machine

    dc = "" if cycle_ns is None else f"    dc: {{assign_activate: 0x0300, cycle_ns: {cycle_ns}}}\n"
    text = ("ecattool: 1\nOFFdrives:\n  - name: x\n    device: {profile: controltechniques, product: digitax-st}\n"
            f"{dc}    parameters:\n      - {{object: modes of operation, value: {mode}}}\n")
    path = tmp_path / "p.yaml"
    path.write_text(text.replace("OFF", ""))
    lint = sorted(f.rule for f in load_machine(path).findings if f.severity.value == "error")
    if cycle_ns == 0:  # no SYNC0 cycle at all: the project schema refuses it (dc.cycle_ns >= 1) before any drive
        assert lint == ["PRJ001"], lint
        return
    assert set(lint) <= {"PRJ041", "PRJ042"}, lint
    path.write_text(text.replace("OFF", "disable_rules:\n  - {rule: PRJ041, reason: t}\n  - {rule: PRJ042, reason: t}\n"))
    report = commission(path)
    assert (not lint) == report.ok, (lint, [s.detail for d in report.drives for s in d.steps if not s.ok])


PRODUCTS = [(p.name, prod.name) for p in profiles.list_profiles() for prod in p.products]


@pytest.mark.parametrize("move", ["pp", "csp"])
@pytest.mark.parametrize(("family", "product"), PRODUCTS, ids=[f"{a}-{b}" for a, b in PRODUCTS])
def test_lint_and_the_simulated_drive_agree_on_the_commissioning_move(tmp_path, family, product, move):
    """A move in a mode the drive lacks (Commander SK, Affinity: vl and tq only) linted clean and failed at
    commissioning; now lint refuses exactly the moves the simulated drive refuses."""
    from ecattool.commission import commission
    from ecattool.project.machine import load_machine

    path = tmp_path / "p.yaml"
    path.write_text(f"ecattool: 1\ndrives:\n  - name: x\n    device: {{profile: {family}, product: {product}}}\n"
                    "    dc: {assign_activate: 0x0300, cycle_ns: 1000000}\n"
                    f"    move: {{distance: 10, mode: {move}}}\n"
                    # Technosoft's profile velocity/acceleration come from its setup (.sw); without one they are 0
                    + ("    parameters: [{object: '6081:00', value: 10000}, {object: '6083:00', value: 100000}]\n"
                       if family == "technosoft-ipos" else ""))
    lint = [f for f in load_machine(path).findings if f.severity.value == "error"]
    assert {f.rule for f in lint} <= {"PRJ017"}, [str(f) for f in lint]
    path.write_text(path.read_text().replace("drives:", "disable_rules:\n  - {rule: PRJ017, reason: t}\ndrives:"))
    report = commission(path)
    assert (not lint) == report.ok, ([str(f) for f in lint], [s.detail for d in report.drives for s in d.steps if not s.ok])


@pytest.mark.parametrize("velocity", [None, 10000])
def test_a_pp_move_without_profile_velocity_is_flagged_and_does_not_move(tmp_path, velocity):
    """Technosoft leaves 6081h at 0 without a setup: lint warns (PRJ019) exactly when the simulated move fails."""
    from ecattool.commission import commission
    from ecattool.project.machine import load_machine

    path = tmp_path / "p.yaml"
    path.write_text("ecattool: 1\ndrives:\n  - name: x\n    device: {profile: technosoft-ipos}\n    parameters:\n"
                    "      - {object: '6060:00', value: 1}\n      - {object: '6083:00', value: 100000}\n"
                    + (f"      - {{object: '6081:00', value: {velocity}}}\n" if velocity else "")
                    + "    move: {distance: 10}\n")
    warned = [f.rule for f in load_machine(path).findings] == ["PRJ019"]
    assert warned is (velocity is None)
    assert commission(path).ok is not warned


#: (60C2h sub1, sub2) targets: 7.4.3 accepts 250 us, 500 us, k x 1 ms (oracle 35's encodings and invalid examples)
PERIODS = [(250, -6), (25, -5), (50, -5), (5, -4), (1, -3), (10, -4), (100, -5), (2, -3), (20, -4), (200, -5),
           (15, -3), (100, -6), (75, -5), (3, -4), (0, -3), (16, -3), (1, 0), (255, -1)]


@pytest.mark.parametrize("sub2_first", [False, True])
@pytest.mark.parametrize(("base", "exp"), PERIODS)
def test_lint_and_the_simulated_drive_agree_on_the_interpolation_period(tmp_path, base, exp, sub2_first):
    """Each write of 60C2h is checked with the other sub-index as it stands, so the order matters: lint follows
    the startup list (PRJ043) exactly where the simulated drive aborts."""
    from ecattool.project.machine import load_machine

    writes = [(1, base), (2, exp)][::-1 if sub2_first else 1]
    path = tmp_path / "p.yaml"
    path.write_text("ecattool: 1\ndrives:\n  - name: x\n    device: {profile: controltechniques, product: digitax-st}\n"
                    "    parameters:\n" + "".join(f"      - {{object: '60C2:0{s}', value: {v}}}\n" for s, v in writes))
    lint = [f.rule for f in load_machine(path).findings if f.severity.value == "error"]
    drive = Drive.from_device(device("controltechniques"))
    drive.request_state(EcState.PREOP)
    refused = False
    try:
        for s, v in writes:
            drive.sdo_download(0x60C2, s, v.to_bytes(1, "little", signed=s == 2))
    except SdoAbort as exc:
        assert exc.code == 0x06090030
        refused = True
    assert lint == (["PRJ043"] if refused else []), (writes, lint, refused)
