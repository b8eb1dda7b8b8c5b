"""Benshaw RSi S/SW CANopen module: EDS checked against the manual.

Manual: Benshaw "CANopen for RSi 'S' & 'SW' Series Variable Frequency Drive, Instruction Manual" (890049-12-00) (Benshaw 890049-12-00, rev 0).
Every expected value below is typed in from the manual (section in the test name or
docstring) or from a choice recorded in od/benshaw-rsi/NOTES.md (marked "choice Cn").
"""
import configparser
import csv
import logging
import re
from pathlib import Path

import pytest

import canopen
from canopen.objectdictionary import datatypes as dt

ROOT = Path(__file__).resolve().parents[2]
DRIVE = ROOT / "od" / "benshaw-rsi"
EDS = DRIVE / "benshaw-rsi.eds"
FAULTS = DRIVE / "faults.csv"
MODES = DRIVE / "modes.csv"
NOTES = DRIVE / "NOTES.md"
NODE = 5


def _load(node_id=NODE):
    return canopen.objectdictionary.import_od(str(EDS), node_id=node_id)


@pytest.fixture(scope="module")
def od():
    return _load()


def _raw():
    cp = configparser.RawConfigParser(inline_comment_prefixes=(";",), strict=True)
    cp.optionxform = str
    cp.read(EDS, encoding="utf-8")
    return cp


# --------------------------------------------------------------------------- loading
def test_loads_without_warning(caplog):
    """CiA 306 file must load in python-canopen with nothing logged at WARNING or above."""
    with caplog.at_level(logging.DEBUG):
        o = _load()
    bad = [r for r in caplog.records if r.levelno >= logging.WARNING]
    assert bad == [], [r.getMessage() for r in bad]
    assert len(o) == 37


def test_loads_with_python_warnings_as_errors():
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _load()


def test_strict_ini_no_duplicate_sections_or_keys():
    _raw()  # strict=True raises on duplicates


# --------------------------------------------------------------------------- structure
OBJ_RE = re.compile(r"^\[([0-9A-F]{4})\]$")
SUB_RE = re.compile(r"^\[([0-9A-F]{4})sub([0-9A-F]+)\]$")


def test_every_object_section_has_source_comment():
    """Convention: a '; source:' comment line above every [XXXX] section."""
    lines = EDS.read_text(encoding="utf-8").splitlines()
    for i, line in enumerate(lines):
        if OBJ_RE.match(line):
            j = i - 1
            block = []
            while j >= 0 and lines[j].startswith(";"):
                block.append(lines[j])
                j -= 1
            assert any(b.startswith("; source:") for b in block), line


def test_object_lists_match_sections():
    cp = _raw()
    listed = []
    for sec in ("MandatoryObjects", "OptionalObjects", "ManufacturerObjects"):
        n = int(cp.get(sec, "SupportedObjects"))
        vals = [int(cp.get(sec, str(k)), 0) for k in range(1, n + 1)]
        assert len(cp.options(sec)) == n + 1
        listed += vals
    objs = sorted(int(s, 16) for s in cp.sections() if re.fullmatch(r"[0-9A-F]{4}", s))
    assert sorted(listed) == objs
    assert len(set(listed)) == len(listed)
    assert [int(cp.get("MandatoryObjects", str(k)), 0) for k in (1, 2, 3)] == [0x1000, 0x1001, 0x1018]


def test_every_entry_has_required_keys_and_subnumber():
    cp = _raw()
    for sec in cp.sections():
        if re.fullmatch(r"[0-9A-F]{4}", sec):
            ot = int(cp.get(sec, "ObjectType"), 0)
            assert cp.has_option(sec, "ParameterName")
            if ot in (0x8, 0x9):
                subs = [s for s in cp.sections() if s.startswith(sec + "sub")]
                assert int(cp.get(sec, "SubNumber")) == len(subs), sec
                assert sec + "sub0" in subs
                assert cp.get(sec + "sub0", "DataType") == "0x0005"
            else:
                assert ot == 0x7
        if SUB_RE.match("[" + sec + "]") or OBJ_RE.match("[" + sec + "]"):
            if cp.has_option(sec, "SubNumber"):
                continue
            for key in ("ParameterName", "ObjectType", "DataType", "AccessType", "DefaultValue", "PDOMapping"):
                assert cp.has_option(sec, key), (sec, key)
            assert cp.get(sec, "AccessType") in ("ro", "wo", "rw", "rww", "rwr", "const")


def test_all_defaults_parse(od):
    """A default that python-canopen cannot parse is silently dropped: catch that."""
    for obj in od.values():
        members = obj.values() if hasattr(obj, "values") else [obj]
        for var in members:
            assert var.default is not None, (hex(var.index), var.subindex)
            if var.min is not None:
                assert var.min <= var.default, (hex(var.index), var.subindex)
            if var.max is not None:
                assert var.default <= var.max, (hex(var.index), var.subindex)


# --------------------------------------------------------------------------- DeviceInfo §3 §4.4
def test_deviceinfo_vendor_0x7D_section3():
    assert _load().device_information.vendor_number == 0x7D


def test_deviceinfo_baudrates_section3_section4_4_no_10k():
    rates = _load().device_information.allowed_baudrates
    assert rates == {20000, 50000, 125000, 250000, 500000, 800000, 1000000}


def test_deviceinfo_lss_na_mapping_na_section3():
    info = _load().device_information
    assert info.LSS_supported is False
    assert info.granularity is False  # "PDO Mapping N/A"
    assert info.simple_boot_up_slave is True


def test_deviceinfo_pdo_counts_pdo1_and_pdo3_section3():
    info = _load().device_information
    assert info.nr_of_RXPDO == 2 and info.nr_of_TXPDO == 2


# --------------------------------------------------------------------------- 0x1000-0x1018 (§7)
def test_device_type_0x00010192_ro_section7_1(od):
    v = od[0x1000]
    assert (v.default, v.data_type, v.access_type) == (0x00010192, dt.UNSIGNED32, "ro")


def test_error_register_u8_ro_section7_2(od):
    v = od[0x1001]
    assert (v.data_type, v.access_type, v.default) == (dt.UNSIGNED8, "ro", 0)


def test_predefined_error_field_section7_3(od):
    """sub0 U8 RW (write 0 resets), sub1 last emergency RO; U32 chosen (C2)."""
    arr = od[0x1003]
    assert isinstance(arr, canopen.objectdictionary.ODArray)
    assert sorted(arr.subindices) == [0, 1]
    assert (arr[0].data_type, arr[0].access_type) == (dt.UNSIGNED8, "rw")
    assert (arr[1].data_type, arr[1].access_type) == (dt.UNSIGNED32, "ro")


def test_cob_id_sync_0x80_rw_section7_4_and_6_1_1(od):
    v = od[0x1005]
    assert (v.default, v.data_type, v.access_type) == (0x80, dt.UNSIGNED32, "rw")
    assert v.default & (1 << 30) == 0 and v.default & (1 << 29) == 0  # gen and frame must be 0


@pytest.mark.parametrize("idx,text,sec", [(0x1008, "CANopen", "7.5"),
                                          (0x1009, "CANopen 1.00", "7.6"),
                                          (0x100A, "Version 1.00", "7.7")])
def test_strings_const_sections7_5_to_7_7(od, idx, text, sec):
    v = od[idx]
    assert (v.default, v.data_type, v.access_type) == (text, dt.VISIBLE_STRING, "const")


def test_guard_time_u16_rw_section7_8(od):
    assert (od[0x100C].data_type, od[0x100C].access_type) == (dt.UNSIGNED16, "rw")


def test_life_time_factor_u8_rw_zero_unused_section7_9(od):
    v = od[0x100D]
    assert (v.data_type, v.access_type, v.default) == (dt.UNSIGNED8, "rw", 0)


@pytest.mark.parametrize("node", [1, 5, 127])
def test_cob_id_emcy_nodeid_plus_0x80_read_only_section7_10(node):
    v = _load(node)[0x1014]
    assert v.default == 0x80 + node
    assert v.relative
    assert v.access_type == "ro"  # C1


def test_producer_heartbeat_u16_rw_section7_11(od):
    v = od[0x1017]
    assert (v.data_type, v.access_type, v.default) == (dt.UNSIGNED16, "rw", 0)


def test_identity_added_vendor_0x7D(od):
    """0x1018 added (NOTES 'Added objects'): vendor 'Vender Name 0x7D' §3."""
    rec = od[0x1018]
    assert sorted(rec.subindices) == [0, 1]
    assert rec[0].default == 1 and rec[1].default == 0x7D
    assert rec[1].access_type == "ro"


# --------------------------------------------------------------------------- PDOs (§6.1.1, §8.2)
@pytest.mark.parametrize("node", [1, 5, 127])
def test_pdo_cob_ids_section6_1_1(node):
    o = _load(node)
    assert o[0x1400][1].default == 0x200 + node          # PDO1 rx 0x201-0x27F
    assert o[0x1800][1].default == 0x180 + node          # PDO1 tx 0x181-0x1FF
    # PDO3: 0x401-0x47F rx, 0x381-0x3FF tx; invalid (bit 31) in factory default CM.11 = 0
    assert o[0x1402][1].default == 0x80000000 | (0x400 + node)
    assert o[0x1802][1].default == 0x80000000 | (0x380 + node)


def test_pdo1_valid_pdo3_invalid_not_both_section6_1_3_9_2_7(od):
    assert not od[0x1400][1].default & 0x80000000 and not od[0x1800][1].default & 0x80000000
    assert od[0x1402][1].default & 0x80000000 and od[0x1802][1].default & 0x80000000


@pytest.mark.parametrize("idx", [0x1400, 0x1402])
def test_rpdo_comm_subs_section8_2_1(od, idx):
    rec = od[idx]
    assert sorted(rec.subindices) == [0, 1, 2]
    assert (rec[0].default, rec[0].access_type, rec[0].data_type) == (2, "ro", dt.UNSIGNED8)
    assert (rec[1].access_type, rec[1].data_type) == ("rw", dt.UNSIGNED32)
    assert (rec[2].access_type, rec[2].data_type, rec[2].default) == ("rw", dt.UNSIGNED8, 255)


@pytest.mark.parametrize("idx", [0x1800, 0x1802])
def test_tpdo_comm_subs_and_type_fixed_255_section8_2_3(od, idx):
    rec = od[idx]
    assert sorted(rec.subindices) == [0, 1, 2, 3, 5]
    assert (rec[0].default, rec[0].access_type) == (5, "ro")
    assert (rec[2].default, rec[2].min, rec[2].max) == (255, 255, 255)
    assert (rec[3].data_type, rec[3].access_type) == (dt.UNSIGNED16, "rw")
    assert (rec[5].data_type, rec[5].access_type) == (dt.UNSIGNED16, "rw")


def _mapping(rec):
    return [rec[s].default for s in range(1, rec[0].default + 1)]


def test_rpdo1_mapping_controlword_target_velocity_ro_section8_2_2_1(od):
    rec = od[0x1600]
    assert _mapping(rec) == [0x60400010, 0x60420010]
    assert all(rec[s].access_type == "ro" for s in (0, 1, 2))


def test_tpdo1_mapping_statusword_control_effort_ro_section8_2_4_1(od):
    rec = od[0x1A00]
    assert _mapping(rec) == [0x60410010, 0x60440010]
    assert all(rec[s].access_type == "ro" for s in (0, 1, 2))


@pytest.mark.parametrize("idx", [0x1602, 0x1A02])
def test_pdo3_mapping_0x3010_to_0x3013_rw_section8_2_2_2_8_2_4_2(od, idx):
    rec = od[idx]
    assert _mapping(rec) == [0x30100010, 0x30110010, 0x30120010, 0x30130010]
    assert [rec[s].access_type for s in (1, 2, 3, 4)] == ["rw"] * 4
    assert rec[0].access_type == "ro"


def test_pdo3_words_are_u16_mappable_section9_3(od):
    for idx in range(0x3010, 0x3014):
        v = od[idx]
        assert (v.data_type, v.access_type, v.pdo_mappable) == (dt.UNSIGNED16, "rw", True)


def test_mapped_objects_exist_with_matching_length(od):
    for m in (0x1600, 0x1602, 0x1A00, 0x1A02):
        for entry in _mapping(od[m]):
            idx, sub, length = entry >> 16, (entry >> 8) & 0xFF, entry & 0xFF
            var = od[idx] if sub == 0 else od[idx][sub]
            assert len(var) == length and var.pdo_mappable


# --------------------------------------------------------------------------- CiA 402 (§8.1.2)
def test_velocity_mode_only_no_6060_6061_section8_1(od):
    for idx in (0x6060, 0x6061, 0x6046, 0x605A, 0x6502, 0x6007):
        assert idx not in od


def test_error_code_603F_u16_ro_section8_1_2_1(od):
    v = od[0x603F]
    assert (v.data_type, v.access_type) == (dt.UNSIGNED16, "ro")


def test_controlword_u16_rw_section8_1_2_2(od):
    v = od[0x6040]
    assert (v.data_type, v.access_type, v.pdo_mappable) == (dt.UNSIGNED16, "rw", True)


def test_statusword_u16_ro_section8_1_2_3(od):
    v = od[0x6041]
    assert (v.data_type, v.access_type, v.pdo_mappable) == (dt.UNSIGNED16, "ro", True)


@pytest.mark.parametrize("idx,access,sec", [(0x6042, "rw", "8.1.2.4"),
                                             (0x6043, "ro", "8.1.2.5"),
                                             (0x6044, "ro", "8.1.2.6")])
def test_vl_velocities_rpm_pm30000_sections8_1_2_4_to_6(od, idx, access, sec):
    v = od[idx]
    assert v.data_type == dt.INTEGER16  # C3: signed range
    assert (v.min, v.max) == (-30000, 30000)
    assert v.access_type == access


@pytest.mark.parametrize("idx,sec", [(0x6048, "8.1.2.7"), (0x6049, "8.1.2.8"), (0x604A, "8.1.2.9")])
def test_ramp_delta_time_0_to_600_0s_sub2_only_sections8_1_2_7_to_9(od, idx, sec):
    rec = od[idx]
    assert sorted(rec.subindices) == [0, 2]  # delta speed fixed at Max Speed: no sub 1
    assert (rec[0].data_type, rec[0].access_type, rec[0].default) == (dt.UNSIGNED8, "ro", 2)
    assert rec[2].data_type == dt.UNSIGNED16
    assert (rec[2].min, rec[2].max) == (0, 6000)  # 0.0-600.0 s in 0.1 s (C5)
    assert rec[2].access_type == "rw"  # 0x604A printed RW; 0x6048/0x6049 per §9.2.7 (C4)


# --------------------------------------------------------------------------- keypad area (§8.1.3, §9)
GROUP = {"DRV": 0x4010, "BAS": 0x4011, "ADV": 0x4012, "CON": 0x4013, "IN": 0x4014, "OUT": 0x4015,
         "COM": 0x4016, "APP": 0x4017, "PRT": 0x401A, "M2": 0x401B, "USS": 0x401C, "USF": 0x401D}


def address(group, code):
    """§8.1.3.1-§8.1.3.13: sub-index = code number; DRV group: code number + 1."""
    return GROUP[group], code + (1 if group == "DRV" else 0)


def test_addressing_rule_manual_examples_section8_1_3():
    assert address("DRV", 8) == (0x4010, 9)    # Output Current, §8.1.3.1
    assert address("BAS", 70) == (0x4011, 70)  # bA.70 ACC.Time-1, §8.1.3.3


# (group, code, name fragment, default, low, high, access, section)
PARAMS = [
    ("DRV", 6, "Cmd Source", 1, 0, 4, "rw", "9.1 (C7)"),
    ("DRV", 7, "Freq Ref Src", 0, 0, 12, "rw", "9.1"),
    ("DRV", 8, "Output Current", 0, None, None, "ro", "8.1.3.1"),
    ("BAS", 70, "ACC.Time-1", 200, 0, 6000, "rw", "8.1.3.3"),
    ("COM", 6, "FBus S/W Ver", 0x0100, None, None, "ro", "9.2.3"),
    ("COM", 7, "FBus ID", 1, 1, 127, "rw", "9.1"),
    ("COM", 9, "FBus LED", 0, None, None, "ro", "9.2.5"),
    ("COM", 10, "Opt Parameter1", 0, 0, 7, "rw", "9.1"),
    ("COM", 11, "Opt Parameter2", 0, 0, 1, "rw", "9.1, 9.2.7"),
    ("COM", 31, "Para Status-1", 0x000A, 0, 0xFFFF, "rw", "9.1"),
    ("COM", 32, "Para Status-2", 0x000E, 0, 0xFFFF, "rw", "9.1"),
    ("COM", 33, "Para Status-3", 0x000F, 0, 0xFFFF, "rw", "9.1"),
    ("COM", 34, "Para Status-4", 0x0000, 0, 0xFFFF, "rw", "9.1"),
    ("COM", 51, "Para Control-1", 0x0005, 0, 0xFFFF, "rw", "9.1"),
    ("COM", 52, "Para Control-2", 0x0006, 0, 0xFFFF, "rw", "9.1"),
    ("COM", 53, "Para Control-3", 0x0000, 0, 0xFFFF, "rw", "9.1"),
    ("COM", 54, "Para Control-4", 0x0000, 0, 0xFFFF, "rw", "9.1"),
    ("COM", 61, "Station ID", 1, 1, 127, "rw", "9.2.8 (C10)"),
    ("COM", 62, "Baud rate", 0, 0, 7, "rw", "9.2.8 (C10)"),
    ("COM", 63, "Profile Sel", 0, 0, 1, "rw", "9.2.8 (C10)"),
    ("COM", 67, "Comm Update", 0, 0, 1, "rw", "9.2.8 (C10)"),
    ("COM", 94, "Comm Update", 0, 0, 1, "rw", "9.1"),
    ("PRT", 7, "Trip Dec Time", 30, 0, 6000, "rw", "9.4.1 (choice)"),
    ("PRT", 12, "Lost Cmd Mode", 0, 0, 5, "rw", "9.1"),
    ("PRT", 13, "Lost Cmd Time", 10, 1, 1200, "rw", "9.1 (1.0 s, 0.1-120.0 s)"),
    ("PRT", 14, "Lost Preset F", 0, 0, 6000, "rw", "9.1 (0 Hz; C31)"),
]


@pytest.mark.parametrize("group,code,name,default,lo,hi,access,sec", PARAMS,
                         ids=[f"{p[0]}.{p[1]:02d}" for p in PARAMS])
def test_named_keypad_parameter_section9_1(od, group, code, name, default, lo, hi, access, sec):
    idx, sub = address(group, code)
    v = od[idx][sub]
    assert name.lower() in v.name.lower()
    assert v.data_type == dt.UNSIGNED16  # "Type U16" in every §8.1.3 table
    assert v.default == default
    assert (v.min, v.max) == (lo, hi)
    assert v.access_type == access
    assert not v.pdo_mappable


def test_drv_acc_time_example_index_0x4010_sub3_section8_1_3_2(od):
    v = od[0x4010][3]
    assert "acc.time-1" in v.name.lower()
    assert (v.data_type, v.access_type, v.min, v.max) == (dt.UNSIGNED16, "rw", 0, 6000)
    assert v.default == od[0x6048][2].default  # same value as 0x6048 (C23, §9.2.7)


def test_drv_sub_is_not_code_for_cmd_source(od):
    """dr.06 is at sub 7, not 6 (§8.1.3.2 'Code Num +1')."""
    assert 6 not in od[0x4010].subindices
    assert "cmd source" in od[0x4010][7].name.lower()


def test_keypad_groups_present_only_when_named(od):
    for idx in (0x4010, 0x4011, 0x4016, 0x401A):
        assert idx in od
    for idx in (0x4012, 0x4013, 0x4014, 0x4015, 0x4017, 0x4018, 0x4019, 0x401B, 0x401C, 0x401D):
        assert idx not in od


def test_keypad_group_sub0_is_highest_subindex(od):
    for idx in (0x4010, 0x4011, 0x4016, 0x401A):
        rec = od[idx]
        assert rec[0].default == max(rec.subindices)


# --------------------------------------------------------------------------- faults.csv (§7.2, §7.3, §8.1.2.1)
# EMCY / 0x1003 table, §7.3 (code -> trip), "0x0000 None" left out
EMCY_7_3 = {
    0x1000: "UNDEFINED", 0x2220: "Inverter OLT", 0x2310: "OverCurrent1", 0x2330: "Ground Trip",
    0x2340: "OverCurrent2", 0x3130: "In Phase Open", 0x3210: "Over Voltage", 0x3220: "Low Voltage",
    0x4000: "NTC Open", 0x4310: "Over Heat", 0x5000: "HWDiag", 0x5450: "Fuse Open",
    0x7120: "No Motor Trip", 0x8401: "Speed Dev Trip", 0x8402: "OverSpeed", 0x8200: "Protocol Error",
    0x8210: "PDO not processed due to length error", 0x8220: "PDO length exceeded",
    0x9001: "External Trip", 0x9002: "BX", 0x9003: "Safety A Trip", 0x9004: "Safety B Trip",
    0xFF02: "Ethermal", 0xFF03: "Out Phase Open", 0xFF04: "Over Load", 0xFF05: "Under Load",
    0xFF06: "Thermal Trip", 0xFF07: "Pre PID Fail", 0xFF0A: "Lost Command",
}
# 0x603F table, §8.1.2.1 (trip -> code) where it differs or is absent
CODE_603F_ONLY = {"Ethermal": 0xFF01}
NOT_IN_603F = {"Protocol Error", "PDO not processed due to length error", "PDO length exceeded",
               "Safety A Trip", "Safety B Trip"}
# §7.2 error-register classes
BIT_7_2 = {
    0: {"HWDiag", "Fuse Open", "External Trip", "BX"},
    1: {"Inverter OLT", "OverCurrent1", "Ground Trip", "OverCurrent2"},
    2: {"In Phase Open", "Over Voltage", "Low Voltage"},
    3: {"NTC Open", "Over Heat"},
    7: {"Ethermal", "Out Phase Open", "Over Load", "Under Load", "Thermal Trip", "Pre PID Fail",
        "Lost Command"},
}


def _faults():
    with open(FAULTS, newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


def test_faults_header():
    with open(FAULTS, encoding="utf-8") as f:
        assert f.readline().strip() == "trip_code,trip_name,emcy_code,error_register_bit,description,section"


def test_faults_every_trip_of_section7_3_once():
    rows = _faults()
    assert sorted(int(r["emcy_code"], 16) for r in rows) == sorted(EMCY_7_3)
    assert len({r["trip_name"] for r in rows}) == len(rows)


@pytest.mark.parametrize("code,name", sorted(EMCY_7_3.items()), ids=[f"0x{c:04X}" for c in sorted(EMCY_7_3)])
def test_fault_row_emcy_code_matches_section7_3(code, name):
    row = [r for r in _faults() if r["trip_name"] == name]
    assert len(row) == 1
    assert int(row[0]["emcy_code"], 16) == code
    expect_603f = CODE_603F_ONLY.get(name, code)
    assert int(row[0]["trip_code"], 16) == expect_603f  # §8.1.2.1 value (C16/C17)
    assert row[0]["section"] and row[0]["description"]


def test_fault_ethermal_conflict_kept_as_printed_7_3_vs_8_1_2_1():
    row = [r for r in _faults() if r["trip_name"] == "Ethermal"][0]
    assert (row["trip_code"], row["emcy_code"]) == ("0xFF01", "0xFF02")


@pytest.mark.parametrize("bit", sorted(BIT_7_2))
def test_fault_error_register_bits_section7_2(bit):
    rows = {r["trip_name"]: int(r["error_register_bit"]) for r in _faults()}
    for name in BIT_7_2[bit]:
        assert rows[name] == bit, name


def test_fault_unmapped_trips_generic_bit0_choice_C29():
    mapped = set().union(*BIT_7_2.values())
    for r in _faults():
        if r["trip_name"] not in mapped:
            assert r["error_register_bit"] == "0", r["trip_name"]


def test_fault_rows_not_in_603F_table_marked():
    for r in _faults():
        if r["trip_name"] in NOT_IN_603F:
            assert "§8.1.2.1" not in r["section"]
        else:
            assert "§8.1.2.1" in r["section"]


# --------------------------------------------------------------------------- modes.csv (CM.11, §9.2.7)
def _modes():
    with open(MODES, newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


def _cob(expr, node):
    m = re.fullmatch(r"\$NODEID\+(0x[0-9A-Fa-f]+)", expr)
    assert m, expr
    return int(m.group(1), 16) + node


def test_modes_header():
    with open(MODES, encoding="utf-8") as f:
        assert f.readline().strip() == \
            "mode_value,pdo,direction,cob_id,transmission_type,mapping,section"


@pytest.mark.parametrize("mode,valid,invalid", [("0", {"RPDO1", "TPDO1"}, {"RPDO3", "TPDO3"}),
                                                ("1", {"RPDO3", "TPDO3"}, {"RPDO1", "TPDO1"})])
def test_modes_cm11_selects_pdo1_or_pdo3_section9_2_7(mode, valid, invalid):
    rows = {r["pdo"]: r for r in _modes() if r["mode_value"] == mode}
    assert set(rows) == valid | invalid
    base = {"RPDO1": 0x200, "TPDO1": 0x180, "RPDO3": 0x400, "TPDO3": 0x380}  # §6.1.1
    for name, r in rows.items():
        cob = _cob(r["cob_id"], 1)
        assert cob & 0x7FF == base[name] + 1
        assert bool(cob & 0x80000000) == (name in invalid)
        assert r["direction"] == ("rx" if name.startswith("R") else "tx")
        assert r["transmission_type"] == "255"  # §8.2.3 fixed for TPDOs; RPDO default choice C27
    maps = {"RPDO1": "0x60400010 0x60420010", "TPDO1": "0x60410010 0x60440010",
            "RPDO3": "0x30100010 0x30110010 0x30120010 0x30130010",
            "TPDO3": "0x30100010 0x30110010 0x30120010 0x30130010"}
    for name, r in rows.items():
        assert r["mapping"] == maps[name]


def test_modes_value0_equals_eds_factory_default(od):
    comm = {"RPDO1": 0x1400, "RPDO3": 0x1402, "TPDO1": 0x1800, "TPDO3": 0x1802}
    for r in _modes():
        if r["mode_value"] != "0":
            continue
        c = comm[r["pdo"]]
        assert od[c][1].default == _cob(r["cob_id"], NODE)
        assert od[c][2].default == int(r["transmission_type"])
        assert [f"0x{v:08X}" for v in _mapping(od[c + 0x200])] == r["mapping"].split()


def test_modes_values_are_cm11_range(od):
    cm11 = od[0x4016][11]
    assert {int(r["mode_value"]) for r in _modes()} == set(range(cm11.min, cm11.max + 1))


# --------------------------------------------------------------------------- NOTES.md
def test_notes_has_required_sections():
    text = NOTES.read_text(encoding="utf-8")
    for h in ("## Source", "## Addressing rule", "## Choices and contradictions", "## Added objects",
              "## Behaviour", "## Modes/configurations"):
        assert h in text, h
    for needle in ("Transition 5", "Pr.12", "Pr.13", "Quick stop", "Fault reset", "free-run (coast)"):
        assert needle.lower() in text.lower(), needle


# --------------------------------------------------------------------------- end to end (virtual bus)
def test_sdo_upload_over_virtual_bus():
    """A master can read 0x1000 (§7.1), 0x1008 (§7.5, segmented) and 0x1014 (§7.10)."""
    can = pytest.importorskip("can")
    net_s, net_m = canopen.Network(), canopen.Network()
    net_s.connect(interface="virtual", channel="benshaw_rsi_test", receive_own_messages=False)
    net_m.connect(interface="virtual", channel="benshaw_rsi_test", receive_own_messages=False)
    try:
        slave = net_s.create_node(NODE, str(EDS))
        master = net_m.add_node(NODE, str(EDS))
        assert master.sdo.upload(0x1000, 0) == bytes([0x92, 0x01, 0x01, 0x00])
        assert master.sdo.upload(0x1008, 0) == b"CANopen"
        assert master.sdo[0x1014].raw == 0x80 + NODE
        assert master.sdo[0x4016][7].raw == 1
        assert slave is not None
    finally:
        net_s.disconnect()
        net_m.disconnect()
