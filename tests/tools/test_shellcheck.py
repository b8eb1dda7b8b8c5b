"""Every shell script of the repository passes shellcheck at severity warning (tools/setup
installs shellcheck: a missing one fails, it is not skipped)."""
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def shell_scripts():
    """Files under tools/, tests/tools/ and .ci/ whose first line names sh or bash."""
    found = []
    for folder in ("tools", "tests/tools", ".ci", "boards"):
        for path in sorted((ROOT / folder).rglob("*")):
            if not path.is_file() or path.suffix in (".py", ".c", ".h", ".md"):
                continue
            with open(path, "rb") as f:
                first = f.readline()
            if first.startswith(b"#!") and (b"bash" in first or first.rstrip().endswith(b"/sh")):
                found.append(path)
    return found


def test_the_scripts_are_found():
    names = {p.relative_to(ROOT).as_posix() for p in shell_scripts()}
    assert {"tools/test-all", "tools/setup", "tools/vcan-run", "tools/veth-run", "tools/fuzz",
            ".ci/run"} <= names, names


@pytest.mark.parametrize("script", shell_scripts(), ids=lambda p: p.relative_to(ROOT).as_posix())
def test_shellcheck(script):
    exe = shutil.which("shellcheck")
    assert exe, "shellcheck is not installed (tools/setup installs it)"
    r = subprocess.run([exe, "-S", "warning", str(script)], capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
