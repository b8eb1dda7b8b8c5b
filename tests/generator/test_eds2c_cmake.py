"""cmake/CanopenOd.cmake in a throwaway project that uses the real include/ headers: the tables are
generated at build time into ${CMAKE_BINARY_DIR}/od, the od_<id> library links and carries the
include dir, an unchanged EDS does not regenerate, a changed one does, and a bad EDS fails the
build with the generator's FILE:LINE message."""

import shutil
import subprocess
import sys

import pytest

from eds2c_testlib import FIXTURES, INCLUDE, ROOT, TEST_EDS

pytestmark = pytest.mark.skipif(shutil.which("cmake") is None, reason="cmake not installed")


def run(cmd, cwd, ok=True):
    r = subprocess.run([str(c) for c in cmd], cwd=cwd, capture_output=True, text=True)
    if ok:
        assert r.returncode == 0, f"{' '.join(map(str, cmd))}\n{r.stdout}\n{r.stderr}"
    return r


def test_canopen_add_od(tmp_path):
    src, build = tmp_path / "src", tmp_path / "build"
    src.mkdir()
    shutil.copyfile(TEST_EDS, src / "test.eds")
    shutil.copyfile(FIXTURES / "ok_minimal.eds", src / "mini.eds")
    (src / "CMakeLists.txt").write_text(f"""cmake_minimum_required(VERSION 3.20)
project(od_cmake_test C)
set(CMAKE_C_STANDARD 99)
set(CMAKE_C_STANDARD_REQUIRED ON)
set(CMAKE_C_EXTENSIONS OFF)
set(CANOPEN_WARNINGS -Wall -Wextra -Wpedantic -Werror -Wshadow -Wstrict-prototypes
    -Wmissing-prototypes)
# stand-in for the core target: only the real public headers
add_library(canopen INTERFACE)
target_include_directories(canopen INTERFACE "{INCLUDE}")
include("{ROOT}/cmake/CanopenOd.cmake")
canopen_add_od(test "${{CMAKE_CURRENT_SOURCE_DIR}}/test.eds" EXPORTER)
canopen_add_od(mini-fixture mini.eds)
add_executable(main main.c)
target_link_libraries(main PRIVATE od_test od_mini_fixture)
""")
    (src / "main.c").write_text("""#include <stdio.h>
#include "od_test.h"
#include "od_mini_fixture.h"
int main(void)
{
    printf("%u %u %u\\n", (unsigned)co_od_test.value_size, (unsigned)CO_OD_TEST_VALUE_SIZE,
           (unsigned)co_od_mini_fixture.entry_count);
    return co_od_test.value_size == CO_OD_TEST_VALUE_SIZE ? 0 : 1;
}
""")
    gen = ["-G", "Ninja"] if shutil.which("ninja") else []
    run(["cmake", "-S", src, "-B", build, f"-DPython3_EXECUTABLE={sys.executable}"] + gen, tmp_path)
    r = run(["cmake", "--build", build], tmp_path)
    assert "Generating object dictionary test" in r.stdout
    assert (build / "od" / "od_test.c").exists() and (build / "od" / "od_test.h").exists()
    assert (build / "od" / "od_mini_fixture.h").exists()
    out = run([build / "main"], tmp_path).stdout.split()
    assert out[0] == out[1] and int(out[2]) == 14
    exported = run([build / "od2eds_test"], tmp_path).stdout
    assert "[6040]" in exported

    # up to date: nothing regenerated
    r = run(["cmake", "--build", build], tmp_path)
    assert "Generating object dictionary" not in r.stdout

    # a changed EDS is regenerated
    eds = src / "test.eds"
    eds.write_text(eds.read_text().replace("DefaultValue=canopen-test", "DefaultValue=changed"))
    r = run(["cmake", "--build", build], tmp_path)
    assert "Generating object dictionary test" in r.stdout
    assert "Generating object dictionary mini-fixture" not in r.stdout
    assert '"changed"' not in (build / "od" / "od_test.c").read_text()  # bytes, not a literal
    assert "0x63, 0x68, 0x61, 0x6E, 0x67, 0x65, 0x64" in (build / "od" / "od_test.c").read_text()

    # a broken EDS fails the build with the generator's message
    shutil.copyfile(FIXTURES / "unknown_data_type.eds", src / "mini.eds")
    r = run(["cmake", "--build", build], tmp_path, ok=False)
    assert r.returncode != 0
    assert f"{src / 'mini.eds'}:" in r.stdout + r.stderr
    assert "error: [1017] unknown data type 0x0017" in r.stdout + r.stderr
