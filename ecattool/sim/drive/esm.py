"""The EtherCAT state machine: allowed transitions, the AL status codes of a refusal, distributed clocks
settings checked on the way to OP."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ecattool.abort import AlStatus, al_status_text
from ecattool.errors import StateChangeError
from ecattool.od.model import EcState
from ecattool.sim.drive.core import RX, TX

if TYPE_CHECKING:
    from ecattool.sim.drive.app import DriveApp

#: allowed ESM transitions (ETG.1000.6; Technosoft §3.1.1 derived matrix, HDT §3.02)
TRANSITIONS: dict[EcState, frozenset[EcState]] = {
    EcState.INIT: frozenset({EcState.PREOP, EcState.BOOT}),
    EcState.PREOP: frozenset({EcState.INIT, EcState.SAFEOP}),
    EcState.SAFEOP: frozenset({EcState.INIT, EcState.PREOP, EcState.OP}),
    EcState.OP: frozenset({EcState.INIT, EcState.PREOP, EcState.SAFEOP}),
    EcState.BOOT: frozenset({EcState.INIT}),
}


class StateMachine:
    """The ESM part: state requests and refusals (the SAFE-OP check is the process data part's, the family's own
    reactions the family part's), and the DC settings the master writes. The state itself is the drive's ``esm``
    (every part reads it)."""

    __slots__ = ("drive", "dc", "dc_shift_ns")

    def __init__(self, drive: DriveApp) -> None:
        self.drive = drive
        #: DC activation (0x0981) and SYNC0 cycle in ns, as the master wrote them (:meth:`configure_dc`)
        self.dc = (0, 0)
        self.dc_shift_ns = 0

    def state(self) -> EcState:
        return self.drive.esm

    def refuse(self, state: EcState, code: int, why: str) -> None:
        drive = self.drive
        drive._log("state_refused", previous=drive.esm.value, requested=state.value, al_status=code, reason=why)

        # the reason goes with the error, so that commission's text, JSON and HTML reports say why
        raise StateChangeError(state.value, drive.esm.value, code, f"{al_status_text(code)} ({why})")

    def request_state(self, state: EcState) -> None:
        drive = self.drive
        current = drive.esm
        refusal = drive.faults.state_refusal(state)
        if refusal is not None:
            self.refuse(state, refusal, "fault injection")
        if state is current:
            return
        if state not in TRANSITIONS[current]:
            self.refuse(state, AlStatus.INVALID_STATE_CHANGE, "not an allowed transition")
        if state is EcState.BOOT and not (drive.device.mailbox and "FoE" in drive.device.mailbox.protocols):
            self.refuse(state, AlStatus.BOOTSTRAP_NOT_SUPPORTED, "the device has no FoE bootstrap")
        if current is EcState.PREOP and state is EcState.SAFEOP:
            drive.layout = {RX: drive.process_data.check_sm(RX), TX: drive.process_data.check_sm(TX)}
        if state is EcState.OP:
            self._check_dc()
        if current is EcState.OP and drive.has_cia402:
            drive._cia_moves(drive.cia.communication_lost(), "ESM left OP")
        drive.esm = state
        drive._log("state", previous=current.value, state=state.value)
        drive.family_part.esm_effects(current, state)
        drive._refresh_inputs()

    def fall_to_safeop(self, code: int, why: str, app_reacts: bool = True) -> None:
        """The slave leaves OP by itself for SAFE-OP with AL status ``code`` (a running axis: as when OP is left,
        unless ``app_reacts`` is False: the caller gives the application's reaction itself)."""
        drive = self.drive
        if drive.esm is not EcState.OP:
            return
        drive._log("state", previous="OP", state="SAFEOP", al_status=code, reason=why)
        drive.esm = EcState.SAFEOP
        if app_reacts and drive.has_cia402:
            drive._cia_moves(drive.cia.communication_lost(), "ESM left OP")
        drive.family_part.esm_effects(EcState.OP, EcState.SAFEOP)

    def watchdog(self) -> None:
        """The process data stops (cable pulled, SM watchdog): from OP the ESM drops to SAFE-OP, AL status 0x001B
        (the application's reaction is its own: :meth:`.injection.Injection.lose_communication`)."""
        self.fall_to_safeop(AlStatus.SM_WATCHDOG, "sync manager watchdog", app_reacts=False)

    def dc_active(self) -> bool:
        return bool(self.dc[0])

    def configure_dc(self, assign_activate: int, sync0_cycle_ns: int = 0, sync0_shift_ns: int = 0) -> None:
        """What the master writes to the ESC before SAFE-OP: DC activation (0x0981, e.g. 0x0300 = SYNC0)
        and the SYNC0 cycle and shift times in ns. ``assign_activate = 0`` = free run."""
        drive = self.drive
        self.dc = (assign_activate, sync0_cycle_ns)
        self.dc_shift_ns = sync0_shift_ns
        drive._log("dc", assign_activate=assign_activate, sync0_cycle_ns=sync0_cycle_ns, sync0_shift_ns=sync0_shift_ns)

    def _check_dc(self) -> None:
        drive = self.drive
        active, cycle = self.dc
        step, most = drive.rules.dc_sync0_step_ns, drive.rules.dc_sync0_max_steps
        if step and active:
            # the family's SYNC0 rule as data (Control Techniques 8.1.1: SYNC0 = n x 250 us, n = 1..60)
            if cycle <= 0 or cycle % step or cycle // step < 1 or (most is not None and cycle // step > most):
                span = f" (n = 1..{most})" if most is not None else ""
                self.refuse(EcState.OP, AlStatus.DC_INVALID_CYCLE,
                        f"SYNC0 cycle {cycle} ns is not n x {step / 1000:g} us{span}")
        if not active and drive.has_cia402 and drive.mode() in drive.rules.dc_required_modes:
            self.refuse(EcState.OP, AlStatus.DC_INVALID_SYNC, f"mode {drive.mode()} needs distributed clocks")
