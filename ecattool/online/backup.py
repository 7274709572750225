"""``backup``: what the drives of a project hold, into one folder: per slave its SII image, its dictionary
snapshot and (Technosoft, where the project has a ``.sw``) its EEPROM setup read back into a ``.sw``.

Everything is read first and written to a new folder beside the target, renamed into place at the end: a bus
that fails half-way leaves no folder and no partial file."""

from __future__ import annotations

import json
import os
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ecattool.errors import InputError, Location
from ecattool.online.dictionary import typed
from ecattool.online.live import LiveBus, Unsupported, describe_slave, sii_facts
from ecattool.online.objects import dump


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


def collect(project: str | Path, bus: LiveBus) -> tuple[dict[str, bytes], list[str]]:
    """The files of a backup (name -> content) and what was skipped, read from the bus. A slave without a CoE
    mailbox (its SII says so) is never sent an SDO: its SII is its backup. A slave that does not answer ends the
    backup (a backup is complete or not written at all)."""
    from ecattool.project.export import refuse_errors
    from ecattool.project.lint import lint_project

    result = lint_project(project)
    if result.loaded is None:
        first = result.findings[0]
        raise InputError(first.message, first.location)
    refuse_errors(result, "back up")
    files: dict[str, bytes] = {}
    skipped: list[str] = []
    for rd in sorted(result.drives, key=lambda r: r.position):
        slave = bus.slave(rd.position)
        stem = f"{rd.position:02d}-{_safe(rd.drive.name)}"
        sii: bytes | None = None
        try:
            sii = files[f"{stem}.sii.bin"] = slave.sii_read()
        except Unsupported as exc:
            skipped.append(f"{rd.drive.name}: SII: {exc}")
        if sii_facts(slave, sii).coe is False:  # the image just read: no second read of the EEPROM
            skipped.append(f"{rd.drive.name}: dictionary: {describe_slave(slave)} has no CoE mailbox (its SII)")
            continue
        snapshot = dump(slave, typed(slave, device=rd.device), bus.spec)
        files[f"{stem}.dict.json"] = (json.dumps(snapshot, indent=2, ensure_ascii=False) + "\n").encode()
        if rd.sw_image is not None:
            from ecattool.sw.image import write
            from ecattool.sw.upload import upload

            image, checks = upload(slave, [(b.start, b.end) for b in rd.sw_image.blocks])
            bad = [c.describe() for c in checks if not c.ok]
            if bad:
                raise InputError(f"drive {rd.drive.name!r}: the .sw read back does not check out: {bad[0]}")
            files[f"{stem}.sw"] = write(image)
    return files, skipped


def backup(project: str | Path, bus: LiveBus, folder: str | Path, overwrite: bool = False) -> BackupReport:
    """Read everything (:func:`collect`), then write it into the new folder ``folder`` in one rename. An existing
    ``folder`` is refused unless ``overwrite``: then the complete new folder takes its place, and the old one is
    removed only after that rename (an interrupted run leaves the old folder or the new one, never half of one)."""
    target = Path(folder)
    if target.exists() and not (overwrite and (target.is_dir() or target.is_file()) and not target.is_symlink()):
        raise InputError("file exists; use --force to replace the backup folder (or give a new one)",
                         Location(str(target)))
    files, skipped = collect(project, bus)
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
    return BackupReport(str(target), sorted(files), skipped)
