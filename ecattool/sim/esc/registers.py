"""Register addresses of the EtherCAT slave controller (ETG.1000.4; Beckhoff ET1100 and Microchip LAN9252
register maps) and which of them the master (the "ECAT" side) may write."""

from __future__ import annotations

TYPE = 0x0000
REVISION = 0x0001
BUILD = 0x0002
FMMUS_SUPPORTED = 0x0004
SMS_SUPPORTED = 0x0005
RAM_SIZE = 0x0006
PORT_DESCRIPTOR = 0x0007
FEATURES = 0x0008
STATION_ADDRESS = 0x0010
STATION_ALIAS = 0x0012
WRITE_ENABLE = 0x0020
WRITE_PROTECTION = 0x0021
ESC_WRITE_ENABLE = 0x0030
ESC_WRITE_PROTECTION = 0x0031
ESC_RESET = 0x0040
DL_CONTROL = 0x0100
PHYSICAL_RW_OFFSET = 0x0108
DL_STATUS = 0x0110
AL_CONTROL = 0x0120
AL_STATUS = 0x0130
AL_STATUS_CODE = 0x0134
PDI_CONTROL = 0x0140
#: PDI control value of an ESC whose PDI is digital I/O (no processor behind it)
PDI_DIGITAL_IO = 0x04
#: ESC configuration 0x0141 bit 0: device emulation (the AL status follows the AL control)
DEVICE_EMULATION = 0x01
ESC_CONFIG = 0x0141
PDI_CONFIG = 0x0150
ECAT_EVENT_MASK = 0x0200
AL_EVENT_MASK = 0x0204
ECAT_EVENT_REQUEST = 0x0210
AL_EVENT_REQUEST = 0x0220
RX_ERROR_COUNTER = 0x0300  # 2 bytes per port: invalid frame, RX error
FORWARDED_RX_ERROR = 0x0308
PROCESSING_UNIT_ERROR = 0x030C
PDI_ERROR = 0x030D
LOST_LINK = 0x0310
WD_DIVIDER = 0x0400
WD_TIME_PDI = 0x0410
WD_TIME_PD = 0x0420
WD_STATUS_PD = 0x0440
WD_COUNTER_PD = 0x0442
WD_COUNTER_PDI = 0x0443
EEPROM_CONFIG = 0x0500
EEPROM_PDI_ACCESS = 0x0501
EEPROM_CONTROL = 0x0502
EEPROM_ADDRESS = 0x0504
EEPROM_DATA = 0x0508
MII_CONTROL = 0x0510
FMMU = 0x0600
FMMU_SIZE = 16
SM = 0x0800
SM_SIZE = 8
DC_RECEIVE_TIME = 0x0900  # port 0..3, 4 bytes each
DC_SYSTEM_TIME = 0x0910
DC_RECEIVE_TIME_PU = 0x0918
DC_SYSTEM_OFFSET = 0x0920
DC_SYSTEM_DELAY = 0x0928
DC_SYSTEM_DIFFERENCE = 0x092C
DC_SPEED_START = 0x0930
DC_SPEED_DIFF = 0x0932
DC_FILTER_DEPTH = 0x0934
DC_CYCLIC_CONTROL = 0x0980
DC_ACTIVATION = 0x0981
DC_PULSE_LENGTH = 0x0982
DC_ACTIVATION_STATUS = 0x0984
DC_SYNC0_STATUS = 0x098E
DC_SYNC1_STATUS = 0x098F
DC_START_TIME = 0x0990
DC_NEXT_SYNC1 = 0x0998
DC_SYNC0_CYCLE = 0x09A0
DC_SYNC1_CYCLE = 0x09A4
DC_LATCH_CONTROL = 0x09A8
PROCESS_RAM = 0x1000

#: EEPROM control/status 0x0502 bits
EE_WRITE_ENABLE = 0x0001
EE_READ_8 = 0x0040
EE_TWO_ADDRESS_BYTES = 0x0080
EE_CMD_MASK = 0x0700
EE_CMD_READ = 0x0100
EE_CMD_WRITE = 0x0200
EE_CMD_RELOAD = 0x0400
EE_CHECKSUM_ERROR = 0x0800
EE_LOAD_ERROR = 0x1000
EE_ACK_ERROR = 0x2000
EE_WRITE_ERROR = 0x4000
EE_BUSY = 0x8000

#: AL status bit 4: error indication; AL control bit 4: error acknowledge
AL_ERROR = 0x10

#: (first, last) inclusive byte ranges below 0x1000 the master may write; all others are read-only for it
#: the digital output registers of an ESC with digital I/O
DIGITAL_OUTPUT, DIGITAL_OUTPUT_SIZE = 0x0F00, 4

ECAT_WRITABLE: tuple[tuple[int, int], ...] = (
    (STATION_ADDRESS, STATION_ADDRESS + 1),
    (WRITE_ENABLE, 0x0021), (ESC_WRITE_ENABLE, 0x0031), (ESC_RESET, ESC_RESET),
    (DL_CONTROL, 0x0103), (PHYSICAL_RW_OFFSET, 0x0109),
    (AL_CONTROL, 0x0121),
    (ECAT_EVENT_MASK, 0x0201),
    (RX_ERROR_COUNTER, 0x0313),
    (WD_DIVIDER, 0x0401), (WD_TIME_PDI, 0x0411), (WD_TIME_PD, 0x0421), (WD_COUNTER_PD, WD_COUNTER_PDI),
    (EEPROM_CONFIG, EEPROM_CONFIG), (EEPROM_CONTROL, 0x050F),
    (MII_CONTROL, 0x0517),
    (FMMU, 0x06FF),
    (DC_RECEIVE_TIME, 0x0903), (DC_SYSTEM_TIME, 0x0917), (DC_SYSTEM_OFFSET, 0x092B),
    (DC_SPEED_START, 0x0931), (DC_FILTER_DEPTH, 0x0935),
    (DC_CYCLIC_CONTROL, 0x0983), (DC_START_TIME, 0x0997), (DC_SYNC0_CYCLE, 0x09A9),
    (0x0F00, 0x0FFF),  # digital output, GPO, user RAM
)


def sm_writable_offsets() -> frozenset[int]:
    """Byte offsets of one sync manager's 8 registers the master may write (status 5 and PDI control 7
    are read-only)."""
    return frozenset({0, 1, 2, 3, 4, 6})


def writable_mask() -> bytes:
    """One byte per register address below 0x1000: 1 where the master may write."""
    mask = bytearray(PROCESS_RAM)
    for first, last in ECAT_WRITABLE:
        mask[first:last + 1] = b"\x01" * (last + 1 - first)
    for n in range(16):
        for off in sm_writable_offsets():
            mask[SM + SM_SIZE * n + off] = 1
    return bytes(mask)
