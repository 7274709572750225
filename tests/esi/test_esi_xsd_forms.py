"""Every typed attribute and element of the ETG.2000 XSDs is read by its type, in every form the schema allows.

The list of typed attributes and elements is not written here: :mod:`tests.xsd_types` derives it from the
bundled XSDs (v1.17, v1.14). Two tests use it:

* **same value, every spelling** — each typed value of a corpus ESI is rewritten in another lexical form of its
  schema type (``#x1A00`` → ``6656``, ``+6656``, ``#x001a00``; ``1`` → ``true``, `` true ``; hex binary in upper
  case with blanks), the variant is validated against both XSDs, and the model read from it must equal the
  model read from the original, field by field;
* **new value, every spelling** — for each typed attribute or element the reader models (the table
  :data:`READ`), a new value is written in each form and read back through the model field it feeds.

Every typed path of the XSD is either in :data:`READ` or in :data:`NOT_MODELLED` (with the reason), so a path
the reader models with a guessed type cannot hide.
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from functools import cache
from typing import Any

import pytest
from lxml import etree

from ecattool.esi import load_bytes, materialize
from tests.conftest import corpus_path
from tests.esi.test_esi_selective import _same
from tests.xsd_types import normalize, typed_paths

XSD = {"EtherCATInfo": ("v1.17", "v1.14_ETG2000_1.0.10"), "EtherCATModule": ("v1.14_ETG2000_1.0.10",),
       "EtherCATDict": ("v1.17", "v1.14_ETG2000_1.0.10")}
#: corpus ESIs that both XSDs accept (SOURCES.md lists the three that are not: Copley's odd hex, CUxxxx's
#: dictionary without DataTypes, the IgH dump without a vendor name)
VALID = ["beckhoff_AX2xxx.xml", "beckhoff_AX5021-xxxx-0001_Dict.xml", "beckhoff_AX5xxx.xml", "beckhoff_EK11xx.xml",
         "beckhoff_EL1xxx.xml", "beckhoff_EM7xxx.xml", "elmo_Elmo_ECAT_00010420_V11.xml",
         "etg_ETG2001_ModulesSlots_CiA402.xml", "ingenia_eve-xcr-e_esi.xml", "inovance_SV660_EOE_1Axis_V9.12.xml",
         "itegva_E7x_Series.xml", "smc_EX260-SECx_V11.xml", "synapticon_Somanet_CiA402-single.xml",
         "synapticon_Somanet_CtrlProto.xml", "weidmueller_UR20_FBC.xml", "weidmueller_UR20_IO.xml"]
READ_TYPES = ("HexDecValue", "xs:int", "xs:integer", "xs:boolean", "xs:hexBinary")


@cache
def schema(version: str, root: str) -> etree.XMLSchema:
    return etree.XMLSchema(etree.parse(str(corpus_path("xsd", version, f"{root}.xsd"))))


@cache
def typed(root: str) -> dict[str, str]:
    """Normalized path → schema type, over every bundled XSD version that has this root; where the versions
    disagree (v1.14 types EnumInfo/Enum xs:integer, v1.17 HexDecValue), both, as ``"HexDecValue|xs:integer"``:
    a variant uses only the forms both allow."""
    out: dict[str, str] = {}
    for version in XSD[root]:
        for path, t in typed_paths(corpus_path("xsd", version, f"{root}.xsd"), root):
            have = out.get(path)
            out[path] = t if have is None or t in have.split("|") else "|".join(sorted({*have.split("|"), t}))
    return out


def parse(name: str) -> etree._ElementTree:
    return etree.ElementTree(etree.fromstring(corpus_path("esi", name).read_bytes()))


def root_name(tree: etree._ElementTree) -> str:
    return etree.QName(tree.getroot()).localname


def assert_valid(tree: etree._ElementTree) -> None:
    root = root_name(tree)
    for version in XSD[root]:
        s = schema(version, root)
        assert s.validate(tree), f"variant not valid against {version}: {s.error_log.last_error}"


def read(tree: etree._ElementTree, name: str, follow: bool = True) -> Any:
    """Load a variant; ``follow``: DictionaryFile/InfoReference files resolved beside the corpus file."""
    data = etree.tostring(tree, xml_declaration=True, encoding="UTF-8")
    return load_bytes(data, name, base_dir=corpus_path("esi") if follow else None)


def _thin(tree: etree._ElementTree, most: int) -> None:
    """Keep at most ``most`` devices (or modules), evenly spread over the file (the large files repeat
    themselves: 141 terminals, 82 I/O slices; a respelled copy of each would cost seconds, not coverage)."""
    root = tree.getroot()
    for container in ("Descriptions/Devices/Device", "Modules/Module", "Descriptions/Modules/Module"):
        items = root.findall(container)
        if len(items) > most:
            step = len(items) / most
            keep = {int(i * step) for i in range(most)}
            for i, el in enumerate(items):
                if i not in keep:
                    el.getparent().remove(el)


# --- lexical forms -------------------------------------------------------------------------------------------
def forms(types: str, value: Any) -> list[str]:
    """The lexical forms of ``value`` that every schema type of ``types`` (``a|b``) allows."""
    first, *rest = types.split("|")
    out = _forms(first, value)
    for t in rest:
        allowed = _forms(t, value)
        out = [f for f in out if f in allowed]
    return out


def _forms(t: str, value: Any) -> list[str]:
    """The lexical forms of ``value`` that schema type ``t`` allows (HexDecValue: xs:string, no blanks)."""
    if t == "xs:boolean":
        return ["true", "1", " true "] if value else ["false", "0", " false "]
    if t == "xs:hexBinary":
        h = value.hex()
        return [h, h.upper(), f" {h.upper()} "]
    v = int(value)
    sign, mag = ("-", -v) if v < 0 else ("", v)
    out = [str(v), f"{sign or '+'}{mag}", f"{sign}00{mag}"]
    if t == "HexDecValue":
        if v >= 0:
            out += [f"#x{v:x}", f"#x{v:X}", f"#x000{v:x}"]
    else:
        out.append(f" {v} ")
    return out


def value_of(types: str, text: str) -> Any:
    t = types.split("|")[0]
    s = text.strip()
    if t == "xs:boolean":
        return s in ("true", "1")
    if t == "xs:hexBinary":
        return bytes.fromhex(s)
    return int(s[2:], 16) if s.startswith("#x") else int(s)


def occurrences(tree: etree._ElementTree) -> list[tuple[str, str, Any, str | None]]:
    """(normalized path, schema type, element, attribute or None) of every typed value the file holds."""
    root = root_name(tree)
    types = typed(root)
    out = []

    def walk(el: Any, raw: str) -> None:
        path = normalize(raw)
        for attr in el.attrib:
            t = types.get(f"{path}@{attr}")
            if t is not None and all(x in READ_TYPES for x in t.split("|")):
                out.append((f"{path}@{attr}", t, el, attr))
        t = types.get(path)
        if t is not None and all(x in READ_TYPES for x in t.split("|")) and el.text is not None and len(el) == 0:
            out.append((path, t, el, None))
        for c in el:
            if isinstance(c.tag, str):
                walk(c, f"{raw}/{etree.QName(c).localname}")

    walk(tree.getroot(), root)
    return out


def put(el: Any, attr: str | None, text: str) -> None:
    if attr is None:
        el.text = text
    else:
        el.set(attr, text)


# --- same value, every spelling ------------------------------------------------------------------------------
def _model(esi: Any) -> Any:
    materialize(esi)
    for d in esi.devices:
        d.extra = sorted(d.extra)  # unmodelled elements are kept as their text: compare which, not how spelled
    return esi


@pytest.mark.parametrize("name", VALID)
def test_every_typed_value_respelled_reads_as_the_same_model(name: str) -> None:
    """Each occurrence gets the next form of its value (cycling), so each form of each type is used."""
    tree = parse(name)
    _thin(tree, 12)
    base = _model(read(tree, name, follow=False))
    occ = occurrences(tree)
    assert occ
    used: dict[str, set[int]] = {}
    count: dict[str, int] = {}
    for path, t, el, attr in occ:
        text = el.get(attr) if attr else el.text
        fs = forms(t, value_of(t, text))
        k = count[t] = (count.get(t, -1) + 1)
        k %= len(fs)
        used.setdefault(t, set()).add(k)
        put(el, attr, fs[k])
    assert_valid(tree)
    variant = _model(read(tree, name, follow=False))
    for field in ("vendor_id", "devices", "modules", "dictionary"):
        _same(getattr(variant, field), getattr(base, field), f"{name}: {field}")
    assert [(w.rule, w.location.line) for w in variant.warnings] == [(w.rule, w.location.line) for w in base.warnings]
    if len(occ) > 300:  # large files: every form of every type they use occurred
        sample = {"xs:hexBinary": b"\x01", "xs:boolean": True}
        missed = {t: ks for t, ks in used.items() if ks != set(range(len(forms(t, sample.get(t, 1)))))}
        assert missed == {}


# --- new value, every spelling -------------------------------------------------------------------------------
INF = 10**9


def _anc(el: Any, *tags: str) -> Any:
    return el if etree.QName(el).localname in tags else next(a for a in el.iterancestors() if etree.QName(a).localname in tags)


def _nth(el: Any) -> int:
    """Position of ``el`` among its siblings of the same tag."""
    return [c for c in el.getparent() if c.tag == el.tag].index(el)


def _dev(esi: Any, el: Any) -> Any:
    return next(d for d in esi.devices if d.location.line <= el.sourceline < (d.end_line or INF))


def _mod(esi: Any, el: Any) -> Any:
    m = _anc(el, "Module")
    return next(mod for mod in esi.modules if mod.location.line == m.sourceline)


def _pdo(esi: Any, el: Any) -> Any:
    p = _anc(el, "RxPdo", "TxPdo")
    owners = [*esi.devices, *esi.modules]
    return next(x for o in owners for x in (*o.rx_pdos, *o.tx_pdos) if x.location.line == p.sourceline)


def _entry(esi: Any, el: Any) -> Any:
    e = _anc(el, "Entry")
    return next(x for x in _pdo(esi, e).entries if x.location.line == e.sourceline)


def _init(esi: Any, el: Any) -> Any:
    c = _anc(el, "InitCmd")
    cmds = [x for d in esi.devices if d.mailbox for x in d.mailbox.init_cmds]
    cmds += [x for m in esi.modules for x in m.init_cmds]
    return next(x for x in cmds if x.location.line == c.sourceline)


def _sm(esi: Any, el: Any) -> Any:
    return next(s for s in _dev(esi, el).sync_managers if s.location.line == el.sourceline)


def _opmode(esi: Any, el: Any) -> Any:
    return _dev(esi, el).dc_opmodes[_nth(_anc(el, "OpMode"))]


def _slot(esi: Any, el: Any) -> Any:
    return _dev(esi, el).slots[_nth(_anc(el, "Slot"))]


def _category(esi: Any, el: Any) -> Any:
    return _dev(esi, el).eeprom.categories[_nth(_anc(el, "Category"))]


Getter = Callable[[Any, Any], Any]
READ: dict[str, Getter] = {
    "Vendor/Id": lambda f, el: f.vendor_id,
    "Device/Type@ProductCode": lambda f, el: _dev(f, el).product_code,
    "Device/Type@RevisionNo": lambda f, el: _dev(f, el).revision,
    "Device/Info/Electrical/EBusCurrent": lambda f, el: _dev(f, el).ebus_current_ma,
    "Device/Profile/ProfileNo": lambda f, el: _dev(f, el).profile_no,
    "Device/Fmmu@Sm": lambda f, el: _dev(f, el).fmmus[_nth(el)].sm,
    "Device/Fmmu@Su": lambda f, el: _dev(f, el).fmmus[_nth(el)].su,
    "Device/Sm@MinSize": lambda f, el: _sm(f, el).min_size,
    "Device/Sm@MaxSize": lambda f, el: _sm(f, el).max_size,
    "Device/Sm@DefaultSize": lambda f, el: _sm(f, el).default_size,
    "Device/Sm@StartAddress": lambda f, el: _sm(f, el).start_address,
    "Device/Sm@ControlByte": lambda f, el: _sm(f, el).control_byte,
    "Device/Sm@Enable": lambda f, el: _sm(f, el).enable_byte,
    "Device/Sm@Virtual": lambda f, el: _sm(f, el).virtual,
    "Device/Sm@OpOnly": lambda f, el: _sm(f, el).op_only,
    "Device/Mailbox@DataLinkLayer": lambda f, el: _dev(f, el).mailbox.data_link_layer,
    "Device/Mailbox/SoE/InitCmd/IDN": lambda f, el: _init(f, el).index,
    "Device/Mailbox/SoE/InitCmd/Data": lambda f, el: _init(f, el).data,
    "Device/Dc/OpMode/AssignActivate": lambda f, el: _opmode(f, el).assign_activate,
    "Device/Eeprom/ByteSize": lambda f, el: _dev(f, el).eeprom.byte_size,
    "Device/Eeprom/ConfigData": lambda f, el: _dev(f, el).eeprom.config_data,
    "Device/Eeprom/BootStrap": lambda f, el: _dev(f, el).eeprom.bootstrap,
    "Device/Eeprom/Data": lambda f, el: _dev(f, el).eeprom.data,
    "Device/Eeprom@AssignToPdi": lambda f, el: _dev(f, el).eeprom.assign_to_pdi,
    "Device/Eeprom/Category/CatNo": lambda f, el: _category(f, el).cat_no,
    "Device/Eeprom/Category/Data": lambda f, el: _category(f, el).data,
    "Device/Eeprom/Category/DataUINT": lambda f, el: int.from_bytes(_category(f, el).data, "little"),
    "Device/Eeprom/Category/DataUDINT": lambda f, el: int.from_bytes(_category(f, el).data, "little"),
    "Device/Slots/Slot/ModuleIdent": lambda f, el: _slot(f, el).module_idents[_nth(el)],
    "Device/Slots/Slot/ModuleIdent@Default": lambda f, el: int(_slot(f, el).default_module == _slot(f, el).module_idents[_nth(el)]),
    "Device/Slots/Slot@MinInstances": lambda f, el: _slot(f, el).min_instances,
    "Device/Slots/Slot@MaxInstances": lambda f, el: _slot(f, el).max_instances,
    "Device/Slots/Slot@SlotPdoIncrement": lambda f, el: _slot(f, el).slot_pdo_increment,
    "Device/Slots/Slot@SlotIndexIncrement": lambda f, el: _slot(f, el).slot_index_increment,
    "Module/Type@ModuleIdent": lambda f, el: _mod(f, el).ident,
}
for _coe in ("SdoInfo", "PdoAssign", "PdoConfig", "PdoUpload", "CompleteAccess", "SegmentedSdo"):
    READ[f"Device/Mailbox/CoE@{_coe}"] = (
        lambda f, el, a="".join("_" + c.lower() if c.isupper() else c for c in _coe).lstrip("_"): getattr(_dev(f, el).mailbox.coe, a))
for _tag, _field in (("CycleTimeSync0", "cycle_time_sync0"), ("ShiftTimeSync0", "shift_time_sync0"),
                     ("CycleTimeSync1", "cycle_time_sync1"), ("ShiftTimeSync1", "shift_time_sync1")):
    READ[f"Device/Dc/OpMode/{_tag}"] = lambda f, el, a=_field: getattr(_opmode(f, el), a)
    READ[f"Device/Dc/OpMode/{_tag}@Factor"] = lambda f, el, a=_field + "_factor": getattr(_opmode(f, el), a)
for _owner in ("Device", "Module"):
    for _dir in ("RxPdo", "TxPdo"):
        _p = f"{_owner}/{_dir}"
        READ[f"{_p}/Index"] = lambda f, el: _pdo(f, el).index
        READ[f"{_p}/Index@DependOnSlot"] = lambda f, el: _pdo(f, el).depend_on_slot
        READ[f"{_p}/Exclude"] = lambda f, el: _pdo(f, el).excludes[_nth(el)]
        READ[f"{_p}/Entry/Index"] = lambda f, el: _entry(f, el).index
        READ[f"{_p}/Entry/Index@DependOnSlot"] = lambda f, el: _entry(f, el).depend_on_slot
        READ[f"{_p}/Entry/SubIndex"] = lambda f, el: _entry(f, el).subindex
        READ[f"{_p}/Entry/BitLen"] = lambda f, el: _entry(f, el).bit_len
        for _a, _f in (("Fixed", "fixed"), ("Mandatory", "mandatory"), ("Virtual", "virtual"), ("Sm", "sm"),
                       ("Su", "su"), ("PdoOrder", "pdo_order"), ("OSFac", "os_fac"), ("OSMin", "os_min"),
                       ("OSMax", "os_max"), ("OSIndexInc", "os_index_inc"),
                       ("OverwrittenByModule", "overwritten_by_module")):
            READ[f"{_p}@{_a}"] = lambda f, el, a=_f: getattr(_pdo(f, el), a)
    _c = f"{_owner}/Mailbox/CoE/InitCmd"
    READ[f"{_c}/Index"] = lambda f, el: _init(f, el).index
    READ[f"{_c}/SubIndex"] = lambda f, el: _init(f, el).subindex
    READ[f"{_c}/Data"] = lambda f, el: _init(f, el).data
    for _a, _f in (("Fixed", "fixed"), ("CompleteAccess", "complete_access"), ("OverwrittenByModule", "overwritten_by_module")):
        if _owner == "Device" or _a != "OverwrittenByModule":
            READ[f"{_c}@{_a}"] = lambda f, el, a=_f: getattr(_init(f, el), a)
READ["Module/Mailbox/CoE/InitCmd/Index@DependOnSlot"] = lambda f, el: _init(f, el).depend_on_slot

#: typed paths the model has no field for, by prefix (the reader does not read them; they never abort a read)
NOT_MODELLED = {
    "@LcId": "language ids pick the English name (test_esi_schema tests their forms)",
    "Dictionary/": "object dictionaries: checked by the respelling test against the original model",
    "Vendor@FileVersion": "not modelled", "Vendor/ImageData16x14": "images not modelled",
    "Groups/": "group sort order and images not modelled",
    "Device@": "Invisible, Crc32 not modelled", "Module@": "Crc32 not modelled",
    "Device/Type@": "other Type attributes (SerialNo, TcCfgModeSafeOp, …) not modelled",
    "Device/HideType@": "kept as text in Device.extra", "Device/AlternativeType@": "not modelled",
    "Device/SubDevice@": "not modelled", "Device/Sci/": "SCI data not modelled",
    "Device/Info/": "Info other than EBusCurrent (timeouts, ports, EtherCATp …) not modelled",
    "Device/Profile/": "channel info and diagnosis messages not modelled",
    "Device/Profile@": "Channel not modelled",
    "Module/Profile/": "channel info and diagnosis messages not modelled",
    "Device/Fmmu@OpOnly": "not modelled",
    "Device/Sm@OneByteMode": "obsolete", "Device/Sm@Watchdog": "obsolete", "Device/Sm@FixedAssignment": "obsolete",
    "Device/Su@": "kept as text in Device.extra", "Device/ESC/": "kept as text in Device.extra",
    "Device/ImageData16x14": "kept as hex text in Device.image (respelling test)",
    "Module/ImageData16x14": "images not modelled",
    "Device/Dc@": "DC flags not modelled", "Device/Dc/OpMode/Sm": "obsolete per-SM DC data",
    "Device/Dc/OpMode/ShiftTimeSync": "Input, delay times not modelled",
    "Device/Eeprom/Category@PreserveOnlineData": "not modelled",
    "Device/Slots@": "slot-group attributes; the increments are defaults of each Slot (respelling test)",
    "Device/Slots/Slot@": "slot groups, Default/Fallback module of a slot not modelled",
    "Device/Slots/Slot/ModuleClass/": "not modelled", "Device/Slots/Slot/ImageData16x14": "images not modelled",
    "Device/Slots/SlotGroupData": "not modelled", "Device/Slots/ModulePdoGroup@": "not modelled",
    "Device/Slots/SlotSelections/": "not modelled",
    "Device/Mailbox@RealTimeMode": "not modelled", "Device/Mailbox/AoE": "AoE details not modelled",
    "Device/Mailbox/EoE": "EoE details not modelled", "Device/Mailbox/SoE@": "not modelled",
    "Device/Mailbox/SoE/InitCmd@Chn": "SoE channel not modelled", "Device/Mailbox/SoE/DiagMessages": "not modelled",
    "Device/Mailbox/CoE@": "other CoE flags (DS402Channels, DiagHistory, …) not modelled",
    "Device/Mailbox/CoE/Object/": "CoE Object (obsolete form of InitCmd) not modelled",
    "Module/Mailbox/CoE@": "module CoE flags not modelled",
    "Device/Mailbox/CoE/InitCmd/Data@": "AdaptAutomatically not modelled",
    "Module/Mailbox/CoE/InitCmd/Data@": "AdaptAutomatically not modelled",
    "Module/Mailbox/CoE/InitCmd/Index@DependOnSlotGroup": "slot groups not modelled",
    "Module/Type@": "ModulePdoGroup, SRA_ParameterSupported not modelled",
    "Module/SafetyParaMapping": "safety parameter mappings not modelled",
    "Module/Profile": "not modelled",
}
for _owner in ("Device", "Module"):
    for _dir in ("RxPdo", "TxPdo"):
        for _rest in ("@SRA_Parameter", "@SafetyConnNumber", "/ExcludedSm", "/Entry@", "/Exclude@",
                      "/Index@DependOnSlotGroup", "/Entry/Index@DependOnSlotGroup"):
            NOT_MODELLED[f"{_owner}/{_dir}{_rest}"] = "safety, slot groups, per-entry flags not modelled"


def test_every_typed_path_of_the_schema_is_read_by_its_type_or_known_not_modelled() -> None:
    paths = {p: t for root in XSD for p, t in typed(root).items()}
    assert len(paths) > 400 and paths["Device/Sm@Enable"] == "HexDecValue"
    assert paths["Dictionary/DataTypes/DataType/EnumInfo/Enum"] == "HexDecValue|xs:integer"
    assert paths["Device/Slots/Slot/ModuleIdent@Default"] == "HexDecValue"
    unknown = [p for p in READ if p not in paths]
    assert unknown == [], "READ names paths the XSDs do not have"
    unclassified = sorted(p for p in paths if p not in READ and not any(
        p.startswith(k) or p.endswith(k) for k in NOT_MODELLED))
    assert unclassified == []


#: where the value test finds each path (the first file with the parent element); extra elements inserted
#: where no corpus file has them
VALUE_FILES = ["synapticon_Somanet_CiA402-single.xml", "etg_ETG2001_ModulesSlots_CiA402.xml",
               "elmo_Elmo_ECAT_00010420_V11.xml", "beckhoff_AX5xxx.xml", "weidmueller_UR20_IO.xml"]
SIGNED = ("EBusCurrent", "@Factor", "ShiftTimeSync0", "ShiftTimeSync1")


def _new_value(types: str, path: str, old: Any, k: int) -> Any:
    t = types.split("|")[0]
    if t == "xs:boolean":
        return not old if k % 2 == 0 else bool(old)
    if t == "xs:hexBinary":
        return bytes([0x2B, 0x01])
    if path.endswith("@Default"):
        return 1
    if any(s in path for s in SIGNED) and k % 2:
        return -43
    return 43


def _attr_paths() -> dict[str, list[str]]:
    out: dict[str, list[str]] = {}
    for p in READ:
        if "@" in p:
            out.setdefault(p.split("@", 1)[0], []).append(p)
    return out


def _targets(tree: etree._ElementTree) -> dict[str, tuple[str, Any, str | None]]:
    """The first occurrence of each READ path in ``tree``: (type, element, attribute); an attribute the file
    does not use is set on the first element that can carry it."""
    root = root_name(tree)
    types = typed(root)
    attrs = _attr_paths()
    out: dict[str, tuple[str, Any, str | None]] = {}
    for path, t, el, attr in occurrences(tree):
        if path in READ:
            out.setdefault(path, (t, el, attr))

    def walk(el: Any, raw: str) -> None:
        for p in attrs.get(normalize(raw), ()):
            if p not in out and types.get(p) in READ_TYPES:
                out[p] = (types[p], el, p.split("@", 1)[1])
        for c in el:
            if isinstance(c.tag, str):
                walk(c, f"{raw}/{etree.QName(c).localname}")

    walk(tree.getroot(), root)
    return out


def _prepare(name: str) -> bytes:
    """A small variant of a corpus file that holds every element the value test needs: its first device (or
    module) and the first one with each feature, a module PDO with an ``Exclude``, EEPROM categories of every
    data form and a device whose EEPROM is raw ``Data`` (no small corpus file has those)."""
    tree = parse(name)
    root = tree.getroot()
    for container, features in (("Descriptions/Devices/Device", ("Mailbox/CoE/InitCmd", "RxPdo/Exclude", "TxPdo/Exclude")),
                                ("Modules/Module", ("Mailbox/CoE/InitCmd",))):
        items = root.findall(container)
        keep = {0} | {next(i for i, d in enumerate(items) if d.find(f) is not None)
                      for f in features if any(d.find(f) is not None for d in items)}
        for i, d in enumerate(items):
            if i not in keep:
                d.getparent().remove(d)
    for tag in ("RxPdo", "TxPdo"):
        pdo = root.find(f".//Module/{tag}")
        if pdo is not None and pdo.find("Exclude") is None:
            pdo.findall("Name")[-1].addnext(etree.Element("Exclude"))
            pdo.find("Exclude").text = "#x1"
    eeprom = root.find(".//Device/Eeprom")
    if eeprom is not None:
        after = [c for c in eeprom if c.tag in ("ByteSize", "ConfigData", "BootStrap", "Category")][-1]
        for tag in ("Data", "DataUINT", "DataUDINT"):
            cat = etree.Element("Category")
            etree.SubElement(cat, "CatNo").text = "1"
            etree.SubElement(cat, tag).text = "00" if tag == "Data" else "1"
            after.addnext(cat)
        raw = copy.deepcopy(eeprom.getparent())
        raw_eeprom = raw.find("Eeprom")
        for c in list(raw_eeprom):
            raw_eeprom.remove(c)
        etree.SubElement(raw_eeprom, "Data").text = "00"
        eeprom.getparent().addnext(raw)
    assert_valid(tree)
    return etree.tostring(tree, xml_declaration=True, encoding="UTF-8")


def test_every_read_path_takes_a_new_value_in_every_form() -> None:
    covered: set[str] = set()
    for name in VALUE_FILES:
        data = _prepare(name)
        for k in range(6):  # the longest form list (HexDecValue) has 6 forms
            tree = etree.ElementTree(etree.fromstring(data))
            expected = {}
            for path, (t, el, attr) in _targets(tree).items():
                text = el.get(attr) if attr else el.text
                old = value_of(t, text) if text is not None and text.strip() else None
                v = _new_value(t, path, old, k)
                fs = forms(t, v)
                put(el, attr, fs[k % len(fs)])
                expected[path] = (el, v, fs[k % len(fs)])
            assert_valid(tree)
            esi = read(tree, name)
            for path, (el, v, text) in expected.items():
                got = READ[path](esi, el)
                assert got == v, f"{name}: {path} = {text!r} read as {got!r}, expected {v!r}"
            covered |= set(expected)
    assert sorted(set(READ) - covered) == []


EXTREMES = {"HexDecValue": ["-1", "#xFFFFFFFFFFFFFFFFFFFF", "0"], "xs:int": ["-2147483648", "2147483647", "0"],
            "xs:integer": ["-99999999999999999999", "99999999999999999999", "0"], "xs:hexBinary": ["", "", ""],
            "xs:boolean": ["0", "1", "0"]}


@pytest.mark.parametrize("k", range(3))
def test_extreme_values_the_schema_allows_still_load_every_device(k: int) -> None:
    """Whatever the XSD accepts loads: every typed value at once set to an extreme of its type (negative, far
    wider than any register, empty binary), schema-validated, and read with each device and module kept."""
    for name in VALUE_FILES:
        tree = etree.ElementTree(etree.fromstring(_prepare(name)))
        for path, t, el, attr in occurrences(tree):
            first = t.split("|")[0]
            text = EXTREMES[first][k]
            if "|" in t:  # HexDecValue|xs:integer (bounded like xs:int in v1.14): a decimal both allow
                text = EXTREMES["xs:int"][k]
            put(el, attr, text)
        assert_valid(tree)
        esi = read(tree, name)
        materialize(esi)
        root = tree.getroot()
        assert len(esi.devices) == len(root.findall("Descriptions/Devices/Device")), name
        assert len(esi.modules) >= len(root.findall(".//Modules/Module")), name
