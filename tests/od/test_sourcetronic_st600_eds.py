"""Tests for od/sourcetronic-st600/sourcetronic-st600.eds, faults.csv.

Every expected value below is copied from the manual
Sourcetronic "Installation and Setup Guide - PROFIBUS/CANopen communication extension cards" (Sourcetronic "Installation and
Setup Guide - PROFIBUS/CANopen communication extension cards"), not read back
from the EDS. The section is named in each test's name or docstring.
Node-ID 3 is used because every example in the manual uses node 3.
"""
import configparser
import csv
import logging
import pathlib
import re
import warnings

import canopen
import pytest
from canopen.objectdictionary import ODArray, ODRecord, ODVariable
from canopen.objectdictionary import datatypes as dt

ROOT = pathlib.Path(__file__).resolve().parents[2]
DRIVE_DIR = ROOT / "od" / "sourcetronic-st600"
EDS = DRIVE_DIR / "sourcetronic-st600.eds"
FAULTS = DRIVE_DIR / "faults.csv"
NODE = 3


def _load(node_id=NODE):
    return canopen.objectdictionary.import_od(str(EDS), node_id=node_id)


@pytest.fixture(scope="module")
def od():
    return _load()


@pytest.fixture(scope="module")
def raw_eds():
    cp = configparser.RawConfigParser(inline_comment_prefixes=(";",))
    cp.optionxform = str
    cp.read(EDS, encoding="utf-8")
    return cp


@pytest.fixture(scope="module")
def pdo_node(od):
    node = canopen.LocalNode(NODE, od)
    net = canopen.Network()
    net.add_node(node)
    node.rpdo.read(from_od=True)
    node.tpdo.read(from_od=True)
    return node


def P(group, number):
    """ST600 function code address rule (§3.5.2.1): MSB = group, LSB = number;
    the EDS images parameter Pgg.nn at index 0x4000 + address, sub 0 (NOTES.md)."""
    return 0x4000 + ((group << 8) | number)


# --------------------------------------------------------------------------- loading

def test_eds_loads_without_any_warning(caplog):
    """CiA 306 file must load in python-canopen with nothing logged at WARNING+."""
    caplog.set_level(logging.WARNING)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        od = _load(node_id=5)
    assert len(od) > 0
    assert [r for r in caplog.records if r.levelno >= logging.WARNING] == []


def test_every_object_section_has_source_comment():
    """Convention: a '; source:' comment above every [XXXX] object section."""
    lines = EDS.read_text(encoding="utf-8").splitlines()
    missing = []
    for i, line in enumerate(lines):
        if re.fullmatch(r"\[[0-9A-F]{4}\]", line):
            j = i - 1
            block = []
            while j >= 0 and lines[j].startswith(";"):
                block.append(lines[j])
                j -= 1
            if not any(b.startswith("; source:") for b in block):
                missing.append(line)
    assert missing == []


def test_object_lists_match_sections(raw_eds):
    """[Mandatory/Optional/ManufacturerObjects] list exactly the object sections (CiA 306)."""
    listed = set()
    for sect in ("MandatoryObjects", "OptionalObjects", "ManufacturerObjects"):
        n = int(raw_eds.get(sect, "SupportedObjects"))
        items = [int(raw_eds.get(sect, str(i)), 16) for i in range(1, n + 1)]
        assert len(items) == n
        listed |= set(items)
    sections = {int(s, 16) for s in raw_eds.sections() if re.fullmatch(r"[0-9A-F]{4}", s)}
    assert listed == sections
    mand = [int(raw_eds.get("MandatoryObjects", str(i)), 16) for i in (1, 2, 3)]
    assert mand == [0x1000, 0x1001, 0x1018]


# --------------------------------------------------------------------------- identity (App. A)

def test_device_type_is_zero_no_cia402_app_a(od):
    """App. A: 1000h Device type RO Unsigned32 = 0x0000 0000 (no device profile)."""
    v = od[0x1000]
    assert v.data_type == dt.UNSIGNED32 and v.access_type == "ro" and v.default == 0


def test_no_cia402_or_0x6000_objects_sec_3_4_9(od):
    """§3.4.9: reading 0x6000:00 aborts 0x06020000 - no profile area in the OD."""
    assert not any(0x6000 <= i <= 0x9FFF for i in od.indices if isinstance(i, int))
    assert 0x6040 not in od and 0x6041 not in od and 0x6000 not in od


def test_unsupported_standard_objects_absent_sec_3_2_app_a(od):
    """§3.2: no storing at power outage (no 1010h/1011h), no time stamp (1012h);
    App. A lists no 1002h, 1014h, 1015h, 1029h."""
    for idx in (0x1002, 0x1010, 0x1011, 0x1012, 0x1014, 0x1015, 0x1029):
        assert idx not in od


def test_communication_area_is_exactly_appendix_a(od):
    """App. A lists exactly these communication objects."""
    expected = {0x1000, 0x1001, 0x1003, 0x1005, 0x1006, 0x1007, 0x1008, 0x1009, 0x100A,
                0x100C, 0x100D, 0x1016, 0x1017, 0x1018, 0x1200, 0x1280,
                0x1400, 0x1401, 0x1402, 0x1403, 0x1600, 0x1601, 0x1602, 0x1603,
                0x1800, 0x1801, 0x1802, 0x1803, 0x1A00, 0x1A01, 0x1A02, 0x1A03}
    got = {i for i in od.indices if isinstance(i, int) and 0x1000 <= i <= 0x1FFF}
    assert got == expected


def test_error_register_app_a(od):
    """App. A: 1001h Error register RO Unsigned8."""
    v = od[0x1001]
    assert v.data_type == dt.UNSIGNED8 and v.access_type == "ro"


def test_error_code_register_app_a(od):
    """App. A: 1003h sub0 'Number of subindexes' RW, sub1 'Error code' RO Unsigned32."""
    obj = od[0x1003]
    assert isinstance(obj, ODArray)
    assert obj[0].access_type == "rw"
    assert obj[1].access_type == "ro" and obj[1].data_type == dt.UNSIGNED32
    assert sorted(obj.subindices) == [0, 1]


def test_sync_cob_id_0x80_sec_3_4_7(od):
    """§3.4.7: 0x1005 COB-ID SYNC = 0x80 (pre-defined connection set); App. A: RW U32."""
    v = od[0x1005]
    assert v.default == 0x80 and v.access_type == "rw" and v.data_type == dt.UNSIGNED32


@pytest.mark.parametrize("idx", [0x1006, 0x1007])
def test_sync_period_and_window_rw_u32_app_a(od, idx):
    """App. A: 1006h/1007h RW Unsigned32."""
    assert od[idx].access_type == "rw" and od[idx].data_type == dt.UNSIGNED32


@pytest.mark.parametrize("idx,text", [(0x1008, "Sourcetronic CANopen"),
                                      (0x1009, "V1.00"), (0x100A, "V1.00")])
def test_strings_app_a(od, idx, text):
    """App. A: 1008h/1009h/100Ah CONST String defaults."""
    v = od[idx]
    assert v.data_type == dt.VISIBLE_STRING and v.access_type == "const" and v.default == text


def test_device_name_is_20_characters_app_a(od):
    """App. A: 'Sourcetronic CANopen' (needs segmented SDO, > 4 bytes)."""
    assert len(od[0x1008].default) == 20


@pytest.mark.parametrize("idx", [0x100C, 0x100D])
def test_guard_time_and_life_factor_u16_rw_0_app_a(od, idx):
    """App. A: 100Ch 'Protection time' and 100Dh 'Life cycle factor' RW Unsigned16 = 0."""
    v = od[idx]
    assert v.data_type == dt.UNSIGNED16 and v.access_type == "rw" and v.default == 0


def test_consumer_heartbeat_app_a(od):
    """App. A: 1016h sub0 RO Unsigned8, sub1 RW Unsigned32."""
    obj = od[0x1016]
    assert obj[0].access_type == "ro" and obj[0].data_type == dt.UNSIGNED8
    assert obj[1].access_type == "rw" and obj[1].data_type == dt.UNSIGNED32


def test_producer_heartbeat_default_0_sec_3_4_5(od):
    """§3.4.5: 16-bit interval in ms, 0 by default; App. A RW Unsigned16 = 0."""
    v = od[0x1017]
    assert v.data_type == dt.UNSIGNED16 and v.access_type == "rw" and v.default == 0


def test_identity_object_app_a(od):
    """App. A: 1018h sub0 = 4; supplier ID, product code, revision, sequence No. = 0, all RO."""
    obj = od[0x1018]
    assert isinstance(obj, ODRecord)
    assert obj[0].default == 4 and obj[0].data_type == dt.UNSIGNED8
    for s in (1, 2, 3, 4):
        assert obj[s].default == 0
        assert obj[s].access_type == "ro" and obj[s].data_type == dt.UNSIGNED32


def test_device_info_identity_and_baud_rates_table_3_1(od):
    """Table 3-1: 1000/800/500/250/125/(100)/50/20 kbit/s; App. A identity = 0; back page: Sourcetronic."""
    di = od.device_information
    assert di.vendor_name.startswith("Sourcetronic")
    assert di.vendor_number == 0 and di.product_number == 0 and di.revision_number == 0
    assert di.allowed_baudrates == {20000, 50000, 125000, 250000, 500000, 800000, 1000000}
    assert di.nr_of_RXPDO == 4 and di.nr_of_TXPDO == 4


def test_server_sdo_cob_ids_app_a(od):
    """App. A: 1200h sub1 = 600h+Node ID, sub2 = 580h+Node ID, RO (§3.4.9: 0x603/0x583 for node 3)."""
    obj = od[0x1200]
    assert obj[1].default == 0x603 and obj[2].default == 0x583
    assert obj[1].access_type == obj[2].access_type == "ro"


def test_client_sdo_all_ro_app_a(od):
    """App. A: 1280h sub0..3 all RO; sub3 Unsigned8."""
    obj = od[0x1280]
    assert sorted(obj.subindices) == [0, 1, 2, 3]
    assert all(obj[s].access_type == "ro" for s in range(4))
    assert obj[3].data_type == dt.UNSIGNED8


# --------------------------------------------------------------------------- PDO communication

@pytest.mark.parametrize("n,cob", [(0, 0x203), (1, 0x303), (2, 0x403), (3, 0x503)])
def test_rpdo_cob_ids_sec_3_4_1(od, n, cob):
    """§3.4.1: PDOn Rx COB-IDs 0x201.., 0x301.., 0x401.., 0x501..; §3.5.2.1/§3.5.3 examples 0x203/0x303."""
    v = od[0x1400 + n][1]
    assert v.default == cob and v.access_type == "rw" and v.data_type == dt.UNSIGNED32


@pytest.mark.parametrize("n,cob", [(0, 0x183), (1, 0x283), (2, 0x383), (3, 0x483)])
def test_tpdo_cob_ids_sec_3_4_1(od, n, cob):
    """§3.4.1: PDOn Tx COB-IDs; §3.5.2.2/§3.5.4 examples 0x183/0x283."""
    v = od[0x1800 + n][1]
    assert v.default == cob and v.access_type == "rw"


def test_cob_ids_are_node_relative_sec_3_4_1():
    """§3.4.1: 'COB-IDs vary according to communication address'."""
    od = _load(node_id=0x7F)
    assert od[0x1800][1].default == 0x1FF and od[0x1403][1].default == 0x57F
    assert od[0x1200][1].default == 0x67F


@pytest.mark.parametrize("n,ttype", [(0, 255), (1, 254), (2, 254), (3, 254)])
def test_tpdo_transmission_types_sec_3_5_1(od, n, ttype):
    """App. A and §3.5.1 defaults table: PDO1 Tx 255, PDO2-4 Tx 254."""
    v = od[0x1800 + n][2]
    assert v.default == ttype and v.data_type == dt.UNSIGNED8 and v.access_type == "rw"


@pytest.mark.parametrize("n", range(4))
def test_tpdo_disabled_time_500_ms_sec_3_5_1(od, n):
    """§3.5.1 table 'Disabled time (ms) 500'; App. A RW Unsigned16. Unit 1 ms, NOT 100 us."""
    v = od[0x1800 + n][3]
    assert v.default == 500 and v.data_type == dt.UNSIGNED16 and v.access_type == "rw"


def test_disabled_time_1000_ms_fits_sec_3_4_9(od):
    """§3.4.9 example writes 0x03E8 (= 1000 ms) to 0x1801:03 with 2-byte code 0x2B."""
    v = od[0x1801][3]
    assert len(v) == 16
    assert v.encode_raw(1000) == bytes([0xE8, 0x03])


@pytest.mark.parametrize("n", range(4))
def test_tpdo_event_timer_0_sec_3_5_1(od, n):
    """§3.5.1 defaults table: Event timer (ms) 0 for PDO1-4 Tx; App. A RW Unsigned16."""
    v = od[0x1800 + n][5]
    assert v.default == 0 and v.data_type == dt.UNSIGNED16 and v.access_type == "rw"


@pytest.mark.parametrize("n", range(4))
def test_tpdo_comm_sub0_ro_and_reserved_sub4_app_a(od, n):
    """App. A: sub0 'Supported Max. number of subindexes' RO U8; sub4 'Reserved' RW U8."""
    obj = od[0x1800 + n]
    assert obj[0].access_type == "ro" and obj[0].data_type == dt.UNSIGNED8
    assert obj[4].data_type == dt.UNSIGNED8 and obj[4].access_type == "rw"


def test_tpdo1_only_type_255_and_no_event_timer_sec_3_5_2(od):
    """§3.5.2 note / Table 3-11: PDO1 Tx supports only asynchronous 255, event timer must stay 0."""
    tt, et = od[0x1800][2], od[0x1800][5]
    assert (tt.min, tt.max) == (255, 255)
    assert (et.min, et.max) == (0, 0)


@pytest.mark.parametrize("n", [1, 2, 3])
def test_tpdo2_4_support_sync_1_to_240_sec_3_5_1(od, n):
    """§3.5.1 / Table 3-11: PDO2-4 Tx support SYNC 1-240, 254 and 255 (0 not listed)."""
    tt = od[0x1800 + n][2]
    assert tt.min == 1 and tt.max == 255


@pytest.mark.parametrize("n", range(4))
def test_rpdo_comm_event_timer_and_type_rw_app_a(od, n):
    """App. A: 14xxh sub1/2/5 RW; sub0 RO Unsigned8; sub3 Unsigned16, sub4 Unsigned8."""
    obj = od[0x1400 + n]
    assert obj[0].access_type == "ro"
    assert obj[2].access_type == "rw" and obj[2].data_type == dt.UNSIGNED8
    assert obj[3].data_type == dt.UNSIGNED16 and obj[4].data_type == dt.UNSIGNED8
    assert obj[5].access_type == "rw" and obj[5].data_type == dt.UNSIGNED16


# --------------------------------------------------------------------------- PDO mapping (App. A)

RPDO_MAP = {0x1600: [0x21000010, 0x21000110, 0x21000210],
            0x1601: [0x21010010, 0x21000310, 0x21000410, 0x21000510],
            0x1602: [0x21000610, 0x21000710, 0x21000810, 0x21000910],
            0x1603: [0x21000A10, 0x21000B10, 0x21000C10, 0x21000D10]}
TPDO_MAP = {0x1A00: [0x20000010, 0x20000110, 0x20000210],
            0x1A01: [0x20010010, 0x20000310, 0x20000410, 0x20000510],
            0x1A02: [0x20000610, 0x20000710, 0x20000810, 0x20000910],
            0x1A03: [0x20000A10, 0x20000B10, 0x20000C10, 0x20000D10]}


@pytest.mark.parametrize("idx,entries", sorted({**RPDO_MAP, **TPDO_MAP}.items()))
def test_default_mappings_app_a(od, idx, entries):
    """App. A: default mapping parameters 1600h-1603h, 1A00h-1A03h (all RW)."""
    obj = od[idx]
    assert obj[0].default == len(entries) and obj[0].access_type == "rw"
    for i, e in enumerate(entries, 1):
        assert obj[i].default == e and obj[i].access_type == "rw"
        assert obj[i].data_type == dt.UNSIGNED32


@pytest.mark.parametrize("idx,entries", sorted({**RPDO_MAP, **TPDO_MAP}.items()))
def test_mapped_objects_exist_are_16_bit_and_mappable_tables_3_19_3_20(od, idx, entries):
    """Tables 3-19/3-20: every mapped object is '2 bytes' (length byte 0x10) and PDO-mappable."""
    for e in entries:
        obj = od[e >> 16]
        var = obj if isinstance(obj, ODVariable) else obj[(e >> 8) & 0xFF]
        assert var.subindex == (e >> 8) & 0xFF
        assert len(var) == (e & 0xFF) == 16
        assert var.pdo_mappable


def test_rpdo1_frame_sec_3_5_2_example(pdo_node):
    """§3.5.2 example: RPDO1 0x203 '02 00 0D 0F 01 00' = request 2 (RAM write), address 0x0F0D (P15.13), data 1."""
    m = pdo_node.rpdo[1]
    assert m.cob_id == 0x203 and m.length == 48  # data domain must be six bytes (§3.5.2.1 note)
    m.on_message(m.cob_id, bytearray.fromhex("02000D0F0100"), 0)
    assert [v.raw for v in m.map] == [2, 0x0F0D, 1]
    assert [(v.index, v.subindex) for v in m.map] == [(0x2100, 0), (0x2100, 1), (0x2100, 2)]


def test_tpdo1_frame_sec_3_5_2_2_example(pdo_node):
    """§3.5.2.2 example: TPDO1 0x183 '01 00 00 00 01 00 00 00' = response 1, error 0, data 1, bytes 6-7 = 0."""
    m = pdo_node.tpdo[1]
    assert m.cob_id == 0x183 and m.trans_type == 255
    m.on_message(m.cob_id, bytearray.fromhex("0100000001000000"), 0)
    assert [v.raw for v in m.map] == [1, 0, 1]
    assert [(v.index, v.subindex) for v in m.map] == [(0x2000, 0), (0x2000, 1), (0x2000, 2)]


def test_rpdo2_frame_sec_3_5_3_example(pdo_node):
    """§3.5.3 example: RPDO2 0x303 '01 00 00 00 88 13 00 00' = CW 1 (forward run), setting 2 = 5000 (50.00 Hz)."""
    m = pdo_node.rpdo[2]
    assert m.cob_id == 0x303
    m.on_message(m.cob_id, bytearray.fromhex("0100000088130000"), 0)
    assert [(v.index, v.subindex, v.raw) for v in m.map] == [
        (0x2101, 0, 1), (0x2100, 3, 0), (0x2100, 4, 5000), (0x2100, 5, 0)]


def test_tpdo2_frame_sec_3_5_4_example(pdo_node):
    """§3.5.4 example: TPDO2 0x283 '01 01 88 13 7C 01 00 00' = SW 0x0101, 50.00 Hz, 380 V, 0."""
    m = pdo_node.tpdo[2]
    assert m.cob_id == 0x283 and m.trans_type == 254
    m.on_message(m.cob_id, bytearray.fromhex("010188137C010000"), 0)
    assert [(v.index, v.subindex, v.raw) for v in m.map] == [
        (0x2001, 0, 0x0101), (0x2000, 3, 5000), (0x2000, 4, 380), (0x2000, 5, 0)]


@pytest.mark.parametrize("n,first_sub", [(3, 0x06), (4, 0x0A)])
def test_pdo3_pdo4_layouts_sec_3_5_5_3_5_6(pdo_node, n, first_sub):
    """§3.5.5/§3.5.6: PDO3 Rx/Tx = settings/returned values 4-7 (sub 06-09), PDO4 = 8-11 (sub 0A-0D)."""
    r, t = pdo_node.rpdo[n], pdo_node.tpdo[n]
    assert [(v.index, v.subindex, v.offset) for v in r.map] == [
        (0x2100, first_sub + k, 16 * k) for k in range(4)]
    assert [(v.index, v.subindex, v.offset) for v in t.map] == [
        (0x2000, first_sub + k, 16 * k) for k in range(4)]


# --------------------------------------------------------------------------- manufacturer objects

def test_0x2000_has_16_u16_ro_entries_sub0_is_data_table_3_20(od):
    """Table 3-20: 2000h sub 0..F, all RO, 2 bytes; sub 0 is 'Response code', NOT a count."""
    obj = od[0x2000]
    assert isinstance(obj, ODRecord)  # RECORD: python-canopen never reads sub 0 as a length
    assert sorted(obj.subindices) == list(range(16))
    for s in range(16):
        assert obj[s].data_type == dt.UNSIGNED16 and obj[s].access_type == "ro"
    assert "response code" in obj[0].name.lower()
    assert "error code" in obj[1].name.lower()
    assert "response data" in obj[2].name.lower()


def test_0x2100_has_16_u16_rw_entries_sub0_is_data_table_3_19(od):
    """Table 3-19: 2100h sub 0..F, all RW, 2 bytes; sub 0 is 'Request code', NOT a count."""
    obj = od[0x2100]
    assert isinstance(obj, ODRecord)
    assert sorted(obj.subindices) == list(range(16))
    for s in range(16):
        assert obj[s].data_type == dt.UNSIGNED16 and obj[s].access_type == "rw"
    assert "request code" in obj[0].name.lower()
    assert "parameter address" in obj[1].name.lower()
    assert "requested data" in obj[2].name.lower()


@pytest.mark.parametrize("n", range(1, 12))
def test_settings_and_returned_values_sub_n_plus_2_tables_3_19_3_20(od, n):
    """Tables 3-19/3-20: Setting n = 2100h sub n+2 (received PZD n+1), Returned value n = 2000h sub n+2."""
    assert od[0x2100][n + 2].name == f"Setting {n}"
    assert od[0x2000][n + 2].name == f"Returned value {n}"


@pytest.mark.parametrize("idx,sub", [(0x2000, 0x0E), (0x2000, 0x0F), (0x2100, 0x0F)])
def test_reserved_entries_tables_3_19_3_20(od, idx, sub):
    """Tables 3-19/3-20: sub E/F are 'Reserved'."""
    assert od[idx][sub].name == "Reserved"


def test_cw_is_0x2101_rw_var_table_3_19(od):
    """Table 3-19: 2101h sub 0 'CW' RW 2 bytes; §3.6 example 1 writes CW=1 with '2B 01 21 00 01 00'."""
    v = od[0x2101]
    assert isinstance(v, ODVariable)
    assert v.subindex == 0 and v.access_type == "rw" and v.data_type == dt.UNSIGNED16
    assert v.pdo_mappable
    assert v.encode_raw(1) == bytes([0x01, 0x00])


def test_sw_is_0x2001_ro_var_table_3_20(od):
    """Table 3-20: 2001h sub 0 'SW' RO 2 bytes; §3.6 example 3 reads 0x0101 ('4B 01 20 00 01 01')."""
    v = od[0x2001]
    assert isinstance(v, ODVariable)
    assert v.subindex == 0 and v.access_type == "ro" and v.data_type == dt.UNSIGNED16
    assert v.pdo_mappable
    assert v.decode_raw(bytes([0x01, 0x01])) == 0x0101


def test_sw_default_is_stopped_and_ready_table_3_18(od):
    """Table 3-18: code 3 = stopped, bit 8 = bus voltage established (ready to run)."""
    sw = od[0x2001].default
    assert sw & 0xFF == 3 and sw & 0x100


def test_set_frequency_50hz_is_0x1388_sec_3_6_example_2(od):
    """§3.6 example 2 / §3.5.3: 50.00 Hz = 5000 = bytes '88 13' in 2100h sub 3 (unit 0.01 Hz)."""
    assert od[0x2100][3].encode_raw(5000) == bytes([0x88, 0x13])


def test_no_other_manufacturer_objects_below_0x4000_sec_3_6(od):
    """§3.6: the manufacturer-defined OD is 2000h, 2001h, 2100h, 2101h (Tables 3-19/3-20)."""
    got = {i for i in od.indices if isinstance(i, int) and 0x2000 <= i < 0x4000}
    assert got == {0x2000, 0x2001, 0x2100, 0x2101}


# --------------------------------------------------------------------------- drive function codes

APP_B_CODES = (
    [(0, 1), (0, 2), (0, 6), (0, 7), (3, 11), (3, 14), (3, 15), (3, 18), (3, 19), (4, 27),
     (6, 1), (6, 2), (6, 3), (6, 4), (6, 14), (6, 16), (7, 27), (9, 0), (9, 2), (10, 0), (10, 1)]
    + [(15, n) for n in range(1, 43)]
    + [(16, n) for n in list(range(1, 19)) + list(range(20, 30)) + list(range(31, 57))]
    + [(19, 0), (19, 1), (19, 2)])


def test_address_rule_examples_sec_3_5_2_1(od):
    """§3.5.2.1: P10.01 -> 0x0A01; §3.5.2 example: P15.13 -> 0x0F0D."""
    assert od[0x4000 + 0x0A01].name.startswith("P10.01")
    assert od[0x4000 + 0x0F0D].name.startswith("P15.13")


@pytest.mark.parametrize("g,n", APP_B_CODES)
def test_every_named_function_code_is_imaged_app_b(od, g, n):
    """App. B and Table 3-14: every named function code exists at 0x4000 + ((g << 8) | n), U16, not mappable."""
    v = od[P(g, n)]
    assert isinstance(v, ODVariable)
    assert v.name.startswith(f"P{g:02d}.{n:02d} ")
    assert v.data_type == dt.UNSIGNED16 and not v.pdo_mappable


def test_reserved_function_codes_not_imaged_app_b(od):
    """App. B: P15.43-P15.69, P16.19 and P16.30 are 'Reserved'."""
    for idx in [P(15, n) for n in range(43, 70)] + [P(16, 19), P(16, 30)]:
        assert idx not in od


@pytest.mark.parametrize("g,n,low,high,default", [
    (0, 1, 0, 2, 0), (0, 2, 0, 5, 0), (0, 6, 0, 15, 0), (0, 7, 0, 15, 2),
    (3, 11, 0, 12, 0), (3, 14, 0, 12, 0), (3, 15, 0, 12, 0), (3, 18, 0, 11, 0), (3, 19, 0, 11, 0),
    (4, 27, 0, 13, 0), (6, 1, 0, 63, 0), (6, 2, 0, 63, 0), (6, 3, 0, 63, 1), (6, 4, 0, 63, 5),
    (6, 14, 0, 47, 0), (6, 16, 0, 47, 0), (9, 0, 0, 12, 0), (9, 2, 0, 10, 0),
    (15, 1, 0, 127, 2), (15, 24, 0, 65535, 0), (15, 27, 0, 7, 0), (15, 28, 0, 127, 1),
    (15, 29, 0, 4, 1), (15, 33, 0, 1, 1), (15, 34, 19, 27, 19), (15, 35, 69, 77, 69),
    (15, 36, 0, 1, 0), (15, 37, 19, 27, 19), (15, 38, 69, 77, 69), (15, 39, 8, 32, 32),
    (15, 40, 8, 32, 32), (15, 41, 0, 1, 0), (15, 42, 0, 5, 0),
    (16, 1, 0, 4, 0), (16, 2, 0, 255, 192), (16, 3, 0, 255, 168), (16, 4, 0, 255, 0),
    (16, 5, 0, 255, 1), (16, 6, 0, 255, 255), (16, 7, 0, 255, 255), (16, 8, 0, 255, 255),
    (16, 9, 0, 255, 0), (16, 10, 0, 255, 192), (16, 11, 0, 255, 168), (16, 12, 0, 255, 1),
    (16, 13, 0, 255, 1), (16, 14, 0, 0xFFFF, 0), (16, 17, 0, 0xFFFF, 0), (16, 20, 0, 4194, 0),
    (16, 21, 0, 999, 1), (16, 22, 0, 1, 0), (16, 55, 0, 4, 0), (16, 56, 0, 1, 0),
    (19, 0, 0, 65535, 0), (19, 2, 0, 65535, 0),
])
def test_function_code_range_and_default_app_b(od, g, n, low, high, default):
    """App. B 'Setting range' and 'Default value' columns."""
    v = od[P(g, n)]
    assert (v.min, v.max, v.default) == (low, high, default)


@pytest.mark.parametrize("n", range(2, 24))
def test_pzd_selectors_0_to_31_default_0_table_3_22_3_23(od, n):
    """Tables 3-22/3-23 and App. B: P15.02-P15.23 range 0-31, default 0 (Invalid)."""
    v = od[P(15, n)]
    assert (v.min, v.max, v.default) == (0, 31, 0)


@pytest.mark.parametrize("n", range(32, 54))
def test_ethernet_pzd_selectors_0_to_31_app_b(od, n):
    """App. B: P16.32-P16.53 range 0-31, default 0."""
    v = od[P(16, n)]
    assert (v.min, v.max, v.default) == (0, 31, 0)


@pytest.mark.parametrize("g,n,default", [(15, 25, 0), (15, 26, 0), (15, 30, 0), (15, 31, 0),
                                         (16, 18, 5), (16, 23, 0), (16, 31, 0)])
def test_timeouts_0_to_300_0_s_in_0_1_s_app_b(od, g, n, default):
    """App. B: '0.0 (invalid)-300.0s' -> raw 0..3000 in 0.1 s; P16.18 default 0.5 s -> 5."""
    v = od[P(g, n)]
    assert (v.min, v.max, v.default) == (0, 3000, default)


@pytest.mark.parametrize("n", range(24, 30))
def test_card_identification_and_timeout_0_to_600_0_s_app_b(od, n):
    """App. B: P16.24-P16.29 0.0-600.0 s (0.1 s units), default 0.0."""
    v = od[P(16, n)]
    assert (v.min, v.max, v.default) == (0, 6000, 0)


def test_canopen_timeout_p15_26_disabled_by_default_app_b(od):
    """App. B: P15.26 CANopen communication timeout time 0.0 (invalid)-300.0 s, default 0.0 s."""
    v = od[P(15, 26)]
    assert "CANopen communication timeout" in v.name and v.default == 0


def test_canopen_baud_p15_27_table_3_21(od):
    """Table 3-21 / App. B: P15.27 0 = 1000k ... 7 = 20k, default 0 (1000 kbit/s)."""
    v = od[P(15, 27)]
    assert "CANopen communication baud rate" in v.name
    assert (v.min, v.max, v.default) == (0, 7, 0)


def test_node_address_p15_01_default_2_sec_3_7_2(od):
    """§3.7.2: CANopen address is set by P15.01; App. B: 0-127, default 2."""
    v = od[P(15, 1)]
    assert "Module address" in v.name and (v.min, v.max, v.default) == (0, 127, 2)


def test_simple_plc_table_3_14(od):
    """Table 3-14: P10.00 options 0-2 default 0; P10.01 options 0-1 default 0."""
    a, b = od[P(10, 0)], od[P(10, 1)]
    assert (a.min, a.max, a.default) == (0, 2, 0)
    assert (b.min, b.max, b.default) == (0, 1, 0)


@pytest.mark.parametrize("n", range(27, 33))
def test_fault_type_records_read_only_app_b(od, n):
    """App. B: P07.27 type of current fault (0 = no fault) and last..5th-last fault types are records."""
    v = od[P(7, n)]
    assert v.access_type == "ro" and v.default == 0


def test_card_slot_states_read_only_app_b(od):
    """App. B: P19.00-P19.02 state of card slot 1-3 (9 = CANopen communication card)."""
    for n in range(3):
        assert od[P(19, n)].access_type == "ro"


def test_motor_switching_channel_range_app_b(od):
    """App. B: Motor 1 and motor 2 switching channel 0x00-0x14, default 0x00 (code illegible, see NOTES)."""
    v = od[P(8, 31)]
    assert "switching channel" in v.name
    assert (v.min, v.max, v.default) == (0x00, 0x14, 0x00)


# --------------------------------------------------------------------------- faults (§3.4.8, App. B P07.27)

MANUAL_FAULTS = {1: "OUT1", 29: "E-DP", 30: "E-NET", 31: "E-CAN", 57: "E-PN", 58: "ESCAN",
                 60: "F1-Er", 61: "F2-Er", 62: "F3-Er", 63: "C1-Er", 64: "C2-Er", 65: "C3-Er",
                 66: "E-CAT", 67: "E-BAC", 68: "E-DEV", 69: "S-Err", 70: "E-EIP"}
# Table 3-6 emergency error code groups (high byte, or full code for the 81xx/82xx rows)
TABLE_3_6_GROUPS = {0x00, 0x10, 0x20, 0x21, 0x22, 0x23, 0x30, 0x31, 0x32, 0x33, 0x40, 0x41, 0x42,
                    0x50, 0x60, 0x61, 0x62, 0x63, 0x70, 0x80, 0x81, 0x82, 0x90, 0xF0, 0xFF}


@pytest.fixture(scope="module")
def faults():
    with open(FAULTS, newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


def test_faults_header(faults):
    with open(FAULTS, encoding="utf-8") as f:
        assert f.readline().strip() == \
            "trip_code,trip_name,emcy_code,error_register_bit,description,section"


def test_fault_list_is_p07_27_list_app_b(faults):
    """App. B P07.27 (+ fault 1 OUT1 from §3.4.8): exactly these trips, with these short names."""
    got = {int(r["trip_code"], 0): r["trip_name"] for r in faults}
    assert got == MANUAL_FAULTS


def test_out1_emcy_0x3000_register_bit_2_sec_3_4_8(faults):
    """§3.4.8 example: fault 1 OUT1 -> EMCY code 0x3000, error register 0x04 (bit 2, voltage)."""
    row = next(r for r in faults if int(r["trip_code"], 0) == 1)
    assert int(row["emcy_code"], 0) == 0x3000
    assert int(row["error_register_bit"]) == 2


def test_out1_emcy_frame_bytes_sec_3_4_8(faults):
    """§3.4.8: node 3, fault 1 -> 0x83: 00 30 04 01 00 00 00 00 (code LSB first, register, 5-byte VFD code)."""
    row = next(r for r in faults if int(r["trip_code"], 0) == 1)
    code, bit, trip = int(row["emcy_code"], 0), int(row["error_register_bit"]), int(row["trip_code"], 0)
    frame = code.to_bytes(2, "little") + bytes([1 << bit]) + trip.to_bytes(5, "little")
    assert 0x80 + NODE == 0x83
    assert frame == bytes.fromhex("0030040100000000")


@pytest.mark.parametrize("trip", sorted(MANUAL_FAULTS))
def test_every_fault_emcy_code_in_table_3_6(faults, trip):
    """Table 3-6: every EMCY code belongs to a listed group; Table 3-7: register bit 0-7, bit 6 reserved."""
    row = next(r for r in faults if int(r["trip_code"], 0) == trip)
    code = int(row["emcy_code"], 0)
    assert code >> 8 in TABLE_3_6_GROUPS and code != 0
    bit = int(row["error_register_bit"])
    assert 0 <= bit <= 7 and bit != 6
    assert row["section"].strip()


@pytest.mark.parametrize("trip", [29, 30, 31, 57, 58, 66, 67, 68, 69, 70])
def test_communication_faults_report_81xx_and_bit_4_table_3_6_3_7(faults, trip):
    """Table 3-6 row 81xx 'Communication error' and Table 3-7 bit 4 'Communication error'."""
    row = next(r for r in faults if int(r["trip_code"], 0) == trip)
    assert int(row["emcy_code"], 0) >> 8 == 0x81
    assert int(row["error_register_bit"]) == 4


def test_ecan_is_canopen_communication_fault_31_app_b(faults):
    """App. B P07.27: 31 = CANopen communication fault (E-CAN)."""
    row = next(r for r in faults if r["trip_name"] == "E-CAN")
    assert int(row["trip_code"], 0) == 31
