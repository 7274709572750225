"""The EtherCAT state machine: allowed transitions, the AL status codes of a refusal, distributed clocks
settings checked on the way to OP."""

from __future__ import annotations

from ecattool.abort import AlStatus
from ecattool.od.model import EcState
from ecattool.sim.drive.core import RX, TX, DriveCore

#: allowed ESM transitions (ETG.1000.6; Technosoft §3.1.1 derived matrix, HDT §3.02)
TRANSITIONS: dict[EcState, frozenset[EcState]] = {
    EcState.INIT: frozenset({EcState.PREOP, EcState.BOOT}),
    EcState.PREOP: frozenset({EcState.INIT, EcState.SAFEOP}),
    EcState.SAFEOP: frozenset({EcState.INIT, EcState.PREOP, EcState.OP}),
    EcState.OP: frozenset({EcState.INIT, EcState.PREOP, EcState.SAFEOP}),
    EcState.BOOT: frozenset({EcState.INIT}),
}


class StateMachine(DriveCore):
    """ESM requests (the SAFE-OP check is :class:`~.process_data.ProcessData`'s, the family's own reactions
    :class:`~.family.FamilyQuirks`'s)."""

    def state(self) -> EcState:
        return self.esm

    def request_state(self, state: EcState) -> None:
        current = self.esm
        refusal = self.faults.state_refusal(state)
        if refusal is not None:
            self._refuse(state, refusal, "fault injection")
        if state is current:
            return
        if state not in TRANSITIONS[current]:
            self._refuse(state, AlStatus.INVALID_STATE_CHANGE, "not an allowed transition")
        if state is EcState.BOOT and not (self.device.mailbox and "FoE" in self.device.mailbox.protocols):
            self._refuse(state, AlStatus.BOOTSTRAP_NOT_SUPPORTED, "the device has no FoE bootstrap")
        if current is EcState.PREOP and state is EcState.SAFEOP:
            self.layout = {RX: self._check_sm(RX), TX: self._check_sm(TX)}
        if state is EcState.OP:
            self._check_dc()
        if current is EcState.OP and self.has_cia402:
            self._cia_moves(self.cia.communication_lost(), "ESM left OP")
        self.esm = state
        self._log("state", previous=current.value, state=state.value)
        self._esm_effects(current, state)
        self._refresh_inputs()

    def _fall_to_safeop(self, code: int, why: str) -> None:
        """The slave leaves OP by itself for SAFE-OP with AL status ``code`` (a running axis: as when OP is
        left)."""
        if self.esm is not EcState.OP:
            return
        self._log("state", previous="OP", state="SAFEOP", al_status=code, reason=why)
        self.esm = EcState.SAFEOP
        if self.has_cia402:
            self._cia_moves(self.cia.communication_lost(), "ESM left OP")
        self._esm_effects(EcState.OP, EcState.SAFEOP)

    def dc_active(self) -> bool:
        return bool(getattr(self, "dc", (0, 0))[0])

    def configure_dc(self, assign_activate: int, sync0_cycle_ns: int = 0, sync0_shift_ns: int = 0) -> None:
        """What the master writes to the ESC before SAFE-OP: DC activation (0x0981, e.g. 0x0300 = SYNC0)
        and the SYNC0 cycle and shift times in ns. ``assign_activate = 0`` = free run."""
        self.dc = (assign_activate, sync0_cycle_ns)
        self.dc_shift_ns = sync0_shift_ns
        self._log("dc", assign_activate=assign_activate, sync0_cycle_ns=sync0_cycle_ns, sync0_shift_ns=sync0_shift_ns)

    def _check_dc(self) -> None:
        active, cycle = getattr(self, "dc", (0, 0))
        step, most = self.rules.dc_sync0_step_ns, self.rules.dc_sync0_max_steps
        if step and active:
            # the family's SYNC0 rule as data (Control Techniques 8.1.1: SYNC0 = n x 250 us, n = 1..60)
            if cycle <= 0 or cycle % step or cycle // step < 1 or (most is not None and cycle // step > most):
                span = f" (n = 1..{most})" if most is not None else ""
                self._refuse(EcState.OP, AlStatus.DC_INVALID_CYCLE,
                             f"SYNC0 cycle {cycle} ns is not n x {step / 1000:g} us{span}")
        if not active and self.has_cia402 and self.mode() in self.rules.dc_required_modes:
            self._refuse(EcState.OP, AlStatus.DC_INVALID_SYNC, f"mode {self.mode()} needs distributed clocks")
