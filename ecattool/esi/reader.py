"""ESI XML → :class:`EsiFile` / :class:`Device` (roots ``EtherCATInfo``, ``EtherCATModule``, ``EtherCATDict``).

Reads bytes (BOM, ISO-8859-1, UTF-8, CRLF), parses through :mod:`ecattool.xmlsafe`, and fills every field of
the device model the file provides. Object dictionaries are built on first use (:class:`LazyDictionary`),
which keeps loading a 141-device file close to the cost of the XML parse; the content is the same.
Tolerated deviations become warnings on ``EsiFile.warnings``; malformed required values raise
:class:`InputError` with file and line.
"""

from __future__ import annotations

import gc
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

from ecattool.errors import EcatToolError, InputError, Location
from ecattool.findings import Finding, Severity
from ecattool.esi.model import (
    AlternativeSmMapping,
    CoeDetails,
    DcOpMode,
    Device,
    Direction,
    Eeprom,
    EepromCategory,
    EsiFile,
    Fmmu,
    Identity,
    IdentityView,
    InitCmd,
    Mailbox,
    Module,
    Pdo,
    PdoEntry,
    Slot,
    SyncManager,
)
from ecattool.esi.values import NO_NAME, Context, lc_text, name_step
from ecattool.esi.values import fast_number as _fast_number  # the name it had here (tests use it)
from ecattool.od.model import ObjectDictionary, OdObject
from ecattool.xmlsafe import MAX_XML_BYTES, parse_xml

ROOTS = ("EtherCATInfo", "EtherCATModule", "EtherCATDict")
_BIT = {"0": 0, "1": 1}
#: sync manager kind -> True when the master writes it (ControlByte direction 01)
_SM_DIRECTION = {"MBoxOut": True, "Outputs": True, "MBoxIn": False, "Inputs": False}


def sm_kind_from_control(control: int, has_pdos: bool) -> str | None:
    """The kind a ``ControlByte`` gives a sync manager (ETG.2000, ESC register 0x0804): bits 2-3 the direction
    (01 written by the master, 00 read by it; 10 and 11 are reserved: None), bits 0-1 the mode (00 buffered:
    process data; 10 one-buffer: a mailbox, or process data when a PDO names the sync manager; 01 and 11:
    None)."""
    direction, mode = (control >> 2) & 3, control & 3
    if direction > 1 or mode in (1, 3):
        return None
    if mode == 2 and not has_pdos:
        return "MBoxOut" if direction else "MBoxIn"
    return "Outputs" if direction else "Inputs"


_NO_INDEX = -(1 << 200)  # a PDO without an Index element (a schema-valid Index is never this)
_T = TypeVar("_T")


def without_gc(build: Callable[[], _T]) -> _T:
    """``build()`` with Python's cyclic garbage collector paused (re-enabled after, if it was enabled).

    Building a model allocates tens of thousands of small objects (entries, locations) and no garbage cycles;
    the collector would run a pass every 700 of them and a full pass over every object of the process now and
    then, finding nothing to free: ~10% of loading a large file. Objects are freed by reference counting as
    usual meanwhile; any cycle is collected by a later pass.

    The model is long-lived, so afterwards the objects go to the collector's oldest generation at once
    (:func:`_age_young_objects`) instead of through the two passes that would move them there: with every new
    object in the youngest generation, the first allocation after the build started a pass over all of them,
    and a second one came a little later (~10 ms each for the complete model of the largest corpus file, ~20 %
    of what the model costs beyond the parse), both finding nothing.
    """
    if not gc.isenabled():
        return build()
    gc.disable()
    try:
        return build()
    finally:
        _age_young_objects()
        gc.enable()


def _age_young_objects() -> None:
    """Move every object the collector tracks to its oldest generation without a pass: ``gc.freeze()`` then
    ``gc.unfreeze()`` (CPython: the permanent generation goes back into the oldest one, the young ones are
    empty and their count restarts). Garbage cycles among the caller's young objects are then found by the next
    full pass instead of a young one: later, not lost. Skipped where the process has frozen objects of its own
    (``gc.freeze`` before a fork, as ``sim serve`` does): unfreezing them is not this function's to decide."""
    if gc.get_freeze_count() == 0:
        gc.freeze()
        gc.unfreeze()
_MODELLED = frozenset({"Type", "Name", "Profile"})


def _element_note(el: Any) -> str:
    """``Tag attr=value … text`` of a vendor-specific element, for ``Device.extra``."""
    attrs = " ".join(f"{k}={v}" for k, v in el.attrib.items())
    inner = (el.text or "").strip() if len(el) == 0 else etree_text(el)
    tag = el.tag.split("}", 1)[-1]
    return " ".join(p for p in (tag, attrs, inner) if p)


def etree_text(el: Any) -> str:
    """Compact text of a small element tree (child tag=text pairs) for ``Device.extra``."""
    parts = []
    for c in el.iter():
        if c is not el and isinstance(c.tag, str) and (c.text or "").strip():
            parts.append(f"{c.tag}={c.text.strip()}")
    return " ".join(parts)[:500]
_PROTOCOLS = ("AoE", "EoE", "CoE", "FoE", "SoE", "VoE")
_BOOLEANS = {"1": True, "0": False, "true": True, "false": False}  # what Context.boolean reads them as
_PDO_BOOLEAN_ATTRIBUTES = (("Fixed", "fixed"), ("Mandatory", "mandatory"), ("Virtual", "virtual"),
                           ("OverwrittenByModule", "overwritten_by_module"))
_PDO_NUMBER_ATTRIBUTES = (("Sm", "sm"), ("Su", "su"), ("PdoOrder", "pdo_order"), ("OSFac", "os_fac"),
                          ("OSMin", "os_min"), ("OSMax", "os_max"), ("OSIndexInc", "os_index_inc"))
#: PDO attribute -> (field, boolean?), for the common spellings read in one pass (Reader._pdo_attributes)
_PDO_ATTRIBUTES = {**{a: (f, True) for a, f in _PDO_BOOLEAN_ATTRIBUTES},
                   **{a: (f, False) for a, f in _PDO_NUMBER_ATTRIBUTES}}


def build_dictionary(el: Any, ctx: Context) -> ObjectDictionary:
    """:func:`ecattool.esi.dictionary.build_dictionary`, imported when a dictionary is first read."""
    from ecattool.esi.dictionary import build_dictionary as build

    return build(el, ctx)


class DeviceHead(IdentityView):
    """What selecting a device needs (its ``Type``: name, product code, revision), read without the rest."""

    __slots__ = ("element", "identity", "index", "type_name")

    def __init__(self, index: int, type_name: str, identity: Identity, element: Any) -> None:
        self.index = index
        self.type_name = type_name
        self.identity = identity
        self.element = element


class LazyEsiFile(EsiFile):
    """An :class:`EsiFile` whose devices are built on demand.

    :func:`ecattool.esi.select` picks among :attr:`device_heads` and builds only the chosen device
    (:meth:`device_at`); reading :attr:`devices` builds all the others (the same objects for the ones already
    built), so the file behaves exactly like a complete :func:`load`. Pickles as a plain :class:`EsiFile`.
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self.device_heads: list[DeviceHead] = []
        self._build: Callable[[DeviceHead], Device] | None = None
        self._skip: Callable[[Any, DeviceHead, InputError], None] | None = None
        self._built: dict[int, Device] = {}
        super().__init__(*args, **kwargs)

    @property
    def devices(self) -> list[Device]:
        if self._build is not None:
            build, self._build = self._build, None
            out = []
            first: InputError | None = None
            for h in self.device_heads:
                dev = self._built.get(h.index)
                if dev is None:
                    try:
                        dev = build(h)
                    except InputError as exc:  # left out with an error finding, as a complete load does
                        first = first or exc
                        if self._skip is not None:
                            self._skip(h.element, h, exc)
                        continue
                out.append(dev)
            self._built.clear()
            if first is not None and not out:
                raise first
            self._devices = out
        return self._devices

    @devices.setter
    def devices(self, value: list[Device]) -> None:
        self._build = None
        self._devices = value

    @property
    def pending(self) -> bool:
        """True while some devices are still unbuilt."""
        return self._build is not None

    def defer(self, heads: list[DeviceHead], build: Callable[[DeviceHead], Device],
              skip: Callable[[Any, DeviceHead, InputError], None] | None = None) -> None:
        self.device_heads = heads
        self._build = build
        self._skip = skip

    def device_at(self, index: int) -> Device:
        """The device at ``index`` in document order, building only that one if the rest are still pending."""
        if self._build is None:
            return self.devices[index]
        dev = self._built.get(index)
        if dev is None:
            dev = self._built[index] = self._build(self.device_heads[index])
        return dev

    def __reduce__(self) -> Any:
        return (EsiFile, tuple(getattr(self, name) for name in EsiFile._fields))


class LazyDictionary(ObjectDictionary):
    """An :class:`ObjectDictionary` whose objects are read from the ESI element on first access."""

    __slots__ = ("_build",)

    def __init__(self, build: Any) -> None:
        super().__init__()
        self._build = build

    def _load(self) -> None:
        build = self._build
        if build is not None:
            self._build = None
            built = without_gc(build)
            self._objects.update(built._objects)
            self._names = None

    def add(self, obj: OdObject) -> None:
        self._load()
        super().add(obj)

    def get(self, index: int) -> OdObject | None:
        self._load()
        return super().get(index)

    def entry(self, index: int, subindex: int) -> Any:
        self._load()
        return super().entry(index, subindex)

    def find(self, name: str) -> tuple[int, int] | None:
        self._load()
        return super().find(name)

    def __contains__(self, index: object) -> bool:
        self._load()
        return super().__contains__(index)

    def __iter__(self) -> Any:
        self._load()
        return super().__iter__()

    def __len__(self) -> int:
        self._load()
        return super().__len__()

    def indices(self) -> list[int]:
        self._load()
        return super().indices()

    def __reduce__(self) -> Any:
        # pickled (e.g. by project caches) as the plain dictionary it builds: the lxml tree stays behind
        self._load()
        return (ObjectDictionary, (dict(self._objects),))

    def merged(self, other: ObjectDictionary) -> ObjectDictionary:
        self._load()
        if isinstance(other, LazyDictionary):
            other._load()
        return super().merged(other)


def _decode_fallback(data: bytes, source: str, ctx: Context) -> bytes | None:
    """Undeclared ISO-8859-1: bytes that are not UTF-8 and no encoding declaration → re-encode as UTF-8."""
    head = data[:200].lstrip(b"\xef\xbb\xbf")
    if head.startswith(b"<?xml") and b"encoding" in head.split(b"?>", 1)[0]:
        return None
    try:
        data.decode("utf-8")
        return None
    except UnicodeDecodeError:
        pass
    ctx.warn("esi-encoding", "file is not UTF-8 and declares no encoding; read as ISO-8859-1")
    text = data.decode("latin-1")
    if text.startswith("<?xml"):
        end = text.find("?>")
        text = text[end + 2:] if end >= 0 else text
    return text.encode("utf-8")


class Reader:
    def __init__(self, source: str, base_dir: Path | None, follow_references: bool = True) -> None:
        self.source = source
        self.base_dir = base_dir
        self.follow_references = follow_references
        self.ctx = Context(source)
        self._numbers: dict[str, int] = {}

    # --- entry points ---------------------------------------------------------------------------
    def read(self, data: bytes, lazy: bool = False) -> EsiFile:
        try:
            tree = parse_xml(data, self.source, drop_blank_text=True)
        except InputError:
            fixed = _decode_fallback(data, self.source, self.ctx)
            if fixed is None:
                raise
            tree = parse_xml(fixed, self.source, drop_blank_text=True)
        root = tree.getroot()
        tag = root.tag if isinstance(root.tag, str) else ""
        if "}" in tag:
            tag = tag.split("}", 1)[1]
        if tag not in ROOTS:
            raise InputError(f"root element is <{tag}>, not an ESI file (expected one of {', '.join(ROOTS)})",
                             self.ctx.loc(root))
        cls = LazyEsiFile if lazy else EsiFile
        esi = cls(self.source, tag, version=root.get("Version", ""), warnings=self.ctx.warnings)
        if tag == "EtherCATDict":
            d = root.find("Dictionary")
            esi.dictionary = build_dictionary(d, self.ctx) if d is not None else ObjectDictionary()
            return esi
        self._vendor(root, esi)
        if tag == "EtherCATModule":
            mods = root.find("Modules")
            esi.modules = self._modules(mods)
            return esi
        for ref in root.iterchildren("InfoReference"):
            esi.info_references.append((ref.text or "").strip())
        desc = root.find("Descriptions")
        if desc is None:
            raise InputError("EtherCATInfo has no Descriptions element", self.ctx.loc(root))
        groups = desc.find("Groups")
        if groups is not None:
            for g in groups.iterchildren("Group"):
                esi.groups[(g.findtext("Type") or "").strip()] = lc_text(g, "Name")
        esi.modules = self._modules(desc.find("Modules"))
        if self.follow_references:
            for ref_el in root.iterchildren("InfoReference"):
                esi.modules.extend(self._referenced_modules(ref_el))
        devices = desc.find("Devices")
        if devices is not None:
            self._devices(devices, esi)
        return esi

    def _devices(self, devices_el: Any, esi: EsiFile) -> None:
        """Read every ``Device``; one that cannot be read is skipped with an ``esi-device-skipped`` error finding
        (its file and line) and never blocks the others. The read fails only when no device can be read."""
        first: InputError | None = None
        heads: list[DeviceHead] = []
        built: list[Device] = []
        lazy = isinstance(esi, LazyEsiFile)
        for el in devices_el.iterchildren("Device"):
            head = None
            try:
                head = self.head(el, esi, len(heads))
                if lazy:
                    heads.append(head)
                else:
                    built.append(self.device(el, esi, head))
            except InputError as exc:
                first = first or exc
                self.skip_device(el, head, exc)
        if first is not None and not heads and not built:
            raise first
        if isinstance(esi, LazyEsiFile):
            esi.defer(heads, lambda h: self.device(h.element, esi, h), self.skip_device)
        else:
            esi.devices = built

    def _modules(self, modules_el: Any) -> list[Module]:
        """Every ``Module`` of a ``Modules`` element; one that cannot be read is left out with an error finding
        ``esi-module-skipped`` (the devices and the other modules still load)."""
        out: list[Module] = []
        for el in (modules_el.iterchildren("Module") if modules_el is not None else ()):
            try:
                out.append(self.module(el))
            except InputError as exc:
                t = el.find("Type")
                what = repr((t.text or "").strip()) if t is not None else f"at line {el.sourceline}"
                self.ctx.warnings.append(Finding("esi-module-skipped", Severity.ERROR, f"module {what} skipped: "
                                                 f"{exc.message}", exc.location or self.ctx.loc(el),
                                                 {"module_line": el.sourceline}))
        return out

    def skip_device(self, el: Any, head: DeviceHead | None, exc: InputError) -> None:
        """Record that the device at ``el`` is left out: an error finding at the value that could not be read."""
        what = (f"{head.type_name} (product 0x{head.product_code:08X} revision 0x{head.revision:08X})"
                if head is not None else f"at line {el.sourceline}")
        data: dict[str, Any] = {"device_line": el.sourceline}
        if head is not None:
            data.update(type=head.type_name, product_code=head.product_code, revision=head.revision)
        self.ctx.warnings.append(Finding("esi-device-skipped", Severity.ERROR,
                                         f"device {what} skipped: {exc.message}", exc.location or self.ctx.loc(el),
                                         data))

    # --- parts ------------------------------------------------------------------------------------
    def _vendor(self, root: Any, esi: EsiFile) -> None:
        ctx = self.ctx
        vendor = root.find("Vendor")
        if vendor is None:
            ctx.warn("esi-vendor-missing", "file has no Vendor element; vendor id taken as 0", root)
            esi.vendor_id = 0
            return
        id_el = vendor.find("Id")
        if id_el is None:
            ctx.warn("esi-vendor-missing", "Vendor has no Id; vendor id taken as 0", vendor)
            esi.vendor_id = 0
        else:
            esi.vendor_id = ctx.number(id_el.text, id_el, "Vendor/Id")
        if vendor.find("Name") is None:
            ctx.warn("esi-vendor-name", "Vendor has no Name", vendor)
        esi.vendor_name = lc_text(vendor, "Name")

    def _resolve_path(self, text: str) -> Path | None:
        """A file named in the ESI (Windows separators allowed), relative to this file's directory."""
        if self.base_dir is None or not text:
            return None
        rel = text.replace("\\", "/")
        cand = self.base_dir / rel
        if cand.is_file():
            return cand
        base = rel.rsplit("/", 1)[-1]
        cand = self.base_dir / base
        if cand.is_file():
            return cand
        low = base.lower()
        try:
            for p in sorted(self.base_dir.iterdir()):
                if p.is_file() and (p.name.lower() == low or p.name.lower().endswith("_" + low)):
                    return p
        except OSError:
            return None
        return None

    def _referenced_modules(self, ref_el: Any) -> list[Module]:
        text = (ref_el.text or "").strip()
        path = self._resolve_path(text)
        if path is None:
            self.ctx.warn("esi-inforeference-missing", f"InfoReference {text!r} not found beside the file; its modules are not loaded", ref_el)
            return []
        sub = Reader(str(path), path.parent, follow_references=False)
        try:
            esi = sub.read(_read(path))
        except EcatToolError as exc:
            self.ctx.warn("esi-inforeference-bad", f"InfoReference {text!r} could not be read: {exc}", ref_el)
            return []
        self.ctx.warnings.extend(sub.ctx.warnings)
        return esi.modules

    def _dictionary(self, profile: Any) -> ObjectDictionary:
        if profile is None:
            return ObjectDictionary()
        d = profile.find("Dictionary")
        if d is not None:
            ctx = self.ctx
            return LazyDictionary(lambda: build_dictionary(d, ctx))
        f = profile.find("DictionaryFile")
        if f is not None:
            text = (f.text or "").strip()
            path = self._resolve_path(text)
            if path is None:
                self.ctx.warn("esi-dictionaryfile-missing", f"DictionaryFile {text!r} not found beside the file; dictionary left empty", f)
                return ObjectDictionary()
            src = str(path)

            def build() -> ObjectDictionary:
                sub = Reader(src, path.parent, follow_references=False)
                try:
                    esi = sub.read(_read(path))
                except EcatToolError as exc:
                    self.ctx.warn("esi-dictionaryfile-bad", f"DictionaryFile {text!r} could not be read: {exc}", f)
                    return ObjectDictionary()
                self.ctx.warnings.extend(sub.ctx.warnings)
                return esi.dictionary or ObjectDictionary()

            return LazyDictionary(build)
        return ObjectDictionary()

    def pdo(self, el: Any, direction: Direction) -> Pdo:
        ctx = self.ctx
        get = el.get
        pdo = Pdo(direction, _NO_INDEX)
        pdo.at_line(self.source, el.sourceline)
        name: str | None = None
        rank = NO_NAME
        entries = pdo.entries
        known = self._numbers
        for child in el[:]:
            tag = child.tag
            if tag == "Entry":
                entries.append(self.entry(child))
            elif tag == "Exclude":  # Beckhoff: several per PDO
                t = child.text
                v = known.get(t)
                pdo.excludes.append(self._number(t, child, "Exclude") if v is None else v)
            elif tag == "Index":
                t = child.text
                v = known.get(t)
                pdo.index = self._number(t, child, f"{el.tag}/Index") if v is None else v
                if child.get("DependOnSlot") is not None:
                    pdo.depend_on_slot = ctx.boolean(child.get("DependOnSlot"), child, "DependOnSlot")
            elif tag == "Name":
                name, rank = name_step(child, name, rank)
        pdo.name = name or ""
        if not 0 <= pdo.index <= 0xFFFF:
            if pdo.index == _NO_INDEX:
                raise InputError(f"{el.tag} has no Index", ctx.loc(el))
            pdo.index = self._in_range(pdo.index, 16, f"{el.tag}/Index", el)
        attrs = el.items()
        if attrs and not self._pdo_attributes(pdo, attrs):
            # an attribute not spelled the common way: every one goes through Context with its warnings and
            # errors, in the schema's order
            for attr, field in _PDO_BOOLEAN_ATTRIBUTES:
                v = get(attr)
                if v is not None:
                    b = _BOOLEANS.get(v)
                    setattr(pdo, field, ctx.boolean(v, el, attr) if b is None else b)
            for attr, name in _PDO_NUMBER_ATTRIBUTES:
                v = get(attr)
                if v is not None:
                    n = known.get(v)
                    setattr(pdo, name, ctx.opt_number(v, el, attr) if n is None else n)
        return pdo

    def _pdo_attributes(self, pdo: Pdo, attrs: list[tuple[str, str]]) -> bool:
        """Set the PDO attributes spelled the common way (``_BOOLEANS``, the number memo) from ``attrs`` (one lxml
        call instead of eleven look-ups); False, with nothing set, when one is not (the caller reads them all)."""
        known = self._numbers
        values = []
        for attr, v in attrs:
            kind = _PDO_ATTRIBUTES.get(attr)
            if kind is None:
                continue
            field, is_bool = kind
            x = _BOOLEANS.get(v) if is_bool else (known.get(v) or _fast_number(v))
            if x is None:
                return False
            values.append((field, x))
        for field, x in values:
            setattr(pdo, field, x)
        return True

    def _number(self, text: str | None, el: Any, what: str) -> int:
        """:meth:`Context.number`, remembering the common spellings (:func:`values.fast_number`) in :attr:`_numbers`."""
        v = _fast_number(text)
        if v is None:
            return self.ctx.number(text, el, what)
        if len(self._numbers) < 65536:
            self._numbers[text] = v  # type: ignore[index]
        return v

    def _in_range(self, v: int, bits: int, what: str, el: Any) -> int:
        """``v`` kept to ``bits`` bits (two's complement when negative), with a warning when it did not fit."""
        if 0 <= v < 1 << bits:
            return v
        masked = v & ((1 << bits) - 1)
        self.ctx.warn("esi-number-range", f"{what} {v} does not fit {bits} bits; read as {masked:#x}", el)
        return masked

    def entry(self, en: Any) -> PdoEntry:
        # the hot loop of a large file (one call per PDO entry): numbers seen before are a dict look-up, and
        # the Name rule is values.name_step
        known = self._numbers
        index = sub = bits = None
        dtype = ""
        name: str | None = None
        rank = NO_NAME
        dep = None
        kids = en[:]
        if len(kids) == 5:  # the common shape (5406 of the largest file's 6392): read in place, in document order
            ci, cs, cb, cn, cd = kids
            if ci.tag == "Index" and cs.tag == "SubIndex" and cb.tag == "BitLen" and cn.tag == "Name" and \
                    cd.tag == "DataType":
                t = ci.text
                index = known.get(t)
                if index is None:
                    index = self._number(t, ci, "Entry/Index")
                dep = ci.get("DependOnSlot")
                t = cs.text
                sub = known.get(t)
                if sub is None:
                    sub = self._number(t, cs, "Entry/SubIndex") if t is not None and t.strip() else 0
                t = cb.text
                bits = known.get(t)
                if bits is None:
                    bits = self._number(t, cb, "Entry/BitLen")
                name = (cn.text or "").strip()  # the only Name: chosen whatever its LcId (values.name_step)
                dtype = (cd.text or "").strip()
                kids = ()
        for c in kids:
            tag = c.tag
            if tag == "Index":
                t = c.text
                index = known.get(t)
                if index is None:
                    index = self._number(t, c, "Entry/Index")
                dep = c.get("DependOnSlot")
            elif tag == "SubIndex":
                t = c.text
                sub = known.get(t)
                if sub is None:
                    sub = self._number(t, c, "Entry/SubIndex") if t is not None and t.strip() else 0
            elif tag == "BitLen":
                t = c.text
                bits = known.get(t)
                if bits is None:
                    bits = self._number(t, c, "Entry/BitLen")
            elif tag == "Name":
                name, rank = name_step(c, name, rank)
            elif tag == "DataType":
                dtype = (c.text or "").strip()
        if index is None:
            raise InputError("PDO Entry has no Index", self.ctx.loc(en))
        if bits is None:
            raise InputError(f"PDO Entry 0x{index:04X}:{sub or 0:02X} has no BitLen", self.ctx.loc(en))
        if index >> 16 or (sub or 0) >> 8 or bits < 0:  # schema-valid, out of range (a negative >> n is -1)
            index = self._in_range(index, 16, "Entry/Index", en)
            sub = self._in_range(sub or 0, 8, "Entry/SubIndex", en)
            if bits < 0:
                self.ctx.warn("esi-number-range", f"Entry/BitLen {bits} is negative; read as 0", en)
                bits = 0
        e = PdoEntry(index, sub or 0, bits, name or "", dtype)
        e.at_line(self.source, en.sourceline)
        if dep is not None:
            e.depend_on_slot = self.ctx.boolean(dep, en, "DependOnSlot")
        return e

    def init_cmd(self, el: Any, protocol: str) -> InitCmd:
        ctx = self.ctx
        transitions = [(t.text or "").strip() for t in el.iterchildren("Transition")]
        if protocol == "SoE":
            idx_el = el.find("IDN")
            index = ctx.number(idx_el.text if idx_el is not None else None, idx_el if idx_el is not None else el, "InitCmd/IDN")
            sub = 0
        else:
            idx_el = el.find("Index")
            index = ctx.number(idx_el.text if idx_el is not None else None, idx_el if idx_el is not None else el, "InitCmd/Index")
            sub = ctx.opt_number(el.findtext("SubIndex"), el, "InitCmd/SubIndex") or 0
        data_el = el.find("Data")
        cmd = InitCmd(protocol, transitions, index, sub,
                      ctx.hexbin(data_el.text, data_el, "InitCmd/Data") if data_el is not None else b"",
                      (el.findtext("Comment") or "").strip(),
                      fixed=ctx.boolean(el.get("Fixed"), el, "Fixed"),
                      complete_access=ctx.boolean(el.get("CompleteAccess"), el, "CompleteAccess"),
                      overwritten_by_module=ctx.boolean(el.get("OverwrittenByModule"), el, "OverwrittenByModule"),
                      location=ctx.loc(el))
        if idx_el is not None and idx_el.get("DependOnSlot") is not None:
            cmd.depend_on_slot = ctx.boolean(idx_el.get("DependOnSlot"), idx_el, "DependOnSlot")
        return cmd

    def mailbox(self, el: Any) -> Mailbox:
        ctx = self.ctx
        mb = Mailbox(data_link_layer=ctx.boolean(el.get("DataLinkLayer"), el, "DataLinkLayer"))
        for child in el.iterchildren():
            tag = child.tag
            if tag not in _PROTOCOLS:
                continue
            mb.protocols.append(tag)
            if tag == "CoE":
                g = child.get
                mb.coe = CoeDetails(
                    sdo_info=ctx.boolean(g("SdoInfo"), child, "SdoInfo"),
                    pdo_assign=ctx.boolean(g("PdoAssign"), child, "PdoAssign"),
                    pdo_config=ctx.boolean(g("PdoConfig"), child, "PdoConfig"),
                    pdo_upload=ctx.boolean(g("PdoUpload"), child, "PdoUpload"),
                    complete_access=ctx.boolean(g("CompleteAccess"), child, "CompleteAccess"),
                    segmented_sdo=ctx.boolean(g("SegmentedSdo"), child, "SegmentedSdo"),
                    eds_file=g("EdsFile", "") or "",
                )
            if tag in ("CoE", "SoE"):
                for ic in child.iterchildren("InitCmd"):
                    mb.init_cmds.append(self.init_cmd(ic, tag))
        return mb

    def sync_manager(self, el: Any, number: int) -> SyncManager:
        ctx = self.ctx
        g = el.get
        # Enable and ControlByte are HexDecValue (the SII enable and control bytes), not booleans: Enable="9"
        # is enable | OP only
        text = g("Enable")
        enable = _BIT.get(text)  # "0" and "1", the common spellings
        if enable is None and text is not None:
            word = text.strip().lower()
            if word in ("true", "false"):
                ctx.warn("esi-sm-enable-boolean", f"Sm Enable {text.strip()!r} is a boolean word; the schema's type "
                         "is the enable byte (HexDecValue); read as " + ("1" if word == "true" else "0"), el)
                text = "1" if word == "true" else "0"
            enable = ctx.unsigned(text, el, "Sm Enable", 8)
        text = g("ControlByte")
        control = self._numbers.get(text) if text is not None else 0
        if control is None or control > 0xFF:
            control = ctx.unsigned(text, el, "Sm ControlByte", 8)
        return SyncManager(
            number, (el.text or "").strip(),
            start_address=ctx.opt_number(g("StartAddress"), el, "Sm StartAddress") or 0,
            default_size=ctx.opt_number(g("DefaultSize"), el, "Sm DefaultSize"),
            min_size=ctx.opt_number(g("MinSize"), el, "Sm MinSize"),
            max_size=ctx.opt_number(g("MaxSize"), el, "Sm MaxSize"),
            control_byte=control or 0,
            enable=True if enable is None else bool(enable & 1),
            virtual=ctx.boolean(g("Virtual"), el, "Sm Virtual"),
            location=ctx.loc(el),
            op_only=ctx.boolean(g("OpOnly"), el, "Sm OpOnly"),
            enable_byte=enable,
        )

    def _sm_kinds(self, dev: Device, elements: list[Any]) -> None:
        """Each sync manager's kind as ETG.2000 defines it: the ``Sm`` text names it (MBoxOut, MBoxIn, Outputs,
        Inputs), the ``ControlByte`` (the SII/ESC control register 0x0804) says it: bits 2-3 the direction
        (01 the master writes: outputs, 00 the master reads: inputs), bits 0-1 the mode (00 buffered, 10 mailbox
        = one buffer). Where the text is missing, is not one of the four words, or names the other direction than
        the ControlByte, the ControlByte decides (with a located warning). A one-buffer sync manager is a mailbox
        unless a PDO of the device names it (process data in one-buffer mode, as EL1252 or EM7004 use it)."""
        named = {p.sm for p in (*dev.rx_pdos, *dev.tx_pdos, *(p for m in dev.modules for p in (*m.rx_pdos, *m.tx_pdos)))}
        for sm, el in zip(dev.sync_managers, elements):
            if el.get("ControlByte") is None:
                continue
            derived = sm_kind_from_control(sm.control_byte, sm.number in named)
            if derived is None or derived == sm.kind:
                continue
            given = _SM_DIRECTION.get(sm.kind)
            if given is not None and given == _SM_DIRECTION[derived]:
                continue  # the same direction: a mailbox-mode process-data SM, or the reverse (the text's word)
            word = sm.kind.lower()
            if given is None and ("outputs" in word or "inputs" in word) and ("outputs" in word) == \
                    _SM_DIRECTION[derived]:
                sm.kind = derived  # a vendor's word that says the same (Beckhoff's DynamicOutputs/DynamicInputs)
                continue
            text = f"{sm.kind!r}" if sm.kind else "no text"
            why = "is not one of MBoxOut, MBoxIn, Outputs, Inputs" if given is None and sm.kind else (
                "names the other direction" if sm.kind else "gives no kind")
            self.ctx.warn("esi-sm-kind", f"Sm {sm.number} has {text}, which {why}; ControlByte "
                          f"#x{sm.control_byte:02X} makes it {derived} (ETG.2000)", el, sm=sm.number,
                          text=sm.kind, kind=derived)
            sm.kind = derived

    def dc(self, el: Any) -> list[DcOpMode]:
        ctx = self.ctx
        out = []
        for om in el.iterchildren("OpMode"):
            first: dict[Any, Any] = {}  # the first child of each tag (what find() gives), in one pass
            for c in om[:]:
                first.setdefault(c.tag, c)
            name_el = first.get("Name")
            m = DcOpMode((name_el.text or "").strip() if name_el is not None else "", lc_text(om, "Desc"))
            aa = first.get("AssignActivate")
            m.assign_activate = ctx.number(aa.text, aa, "AssignActivate") if aa is not None else 0
            for tag, attr in (("CycleTimeSync0", "cycle_time_sync0"), ("ShiftTimeSync0", "shift_time_sync0"),
                              ("CycleTimeSync1", "cycle_time_sync1"), ("ShiftTimeSync1", "shift_time_sync1")):
                t = first.get(tag)
                if t is not None:
                    setattr(m, attr, ctx.opt_number(t.text, t, tag))
                    if t.get("Factor") is not None:
                        setattr(m, attr + "_factor", ctx.number(t.get("Factor"), t, f"{tag} Factor"))
            out.append(m)
        return out

    def eeprom(self, el: Any) -> Eeprom:
        ctx = self.ctx
        ee = Eeprom(assign_to_pdi=ctx.boolean(el.get("AssignToPdi"), el, "AssignToPdi"))
        for child in el.iterchildren():
            tag = child.tag
            if tag == "ByteSize":
                ee.byte_size = ctx.number(child.text, child, "Eeprom/ByteSize")
            elif tag == "ConfigData":
                ee.config_data = ctx.hexbin(child.text, child, "Eeprom/ConfigData")
            elif tag == "BootStrap":
                ee.bootstrap = ctx.hexbin(child.text, child, "Eeprom/BootStrap")
            elif tag == "Data":
                ee.data = ctx.hexbin(child.text, child, "Eeprom/Data")
            elif tag == "Category":
                cat = ctx.number(child.findtext("CatNo"), child, "Category/CatNo")
                payload = b""
                for d in child.iterchildren():
                    if d.tag == "Data":
                        payload = ctx.hexbin(d.text, d, "Category/Data")
                    elif d.tag == "DataString":
                        payload = (d.text or "").encode("latin-1", errors="replace")
                    elif d.tag == "DataUINT":
                        payload = (ctx.number(d.text, d, "DataUINT") & 0xFFFF).to_bytes(2, "little")
                    elif d.tag == "DataUDINT":
                        payload = (ctx.number(d.text, d, "DataUDINT") & 0xFFFFFFFF).to_bytes(4, "little")
                ee.categories.append(EepromCategory(cat, payload))
        return ee

    def slots(self, el: Any) -> list[Slot]:
        ctx = self.ctx
        inc_i = ctx.opt_number(el.get("SlotIndexIncrement"), el, "SlotIndexIncrement")
        inc_p = ctx.opt_number(el.get("SlotPdoIncrement"), el, "SlotPdoIncrement")
        out = []
        for s in el.iterchildren("Slot"):
            slot = Slot(lc_text(s, "Name"),
                        min_instances=ctx.opt_number(s.get("MinInstances"), s, "MinInstances") or 0,
                        max_instances=ctx.opt_number(s.get("MaxInstances"), s, "MaxInstances") or 1,
                        slot_index_increment=ctx.opt_number(s.get("SlotIndexIncrement"), s, "SlotIndexIncrement") or inc_i,
                        slot_pdo_increment=ctx.opt_number(s.get("SlotPdoIncrement"), s, "SlotPdoIncrement") or inc_p)
            for mi in s.iterchildren("ModuleIdent"):
                v = ctx.number(mi.text, mi, "ModuleIdent")
                slot.module_idents.append(v)
                if ctx.flag(mi.get("Default"), mi, "ModuleIdent Default"):  # HexDecValue, non-zero = default
                    slot.default_module = v
            for mc in s.iterchildren("ModuleClass"):
                cls = mc.findtext("Class")  # <ModuleClass><Class>Di</Class><Name>…</Name></ModuleClass>
                slot.module_classes.append((cls if cls is not None else (mc.text or "")).strip())
            out.append(slot)
        return out

    def module(self, el: Any) -> Module:
        ctx = self.ctx
        t = el.find("Type")
        if t is None:
            raise InputError("Module has no Type", ctx.loc(el))
        mod = Module((t.text or "").strip(), lc_text(el, "Name"),
                     ident=ctx.opt_number(t.get("ModuleIdent"), t, "ModuleIdent"),
                     module_class=t.get("ModuleClass", "") or "", location=ctx.loc(el))
        for child in el.iterchildren():
            tag = child.tag
            if tag == "RxPdo":
                mod.rx_pdos.append(self.pdo(child, Direction.RX))
            elif tag == "TxPdo":
                mod.tx_pdos.append(self.pdo(child, Direction.TX))
            elif tag == "Mailbox":
                for proto in ("CoE", "SoE"):
                    p = child.find(proto)
                    if p is not None:
                        mod.init_cmds.extend(self.init_cmd(ic, proto) for ic in p.iterchildren("InitCmd"))
            elif tag == "Profile":
                mod.dictionary = self._dictionary(child)
        return mod

    def _vendor_specific(self, el: Any, dev: Device) -> None:
        """``VendorSpecific`` (schema: ``xs:any``, not validated): TwinCAT's ``AlternativeSmMapping`` is read; other
        content is kept as text in ``Device.extra["VendorSpecific"]``; a part that cannot be read is skipped with a
        located warning ``esi-vendor-specific``, never an error."""
        kept = []
        for vendor in el.iterchildren():
            if not isinstance(vendor.tag, str):
                continue
            if vendor.tag != "TwinCAT":
                kept.append(_element_note(vendor))
                continue
            attrs = " ".join(f"{k}={v}" for k, v in vendor.attrib.items())
            for item in vendor.iterchildren():
                if item.tag == "AlternativeSmMapping":
                    m = self._alternative_sm_mapping(item)
                    if m is not None:
                        dev.alternative_sm_mappings.append(m)
                elif isinstance(item.tag, str):
                    kept.append("TwinCAT/" + _element_note(item))
            if attrs:
                kept.append(f"TwinCAT {attrs}")
        if kept:
            note = "; ".join(kept)[:500]
            old = dev.extra.get("VendorSpecific")
            dev.extra["VendorSpecific"] = f"{old}; {note}" if old else note

    def _alternative_sm_mapping(self, el: Any) -> AlternativeSmMapping | None:
        """One TwinCAT ``AlternativeSmMapping``: SM number → PDO indices (an empty ``<Pdo/>``: no PDO on that SM);
        None, with a located warning, when a part of it is not a number or a boolean."""
        ctx = self.ctx
        name = lc_text(el, "Name")
        try:
            m = AlternativeSmMapping(name, ctx.boolean(el.get("Default"), el, "Default"))
            for sm in el.iterchildren("Sm"):
                no = ctx.number(sm.get("No"), sm, "AlternativeSmMapping/Sm No")
                pdos = m.sms.setdefault(no, [])
                for p in sm.iterchildren("Pdo"):
                    if p.text is not None and p.text.strip():
                        pdos.append(ctx.number(p.text, p, "AlternativeSmMapping/Sm/Pdo"))
        except InputError as exc:
            ctx.warnings.append(Finding(
                "esi-vendor-specific", Severity.WARNING,
                f"TwinCAT AlternativeSmMapping {name!r} skipped (vendor-specific content): {exc.message}",
                exc.location or ctx.loc(el)))
            return None
        return m

    def head(self, el: Any, esi: EsiFile, index: int) -> DeviceHead:
        """The device's ``Type``: all that selection needs."""
        ctx = self.ctx
        t = el.find("Type")
        if t is None:
            raise InputError("Device has no Type element", ctx.loc(el))
        pc = t.get("ProductCode")
        if pc is None:
            ctx.warn("esi-productcode-missing", "Device Type has no ProductCode; taken as 0", t)
        ident = Identity(esi.vendor_id or 0, ctx.opt_number(pc, t, "ProductCode") or 0,
                         ctx.opt_number(t.get("RevisionNo"), t, "RevisionNo") or 0)
        return DeviceHead(index, (t.text or "").strip(), ident, el)

    def device(self, el: Any, esi: EsiFile, head: DeviceHead | None = None) -> Device:
        ctx = self.ctx
        h = head or self.head(el, esi, -1)
        dev = Device(h.identity, h.type_name, lc_text(el, "Name"), physics=el.get("Physics", "") or "",
                     source=self.source, location=ctx.loc(el))
        sm_no = 0
        sm_elements: list[Any] = []
        profile_seen = False
        url_rank = NO_NAME
        for child in el[:]:
            tag = child.tag
            if tag == "TxPdo":
                dev.tx_pdos.append(self.pdo(child, Direction.TX))
            elif tag == "RxPdo":
                dev.rx_pdos.append(self.pdo(child, Direction.RX))
            elif tag == "Sm":
                dev.sync_managers.append(self.sync_manager(child, sm_no))
                sm_elements.append(child)
                sm_no += 1
            elif tag == "Fmmu":
                dev.fmmus.append(Fmmu((child.text or "").strip(), ctx.opt_number(child.get("Sm"), child, "Fmmu Sm"),
                                      ctx.opt_number(child.get("Su"), child, "Fmmu Su")))
            elif tag == "GroupType":
                dev.group_type = (child.text or "").strip()
            elif tag == "Profile" and not profile_seen:
                profile_seen = True
                pn = child.findtext("ProfileNo")
                if pn is not None and pn.strip():
                    dev.profile_no = ctx.number(pn, child, "ProfileNo")
                dev.dictionary = self._dictionary(child)
            elif tag == "Mailbox":
                dev.mailbox = self.mailbox(child)
            elif tag == "Dc":
                dev.dc_opmodes = self.dc(child)
            elif tag == "Eeprom":
                dev.eeprom = self.eeprom(child)
            elif tag == "Slots":
                dev.slots = self.slots(child)
            elif tag == "URL":
                url, url_rank = name_step(child, dev.url or None, url_rank)
                dev.url = url or ""
            elif tag == "ImageData16x14":  # xs:hexBinary: kept in its canonical form (lower case, no blanks)
                dev.image = "".join((child.text or "").split()).lower()
            elif tag == "Image16x14":  # a file name
                dev.image = (child.text or "").strip()
            elif tag == "Info":
                cur = child.find("Electrical/EBusCurrent")
                if cur is not None:
                    dev.ebus_current_ma = ctx.opt_number(cur.text, cur, "EBusCurrent")
                for path in ("Mailbox/Timeout", "StateMachine/Timeout"):  # ms, read by ecattool.target.timeouts
                    for t in child.iterfind(f"{path}/*"):
                        if isinstance(t.tag, str):
                            dev.extra[f"{path}/{t.tag}"] = (t.text or "").strip()
                for vs in child.iterchildren("VendorSpecific"):
                    self._vendor_specific(vs, dev)
            elif tag == "VendorSpecific":
                self._vendor_specific(child, dev)
            elif tag == "HideType":
                hidden = dev.extra.get("HideType", "")
                dev.extra["HideType"] = (hidden + " " if hidden else "") + (child.get("RevisionNo") or child.get("ProductRevision") or "")
            elif tag == "Comment":
                dev.extra.setdefault("Comment", lc_text(el, "Comment"))
            elif isinstance(tag, str) and tag not in _MODELLED:
                # kept, not dropped: attributes and text of elements the model has no field for (Su, ESC, …)
                attrs = " ".join(f"{k}={v}" for k, v in child.attrib.items())
                text = (child.text or "").strip()
                note = " ".join(p for p in (attrs, text if len(child) == 0 else "") if p) or etree_text(child)
                dev.extra[tag] = f"{dev.extra[tag]}; {note}" if tag in dev.extra else note
        dev.end_line = _next_line(el)
        dev.group_name = esi.groups.get(dev.group_type, "")
        if dev.slots and esi.modules:
            idents = {i for s in dev.slots for i in s.module_idents}
            classes = {c for s in dev.slots for c in s.module_classes if c}
            dev.modules = [m for m in esi.modules if m.ident in idents or (m.module_class and m.module_class in classes)]
        self._sm_kinds(dev, sm_elements)
        return dev


def _next_line(el: Any) -> int | None:
    """The line of whatever follows ``el`` in the document (its next sibling, else its parent's, …); None at the end."""
    while el is not None:
        nxt = el.getnext()
        if nxt is not None:
            return nxt.sourceline  # type: ignore[no-any-return]
        el = el.getparent()
    return None


def _read(path: Path) -> bytes:
    from ecattool.fileio import read_bytes

    return read_bytes(path, MAX_XML_BYTES)  # bounded by the bytes read: a FIFO or /dev/zero has no size on disk


def load_bytes(data: bytes, source: str = "<bytes>", base_dir: str | Path | None = None,
               lazy: bool = False) -> EsiFile:
    """Read an ESI document from bytes. ``base_dir`` resolves DictionaryFile/InfoReference paths; ``lazy``
    returns a :class:`LazyEsiFile` (devices built when selected or listed)."""
    reader = Reader(source, Path(base_dir) if base_dir is not None else None)
    try:
        return without_gc(lambda: reader.read(data, lazy))
    except EcatToolError:
        raise
    except RecursionError:
        raise InputError("ESI document is nested too deeply", Location(source)) from None


def load(path: str | Path, lazy: bool = False) -> EsiFile:
    """Read an ESI file (EtherCATInfo, EtherCATModule or EtherCATDict root); ``lazy`` as in :func:`load_bytes`."""
    p = Path(path)
    return load_bytes(_read(p), str(p), p.parent, lazy)
