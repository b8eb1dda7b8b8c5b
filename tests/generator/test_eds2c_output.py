"""The generated C: strict C99 under gcc and clang, const tables only, a header with the
documented names, deterministic bytes."""

import os
import re
import shutil
import subprocess

import pytest

from eds2c_testlib import (EXTRA, INCLUDE, OD_CASES, ROOT, STRICT, cc, compilers, run_generator,
                           sym)


@pytest.mark.parametrize("compiler", compilers())
@pytest.mark.parametrize("od_id", OD_CASES)
def test_compiles_strict_c99(od_id, compiler, generated, tmp_path):
    """-std=c99 -Wall -Wextra -Wpedantic -Werror (plus conversion/shadow/cast-align/prototype
    warnings), with and without the name tables."""
    _, c, _ = generated(od_id)
    for extra in ([], ["-DCO_OD_NO_NAMES"]):
        cc(compiler, STRICT + EXTRA + extra + [f"-I{INCLUDE}", f"-I{c.parent}", "-c", c,
                                               "-o", tmp_path / "od.o"])


@pytest.mark.parametrize("od_id", OD_CASES)
def test_no_writable_globals(od_id, generated, tmp_path):
    """Every table is const: nothing in .data/.bss, and without PIC every symbol is read-only."""
    _, c, _ = generated(od_id)
    compiler = compilers()[0]
    for pic in ("-fno-pic", "-fPIC"):
        obj = tmp_path / f"od{pic}.o"
        cc(compiler, STRICT + [pic, f"-I{INCLUDE}", f"-I{c.parent}", "-c", c, "-o", obj])
        heads = subprocess.run(["objdump", "-h", str(obj)], capture_output=True, text=True,
                               check=True).stdout
        for m in re.finditer(r"^\s*\d+\s+(\S+)\s+([0-9a-f]+)", heads, re.M):
            if m.group(1) in (".data", ".bss") or m.group(1).startswith((".data.", ".bss.")) \
                    and not m.group(1).startswith(".data.rel.ro"):
                assert int(m.group(2), 16) == 0, f"{m.group(1)} is not empty with {pic}"
        if pic == "-fno-pic":
            syms = subprocess.run(["nm", str(obj)], capture_output=True, text=True,
                                  check=True).stdout.split("\n")
            kinds = {line.split()[-2] for line in syms if line.strip()}
            assert kinds <= {"R", "r"}, f"non read-only symbols: {syms}"


@pytest.mark.parametrize("od_id", OD_CASES)
def test_header_declares_table_and_sizes(od_id, generated, tmp_path):
    _, c, h = generated(od_id)
    up = od_id.replace("-", "_").upper()
    text = h.read_text()
    assert re.search(rf"^#define CO_OD_{up}_VALUE_SIZE \d+u$", text, re.M)
    assert re.search(rf"^extern const co_od {sym(od_id)};$", text, re.M)
    main = tmp_path / "main.c"
    main.write_text(f"""#include <stdio.h>
#include <string.h>
#include "{h.name}"
int main(void)
{{
    int ok = co_od_{od_id.replace('-', '_')}.value_size == CO_OD_{up}_VALUE_SIZE
        && {sym(od_id)}.comm_persist_size == CO_OD_{up}_COMM_PERSIST_SIZE
        && {sym(od_id)}.persist_size == CO_OD_{up}_PERSIST_SIZE
        && {sym(od_id)}.layout_hash == CO_OD_{up}_LAYOUT_HASH
        && {sym(od_id)}.entry_count == CO_OD_{up}_ENTRY_COUNT
        && strcmp({sym(od_id)}.name, "{od_id}") == 0
        && {sym(od_id)}.value_size % 8u == 0u;
    static unsigned char block[CO_OD_{up}_VALUE_SIZE + 1u];
    (void)block;
    puts(ok ? "OK" : "MISMATCH");
    return ok ? 0 : 1;
}}
""")
    exe = tmp_path / "main"
    cc(compilers()[0], STRICT + [f"-I{INCLUDE}", f"-I{c.parent}", main, c, "-o", exe])
    r = subprocess.run([str(exe)], capture_output=True, text=True)
    assert r.returncode == 0 and r.stdout.strip() == "OK"


@pytest.mark.parametrize("od_id", OD_CASES)
def test_deterministic(od_id, generated, tmp_path):
    """Byte-identical on a re-run from another directory with a relative path; no timestamps, no
    absolute paths in the output. (Runs on a private copy: the drive EDS files are edited while
    this suite runs.)"""
    eds, _, _ = generated(od_id)
    src = tmp_path / "src"
    src.mkdir()
    copy = src / eds.name
    shutil.copyfile(eds, copy)
    uid = od_id.replace("-", "_")
    outs = []
    for n, (path, cwd) in enumerate(((copy, "/"), (os.path.relpath(copy, tmp_path), tmp_path))):
        d = tmp_path / f"run{n}"
        d.mkdir()
        r = run_generator(path, od_id, d / f"od_{uid}.c", d / f"od_{uid}.h", cwd=cwd)
        assert r.returncode == 0, r.stderr
        outs.append(((d / f"od_{uid}.c").read_bytes(), (d / f"od_{uid}.h").read_bytes()))
    assert outs[0] == outs[1]
    text = (outs[0][0] + outs[0][1]).decode()
    assert str(ROOT) not in text and str(tmp_path) not in text
    assert not re.search(r"\b20\d\d-\d\d-\d\d\b|\d\d:\d\d:\d\d", text), "looks like a timestamp"


def test_rule_comment_at_top_of_generator():
    head = (ROOT / "tools" / "eds2c.py").read_text()[:6000]
    assert "WHICH VALUES ARE PERSISTENT" in head
    assert "0x1010" in head and "PDOMapping" in head


@pytest.mark.parametrize("compiler", compilers())
def test_dictionary_without_limits_compiles(compiler, tmp_path):
    """No LowLimit/HighLimit anywhere: limits = NULL, limit_count = 0 (C99 has no empty arrays)."""
    from eds2c_testlib import FIXTURES, generate

    text = "\n".join(line for line in (FIXTURES / "ok_minimal.eds").read_text().splitlines()
                     if not line.startswith(("LowLimit", "HighLimit")))
    (tmp_path / "nolim.eds").write_text(text + "\n")
    c, _ = generate(tmp_path / "nolim.eds", "nolim", tmp_path)
    src = c.read_text()
    assert "co_od_limit " not in src and "    NULL,\n" in src
    cc(compiler, STRICT + EXTRA + [f"-I{INCLUDE}", f"-I{tmp_path}", "-c", c,
                                   "-o", tmp_path / "o.o"])
