"""--trace (candump -L) and several buses (--iface repeated) in one process."""
import re
import subprocess

import pytest

from canopen_sim import Control
from conftest import BIN, IFACE, TIMEOUT

LINE = re.compile(r"^\((\d+)\.(\d{6})\) (\S+) ([0-9A-F]{3})#(R[0-9A-F]?|(?:[0-9A-F]{2}){0,8})$")


def frames(path):
    out = []
    for line in path.read_text().splitlines():
        m = LINE.match(line)
        assert m, f"not a candump -L line: {line!r}"
        out.append((m.group(3), int(m.group(4), 16), m.group(5)))
    return out


def test_trace_records_both_directions(canopen_sim_factory, network, recorder, tmp_path):
    trace = tmp_path / "t.log"
    sim = canopen_sim_factory([("vf-s15", 5)], trace=trace)
    mark = recorder.mark()
    network.send_message(0x605, bytes.fromhex("4000100000000000"))  # SDO upload 0x1000
    recorder.wait_frame(0x585, bytes.fromhex("4300100092010100"), since=mark)
    network.send_message(0x705, b"", remote=True)                   # node guarding RTR
    recorder.wait_frame(0x705, b"\x7f", since=mark)                  # its answer (PRE-OP)
    sim.state(5)  # a round trip: the trace socket has read what came before
    sim.stop()
    got = frames(trace)
    assert got[0] == (IFACE, 0x705, "00")                 # the boot-up it sent
    assert (IFACE, 0x605, "4000100000000000") in got      # what it received
    assert (IFACE, 0x585, "4300100092010100") in got      # its answer
    assert (IFACE, 0x705, "R") in got                     # a remote frame
    assert got.index((IFACE, 0x705, "R")) < got.index((IFACE, 0x705, "7F"))
    assert got.index((IFACE, 0x605, "4000100000000000")) < got.index(
        (IFACE, 0x585, "4300100092010100"))


def test_trace_that_cannot_be_written(canopen_sim_factory, tmp_path):
    # cannot be opened: said at start, the simulator runs without a trace
    sim = canopen_sim_factory([("vf-s15", 5)], trace=tmp_path / "no" / "such" / "dir.log")
    sim.wait_output(r"--trace .*: No such file or directory; running without a trace",
                    stream="err")
    assert sim.state(5)["nmt"] == "PRE-OPERATIONAL"
    sim.stop()
    # opened but every write fails (a full disk): said once, tracing stops, the simulation goes on
    sim = canopen_sim_factory([("vf-s15", 6)], trace="/dev/full")
    sim.wait_output(r"--trace /dev/full: cannot write: No space left on device; tracing stopped",
                    stream="err")
    sim.nmt(6, "start")
    sim.wait_event(r"-> OPERATIONAL", node=6)
    assert sim.state(6)["nmt"] == "OPERATIONAL"


def test_two_buses_one_process(canopen_sim_factory, tmp_path):
    trace = tmp_path / "two.log"
    sim = canopen_sim_factory({IFACE: [("vf-s15", 5)], "vcan1": [("benshaw-rsi", 7)]},
                              trace=trace)
    assert sim.nodes() == [(5, "vf-s15", IFACE), (7, "benshaw-rsi", "vcan1")]
    sim.wait_output(rf"2 node\(s\) on {IFACE} and vcan1, trace ")
    sim.nmt(7, "start")
    sim.wait_event(r"PRE-OPERATIONAL -> OPERATIONAL", node=7)
    sim.stop()
    got = frames(trace)
    assert (IFACE, 0x705, "00") in got and ("vcan1", 0x707, "00") in got
    assert (IFACE, 0x707, "00") not in got and ("vcan1", 0x705, "00") not in got


@pytest.mark.parametrize("args, message", [
    (["--iface", IFACE, "--drive", "vf-s15", "--node-id", "5", "--iface", "vcan1"],
     "--iface vcan1 has no --drive"),
    (["--iface", IFACE, "--iface", "vcan1", "--drive", "vf-s15", "--node-id", "5"],
     f"--iface {IFACE} has no --drive"),
    (["--drive", "vf-s15", "--node-id", "5", "--iface", IFACE, "--iface", "vcan1", "--drive",
      "vf-s15", "--node-id", "6"], "comes before any --iface"),
    (["--iface", IFACE, "--drive", "vf-s15", "--node-id", "5", "--iface", "vcan1", "--drive",
      "vf-s15", "--node-id", "5"], "node-ID 5 given twice"),
    (["--iface", IFACE, "--drive", "vf-s15", "--node-id", "5", "--trace", ""],
     "--trace needs a file name"),
    (["--iface", IFACE, "--drive", "vf-s15", "--node-id", "5", "--trace", "a", "--trace", "b"],
     "--trace given twice"),
    (["--iface", IFACE, "--drive", "vf-s15", "--node-id", "5", "--trace", "t" * 5000],
     "--trace 'tttt"),
    (["--iface", IFACE, "--drive", "vf-s15", "--node-id", "5", "--scenario", "s" * 5000],
     "a file name of 5000 bytes is longer than any path"),
    (["--iface", IFACE, "--drive", "vf-s15", "--node-id", "5", "--scenario", ""],
     "--scenario needs a file name"),
])
def test_bus_and_trace_command_line_errors(args, message):
    r = subprocess.run([str(BIN), *args], capture_output=True, text=True, timeout=TIMEOUT,
                       stdin=subprocess.DEVNULL)
    assert r.returncode == 2 and message in r.stderr, r.stderr


def test_dbc_of_the_mapping_in_force(canopen_sim_factory, network):
    """`pdo NODE` reports the layout the master configured, and the DBC follows it."""
    import canopen
    from canopen_sim.dbc import make_dbc, parse_layout
    from drives import ROOT
    eds = str(ROOT / "od" / "vf-s15" / "vf-s15.eds")
    sim = canopen_sim_factory([("vf-s15", 5)])
    before = parse_layout(sim.command("pdo 5"))
    assert ("tpdo", 1, 0x185, [0x60410010, 0x60440010]) in before
    node = network.add_node(5, eds)
    try:
        node.sdo.RESPONSE_TIMEOUT = 2.0
        node.sdo[0x1800][1].raw = 0x80000185  # the master switches TPDO1 off
    finally:
        del network[5]
    after = parse_layout(sim.command("pdo 5"))
    assert ("tpdo", 1, 0x80000185, [0x60410010, 0x60440010]) in after
    od = canopen.import_od(eds, 5)
    assert "BO_ 389 TPDO1_vf_s15_5" in make_dbc([(od, 5, "vf-s15", None)])
    assert "BO_ 389 " not in make_dbc([(od, 5, "vf-s15", after)])
    assert "BO_ 517 RPDO1_vf_s15_5" in make_dbc([(od, 5, "vf-s15", after)])
