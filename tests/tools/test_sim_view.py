"""The live view's rendering (canopen_sim.view.render) and the package's pure parts (event lines,
DBC text), without a terminal or a bus."""
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "python" / "canopen_sim" / "src"))
from canopen_sim.control import parse_event  # noqa: E402
from canopen_sim.dbc import parse_layout  # noqa: E402
from canopen_sim.view import BARS, History, render, sparkline  # noqa: E402


def state(node=5, **kw):
    st = {"node": node, "drive": "vf-s15", "iface": "vcan0", "nmt": "OPERATIONAL",
          "state": "OPERATION ENABLED", "controlword": 15, "statusword": 0x0637, "target": 1500, "actual": 750,
          "fault": None, "rx": 120, "tx": 340, "rx_malformed": 0, "tx_dropped": 0,
          "sdo_aborts": 1, "trips": 0}
    st.update(kw)
    return st


def test_sparkline_scales_a_ramp():
    line = sparkline([0, 250, 500, 750, 1000, 1500], 40)
    assert line[0] == BARS[0] and line[-1] == BARS[-1]
    assert list(line) == sorted(line, key=BARS.index)  # a ramp up plots rising
    assert sparkline([7] * 3, 10) == BARS[-1] * 3      # scaled from 0
    assert sparkline([0, 0], 10) == BARS[0] * 2
    assert len(sparkline(range(100), 20)) == 20  # only the last `width` samples
    assert sparkline([], 5) == ""


def test_render_shows_every_drive():
    h = History(seconds=10)
    for t in range(11):
        h.add(t, 5, t * 150)
        h.add(t, 7, 0)
    h.add(11.5, 5, 1500)  # the sample at t=0 and t=1 are older than 10 s now
    assert h.values(5)[0] == 300
    tripped = state(7, drive="benshaw-rsi", state="FAULT", actual=0, trips=1,
                    fault={"trip": 1, "emcy": 0x2310, "name": "OC1", "cause": True})
    text = render([state(), tripped], h, width=100)
    lines = text.splitlines()
    assert all(len(line) <= 100 for line in lines)
    assert lines[0].startswith("canopen-drive: 2 node(s)")
    assert "node   5 vf-s15" in text and "NMT OPERATIONAL" in text and "OPERATION ENABLED" in text
    assert "target   1500  actual    750  statusword 0x0637  fault -" in text
    assert "fault OC1 0x01 EMCY 0x2310 (cause present)" in text
    assert "rx 120 tx 340" in text and "SDO aborts 1" in text and "trips 1" in text
    plot5 = next(line for line in lines if "max 1500" in line)
    assert BARS[-1] in plot5
    # the benchmark device has no CiA 402 state
    assert "NMT PRE-OPERATIONAL  -" in render([state(9, drive="bench", state=None,
                                                      nmt="PRE-OPERATIONAL")], h)


def test_event_lines_and_pdo_layout():
    ev = parse_event("event 12.503117 node 5 vf-s15: CiA 402 SWITCH ON DISABLED -> FAULT")
    assert (ev.time, ev.node, ev.drive, ev.text) == (12.503117, 5, "vf-s15",
                                                     "CiA 402 SWITCH ON DISABLED -> FAULT")
    ev = parse_event("event 0.700000 slave 2 vf-mb1-ecat: EtherCAT SAFEOP -> OP")  # --ecat-iface
    assert (ev.node, ev.drive, ev.text) == (2, "vf-mb1-ecat", "EtherCAT SAFEOP -> OP")
    ev = parse_event("event 1.000000 canopen-drive: scenario s.txt:2 at 1.000000 s: quit")
    assert ev.node is None and ev.text.startswith("canopen-drive: scenario")
    assert parse_event("data 1") is None
    assert parse_layout(["tpdo 1 0x00000185 0x60410010 0x60440010", "rpdo 2 0x80000305"]) == [
        ("tpdo", 1, 0x185, [0x60410010, 0x60440010]), ("rpdo", 2, 0x80000305, [])]
