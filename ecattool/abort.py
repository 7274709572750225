"""CiA-301 SDO abort codes and EtherCAT AL status codes, with their standard texts."""

from __future__ import annotations

from enum import IntEnum

OBJECT_DOES_NOT_EXIST = 0x06020000
SUBINDEX_DOES_NOT_EXIST = 0x06090011
READ_ONLY = 0x06010002
WRITE_ONLY = 0x06010001
UNSUPPORTED_ACCESS = 0x06010000
SUBINDEX_CANNOT_BE_WRITTEN_SI0_NONZERO = 0x06010003
COMPLETE_ACCESS_NOT_SUPPORTED = 0x06010004
LENGTH_MISMATCH = 0x06070010
LENGTH_TOO_HIGH = 0x06070012
LENGTH_TOO_LOW = 0x06070013
VALUE_RANGE_EXCEEDED = 0x06090030
VALUE_TOO_HIGH = 0x06090031
VALUE_TOO_LOW = 0x06090032
NOT_MAPPABLE = 0x06040041
PDO_LENGTH_EXCEEDED = 0x06040042
GENERAL_PARAMETER_INCOMPATIBILITY = 0x06040043
GENERAL_INTERNAL_INCOMPATIBILITY = 0x06040047
HARDWARE_ERROR = 0x06060000
INVALID_VALUE = 0x06090030
GENERAL_ERROR = 0x08000000
DATA_CANNOT_BE_STORED = 0x08000020
DATA_CANNOT_BE_STORED_LOCAL = 0x08000021
DATA_CANNOT_BE_STORED_STATE = 0x08000022
NO_DATA_AVAILABLE = 0x08000024
TIMEOUT = 0x05040000
COMMAND_INVALID = 0x05040001
OUT_OF_MEMORY = 0x05040005

ABORT_TEXTS: dict[int, str] = {
    0x05030000: "toggle bit not changed",
    0x05040000: "SDO protocol timeout",
    0x05040001: "client/server command specifier not valid or unknown",
    0x05040005: "out of memory",
    0x06010000: "unsupported access to an object",
    0x06010001: "attempt to read a write-only object",
    0x06010002: "attempt to write a read-only object",
    0x06010003: "subindex cannot be written, SI0 must be 0 for write access",
    0x06010004: "SDO complete access not supported for this object",
    0x06020000: "the object does not exist in the object dictionary",
    0x06040041: "the object cannot be mapped into the PDO",
    0x06040042: "the number and length of the objects to be mapped would exceed the PDO length",
    0x06040043: "general parameter incompatibility reason",
    0x06040047: "general internal incompatibility in the device",
    0x06060000: "access failed due to a hardware error",
    0x06070010: "data type does not match, length of service parameter does not match",
    0x06070012: "data type does not match, length of service parameter too high",
    0x06070013: "data type does not match, length of service parameter too low",
    0x06090011: "subindex does not exist",
    0x06090030: "value range of parameter exceeded",
    0x06090031: "value of parameter written too high",
    0x06090032: "value of parameter written too low",
    0x06090036: "maximum value is less than minimum value",
    0x08000000: "general error",
    0x08000020: "data cannot be transferred or stored to the application",
    0x08000021: "data cannot be transferred or stored because of local control",
    0x08000022: "data cannot be transferred or stored because of the present device state",
    0x08000023: "object dictionary dynamic generation fails or no object dictionary is present",
    0x08000024: "no data available",
}


class AlStatus(IntEnum):
    """EtherCAT AL status codes (register 0x0134, ETG.1000.6 Table 11): the one definition; the standard text of
    each is :attr:`text` (:data:`AL_STATUS_TEXTS`)."""

    NO_ERROR = 0x0000
    UNSPECIFIED_ERROR = 0x0001
    NO_MEMORY = 0x0002
    INVALID_STATE_CHANGE = 0x0011
    UNKNOWN_STATE = 0x0012
    BOOTSTRAP_NOT_SUPPORTED = 0x0013
    NO_VALID_FIRMWARE = 0x0014
    INVALID_MAILBOX_BOOT = 0x0015
    INVALID_MAILBOX = 0x0016
    INVALID_SM = 0x0017
    NO_VALID_INPUTS = 0x0018
    NO_VALID_OUTPUTS = 0x0019
    SYNC_ERROR = 0x001A
    SM_WATCHDOG = 0x001B
    INVALID_SM_TYPES = 0x001C
    INVALID_OUTPUT_CONFIG = 0x001D
    INVALID_INPUT_CONFIG = 0x001E
    INVALID_WATCHDOG_CONFIG = 0x001F
    NEEDS_COLD_START = 0x0020
    NEEDS_INIT = 0x0021
    NEEDS_PREOP = 0x0022
    NEEDS_SAFEOP = 0x0023
    INVALID_INPUT_MAPPING = 0x0024
    INVALID_OUTPUT_MAPPING = 0x0025
    INCONSISTENT_SETTINGS = 0x0026
    FREERUN_NOT_SUPPORTED = 0x0027
    SYNC_NOT_SUPPORTED = 0x0028
    FREERUN_NEEDS_3_BUFFER = 0x0029
    BACKGROUND_WATCHDOG = 0x002A
    NO_VALID_IO = 0x002B
    FATAL_SYNC_ERROR = 0x002C
    NO_SYNC_ERROR = 0x002D
    DC_INVALID_SYNC = 0x0030
    DC_INVALID_LATCH = 0x0031
    PLL_ERROR = 0x0032
    DC_SYNC_IO_ERROR = 0x0033
    DC_SYNC_TIMEOUT = 0x0034
    DC_INVALID_CYCLE = 0x0035
    DC_SYNC0_CYCLE = 0x0036
    DC_SYNC1_CYCLE = 0x0037

    @property
    def text(self) -> str:
        """The standard text (``invalid requested state change``)."""
        return AL_STATUS_TEXTS[self]


#: the standard text of each AL status code
AL_STATUS_TEXTS: dict[int, str] = {
    AlStatus.NO_ERROR: "no error",
    AlStatus.UNSPECIFIED_ERROR: "unspecified error",
    AlStatus.NO_MEMORY: "no memory",
    AlStatus.INVALID_STATE_CHANGE: "invalid requested state change",
    AlStatus.UNKNOWN_STATE: "unknown requested state",
    AlStatus.BOOTSTRAP_NOT_SUPPORTED: "bootstrap not supported",
    AlStatus.NO_VALID_FIRMWARE: "no valid firmware",
    AlStatus.INVALID_MAILBOX_BOOT: "invalid mailbox configuration (bootstrap)",
    AlStatus.INVALID_MAILBOX: "invalid mailbox configuration",
    AlStatus.INVALID_SM: "invalid sync manager configuration",
    AlStatus.NO_VALID_INPUTS: "no valid inputs available",
    AlStatus.NO_VALID_OUTPUTS: "no valid outputs",
    AlStatus.SYNC_ERROR: "synchronization error",
    AlStatus.SM_WATCHDOG: "sync manager watchdog",
    AlStatus.INVALID_SM_TYPES: "invalid sync manager types",
    AlStatus.INVALID_OUTPUT_CONFIG: "invalid output configuration",
    AlStatus.INVALID_INPUT_CONFIG: "invalid input configuration",
    AlStatus.INVALID_WATCHDOG_CONFIG: "invalid watchdog configuration",
    AlStatus.NEEDS_COLD_START: "slave needs cold start",
    AlStatus.NEEDS_INIT: "slave needs INIT",
    AlStatus.NEEDS_PREOP: "slave needs PREOP",
    AlStatus.NEEDS_SAFEOP: "slave needs SAFEOP",
    AlStatus.INVALID_INPUT_MAPPING: "invalid input mapping",
    AlStatus.INVALID_OUTPUT_MAPPING: "invalid output mapping",
    AlStatus.INCONSISTENT_SETTINGS: "inconsistent settings",
    AlStatus.FREERUN_NOT_SUPPORTED: "freerun not supported",
    AlStatus.SYNC_NOT_SUPPORTED: "synchronization not supported",
    AlStatus.FREERUN_NEEDS_3_BUFFER: "freerun needs 3-buffer mode",
    AlStatus.BACKGROUND_WATCHDOG: "background watchdog",
    AlStatus.NO_VALID_IO: "no valid inputs and outputs",
    AlStatus.FATAL_SYNC_ERROR: "fatal sync error",
    AlStatus.NO_SYNC_ERROR: "no sync error",
    AlStatus.DC_INVALID_SYNC: "invalid DC SYNC configuration",
    AlStatus.DC_INVALID_LATCH: "invalid DC latch configuration",
    AlStatus.PLL_ERROR: "PLL error",
    AlStatus.DC_SYNC_IO_ERROR: "DC sync IO error",
    AlStatus.DC_SYNC_TIMEOUT: "DC sync timeout error",
    AlStatus.DC_INVALID_CYCLE: "DC invalid sync cycle time",
    AlStatus.DC_SYNC0_CYCLE: "DC sync0 cycle time",
    AlStatus.DC_SYNC1_CYCLE: "DC sync1 cycle time",
}


def abort_text(code: int) -> str:
    return ABORT_TEXTS.get(code, "unknown abort code")


def al_status_text(code: int) -> str:
    return AL_STATUS_TEXTS.get(code, "unknown AL status code")
