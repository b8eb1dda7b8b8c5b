"""tools/eds2sii.py on broken input: each case changes one thing in the VF-MB1's EDS or choices
file; the generator must exit with status 1, write nothing, and report `FILE:LINE: error: reason`
naming the file, the line and the reason. Also the PDO assignment taken from 0x1C12/0x1C13 when
the EDS has them."""

import re

import pytest

from eds2sii_testlib import MB1_CHOICES, MB1_EDS, Sii, run_sii

LINE_RE = re.compile(r"^(?P<file>.+?):(?P<line>\d+): error: (?P<reason>.+)$")

ASSIGN_OBJECTS = """
[1C12]
ParameterName=Sync manager 2 PDO assignment
ObjectType=0x8
SubNumber=2

[1C12sub0]
ParameterName=Number of assigned PDOs
ObjectType=0x7
DataType=0x0005
AccessType=rw
DefaultValue={count}
PDOMapping=0

[1C12sub1]
ParameterName=PDO 1
ObjectType=0x7
DataType=0x0006
AccessType=rw
DefaultValue={rx}
PDOMapping=0

[1C13]
ParameterName=Sync manager 3 PDO assignment
ObjectType=0x8
SubNumber=2

[1C13sub0]
ParameterName=Number of assigned PDOs
ObjectType=0x7
DataType=0x0005
AccessType=rw
DefaultValue=1
PDOMapping=0

[1C13sub1]
ParameterName=PDO 1
ObjectType=0x7
DataType=0x0006
AccessType=rw
DefaultValue=0x1A00
PDOMapping=0
"""


def replace_once(text, old, new):
    assert text.count(old) == 1, f"{old!r} occurs {text.count(old)} times"
    return text.replace(old, new)


def remove_sections(text, names):
    out, skipping = [], False
    for line in text.split("\n"):
        m = re.match(r"^\[(.+)\]", line)
        if m:
            skipping = m.group(1) in names
        if not skipping:
            out.append(line)
    return "\n".join(out)


def with_assign_objects(eds, count=1, rx="0x1600"):
    eds = replace_once(eds, "SupportedObjects=25\n", "SupportedObjects=27\n")
    eds = replace_once(eds, "25=0x6502\n", "25=0x6502\n26=0x1C12\n27=0x1C13\n")
    return eds + ASSIGN_OBJECTS.format(count=count, rx=rx)


def line_of(text, needle):
    lines = [i for i, t in enumerate(text.split("\n"), start=1) if t == needle]
    assert len(lines) == 1, f"{needle!r} on lines {lines}"
    return lines[0]


def write(tmp_path, eds=None, ini=None):
    e, c = tmp_path / "drive.eds", tmp_path / "ecat.ini"
    e.write_text(eds if eds is not None else MB1_EDS.read_text())
    c.write_text(ini if ini is not None else MB1_CHOICES.read_text())
    return e, c


def expect_error(tmp_path, eds=None, ini=None, where=None, reason=""):
    """where = ("eds" | "ini", line text that must be reported)."""
    e, c = write(tmp_path, eds, ini)
    out = tmp_path / "out"
    r = run_sii(e, c, "drive", out)
    assert r.returncode == 1, r.stderr
    assert not list(out.iterdir()), "nothing may be written on an error"
    lines = r.stderr.strip().split("\n")
    parsed = [LINE_RE.match(x) for x in lines]
    assert all(parsed), r.stderr
    path, text = (e, e.read_text()) if where[0] == "eds" else (c, c.read_text())
    line = line_of(text, where[1])
    hits = [m for m in parsed if m.group("file") == str(path) and int(m.group("line")) == line
            and re.search(reason, m.group("reason"))]
    assert hits, f"expected {path.name}:{line}: ... {reason}\ngot:\n{r.stderr}"


EDS = MB1_EDS.read_text()
INI = MB1_CHOICES.read_text()


def test_unchanged_copies_generate(tmp_path):
    e, c = write(tmp_path)
    r = run_sii(e, c, "drive", tmp_path / "out")
    assert r.returncode == 0, r.stderr


def test_missing_1018(tmp_path):
    eds = remove_sections(EDS, {"1018", "1018sub0", "1018sub1", "1018sub2", "1018sub3",
                                "1018sub4"})
    eds = replace_once(eds, "SupportedObjects=3\n1=0x1000\n2=0x1001\n3=0x1018\n",
                       "SupportedObjects=2\n1=0x1000\n2=0x1001\n")
    expect_error(tmp_path, eds=eds, where=("eds", "[MandatoryObjects]"),
                 reason=r"missing mandatory object 0x1018$")


def test_missing_product_code(tmp_path):
    eds = remove_sections(EDS, {"1018sub2"})
    eds = replace_once(eds, "ParameterName=Identity object\nObjectType=0x9\nSubNumber=5",
                       "ParameterName=Identity object\nObjectType=0x9\nSubNumber=4")
    expect_error(tmp_path, eds=eds, where=("eds", "[1018]"),
                 reason=r"0x1018 sub 2 \(product code\) is missing")


def test_device_info_disagrees_with_1018(tmp_path):
    eds = replace_once(EDS, "ProductNumber=0x000000E1", "ProductNumber=0x000000E2")
    expect_error(tmp_path, eds=eds, where=("eds", "ProductNumber=0x000000E2"),
                 reason=r"differs from 0x1018 sub 2 \(0x000000E1\)")


def test_mapping_entry_points_at_absent_object(tmp_path):
    eds = replace_once(EDS, "DefaultValue=0x60420010", "DefaultValue=0x60450010")
    expect_error(tmp_path, eds=eds, where=("eds", "DefaultValue=0x60450010"),
                 reason=r"points at 0x6045 sub 0, which does not exist")


def test_assignment_in_eds_and_choices(tmp_path):
    expect_error(tmp_path, eds=with_assign_objects(EDS), where=("ini", "RxPdoAssign=0x1600"),
                 reason=r"the EDS has 0x1C12 \(line \d+\).*remove the key")


def test_assignment_names_no_mapping_object(tmp_path):
    eds = with_assign_objects(EDS, rx="0x1601")
    ini = replace_once(INI, "RxPdoAssign=0x1600\n", "")
    ini = replace_once(ini, "TxPdoAssign=0x1A00\n", "")
    expect_error(tmp_path, eds=eds, ini=ini, where=("eds", "DefaultValue=0x1601"),
                 reason=r"0x1C12 sub 1: 0x1601 is not a PDO mapping object")


CHOICE_CASES = {
    "unknown key": (("[Device]\n", "[Device]\nColour=blue\n"), "Colour=blue",
                    r"\[Device\] unknown key Colour"),
    "unknown section": (("[CoE]\n", "[Foo]\nBar=1\n[CoE]\n"), "[Foo]", r"unknown section \[Foo\]"),
    "missing key": (("OutSize=128\n", ""), "[Mailbox]", r"\[Mailbox\] lacks OutSize"),
    "mailbox too small": (("OutSize=128\n", "OutSize=8\n"), "OutSize=8", r"8 outside 16-1486"),
    "SM2 control in mailbox mode": (("OutputsControl=0x64", "OutputsControl=0x66"),
                                    "OutputsControl=0x66", r"SM2 must be buffered, master writes"),
    "SM1 control with master writing": (("InControl=0x22", "InControl=0x26"), "InControl=0x26",
                                        r"SM1 must be mailbox, master reads"),
    "buffers overlap": (("OutputsMaxSize=12", "OutputsMaxSize=64"), "InputsStart=0x1180",
                        r"SM2 \(0x1100, 192 bytes\) and SM3 \(0x1180, 36 bytes\) overlap"),
    "default PDOs exceed the maximum": (("OutputsMaxSize=12", "OutputsMaxSize=2"),
                                        "OutputsMaxSize=2",
                                        r"smaller than SM2's default PDOs \(4 bytes\)"),
    "outside the process RAM": (("OutStart=0x1000", "OutStart=0x0F00"), "OutStart=0x0F00",
                                r"SM0 at 0x0F00-0x0F7F is outside the ESC's process RAM"),
    "assignment of an absent PDO": (("RxPdoAssign=0x1600", "RxPdoAssign=0x1601"),
                                    "RxPdoAssign=0x1601",
                                    r"the EDS has no PDO mapping object 0x1601"),
    "name longer than a master shows": (("Type=VF-MB1 IPE003Z", "Type=" + "X" * 41),
                                        "Type=" + "X" * 41, r"longer than 40 characters"),
    "device emulation": (("EscConfig=0x00", "EscConfig=0x01"), "EscConfig=0x01",
                         r"device emulation"),
    "EEPROM too small": (("ByteSize=2048", "ByteSize=128"), "ByteSize=128",
                         r"the SII image is \d+ bytes, more than 128"),
    "EEPROM size not a power of two": (("ByteSize=2048", "ByteSize=1000"), "ByteSize=1000",
                                       r"a power of two"),
    "no CoE": (("Protocols=CoE", "Protocols=EoE"), "Protocols=EoE", r"must include CoE"),
    "unknown protocol": (("Protocols=CoE", "Protocols=CoE, XoE"), "Protocols=CoE, XoE",
                         r"'XoE' is not one of"),
    "too many FMMUs": (("Fmmus=8", "Fmmus=1"), "Usage=Outputs, Inputs",
                       r"2 FMMUs but the ESC has 1"),
    "bad boolean": (("SdoInfo=1", "SdoInfo=yes"), "SdoInfo=yes", r"'yes' is not 0 or 1"),
}


@pytest.mark.parametrize("case", sorted(CHOICE_CASES))
def test_bad_choices(tmp_path, case):
    (old, new), line, reason = CHOICE_CASES[case]
    expect_error(tmp_path, ini=replace_once(INI, old, new), where=("ini", line), reason=reason)


def test_assignment_from_1c12_1c13(tmp_path):
    """With 0x1C12/0x1C13 in the EDS (sub 0 writable) the assignment comes from their defaults and
    GENERAL announces PDO assignment; an empty 0x1C12 leaves SM2 with length 0, disabled, and the
    RxPDO unassigned (SM 0xFF)."""
    ini = replace_once(INI, "RxPdoAssign=0x1600\n", "")
    ini = replace_once(ini, "TxPdoAssign=0x1A00\n", "")
    for count, sm2_length, rx_sm in ((1, 4, 2), (0, 0, 0xFF)):
        e, c = write(tmp_path, eds=with_assign_objects(EDS, count=count), ini=ini)
        out = tmp_path / f"out{count}"
        r = run_sii(e, c, "drive", out)
        assert r.returncode == 0, r.stderr
        sii = Sii((out / "sii.bin").read_bytes())
        assert sii.general()["coe"] == 0x01 | 0x02 | 0x04 | 0x08 | 0x20
        sms = sii.sync_managers()
        assert (sms[2]["length"], sms[2]["enable"]) == (sm2_length, 1 if sm2_length else 0)
        assert (sms[3]["length"], sms[3]["enable"]) == (4, 1)
        assert sii.pdos(51)[0]["sm"] == rx_sm and sii.pdos(50)[0]["sm"] == 3
        assert 'PdoAssign="true"' in (out / "drive.xml").read_text()
