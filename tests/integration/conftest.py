"""Fixtures of the SocketCAN integration suite: python-canopen as the master on vcan0, the
canopen-drive simulator as a child process, and a recorder of every frame on the bus.

Run inside tools/vcan-run (the ctest label `integration` does). Nothing here sleeps to let time
pass: every wait is for a frame, an output line or a process exit, with a timeout.

Environment:
  CANOPEN_DRIVE_BIN   the simulator (default build/default/boards/linux/canopen-drive)
  CANOPEN_IFACE       interface (default vcan0)
  CANOPEN_TEST_DRIVES comma-separated drive ids to test (default: all five)
  CANOPEN_TIMEOUT     seconds any single wait may take (default 5; the UML guest is slow)
  CANOPEN_DRIVE_WRAPPER  a command every simulator the fixtures start runs under, split like a
                      shell would (e.g. "valgrind --error-exitcode=99 --leak-check=full"): its
                      exit status is the simulator's, which must be 0 (ctest memcheck_vf_s15)
"""
import functools
import os
import re
import shlex
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import can
import canopen
import canopen_sim
import pytest
from canopen.profiles.p402 import BaseNode402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from drives import BY_ID, DRIVES, ROOT  # noqa: E402

IFACE = os.environ.get("CANOPEN_IFACE", "vcan0")
BUILT = Path(os.environ.get("CANOPEN_DRIVE_BIN",
                            ROOT / "build" / "default" / "boards" / "linux" / "canopen-drive"))
TIMEOUT = float(os.environ.get("CANOPEN_TIMEOUT", "5"))
WRAPPER = shlex.split(os.environ.get("CANOPEN_DRIVE_WRAPPER", ""))

# The suite runs a private copy of the simulator, so a rebuild of the tree while it runs (other
# work in the same build directory) cannot swap the binary under a test.
_BIN_DIR = tempfile.mkdtemp(prefix="canopen-drive-it-")
BIN = Path(_BIN_DIR) / BUILT.name
if BUILT.exists():
    shutil.copy2(BUILT, BIN)
    # the canopen_sim package's fixtures (canopen_sim, canopen_sim_factory) run this copy too
    os.environ["CANOPEN_DRIVE_BIN"] = str(BIN)


def pytest_sessionfinish(session, exitstatus):
    shutil.rmtree(_BIN_DIR, ignore_errors=True)


def selected_drives():
    wanted = os.environ.get("CANOPEN_TEST_DRIVES", "")
    if not wanted.strip():
        return DRIVES
    ids = [w.strip() for w in wanted.split(",") if w.strip()]
    unknown = [i for i in ids if i not in BY_ID]
    if unknown:
        raise pytest.UsageError(f"CANOPEN_TEST_DRIVES: unknown drive(s) {unknown}")
    return [BY_ID[i] for i in ids]


def pytest_configure(config):
    config.addinivalue_line("markers", "drive: parametrised over the simulated drives")


def can_available():
    try:
        s = socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
    except OSError as e:
        return f"no SocketCAN here ({e}); run the suite through tools/vcan-run"
    try:
        s.bind((IFACE,))
    except OSError as e:
        return f"cannot bind to {IFACE} ({e}); run the suite through tools/vcan-run"
    finally:
        s.close()
    return None


# --- the bus ---------------------------------------------------------------------------------------

SO_RCVBUFFORCE = getattr(socket, "SO_RCVBUFFORCE", 33)  # needs CAP_NET_ADMIN: root in the guest


class Recorder(can.Listener):
    """Every frame the master's socket receives, in order, with a condition to wait on."""

    def __init__(self):
        self.frames = []
        self.cond = threading.Condition()

    def on_message_received(self, msg):
        with self.cond:
            self.frames.append(msg)
            self.cond.notify_all()

    def mark(self):
        with self.cond:
            return len(self.frames)

    def wait_for(self, pred, since=0, timeout=TIMEOUT, what="a frame"):
        """The first frame at or after position `since` that satisfies pred."""
        deadline = time.monotonic() + timeout
        pos = since
        with self.cond:
            while True:
                while pos < len(self.frames):
                    msg = self.frames[pos]
                    pos += 1
                    if pred(msg):
                        return msg
                left = deadline - time.monotonic()
                if left <= 0:
                    raise AssertionError(f"timed out after {timeout} s waiting for {what}; "
                                         f"last frames: {self.describe(since)}")
                self.cond.wait(left)

    def wait_frame(self, cob_id, data=None, since=0, timeout=TIMEOUT, rtr=False):
        def pred(m):
            return (m.arbitration_id == cob_id and not m.is_error_frame
                    and m.is_remote_frame == rtr
                    and (data is None or bytes(m.data) == bytes(data)))
        want = f"0x{cob_id:03X}" + (f" [{bytes(data).hex(' ')}]" if data is not None else "")
        return self.wait_for(pred, since, timeout, want)

    def since(self, since, pred=lambda m: True):
        with self.cond:
            return [m for m in self.frames[since:] if pred(m)]

    def describe(self, since=0, limit=12):
        frames = self.since(since)[-limit:]
        return ", ".join(f"{m.arbitration_id:03X}#{bytes(m.data).hex()}" +
                         ("R" if m.is_remote_frame else "") for m in frames) or "none"


@pytest.fixture(scope="session")
def network():
    why = can_available()
    if why:
        pytest.fail(why, pytrace=False)
    if not BIN.exists():
        pytest.fail(f"{BUILT} does not exist: build first (cmake --build --preset default)",
                    pytrace=False)
    net = canopen.Network()
    net.connect(interface="socketcan", channel=IFACE, receive_own_messages=False)
    # A 127-segment SDO block arrives in a few milliseconds; on a busy machine the master's
    # receive thread may not run for longer than that, and the default socket buffer of the
    # emulated kernel then drops the tail of the block (the client waits for segments that never
    # come while the server times out). Real masters size their buffers for bursts too.
    net.bus.socket.setsockopt(socket.SOL_SOCKET, SO_RCVBUFFORCE, 8 << 20)
    net.recorder = Recorder()
    net.notifier.add_listener(net.recorder)
    yield net
    net.disconnect()


@pytest.fixture
def recorder(network):
    return network.recorder


# --- the simulator process --------------------------------------------------------------------------

class Sim:
    """A canopen-drive process; its stdout/stderr lines are collected (canopen_sim.Lines)."""

    def __init__(self, args, cwd=None, control_path=None):
        self.args = [*WRAPPER, str(BIN), *args]
        self.control_path = control_path
        self._control = None
        self.proc = subprocess.Popen(self.args, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True, bufsize=1, cwd=cwd)
        self.stdout = canopen_sim.Lines(self.proc.stdout, self.proc, "stdout of canopen-drive")
        self.stderr = canopen_sim.Lines(self.proc.stderr, self.proc, "stderr of canopen-drive")
        self.out, self.err = self.stdout.lines, self.stderr.lines
        self.cond = self.stdout.cond  # guards self.out
        self.threads = [self.stdout.thread, self.stderr.thread]

    def send(self, line):
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()

    def wait_out(self, pattern, since=0, timeout=TIMEOUT):
        return self.stdout.wait(pattern, since, timeout,
                                context=lambda: f"; stderr: {self.err[-5:]}")[0]

    def wait_err(self, pattern, since=0, timeout=TIMEOUT):
        return self.stderr.wait(pattern, since, timeout)[0]

    def out_mark(self):
        return self.stdout.mark()

    def err_mark(self):
        return self.stderr.mark()

    @property
    def control(self):
        """A canopen_sim.Control on the simulator's --control socket (connected on first use,
        once the simulator said it is ready): the package the suite's users test with."""
        if self._control is None:
            assert self.control_path is not None, "started without a control socket"
            self.wait_out(r"ready$")
            self._control = canopen_sim.Control(self.control_path, timeout=TIMEOUT)
        return self._control

    def stop(self, sig=signal.SIGTERM, timeout=TIMEOUT):
        """Signals the process and returns its exit status."""
        if self._control is not None:
            self._control.close()
            self._control = None
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
        try:
            rc = self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
            raise AssertionError(f"canopen-drive did not stop within {timeout} s of {sig!r}")
        for t in self.threads:
            t.join(timeout)
        try:
            self.proc.stdin.close()
        except OSError:
            pass
        return rc


@pytest.fixture
def sims(network):
    """Starts simulators: sims.start([(drive_id, node_id), ...], store=None) waits for every
    node's boot-up and returns the Sim. Every simulator still running at the end is stopped with
    SIGTERM and must exit 0."""
    started = []
    control_dir = tempfile.mkdtemp(prefix="canopen-ctl-")

    class Factory:
        def start(self, pairs, store=None, extra=(), wait_bootup=True):
            args = ["--iface", IFACE]
            for drive_id, node_id in pairs:
                args += ["--drive", drive_id, "--node-id", str(node_id)]
            if store is not None:
                args += ["--store", str(store)]
            args += list(extra)
            control_path = None
            if not any(a.startswith("--control") for a in args):
                # every simulator the suite starts also serves the control socket (sim.control)
                control_path = os.path.join(control_dir, f"sim{len(started)}.sock")
                args += ["--control", control_path]
            mark = network.recorder.mark()
            sim = Sim(args, control_path=control_path)
            started.append(sim)
            sim.bootup_mark = mark
            if wait_bootup:
                for _, node_id in pairs:
                    network.recorder.wait_frame(0x700 + node_id, b"\x00", since=mark)
            return sim

    yield Factory()
    failures = []
    for sim in started:
        rc = sim.stop()
        if rc != 0:
            failures.append(f"{' '.join(sim.args)} exited {rc}; stderr: {sim.err[-5:]}")
    shutil.rmtree(control_dir, ignore_errors=True)
    assert not failures, "; ".join(failures)


# --- python-canopen nodes ----------------------------------------------------------------------------

@functools.lru_cache(maxsize=None)
def _od(drive_id, node_id):
    return canopen.import_od(str(BY_ID[drive_id].eds), node_id)


def make_node(network, drive, node_id=None, cls=None):
    """A python-canopen RemoteNode (BaseNode402 for CiA 402 drives) on the network, with
    timeouts that suit a slow guest. Removed again by the drive_node fixture or remove_node."""
    node_id = node_id or drive.node_id
    if cls is None:
        cls = BaseNode402 if drive.cia402 else canopen.RemoteNode
    node = cls(node_id, _od(drive.id, node_id))
    network.add_node(node)
    node.sdo.RESPONSE_TIMEOUT = 2.0
    node.sdo.MAX_RETRIES = 1  # one attempt: python-canopen counts the first one
    if isinstance(node, BaseNode402):
        node.TIMEOUT_SWITCH_STATE_FINAL = 5.0
        node.TIMEOUT_SWITCH_STATE_SINGLE = 2.0
        node.TIMEOUT_CHECK_TPDO = 1.0
        node.TIMEOUT_RESET_FAULT = 2.0
    return node


def remove_node(network, node):
    if node.id in network:
        del network[node.id]


@pytest.fixture
def nodes(network):
    """Factory for python-canopen nodes that are taken off the network after the test."""
    made = []

    def make(drive, node_id=None, cls=None):
        node = make_node(network, drive, node_id, cls)
        made.append(node)
        return node

    yield make
    for node in made:
        for pdo in list(node.tpdo.map.values()) + list(node.rpdo.map.values()):
            try:
                pdo.stop()
            except Exception:
                pass
        remove_node(network, node)


def pytest_generate_tests(metafunc):
    if "drive" in metafunc.fixturenames:
        drives = selected_drives()
        metafunc.parametrize("drive", drives, ids=[d.id for d in drives])


@pytest.fixture
def running(sims, nodes, drive, tmp_path):
    """One simulator running `drive` alone (with a store file, as a drive with 0x1010 is run),
    and its python-canopen node: (sim, node)."""
    sim = sims.start([(drive.id, drive.node_id)], store=tmp_path / "store.bin")
    node = nodes(drive)
    return sim, node


# --- helpers -----------------------------------------------------------------------------------------

def od_variables(od):
    """Every ODVariable of a dictionary, in index/sub-index order."""
    out = []
    for index in sorted(od.indices):
        obj = od[index]
        if isinstance(obj, canopen.objectdictionary.ODVariable):
            out.append(obj)
        else:
            for sub in sorted(obj.subindices):
                out.append(obj.subindices[sub])
    return out


def is_readable(var):
    return "r" in var.access_type or var.access_type == "const"


def is_writable(var):
    return "w" in var.access_type


def sdo_abort(node, index, sub, fn):
    """Runs fn() and returns the SDO abort code (0 if it succeeded)."""
    try:
        fn()
    except canopen.SdoAbortedError as e:
        return e.code
    return 0


def param_channel_write(network, recorder, node_id, address, value):
    """Sourcetronic PDO1 parameter channel write (NOTES B11): RPDO1 `02 00 addr value`; returns
    the TPDO1 response frame."""
    mark = recorder.mark()
    network.send_message(0x200 + node_id, struct.pack("<HHH", 2, address, value))
    return recorder.wait_frame(0x180 + node_id, since=mark)


def wait_emcy(node, since, code=None, timeout=TIMEOUT):
    """The first EMCY in node.emcy.log at or after position `since` (with this code)."""
    deadline = time.monotonic() + timeout
    pos = since
    with node.emcy.emcy_received:
        while True:
            while pos < len(node.emcy.log):
                e = node.emcy.log[pos]
                pos += 1
                if code is None or e.code == code:
                    return e
            left = deadline - time.monotonic()
            if left <= 0:
                got = [f"0x{e.code:04X}" for e in node.emcy.log[since:]]
                raise AssertionError(f"no EMCY {'' if code is None else hex(code)} from node "
                                     f"{node.id} within {timeout} s (got {got})")
            node.emcy.emcy_received.wait(left)
