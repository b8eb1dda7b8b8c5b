"""python/canopen_sim is pip-installable from its folder: a wheel builds (offline, with the
installed setuptools) and holds the modules and the pytest11 entry point."""
import subprocess
import sys
import zipfile
from pathlib import Path

PKG = Path(__file__).resolve().parents[2] / "python" / "canopen_sim"


def test_wheel_builds_with_modules_and_pytest_entry_point(tmp_path):
    r = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
                        "--disable-pip-version-check", "-q", "-w", str(tmp_path), str(PKG)],
                       capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    wheels = list(tmp_path.glob("canopen_sim-*.whl"))
    assert len(wheels) == 1
    names = zipfile.ZipFile(wheels[0]).namelist()
    for module in ("control", "lines", "simulator", "pytest_plugin", "dbc", "view", "__init__"):
        assert f"canopen_sim/{module}.py" in names
    ep = next(n for n in names if n.endswith("entry_points.txt"))
    text = zipfile.ZipFile(wheels[0]).read(ep).decode()
    assert "[pytest11]" in text and "canopen_sim.pytest_plugin = canopen_sim.pytest_plugin" in text
