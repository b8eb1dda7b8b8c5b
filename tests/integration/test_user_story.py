"""The simulator as a test instrument, written as a user of the canopen_sim package would write
it: a VF-S15 from the pytest fixture, ramped with python-canopen, a trip injected at a chosen
moment (at speed), the EMCY seen by the master, and the --trace decoded with a DBC of the drive's
PDOs by cantools."""
import struct
import time

import cantools
import canopen
from canopen.profiles.p402 import BaseNode402
from canopen_sim.dbc import make_dbc, parse_layout

from conftest import IFACE, TIMEOUT
from drives import ROOT

EDS = ROOT / "od" / "vf-s15" / "vf-s15.eds"
SPEED = 1500  # min^-1


def wait_tpdo_speed(drive, speed, timeout):
    """Until TxPDO1 (statusword, 0x6044) shows `speed`."""
    deadline = time.monotonic() + timeout
    while drive.tpdo[1][0x6044].raw != speed:
        left = deadline - time.monotonic()
        assert left > 0, f"0x6044 is {drive.tpdo[1][0x6044].raw}, not {speed}"
        drive.tpdo[1].wait_for_reception(timeout=left)


def wait_emcy(drive, since, timeout):
    """The first EMCY python-canopen logged at or after position `since` (the fault command
    returns once the EMCY is sent, so it may be in the log before a wait would start)."""
    deadline = time.monotonic() + timeout
    with drive.emcy.emcy_received:
        while len(drive.emcy.log) <= since:
            left = deadline - time.monotonic()
            assert left > 0, "no EMCY"
            drive.emcy.emcy_received.wait(left)
        return drive.emcy.log[since]


def test_ramp_trip_at_speed_and_decode_the_trace(canopen_sim_factory, tmp_path):
    trace = tmp_path / "bus.log"
    sim = canopen_sim_factory([("vf-s15", 5)], trace=trace)   # the fixture: running, ready

    net = canopen.Network()
    net.connect(interface="socketcan", channel=IFACE)
    try:
        drive = BaseNode402(5, str(EDS))
        net.add_node(drive)
        drive.sdo.RESPONSE_TIMEOUT = 2.0
        drive.sdo[0x2003].raw = 3                # run/stop from CANopen (manual §7.1)
        drive.sdo[0x2004].raw = 6                # speed from CANopen
        drive.sdo[0x6048][1].raw = SPEED         # 0 -> 1500 min^-1 in 1 s
        drive.sdo[0x6048][2].raw = 1
        drive.nmt.state = "PRE-OPERATIONAL"
        drive.setup_402_state_machine()
        drive.nmt.state = "OPERATIONAL"
        drive.tpdo_values[0x6041] = drive.sdo[0x6041].raw
        drive.state = "OPERATION ENABLED"
        drive.rpdo[1][0x6042].raw = SPEED
        drive.controlword = 0x000F               # RPDO1: enable operation + target
        wait_tpdo_speed(drive, SPEED, timeout=10 * TIMEOUT)
        assert sim.state(5)["actual"] == SPEED

        # the chosen moment: at speed, trip OC1 through the API
        mark, emcy_mark = sim.mark(), len(drive.emcy.log)
        sim.fault(5, 0x01)
        emcy = wait_emcy(drive, emcy_mark, TIMEOUT)
        assert emcy.code == 0x2310 and emcy.register & 0x01
        sim.wait_event(r"CiA 402 FAULT REACTION ACTIVE -> FAULT$", node=5, since=mark)
        state = sim.state(5)
        assert state["state"] == "FAULT" and state["fault"]["name"] == "OC1"
        assert state["statusword"] & 0x4F == 0x08 and state["statusword"] == drive.sdo[0x6041].raw
        layout = parse_layout(sim.command("pdo 5"))   # the mapping in force
    finally:
        net.disconnect()
    sim.stop()

    # decode the trace with the DBC of the mapping in force (= the default one here)
    od = canopen.import_od(str(EDS), 5)
    dbc = make_dbc([(od, 5, "vf-s15", layout)])
    assert dbc == make_dbc([(od, 5, "vf-s15", None)])
    db = cantools.database.load_string(dbc, database_format="dbc")
    with open(trace) as f:
        frames = list(cantools.logreader.Parser(f))
    assert frames and all(fr.channel == IFACE for fr in frames)
    ids = {fr.frame_id for fr in frames}
    assert {0x705, 0x605, 0x585, 0x000, 0x205, 0x185, 0x085} <= ids  # boot-up, SDO, NMT, PDOs, EMCY
    tpdo = [db.decode_message(fr.frame_id, fr.data) for fr in frames if fr.frame_id == 0x185]
    rpdo = [db.decode_message(fr.frame_id, fr.data) for fr in frames if fr.frame_id == 0x205]
    speeds = [m["vl_velocity_actual_value_6044"] for m in tpdo]
    assert max(speeds) == SPEED and 0 < sorted(set(speeds))[1] < SPEED  # a ramp, not a step
    assert tpdo[-1]["Statusword_6041"] & 0x0008, "the last TPDO1 shows the fault"
    assert {"Controlword_6040": 0x000F, "vl_target_velocity_6042": SPEED} in rpdo
    emcy = [fr for fr in frames if fr.frame_id == 0x085]
    assert struct.unpack_from("<H", emcy[0].data)[0] == 0x2310
