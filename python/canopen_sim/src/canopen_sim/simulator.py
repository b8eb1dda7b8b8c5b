"""Start a canopen-drive process with a control socket and talk to it."""
import os
import shlex
import shutil
import signal
import subprocess
import tempfile
from pathlib import Path

from .control import Control, ControlError
from .lines import Lines, LineTimeout


class SimulatorError(Exception):
    """The simulator could not be started, or stopped badly."""


def find_binary(binary=None):
    """The canopen-drive to run: `binary`, else $CANOPEN_DRIVE_BIN, else canopen-drive on PATH."""
    cand = binary or os.environ.get("CANOPEN_DRIVE_BIN") or shutil.which("canopen-drive")
    if not cand or not Path(cand).exists():
        raise SimulatorError("no canopen-drive: build it (cmake --build --preset default) and "
                             "set CANOPEN_DRIVE_BIN, or put it on PATH")
    return str(cand)


class Simulator:
    """A canopen-drive process with its control socket.

        sim = Simulator([("vf-s15", 5)], iface="vcan0").start()
        sim.fault(5, 0x01); sim.wait_event("-> FAULT", node=5); sim.stop()

    `drives`: [(drive_id, node_id), ...] or, for several buses, {iface: [(drive_id, node_id)]};
    with `ecat_iface` (an EtherCAT line on that Ethernet interface) [drive_id, ...] in line order,
    and the commands take the slave's position (1, 2, ...) for NODE.
    `store`, `trace`, `scenario`: the --store/--trace/--scenario files; `args`: more options.
    `control_path`: the socket (default: in a fresh temporary directory).
    `wrapper`: a command to run the simulator under (e.g. "valgrind -q"). Also a context
    manager (start on enter, stop on exit). The Control methods (fault, clear, nmt, state,
    status, nodes, wait_event, mark, events) are available on the Simulator itself."""

    def __init__(self, drives=(("vf-s15", 5),), iface="vcan0", binary=None, store=None,
                 trace=None, scenario=None, args=(), wrapper=None, timeout=5.0, control_path=None,
                 ecat_iface=None):
        self.binary = find_binary(binary)
        self.timeout = timeout
        self._dir = tempfile.mkdtemp(prefix="canopen-sim-")
        self.control_path = str(control_path or os.path.join(self._dir, "control.sock"))
        argv = []
        if ecat_iface is not None:
            argv += ["--ecat-iface", ecat_iface]
            for drive_id in drives:
                argv += ["--drive", drive_id]
            self.node_ids = list(range(1, len(drives) + 1))
        else:
            buses = drives if isinstance(drives, dict) else {iface: list(drives)}
            for bus, pairs in buses.items():
                argv += ["--iface", bus]
                for drive_id, node_id in pairs:
                    argv += ["--drive", drive_id, "--node-id", str(node_id)]
            self.node_ids = [n for pairs in buses.values() for _, n in pairs]
        for opt, value in (("--store", store), ("--trace", trace), ("--scenario", scenario)):
            if value is not None:
                argv += [opt, str(value)]
        argv += ["--control", self.control_path, *args]
        wrap = shlex.split(wrapper) if isinstance(wrapper, str) else list(wrapper or [])
        self.argv = [*wrap, self.binary, *argv]
        self.proc = None
        self.control = None
        self.out, self.err = [], []  # the lines of stdout and stderr, once started
        self._streams = {}

    # --- process ----------------------------------------------------------------------------------

    def start(self):
        """Starts the process and returns once it is ready and the control socket answers."""
        self.proc = subprocess.Popen(self.argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True, bufsize=1)
        self._streams = {"out": Lines(self.proc.stdout, self.proc, "simulator's stdout"),
                         "err": Lines(self.proc.stderr, self.proc, "simulator's stderr")}
        self.out, self.err = self._streams["out"].lines, self._streams["err"].lines
        try:
            self.wait_output(r"ready$", timeout=self.timeout * 2)
            self.control = Control(self.control_path, timeout=self.timeout)
        except BaseException:
            self.stop(check=False)
            raise
        return self

    def wait_output(self, pattern, since=0, timeout=None, stream="out"):
        """The first line of stdout (or stderr) from position `since` matching `pattern`."""
        try:
            return self._streams[stream].wait(
                pattern, since, self.timeout if timeout is None else timeout,
                context=lambda: f"; stderr: {self.err[-5:]}")[0]
        except LineTimeout as e:
            raise SimulatorError(f"canopen-drive: {e}") from None

    def stop(self, sig=signal.SIGTERM, check=True):
        """Stops the process (SIGTERM) and returns its exit status; with check, anything but 0
        raises SimulatorError."""
        if self.control is not None:
            self.control.close()
            self.control = None
        rc = None
        if self.proc is not None:
            if self.proc.poll() is None:
                self.proc.send_signal(sig)
            try:
                rc = self.proc.wait(self.timeout * 2)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                rc = self.proc.wait()
                if check:
                    raise SimulatorError("canopen-drive did not stop on SIGTERM (killed)")
            for lines in self._streams.values():
                lines.join(self.timeout)
            for s in (self.proc.stdin, self.proc.stdout, self.proc.stderr):
                try:
                    s.close()
                except OSError:
                    pass
        shutil.rmtree(self._dir, ignore_errors=True)
        if check and rc not in (0, None):
            raise SimulatorError(f"canopen-drive exited {rc}; stderr: {self.err[-5:]}")
        return rc

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.stop(check=exc[0] is None)

    # --- the control socket's methods, on the simulator ------------------------------------------

    def __getattr__(self, name):
        if name in ("fault", "clear", "nmt", "state", "status", "nodes", "wait_event", "mark",
                    "events", "command", "quit"):
            control = self.__dict__.get("control")
            if control is None:
                raise ControlError("the simulator is not running")
            return getattr(control, name)
        raise AttributeError(name)
