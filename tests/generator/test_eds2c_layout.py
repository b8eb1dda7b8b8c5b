"""The value block layout of the GENERATED TABLES (read back through tools/od2eds.c): regions as
od.h orders them, natural alignment, no overlap, the persistence rule of eds2c.py checked against
the original EDS, flags, limits and the layout hash as documented."""

import struct

import pytest

from eds2c_testlib import OD_CASES, TYPE_INFO, layout_of, load_od, raw_sections, variables

NOT_STORED_COMM = {0x1001, 0x1003, 0x1010, 0x1011}


def natural_align(code, size):
    if TYPE_INFO[code][0] is None or size <= 1:
        return 1
    return 2 if size == 2 else 4 if size <= 4 else 8


def fnv1a(data, h):
    for b in data:
        h = ((h ^ b) * 0x01000193) & 0xFFFFFFFF
    return h


@pytest.mark.parametrize("od_id", OD_CASES)
def test_layout(od_id, exported):
    eds, _, _, out = exported(od_id)
    info, subs = layout_of(out)
    orig = variables(load_od(eds)[0])
    raw = raw_sections(eds)
    sub_keys = {(k[0], k[1]) for k in raw if k[2] == "sub"}
    assert set(subs) == set(orig)
    comm, persist, size = info["comm_persist_size"], info["persist_size"], info["value_size"]
    assert 0 <= comm <= persist <= size and size % 8 == 0

    used = []
    for key, s in sorted(subs.items()):
        var = orig[key]
        where = f"0x{key[0]:04X} sub {key[1]}"
        index = key[0]
        # size
        tsize, kind = TYPE_INFO[var.data_type]
        if kind == "domain":
            assert s["size"] == 0 and s["offset"] == 0, where
        elif tsize is not None:
            assert s["size"] == tsize, where
        elif kind == "ostring":
            assert s["size"] == len(var.default), where
        else:  # VISIBLE_STRING / UNICODE_STRING: capacity >= default (32 unless '; capacity:')
            enc = (var.default or "").encode("ascii" if kind == "vstring" else "utf-16-le")
            assert s["size"] >= len(enc), where
        # persistence rule (eds2c.py docstring), from the original EDS
        access = var.access_type.lower()
        want = (access in ("rw", "rww", "rwr") and not var.pdo_mappable and kind != "domain"
                and ((0x1000 <= index <= 0x1FFF and index not in NOT_STORED_COMM)
                     or 0x2000 <= index <= 0x9FFF))
        assert ("PERSIST" in s["flags"]) == want, f"{where}: PERSIST should be {want}"
        # region and alignment
        if s["size"]:
            lo, hi = s["offset"], s["offset"] + s["size"]
            if want and index < 0x2000:
                assert hi <= comm, f"{where} outside [0, comm_persist_size)"
            elif want:
                assert comm <= lo and hi <= persist, f"{where} outside the application region"
            else:
                assert persist <= lo and hi <= size, f"{where} outside the never-stored region"
            assert lo % natural_align(var.data_type, s["size"]) == 0, f"{where} misaligned"
            used.append((lo, hi, where))
        # flags from AccessType + PDOMapping
        f = s["flags"]
        assert ("READ" in f) == (access != "wo"), where
        assert ("WRITE" in f) == (access in ("wo", "rw", "rww", "rwr")), where
        assert ("CONST" in f) == (access == "const"), where
        pdo = var.pdo_mappable
        assert ("TPDO" in f) == (pdo and access in ("ro", "const", "rw", "rwr")), where
        assert ("RPDO" in f) == (pdo and access in ("wo", "rw", "rww")), where
        assert ("NODEID" in f) == bool(var.relative), where
        sec = raw[(key[0], key[1], "obj" if (key[0], key[1]) not in sub_keys else "sub")]
        ranged = bool(sec.get("LowLimit") or sec.get("HighLimit"))
        assert ("LIMITS" in f) == ranged, f"{where}: LIMITS should be {ranged}"
        assert s["limit"] < info["limit_count"] if ranged else s["limit"] == 0, where
    used.sort()
    for (a0, a1, wa), (b0, b1, wb) in zip(used, used[1:]):
        assert a1 <= b0, f"{wa} overlaps {wb}"

    # layout hash as documented in eds2c.py
    h = 0x811C9DC5
    for key in sorted(k for k, s in subs.items() if "PERSIST" in s["flags"]):
        s = subs[key]
        h = fnv1a(struct.pack("<HBBIH", key[0], key[1], orig[key].data_type, s["offset"],
                              s["size"]), h)
    h = fnv1a(struct.pack("<II", comm, persist), h)
    assert h == info["layout_hash"]


def test_layout_hash_changes_with_the_persistent_layout(tmp_path):
    """Adding a persistent parameter changes the hash; changing only a default does not."""
    from eds2c_testlib import FIXTURES, export, generate

    base = (FIXTURES / "ok_minimal.eds").read_text()
    variants = {
        "same": base,
        "default": base.replace("DefaultValue=abc", "DefaultValue=xyz"),
        "type": base.replace("[1017]\nParameterName=Producer heartbeat time\nObjectType=0x7\n"
                             "DataType=0x0006", "[1017]\nParameterName=Producer heartbeat time\n"
                             "ObjectType=0x7\nDataType=0x0007"),
    }
    hashes = {}
    for name, text in variants.items():
        d = tmp_path / name
        d.mkdir()
        (d / "v.eds").write_text(text)
        c, _ = generate(d / "v.eds", "v", d)
        info, _ = layout_of(export(c, "v", d))
        hashes[name] = info["layout_hash"]
    assert variants["type"] != base
    assert hashes["same"] == hashes["default"]
    assert hashes["same"] != hashes["type"]
