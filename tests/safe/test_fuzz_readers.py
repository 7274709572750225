"""Mutated real files through every command that reads a file: a result or one located line, never a raw
exception (issues 23.2 and 28.5; the entries and mutations are in tests/safe/fuzz_readers.py).

A few examples per entry here (the suite's budget); the long run is ``python3 scripts/fuzz.py --examples 2000``
(ECATTOOL_FUZZ_EXAMPLES sets the count, and then the examples are random rather than the suite's fixed ones).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings


from tests.conftest import CORPUS, need_corpus
from tests.safe.fuzz_readers import (
    ENTRIES,
    INPUT_KINDS,
    PATH_KINDS,
    Entry,
    check,
    check_named_path,
    check_output_path,
    hostile_paths,
    mutants,
    place,
    seed_bytes,
    workdir,
)

need_corpus()  # the seeds are corpus files and samples that name them

EXAMPLES = int(os.environ.get("ECATTOOL_FUZZ_EXAMPLES", "12"))
LONG_RUN = "ECATTOOL_FUZZ_EXAMPLES" in os.environ


@pytest.fixture(scope="module")
def work(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return workdir(tmp_path_factory.mktemp("fuzz"))


@pytest.fixture(autouse=True)
def _own_cache(monkeypatch: pytest.MonkeyPatch, tmp_path_factory: pytest.TempPathFactory) -> None:
    monkeypatch.setenv("ECATTOOL_CACHE_DIR", str(tmp_path_factory.getbasetemp() / "fuzz-cache"))


def _id(entry: Entry) -> str:
    return "-".join(entry.name.replace("(", "").replace(")", "").split())


@pytest.mark.parametrize("entry", ENTRIES, ids=_id)
def test_mutated_input_gives_a_result_or_one_located_line(entry: Entry, work: Path) -> None:
    @settings(max_examples=EXAMPLES, deadline=None, derandomize=not LONG_RUN, database=None,
              suppress_health_check=list(HealthCheck))
    @given(case=mutants(entry))
    def run(case: tuple[str, bytes]) -> None:
        seed, data = case
        check(entry, place(work, entry, seed, data), work)

    run()


def test_the_seeds_themselves_pass(work: Path) -> None:
    """Unmutated, every seed is a valid input of its entry (else the fuzzing would only test error paths)."""
    from tests.safe.fuzz_readers import invoke, seed_bytes

    for entry in ENTRIES:
        for seed in entry.seeds:
            path = place(work, entry, seed, seed_bytes(seed))
            sw = CORPUS
            argv = [a.format(f=path, o=work / "fuzz-output", sw=sw / "sw" / "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw",
                             script=work / "steps.yaml") for a in entry.argv]
            code, out, err, escaped = invoke(argv)
            assert escaped is None and (code == 0 or entry.reporter and code in (0, 1)), f"{argv}: {code} {err}{out[-500:]}"




# --------------------------------------------------------------------- hostile paths (issue 37.4 and 37.5)
@pytest.fixture
def hostile(tmp_path: Path):  # type: ignore[no-untyped-def]
    """:func:`hostile_paths` as a factory; the folders it made (under /tmp where tmp_path is too long for a socket
    name) are removed afterwards."""
    import shutil

    made: list[Path] = []

    def make() -> dict[str, Path]:
        paths = hostile_paths(tmp_path)
        made.append(paths["missing"].parent)
        return paths

    yield make
    for folder in made:
        shutil.rmtree(folder, ignore_errors=True)


@pytest.mark.parametrize("kind", INPUT_KINDS)
def test_every_reader_given_a_hostile_path(kind: str, work: Path, hostile) -> None:  # type: ignore[no-untyped-def]
    """A name too long, a directory, a device, a dangling link, a loop of links, a socket as a command's input:
    a result or one located line (``check``'s contract), never a traceback."""
    path = hostile()[kind]
    for entry in ENTRIES:
        check(entry, path, work)


@pytest.mark.parametrize("kind", PATH_KINDS)
def test_every_writer_given_a_hostile_output(kind: str, work: Path, hostile) -> None:  # type: ignore[no-untyped-def]
    """The same paths as ``-o``: a socket, a directory, a name too long are one line and never written; /dev/null
    is written through; a FIFO gets its data when someone reads it."""
    import threading

    for entry in (e for e in ENTRIES if "{o}" in e.argv):
        path = hostile()[kind]
        reader = None
        if kind == "fifo":  # someone reads it (else the writer waits for a reader, as `echo > FIFO` does)
            def drain(p: Path = path) -> None:
                with open(p, "rb") as fh:
                    fh.read()

            reader = threading.Thread(target=drain, daemon=True)
            reader.start()
        seed = place(work, entry, entry.seeds[0], seed_bytes(entry.seeds[0]))
        check_output_path(entry, kind, path, work, seed)
        if reader is not None:
            reader.join(60)


@pytest.mark.parametrize("kind", PATH_KINDS)
def test_a_project_naming_a_hostile_path(kind: str, work: Path, hostile) -> None:  # type: ignore[no-untyped-def]
    check_named_path(kind, hostile()[kind], work)
