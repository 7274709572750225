"""Control Techniques SM-EtherCAT (vendor 0xF9) on Unidrive SP, Digitax ST, Commander SK, Mentor MP, Affinity.

From the SM-EtherCAT User Guide (issue 5). The module has one identity for every host drive (product code =
module ID Pr MM.01 = 421, revision = firmware MM.02 (xx.yy) in the high word and MM.51 (zz) in the low word);
the host drive decides the device type (1000h) and the supported modes (§7, digest §11.1).
"""

from __future__ import annotations

import re

from ecattool.errors import SelectionError
from ecattool.esi.model import CoeDetails, Device, Identity, Pdo
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

NAME = "controltechniques"
VENDOR_ID = 0x000000F9
PRODUCT_CODE = 421  # Pr MM.01 module ID code (§6.3.1, §9.1.1)
RX_INDICES = (0x1600, 0x1601, 0x1605, 0x1615)
TX_INDICES = (0x1A00, 0x1A01, 0x1A02, 0x1A05, 0x1A15)
CF = 5  # entries per PDO: "at most five mappings in one PDO" (§5.1.3); an ESI's CF overrides it
SLOT_MENU = 15
SLOW_MENUS = (70, 71)
SLOW_INDICES = frozenset(0x2000 + m for m in SLOW_MENUS)
REVISIONS = ("01.00.00", "01.01.00", "01.02.00")
DEFAULT_REVISION = "01.02.00"


#: host drive → (title, 1000h device type, supported modes, minimum SM-EtherCAT firmware, has a 2nd slot)
DRIVES: dict[str, tuple[str, int, tuple[int, ...], str, bool]] = {
    # servo / closed-loop vector / RFC mode: bit 17 servo (§6.3.1) — decision CT-1
    "unidrive-sp": ("Unidrive SP + SM-EtherCAT", 0x00020192, (2, 4, 6, 7, 8), "01.00.00", True),
    "digitax-st": ("Digitax ST + SM-EtherCAT", 0x00020192, (2, 4, 6, 7, 8), "01.00.00", True),
    "mentor-mp": ("Mentor MP + SM-EtherCAT", 0x00010192, (2, 4, 6, 7, 8), "01.02.00", True),
    # device type of SK and Affinity not specified: printed default kept
    "commander-sk": ("Commander SK + SM-EtherCAT", 0x00030192, (2, 4), "01.00.00", False),
    "affinity": ("Affinity + SM-EtherCAT", 0x00030192, (2, 4), "01.00.00", True),
}

PRODUCTS = tuple(
    ProductInfo(k, v[0], PRODUCT_CODE, tuple(r for r in REVISIONS if r >= v[3]), DEFAULT_REVISION,
                f"modes {', '.join(map(str, v[2]))}; SM-EtherCAT firmware {v[3]} or later")
    for k, v in DRIVES.items()
)

INFO = ProfileInfo(
    name=NAME,
    family=NAME,
    title="Control Techniques SM-EtherCAT (Unidrive SP, Digitax ST, Commander SK, Mentor MP, Affinity)",
    vendor_id=VENDOR_ID,
    vendor_name="Control Techniques",
    products=PRODUCTS,
    default_product="unidrive-sp",
    source="Control Techniques SM-EtherCAT User Guide issue 5",
    notes=("drive parameter Pr menu.par = object 0x2000+menu, sub-index par (§6.2)",
           "at most 2 PDOs per direction; the 2nd is low priority and the only place for slow parameters (§6.1.1)"),
)

_REV = re.compile(r"^V?(\d{1,2})\.(\d{1,2})(?:\.(\d{1,2}))?$")


def parse_revision(value: str | int | None) -> tuple[int, str]:
    """``"01.02.00"`` / ``"V01.02.00"`` / int → (1018h:3 value, "xx.yy.zz"): high word xx*100+yy, low word zz."""
    if value is None or value == "":
        value = DEFAULT_REVISION
    if isinstance(value, int):
        hi, lo = value >> 16, value & 0xFFFF
        return value, f"{hi // 100:02d}.{hi % 100:02d}.{lo:02d}"
    m = _REV.match(value.strip().upper())
    if not m:
        raise SelectionError(f"{value!r} is not an SM-EtherCAT firmware version (write 01.02.00)")
    xx, yy, zz = int(m.group(1)), int(m.group(2)), int(m.group(3) or 0)
    return ((xx * 100 + yy) << 16) | zz, f"{xx:02d}.{yy:02d}.{zz:02d}"


def _max_pdo_bytes(_pdos: list[Pdo]) -> int:
    return 2 * CF * 4  # two PDOs of five 32-bit entries


def load(product: str | None = None, revision: str | int | None = None) -> Device:
    key = choose(DRIVES, product, INFO.default_product, "host drive", NAME)
    title, device_type, _modes, min_fw, second_slot = DRIVES[key]
    rev, text = parse_revision(revision)
    if text < min_fw:
        raise SelectionError(f"{title} needs SM-EtherCAT firmware {min_fw} or later (got {text})")
    od = build_dictionary(load_data("controltechniques"), lambda req: req == "applications-slot" and second_slot)
    set_default(od, 0x1000, 0, device_type)
    set_default(od, 0x1018, 2, PRODUCT_CODE)
    set_default(od, 0x1018, 3, rev)
    set_default(od, 0x1018, 4, 0)
    for menu in (SLOT_MENU, 60):
        set_default(od, 0x2000 + menu, 2, rev >> 16)
        set_default(od, 0x2000 + menu, 51, rev & 0xFFFF)
    return assemble_device(
        identity=Identity(VENDOR_ID, PRODUCT_CODE, rev),
        type_name=title,
        name=f"{title} (firmware {text})",
        od=od,
        rx_indices=RX_INDICES,
        tx_indices=TX_INDICES,
        max_pdo_bytes=_max_pdo_bytes,
        protocols=["CoE", "EoE"],
        coe=CoeDetails(sdo_info=False, pdo_assign=True, pdo_config=True, complete_access=False, segmented_sdo=False),
        source=f"profile:{NAME}",
        extra={"profile": NAME, "product": key, "drive": key, "firmware": text},
    )


def _cf_of(device: Device) -> int:
    """CF: the mapping sub-indices the device's own description defines (the ESI's), else 5."""
    if device.extra.get("profile") == NAME:
        return CF
    subs = [o.max_subindex for o in device.dictionary if o.index in (*RX_INDICES, *TX_INDICES) and o.entries]
    return max(subs) if subs else CF


_DRIVE_WORDS = {"unidrive": "unidrive-sp", "digitax": "digitax-st", "mentor": "mentor-mp", "commander": "commander-sk",
                "affinity": "affinity"}


def drive_of(device: Device) -> str | None:
    """The host drive: the profile's product, else a drive name in the ESI's type name or name."""
    drive = device.extra.get("drive") or device.extra.get("product")
    if drive in DRIVES:
        return drive
    text = f"{device.type_name} {device.name}".lower()
    for word, key in _DRIVE_WORDS.items():
        if word in text:
            return key
    return None


def rules(device: Device | None = None) -> FamilyRules:
    drive = drive_of(device) if device is not None else None
    modes = DRIVES[drive][2] if drive in DRIVES else (2, 4, 6, 7, 8)
    return FamilyRules(
        family=NAME,
        vendor_id=VENDOR_ID,
        rx_mapping_indices=RX_INDICES,
        tx_mapping_indices=TX_INDICES,
        max_pdo_bits=None,
        max_pdo_entries=_cf_of(device) if device is not None else CF,
        max_assigned_rx=2,
        max_assigned_tx=2,
        dummy_indices=frozenset(),
        dummies_in_rx=False,
        dummies_in_tx=False,
        gaps_allowed=True,
        mapping_write_needs_sub0_zero=False,
        assign_write_needs_sub0_zero=False,
        priority_rule=True,
        supported_modes=modes,
        dc_required_modes=tuple(m for m in (7, 8) if m in modes),
        dc_sync0_step_ns=250_000,
        dc_sync0_max_steps=60,
        ip_periods_ns=(250_000, 500_000),
        ip_period_step_ns=1_000_000,
        max_assign_entries=2,
        min_entry_bits=8,
        max_entry_bits=32,
        slow_indices=SLOW_INDICES,
        sdo_only_indices=frozenset({0x608F, 0x6091, 0x6092}),
        pdo_only_indices=frozenset({0x2830, 0x2831}),
        read_only_indices=frozenset({0x608F}),
        factor_group="cia402-2",
        device_type=DRIVES[drive][1] if drive in DRIVES else None,
        notes=(
            "§5.1.3: at most five mappings per PDO (CF from the XML), at most two RxPDOs and two TxPDOs",
            "§6.1.1: with two PDOs in a sync manager the second is low priority; slow parameters "
            "(SM-Applications / Inter-Option) only there, else SDO abort",
            "§7.3.11-13: 608Fh read-only; 608Fh/6091h/6092h not changeable cyclically (SDO only)",
            "§7.4/§8.1: interpolated and cyclic synchronous position need distributed clocks",
            "§8.5: 2830h/2831h only cyclically (no SDO access)",
        ),
    )
