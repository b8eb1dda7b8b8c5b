"""The canopen-drive process itself: command line, standard input, signals, several drives in one
process, and the can-utils (candump, cansend) seeing and driving the simulated drives."""
import os
import select
import shutil
import signal
import struct
import subprocess
import time

import can
import pytest

from conftest import BIN, IFACE, TIMEOUT, Sim
from drives import DRIVES, BY_ID


def run(*args, timeout=TIMEOUT):
    return subprocess.run([str(BIN), *args], capture_output=True, text=True, timeout=timeout,
                          stdin=subprocess.DEVNULL)


# --- command line ------------------------------------------------------------------------------------

def test_help_and_list_drives(network):
    r = run("--help")
    assert r.returncode == 0 and "--iface" in r.stdout and "fault NODE TRIP" in r.stdout
    r = run("--list-drives")
    assert r.returncode == 0
    ids = [line.split()[0] for line in r.stdout.splitlines() if not line[:1].isspace()]
    # the five drives, and the benchmark device of tools/bench --vcan (not a drive)
    assert sorted(ids) == sorted([d.id for d in DRIVES] + ["bench"])


@pytest.mark.parametrize("args, message", [
    ([], "--iface is required"),
    (["--iface", IFACE], "no drive given"),
    (["--iface", IFACE, "--drive", "nope", "--node-id", "5"], "unknown drive 'nope'"),
    (["--iface", IFACE, "--drive", "vf-s15", "--node-id", "0"], "not a number in 1..127"),
    (["--iface", IFACE, "--drive", "vf-s15", "--node-id", "128"], "not a number in 1..127"),
    (["--iface", IFACE, "--drive", "vf-s15", "--node-id", "5x"], "not a number in 1..127"),
    (["--iface", IFACE, "--drive", "vf-s15", "--node-id", "5", "--drive", "vf-s15",
      "--node-id", "5"], "node-ID 5 given twice"),
    (["--iface", IFACE, "--drive", "vf-s15"], "1 --drive but 0 --node-id"),
    (["--iface", IFACE, "--drive", "vf-s15", "--node-id"], "needs a value"),
    (["--iface", IFACE, "--drive", "--node-id", "5"], "needs a value"),
    (["--iface", IFACE, "--drive", "vf-s15", "--node-id", "5", "--bogus"], "unknown option"),
    (["--iface", IFACE, "--drive", "vf-s15", "--node-id", "5", "extra"], "unexpected argument"),
    (["--iface", IFACE, "--drive", "vf-s15", "--node-id", "5", "--sdo-timeout", "0"],
     "not a number of milliseconds in 1..2147483"),
    (["--iface", IFACE, "--drive", "vf-s15", "--node-id", "5", "--sdo-timeout", "2147484"],
     "not a number of milliseconds in 1..2147483"),
    (["--iface", IFACE, "--set", "a=1", "--drive", "vf-s15", "--node-id", "5"], "after the --drive"),
    (["--iface", IFACE, "--drive", "vf-s15", "--set", "nope=1", "--node-id", "5"],
     "has no setting 'nope'"),
    (["--iface", IFACE, "--drive", "vf-s15", "--set", "preset_speed=99999", "--node-id", "5"],
     "not a number in 0..30000"),
    (["--iface", IFACE, "--iface", IFACE, "--drive", "vf-s15", "--node-id", "5"],
     f"--iface {IFACE} given twice"),
    (["--iface", IFACE, "--drive", "vf-s15", "--node-id", "5", "--store", "a", "--store", "b"],
     "--store given twice"),
    (["--iface", IFACE, "--drive", "vf-s15", "--node-id", "5", "--store", ""],
     "--store needs a file name"),
], ids=lambda v: v if isinstance(v, str) else None)
def test_usage_errors_exit_2(network, args, message):
    r = run(*args)
    assert r.returncode == 2, r.stderr
    assert message in r.stderr and "--help" in r.stderr
    assert r.stdout == ""


def test_long_and_binary_arguments_are_cut_and_escaped(network):
    """A 120 kB argument is not echoed whole, nor a control byte raw."""
    huge = "x" * (120 * 1024)
    r = run("--iface", IFACE, "--drive", huge, "--node-id", "5")
    assert r.returncode == 2
    assert f"unknown drive '{'x' * 64}...'" in r.stderr
    assert len(r.stderr) < 2000, f"{len(r.stderr)} bytes of message"
    r = run("--iface", IFACE, "--drive", "vf-s15", "--node-id", "5\x1b[2J\x07")
    assert r.returncode == 2
    assert "node-ID '5\\x1B[2J\\x07' is not a number" in r.stderr
    assert "\x1b" not in r.stderr and "\x07" not in r.stderr
    r = run("--iface", "i" * 5000, "--drive", "vf-s15", "--node-id", "5")
    assert r.returncode == 2 and "is not an interface name" in r.stderr
    assert len(r.stderr) < 1000


def test_missing_interface_is_a_clear_error(network):
    r = run("--iface", "nocan9", "--drive", "vf-s15", "--node-id", "5")
    assert r.returncode == 1
    assert "nocan9" in r.stderr and "vcan" in r.stderr


# --- the store file -----------------------------------------------------------------------------------

def test_a_store_file_serves_one_process(sims, nodes, tmp_path):
    """Two processes on one store file: B's save would silently replace A's acknowledged one (A
    node 5 saves 0x1017=111, B node 6 saves 222, A restarted reads the default). B must refuse to
    start, saying who holds the file, and A's save must survive."""
    store = tmp_path / "store.bin"
    a = sims.start([("vf-s15", 5)], store=store)
    node = nodes(BY_ID["vf-s15"])
    node.sdo[0x1017].raw = 111
    node.sdo.download(0x1010, 1, struct.pack("<I", 0x65766173))  # "save"
    r = run("--iface", IFACE, "--drive", "vf-s15", "--node-id", "6", "--store", str(store))
    assert r.returncode == 1, r.stderr
    assert "in use by another process" in r.stderr
    assert f"(process {a.proc.pid})" in r.stderr and "store.bin.lock" in r.stderr
    assert r.stdout == ""
    assert a.stop() == 0
    sims.start([("vf-s15", 5)], store=store)  # A again: the lock went with the process
    assert node.sdo[0x1017].raw == 111


@pytest.mark.parametrize("kind", ["fifo", "directory", "dev-zero", "2GB"])
def test_a_store_that_is_not_a_store_file_is_refused(network, tmp_path, kind):
    """Each of these used to hang (the FIFO) or start with 'cannot read it to the end'."""
    path = tmp_path / "store"
    if kind == "fifo":
        os.mkfifo(path)
        want = "is a FIFO (named pipe), not a regular file"
    elif kind == "directory":
        path.mkdir()
        want = "is a directory, not a regular file"
    elif kind == "dev-zero":
        path.symlink_to("/dev/zero")
        want = "is a character device, not a regular file"
    else:
        with open(path, "wb") as f:
            f.truncate(2 << 30)  # sparse
        want = "is 2147483648 bytes, larger than any store file can be (at most "
    r = run("--iface", IFACE, "--drive", "vf-s15", "--node-id", "5", "--store", str(path))
    assert r.returncode == 1, r.stderr
    assert f"store {path}: {want}" in r.stderr
    assert not (tmp_path / "store.lock").exists()


# --- standard input and signals -----------------------------------------------------------------------

@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_signals_stop_cleanly(sims, sig):
    sim = sims.start([("vf-s15", 5)])
    assert sim.stop(sig) == 0
    sim.wait_out(r"stopping")


def test_quit_command(sims):
    sim = sims.start([("vf-s15", 5)])
    # like every other command, quit refuses words it does not take
    for line in ("quit now", "exit 0", "help me"):
        mark = sim.err_mark()
        sim.send(line)
        sim.wait_err(r"usage: (quit|exit|help) \(no arguments\)", since=mark)
    assert sim.proc.poll() is None
    sim.send("quit")
    assert sim.proc.wait(TIMEOUT) == 0


def test_binary_and_long_commands_are_echoed_escaped_and_cut(sims):
    sim = sims.start([("vf-s15", 5)])
    sim.proc.stdin.write("\x1b[2J\x01\x7f\n")
    sim.proc.stdin.flush()
    m = sim.wait_err(r"unknown command '(.*)' \(try")
    assert m.group(1) == "\\x1B[2J\\x01\\x7F"
    mark = sim.err_mark()
    sim.send("z" * 400)
    m = sim.wait_err(r"unknown command '(.*)' \(try", since=mark)
    assert m.group(1) == "z" * 64 + "..."
    mark = sim.err_mark()
    sim.send("fault 5 " + "9" * 300)
    m = sim.wait_err(r"'(.*)' is not a trip code", since=mark)
    assert m.group(1) == "9" * 64 + "..."
    assert sim.proc.poll() is None


def test_an_interface_that_is_down_gets_a_warning(network, tmp_path):
    """vcan9, created down: the simulator starts (frames wait until it is up) but says so."""
    if subprocess.run(["ip", "link", "add", "dev", "vcan9", "type", "vcan"],
                      capture_output=True).returncode != 0:
        pytest.skip("cannot create a vcan interface here (needs root and the vcan module)")
    try:
        sim = Sim(["--iface", "vcan9", "--drive", "vf-s15", "--node-id", "5"])
        try:
            sim.wait_err(r"warning: interface vcan9 is down: .*ip link set vcan9 up")
            sim.wait_out(r"ready")
        finally:
            assert sim.stop() == 0
        # an interface that is up gets no warning
        subprocess.run(["ip", "link", "set", "vcan9", "up"], check=True)
        sim = Sim(["--iface", "vcan9", "--drive", "vf-s15", "--node-id", "5"])
        try:
            sim.wait_out(r"ready")
        finally:
            assert sim.stop() == 0
        assert not any("down" in line for line in sim.err), sim.err
    finally:
        subprocess.run(["ip", "link", "del", "dev", "vcan9"], capture_output=True)


def test_unknown_command_is_reported_and_the_drive_keeps_running(sims, nodes):
    sim = sims.start([("vf-s15", 5)])
    node = nodes(BY_ID["vf-s15"])
    sim.send("frobnicate 5")
    sim.wait_err(r"unknown command 'frobnicate'")
    for bad, why in (("fault 5", "usage: fault"), ("fault 9 1", "no node 9"),
                     ("fault 5 zz", "not a trip code"), ("clear x", "not a node-ID"),
                     ("nmt 5 dance", "unknown NMT command")):
        mark = sim.err_mark()
        sim.send(bad)
        sim.wait_err(why, since=mark)
    assert node.sdo[0x1000].raw == node.object_dictionary[0x1000].default
    mark = sim.out_mark()
    sim.send("status 5")
    sim.wait_out(r"node 5 vf-s15: .*NMT PRE-OPERATIONAL", since=mark)
    assert sim.proc.poll() is None


def test_local_nmt_command(sims, recorder):
    sim = sims.start([("vf-s15", 5)])
    mark = recorder.mark()
    sim.send("nmt 5 reset-node")
    recorder.wait_frame(0x705, b"\x00", since=mark)


# --- several drives in one process ------------------------------------------------------------------

def test_all_drives_in_one_process(sims, nodes, network, recorder):
    pairs = [(d.id, d.node_id) for d in DRIVES]
    sim = sims.start(pairs)
    sim.wait_out(rf"{len(pairs)} node\(s\) on {IFACE}, control \S+, ready")
    made = {d.id: nodes(d) for d in DRIVES}
    for d in DRIVES:
        node = made[d.id]
        # Each answers with its own dictionary.
        assert node.sdo[0x1000].raw == node.object_dictionary[0x1000].default
        assert node.sdo[0x1018][1].raw == node.object_dictionary[0x1018][1].default
    mark = recorder.mark()
    network.nmt.send_command(0x01)  # broadcast start
    for d in DRIVES:
        sim.wait_out(rf"node {d.node_id} {d.id}: NMT PRE-OPERATIONAL -> OPERATIONAL")
        # Guarding where the drive has it, else a heartbeat.
        node = made[d.id]
        if 0x100C in node.object_dictionary:
            node.network.send_message(0x700 + d.node_id, b"", remote=True)
        else:
            node.sdo[0x1017].raw = 100
        recorder.wait_for(lambda m, n=d.node_id: m.arbitration_id == 0x700 + n
                          and not m.is_remote_frame and m.dlc == 1 and m.data[0] & 0x7F == 0x05,
                          mark, what=f"node {d.node_id} OPERATIONAL")
    # A fault on one drive reaches the bus from that drive only.
    target = next(d for d in DRIVES if d.trip is not None)
    mark = recorder.mark()
    sim.send(f"fault {target.node_id} {target.trip}")
    recorder.wait_for(lambda m: m.arbitration_id == 0x80 + target.node_id and m.dlc == 8, mark,
                      what="EMCY")
    others = [d.node_id for d in DRIVES if d is not target]
    assert not recorder.since(mark, lambda m: m.arbitration_id in [0x80 + n for n in others])


def test_drives_in_one_process_see_each_other(sims, nodes, recorder):
    """Each node has its own socket, so one node's frames reach the others as on a real bus: a
    heartbeat consumer on node 6 watches node 5's heartbeat."""
    sim = sims.start([("vf-s15", 5), ("vf-s15", 6)])
    a, b = nodes(BY_ID["vf-s15"], 5), nodes(BY_ID["vf-s15"], 6)
    b.sdo[0x1016][1].raw = (5 << 16) | 300   # node 6 consumes node 5's heartbeat, 300 ms
    mark = recorder.mark()
    a.sdo[0x1017].raw = 100
    recorder.wait_frame(0x705, b"\x7f", since=mark)  # node 6 has heard node 5 at least once
    mark = recorder.mark()
    a.sdo[0x1017].raw = 0                    # node 5 falls silent: node 6 must notice
    recorder.wait_for(lambda m: m.arbitration_id == 0x86 and m.dlc == 8
                      and m.data[0] == 0x30 and m.data[1] == 0x81, mark, timeout=TIMEOUT,
                      what="EMCY 0x8130 (heartbeat lost) from node 6")


def test_receive_filters_follow_a_new_cob_id(sims, nodes, network, recorder):
    """The kernel filters only let the node's COB-IDs through: moving RPDO1 to an ID outside the
    predefined set must open the filter for it (and the old ID no longer reaches the node)."""
    sim = sims.start([("vf-s15", 5)])
    node = nodes(BY_ID["vf-s15"], 5)
    node.sdo[0x1400][1].raw = 0x80000205      # disable, then move (CiA 301 procedure)
    node.sdo[0x1400][1].raw = 0x80000222
    node.sdo[0x1400][1].raw = 0x00000222
    node.nmt.state = "OPERATIONAL"
    network.send_message(0x205, b"\x00\x00\x2C\x01")   # old ID: 6042 = 300, must be ignored
    network.send_message(0x222, b"\x00\x00\x64\x00")   # new ID: 6042 = 100
    assert node.sdo[0x6042].raw == 100
    network.send_message(0x205, b"\x00\x00\x2C\x01")
    assert node.sdo[0x6042].raw == 100


# --- can-utils -------------------------------------------------------------------------------------

def test_candump_and_cansend_drive_the_simulator(sims):
    if not shutil.which("cansend") or not shutil.which("candump"):
        pytest.fail("can-utils missing (tools/setup installs it)")
    sim = sims.start([("vf-s15", 5)])
    dump = subprocess.Popen(["candump", "-L", f"{IFACE},585:7FF"], stdout=subprocess.PIPE,
                            text=True)
    try:
        # candump cannot say when it is listening: send the request until it shows the answer.
        line = ""
        deadline = time.monotonic() + TIMEOUT
        while not line and time.monotonic() < deadline:
            subprocess.run(["cansend", IFACE, "605#4000100000000000"], check=True,
                           timeout=TIMEOUT)
            if select.select([dump.stdout], [], [], 0.5)[0]:
                line = dump.stdout.readline()
        # 0x1000 device type 0x00010192: CiA 402 drive, velocity mode
        assert line.split()[-1] == "585#4300100092010100", line
    finally:
        dump.terminate()
        dump.wait(TIMEOUT)
    mark = sim.out_mark()
    subprocess.run(["cansend", IFACE, "000#0105"], check=True, timeout=TIMEOUT)
    sim.wait_out(r"NMT PRE-OPERATIONAL -> OPERATIONAL", since=mark)


# --- CAN error frames --------------------------------------------------------------------------

def send_error_frame(network, can_id, ctrl=0):
    """An error frame as a CAN controller's driver reports it (linux/can/error.h); vcan hands it
    to every socket that asked for error frames, as a real interface would."""
    data = bytearray(8)
    data[1] = ctrl
    network.bus.send(can.Message(arbitration_id=can_id, is_error_frame=True,
                                 is_extended_id=False, data=data))


def test_error_frames_reach_the_core(sims, network, recorder):
    """Error passive -> EMCY 0x8120; error active again -> error reset; bus-off and the
    controller's restart -> EMCY 0x8140 "recovered from bus-off" (CiA 301)."""
    CAN_ERR_CRTL, CAN_ERR_BUSOFF, CAN_ERR_RESTARTED = 0x04, 0x40, 0x100
    CAN_ERR_CRTL_TX_PASSIVE, CAN_ERR_CRTL_ACTIVE = 0x20, 0x40
    sim = sims.start([("vf-s15", 5)])

    def emcy(code, mark):
        return recorder.wait_for(lambda m: m.arbitration_id == 0x85 and m.dlc == 8
                                 and m.data[0] == code & 0xFF and m.data[1] == code >> 8, mark,
                                 what=f"EMCY 0x{code:04X}")

    mark = recorder.mark()
    send_error_frame(network, CAN_ERR_CRTL, CAN_ERR_CRTL_TX_PASSIVE)
    assert emcy(0x8120, mark).data[2] & 0x10  # communication error bit
    sim.wait_out(r"node 5 vf-s15: CAN error passive")
    mark = recorder.mark()
    send_error_frame(network, CAN_ERR_CRTL, CAN_ERR_CRTL_ACTIVE)
    emcy(0x0000, mark)
    mark = recorder.mark()
    send_error_frame(network, CAN_ERR_BUSOFF)
    sim.wait_out(r"node 5 vf-s15: CAN bus-off")
    send_error_frame(network, CAN_ERR_RESTARTED)
    emcy(0x8140, mark)
    sim.wait_out(r"node 5 vf-s15: CAN controller restarted")


def test_receive_overruns_are_logged_once_a_second(sims, network):
    """A flood of overruns (593 in 5 s were seen, one log line each) is one line a second, with
    the count since the previous line."""
    CAN_ERR_CRTL, CAN_ERR_CRTL_RX_OVERFLOW = 0x04, 0x01
    sim = sims.start([("vf-s15", 5)])
    mark = sim.out_mark()
    for _ in range(300):
        send_error_frame(network, CAN_ERR_CRTL, CAN_ERR_CRTL_RX_OVERFLOW)
    sim.wait_out(r"node 5 vf-s15: CAN receive overrun$", since=mark)
    # the rest: counted, and written once their second is over
    sim.wait_out(r"CAN receive overrun: \d+ more since the previous such line \(300 in all\)",
                 since=mark, timeout=TIMEOUT + 2)
    with sim.cond:
        lines = [line for line in sim.out[mark:] if "receive overrun" in line]
    assert len(lines) <= 4, lines
    m = sim.out_mark()
    sim.send("status 5")
    sim.wait_out(r"receive overruns 300", since=m)


def test_sdo_timeout_option_sets_the_servers_timeout(sims, network, recorder):
    """--sdo-timeout 3000: a download left after its initiate is aborted with 0x05040000, and not
    before 3 s (only the lower bound is checked: a busy machine may answer late, never early)."""
    sims.start([("bench", 4)], extra=("--sdo-timeout", "3000"))
    mark = recorder.mark()
    t0 = time.monotonic()
    network.send_message(0x604, bytes([0x21, 0x00, 0x20, 0x00, 0x10, 0x00, 0x00, 0x00]))
    recorder.wait_frame(0x584, bytes([0x60, 0x00, 0x20, 0x00, 0, 0, 0, 0]), since=mark)
    abort = recorder.wait_for(lambda m: m.arbitration_id == 0x584 and m.data[0] == 0x80, mark,
                              timeout=TIMEOUT + 3, what="the timeout abort")
    assert time.monotonic() - t0 >= 2.9
    assert bytes(abort.data) == bytes([0x80, 0x00, 0x20, 0x00, 0x00, 0x00, 0x04, 0x05])
