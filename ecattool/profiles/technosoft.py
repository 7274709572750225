"""Technosoft iPOS (vendor 0x1A3), from "iPOS CoE Programming" P091.064.UM.0524.

Models and product codes: §1.5.4.6 / §4.8.6. Firmware revisions are the firmware name without its leading
"F" as four ASCII characters, most significant first (F515I → "515I" → 0x35313549 = 892417353). The firmware
gates which objects exist (digest "Firmware families"): CiA-402-2 factor objects from F515K / FA0xx, the
obsolete CiA-402 factor set before, FoE from F515F, EoE from F515J, and so on.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from ecattool.errors import SelectionError
from ecattool.esi.model import CoeDetails, Device, Identity, InitCmd, Pdo
from ecattool.profiles._common import (
    ProductInfo,
    ProfileInfo,
    assemble_device,
    build_dictionary,
    choose,
    load_data,
    set_default,
)
from ecattool.profiles.rules import FamilyRules

NAME = "technosoft-ipos"
VENDOR_ID = 0x000001A3
RX_INDICES = (0x1600, 0x1601, 0x1602, 0x1603)
TX_INDICES = (0x1A00, 0x1A01, 0x1A02, 0x1A03)
DUMMY_INDICES = frozenset({1, 2, 3, 4, 5, 6, 7, 0x207D})
DEVICE_TYPE = 0x00060192  # printed "60192h for iPOS family" (§4.8.1), kept as printed (ambiguity 3)

#: firmware names the manual mentions (§1.3, §3.1, §5, §17); any F51xY / FA0xY name is accepted
REVISIONS = ("F515F", "F515G", "F515I", "F515J", "F515K", "FA00C", "FA00G", "FA02G")
DEFAULT_REVISION = "F515K"

PRODUCTS = (
    ProductInfo("ipos360x-vx-cat", "iPOS360x VX-CAT", 28002021, REVISIONS, DEFAULT_REVISION, "§1.5.4.6"),
    ProductInfo("ipos4808-my-cat-sto", "iPOS4808 MY-CAT-STO", 27314121, REVISIONS, DEFAULT_REVISION, "§1.5.4.6"),
    ProductInfo("ipos4808-bx-cat-sto", "iPOS4808 BX-CAT-STO", 27314221, REVISIONS, DEFAULT_REVISION, "§1.5.4.6"),
    ProductInfo("ipos4808-bx-cat", "iPOS4808 BX-CAT", 27214221, REVISIONS, DEFAULT_REVISION,
                "product code 0x019F418D from corpus configs/ecmc_ecmciPOS4808.cmd (label P027.214.E221 by §4.8.6)"),
)

_NAME_RE = re.compile(r"^F?(51[015][A-Z]|A0[0-9][A-Z])$")


@dataclass(frozen=True, slots=True)
class Firmware:
    """A Technosoft firmware name such as ``F515K`` or ``FA00G`` and what it enables."""

    name: str

    @classmethod
    def parse(cls, value: str | int | None) -> "Firmware":
        """``"F515K"``, ``"515K"``, ``892417355``, ``"0x3531354B"`` → Firmware("F515K")."""
        if value is None or value == "":
            return cls(DEFAULT_REVISION)
        if isinstance(value, str) and value.strip().lower().startswith(("0x", "#x")):
            try:
                value = int(value.strip()[2:], 16)
            except ValueError:  # "0x" alone, "0xZZ": the same answer as any other wrong name
                raise SelectionError(f"{value!r} is not a Technosoft firmware revision "
                                     "(write e.g. F515K, 515K, FA00G or 0x3531354B)") from None
        if isinstance(value, str) and value.strip().isdigit() and len(value.strip()) > 4:
            value = int(value.strip())
        if isinstance(value, int):
            try:
                text = value.to_bytes(4, "big").decode("ascii")
            except (OverflowError, UnicodeDecodeError):
                raise SelectionError(f"revision {value:#x} is not a Technosoft firmware name in ASCII") from None
        else:
            text = value.strip().upper()
        m = _NAME_RE.match(text)
        if not m:
            raise SelectionError(
                f"{value!r} is not a Technosoft firmware revision (write e.g. F515K, 515K, FA00G or 0x3531354B)")
        return cls("F" + m.group(1))

    @property
    def line(self) -> str:
        return self.name[:4]

    @property
    def letter(self) -> str:
        return self.name[4]

    @property
    def revision(self) -> int:
        """1018h sub 3 / ESI revision: the name without "F", ASCII, most significant byte first."""
        return int.from_bytes(self.name[1:].encode("ascii"), "big")

    @property
    def is_fa(self) -> bool:
        return self.line.startswith("FA")

    def has(self, requirement: str) -> bool:
        """Whether an object gated by ``requirement`` (see ``_build_data.TS_REQUIRES``) exists."""
        f515 = self.line == "F515"
        checks = {
            "cia402-2": self.is_fa or (f515 and self.letter >= "K"),
            "cia402-obsolete": not (self.is_fa or (f515 and self.letter >= "K")),
            "F515K+": self.is_fa or (f515 and self.letter >= "K"),
            "F515K/FA00C+": (self.is_fa and self.letter >= "C") or (f515 and self.letter >= "K"),
            "F515x": f515,
            "FA0xx": self.is_fa,
            "FA00G+": self.is_fa and self.letter >= "G",
            "F515J+": self.is_fa or (f515 and self.letter >= "J"),
            "F515F+": self.is_fa or (f515 and self.letter >= "F"),
            "F515I+": self.is_fa or (f515 and self.letter >= "I"),
        }
        return checks.get(requirement, True)

    @property
    def factor_group(self) -> str:
        return "cia402-2" if self.has("cia402-2") else "cia402-obsolete"

    @property
    def protocols(self) -> list[str]:
        out = ["CoE"]
        if self.has("F515J+"):
            out.append("EoE")
        if self.has("F515F+"):
            out.append("FoE")
        return out


def product_code_from_label(product_id: str) -> int:
    """Drive label product ID → 1018h sub 2 (§4.8.6): ``P027.214.E121`` → 27214121 (the digits, decimal)."""
    m = re.fullmatch(r"\s*P?(\d{3})\.(\d{3})\.[A-Z]?(\d{3})\s*", product_id.upper())
    if not m:
        raise SelectionError(f"{product_id!r} is not a Technosoft product ID (write e.g. P027.214.E121)")
    return int("".join(m.groups()))


def ascii_msb_first(value: int) -> str:
    """Revision / serial convention (1018h sub 3, §4.8.6): first character in the most significant byte."""
    return value.to_bytes(4, "big").decode("latin-1")


def ascii_lsb_first(value: int) -> str:
    """2060h convention (§4.8.5): first character in the least significant byte (0x322E3156 → "V1.2")."""
    return value.to_bytes(4, "little").decode("latin-1")


def serial_text(value: int) -> str:
    """1018h sub 4 (§4.8.6): two ASCII letters then a 16-bit hex number (0x4C451158 → "LE1158")."""
    return ascii_msb_first(value)[:2] + f"{value & 0xFFFF:04X}"


INFO = ProfileInfo(
    name=NAME,
    family=NAME,
    title="Technosoft iPOS drives (CoE)",
    vendor_id=VENDOR_ID,
    vendor_name="Technosoft",
    products=PRODUCTS,
    default_product=PRODUCTS[0].name,
    source="iPOS CoE Programming P091.064.UM.0524",
    notes=("revision = firmware name without 'F' in ASCII (F515K, F515I …); F515K/FA0xx and newer use the "
           "CiA-402-2 factor group, older firmware the obsolete CiA-402 factor objects",),
)


def _max_pdo_bytes(_pdos: list[Pdo]) -> int:
    return 4 * 64 // 8


def load(product: str | None = None, revision: str | int | None = None) -> Device:
    key = choose({p.name: p for p in PRODUCTS}, product, INFO.default_product, "product", NAME)
    prod = next(p for p in PRODUCTS if p.name == key)
    fw = Firmware.parse(revision)
    data = load_data("technosoft")
    obsolete = not fw.has("cia402-2")

    def names(e: dict[str, object]) -> str | None:
        return str(e["name_obsolete"]) if obsolete and "name_obsolete" in e else None

    od = build_dictionary(data, fw.has, names=names)
    set_default(od, 0x1018, 2, prod.product_code)
    set_default(od, 0x1018, 3, fw.revision)
    set_default(od, 0x1018, 4, 0)
    set_default(od, 0x100A, 0, fw.name)
    if obsolete:
        for idx, nm in ((0x6093, "Position factor"), (0x6094, "Velocity encoder factor"), (0x6097, "Acceleration factor")):
            obj = od.get(idx)
            if obj is not None:
                obj.name = nm
    init = [InitCmd("CoE", ["PS"], 0x6060, 0, bytes([8]), comment="Technosoft XML startup: modes of operation = CSP (§1.6.1)")]
    return assemble_device(
        identity=Identity(VENDOR_ID, prod.product_code, fw.revision),
        type_name=prod.title,
        name=f"{prod.title} ({fw.name})",
        od=od,
        rx_indices=RX_INDICES,
        tx_indices=TX_INDICES,
        max_pdo_bytes=_max_pdo_bytes,
        protocols=fw.protocols,
        coe=CoeDetails(sdo_info=False, pdo_assign=True, pdo_config=True, pdo_upload=False, complete_access=False,
                       segmented_sdo=True),
        init_cmds=init,
        source=f"profile:{NAME}",
        extra={"profile": NAME, "product": prod.name, "firmware": fw.name},
    )


def rules(device: Device | None = None) -> FamilyRules:
    fw = Firmware(DEFAULT_REVISION)
    if device is not None:
        try:
            fw = Firmware.parse(device.extra.get("firmware") or device.revision)
        except SelectionError:
            fw = Firmware(DEFAULT_REVISION)
    modes = [1, 3, 6, 7, 8, 9, 10, -1, -2]
    if fw.has("F515K+"):
        modes.insert(2, 4)
    return FamilyRules(
        family=NAME,
        vendor_id=VENDOR_ID,
        rx_mapping_indices=RX_INDICES,
        tx_mapping_indices=TX_INDICES,
        max_pdo_bits=64,
        max_pdo_entries=8,
        max_assigned_rx=4,
        max_assigned_tx=4,
        dummy_indices=DUMMY_INDICES,
        dummies_in_rx=True,
        dummies_in_tx=False,
        gaps_allowed=False,
        mapping_write_needs_sub0_zero=True,
        assign_write_needs_sub0_zero=True,
        supported_modes=tuple(modes),
        unsupported_mode_accepted=True,
        dc_required_modes=(),
        max_assign_entries=4,
        factor_group=fw.factor_group,
        device_type=DEVICE_TYPE,
        # §17.4.5: "Only drives with firmware F515I or newer, support FoE ... Setup data while in Bootstrap
        # state when object 210Ch = 1"
        foe_setup_in_boot=fw.has("F515I+"),
        # §3.2.1 "The SYNC 0 signal must have the period equal or multiple than the drive slow control loop";
        # §13.2.1 60C2h "must be set with the time value of the EtherCAT master communication cycle time and
        # sync time"
        sync0_multiple_of_slow_loop=True,
        ip_period_equals_sync0=True,
        notes=(
            "§1.6.3.1: the sum of the mapped object sizes must not exceed 64 bits per PDO (EMCY 8210h/8220h, abort 0604 0042h)",
            "§2.4: up to 8 entries per PDO (sub-indices 1-8)",
            "§2.3.1: dummy entries (data-type indices 1-7) and 207Dh only in RxPDOs",
            "§2.3.10/§2.3.11: 1C12h/1C13h and the mapping objects change only in Pre-Op with sub-index 0 = 0",
            f"firmware {fw.name}: {fw.factor_group} factor group",
        ),
    )
