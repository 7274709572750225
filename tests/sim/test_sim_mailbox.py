"""The mailbox server against frames built byte by byte from ETG.1000.4/.6, compared with the in-process
drive (a second Drive of the same device answers the same SDO through its Python API)."""

from __future__ import annotations

import struct

import pytest

from ecattool.errors import SdoAbort
from ecattool.od.model import EcState
from ecattool.sim import Drive
from ecattool.sim.mailbox import MailboxServer
from tests.conftest import corpus_path

ETG_ESI = "samples/esi/etg2001_cia402.xml"  # SdoInfo and CompleteAccess on, FoE
FAMILIES = ["technosoft-ipos", "hdt", "controltechniques"]


def preop(drive: Drive) -> Drive:
    drive.request_state(EcState.PREOP)
    return drive


def family(name: str) -> Drive:
    return preop(Drive.from_profile(name))


def etg() -> Drive:
    return preop(Drive.from_esi(ETG_ESI))


def mbx(mtype: int, data: bytes, counter: int = 1) -> bytes:
    """A mailbox frame: length, address 0, channel/priority 0, type | counter << 4."""
    return struct.pack("<HHBB", len(data), 0, 0, mtype | (counter << 4)) + data


def coe(data: bytes, counter: int = 1, service: int = 2) -> bytes:
    return mbx(3, struct.pack("<H", service << 12) + data, counter)


def sdo_up(index: int, sub: int, counter: int = 1, ca: bool = False) -> bytes:
    return coe(struct.pack("<BHBI", 0x50 if ca else 0x40, index, sub, 0), counter)


def reply(server: MailboxServer) -> tuple[int, int, bytes]:
    """(type, counter, data) of the next reply; the header's length must match the data."""
    frame = server.pending()
    assert frame is not None, "no reply"
    length, address, chan, type_cnt = struct.unpack_from("<HHBB", frame)
    assert length == len(frame) - 6 and address == 0 and chan == 0
    return type_cnt & 0x0F, (type_cnt >> 4) & 7, frame[6:]


def abort_code(data: bytes) -> int:
    assert data[:2] == b"\x00\x20" and data[2] == 0x80, data.hex()
    return int(struct.unpack_from("<I", data, 6)[0])


def upload(server: MailboxServer, index: int, sub: int, counter: int = 1, ca: bool = False) -> bytes:
    """A whole SDO upload the way SOEM's ecx_SDOread does it (expedited, normal or segmented)."""
    server.handle(sdo_up(index, sub, counter, ca))
    _, _, d = reply(server)
    assert d[:2] == b"\x00\x30", d.hex()  # CoE: number 0, service 3 (SDO response)
    cmd = d[2]
    assert cmd >> 5 == 2, d.hex()
    assert struct.unpack_from("<HB", d, 3) == (index, sub)
    if cmd & 0x02:  # expedited
        return d[6:6 + 4 - ((cmd >> 2) & 3)]
    size = struct.unpack_from("<I", d, 6)[0]
    out = d[10:]
    toggle = 0
    while len(out) < size:
        counter = counter % 7 + 1
        server.handle(coe(bytes([0x60 | toggle]) + bytes(7), counter))
        _, _, s = reply(server)
        assert s[:2] == b"\x00\x30" and s[2] & 0xE0 == 0 and s[2] & 0x10 == toggle, s.hex()
        chunk = s[3:]
        if s[2] & 1 and len(s) == 10:
            chunk = chunk[:7 - ((s[2] >> 1) & 7)]
        out += chunk
        toggle ^= 0x10
        if s[2] & 1:
            break
    assert len(out) == size
    return out


# ----------------------------------------------------------------------------------------------
# SDO upload


@pytest.mark.parametrize("name", FAMILIES)
def test_expedited_upload_of_the_identity_matches_the_in_process_drive(name):
    server = MailboxServer(family(name), 128, 128)
    twin = family(name)
    server.handle(bytes.fromhex("0a00 0000 0013 0020 40 1810 01 00000000"))  # 1018:01 vendor id, counter 1
    mtype, counter, d = reply(server)
    assert (mtype, counter) == (3, 1)
    assert d[:6] == bytes.fromhex("0030 43 1810 01")  # expedited, size indicated, 4 octets
    assert d[6:10] == twin.sdo_upload(0x1018, 1)
    for sub in (2, 3):
        assert upload(server, 0x1018, sub, counter=sub) == twin.sdo_upload(0x1018, sub)


def test_expedited_upload_of_one_octet_says_three_unused():
    server = MailboxServer(etg(), 128, 128)
    server.handle(sdo_up(0x1018, 0))
    _, _, d = reply(server)
    assert d[2] == 0x4F and d[6] == etg().sdo_upload(0x1018, 0)[0]  # 0x43 | (4 - 1) << 2


def test_normal_upload_carries_the_size_and_the_data():
    server = MailboxServer(etg(), 128, 128)
    server.handle(sdo_up(0x1008, 0))
    _, _, d = reply(server)
    assert d[2] == 0x41 and struct.unpack_from("<I", d, 6)[0] == 6 and d[10:] == etg().sdo_upload(0x1008, 0)


@pytest.mark.parametrize(("index", "in_size"), [(0x1C32, 17), (0x1C32, 20), (0x1C32, 24), (0x1C32, 33),
                                                (0xF010, 128)])
def test_segmented_upload_through_a_small_mailbox_reassembles_to_the_drive_value(index, in_size):
    server = MailboxServer(etg(), 128, in_size)
    value = upload(server, index, 0, ca=True)
    assert value == etg().sdo_upload(index, 0, complete_access=True)
    assert len(value) > in_size - 16  # it really was segmented
    # every reply fits SM1
    server.handle(sdo_up(index, 0, 2, ca=True))
    assert len(server.pending() or b"") <= in_size


def test_segment_with_the_wrong_toggle_is_aborted():
    server = MailboxServer(etg(), 128, 20)
    server.handle(sdo_up(0x1A00, 0, ca=True))
    reply(server)
    server.handle(coe(bytes([0x70]) + bytes(7), 2))  # toggle 1 on the first segment
    assert abort_code(reply(server)[2]) == 0x05030000


def test_segment_request_without_a_transfer_is_an_invalid_command():
    server = MailboxServer(etg(), 128, 128)
    server.handle(coe(bytes([0x60]) + bytes(7)))
    assert abort_code(reply(server)[2]) == 0x05040001


@pytest.mark.parametrize("name", FAMILIES)
@pytest.mark.parametrize(("index", "sub"), [(0x5FFE, 0), (0x1018, 0x42), (0x6040, 0)])
def test_upload_aborts_carry_the_drive_code(name, index, sub):
    server = MailboxServer(family(name), 128, 128)
    try:
        family(name).sdo_upload(index, sub)
        expected = None
    except SdoAbort as exc:
        expected = exc.code
    server.handle(sdo_up(index, sub))
    _, _, d = reply(server)
    if expected is None:
        assert d[2] >> 5 == 2
    else:
        assert abort_code(d) == expected and struct.unpack_from("<HB", d, 3) == (index, sub)


def test_complete_access_refused_where_the_device_has_none():
    server = MailboxServer(family("technosoft-ipos"), 128, 128)
    server.handle(sdo_up(0x1C12, 0, ca=True))
    assert abort_code(reply(server)[2]) == 0x06010004


# ----------------------------------------------------------------------------------------------
# SDO download


def test_expedited_download_changes_the_drive_like_the_api():
    drive = family("technosoft-ipos")
    server = MailboxServer(drive, 128, 128)
    server.handle(coe(bytes.fromhex("2f 6060 00 08000000")))  # 6060:00 = 8 (CSP), one octet
    _, _, d = reply(server)
    assert d == bytes.fromhex("0030 60 6060 00 00000000")
    assert drive.sdo_upload(0x6060, 0) == b"\x08"


@pytest.mark.parametrize("name", FAMILIES)
def test_download_aborts_carry_the_drive_code(name):
    twin = family(name)
    with pytest.raises(SdoAbort) as exc:
        twin.sdo_download(0x1018, 1, b"\x01\x00\x00\x00")
    server = MailboxServer(family(name), 128, 128)
    server.handle(coe(bytes.fromhex("23 1810 01 01000000")))
    assert abort_code(reply(server)[2]) == exc.value.code == 0x06010002


def test_normal_download_of_a_mapping_by_complete_access():
    drive = etg()
    server = MailboxServer(drive, 128, 128)
    twin = etg()
    value = twin.sdo_upload(0x1A00, 0, complete_access=True)
    twin.sdo_download(0x1A00, 0, value, complete_access=True)
    server.handle(coe(struct.pack("<BHBI", 0x31, 0x1A00, 0, len(value)) + value))  # normal, CA, size indicated
    _, _, d = reply(server)
    assert d[:6] == bytes.fromhex("0030 70 001A 00")  # download response with the CA bit
    assert drive.sdo_upload(0x1A00, 0, complete_access=True) == twin.sdo_upload(0x1A00, 0, complete_access=True)


@pytest.mark.parametrize("out_size", [18, 24, 40])
def test_segmented_download_as_soem_sends_it(out_size):
    """SOEM ecx_SDOwrite: the first frame carries mbx_l - 16 octets, segments mbx_l - 9, and a last segment of
    fewer than 7 octets is padded to 7 with the unused count in the command."""
    drive = etg()
    value = etg().sdo_upload(0x1A00, 0, complete_access=True)
    server = MailboxServer(drive, out_size, 128)
    first = out_size - 16
    server.handle(coe(struct.pack("<BHBI", 0x31, 0x1A00, 0, len(value)) + value[:first]))
    _, _, d = reply(server)
    assert d[2] == 0x70, d.hex()
    rest, toggle, counter = value[first:], 0, 1
    while rest:
        chunk, rest = rest[:out_size - 9], rest[out_size - 9:]
        cmd = toggle | (0 if rest else 1)
        if not rest and len(chunk) < 7:
            cmd |= (7 - len(chunk)) << 1
            chunk = chunk.ljust(7, b"\x00")
        counter = counter % 7 + 1
        server.handle(coe(bytes([cmd]) + chunk, counter))
        _, _, s = reply(server)
        assert s == b"\x00\x30" + bytes([0x20 | toggle]) + bytes(7), s.hex()
        toggle ^= 0x10
    assert drive.sdo_upload(0x1A00, 0, complete_access=True) == value
    assert [e.kind for e in drive.events].count("sdo_download") == 1


def test_segmented_download_refused_by_the_drive_at_the_last_segment():
    value = b"\x01\x00" + bytes(10)  # 1A00h with one mapped entry 0000:00 of 0 bits
    twin = etg()
    with pytest.raises(SdoAbort) as exc:
        twin.sdo_download(0x1A00, 0, value, complete_access=True)
    server = MailboxServer(etg(), 20, 128)
    server.handle(coe(struct.pack("<BHBI", 0x31, 0x1A00, 0, len(value)) + value[:4]))  # 20 - 16 = 4 octets
    assert reply(server)[2][2] == 0x70
    server.handle(coe(bytes([0x01]) + value[4:], 2))  # the 8 octets left: one last segment (11 would fit)
    assert abort_code(reply(server)[2]) == exc.value.code


def test_segments_longer_than_announced_are_refused():
    server = MailboxServer(etg(), 20, 128)  # complete access: only the cap bounds the announced size
    server.handle(coe(struct.pack("<BHBI", 0x31, 0x1A00, 0, 6) + b"\x01\x02\x03\x04"))
    reply(server)
    server.handle(coe(bytes([0x01]) + bytes(9), 2))
    assert abort_code(reply(server)[2]) == 0x06070010


def test_an_announced_size_the_object_cannot_have_is_refused_at_the_initiate():
    """1C12h:00 (writable in PRE-OP) is one octet: a segmented download announcing 6 is aborted at once
    (0x06070012), as a slave stack checks it, and the segments that follow belong to no transfer. (1A00h:00 of this
    ESI is read-only: that is refused at the initiate too, with 0x06010002 — tests/wire/test_wire_esc_bounds.py.)"""
    server = MailboxServer(etg(), 20, 128)
    server.handle(coe(struct.pack("<BHBI", 0x21, 0x1C12, 0, 6) + b"\x01\x02\x03\x04"))
    assert abort_code(reply(server)[2]) == 0x06070012
    server.handle(coe(bytes([0x01]) + bytes(9), 2))
    assert abort_code(reply(server)[2]) == 0x05040001


def test_master_abort_ends_the_transfer_without_a_reply():
    server = MailboxServer(etg(), 128, 20)
    server.handle(sdo_up(0x1A00, 0, ca=True))
    reply(server)
    server.handle(coe(struct.pack("<BHBI", 0x80, 0x1A00, 0, 0x05040000), 2))
    assert server.pending() is None
    server.handle(coe(bytes([0x60]) + bytes(7), 3))
    assert abort_code(reply(server)[2]) == 0x05040001


# ----------------------------------------------------------------------------------------------
# mailbox layer


@pytest.mark.parametrize(("mtype", "detail"), [(1, 2), (2, 2), (5, 2), (15, 2)])
def test_unsupported_mailbox_type_gets_a_mailbox_error(mtype, detail):
    server = MailboxServer(family("hdt"), 128, 128)  # HDT: CoE only
    server.handle(mbx(mtype, bytes(10)))
    t, _, d = reply(server)
    assert t == 0 and d == struct.pack("<HH", 1, detail)


def test_unsupported_coe_service_and_bad_sizes_get_mailbox_errors():
    server = MailboxServer(family("hdt"), 128, 128)
    server.handle(coe(bytes(8), service=5))  # RxPDO over the mailbox
    assert reply(server)[2] == bytes.fromhex("0100 0400")
    server.handle(bytes.fromhex("4000 0000 0023") + bytes(10))  # length 64 in a 16-octet frame
    assert reply(server)[2] == bytes.fromhex("0100 0800")
    server.handle(coe(bytes.fromhex("40 1810"), 3))  # SDO shorter than 10 octets
    assert reply(server)[2] == bytes.fromhex("0100 0600")


def test_padded_frames_use_the_header_length():
    server = MailboxServer(family("hdt"), 128, 128)
    server.handle(sdo_up(0x1018, 1).ljust(128, b"\xEE"))
    assert reply(server)[2][2] == 0x43


def test_a_repeated_counter_is_executed_once_and_repeat_gives_the_last_frame():
    drive = family("technosoft-ipos")
    server = MailboxServer(drive, 128, 128)
    write = coe(bytes.fromhex("2f 6060 00 01000000"), counter=3)
    server.handle(write)
    server.handle(write)
    first = server.pending()
    assert server.pending() is None
    assert server.repeat() == first
    assert [e.kind for e in drive.events].count("sdo_download") == 1
    server.handle(coe(bytes.fromhex("2f 6060 00 08000000"), counter=4))
    assert reply(server)[1] == 2  # the slave counts its own replies 1, 2, ...
    server.resize(128, 128)  # the master set the mailbox up again: counter 4 is new once more
    server.handle(coe(bytes.fromhex("2f 6060 00 08000000"), counter=4))
    assert reply(server)[1] == 1


def test_slave_counter_wraps_from_7_to_1():
    server = MailboxServer(family("hdt"), 128, 128)
    counters = []
    for n in range(9):
        server.handle(sdo_up(0x1018, 1, counter=n % 7 + 1))
        counters.append(reply(server)[1])
    assert counters == [1, 2, 3, 4, 5, 6, 7, 1, 2]


# ----------------------------------------------------------------------------------------------
# Emergency


def test_drive_emergencies_become_coe_emergency_frames_after_the_reply():
    drive = family("technosoft-ipos")
    server = MailboxServer(drive, 128, 128)
    server.handle(coe(bytes.fromhex("2f 6060 00 05000000")))  # mode 5: Technosoft takes it, EMCY FF04h
    assert reply(server)[2][2] == 0x60
    emcy = drive.emergencies[-1]
    t, _, d = reply(server)
    assert t == 3 and d[:2] == b"\x00\x10"  # service 1
    assert struct.unpack_from("<HB", d, 2) == (0xFF04, emcy.register) and len(d) == 10
    drive.inject_fault(0x7500)
    t, _, d = reply(server)
    assert struct.unpack_from("<H", d, 2)[0] == 0x7500 and d[4] & 0x01
    assert server.pending() is None


def test_emergencies_while_the_mailbox_is_off_are_not_sent():
    drive = Drive.from_profile("hdt")  # INIT
    server = MailboxServer(drive, 128, 128)
    drive.emcy(0x5000)
    assert server.pending() is None
    drive.request_state(EcState.PREOP)
    assert server.pending() is None


# ----------------------------------------------------------------------------------------------
# SDO information


def info(opcode: int, body: bytes, counter: int = 1) -> bytes:
    return coe(struct.pack("<BBH", opcode, 0, 0) + body, counter, service=8)


def read_od_list(server: MailboxServer, list_type: int) -> list[int]:
    """As SOEM's ecx_readODlist: the first fragment starts with the list type, then UINT16 indices, while
    Fragments Left > 0."""
    server.handle(info(0x01, struct.pack("<H", list_type), counter=list_type + 1))  # a new counter each time
    values: list[int] = []
    first = True
    while True:
        t, _, d = reply(server)
        assert t == 3 and d[:2] == b"\x00\x80" and d[2] & 0x7F == 0x02, d.hex()
        left = struct.unpack_from("<H", d, 4)[0]
        body = d[6:]
        if first:
            assert struct.unpack_from("<H", body)[0] == list_type
            body = body[2:]
            first = False
        values += struct.unpack(f"<{len(body) // 2}H", body)
        assert bool(d[2] & 0x80) == (left > 0)
        if not left:
            return values


@pytest.mark.parametrize("in_size", [128, 24])
def test_od_list_in_fragments(in_size):
    drive = etg()
    server = MailboxServer(drive, 128, in_size)
    objects = list(drive.device.dictionary)
    assert read_od_list(server, 1) == [o.index for o in objects]
    rx = [o.index for o in objects if any(e.rx_mappable for e in o)]
    tx = [o.index for o in objects if any(e.tx_mappable for e in o)]
    assert read_od_list(server, 2) == rx and 0x6040 in rx
    assert read_od_list(server, 3) == tx and 0x6041 in tx
    assert read_od_list(server, 0)[:3] == [len(objects), len(rx), len(tx)]


def test_object_description_as_soem_reads_it():
    drive = etg()
    server = MailboxServer(drive, 128, 128)
    server.handle(info(0x03, struct.pack("<H", 0x1018)))
    _, _, d = reply(server)
    # SOEM: wdata[1] data type, bdata[4] max sub-index, bdata[5] object code, name from bdata[6]
    assert d[2:6] == bytes.fromhex("04 00 0000")
    index, dtype, max_sub, code = struct.unpack_from("<HHBB", d, 6)
    assert (index, dtype, max_sub, code) == (0x1018, 0x0023, 4, 9)
    assert d[12:].decode() == drive.device.dictionary.get(0x1018).name
    server.handle(info(0x03, struct.pack("<H", 0x6040), 2))
    _, _, d = reply(server)
    assert struct.unpack_from("<HHBB", d, 6) == (0x6040, 0x0006, 0, 7)  # UINT16 VAR


def test_entry_description_as_soem_reads_it():
    drive = etg()
    server = MailboxServer(drive, 128, 128)
    server.handle(info(0x05, struct.pack("<HBB", 0x6040, 0, 0x07)))  # SOEM asks value info 1 + 2 + 4
    _, _, d = reply(server)
    index, sub, vinfo, dtype, bits, access = struct.unpack_from("<HBBHHH", d, 6)
    assert (index, sub, vinfo, dtype, bits) == (0x6040, 0, 0x07, 0x0006, 16)
    e = drive.device.dictionary.entry(0x6040, 0)
    assert access & 0x3F == 0x3F and bool(access & 0x40) == e.rx_mappable and not access & 0x80
    assert d[16:].decode() == e.name
    server.handle(info(0x05, struct.pack("<HBB", 0x1018, 1, 0x07), 2))
    _, _, d = reply(server)
    assert struct.unpack_from("<HHH", d, 10) == (0x0007, 32, 0x0007)  # UDINT, read-only in every state


def test_entry_description_with_default_and_limits():
    """1C12:00 of the ETG sample: USINT, default 2, maximum 2, no minimum: value info says what is present."""
    server = MailboxServer(etg(), 128, 128)
    server.handle(info(0x05, struct.pack("<HBB", 0x1C12, 0, 0x77)))  # default, minimum and maximum asked
    _, _, d = reply(server)
    assert d[9] == 0x57  # 0x07 | default 0x10 | maximum 0x40: no minimum in the ESI
    assert d[16:18] == b"\x02\x02"
    assert d[18:].decode() == etg().device.dictionary.entry(0x1C12, 0).name


@pytest.mark.parametrize(("body", "code"), [(struct.pack("<H", 0x5FFE), 0x06020000)])
def test_object_description_of_a_missing_object_is_an_info_error(body, code):
    server = MailboxServer(etg(), 128, 128)
    server.handle(info(0x03, body))
    _, _, d = reply(server)
    assert d[:3] == bytes.fromhex("0080 07") and struct.unpack_from("<I", d, 6)[0] == code
    server.handle(info(0x05, struct.pack("<HBB", 0x1018, 9, 0), 2))
    assert struct.unpack_from("<I", reply(server)[2], 6)[0] == 0x06090011


def test_sdo_information_where_the_device_has_none_is_a_mailbox_error():
    server = MailboxServer(family("technosoft-ipos"), 128, 128)  # profile: no SdoInfo
    server.handle(info(0x01, struct.pack("<H", 1)))
    assert reply(server)[:3:2] == (0, bytes.fromhex("0100 0400"))


# ----------------------------------------------------------------------------------------------
# FoE


SETUP = "ecmc_ipos4808_BRUSHDC_VOLT_48V_20A.bin"


def foe(opcode: int, word: int, body: bytes, counter: int) -> bytes:
    return mbx(4, struct.pack("<BBI", opcode, 0, word) + body, counter)


def foe_write(server: MailboxServer, name: str, data: bytes, password: int = 0, size: int = 128
              ) -> list[tuple[int, int]]:
    """A write as SOEM's ecx_FOEwrite sends it (packets of mbx_l - 12 octets, an empty last packet after a
    full one, the same packet again after BUSY); returns the (opcode, word) of every reply."""
    full = size - 12
    packets = [data[i:i + full] for i in range(0, len(data), full)]
    if len(data) % full == 0:
        packets.append(b"")
    counter = 1
    server.handle(foe(2, password, name.encode(), counter))
    seen = []
    sent = 0
    while True:
        t, _, d = reply(server)
        assert t == 4
        opcode, word = d[0], struct.unpack_from("<I", d, 2)[0]
        seen.append((opcode, word))
        if opcode == 4:
            assert word == sent
            if sent == len(packets):
                return seen
            sent += 1
        elif opcode != 6:  # an error ends the write; BUSY: the same packet again
            return seen
        counter = counter % 7 + 1
        server.handle(foe(3, sent, packets[sent - 1], counter))


def technosoft() -> Drive:
    return family("technosoft-ipos")


def test_foe_write_of_a_setup_file_programs_the_eeprom_like_the_api():
    data = corpus_path("sw", SETUP).read_bytes()
    drive, twin = technosoft(), technosoft()
    twin.foe_write("FOESW_AXIS1.bin", data)
    server = MailboxServer(drive, 128, 128)
    seen = foe_write(server, "FOESW_AXIS1.bin", data)
    packets = -(-len(data) // 116) + (1 if len(data) % 116 == 0 else 0)
    assert seen == [(4, n) for n in range(packets + 1)]
    assert drive.eeprom_words(0x7000, 0x1000) == twin.eeprom_words(0x7000, 0x1000)
    assert drive.eeprom_words(0x7000, 0x1000) != technosoft().eeprom_words(0x7000, 0x1000)


@pytest.mark.parametrize(("name", "password", "code"), [
    ("setup.bin", 0, 0x8004),              # not FOESW_
    ("FOESW_AXIS1.bin", 7, 0x800A),         # setup files need password 0
    ("FOEFW_F515K.foe", 0x35313546, 0x8008),  # firmware only in BOOT
])
def test_foe_refusals_carry_the_drive_code(name, password, code):
    """A wrong name, password or state is refused at the write request, before any data is sent."""
    data = corpus_path("sw", SETUP).read_bytes()
    server = MailboxServer(technosoft(), 128, 128)
    seen = foe_write(server, name, data, password)
    assert seen == [(5, code)]


def test_foe_content_refused_after_the_last_packet():
    """What is wrong inside the file shows only once the drive has it all: the data packets are acknowledged."""
    server = MailboxServer(technosoft(), 128, 128)
    seen = foe_write(server, "FOESW_AXIS1.bin", b"\x01\x02\x03" * 100)
    assert seen[-1] == (5, 0x8004) and len(seen) > 2 and all(op == 4 for op, _ in seen[:-1])


def test_foe_busy_then_ack_on_the_repeated_last_packet():
    data = corpus_path("sw", SETUP).read_bytes()
    drive = technosoft()
    server = MailboxServer(drive, 128, 128)
    server.foe.busy_replies = 2
    seen = foe_write(server, "FOESW_AXIS1.bin", data)
    assert [op for op, _ in seen[-3:]] == [6, 6, 4]
    assert drive.eeprom_words(0x7000, 0x1000) != technosoft().eeprom_words(0x7000, 0x1000)


def test_foe_packet_number_out_of_order_is_an_error():
    server = MailboxServer(technosoft(), 128, 128)
    server.handle(foe(2, 0, b"FOESW_AXIS1.bin", 1))
    assert reply(server)[2][:6] == bytes.fromhex("04 00 00000000")
    server.handle(foe(3, 2, bytes(116), 2))
    _, _, d = reply(server)
    assert d[0] == 5 and struct.unpack_from("<I", d, 2)[0] == 0x8005


def test_foe_on_a_drive_without_foe_is_a_mailbox_error():
    server = MailboxServer(family("hdt"), 128, 128)
    server.handle(foe(2, 0, b"FOESW_AXIS1.bin", 1))
    assert reply(server)[:3:2] == (0, bytes.fromhex("0100 0200"))


@pytest.mark.parametrize("size", [0, 5, 116, 117, 300])
def test_foe_read_in_packets(size):
    server = MailboxServer(technosoft(), 128, 128)
    content = bytes(range(256)) * 2
    server.foe.files["log.txt"] = content[:size]
    server.handle(foe(1, 0, b"log.txt\x00", 1))
    got, counter = b"", 1
    while True:
        t, _, d = reply(server)
        assert t == 4 and d[0] == 3
        packet = struct.unpack_from("<I", d, 2)[0]
        got += d[6:]
        counter = counter % 7 + 1
        server.handle(foe(4, packet, b"", counter))
        if len(d) - 6 < 116:
            break
    assert got == content[:size] and server.pending() is None


def test_foe_read_of_a_missing_file_is_not_found():
    server = MailboxServer(technosoft(), 128, 128)
    server.handle(foe(1, 0, b"FOESW_AXIS1.bin", 1))
    _, _, d = reply(server)
    assert d[0] == 5 and struct.unpack_from("<I", d, 2)[0] == 0x8001
