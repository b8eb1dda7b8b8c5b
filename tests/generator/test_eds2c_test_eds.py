"""od/test/test.eds holds what the core's unit tests rely on (the list in its header comment).
These assertions are written from that list, not read back from the file."""

import pytest

import canopen.objectdictionary as cod

from eds2c_testlib import TEST_EDS, layout_of, load_od, variables

NODE = 5


@pytest.fixture(scope="module")
def od():
    od, warns = load_od(TEST_EDS, node_id=NODE)
    assert warns == [], warns
    return od


def var(od, index, sub=0):
    obj = od[index]
    return obj if isinstance(obj, cod.ODVariable) else obj.subindices[sub]


def check(od, index, sub, dtype, access, pdo=False, default=None):
    v = var(od, index, sub)
    assert (v.data_type, v.access_type, v.pdo_mappable) == (dtype, access, pdo), \
        f"0x{index:04X} sub {sub}"
    if default is not None:
        assert v.default == default, f"0x{index:04X} sub {sub}: {v.default!r}"


def test_cia301_communication_objects(od):
    check(od, 0x1000, 0, 0x07, "ro")
    check(od, 0x1001, 0, 0x05, "ro", True)  # TPDO-mappable error register
    assert isinstance(od[0x1003], cod.ODArray) and sorted(od[0x1003].subindices) == list(range(9))
    check(od, 0x1003, 0, 0x05, "rw", default=0)
    check(od, 0x1005, 0, 0x07, "rw", default=0x80)
    check(od, 0x1008, 0, 0x09, "const")
    for index, dtype in ((0x1009, 0x09), (0x100A, 0x09), (0x100C, 0x06), (0x100D, 0x05),
                         (0x1015, 0x06), (0x1017, 0x06), (0x1019, 0x05)):
        assert var(od, index).data_type == dtype, hex(index)
    for index in (0x1010, 0x1011):
        assert sorted(od[index].subindices) == [0, 1, 2, 3, 4]
    check(od, 0x1014, 0, 0x07, "rw", default=0x80 + NODE)
    assert var(od, 0x1014).relative
    assert sorted(od[0x1016].subindices) == [0, 1, 2, 3, 4]
    assert sorted(od[0x1018].subindices) == [0, 1, 2, 3, 4]
    assert 0x1029 in od
    check(od, 0x1200, 1, 0x07, "ro", default=0x600 + NODE)
    check(od, 0x1200, 2, 0x07, "ro", default=0x580 + NODE)


def test_pdo_defaults_follow_the_cia301_predefined_connection_set(od):
    for n in range(4):
        rx, tx = var(od, 0x1400 + n, 1).default, var(od, 0x1800 + n, 1).default
        assert rx & 0x7FF == 0x200 + 0x100 * n + NODE
        assert tx & 0x7FF == 0x180 + 0x100 * n + NODE
        assert bool(rx & 0x80000000) == (n > 0) and bool(tx & 0x80000000) == (n > 0)
        assert 0x1600 + n in od and 0x1A00 + n in od
    assert var(od, 0x1600, 1).default == 0x60400010
    assert var(od, 0x1A00, 1).default == 0x60410010


def test_every_basic_type_and_access_type_in_the_application_area(od):
    app = [v for (i, _), v in variables(od).items() if 0x2000 <= i <= 0x20FF]
    types = {v.data_type for v in app}
    # BOOLEAN, INTEGER8/16/24/32/64, UNSIGNED8/16/24/32/64, REAL32/64, VISIBLE/OCTET_STRING, DOMAIN
    assert {0x01, 0x02, 0x03, 0x10, 0x04, 0x15, 0x05, 0x06, 0x16, 0x07, 0x1B, 0x08, 0x11, 0x09,
            0x0A, 0x0F} <= types
    assert {"ro", "wo", "rw", "rww", "rwr", "const"} <= {v.access_type for v in app}
    ranged = [v for v in app if v.max is not None]
    assert any(v.data_type in (0x02, 0x03, 0x04) and v.min < 0 for v in ranged), "signed range"
    assert any(v.data_type in (0x05, 0x06, 0x07) for v in ranged), "unsigned range"
    sizes = {len(v) for v in app if v.pdo_mappable}
    assert {8, 16, 32} <= sizes
    assert any(isinstance(od[i], cod.ODRecord) for i in range(0x2000, 0x2100) if i in od)
    assert any(isinstance(od[i], cod.ODArray) for i in range(0x2000, 0x2100) if i in od)


def test_cia402_objects(od):
    check(od, 0x6040, 0, 0x06, "rww", True)
    check(od, 0x6041, 0, 0x06, "ro", True)
    check(od, 0x6042, 0, 0x03, "rww", True)
    assert (var(od, 0x6042).min, var(od, 0x6042).max) == (-32768, 32767)
    check(od, 0x6043, 0, 0x03, "ro", True)
    check(od, 0x6044, 0, 0x03, "ro", True)
    for index, types in ((0x6046, (0x07, 0x07)), (0x6048, (0x07, 0x06)), (0x6049, (0x07, 0x06))):
        assert [var(od, index, s).data_type for s in (1, 2)] == list(types), hex(index)
    check(od, 0x605A, 0, 0x03, "rw")
    assert (var(od, 0x605A).min, var(od, 0x605A).max) == (-2, 7)


def test_persistence_in_the_generated_tables(exported):
    """What 0x1010 stores, read from the generated tables."""
    _, _, _, out = exported("test")
    _, subs = layout_of(out)
    persistent = {k for k, s in subs.items() if "PERSIST" in s["flags"]}
    for key in ((0x1005, 0), (0x100C, 0), (0x1014, 0), (0x1017, 0), (0x1016, 1), (0x1400, 1),
                (0x1600, 0), (0x1600, 1), (0x1A00, 1), (0x1800, 5), (0x1029, 1), (0x2022, 0),
                (0x200D, 0), (0x6046, 2), (0x6048, 1), (0x605A, 0)):
        assert key in persistent, f"0x{key[0]:04X} sub {key[1]} must be stored"
    for key in ((0x1000, 0), (0x1001, 0), (0x1003, 0), (0x1010, 1), (0x1011, 1), (0x1018, 1),
                (0x1200, 1), (0x2010, 0), (0x2020, 0), (0x2021, 0), (0x2023, 0), (0x2024, 0),
                (0x2025, 0), (0x2026, 0), (0x6040, 0), (0x6041, 0), (0x6042, 0), (0x6044, 0)):
        assert key not in persistent, f"0x{key[0]:04X} sub {key[1]} must not be stored"
    assert subs[(0x200E, 0)]["size"] == 16, "'; capacity: 16'"
    assert subs[(0x200D, 0)]["size"] == 32, "default capacity"
    assert subs[(0x2010, 0)]["size"] == 0, "DOMAIN has no value"
    assert subs[(0x2070, 0)]["limit"] == subs[(0x2022, 0)]["limit"], "limits are deduplicated"
