"""Data types of the standard CiA-402 objects that are mapped into PDOs (CiA 402-2 object definitions).

For startup-list formats that carry an entry's size but not its sign (ecmc's 10-argument
``EcAddEntryComplete``, a CSV without types): a target position 607Ah is an INTEGER32 on every drive, and a
ros2 or TwinCAT configuration written as UNSIGNED32 would read negative positions as large positive ones.
"""

from __future__ import annotations

#: index -> type name (every sub-index of an ARRAY/RECORD has the same type here, sub-index 0 aside)
CIA402_TYPES: dict[int, str] = {
    0x603F: "UINT", 0x6040: "UINT", 0x6041: "UINT", 0x605A: "INT", 0x605B: "INT", 0x605C: "INT",
    0x605D: "INT", 0x605E: "INT", 0x6060: "SINT", 0x6061: "SINT", 0x6062: "DINT", 0x6063: "DINT",
    0x6064: "DINT", 0x6065: "UDINT", 0x6066: "UINT", 0x6067: "UDINT", 0x6068: "UINT", 0x6069: "DINT",
    0x606B: "DINT", 0x606C: "DINT", 0x606D: "UINT", 0x606E: "UINT", 0x606F: "UINT", 0x6070: "UINT",
    0x6071: "INT", 0x6072: "UINT", 0x6073: "UINT", 0x6074: "INT", 0x6075: "UDINT", 0x6076: "UDINT",
    0x6077: "INT", 0x6078: "INT", 0x6079: "UDINT", 0x607A: "DINT", 0x607B: "DINT", 0x607C: "DINT",
    0x607D: "DINT", 0x607E: "USINT", 0x607F: "UDINT", 0x6080: "UDINT", 0x6081: "UDINT", 0x6082: "UDINT",
    0x6083: "UDINT", 0x6084: "UDINT", 0x6085: "UDINT", 0x6086: "INT", 0x6087: "UDINT", 0x6088: "INT",
    0x6098: "SINT", 0x6099: "UDINT", 0x609A: "UDINT", 0x60B0: "DINT", 0x60B1: "DINT", 0x60B2: "INT",
    0x60B8: "UINT", 0x60B9: "UINT", 0x60BA: "DINT", 0x60BB: "DINT", 0x60BC: "DINT", 0x60BD: "DINT",
    0x60C1: "DINT", 0x60E0: "UINT", 0x60E1: "UINT", 0x60F2: "UINT", 0x60F4: "DINT", 0x60FA: "DINT",
    0x60FC: "DINT", 0x60FD: "UDINT", 0x60FE: "UDINT", 0x60FF: "DINT", 0x6402: "UINT", 0x6502: "UDINT",
}
_BITS = {"USINT": 8, "SINT": 8, "UINT": 16, "INT": 16, "UDINT": 32, "DINT": 32}


def standard_type(index: int, subindex: int, bit_len: int) -> str | None:
    """The CiA-402 type of ``index:subindex`` when it is a standard object of that size, else None."""
    name = CIA402_TYPES.get(index)
    if name is None or (subindex == 0 and index in _ARRAYS) or _BITS[name] != bit_len:
        return None
    return name


def standard_bits(index: int, subindex: int) -> int | None:
    """The CiA-402 bit size of ``index:subindex`` (8 for the count of an ARRAY/RECORD), None if not standard."""
    name = CIA402_TYPES.get(index)
    if name is None:
        return None
    return 8 if subindex == 0 and index in _ARRAYS else _BITS[name]


#: the ARRAY/RECORD objects of the table (their sub-index 0 is a count, not of the element type)
_ARRAYS = frozenset({0x607B, 0x607D, 0x6099, 0x60C1, 0x60FE})


#: CiA 402-2 names of the standard VAR objects, for lookups by name where a vendor ESI names them its own way
#: (Copley "Axis A Control word", Ingenia "Position set-point", Synapticon "Op Mode"); normalised as
#: ``od.model.normalize_name`` does (lower case, letters and digits only)
CIA402_NAMES: dict[str, int] = {
    "errorcode": 0x603F, "controlword": 0x6040, "statusword": 0x6041, "quickstopoptioncode": 0x605A,
    "shutdownoptioncode": 0x605B, "disableoperationoptioncode": 0x605C, "haltoptioncode": 0x605D,
    "faultreactionoptioncode": 0x605E, "modesofoperation": 0x6060, "modesofoperationdisplay": 0x6061,
    "positiondemandvalue": 0x6062, "positionactualinternalvalue": 0x6063, "positionactualvalue": 0x6064,
    "followingerrorwindow": 0x6065, "followingerrortimeout": 0x6066, "positionwindow": 0x6067,
    "positionwindowtime": 0x6068, "velocitydemandvalue": 0x606B, "velocityactualvalue": 0x606C,
    "targettorque": 0x6071, "maxtorque": 0x6072, "torquedemand": 0x6074, "torqueactualvalue": 0x6077,
    "targetposition": 0x607A, "homeoffset": 0x607C, "polarity": 0x607E, "maxprofilevelocity": 0x607F,
    "maxmotorspeed": 0x6080, "profilevelocity": 0x6081, "profileacceleration": 0x6083,
    "profiledeceleration": 0x6084, "quickstopdeceleration": 0x6085, "motionprofiletype": 0x6086,
    "homingmethod": 0x6098, "homingacceleration": 0x609A, "touchprobefunction": 0x60B8,
    "touchprobestatus": 0x60B9, "followingerroractualvalue": 0x60F4, "digitalinputs": 0x60FD,
    "targetvelocity": 0x60FF, "supporteddrivemodes": 0x6502,
}


#: CiA-301 communication objects whose name and data type are the same on every CoE slave (CiA 301, 7.5.2;
#: ETG.1000.6 5.6.7.4): (index, sub-index) -> (name, type name). ``sdo read`` of one of them types the value with
#: this table instead of loading a dictionary (ecattool.online.dictionary.standard_typed)
CIA301_OBJECTS: dict[tuple[int, int], tuple[str, str]] = {
    (0x1000, 0): ("Device type", "UDINT"), (0x1001, 0): ("Error register", "USINT"),
    (0x1008, 0): ("Manufacturer device name", "VISIBLE_STRING"),
    (0x1009, 0): ("Manufacturer hardware version", "VISIBLE_STRING"),
    (0x100A, 0): ("Manufacturer software version", "VISIBLE_STRING"),
    (0x1018, 0): ("Number of entries", "USINT"), (0x1018, 1): ("Vendor ID", "UDINT"),
    (0x1018, 2): ("Product code", "UDINT"), (0x1018, 3): ("Revision number", "UDINT"),
    (0x1018, 4): ("Serial number", "UDINT"),
}
