"""The mailbox over the wire (issue 13, items 3 and 6): KickCAT's Python master (the ``kickcat`` package, 2.5)
commissions the virtual bus over raw Ethernet; SOEM (pysoem) reads the object dictionary through SDO
information (faults over the wire, an SDO abort among them: tests/wire/test_wire_faults.py); all inside a private network namespace with a veth pair the test makes
itself (never the host's interfaces).
Skipped, with the reason printed, only where a master is missing or the kernel refuses the namespace.

Each test is one subprocess with a timeout; every loop inside it is bounded."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from ecattool.od.model import MAILBOX_STATES, EcState, ObjectCode
from ecattool.project.export import slave_configs
from ecattool.sim.bus import netns
from ecattool.project.bus import devices_in_bus_order
from ecattool.sim.bus.serve import Served, device_source, virtual_slaves
from tests.conftest import ROOT
from tests.wire.wire_helpers import last_json, skip_without

#: every bus of these tests runs in one xdist worker (scripts/dev.py: --dist loadgroup), never two at once
pytestmark = pytest.mark.xdist_group("wire")

HERE = Path(__file__).parent
#: the samples KickCAT takes to OP on one bus (Control Techniques runs CSP, which needs DC: see below)
PROJECTS = ["samples/hdt/project.yaml", "samples/technosoft_ipos/project.yaml", "samples/generic_esi/project.yaml"]


def _scenario(script: str, *args: str, timeout: int, module: str) -> dict[str, Any]:
    skip_without(module)
    # faulthandler: a crash inside a master's compiled code still names the Python line that called it
    argv = netns.command([sys.executable, "-X", "faulthandler", str(HERE / script), *args])
    done = subprocess.run(argv, capture_output=True, text=True, timeout=timeout, cwd=ROOT)
    if done.returncode < 0 and module == "kickcat":
        # KickCAT 2.5's C++ master has crashed (SIGSEGV) in create_mapping's SDO reads on a heavily loaded machine
        # (the full suite beside a benchmark); it is KickCAT's own process that dies: run the scenario once more
        print(f"KickCAT crashed (signal {-done.returncode}), running the scenario again:\n{done.stderr[-1500:]}",
              file=sys.stderr)
        done = subprocess.run(argv, capture_output=True, text=True, timeout=timeout, cwd=ROOT)
    assert done.returncode == 0, done.stderr[-3000:]
    # the scenario's result is its last JSON line: KickCAT's C++ side writes its own lines to stdout, and
    # its buffer may be flushed after Python's at exit ("Opening redundant interface: None")
    return last_json(done.stdout)


def load_sources(sources: list[str]) -> list[Served]:
    """The slaves ``ecattool sim serve SOURCES`` serves, in process."""
    return virtual_slaves([d for src in sources for d in (
        devices_in_bus_order(src) if src.endswith(".yaml") else [device_source(src)])])


def _expected(projects: list[str]) -> tuple[list[list[int]], list[list[int]]]:
    """Identity and process image sizes of the same drives in process, after the same startup SDOs."""
    drives = [s.slave.drive for s in load_sources(projects)]
    configs = [c for p in projects for c in slave_configs(p)]
    identity, sizes = [], []
    for drive, cfg in zip(drives, configs):
        ident = drive.identity()
        identity.append([ident.vendor_id, ident.product_code, ident.revision])
        drive.request_state(EcState.PREOP)
        for cmd in cfg.commands:
            if cmd.transition == "PS":
                drive.sdo_download(cmd.index, cmd.subindex, cmd.data, complete_access=cmd.complete_access)
        drive.request_state(EcState.SAFEOP)
        sizes.append(list(drive.process_image_sizes()))
    return identity, sizes


def test_kickcat_brings_the_samples_to_op_with_their_mapping() -> None:
    out = _scenario("wire_kickcat_scenario.py", *PROJECTS, timeout=300, module="kickcat")
    identity, sizes = _expected(PROJECTS)
    assert out["error"] is None, out
    assert out["found"] == len(PROJECTS)
    assert out["identity"] == identity  # SDO reads of 1018h:01..03 agree with the in-process drives
    assert out["writes"] and all(status == 0 for _, _, status in out["writes"])  # every startup SDO: SUCCESS
    assert out["sizes"] == sizes  # KickCAT read the projects' mapping back over SDO
    assert out["op"] == [True] * len(PROJECTS) and out["pd_errors"] == 0
    assert out["op_sdo"] == [ident[0].to_bytes(4, "little").hex() for ident in identity]
    assert out["init"] is True
    assert out["server"] == {"returncode": 0, "stderr": ""}


def test_kickcat_is_refused_op_where_the_project_needs_dc() -> None:
    """KickCAT 2.5's Python master cannot switch distributed clocks on (Bus.init no longer calls enableDC and
    the binding does not offer it): the Control Techniques sample runs CSP, and the drive refuses OP with AL
    0x0030 exactly as in process; KickCAT reports the refusal."""
    project = "samples/controltechniques/project.yaml"
    out = _scenario("wire_kickcat_scenario.py", project, timeout=300, module="kickcat")
    identity, sizes = _expected([project])
    assert out["identity"] == identity and out["sizes"] == sizes and out["safeop"] is True
    assert out["error"].startswith("OP: ErrorAL")
    assert out["server"]["returncode"] == 0


def test_soem_reads_the_object_dictionary_through_sdo_information_and_maps_by_complete_access() -> None:
    """pysoem's ``slave.od`` (ecx_readODlist, ecx_readODdescription, ecx_readOE) against the ETG.2001 sample
    drive, which declares SdoInfo: every object, its name, object code and data type, and every entry of the
    ARRAY/RECORD objects with its name, data type, bit length and access word (ETG.1000.6: bits 0-2 readable
    in PRE-OP/SAFE-OP/OP, 3-5 writable, 6/7 RxPDO/TxPDO mappable)."""
    esi = "samples/esi/etg2001_cia402.xml"
    out = _scenario("wire_mailbox_scenario.py", "od", esi, timeout=200, module="pysoem")
    dictionary = load_sources([esi])[0].slave.drive.device.dictionary
    assert [row[0] for row in out["od"]] == [o.index for o in dictionary]
    states = sorted(MAILBOX_STATES, key=lambda s: s.code)  # PRE-OP, SAFE-OP, OP
    codes = {ObjectCode.VAR: 7, ObjectCode.ARRAY: 8, ObjectCode.RECORD: 9}
    for (index, name, code, dtype, entries), obj in zip(out["od"], dictionary):
        assert (name, code) == (obj.name, codes[obj.object_code]), hex(index)
        if obj.object_code is ObjectCode.VAR:
            assert dtype == obj.entries[0].datatype.code and entries == []  # pysoem lists entries of VARs not
            continue
        want = []
        for e in obj:
            access = sum(1 << i for i, s in enumerate(states) if s in e.access.read)
            access |= sum(1 << (3 + i) for i, s in enumerate(states) if s in e.access.write)
            access |= (0x40 if e.rx_mappable else 0) | (0x80 if e.tx_mappable else 0)
            want.append([e.name, e.datatype.code, e.bit_size, access])
        assert entries == want, hex(index)
    drive = load_sources([esi])[0].slave.drive
    drive.request_state(EcState.PREOP)
    drive.request_state(EcState.SAFEOP)
    assert out["sizes"] == list(drive.process_image_sizes())  # config_map read 1C12h/1C13h by complete access
    assert out["server"] == {"returncode": 0, "stderr": ""}


def test_soem_writes_a_setup_image_by_foe() -> None:
    """FoE over the wire (item 3, as Technosoft §17.4 uses it): the sample's setup.sw made into an FoE setup file
    (``ecattool sw foe``) and written by SOEM's ``foe_write`` in PRE-OP. The drive refuses a name without FOESW_
    and a password other than 0 (SOEM returns -5, its FoE error); the right request programs the EEPROM, which
    ``ecattool sw verify --target pysoem`` finds differing before and holding the image after."""
    out = _scenario("wire_mailbox_scenario.py", "foe", "samples/technosoft_ipos/project.yaml",
                    "samples/technosoft_ipos/setup.sw", timeout=240, module="pysoem")
    assert out["verify_before"]["returncode"] == 1 and json.loads(out["verify_before"]["stdout"])["ok"] is False
    assert [w.get("result") for w in out["writes"]] == [-5, -5, 1], out["writes"]
    after = json.loads(out["verify_after"]["stdout"])
    assert out["verify_after"]["returncode"] == 0 and after["ok"] is True and all(b["ok"] for b in after["blocks"])
    assert out["server"] == {"returncode": 0, "stderr": ""}
