#!/usr/bin/env python3
"""The EtherCAT demo's master: pysoem (SOEM) drives a simulated Toshiba VF-MB1 with its EtherCAT
option (IPE003Z) over a veth pair.

It scans the line (the slave's name and identity come from its SII EEPROM), sets the drive up to
take run/stop and speed from EtherCAT over CoE (C003 = 4, F004 = 7, then F899 = 1 to apply them,
as the option's manual §3.1 asks for a reset), maps the process data, brings the slave to OP,
walks the CiA 402 state machine through the cyclic outputs (controlword 0x6040, target 0x6042),
ramps to speed and back, and prints what the cyclic inputs (statusword 0x6041, speed 0x6044)
showed: a table and a plot of 0x6044 over time, as the CAN demo does.

Run it through tools/demo --ecat, which starts the simulator first:
    canopen-drive --ecat-iface veth0 --drive vf-mb1-ecat
"""
import argparse
import struct
import sys
import threading
import time
from pathlib import Path

import pysoem

sys.path.insert(0, str(Path(__file__).resolve().parent))
from demo import plot  # noqa: E402  (the CAN demo's ASCII plot)


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--iface", default="veth1", help="the master's end of the pair")
    p.add_argument("--speed", type=int, default=1500, help="target speed, min^-1 (0x6042)")
    p.add_argument("--ramp", type=int, default=5,
                   help="seconds from 0 to --speed and back (0x6048/0x6049)")
    p.add_argument("--step", type=float, default=0.5, help="seconds between table rows")
    p.add_argument("--cycle", type=float, default=2.0, help="process data cycle, ms (1-4)")
    return p.parse_args()


class Cycle:
    """The master's cyclic task: one LRW frame per period; every input sample kept."""

    def __init__(self, master, period):
        self.master = master
        self.period = period
        self.lock = threading.Lock()
        self.samples = []            # (t, statusword, speed)
        self.wkc_bad = 0             # in OP: a frame back with another working counter
        self.no_frame = 0            # in OP: no frame back within 2 ms
        self.frames = 0
        self.in_op = False
        self.t0 = time.monotonic()
        self.running = True
        self.thread = threading.Thread(target=self.run, daemon=True)

    def run(self):
        nxt = time.monotonic()
        while self.running:
            with self.lock:
                self.master.send_processdata()
                # up to 20 ms for the answer: the simulator is a process on a machine that may
                # be busy, not a real-time slave (a late frame slips the cycle, it is not lost)
                wkc = self.master.receive_processdata(20000)
                sw, speed = struct.unpack("<Hh", bytes(self.master.slaves[0].input)[:4])
                if self.in_op:
                    self.frames += 1
                    if wkc < 0:
                        self.no_frame += 1
                    elif wkc != self.master.expected_wkc:
                        self.wkc_bad += 1
                self.samples.append((time.monotonic() - self.t0, sw, speed))
            nxt += self.period
            delay = nxt - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            else:
                nxt = time.monotonic()

    def restart(self):
        with self.lock:
            self.t0 = time.monotonic()
            self.samples = []

    def output(self, controlword, speed=0):
        with self.lock:
            self.master.slaves[0].output = struct.pack("<Hh", controlword, speed)

    def last(self):
        with self.lock:
            return self.samples[-1] if self.samples else (0.0, 0, 0)

    def wait(self, test, what, timeout):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if test(*self.last()):
                return self.last()
            time.sleep(0.01)
        sys.exit(f"demo: no {what} after {timeout} s (statusword 0x{self.last()[1]:04X}, "
                 f"0x6044 {self.last()[2]})")

    def rows(self, step):
        with self.lock:
            samples = list(self.samples)
        out, nxt = [], 0.0
        for t, sw, speed in samples:
            if t >= nxt:
                out.append((t, sw, speed))
                nxt += step
        if samples and out[-1] != samples[-1]:
            out.append(samples[-1])
        return out


def sdo_write(slave, index, sub, fmt, value):
    slave.sdo_write(index, sub, struct.pack(fmt, value))


def wait_al(master, state, timeout=5.0):
    end = time.monotonic() + timeout
    while master.state_check(state, 50000) != state:
        if time.monotonic() > end:
            master.read_state()
            s = master.slaves[0]
            sys.exit(f"demo: the slave stays in AL state 0x{s.state:02X}, AL status code "
                     f"0x{s.al_status:04X}, not 0x{state:02X}")


def main():
    args = parse_args()
    sys.stdout.reconfigure(line_buffering=True)  # interleaves with the simulator's lines
    master = pysoem.Master()
    master.open(args.iface)
    cycle = None
    try:
        end = time.monotonic() + 10
        while master.config_init() < 1:          # the simulator was started just before us
            if time.monotonic() > end:
                sys.exit(f"demo: no EtherCAT slave answers on {args.iface}")
            time.sleep(0.1)
        s = master.slaves[0]
        print(f"demo: slave 1: {s.name}, vendor 0x{s.man:08X}, product 0x{s.id:08X}, revision "
              f"0x{s.rev:08X} (from its SII EEPROM); {s.sdo_read(0x1008, 0).decode()} over CoE")

        # Manual §3.1: run/stop and frequency from the option, applied by a communication
        # function reset (F899 = 1) - all over CoE, in PRE-OP.
        sdo_write(s, 0x2003, 0, "<H", 4)          # C003 (CMOd) = 4: option
        sdo_write(s, 0x2004, 0, "<H", 7)          # F004 (FMOd) = 7: option
        sdo_write(s, 0x2899, 0, "<H", 1)          # F899 = 1: reset, the settings take effect
        sdo_write(s, 0x6048, 1, "<I", args.speed)  # acceleration: speed per time
        sdo_write(s, 0x6048, 2, "<H", args.ramp)
        sdo_write(s, 0x6049, 1, "<I", args.speed)  # deceleration
        sdo_write(s, 0x6049, 2, "<H", args.ramp)
        print(f"demo: C003 = 4, F004 = 7, F899 = 1 (reset); ramps 6048/6049 = {args.speed} "
              f"min^-1 per {args.ramp} s")

        size = master.config_map()
        master.config_dc()
        wait_al(master, pysoem.SAFEOP_STATE)
        cycle = Cycle(master, args.cycle / 1000.0)
        cycle.thread.start()
        master.state = pysoem.OP_STATE
        master.write_state()
        wait_al(master, pysoem.OP_STATE)
        cycle.in_op = True
        print(f"demo: OP; {size}-byte process image, one LRW frame every {args.cycle:g} ms, "
              f"working counter {master.expected_wkc} expected")

        for cw, want, name in ((0x0006, 0x21, "READY TO SWITCH ON"), (0x0007, 0x23, "SWITCHED ON"),
                               (0x000F, 0x27, "OPERATION ENABLED")):
            cycle.output(cw, args.speed if cw == 0x000F else 0)
            if cw == 0x000F:
                cycle.restart()
            _, sw, _ = cycle.wait(lambda t, sw, sp, w=want: sw & 0x6F == w, name, 5)
            print(f"demo: controlword 0x{cw:04X} -> CiA 402 {name} (statusword 0x{sw:04X})")
        print(f"demo: target 0x6042 = {args.speed} min^-1; ramping")
        t_up = cycle.wait(lambda t, sw, sp: sp == args.speed, "speed", args.ramp + 5)[0]
        print(f"demo: at speed after {t_up:.2f} s")
        cycle.output(0x000F, 0)                   # target 0: down on the 0x6049 ramp
        print("demo: target 0x6042 = 0: decelerating")
        cycle.wait(lambda t, sw, sp: sp == 0, "stop", args.ramp + 5)
        cycle.output(0x0000)                      # disable voltage
        cycle.wait(lambda t, sw, sp: sw & 0x4F == 0x40, "SWITCH ON DISABLED", 5)
        print("demo: stopped; CiA 402 -> SWITCH ON DISABLED")

        pole_pairs = struct.unpack("<H", s.sdo_read(0x2856, 0)[:2])[0] or 2
        print()
        print("   t [s]   6041 statusword   6044 [min^-1]   f [Hz]")
        for t, sw, speed in cycle.rows(args.step):
            print(f"  {t:6.2f}   0x{sw:04X}            {speed:6d}        "
                  f"{speed * pole_pairs / 60:6.2f}")
        print()
        with cycle.lock:
            samples = list(cycle.samples)
            frames, bad, lost = cycle.frames, cycle.wkc_bad, cycle.no_frame
        print(f"0x6044 vl velocity actual value [min^-1] over time ({len(samples)} cycles)")
        print(plot([(t, sw, sp) for t, sw, sp in samples], args.speed))
        print(f"in OP: {frames} LRW frames, {bad} with a wrong working counter, {lost} not back "
              f"within 2 ms")
        cycle.running = False
        cycle.thread.join()
        master.state = pysoem.INIT_STATE
        master.write_state()
        return 0
    finally:
        if cycle is not None:
            cycle.running = False
        master.close()


if __name__ == "__main__":
    sys.exit(main())
