"""``ecattool lint`` on the command line: text, JSON, SARIF 2.1.0 (required properties checked), GitHub
annotations, --strict, exit codes 0/1/2, and the content-keyed ESI cache (pickle reused, damaged entry rebuilt)."""

from __future__ import annotations

import json

import pickle
import re
from pathlib import Path

import pytest

from ecattool.project import cache
from ecattool.project.machine import load_machine
from tests.conftest import corpus_path
from tests.project.project_helpers import BELT_PROJECT, DATA, SAMPLES, run, run_json, sample, write_project

BROKEN = str(DATA / "prj010_no_object.yaml")  # two errors
WARN_ONLY = str(DATA / "prj015_enum.yaml")  # one warning


# --- exit codes and --strict ------------------------------------------------------------------------------

def test_clean_samples_exit_0(capsys):
    code, out, _ = run(capsys, "lint", *(str(sample(n)) for n in SAMPLES))
    assert code == 0
    assert out.count("0 error(s), 0 warning(s)") == 4


def test_errors_exit_1_with_located_lines(capsys):
    code, out, _ = run(capsys, "lint", BROKEN)
    assert code == 1
    assert f"{BROKEN}:7:18: error: object 0x5FFF does not exist" in out
    assert f"{BROKEN}:8:18: error: no object named 'warp factor'" in out and out.rstrip().endswith("2 error(s), 0 warning(s)")


def test_warnings_pass_unless_strict(capsys):
    assert run(capsys, "lint", WARN_ONLY)[0] == 0
    code, out, _ = run(capsys, "lint", "--strict", WARN_ONLY)
    assert code == 1 and "[PRJ015]" in out


def test_infos_do_not_fail_strict(capsys, tmp_path):
    p = write_project(tmp_path, BELT_PROJECT)
    assert run(capsys, "lint", "--strict", str(p))[0] == 0


def test_usage_errors_exit_2(capsys):
    assert run(capsys, "lint")[0] == 2
    assert run(capsys, "lint", "--format", "xml", WARN_ONLY)[0] == 2


def test_unreadable_project_exits_1(capsys, tmp_path):
    p = write_project(tmp_path, "ecattool: 2\ndrives: []\n")
    code, out, _ = run(capsys, "lint", str(p))
    assert code == 1 and f"{p}:1:11: error: unsupported project format version 2" in out
    missing = tmp_path / "nope.yaml"
    code, out, err = run(capsys, "lint", str(missing))
    assert code == 1 and "nope.yaml" in out + err


def test_several_projects_fail_if_one_fails(capsys):
    assert run(capsys, "lint", str(sample("hdt")), BROKEN)[0] == 1


# --- formats ----------------------------------------------------------------------------------------------

def test_json_format(capsys):
    code, doc = run_json(capsys, "lint", "--format", "json", BROKEN, WARN_ONLY)
    assert code == 1
    assert doc["files"] == [BROKEN, WARN_ONLY]
    assert doc["summary"] == {"error": 2, "warning": 1, "info": 0}
    rules = [(f["rule"], f["severity"]) for f in doc["findings"]]
    assert rules == [("PRJ010", "error"), ("PRJ010", "error"), ("PRJ015", "warning")]
    first = doc["findings"][0]
    assert "0x5FFF" in first["message"]
    assert run_json(capsys, "lint", "--json", WARN_ONLY) == (0, run_json(capsys, "lint", "--format", "json", WARN_ONLY)[1])


def _check_sarif(log: dict) -> None:
    """The properties SARIF 2.1.0 requires (sarif-schema-2.1.0.json), and the consistency of rule indexes."""
    assert log["version"] == "2.1.0" and isinstance(log["runs"], list) and log["runs"]
    assert log["$schema"].endswith("sarif-2.1.0.json")
    for r in log["runs"]:
        driver = r["tool"]["driver"]
        assert isinstance(driver["name"], str) and driver["name"]
        rules = driver.get("rules", [])
        ids = [x["id"] for x in rules]
        assert len(ids) == len(set(ids))
        for rule in rules:
            assert isinstance(rule["id"], str) and isinstance(rule["shortDescription"]["text"], str)
        for res in r["results"]:
            assert isinstance(res["message"]["text"], str) and res["message"]["text"]
            assert res["level"] in ("none", "note", "warning", "error")
            assert rules[res["ruleIndex"]]["id"] == res["ruleId"]
            for loc in res.get("locations", []):
                phys = loc["physicalLocation"]
                uri = phys["artifactLocation"]["uri"]
                assert isinstance(uri, str) and uri and "\\" not in uri
                region = phys.get("region", {})
                assert region.get("startLine", 1) >= 1 and region.get("startColumn", 1) >= 1


def test_sarif_format(capsys, tmp_path):
    out = tmp_path / "lint.sarif"
    code, _, _ = run(capsys, "lint", "--format", "sarif", "-o", str(out), BROKEN, WARN_ONLY)
    assert code == 1
    import json

    log = json.loads(out.read_text())
    _check_sarif(log)
    results = log["runs"][0]["results"]
    assert [(r["ruleId"], r["level"]) for r in results] == [("PRJ010", "error"), ("PRJ010", "error"), ("PRJ015", "warning")]
    region = results[0]["locations"][0]["physicalLocation"]["region"]
    assert region == {"startLine": 7, "startColumn": 18}
    assert results[0]["locations"][0]["physicalLocation"]["artifactLocation"]["uri"].endswith(
        "tests/data/projects/prj010_no_object.yaml")
    rules = {r["id"]: r["shortDescription"]["text"] for r in log["runs"][0]["tool"]["driver"]["rules"]}
    assert rules["PRJ010"] == "a parameter names an object that does not exist"


def test_sarif_describes_pdo_and_esi_rules_and_invents_no_web_addresses(capsys, tmp_path):
    import shutil

    from ecattool.pdo.check import RULES as PDO_RULES
    from ecattool.project.lint import rule_descriptions

    shutil.copy(corpus_path("esi", "beckhoff_AX2xxx.xml"), tmp_path / "ax.xml")
    p = tmp_path / "m.yaml"  # esi-pdo-object-missing, and a PDO rule (an 80-bit Technosoft PDO)
    p.write_text("ecattool: 1\ndrives:\n  - name: a\n    device: {esi: ax.xml}\n  - name: b\n"
                 "    device: {profile: technosoft-ipos}\n    pdo:\n      rx: [{index: 0x1600, entries: "
                 "['0x6040:00/16', '0x607A:00/32', '0x60FF:00/32']}]\n")
    code, log = run_json(capsys, "lint", "--format", "sarif", str(p))
    _check_sarif(log)
    rules = {r["id"]: r["shortDescription"]["text"] for r in log["runs"][0]["tool"]["driver"]["rules"]}
    assert rules["esi-pdo-object-missing"].startswith("a PDO entry names an object")
    assert any(k.startswith("PDO") for k in rules) and all(rules[k] == PDO_RULES[k][1] for k in rules if k.startswith("PDO"))
    assert all(text != rid for rid, text in rules.items())
    assert set(rule_descriptions()) >= set(PDO_RULES)
    assert "ecattool.dev" not in json.dumps(log) and "Uri" not in json.dumps(log["runs"][0]["tool"])


def test_sarif_of_a_clean_project_is_valid_and_empty(capsys):
    code, log = run_json(capsys, "lint", "--format", "sarif", str(sample("hdt")))
    assert code == 0
    _check_sarif(log)
    assert log["runs"][0]["results"] == []


def test_github_annotations(capsys):
    code, out, _ = run(capsys, "lint", "--format", "github", BROKEN, WARN_ONLY)
    assert code == 1
    lines = out.splitlines()
    assert len(lines) == 3
    pattern = re.compile(r"^::(error|warning|notice) file=([^,]+),line=(\d+),col=(\d+),title=([A-Z]+\d+)::(.+)$")
    parsed = [pattern.match(line) for line in lines]
    assert all(parsed), lines
    assert [(m[1], m[3], m[4], m[5]) for m in parsed] == [("error", "7", "18", "PRJ010"), ("error", "8", "18", "PRJ010"),
                                                         ("warning", "7", "36", "PRJ015")]
    assert parsed[0][2].endswith("tests/data/projects/prj010_no_object.yaml")


def test_text_to_file(capsys, tmp_path):
    out = tmp_path / "lint.txt"
    assert run(capsys, "lint", "-o", str(out), BROKEN)[0] == 1
    text = out.read_text()
    assert "[PRJ010]" in text and "2 error(s)" in text


# --- the ESI cache ----------------------------------------------------------------------------------------

ESI_PROJECT = sample("generic_esi")


def fresh_process(monkeypatch) -> None:
    """Forget what this process has cached in memory, as a new `ecattool lint` process would."""
    for name in ("_MEMORY", "_DEVICES", "_CHECKS", "_PROFILES", "_DIGESTS"):
        monkeypatch.setattr(cache, name, {})


@pytest.fixture()
def cache_dir(tmp_path, monkeypatch):
    d = tmp_path / "cache"
    monkeypatch.setenv("ECATTOOL_CACHE_DIR", str(d))
    monkeypatch.delenv("ECATTOOL_NO_CACHE", raising=False)
    fresh_process(monkeypatch)
    return d


def _entries(d: Path, kind: str) -> list[Path]:
    return sorted((d / kind).glob("*.pickle"))


def test_second_lint_reads_the_pickles(cache_dir, monkeypatch):
    first = load_machine(ESI_PROJECT)
    (device_entry,) = _entries(cache_dir, "device")
    (check_entry,) = _entries(cache_dir, "check")
    assert len(device_entry.stem) == 64  # a SHA-256
    assert type(pickle.loads(device_entry.read_bytes())).__name__ == "RunningDevice"
    assert _inovance_checks(pickle.loads(check_entry.read_bytes()))
    # a fresh process: nothing in memory, and reading the ESI or completing the device is not allowed any more
    fresh_process(monkeypatch)
    from ecattool import esi
    from ecattool.profiles import running

    def no_parse(*a, **k):
        raise AssertionError("the ESI was parsed (or the device completed) again instead of read from the cache")

    monkeypatch.setattr(esi, "load_bytes", no_parse)
    monkeypatch.setattr(esi, "check_structure", no_parse)
    monkeypatch.setattr(running, "complete_generic", no_parse)
    second = load_machine(ESI_PROJECT)
    assert second.findings == first.findings == ()
    assert second.slaves[0].device.product_code == first.slaves[0].device.product_code
    assert _entries(cache_dir, "device") == [device_entry] and _entries(cache_dir, "check") == [check_entry]


def _inovance_checks(findings: object) -> bool:
    """The structural findings of the Inovance ESI: only its 1702h, whose DefaultData maps 60B8h where its
    RxPdo element maps 60FFh (issue 35 item 7), a PDO the sample project does not use (lint leaves it out)."""
    return isinstance(findings, list) and [(f.rule, f.data.get("pdo")) for f in findings] == [
        ("esi-pdo-default-differs", 0x1702)]


def test_cached_esi_findings_keep_their_locations(cache_dir, monkeypatch, tmp_path):
    esi = corpus_path("esi", "synapticon_Somanet_CiA402-single.xml")
    p = write_project(tmp_path, f"ecattool: 1\ndrives:\n  - name: s\n    device: {{esi: {esi}}}\n")
    first = load_machine(p).findings
    fresh_process(monkeypatch)
    second = load_machine(p).findings
    assert second == first and any(f.location.line == 898 for f in second)


@pytest.mark.parametrize("kind, check", [("device", lambda o: type(o).__name__ == "RunningDevice"),
                                         ("check", lambda o: _inovance_checks(o))])
def test_damaged_cache_entry_is_rebuilt(cache_dir, monkeypatch, kind, check):
    load_machine(ESI_PROJECT)
    (entry,) = _entries(cache_dir, kind)
    good = entry.read_bytes()
    entry.write_bytes(b"not a pickle at all")
    fresh_process(monkeypatch)
    result = load_machine(ESI_PROJECT)
    assert result.findings == () and result.slaves[0].device is not None
    assert entry.read_bytes() != b"not a pickle at all"
    assert check(pickle.loads(entry.read_bytes())) and len(entry.read_bytes()) == len(good)


@pytest.mark.parametrize("kind, check", [("device", lambda o: type(o).__name__ == "RunningDevice"),
                                         ("check", lambda o: _inovance_checks(o))])
def test_foreign_pickle_is_not_trusted(cache_dir, monkeypatch, kind, check):
    load_machine(ESI_PROJECT)
    (entry,) = _entries(cache_dir, kind)
    entry.write_bytes(pickle.dumps({"not": "what the cache wrote"}))
    fresh_process(monkeypatch)
    assert load_machine(ESI_PROJECT).slaves[0].device is not None
    assert check(pickle.loads(entry.read_bytes()))


def test_changed_esi_content_is_a_new_entry(cache_dir, tmp_path):
    src = ESI_PROJECT.parent
    dst = tmp_path / "proj"
    dst.mkdir()
    (dst / "project.yaml").write_text(ESI_PROJECT.read_text())
    xml = (src / "inovance_SV660_EOE_1Axis_V9.12.xml").read_bytes()
    (dst / "inovance_SV660_EOE_1Axis_V9.12.xml").write_bytes(xml)
    load_machine(dst / "project.yaml")
    (dst / "inovance_SV660_EOE_1Axis_V9.12.xml").write_bytes(xml + b"\n<!-- edited -->\n")
    load_machine(dst / "project.yaml")
    assert len(_entries(cache_dir, "check")) == 2 and len(_entries(cache_dir, "device")) == 2


def test_no_cache_env_writes_nothing(cache_dir, monkeypatch):
    monkeypatch.setenv("ECATTOOL_NO_CACHE", "1")
    assert load_machine(ESI_PROJECT).findings == ()
    assert not cache_dir.exists()



def test_a_changed_dictionary_file_invalidates_the_esi_entries(cache_dir, tmp_path):
    # an ESI whose dictionary lives in another file (DictionaryFile): editing that file must not reuse the
    # device completed from the old one
    d = tmp_path / "proj"
    d.mkdir()
    esi = d / "device.xml"
    esi.write_text("""<?xml version="1.0"?>
<EtherCATInfo><Vendor><Id>#x2</Id><Name>V</Name></Vendor><Descriptions><Groups><Group><Type>G</Type><Name>G</Name></Group></Groups>
<Devices><Device><Type ProductCode="#x10" RevisionNo="#x1">Dev</Type><Name>Dev</Name><GroupType>G</GroupType>
<Sm StartAddress="#x1000" ControlByte="#x26" Enable="1">MBoxOut</Sm><Sm StartAddress="#x1400" ControlByte="#x22" Enable="1">MBoxIn</Sm>
<Mailbox><CoE/></Mailbox>
<Profile><DictionaryFile>dict.xml</DictionaryFile></Profile></Device></Devices></Descriptions></EtherCATInfo>
""")
    p = write_project(d, "ecattool: 1\ndrives:\n  - name: a\n    device: {esi: device.xml}\n")
    load_machine(p)
    assert len(_entries(cache_dir, "device")) == 1
    (d / "dict.xml").write_text("<Dictionary/>\n")
    cache._DIGESTS.clear()
    cache._DEVICES.clear()
    load_machine(p)
    assert len(_entries(cache_dir, "device")) == 2


def test_changed_reader_code_is_a_new_entry(cache_dir, monkeypatch, tmp_path):
    """A development checkout whose esi/od/profiles code changed since an entry was written (same version, same
    model fields) must not be served the device the old code parsed."""
    load_machine(ESI_PROJECT)
    assert len(_entries(cache_dir, "device")) == 1
    # the digest follows the code: one changed byte in a copy of the packages gives another digest
    copy = tmp_path / "pkg"
    for part in ("esi", "od"):
        for f in (cache.PACKAGE / part).glob("*.py"):
            (copy / part).mkdir(parents=True, exist_ok=True)
            (copy / part / f.name).write_bytes(f.read_bytes())
    before = cache.code_digest(copy, ("esi", "od"))
    assert cache.code_digest(copy, ("esi", "od")) == before
    reader = copy / "esi" / "reader.py"
    reader.write_bytes(reader.read_bytes() + b"\n# changed\n")
    after = cache.code_digest(copy, ("esi", "od"))
    assert after != before
    # another code digest: the entries written before are not read, new ones are written beside them
    fresh_process(monkeypatch)
    monkeypatch.setattr(cache, "_code", lambda: after)
    from ecattool.profiles import running

    completed = []
    real = running.complete_generic
    monkeypatch.setattr(running, "complete_generic", lambda *a, **k: completed.append(1) or real(*a, **k))
    assert load_machine(ESI_PROJECT).findings == ()
    assert completed and len(_entries(cache_dir, "device")) == 2 and len(_entries(cache_dir, "check")) == 2
