"""tools/bench re-runs CMake's configure step when a build tree has CMakeCache.txt but no build
file: a configure interrupted after writing its cache used to make every later `tools/bench` stop
with "ninja: error: loading 'build.ninja'". The commands tools/bench would run are recorded, not
run."""
import importlib.machinery
import importlib.util
import subprocess
from pathlib import Path
from types import SimpleNamespace

import pytest

ROOT = Path(__file__).resolve().parents[2]


def load_bench():
    loader = importlib.machinery.SourceFileLoader("tools_bench", str(ROOT / "tools" / "bench"))
    spec = importlib.util.spec_from_loader("tools_bench", loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


@pytest.fixture
def bench(monkeypatch):
    """tools/bench as a module, with its commands recorded in bench.commands."""
    module = load_bench()
    module.commands = []

    def fake_run(cmd, **kw):
        module.commands.append([str(c) for c in cmd])
        return subprocess.CompletedProcess(cmd, 0, "", "")

    monkeypatch.setattr(module, "run", fake_run)
    monkeypatch.setattr(module.subprocess, "run", fake_run)
    return module


def configures(commands):
    return [c for c in commands if c[0] == "cmake" and "--build" not in c]


def test_interrupted_configure_is_configured_again(bench, tmp_path):
    (tmp_path / "CMakeCache.txt").write_text("CMAKE_GENERATOR:INTERNAL=Ninja\n")
    bench.build_host(SimpleNamespace(build_dir=tmp_path), ["bench"])
    assert configures(bench.commands) == [["cmake", "-S", str(ROOT), "-B", str(tmp_path)]]
    assert bench.commands[-1][:3] == ["cmake", "--build", str(tmp_path)]


def test_a_configured_tree_is_only_built(bench, tmp_path):
    (tmp_path / "CMakeCache.txt").write_text("CMAKE_GENERATOR:INTERNAL=Ninja\n")
    (tmp_path / "build.ninja").write_text("")
    bench.build_host(SimpleNamespace(build_dir=tmp_path), ["bench"])
    assert configures(bench.commands) == []
    assert bench.commands == [["cmake", "--build", str(tmp_path), "--target", "bench"]]


def test_a_tree_never_configured_is_refused(bench, tmp_path):
    with pytest.raises(SystemExit, match="is not configured"):
        bench.build_host(SimpleNamespace(build_dir=tmp_path), ["bench"])
    assert bench.commands == []
