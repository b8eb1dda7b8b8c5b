"""A second EDS validator beside tools/eds2c.py: Lely's dcfchk (PyPI package dcf-tools, installed
by tools/setup) must accept every od/*/*.eds with a node-ID given (1 and 127, so every $NODEID
value is checked at both ends), its PDO mappings printed (-p, which resolves them).

Every message dcfchk prints must be a departure written down in that dictionary's NOTES.md: a
section headed `## dcfchk departures` with one bullet per message, the message in backquotes
first, then why (the manual's section that forces it). A listed departure dcfchk no longer reports
fails too, so the list stays true."""
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DICTIONARIES = sorted({eds.parent for eds in (ROOT / "od").glob("*/*.eds")})
NODE_IDS = (1, 127)
MESSAGE_RE = re.compile(r"UserWarning: (.*)$")
SECTION_RE = re.compile(r"^## dcfchk departures\s*$(.*?)(?=^## |\Z)", re.M | re.S)
BULLET_RE = re.compile(r"^- `([^`]+)`", re.M)


def departures(folder):
    """The messages listed in folder/NOTES.md under '## dcfchk departures'."""
    notes = folder / "NOTES.md"
    if not notes.exists():
        return set()
    m = SECTION_RE.search(notes.read_text())
    return set(BULLET_RE.findall(m.group(1))) if m else set()


def dcfchk(eds, node_id):
    """(exit status, messages, output) of `dcfchk -n node_id -p eds`."""
    try:
        import dcf.cli  # noqa: F401
    except ImportError:
        pytest.fail("dcfchk is missing: run tools/setup (pip package dcf-tools)", pytrace=False)
    # -m dcf.cli is the dcfchk script's entry point, run by this interpreter whatever PATH holds
    r = subprocess.run([sys.executable, "-W", "always::UserWarning", "-m", "dcf.cli", "-n",
                        str(node_id), "-p", str(eds)], capture_output=True, text=True, timeout=120)
    messages = [m.group(1) for m in map(MESSAGE_RE.search, r.stderr.splitlines()) if m]
    return r.returncode, messages, r.stderr


@pytest.mark.parametrize("folder", DICTIONARIES, ids=[d.name for d in DICTIONARIES])
def test_dcfchk_accepts_every_eds_but_the_listed_departures(folder):
    allowed = departures(folder)
    seen = set()
    for eds in sorted(folder.glob("*.eds")):
        for node_id in NODE_IDS:
            rc, messages, output = dcfchk(eds, node_id)
            where = f"{eds.relative_to(ROOT)} (node-ID {node_id})"
            unlisted = [m for m in messages if m not in allowed]
            assert not unlisted, (f"dcfchk on {where}: {unlisted} not listed under "
                                  f"'## dcfchk departures' in {folder.relative_to(ROOT)}/NOTES.md")
            assert rc == 0 or messages, f"dcfchk on {where} failed without a message:\n{output}"
            seen.update(messages)
    stale = allowed - seen
    assert not stale, (f"{folder.relative_to(ROOT)}/NOTES.md lists dcfchk departures it no "
                       f"longer reports: {sorted(stale)}")


def test_departure_lists_are_read():
    """The parser of the lists finds the ST600's (its manual's 16-bit sub 0)."""
    assert "DataType should be UNSIGNED8 in [2000sub0]" in departures(
        ROOT / "od" / "sourcetronic-st600")
