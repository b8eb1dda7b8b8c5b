"""Toshiba TOSVERT VF-S15 CANopen: EDS, fault table and notes checked against the manual.

Manual: Toshiba "TOSVERT VF-S15 series CANopen Communication Function Manual" ("VF-S15 CANopen Communication Function Manual").
Every expected value below is typed in from the manual (section in the test name or docstring),
never read back from the EDS. Choices where the manual is ambiguous are in od/vf-s15/NOTES.md.
"""
import configparser
import csv
import logging
import re
import struct
import warnings
from pathlib import Path

import pytest

import canopen
from canopen.objectdictionary import ODArray, ODRecord, ODVariable, datatypes

ROOT = Path(__file__).resolve().parents[2]
DRIVE = ROOT / "od" / "vf-s15"
EDS = DRIVE / "vf-s15.eds"
FAULTS = DRIVE / "faults.csv"
NOTES = DRIVE / "NOTES.md"
NODE = 5

U8, U16, U32 = datatypes.UNSIGNED8, datatypes.UNSIGNED16, datatypes.UNSIGNED32
I8, I16 = datatypes.INTEGER8, datatypes.INTEGER16
STR = datatypes.VISIBLE_STRING


def _load(node_id=NODE):
    return canopen.objectdictionary.import_od(str(EDS), node_id=node_id)


@pytest.fixture(scope="module")
def od():
    return _load()


@pytest.fixture(scope="module")
def raw():
    cp = configparser.RawConfigParser(inline_comment_prefixes=(";",))
    cp.optionxform = str
    cp.read(EDS, encoding="utf-8")
    return cp


def entry(od, index, sub=None):
    obj = od[index]
    if sub is None:
        assert isinstance(obj, ODVariable), f"0x{index:04X} should be a VAR"
        return obj
    assert isinstance(obj, (ODArray, ODRecord)), f"0x{index:04X} should be ARRAY/RECORD"
    assert sub in obj.subindices, f"0x{index:04X}:{sub:02X} missing"
    return obj[sub]


def check(var, dtype, access, default, pdo=False, low=None, high=None):
    assert var.data_type == dtype, f"{var.name}: data type"
    assert var.access_type == access, f"{var.name}: access"
    assert var.default == default, f"{var.name}: default {var.default!r} != {default!r}"
    assert var.pdo_mappable == pdo, f"{var.name}: PDO mapping"
    if low is not None or high is not None:
        assert (var.min, var.max) == (low, high), f"{var.name}: range"


# ------------------------------------------------------------------ loading, file structure
def test_eds_loads_without_warning(caplog):
    """CiA 306 file loads in python-canopen with no Python warning and nothing logged >= WARNING."""
    with caplog.at_level(logging.WARNING):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            od = _load()
    assert not [r for r in caplog.records if r.levelno >= logging.WARNING], caplog.text
    assert len(od) > 100


def test_object_lists_match_sections(raw):
    """CiA 306: [Mandatory/Optional/ManufacturerObjects] list every object section exactly once."""
    listed = []
    for sect in ("MandatoryObjects", "OptionalObjects", "ManufacturerObjects"):
        n = int(raw.get(sect, "SupportedObjects"))
        items = [int(raw.get(sect, str(i)), 16) for i in range(1, n + 1)]
        assert not raw.has_option(sect, str(n + 1))
        listed += items
        if sect == "MandatoryObjects":
            assert items == [0x1000, 0x1001, 0x1018]
        if sect == "ManufacturerObjects":
            assert all(0x2000 <= i <= 0x5FFF for i in items)
    sections = [int(s, 16) for s in raw.sections() if re.fullmatch(r"[0-9A-F]{4}", s)]
    assert sorted(listed) == sorted(sections)
    assert len(set(listed)) == len(listed)


def test_every_object_section_has_source_comment():
    """Convention: a '; source:' comment (manual + section) directly above every [XXXX] section."""
    lines = EDS.read_text(encoding="utf-8").splitlines()
    for i, line in enumerate(lines):
        if re.fullmatch(r"\[[0-9A-F]{4}\]", line):
            j = i - 1
            block = []
            while j >= 0 and lines[j].startswith(";"):
                block.append(lines[j])
                j -= 1
            assert any(b.startswith("; source:") and "§" in b for b in block), line


def test_array_record_sub0_and_subnumber(raw):
    """Convention: ARRAY/RECORD have SubNumber and a UNSIGNED8 sub 0 equal to the highest sub-index
    (PDO mapping records excepted: their sub 0 is the number of mapped objects, §4.1.4/§4.1.5)."""
    for s in raw.sections():
        if re.fullmatch(r"[0-9A-F]{4}", s) and int(raw.get(s, "ObjectType"), 0) in (8, 9):
            subs = [k for k in raw.sections() if k.startswith(s + "sub")]
            assert int(raw.get(s, "SubNumber")) == len(subs), s
            assert int(raw.get(s + "sub0", "DataType"), 0) == 0x0005, s
            highest = max(int(k[len(s) + 3:], 16) for k in subs)
            if 0x1600 <= int(s, 16) <= 0x17FF or 0x1A00 <= int(s, 16) <= 0x1BFF:
                assert highest == 4, s
                continue
            assert int(raw.get(s + "sub0", "DefaultValue"), 0) == highest, s


# ------------------------------------------------------------------ DeviceInfo (§4.1.1, §3.2, §8.2)
def test_deviceinfo_identity_and_pdo_count(raw):
    """§4.1.1 vendor 0x284 'Toshiba Schneider Inverter Co.', name VF-S15; §4.1.3/§8.2: PDO1,2,3,21."""
    assert int(raw.get("DeviceInfo", "VendorNumber"), 0) == 0x284
    assert raw.get("DeviceInfo", "VendorName") == "Toshiba Schneider Inverter Co."
    assert raw.get("DeviceInfo", "ProductName") == "VF-S15"
    assert raw.get("DeviceInfo", "NrOfRXPDO") == "4"
    assert raw.get("DeviceInfo", "NrOfTXPDO") == "4"
    assert raw.get("DeviceInfo", "SimpleBootUpSlave") == "1"
    assert raw.get("DeviceInfo", "LSS_Supported") == "0"
    assert int(raw.get("DeviceInfo", "Granularity")) > 0, "§8.2: objects are variable mapping"


def test_deviceinfo_baud_rates(od):
    """§3.2 C702 / §8.2: 20k, 50k, 125k, 250k, 500k, 800k, 1M (10k only in the §2.7 cable table)."""
    assert od.device_information.allowed_baudrates == {
        20000, 50000, 125000, 250000, 500000, 800000, 1000000}


# ------------------------------------------------------------------ §4.1.1 communication profile
def test_1000_device_type(od):
    """§4.1.1: 0x1000 RO u32 0x00010192 (type 1, profile 402)."""
    check(entry(od, 0x1000), U32, "ro", 0x00010192)


def test_1001_error_register(od):
    """§4.1.1: 0x1001 RO u8 0x00."""
    check(entry(od, 0x1001), U8, "ro", 0)


def test_1003_depth_one(od):
    """§4.1.1: 0x1003 sub 00 RO u8 0x01 ('Only one possible error'), sub 01 RO u32 0; no sub 02."""
    assert set(od[0x1003].subindices) == {0, 1}
    check(entry(od, 0x1003, 0), U8, "ro", 1)
    check(entry(od, 0x1003, 1), U32, "ro", 0)


def test_1005_sync_cob_id(od):
    """§4.1.1: 0x1005 R/W u32 0x00000080."""
    check(entry(od, 0x1005), U32, "rw", 0x80)


def test_1008_100a_strings(od):
    """§4.1.1: 0x1008 RO string 'VF-S15'; 0x100A RO string '1.00'."""
    check(entry(od, 0x1008), STR, "ro", "VF-S15")
    check(entry(od, 0x100A), STR, "ro", "1.00")


def test_100c_100d_1017_error_control(od):
    """§4.1.1: guard time u16 0 (1 ms), life time factor u8 0 (0-255, §3.2 C705), producer HB u16 0."""
    check(entry(od, 0x100C), U16, "rw", 0)
    check(entry(od, 0x100D), U8, "rw", 0, low=0, high=255)
    check(entry(od, 0x1017), U16, "rw", 0)


def test_1010_1011_store_restore(od):
    """§4.1.1: 0x1010 sub00 RO 1, sub01 R/W 0x00000003; 0x1011 sub00 RO 1, sub01 R/W 0x00000001."""
    assert set(od[0x1010].subindices) == {0, 1}
    assert set(od[0x1011].subindices) == {0, 1}
    check(entry(od, 0x1010, 0), U8, "ro", 1)
    check(entry(od, 0x1010, 1), U32, "rw", 0x00000003)
    check(entry(od, 0x1011, 0), U8, "ro", 1)
    check(entry(od, 0x1011, 1), U32, "rw", 0x00000001)


def test_1014_emcy_cob_id_read_only(od):
    """§4.1.1: 0x1014 RO u32 0x80 + Node-ID."""
    var = entry(od, 0x1014)
    check(var, U32, "ro", 0x80 + NODE)
    assert var.relative


def test_1016_one_consumer(od):
    """§4.1.1: 0x1016 sub 00 RO 0x01 (single producer), sub 01 R/W u32 0; no sub 02."""
    assert set(od[0x1016].subindices) == {0, 1}
    check(entry(od, 0x1016, 0), U8, "ro", 1)
    check(entry(od, 0x1016, 1), U32, "rw", 0)


def test_1018_identity_vendor_only(od):
    """§4.1.1: 0x1018 sub 00 RO 0x01, sub 01 RO 0x00000284; no product code/revision/serial."""
    assert set(od[0x1018].subindices) == {0, 1}
    check(entry(od, 0x1018, 0), U8, "ro", 1)
    check(entry(od, 0x1018, 1), U32, "ro", 0x00000284)


def test_absent_standard_objects(od):
    """§4.1.1/§4.3 do not list these; they are not added (NOTES 'Added objects': none)."""
    for idx in (0x1002, 0x1006, 0x1007, 0x1009, 0x1012, 0x1013, 0x1015, 0x1029, 0x1F80, 0x1201,
                0x6007, 0x605B, 0x605C, 0x605D, 0x605E, 0x6402, 0x604B, 0x604C):
        assert idx not in od, f"0x{idx:04X}"


def test_comm_profile_not_pdo_mappable(od):
    """§4.1.1: 'These communication profile object can not be mapped into PDO.'"""
    for obj in od.values():
        if 0x1000 <= obj.index <= 0x1FFF:
            vars_ = [obj] if isinstance(obj, ODVariable) else list(obj.values())
            assert not any(v.pdo_mappable for v in vars_), hex(obj.index)


# ------------------------------------------------------------------ §4.1.2 SDO server
def test_1200_sdo_server(od):
    """§4.1.2: 0x1200 RO: sub00 0x02, sub01 0x600 + ID, sub02 0x580 + ID."""
    assert set(od[0x1200].subindices) == {0, 1, 2}
    check(entry(od, 0x1200, 0), U8, "ro", 2)
    check(entry(od, 0x1200, 1), U32, "ro", 0x600 + NODE)
    check(entry(od, 0x1200, 2), U32, "ro", 0x580 + NODE)


# ------------------------------------------------------------------ §4.1.3-§4.1.5 PDOs
RPDO = {1: (0x1400, 0x00000200), 2: (0x1401, 0x80000300), 3: (0x1402, 0x80000400), 21: (0x1414, 0x80000500)}
TPDO = {1: (0x1800, 0x00000180), 2: (0x1801, 0x80000280), 3: (0x1802, 0x80000380), 21: (0x1814, 0x80000480)}


def test_pdo_numbers_are_1_2_3_21(od):
    """§4.1.3: 'PDO1 to PDO3 and PDO21' - no other PDO communication/mapping objects."""
    for base in (0x1400, 0x1600, 0x1800, 0x1A00):
        present = {i - base for i in range(base, base + 0x200) if i in od}
        assert present == {0x00, 0x01, 0x02, 0x14}, hex(base)


@pytest.mark.parametrize("n", [1, 2, 3, 21])
def test_rpdo_communication(od, n):
    """§4.1.4: RPDOn sub00 R 0x02, sub01 R/W COB-ID, sub02 0xFF (R for RPDO1, R/W otherwise)."""
    idx, cob = RPDO[n]
    assert set(od[idx].subindices) == {0, 1, 2}
    check(entry(od, idx, 0), U8, "ro", 2)
    check(entry(od, idx, 1), U32, "rw", cob + NODE)
    check(entry(od, idx, 2), U8, "ro" if n == 1 else "rw", 0xFF)


@pytest.mark.parametrize("n", [1, 2, 3, 21])
def test_tpdo_communication(od, n):
    """§4.1.5: TPDOn sub00 R 0x05, COB-ID, type 0xFF, inhibit 0x001E (100 us), reserved 0, event 0x0064."""
    idx, cob = TPDO[n]
    assert set(od[idx].subindices) == {0, 1, 2, 3, 4, 5}
    check(entry(od, idx, 0), U8, "ro", 5)
    check(entry(od, idx, 1), U32, "rw", cob + NODE)
    check(entry(od, idx, 2), U8, "rw", 0xFF)
    check(entry(od, idx, 3), U16, "rw", 0x001E)
    check(entry(od, idx, 4), U8, "rw", 0x00)
    check(entry(od, idx, 5), U16, "rw", 0x0064)


def test_pdo_cob_ids_are_node_relative(raw):
    """§4.1.4/§4.1.5: every PDO COB-ID default is '<base> + Node-ID'."""
    for idx in list(RPDO.values()) + list(TPDO.values()):
        assert raw.get(f"{idx[0]:04X}sub1", "DefaultValue").startswith("$NODEID+")


RMAP = {1: [0x60400010, 0x60420010], 2: [0x60400010], 3: [0x60400010], 21: [0x60400010]}
TMAP = {1: [0x60410010, 0x60440010], 2: [0x60410010], 3: [0x60410010], 21: [0x60410010]}


@pytest.mark.parametrize("n", [1, 2, 3, 21])
def test_pdo_mapping_defaults(od, n):
    """§4.1.4/§4.1.5: 16xx/1Axx sub00 R/W count, subs 01-04 R/W u32; RPDO1 6040+6042, TPDO1 6041+6044,
    the others 6040 / 6041 only."""
    off = {1: 0, 2: 1, 3: 2, 21: 0x14}[n]
    for base, maps in ((0x1600, RMAP), (0x1A00, TMAP)):
        idx = base + off
        assert set(od[idx].subindices) == {0, 1, 2, 3, 4}
        m = maps[n]
        check(entry(od, idx, 0), U8, "rw", len(m), low=0, high=4)
        for s in range(1, 5):
            check(entry(od, idx, s), U32, "rw", m[s - 1] if s <= len(m) else 0)


def test_python_canopen_sees_pdo_maps_1_2_3_21(od):
    """§4.1.3: python-canopen numbers the maps from the index offset, giving 1, 2, 3 and 21."""
    node = canopen.RemoteNode(1, _load(1))
    assert set(node.rpdo.map) == {1, 2, 3, 21}
    assert set(node.tpdo.map) == {1, 2, 3, 21}


def _pdo_nodes():
    net = canopen.Network()
    node = canopen.RemoteNode(1, _load(1))
    net.add_node(node)
    node.rpdo.read(from_od=True)
    node.tpdo.read(from_od=True)
    return node


def test_section7_frames_match_default_rpdo1_tpdo1_mapping():
    """§7.1/§7.2 with node 1: RxPDO1 0x201 = controlword + vl_target_velocity
    (06 00 00 00 / 07 00 00 00 / 0F 00 DC 05), TxPDO1 0x181 = statusword + vl_velocity_actual_value
    (37 06 DC 05). The default mappings must lay the bytes out exactly like that."""
    node = _pdo_nodes()
    rp, tp = node.rpdo[1], node.tpdo[1]
    assert rp.enabled and tp.enabled
    assert rp.cob_id == 0x201 and tp.cob_id == 0x181
    assert [(v.index, v.subindex, v.length) for v in rp.map] == [(0x6040, 0, 16), (0x6042, 0, 16)]
    assert [(v.index, v.subindex, v.length) for v in tp.map] == [(0x6041, 0, 16), (0x6044, 0, 16)]
    for cw, target, frame in ((0x0006, 0, "06 00 00 00"), (0x0007, 0, "07 00 00 00"),
                              (0x000F, 1500, "0f 00 dc 05")):
        rp[0x6040].raw = cw
        rp[0x6042].raw = target
        assert bytes(rp.data[:rp.length // 8]) == bytes.fromhex(frame)
    # TxPDO1 of step 8 decodes to statusword 0x0637 (operation enabled + remote + target reached), 1500 rpm
    tp.on_message(0x181, bytes.fromhex("37 06 dc 05"), 0.0)
    assert tp[0x6041].raw == 0x0637
    assert tp[0x6044].raw == 1500
    assert (tp[0x6041].raw & 0x006F) == 0x0027, "§5.1.3: x01x 0111 = Operation enabled"
    # 6042 is signed: a reverse target 0xFA24 is -1500 (§5.1.4 'negative values indicates reverse')
    rp[0x6042].raw = -1500
    assert bytes(rp.data[2:4]) == struct.pack("<h", -1500)


def test_other_pdos_disabled_by_default():
    """§4.1.4/§4.1.5: PDO2/3/21 COB-IDs carry bit 31 (0x8000xxxx) - disabled; PDO1 enabled."""
    node = _pdo_nodes()
    for n in (2, 3, 21):
        assert not node.rpdo[n].enabled and not node.tpdo[n].enabled
    assert node.rpdo[2].cob_id == 0x301 and node.tpdo[21].cob_id == 0x481


# ------------------------------------------------------------------ §4.3/§5 device profile
def test_603f_to_6044(od):
    """§4.3: 603F R u16, 6040 R/W u16, 6041 R u16, 6042 R/W i16, 6043/6044 R i16; all PDO 'Yes', default 0."""
    check(entry(od, 0x603F), U16, "ro", 0, pdo=True)
    check(entry(od, 0x6040), U16, "rw", 0, pdo=True)
    check(entry(od, 0x6041), U16, "ro", 0, pdo=True)
    check(entry(od, 0x6042), I16, "rw", 0, pdo=True)
    check(entry(od, 0x6043), I16, "ro", 0, pdo=True)
    check(entry(od, 0x6044), I16, "ro", 0, pdo=True)


def test_6042_not_range_limited(od):
    """§5.1: a target outside 6046 is clamped by the drive, not refused - so no LowLimit/HighLimit."""
    var = entry(od, 0x6042)
    assert var.min is None and var.max is None


def test_6046_min_max_amount(od):
    """§4.3: 6046 sub00 R 0x02, sub01 R/W u32 0, sub02 R/W u32 0x000005DC (1500 min-1), PDO No."""
    assert set(od[0x6046].subindices) == {0, 1, 2}
    check(entry(od, 0x6046, 0), U8, "ro", 2)
    check(entry(od, 0x6046, 1), U32, "rw", 0)
    check(entry(od, 0x6046, 2), U32, "rw", 1500)


@pytest.mark.parametrize("idx", [0x6048, 0x6049])
def test_6048_6049_ramps_and_ranges(od, idx):
    """§4.3 defaults 0x05DC / 0x000A; §5.1.8/§5.1.9 ranges 225-30000 min-1 and 0-3600 s."""
    assert set(od[idx].subindices) == {0, 1, 2}
    check(entry(od, idx, 0), U8, "ro", 2)
    check(entry(od, idx, 1), U32, "rw", 1500, low=225, high=30000)
    check(entry(od, idx, 2), U16, "rw", 10, low=0, high=3600)


def test_604a_quick_stop_ramp(od):
    """§4.3: 604A sub01 R/W u32 printed 0x0000 0D5C, sub02 R/W u16 0x0006 (NOTES choice 6)."""
    assert set(od[0x604A].subindices) == {0, 1, 2}
    check(entry(od, 0x604A, 0), U8, "ro", 2)
    check(entry(od, 0x604A, 1), U32, "rw", 0x00000D5C)
    check(entry(od, 0x604A, 2), U16, "rw", 6)


def test_605a_quick_stop_option_code(od):
    """§4.3: 605A R/W i16 default 0x02, PDO No; §5.1.11 defines -32768..32767."""
    check(entry(od, 0x605A), I16, "rw", 2, low=-32768, high=32767)


def test_6060_6061_6502_velocity_mode_only(od):
    """§5.1.12-§5.1.14: only velocity mode: 6061 displays 2, 6502 = 0x00000002."""
    check(entry(od, 0x6060), I8, "rw", 2, low=-128, high=127)
    check(entry(od, 0x6061), I8, "ro", 2)
    check(entry(od, 0x6502), U32, "ro", 0x00000002)


def test_device_profile_mappability(od):
    """§4.3: PDO mapping 'Yes' only for 603F, 6040-6044."""
    mappable = set()
    for obj in od.values():
        if obj.index >= 0x6000:
            vars_ = [obj] if isinstance(obj, ODVariable) else list(obj.values())
            if any(v.pdo_mappable for v in vars_):
                mappable.add(obj.index)
    assert mappable == {0x603F, 0x6040, 0x6041, 0x6042, 0x6043, 0x6044}


def test_units_in_comments():
    """Units of §4.3/§5.1.4-§5.1.10 (min-1, s) and §4.1.1/§4.1.5 (1 ms, 100 us) are written above the objects."""
    text = EDS.read_text(encoding="utf-8")
    for sect, unit in (("6042", "min-1"), ("6044", "min-1"), ("6048", "1 s"), ("100C", "1 ms"),
                       ("1017", "1 ms"), ("4100", "0.1 s"), ("4717", "100 us")):
        head = text.split(f"\n[{sect}]\n")[0].rsplit("\n\n", 1)[-1]
        assert "unit:" in head and unit in head, sect


# ------------------------------------------------------------------ §4.2 manufacturer area
def index_of(param):
    """§4.2 addressing rule applied to a Toshiba communication number (see NOTES 'Addressing rule')."""
    base = {"0": 0x2000, "F": 0x2000, "A": 0x3000, "C": 0x4000}[param[0]]
    return base + int(param[1:], 16)


def test_addressing_rule_examples():
    """§4.2 table: F000-F999 -> 2000-2999, FA00-FFFF -> 2A00-2FFF, A -> 3xxx, C -> 4xxx."""
    assert index_of("0000") == 0x2000 and index_of("0999") == 0x2999
    assert index_of("FA00") == 0x2A00 and index_of("FFFF") == 0x2FFF
    assert index_of("A000") == 0x3000 and index_of("CFFF") == 0x4FFF
    assert index_of("0856") == 0x2856 and index_of("C750") == 0x4750


NAMED = (["0003", "0004", "0519", "0856", "0898", "0899", "FA00", "FA04", "FA06", "FE08",
          "C100", "C101", "C102", "C103"] + [f"C70{i}" for i in range(1, 9)]
         + [f"C7{d}{k}" for d in range(1, 5) for k in (1, 2, 3, 4, 5, 6, 7, 9)]
         + [f"C{n}" for n in range(750, 790)])


def test_every_named_parameter_present(od):
    """§3.1, §3.2, §4.1.1 (FE08), §5.1.8 (F519): every parameter the manual names and numbers is an object."""
    assert len(NAMED) == 94
    for p in NAMED:
        idx = index_of(p)
        assert idx in od, p
        var = entry(od, idx)
        assert var.data_type == U16, p
        assert var.pdo_mappable == (0x2A00 <= idx <= 0x2FFF), p
    manu = {o.index for o in od.values() if 0x2000 <= o.index <= 0x5FFF}
    assert manu == {index_of(p) for p in NAMED}


def test_manufacturer_names_carry_parameter_number(od):
    """§3.2 / §4.2: the object name starts with the Toshiba parameter name (C701, F856, ...)."""
    assert od[0x2003].name.startswith("CMOd")
    assert od[0x2004].name.startswith("FMOd")
    for p in NAMED[2:]:
        name = ("F" + p[1:]) if p[0] == "0" else p
        assert od[index_of(p)].name.startswith(name), p


def test_cmod_fmod(od):
    """§3.1: CMOd default 1 (3 = CANopen), FMOd default 0 (6 = CANopen); ranges from sibling §3.1."""
    check(entry(od, 0x2003), U16, "rw", 1, low=0, high=4)
    check(entry(od, 0x2004), U16, "rw", 0, low=0, high=11)


def test_f856_f898_f899(od):
    """§3.2: F856 default 2 (4 poles), F898 default 0 (0..2), F899 default 0 (0..1)."""
    check(entry(od, 0x2856), U16, "rw", 2, low=1, high=8)
    check(entry(od, 0x2898), U16, "rw", 0, low=0, high=2)
    check(entry(od, 0x2899), U16, "rw", 0, low=0, high=1)


def test_fa_command_and_fe08_monitor(od):
    """§4.2: FA00-FFFF are SDO and PDO; FE08 (0x100A source, §4.1.1) is a monitor (read-only)."""
    for idx in (0x2A00, 0x2A04, 0x2A06):
        check(entry(od, idx), U16, "rw", 0, pdo=True)
    check(entry(od, 0x2E08), U16, "ro", 0x0100, pdo=True)


def test_c100_to_c103_communication_loss(od):
    """§3.2: C100 0.0-100.0 s (0.1 s units -> 0..1000) default 0.0; C101 0..5 default 4;
    C102 0..15 default 0; C103 0..2 default 1."""
    check(entry(od, 0x4100), U16, "rw", 0, low=0, high=1000)
    check(entry(od, 0x4101), U16, "rw", 4, low=0, high=5)
    check(entry(od, 0x4102), U16, "rw", 0, low=0, high=15)
    check(entry(od, 0x4103), U16, "rw", 1, low=0, high=2)


def test_c701_to_c708(od):
    """§3.2 (printed C101..C108): Node ID 0 (0..127), baud 2 (0..6 = 20k..1M), SYNC 0x0080,
    guard 0, life factor 0 (0..255), HB producer node 0, consumer time 0, producer time 0."""
    check(entry(od, 0x4701), U16, "rw", 0, low=0, high=127)
    check(entry(od, 0x4702), U16, "rw", 2, low=0, high=6)
    check(entry(od, 0x4703), U16, "rw", 0x0080)
    check(entry(od, 0x4704), U16, "rw", 0)
    check(entry(od, 0x4705), U16, "rw", 0, low=0, high=255)
    for idx in (0x4706, 0x4707, 0x4708):
        check(entry(od, idx), U16, "rw", 0)


@pytest.mark.parametrize("d,hi,rlo,tlo", [(1, 0x0000, 0x0200, 0x0180), (2, 0x8000, 0x0300, 0x0280),
                                          (3, 0x8000, 0x0400, 0x0380), (4, 0x8000, 0x0500, 0x0480)])
def test_c7x1_to_c7x9_pdo_communication_words(od, d, hi, rlo, tlo):
    """§3.2: C7d1/C7d2 RPDO COB-ID high/low word, C7d3 type 0x0FF, C7d4/C7d5 TPDO COB-ID,
    C7d6 type 0x0FF, C7d7 inhibit (100 us), C7d9 event timer (1 ms); d = 1,2,3,4 for PDO1,2,3,21.
    Inhibit/event defaults follow §4.1.5 (0x001E / 0x0064), NOTES choice 1."""
    b = 0x4700 + d * 0x10
    check(entry(od, b + 1), U16, "rw", hi)
    check(entry(od, b + 2), U16, "rw", rlo)
    check(entry(od, b + 3), U16, "rw", 0xFF, low=0, high=0xFF)
    check(entry(od, b + 4), U16, "rw", hi)
    check(entry(od, b + 5), U16, "rw", tlo)
    check(entry(od, b + 6), U16, "rw", 0xFF, low=0, high=0xFF)
    check(entry(od, b + 7), U16, "rw", 0x001E)
    check(entry(od, b + 9), U16, "rw", 0x0064)
    assert b + 8 not in od, "§3.2: C7d8 is a '---' reserved row"


def test_c750_to_c789_pdo_mapping_words(od):
    """§3.2: C750 2 / C751 0x6040 / C752 0x6042; C755 2 / C756 0x6041 / C757 0x6044;
    C760/C770/C780 1 + 0x6040; C765/C775/C785 1 + 0x6041; all other entries 0."""
    exp = {750: 2, 751: 0x6040, 752: 0x6042, 755: 2, 756: 0x6041, 757: 0x6044}
    for t in (760, 770, 780):
        exp.update({t: 1, t + 1: 0x6040, t + 5: 1, t + 6: 0x6041})
    for n in range(750, 790):
        var = entry(od, index_of(f"C{n}"))
        check(var, U16, "rw", exp.get(n, 0))
        if n % 5 == 0:
            assert (var.min, var.max) == (0, 4), n


def test_c_params_mirror_pdo_objects(od):
    """§3.2 '#1400 subidx 01' etc.: C7xx factory values equal the 0x14xx/0x18xx/0x16xx/0x1Axx defaults
    (COB-ID without the Node-ID)."""
    offs = {1: 0, 2: 1, 3: 2, 4: 0x14}
    for d, off in offs.items():
        b = 0x4700 + d * 0x10
        r = (od[b + 1].default << 16 | od[b + 2].default) + NODE
        t = (od[b + 4].default << 16 | od[b + 5].default) + NODE
        assert r == od[0x1400 + off][1].default
        assert t == od[0x1800 + off][1].default
        assert od[b + 7].default == od[0x1800 + off][3].default
        assert od[b + 9].default == od[0x1800 + off][5].default
        for kind, mb, dig in (("R", 0x1600, 0), ("T", 0x1A00, 5)):
            c = 0x4750 + (d - 1) * 0x10 + dig
            assert od[c].default == od[mb + off][0].default
            for s in range(1, 5):
                assert od[c + s].default == od[mb + off][s].default >> 16


# ------------------------------------------------------------------ §5.1.1 fault table
# (trip code, 603F/EMCY code) exactly as printed in §5.1.1; None = '---' (CANopen-layer event)
MANUAL_TRIPS = {
    0x0E: 0x1000, 0x15: 0x1000, 0x16: 0x1000, 0x17: 0x1000, 0x1A: 0x1000, 0x1C: 0x1000, 0x28: 0x1000,
    0x35: 0x1000, 0x3A: 0x1000, 0x3F: 0x1000, 0x55: 0x1000, 0x56: 0x1000,
    0x05: 0x2230, 0x01: 0x2310, 0x02: 0x2310, 0x03: 0x2310, 0x20: 0x2311, 0x41: 0x2311, 0x48: 0x2311,
    0x04: 0x2320, 0x22: 0x2330, 0x0A: 0x3110, 0x0B: 0x3110, 0x0C: 0x3110, 0x1E: 0x3120, 0x08: 0x3130,
    0x09: 0x3310, 0x0F: 0x3310, 0x0D: 0x4210, 0x10: 0x4210, 0x3E: 0x4210,
    0x12: 0x5530, 0x13: 0x5530, 0x14: 0x5530, 0x29: 0x5530, 0x33: 0x6100, 0x37: 0x6100,
    0x2E: 0x7300, 0x32: 0x7300, 0x40: 0x7300, 0x2D: 0x7310, 0x18: 0x7510, 0x1B: 0x7520,
    0x2F: 0x8331, 0x45: 0x8501, 0x11: 0x9000, 0x2A: 0x9000, 0x54: 0xFF00,
    0x1D: 0xFF03, 0x3B: 0xFF03, 0x49: 0xFF03,
}
MANUAL_COMM_EVENTS = {0x8100, 0x8130, 0x8140}


@pytest.fixture(scope="module")
def faults():
    with FAULTS.open(encoding="utf-8", newline="") as f:
        return list(csv.DictReader(f))


def test_faults_header():
    """Convention header of faults.csv."""
    first = FAULTS.read_text(encoding="utf-8").splitlines()[0]
    assert first == "trip_code,trip_name,emcy_code,error_register_bit,description,section"


def test_faults_cover_every_trip_of_5_1_1(faults):
    """§5.1.1: every printed trip code is present exactly once with the printed error code."""
    trips = [r for r in faults if r["trip_code"]]
    got = {int(r["trip_code"], 16): int(r["emcy_code"], 16) for r in trips}
    assert len(got) == len(trips), "duplicate trip code"
    assert got == MANUAL_TRIPS
    comm = {int(r["emcy_code"], 16) for r in faults if not r["trip_code"]}
    assert comm == MANUAL_COMM_EVENTS
    assert all(r["section"] == "§5.1.1" for r in faults)


@pytest.mark.parametrize("trip,name,code", [
    (0x01, "OC1", 0x2310), (0x11, "E", 0x9000), (0x1E, "UP1", 0x3120), (0x10, "OH", 0x4210),
    (0x0A, "OP1", 0x3110), (0x12, "EEP1", 0x5530), (0x2F, "SOUt", 0x8331), (0x1B, "Err8", 0x7520)])
def test_fault_rows_examples(faults, trip, name, code):
    """§5.1.1 examples: OC1 0x01 -> 2310h, emergency stop E 0x11 -> 9000h, UP1 0x1E -> 3120h, ..."""
    row = next(r for r in faults if r["trip_code"] and int(r["trip_code"], 16) == trip)
    assert row["trip_name"] == name
    assert int(row["emcy_code"], 16) == code


def test_fault_error_register_bits(faults):
    """§4.1.1 0x1001 bits (current 1, voltage 2, temperature 3, communication 4, profile 5, manuf. 7);
    mapping per NOTES choice 20."""
    for r in faults:
        code, bit = int(r["emcy_code"], 16), int(r["error_register_bit"])
        hi = code >> 12
        if hi == 2:
            assert bit == 1
        elif hi == 3:
            assert bit == 2
        elif hi == 4:
            assert bit == 3
        elif code in MANUAL_COMM_EVENTS:
            assert bit == 4
        elif code in (0x8331, 0x8501):
            assert bit == 5
        elif hi == 0xF:
            assert bit == 7
        else:
            assert bit == 0, r


# ------------------------------------------------------------------ NOTES.md
def test_notes_sections_and_behaviour_items():
    """Convention NOTES.md headings; Behaviour covers §6.2, §5.1.2 note, §5.1.4, §5.1, §5.1.11,
    C100/C101/C103, §4.1.1 store/restore ranges and F856."""
    text = NOTES.read_text(encoding="utf-8")
    for h in ("## Source", "## Addressing rule", "## Choices and contradictions", "## Added objects",
              "## Behaviour", "## Modes/configurations"):
        assert h in text, h
    beh = text.split("## Behaviour", 1)[1].split("## Modes/configurations", 1)[0]
    for needle in ("0x1000–0x1FFF are read-only in OPERATIONAL", "Switch on + enable operation in one step",
                   "Target cleared on entering Operation enabled", "internal limit active",
                   "Limit clamping", "605A", "C100", "C101", "C103", "C700–C789", "C703–C789",
                   "F856", "0x65766173", "0x64616F6C", "3 s main-power rule"):
        assert needle in beh, needle
