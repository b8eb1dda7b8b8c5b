#!/usr/bin/env python3
"""tools/vcan_bench.py - the bus-level part of tools/bench: run inside ONE tools/vcan-run call.

    tools/vcan-run python3 tools/vcan_bench.py [--drives 10,127] [--window 10] [--sdo-runs 3]
                                               [--json-out FILE]

Scale: canopen-drive runs N VF-S15 drives (node-IDs 1..N) on vcan0. A master (python-canopen, SDO
in PRE-OPERATIONAL, as a user would) sets the event timer (0x18xx sub 5) of every TPDO that is
valid (COB-ID bit 31 clear) to 10 ms, making it event-driven (type 255) if it is not; the
dictionary's own defaults are left alone otherwise. NMT start all; after a settling second, a
window of --window seconds. `can-count` (boards/linux/can_count.c) records every frame with the
kernel's receive timestamp from before the simulator starts until after it stopped sending; the
simulator's CPU time is utime + stime of /proc/PID/stat across the window.

  fps             frames received in the window / window length
  expected_fps    TPDOs configured x 100/s (+ heartbeats: none, 0x1017 defaults to 0)
  lost            frames the nodes sent that can-count did not receive, over the whole run:
                  sum of every node's socket tx counter (`status` after NMT stop) + frames the
                  core had to drop (its tx queue full) - frames can-count got from the nodes
  below_nominal_pct  how far below 100/s per TPDO the rate is: CiA 301 restarts the event timer
                  at each transmission, so every wake-up latency lengthens the period
SDO: canopen-drive --drive bench (the benchmark device: od/bench, DOMAIN 0x2000 in RAM); a
python-canopen client downloads 100 000 random bytes and uploads them back, block and segmented,
--sdo-runs times each; the time of one transfer is from open() to close(); every upload is
compared byte for byte with what was downloaded.

The last line of stdout is one JSON object.
"""
import argparse
import json
import os
import random
import re
import signal
import socket
import struct
import subprocess
import sys
import time
from pathlib import Path

import canopen

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "python" / "canopen_sim" / "src"))  # this tree's package
from canopen_sim import Lines  # noqa: E402
IFACE = os.environ.get("CANOPEN_IFACE", "vcan0")
TPDO_PERIOD_MS = 10
SDO_BYTES = 100_000
CLK_TCK = os.sysconf("SC_CLK_TCK")


def log(msg):
    print(msg, file=sys.stderr, flush=True)


STARTED = []  # every Proc, so that a failed measurement leaves no process behind


class Proc:
    """A child process whose stdout lines are collected (canopen_sim.Lines)."""

    def __init__(self, args):
        STARTED.append(self)
        self.proc = subprocess.Popen([str(a) for a in args], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, text=True, bufsize=1)
        self.output = Lines(self.proc.stdout, self.proc, f"output of {self.proc.args[0]}")
        self.lines = self.output.lines

    def mark(self):
        return self.output.mark()

    def wait(self, pattern, since=0, count=1, timeout=60.0):
        """The first `count` lines at or after `since` matching pattern."""
        return self.output.wait(pattern, since, timeout, count)

    def send(self, line):
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()

    def stop(self, timeout=60.0):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
        rc = self.proc.wait(timeout)
        self.output.join(timeout)
        return rc


def cpu_seconds(pid):
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLK_TCK  # utime, stime (fields 14, 15)


def system_cpu():
    """Jiffies of the whole (guest) system by kind, from the cpu line of /proc/stat."""
    names = ("user", "nice", "system", "idle", "iowait", "irq", "softirq", "steal")
    v = [int(x) for x in Path("/proc/stat").read_text().splitlines()[0].split()[1:]]
    return dict(zip(names, v))


def all_cpu_seconds():
    """{(pid, name): utime + stime} of every process and kernel thread of the (guest) system."""
    out = {}
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                head, tail = (d / "stat").read_text().rsplit(")", 1)
            except OSError:
                continue
            f = tail.split()
            out[(int(d.name), head.split("(", 1)[1])] = (int(f[11]) + int(f[12])) / CLK_TCK
    return out


def bin_dir(build_dir):
    return Path(build_dir) / "boards" / "linux"


def read_records(path):
    """[(ts_ns, can_id)] written by can-count."""
    data = Path(path).read_bytes()
    return [(ts, cid) for ts, cid, _ in struct.iter_unpack("=QII", data)]


def configure_tpdos(network, eds, node_ids, period_ms):
    """Sets the event timer of every valid TPDO of every node; returns the COB-IDs configured."""
    od = canopen.import_od(str(eds))
    tpdo_params = [i for i in range(0x1800, 0x1A00) if i in od and 5 in od[i].subindices]
    cob_ids = []
    for nid in node_ids:
        node = canopen.RemoteNode(nid, canopen.ObjectDictionary())
        network.add_node(node)
        node.sdo.RESPONSE_TIMEOUT = 2.0
        for index in tpdo_params:
            cob = struct.unpack("<I", node.sdo.upload(index, 1))[0]
            if cob & 0x80000000:
                continue  # not valid: left as the drive has it
            ttype = node.sdo.upload(index, 2)[0]
            if ttype not in (254, 255):
                node.sdo.download(index, 2, bytes([255]))
            node.sdo.download(index, 5, struct.pack("<H", period_ms))
            cob_ids.append(cob & 0x7FF)
        del network[nid]
    return cob_ids


def send_nmt(command):
    """NMT to all nodes from a socket that receives nothing: a python-canopen network left
    connected would take every frame of the window through its reader thread, stealing the
    guest's one CPU from the simulator."""
    with socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW) as s:
        s.setsockopt(socket.SOL_CAN_RAW, socket.CAN_RAW_FILTER, b"")
        s.bind((IFACE,))
        s.send(struct.pack("=IB3x8s", 0x000, 2, bytes([command, 0]).ljust(8, b"\0")))


def parse_status(lines):
    """{node: {"sock_tx": n, "core_dropped": n, ...}} from `status` lines."""
    out = {}
    for line in lines:
        m = re.match(r"node (\d+) \S+: .*tx (\d+) \(deferred (\d+), dropped (\d+)\).*socket: tx "
                     r"(\d+), EAGAIN (\d+), ENOBUFS (\d+), other errors (\d+), rx dropped by "
                     r"kernel (\d+)", line)
        if m:
            v = [int(x) for x in m.groups()]
            out[v[0]] = {"core_tx": v[1], "core_deferred": v[2], "core_dropped": v[3],
                         "sock_tx": v[4], "eagain": v[5], "enobufs": v[6], "other": v[7],
                         "rx_dropped": v[8]}
    return out


def scale_run(args, n):
    bins = bin_dir(args.build_dir)
    rec_path = Path(args.tmp) / f"scale{n}.frames"
    counter = Proc([bins / "can-count", "--iface", IFACE, "--out", rec_path])
    counter.wait(r"^can-count: ready")
    node_ids = list(range(1, n + 1))
    cmd = [bins / "canopen-drive", "--iface", IFACE]
    for nid in node_ids:
        cmd += ["--drive", "vf-s15", "--node-id", str(nid)]
    sim = Proc(cmd)
    sim.wait(r"node\(s\) on .*ready", timeout=120)
    net = canopen.Network()
    net.connect(interface="socketcan", channel=IFACE, receive_own_messages=False)
    try:
        t = time.monotonic()
        cobs = configure_tpdos(net, ROOT / "od" / "vf-s15" / "vf-s15.eds", node_ids,
                               TPDO_PERIOD_MS)
        log(f"scale{n}: {len(cobs)} TPDOs set to {TPDO_PERIOD_MS} ms in "
            f"{time.monotonic() - t:.1f} s")
    finally:
        net.disconnect()
    send_nmt(0x01)  # start all
    sim.wait(r"NMT PRE-OPERATIONAL -> OPERATIONAL", count=n, timeout=60)
    time.sleep(1.0)  # every timer running
    sys0, cnt0, all0 = system_cpu(), cpu_seconds(counter.proc.pid), all_cpu_seconds()
    cpu0, w0 = cpu_seconds(sim.proc.pid), time.time()
    time.sleep(args.window)
    cpu1, w1 = cpu_seconds(sim.proc.pid), time.time()
    sys1, cnt1, all1 = system_cpu(), cpu_seconds(counter.proc.pid), all_cpu_seconds()
    send_nmt(0x02)  # stop all: the TPDOs end
    sim.wait(r"NMT OPERATIONAL -> STOPPED", count=n, timeout=60)
    time.sleep(0.5)
    mark = sim.mark()
    sim.send("status")
    status = parse_status(m.string for m in sim.wait(r"socket: tx", since=mark, count=n))
    sim_rc = sim.stop()
    counter.proc.send_signal(signal.SIGINT)
    summary = counter.wait(r"^can-count: frames (\d+) dropped (\d+)", timeout=60)[0]
    counter.stop()
    counter_dropped = int(summary.group(2))
    recs = read_records(rec_path)
    rec_path.unlink()

    node_cobs = set()
    for nid in node_ids:  # everything a VF-S15 node sends uses its predefined COB-IDs
        node_cobs |= {0x080 + nid, 0x180 + nid, 0x280 + nid, 0x380 + nid, 0x480 + nid,
                      0x580 + nid, 0x700 + nid}
    received = sum(1 for _, cid in recs if (cid & 0x7FF) in node_cobs and not cid & 0xE0000000)
    sent = sum(s["sock_tx"] for s in status.values())
    core_dropped = sum(s["core_dropped"] for s in status.values())
    tpdo_set = set(cobs)
    in_window = [(ts, cid & 0x7FF) for ts, cid in recs if w0 * 1e9 <= ts < w1 * 1e9]
    window = w1 - w0
    per_cob = {}
    for ts, cid in in_window:
        per_cob.setdefault(cid, []).append(ts)
    tpdo_frames = sum(len(v) for c, v in per_cob.items() if c in tpdo_set)
    gaps = [(b - a) / 1e6 for c, v in per_cob.items() if c in tpdo_set for a, b in zip(v, v[1:])]
    expected = len(cobs) * 1000 / TPDO_PERIOD_MS
    res = {
        "drives": n, "tpdos": len(cobs), "window_s": round(window, 3),
        "fps": round(len(in_window) / window, 1),
        "tpdo_fps": round(tpdo_frames / window, 1),
        "expected_fps": expected,
        "below_nominal_pct": round(100 * (1 - tpdo_frames / window / expected), 2),
        "period_mean_ms": round(sum(gaps) / len(gaps), 3) if gaps else None,
        "period_max_ms": round(max(gaps), 3) if gaps else None,
        "sent": sent, "received": received, "lost": sent + core_dropped - received,
        "core_tx_dropped": core_dropped,
        "socket_eagain": sum(s["eagain"] for s in status.values()),
        "socket_enobufs": sum(s["enobufs"] for s in status.values()),
        "sim_rx_dropped_by_kernel": sum(s["rx_dropped"] for s in status.values()),
        "counter_dropped": counter_dropped,
        "cpu_pct": round(100 * (cpu1 - cpu0) / window, 1),
        "counter_cpu_pct": round(100 * (cnt1 - cnt0) / window, 1),
        "system_cpu_pct": {k: round(100 * (sys1[k] - sys0[k]) / CLK_TCK / window, 1)
                           for k in sys1},
        "top_cpu_pct": dict(sorted(((f"{name}[{pid}]", round(100 * (v - all0.get((pid, name), 0))
                                                              / window, 1))
                                    for (pid, name), v in all1.items()
                                    if v - all0.get((pid, name), 0) > 0),
                                   key=lambda kv: -kv[1])[:6]),
        "status_nodes": len(status), "sim_exit": sim_rc,
    }
    log(f"scale{n}: {json.dumps(res)}")
    return res


def server_share_ms(recs, t0, t1, server_cob, client_cob):
    """Of the transfer between t0 and t1 (s), the time the server had the turn (ms): from each
    client frame that the server answers to the server's first frame after it, plus the bursts of
    server frames (block upload sub-blocks). The rest is the client's."""
    frames = [(ts, cid & 0x7FF) for ts, cid in recs if t0 * 1e9 <= ts <= t1 * 1e9
              and cid & 0x7FF in (server_cob, client_cob)]
    total = 0
    for (ta, a), (tb, b) in zip(frames, frames[1:]):
        if b == server_cob:  # the server is at work from the frame before its own
            total += tb - ta
    return total / 1e6


def sdo_run(args):
    bins = bin_dir(args.build_dir)
    rec_path = Path(args.tmp) / "sdo.frames"
    counter = Proc([bins / "can-count", "--iface", IFACE, "--out", rec_path])
    counter.wait(r"^can-count: ready")
    sim = Proc([bins / "canopen-drive", "--iface", IFACE, "--drive", "bench", "--node-id", "1"])
    sim.wait(r"node\(s\) on .*ready")
    net = canopen.Network()
    net.connect(interface="socketcan", channel=IFACE, receive_own_messages=False)
    data = random.Random(0x2000).randbytes(SDO_BYTES)
    kinds = ("block_download", "block_upload", "segmented_download", "segmented_upload")
    spans = {k: [] for k in kinds}  # (t0, t1) wall clock of each transfer
    equal = True
    try:
        node = canopen.RemoteNode(1, str(ROOT / "od" / "bench" / "bench.eds"))
        net.add_node(node)
        node.sdo.RESPONSE_TIMEOUT = 2.0
        var = node.sdo[0x2000]

        def download(block):
            with var.open("wb", size=len(data), block_transfer=block) as f:
                f.write(data)

        def upload(block):
            with var.open("rb", block_transfer=block) as f:
                return f.read()

        for _ in range(args.sdo_runs):
            for block, name in ((True, "block"), (False, "segmented")):
                t0 = time.time()
                download(block)
                t1 = time.time()
                got = upload(block)
                t2 = time.time()
                spans[f"{name}_download"].append((t0, t1))
                spans[f"{name}_upload"].append((t1, t2))
                if bytes(got) != data:
                    equal = False
                    log(f"sdo: {name} upload returned {len(got)} bytes, not what was "
                        "downloaded")
    finally:
        net.disconnect()
    rc = sim.stop()
    counter.proc.send_signal(signal.SIGINT)
    summary = counter.wait(r"^can-count: frames (\d+) dropped (\d+)", timeout=60)[0]
    counter.stop()
    recs = read_records(rec_path)
    rec_path.unlink()
    res = {"bytes": SDO_BYTES, "equal": equal, "sim_exit": rc,
           "counter_dropped": int(summary.group(2))}
    for k, v in spans.items():
        runs = [round((b - a) * 1000, 1) for a, b in v]
        server = [round(server_share_ms(recs, a, b, 0x581, 0x601), 1) for a, b in v]
        best = runs.index(min(runs))
        res[f"{k}_ms"] = runs[best]
        res[f"{k}_server_ms"] = server[best]
        res[f"{k}_runs_ms"] = runs
        res[f"{k}_server_runs_ms"] = server
    log(f"sdo: {json.dumps(res)}")
    return res


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--drives", default="10,127")
    ap.add_argument("--window", type=float, default=10.0)
    ap.add_argument("--sdo-runs", type=int, default=3)
    ap.add_argument("--no-sdo", action="store_true")
    ap.add_argument("--build-dir", default=str(ROOT / "build" / "default"))
    ap.add_argument("--tmp", default="/tmp")
    ap.add_argument("--json-out")
    args = ap.parse_args()
    report = {"guest": os.environ.get("VCAN_RUN_GUEST") == "1", "cpus": os.cpu_count(),
              "scale": {}}
    try:
        for n in (int(x) for x in args.drives.split(",") if x):
            report["scale"][str(n)] = scale_run(args, n)
        if not args.no_sdo:
            report["sdo"] = sdo_run(args)
    finally:
        for proc in STARTED:
            if proc.proc.poll() is None:
                proc.proc.kill()
                proc.proc.wait()
    line = json.dumps(report, sort_keys=True)
    if args.json_out:
        Path(args.json_out).write_text(line + "\n")
    print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
