"""Shared by the whole-process benchmarks: run variants as separate processes, interleaved, and report each
median with its ratio to a baseline measured in the same run (and the ratio of minima, which moves less when
other jobs share the machine)."""

from __future__ import annotations

import os
import resource
import statistics
import subprocess
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: A variant: the command line, and the directory holding another revision's ``ecattool`` package (or None).
Variant = tuple[list[str], "Path | None"]


def steal_s() -> float:
    """The machine's steal time so far, s (``/proc/stat``: time a virtual machine's CPUs were runnable but the
    hypervisor ran something else); 0 where it is not reported. Some hypervisors do not report all of it
    (``machine_stalls.py`` finds the stops it leaves out)."""
    try:
        with open("/proc/stat", encoding="ascii") as f:
            fields = f.readline().split()
        return int(fields[8]) / os.sysconf("SC_CLK_TCK") if len(fields) > 8 else 0.0
    except (OSError, ValueError):
        return 0.0


def env_for(package_dir: Path | None = None) -> dict[str, str]:
    # measure ecattool as installed: byte-compiled modules. Where the shell sets PYTHONDONTWRITEBYTECODE every
    # run would recompile every imported module (earlier 2.4-2.9x figures included that); the warm-up run
    # writes the .pyc files.
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    if package_dir is not None:
        env["PYTHONPATH"] = str(package_dir)
    return env


#: CPU time (user + system, s) of every process :func:`run_once` ran, per command line, in order
CPU: dict[tuple[str, ...], list[float]] = {}


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run_once(cmd: list[str], package_dir: Path | None = None) -> float:
    """Wall time of one process; another revision's package runs in its own directory so it is found first.
    Its CPU time goes to :data:`CPU` (less disturbed by other jobs on the machine than the wall time)."""
    c0 = _children_cpu()
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, cwd=package_dir or ROOT, stdout=subprocess.DEVNULL, env=env_for(package_dir))
    wall = time.perf_counter() - t0
    CPU.setdefault((*cmd, str(package_dir)), []).append(_children_cpu() - c0)
    return wall


def interleaved(variants: dict[str, Variant], runs: int, warmups: int = 1,
                cpu: dict[str, list[float]] | None = None) -> dict[str, list[float]]:
    """``runs`` wall times of each variant, one of each in turn, after warming the OS file cache and .pyc files;
    with ``cpu``, each run's CPU time (user + system of the process) goes there under the variant's name."""
    for _ in range(warmups):
        for cmd, package_dir in variants.values():
            run_once(cmd, package_dir)
    times: dict[str, list[float]] = {k: [] for k in variants}
    for _ in range(runs):
        for name, (cmd, package_dir) in variants.items():
            times[name].append(run_once(cmd, package_dir))
            if cpu is not None:
                cpu.setdefault(name, []).append(CPU[(*cmd, str(package_dir))][-1])
    return times


def report(times: dict[str, list[float]], baseline: str, cpu: dict[str, list[float]] | None = None) -> None:
    """Median wall time per variant and its ratio to ``baseline``'s (ratio of minima too); with ``cpu``, also
    the median CPU time and the median of the per-round CPU ratios (each run against the baseline's run of the
    same round)."""
    base, base_min = statistics.median(times[baseline]), min(times[baseline])
    for name, ts in times.items():
        med = statistics.median(ts)
        line = (f"  {name:16s} {med * 1000:7.1f} ms   ratio {med / base:4.2f}x   "
                f"(min {min(ts) * 1000:.1f} ms, ratio of minima {min(ts) / base_min:4.2f}x)")
        if cpu is not None and name in cpu:
            ratios = [c / b for c, b in zip(cpu[name], cpu[baseline])]
            line += (f"   CPU {statistics.median(cpu[name]) * 1000:6.1f} ms, median ratio "
                     f"{statistics.median(ratios):4.2f}x")
        print(line)


def has_package(directory: Path) -> bool:
    return (directory / "ecattool" / "__init__.py").is_file()
