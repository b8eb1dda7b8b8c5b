"""Fixtures of the EtherCAT suite: pysoem (the SOEM master, unmodified) on one end of a veth pair,
canopen-drive --ecat-iface on the other, as a child process with its stdin for commands.

Run inside tools/veth-run (the ctest label `ecat` does):
    tools/veth-run ctest --test-dir build/default -L ecat --output-on-failure
Nothing sleeps to let time pass on the drive's side except the master's own cycle (the process
data must flow at a steady 1-4 ms, as a master's task does); every other wait is for an output
line, an AL state or a value, with a timeout.

Environment:
  CANOPEN_DRIVE_BIN   the simulator (default build/default/boards/linux/canopen-drive)
  ECAT_SLAVE_IFACE    the simulator's end of the pair (default veth0)
  ECAT_MASTER_IFACE   the master's end (default veth1)
  CANOPEN_TIMEOUT     seconds any single wait may take (default 5; the UML guest is slower)
"""
import configparser
import os
import queue
import shutil
import socket
import subprocess
import tempfile
import threading
import time
from pathlib import Path

import canopen_sim
import pysoem
import pytest

ROOT = Path(__file__).resolve().parents[2]
BUILT = Path(os.environ.get("CANOPEN_DRIVE_BIN",
                            ROOT / "build" / "default" / "boards" / "linux" / "canopen-drive"))
SLAVE_IF = os.environ.get("ECAT_SLAVE_IFACE", "veth0")
MASTER_IF = os.environ.get("ECAT_MASTER_IFACE", "veth1")
TIMEOUT = float(os.environ.get("CANOPEN_TIMEOUT", "5"))
EDS = ROOT / "od" / "vf-mb1-ecat" / "vf-mb1-ecat.eds"

# A private copy of the simulator: a rebuild while the suite runs cannot swap it.
_BIN_DIR = tempfile.mkdtemp(prefix="canopen-drive-ecat-")
BIN = Path(_BIN_DIR) / BUILT.name
if BUILT.exists():
    shutil.copy2(BUILT, BIN)


def pytest_sessionfinish(session, exitstatus):
    shutil.rmtree(_BIN_DIR, ignore_errors=True)


def eds():
    """The drive's EDS, read as plain INI (sections [1018sub1], ...)."""
    cp = configparser.ConfigParser(strict=False, interpolation=None)
    cp.optionxform = str
    cp.read(EDS, encoding="latin-1")
    return cp


def eds_int(value):
    v = value.strip()
    return int(v, 0) if v.lower().startswith("0x") else int(v)


def wire_available():
    for name in (SLAVE_IF, MASTER_IF):
        try:
            s = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(0x88A4))
            s.bind((name, 0))
            s.close()
        except OSError as e:
            return f"cannot open a raw socket on {name} ({e}); run the suite through tools/veth-run"
    return None


@pytest.fixture(scope="session", autouse=True)
def wire():
    why = wire_available()
    if why:
        pytest.fail(why)  # not a skip: the suite is asked for, the wire must be there
    if not BIN.exists():
        pytest.fail(f"{BUILT} is not built (cmake --build --preset default)")


class Sim:
    """canopen-drive --ecat-iface SLAVE_IF with n drives; every output line is kept."""

    def __init__(self, drives, extra=()):
        args = [str(BIN), "--ecat-iface", SLAVE_IF]
        for d in drives:
            args += ["--drive", d]
        args += list(extra)
        self.proc = subprocess.Popen(args, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=subprocess.STDOUT, text=True, bufsize=1)
        self.output = canopen_sim.Lines(self.proc.stdout, self.proc, "simulator's output")
        self.lines = self.output.lines
        self.wait_line(r"EtherCAT slave\(s\) on .*, ready")

    def mark(self):
        return self.output.mark()

    def wait_line(self, pattern, since=0, timeout=TIMEOUT):
        return self.output.wait(pattern, since, timeout)[0].string

    def command(self, line):
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()

    def stop(self):
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(TIMEOUT)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.output.join(TIMEOUT)
        return self.proc.returncode


class Line:
    """The master: pysoem on MASTER_IF, with a cyclic process-data task (LRW) on demand."""

    def __init__(self):
        self.master = pysoem.Master()
        self.master.open(MASTER_IF)
        self.lock = threading.Lock()   # SOEM's context is used by one thread at a time
        self.cycle_thread = None
        self.running = False
        self.wkcs = []
        self.samples = []              # (t, [input bytes per slave]) every cycle
        self.outputs = {}

    @property
    def slaves(self):
        return self.master.slaves

    def init(self, expect):
        with self.lock:
            n = self.master.config_init()
        assert n == expect, f"config_init found {n} slaves, not {expect}"
        return n

    def sdo_read(self, pos, index, sub, **kw):
        with self.lock:
            return self.master.slaves[pos - 1].sdo_read(index, sub, **kw)

    def sdo_write(self, pos, index, sub, data, **kw):
        with self.lock:
            return self.master.slaves[pos - 1].sdo_write(index, sub, data, **kw)

    def mbx_receive(self, pos):
        with self.lock:
            return self.master.slaves[pos - 1].mbx_receive()

    def request(self, state, pos=None):
        """Writes AL control for one slave (pos) or all."""
        with self.lock:
            if pos is None:
                self.master.state = state
                self.master.write_state()
            else:
                s = self.master.slaves[pos - 1]
                s.state = state
                s.write_state()

    def wait_state(self, state, pos=None, timeout=TIMEOUT):
        """Reads AL status until every slave (or pos) shows state; returns the slaves."""
        end = time.monotonic() + timeout
        while True:
            with self.lock:
                self.master.read_state()
                slaves = self.master.slaves if pos is None else [self.master.slaves[pos - 1]]
                got = [(s.state, s.al_status) for s in slaves]
            if all(st == state for st, _ in got):
                return slaves
            if time.monotonic() > end:
                raise AssertionError(f"AL states {[(hex(a), hex(b)) for a, b in got]}, "
                                     f"not 0x{state:X}")
            time.sleep(0.005)

    def set_output(self, pos, data):
        with self.lock:
            self.outputs[pos] = bytes(data)
            self.master.slaves[pos - 1].output = bytes(data)

    def _cycle(self, period):
        nxt = time.monotonic()
        t0 = nxt
        while self.running:
            with self.lock:
                self.master.send_processdata()
                # The simulator is a process, not a real-time slave: on a busy machine its answer
                # can take longer than a cycle. Waiting up to 20 ms for it (the cycle then slips)
                # keeps a late frame from counting as a lost one; a frame that never comes still
                # gives a wrong working counter.
                wkc = self.master.receive_processdata(20000)
                inputs = [bytes(s.input) for s in self.master.slaves]
            self.wkcs.append(wkc)
            self.samples.append((time.monotonic() - t0, inputs))
            nxt += period
            delay = nxt - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            else:
                nxt = time.monotonic()

    def start_cycle(self, period=0.002):
        assert self.cycle_thread is None
        self.running = True
        self.cycle_thread = threading.Thread(target=self._cycle, args=(period,), daemon=True)
        self.cycle_thread.start()

    def stop_cycle(self):
        self.running = False
        if self.cycle_thread is not None:
            self.cycle_thread.join(TIMEOUT)
        self.cycle_thread = None

    def wait_input(self, pos, predicate, what, timeout=TIMEOUT):
        """Waits until predicate(input bytes of slave pos) holds in a cycle's sample."""
        end = time.monotonic() + timeout
        seen = len(self.samples)
        while time.monotonic() < end:
            samples = self.samples[seen:]
            for _, inputs in samples:
                if predicate(inputs[pos - 1]):
                    return inputs[pos - 1]
            seen += len(samples)
            time.sleep(0.005)
        last = self.samples[-1][1][pos - 1].hex() if self.samples else "none"
        raise AssertionError(f"slave {pos}: inputs never showed {what} (last {last})")

    def close(self):
        self.stop_cycle()
        self.master.close()


@pytest.fixture
def line():
    """line(n, extra=()): n VF-MB1 drives on the wire (more canopen-drive options in extra) and a
    master that found them (config_init)."""
    made = []

    def make(n=1, extra=()):
        sim = Sim(["vf-mb1-ecat"] * n, extra)
        master = Line()
        made.append((sim, master))
        master.init(n)
        return sim, master

    yield make
    for sim, master in made:
        master.close()
        rc = sim.stop()
        assert rc == 0, f"the simulator exited with {rc}"
