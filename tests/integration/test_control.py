"""The control socket (--control, --control-tcp) and the canopen_sim package that wraps it: every
command, the structured state, the event stream, several clients, and bad input (unknown
commands, bad node-IDs, overlong lines, binary data, half lines, abrupt disconnects) harming
nothing."""
import os
import re
import socket
import struct
import subprocess
import time

import pytest

from canopen_sim import Control, ControlError
from conftest import BIN, IFACE, TIMEOUT


def raw_client(path):
    """A plain socket on the control socket, past its greeting; lines come from .readline()."""
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.settimeout(TIMEOUT)
    s.connect(path)
    f = s.makefile("rb")
    assert f.readline() == b"hello canopen-drive control 1\n"
    return s, f


def hang_up(s, f):
    """Closes the connection for real (the file from makefile() holds the descriptor too)."""
    f.close()
    s.close()


def test_commands_state_and_events(canopen_sim_factory, recorder):
    sim = canopen_sim_factory([("vf-s15", 5), ("benshaw-rsi", 7)])
    ctl = sim.control
    assert ctl.nodes() == [(5, "vf-s15", IFACE), (7, "benshaw-rsi", IFACE)]
    assert ctl.command("version") == ["1"]
    st = ctl.state(5)
    assert (st["node"], st["drive"], st["iface"]) == (5, "vf-s15", IFACE)
    assert (st["nmt"], st["state"], st["fault"]) == ("PRE-OPERATIONAL", "SWITCH ON DISABLED", None)
    assert st["tx"] >= 1  # its boot-up

    mark = ctl.mark()
    ctl.nmt(5, "start")
    ev = ctl.wait_event(r"NMT PRE-OPERATIONAL -> OPERATIONAL", node=5, since=mark)
    assert ev.drive == "vf-s15" and ev.time > 0
    assert ctl.state(5)["nmt"] == "OPERATIONAL"
    assert ctl.state(7)["nmt"] == "PRE-OPERATIONAL"  # only node 5 was started

    frames = recorder.mark()
    ctl.fault(5, 0x01)
    ctl.wait_event(r"fault: trip 0x01 OC1, EMCY 0x2310", node=5, since=mark)
    ctl.wait_event(r"CiA 402 SWITCH ON DISABLED -> FAULT", node=5, since=mark)
    emcy = recorder.wait_frame(0x85, since=frames)
    assert struct.unpack_from("<H", bytes(emcy.data))[0] == 0x2310
    fault = ctl.state(5)["fault"]
    assert fault == {"trip": 1, "emcy": 0x2310, "name": "OC1", "cause": True}
    ctl.clear(5)
    assert ctl.state(5)["fault"]["cause"] is False
    assert any("node 5 vf-s15: NMT OPERATIONAL" in line for line in ctl.status(5))
    assert len(ctl.status()) == 2

    # refusals: one "error" each, nothing done, the connection stays usable
    for line, reason in [("bogus", r"unknown command 'bogus'"),
                         ("fault 9 1", r"no node 9 here \(nodes: 5 7\)"),
                         ("fault 0 1", r"'0' is not a node-ID"),
                         ("fault 5x 1", r"'5x' is not a node-ID"),
                         ("fault 5 0xZZ", r"'0xZZ' is not a trip code"),
                         ("fault 5 0x7777", r"no trip code 0x7777"),
                         ("fault 5", r"usage: fault NODE TRIP"),
                         ("nmt 5 jump", r"unknown NMT command 'jump'"),
                         ("state", r"usage: state NODE"),
                         ("subscribe now", r"usage: subscribe"),
                         ("status 1 2 3 4 5 6", r"usage: status")]:
        with pytest.raises(ControlError, match=reason):
            ctl.command(line)
    assert ctl.command("") == [] and ctl.command("# a comment") == []
    assert ctl.state(7)["fault"] is None


def test_load_command(canopen_sim_factory):
    sim = canopen_sim_factory([("vacon-optc6", 5)])
    ctl = sim.control
    assert ctl.state(5)["load"] == 0
    mark = ctl.mark()
    ctl.load(5, 80)
    ctl.wait_event(r"load 80 % of rated torque", node=5, since=mark)
    assert ctl.state(5)["load"] == 80
    for line, reason in [("load 5 201", r"load 5: '201' is not a load \(0\.\.200 % of rated"),
                         ("load 5 -3", r"'-3' is not a load"),
                         ("load 5 1.5", r"'1\.5' is not a load"),
                         ("load 5", r"usage: load NODE PERCENT"),
                         ("load 9 10", r"no node 9 here")]:
        with pytest.raises(ControlError, match=reason):
            ctl.command(line)
    assert ctl.state(5)["load"] == 80  # the refusals changed nothing
    ctl.load(5, 0)
    assert ctl.state(5)["load"] == 0


def test_several_clients_and_bad_input(canopen_sim_factory):
    sim = canopen_sim_factory([("vf-s15", 5)])
    path = sim.control_path
    other = Control(path)                        # a second subscriber
    quiet = Control(path, subscribe=False)       # a client that only asks
    s, f = raw_client(path)

    # binary data, an overlong line and a lone CR: each answered, none run
    s.sendall(b"fault 5 \x00\x01\xff\n")
    assert f.readline() == b"error line with bytes other than printable ASCII ignored\n"
    s.sendall(b"fault 5 1" + b" " * 5000 + b"\n")
    assert f.readline() == b"error line longer than 511 bytes ignored\n"
    s.sendall(b"state 5\r\n")
    assert f.readline().startswith(b'data {"node":5,')
    assert f.readline() == b"ok\n"
    # a line split over several writes is one line
    for part in (b"ver", b"si", b"on\n"):
        s.sendall(part)
        time.sleep(0.01)
    assert f.readline() == b"data 1\n" and f.readline() == b"ok\n"
    # a half-written command, then the client goes away: it is never run
    s.sendall(b"fault 5 0x01")
    hang_up(s, f)
    # a client that resets its connection (RST, not FIN) after asking
    r, rf = raw_client(path)
    r.sendall(b"subscribe\nstatus\n")
    r.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    hang_up(r, rf)

    assert sim.state(5)["fault"] is None, "the half line must not have been run"
    mark, other_mark = sim.mark(), other.mark()
    sim.fault(5, 0x01)
    sim.wait_event(r"-> FAULT", node=5, since=mark)
    other.wait_event(r"-> FAULT", node=5, since=other_mark)
    assert quiet.events == []
    assert quiet.state(5)["fault"]["emcy"] == 0x2310
    other.close()
    quiet.close()
    sim.state(5)  # a round trip: the simulator has seen both go

    # more clients than the simulator serves: the 17th is told so, the others work
    clients = [raw_client(path) for _ in range(16 - 1)]  # sim.control is the 16th
    extra = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    extra.settimeout(TIMEOUT)
    extra.connect(path)
    assert extra.makefile("rb").readline() == b"error too many control clients (16)\n"
    extra.close()
    for c, cf in clients:
        hang_up(c, cf)
    assert sim.state(5)["nmt"] == "PRE-OPERATIONAL"


def test_client_that_never_reads_is_dropped(canopen_sim_factory):
    """A subscriber that reads nothing while answers pile up is disconnected; the simulator and
    the other clients go on."""
    sim = canopen_sim_factory([("vf-s15", 5)])
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    s.connect(sim.control_path)
    s.setblocking(False)
    line = b"status\n" * 64
    sent = 0
    try:
        for _ in range(2000):  # ~400 bytes of answer per status line
            sent += s.send(line)
    except (BlockingIOError, ConnectionResetError, BrokenPipeError):
        pass
    sim.wait_output(r"control client dropped: \d+ bytes of answers and events unread",
                    stream="err", timeout=TIMEOUT * 4)
    s.close()
    assert sim.state(5)["nmt"] == "PRE-OPERATIONAL"


def test_tcp_and_socket_file_rules(canopen_sim_factory, tmp_path):
    sim = canopen_sim_factory([("vf-s15", 5)], args=["--control-tcp", "0"])
    port = int(sim.wait_output(r"control tcp 127\.0\.0\.1:(\d+)").group(1))
    with Control(tcp=("127.0.0.1", port)) as c:
        assert c.nodes() == [(5, "vf-s15", IFACE)]
    # a second simulator may not take over a live socket
    r = subprocess.run([str(BIN), "--iface", IFACE, "--drive", "vf-s15", "--node-id", "6",
                        "--control", sim.control_path], capture_output=True, text=True,
                       timeout=TIMEOUT * 2, stdin=subprocess.DEVNULL)
    assert r.returncode == 1 and "another process is listening on it" in r.stderr
    # a regular file is never replaced
    plain = tmp_path / "plain"
    plain.write_text("keep me")
    r = subprocess.run([str(BIN), "--iface", IFACE, "--drive", "vf-s15", "--node-id", "6",
                        "--control", str(plain)], capture_output=True, text=True,
                       timeout=TIMEOUT * 2, stdin=subprocess.DEVNULL)
    assert r.returncode == 1 and "exists and is not a socket" in r.stderr
    assert plain.read_text() == "keep me"
    # a stale socket (its simulator was killed) is replaced
    stale = str(tmp_path / "stale.sock")
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.bind(stale)
    s.close()
    again = canopen_sim_factory([("vf-s15", 6)], control_path=stale)
    with Control(stale) as c:
        assert c.nodes() == [(6, "vf-s15", IFACE)]
    again.stop()
    assert not os.path.exists(stale), "the socket file is removed at exit"


@pytest.mark.parametrize("args, message", [
    (["--control", ""], "a socket path has 1 to 107 bytes"),
    (["--control", "x" * 200], "a socket path has 1 to 107 bytes"),
    (["--control", "a", "--control", "b"], "--control given twice"),
    (["--control-tcp", "70000"], "not a port number in 0..65535"),
    (["--control-tcp", "-1"], "not a port number"),
])
def test_control_command_line_errors(args, message):
    r = subprocess.run([str(BIN), "--iface", IFACE, "--drive", "vf-s15", "--node-id", "5", *args],
                       capture_output=True, text=True, timeout=TIMEOUT, stdin=subprocess.DEVNULL)
    assert r.returncode == 2 and message in r.stderr, r.stderr


@pytest.mark.canopen_sim(drives=[("vacon-optc6", 8)])
def test_fixture_in_one_line(canopen_sim):
    """The pytest plugin's fixture, as a user's suite uses it."""
    assert canopen_sim.nodes() == [(8, "vacon-optc6", IFACE)]
    canopen_sim.nmt(8, "start")
    canopen_sim.wait_event(r"-> OPERATIONAL", node=8)


def test_live_view_once(canopen_sim_factory):
    """tools/sim-view through the control socket, one frame of it."""
    import sys
    from drives import ROOT
    sim = canopen_sim_factory([("vf-s15", 5), ("sourcetronic-st600", 3)])
    sim.fault(5, 0x01)
    r = subprocess.run([sys.executable, str(ROOT / "tools" / "sim-view"), "--control",
                        sim.control_path, "--once", "--width", "160"], capture_output=True, text=True,
                       timeout=TIMEOUT * 2)
    assert r.returncode == 0, r.stderr
    assert "canopen-drive: 2 node(s)" in r.stdout
    assert re.search(r"node +5 vf-s15 +vcan0 +NMT PRE-OPERATIONAL +FAULT", r.stdout)
    assert "fault OC1 0x01 EMCY 0x2310 (cause present)" in r.stdout
    assert re.search(r"node +3 sourcetronic-st600", r.stdout)
