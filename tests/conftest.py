"""Shared fixtures, and the one way a test finds the real-file corpus.

The corpus (third-party files, listed with their public origin and SHA-256 in tests/corpus-manifest.json) is at
``$ECATTOOL_CORPUS`` or ``../shared/corpus`` beside the checkout; the manual extracts are at ``$ECATTOOL_REFERENCE``
or beside the corpus (``../shared/reference``). A test that needs either reaches it through :func:`corpus_path`,
the ``corpus`` fixture, :func:`reference_path` or the ``corpus`` marker (for tests that read it indirectly, e.g.
through samples/sw/build.yaml). Where it is missing, those tests skip from one place with one reason, so
``pytest -rs`` prints one line with their count, why and how to get the corpus, and everything else runs.
CI (.ci/run) refuses to start without the corpus, so there it is never skipped.
"""

from __future__ import annotations

import os
from pathlib import Path
from collections.abc import Callable
from typing import Any, NoReturn

import pytest
from hypothesis import HealthCheck, settings

ROOT = Path(__file__).resolve().parent.parent
CORPUS = Path(os.environ.get("ECATTOOL_CORPUS") or ROOT.parent / "shared" / "corpus")
REFERENCE = Path(os.environ.get("ECATTOOL_REFERENCE") or CORPUS.parent / "reference")
#: the reason every corpus test gives when it skips (one line in ``pytest -rs``)
NO_REFERENCE = (f"the manual extracts are not at {REFERENCE} (they come with the corpus beside the checkout, "
                "../shared/reference; set ECATTOOL_REFERENCE=DIR)")
NO_CORPUS = (f"the real-file corpus is not at {CORPUS}: set ECATTOOL_CORPUS=DIR, or fetch it with "
             "`python3 scripts/dev.py corpus` (origins in tests/corpus-manifest.json)"
             # in a fresh clone neither is there: one reason (one -rs line) for both
             + ("" if REFERENCE.is_dir() else f"; {NO_REFERENCE}"))

settings.register_profile(
    "ci", max_examples=60, deadline=None, derandomize=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
settings.load_profile("ci")


def have_corpus() -> bool:
    return CORPUS.is_dir()


def need_corpus() -> None:
    """Skip the calling test (or, at import time, its whole module) when the corpus is missing."""
    if not have_corpus():
        _skip(NO_CORPUS)


def _skip(reason: str) -> NoReturn:
    # one place raises every such skip, so that pytest folds them into one line of its -rs summary
    raise pytest.skip.Exception(reason, allow_module_level=True)


_HERE = str(Path(__file__).relative_to(ROOT)) if Path(__file__).is_relative_to(ROOT) else __file__
_SKIP_LINE = _skip.__code__.co_firstlineno + 2  # the line of the raise above, as pytest reports it (1-based)


def corpus_path(*parts: str) -> Path:
    """A file or folder of the corpus; skips when the corpus is missing, fails when only this file is."""
    need_corpus()
    p = CORPUS.joinpath(*parts)
    if not p.exists():
        raise FileNotFoundError(f"corpus file missing: {p} (compare with `python3 scripts/dev.py corpus --check`)")
    return p


def corpus_files(*patterns: str, form: str = "path", keep: Callable[[Path], bool] = lambda p: True) -> list[Any]:
    """The corpus files matching ``patterns`` (``"sii/*.bin"``), sorted per pattern, for ``parametrize``: as paths,
    ``form="name"`` file names or ``form="str"`` strings. Without the corpus: one parameter that skips (with the
    corpus reason), so that a module can list its cases at import time and still run its other tests."""
    if not have_corpus():
        return [pytest.param(CORPUS / "missing", marks=pytest.mark.skip(reason=NO_CORPUS), id="no-corpus")]
    out: list[Any] = []
    for pattern in patterns:
        sub, _, glob = pattern.rpartition("/")
        found = sorted(p for p in CORPUS.joinpath(sub).glob(glob) if keep(p))
        out += [p.name if form == "name" else str(p) if form == "str" else p for p in found]
    return out


def reference_path(*parts: str) -> Path:
    """A file of the manual extracts (../shared/reference); skips when they are missing."""
    if not REFERENCE.is_dir():
        _skip(NO_REFERENCE if have_corpus() else NO_CORPUS)
    p = REFERENCE.joinpath(*parts)
    if not p.exists():
        raise FileNotFoundError(f"reference file missing: {p}")
    return p


SEEDS = Path(os.environ.get("ECATTOOL_SEEDS") or CORPUS.parent / "seeds")


def seeds_path(*parts: str) -> Path:
    """A file of the manuals' seed texts (../shared/seeds); skips when they are missing, like the corpus."""
    if not SEEDS.is_dir():
        _skip(NO_CORPUS if not have_corpus() else f"the manuals' seed texts are not at {SEEDS} (set ECATTOOL_SEEDS=DIR)")
    p = SEEDS.joinpath(*parts)
    if not p.exists():
        raise FileNotFoundError(f"seed file missing: {p}")
    return p


def sample_sw_spec(directory: Path) -> Path:
    """samples/sw/build.yaml copied into ``directory`` with its corpus paths pointing at the corpus in use (it
    names them as ../../../shared/corpus, right only for the corpus beside the checkout); skips without it."""
    need_corpus()
    spec = directory / "build.yaml"
    spec.write_text((ROOT / "samples" / "sw" / "build.yaml").read_text(encoding="utf-8")
                    .replace("../../../shared/corpus", CORPUS.resolve().as_posix()), encoding="utf-8")
    return spec


@pytest.fixture(scope="session")
def corpus() -> Path:
    need_corpus()
    return CORPUS


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "corpus: the test reads the real-file corpus indirectly (skips without it)")


#: a test that runs frames through a private network namespace (a served bus and a real master) runs once more
#: when it fails: both ends are processes the host schedules, and on a shared 2-core CI machine a frame may come
#: back late once. A rerun is listed in the summary (pytest-rerunfailures, "R"); failing twice fails the suite.
WIRE_RERUNS = 1


#: the xdist groups that start first, in this order: with two workers each long group starts on a worker of its own
#: at once (xdist's loadgroup hands out work in collection order), instead of the hostile slave's 2.5 minutes of
#: bounded waits starting after everything else on the last free worker (a 2-core CI run is as long as its longest
#: worker)
GROUPS_FIRST = ("wire-hostile", "wire")


def _group(item: pytest.Item) -> str | None:
    marker = item.get_closest_marker("xdist_group")
    if marker is None:
        return None
    return str(marker.args[0] if marker.args else marker.kwargs.get("name"))


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    rank = {name: i for i, name in enumerate(GROUPS_FIRST)}
    items.sort(key=lambda item: rank.get(_group(item) or "", len(rank)))  # stable: the rest keep their order
    if not config.pluginmanager.hasplugin("rerunfailures"):
        return
    for item in items:
        if item.path.name.startswith("test_wire_") and item.get_closest_marker("flaky") is None:
            item.add_marker(pytest.mark.flaky(reruns=WIRE_RERUNS))


def pytest_runtest_setup(item: pytest.Item) -> None:
    if item.get_closest_marker("corpus") is not None:
        need_corpus()


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]):  # type: ignore[no-untyped-def]
    # a skip raised in a fixture is reported at the test's own line: report every corpus skip at one place, so
    # that -rs folds them all into one line
    outcome = yield
    report = outcome.get_result()
    if report.skipped and isinstance(report.longrepr, tuple) and report.longrepr[2].endswith(NO_CORPUS):
        report.longrepr = (_HERE, _SKIP_LINE, report.longrepr[2])


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter, exitstatus: int, config: pytest.Config) -> None:
    for report in terminalreporter.stats.get("rerun", []):
        crash = getattr(report.longrepr, "reprcrash", None)
        reason = str(getattr(crash, "message", "") or "").strip().splitlines()
        why = f" — the first run: {reason[0][:200]}" if reason else ""
        terminalreporter.write_line(f"rerun once (a wire test failed, see WIRE_RERUNS): {report.nodeid}{why}")
    # with -rs pytest prints the folded reason itself; without it, say once why tests were skipped
    if have_corpus() or "s" in (config.option.reportchars or "") or "a" in (config.option.reportchars or ""):
        return
    skipped = [r for r in terminalreporter.stats.get("skipped", []) if NO_CORPUS in str(r.longrepr)]
    if skipped:
        terminalreporter.write_line(f"{len(skipped)} skipped: {NO_CORPUS}")


def run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    """Run ``ecattool ARGS`` through the real entry point; returns (exit code, stdout, stderr)."""
    from ecattool.cli import main

    try:
        main(list(args))
        code = 0
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 0
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def ideal_plant(monkeypatch: pytest.MonkeyPatch) -> None:
    """Drives built in the test have no plant (actual = demand), unless the test gives one: for the tests of the
    manuals' exact timings and traces (issue 33)."""
    from ecattool.sim.drive import family

    monkeypatch.setattr(family, "plant_for", lambda name: None)  # the family part's default plant
