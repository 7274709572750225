"""A private network namespace with a veth pair, for running a master and the virtual bus without touching the
host's interfaces. The recipe (docs/virtual-bus.md) as code:

    unshare -n sh -c 'ip link add ecat0 type veth peer name ecat1 && ip link set ecat0 up &&
                      ip link set ecat1 up && exec COMMAND'

The master opens ``ecat0``, ``ecattool sim serve ... --iface ecat1`` the other end. Without root the namespace
is made inside a user namespace (``unshare -rn``) where the kernel allows it.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from collections.abc import Sequence

MASTER_IF = "ecat0"
SLAVE_IF = "ecat1"


def _unshare() -> list[str]:
    exe = shutil.which("unshare") or "/usr/bin/unshare"
    return [exe, "-n"] if os.geteuid() == 0 else [exe, "-r", "-n"]


def _ip() -> str:
    return shutil.which("ip") or "/usr/sbin/ip"


def pair_script(master_if: str = MASTER_IF, slave_if: str = SLAVE_IF) -> str:
    """The shell commands that make a veth pair (in the namespace they run in) and bring both ends up."""
    ip = _ip()
    return (f"{ip} link add {master_if} type veth peer name {slave_if} && "
            f"{ip} link set {master_if} up && {ip} link set {slave_if} up")


def setup_script(master_if: str = MASTER_IF, slave_if: str = SLAVE_IF) -> str:
    """The shell commands that make the veth pair inside the namespace and bring both ends up."""
    return f"{_ip()} link set lo up && {pair_script(master_if, slave_if)}"


def command(argv: Sequence[str], master_if: str = MASTER_IF, slave_if: str = SLAVE_IF) -> list[str]:
    """``argv`` wrapped to run in a new network namespace that holds only the veth pair."""
    return [*_unshare(), "sh", "-c", setup_script(master_if, slave_if) + ' && exec "$@"', "sh", *argv]


def unavailable() -> str | None:
    """Why a private network namespace with a veth pair cannot be made here, or None when it can."""
    if not os.path.exists(_ip()) and shutil.which("ip") is None:
        return "the 'ip' command (iproute2) is not installed"
    if shutil.which("unshare") is None and not os.path.exists("/usr/bin/unshare"):
        return "the 'unshare' command (util-linux) is not installed"
    try:
        done = subprocess.run(command(["true"]), capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired) as exc:
        return f"unshare failed: {exc}"
    if done.returncode != 0:
        return "the kernel refused a private network namespace with a veth pair: " + \
            (done.stderr.strip().splitlines() or ["no reason given"])[-1]
    return None
