"""Mutated real files through every command that reads a file: a result or one located line, never a raw
exception (issues 23.2 and 28.5; the entries and mutations are in tests/fuzz_readers.py).

A few examples per entry here (the suite's budget); the long run is ``python3 scripts/fuzz.py --examples 2000``
(ECATTOOL_FUZZ_EXAMPLES sets the count, and then the examples are random rather than the suite's fixed ones).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings


from tests.conftest import CORPUS, need_corpus
from tests.fuzz_readers import ENTRIES, Entry, check, mutants, place, workdir

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
    from tests.fuzz_readers import invoke, seed_bytes

    for entry in ENTRIES:
        for seed in entry.seeds:
            path = place(work, entry, seed, seed_bytes(seed))
            sw = CORPUS
            argv = [a.format(f=path, o=work / "fuzz-output", sw=sw / "sw" / "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.sw",
                             script=work / "steps.yaml") for a in entry.argv]
            code, out, err, escaped = invoke(argv)
            assert escaped is None and (code == 0 or entry.reporter and code in (0, 1)), f"{argv}: {code} {err}{out[-500:]}"


