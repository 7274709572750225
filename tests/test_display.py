"""Values people read: object values decoded by data type (decimal and hex, bits named), tables that keep
identifiers whole at 80 columns, and --json that stays machine-first."""

from __future__ import annotations

import json
import os
import pty
import re
import subprocess
import sys
from pathlib import Path

import pytest

from ecattool.od.display import bit_names, int_text, value_text
from ecattool.od.types import lookup
from tests.conftest import ROOT, corpus_path, run

ESI = ROOT / "samples" / "esi" / "etg2001_cia402.xml"


def test_values_decode_by_data_type() -> None:
    assert value_text(bytes.fromhex("d0070000")) == "2000 (0x000007D0)"  # no type: unsigned by size
    assert value_text(bytes.fromhex("1027"), lookup("UINT")) == "10000 (0x2710)"
    assert value_text(bytes.fromhex("fbff"), lookup("INT")) == "-5 (0xFFFB)"
    assert value_text(bytes.fromhex("1027"), lookup("UINT"), unit="rpm") == "10000 rpm (0x2710)"
    assert value_text(bytes.fromhex("0000803f"), lookup("REAL")) == "1"
    assert value_text(b"Drive1", lookup("STRING(6)")) == "'Drive1'"
    assert value_text(bytes(range(1, 11))) == "01 02 03 04 05 06 07 08 09 0a"  # no integer of 10 bytes
    assert int_text(0x0F, 2, 0x6040) == "15 (0x000F): switch on, enable voltage, quick stop, enable operation"
    assert bit_names(0x6041, 0x0237) == ["ready to switch on", "switched on", "operation enabled", "voltage enabled",
                                         "quick stop", "remote"]
    assert bit_names(0x6064, 0xFFFF) == []


def test_esi_objects_show_defaults_as_values_and_json_keeps_the_bytes(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "esi", "show", str(ESI), "--objects")
    assert code == 0 and "5001 (0x00001389)" in out and "89130000" not in out  # 1000h device type: DS402
    code, out, _ = run(capsys, "esi", "show", str(ESI), "--objects", "--json")
    entry = json.loads(out)["objects"][0]["entries"][0]
    assert code == 0 and entry["default"] == "89130000"


def test_startup_import_shows_values(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    out_file = tmp_path / "ipos.json"
    assert run(capsys, "startup", "export", "--project", str(ROOT / "samples/technosoft_ipos/project.yaml"),
               "--format", "json", "-o", str(out_file))[0] == 0
    raw = json.loads(out_file.read_text())
    code, out, _ = run(capsys, "startup", "import", str(out_file))
    assert code == 0
    # every command's value is shown decoded: a 4-byte write as decimal and 8 hex digits, never as raw bytes
    commands = [c for s in raw["slaves"] for c in s["commands"] if not c.get("complete_access")]
    assert commands
    for c in commands:
        data = bytes.fromhex(c["data"])
        assert value_text(data, index=int(str(c["index"]), 0) if isinstance(c["index"], str) else c["index"]) in out


def test_sii_info_mailbox_reads_as_addresses(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "sii", "info", str(ROOT / "samples/sii/custom_slave.bin"))
    assert code == 0 and "out 0x1000 (128 bytes), in 0x1080 (128 bytes)" in out and "rx_offset" not in out


def test_sim_run_names_the_statusword(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    script = tmp_path / "s.yaml"
    script.write_text('- state: PREOP\n- read: "6041:00"\n- write: "6040:00"\n  value: 6\n- read: "6041:00"\n')
    code, out, _ = run(capsys, "sim", "run", "hdt", str(script))
    lines = out.splitlines()
    assert code == 0
    assert lines[1].endswith("= 1600 (0x0640): switch on disabled, remote, target reached — SWITCH_ON_DISABLED")
    assert lines[2].endswith("= 6 (0x0006): enable voltage, quick stop")
    assert "READY_TO_SWITCH_ON" in lines[3]


def _at_80_columns(*args: str) -> str:
    """The command's output on an 80-column terminal (a pseudo-terminal, as a person sees it)."""
    master, slave = pty.openpty()
    env = {**os.environ, "COLUMNS": "80", "LINES": "50", "TERM": "xterm"}
    proc = subprocess.Popen([sys.executable, "-m", "ecattool", *args], stdout=slave, stderr=subprocess.DEVNULL,
                            stdin=subprocess.DEVNULL, env=env, cwd=ROOT)
    os.close(slave)
    chunks = []
    while True:
        try:
            chunk = os.read(master, 65536)
        except OSError:  # the child closed the terminal
            break
        if not chunk:
            break
        chunks.append(chunk)
    assert proc.wait(timeout=60) == 0
    os.close(master)
    text = re.sub(r"\x1b\[[0-9;?]*[a-zA-Z]", "", b"".join(chunks).decode("utf-8", "replace"))
    assert max(len(line) for line in text.splitlines()) <= 80
    return text


def test_tables_keep_identifiers_whole_at_80_columns() -> None:
    out = _at_80_columns("scale", "compute", "samples/scaling/ballscrew.yaml")
    assert "…" not in out
    for hex_value in ("0x000007D0", "0x608F:01", "0x6092:02"):
        assert hex_value in out, out
    elmo = corpus_path("esi", "elmo_Elmo_ECAT_00010420_V11.xml")
    out = _at_80_columns("esi", "devices", str(elmo))
    # the four Elmo devices differ only in product code and revision: both stay readable
    for code in ("0x00030924", "0x00030925", "0x00000001", "0x00010420"):
        assert code in out, out
