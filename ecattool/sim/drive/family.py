"""Family behaviour beyond storing values: objects that check or react to what is written (HDT 6046h, Control
Techniques 604Bh/604Ch/6046h, interpolation periods 60C2h, the CiA-301 store signature 1010h), what a family's
module does itself on an ESM change, and the encoder resolution it reports. The choices as data are
:mod:`.behaviour`."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from ecattool import abort as A
from ecattool.od.model import EcState
from ecattool.profiles.rules import FamilyRules, interpolation_period_ns
from ecattool.sim.drive.behaviour import BEHAVIOURS, Behaviour
from ecattool.sim.drive.core import sdo_abort
from ecattool.sim.drive.halt_homing import CURRENT_POSITION, SEARCH
from ecattool.sim.drive.plant import PlantParams, plant_for

if TYPE_CHECKING:
    from ecattool.sim.drive.app import DriveApp


class Family:
    """The family part, chosen once from the family's data when the drive is built: its name, its
    :class:`~ecattool.profiles.rules.FamilyRules` (the profile files), its :class:`~.behaviour.Behaviour` (where the
    manuals leave a choice), its homing method tables and its default plant; and what the family's drive does
    beyond storing values: the object handlers that check or react to writes, and its module's ESM reactions. A
    family the simulator has no behaviour for runs as the generic CiA-402 drive."""

    __slots__ = ("drive", "name", "rules", "behaviour", "homing_current", "homing_search", "default_plant")

    def __init__(self, drive: DriveApp, rules: FamilyRules) -> None:
        self.drive = drive
        self.rules = rules
        self.name = rules.family if rules.family in BEHAVIOURS else "generic"
        self.behaviour: Behaviour = BEHAVIOURS[self.name]
        #: the homing methods that home on the current position, and those that search a switch or index pulse
        #: (None: every method 1-34 the generic table has)
        self.homing_current: frozenset[int] = CURRENT_POSITION.get(self.name, CURRENT_POSITION["generic"])
        self.homing_search: frozenset[int] | None = SEARCH.get(self.name)
        #: the plant a drive of the family runs on unless the project gives one
        self.default_plant: PlantParams = plant_for(self.name)

    def report_encoder_resolution(self) -> None:
        """Control Techniques 608Fh is read-only and "read from the drive's encoder configuration" (A24):
        the drive reports its position resolution, 65536 increments per revolution (the drive's 1/2^16-turn
        position format), not the table default 1/1. :meth:`set_encoder_resolution` changes it."""
        drive = self.drive
        if self.behaviour.encoder_resolution_reported and (0x608F, 1) in drive.objects.entries:
            drive._put(0x608F, 1, self.rules.counts_per_rev or 65536)
            drive._put(0x608F, 2, 1)

    def set_encoder_resolution(self, increments: int, revolutions: int = 1) -> None:
        """The drive's feedback configuration changes (what 608Fh reports; also writable where 608Fh is RW)."""
        drive = self.drive
        drive._put(0x608F, 1, increments)
        drive._put(0x608F, 2, revolutions)

    #: Control Techniques Pr MM.04 (5.5, Table 5.6): the ESM state as the module reports it in its menu
    _CT_MM04 = {EcState.INIT: 1, EcState.PREOP: 2, EcState.SAFEOP: 4, EcState.OP: 8}
    #: Control Techniques 7.3.1 (lines 1473-1488): the module writes these sixteen drive parameters, in this
    #: order, on SAFE-OP -> OP ("Pr 6.42 to 0 ... Pr 1.14 to 3"); Pr 3.22/3.23 "where present", Pr 3.13 only
    #: "in open-loop operating modes" (see :meth:`_ct_open_loop`)
    _CT_TO_OP = ((0x2006, 42, 0), (0x2006, 43, 1), (0x2003, 22, 0), (0x2003, 23, 1), (0x2003, 13, 0),
                 (0x2002, 10, 1), (0x2002, 20, 1), (0x2002, 2, 1), (0x2001, 4, 0), (0x2001, 21, 0),
                 (0x2001, 38, 0), (0x2001, 8, 0), (0x2001, 10, 1), (0x2001, 9, 0), (0x2001, 15, 1),
                 (0x2001, 14, 3))

    def _ct_open_loop(self) -> bool:
        """Whether the host drive runs open loop: one without position control (no homing, 6060h = 6, in its
        modes: Commander SK, Affinity), decision "Control Techniques SAFE-OP -> OP parameters"."""
        return 6 not in self.rules.supported_modes

    def esm_effects(self, previous: EcState, state: EcState) -> None:
        """What a family's module does itself on an ESM change (Control Techniques: MM.04 follows the state in
        the slot menu 0x200F and its mirror 0x203C; the SAFE-OP -> OP parameter writes)."""
        drive = self.drive
        if not self.behaviour.module_menu:
            return
        code = self._CT_MM04.get(state)
        if code is not None:
            for menu in (0x200F, 0x203C):
                drive._put(menu, 4, code)
        if previous is EcState.SAFEOP and state is EcState.OP:
            for index, sub, value in self._CT_TO_OP:
                if (index, sub) == (0x2003, 13) and not self._ct_open_loop():
                    continue
                if (index, sub) in drive.objects.entries:
                    drive._put(index, sub, value)
                    drive._log("drive_parameter", parameter=f"{index - 0x2000}.{sub:02d}", value=value,
                              reason="SAFE-OP -> OP (7.3.1)")

    def _check_min_max(self, sub: int, data: bytes, value: int | None) -> bool:
        """HDT §4.11.6: 6046h max <= min is refused with 0609 0030h."""
        drive = self.drive
        other = drive._read_int(0x6046, 2 if sub == 1 else 1) or 0
        lo, hi = (value or 0, other) if sub == 1 else (other, value or 0)
        if sub in (1, 2) and hi <= lo:
            raise sdo_abort(0x6046, sub, A.INVALID_VALUE)
        return True

    def _check_store_signature(self, sub: int, data: bytes, value: int | None) -> bool:
        """CiA-301 1010h (HDT §2.08.1.a): a store command is the signature "save" (65766173h, bytes 73 61 76
        65 on the wire); anything else is refused with 0800 0020h."""
        if sub and value != 0x65766173:
            raise sdo_abort(0x1010, sub, A.DATA_CANNOT_BE_STORED)
        return True

    def _copy_min_max_amount(self, sub: int, value: int | None) -> None:
        """Control Techniques 7.5.4: writing 6046h sub 1 (sub 2) overwrites 6047h sub 1 and 3 (2 and 4)."""
        drive = self.drive
        if sub in (1, 2):
            for target in (sub, sub + 2):
                drive._put(0x6047, target, value or 0)

    @staticmethod
    def _nonzero(index: int) -> Callable[[int, bytes, int | None], bool]:
        """Control Techniques 7.5.9/7.5.10: a 0 in 604Bh/604Ch is invalid (code not stated: 0609 0030h)."""
        def check(sub: int, data: bytes, value: int | None) -> bool:
            if sub and not value:
                raise sdo_abort(index, sub, A.INVALID_VALUE)
            return True
        return check

    def _check_interpolation_period(self, sub: int, data: bytes, value: int | None) -> bool:
        """The family's interpolation periods (``FamilyRules.accepts_ip_period``; Control Techniques 7.4.3:
        250 us, 500 us or k x 1 ms); any other value is refused (code not stated: 0609 0030h). Checked on each
        write, with the other sub-index as stored."""
        drive = self.drive
        if sub not in (1, 2):
            return True
        base = (value or 0) if sub == 1 else (drive._read_int(0x60C2, 1) or 0)
        exp = (value or 0) if sub == 2 else (drive._read_int(0x60C2, 2) or 0)
        if not -9 <= exp <= 2:
            return True  # the entry's own range check answers
        if not self.rules.accepts_ip_period(interpolation_period_ns(base, exp)):
            raise sdo_abort(0x60C2, sub, A.INVALID_VALUE)
        return True

    def _linked(self, index: int) -> Callable[[int, int | None], None]:
        """A write to ``index`` changes the objects ``Behaviour.linked_objects`` ties to it (Control Techniques
        7.3.17: 6080h and Pr 1.06)."""
        drive = self.drive
        def after(sub: int, value: int | None) -> None:
            for a, b in self.behaviour.linked_objects:
                if a == (index, sub):
                    drive._put(*b, value or 0)
                elif b == (index, sub):
                    drive._put(*a, value or 0)
        return after

    def install_handlers(self) -> None:
        drive = self.drive
        drive._handlers_down[0x1010] = self._check_store_signature
        if self.behaviour.home_offset_continuous:
            drive._after_write[0x607C] = lambda sub, value: drive._refresh_inputs()  # 6064h = sensor + 607Ch
        if self.behaviour.vl_min_max_checked:
            drive._handlers_down[0x6046] = self._check_min_max
        if self.rules.ip_periods_ns or self.rules.ip_period_step_ns:
            drive._handlers_down[0x60C2] = self._check_interpolation_period
        for pair in self.behaviour.linked_objects:
            for index in {pair[0][0], pair[1][0]}:
                drive._after_write[index] = self._linked(index)
        if self.behaviour.vl_factors_nonzero:
            drive._handlers_down[0x604B] = self._nonzero(0x604B)
            drive._handlers_down[0x604C] = self._nonzero(0x604C)
            drive._after_write[0x6046] = self._copy_min_max_amount
