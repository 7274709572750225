"""Small helpers for the simulator tests: SDO reads/writes by value, the abort code of a refused call, a drive
brought up to an EtherCAT state."""

from __future__ import annotations

from typing import Any

import pytest

from ecattool.errors import SdoAbort
from ecattool.od.model import EcState
from ecattool.sim import Drive

PRE, SAFE, OP = EcState.PREOP, EcState.SAFEOP, EcState.OP


def w(d: Drive, index: int, sub: int, value: int, size: int) -> None:
    """Download ``value`` as ``size`` little-endian bytes (two's complement when negative)."""
    d.sdo_download(index, sub, value.to_bytes(size, "little", signed=value < 0))


def r(d: Drive, index: int, sub: int = 0, signed: bool = False) -> int:
    return int.from_bytes(d.sdo_upload(index, sub), "little", signed=signed)


def code_of(fn: Any, *args: Any) -> int:
    """The SDO abort code ``fn(*args)`` raises (the test fails when it does not abort)."""
    with pytest.raises(SdoAbort) as exc:
        fn(*args)
    return exc.value.code


def at(name: str, state: EcState = PRE, **kw: Any) -> Drive:
    """A drive of profile ``name`` brought from INIT up to ``state``. On the ideal plant (actual = demand) unless
    ``plant`` is given: these tests check the manuals' exact timings and traces (issue 33)."""
    kw.setdefault("plant", "ideal")
    d = Drive.from_profile(name, **kw)
    for s in (PRE, SAFE, OP):
        d.request_state(s)
        if s is state:
            break
    return d


def in_mode(name: str, mode: int) -> Drive:
    """A drive of profile ``name`` in OP with mode of operation ``mode`` (6060h written in PRE-OP), on the ideal
    plant."""
    d = at(name, PRE)
    w(d, 0x6060, 0, mode, 1)
    d.request_state(SAFE)
    d.request_state(OP)
    return d
