"""tools/eds2sii.py on the VF-MB1 (od/vf-mb1-ecat): the SII image decoded by an independent
reader (eds2sii_testlib.Sii) and compared with the EDS as python-canopen reads it and with the
choices file as configparser reads it; the ESI file parsed and compared with the image; the C
output compiled and compared byte for byte."""

import configparser
import subprocess
import xml.etree.ElementTree as ET

import pytest

from eds2c_testlib import STRICT, cc, compilers
from eds2sii_testlib import (MB1_CHOICES, MB1_EDS, Sii, c_array_bytes, crc8_reference,
                            run_sii)

ID = "vf-mb1-ecat"
SYM = "co_sii_vf_mb1_ecat"


@pytest.fixture(scope="module")
def out(tmp_path_factory):
    outdir = tmp_path_factory.mktemp("sii")
    r = run_sii(MB1_EDS, MB1_CHOICES, ID, outdir)
    assert r.returncode == 0, r.stderr
    assert r.stderr == ""
    return outdir


@pytest.fixture(scope="module")
def sii(out):
    return Sii((out / "sii.bin").read_bytes())


@pytest.fixture(scope="module")
def od():
    import canopen
    return canopen.objectdictionary.import_od(str(MB1_EDS), node_id=None)


@pytest.fixture(scope="module")
def choices():
    cp = configparser.ConfigParser(inline_comment_prefixes=(";",))
    cp.optionxform = str
    cp.read(MB1_CHOICES)
    return cp


def num(text):
    return int(text, 0)


def test_c_array_is_the_image(out, sii):
    c = (out / "sii_vf_mb1_ecat.c").read_text()
    assert c_array_bytes(c, SYM) == sii.image
    h = (out / "sii_vf_mb1_ecat.h").read_text()
    assert f"#define CO_SII_VF_MB1_ECAT_SIZE {len(sii.image)}u" in h


def test_deterministic(out, tmp_path):
    r = run_sii(MB1_EDS, MB1_CHOICES, ID, tmp_path)
    assert r.returncode == 0, r.stderr
    for name in ("sii_vf_mb1_ecat.c", "sii_vf_mb1_ecat.h", f"{ID}.xml", "sii.bin"):
        assert (tmp_path / name).read_bytes() == (out / name).read_bytes(), name


def test_header_checksum(sii):
    assert sii.words[7] >> 8 == 0
    assert sii.words[7] & 0xFF == crc8_reference(sii.image[:14])
    # the check is not vacuous: any change of words 0-6 changes it
    for i in range(14):
        changed = bytearray(sii.image[:14])
        changed[i] ^= 0x01
        assert crc8_reference(bytes(changed)) != sii.words[7] & 0xFF


def gf2_mod(value, poly=0x107):
    """value mod poly, both as polynomials over GF(2)."""
    while value.bit_length() >= poly.bit_length():
        value ^= poly << (value.bit_length() - poly.bit_length())
    return value


def crc8_by_division(data):
    """The same CRC as the remainder of 0xFF x^(8n) + M(x) x^8 divided by x^8+x^2+x+1 (n bytes
    of message M, first byte highest): the definition itself, a third way to compute it."""
    n = len(data)
    message = int.from_bytes(data, "big") if data else 0
    return gf2_mod((0xFF << (8 * n)) ^ (message << 8))


def test_crc_reference_against_the_definition(sii):
    import random
    rng = random.Random(7)
    samples = [b"", b"\x00", b"\xff", sii.image[:14]] + \
        [bytes(rng.randrange(256) for _ in range(14)) for _ in range(50)]
    for data in samples:
        assert crc8_reference(data) == crc8_by_division(data), data.hex()
    assert crc8_reference(b"\xff") == 0x00     # the preset cancels against a 0xFF byte


def test_category_chain_walks_to_end(sii):
    kinds = [k for k, _, _ in sii.categories]
    assert kinds == [10, 30, 40, 41, 50, 51]
    assert sii.end_offset == len(sii.image) - 2     # END is the last word of the image
    assert len(sii.image) <= (sii.words[0x3E] + 1) * 128   # fits the EEPROM it announces
    assert len(sii.image) <= 4096


def test_identity_matches_1018(sii, od):
    ident = od[0x1018]
    assert sii.u32(0x08) == ident[1].default == 0x00000284
    assert sii.u32(0x0A) == ident[2].default == 0x000000E1
    assert sii.u32(0x0C) == ident[3].default == 0x00010002
    assert sii.u32(0x0E) == ident[4].default


def test_header_words(sii, choices):
    esc, mbx = choices["Esc"], choices["Mailbox"]
    assert sii.words[0] == num(esc["PdiControl"]) | num(esc["EscConfig"]) << 8
    assert sii.words[4] == num(esc["Alias"]) == 0              # Manual §3.2: C401 default 0
    assert sii.words[0x14:0x18] == (0, 0, 0, 0)                 # no bootstrap mailbox
    assert sii.words[0x18:0x1C] == (num(mbx["OutStart"]), num(mbx["OutSize"]),
                                    num(mbx["InStart"]), num(mbx["InSize"]))
    assert sii.words[0x1C] == 0x0004                            # CoE only
    assert all(w == 0 for w in sii.words[0x1D:0x3E])
    assert (sii.words[0x3E] + 1) * 128 == num(choices["Eeprom"]["ByteSize"])
    assert sii.words[0x3F] == 1


def test_strings_and_general(sii, od, choices):
    strings = sii.strings()
    assert strings[0] == choices["Device"]["Type"]            # masters show string 1
    assert len(strings[0]) <= 40
    g = sii.general()
    assert sii.string(g["name"]) == "TOSVERT VF-MB1/S15 EtherCAT option IPE003Z"
    assert sii.string(g["order"]) == "IPE003Z"
    assert sii.string(g["group"]) == choices["Device"]["GroupType"] == sii.string(g["group2"])
    assert g["image"] == 0
    # SDO, SDO info, PDO configuration (0x1600/0x1A00 sub 0 are rw), complete access; no PDO
    # assignment (no 0x1C12/0x1C13 in the EDS), no upload at startup
    assert 0x1C12 not in od and 0x1C13 not in od
    assert od[0x1600][0].access_type == "rw" and od[0x1A00][0].access_type == "rw"
    assert g["coe"] == 0x01 | 0x02 | 0x08 | 0x20
    assert (g["foe"], g["eoe"], g["soe"]) == (0, 0, 0)
    assert od[0x1000].default & 0xFFFF == 402 and g["ds402"] == 1
    assert g["flags"] == 0 and g["ebus"] == 0
    assert g["ports"] == 0x0011                                 # Manual §2.1: X1, X2


def test_fmmu(sii):
    assert sii.category(40) == bytes([1, 2])                    # outputs, inputs


def mapped(od, index):
    rec = od[index]
    out = []
    for n in range(1, rec[0].default + 1):
        v = rec[n].default
        out.append((v >> 16, (v >> 8) & 0xFF, v & 0xFF))
    return out


def test_sync_managers(sii, od, choices):
    pd = choices["ProcessData"]
    sms = sii.sync_managers()
    assert [s["type"] for s in sms] == [1, 2, 3, 4]
    assert [s["start"] for s in sms] == [sii.words[0x18], sii.words[0x1A],
                                         num(pd["OutputsStart"]), num(pd["InputsStart"])]
    assert [s["length"] for s in sms[:2]] == [sii.words[0x19], sii.words[0x1B]]
    out_bits = sum(bits for _, _, bits in mapped(od, 0x1600))
    in_bits = sum(bits for _, _, bits in mapped(od, 0x1A00))
    assert (sms[2]["length"], sms[3]["length"]) == ((out_bits + 7) // 8, (in_bits + 7) // 8) \
        == (4, 4)
    assert [s["control"] for s in sms] == [0x26, 0x22, 0x64, 0x20]
    assert [s["enable"] & 1 for s in sms] == [1, 1, 1, 1]
    # the control bytes' mode (bits 1:0) and direction (bits 3:2) fit each SyncManager's type
    assert [(s["control"] & 3, s["control"] >> 2 & 3) for s in sms] == [(2, 1), (2, 0), (0, 1),
                                                                         (0, 0)]
    # a buffered SyncManager occupies three buffers: SM2's largest fits before SM3
    assert num(pd["OutputsStart"]) + 3 * num(pd["OutputsMaxSize"]) <= num(pd["InputsStart"])
    # mailboxes do not overlap the process data
    assert sms[1]["start"] + sms[1]["length"] <= sms[2]["start"]


@pytest.mark.parametrize("kind, index, sm", [(51, 0x1600, 2), (50, 0x1A00, 3)])
def test_pdo_categories_match_mapping(sii, od, kind, index, sm):
    pdos = sii.pdos(kind)
    assert [p["index"] for p in pdos] == [index]
    pdo = pdos[0]
    assert pdo["sm"] == sm
    assert pdo["name"] == od[index].name
    assert [(e["index"], e["sub"], e["bits"]) for e in pdo["entries"]] == mapped(od, index)
    for e in pdo["entries"]:
        target = od[e["index"]]
        assert e["type"] == target.data_type
        assert e["name"] == target.name


def test_esi_matches_sii(out, sii):
    text = (out / f"{ID}.xml").read_text()
    assert "Generated by tools/eds2sii.py" in text and "from its vendor" in text
    root = ET.fromstring(text)
    assert root.tag == "EtherCATInfo"
    hexv = lambda s: int(s.replace("#x", "0x"), 0)  # noqa: E731
    assert hexv(root.find("Vendor/Id").text) == sii.u32(0x08)
    dev = root.find("Descriptions/Devices/Device")
    t = dev.find("Type")
    assert hexv(t.get("ProductCode")) == sii.u32(0x0A)
    assert hexv(t.get("RevisionNo")) == sii.u32(0x0C)
    g = sii.general()
    assert t.text == sii.string(1)
    assert dev.find("Name").text == sii.string(g["name"])
    assert dev.find("GroupType").text == sii.string(g["group"])
    assert root.find("Descriptions/Groups/Group/Type").text == sii.string(g["group"])
    assert dev.get("Physics") == "YY"
    assert dev.find("Profile/ProfileNo").text == "402"
    assert [f.text for f in dev.findall("Fmmu")] == ["Outputs", "Inputs"]
    sms = sii.sync_managers()
    esi_sms = dev.findall("Sm")
    assert [s.text for s in esi_sms] == ["MBoxOut", "MBoxIn", "Outputs", "Inputs"]
    for s, e in zip(sms, esi_sms):
        assert hexv(e.get("StartAddress")) == s["start"]
        assert int(e.get("DefaultSize")) == s["length"]
        assert hexv(e.get("ControlByte")) == s["control"]
        assert int(e.get("Enable")) == s["enable"]
    for tag, kind in (("RxPdo", 51), ("TxPdo", 50)):
        esi = dev.findall(tag)
        cat = sii.pdos(kind)
        assert len(esi) == len(cat)
        for e, c in zip(esi, cat):
            assert hexv(e.find("Index").text) == c["index"]
            assert int(e.get("Sm")) == c["sm"]
            assert e.find("Name").text == c["name"]
            got = [(hexv(x.find("Index").text), int(x.find("SubIndex").text),
                    int(x.find("BitLen").text), x.find("Name").text) for x in e.findall("Entry")]
            assert got == [(x["index"], x["sub"], x["bits"], x["name"]) for x in c["entries"]]
    coe = dev.find("Mailbox/CoE")
    assert [m.tag for m in dev.find("Mailbox")] == ["CoE"]
    bits = {"SdoInfo": 0x02, "PdoAssign": 0x04, "PdoConfig": 0x08, "PdoUpload": 0x10,
            "CompleteAccess": 0x20}
    for attr, bit in bits.items():
        assert coe.get(attr) == ("true" if g["coe"] & bit else "false"), attr
    assert int(dev.find("Eeprom/ByteSize").text) == (sii.words[0x3E] + 1) * 128
    assert bytes.fromhex(dev.find("Eeprom/ConfigData").text) == sii.image[:14]


@pytest.mark.parametrize("compiler", compilers())
def test_c_compiles_and_matches(out, sii, tmp_path, compiler):
    main = tmp_path / "main.c"
    main.write_text("""#include <stdio.h>
#include "sii_vf_mb1_ecat.h"
int main(void)
{
    unsigned i;
    if (sizeof co_sii_vf_mb1_ecat != CO_SII_VF_MB1_ECAT_SIZE ||
        co_sii_vf_mb1_ecat_size != CO_SII_VF_MB1_ECAT_SIZE)
        return 1;
    for (i = 0; i < CO_SII_VF_MB1_ECAT_SIZE; i++)
        printf("%02x", co_sii_vf_mb1_ecat[i]);
    printf("\\n%x %x %x %x %x %x\\n", (unsigned)CO_SII_VF_MB1_ECAT_PRODUCT_CODE,
           (unsigned)CO_SII_VF_MB1_ECAT_SM2_START, (unsigned)CO_SII_VF_MB1_ECAT_SM2_LENGTH,
           (unsigned)CO_SII_VF_MB1_ECAT_SM3_START, (unsigned)CO_SII_VF_MB1_ECAT_MBX_OUT_SIZE,
           (unsigned)CO_SII_VF_MB1_ECAT_COE_DETAILS);
    return 0;
}
""")
    exe = tmp_path / "main"
    cc(compiler, STRICT + ["-Wconversion", "-Wmissing-prototypes", f"-I{out}", main,
                           out / "sii_vf_mb1_ecat.c", "-o", exe])
    lines = subprocess.run([exe], capture_output=True, text=True, check=True).stdout.split("\n")
    assert bytes.fromhex(lines[0]) == sii.image
    sms = sii.sync_managers()
    assert lines[1].split() == [f"{v:x}" for v in (sii.u32(0x0A), sms[2]["start"],
                                                   sms[2]["length"], sms[3]["start"],
                                                   sii.words[0x19], sii.general()["coe"])]
