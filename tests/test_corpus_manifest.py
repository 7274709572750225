"""The real-file corpus: its manifest (tests/corpus-manifest.json), `dev.py corpus`, and the one-line skip.

The manifest names every corpus file with its public origin and SHA-256; `scripts/dev.py corpus --check` compares
the corpus that is there with it, and `scripts/dev.py corpus` fetches what is missing (one line when it cannot).
Without the corpus the tests that need it skip, and pytest -rs says so in one line.
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path
from types import ModuleType


from tests.conftest import CORPUS, NO_CORPUS, REFERENCE, ROOT, corpus_path

MANIFEST = json.loads((ROOT / "tests" / "corpus-manifest.json").read_text(encoding="utf-8"))


def _dev() -> ModuleType:
    spec = importlib.util.spec_from_file_location("ecattool_dev_script", ROOT / "scripts" / "dev.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_entry_names_its_public_origin() -> None:
    entries = MANIFEST["files"]
    assert len({e["path"] for e in entries}) == len(entries) >= 90
    for e in entries:
        assert re.fullmatch(r"[\w.-]+/[\w.-]+", e["repository"]), e
        assert re.fullmatch(r"[0-9a-f]{40}", e["commit"]), e
        assert re.fullmatch(r"[0-9a-f]{64}", e["sha256"]), e
        assert e["source"] and not e["source"].startswith("/") and ".." not in e["source"].split("/"), e


def test_the_manifest_is_the_corpus() -> None:
    corpus_path()  # skips without the corpus
    files = {p.relative_to(CORPUS).as_posix() for p in CORPUS.rglob("*") if p.is_file() and p.name != "SOURCES.md"}
    assert files == {e["path"] for e in MANIFEST["files"]}
    assert _dev().check_corpus(CORPUS, MANIFEST["files"]) == []


def test_check_names_each_missing_or_changed_file(tmp_path: Path) -> None:
    source = corpus_path("sii")
    entries = [e for e in MANIFEST["files"] if e["path"] in ("sii/ni9144.bin", "sii/ni9144_rev1.bin", "sii/ni9144.xml")]
    (tmp_path / "sii").mkdir()
    shutil.copy(source / "ni9144.bin", tmp_path / "sii" / "ni9144.bin")
    changed = bytearray((source / "ni9144.xml").read_bytes())
    changed[100] ^= 1
    (tmp_path / "sii" / "ni9144.xml").write_bytes(bytes(changed))
    problems = _dev().check_corpus(tmp_path, entries)
    assert problems == [f"{tmp_path}/sii/ni9144.xml: SHA-256 differs from the manifest (not the file at "
                        f"DiamondLightSource/ethercat@b1c8fdd)", f"{tmp_path}/sii/ni9144_rev1.bin: missing"]


def test_fetch_without_a_network_stops_in_one_line(tmp_path: Path) -> None:
    dev = _dev()
    dev.RAW = "http://127.0.0.1:9/{repository}/{commit}/{source}"  # nothing listens on the discard port
    entry = MANIFEST["files"][0]
    stopped = dev.fetch_corpus(tmp_path, [entry])
    assert stopped is not None and "\n" not in stopped and entry["path"] in stopped and "ECATTOOL_CORPUS" in stopped
    assert not any(tmp_path.iterdir())  # nothing half-written
    # a file that is there and matches is not fetched again
    target = tmp_path / entry["path"]
    target.parent.mkdir(parents=True)
    data = corpus_path(entry["path"]).read_bytes()
    target.write_bytes(data)
    assert hashlib.sha256(data).hexdigest() == entry["sha256"] and dev.fetch_corpus(tmp_path, [entry]) is None


def test_without_the_corpus_its_tests_skip_in_one_line(tmp_path: Path) -> None:
    # the corpus missing, the manual extracts where they are (their absence would add itself to the one reason)
    env = {**os.environ, "ECATTOOL_CORPUS": str(tmp_path / "no-corpus"), "ECATTOOL_REFERENCE": str(REFERENCE)}
    env.pop("PYTEST_XDIST_WORKER", None)
    done = subprocess.run([sys.executable, "-m", "pytest", "-rs", "-p", "no:cacheprovider", "-n", "0",
                           "tests/sii/test_sii_crc.py", "tests/esi/test_esi_eds.py", "tests/scaling/test_scaling_model.py"],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout[-3000:]
    skipped = [line for line in done.stdout.splitlines() if line.startswith("SKIPPED")]
    reason = NO_CORPUS.replace(str(CORPUS), str(tmp_path / "no-corpus"))
    assert len(skipped) == 1 and skipped[0].endswith(reason), skipped
    count = int(re.search(r"SKIPPED \[(\d+)\]", skipped[0]).group(1))  # type: ignore[union-attr]
    assert count > 10 and re.search(rf"\b\d+ passed, {count} skipped", done.stdout), done.stdout[-500:]
