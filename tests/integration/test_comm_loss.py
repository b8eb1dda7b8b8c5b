"""Communication loss over vcan: python-canopen is the master, produces its heartbeat or guards
the drive, enables it and runs the motor, then falls silent; the drive's configured reaction is
observed as a master sees it: the EMCY, 0x603F (0x2063 on the Vacon, which has no 0x603F), the
statusword and the speed 0x6044.

The reactions and parameters are those of each drive's NOTES.md and manual:
  VF-S15 (NOTES B9, manual §3.2): heartbeat consumer 0x1016 or life guarding 0x100C/0x100D;
    C100 = 0x4100 (delay, 0.1 s), C101 = 0x4101: 1 none, 2 deceleration stop, 3 coast stop,
    4 emergency stop (trip 0x8130), 5 preset speed C102 (0x4102); EMCY 0x8130 at every loss.
  Benshaw RSi (NOTES B2, B13, C20, C22): life guarding only; a guard error puts the node in
    PRE-OPERATIONAL (no EMCY), Lost Command after Pr.13 = 0x401A:0D (0.1 s) outside OPERATIONAL;
    Pr.12 = 0x401A:0C: 1 free-run trip 0xFF0A, 2 decelerating trip 0xFF0A, 3/4/5 warnings (bit 7).
  VF-MB1 (NOTES B8): heartbeat consumer 0x1016 as the EtherCAT watchdog; C100/C101 as on the
    VF-S15 but C101 = 4 trips Err8 with 0x7520 and there is no 0x81xx EMCY; the other reactions
    keep the CiA 402 state and set alarm FC91 (0x2C91) bit 11 while the loss lasts.
  Vacon OPT-C6 (NOTES B2): life guarding only; expiry = Fieldbus Fault 53, EMCY 0x8130; reaction
    by the board setting fieldbus_fault_response: 1 warning, 2 fault + ramp stop, 3 fault + coast.

Nothing sleeps to let time pass: every wait is for a frame or for an SDO-read value, with a
timeout. On a busy machine (tests/README of tools/test-all: two cores, several suites) a process
may not run for a few hundred milliseconds, so the monitoring times are far above the master's
periods (a heartbeat consumer time of 1 s for a 50 ms heartbeat, a life time of 1 s for a 50 ms
guard period: a stall of the master cannot look like a loss), a time is taken before the master
falls silent (the last frame it sent is no later than that minus one period; taken after, a slow
return of stop() shortened what the test measured), and every ramp a test watches lasts seconds
(a deceleration is seen by SDO polls, which may each take a while).
"""
import time

import can

from conftest import IFACE, TIMEOUT, wait_emcy
from drives import BY_ID

MASTER = 0x7F        # the master's node-ID for its heartbeat (0x77F)
SPEED = 600          # min^-1: reached within a second with the ramps set below


def poll(read, pred, what, timeout=TIMEOUT):
    """Reads (by SDO) until pred(value) holds; returns the value."""
    deadline = time.monotonic() + timeout
    seen = []
    while True:
        value = read()
        if pred(value):
            return value
        if not seen or seen[-1] != value:
            seen.append(value)
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}; read "
                                 f"{seen[-8:]}")


def state_of(sw):
    """CiA 402 state from a statusword (the bits of CiA 402 Table 30)."""
    if sw & 0x4F == 0x08:
        return "FAULT"
    if sw & 0x4F == 0x0F:
        return "FAULT REACTION ACTIVE"
    if sw & 0x4F == 0x40:
        return "SWITCH ON DISABLED"
    if sw & 0x6F == 0x21:
        return "READY TO SWITCH ON"
    if sw & 0x6F == 0x23:
        return "SWITCHED ON"
    if sw & 0x6F == 0x27:
        return "OPERATION ENABLED"
    if sw & 0x6F == 0x07:
        return "QUICK STOP ACTIVE"
    return f"? 0x{sw:04X}"


def wait_state(node, state, timeout=TIMEOUT):
    return poll(lambda: node.sdo[0x6041].raw, lambda sw: state_of(sw) == state,
                f"statusword of {state}", timeout)


def speed(node):
    return node.sdo[0x6044].raw


def enable_and_run(node, target=SPEED):
    """Controlword by SDO (Shutdown, Switch on, Enable operation; 0x007F keeps the vl bits of
    the drives that latch them) and the target; returns once 0x6044 shows the speed."""
    node.nmt.state = "OPERATIONAL"
    node.sdo[0x6042].raw = 0  # the VF-MB1 enables only once 6042 was received (its NOTES B4.4)
    for cw in (0x0006, 0x0007, 0x000F):
        node.sdo[0x6040].raw = cw
    wait_state(node, "OPERATION ENABLED")
    node.sdo[0x6040].raw = 0x007F if node.id == BY_ID["benshaw-rsi"].node_id else 0x000F
    node.sdo[0x6042].raw = target
    poll(lambda: speed(node), lambda v: v == target, f"0x6044 = {target}")


def wait_master_heartbeats(count=3):
    """Returns once `count` heartbeats of the master have been on the bus, seen from a socket of
    its own (the master's socket does not receive what it sends): the drive has then taken at
    least one after its consumer was configured, and monitors it."""
    with can.Bus(interface="socketcan", channel=IFACE,
                 can_filters=[{"can_id": 0x700 + MASTER, "can_mask": 0x7FF}]) as bus:
        deadline = time.monotonic() + TIMEOUT
        for _ in range(count):
            msg = bus.recv(timeout=max(0.0, deadline - time.monotonic()))
            assert msg is not None, f"no heartbeat of the master within {TIMEOUT} s"


def emcy_codes(node, since):
    return [e.code for e in node.emcy.log[since:]]


# --- Toshiba VF-S15: heartbeat and life guarding, C100/C101 ---------------------------------------

VF_S15 = BY_ID["vf-s15"]
VF_MB1 = BY_ID["vf-mb1-ecat"]
HB_CONSUMER_MS = 1000
HB_PERIOD = 0.05
GUARD_TIME_MS = 100
LIFE_FACTOR = 10     # life time 1 s: twenty guard periods


def toshiba_running(sims, nodes, network, c101, c100=0, guarding=False, extra=(), drive=VF_S15,
                    c103=None, command_mode=None, run=True):
    """VF-S15 (or VF-MB1) run from CANopen (CMOd/FMOd of drives.py) at SPEED, its loss reaction
    C101 (0x4101), delay C100 (0x4100, 0.1 s) and condition C103 (0x4103, None: the default),
    monitoring the master by heartbeat consumer 0x1016 or by life guarding (100 ms x 10).
    command_mode: CMOd (0x2003) instead of the CANopen one; run=False: not enabled. Returns
    (node, stop): stop() silences the master and returns the time just before."""
    sims.start([(drive.id, drive.node_id)], extra=extra)
    node = nodes(drive)
    for index, sub, value in drive.run_from_canopen:
        node.sdo[index].raw = value
    if command_mode is not None:
        node.sdo[0x2003].raw = command_mode
    if drive is VF_MB1:
        # its profile selection (CMOd/FMOd) takes effect at a reset (test_drive_vf_mb1_ecat.c
        # test_boot_and_profile_selection_needs_a_reset); 0x1016 is volatile, so set after it
        mark = network.recorder.mark()
        node.nmt.send_command(0x81)
        network.recorder.wait_frame(0x700 + drive.node_id, b"\x00", since=mark)
    node.sdo[0x4101].raw = c101
    node.sdo[0x4100].raw = c100
    if c103 is not None:
        node.sdo[0x4103].raw = c103
    node.sdo[0x6048][2].raw = 1  # 1500 min^-1 per 1 s
    node.sdo[0x6049][2].raw = 10  # 1500 min^-1 per 10 s: 4 s from SPEED, long enough to watch
    if guarding:
        node.sdo[0x1017].raw = 0  # guarding is answered only without a heartbeat (B9)
        node.sdo[0x100C].raw = GUARD_TIME_MS
        node.sdo[0x100D].raw = LIFE_FACTOR
        node.nmt.start_node_guarding(HB_PERIOD)
        silence = node.nmt.stop_node_guarding
    else:
        task = network.send_periodic(0x700 + MASTER, b"\x05", HB_PERIOD)
        silence = task.stop
        # 0x1016 is read-only in OPERATIONAL (§6.2): configured in PRE-OPERATIONAL
        node.sdo[0x1016][1].raw = (MASTER << 16) | HB_CONSUMER_MS
    try:
        if run:
            enable_and_run(node)
        else:
            node.nmt.state = "OPERATIONAL"
            if not guarding:
                wait_master_heartbeats()
    except BaseException:
        silence()
        raise
    assert not [c for c in emcy_codes(node, 0) if c], "no EMCY before the loss"

    def stop():
        before = time.time()
        silence()
        return before
    return node, stop


def test_vf_s15_heartbeat_loss_c101_4_emergency_stop_trips_8130(sims, nodes, network):
    node, stop = toshiba_running(sims, nodes, network, c101=4)
    since = len(node.emcy.log)
    t_stop = stop()
    emcy = wait_emcy(node, since, 0x8130)
    assert emcy.register & 0x10, f"error register 0x{emcy.register:02X}: communication bit"
    # detected one consumer time after the last heartbeat, not before
    assert emcy.timestamp - t_stop >= HB_CONSUMER_MS / 1000 - HB_PERIOD - 0.01
    wait_state(node, "FAULT")
    assert node.sdo[0x603F].raw == 0x8130
    assert speed(node) == 0
    assert node.sdo[0x1001].raw & 0x10


def test_vf_s15_heartbeat_loss_c101_3_coast_stop(sims, nodes, network):
    node, stop = toshiba_running(sims, nodes, network, c101=3)
    since = len(node.emcy.log)
    stop()
    wait_emcy(node, since, 0x8130)  # the loss itself is reported whatever C101 says
    sw = wait_state(node, "SWITCH ON DISABLED")
    assert speed(node) == 0, "a coast stop switches the output off at once"
    assert node.sdo[0x603F].raw == 0, "a coast stop is not a trip"
    assert not sw & 0x08


def test_vf_s15_heartbeat_loss_c101_2_deceleration_stop(sims, nodes, network):
    node, stop = toshiba_running(sims, nodes, network, c101=2)
    since = len(node.emcy.log)
    stop()
    wait_emcy(node, since, 0x8130)
    # on the 0x6049 ramp: still OPERATION ENABLED with a speed between SPEED and 0 ...
    poll(lambda: (speed(node), state_of(node.sdo[0x6041].raw)),
         lambda v: 0 < v[0] < SPEED and v[1] == "OPERATION ENABLED",
         "a decelerating drive")
    # ... then SWITCH ON DISABLED at standstill, no trip
    wait_state(node, "SWITCH ON DISABLED", timeout=TIMEOUT + 5)
    assert speed(node) == 0
    assert node.sdo[0x603F].raw == 0


def test_vf_s15_heartbeat_loss_c101_1_none_keeps_running(sims, nodes, network):
    node, stop = toshiba_running(sims, nodes, network, c101=1)
    since = len(node.emcy.log)
    stop()
    wait_emcy(node, since, 0x8130)
    # Back: the EMCY's end (0x0000) says the loss is over; the drive ran on through it.
    since = len(node.emcy.log)
    task = network.send_periodic(0x700 + MASTER, b"\x05", HB_PERIOD)
    try:
        wait_emcy(node, since, 0x0000)
        assert state_of(node.sdo[0x6041].raw) == "OPERATION ENABLED"
        assert speed(node) == SPEED
        assert node.sdo[0x603F].raw == 0
    finally:
        task.stop()


def test_vf_s15_heartbeat_loss_c101_5_preset_speed(sims, nodes, network):
    # the preset frequencies are not in the manual: the board setting preset_speed (NOTES B9)
    node, stop = toshiba_running(sims, nodes, network, c101=5, extra=["--set", "preset_speed=300"])
    node.sdo[0x4102].raw = 1  # C102: preset speed 1
    since = len(node.emcy.log)
    stop()
    wait_emcy(node, since, 0x8130)
    poll(lambda: speed(node), lambda v: v == 300, "0x6044 at the preset speed 300")
    assert state_of(node.sdo[0x6041].raw) == "OPERATION ENABLED"
    assert node.sdo[0x603F].raw == 0


def test_vf_s15_c100_delays_the_emergency_stop(sims, nodes, network):
    node, stop = toshiba_running(sims, nodes, network, c101=4, c100=10)  # 1.0 s
    since = len(node.emcy.log)
    stop()
    detected = wait_emcy(node, since, 0x8130).timestamp
    sw = wait_state(node, "FAULT", timeout=TIMEOUT + 1)
    tripped = time.time()
    assert tripped - detected >= 1.0 - 0.02, f"tripped {tripped - detected:.3f} s after the EMCY"
    assert node.sdo[0x603F].raw == 0x8130, f"statusword 0x{sw:04X}"


def test_vf_s15_life_guarding_loss_c101_3_coast_stop(sims, nodes, network):
    node, stop = toshiba_running(sims, nodes, network, c101=3, guarding=True)
    since = len(node.emcy.log)
    stop()
    wait_emcy(node, since, 0x8130)
    wait_state(node, "SWITCH ON DISABLED")
    assert speed(node) == 0
    assert node.sdo[0x603F].raw == 0


def test_vf_s15_life_guarding_loss_c101_4_trips_8130(sims, nodes, network):
    node, stop = toshiba_running(sims, nodes, network, c101=4, guarding=True)
    since = len(node.emcy.log)
    stop()
    wait_emcy(node, since, 0x8130)
    wait_state(node, "FAULT")
    assert node.sdo[0x603F].raw == 0x8130
    assert speed(node) == 0


# C103 (NOTES B9): 0 react always, 1 (default) only with CMOd and FMOd on CANopen, 2 as 1 and only
# while running. The loss itself sends EMCY 0x8130 whatever C103 says; C101 = 4 with C100 = 0
# trips in the same pass that sends it, so once the EMCY is in, the trip is there or never comes.

def test_vf_s15_c103_0_reacts_outside_canopen_command_mode(sims, nodes, network):
    node, stop = toshiba_running(sims, nodes, network, c101=4, c103=0, command_mode=1, run=False)
    since = len(node.emcy.log)
    stop()
    wait_emcy(node, since, 0x8130)
    wait_state(node, "FAULT")
    assert node.sdo[0x603F].raw == 0x8130


def test_vf_s15_c103_1_ignores_a_loss_outside_canopen_command_mode(sims, nodes, network):
    node, stop = toshiba_running(sims, nodes, network, c101=4, c103=1, command_mode=1, run=False)
    since = len(node.emcy.log)
    stop()
    wait_emcy(node, since, 0x8130)
    assert node.sdo[0x603F].raw == 0, "C103 = 1 with CMOd = 1: no reaction"
    assert state_of(node.sdo[0x6041].raw) == "SWITCH ON DISABLED"


def test_vf_s15_c103_2_ignores_a_loss_while_not_running(sims, nodes, network):
    node, stop = toshiba_running(sims, nodes, network, c101=4, c103=2, run=False)
    since = len(node.emcy.log)
    stop()
    wait_emcy(node, since, 0x8130)
    assert node.sdo[0x603F].raw == 0, "C103 = 2 with the drive not running: no reaction"
    assert state_of(node.sdo[0x6041].raw) == "SWITCH ON DISABLED"


def test_vf_s15_c103_2_trips_while_running(sims, nodes, network):
    node, stop = toshiba_running(sims, nodes, network, c101=4, c103=2)
    since = len(node.emcy.log)
    stop()
    wait_emcy(node, since, 0x8130)
    wait_state(node, "FAULT")
    assert node.sdo[0x603F].raw == 0x8130
    assert speed(node) == 0


# --- Toshiba VF-MB1 (EtherCAT dictionary on CAN): heartbeat consumer as the watchdog, C100/C101 ---
# NOTES B8: C101 = 4 is the network error stop, trip Err8 with 0x603F/EMCY 0x7520 and no 0x81xx
# EMCY (C34); C101 = 0, 1, 2, 3, 5 keep the CiA 402 state, set the alarm FC91 (0x2C91) bit 11 and
# statusword bit 7 while the error lasts, and the drive follows the command again afterwards.


def test_vf_mb1_heartbeat_loss_c101_4_network_error_stop_err8_7520(sims, nodes, network):
    node, stop = toshiba_running(sims, nodes, network, c101=4, c100=1, drive=VF_MB1)
    since = len(node.emcy.log)
    stop()
    emcy = wait_emcy(node, since, 0x7520)
    assert emcy.data[0] == 0x1B, f"trip code Err8 (0x1B) in the EMCY: {emcy.data.hex()}"
    wait_state(node, "FAULT")
    assert node.sdo[0x603F].raw == 0x7520
    assert not [c for c in emcy_codes(node, since) if c & 0xFF00 == 0x8100], \
        "no 0x81xx EMCY on this drive (C34)"


def test_vf_mb1_heartbeat_loss_c101_3_coasts_while_lost_and_resumes(sims, nodes, network):
    node, stop = toshiba_running(sims, nodes, network, c101=3, c100=1, drive=VF_MB1)
    since = len(node.emcy.log)
    stop()
    poll(lambda: (speed(node), node.sdo[0x2C91].raw),
         lambda v: v == (0, 0x0800), "0x6044 = 0 with alarm FC91 bit 11")
    sw = node.sdo[0x6041].raw
    assert state_of(sw) == "OPERATION ENABLED" and sw & 0x0080, f"statusword 0x{sw:04X}"
    task = network.send_periodic(0x700 + MASTER, b"\x05", HB_PERIOD)
    try:
        poll(lambda: node.sdo[0x2C91].raw, lambda v: v == 0, "alarm FC91 cleared")
        poll(lambda: speed(node), lambda v: v == SPEED, f"0x6044 back at {SPEED}")
    finally:
        task.stop()
    assert not [c for c in emcy_codes(node, since) if c], "a coast stop here is no trip, no EMCY"


# RPDO1 deadline 0x1400:05 as the EtherCAT watchdog (NOTES B8.1a): armed by the first RPDO1 in
# OPERATIONAL; C101 = 1 keeps going, 2 decelerates on 0x6049, 5 (preset speed, not in the OD) as 2;
# FC91 bit 11 while the error lasts, the CiA 402 state kept, the command followed again after.
RPDO_DEADLINE_MS = 1000  # twenty RPDO1 periods


def rpdo1(cw, target):
    return bytes([cw & 0xFF, cw >> 8]) + (target & 0xFFFF).to_bytes(2, "little")


def vf_mb1_rpdo_watched(sims, nodes, network, c101):
    """VF-MB1 in the CiA 402 profile, RPDO1 (0x6040, 0x6042) from the master every HB_PERIOD with
    deadline RPDO_DEADLINE_MS, C100 = 0.1 s, running at SPEED. Returns (node, task, stop)."""
    drive = VF_MB1
    sims.start([(drive.id, drive.node_id)])
    node = nodes(drive)
    for index, sub, value in drive.run_from_canopen:
        node.sdo[index].raw = value
    mark = network.recorder.mark()
    node.nmt.send_command(0x81)  # the profile selection takes effect at a reset
    network.recorder.wait_frame(0x700 + drive.node_id, b"\x00", since=mark)
    node.sdo[0x4101].raw = c101
    node.sdo[0x4100].raw = 1
    node.sdo[0x6048][2].raw = 1   # 1500 min^-1 per 1 s
    node.sdo[0x6049][2].raw = 10  # 1500 min^-1 per 10 s: 4 s from SPEED
    node.sdo[0x1400][5].raw = RPDO_DEADLINE_MS  # PRE-OPERATIONAL only (NOTES B2.7)
    node.nmt.state = "OPERATIONAL"
    cob = 0x200 + drive.node_id
    task = network.send_periodic(cob, rpdo1(0x0006, 0), HB_PERIOD)
    try:
        for cw in (0x0006, 0x0007, 0x000F):
            task.update(rpdo1(cw, SPEED if cw == 0x000F else 0))
            if cw != 0x000F:
                wait_state(node, "READY TO SWITCH ON" if cw == 0x0006 else "SWITCHED ON")
        wait_state(node, "OPERATION ENABLED")
        poll(lambda: speed(node), lambda v: v == SPEED, f"0x6044 = {SPEED}")
    except BaseException:
        task.stop()
        raise
    assert node.sdo[0x2C91].raw & 0x0800 == 0

    def resume():
        return network.send_periodic(cob, rpdo1(0x000F, SPEED), HB_PERIOD)
    return node, task, resume


def test_vf_mb1_rpdo_deadline_c101_1_keeps_running_and_flags_fc91(sims, nodes, network):
    node, task, resume = vf_mb1_rpdo_watched(sims, nodes, network, c101=1)
    since = len(node.emcy.log)
    task.stop()
    poll(lambda: node.sdo[0x2C91].raw & 0x0800, lambda v: v, "alarm FC91 bit 11")
    sw = node.sdo[0x6041].raw
    assert state_of(sw) == "OPERATION ENABLED" and sw & 0x0080, f"statusword 0x{sw:04X}"
    assert speed(node) == SPEED, "C101 = 1: the last command is kept"
    task = resume()
    try:
        poll(lambda: node.sdo[0x2C91].raw & 0x0800, lambda v: not v, "alarm FC91 cleared")
        assert speed(node) == SPEED
    finally:
        task.stop()
    assert not [c for c in emcy_codes(node, since) if c], "no trip, no EMCY (C34)"


def vf_mb1_rpdo_deadline_decelerates(sims, nodes, network, c101):
    node, task, resume = vf_mb1_rpdo_watched(sims, nodes, network, c101=c101)
    since = len(node.emcy.log)
    task.stop()
    poll(lambda: node.sdo[0x2C91].raw & 0x0800, lambda v: v, "alarm FC91 bit 11")
    # down the 0x6049 ramp in OPERATION ENABLED, to a standstill in the same state
    poll(lambda: (speed(node), state_of(node.sdo[0x6041].raw)),
         lambda v: 0 < v[0] < SPEED and v[1] == "OPERATION ENABLED", "a decelerating drive")
    poll(lambda: speed(node), lambda v: v == 0, "0x6044 = 0", timeout=TIMEOUT + 5)
    assert state_of(node.sdo[0x6041].raw) == "OPERATION ENABLED"
    assert node.sdo[0x603F].raw == 0
    task = resume()
    try:
        poll(lambda: node.sdo[0x2C91].raw & 0x0800, lambda v: not v, "alarm FC91 cleared")
        poll(lambda: speed(node), lambda v: v == SPEED, f"0x6044 back at {SPEED}")
    finally:
        task.stop()
    assert not [c for c in emcy_codes(node, since) if c], "no trip, no EMCY (C34)"


def test_vf_mb1_rpdo_deadline_c101_2_decelerates_and_resumes(sims, nodes, network):
    vf_mb1_rpdo_deadline_decelerates(sims, nodes, network, c101=2)


def test_vf_mb1_rpdo_deadline_c101_5_preset_speed_acts_as_2(sims, nodes, network):
    vf_mb1_rpdo_deadline_decelerates(sims, nodes, network, c101=5)


# --- Benshaw RSi: life guarding, Lost Command Pr.12/Pr.13 -----------------------------------------

BENSHAW = BY_ID["benshaw-rsi"]
PR07 = (0x401A, 0x07)
PR12 = (0x401A, 0x0C)
PR13 = (0x401A, 0x0D)
PR14 = (0x401A, 0x0E)


def benshaw_running(sims, nodes, pr12, pr13=5, pr14=None):
    """Benshaw RSi with dr.06 = 4, dr.07 = 8 (fieldbus), Lost Command Pr.12, Pr.13 (0.1 s) and
    Pr.14 (0.01 Hz), Pr.07 10.0 s, guarded at 100 ms x 10, running at SPEED. Returns (node,
    stop): stop() ends the guarding and returns the time just before."""
    sims.start([(BENSHAW.id, BENSHAW.node_id)])
    node = nodes(BENSHAW)
    for index, sub, value in BENSHAW.run_from_canopen:
        node.sdo[index][sub].raw = value
    node.sdo[PR12[0]][PR12[1]].raw = pr12
    node.sdo[PR13[0]][PR13[1]].raw = pr13
    if pr14 is not None:
        node.sdo[PR14[0]][PR14[1]].raw = pr14
    node.sdo[PR07[0]][PR07[1]].raw = 100  # trip deceleration 10.0 s from 1800: 3.3 s from SPEED
    node.sdo[0x6048][2].raw = 10  # 0.1 s units, from max speed
    node.sdo[0x6049][2].raw = 10
    node.sdo[0x100C].raw = GUARD_TIME_MS
    node.sdo[0x100D].raw = LIFE_FACTOR
    node.nmt.start_node_guarding(HB_PERIOD)
    try:
        enable_and_run(node)
    except BaseException:
        node.nmt.stop_node_guarding()
        raise

    def stop():
        before = time.time()
        node.nmt.stop_node_guarding()
        return before
    return node, stop


def test_benshaw_guarding_loss_pr12_1_free_run_trips_ff0a_after_pr13(sims, nodes, network,
                                                                     recorder):
    node, stop = benshaw_running(sims, nodes, pr12=1, pr13=5)  # 0.5 s
    since = len(node.emcy.log)
    stop()
    emcy = wait_emcy(node, since, 0xFF0A)
    # life time + Pr.13 (500 ms) after the last guard request the node answered: its reply's
    # kernel timestamp, like the EMCY's (the master's guarding thread, late on a busy machine,
    # may have sent its last request well before stop())
    last_reply = recorder.since(0, lambda m: m.arbitration_id == 0x700 + BENSHAW.node_id
                                and not m.is_remote_frame and len(m.data) == 1
                                and m.timestamp < emcy.timestamp)[-1].timestamp
    life = GUARD_TIME_MS * LIFE_FACTOR / 1000
    assert emcy.timestamp - last_reply >= life + 0.5 - 0.01, emcy.timestamp - last_reply
    assert emcy.register & 0x80
    assert emcy_codes(node, since)[0] == 0xFF0A, "a guard error itself sends no EMCY (B2.2)"
    wait_state(node, "FAULT")
    assert node.sdo[0x603F].raw == 0xFF0A
    # Free-Run: the output is blocked and the motor coasts down by itself (no ramp to follow)
    poll(lambda: speed(node), lambda v: v == 0, "the coasting motor at 0x6044 = 0")
    # the guard error left OPERATIONAL (§6.3.1): a guard request now answers PRE-OPERATIONAL
    mark = recorder.mark()
    network.send_message(0x700 + BENSHAW.node_id, b"", remote=True)
    reply = recorder.wait_for(lambda m: m.arbitration_id == 0x700 + BENSHAW.node_id
                              and not m.is_remote_frame and m.dlc == 1, mark)
    assert reply.data[0] & 0x7F == 0x7F


def test_benshaw_guarding_loss_pr12_4_hold_output_warns(sims, nodes, network):
    node, stop = benshaw_running(sims, nodes, pr12=4, pr13=5)
    since = len(node.emcy.log)
    stop()
    poll(lambda: node.sdo[0x6041].raw, lambda sw: sw & 0x0080, "statusword bit 7 (warning)")
    # Hold Output: a new target is not followed while the command is lost
    node.sdo[0x6042].raw = 0
    assert state_of(node.sdo[0x6041].raw) == "OPERATION ENABLED"
    assert speed(node) == SPEED
    assert node.sdo[0x603F].raw == 0
    # Operational again: the warning ends and the drive follows the (new) target
    node.nmt.state = "OPERATIONAL"
    poll(lambda: node.sdo[0x6041].raw, lambda sw: not sw & 0x0080, "warning bit cleared")
    poll(lambda: speed(node), lambda v: v == 0, "0x6044 = 0")
    assert not [c for c in emcy_codes(node, since) if c], "a warning sends no EMCY (C22)"


def test_benshaw_guarding_loss_pr12_2_decelerating_trip(sims, nodes, network):
    node, stop = benshaw_running(sims, nodes, pr12=2, pr13=1)
    since = len(node.emcy.log)
    stop()
    wait_emcy(node, since, 0xFF0A)
    # FAULT REACTION ACTIVE while decelerating on Pr.07, then FAULT at standstill
    poll(lambda: (speed(node), state_of(node.sdo[0x6041].raw)),
         lambda v: 0 < v[0] < SPEED and v[1] == "FAULT REACTION ACTIVE",
         "decelerating in FAULT REACTION ACTIVE")
    wait_state(node, "FAULT", timeout=TIMEOUT + 4)
    assert speed(node) == 0
    assert node.sdo[0x603F].raw == 0xFF0A


def test_benshaw_guarding_loss_pr12_3_hold_input_warns_and_keeps_the_command(sims, nodes,
                                                                            network):
    node, stop = benshaw_running(sims, nodes, pr12=3, pr13=5)
    since = len(node.emcy.log)
    stop()
    poll(lambda: node.sdo[0x6041].raw, lambda sw: sw & 0x0080, "statusword bit 7 (warning)")
    # Hold Input: running on in OPERATION ENABLED on the last received command
    assert state_of(node.sdo[0x6041].raw) == "OPERATION ENABLED"
    assert speed(node) == SPEED
    assert node.sdo[0x603F].raw == 0
    node.nmt.state = "OPERATIONAL"
    poll(lambda: node.sdo[0x6041].raw, lambda sw: not sw & 0x0080, "warning bit cleared")
    assert speed(node) == SPEED
    assert not [c for c in emcy_codes(node, since) if c], "a warning sends no EMCY (C22)"


def test_benshaw_guarding_loss_pr12_5_lost_preset_runs_at_pr14(sims, nodes, network):
    node, stop = benshaw_running(sims, nodes, pr12=5, pr13=5, pr14=1000)  # 10.00 Hz = 300 min^-1
    since = len(node.emcy.log)
    stop()
    poll(lambda: node.sdo[0x6041].raw, lambda sw: sw & 0x0080, "statusword bit 7 (warning)")
    poll(lambda: speed(node), lambda v: v == 300, "0x6044 at the Lost Preset 300",
         timeout=TIMEOUT + 5)
    assert state_of(node.sdo[0x6041].raw) == "OPERATION ENABLED"
    assert node.sdo[0x603F].raw == 0
    # Operational again: the warning ends and the drive goes back to its target
    node.nmt.state = "OPERATIONAL"
    poll(lambda: node.sdo[0x6041].raw, lambda sw: not sw & 0x0080, "warning bit cleared")
    poll(lambda: speed(node), lambda v: v == SPEED, f"0x6044 back at {SPEED}",
         timeout=TIMEOUT + 5)
    assert not [c for c in emcy_codes(node, since) if c], "a warning sends no EMCY (C22)"


# --- Vacon OPT-C6: life guarding, Fieldbus Fault --------------------------------------------------

VACON = BY_ID["vacon-optc6"]


def vacon_running(sims, nodes, response):
    sims.start([(VACON.id, VACON.node_id)],
               extra=["--set", f"fieldbus_fault_response={response}"])
    node = nodes(VACON)
    node.sdo[0x100C].raw = GUARD_TIME_MS
    node.sdo[0x100D].raw = LIFE_FACTOR
    node.nmt.start_node_guarding(HB_PERIOD)
    try:
        enable_and_run(node, target=900)
    except BaseException:
        node.nmt.stop_node_guarding()
        raise
    return node


def test_vacon_guarding_loss_fieldbus_fault_53_coasts(sims, nodes, network):
    node = vacon_running(sims, nodes, response=3)
    since = len(node.emcy.log)
    node.nmt.stop_node_guarding()
    emcy = wait_emcy(node, since, 0x8130)
    assert emcy.data[0] == 53, f"NX fault number in the EMCY: {emcy.data.hex()}"
    assert node.sdo[0x2063].raw == 53
    # coast: FAULT with the output off while the motor still turns down on its own
    poll(lambda: (state_of(node.sdo[0x6041].raw), speed(node)),
         lambda v: v[0] == "FAULT" and v[1] > 0, "FAULT while coasting")
    assert node.sdo[0x1001].raw & 0x10


def test_vacon_guarding_loss_fieldbus_fault_53_ramp_stop(sims, nodes, network):
    node = vacon_running(sims, nodes, response=2)
    since = len(node.emcy.log)
    node.nmt.stop_node_guarding()
    wait_emcy(node, since, 0x8130)
    assert node.sdo[0x2063].raw == 53
    poll(lambda: (speed(node), state_of(node.sdo[0x6041].raw)),
         lambda v: 0 < v[0] < 900 and v[1] == "FAULT REACTION ACTIVE",
         "ramping down in FAULT REACTION ACTIVE")
    wait_state(node, "FAULT")
    assert speed(node) == 0


def test_vacon_guarding_loss_response_1_only_warns(sims, nodes, network):
    node = vacon_running(sims, nodes, response=1)
    since = len(node.emcy.log)
    node.nmt.stop_node_guarding()
    poll(lambda: node.sdo[0x6041].raw, lambda sw: sw & 0x0080, "statusword bit 7 (warning)")
    assert state_of(node.sdo[0x6041].raw) == "OPERATION ENABLED"
    assert speed(node) == 900
    assert node.sdo[0x2063].raw == 0
    # the next guard request re-arms guarding and ends the warning (B2.6)
    node.nmt.start_node_guarding(HB_PERIOD)
    try:
        poll(lambda: node.sdo[0x6041].raw, lambda sw: not sw & 0x0080, "warning bit cleared")
    finally:
        node.nmt.stop_node_guarding()
    assert speed(node) == 900
    assert not emcy_codes(node, since), "no Fieldbus Fault, no EMCY (B2.5)"
