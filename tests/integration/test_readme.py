"""The README's examples run as written: its python-canopen master against a simulated VF-S15."""
import re
import subprocess
import sys

from conftest import TIMEOUT
from drives import ROOT


def readme_python_blocks():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    return re.findall(r"^```python\n(.*?)^```", text, flags=re.S | re.M)


def test_readme_python_canopen_example(sims):
    blocks = [b for b in readme_python_blocks() if "BaseNode402" in b]
    assert len(blocks) == 1, "the README has one python-canopen master example"
    sim = sims.start([("vf-s15", 5)])
    mark = sim.out_mark()
    # As a user runs it: a fresh interpreter, from the repository's top (the EDS path is relative).
    r = subprocess.run([sys.executable, "-c", blocks[0]], cwd=ROOT, capture_output=True,
                       text=True, timeout=10 * TIMEOUT)
    assert r.returncode == 0, f"the README example failed:\n{r.stderr[-2000:]}"
    assert r.stdout.strip().splitlines()[-1] == "OPERATION ENABLED"
    # and the drive itself says so
    sim.wait_out(r"node 5 vf-s15: NMT PRE-OPERATIONAL -> OPERATIONAL", since=mark)
    sim.wait_out(r"node 5 vf-s15: CiA 402 SWITCHED ON -> OPERATION ENABLED", since=mark)
