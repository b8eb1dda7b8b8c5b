"""eds2c --compact: 6-byte sub-entries (od.h CO_CONFIG_OD_COMPACT, what boards/cortex-m4 links).
Every sub-entry must say what the plain output says: the same offset, sub-index, type and flags,
a size its type gives (numbers) or its one byte holds (strings), and the same limits index."""

import re

import pytest

from eds2c_testlib import DRIVES, ROOT, generate_plain_and, run_generator
from eds2c_testlib import sym as od_sym

TYPE_SIZES = {"CO_BOOLEAN": 1, "CO_INTEGER8": 1, "CO_UNSIGNED8": 1, "CO_INTEGER16": 2,
              "CO_UNSIGNED16": 2, "CO_INTEGER24": 3, "CO_UNSIGNED24": 3, "CO_INTEGER32": 4,
              "CO_UNSIGNED32": 4, "CO_REAL32": 4, "CO_INTEGER40": 5, "CO_UNSIGNED40": 5,
              "CO_INTEGER48": 6, "CO_UNSIGNED48": 6, "CO_TIME_OF_DAY": 6,
              "CO_TIME_DIFFERENCE": 6, "CO_INTEGER56": 7, "CO_UNSIGNED56": 7, "CO_INTEGER64": 8,
              "CO_UNSIGNED64": 8, "CO_REAL64": 8}  # as co_type_size() in src/od.c


def sub_rows(text, sym):
    # plain: an array of its own; compact: the subs of one object with the entries
    # (the runs of descriptors after their headers {descriptors})
    m = (re.search(rf"{sym}_subs\[\d+\] = \{{(.*?)\n\}};", text, re.S) or
         re.search(rf"\}} {sym}_tables = \{{\n(.*?)\n    \.entries = \{{", text, re.S))
    assert m
    body = re.sub(r"/\*.*?\*/", "", m.group(1), flags=re.S)
    body = re.sub(r"\{\d+u\},", "", body)
    return [[f.strip() for f in row.split(",")] for row in re.findall(r"\{([^{}]*)\}", body)]


def sub_size(type_name, aux):
    """co_od_sub_size() of a compact sub-entry."""
    return TYPE_SIZES.get(type_name, 0) or aux


@pytest.mark.parametrize("od_id", ("test", "bench") + DRIVES)
def test_compact_sub_entries_say_what_the_plain_ones_say(od_id, tmp_path):
    plain, compact = generate_plain_and(od_id, tmp_path, "compact", "--compact")
    sym = od_sym(od_id)
    text = compact.read_text()
    assert "#if !CO_CONFIG_OD_COMPACT" in text
    rows = sub_rows(plain.read_text(), sym)
    compact_rows = sub_rows(text, sym)
    assert len(rows) == len(compact_rows) > 0
    for (offset, size, limit, subindex, type_name, flags), row in zip(rows, compact_rows):
        c_offset, aux, c_subindex, c_type, c_flags = row
        assert (c_offset, c_subindex, c_type, c_flags) == (offset, subindex, type_name, flags)
        aux = int(aux.rstrip("u"))
        assert sub_size(type_name, aux) == int(size.rstrip("u"))
        if "CO_OD_LIMITS" in flags:
            assert aux == int(limit.rstrip("u"))


def test_a_string_beyond_one_byte_is_refused(tmp_path):
    eds = tmp_path / "long.eds"
    text = (ROOT / "od" / "bench" / "bench.eds").read_text()
    eds.write_text(text.replace("DefaultValue=canopen-drive bench",
                                "DefaultValue=" + "x" * 300, 1))
    r = run_generator(eds, "bench", out_c=tmp_path / "o.c", out_h=tmp_path / "o.h",
                      extra=["--compact"])
    assert r.returncode != 0
    assert "at most 255" in r.stderr
    r = run_generator(eds, "bench", out_c=tmp_path / "o.c", out_h=tmp_path / "o.h")
    assert r.returncode == 0, r.stderr


def test_tables_beyond_an_entrys_16_bit_reach_are_refused():
    """--compact: an entry finds its descriptors by a 16-bit distance back from itself (od.h
    co_od_entry.subs_back), so tables of more than 64 KiB are refused with a reason."""
    import importlib.util
    from types import SimpleNamespace

    from eds2c_testlib import GENERATOR
    spec = importlib.util.spec_from_file_location("eds2c_compact_reach", GENERATOR)
    gen = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(gen)

    def objects(count, subs_each):
        return [SimpleNamespace(subs=[SimpleNamespace(index=0x2000 + i, subindex=k, type=0x07,
                                                      size=4, limit=None)
                                      for k in range(subs_each)])
                for i in range(count)]

    fits = objects(1000, 9)  # 6 * 9000 + 8 * 1000 = 62000 bytes
    assert not gen.compact_problems(fits)
    too_many = objects(1100, 9)  # 6 * 9900 + 8 * 1100 = 68200 bytes
    problems = gen.compact_problems(too_many)
    assert len(problems) == 1 and "at most 65535 bytes" in problems[0][1]
