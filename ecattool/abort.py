"""CiA-301 SDO abort codes and EtherCAT AL status codes, with their standard texts."""

from __future__ import annotations

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

AL_STATUS_TEXTS: dict[int, str] = {
    0x0000: "no error",
    0x0001: "unspecified error",
    0x0002: "no memory",
    0x0011: "invalid requested state change",
    0x0012: "unknown requested state",
    0x0013: "bootstrap not supported",
    0x0014: "no valid firmware",
    0x0015: "invalid mailbox configuration (bootstrap)",
    0x0016: "invalid mailbox configuration",
    0x0017: "invalid sync manager configuration",
    0x0018: "no valid inputs available",
    0x0019: "no valid outputs",
    0x001A: "synchronization error",
    0x001B: "sync manager watchdog",
    0x001C: "invalid sync manager types",
    0x001D: "invalid output configuration",
    0x001E: "invalid input configuration",
    0x001F: "invalid watchdog configuration",
    0x0020: "slave needs cold start",
    0x0021: "slave needs INIT",
    0x0022: "slave needs PREOP",
    0x0023: "slave needs SAFEOP",
    0x0024: "invalid input mapping",
    0x0025: "invalid output mapping",
    0x0026: "inconsistent settings",
    0x0027: "freerun not supported",
    0x0028: "synchronization not supported",
    0x0029: "freerun needs 3-buffer mode",
    0x002A: "background watchdog",
    0x002B: "no valid inputs and outputs",
    0x002C: "fatal sync error",
    0x002D: "no sync error",
    0x0030: "invalid DC SYNC configuration",
    0x0031: "invalid DC latch configuration",
    0x0032: "PLL error",
    0x0033: "DC sync IO error",
    0x0034: "DC sync timeout error",
    0x0035: "DC invalid sync cycle time",
    0x0036: "DC sync0 cycle time",
    0x0037: "DC sync1 cycle time",
}


def abort_text(code: int) -> str:
    return ABORT_TEXTS.get(code, "unknown abort code")


def al_status_text(code: int) -> str:
    return AL_STATUS_TEXTS.get(code, "unknown AL status code")
