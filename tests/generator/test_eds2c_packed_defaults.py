"""eds2c --packed-defaults: the default value block as runs of non-zero bytes (co_od.packed_defaults,
what boards/cortex-m4 links). The runs must describe exactly the block the plain output has."""

import importlib.util
import random
import re

import pytest

from eds2c_testlib import DRIVES, GENERATOR, export, generate_plain_and
from eds2c_testlib import sym as od_sym

_spec = importlib.util.spec_from_file_location("eds2c", GENERATOR)
eds2c = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(eds2c)


def c_bytes(text, name):
    m = re.search(rf"{name}\[\d+\] = \{{(.*?)\}};", text, re.S)
    assert m, name
    body = re.sub(r"/\*.*?\*/", "", m.group(1), flags=re.S)
    return bytes(int(x, 16) for x in re.findall(r"0x([0-9A-F]{2})", body))


@pytest.mark.parametrize("od_id", ("test", "bench") + DRIVES)
def test_packed_runs_give_the_plain_block(od_id, tmp_path):
    plain, packed = generate_plain_and(od_id, tmp_path, "packed", "--packed-defaults")
    sym = od_sym(od_id)
    block = c_bytes(plain.read_text(), f"{sym}_defaults")
    text = packed.read_text()
    runs = c_bytes(text, f"{sym}_packed_defaults")
    assert eds2c.unpack_defaults(runs, len(block)) == block
    assert len(runs) < len(block)
    assert f"{sym}_defaults[" not in text  # the whole block is not linked as well
    assert re.search(rf"^    {sym}_packed_defaults,? /\* packed_defaults \*/$", text, re.M)
    # od2eds reads either form: the same EDS comes back
    plain_dir, packed_dir = tmp_path / "plain", tmp_path / "packed"
    plain_dir.mkdir()
    packed_dir.mkdir()
    for out, d in ((plain, plain_dir), (packed, packed_dir)):
        (d / f"od_{od_id.replace('-', '_')}.h").write_text((tmp_path / f"{out.stem}.h").read_text())
    assert (export(packed, od_id, packed_dir).read_text()
            == export(plain, od_id, plain_dir).read_text())


def test_pack_round_trips():
    rng = random.Random(7)
    for _ in range(500):
        n = rng.randint(0, 1500)
        block = bytearray(n)
        for _ in range(rng.randint(0, 40)):
            if n:
                at = rng.randrange(n)
                for i in range(at, min(n, at + rng.randint(1, 400))):
                    block[i] = 0 if rng.random() < 0.3 else rng.randint(1, 255)
        runs = eds2c.pack_defaults(bytes(block))
        assert eds2c.unpack_defaults(runs, n) == bytes(block)
        assert runs[-3:] == b"\0\0\0"
