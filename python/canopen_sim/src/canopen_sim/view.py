"""A live view of every drive in a running simulator, through its control socket.

    python -m canopen_sim.view --control /tmp/sim.sock        (or tools/sim-view)

One block per node: NMT and CiA 402 state, target and actual speed, the active fault, frame
counters, and a plot of the actual speed over the last seconds. `render()` makes the text from
plain data, so it is tested without a terminal; `main()` only polls and prints it.
"""
import argparse
import collections
import sys
import time

from .control import Control

BARS = " ▁▂▃▄▅▆▇█"


def sparkline(values, width):
    """The last `width` values as bars scaled between their minimum (or 0) and maximum."""
    values = list(values)[-width:]
    if not values:
        return ""
    lo, hi = min(0, min(values)), max(values)
    span = hi - lo
    out = []
    for v in values:
        level = 0 if span == 0 else round((v - lo) * (len(BARS) - 1) / span)
        out.append(BARS[level])
    return "".join(out)


class History:
    """Actual speed samples per node, for the last `seconds`."""

    def __init__(self, seconds=10.0):
        self.seconds = seconds
        self.samples = collections.defaultdict(collections.deque)

    def add(self, now, node, actual):
        q = self.samples[node]
        q.append((now, actual))
        while q and q[0][0] < now - self.seconds:
            q.popleft()

    def values(self, node):
        return [v for _, v in self.samples.get(node, ())]


def _fault(state):
    f = state.get("fault")
    if not f:
        return "-"
    text = f"{f['name'] or 'trip'} 0x{f['trip']:02X} EMCY 0x{f['emcy']:04X}"
    return text + (" (cause present)" if f["cause"] else " (cause gone)")


def render(states, history, width=100, title="canopen-drive"):
    """The view as text: `states` is [state dict, ...] as Control.state() returns them."""
    lines = [f"{title}: {len(states)} node(s)".ljust(width)[:width], ""]
    plot_width = max(10, width - 24)
    for st in states:
        node = st["node"]
        head = (f"node {node:>3} {st['drive']:<19} {st['iface']:<8} NMT {st['nmt']:<16} "
                f"{st['state'] or '-'}")
        sw = st.get("statusword")
        speed = (f"    target {st['target']:>6}  actual {st['actual']:>6}  "
                 f"statusword {'-' if sw is None else f'0x{sw:04X}'}  fault {_fault(st)}")
        count = (f"    rx {st['rx']} tx {st['tx']}  malformed {st['rx_malformed']}  "
                 f"tx dropped {st['tx_dropped']}  SDO aborts {st['sdo_aborts']}  "
                 f"trips {st['trips']}")
        values = history.values(node)
        plot = (f"    speed {sparkline(values, plot_width):<{plot_width}} "
                f"max {max(values) if values else 0}")
        lines += [head, speed, count, plot, ""]
    return "\n".join(line[:width] for line in lines)


def snapshot(ctl, history=None, now=None):
    """Every node's state from a Control, added to history (if given)."""
    states = [ctl.state(node) for node, _, _ in ctl.nodes()]
    if history is not None:
        now = time.monotonic() if now is None else now
        for st in states:
            history.add(now, st["node"], st["actual"])
    return states


def main(argv=None):
    p = argparse.ArgumentParser(description="live view of a running canopen-drive")
    g = p.add_mutually_exclusive_group(required=True)
    g.add_argument("--control", help="the simulator's --control socket")
    g.add_argument("--tcp", type=int, help="its --control-tcp port on 127.0.0.1")
    p.add_argument("--interval", type=float, default=0.2, help="seconds between updates")
    p.add_argument("--seconds", type=float, default=10.0, help="seconds of speed plotted")
    p.add_argument("--once", action="store_true", help="print one view and exit")
    p.add_argument("--width", type=int, help="columns (default: the terminal's)")
    args = p.parse_args(argv)
    ctl = (Control(args.control, subscribe=False) if args.control
           else Control(tcp=("127.0.0.1", args.tcp), subscribe=False))
    history = History(args.seconds)
    try:
        while True:
            import shutil
            width = args.width or shutil.get_terminal_size((100, 30)).columns
            text = render(snapshot(ctl, history), history, width=width)
            if args.once:
                print(text)
                return 0
            sys.stdout.write("\x1b[H\x1b[2J" + text + "\n")
            sys.stdout.flush()
            time.sleep(args.interval)
    except KeyboardInterrupt:
        return 0
    finally:
        ctl.close()


if __name__ == "__main__":
    sys.exit(main())
