"""``ecattool project new``: the skeleton of every built-in product and every corpus drive ESI lints without
errors and commissions on the simulator; bad names are refused before anything is written."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
import yaml

from ecattool import profiles
from ecattool.commission import commission
from ecattool.findings import Severity
from ecattool.project.machine import load_machine
from tests.conftest import corpus_path, run

PRODUCTS = [(p.name, prod.name) for p in profiles.list_profiles() for prod in p.products]
#: (file, selector, flaws) of every CoE drive ESI of the corpus; Elmo's file starts with boot devices. flaws:
#: PDO entries of the default mapping whose object the ESI's own dictionary lacks (Synapticon 607A:04 and
#: 60FF:05 where 607Ah/60FFh are VARs; AX2000's fixed 1702h/1B03h map 606Bh/6077h, never listed) and init commands
#: the ESI's own dictionary refuses (AX2000: 6060h read-only, 60C2h:01/02 not listed)
ESIS = [("elmo_Elmo_ECAT_00010420_V11.xml", "2", 0), ("inovance_SV660_EOE_1Axis_V9.12.xml", None, 0),
        ("ingenia_eve-xcr-e_esi.xml", None, 0), ("copley_XE2_4.60.xml", None, 0),
        ("synapticon_Somanet_CiA402-single.xml", None, 2), ("beckhoff_AX2xxx.xml", None, 5),
        ("etg_ETG2001_ModulesSlots_CiA402.xml", None, 0)]


def _errors(path: Path) -> list[str]:
    return [str(f) for f in load_machine(path).findings if f.severity is Severity.ERROR]


def _check(capsys, path: Path, *args: str, flaws: int = 0) -> dict:
    code, _, err = run(capsys, "project", "new", *args, "-o", str(path))
    assert code == 0, err
    errors = _errors(path)
    # the vendor file's flaws, each at its ESI line: PDO entries its dictionary lacks, init commands it refuses
    assert len(errors) == flaws and all("[esi-pdo-object-missing]" in e or ".xml:" in e and "[PRJ021]" in e
                                        for e in errors), errors
    text = path.read_text()
    assert ("    # disable_rules:\n" in text) is bool(flaws)  # the skeleton points the vendor file's flaws out
    assert ("    # esi_init_cmds:\n" in text) is any("[PRJ021]" in e for e in errors)
    if flaws:  # refused until the flaw is accepted knowingly: uncomment what the skeleton proposes
        assert not commission(path).ok
        path.write_text(text.replace("    # disable_rules:", "    disable_rules:").replace("    #   - {rule", "      - {rule")
                        .replace("    # esi_init_cmds:", "    esi_init_cmds:").replace("    #   - {object", "      - {object"))
        assert _errors(path) == []
    report = commission(path)
    assert report.ok, [s.detail for d in report.drives for s in d.steps if not s.ok]
    return yaml.safe_load(path.read_text())


@pytest.mark.parametrize(("profile", "product"), PRODUCTS, ids=[f"{a}-{b}" for a, b in PRODUCTS])
def test_every_built_in_product_gets_a_skeleton_that_lints_and_commissions(capsys, tmp_path, profile, product):
    data = _check(capsys, tmp_path / "m.yaml", "--profile", profile, "--product", product)
    drive = data["drives"][0]
    modes = profiles.rules_for(profiles.load(profile, product)).supported_modes
    if 1 in modes:  # profile position: the skeleton asks for a PP move, and it happened
        assert drive["move"] == {"distance": 1}
        assert {"object": "6060:00", "value": 1, "comment": "profile position mode"} in drive["parameters"]
    else:  # Control Techniques drives have no PP mode: no move the drive would refuse
        assert "move" not in drive and "parameters" not in drive
        text = (tmp_path / "m.yaml").read_text()
        assert "has no profile position mode" in text
        # a CSP move is proposed only to a drive that has CSP (Commander SK and Affinity have vl and tq only)
        assert ("mode: csp" in text) is (8 in modes), text


@pytest.mark.parametrize(("name", "select", "flaws"), ESIS, ids=[e[0].split("_")[0] for e in ESIS])
def test_every_corpus_drive_esi_gets_a_skeleton_that_lints_and_commissions(capsys, tmp_path, name, select, flaws):
    shutil.copy(corpus_path("esi", name), tmp_path / name)
    sub = tmp_path / "machine"
    sub.mkdir()
    # the ESI path is relative to where the project will be, as the project file reads it
    data = _check(capsys, sub / "m.yaml", "--esi", f"../{name}", *(["--select", select] if select else []),
                  flaws=flaws)
    assert data["drives"][0]["device"]["esi"] == f"../{name}"


def test_profile_velocity_is_set_only_where_the_esi_leaves_it_zero(capsys, tmp_path):
    for name, wanted in (("ingenia_eve-xcr-e_esi.xml", True), ("inovance_SV660_EOE_1Axis_V9.12.xml", False)):
        shutil.copy(corpus_path("esi", name), tmp_path / name)
        data = _check(capsys, tmp_path / f"{name}.yaml", "--esi", name)
        objects = [p["object"] for p in data["drives"][0].get("parameters", [])]
        assert ("6081:00" in objects) is wanted, objects


def test_a_name_yaml_would_misread_is_quoted(capsys, tmp_path):
    data = _check(capsys, tmp_path / "m.yaml", "--profile", "hdt", "--name", "x: 1 # no")
    assert data["drives"][0]["name"] == "x: 1 # no"
    data = _check(capsys, tmp_path / "n.yaml", "--profile", "hdt", "--name", "yes")
    assert data["drives"][0]["name"] == "yes"


@pytest.mark.parametrize(("args", "words"), [
    (["--profile", "bogus"], "unknown drive profile 'bogus'"),
    (["--profile", "hdt", "--product", "nope"], "no product 'nope'"),
    (["--esi", "missing.xml"], "missing.xml"),
    (["--esi", "drive.xml", "--select", "0x12345678"], "0x12345678"),
])
def test_a_device_that_does_not_resolve_writes_nothing(capsys, tmp_path, args, words):
    shutil.copy(corpus_path("esi", "copley_XE2_4.60.xml"), tmp_path / "drive.xml")
    out = tmp_path / "m.yaml"
    code, stdout, err = run(capsys, "project", "new", *args, "-o", str(out))
    assert code == 1 and not out.exists()
    assert len(err.strip().splitlines()) == 1 and words in err and "Traceback" not in err


def test_esi_flaws_in_pdos_the_mapping_does_not_use_are_warnings(tmp_path):
    """AX2000: 38 PDO entries name objects its dictionary lacks; the default mapping uses 2 of those PDOs."""
    shutil.copy(corpus_path("esi", "beckhoff_AX2xxx.xml"), tmp_path / "ax.xml")
    p = tmp_path / "m.yaml"
    p.write_text("ecattool: 1\ndrives:\n  - name: a\n    device: {esi: ax.xml}\n")
    found = [f for f in load_machine(p).findings if f.rule == "esi-pdo-object-missing"]
    errors = [f for f in found if f.severity is Severity.ERROR]
    warnings = [f for f in found if f.severity is Severity.WARNING]
    assert sorted(f.data["pdo"] for f in errors) == [0x1702, 0x1B03]
    assert len(warnings) == 36 and all("does not use" in f.message for f in warnings)
    assert {f.data["pdo"] for f in warnings}.isdisjoint({0x1702, 0x1B03})
