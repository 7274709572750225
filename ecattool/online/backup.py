"""``backup``: what the drives of a project hold, into one folder: per slave its SII image, its dictionary
snapshot and (Technosoft, where the project has a ``.sw``) its EEPROM setup read back into a ``.sw``.

Everything is read first and written to a new folder beside the target, renamed into place at the end: a bus
that fails half-way leaves no folder and no partial file.

A back-up never destroys and never lies:

- the folder may not be, hold or lie inside one of the project's inputs (the project file, the ESI and ``.sw``
  files it names), nor be the project's folder or hold it; an existing folder is replaced (``overwrite``, the
  CLI's ``--force``) only when it is a back-up: it holds the manifest :data:`MANIFEST` a back-up writes;
- what is saved is checked first: the slave's identity against the project's device (as ``audit`` compares
  it), the SII image's fixed area (not blank, not all zero), its CRC and its category chain's end marker, and
  every value's size against its data type; a slave that gives nothing to vouch for (no object read, e.g. in
  INIT) fails the back-up. Any of these is an error and no folder is written.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

from ecattool.errors import InputError, Location, SdoAbort, TargetError
from ecattool.esi.model import Identity
from ecattool.od.model import MAILBOX_STATES
from ecattool.online.dictionary import typed
from ecattool.online.live import LiveBus, describe_slave, sii_facts
from ecattool.online.objects import dump
from ecattool.project.machine import Machine
from ecattool.project.slave import Slave
from ecattool.target.base import LiveSlave, Unsupported

if TYPE_CHECKING:
    from ecattool.target.base import SlaveTarget

#: the file that makes a folder an ecattool back-up (the only kind of folder ``--force`` replaces)
MANIFEST = "ecattool-backup.json"
MANIFEST_FORMAT = "ecattool-backup"

@dataclass
class BackupReport:
    folder: str
    files: list[str] = field(default_factory=list)
    #: what a target could not give (e.g. SII through KickCAT), or a slave has not (a dictionary without a mailbox)
    skipped: list[str] = field(default_factory=list)

    def to_json(self) -> dict[str, Any]:
        return {"folder": self.folder, "files": self.files, "skipped": self.skipped}


def _safe(name: str) -> str:
    return "".join(c if c.isalnum() or c in "-_." else "_" for c in name) or "slave"


def _identity_1018(slave: LiveSlave) -> Identity:
    """The identity object 1018h:01-03 (vendor, product code, revision) as the slave's CoE reports it; the
    identity the master read from the SII where the slave has no 1018h (an SDO abort)."""
    values = []
    for sub in (1, 2, 3):
        try:
            data = slave.sdo_upload(0x1018, sub, size=4)  # a UDINT (CiA-301)
        except SdoAbort:
            return slave.identity()
        if len(data) != 4:
            raise TargetError(f"slave {slave.position}: 0x1018:{sub:02X}: answered {len(data)} byte(s), a UDINT has 4")
        values.append(int.from_bytes(data, "little"))
    return Identity(*values)


def _check_identity(rd: Slave, slave: LiveSlave, sdo: bool = True) -> None:
    """The slave at the drive's position is the project's device (the fields its ``identity:`` checks): by 1018h,
    or without ``sdo`` (a slave without a CoE mailbox) by the identity its SII holds."""
    from ecattool.online.audit import identity_differences

    if sdo:
        state = slave.state()
        if state not in MAILBOX_STATES:
            raise TargetError(f"slave {rd.position} ({rd.drive.name}) is in {state.value}: its mailbox does not "
                              "answer there, no object can be read; nothing backed up")
    wrong = identity_differences(rd, _identity_1018(slave) if sdo else slave.identity())
    if wrong:
        f, want, got = wrong[0]
        raise TargetError(f"slave {rd.position} is not drive {rd.drive.name!r} of the project: its {f} is "
                          f"0x{got:08X}, the project's device has 0x{want:08X}; nothing backed up")


def collect(machine: Machine, bus: LiveBus) -> tuple[dict[str, bytes], list[str]]:
    """The files of a backup (name -> content) and what was skipped, read from the bus and checked (module text):
    a :class:`TargetError` naming the slave when something read cannot be vouched for. A slave without a CoE mailbox
    (its SII says so) is never sent an SDO: its SII is its backup. ``machine``: the project's machine, built
    once by the caller (:func:`ecattool.project.machine.load_machine`; :func:`backup` refuses one with lint
    errors before anything is read)."""
    from ecattool.online.sii_access import read_checked

    files: dict[str, bytes] = {}
    skipped: list[str] = []
    for rd in machine.in_bus_order():
        slave = bus.slave(rd.position)
        stem = f"{rd.position:02d}-{_safe(rd.drive.name)}"
        sii: bytes | None = None
        try:
            sii = files[f"{stem}.sii.bin"] = read_checked(slave)
        except Unsupported as exc:
            skipped.append(f"{rd.drive.name}: SII: {exc}")
        if sii_facts(slave, sii).coe is False:  # the image just read: no second read of the EEPROM
            _check_identity(rd, slave, sdo=False)
            skipped.append(f"{rd.drive.name}: dictionary: {describe_slave(slave)} has no CoE mailbox (its SII)")
            continue
        _check_identity(rd, slave)
        snapshot = dump(slave, typed(slave, device=rd.device), bus.spec)
        if not any("value" in row for key, row in snapshot["objects"].items() if not key.startswith("0x1018:")):
            raise TargetError(f"slave {rd.position} ({rd.drive.name}) gave no object to back up (state "
                              f"{snapshot['state']}, {len(snapshot['objects'])} object(s) read, none with a value "
                              "beyond the identity 1018h); nothing backed up")
        files[f"{stem}.dict.json"] = (json.dumps(snapshot, indent=2, ensure_ascii=False) + "\n").encode()
        if rd.sw_image is not None:
            from ecattool.sw.image import write
            from ecattool.sw.upload import upload

            # see online.audit: a live slave changes state too, which LiveSlave does not list yet (issue 36 item 3)
            image, checks = upload(cast("SlaveTarget", slave), [(b.start, b.end) for b in rd.sw_image.blocks])
            bad = [c.describe() for c in checks if not c.ok]
            if bad:
                raise InputError(f"drive {rd.drive.name!r}: the .sw read back does not check out: {bad[0]}")
            files[f"{stem}.sw"] = write(image)
    return files, skipped


def _resolved(path: str | Path) -> Path:
    return Path(os.path.realpath(os.path.abspath(path)))


def _inside(path: Path, folder: Path) -> bool:
    return path == folder or folder in path.parents


def refuse_folder(folder: str | Path, project: str | Path, named: list[Path]) -> None:
    """Raise :class:`InputError` when the back-up folder is, holds or lies inside one of the inputs (the project
    file, the files it names), or is or holds the project's folder (links resolved)."""
    target = _resolved(folder)
    where = Location(str(folder))
    base = _resolved(Path(project).parent)
    if _inside(base, target):
        raise InputError(f"the back-up folder {'is' if base == target else 'holds'} the project's folder; choose a "
                         "new folder (e.g. beside the project file)", where)
    for src in [Path(project), *named]:
        real = _resolved(src)
        if _inside(real, target) or _inside(target, real):
            raise InputError(f"the back-up folder would replace {'' if real == target else 'or hold '}the "
                             f"project's input {str(src)!r}; choose a folder outside it", where)


def is_backup(folder: str | Path) -> bool:
    """Whether ``folder`` is a back-up folder: a real directory (not a link) holding a back-up's manifest."""
    p = Path(folder)
    try:
        if p.is_symlink() or not p.is_dir():
            return False
        from ecattool.fileio import read_bytes

        data = json.loads(read_bytes(p / MANIFEST, 1 << 20))
    except (OSError, ValueError, InputError):
        return False
    return isinstance(data, dict) and data.get("format") == MANIFEST_FORMAT


def _manifest(project: str | Path, spec: str, files: dict[str, bytes]) -> bytes:
    doc = {"format": MANIFEST_FORMAT, "version": 1, "project": str(project), "target": spec,
           "files": {name: {"bytes": len(data), "sha256": hashlib.sha256(data).hexdigest()}
                     for name, data in sorted(files.items())}}
    return (json.dumps(doc, indent=2, ensure_ascii=False) + "\n").encode()


def check_folder(folder: str | Path, machine: Machine, overwrite: bool = False) -> None:
    """Everything :func:`backup` refuses about its folder, before the bus is read: an input (the project file
    of ``machine`` and the files it names), the project's folder, a name that is no new folder; an existing one
    that is not a back-up, or one without ``overwrite``."""
    if str(folder) in ("", "-"):
        raise InputError("give a folder for the back-up (-o DIR)", Location(repr(str(folder))))
    target = Path(os.path.abspath(folder))
    if not target.name or target.name in (".", ".."):
        raise InputError("not a folder name a back-up can be created as", Location(str(folder)))
    refuse_folder(folder, machine.path, machine.require_loaded().named_files())
    if os.path.lexists(target):
        if not overwrite:
            raise InputError("file exists; use --force to replace the backup folder (or give a new one)",
                             Location(str(folder)))
        if not is_backup(target):
            raise InputError(f"exists and is not a back-up folder (no {MANIFEST} in it): --force replaces only a "
                             "back-up; give a new folder", Location(str(folder)))


def backup(machine: Machine, bus: LiveBus, folder: str | Path, overwrite: bool = False,
           allow_errors: bool = False) -> BackupReport:
    """Read everything (:func:`collect`) of the drives of ``machine`` (built once by the caller:
    :func:`ecattool.project.machine.load_machine`), then write it into the new folder ``folder`` in one rename.
    A machine with lint errors is refused unless ``allow_errors`` (:meth:`Machine.refuse_errors`, as
    ``commission`` does). An existing ``folder`` is refused unless ``overwrite``: then the complete new folder
    takes its place, and the old one is removed only after that rename (an interrupted run leaves the old folder
    or the new one, never half of one)."""
    machine.refuse_errors("back up", allow_errors=allow_errors)
    check_folder(folder, machine, overwrite)
    target = Path(os.path.abspath(folder))
    files, skipped = collect(machine, bus)
    check_folder(folder, machine, overwrite)  # again: the bus took time, and the folder may have appeared
    files[MANIFEST] = _manifest(machine.path, bus.spec, files)
    tmp = target.with_name(f".{target.name}.{os.getpid()}.tmp")
    old = target.with_name(f".{target.name}.{os.getpid()}.old")
    try:
        tmp.mkdir(parents=False)
        for name, data in files.items():
            (tmp / name).write_bytes(data)
        if target.exists():
            os.replace(target, old)
        os.replace(tmp, target)
    except OSError as exc:
        shutil.rmtree(tmp, ignore_errors=True)
        if old.exists() and not target.exists():
            os.replace(old, target)
        raise InputError(f"cannot write the backup folder: {exc.strerror or exc}", Location(str(target))) from None
    if old.is_dir():
        shutil.rmtree(old, ignore_errors=True)
    elif old.exists():
        old.unlink()
    return BackupReport(str(folder), sorted(n for n in files if n != MANIFEST), skipped)
