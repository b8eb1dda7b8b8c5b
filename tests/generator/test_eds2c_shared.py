"""eds2c: objects of one shape share one run of sub-entry descriptors (od.h co_od_entry.value_base,
co_od_value_offset). In both output formats every value must still be where the generator's own
layout put it (value_base + the descriptor's offset), the values must not overlap, and the
objects of one shape (the PDO parameters of the bench dictionary, ...) must point at one run."""

import importlib.util
import re

import pytest

from eds2c_testlib import DRIVES, GENERATOR, ROOT, TEST_EDS, generate_plain_and
from eds2c_testlib import sym as od_sym


def generator_module():
    spec = importlib.util.spec_from_file_location("eds2c_module", GENERATOR)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def eds_path(od_id):
    return TEST_EDS if od_id == "test" else ROOT / "od" / od_id / f"{od_id}.eds"


def tables(text, sym):
    """(descriptor rows as lists of fields, entry rows (index, sub_count, value_base, first))."""
    if f"}} {sym}_tables = {{" in text:
        return compact_tables(text, sym)
    m = re.search(rf"{sym}_subs\[(\d+)\] = \{{(.*?)\n\}};", text, re.S)
    assert m
    body = re.sub(r"/\*.*?\*/", "", m.group(2), flags=re.S)
    subs = [[f.strip() for f in row.split(",")] for row in re.findall(r"\{([^{}]*)\}", body)]
    assert len(subs) == int(m.group(1))
    m = re.search(rf"{sym}_entries\[\d+\] = \{{(.*?)\n\}};", text, re.S)
    assert m
    entries = [(int(i, 16), int(n), int(base), int(first)) for i, n, base, first in re.findall(
        rf"\{{0x([0-9A-F]{{4}})u, CO_OBJ_\w+, (\d+)u, (\d+)u, &{sym}_subs\[(\d+)\]\}}",
        m.group(1))]
    return subs, entries


def compact_tables(text, sym):
    """tables() of --compact, whose descriptor runs and entries are one object: each run of
    6-byte descriptors after its 2-byte header (descriptors), then the 6-byte
    entries; an entry holds the bytes back from itself to its first descriptor and reads its
    sub_count from the header before it."""
    m = re.search(rf"struct {sym}_tables \{{\n((?:    co_od_run h\d+;\n    co_od_sub s\d+\[\d+\];\n)*)"
                  rf"    co_od_entry entries\[(\d+)\];\n\}} {sym}_tables = \{{\n(.*?)"
                  rf"\n    \.entries = \{{(.*?)\n    \}},\n\}};", text, re.S)
    assert m
    counts = [int(n) for n in re.findall(r"co_od_sub s\d+\[(\d+)\];", m.group(1))]
    body = re.sub(r"/\*.*?\*/", "", m.group(3), flags=re.S)
    runs = re.findall(r"\{(\d+)u\},\s*\{(.*?)\n    \},", body, re.S)
    assert [int(n) for n, _ in runs] == counts
    subs, header = [], {}  # header: first descriptor -> (its byte offset, descriptors)
    at = 0
    for n, run in runs:
        rows = [[f.strip() for f in row.split(",")] for row in re.findall(r"\{([^{}]*)\}", run)]
        assert len(rows) == int(n)
        header[len(subs)] = (at + 2, int(n))
        at += 2 + 6 * len(rows)
        subs.extend(rows)
    rows = re.findall(r"\{0x([0-9A-F]{4})u, (\d+)u, (\d+)u\}, /\* subs\[(\d+)\] \*/", m.group(4))
    assert len(rows) == int(m.group(2))
    entries = []
    for k, (i, base, back, first) in enumerate(rows):
        assert int(first) in header
        assert int(back) == at + 6 * k - header[int(first)][0]
        entries.append((int(i, 16), header[int(first)][1], int(base), int(first)))
    assert (f"offsetof(struct {sym}_tables, entries) == {at}u && sizeof(co_od_run) == 2u && "
            "sizeof(co_od_sub) == 6u && sizeof(co_od_entry) == 6u ? 1 : -1];") in text
    return subs, entries


@pytest.mark.parametrize("od_id", ("test", "bench") + DRIVES)
def test_every_value_is_where_the_layout_put_it(od_id, tmp_path):
    plain, compact = generate_plain_and(od_id, tmp_path, "compact", "--compact")
    gen = generator_module()
    objects = gen.load(str(eds_path(od_id)), gen.Problems())
    lay = gen.layout(objects)
    sym = od_sym(od_id)
    for path in (plain, compact):
        subs, entries = tables(path.read_text(), sym)
        assert len(entries) == len(objects)
        used = []
        for e, (index, count, base, first) in zip(objects, entries):
            assert (index, count) == (e.index, len(e.subs))
            assert first + count <= len(subs)
            for k, s in enumerate(e.subs):
                row = subs[first + k]
                assert row[2 if "compact" in path.name else 3] == f"0x{s.subindex:02X}u"
                if s.size:
                    at = base + int(row[0].rstrip("u"))
                    assert at == s.offset, f"0x{e.index:04X} sub {s.subindex}"
                    assert at % s.align == 0
                    used.append((at, at + s.size, e.index, s.subindex))
        used.sort()
        for a, b in zip(used, used[1:]):
            assert a[1] <= b[0], f"0x{a[2]:04X} sub {a[3]} overlaps 0x{b[2]:04X} sub {b[3]}"
        assert not used or used[-1][1] <= lay["value_size"]
        # every run of descriptors is emitted once
        runs = {tuple(tuple(subs[first + k]) for k in range(count))
                for _, count, _, first in entries}
        assert sum(len(r) for r in runs) >= len(subs)


@pytest.mark.parametrize("flag", ("--compact", "--packed-defaults"))
def test_pdo_parameters_share_their_descriptors(flag, tmp_path):
    plain, other = generate_plain_and("bench", tmp_path, "other", flag)
    for path in (plain, other):
        subs, entries = tables(path.read_text(), od_sym("bench"))
        first = {index: f for index, _, _, f in entries}
        base = {index: b for index, _, b, _ in entries}
        for group in ((0x1010, 0x1011), range(0x1400, 0x1404), range(0x1800, 0x1804),
                      list(range(0x1600, 0x1604)) + list(range(0x1A00, 0x1A04))):
            assert len({first[i] for i in group}) == 1, [hex(i) for i in group]
            assert len({base[i] for i in group}) == len(group)
        assert len(subs) < sum(n for _, n, _, _ in entries) - 80
