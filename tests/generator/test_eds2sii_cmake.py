"""cmake/EcatSii.cmake in a throwaway project: the SII image, its header and the ESI file are
generated at build time into ${CMAKE_BINARY_DIR}/sii, the sii_<id> library links and carries the
include dir, esi_<id> builds the ESI file alone, unchanged inputs do not regenerate, a changed
choices file does, and a bad one fails the build with the generator's FILE:LINE message."""

import shutil
import subprocess
import sys

import pytest

from eds2sii_testlib import MB1_CHOICES, MB1_EDS, ROOT, Sii

pytestmark = pytest.mark.skipif(shutil.which("cmake") is None, reason="cmake not installed")


def run(cmd, cwd, ok=True):
    r = subprocess.run([str(c) for c in cmd], cwd=cwd, capture_output=True, text=True)
    if ok:
        assert r.returncode == 0, f"{' '.join(map(str, cmd))}\n{r.stdout}\n{r.stderr}"
    return r


def test_canopen_add_sii(tmp_path):
    src, build = tmp_path / "src", tmp_path / "build"
    src.mkdir()
    shutil.copyfile(MB1_EDS, src / "mb1.eds")
    shutil.copyfile(MB1_CHOICES, src / "mb1.ini")
    (src / "CMakeLists.txt").write_text(f"""cmake_minimum_required(VERSION 3.20)
project(sii_cmake_test C)
set(CMAKE_C_STANDARD 99)
set(CANOPEN_WARNINGS -Wall -Wextra -Wpedantic -Werror)
include("{ROOT}/cmake/EcatSii.cmake")
canopen_add_sii(mb1-test mb1.eds "${{CMAKE_CURRENT_SOURCE_DIR}}/mb1.ini")
add_executable(main main.c)
target_link_libraries(main PRIVATE sii_mb1_test)
""")
    (src / "main.c").write_text("""#include <stdio.h>
#include "sii_mb1_test.h"
int main(void)
{
    unsigned i;
    for (i = 0; i < co_sii_mb1_test_size; i++)
        printf("%02x", co_sii_mb1_test[i]);
    printf("\\n");
    return co_sii_mb1_test_size == CO_SII_MB1_TEST_SIZE ? 0 : 1;
}
""")
    gen = ["-G", "Ninja"] if shutil.which("ninja") else []
    run(["cmake", "-S", src, "-B", build, f"-DPython3_EXECUTABLE={sys.executable}"] + gen, tmp_path)

    # the ESI target alone
    r = run(["cmake", "--build", build, "--target", "esi_mb1_test"], tmp_path)
    assert "Generating SII image and ESI mb1-test" in r.stdout
    assert (build / "sii" / "mb1-test.xml").exists()
    assert not (build / "main").exists()

    r = run(["cmake", "--build", build], tmp_path)
    assert "Generating SII image" not in r.stdout        # generated above, inputs unchanged
    image = bytes.fromhex(run([build / "main"], tmp_path).stdout.strip())
    sii = Sii(image)
    assert sii.u32(0x0A) == 0xE1

    r = run(["cmake", "--build", build], tmp_path)
    assert "Generating SII image" not in r.stdout

    # a changed choices file is regenerated
    ini = src / "mb1.ini"
    ini.write_text(ini.read_text().replace("Alias=0", "Alias=7"))
    r = run(["cmake", "--build", build], tmp_path)
    assert "Generating SII image and ESI mb1-test" in r.stdout
    assert Sii(bytes.fromhex(run([build / "main"], tmp_path).stdout.strip())).words[4] == 7

    # a broken one fails the build with the generator's message
    ini.write_text(ini.read_text().replace("OutputsControl=0x64", "OutputsControl=0x66"))
    r = run(["cmake", "--build", build], tmp_path, ok=False)
    assert r.returncode != 0
    assert f"{ini}:" in r.stdout + r.stderr
    assert "error: [ProcessData] OutputsControl 0x66" in r.stdout + r.stderr
