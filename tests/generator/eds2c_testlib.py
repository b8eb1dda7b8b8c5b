"""Helpers for the tests of tools/eds2c.py (EDS -> C tables) and tools/od2eds.c (C tables -> EDS).
A uniquely named module (not conftest.py) so that other test folders' conftest files cannot shadow
it. Run the suite: python3 -m pytest -q tests/generator"""

from __future__ import annotations

import configparser
import logging
import os
import re
import shutil
import subprocess
import sys
import warnings
from pathlib import Path


ROOT = Path(__file__).resolve().parents[2]
GENERATOR = ROOT / "tools" / "eds2c.py"
EXPORTER = ROOT / "tools" / "od2eds.c"
INCLUDE = ROOT / "include"
FIXTURES = Path(__file__).resolve().parent / "fixtures"
TEST_EDS = ROOT / "od" / "test" / "test.eds"
# The five drives of the project; their EDS files are written by other engineers.
DRIVES = ("vf-s15", "benshaw-rsi", "vacon-optc6", "sourcetronic-st600", "vf-mb1-ecat")
# Set to 1 (e.g. in CI once every drive exists) to turn "EDS not written yet" skips into failures.
REQUIRE_ALL = os.environ.get("CANOPEN_REQUIRE_ALL_OD") == "1"

STRICT = ["-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Werror"]
EXTRA = ["-Wconversion", "-Wsign-conversion", "-Wshadow", "-Wcast-align", "-Wmissing-prototypes",
         "-Wstrict-prototypes", "-Wwrite-strings"]


def compilers():
    return [cc for cc in ("gcc", "clang") if shutil.which(cc)]


def sym(od_id):
    return "co_od_" + od_id.replace("-", "_")


def run_generator(eds, od_id, out_c=None, out_h=None, cwd=None, extra=()):
    cmd = [sys.executable, str(GENERATOR), str(eds), "--id", od_id, *extra]
    if out_c:
        cmd += ["--out-c", str(out_c)]
    if out_h:
        cmd += ["--out-h", str(out_h)]
    return subprocess.run(cmd, capture_output=True, text=True, cwd=cwd)


def generate_plain_and(od_id, tmp_path, variant, flag):
    """Generates a project dictionary (od/test/test.eds or od/<id>/<id>.eds) twice into tmp_path:
    plain.c/.h, and <variant>.c/.h with the generator option flag. Returns the two .c paths;
    skips when that EDS is not written."""
    eds = TEST_EDS if od_id == "test" else ROOT / "od" / od_id / f"{od_id}.eds"
    if not eds.exists():
        import pytest
        pytest.skip(f"{eds} not written")
    plain, other = tmp_path / "plain.c", tmp_path / f"{variant}.c"
    for out, extra in ((plain, []), (other, [flag])):
        r = run_generator(eds, od_id, out_c=out, out_h=tmp_path / f"{out.stem}.h", extra=extra)
        assert r.returncode == 0, r.stderr
    return plain, other


def generate(eds, od_id, outdir):
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    uid = od_id.replace("-", "_")
    c, h = outdir / f"od_{uid}.c", outdir / f"od_{uid}.h"
    r = run_generator(eds, od_id, c, h)
    assert r.returncode == 0, f"eds2c.py failed on {eds}:\n{r.stderr}"
    assert r.stderr == "", r.stderr
    return c, h


def cc(compiler, args, cwd=None):
    r = subprocess.run([compiler] + [str(a) for a in args], capture_output=True, text=True, cwd=cwd)
    assert r.returncode == 0, f"{compiler} {' '.join(map(str, args))}\n{r.stderr}"
    return r


def build_exporter(c_file, od_id, outdir, compiler="gcc"):
    exe = Path(outdir) / f"od2eds_{od_id.replace('-', '_')}_{compiler}"
    cc(compiler, STRICT + [f"-I{INCLUDE}", f"-I{Path(c_file).parent}",
                           f"-DCO_OD_SYMBOL={sym(od_id)}", EXPORTER, c_file, "-o", exe])
    return exe


def export(c_file, od_id, outdir, compiler="gcc"):
    exe = build_exporter(c_file, od_id, outdir, compiler)
    r = subprocess.run([str(exe)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    path = Path(outdir) / f"exported_{od_id}.eds"
    path.write_text(r.stdout)
    return path


def load_od(path, node_id=5):
    """Loads an EDS with python-canopen; returns (od, warnings logged)."""
    import canopen

    messages = []

    class H(logging.Handler):
        def emit(self, record):
            messages.append(record.getMessage())

    h = H(logging.WARNING)
    log = logging.getLogger("canopen")
    log.addHandler(h)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            od = canopen.objectdictionary.import_od(str(path), node_id=node_id)
    finally:
        log.removeHandler(h)
    return od, messages


def raw_sections(path):
    """(index, sub) -> dict of keys, parsed the way python-canopen parses (for LowLimit/HighLimit,
    which python-canopen drops for REAL and 24/40/48/56-bit types)."""
    cp = configparser.RawConfigParser(inline_comment_prefixes=(";",))
    cp.optionxform = str
    cp.read(path, encoding="utf-8")
    out = {}
    for name in cp.sections():
        m = re.match(r"^([0-9A-Fa-f]{4})$", name)
        if m:
            out[(int(m.group(1), 16), 0, "obj")] = dict(cp.items(name))
            continue
        m = re.match(r"^([0-9A-Fa-f]{4})[Ss]ub([0-9A-Fa-f]+)$", name)
        if m:
            out[(int(m.group(1), 16), int(m.group(2), 16), "sub")] = dict(cp.items(name))
    return out


def layout_of(exported_path):
    """Parses the `; od:` and `; layout:` comments od2eds.c writes."""
    od_info, subs = {}, {}
    section = None
    for line in Path(exported_path).read_text().splitlines():
        m = re.match(r"^; od: (.*)$", line)
        if m:
            for kv in m.group(1).split():
                k, v = kv.split("=")
                od_info[k] = int(v, 0)
            continue
        m = re.match(r"^\[([0-9A-F]{4})(?:sub([0-9A-F]+))?\]$", line)
        if m:
            section = (int(m.group(1), 16), int(m.group(2), 16) if m.group(2) else 0)
            continue
        m = re.match(r"^; layout: offset=(\d+) size=(\d+) flags=(\S*) limit=(\d+)$", line)
        if m:
            subs[section] = {"offset": int(m.group(1)), "size": int(m.group(2)),
                             "flags": set(m.group(3).split("|")) - {""},
                             "limit": int(m.group(4))}
    return od_info, subs


# CiA 301 data types the tests need to know about: code -> (size in bytes or None, kind)
TYPE_INFO = {
    0x01: (1, "bool"), 0x02: (1, "int"), 0x03: (2, "int"), 0x04: (4, "int"), 0x05: (1, "uint"),
    0x06: (2, "uint"), 0x07: (4, "uint"), 0x08: (4, "real"), 0x09: (None, "vstring"),
    0x0A: (None, "ostring"), 0x0B: (None, "ustring"), 0x0C: (6, "uint"), 0x0D: (6, "uint"),
    0x0F: (0, "domain"), 0x10: (3, "int"), 0x11: (8, "real"), 0x12: (5, "int"), 0x13: (6, "int"),
    0x14: (7, "int"), 0x15: (8, "int"), 0x16: (3, "uint"), 0x18: (5, "uint"), 0x19: (6, "uint"),
    0x1A: (7, "uint"), 0x1B: (8, "uint"),
}


def type_bounds(code):
    size, kind = TYPE_INFO[code]
    if kind == "real":
        m = 3.4028234663852886e38 if size == 4 else sys.float_info.max
        return -m, m
    if kind == "bool":
        return 0, 1
    if kind == "int":
        return -(1 << (size * 8 - 1)), (1 << (size * 8 - 1)) - 1
    return 0, (1 << (size * 8)) - 1


def parse_bound(text, code):
    size, kind = TYPE_INFO[code]
    if kind == "real":
        return float(text)
    v = int(text, 0)
    if kind == "int" and text.strip().lower().startswith("0x") and v >= 1 << (size * 8 - 1):
        v -= 1 << (size * 8)
    return v


def drive_eds(od_id):
    return ROOT / "od" / od_id / f"{od_id}.eds"


OD_CASES = ("test",) + DRIVES


def eds_of(od_id):
    return TEST_EDS if od_id == "test" else drive_eds(od_id)


def variables(od):
    """(index, sub) -> ODVariable for every object from 0x1000 on, in the order of the file."""
    import canopen.objectdictionary as cod

    out = {}
    for index in sorted(od.indices):
        if index < 0x1000:
            continue
        obj = od.indices[index]
        if isinstance(obj, cod.ODVariable):
            out[(index, 0)] = obj
        else:
            for s in sorted(obj.subindices):
                out[(index, s)] = obj.subindices[s]
    return out
