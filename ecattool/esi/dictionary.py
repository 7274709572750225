"""ESI ``Dictionary`` → :class:`ObjectDictionary`: DataTypes resolved recursively, Objects flattened to entries.

Resolution of a type name, in order:
1. a file ``DataType`` with ``SubItem`` children is a record (or an ARRAY object's layout);
2. one with ``ArrayInfo`` is an array of its ``BaseType``;
3. one with a ``BaseType`` takes the base's CoE type (plus ``EnumInfo`` when present);
4. a standard CoE name (``UINT``, ``DINT32``, ``STRING(6)``, ``BIT2``) resolves through ``od.types``;
5. a vendor name with only a ``BitSize`` (``DT0800``) becomes the unsigned type / BITn of that size;
6. anything else gets ``datatype=None`` and a warning — never an exception.
"""

from __future__ import annotations

from typing import Any

from ecattool.errors import EcatToolError, InputError
from ecattool.esi.values import NO_NAME, Context, fast_number, lc_text, name_step
from ecattool.findings import Finding, Severity
from ecattool.od.model import Access, Entry, ObjectCode, ObjectDictionary, OdObject
from ecattool.od.types import BY_CODE, DataType, Kind, lookup, parse_array_name
from ecattool.record import Record

_USINT = BY_CODE[0x05]
_UINT_BY_BITS = {8: BY_CODE[0x05], 16: BY_CODE[0x06], 24: BY_CODE[0x16], 32: BY_CODE[0x07], 40: BY_CODE[0x18],
                 48: BY_CODE[0x19], 56: BY_CODE[0x1A], 64: BY_CODE[0x1B]}
_BITS = {i: BY_CODE[0x30 + i - 1] for i in range(1, 9)}
_DEFAULT_ACCESS = Access.parse("ro")
_INT_KINDS = frozenset({Kind.UNSIGNED, Kind.SIGNED, Kind.BITS, Kind.BOOL})
_INFO_TAGS = frozenset({"DefaultValue", "MinValue", "MaxValue"})  # a DataType SubItem with its own values
_MAX_VALUE_BITS = 8 * 65536  # no CoE value is larger; guards encoders against absurd sizes in hostile files


class ResolvedType(Record):
    """A type name resolved against the file's DataTypes."""

    __slots__ = ("name", "kind", "datatype", "bits", "enum", "element", "lbound", "elements", "element_type")
    name: str
    kind: str  # "base", "array", "record", "unknown"
    datatype: DataType | None
    bits: int | None
    enum: dict[int, str]
    element: Any  # the DataType element (records: SubItems; arrays: ArrayInfo)
    lbound: int
    elements: int
    element_type: str

    def __init__(self, name: str, kind: str, datatype: DataType | None = None, bits: int | None = None,
                 enum: dict[int, str] | None = None, element: Any = None, lbound: int = 0, elements: int = 0,
                 element_type: str = "") -> None:
        self.name = name
        self.kind = kind
        self.datatype = datatype
        self.bits = bits
        self.enum = {} if enum is None else enum
        self.element = element
        self.lbound = lbound
        self.elements = elements
        self.element_type = element_type


def _blob(name: str, bits: int | None) -> DataType:
    """A record used as a value (nested struct, array of records): an octet string of its size."""
    return DataType(0x000A, name, Kind.OCTETS, bits)


class TypeResolver:
    """Memoised resolution of type names for one ``Dictionary`` (or one ``Module``'s dictionary)."""

    def __init__(self, datatypes_el: Any, ctx: Context) -> None:
        self.ctx = ctx
        self.raw: dict[str, Any] = {}
        self.memo: dict[str, ResolvedType] = {}
        if datatypes_el is not None:
            for dt in datatypes_el.iterchildren("DataType"):
                n = dt.findtext("Name")
                if n is not None:
                    self.raw.setdefault(n.strip(), dt)

    def resolve(self, name: str, where: Any = None, _depth: int = 0) -> ResolvedType:
        name = (name or "").strip()
        r = self.memo.get(name)
        if r is not None:
            return r
        if _depth > 32:
            self.ctx.warn("esi-type-cycle", f"data type {name!r} refers to itself (cycle or nesting deeper than 32)", where)
            return ResolvedType(name, "unknown")
        r = self._resolve(name, where, _depth)
        self.memo[name] = r
        return r

    def _bitsize(self, el: Any, what: str) -> int | None:
        t = el.findtext("BitSize")
        return _not_negative(self.ctx.opt_number(t, el, what), el, what, self.ctx) if t is not None else None

    def _resolve(self, name: str, where: Any, depth: int) -> ResolvedType:
        ctx = self.ctx
        el = self.raw.get(name)
        if el is not None:
            bits = self._bitsize(el, f"BitSize of data type {name!r}")
            if el.find("SubItem") is not None:
                return ResolvedType(name, "record", None, bits, element=el)
            arr = el.find("ArrayInfo")
            if arr is not None:
                lb = ctx.number(arr.findtext("LBound", "0"), arr, "ArrayInfo/LBound")
                n = ctx.number(arr.findtext("Elements"), arr, "ArrayInfo/Elements")
                base = (el.findtext("BaseType") or "").strip()
                if not base:
                    parsed = parse_array_name(name)
                    base = parsed[2] if parsed else ""
                return ResolvedType(name, "array", None, bits, element=el, lbound=lb, elements=n, element_type=base)
            enum: dict[int, str] = {}
            for e in el.iterchildren("EnumInfo"):
                enum[ctx.number(e.findtext("Enum"), e, "EnumInfo/Enum")] = lc_text(e, "Text")
            base_name = el.findtext("BaseType")
            if base_name is not None and base_name.strip() and base_name.strip() != name:
                base = self.resolve(base_name, el, depth + 1)
                return ResolvedType(name, base.kind if base.kind != "unknown" else "unknown", base.datatype,
                                    bits if bits is not None else base.bits, enum or base.enum, base.element,
                                    base.lbound, base.elements, base.element_type)
            std = lookup(name)
            if std is not None:
                return ResolvedType(name, "base", std, bits if bits is not None else std.bits, enum)
            if bits is not None:
                dt = _BITS.get(bits) if bits < 8 else _UINT_BY_BITS.get(bits)
                if dt is None and 0 < bits <= 64:
                    dt = DataType(0x0000, name, Kind.BITS, bits)  # e.g. UINT14: an unsigned bit field
                if dt is not None:
                    return ResolvedType(name, "base", dt, bits, enum)
            ctx.warn("esi-type-unknown", f"data type {name!r} has no base type and no standard size; kept untyped", el,
                     type=name)
            return ResolvedType(name, "unknown", None, bits, enum)
        std = lookup(name)
        if std is not None:
            return ResolvedType(name, "base", std, std.bits)
        parsed = parse_array_name(name)
        if parsed is not None:
            lo, hi, base = parsed
            elem = self.resolve(base, where, depth + 1)
            bits = elem.bits * (hi - lo + 1) if elem.bits is not None else None
            return ResolvedType(name, "array", None, bits, lbound=lo, elements=hi - lo + 1, element_type=base)
        ctx.warn("esi-type-unknown", f"data type {name!r} is not defined in the file's DataTypes nor a CoE type",
                 where, type=name)
        return ResolvedType(name, "unknown")


_FLAGS_MEMO: dict[tuple[Any, ...], tuple[Access, str, bool, bool, str]] = {}


def _flags(flags_el: Any, ctx: Context) -> tuple[Access, str, bool, bool, str]:
    """(access, PdoMapping, Backup, Setting, Category) of a ``Flags`` element (memoised by content)."""
    if flags_el is None:
        return _DEFAULT_ACCESS, "", False, False, ""
    key_parts: list[Any] = []
    for c in flags_el[:]:
        tag = c.tag
        if tag == "Access":
            key_parts.append((tag, c.text, c.get("ReadRestrictions"), c.get("WriteRestrictions")))
        elif tag in ("PdoMapping", "Backup", "Setting", "Category"):
            key_parts.append((tag, c.text))
    key = tuple(key_parts)
    hit = _FLAGS_MEMO.get(key)
    if hit is not None:
        return hit
    access = _DEFAULT_ACCESS
    mapping = category = ""
    backup = setting = False
    for part in key_parts:
        tag, text = part[0], part[1]
        if tag == "Access":
            access = Access.parse(text, part[2], part[3])
        elif tag == "PdoMapping":
            mapping = text or ""
        elif tag == "Category":
            category = (text or "").strip()
        elif (text or "").strip():
            v = ctx.number(text, flags_el, f"Flags/{tag}") != 0
            if tag == "Backup":
                backup = v
            else:
                setting = v
    result = (access, mapping, backup, setting, category)
    if len(_FLAGS_MEMO) < 4096:
        _FLAGS_MEMO[key] = result
    return result


_ENTRY_SLOTS = tuple(Entry.__slots__)


def _make_clone() -> Any:
    """``_clone(entries, location)``: shallow copies of a template's entries (objects of one record type share
    the template) at the object's location, in one call per object.

    Generated from ``Entry.__slots__`` so that fields added to the shared model are copied too.
    """
    body = "\n".join(f"        c.{n} = e.{n}" for n in _ENTRY_SLOTS if n != "location")
    ns: dict[str, Any] = {"_new": object.__new__, "Entry": Entry}
    source = (f"def _clone(entries, location):\n    out = []\n    for e in entries:\n        c = _new(Entry)\n{body}\n"
              "        c.location = location\n        out.append(c)\n    return out\n")
    exec(source, ns)  # noqa: S102 - fixed template
    return ns["_clone"]


_clone = _make_clone()


#: Largest entry a dictionary may declare: 128 KiB (four times the largest in the corpus, Copley's 32 KiB). A
#: BitSize of 34359738360 would make every reader that stores a value (the simulator) allocate 4 GiB.
MAX_ENTRY_BITS = 1 << 20
#: Largest sum of the entries of one dictionary (the real ones hold well under 1 MiB)
MAX_DICTIONARY_BYTES = 16 * 1024 * 1024


def _bounded_size(obj: Any, total: int, location: Any) -> int:
    """The bytes of ``obj``'s entries, checked against :data:`MAX_ENTRY_BITS` and, with the ``total`` so far,
    :data:`MAX_DICTIONARY_BYTES` (issue 28.2: every size a file gives has a limit, checked where it is read)."""
    size = 0
    for entry in obj.entries.values():
        if entry.bit_size > MAX_ENTRY_BITS:
            raise InputError(f"0x{obj.index:04X}:{entry.subindex:02X} has a BitSize of {entry.bit_size}, beyond the "
                             f"{MAX_ENTRY_BITS} bits (128 KiB) of any real CoE object", location)
        size += (entry.bit_size + 7) // 8
    if total + size > MAX_DICTIONARY_BYTES:
        raise InputError(f"the dictionary's objects add up to more than {MAX_DICTIONARY_BYTES} bytes", location)
    return size


def _not_negative(v: int | None, el: Any, what: str, ctx: Context) -> int | None:
    """A size or offset: the schema allows any integer; a negative one makes its object unreadable (skipped)."""
    if v is not None and v < 0:
        raise InputError(f"{what} {v} is negative", ctx.loc(el))
    return v


def _signed_fix(value: int, dt: DataType | None, bits: int) -> int:
    """Signed sentinels: ``#xFFFFFFFF`` for a DINT minimum means -1 (two's complement of the entry size)."""
    if dt is not None and dt.kind is Kind.SIGNED and bits and (1 << (bits - 1)) <= value < (1 << bits):
        return value - (1 << bits)
    return value


def _default_data(entry: Entry, text: str | None, el: Any, ctx: Context) -> bytes:
    """The value of a ``DefaultData`` element; an integer given in fewer bytes than its type is zero-extended."""
    raw = None
    if text is not None and not len(text) & 1:  # Context.hexbin's common case, without the call
        try:
            raw = bytes.fromhex(text)
        except ValueError:
            pass
    if raw is None:
        raw = ctx.hexbin(text, el, "DefaultData")
    size = (entry.bit_size + 7) // 8
    dt = entry.datatype
    if dt is not None and dt.kind in _INT_KINDS and 0 < len(raw) < size <= 8:
        ctx.warn("esi-default-short", f"DefaultData {raw.hex()} is shorter than {entry.type_name or dt.name} "
                 f"({size} bytes); zero-extended", el)
        raw = raw.ljust(size, b"\x00")
    return raw


def _apply_info(entry: Entry, info: Any, ctx: Context) -> None:
    """Fill default/minimum/maximum from an ``Info`` element (DefaultData, DefaultValue, DefaultString, …)."""
    if info is None:
        return
    dt = entry.datatype
    for child in info[:]:  # comments and processing instructions match none of the tags below
        tag = child.tag
        text = child.text
        if tag == "DefaultData":
            entry.default = _default_data(entry, text, child, ctx)
        elif tag == "DefaultValue":
            entry.default = _encode_value(entry, text, child, ctx)
        elif tag == "DefaultString":
            entry.default = (text or "").encode("latin-1", errors="replace")
        elif tag in ("MinValue", "MaxValue"):
            v: int | float | None = _number_or_float(text, child, ctx, tag)
            if isinstance(v, int):
                v = _signed_fix(v, dt, entry.bit_size)
            if tag == "MinValue":
                entry.minimum = v
            else:
                entry.maximum = v
        elif tag in ("MinData", "MaxData"):
            raw = ctx.hexbin(text, child, tag)
            val = None
            if dt is not None and dt.is_numeric:
                try:
                    val = dt.decode(raw, entry.bit_size)
                except EcatToolError:
                    ctx.warn("esi-info-size", f"{tag} has {len(raw)} bytes, not the size of {entry.type_name}", child)
            if tag == "MinData":
                entry.minimum = val
            else:
                entry.maximum = val


def _number_or_float(text: str | None, el: Any, ctx: Context, what: str) -> int | float | None:
    if text is None or not text.strip():
        return None
    s = text.strip()
    if s[:2] not in ("#x", "0x") and any(c in s for c in ".eE") and not s.lstrip("+-").isdigit():
        try:
            return float(s)
        except ValueError:
            pass
    return ctx.number(s, el, what)


def _encode_value(entry: Entry, text: str | None, el: Any, ctx: Context) -> bytes | None:
    dt = entry.datatype
    if dt is None:
        return None
    if max(dt.bits or 0, entry.bit_size) > _MAX_VALUE_BITS:
        ctx.warn("esi-default-size", f"DefaultValue of a {entry.bit_size}-bit entry is not encoded (larger than 64 KiB)", el)
        return None
    try:
        if dt.kind in (Kind.STRING, Kind.UNICODE):
            return dt.encode(text or "", entry.bit_size or None)
        v = _number_or_float(text, el, ctx, "DefaultValue")
        if v is None:
            return None
        if isinstance(v, int):
            v = _signed_fix(v, dt, entry.bit_size)
            if dt.kind is Kind.OCTETS:
                return v.to_bytes(max(1, (entry.bit_size + 7) // 8), "little", signed=v < 0)
        return entry.encode(v)
    except (EcatToolError, OverflowError) as exc:
        ctx.warn("esi-default-range", f"DefaultValue {(text or '').strip()!r} does not fit {entry.type_name}: {exc}", el)
        return None


class DictionaryBuilder:
    """Builds one :class:`ObjectDictionary` from a ``Dictionary`` element."""

    def __init__(self, dict_el: Any, ctx: Context) -> None:
        self.el = dict_el
        self.ctx = ctx
        self.types = TypeResolver(dict_el.find("DataTypes"), ctx)
        self._templates: dict[tuple[str, tuple[Access, str, bool, bool, str]], _Template] = {}
        self._numbers: dict[str | None, int] = {}
        self._flags_free: dict[str, _Template] = {}  # record types whose SubItems all have their own Flags

    def _number(self, text: str | None, el: Any, what: str) -> int:
        """:meth:`Context.number`, with the common spellings (:func:`values.fast_number`) remembered by text."""
        v = self._numbers.get(text)
        if v is None:
            v = fast_number(text)
            if v is None:
                return self.ctx.number(text, el, what)
            self._numbers[text] = v
        return v

    def _opt_number(self, text: str | None, el: Any, what: str) -> int | None:
        if text is None or not text.strip():
            return None
        return self._number(text, el, what)

    def build(self) -> ObjectDictionary:
        od = ObjectDictionary()
        objects = self.el.find("Objects")
        if objects is None:
            return od
        total = 0
        for obj_el in objects.iterchildren("Object"):
            try:
                obj = self.object(obj_el)
                total += _bounded_size(obj, total, obj.location)  # the object's Location: ctx.loc(obj_el)
            except EcatToolError as exc:
                self.ctx.warnings.append(Finding("esi-object-skipped", Severity.WARNING,
                                                 f"object skipped: {exc.message}", exc.location or self.ctx.loc(obj_el)))
                continue
            od.add(obj)
        return od

    def object(self, el: Any) -> OdObject:
        ctx = self.ctx
        loc = ctx.loc(el)
        index_t = type_name = bits_t = None
        name: str | None = None
        rank = NO_NAME
        flags_el = info = None
        comment = ""
        idx_el = el
        for c in el[:]:
            tag = c.tag
            if tag == "Index":
                index_t, idx_el = c.text, c
            elif tag == "Name":
                name, rank = name_step(c, name, rank)
            elif tag == "Type":
                type_name = (c.text or "").strip()
            elif tag == "BitSize":
                bits_t = c.text
            elif tag == "Flags":
                flags_el = c
            elif tag == "Info":
                info = c
            elif tag == "Comment" and not comment:
                comment = (c.text or "").strip()
        index = self._number(index_t, idx_el, "Object/Index")
        if not 0 <= index <= 0xFFFF:  # schema-valid (any integer), not an object index: the object is skipped
            raise InputError(f"Object/Index {index} is not an object index (0 … 0xFFFF)", ctx.loc(idx_el))
        type_name = type_name or ""
        name = name or ""
        bits = self._opt_number(bits_t, el, "Object/BitSize")
        if bits is not None and bits < 0:
            _not_negative(bits, el, "Object/BitSize", ctx)
        flags = _flags(flags_el, ctx)
        t = self.types.resolve(type_name, el)
        if t.kind == "record":
            key = (t.name, flags)
            template = self._templates.get(key)
            if template is None:
                template = self._templates[key] = self._template(t, flags)
            entries = _clone(template.entries, loc)
            if info is not None:
                self._apply_subitem_infos(entries, template.first_by_name, info, index)
            return OdObject(index, name, template.code, dict(zip(template.subindices, entries)), type_name=type_name,
                            category=flags[4], location=loc)
        else:
            dt = t.datatype
            if t.kind == "array":
                dt = _blob(type_name, bits if bits is not None else t.bits)
            size = bits if bits is not None else (t.bits or 0)
            access, mapping, backup, setting, category = flags
            e = Entry(0, name, dt, size, type_name=type_name, access=access, pdo_mapping=mapping, enum=dict(t.enum),
                      backup=backup, setting=setting, category=category, comment=comment, location=loc)
            _apply_info(e, info, ctx)
            return OdObject(index, name, ObjectCode.VAR, {0: e}, type_name=type_name, category=flags[4], location=loc)

    def _template(self, t: ResolvedType, obj_flags: tuple[Access, str, bool, bool, str]) -> _Template:
        """The entries of record type ``t`` for an object with ``obj_flags``.

        Where every SubItem of the type has its own Flags the object's flags do not matter, and the entries made
        for one object serve objects with other flags too (a type flattened again would give the same entries
        and, if the first time gave no warnings, no warnings either).
        """
        template = self._flags_free.get(t.name)
        if template is None:
            n_warnings = len(self.ctx.warnings)
            entries, is_array, used_obj_flags = self._flatten(t, obj_flags)
            template = _Template(entries, is_array)
            if not used_obj_flags and len(self.ctx.warnings) == n_warnings:
                self._flags_free[t.name] = template
        return template

    def _flatten(self, t: ResolvedType,
                 obj_flags: tuple[Access, str, bool, bool, str]) -> tuple[list[Entry], bool, bool]:
        """(entries, ARRAY-like, whether ``obj_flags`` were used for a SubItem without its own Flags)."""
        ctx = self.ctx
        used_obj_flags = False
        out: list[Entry] = []
        next_sub = 0
        array_like = True
        expanded = False
        sub_items = list(t.element.iterchildren("SubItem"))
        for si in sub_items:
            si_type = ""
            si_name: str | None = None
            rank = NO_NAME
            sidx_t = bits_t = offs_t = flags_el = None
            has_info = False
            for c in si[:]:
                tag = c.tag
                if tag == "Name":
                    si_name, rank = name_step(c, si_name, rank)
                elif tag == "Type":
                    si_type = (c.text or "").strip()
                elif tag == "SubIdx":
                    sidx_t = c.text
                elif tag == "BitSize":
                    bits_t = c.text
                elif tag == "BitOffs":
                    offs_t = c.text
                elif tag == "Flags" and flags_el is None:
                    flags_el = c
                elif tag in _INFO_TAGS:
                    has_info = True
            si_name = si_name or ""
            st = self.types.resolve(si_type, si)
            sidx = self._number(sidx_t, si, "SubItem/SubIdx") if sidx_t is not None and sidx_t.strip() else None
            if sidx is not None and not 0 <= sidx <= 0xFF:
                raise InputError(f"SubItem/SubIdx {sidx} is not a sub-index (0 … 255)", ctx.loc(si))
            bits = self._opt_number(bits_t, si, "SubItem/BitSize")
            offs = self._opt_number(offs_t, si, "SubItem/BitOffs") or 0
            if (bits or 0) < 0 or offs < 0:
                _not_negative(bits, si, "SubItem/BitSize", ctx)
                _not_negative(offs, si, "SubItem/BitOffs", ctx)
            if flags_el is not None:
                access, mapping, backup, setting, category = _flags(flags_el, ctx)
            else:
                access, mapping, backup, setting, category = obj_flags
                used_obj_flags = True
            if st.kind == "array" and sidx is None:
                elem = self.types.resolve(st.element_type, si)
                n = st.elements
                if n < 0 or max(st.lbound, next_sub) + n > 256:
                    ctx.warn("esi-array-size", f"array {st.name!r} has {n} elements from {st.lbound}; sub-indices end at 255",
                             si)
                    n = max(0, 256 - max(st.lbound, next_sub))
                total = bits if bits is not None else st.bits
                ebits = elem.bits if elem.bits is not None else ((total // n) if total and n else 0)
                edt = elem.datatype if elem.kind == "base" else (_blob(elem.name, ebits) if elem.kind != "unknown" else None)
                start = max(st.lbound, next_sub)
                for k in range(n):
                    sub = start + k
                    e = Entry(sub, f"SubIndex {sub:03d}", edt, ebits or 0, type_name=elem.name, bit_offset=offs + k * (ebits or 0),
                              access=access, pdo_mapping=mapping, enum=dict(elem.enum), backup=backup, setting=setting,
                              category=category)
                    out.append(e)
                next_sub = start + n
                expanded = True
                continue
            if sidx is None:
                sidx = next_sub
            if sidx != 0:
                array_like = False
            if st.kind == "base":
                dt = st.datatype
            elif st.kind in ("record", "array"):
                dt = _blob(si_type, bits if bits is not None else st.bits)
            else:
                dt = None
            size = bits if bits is not None else (st.bits or 0)
            e = Entry(sidx, si_name, dt, size, type_name=si_type, bit_offset=offs, access=access, pdo_mapping=mapping,
                      enum=dict(st.enum), backup=backup, setting=setting, category=category)
            if has_info:
                _apply_info(e, si, ctx)
            out.append(e)
            next_sub = sidx + 1
        return out, expanded and array_like, used_obj_flags

    def _apply_subitem_infos(self, entries: list[Entry], first_by_name: dict[str, int], info: Any, index: int) -> None:
        # one pass per Info/SubItem of every record object (7518 in the largest corpus file): children are read
        # from slices (el[:] builds the proxies in one call; a child iterator per element costs more than its
        # proxies); the Name rule is values.name_step
        ctx = self.ctx
        pos = -1
        n_entries = len(entries)
        for si in info[:]:
            if si.tag != "SubItem":
                continue
            pos += 1
            kids = si[:]
            if len(kids) == 2 and kids[0].tag == "Name" and kids[1].tag == "Info" and kids[0].get("LcId") is None:
                n = (kids[0].text or "").strip()  # the common shape (every one of the largest file's 7518)
                sub_info = kids[1]
            else:
                n_opt: str | None = None
                rank = NO_NAME
                sub_info = None
                for c in kids:
                    tag = c.tag
                    if tag == "Name":
                        n_opt, rank = name_step(c, n_opt, rank)
                    elif tag == "Info" and sub_info is None:
                        sub_info = c
                n = n_opt or ""
            at = first_by_name.get(n, pos)
            if at >= n_entries:
                ctx.warn("esi-info-subitem", f"object 0x{index:04X}: Info/SubItem {n!r} matches no sub-index", si)
                continue
            e = entries[at]
            if n and not n.startswith("SubIndex ") and e.name.startswith("SubIndex "):
                e.name = n
            if sub_info is not None:
                values = sub_info[:]
                if len(values) == 1 and values[0].tag == "DefaultData":  # 7476 of the 7518 in the largest file
                    e.default = _default_data(e, values[0].text, values[0], ctx)
                else:
                    _apply_info(e, sub_info, ctx)


class _Template(Record):
    """The entries of one record type with one set of object flags, cloned for each object of that type."""

    __slots__ = ("entries", "code", "subindices", "first_by_name")
    entries: list[Entry]
    code: ObjectCode
    subindices: list[int]
    first_by_name: dict[str, int]  # entry name -> position of the first entry of that name (Info/SubItem lookup)

    def __init__(self, entries: list[Entry], is_array: bool) -> None:
        self.entries = entries
        self.code = ObjectCode.ARRAY if is_array else ObjectCode.RECORD
        self.subindices = [e.subindex for e in entries]
        self.first_by_name = {}
        for at, e in enumerate(entries):
            self.first_by_name.setdefault(e.name, at)


def build_dictionary(dict_el: Any, ctx: Context) -> ObjectDictionary:
    return DictionaryBuilder(dict_el, ctx).build()


__all__ = ["TypeResolver", "ResolvedType", "DictionaryBuilder", "build_dictionary"]
