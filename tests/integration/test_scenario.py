"""--scenario: the example files run against a simulated drive, and bad files are refused at
start with the file, line and reason. (Parser and scheduler: unit test test_scenario.)"""
import subprocess
import time

import pytest

from canopen_sim import SimulatorError
from conftest import BIN, IFACE, TIMEOUT
from drives import ROOT

EXAMPLES = ROOT / "examples" / "scenarios"


def test_heartbeat_loss_example(canopen_sim_factory, network, recorder):
    sim = canopen_sim_factory([("vf-s15", 5)], scenario=EXAMPLES / "heartbeat-loss.txt")
    node = network.add_node(5, str(ROOT / "od" / "vf-s15" / "vf-s15.eds"))
    try:
        node.sdo.RESPONSE_TIMEOUT = 2.0
        node.sdo[0x1017].raw = 100             # heartbeat every 100 ms
        mark = recorder.mark()
        network.send_message(0, [0x01, 5])     # NMT start: the scenario's condition
        ev = sim.wait_event(r"muted: sends nothing", node=5, timeout=3 * TIMEOUT)
        recorder.wait_frame(0x705, b"\x05", since=mark)
        sim.wait_output(r"scenario .*heartbeat-loss\.txt:7 at \d+\.\d+ s: mute 5")
        silent = recorder.mark()
        back = sim.wait_event(r"unmuted: sends again", node=5, timeout=4 + TIMEOUT)
        assert back.time >= 4.0 and back.time - ev.time > 1.0
        hb = recorder.wait_frame(0x705, b"\x05", since=silent)
        # nothing from node 5 between the mute and the unmute
        quiet = recorder.since(silent, lambda m: m.arbitration_id == 0x705)
        assert quiet[0] is hb
    finally:
        del network[5]


def test_load_step_example(canopen_sim_factory, network):
    sim = canopen_sim_factory([("vacon-optc6", 5)], scenario=EXAMPLES / "load-step.txt")
    node = network.add_node(5, str(ROOT / "od" / "vacon-optc6" / "vacon-optc6.eds"))
    try:
        node.sdo.RESPONSE_TIMEOUT = 2.0
        network.send_message(0, [0x01, 5])     # NMT start
        for cw in (0x0006, 0x0007, 0x000F):    # Drive Profile: RUN (manual §7.5)
            node.sdo[0x6040].raw = cw
        assert node.sdo[0x2003].raw == 300     # no load: the magnetising current, 3.00 A
        node.sdo[0x6042].raw = 1500
        ev = sim.wait_event(r"load 80 % of rated torque", node=5, timeout=10 + TIMEOUT)
        assert node.sdo[0x6044].raw == 1500    # the speed stays
        assert node.sdo[0x2003].raw == 820     # 8.20 A
        assert node.sdo[0x2004].raw == 800     # 80.0 %
        assert sim.state(5)["load"] == 80
        node.sdo[0x6040].raw = 0x0006          # shutdown: the output goes off
        # the monitors show it from the drive's next tick (the write is answered before it), as a
        # real drive's monitors lag its output by a scan: poll briefly
        deadline = time.monotonic() + 2.0
        while (node.sdo[0x2003].raw, node.sdo[0x2004].raw) != (0, 0):
            assert time.monotonic() < deadline, "the monitors still show a load with the output off"
            time.sleep(0.01)
        assert ev.time >= 2.0
    finally:
        del network[5]


def test_trip_example_is_a_valid_file(canopen_sim_factory):
    sim = canopen_sim_factory([("vf-s15", 5)], scenario=EXAMPLES / "trip-at-speed.txt")
    assert sim.state(5)["fault"] is None  # nothing happens until the drive reaches speed


def test_at_steps_on_the_simulator(canopen_sim_factory, tmp_path):
    f = tmp_path / "s.txt"
    f.write_text("at 0.2: nmt 5 start\n"
                 "when 5 nmt OPERATIONAL after 0.3: fault 5 0x01\n"
                 "when 5 fault after 0.2: clear 5\n")
    sim = canopen_sim_factory([("vf-s15", 5)], scenario=f)
    # stdout from the start (the steps may run before a control client subscribes)
    at = [float(sim.wait_output(rf"scenario .*s\.txt:{line} at (\d+\.\d+) s: {cmd}").group(1))
          for line, cmd in ((1, "nmt 5 start"), (2, "fault 5 0x01"), (3, "clear 5"))]
    sim.wait_output(r"node 5 vf-s15: fault cause cleared")
    assert at[0] >= 0.2 and at[1] - at[0] >= 0.3 and at[2] - at[1] >= 0.2, at
    out = "\n".join(sim.out)
    order = [out.index(s) for s in ("s.txt:1 at", "NMT PRE-OPERATIONAL -> OPERATIONAL",
                                    "s.txt:2 at", "fault: trip 0x01 OC1", "s.txt:3 at",
                                    "fault cause cleared")]
    assert order == sorted(order)
    assert sim.state(5)["fault"] == {"trip": 1, "emcy": 0x2310, "name": "OC1", "cause": False}


@pytest.mark.parametrize("text, message", [
    ("at 1: nmt 5 start\nat soon: quit\n", "s.txt:2: 'at' wants SECONDS"),
    ("when 6 fault: quit\n", "s.txt:1: no node 6 in this simulator"),
    ("at 1: fault 5\n", "s.txt:1: usage: fault NODE TRIP"),
    ("when 5 state RUNNING: quit\n", "s.txt:1: 'state' wants a CiA 402 state"),
    ("\x00", "holds a NUL byte"),
    ("at 1: load 5 250\n", "s.txt:1: '250' is not a load (0..200 % of rated torque)"),
])
def test_bad_scenario_refused_at_start(tmp_path, text, message):
    f = tmp_path / "s.txt"
    f.write_text(text)
    r = subprocess.run([str(BIN), "--iface", IFACE, "--drive", "vf-s15", "--node-id", "5",
                        "--scenario", str(f)], capture_output=True, text=True, timeout=TIMEOUT,
                       stdin=subprocess.DEVNULL)
    assert r.returncode == 2 and message in r.stderr, r.stderr


def test_missing_scenario_file(tmp_path):
    r = subprocess.run([str(BIN), "--iface", IFACE, "--drive", "vf-s15", "--node-id", "5",
                        "--scenario", str(tmp_path / "nope")], capture_output=True, text=True,
                       timeout=TIMEOUT, stdin=subprocess.DEVNULL)
    assert r.returncode == 2 and "No such file or directory" in r.stderr
