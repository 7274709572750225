"""Family rules: the data that describes what a drive family accepts (limits and conventions).

These are *data*, shared by the static checker (``ecattool.pdo``) and the simulator (``ecattool.sim``);
each of them makes its own decisions from this data. ``ecattool.profiles.rules_for(device)`` returns the
rules of a device's family (by vendor id / product) or rules synthesised from its ESI for generic devices.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction


def interpolation_period_ns(base: int, exponent: int) -> Fraction:
    """The interpolation period 60C2h in ns: sub-index 1 x 10^(sub-index 2) s."""
    return Fraction(base) * Fraction(10) ** (exponent + 9)


@dataclass(frozen=True, slots=True)
class FamilyRules:
    family: str  # "technosoft-ipos", "hdt", "controltechniques", "generic"
    vendor_id: int | None = None
    #: mapping objects that exist, per direction (e.g. Technosoft Rx 0x1600-0x1603, Tx 0x1A00-0x1A03)
    rx_mapping_indices: tuple[int, ...] = ()
    tx_mapping_indices: tuple[int, ...] = ()
    #: bit limit of one PDO (Technosoft: 64), None = no family limit (sync manager size still applies)
    max_pdo_bits: int | None = None
    #: entries per PDO (Technosoft and HDT: 8; Control Techniques: the ESI's "CF" limit)
    max_pdo_entries: int | None = None
    #: PDOs that may be assigned at once per direction (Control Techniques: 2)
    max_assigned_rx: int | None = None
    max_assigned_tx: int | None = None
    #: whether the PDO assignment (1C12h/1C13h) and the mapping objects can be written at all
    assign_writable: bool = True
    mapping_writable: bool = True
    #: gap/dummy entries: which "object" indices count as dummies (Technosoft: data-type indices 1-7 and 0x207D)
    dummy_indices: frozenset[int] = frozenset()
    dummies_in_rx: bool = True
    dummies_in_tx: bool = False
    #: index 0 gap entries allowed in mapping objects
    gaps_allowed: bool = True
    #: mapping entries may only be written while the mapping's sub-index 0 is 0 (CiA-301 / ETG.1000.6)
    mapping_write_needs_sub0_zero: bool = True
    #: assignment entries may only be written while the assignment's sub-index 0 is 0
    assign_write_needs_sub0_zero: bool = True
    #: Control Techniques' priority rule: slow (non-cyclic-capable) parameters only in the first PDO
    priority_rule: bool = False
    #: modes of operation (6060h values) the device supports, () = unknown
    supported_modes: tuple[int, ...] = ()
    #: modes that need distributed clocks (Control Techniques: CSP/CSV/CST …)
    dc_required_modes: tuple[int, ...] = ()
    #: SYNC0 cycle times the drive accepts: n x step for n = 1..max_steps (Control Techniques 8.1.1:
    #: 250 us, 1..60); None = no family rule
    dc_sync0_step_ns: int | None = None
    dc_sync0_max_steps: int | None = None
    #: interpolation periods (60C2h) the drive accepts: these, and the multiples of ip_period_step_ns
    #: (Control Techniques 7.4.3: 250 us, 500 us, k x 1 ms); () and None = no family rule
    ip_periods_ns: tuple[int, ...] = ()
    ip_period_step_ns: int | None = None
    #: positions / velocities: internal counts per motor revolution where fixed (HDT: 65536)
    counts_per_rev: int | None = None
    notes: tuple[str, ...] = field(default_factory=tuple)
    # --- added for the built-in families (all optional; generic devices keep the defaults) ---------------
    #: entries the sync manager assignment objects (1C12h/1C13h) have, i.e. PDOs assignable at most
    max_assign_entries: int | None = None
    #: size limits of one mapping entry in bits (Control Techniques: 8..32, i.e. 1-4 bytes)
    min_entry_bits: int | None = None
    max_entry_bits: int | None = None
    #: Control Techniques' priority rule: object indices of "slow" parameters (SM-Applications / Inter-Option
    #: menus). Such entries also carry ``Entry.category == "slow"`` in the profile's dictionary.
    slow_indices: frozenset[int] = frozenset()
    #: objects that can only be accessed by SDO (never PDO-mapped), e.g. Control Techniques 6091h/6092h
    sdo_only_indices: frozenset[int] = frozenset()
    #: objects that can only be accessed cyclically (SDO access refused), e.g. Control Techniques 2830h/2831h
    pdo_only_indices: frozenset[int] = frozenset()
    #: objects that are read-only although CiA-402 makes them writable (Control Techniques 608Fh)
    read_only_indices: frozenset[int] = frozenset()
    #: bits of 60FDh that carry the (negative, positive) limit switches; HDT swaps them (CW = bit 0 = positive)
    limit_switch_bits: tuple[int, int] = (0, 1)
    #: option-code behaviours where a family departs from CiA-402: (object index, value, end state name)
    option_code_end_states: tuple[tuple[int, int, str], ...] = ()
    #: factor group flavour: "cia402-2" (608Fh/6091h/6092h…), "cia402-obsolete" (6093h/6094h/6097h as
    #: numerator/divisor, Technosoft before F515K), "" = unknown/ESI
    factor_group: str = ""
    #: device type (1000h) the family documents, for cross-checks; None = unknown
    device_type: int | None = None
    #: an FoE setup file (FOESW_) is accepted in BOOT while 210Ch = 1 (Technosoft F515I and newer, §17.4.5)
    foe_setup_in_boot: bool = False
    #: SYNC0 must equal or be a multiple of the drive's slow control loop (Technosoft §3.2.1; the loop is
    #: 1 ms by default and set per setup), and the interpolation period 60C2h must equal the sync cycle
    #: (Technosoft §13.2.1); see :func:`dc_cycle_problems`
    sync0_multiple_of_slow_loop: bool = False
    ip_period_equals_sync0: bool = False
    #: a mode of operation the drive does not support is accepted in 6060h and reported by an emergency
    #: (Technosoft §4.2.3: FF04h) instead of aborted (0609 0030h, HDT and Control Techniques)
    unsupported_mode_accepted: bool = False

    def dc_cycle_problems(self, sync0_ns: int, ip_period_ns: Fraction | int | None,
                          slow_loop_ns: Fraction | int = 1_000_000) -> list[tuple[str, str]]:
        """What is wrong with a SYNC0 cycle (and the interpolation period 60C2h that goes with it) for this
        family: (``"sync0"`` or ``"60C2h"``, message) pairs; [] where the family has no such rule."""
        out: list[tuple[str, str]] = []
        if self.sync0_multiple_of_slow_loop and slow_loop_ns > 0 and (sync0_ns <= 0 or sync0_ns % slow_loop_ns):
            out.append(("sync0", f"SYNC0 cycle {sync0_ns / 1000:g} us is not the slow loop ({float(slow_loop_ns) / 1000:g} "
                                  "us) or a multiple of it (the drive synchronises its slow control loop on SYNC0)"))
        if self.ip_period_equals_sync0 and ip_period_ns is not None and ip_period_ns != sync0_ns:
            out.append(("60C2h", f"interpolation period 60C2h = {float(ip_period_ns) / 1000:g} us is not the sync cycle "
                                 f"{sync0_ns / 1000:g} us (60C2h must be set to the master's communication and sync "
                                 "cycle)"))
        return out

    def accepts_ip_period(self, ns: Fraction | int) -> bool:
        """Whether the drive takes this interpolation period (60C2h); True where the family has no rule."""
        if not self.ip_periods_ns and not self.ip_period_step_ns:
            return True
        step = self.ip_period_step_ns
        return ns in self.ip_periods_ns or bool(step and ns > 0 and ns % step == 0)


#: the rules of a device whose rules are not known (a slave whose device did not resolve): every field at its
#: "no family rule" default, so ``(rules or NO_RULES).field`` reads a typed field instead of ``getattr``
NO_RULES = FamilyRules("generic")
