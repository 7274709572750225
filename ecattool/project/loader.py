"""Load a project file: YAML with locations → pydantic models, every problem located at file:line:column."""

from __future__ import annotations

import typing
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ValidationError
from pydantic_core import ErrorDetails

from ecattool.errors import EcatToolError, InputError, Location, did_you_mean
from ecattool.fileio import read_bytes
from ecattool.findings import Finding, Severity
from ecattool.project.model import Project
from ecattool.yamlloc import LocatedYaml, load_yaml


@dataclass(slots=True)
class LoadedProject:
    project: Project
    path: Path
    yaml: LocatedYaml

    @property
    def base(self) -> Path:
        return self.path.parent

    def resolve(self, relative: str) -> Path:
        p = Path(relative)
        return p if p.is_absolute() else self.base / p

    def locate(self, *path: str | int) -> Location:
        return self.yaml.locate(tuple(path))

    def named_files(self) -> list[Path]:
        """The files the drives name (ESI, .sw image), resolved: an output must never overwrite one of them."""
        named = []
        for drive in self.project.drives:
            if drive.device.esi:
                named.append(self.resolve(drive.device.esi))
            if drive.sw_config is not None:
                named.append(self.resolve(drive.sw_config.file))
        return named

    def drive_location(self, i: int, *path: str | int) -> Location:
        return self.yaml.locate(("drives", i, *path))


def _model_of(annotation: Any) -> type[BaseModel] | None:
    """The pydantic model an annotation holds (through list[...], X | None, Annotated[...]), if any."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in typing.get_args(annotation):
        found = _model_of(arg)
        if found is not None:
            return found
    return None


def known_keys(path: tuple[str | int, ...]) -> list[str]:
    """The keys the project format knows in the mapping at ``path`` (e.g. ``("drives", 0)`` → a drive's keys)."""
    model: type[BaseModel] | None = Project
    for part in path:
        if isinstance(part, int):
            continue
        field = model.model_fields.get(part) if model is not None else None
        model = _model_of(field.annotation) if field is not None else None
        if model is None:
            return []
    return list(model.model_fields) if model is not None else []


def _message(err: ErrorDetails, path: tuple[str | int, ...]) -> str:
    loc = ".".join(str(p) for p in err.get("loc", ()))
    msg = err.get("msg", "invalid value")
    if err.get("type") == "extra_forbidden":
        key = str(err["loc"][-1])
        msg = f"unknown field {key!r}{did_you_mean(key, known_keys(path[:-1]))}"
    elif msg.startswith("Value error, "):
        msg = msg[len("Value error, "):]
    return f"{loc}: {msg}" if loc else msg


def validation_findings(exc: ValidationError, doc: LocatedYaml) -> list[Finding]:
    out = []
    for err in exc.errors():
        path = tuple(p for p in err.get("loc", ()) if not (isinstance(p, str) and "[" in p))
        # pydantic adds union member names ("int", "str") to the path; drop the ones that are not keys
        clean: list[str | int] = []
        node: Any = doc.data
        for p in path:
            if isinstance(node, dict) and p in node:
                clean.append(p)
                node = node[p]
            elif isinstance(node, list) and isinstance(p, int) and p < len(node):
                clean.append(p)
                node = node[p]
        where = doc.locate_key(tuple(clean)) if err.get("type") == "extra_forbidden" else doc.locate(tuple(clean))
        out.append(Finding("PRJ001", Severity.ERROR, _message(err, tuple(clean)), where))
    return out


def _valid_drives(doc: LocatedYaml) -> tuple[Project, LocatedYaml] | None:
    """The project without the drives that do not validate, and its YAML with the drives renumbered to match
    (locations stay those of the file): so that lint can still check every drive that is well-formed. None when
    the problem is outside the drives, or no drive is left."""
    assert isinstance(doc.data, dict)
    drives = doc.data.get("drives")
    if not isinstance(drives, list):
        return None
    keep = []
    for i, d in enumerate(drives):
        try:
            Project.model_validate({**doc.data, "drives": [d]})
            keep.append(i)
        except ValidationError:
            continue
    if not keep or len(keep) == len(drives):
        return None
    data = {**doc.data, "drives": [drives[i] for i in keep]}
    try:
        project = Project.model_validate(data)
    except ValidationError:
        return None
    new_index = {old: new for new, old in enumerate(keep)}

    def renumber(table: dict[tuple[str | int, ...], Location]) -> dict[tuple[str | int, ...], Location]:
        out = {}
        for path, where in table.items():
            if len(path) >= 2 and path[0] == "drives" and isinstance(path[1], int):
                if path[1] not in new_index:
                    continue
                path = ("drives", new_index[path[1]], *path[2:])
            out[path] = where
        return out

    return project, LocatedYaml(data, renumber(doc.locations), doc.source, renumber(doc.key_locations))


def parse_project(text: bytes | str, source: str) -> tuple[Project | None, LocatedYaml, list[Finding]]:
    """Parse project text. Returns (project or None, located YAML, findings of schema problems).

    Where the schema problems are all inside some drives, the project returned holds the other drives (with the
    YAML renumbered to match), so that a lint still reports everything it can about them; any finding means the
    file is not valid."""
    doc = load_yaml(text, source)
    if not isinstance(doc.data, dict):
        raise InputError("a project file must be a YAML mapping with 'ecattool: 1' and 'drives'", Location(source, 1, 1))
    if "ecattool" not in doc.data:
        raise InputError("not an ecattool project: missing 'ecattool: 1' (format version)", Location(source, 1, 1))
    if doc.data.get("ecattool") != 1:
        raise InputError(f"unsupported project format version {doc.data.get('ecattool')!r}; this ecattool reads 1",
                         doc.locate(("ecattool",)))
    try:
        return Project.model_validate(doc.data), doc, []
    except ValidationError as exc:
        findings = validation_findings(exc, doc)
        partial = _valid_drives(doc)
        if partial is None:
            return None, doc, findings
        return partial[0], partial[1], findings


def load_project(path: str | Path) -> LoadedProject:
    """Load and validate a project file; raises InputError (located) on the first problem."""
    p = Path(path)
    project, doc, findings = parse_project(read_bytes(p, 16 * 1024 * 1024), str(p))
    if project is None or findings:
        first = findings[0]
        raise InputError(first.message, first.location)
    return LoadedProject(project, p, doc)


def project_inputs(paths: Iterable[str | Path]) -> list[str]:
    """The project files and every file they name: what an ``-o`` output must never overwrite.

    A project that cannot be loaded names nothing (its own error is reported where it is read)."""
    out: list[str] = []
    for p in paths:
        out.append(str(p))
        try:
            out += [str(f) for f in load_project(p).named_files()]
        except EcatToolError:
            pass
    return out
