"""A client of canopen-drive's control socket (protocol version 1).

Lines both ways. The server greets with ``hello canopen-drive control 1``; every command is
answered by zero or more ``data TEXT`` lines and then exactly one ``ok`` or ``error REASON``;
after ``subscribe``, ``event SECONDS LINE`` lines arrive for every line the simulator logs for a
node, at any time. A reader thread takes every line as it comes, so events never pile up unread
in the simulator (which drops a client that lets 64 KiB of them wait).
"""
import json
import re
import socket
import threading
import time
from dataclasses import dataclass

PROTOCOL = 1
_EVENT = re.compile(r"^event (\d+\.\d+) (.*)$")
_NODE_LINE = re.compile(r"^(?:node|slave) (\d+) (\S+): (.*)$")  # "slave N": an EtherCAT line


class ControlError(Exception):
    """The simulator refused a command (its reason is the message), or the connection failed."""


@dataclass(frozen=True)
class Event:
    """One line the simulator logged: ``time`` in seconds since it started, the ``node`` and
    ``drive`` it is about (None for a process line) and the ``text`` after "node N ID: " (on an
    EtherCAT line "slave N ID: ", N the slave's position)."""
    time: float
    node: int
    drive: str
    text: str
    line: str


def parse_event(line):
    m = _EVENT.match(line)
    if not m:
        return None
    body = m.group(2)
    n = _NODE_LINE.match(body)
    if n:
        return Event(float(m.group(1)), int(n.group(1)), n.group(2), n.group(3), body)
    return Event(float(m.group(1)), None, None, body, body)


class Control:
    """A connection to a running simulator's control socket.

    Control(path="/tmp/sim.sock") or Control(tcp=("127.0.0.1", port)). Subscribes to events at
    once (``events``, ``wait_event``)."""

    def __init__(self, path=None, tcp=None, timeout=5.0, subscribe=True):
        if (path is None) == (tcp is None):
            raise ValueError("give path or tcp")
        self.timeout = timeout
        self.events = []            # every Event received, in order
        self._answers = []          # complete answers: (ok, data lines, error reason)
        self._partial = []
        self._cond = threading.Condition()
        self._closed = False
        self._lock = threading.Lock()  # one command at a time
        if path is not None:
            self._sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            target = str(path)
        else:
            self._sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            target = tuple(tcp)
        self._sock.settimeout(timeout)
        try:
            self._sock.connect(target)
        except OSError as e:
            self._sock.close()
            raise ControlError(f"cannot connect to the simulator's control socket {target}: {e}")
        self._sock.settimeout(None)
        self._file = self._sock.makefile("r", encoding="ascii", errors="replace", newline="\n")
        hello = self._file.readline().rstrip("\n")
        m = re.fullmatch(r"hello canopen-drive control (\d+)", hello)
        if not m:
            self.close()
            raise ControlError(f"not a canopen-drive control socket (it said {hello!r})")
        self.protocol = int(m.group(1))
        if self.protocol != PROTOCOL:
            self.close()
            raise ControlError(f"control protocol {self.protocol}, this client speaks {PROTOCOL}")
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()
        if subscribe:
            self.command("subscribe")

    # --- the connection ---------------------------------------------------------------------------

    def _read(self):
        try:
            for raw in self._file:
                line = raw.rstrip("\n")
                with self._cond:
                    ev = parse_event(line)
                    if ev is not None:
                        self.events.append(ev)
                    elif line.startswith("data "):
                        self._partial.append(line[5:])
                    elif line == "ok":
                        self._answers.append((True, self._partial, None))
                        self._partial = []
                    elif line.startswith("error "):
                        self._answers.append((False, self._partial, line[6:]))
                        self._partial = []
                    self._cond.notify_all()
        except (OSError, ValueError):
            pass
        with self._cond:
            self._closed = True
            self._cond.notify_all()

    def command(self, line, timeout=None):
        """Sends one command line; returns its data lines, raises ControlError if refused."""
        if "\n" in line:
            raise ValueError("one line at a time")
        timeout = self.timeout if timeout is None else timeout
        with self._lock:
            with self._cond:
                start = len(self._answers)
            try:
                self._sock.sendall((line + "\n").encode("ascii"))
            except OSError as e:
                raise ControlError(f"the simulator went away: {e}")
            deadline = time.monotonic() + timeout
            with self._cond:
                while len(self._answers) == start:
                    left = deadline - time.monotonic()
                    if self._closed:
                        raise ControlError(f"the simulator closed the connection ({line!r})")
                    if left <= 0:
                        raise ControlError(f"no answer to {line!r} within {timeout} s")
                    self._cond.wait(left)
                ok, data, reason = self._answers[start]
                del self._answers[:start + 1]
        if not ok:
            raise ControlError(reason)
        return data

    def close(self):
        try:
            self._sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        self._sock.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # --- commands ---------------------------------------------------------------------------------

    def fault(self, node, trip):
        """The drive trips with its own trip code (e.g. 0x01 = OC1 on the VF-S15)."""
        self.command(f"fault {int(node)} {int(trip):#x}")

    def clear(self, node):
        """The fault's cause is gone (the master must still reset it)."""
        self.command(f"clear {int(node)}")

    def nmt(self, node, command):
        """A local NMT command: start, stop, preop, reset-node or reset-comm."""
        self.command(f"nmt {int(node)} {command}")

    def load(self, node, percent):
        """The mechanical load on the drive's motor, 0..200 % of its rated torque: the drive's
        current and torque monitors follow it while the output is on."""
        self.command(f"load {int(node)} {int(percent)}")

    def state(self, node):
        """The node's state as a dict: node, drive, iface, nmt, state, controlword, target,
        actual, load, fault (None or {trip, emcy, name, cause}), rx, tx, ... counters."""
        return json.loads(self.command(f"state {int(node)}")[0])

    def status(self, node=None):
        """The status lines (one per node), as stdin's status prints them."""
        return self.command("status" if node is None else f"status {int(node)}")

    def nodes(self):
        """[(node_id, drive_id, iface), ...]"""
        out = []
        for line in self.command("nodes"):
            node, drive, iface = line.split()
            out.append((int(node), drive, iface))
        return out

    def quit(self):
        """Stops the simulator (exit status 0)."""
        self.command("quit")

    # --- events -----------------------------------------------------------------------------------

    def mark(self):
        """A position in the event list: wait_event(since=mark) looks only at later events."""
        with self._cond:
            return len(self.events)

    def wait_event(self, pattern, node=None, since=0, timeout=None):
        """The first event at or after position `since` whose text matches the regular
        expression `pattern` (re.search), for `node` if given. Raises TimeoutError."""
        rx = re.compile(pattern)
        timeout = self.timeout if timeout is None else timeout
        deadline = time.monotonic() + timeout
        pos = since
        with self._cond:
            while True:
                while pos < len(self.events):
                    ev = self.events[pos]
                    pos += 1
                    if (node is None or ev.node == node) and rx.search(ev.text):
                        return ev
                left = deadline - time.monotonic()
                if left <= 0 or self._closed:
                    seen = [e.line for e in self.events[since:]][-8:]
                    raise TimeoutError(f"no event /{pattern}/"
                                       f"{'' if node is None else f' of node {node}'} within "
                                       f"{timeout} s{' (connection closed)' if self._closed else ''}"
                                       f"; last events: {seen}")
                self._cond.wait(left)
