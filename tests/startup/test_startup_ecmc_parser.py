"""Issue 27: every ecmc export read by ecmc's own command parser patterns, not an imitation.

ecmc dispatches a ``Cfg.`` command in ``handleCfgCommand`` (ecmcCmdParser.c, ../shared/consumers/ecmc): one
``sscanf(myarg_1, "<pattern>", …)`` after the other, in file order, and runs the first whose conversions all
succeed. The test takes those patterns from the real file, compiles them into a small C program with the C
library's own ``sscanf``, and checks that each ``Cfg.`` line of an ecmc export is taken by the command it is meant
to be (with the script's macros expanded as iocsh does).
"""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

from ecattool.errors import EncodeError
from ecattool.esi.model import Identity
from ecattool.startup import export, import_file
from tests.conftest import ROOT, corpus_path

PARSER = ROOT.parent / "shared" / "consumers" / "ecmc" / "ecmcCmdParser.c"
_MAX_CONVERSIONS = 16


def _patterns() -> list[str]:
    text = PARSER.read_text(encoding="utf-8", errors="replace")
    body = text[text.index("static int handleCfgCommand(const char *myarg_1)"):]
    return [m.group(1) for m in re.finditer(r'sscanf\(\s*myarg_1,\s*"((?:[^"\\]|\\.)*)"', body)]


def _conversions(pattern: str) -> int:
    return len(re.findall(r"%(?!%)(?!\*)(?:\[[^\]]*\]|[-+ #0-9.hlLqjzt]*[diouxXeEfgGsc])", pattern.replace("%%", "")))


@pytest.fixture(scope="module")
def ecmc_parser(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[str]]:
    gcc = shutil.which("gcc")
    if gcc is None:
        pytest.skip("gcc is not installed: ecmc's parser patterns cannot be run here")
    if not PARSER.is_file():
        pytest.skip(f"ecmc's command parser is missing ({PARSER}; see ../shared/consumers/README.md)")
    patterns = [p for p in _patterns() if p.startswith("Ec") and _conversions(p) <= _MAX_CONVERSIONS]
    assert len(patterns) > 50 and any(p.startswith("EcAddSdo(") for p in patterns)
    out = tmp_path_factory.mktemp("ecmc")
    table = ",\n".join(f'  {{"{p}", {_conversions(p)}}}' for p in patterns)
    args = ", ".join(f"b[{i}]" for i in range(_MAX_CONVERSIONS))
    (out / "match.c").write_text(f"""#include <stdio.h>
#include <string.h>
static struct {{ const char *pattern; int count; }} patterns[] = {{
{table}
}};
static char b[{_MAX_CONVERSIONS}][8192] __attribute__((aligned(16)));
int main(void) {{
  static char line[1 << 16];
  while (fgets(line, sizeof line, stdin)) {{
    line[strcspn(line, "\\n")] = 0;
    int found = -1;
    for (size_t i = 0; i < sizeof patterns / sizeof patterns[0]; i++) {{
      if (sscanf(line, patterns[i].pattern, {args}) == patterns[i].count) {{ found = (int)i; break; }}
    }}
    printf("%d\\n", found);
  }}
  return 0;
}}
""")
    result = subprocess.run([gcc, "-w", "-O1", "-o", str(out / "match"), str(out / "match.c")],
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    return out / "match", patterns


def _commands(script: str) -> list[str]:
    """The Cfg. commands of a script as ecmc receives them: macros expanded (iocsh), without ``Cfg.``."""
    env = {"ECMC_EC_SLAVE_NUM": "7", "ECMC_TEMP_PERIOD_NANO_SECS": "1000000", "ECMC_EC_VENDOR_ID": "0x2",
           "ECMC_EC_PRODUCT_ID": "0x3"}
    out = []
    for line in script.splitlines():
        m = re.match(r'\s*epicsEnvSet\("(\w+)"\s*"([^"]*)"\)', line)
        if m:
            env[m.group(1)] = m.group(2)
        m = re.match(r'\s*ecmcConfig(?:OrDie)?\s+"Cfg\.([^"]*)"', line)
        if m:
            out.append(re.sub(r"\$\{(\w+)\}", lambda x: env[x.group(1)], m.group(1)))
    return out


def _check(ecmc_parser, script: str) -> int:
    binary, patterns = ecmc_parser
    commands = _commands(script)
    if not commands:
        return 0
    result = subprocess.run([str(binary)], input="\n".join(commands) + "\n", capture_output=True, text=True)
    taken = [int(x) for x in result.stdout.split()]
    assert len(taken) == len(commands)
    for cmd, i in zip(commands, taken):
        assert i >= 0, f"no pattern of ecmc's parser takes {cmd!r}"
        assert patterns[i].split("(")[0] == cmd.split("(")[0], f"{cmd!r} is taken as {patterns[i]!r}"
    return len(commands)


def _configs():
    from ecattool.project.export import slave_configs

    for p in sorted(corpus_path("configs").iterdir()):
        if p.name in ("hwdevmgr_device_config.yaml", "ecmc_ecmciPOS4808.cmd"):
            continue
        yield p.name, import_file(p)
    for project in sorted((ROOT / "samples").glob("*/project.yaml")):
        yield project.parent.name, slave_configs(project)


def test_every_ecmc_export_is_taken_by_ecmcs_own_parser(ecmc_parser):
    counted = {}
    for name, configs in _configs():
        for c in configs:
            c.identity = c.identity or Identity(0x1A3, 0x019F418D)
        try:
            counted[name] = _check(ecmc_parser, export(configs, "ecmc", lossy=True))
        except EncodeError as exc:  # what ecmc has no form for is refused, with the command named
            assert "ecmc" in exc.message or "one-shot write" in exc.message, exc
    print(f"ecmc lines taken by ecmcCmdParser.c's patterns: {counted}")
    assert len(counted) >= 15 and sum(counted.values()) > 1500


def test_real_entries_sync1_and_one_shots_are_forms_ecmc_takes(ecmc_parser):
    from ecattool.esi.model import Direction, Pdo, PdoEntry
    from ecattool.startup import SlaveConfig, StartupCommand, StartupList

    cfg = SlaveConfig(StartupList([StartupCommand("PS", 0x2064, 0, (0x7B780008).to_bytes(4, "little"), once=True),
                                   StartupCommand("PS", 0x2080, 0, b"\x01\x00", expect_reply=False)]),
                      name="x", position=0, identity=Identity(2, 3), dc_assign_activate=0x0700, dc_cycle_ns=1_000_000,
                      dc_sync1_cycle_ns=500_000, dc_sync1_shift_ns=1000,
                      rx_pdos=[Pdo(Direction.RX, 0x1600, "rx", [PdoEntry(0x7000, 1, 32, "Value", "REAL")])])
    text = export(cfg, "ecmc")
    assert "Cfg.EcAddEntryDT(0,${ECMC_EC_VENDOR_ID},${ECMC_EC_PRODUCT_ID},1,2,0x1600,0x7000,0x1,F32,Value)" in text
    assert _check(ecmc_parser, text) == 4
