"""Named definitions (issue 36.5): the AL status codes, the CiA-402 state coding and the family data that rules
used to restate by family name, each defined once and checked against its source."""

from __future__ import annotations

import re
from dataclasses import replace

import pytest

from ecattool.abort import AL_STATUS_TEXTS, AlStatus, al_status_text
from ecattool.od import cia402
from ecattool.od.cia402 import MASK_OF, STATUS_BITS, State, state_of
from tests.conftest import seeds_path

#: Technosoft iPOS CoE Programming (P091.064), "Table 4.2.4 – State coding in Statusword"
TECHNOSOFT = "000_a0ab57c0bda88c2c.txt"
#: Control Techniques SM-EtherCAT User Guide, "Table 7.5 State coding"
CONTROL_TECHNIQUES = "004_b59360cba58a7982.txt"

_ROW = re.compile(r"^\|?\s*(xxxx xxxx [x01]{4} [x01]{4})\s*_?b\s*\|?\s*([A-Za-z ]+?)\s*\|?\s*$")


def _coding(name: str, first: int, last: int) -> dict[str, tuple[int, int]]:
    """State name (lower case) → (mask, value) of the rows ``first``..``last`` (1-based lines) of a manual's
    state coding table: a 0/1 digit is a bit that must have that value, an x one that does not matter. Skips, as
    every test of the manuals' texts, where ../shared/seeds is not beside the checkout."""
    path = seeds_path(name)
    lines = path.read_text(encoding="utf-8").splitlines()[first - 1:last]
    out = {}
    for line in lines:
        m = _ROW.match(line)
        assert m, f"{path.name}: not a state coding row: {line!r}"
        bits = m.group(1).replace(" ", "")
        mask = int("".join("0" if c == "x" else "1" for c in bits), 2)
        value = int(bits.replace("x", "0"), 2)
        out[m.group(2).strip().lower()] = (mask, value)
    return out


@pytest.mark.parametrize("path, first, last", [
    (TECHNOSOFT, 2150, 2157),  # 000_a0ab57c0bda88c2c.txt:2150-2157, Table 4.2.4
    (CONTROL_TECHNIQUES, 1386, 1393),  # 004_b59360cba58a7982.txt:1386-1393, Table 7.5
])
def test_the_state_coding_is_the_manuals(path: str, first: int, last: int) -> None:
    table = _coding(path, first, last)
    assert set(table) == {s.text for s in State}
    for state in State:
        assert (MASK_OF[state], STATUS_BITS[state]) == table[state.text], state
    # every statusword shows the state whose row it matches (at most one row matches any word)
    for sw in range(0x10000):
        rows = [name for name, (mask, value) in table.items() if sw & mask == value]
        assert len(rows) <= 1, (hex(sw), rows)
        shown = state_of(sw)
        assert (shown.text if shown is not None else None) == (rows[0] if rows else None), hex(sw)


def test_both_readers_of_the_statusword_use_the_definitions() -> None:
    from ecattool.commission.cia402 import state_of as commission_state
    from ecattool.sim.cia402 import decode_statusword

    assert commission_state(0x0237) == "operation enabled" and decode_statusword(0x0237) is State.OPERATION_ENABLED
    assert commission_state(0x0001) == "unknown (0x0001)" and decode_statusword(0x0001) is State.NOT_READY
    assert cia402.decode_statusword is decode_statusword


def test_al_status_codes_have_their_texts() -> None:
    assert set(AL_STATUS_TEXTS) == set(AlStatus)
    assert AlStatus.INVALID_STATE_CHANGE == 0x0011 and AlStatus(0x001D) is AlStatus.INVALID_OUTPUT_CONFIG
    assert AlStatus.DC_INVALID_CYCLE.text == "DC invalid sync cycle time" == al_status_text(0x0035)
    assert al_status_text(0x0099) == "unknown AL status code"


def test_the_simulator_refuses_with_al_status_members() -> None:
    from ecattool.errors import StateChangeError
    from ecattool.od.model import EcState
    from ecattool.sim import Drive

    d = Drive.from_profile("hdt")
    with pytest.raises(StateChangeError) as exc:
        d.request_state(EcState.OP)  # INIT -> OP is no transition
    assert exc.value.al_status is AlStatus.INVALID_STATE_CHANGE


def test_the_sync0_rule_is_the_family_data(monkeypatch: pytest.MonkeyPatch) -> None:
    """The simulator's SYNC0 check reads FamilyRules.dc_sync0_step_ns/dc_sync0_max_steps (Control Techniques
    8.1.1: n x 250 us, n = 1..60), not the family name: other data, another rule."""
    from ecattool import profiles
    from ecattool.errors import StateChangeError
    from ecattool.od.model import EcState
    from ecattool.sim import Drive

    device = profiles.load("hdt")
    own = profiles.rules_for(device)
    stepped = replace(own, dc_sync0_step_ns=500_000, dc_sync0_max_steps=4)

    def to_op(cycle_ns: int, rules: object) -> None:
        d = Drive(device, rules)  # type: ignore[arg-type]
        d.request_state(EcState.PREOP)
        d.request_state(EcState.SAFEOP)
        d.configure_dc(0x0300, cycle_ns)
        d.request_state(EcState.OP)

    to_op(2_000_000, stepped)  # 4 x 500 us
    with pytest.raises(StateChangeError, match=r"not n x 500 us \(n = 1..4\)") as exc:
        to_op(2_500_000, stepped)
    assert exc.value.al_status is AlStatus.DC_INVALID_CYCLE
    with pytest.raises(StateChangeError, match="not n x 500 us"):
        to_op(750_000, stepped)
    to_op(750_000, own)  # the HDT's own rules have no SYNC0 rule


def test_fixed_counts_per_rev_is_the_family_data(monkeypatch: pytest.MonkeyPatch) -> None:
    from ecattool.profiles import hdt
    from ecattool.scaling.compute import fixed_counts_per_rev

    assert fixed_counts_per_rev("hdt") == 65536 == hdt.rules().counts_per_rev
    assert fixed_counts_per_rev("technosoft-ipos") is None and fixed_counts_per_rev("generic") is None
    real = hdt.rules
    monkeypatch.setattr(hdt, "rules", lambda device=None: replace(real(device), counts_per_rev=4096))
    assert fixed_counts_per_rev("hdt") == 4096
