#!/usr/bin/env python3
"""The demo's master: python-canopen drives a simulated Toshiba VF-S15 on vcan0.

It waits for the drive, sets it up to take run/stop and speed from CANopen (CMOd = 3, FMOd = 6,
as the manual's §7 example), enables it through the CiA 402 state machine with python-canopen's
BaseNode402, ramps it to speed, stops it again, and prints what TxPDO1 (statusword 0x6041, speed
0x6044) showed on the way: a table and a plot of 0x6044 over time.

Run it through tools/demo, which starts the simulator first:
    canopen-drive --iface vcan0 --drive vf-s15 --node-id 5
"""
import argparse
import logging
import sys
import threading
import time
from pathlib import Path

import canopen
from canopen.profiles.p402 import BaseNode402

ROOT = Path(__file__).resolve().parents[1]


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--iface", default="vcan0")
    p.add_argument("--node-id", type=int, default=5)
    p.add_argument("--eds", default=str(ROOT / "od" / "vf-s15" / "vf-s15.eds"))
    p.add_argument("--speed", type=int, default=1500, help="target speed, min^-1 (0x6042)")
    p.add_argument("--ramp", type=int, default=5,
                   help="seconds from 0 to --speed and back (0x6048/0x6049; factory: 10)")
    p.add_argument("--step", type=float, default=0.5, help="seconds between table rows")
    return p.parse_args()


def wait_for_drive(node, timeout=10.0):
    """The simulator was started just before us: ask until its SDO server answers."""
    end = time.monotonic() + timeout
    while True:
        try:
            return node.sdo[0x1000].raw
        except canopen.SdoCommunicationError:
            if time.monotonic() > end:
                sys.exit(f"demo: node {node.id} does not answer on the bus")


class Trace:
    """Every TxPDO1 the drive sends: (time, statusword, speed)."""

    def __init__(self):
        self.samples = []
        self.lock = threading.Lock()
        self.t0 = time.monotonic()

    def restart(self, statusword, speed):
        """Time 0 is now (the target is about to be sent)."""
        with self.lock:
            self.t0 = time.monotonic()
            self.samples = [(0.0, statusword, speed)]

    def on_tpdo(self, pdo):
        values = {var.index: var.raw for var in pdo}
        with self.lock:
            self.samples.append((time.monotonic() - self.t0, values.get(0x6041, 0),
                                 values.get(0x6044, 0)))

    def last(self):
        with self.lock:
            return self.samples[-1] if self.samples else (0.0, 0, 0)

    def wait_speed(self, speed, timeout):
        end = time.monotonic() + timeout
        while self.last()[2] != speed:
            if time.monotonic() > end:
                sys.exit(f"demo: 0x6044 is {self.last()[2]}, not {speed}, after {timeout} s")
            time.sleep(0.05)

    def rows(self, step):
        """One row every `step` seconds: the last TxPDO1 at or before that time."""
        with self.lock:
            samples = list(self.samples)
        if not samples:
            return []
        rows, i, t = [], 0, 0.0
        end = samples[-1][0]
        while t <= end + 1e-9:
            while i + 1 < len(samples) and samples[i + 1][0] <= t:
                i += 1
            if samples[i][0] <= t:
                rows.append((t, samples[i][1], samples[i][2]))
            t += step
        return rows


def plot(samples, top, width=64, height=12):
    """ASCII plot of 0x6044 over time, from every TxPDO1."""
    if not samples:
        return ""
    end = samples[-1][0] or 1.0
    grid = [[" "] * width for _ in range(height + 1)]
    for t, _, speed in samples:
        x = min(width - 1, int(t / end * (width - 1) + 0.5))
        y = min(height, max(0, int(speed / top * height + 0.5))) if top else 0
        grid[height - y][x] = "*"
    out = []
    for r, line in enumerate(grid):
        level = top * (height - r) / height
        label = f"{level:6.0f} |" if r % 3 == 0 else "       |"
        out.append(label + "".join(line))
    out.append("       +" + "-" * width)
    out.append(f"        0 s{'':{width - 14}}{end:5.1f} s")
    return "\n".join(out)


def main():
    args = parse_args()
    logging.basicConfig(level=logging.ERROR)  # python-canopen's advice on PDOs is not for a demo
    net = canopen.Network()
    net.connect(interface="socketcan", channel=args.iface)
    node = BaseNode402(args.node_id, args.eds)
    net.add_node(node)
    node.sdo.RESPONSE_TIMEOUT = 1.0
    for name in ("TIMEOUT_SWITCH_STATE_FINAL", "TIMEOUT_SWITCH_STATE_SINGLE"):
        setattr(node, name, 3.0)
    try:
        device_type = wait_for_drive(node)
        print(f"demo: node {node.id}: {node.sdo[0x1008].raw} (software {node.sdo[0x100A].raw}), "
              f"device type 0x{device_type:08X}, vendor 0x{node.sdo[0x1018][1].raw:08X}")

        # Run/stop and frequency from CANopen (manual §7.1), and the ramp to show.
        node.sdo[0x2003].raw = 3           # CMOd: command mode = CANopen
        node.sdo[0x2004].raw = 6           # FMOd: frequency setting = CANopen
        node.sdo[0x6048][1].raw = args.speed  # acceleration: speed per time
        node.sdo[0x6048][2].raw = args.ramp
        node.sdo[0x6049][1].raw = args.speed  # deceleration
        node.sdo[0x6049][2].raw = args.ramp
        print(f"demo: CMOd = 3, FMOd = 6; ramps 6048/6049 = {args.speed} min^-1 per {args.ramp} s")

        node.nmt.state = "PRE-OPERATIONAL"
        node.setup_402_state_machine()    # reads the PDO mappings: RPDO1 6040+6042, TPDO1 6041+6044
        trace = Trace()
        node.tpdo[1].add_callback(trace.on_tpdo)
        node.nmt.state = "OPERATIONAL"
        node.tpdo_values[0x6041] = node.sdo[0x6041].raw
        print(f"demo: NMT OPERATIONAL; CiA 402 state {node.state}")
        for state in ("READY TO SWITCH ON", "SWITCHED ON", "OPERATION ENABLED"):
            node.state = state
            print(f"demo: CiA 402 -> {node.state} (statusword 0x{node.statusword:04X})")

        trace.restart(node.statusword, node.sdo[0x6044].raw)
        node.rpdo[1][0x6042].raw = args.speed  # vl target velocity, mapped next to 0x6040
        node.controlword = 0x000F              # RPDO1: 0F 00 + target
        print(f"demo: target 0x6042 = {args.speed} min^-1; ramping")
        trace.wait_speed(args.speed, args.ramp + 5)
        t_up = trace.last()[0]
        print(f"demo: at speed after {t_up:.2f} s (statusword 0x{trace.last()[1]:04X})")

        node.controlword = 0x0007              # disable operation: stop on the 0x6049 ramp
        print("demo: disable operation (0x0007): decelerating")
        trace.wait_speed(0, args.ramp + 5)
        node.state = "SWITCH ON DISABLED"
        print(f"demo: stopped; CiA 402 -> {node.state}")
        node.nmt.state = "PRE-OPERATIONAL"

        pole_pairs = node.sdo[0x2856].raw or 2  # F856: f [Hz] = n [min^-1] x F856 / 60
        rows = trace.rows(args.step)
        print()
        print("   t [s]   6041 statusword   6044 [min^-1]   f [Hz]")
        for t, sw, speed in rows:
            print(f"  {t:6.2f}   0x{sw:04X}            {speed:6d}        "
                  f"{speed * pole_pairs / 60:6.2f}")
        print()
        with trace.lock:
            samples = list(trace.samples)
        print(f"0x6044 vl velocity actual value [min^-1] over time ({len(samples)} TxPDO1 frames)")
        print(plot(samples, args.speed))
        return 0
    finally:
        net.disconnect()


if __name__ == "__main__":
    sys.exit(main())
