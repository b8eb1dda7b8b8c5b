"""Helpers for the tests of tools/eds2sii.py (EDS + EtherCAT choices -> SII image, ESI).

The SII reader here is written from the format (ETG.1000.6 §5.4: header words 0x00-0x3F, then
categories of type word, length word, data), not from the generator: it is what checks it."""

from __future__ import annotations

import re
import struct
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SII_GENERATOR = ROOT / "tools" / "eds2sii.py"
MB1_EDS = ROOT / "od" / "vf-mb1-ecat" / "vf-mb1-ecat.eds"
MB1_CHOICES = ROOT / "od" / "vf-mb1-ecat" / "ecat.ini"

CATEGORY_NAMES = {10: "STRINGS", 20: "DATATYPES", 30: "GENERAL", 40: "FMMU", 41: "SYNCM",
                  50: "TXPDO", 51: "RXPDO", 60: "DC", 0xFFFF: "END"}


def run_sii(eds, choices, sii_id, outdir=None, extra=()):
    cmd = [sys.executable, str(SII_GENERATOR), str(eds), "--choices", str(choices), "--id", sii_id]
    if outdir is not None:
        outdir = Path(outdir)
        outdir.mkdir(parents=True, exist_ok=True)
        uid = sii_id.replace("-", "_")
        cmd += ["--out-c", str(outdir / f"sii_{uid}.c"), "--out-h", str(outdir / f"sii_{uid}.h"),
                "--out-xml", str(outdir / f"{sii_id}.xml"), "--out-bin", str(outdir / "sii.bin")]
    return subprocess.run(cmd + list(extra), capture_output=True, text=True)


def c_array_bytes(c_text, symbol):
    """The bytes of `const uint8_t symbol[...] = { ... };` in a generated C file."""
    m = re.search(r"const uint8_t " + re.escape(symbol) + r"\[[^\]]*\] = \{(.*?)\};", c_text,
                  re.S)
    assert m, f"no array {symbol}"
    body = re.sub(r"/\*.*?\*/", "", m.group(1), flags=re.S)
    return bytes(int(tok, 16) for tok in re.findall(r"0x[0-9A-Fa-f]{2}", body))


def crc8_reference(data):
    """CRC-8 as ETG.1000.6 §5.4 defines the SII checksum: remainder of the division by
    x^8+x^2+x+1 with the register preset to 0xFF. Table-driven, unlike the generator."""
    table = []
    for n in range(256):
        r = n
        for _ in range(8):
            r = ((r << 1) ^ 0x107) if r & 0x80 else (r << 1)
        table.append(r & 0xFF)
    crc = 0xFF
    for b in data:
        crc = table[crc ^ b]
    return crc


class Sii:
    """A decoded SII image."""

    def __init__(self, image):
        self.image = image
        self.words = struct.unpack_from("<64H", image, 0)
        self.categories = []            # [(type, byte offset of data, data)]
        self.end_offset = None
        pos = 0x80
        while True:
            assert pos + 2 <= len(image), f"category chain runs off the image at byte {pos}"
            (kind,) = struct.unpack_from("<H", image, pos)
            if kind == 0xFFFF:
                self.end_offset = pos
                break
            (length,) = struct.unpack_from("<H", image, pos + 2)
            data = image[pos + 4:pos + 4 + 2 * length]
            assert len(data) == 2 * length, f"category {kind} at byte {pos} is truncated"
            self.categories.append((kind, pos + 4, data))
            pos += 4 + 2 * length

    def u32(self, word):
        return self.words[word] | self.words[word + 1] << 16

    def category(self, kind):
        found = [data for k, _, data in self.categories if k == kind]
        assert len(found) == 1, f"category {kind}: {len(found)} found"
        return found[0]

    def strings(self):
        data = self.category(10)
        count, pos, out = data[0], 1, []
        for _ in range(count):
            n = data[pos]
            out.append(data[pos + 1:pos + 1 + n].decode("ascii"))
            pos += 1 + n
        return out

    def string(self, index):
        return "" if index == 0 else self.strings()[index - 1]

    def general(self):
        g = self.category(30)
        assert len(g) == 32
        return {"group": g[0], "image": g[1], "order": g[2], "name": g[3], "coe": g[5],
                "foe": g[6], "eoe": g[7], "soe": g[8], "ds402": g[9], "flags": g[11],
                "ebus": struct.unpack_from("<h", g, 12)[0], "group2": g[14],
                "ports": struct.unpack_from("<H", g, 16)[0]}

    def sync_managers(self):
        data = self.category(41)
        assert len(data) % 8 == 0
        return [dict(zip(("start", "length", "control", "status", "enable", "type"),
                         struct.unpack_from("<HHBBBB", data, i)))
                for i in range(0, len(data), 8)]

    def pdos(self, kind):
        data = self.category(kind)
        out, pos = [], 0
        while pos < len(data):
            index, n, sm, su, name, flags = struct.unpack_from("<HBBBBH", data, pos)
            pos += 8
            entries = []
            for _ in range(n):
                e_index, sub, e_name, dtype, bits, e_flags = struct.unpack_from("<HBBBBH", data,
                                                                                 pos)
                pos += 8
                entries.append({"index": e_index, "sub": sub, "name": self.string(e_name),
                                "type": dtype, "bits": bits})
            out.append({"index": index, "sm": sm, "name": self.string(name), "entries": entries})
        return out
