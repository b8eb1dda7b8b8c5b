"""Tests for od/vf-mb1-ecat/vf-mb1-ecat.eds against the manual.

Manual: Toshiba "TOSVERT VF-MB1/S15 series EtherCAT option unit Function Manual, IPE003Z", "TOSVERT VF-MB1/S15 series EtherCAT option
unit Function Manual, IPE003Z" (called "the manual" below; sections are its sections).
Every expected value below is typed in from the manual (or, for objects added for the CAN
transport, from the choices written in od/vf-mb1-ecat/NOTES.md), never read back from the EDS.
"""
import csv
import logging
import pathlib
import re
import warnings

import canopen
import pytest
from canopen.objectdictionary import datatypes as dt

ROOT = pathlib.Path(__file__).resolve().parents[2]
DRIVE = ROOT / "od" / "vf-mb1-ecat"
EDS = DRIVE / "vf-mb1-ecat.eds"
FAULTS = DRIVE / "faults.csv"
NOTES = DRIVE / "NOTES.md"
NODE_ID = 5


@pytest.fixture(scope="module")
def od():
    return canopen.objectdictionary.import_od(str(EDS), node_id=NODE_ID)


@pytest.fixture(scope="module")
def eds_text():
    return EDS.read_text(encoding="utf-8")


def _object_sections(text):
    """Return {index: [comment lines directly above the [XXXX] section]}."""
    lines = text.splitlines()
    out = {}
    for n, line in enumerate(lines):
        m = re.fullmatch(r"\[([0-9A-F]{4})\]", line.strip())
        if not m:
            continue
        comments = []
        k = n - 1
        while k >= 0 and lines[k].startswith(";"):
            comments.insert(0, lines[k])
            k -= 1
        out[int(m.group(1), 16)] = comments
    return out


# --------------------------------------------------------------------------- loading
def test_eds_loads_without_warning(caplog):
    """CiA 306 conformance: python-canopen loads the EDS with no warning (project convention)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with caplog.at_level(logging.WARNING):
            od = canopen.objectdictionary.import_od(str(EDS), node_id=NODE_ID)
    assert [r for r in caplog.records if r.levelno >= logging.WARNING] == []
    assert len(od) > 100


def test_every_object_has_a_source_comment(eds_text):
    """Convention: every [XXXX] section is preceded by a '; source:' comment line."""
    sections = _object_sections(eds_text)
    missing = [hex(i) for i, c in sections.items() if not any(x.startswith("; source:") for x in c)]
    assert missing == []


ADDED = {0x1005, 0x1014, 0x1016, 0x1017, 0x1200, 0x1400, 0x1800}


def test_objects_not_in_manual_are_marked_added(eds_text):
    """§4.1 lists 1000/1001/1003/1008/1018 only; the CAN-transport objects must be marked 'added'."""
    sections = _object_sections(eds_text)
    marked = {i for i, c in sections.items()
              if any(x.startswith("; source: added (not in manual): CoE served over CAN") for x in c)}
    assert marked == ADDED


def test_notes_has_required_headings():
    """Convention: NOTES.md carries the required sections."""
    text = NOTES.read_text(encoding="utf-8")
    for h in ["Source", "Addressing rule", "Choices and contradictions", "Added objects", "Behaviour",
              "Modes/configurations"]:
        assert re.search(r"^#+ .*" + re.escape(h), text, re.M), h


# --------------------------------------------------------------------------- §4.1 communication profile
def test_device_type_0x1000(od):
    """§4.1: 0x1000 u32 RO, default 0x00410192."""
    v = od[0x1000]
    assert v.default == 0x00410192
    assert v.data_type == dt.UNSIGNED32
    assert v.access_type == "ro"


def test_error_register_0x1001(od):
    """§4.1: 0x1001 u8 RO, default 0x00."""
    v = od[0x1001]
    assert (v.data_type, v.access_type, v.default) == (dt.UNSIGNED8, "ro", 0)


def test_error_history_0x1003(od):
    """§4.1: 0x1003 sub 0 u8 RO default 0, sub 0x01..0x10 u32 RO (16 entries)."""
    arr = od[0x1003]
    assert isinstance(arr, canopen.objectdictionary.ODArray)
    assert sorted(arr.subindices) == list(range(0, 17))
    assert (arr[0].data_type, arr[0].access_type, arr[0].default) == (dt.UNSIGNED8, "ro", 0)
    for s in range(1, 17):
        assert (arr[s].data_type, arr[s].access_type, arr[s].default) == (dt.UNSIGNED32, "ro", 0)


def test_device_name_0x1008(od):
    """§4.1: 0x1008 string RO, 'depends on the drive name' (VF-MB1 chosen, NOTES)."""
    v = od[0x1008]
    assert v.data_type == dt.VISIBLE_STRING and v.access_type == "ro"
    assert v.default == "VF-MB1"


@pytest.mark.parametrize("sub,value", [(0, 0x04), (1, 0x00000284), (2, 0x000000E1), (3, 0x00010002)])
def test_identity_0x1018(od, sub, value):
    """§4.1: 0x1018 sub0 = 4, vendor 0x284 (Toshiba Schneider Inverter), product 0xE1, revision 0x00010002."""
    v = od[0x1018][sub]
    assert v.default == value
    assert v.access_type == "ro"


def test_identity_serial_number_exists(od):
    """§4.1: 0x1018 sub 4 serial number, u32 RO (value device specific)."""
    v = od[0x1018][4]
    assert v.data_type == dt.UNSIGNED32 and v.access_type == "ro"


def test_deviceinfo_matches_identity(od):
    """§4.1: DeviceInfo vendor/product/revision equal the 0x1018 values; one RxPDO and one TxPDO (§1.1)."""
    di = od.device_information
    assert di.vendor_number == 0x284
    assert di.product_number == 0xE1
    assert di.revision_number == 0x00010002
    assert di.nr_of_RXPDO == 1 and di.nr_of_TXPDO == 1


def test_communication_profile_not_mappable(od):
    """§4.1: 'These communication profile object can not be mapped into PDO'."""
    for obj in od.values():
        if obj.index >= 0x2000:
            continue
        members = obj.values() if hasattr(obj, "values") else [obj]
        for v in members:
            assert not v.pdo_mappable, hex(obj.index)


def test_no_sync_manager_objects(od):
    """§4.1 is the whole communication profile: the manual lists no 0x1C00/0x1C12/0x1C13/0x1C32/0x1C33."""
    for idx in (0x1C00, 0x1C12, 0x1C13, 0x1C32, 0x1C33):
        assert idx not in od


# --------------------------------------------------------------------------- §4.2/§4.3 PDO mapping
RPDO_MAP = [0x02, 0x60400010, 0x60420010, 0, 0, 0, 0]
TPDO_MAP = [0x02, 0x60410010, 0x60440010, 0, 0, 0, 0]


@pytest.mark.parametrize("index,expected", [(0x1600, RPDO_MAP), (0x1A00, TPDO_MAP)])
def test_pdo_mapping_defaults(od, index, expected):
    """§4.2 (0x1600 CMD+LFRD) and §4.3 (0x1A00 ETA+RFRD): defaults, R/W, sub 0..6."""
    rec = od[index]
    assert sorted(rec.subindices) == list(range(7))
    assert rec[0].data_type == dt.UNSIGNED8
    for s, val in enumerate(expected):
        assert rec[s].default == val, (hex(index), s)
        assert rec[s].access_type == "rw"
        if s:
            assert rec[s].data_type == dt.UNSIGNED32


@pytest.mark.parametrize("index", [0x1600, 0x1A00])
def test_pdo_mapping_at_most_six(od, index):
    """§8.9: 'The MB1 has maximum 6 TPDO and 6 RPDO' -> sub 0 range 0..6."""
    assert od[index][0].min == 0
    assert od[index][0].max == 6


# --------------------------------------------------------------------------- §4.4 addressing rule
@pytest.mark.parametrize("index,name_part", [
    (0x2880, "Free notes"), (0x2C91, "Alarm code"), (0x2D00, "Output frequency"),
    (0x2D01, "status"), (0x2D03, "Output current"), (0x2D04, "DC bus"), (0x2D05, "Output voltage"),
    (0x2D06, "Input terminal"), (0x2D07, "Output terminal"), (0x2D16, "Estimated speed"),
    (0x2D18, "Torque"), (0x2D20, "Torque current"), (0x2D22, "PID feedback"), (0x2D23, "Motor overload"),
])
def test_twincat_dictionary_list(od, index, name_part):
    """§8.16 'From Dictionary' list: index and name, TxPDO mappable (confirms the §4.4 rule)."""
    v = od[index]
    assert name_part.lower() in v.name.lower()
    assert v.pdo_mappable


@pytest.mark.parametrize("param,index", [
    ("CMOd", 0x2003), ("FMOd", 0x2004), ("F856", 0x2856), ("F899", 0x2899), ("F601", 0x2601),
    ("F880", 0x2880), ("FA06", 0x2A06), ("FA07", 0x2A07), ("FA23", 0x2A23), ("FA50", 0x2A50),
    ("FA51", 0x2A51), ("FC91", 0x2C91), ("FD00", 0x2D00), ("FD01", 0x2D01), ("FE14", 0x2E14),
    ("C001", 0x4001), ("C021", 0x4021), ("C100", 0x4100), ("C400", 0x4400), ("C410", 0x4410),
    ("C416", 0x4416), ("C421", 0x4421),
])
def test_addressing_rule(od, param, index):
    """§4.4: F000-F999 -> 0x2000-0x2999, FA00-FF99 -> 0x2A00-0x2F99, C000-CF99 -> 0x4000-0x4F99 (digits kept)."""
    assert od[index].name.startswith(param + " ")


SCANNER_IN = {1: 0x2A06, 2: 0x2A23, 3: 0x2A07, 5: 0x2A50, 6: 0x2A51, 8: 0x2601, 100: 0x6040, 101: 0x6042}
SCANNER_OUT = {1: 0x2D01, 2: 0x2D00, 3: 0x2D03, 4: 0x2D05, 5: 0x2C91, 6: 0x2D22, 7: 0x2D06, 8: 0x2D07,
               9: 0x2E36, 10: 0x2E35, 11: 0x2E37, 12: 0x2D04, 13: 0x2D16, 14: 0x2D18, 19: 0x2880,
               20: 0x2D29, 21: 0x2D30, 22: 0x2E14, 23: 0x2E40, 25: 0x2D20, 26: 0x2D23, 27: 0x2D24,
               28: 0x2D25, 29: 0x2D26, 30: 0x2D27, 31: 0x2E56, 32: 0x2E70, 33: 0x2E76, 34: 0x2E77,
               35: 0x2D83, 100: 0x6041, 101: 0x6044}


@pytest.mark.parametrize("code,index", sorted(SCANNER_IN.items()))
def test_scanner_input_objects(od, code, index):
    """§3.2 C001 codes / §4.4 footnote: scanner input objects exist, are writable and PDO mappable."""
    v = od[index]
    assert v.pdo_mappable and v.access_type in ("rw", "rww", "wo")


@pytest.mark.parametrize("code,index", sorted(SCANNER_OUT.items()))
def test_scanner_output_objects(od, code, index):
    """§3.2 C021 codes / §4.4 footnote: scanner output objects exist, are readable and PDO mappable."""
    v = od[index]
    assert v.pdo_mappable and v.access_type in ("ro", "rw", "rwr")


def test_parameter_areas_sdo_only(od):
    """§4.4: 0x3000-0x3F99 and 0x4000-0x4F99 are SDO only (not PDO mappable)."""
    for obj in od.values():
        if 0x3000 <= obj.index <= 0x4FFF:
            assert not obj.pdo_mappable, hex(obj.index)


def test_manufacturer_objects_are_16_bit_sub0(od):
    """§4.4/§8.9: drive parameters are single 16-bit words (TwinCAT WORD variables) at sub-index 0."""
    for obj in od.values():
        if 0x2000 <= obj.index <= 0x4FFF:
            assert isinstance(obj, canopen.objectdictionary.ODVariable), hex(obj.index)
            assert obj.subindex == 0
            assert obj.data_type in (dt.UNSIGNED16, dt.INTEGER16), hex(obj.index)


# --------------------------------------------------------------------------- §3.1 / §3.2 parameters
@pytest.mark.parametrize("index,lo,hi", [
    (0x2003, 0, 4),      # CMOd 0..4 (§3.1)
    (0x2004, 0, 11),     # FMOd 0..11 (§3.1)
    (0x2856, 1, 8),      # F856 1 = 2 poles .. 8 = 16 poles (§3.1)
    (0x2899, 0, 1),      # F899 (§3.1)
    (0x4100, 0, 1000),   # C100 0.0-100.0 s in 0.1 s (§3.2, §3.3.1)
    (0x4101, 0, 5),      # C101 (§3.2)
    (0x4102, 0, 15),     # C102 (§3.2)
    (0x4103, 0, 2),      # C103 (§3.2)
    (0x4401, 0, 65535),  # C401 (§3.2)
    (0x4402, 0, 65535),  # C402 (§3.2)
] + [(0x4000 + i, 0, 101) for i in range(1, 7)] + [(0x4020 + i, 0, 101) for i in range(1, 7)])
def test_parameter_ranges(od, index, lo, hi):
    """§3.1/§3.2: printed setting ranges."""
    assert (od[index].min, od[index].max) == (lo, hi)


@pytest.mark.parametrize("index,default", [
    (0x4001, 100), (0x4002, 101),                 # C001 CMD, C002 LFRD
    (0x4021, 100), (0x4022, 101),                 # C021 ETA, C022 RFRD
    (0x4103, 0),                                  # C103
    (0x4401, 0),                                  # C401
    (0x4410, 0x6040), (0x4411, 0x6042), (0x4412, 0), (0x4413, 0), (0x4414, 0), (0x4415, 0),
    (0x4416, 0x6041), (0x4417, 0x6044), (0x4418, 0), (0x4419, 0), (0x4420, 0), (0x4421, 0),
])
def test_parameter_defaults(od, index, default):
    """§3.2: printed defaults of C001/C002/C021/C022/C103/C401 and C410-C421."""
    assert od[index].default == default


@pytest.mark.parametrize("index", [0x4041 + i for i in range(6)] + [0x4061 + i for i in range(6)]
                         + [0x4400, 0x4402])
def test_monitor_parameters_read_only(od, index):
    """§3.2 footnote *3: C041-C046, C061-C066, C400, C402 are monitor data."""
    assert od[index].access_type == "ro"


@pytest.mark.parametrize("index", [0x2003, 0x2004, 0x2856, 0x2899, 0x4100, 0x4101, 0x4102, 0x4103, 0x4401]
                         + [0x4410 + i for i in range(6)] + [0x4416, 0x4417, 0x4418, 0x4419, 0x4420, 0x4421])
def test_setting_parameters_writable(od, index):
    """§3.1/§3.2: setting parameters are written by the master."""
    assert od[index].access_type == "rw"


def test_f856_default_four_poles(od):
    """§8.14: 1500 min-1 displays 50.0 Hz, i.e. 4 poles -> F856 = 2 (1 = 2 poles, 2 = 4 poles, §3.1)."""
    assert od[0x2856].default == 2


# --------------------------------------------------------------------------- §5.2 Toshiba profile objects
@pytest.mark.parametrize("index", [0x2A06, 0x2A07, 0x2A23, 0x2A50, 0x2A51])
def test_toshiba_command_words(od, index):
    """§5.2.1.1-§5.2.1.5: FA06/FA07/FA23/FA50/FA51 are written commands, u16, PDO mappable."""
    v = od[index]
    assert v.access_type == "rw" and v.pdo_mappable and v.data_type == dt.UNSIGNED16


@pytest.mark.parametrize("index", [0x2D01, 0x2C91, 0x2D00, 0x2D03, 0x2D06, 0x2D07, 0x2E14, 0x2E40])
def test_toshiba_monitor_words(od, index):
    """§5.2.1.6-§5.2.1.14: FD01/FC91/FD00/FD03/FD06/FD07/FE14/FE40 are read-only monitors."""
    v = od[index]
    assert v.access_type == "ro" and v.pdo_mappable


def test_fa51_range(od):
    """§5.2.1.5: FM analog output data 0 to 1000 (10 bit)."""
    assert (od[0x2A51].min, od[0x2A51].max) == (0, 1000)


@pytest.mark.parametrize("index,dtype,lo,hi", [
    (0x2E35, dt.UNSIGNED16, 0x0000, 0x2710),   # VIA
    (0x2E36, dt.INTEGER16, -10000, 10000),     # VIB signed 0xD8F0..0x2710
    (0x2E37, dt.UNSIGNED16, 0x0000, 0x2710),   # VIC
    (0x2E40, dt.UNSIGNED16, 0, 10000),         # FE40 (§5.2.1.11)
])
def test_analog_monitor_ranges(od, index, dtype, lo, hi):
    """§5.2.1.9/§5.2.1.11: VIA/VIC unsigned 0..0x2710, VIB signed 0xD8F0..0x2710, FE40 0..10000."""
    v = od[index]
    assert v.data_type == dtype
    assert (v.min, v.max) == (lo, hi)


# --------------------------------------------------------------------------- §4.5 CiA 402
CIA402 = [
    # index, sub, type, access, pdo, default
    (0x603F, 0, dt.UNSIGNED16, "ro", False, 0x0000),
    (0x6040, 0, dt.UNSIGNED16, "rw", True, 0x0000),
    (0x6041, 0, dt.UNSIGNED16, "ro", True, 0x0000),
    (0x6042, 0, dt.INTEGER16, "rw", True, 0),
    (0x6043, 0, dt.INTEGER16, "ro", False, 0),
    (0x6044, 0, dt.INTEGER16, "ro", True, 0),
    (0x6046, 0, dt.UNSIGNED8, "ro", False, 0x02),
    (0x6046, 1, dt.UNSIGNED32, "rw", False, 0x00000000),
    (0x6046, 2, dt.UNSIGNED32, "rw", False, 0x000005DC),
    (0x6048, 0, dt.UNSIGNED8, "ro", False, 0x02),
    (0x6048, 1, dt.UNSIGNED32, "rw", False, 0x000005DC),
    (0x6048, 2, dt.UNSIGNED16, "rw", False, 0x000A),
    (0x6049, 0, dt.UNSIGNED8, "ro", False, 0x02),
    (0x6049, 1, dt.UNSIGNED32, "rw", False, 0x000005DC),
    (0x6049, 2, dt.UNSIGNED16, "rw", False, 0x000A),
    (0x604A, 0, dt.UNSIGNED8, "ro", False, 0x02),
    (0x604A, 1, dt.UNSIGNED32, "rw", False, 0x000005DC),
    (0x604A, 2, dt.UNSIGNED16, "rw", False, 0x0006),
    (0x605A, 0, dt.INTEGER16, "rw", False, 2),
    (0x6502, 0, dt.UNSIGNED32, "ro", False, 0x00000002),
    (0x6060, 0, dt.INTEGER8, "rw", False, 2),
    (0x6061, 0, dt.INTEGER8, "ro", False, 2),
]


@pytest.mark.parametrize("index,sub,dtype,access,pdo,default", CIA402)
def test_cia402_table(od, index, sub, dtype, access, pdo, default):
    """§4.5 Application Profile table: type, access, PDO mapping, default of every entry."""
    obj = od[index]
    v = obj[sub] if not isinstance(obj, canopen.objectdictionary.ODVariable) else obj
    assert v.data_type == dtype
    assert v.access_type == access
    assert v.pdo_mappable == pdo
    assert v.default == default


@pytest.mark.parametrize("index", [0x6048, 0x6049, 0x604A])
def test_ramp_delta_speed_range(od, index):
    """§6.1.10-§6.1.12: delta speed 225 to 30,000 min-1."""
    assert (od[index][1].min, od[index][1].max) == (225, 30000)


@pytest.mark.parametrize("index", [0x6048, 0x6049, 0x604A])
def test_ramp_delta_time_range(od, index):
    """§6.1.10-§6.1.12: delta time 0.1 to 3,600 s on a u16 in s -> 1..3600 (NOTES Choices)."""
    assert (od[index][2].min, od[index][2].max) == (1, 3600)


def test_quick_stop_option_range(od):
    """§6.1.13: value table spans -32768 .. +32767."""
    assert (od[0x605A].min, od[0x605A].max) == (-32768, 32767)


def test_record_sub_counts(od):
    """§4.5: 6046/6048/6049/604A have sub 0..2; §4.1: 1018 has sub 0..4."""
    for idx in (0x6046, 0x6048, 0x6049, 0x604A):
        assert sorted(od[idx].subindices) == [0, 1, 2]
    assert sorted(od[0x1018].subindices) == [0, 1, 2, 3, 4]


# --------------------------------------------------------------------------- added CAN objects (NOTES)
@pytest.mark.parametrize("index,sub,value", [
    (0x1400, 1, 0x200 + NODE_ID),   # RPDO1 COB-ID, CiA 301 pre-defined connection set
    (0x1400, 2, 0xFF),
    (0x1400, 5, 0),
    (0x1800, 1, 0x180 + NODE_ID),   # TPDO1 COB-ID
    (0x1800, 2, 0xFF),
    (0x1800, 3, 0x001E),            # as VF-S15 CANopen manual §4.1.5 OD table
    (0x1800, 5, 0x0064),
    (0x1200, 1, 0x600 + NODE_ID),
    (0x1200, 2, 0x580 + NODE_ID),
    (0x1016, 1, 0),
])
def test_added_can_objects_defaults(od, index, sub, value):
    """NOTES 'Added objects': CANopen default COB-IDs and PDO parameters for the CAN transport."""
    assert od[index][sub].default == value


@pytest.mark.parametrize("index,value", [(0x1014, 0x80 + NODE_ID), (0x1005, 0x80), (0x1017, 0)])
def test_added_can_variables(od, index, value):
    """NOTES 'Added objects': EMCY COB-ID (node relative), SYNC COB-ID, heartbeat producer off."""
    assert od[index].default == value


def test_added_cob_ids_are_node_relative(od):
    """CiA 301 pre-defined connection set: the COB-ID defaults are written $NODEID+..."""
    assert od[0x1400][1].relative and od[0x1800][1].relative and od[0x1014].relative


# --------------------------------------------------------------------------- §6.2 faults
MANUAL_603F = {
    0x0E: 0x1000, 0x15: 0x1000, 0x16: 0x1000, 0x17: 0x1000, 0x1A: 0x1000, 0x1C: 0x1000, 0x28: 0x1000,
    0x35: 0x1000, 0x3A: 0x1000, 0x55: 0x1000, 0x56: 0x1000,
    0x05: 0x2230, 0x01: 0x2310, 0x02: 0x2310, 0x03: 0x2310, 0x20: 0x2311, 0x41: 0x2311, 0x48: 0x2311,
    0x04: 0x2320, 0x22: 0x2330, 0x0A: 0x3110, 0x0B: 0x3110, 0x0C: 0x3110, 0x1E: 0x3120, 0x08: 0x3130,
    0x09: 0x3310, 0x0F: 0x3310, 0x47: 0x3310, 0x0D: 0x4210, 0x10: 0x4210, 0x3E: 0x4210,
    0x12: 0x5530, 0x13: 0x5530, 0x14: 0x5530, 0x29: 0x5530, 0x33: 0x6100, 0x37: 0x6100,
    0x2E: 0x7300, 0x32: 0x7300, 0x40: 0x7300, 0x2D: 0x7310, 0x18: 0x7510, 0x1B: 0x7520,
    0x2F: 0x8331, 0x34: 0x8331, 0x45: 0x8501, 0x11: 0x9000, 0x1D: 0xFF03, 0x3B: 0xFF03, 0x49: 0xFF03,
}


@pytest.fixture(scope="module")
def fault_rows():
    with FAULTS.open(newline="", encoding="utf-8") as f:
        reader = csv.DictReader(f)
        assert reader.fieldnames == ["trip_code", "trip_name", "emcy_code", "error_register_bit",
                                     "description", "section"]
        return list(reader)


def test_fault_table_complete(fault_rows):
    """§6.2: every drive trip code of the 603F table appears exactly once (0x54 printed twice)."""
    codes = [int(r["trip_code"], 16) for r in fault_rows]
    assert len(codes) == len(set(codes))
    assert set(codes) == set(MANUAL_603F) | {0x54}


@pytest.mark.parametrize("trip,emcy", sorted(MANUAL_603F.items()))
def test_fault_emcy_code(fault_rows, trip, emcy):
    """§6.2: trip code -> 603F/EMCY error code."""
    row = next(r for r in fault_rows if int(r["trip_code"], 16) == trip)
    assert int(row["emcy_code"], 16) == emcy


def test_fault_0x54_choice(fault_rows):
    """§6.2 prints Etn1 (0x54) under 0x1000 and 0xFF00; 0xFF00 chosen (NOTES Choices)."""
    row = next(r for r in fault_rows if int(r["trip_code"], 16) == 0x54)
    assert int(row["emcy_code"], 16) == 0xFF00


def test_network_error_trip(fault_rows):
    """§3.3.1: C101 = 4 'Network error stop' trips Err8 = 0x001B; §6.2: 0x1B -> 0x7520."""
    row = next(r for r in fault_rows if int(r["trip_code"], 16) == 0x1B)
    assert row["trip_name"] == "Err8" and int(row["emcy_code"], 16) == 0x7520


def test_emergency_stop_trip(fault_rows):
    """§5.2.1.1 FA06 bit 12 ('E' trip) and §6.2: E = 0x11 -> 0x9000."""
    row = next(r for r in fault_rows if int(r["trip_code"], 16) == 0x11)
    assert row["trip_name"] == "E" and int(row["emcy_code"], 16) == 0x9000


def test_fault_error_register_bit(fault_rows):
    """§4.1: 0x1001 is 'Error (= 1) or no error (= 0)' -> only bit 0 is used."""
    assert {r["error_register_bit"] for r in fault_rows} == {"0"}
