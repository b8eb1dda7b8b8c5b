"""The simulated VF-MB1 with its EtherCAT option (IPE003Z) under pysoem, the SOEM master, over a
veth pair: scan, configuration, ESM, CoE SDO and SDO information, emergencies, cyclic process data
(LRW) with the CiA 402 walk and a velocity ramp, the SM watchdog, and a line of two drives.

Manual = TOSVERT VF-MB1/S15 EtherCAT option unit Function Manual (IPE003Z).
"""
import re
import subprocess
import struct
import time

import pysoem
import pytest

from conftest import TIMEOUT, eds, eds_int

INIT, PREOP, BOOT, SAFEOP, OP = (pysoem.INIT_STATE, pysoem.PREOP_STATE, 0x03,
                                 pysoem.SAFEOP_STATE, pysoem.OP_STATE)
ERROR = 0x10
SPEED = 1500         # min^-1, 0x6042
PERIOD = 0.002       # the master's cycle, s

# EDS DataType -> struct format
FORMATS = {0x0001: "<?", 0x0002: "<b", 0x0003: "<h", 0x0004: "<i", 0x0005: "<B", 0x0006: "<H",
           0x0007: "<I"}


def sdo_format(index, sub):
    cp = eds()
    sec = f"{index:04X}" if sub == 0 and cp.has_section(f"{index:04X}") and \
        not cp.has_section(f"{index:04X}sub0") else f"{index:04X}sub{sub:X}"
    return FORMATS[eds_int(cp[sec]["DataType"])]


def write(line, pos, index, sub, value):
    line.sdo_write(pos, index, sub, struct.pack(sdo_format(index, sub), value))


def read(line, pos, index, sub):
    fmt = sdo_format(index, sub)
    return struct.unpack(fmt, line.sdo_read(pos, index, sub)[:struct.calcsize(fmt)])[0]


def run_from_ethercat(line, pos):
    """Manual §3.1: C003 (CMOd, 0x2003) = 4 and F004 (FMOd, 0x2004) = 7 take run/stop and the
    frequency from the option, and take effect at a reset: F899 = 1 (communication function
    reset) written over CoE is that reset. Ramps: 1500 min^-1 per 1 s up, per 1 s down."""
    write(line, pos, 0x2003, 0, 4)
    write(line, pos, 0x2004, 0, 7)
    write(line, pos, 0x2899, 0, 1)
    write(line, pos, 0x6048, 1, SPEED)
    write(line, pos, 0x6048, 2, 1)
    write(line, pos, 0x6049, 1, SPEED)
    write(line, pos, 0x6049, 2, 1)


def to_op(line, n=1, period=PERIOD):
    """config_map, config_dc, SAFE-OP, the cycle running (period s), OP. Returns the io map
    size."""
    with line.lock:
        size = line.master.config_map()
        dc = line.master.config_dc()
    # ecat/NOTES.md: no distributed clocks, advertised consistently (0x0008 bit 2 clear), so
    # SOEM finds no DC slave and configures none.
    assert not dc, "config_dc() found a DC slave; the ESC advertises none"
    line.wait_state(SAFEOP)
    line.start_cycle(period)
    line.request(OP)
    line.wait_state(OP)
    return size


def outputs(controlword, speed=0):
    return struct.pack("<Hh", controlword, speed)


def sw_sp(data):
    return struct.unpack("<Hh", data[:4])


def cia402(sw):
    """The CiA 402 state of a statusword (CiA 402 Table 30)."""
    for mask, value, name in ((0x4F, 0x00, "NOT READY TO SWITCH ON"),
                              (0x4F, 0x40, "SWITCH ON DISABLED"),
                              (0x6F, 0x21, "READY TO SWITCH ON"),
                              (0x6F, 0x23, "SWITCHED ON"),
                              (0x6F, 0x27, "OPERATION ENABLED"),
                              (0x6F, 0x07, "QUICK STOP ACTIVE"),
                              (0x4F, 0x0F, "FAULT REACTION ACTIVE"),
                              (0x4F, 0x08, "FAULT")):
        if sw & mask == value:
            return name
    return "?"


def enable(line, pos, speed=SPEED):
    """CiA 402 walk through the cyclic outputs: shutdown, switch on, enable operation."""
    for cw, state in ((0x0006, "READY TO SWITCH ON"), (0x0007, "SWITCHED ON"),
                      (0x000F, "OPERATION ENABLED")):
        line.set_output(pos, outputs(cw, speed if cw == 0x000F else 0))
        line.wait_input(pos, lambda d, s=state: cia402(sw_sp(d)[0]) == s, state)


def emergencies(line, pos, code, timeout=TIMEOUT):
    """Reads SM1 until a CoE emergency with code arrives; returns the emergencies seen."""
    seen = []
    slave = line.slaves[pos - 1]
    slave.add_emergency_callback(seen.append)
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        try:
            line.mbx_receive(pos)
        except pysoem.Emergency as e:  # older pysoem raises instead of calling back
            seen.append(e)
        if any(getattr(e, "error_code", None) == code for e in seen):
            return seen
        time.sleep(0.01)
    raise AssertionError(f"no CoE emergency 0x{code:04X} from slave {pos}; got "
                         f"{[hex(getattr(e, 'error_code', -1)) for e in seen]}")


# --- scan ------------------------------------------------------------------------------------------

def test_config_init_finds_the_slave_with_its_sii_identity(line):
    sim, m = line(1)
    s = m.slaves[0]
    cp = eds()
    # SII string 1 (od/vf-mb1-ecat/ecat.ini Device Type); identity from 0x1018 of the EDS
    assert s.name == "VF-MB1 IPE003Z"
    assert s.man == eds_int(cp["1018sub1"]["DefaultValue"]) == 0x284
    assert s.id == eds_int(cp["1018sub2"]["DefaultValue"]) == 0xE1  # manual: product code 0xE1
    assert s.rev == eds_int(cp["1018sub3"]["DefaultValue"])
    m.wait_state(PREOP)  # config_init leaves the line in PRE-OP: mailbox SMs accepted
    sim.wait_line(r"slave 1 vf-mb1-ecat: EtherCAT INIT -> PREOP")


# --- ESM -------------------------------------------------------------------------------------------

def test_config_map_and_op_with_the_expected_working_counter(line):
    sim, m = line(1)
    size = to_op(m)
    assert size == 8, "4 bytes out (0x6040, 0x6042) + 4 in (0x6041, 0x6044)"
    assert m.master.expected_wkc == 3, "one LRW: +2 for the outputs, +1 for the inputs"
    n = len(m.wkcs)
    m.wait_input(1, lambda d: True, "a cycle")
    time.sleep(50 * PERIOD)  # the master's cycles, at its own period
    wkcs = m.wkcs[n:]
    assert len(wkcs) >= 10 and all(w == 3 for w in wkcs), wkcs
    sim.wait_line(r"EtherCAT SAFEOP -> OP")


def test_wrong_transitions_get_their_al_status_codes(line):
    sim, m = line(1)
    m.request(INIT)
    m.wait_state(INIT)
    m.request(OP)  # INIT -> OP skips PRE-OP and SAFE-OP
    s = m.wait_state(INIT | ERROR)[0]
    assert s.al_status == 0x0011, f"invalid requested state change, got 0x{s.al_status:04X}"
    line_seen = sim.wait_line(r"EtherCAT .*AL status code 0x0011")
    m.request(INIT | ERROR)  # acknowledge
    m.wait_state(INIT)
    m.request(BOOT)  # no bootstrap (no FoE): refused from INIT
    s = m.wait_state(INIT | ERROR)[0]
    assert s.al_status == 0x0013, f"bootstrap not supported, got 0x{s.al_status:04X}"
    m.request(INIT | ERROR)
    m.wait_state(INIT)
    m.request(PREOP)
    m.wait_state(PREOP)
    m.request(OP)  # PRE-OP -> OP skips SAFE-OP
    s = m.wait_state(PREOP | ERROR)[0]
    assert s.al_status == 0x0011
    assert line_seen


# --- CoE SDO ---------------------------------------------------------------------------------------

def test_sdo_read_write_of_drive_parameters_and_aborts(line):
    sim, m = line(1)
    assert m.sdo_read(1, 0x1008, 0) == b"VF-MB1"  # a string longer than 4 bytes: normal upload
    assert read(m, 1, 0x1000, 0) == eds_int(eds()["1000"]["DefaultValue"])
    write(m, 1, 0x6048, 2, 7)
    assert read(m, 1, 0x6048, 2) == 7
    write(m, 1, 0x2003, 0, 4)
    assert read(m, 1, 0x2003, 0) == 4
    with pytest.raises(pysoem.SdoError) as e:
        m.sdo_read(1, 0x5FFF, 0)
    assert e.value.abort_code == 0x06020000  # object does not exist, as over CAN
    with pytest.raises(pysoem.SdoError) as e:
        m.sdo_write(1, 0x1008, 0, b"XYZ")
    assert e.value.abort_code == 0x06010002  # read-only
    assert m.sdo_read(1, 0x1008, 0) == b"VF-MB1", "the refused write changed nothing"


def test_complete_access_read_and_write(line):
    sim, m = line(1)
    # 0x1C12 (SM2 assignment): sub 0 as 16 bits, then 0x1600
    assert m.sdo_read(1, 0x1C12, 0, ca=True) == struct.pack("<BBH", 1, 0, 0x1600)
    ca = m.sdo_read(1, 0x1600, 0, ca=True)
    n = ca[0]
    entries = struct.unpack(f"<{n}I", ca[2:2 + 4 * n])
    assert n == 2 and entries == (0x60400010, 0x60420010), ca.hex()
    # 0x6048 vl velocity acceleration: sub 1 UNSIGNED32 delta speed, sub 2 UNSIGNED16 delta time
    m.sdo_write(1, 0x6048, 1, struct.pack("<IH", 1200, 3), ca=True)
    assert read(m, 1, 0x6048, 1) == 1200 and read(m, 1, 0x6048, 2) == 3
    assert m.sdo_read(1, 0x6048, 0, ca=True) == struct.pack("<BBIH", 2, 0, 1200, 3)


def test_sdo_information_od_list_matches_the_eds(line):
    sim, m = line(1)
    cp = eds()
    want = {int(s, 16) for s in cp.sections() if re.fullmatch(r"[0-9A-Fa-f]{4}", s)}
    # plus the EtherCAT communication objects the slave layer serves from its layout (ecat.ini:
    # the manual documents no 0x1C00/0x1C12/0x1C13, so the EDS has none): SM types, PDO assign
    want |= {0x1C00, 0x1C12, 0x1C13}
    with m.lock:
        od = m.slaves[0].od  # SDO information: OD list, then each object's description
    got = {o.index for o in od}
    assert got == want, f"missing {sorted(hex(i) for i in want - got)}, " \
                        f"extra {sorted(hex(i) for i in got - want)}"
    # each object's description (SDO information, Get object description) against the EDS: its
    # object code, its name (ParameterName, from the generated dictionary's name tables) and, for
    # a VAR, its data type
    for o in od:
        if o.index not in {0x1C00, 0x1C12, 0x1C13}:
            sec = cp[f"{o.index:04X}"]
            assert o.object_code == eds_int(sec["ObjectType"]), hex(o.index)
            assert same_name(o.name, sec["ParameterName"]), (hex(o.index), o.name)
            if o.object_code == 7:
                assert o.data_type == eds_int(sec["DataType"]), hex(o.index)


def same_name(got, want):
    """A name from SDO information equals the EDS one; SOEM keeps at most EC_MAXNAME (40) bytes."""
    got = got.decode("latin-1") if isinstance(got, bytes) else got
    return got == want[:40] if len(want) > 40 else got == want


def test_sdo_information_entry_names_match_the_eds(line):
    """Get entry description of each sub-entry of the records and arrays: the EDS names of the
    sub-entries (what a master shows when it opens an object), data type and bit length."""
    sim, m = line(1)
    cp = eds()
    with m.lock:
        od = m.slaves[0].od
        checked = 0
        for o in od:
            if o.index in {0x1C00, 0x1C12, 0x1C13} or o.object_code == 7:
                continue
            for sub, e in enumerate(o.entries):
                sec = f"{o.index:04X}sub{sub:X}"
                if not cp.has_section(sec):
                    continue  # a sub-index the object does not have
                assert same_name(e.name, cp[sec]["ParameterName"]), (sec, e.name)
                assert e.data_type == eds_int(cp[sec]["DataType"]), sec
                checked += 1
    assert checked > 20, checked


# --- emergencies and faults ------------------------------------------------------------------------

def test_fault_gives_a_coe_emergency_and_603f(line):
    sim, m = line(1)
    to_op(m)
    mark = sim.mark()
    sim.command("fault 1 0x01")  # OC1 (faults.csv: EMCY 0x2310)
    sim.wait_line(r"slave 1 vf-mb1-ecat: fault: trip 0x01", since=mark)
    seen = emergencies(m, 1, 0x2310)
    assert any(getattr(e, "error_code", 0) == 0x2310 for e in seen)
    assert read(m, 1, 0x603F, 0) == 0x2310
    m.wait_input(1, lambda d: cia402(sw_sp(d)[0]) == "FAULT", "FAULT in the statusword")


# --- cyclic process data: CiA 402 and the ramp -----------------------------------------------------

@pytest.mark.parametrize("period", [0.001, 0.002, 0.004], ids=["1ms", "2ms", "4ms"])
def test_cia402_walk_and_velocity_ramp_over_lrw(line, period):
    sim, m = line(1)
    run_from_ethercat(m, 1)
    to_op(m, period=period)
    m.wait_input(1, lambda d: cia402(sw_sp(d)[0]) == "SWITCH ON DISABLED", "SWITCH ON DISABLED")
    start = len(m.samples)
    enable(m, 1)
    m.wait_input(1, lambda d: sw_sp(d)[1] == SPEED, f"0x6044 = {SPEED}", timeout=TIMEOUT + 2)
    up = [sw_sp(i[0])[1] for _, i in m.samples[start:]]
    assert all(b >= a for a, b in zip(up, up[1:])), "0x6044 only rises on the way up"
    between = {v for v in up if 0 < v < SPEED}
    assert len(between) >= 10, f"a ramp, not a step: {sorted(between)[:20]}"
    t = [t for t, i in m.samples[start:] if 0 < sw_sp(i[0])[1]]
    t_full = [t for t, i in m.samples[start:] if sw_sp(i[0])[1] == SPEED]
    assert 0.5 <= t_full[0] - t[0] <= 2.0, "about 1 s from 0 to 1500 min^-1 (0x6048)"
    m.set_output(1, outputs(0x0007))  # disable operation: decelerate on 0x6049
    m.wait_input(1, lambda d: sw_sp(d)[1] == 0, "0x6044 = 0", timeout=TIMEOUT + 2)
    assert all(w == 3 for w in m.wkcs[-50:]), f"working counters {m.wkcs[-50:]}"


def test_stopping_the_cycle_trips_the_sm_watchdog_reaction(line):
    sim, m = line(1)
    run_from_ethercat(m, 1)
    to_op(m)
    enable(m, 1)
    m.wait_input(1, lambda d: sw_sp(d)[1] > 0, "the motor turning")
    mark = sim.mark()
    m.stop_cycle()  # outputs stop arriving: the SM2 watchdog (100 ms) runs out
    s = m.wait_state(SAFEOP | ERROR)[0]
    assert s.al_status == 0x001B, f"sync manager watchdog, got 0x{s.al_status:04X}"
    sim.wait_line(r"EtherCAT OP -> SAFEOP, error: AL status code 0x001B", since=mark)
    # the drive reacts as to a loss of communication (manual §7: C101, default 4: Err8, 0x7520)
    seen = emergencies(m, 1, 0x7520)
    assert seen
    assert read(m, 1, 0x603F, 0) == 0x7520


# --- a line of two drives --------------------------------------------------------------------------

def test_two_drives_in_a_chain(line):
    sim, m = line(2)
    assert [s.name for s in m.slaves] == ["VF-MB1 IPE003Z"] * 2
    assert [s.id for s in m.slaves] == [0xE1, 0xE1]
    for pos in (1, 2):
        run_from_ethercat(m, pos)
    size = to_op(m)
    assert size == 16
    assert m.master.expected_wkc == 6
    enable(m, 2, speed=SPEED)
    m.wait_input(2, lambda d: sw_sp(d)[1] > 0, "slave 2 turning")
    assert cia402(sw_sp(m.samples[-1][1][0])[0]) == "SWITCH ON DISABLED", "slave 1 untouched"
    assert all(w == 6 for w in m.wkcs[-20:])
    mark = sim.mark()
    sim.command("fault 1 0x01")  # by position: the first drive only
    sim.wait_line(r"slave 1 vf-mb1-ecat: fault: trip 0x01", since=mark)
    emergencies(m, 1, 0x2310)
    assert read(m, 1, 0x603F, 0) == 0x2310
    assert read(m, 2, 0x603F, 0) == 0, "slave 2 has no fault"
    sim.command("status 2")
    st = sim.wait_line(r"slave 2 vf-mb1-ecat: EtherCAT OP", since=mark)
    assert "RUN LED on" in st, st


# --- the command line ------------------------------------------------------------------------------

@pytest.mark.parametrize("args, message", [
    (["--ecat-iface", "veth0", "--drive", "vf-s15"], "drive 'vf-s15' has no EtherCAT face"),
    (["--ecat-iface", "veth0", "--drive", "vf-mb1-ecat", "--node-id", "3"],
     "addressed by their position"),
    (["--ecat-iface", "veth0", "--iface", "vcan0", "--drive", "vf-mb1-ecat"],
     "--iface and --ecat-iface together"),
    (["--ecat-iface", "veth0"], "no drive given"),
    (["--ecat-iface", "veth0", "--ecat-iface", "veth1", "--drive", "vf-mb1-ecat"],
     "--ecat-iface given twice"),
    (["--ecat-iface", "x" * 20, "--drive", "vf-mb1-ecat"], "is not an interface name"),
    (["--ecat-iface", "veth0", "--drive", "vf-mb1-ecat", "--trace", "t.log"],
     "--trace writes CAN frames"),
    (["--ecat-iface", "veth0", "--drive", "vf-mb1-ecat", "--scenario", "/nonexistent/s.txt"],
     "--scenario /nonexistent/s.txt: No such file"),
])
def test_bad_command_lines_get_a_clear_message(args, message):
    from conftest import BIN
    r = subprocess.run([str(BIN), *args], capture_output=True, text=True, timeout=TIMEOUT)
    assert r.returncode == 2 and message in r.stderr, (r.returncode, r.stderr)


def test_a_missing_interface_is_a_run_time_failure():
    from conftest import BIN
    r = subprocess.run([str(BIN), "--ecat-iface", "nosuch0", "--drive", "vf-mb1-ecat"],
                       capture_output=True, text=True, timeout=TIMEOUT)
    assert r.returncode == 1 and "no interface nosuch0" in r.stderr, (r.returncode, r.stderr)


def test_stdin_commands_by_position(line):
    sim, m = line(2)
    mark = sim.mark()
    sim.command("nmt 1 start")   # the ESM drives the state on EtherCAT
    sim.command("status 3")      # there is no slave 3
    sim.command("status 1")
    sim.wait_line(r"slave 1 is on EtherCAT: its state follows the master's AL control", since=mark)
    sim.wait_line(r"no slave 3 here \(slaves: 1 2\)", since=mark)
    st = sim.wait_line(r"slave 1 vf-mb1-ecat: EtherCAT PREOP, AL status code 0x0000", since=mark)
    assert "RUN LED blinking" in st, st  # manual §2: RUN blinking in PRE-OPERATIONAL


def test_the_demo_master_ramps_the_drive():
    """tools/demo --ecat's master (tools/demo_ecat.py) against the simulator: it must reach the
    speed and come back, with every LRW frame in OP answered with the right working counter."""
    from conftest import ROOT, Sim
    import sys
    sim = Sim(["vf-mb1-ecat"])
    try:
        r = subprocess.run([sys.executable, str(ROOT / "tools" / "demo_ecat.py"), "--iface",
                            "veth1", "--ramp", "1", "--step", "0.25"], capture_output=True,
                           text=True, timeout=60)
    finally:
        assert sim.stop() == 0
    assert r.returncode == 0, r.stdout + r.stderr
    assert "demo: at speed after" in r.stdout and "SWITCH ON DISABLED" in r.stdout, r.stdout
    m = re.search(r"in OP: (\d+) LRW frames, (\d+) with a wrong working counter", r.stdout)
    assert m and int(m.group(1)) > 500 and m.group(2) == "0", r.stdout
    assert "1500 |" in r.stdout  # the plot's top line


# --- the test engineer's instruments on an EtherCAT line ------------------------------------------

def test_control_socket_by_position(line, tmp_path):
    """--control works on a line as on CAN: slaves by position, the same commands and events."""
    import canopen_sim
    path = str(tmp_path / "ctl.sock")
    sim, m = line(2, extra=["--control", path])
    to_op(m, 2)
    with canopen_sim.Control(path, timeout=TIMEOUT) as ctl:
        from conftest import SLAVE_IF
        assert ctl.nodes() == [(1, "vf-mb1-ecat", SLAVE_IF), (2, "vf-mb1-ecat", SLAVE_IF)]
        mark = ctl.mark()
        ctl.fault(2, 0x01)  # OC1 (faults.csv: EMCY 0x2310)
        ctl.wait_event(r"fault: trip 0x01", node=2, since=mark, timeout=TIMEOUT)
        emergencies(m, 2, 0x2310)
        assert read(m, 2, 0x603F, 0) == 0x2310
        assert read(m, 1, 0x603F, 0) == 0, "slave 1 has no fault"
        assert ctl.state(2)["fault"]["emcy"] == 0x2310, ctl.state(2)
        with pytest.raises(canopen_sim.ControlError, match="slave 1 is on EtherCAT"):
            ctl.command("mute 1")
        with pytest.raises(canopen_sim.ControlError, match=r"no slave 3 here \(slaves: 1 2\)"):
            ctl.fault(3, 0x01)


def test_scenario_on_a_line(line, tmp_path):
    """--scenario's conditions see a slave's state: 0.3 s after slave 1 reaches OP (its NMT state
    follows the EtherCAT state, manual §7) the scenario trips it, and the master gets the CoE
    emergency."""
    scenario = tmp_path / "trip.txt"
    scenario.write_text("when 1 nmt OPERATIONAL after 0.3: fault 1 0x01\n")
    sim, m = line(1, extra=["--scenario", str(scenario)])
    mark = sim.mark()
    to_op(m)
    sim.wait_line(r"scenario .*trip.txt:1 at .*: fault 1 0x01", since=mark)
    sim.wait_line(r"slave 1 vf-mb1-ecat: fault: trip 0x01", since=mark)
    emergencies(m, 1, 0x2310)
    assert read(m, 1, 0x603F, 0) == 0x2310


def test_python_simulator_on_a_line():
    """canopen_sim.Simulator starts an EtherCAT line too (ecat_iface=) and talks to it."""
    import canopen_sim
    from conftest import BIN, SLAVE_IF
    with canopen_sim.Simulator(["vf-mb1-ecat"], ecat_iface=SLAVE_IF, binary=str(BIN),
                               timeout=TIMEOUT) as sim:
        assert sim.node_ids == [1]
        assert sim.nodes() == [(1, "vf-mb1-ecat", SLAVE_IF)]
        mark = sim.mark()
        sim.fault(1, 0x01)
        sim.wait_event(r"CiA 402 .* -> FAULT$", node=1, since=mark)
        assert sim.state(1)["fault"]["trip"] == 0x01
