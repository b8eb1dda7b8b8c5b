"""What od.h's 8-byte co_od_sub can index: a value block below 64 KiB (16-bit offsets) and at
most 256 different LowLimit/HighLimit pairs (8-bit limit index). A dictionary beyond either is
refused with a reason, nothing written; one at the edge is accepted."""

import re

from eds2c_testlib import FIXTURES, run_generator

BASE = (FIXTURES / "ok_minimal.eds").read_text()


def with_objects(sections):
    """ok_minimal.eds plus manufacturer objects 0x3000.. given as (body lines) each."""
    listed = "\n".join(f"{5 + i}=0x{0x3000 + i:04X}" for i in range(len(sections)))
    text = BASE.replace("[ManufacturerObjects]\nSupportedObjects=4\n",
                        f"[ManufacturerObjects]\nSupportedObjects={4 + len(sections)}\n", 1)
    text = text.replace("4=0x2003\n", f"4=0x2003\n{listed}\n", 1)
    body = "".join(f"\n[{0x3000 + i:04X}]\nParameterName=o{i}\nObjectType=0x7\n{lines}\n"
                   for i, lines in enumerate(sections))
    return text + body


def string_object(chars):
    return f"DataType=0x0009\nAccessType=rw\nDefaultValue={'x' * chars}\nPDOMapping=0"


def ranged_object(high):
    return (f"DataType=0x0007\nAccessType=rw\nDefaultValue=0\nPDOMapping=0\nLowLimit=0\n"
            f"HighLimit={high}")


def run(tmp_path, text):
    eds = tmp_path / "t.eds"
    eds.write_text(text)
    out_c, out_h = tmp_path / "t.c", tmp_path / "t.h"
    return run_generator(eds, "t", out_c, out_h), out_c, out_h


def test_value_block_of_64_kib_is_refused(tmp_path):
    r, out_c, out_h = run(tmp_path, with_objects([string_object(40000), string_object(30000)]))
    assert r.returncode == 1, r.stderr
    assert re.search(r":1: error: value block of \d+ bytes: od.h offsets are 16 bits", r.stderr)
    assert not out_c.exists() and not out_h.exists()


def test_value_block_below_64_kib_is_accepted(tmp_path):
    r, _, _ = run(tmp_path, with_objects([string_object(30000), string_object(30000)]))
    assert r.returncode == 0, r.stderr


def test_more_than_256_limit_pairs_are_refused(tmp_path):
    r, out_c, _ = run(tmp_path, with_objects([ranged_object(1000 + i) for i in range(257)]))
    assert r.returncode == 1, r.stderr
    assert re.search(r":1: error: \d+ different LowLimit/HighLimit pairs: od.h indexes at most "
                     r"256", r.stderr)
    assert not out_c.exists()


def test_256_limit_pairs_are_accepted(tmp_path):
    # ok_minimal.eds has limit pairs of its own: fill up to exactly 256
    r, out_c, _ = run(tmp_path, with_objects([ranged_object(1000 + i) for i in range(250)]))
    assert r.returncode == 0, r.stderr
    have = int(re.search(r"(\d+) limits;", out_c.read_text()).group(1))
    r, out_c, _ = run(tmp_path, with_objects([ranged_object(1000 + i)
                                             for i in range(250 + 256 - have)]))
    assert r.returncode == 0, r.stderr
    assert re.search(r" 256 limits;", out_c.read_text())
