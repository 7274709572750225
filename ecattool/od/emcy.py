"""What an emergency / error code (EMCY bytes 0-1, 603Fh) means: the drive family's own table first, then the
CiA-301/402 classes by their high byte.

Family tables as printed: Technosoft iPOS §3.1.3 (Table 3.1.3), HDT §2.08.2 (with the FA alarm number the table
order implies). Control Techniques reports its trips in Pr MM.50 rather than by EMCY code and gets the classes.
"""

from __future__ import annotations

TECHNOSOFT: dict[int, str] = {
    0x1000: "generic error (communication error, 2000h bit 0)", 0x2310: "continuous over-current",
    0x2340: "short-circuit", 0x3210: "DC-link over-voltage", 0x3220: "DC-link under-voltage",
    0x4280: "over temperature motor", 0x4310: "over temperature drive",
    0x5441: "drive disabled due to enable or STO input", 0x5442: "negative limit switch active",
    0x5443: "positive limit switch active", 0x6100: "invalid setup data", 0x7300: "sensor error (2009h)",
    0x7500: "communication error", 0x8100: "EtherCAT communication error",
    0x8210: "PDO not processed due to length error", 0x8220: "PDO length exceeded",
    0x8331: "I2t protection triggered", 0x8580: "position wraparound or hall sensor error",
    0x8611: "control error / following error", 0x9000: "command error",
    0xFF01: "generic interpolated position mode error (PVT/PT)", 0xFF02: "change set acknowledge bit wrong value",
    0xFF03: "specified homing method not available", 0xFF04: "a wrong mode is set in 6060h",
    0xFF05: "specified digital I/O line not available", 0xFF06: "positive software position limit triggered",
    0xFF07: "negative software position limit triggered", 0xFF08: "enable/STO circuit hardware error",
}
HDT: dict[int, str] = {
    0x7600: "parameter memorization error (FA_01)", 0xFF01: "current offset error (FA_02)",
    0x2340: "power circuit overcurrent (FA_03)", 0x3210: "DC bus overvoltage (FA_04)",
    0xFF0B: "Hall sensors error (FA_07)", 0xFF08: "secure disable (FA_08)",
    0x7120: "motor overtemperature (FA_09)", 0x7110: "braking resistor (FA_10)",
    0x3220: "DC bus undervoltage (FA_12)", 0x8611: "following error: position error (FA_13)",
    0xFF02: "home position error (FA_14)", 0xFF03: "warning I2t inverter (FA_15)",
    0xFF04: "warning I2t motor (FA_16)", 0xFF05: "warning overspeed (FA_17)",
    0xFF09: "secure disable error 1 (FA_18)", 0x8130: "life guard error (FA_20)",
    0xFF07: "memory fault (FA_21)", 0xFF0A: "motor phases error (FA_22)",
    0xFF0D: "secure disable error 2 (FA_23)", 0x4310: "radiator overtemperature (FA_24)",
    0xFF0C: "Hall sensors sequence error (FA_25)", 0x8400: "speed error (FA_26)",
}
_FAMILIES = {"technosoft-ipos": TECHNOSOFT, "hdt": HDT}
#: CiA-301 error code classes (high byte, or high nibble where the class is one digit)
_CLASSES = {0x00: "no error / error reset", 0x10: "generic error", 0x20: "current", 0x21: "current, device input side",
            0x22: "current inside the device", 0x23: "current, device output side", 0x30: "voltage",
            0x31: "mains voltage", 0x32: "voltage inside the device", 0x33: "output voltage", 0x40: "temperature",
            0x41: "ambient temperature", 0x42: "device temperature", 0x50: "device hardware", 0x60: "device software",
            0x61: "internal software", 0x62: "user software", 0x63: "data set", 0x70: "additional modules",
            0x80: "monitoring", 0x81: "communication", 0x82: "protocol error", 0x86: "position control",
            0x90: "external error", 0xF0: "additional functions", 0xFF: "device specific"}


def error_text(code: int, family: str | None = None) -> str:
    """A short text for an EMCY / 603Fh error code: the family's entry, else its CiA-301 class."""
    text = _FAMILIES.get(family or "", {}).get(code)
    if text is not None:
        return text
    high = code >> 8
    return _CLASSES.get(high) or _CLASSES.get(high & 0xF0) or "unknown error code"
