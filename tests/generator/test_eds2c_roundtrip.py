"""Round trip: original EDS -> eds2c.py -> C tables -> od2eds.c -> exported EDS. Both EDS files are
loaded with python-canopen (what masters use) and compared object by object: object kind, the set
of sub-indices, names, data type, access, PDO mapping, default, $NODEID-relativity and limits.
Runs for od/test/test.eds and for every drive EDS (skipped, with the reason, while a drive's EDS
does not exist yet; CANOPEN_REQUIRE_ALL_OD=1 makes that a failure)."""

import struct

import pytest

from eds2c_testlib import (OD_CASES, TYPE_INFO, load_od, parse_bound, raw_sections, type_bounds,
                           variables)


def norm_access(var):
    a = var.access_type.lower()
    if a in ("rww", "rwr") and not var.pdo_mappable:
        return "rw"  # without PDOMapping=1 these are plain rw (see eds2c.py FLAGS)
    return a


def norm_default(var):
    size, kind = TYPE_INFO[var.data_type]
    d = var.default
    if kind == "domain":
        return None
    if kind == "real":
        return struct.pack("<f" if size == 4 else "<d", d if d is not None else 0.0)
    if kind in ("vstring", "ustring"):
        return d or ""
    if kind == "ostring":
        return bytes(d or b"")
    return d if d is not None else 0


def canopen_limits(var):
    """python-canopen's min/max; a missing one beside a present one is the type's bound (the
    tables store both bounds, so "no LowLimit" and "LowLimit = type minimum" are the same)."""
    if var.min is None and var.max is None:
        return None
    tlo, thi = type_bounds(var.data_type)
    return (tlo if var.min is None else var.min, thi if var.max is None else var.max)


def effective_limits(section, code):
    """(low, high) with a missing bound replaced by the type's bound; None if no limits."""
    low, high = section.get("LowLimit") or None, section.get("HighLimit") or None
    if low is None and high is None:
        return None
    tlo, thi = type_bounds(code)
    return (tlo if low is None else parse_bound(low, code),
            thi if high is None else parse_bound(high, code))


@pytest.mark.parametrize("od_id", OD_CASES)
def test_roundtrip(od_id, exported):
    eds, _, _, out = exported(od_id)
    import canopen.objectdictionary as cod

    orig, _ = load_od(eds)
    back, warns = load_od(out)
    assert warns == [], f"exported EDS makes python-canopen warn: {warns}"

    # objects: same indices, same kind, same names
    oi = [i for i in orig.indices if i >= 0x1000]
    bi = [i for i in back.indices if i >= 0x1000]
    assert sorted(oi) == sorted(bi), (f"missing {sorted(set(oi) - set(bi))}, "
                                      f"extra {sorted(set(bi) - set(oi))}")
    for index in oi:
        a, b = orig.indices[index], back.indices[index]
        assert type(a) is type(b), f"0x{index:04X}: {type(a).__name__} became {type(b).__name__}"
        assert a.name == b.name, f"0x{index:04X}: name"
        if not isinstance(a, cod.ODVariable):
            assert sorted(a.subindices) == sorted(b.subindices), f"0x{index:04X}: sub-indices"

    va, vb = variables(orig), variables(back)
    assert list(va) == list(vb)
    raw_a, raw_b = raw_sections(eds), raw_sections(out)
    compared = 0
    for key, a in va.items():
        b = vb[key]
        where = f"0x{key[0]:04X} sub {key[1]}"
        assert a.name == b.name, f"{where}: name"
        assert a.data_type == b.data_type, f"{where}: data type"
        assert norm_access(a) == b.access_type, \
            f"{where}: access {a.access_type} -> {b.access_type}"
        assert a.pdo_mappable == b.pdo_mappable, f"{where}: PDOMapping"
        assert a.relative == b.relative, f"{where}: $NODEID-relative"
        assert norm_default(a) == norm_default(b), \
            f"{where}: default {a.default!r} -> {b.default!r}"
        if TYPE_INFO[a.data_type][1] != "real":
            # python-canopen reads REAL limits with int(): "10.0" is dropped but "10" is not, so
            # its view of them depends on spelling; they are compared as written just below.
            assert canopen_limits(a) == canopen_limits(b), \
                f"{where}: python-canopen limits {a.min}..{a.max} -> {b.min}..{b.max}"
        # LowLimit/HighLimit as written (python-canopen drops REAL and 24/40/48/56-bit ones)
        sec_kind = "obj" if isinstance(a.parent, cod.ObjectDictionary) else "sub"
        la = effective_limits(raw_a[(key[0], key[1], sec_kind)], a.data_type)
        lb = effective_limits(raw_b[(key[0], key[1], sec_kind)], b.data_type)
        assert la == lb, f"{where}: limits {la} -> {lb}"
        compared += 1
    assert compared == len(va) > 0
