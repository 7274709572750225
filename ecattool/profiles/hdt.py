"""HDT Tomcat / DGFOX / NTT drives (vendor 0x289), from "DS-301 protocol CANopen – EtherCAT" Rev 4.0.

One object dictionary for the three families (digest §19: "The OD is otherwise common"); the NTT-only
objects (ADC3 2023h, outputs Out3..Out6 203Dh/2082h–2084h) exist only on ``ntt``. The document gives a single
product code (printed with a lost digit, decision HDT-2) and no revision.
"""

from __future__ import annotations

from ecattool.errors import EcatToolError, SelectionError
from ecattool.esi.model import CoeDetails, Device, Identity, Pdo
from ecattool.od.numbers import parse_int
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

NAME = "hdt"
VENDOR_ID = 0x00000289
PRODUCT_CODE = 0x000C0458  # printed "00C0458h" (7 digits, §2.08): decision HDT-2
RX_INDICES = (0x1600, 0x1601, 0x1602, 0x1603)
TX_INDICES = (0x1A00, 0x1A01, 0x1A02, 0x1A03)
COUNTS_PER_REV = 65536  # §4.05.3, §4.06.2
DEVICE_TYPE = 0x00020192  # §2.08

PRODUCTS = (
    ProductInfo("tomcat", "HDT TomCat EVO", PRODUCT_CODE, (), "", "braking-resistor alarm FA_10; touch probe on inputs 1st/5th"),
    ProductInfo("dgfox", "HDT DgFox EVO", PRODUCT_CODE, (), "", "touch probe on inputs 1st/5th"),
    ProductInfo("ntt", "HDT NTT", PRODUCT_CODE, (), "", "7 outputs (203Dh, 2082h-2084h), ADC3 2023h, 16-bit ADC1"),
)

INFO = ProfileInfo(
    name=NAME,
    family=NAME,
    title="HDT Tomcat / DGFOX / NTT drives (CANopen / EtherCAT)",
    vendor_id=VENDOR_ID,
    vendor_name="HDT (hdtlovato)",
    products=PRODUCTS,
    default_product="tomcat",
    source="HDT DS-301 protocol CANopen - EtherCAT user guide Rev 4.0",
    notes=("65536 counts per motor revolution; factor defaults 6093h 65536/65536, 6094h 65536/60, 6097h 65536/60",
           "60FDh bit 0 = CW (positive) limit switch, bit 1 = CCW (negative): the reverse of CiA-402"),
)

#: option codes whose end state departs from CiA-402 as printed (§4.03.3–§4.03.10, ambiguity 37)
OPTION_CODE_END_STATES: tuple[tuple[int, int, str], ...] = (
    (0x605A, 0, "SWITCH_ON_DISABLED"), (0x605A, 1, "SWITCH_ON_DISABLED"), (0x605A, 2, "SWITCH_ON_DISABLED"),
    (0x605A, 5, "QUICK_STOP_ACTIVE"), (0x605A, 6, "QUICK_STOP_ACTIVE"),
    (0x605D, 0, "SWITCH_ON_DISABLED"), (0x605D, 1, "OPERATION_ENABLED"), (0x605D, 2, "OPERATION_ENABLED"),
    (0x6007, 0, "NO_ACTION"), (0x6007, 1, "SWITCH_ON_DISABLED"), (0x6007, 2, "SWITCH_ON_DISABLED"),
    (0x6007, 3, "OPERATION_ENABLED"),
    (0x605E, 0, "FAULT"), (0x605E, 1, "FAULT"), (0x605E, 2, "FAULT"), (0x605E, 3, "FAULT"),
)
SUPPORTED_MODES = (-2, -1, 1, 2, 3, 4, 6, 7, 8, 9, 10)


def _max_pdo_bytes(pdos: list[Pdo]) -> int:
    return len(pdos) * 8 * 32 // 8  # 8 entries of at most 32 bits (no byte limit documented for EtherCAT)


def _revision(revision: str | int | None) -> int:
    """HDT documents no revision: accept a number (``0x00010000``, ``#x…``, decimal) for ESI matching, else 0."""
    if revision is None or revision == "":
        return 0
    try:
        return parse_int(revision)
    except EcatToolError:
        raise SelectionError(f"HDT revision {revision!r} is not a number (write e.g. 0x00010000)") from None


def load(product: str | None = None, revision: str | int | None = None) -> Device:
    key = choose({p.name: p for p in PRODUCTS}, product, INFO.default_product, "product", NAME)
    prod = next(p for p in PRODUCTS if p.name == key)
    rev = _revision(revision)
    od = build_dictionary(load_data("hdt"), lambda req: req == key)
    if rev:
        set_default(od, 0x1018, 3, rev)
    return assemble_device(
        identity=Identity(VENDOR_ID, prod.product_code, rev),
        type_name=prod.title,
        name=prod.title,
        od=od,
        rx_indices=RX_INDICES,
        tx_indices=TX_INDICES,
        max_pdo_bytes=_max_pdo_bytes,
        protocols=["CoE"],
        coe=CoeDetails(sdo_info=False, pdo_assign=True, pdo_config=True, complete_access=False, segmented_sdo=True),
        source=f"profile:{NAME}",
        extra={"profile": NAME, "product": prod.name},
    )


def rules(device: Device | None = None) -> FamilyRules:
    return FamilyRules(
        family=NAME,
        vendor_id=VENDOR_ID,
        rx_mapping_indices=RX_INDICES,
        tx_mapping_indices=TX_INDICES,
        max_pdo_bits=None,
        max_pdo_entries=8,
        max_assigned_rx=4,
        max_assigned_tx=4,
        dummy_indices=frozenset(),
        dummies_in_rx=False,
        dummies_in_tx=False,
        gaps_allowed=False,
        supported_modes=SUPPORTED_MODES,
        dc_required_modes=(),
        counts_per_rev=COUNTS_PER_REV,
        max_assign_entries=4,
        limit_switch_bits=(1, 0),
        option_code_end_states=OPTION_CODE_END_STATES,
        factor_group="cia402-obsolete",
        device_type=DEVICE_TYPE,
        notes=(
            "§2.10/§2.11: sub-index 0 of a mapping object 0..8 → at most 8 entries per PDO",
            "no byte limit per PDO is documented for EtherCAT (64 bits on CAN, inferred)",
            "§4.02: 1001h (error register) is mapped in 1A00h by default although its table says Map No",
            "§4.04.1: 60FDh bit 0 = CW/positive limit, bit 1 = CCW/negative limit",
            "§4.05: internal resolution 65536 counts per motor revolution",
        ),
    )
