"""The public entry points: :func:`export`, :func:`import_file`, :func:`import_bytes`, :func:`detect_format`."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from ecattool.errors import EncodeError, InputError, Location, SelectionError
from ecattool.startup.config import SlaveConfig
from ecattool.startup.formats import FORMATS, Format
from ecattool.startup.model import StartupList


def _format(fmt: str, direction: str) -> Format:
    f = FORMATS.get(fmt.strip().lower())
    if f is None:
        raise InputError(f"unknown startup format {fmt!r} (one of {', '.join(FORMATS)})")
    if direction == "export" and not f.can_export:
        raise InputError(f"format {f.name!r} can only be read, not written "
                         f"(writable: {', '.join(n for n, x in FORMATS.items() if x.can_export)})")
    if direction == "import" and not f.can_import:
        raise InputError(f"format {f.name!r} can only be written, not read "
                         f"(readable: {', '.join(n for n, x in FORMATS.items() if x.can_import)})")
    return f


def as_configs(config_or_list: SlaveConfig | StartupList | Sequence[SlaveConfig | StartupList]) -> list[SlaveConfig]:
    if isinstance(config_or_list, SlaveConfig):
        return [config_or_list]
    if isinstance(config_or_list, StartupList):
        return [SlaveConfig.from_list(config_or_list)]
    return [c if isinstance(c, SlaveConfig) else SlaveConfig.from_list(c) for c in config_or_list]


def losses(config_or_list: SlaveConfig | StartupList | Sequence[SlaveConfig | StartupList], fmt: str) -> list[str]:
    """What format ``fmt`` cannot carry of the configurations, one line each naming the slave (one-shot writes
    in a format of startup writes, DC or SoE where it has none, an unknown identity an ENI needs, …)."""
    module = _format(fmt, "export").module
    if not hasattr(module, "losses"):
        return []
    return [f"{c.label}: {what}" for c in as_configs(config_or_list) for what in module.losses(c)]


def export(config_or_list: SlaveConfig | StartupList | Sequence[SlaveConfig | StartupList], fmt: str, *,
           lossy: bool = False) -> str:
    """Write slave configurations (or a bare startup list) in format ``fmt`` (see :data:`FORMATS`).

    Nothing is lost silently: where ``fmt`` cannot carry part of the configuration (see :func:`losses`) this
    raises :class:`EncodeError` listing it, unless ``lossy`` accepts the losses; an output that would carry
    nothing at all is refused either way, never written empty."""
    configs = as_configs(config_or_list)
    f = _format(fmt, "export")
    lost = losses(configs, f.name)
    if lost and not lossy:
        shown = "; ".join(lost[:4]) + (f"; and {len(lost) - 4} more" if len(lost) > 4 else "")
        raise EncodeError(f"{f.name} cannot carry {len(lost)} part(s) of the configuration: {shown} (--lossy "
                          "writes it without them, each listed)", configs[0].source if configs else None)
    empty = getattr(f.module, "nothing_left", None)
    if empty is not None and (not configs or all(empty(c) for c in configs)):
        why = f": {'; '.join(lost[:4])}" if lost else ""
        raise EncodeError(f"nothing to write: {f.name} carries nothing of this configuration{why}",
                          configs[0].source if configs else None)
    return str(f.module.export(configs))


_HWDEVMGR_KEYS = ("param_values", "sync_manager", "test_category")


def _yaml_format(data: bytes, source: str) -> str:
    from ecattool.startup.formats import ros2
    from ecattool.startup.formats._common import decode_text

    doc = ros2.load_located(decode_text(data, source), source)
    top = doc.data
    if isinstance(top, list) and top and all(isinstance(x, dict) for x in top) and \
            any(k in top[0] for k in _HWDEVMGR_KEYS):
        raise InputError(
            "this is a hw_device_mgr device configuration: its PDO entries and param_values carry no data types "
            "or sizes, and its values are lists per test drive, so it cannot become startup commands without the "
            "drives' ESI files; describe the drives in an ecattool project instead", doc.locate((0,)))
    if ros2.detect_yaml(top):
        return "ros2"
    raise InputError("YAML file is not an ethercat_driver_ros2 slave configuration (no vendor_id/product_id/"
                     "rpdo/tpdo/sdo keys)", doc.locate(()))


def detect_format(data: bytes, source: str = "<input>") -> str:
    """The format of ``data``, from its content (never from the file name alone)."""
    head = data[:4096].lstrip(b"\xef\xbb\xbf").lstrip()
    if head.startswith(b"<"):
        for name in ("eni", "lcec"):
            if FORMATS[name].module.detect(data):
                return name
        if FORMATS["twincat"].module.detect(data):
            return "twincat"
        raise InputError("XML file is neither an ENI (<EtherCATConfig>), a TwinCAT <EtherCATMailbox> export nor "
                         "an lcec <masters> configuration", Location(source, 1))
    for name in ("json", "csv", "twincat", "ecmc"):
        if FORMATS[name].module.detect(data):
            return name
    if head.startswith(b"{") or head.startswith(b"["):
        raise InputError("JSON file is not an ecattool startup file (\"format\": \"ecattool-startup\")",
                         Location(source, 1))
    return _yaml_format(data, source)


def import_bytes(data: bytes, source: str = "<input>", fmt: str | None = None) -> list[SlaveConfig]:
    name = fmt or detect_format(data, source)
    if name == "ros2":
        _yaml_format(data, source)  # refuses hw_device_mgr files with a clear message
    from ecattool.startup.formats._common import check_commands, find_contradictions

    configs = list(_format(name, "import").module.load(data, source))
    check_commands(configs)
    find_contradictions(configs)
    if not any(c.commands or c.has_pdo_info or c.dc_assign_activate or c.soe_commands for c in configs):
        notes = [n for c in configs for n in c.notes]
        first = (f"; {len(notes)} part(s) not used, first: {notes[0].location}: {notes[0].message[:160]}"
                 if notes else "")
        raise InputError(f"nothing to import: no startup command, PDO, DC setting or SoE command was read{first}",
                         Location(source, 1))
    return configs


def import_file(path: str | Path, fmt: str | None = None) -> list[SlaveConfig]:
    """Read a startup configuration file; the format is detected from the content unless ``fmt`` is given."""
    from ecattool.fileio import read_bytes

    return import_bytes(read_bytes(path), str(path), fmt)


def describe_slaves(configs: Sequence[SlaveConfig]) -> str:
    """``name at position, ...`` of ``configs`` (the index where a slave has no position), for an error that asks
    the user to choose one; ``none`` for no slaves."""
    return ", ".join(f"{c.name or '(no name)'} at {c.position if c.position is not None else i}"
                     for i, c in enumerate(configs)) or "none"


def select_slaves(configs: Sequence[SlaveConfig], selectors: Sequence[str]) -> list[SlaveConfig]:
    """The slaves ``selectors`` name, in bus order: a slave (project drive) name, else a bus position.

    For the formats that hold one slave (TwinCAT lines, ros2): pick a drive of a project or a slave of an ENI.
    No selectors: every slave. A selector that matches nothing raises :class:`SelectionError` listing them."""
    if not selectors:
        return list(configs)
    chosen: list[SlaveConfig] = []
    for sel in selectors:
        found = [c for c in configs if c.name == sel] or [
            c for i, c in enumerate(configs)
            if sel.strip().isdigit() and (c.position if c.position is not None else i) == int(sel)]
        if not found:
            raise SelectionError(f"no slave named or at position {sel!r} (slaves: {describe_slaves(configs)})")
        chosen += [c for c in found if all(c is not x for x in chosen)]
    return [c for c in configs if any(c is x for x in chosen)]


def select_one(configs: Sequence[SlaveConfig], selector: str | None, source: str) -> SlaveConfig:
    """The one slave of ``source``'s ``configs`` that ``selector`` names (:func:`select_slaves`), or its only slave
    without one; a SelectionError listing the slaves where that is not exactly one (``map … --startup``)."""
    if selector is None:
        if len(configs) == 1:
            return configs[0]
        raise SelectionError(f"{source} has {len(configs)} slaves; choose one with --drive NAME "
                             f"({describe_slaves(configs)})")
    chosen = select_slaves(configs, [selector])
    if len(chosen) > 1:
        raise SelectionError(f"{source} has {len(chosen)} slaves named {selector!r}; choose one by its bus "
                             f"position with --drive N ({describe_slaves(configs)})")
    return chosen[0]
