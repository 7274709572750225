"""Commissioning: bring each drive of a project from INIT to a checked move, on a target.

For each drive: INIT → PRE-OP, identity check, ``.sw`` verify/download, the startup list with every write
verified by read-back, SAFE-OP, OP, enable through the CiA-402 state machine, a short move in user units
checked in internal units, and a report. On any failure the drive is stopped in a safe state and the failing
command is named with its abort code; success is never reported for a drive that failed.
"""

from ecattool.commission.runner import CommissionReport, DriveReport, Step, commission, commission_drive

__all__ = ["CommissionReport", "DriveReport", "Step", "commission", "commission_drive"]
