"""Broken EDS files: eds2c.py must exit with status 1, write nothing, and print
`FILE:LINE: error: reason` naming the file, the line (marked ERROR-HERE in each fixture) and the
reason. One fixture per kind of fault, in tests/generator/fixtures/."""

import re

import pytest

from eds2c_testlib import FIXTURES, run_generator

# fixture name -> regex the reason must match
EXPECTED = {
    "unknown_data_type": r"unknown data type 0x0017",
    "unknown_data_type_above_1b": r"unknown data type 0x0040",
    "unknown_access_type": r"unknown AccessType 'readwrite'",
    "default_above_high_limit": r"0x2000 sub 0: DefaultValue 2000 outside LowLimit/HighLimit",
    "default_below_low_limit": r"0x2002 sub 1: DefaultValue -11 outside LowLimit/HighLimit",
    "default_out_of_type_range": r"0x2003 sub 1: DefaultValue 300 does not fit UNSIGNED8",
    "limit_out_of_type_range": r"0x2003 sub 1: HighLimit 256 does not fit UNSIGNED8",
    "low_limit_above_high_limit": r"0x2002 sub 2: LowLimit 20 > HighLimit 10",
    "pdo_mapping_over_64_bits": r"0x1600: mapped objects add up to 80 bits, more than 64",
    "pdo_mapping_missing_object": r"mapping entry 0x20100010 points at 0x2010 sub 0, which does "
                                  r"not exist",
    "pdo_mapping_not_mappable": r"mapping entry 0x10170010 points at 0x1017 sub 0, which is not "
                                r"PDO-mappable",
    "pdo_mapping_wrong_direction": r"0x6040 sub 0, which is not TPDO-mappable",
    "pdo_mapping_wrong_length": r"length 16 bits does not match UNSIGNED8",
    "missing_1000": r"missing mandatory object 0x1000$",
    "missing_1001": r"missing mandatory object 0x1001$",
    "missing_1018": r"missing mandatory object 0x1018$",
    "missing_1018_sub1": r"missing mandatory 0x1018 sub 1",
    "duplicate_section": r"duplicate section \[1017\] \(first at line \d+\)",
    "duplicate_sub_section": r"duplicate section \[2002sub01\] for 0x2002 sub 1",
    "unparsable_default": r"0x1017 sub 0: DefaultValue: unparsable number '12abc'",
    "unparsable_limit": r"0x2000 sub 0: HighLimit: unparsable number '0x1G'",
    "unparsable_real_default": r"0x2003 sub 2: DefaultValue: unparsable number '0,5'",
    "string_longer_than_capacity": r"default string is 10 bytes, longer than its capacity 8",
    "array_without_sub0": r"ARRAY 0x2002 has no sub-index 0",
    "record_without_sub0": r"RECORD 0x2003 has no sub-index 0",
    "subnumber_mismatch": r"SubNumber=4 but 0x2002 has 3 sub-index sections",
    "object_not_listed": r"object \[2003\] is not listed",
    "nodeid_on_signed": r"\$NODEID default needs an unsigned type",
    "missing_fileinfo": r"missing \[FileInfo\] section",
    "section_not_an_index": r"section \[12345\] is neither an object section .* nor a "
                            r"sub-index section",
    "object_0000": r"object 0x0000 cannot exist: CiA 301 leaves index 0x0000 unused",
    "empty_high_limit": r"0x2000 sub 0: HighLimit is empty",
    "nul_in_parameter_name": r"control character 0x00 in ParameterName",
}

LINE_RE = re.compile(r"^(?P<file>.+?):(?P<line>\d+): error: (?P<reason>.+)$")


def marker_line(path):
    lines = [i for i, text in enumerate(path.read_text().splitlines(), start=1)
             if "ERROR-HERE" in text and not text.startswith(";")]
    assert len(lines) == 1, f"{path.name} must mark exactly one line with ERROR-HERE"
    return lines[0]


def test_every_fixture_has_an_expectation():
    broken = {p.stem for p in FIXTURES.glob("*.eds")} - {"ok_minimal"}
    assert broken == set(EXPECTED), "fixtures and EXPECTED differ"


def test_base_fixture_is_valid(tmp_path):
    """All broken fixtures derive from ok_minimal.eds, so it must itself be accepted."""
    r = run_generator(FIXTURES / "ok_minimal.eds", "ok", tmp_path / "ok.c", tmp_path / "ok.h")
    assert r.returncode == 0, r.stderr
    assert r.stderr == ""


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_broken_eds_is_refused_with_file_line_and_reason(name, tmp_path):
    path = FIXTURES / f"{name}.eds"
    out_c, out_h = tmp_path / "x.c", tmp_path / "x.h"
    r = run_generator(path, "x", out_c, out_h)
    assert r.returncode == 1, f"exit {r.returncode}\n{r.stderr}"
    assert not out_c.exists() and not out_h.exists(), "nothing may be written for a bad EDS"
    lines = r.stderr.splitlines()
    assert lines, "no message"
    for text in lines:
        assert LINE_RE.match(text), f"not FILE:LINE: error: reason -> {text!r}"
    want_line = marker_line(path)
    hits = [LINE_RE.match(t) for t in lines]
    hits = [m for m in hits if m.group("file") == str(path) and int(m.group("line")) == want_line
            and re.search(EXPECTED[name], m.group("reason"))]
    assert hits, (f"expected {path}:{want_line}: error: /{EXPECTED[name]}/, got:\n{r.stderr}")


def test_missing_file_is_an_error(tmp_path):
    r = run_generator(tmp_path / "nope.eds", "x", tmp_path / "x.c", tmp_path / "x.h")
    assert r.returncode == 1
    assert re.match(rf"^{re.escape(str(tmp_path / 'nope.eds'))}:1: error: cannot read", r.stderr)


def test_bad_id_is_a_usage_error(tmp_path):
    r = run_generator(FIXTURES / "ok_minimal.eds", "9-bad id", tmp_path / "x.c", tmp_path / "x.h")
    assert r.returncode == 2
    assert not (tmp_path / "x.c").exists()
