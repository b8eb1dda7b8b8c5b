"""Tests for od/vacon-optc6/vacon-optc6.eds (VACON NX OPTC6 CANopen option board).

Every expected value below is copied from the manual
"VACON NX AC Drives, OPTC6 CANopen Option Board User Manual" (DPD00896B) (DPD00896B Rev. B); section numbers ("§8", "Tab. 7-2", ...)
are the manual's own.  Values that are project choices (not printed in the manual) are marked "choice" and
refer to od/vacon-optc6/NOTES.md.
"""
import configparser
import csv
import logging
import re
from pathlib import Path

import canopen
import pytest
from canopen.objectdictionary import datatypes as dt

ROOT = Path(__file__).resolve().parents[2]
DIR = ROOT / "od" / "vacon-optc6"
EDS = DIR / "vacon-optc6.eds"
NODE = 5

U8, U16, U32 = dt.UNSIGNED8, dt.UNSIGNED16, dt.UNSIGNED32
I8, I16 = dt.INTEGER8, dt.INTEGER16


@pytest.fixture(scope="module")
def od():
    return canopen.objectdictionary.import_od(str(EDS), node_id=NODE)


@pytest.fixture(scope="module")
def raw():
    cp = configparser.RawConfigParser(inline_comment_prefixes=(";",))
    cp.optionxform = str
    cp.read(EDS, encoding="utf-8")
    return cp


def check(var, data_type, access, default, lo=None, hi=None):
    assert var.data_type == data_type, var.name
    assert var.access_type == access, var.name
    assert var.default == default, var.name
    if lo is not None:
        assert var.min == lo, var.name
    if hi is not None:
        assert var.max == hi, var.name


# ---------------------------------------------------------------- loading / file conventions

def test_loads_without_warning(caplog):
    """CiA 306 file loads in python-canopen with nothing logged at WARNING or above."""
    with caplog.at_level(logging.WARNING):
        o = canopen.objectdictionary.import_od(str(EDS), node_id=NODE)
    assert len(o) == 66
    assert [r for r in caplog.records if r.levelno >= logging.WARNING] == []


def test_every_object_section_has_source_comment():
    """Convention: every [XXXX] object section is preceded by '; source:' comment lines naming §-sections."""
    lines = EDS.read_text(encoding="utf-8").splitlines()
    for i, line in enumerate(lines):
        if re.fullmatch(r"\[[0-9A-F]{4}\]", line):
            j = i - 1
            block = []
            while j >= 0 and lines[j].startswith(";"):
                block.append(lines[j])
                j -= 1
            assert block, line
            assert any(b.startswith("; source:") and "§" in b for b in block), line


def test_object_lists_cover_all_sections(raw):
    """[Mandatory/Optional/ManufacturerObjects] list exactly the object sections present."""
    listed = []
    for sec in ("MandatoryObjects", "OptionalObjects", "ManufacturerObjects"):
        n = int(raw.get(sec, "SupportedObjects"))
        listed += [int(raw.get(sec, str(i)), 0) for i in range(1, n + 1)]
    present = [int(s, 16) for s in raw.sections() if re.fullmatch(r"[0-9A-F]{4}", s)]
    assert sorted(listed) == sorted(present)
    assert [int(raw.get("MandatoryObjects", str(i)), 0) for i in (1, 2, 3)] == [0x1000, 0x1001, 0x1018]


def test_subnumber_matches_subsections(raw):
    """SubNumber on every ARRAY/RECORD equals the number of [XXXXsubN] sections."""
    for s in raw.sections():
        if re.fullmatch(r"[0-9A-F]{4}", s) and raw.has_option(s, "SubNumber"):
            subs = [x for x in raw.sections() if x.startswith(s + "sub")]
            assert int(raw.get(s, "SubNumber")) == len(subs), s


# ---------------------------------------------------------------- DeviceInfo

def test_deviceinfo_identity_and_baud_rates(od):
    """§8 1018 (vendor 0x90, product 0x119, revision 1); §2.1 / Tab. 6-1 baud rates (no 800 kBaud)."""
    di = od.device_information
    assert di.vendor_number == 0x90
    assert di.product_number == 0x119
    assert di.revision_number == 1
    assert di.allowed_baudrates == {10000, 20000, 50000, 125000, 250000, 500000, 1000000}
    assert di.simple_boot_up_slave is True
    assert di.LSS_supported is False


def test_deviceinfo_pdo_counts_and_static_mapping(od):
    """§8: five RPDO (1, 6, 21, 22, 23) and five TPDO objects; mapping is static (all mapping subs ro)."""
    di = od.device_information
    assert di.nr_of_RXPDO == 5
    assert di.nr_of_TXPDO == 5
    assert di.granularity is False  # Granularity=0: mapping not modifiable


# ---------------------------------------------------------------- communication profile area

def test_1000_device_type(od):
    """§8 1000: 0x00010192, u32, co."""
    check(od[0x1000], U32, "const", 0x00010192)


def test_1001_error_register(od):
    """§8 1001: u8 ro, default 0x00, range 0x00..0xFF."""
    check(od[0x1001], U8, "ro", 0, 0, 0xFF)


def test_1003_error_history_depth_10(od):
    """§8 1003: sub 00 u8 rw (0..0xFE, default 0), subs 01..0A u32 ro default 0 (10 entries)."""
    arr = od[0x1003]
    assert isinstance(arr, canopen.objectdictionary.ODArray)
    assert sorted(arr.subindices) == list(range(0, 11))
    check(arr[0], U8, "rw", 0, 0, 0xFE)
    for s in range(1, 11):
        check(arr[s], U32, "ro", 0, 0, 0xFFFFFFFF)


def test_1005_sync_cob_id(od):
    """§8 1005: 0x80000080, u32 ro, range 0x00000001..0xFFFFFFFF."""
    check(od[0x1005], U32, "ro", 0x80000080, 1, 0xFFFFFFFF)


def test_100c_100d_node_guarding(od):
    """§8 100C/100D and §9: guard time 1000 ms (u16 rw 0..65535), life time factor 2 (u8 rw 0..255): 2 s."""
    check(od[0x100C], U16, "rw", 1000, 0, 65535)
    check(od[0x100D], U8, "rw", 2, 0, 255)
    assert od[0x100C].default * od[0x100D].default == 2000


def test_1018_identity(od):
    """§8 1018: sub0 = 4 (1..4), vendor 0x90, product 0x119, revision 0x1, serial 0; all u32 ro."""
    rec = od[0x1018]
    check(rec[0], U8, "ro", 4, 1, 4)
    check(rec[1], U32, "ro", 0x00000090)
    check(rec[2], U32, "ro", 0x00000119)
    check(rec[3], U32, "ro", 0x00000001)
    check(rec[4], U32, "ro", 0x00000000)


def test_1200_sdo_server(od):
    """§8 1200: sub0 = 2; 0x600+NodeID / 0x580+NodeID, ro, node relative."""
    rec = od[0x1200]
    check(rec[0], U8, "ro", 2, 2, 2)
    check(rec[1], U32, "ro", 0x600 + NODE, 0x601, 0xFFFFFFFF)
    check(rec[2], U32, "ro", 0x580 + NODE, 0x581, 0xFFFFFFFF)
    assert rec[1].relative and rec[2].relative


def test_absent_objects(od):
    """§8 lists no 0x1008-0x100A, 0x1014, 0x1016, 0x1017, 0x603F, 0x6502: they must not be in the OD."""
    for idx in (0x1002, 0x1008, 0x1009, 0x100A, 0x1010, 0x1014, 0x1016, 0x1017, 0x603F, 0x6502, 0x27D2, 0x2837):
        assert idx not in od, hex(idx)


# ---------------------------------------------------------------- PDO communication parameters

RPDO_BASE = {0x1400: 0x200, 0x1405: 0x300, 0x1414: 0x400, 0x1415: 0x500, 0x1416: 0x300}
TPDO_BASE = {0x1800: 0x180, 0x1805: 0x280, 0x1814: 0x380, 0x1815: 0x480, 0x1816: 0x280}
ACTIVE_DRIVE_PROFILE = {0x1400, 0x1405, 0x1800, 0x1805}  # Tab. 6-1 mode 1 = xPDO1, xPDO6; Tab. 7-1


@pytest.mark.parametrize("idx,base", sorted(RPDO_BASE.items()))
def test_rpdo_comm(od, idx, base):
    """§8 1400/1405/1414/1415/1416: sub0 = 2 (2..5) ro; COB-ID base+NodeID ro; transmission type 0xFF ro."""
    rec = od[idx]
    assert sorted(rec.subindices) == [0, 1, 2]
    check(rec[0], U8, "ro", 2, 2, 5)
    cob = rec[1]
    assert cob.data_type == U32 and cob.access_type == "ro" and cob.relative
    assert cob.default & 0x7FF == base + NODE
    assert cob.min == base + 1 and cob.max == 0xFFFFFFFF
    check(rec[2], U8, "ro", 0xFF, 0, 0xFF)


@pytest.mark.parametrize("idx", sorted(list(RPDO_BASE) + list(TPDO_BASE)))
def test_pdo_valid_bit_follows_default_operate_mode(od, idx):
    """Tab. 6-1 (default Operate mode 1 = xPDO1, xPDO6) + Tab. 7-1; bit 31 on the others (choice, NOTES)."""
    cob = od[idx][1].default
    if idx in ACTIVE_DRIVE_PROFILE:
        assert cob & 0x80000000 == 0
    else:
        assert cob & 0x80000000 == 0x80000000


def test_tpdo1_comm(od):
    """§8 1800 and §7.3: sub0 = 4 (no event timer), COB-ID 0x180+NodeID ro, type 0xFF ro,
    inhibit 0x03E8 (100 ms) rw, compatibility entry 0x03 ro."""
    rec = od[0x1800]
    assert sorted(rec.subindices) == [0, 1, 2, 3, 4]
    check(rec[0], U8, "ro", 4, 2, 5)
    check(rec[1], U32, "ro", 0x180 + NODE, 0x181, 0xFFFFFFFF)
    check(rec[2], U8, "ro", 0xFF, 0, 0xFF)
    check(rec[3], U16, "rw", 0x03E8, 0, 0xFFFF)
    check(rec[4], U8, "ro", 0x03, 0, 0xFF)


@pytest.mark.parametrize("idx", [0x1805, 0x1814, 0x1815, 0x1816])
def test_tpdo_comm_with_event_timer(od, idx):
    """§8 1805/1814/1815/1816 and §7.3: sub0 = 5; COB-ID ro; type 0xFF rw; inhibit 0x03E8 rw (100 us units);
    compatibility 0x03 ro; event timer 0 rw (1 ms units)."""
    rec = od[idx]
    base = TPDO_BASE[idx]
    assert sorted(rec.subindices) == [0, 1, 2, 3, 4, 5]
    check(rec[0], U8, "ro", 5, 2, 5)
    assert rec[1].access_type == "ro" and rec[1].default & 0x7FF == base + NODE
    assert rec[1].min == base + 1
    check(rec[2], U8, "rw", 0xFF, 0, 0xFF)
    check(rec[3], U16, "rw", 0x03E8, 0, 0xFFFF)
    check(rec[4], U8, "ro", 0x03, 0, 0xFF)
    check(rec[5], U16, "rw", 0, 0, 0xFFFF)


# ---------------------------------------------------------------- PDO mapping

MAPPINGS = {
    0x1600: [0x60400010],
    0x1605: [0x60400010, 0x60420010],
    0x1614: [0x27D10010, 0x27D30010, 0x27D40010, 0x27D50010],
    0x1615: [0x27D60010, 0x27D70010, 0x27D80010, 0x27D90010],
    0x1616: [0x27DA0010, 0x27DB0010],
    0x1A00: [0x60410010],
    0x1A05: [0x60410010, 0x60440010],
    0x1A14: [0x28360010, 0x28380010, 0x28390010, 0x283A0010],
    0x1A15: [0x283B0010, 0x283C0010, 0x283D0010, 0x283E0010],
    0x1A16: [0x283F0010, 0x28400010],
}


@pytest.mark.parametrize("idx,entries", sorted(MAPPINGS.items()))
def test_pdo_mapping(od, idx, entries):
    """§8 16xx/1Axx mapping parameters (static, all ro, sub0 range 0..0x40) = §7.5/§7.6 PDO layouts."""
    rec = od[idx]
    check(rec[0], U8, "ro", len(entries), 0, 0x40)
    assert sorted(rec.subindices) == list(range(len(entries) + 1))
    for s, e in enumerate(entries, 1):
        check(rec[s], U32, "ro", e, 0, 0xFFFFFFFF)


@pytest.mark.parametrize("idx,entries", sorted(MAPPINGS.items()))
def test_mapped_objects_exist_and_are_mappable(od, idx, entries):
    """§8: every mapped object exists, is 16 bit (length 0x10) and has PDOMapping=1; RPDO targets are writable."""
    for e in entries:
        target = od[e >> 16]
        assert target.data_type in (U16, I16)
        assert e & 0xFF == 16
        assert target.pdo_mappable
        if idx < 0x1800:
            assert target.access_type == "rw"


def test_python_canopen_pdo_view(od):
    """Tab. 7-1 (node 5): python-canopen sees TPDO1 0x185, TPDO6 0x285, RPDO1 0x205, RPDO6 0x305 enabled;
    PDO21/22/23 disabled in the factory-default Drive Profile mode."""
    net = canopen.Network()
    node = canopen.LocalNode(NODE, od)
    net.add_node(node)
    node.tpdo.read(from_od=True)
    node.rpdo.read(from_od=True)
    assert sorted(node.tpdo.map.maps) == [1, 6, 21, 22, 23]
    assert sorted(node.rpdo.map.maps) == [1, 6, 21, 22, 23]
    assert node.tpdo.map.maps[1].cob_id == 0x185 and node.tpdo.map.maps[1].enabled
    assert node.tpdo.map.maps[6].cob_id == 0x285 and node.tpdo.map.maps[6].enabled
    assert node.rpdo.map.maps[1].cob_id == 0x205 and node.rpdo.map.maps[1].enabled
    assert node.rpdo.map.maps[6].cob_id == 0x305 and node.rpdo.map.maps[6].enabled
    for n in (21, 22, 23):
        assert not node.tpdo.map.maps[n].enabled
        assert not node.rpdo.map.maps[n].enabled
    assert [v.index for v in node.rpdo.map.maps[6].map] == [0x6040, 0x6042]
    assert [v.index for v in node.tpdo.map.maps[6].map] == [0x6041, 0x6044]
    assert node.tpdo.map.maps[6].length == 32  # DLC 4 (§7.5 PDO6 Tx "Len 4")


# ---------------------------------------------------------------- manufacturer area

def test_anyparameter_objects(od):
    """§7.8 and §8 2000-2002: ReadID U16 rw; ReadValue U32 ro (hi Status, lo Value); Write U32 rw (hi ID, lo value)."""
    check(od[0x2000], U16, "rw", 0, 0, 0xFFFF)
    check(od[0x2001], U32, "ro", 0, 0, 0xFFFFFFFF)
    check(od[0x2002], U32, "rw", 0, 0, 0xFFFFFFFF)
    for idx in (0x2000, 0x2001, 0x2002):
        assert not od[idx].pdo_mappable


def test_monitor_objects(od):
    """§8 2003 (u16 ro, 1 = 0.01 A), 2004 (u16 ro, 0..1000 = 0.0..100.0 %), 2063 (i16 ro, 0 = no fault)."""
    check(od[0x2003], U16, "ro", 0, 0, 0xFFFF)
    check(od[0x2004], U16, "ro", 0, 0, 0xFFFF)
    check(od[0x2063], I16, "ro", 0, -32768, 32767)


def test_units_in_comments():
    """§8 2003 '1 = 0.01A', 2004 '0..1000', §7.6 nx_speed_reference 0.01 %, §7.5 vl objects in RPM."""
    text = EDS.read_text(encoding="utf-8")

    def comment_of(idx):
        m = re.search(r"((?:;[^\n]*\n)+)\[%04X\]\n" % idx, text)
        return m.group(1)

    assert "0.01 A" in comment_of(0x2003)
    assert "0.1 %" in comment_of(0x2004)
    assert "0.01 %" in comment_of(0x27D3) and "-10000..10000" in comment_of(0x27D3)
    assert "0..10000" in comment_of(0x2838)
    for idx in (0x6042, 0x6043, 0x6044, 0x6046):
        assert "rpm" in comment_of(idx)
    assert "1 ms" in comment_of(0x100C)
    assert "100 us" in comment_of(0x1805) and "1 ms" in comment_of(0x1805)


@pytest.mark.parametrize("idx", [0x27D1, 0x27D3] + list(range(0x27D4, 0x27DC)))
def test_process_data_in_objects(od, idx):
    """§8 27D1, 27D3..27DB: i16 rw, default 0, range 0x8000..0x7FFF, PDO mapped (§7.6)."""
    check(od[idx], I16, "rw", 0, -32768, 32767)
    assert od[idx].pdo_mappable


@pytest.mark.parametrize("idx", [0x2836] + list(range(0x2838, 0x2841)))
def test_process_data_out_objects(od, idx):
    """§8 2836, 2838..2840: i16 ro, default 0, range 0x8000..0x7FFF, PDO mapped (§7.6)."""
    check(od[idx], I16, "ro", 0, -32768, 32767)
    assert od[idx].pdo_mappable


def test_manufacturer_names(od):
    """§8 names of the NX objects."""
    assert od[0x27D1].name == "NX control word"
    assert od[0x27D3].name == "NX speed reference"
    assert od[0x2836].name == "NX status word"
    assert od[0x2838].name == "NX actual speed"
    assert od[0x2063].name == "NX fault code"
    assert od[0x27D4].name == "Process Data In1" and od[0x27DB].name == "Process Data In8"
    assert od[0x2839].name == "Process data out1" and od[0x2840].name == "Process data out8"


# ---------------------------------------------------------------- device profile area

def test_6040_6041(od):
    """§8 6040 controlword u16 rw, 6041 statusword u16 ro; default 0; 0..0xFFFF; mapped in PDO1/PDO6."""
    check(od[0x6040], U16, "rw", 0, 0, 0xFFFF)
    check(od[0x6041], U16, "ro", 0, 0, 0xFFFF)
    assert od[0x6040].pdo_mappable and od[0x6041].pdo_mappable


def test_vl_velocity_objects(od):
    """§8 6042 (i16 rw), 6043 (i16 ro), 6044 (i16 ro): RPM, range 0x8000..0x7FFF, default 0."""
    check(od[0x6042], I16, "rw", 0, -32768, 32767)
    check(od[0x6043], I16, "ro", 0, -32768, 32767)
    check(od[0x6044], I16, "ro", 0, -32768, 32767)


def test_6046_min_max(od):
    """§8 6046: sub0 = 2 (0..2) ro; min/max speed u32 rw default 0 (rpm)."""
    arr = od[0x6046]
    check(arr[0], U8, "ro", 2, 0, 2)
    check(arr[1], U32, "rw", 0, 0, 0xFFFFFFFF)
    check(arr[2], U32, "rw", 0, 0, 0xFFFFFFFF)


@pytest.mark.parametrize("idx", [0x6048, 0x6049, 0x604A])
def test_ramps(od, idx):
    """§8 6048/6049/604A: sub0 = 2 ro; delta_speed u32 rw default 0; delta_time u16 rw default 1 (0..0xFFFF)."""
    rec = od[idx]
    assert isinstance(rec, canopen.objectdictionary.ODRecord)
    check(rec[0], U8, "ro", 2, 0, 2)
    check(rec[1], U32, "rw", 0, 0, 0xFFFFFFFF)
    check(rec[2], U16, "rw", 1, 0, 0xFFFF)


def test_604e_velocity_reference(od):
    """§8 summary table 604E vl_velocity_reference: Unsigned32 RW (default 0 = choice, NOTES)."""
    assert od[0x604E].data_type == U32 and od[0x604E].access_type == "rw"


def test_6060_6061_velocity_mode(od):
    """§8 6060/6061 and §3/App. A: modes of operation = 2 (velocity mode), i8 ro, range 0x80..0x7F."""
    check(od[0x6060], I8, "ro", 2, -128, 127)
    check(od[0x6061], I8, "ro", 2, -128, 127)


# ---------------------------------------------------------------- modes.csv

def load_modes():
    with open(DIR / "modes.csv", newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


# Tab. 6-1: communication set per Operate mode value
MODE_SETS = {1: {1, 6}, 2: {1, 21, 22}, 3: {1, 21, 22}, 4: {1, 21, 22, 23}, 5: {1, 21, 22, 23}}
MODE_NAMES = {1: "Drive Profile", 2: "ByPass", 3: "ByPass 2", 4: "Bypass 3", 5: "Bypass 4"}
# Tab. 7-1 / Tab. 7-2 COB-ID bases
COB = {("rx", 1): 0x200, ("tx", 1): 0x180, ("rx", 6): 0x300, ("tx", 6): 0x280,
       ("rx", 21): 0x400, ("tx", 21): 0x380, ("rx", 22): 0x500, ("tx", 22): 0x480,
       ("rx", 23): 0x300, ("tx", 23): 0x280}


def cob_value(text, node):
    assert text.startswith("$NODEID+")
    return int(text[len("$NODEID+"):], 0) + node


def test_modes_csv_header_and_size():
    """modes.csv columns; 5 Operate modes (Tab. 6-1) x 10 PDO objects."""
    rows = load_modes()
    assert list(rows[0].keys()) == ["mode_value", "mode_name", "pdo", "direction", "cob_id",
                                    "transmission_type", "mapping", "section"]
    assert len(rows) == 50
    for r in rows:
        assert MODE_NAMES[int(r["mode_value"])] == r["mode_name"]


@pytest.mark.parametrize("mode", [1, 2, 3, 4, 5])
def test_modes_csv_active_sets(mode):
    """Tab. 6-1 sets and Tab. 7-1/7-2 COB-IDs: active PDOs valid at base+node, others bit 31 set."""
    for r in load_modes():
        if int(r["mode_value"]) != mode:
            continue
        n = int(r["pdo"][4:])
        cob = cob_value(r["cob_id"], NODE)
        assert cob & 0x7FF == COB[(r["direction"], n)] + NODE
        assert bool(cob & 0x80000000) == (n not in MODE_SETS[mode]), r
        assert int(r["transmission_type"], 0) == 0xFF


def test_modes_csv_no_cob_id_collision():
    """Tab. 7-1/7-2: in every mode the valid COB-IDs are unique (PDO6 and PDO23 share 0x280/0x300)."""
    for mode in MODE_SETS:
        ids = [cob_value(r["cob_id"], NODE) for r in load_modes() if int(r["mode_value"]) == mode]
        valid = [c for c in ids if not c & 0x80000000]
        assert len(valid) == len(set(valid))


def test_modes_csv_mappings_match_manual():
    """§8 mapping objects: modes.csv mapping column equals the manual's static mapping in every mode."""
    for r in load_modes():
        n = int(r["pdo"][4:])
        idx = (0x1600 if r["direction"] == "rx" else 0x1A00) + n - 1
        assert [int(x, 16) for x in r["mapping"].split()] == MAPPINGS[idx]


def test_modes_csv_mode1_equals_eds_defaults(od):
    """Factory default Operate mode 1 (Tab. 6-1): the EDS defaults equal the mode-1 rows of modes.csv."""
    for r in load_modes():
        if r["mode_value"] != "1":
            continue
        n = int(r["pdo"][4:])
        idx = (0x1400 if r["direction"] == "rx" else 0x1800) + n - 1
        assert od[idx][1].default == cob_value(r["cob_id"], NODE)
        assert od[idx][2].default == int(r["transmission_type"], 0)


# ---------------------------------------------------------------- faults.csv

def load_faults():
    with open(DIR / "faults.csv", newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


def test_faults_header():
    """Convention header of faults.csv."""
    rows = load_faults()
    assert list(rows[0].keys()) == ["trip_code", "trip_name", "emcy_code", "error_register_bit",
                                    "description", "section"]


def test_fault_fieldbus_fault_row():
    """§9 'Fieldbus Fault' on node-guarding life-time expiry; §8 1001 bit 4 = communication error.
    EMCY 0x8130 (CiA 301 life guard) and NX code 53 are choices (NOTES)."""
    rows = {r["trip_name"]: r for r in load_faults()}
    r = rows["Fieldbus Fault"]
    assert int(r["trip_code"]) == 53
    assert int(r["emcy_code"], 16) == 0x8130
    assert int(r["error_register_bit"]) == 4
    assert "§9" in r["section"]


def test_fault_communication_error_rows():
    """§8 1001 bit 4 'communication error (overrun, error state)': overrun and error-state rows, bit 4."""
    rows = {r["trip_name"]: r for r in load_faults()}
    assert int(rows["CAN overrun"]["emcy_code"], 16) == 0x8110
    assert int(rows["CAN error passive"]["emcy_code"], 16) == 0x8120
    for name in ("CAN overrun", "CAN error passive"):
        assert rows[name]["error_register_bit"] == "4"
        assert rows[name]["trip_code"] == ""  # no drive trip: 0x2063 stays 0


def test_fault_rows_well_formed():
    """Every fault row: EMCY code is a 16-bit hex value in a CiA 301 class, bit 0..7, section given."""
    for r in load_faults():
        code = int(r["emcy_code"], 16)
        assert 0x1000 <= code <= 0xFFFF
        assert 0 <= int(r["error_register_bit"]) <= 7
        assert "§" in r["section"]


# ---------------------------------------------------------------- NOTES.md

def test_notes_sections_and_key_behaviour():
    """NOTES.md has the convention headings and the behaviour items the manual states (§7.5, §7.6, §7.8, §9)."""
    text = (DIR / "NOTES.md").read_text(encoding="utf-8")
    for h in ("## Source", "## Addressing rule", "## Choices and contradictions", "## Added objects",
              "## Behaviour", "## Modes/configurations"):
        assert h in text
    for needle in ("0x000F", "0x0006", "0x0007", "Fieldbus Fault", "rising edge", "0xFFFF0000",
                   "RST", "DIR", "Quick stop", "Not Used", "life time"):
        assert needle.lower() in text.lower(), needle
