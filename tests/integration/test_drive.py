"""Every simulated drive against python-canopen as the master, over SocketCAN.

Each test runs once per drive (CANOPEN_TEST_DRIVES narrows the set). The expectations come from
the drive's EDS (through python-canopen, as a master would load it) and, where an EDS cannot say,
from drives.py, which cites the drive's NOTES.md.
"""
import struct

import canopen
import pytest
from canopen.objectdictionary import datatypes

from conftest import (TIMEOUT, is_readable, is_writable, od_variables, param_channel_write,
                      sdo_abort, wait_emcy)

SAVE = 0x65766173  # "save"
LOAD = 0x64616F6C  # "load"

INT_RANGES = {
    datatypes.BOOLEAN: (0, 1),
    datatypes.INTEGER8: (-0x80, 0x7F), datatypes.INTEGER16: (-0x8000, 0x7FFF),
    datatypes.INTEGER32: (-0x80000000, 0x7FFFFFFF),
    datatypes.UNSIGNED8: (0, 0xFF), datatypes.UNSIGNED16: (0, 0xFFFF),
    datatypes.UNSIGNED32: (0, 0xFFFFFFFF),
    datatypes.INTEGER64: (-(1 << 63), (1 << 63) - 1), datatypes.UNSIGNED64: (0, (1 << 64) - 1),
}


def sdo_vars(drive, node):
    """The EDS variables the SDO server exposes (DOMAINs and hidden images left out)."""
    return [v for v in od_variables(node.object_dictionary)
            if v.data_type != datatypes.DOMAIN and not drive.hidden(v.index)]


def read_raw(node, var):
    return var.decode_raw(node.sdo.upload(var.index, var.subindex))


def write_raw(node, var, value):
    node.sdo.download(var.index, var.subindex, var.encode_raw(value))


def is_comm(var):
    return 0x1000 <= var.index <= 0x1FFF


def is_pdo_object(var):
    return 0x1400 <= var.index <= 0x1BFF


def same(var, a, b):
    if var.data_type in (datatypes.REAL32, datatypes.REAL64):
        return abs(a - b) <= 1e-6 * max(1.0, abs(b))
    return a == b


# --- boot-up ---------------------------------------------------------------------------------------

def test_boot_up(sims, recorder, drive):
    sim = sims.start([(drive.id, drive.node_id)], wait_bootup=False)
    boot = recorder.wait_frame(0x700 + drive.node_id, since=sim.bootup_mark)
    assert bytes(boot.data) == b"\x00" and boot.dlc == 1
    sim.wait_out(rf"node {drive.node_id} {drive.id}: NMT INITIALISING -> PRE-OPERATIONAL")
    sim.wait_out(r"ready")


# --- the dictionary ----------------------------------------------------------------------------------

def test_every_readable_object_reads_its_eds_default(running, drive):
    sim, node = running
    wrong, failed = [], []
    checked = 0
    for var in sdo_vars(drive, node):
        if not is_readable(var) or var.default is None:
            continue
        if (var.index, var.subindex) in drive.live:
            continue
        try:
            value = read_raw(node, var)
        except canopen.SdoAbortedError as e:
            failed.append(f"0x{var.index:04X}:{var.subindex:02X} aborted 0x{e.code:08X}")
            continue
        checked += 1
        if not same(var, value, var.default):
            wrong.append(f"0x{var.index:04X}:{var.subindex:02X} {var.name!r} = {value!r}, "
                         f"EDS default {var.default!r}")
    assert not failed and not wrong, "\n".join(failed + wrong)
    assert checked > 10


def test_hidden_and_absent_objects_abort(running, drive):
    sim, node = running
    od = node.object_dictionary
    for lo, hi in drive.sdo_hidden:
        for index in sorted(i for i in od.indices if lo <= i <= hi)[:5]:
            code = sdo_abort(node, index, 0, lambda: node.sdo.upload(index, 0))
            assert code == 0x06020000, f"0x{index:04X} is hidden: abort 0x06020000, got {code:#x}"
    absent = [i for i in (0x1FFF, 0x2FFF, 0x5FFE, 0x6FFF, 0x9FFF) if i not in od.indices]
    for index in absent:
        code = sdo_abort(node, index, 0, lambda: node.sdo.upload(index, 0))
        assert code == 0x06020000, f"read of absent 0x{index:04X}: got {code:#010x}"
        code = sdo_abort(node, index, 0, lambda: node.sdo.download(index, 0, b"\x01\x00"))
        assert code == 0x06020000, f"write of absent 0x{index:04X}: got {code:#010x}"
    # A sub-index the object does not have.
    ident = od[0x1018]
    missing = max(ident.subindices) + 1
    code = sdo_abort(node, 0x1018, missing, lambda: node.sdo.upload(0x1018, missing))
    assert code == 0x06090011


def test_writable_objects_take_their_default_back(running, drive):
    """Every rw object accepts its own EDS default and reads it back."""
    sim, node = running
    problems = []
    for var in sdo_vars(drive, node):
        if not is_writable(var) or var.default is None or is_pdo_object(var):
            continue
        if (var.index, var.subindex) in drive.commands or var.index in (0x1010, 0x1011, 0x1003):
            continue
        code = sdo_abort(node, var.index, var.subindex, lambda: write_raw(node, var, var.default))
        if code:
            problems.append(f"write 0x{var.index:04X}:{var.subindex:02X} = {var.default!r}: "
                            f"abort 0x{code:08X}")
            continue
        if is_readable(var) and (var.index, var.subindex) not in drive.live:
            value = read_raw(node, var)
            if not same(var, value, var.default):
                problems.append(f"0x{var.index:04X}:{var.subindex:02X} reads {value!r} after "
                                f"writing {var.default!r}")
    assert not problems, "\n".join(problems)


def limited_vars(drive, node, comm=False):
    """Writable objects with limits (application objects only, unless comm). 0x6046 is left to
    its own test: its two sub-entries limit each other (min above max aborts 0x06090036)."""
    return [v for v in sdo_vars(drive, node)
            if is_writable(v) and is_readable(v) and (comm or not is_comm(v)) and v.index != 0x6046
            and v.data_type in INT_RANGES and (v.min is not None or v.max is not None)
            and (v.index, v.subindex) not in drive.commands]


def test_writes_at_the_limits_read_back(running, drive):
    """Application objects with limits: the lowest and the highest value are taken and read back
    (the default is written back afterwards)."""
    sim, node = running
    problems = []
    for var in limited_vars(drive, node):
        for value in (var.max, var.min):
            if value is None:
                continue
            code = sdo_abort(node, var.index, var.subindex, lambda: write_raw(node, var, value))
            if code:
                problems.append(f"0x{var.index:04X}:{var.subindex:02X} {var.name!r} = {value}: "
                                f"abort 0x{code:08X}")
                continue
            got = read_raw(node, var)
            if got != value:
                problems.append(f"0x{var.index:04X}:{var.subindex:02X} reads {got} after "
                                f"writing {value}")
        if var.default is not None:
            sdo_abort(node, var.index, var.subindex, lambda: write_raw(node, var, var.default))
    assert not problems, "\n".join(problems)


def test_out_of_range_writes_abort_and_change_nothing(running, drive):
    sim, node = running
    problems = []
    checked = 0
    for var in limited_vars(drive, node, comm=True):
        lo, hi = INT_RANGES[var.data_type]
        before = read_raw(node, var)
        cases = []
        if var.max is not None and var.max < hi:
            cases.append((var.max + 1, 0x06090031))
        if var.min is not None and var.min > lo:
            cases.append((var.min - 1, 0x06090032))
        for value, want in cases:
            checked += 1
            code = sdo_abort(node, var.index, var.subindex, lambda: write_raw(node, var, value))
            if code != want:
                problems.append(f"0x{var.index:04X}:{var.subindex:02X} {var.name!r} = {value}: "
                                f"abort 0x{code:08X}, expected 0x{want:08X}")
            after = read_raw(node, var)
            if after != before:
                problems.append(f"0x{var.index:04X}:{var.subindex:02X} changed from {before} to "
                                f"{after} by a refused write")
    assert not problems, "\n".join(problems)
    if not checked:
        pytest.skip(f"{drive.id} has no writable object with a narrower range than its type")


def test_velocity_min_above_max_is_refused(running, drive):
    sim, node = running
    od = node.object_dictionary
    if 0x6046 not in od or 1 not in od[0x6046].subindices or 2 not in od[0x6046].subindices:
        pytest.skip(f"{drive.id} has no 0x6046 min/max amount")
    mn, mx = node.sdo[0x6046][1].raw, node.sdo[0x6046][2].raw
    var = od[0x6046][1]
    if mx < INT_RANGES[var.data_type][1] and in_limits(var, mx + 1):
        code = sdo_abort(node, 0x6046, 1,
                         lambda: node.sdo.download(0x6046, 1, var.encode_raw(mx + 1)))
        assert code == 0x06090036, f"6046:01 above 6046:02: abort {code:#010x}"
    assert (node.sdo[0x6046][1].raw, node.sdo[0x6046][2].raw) == (mn, mx)


def test_read_only_writes_abort(running, drive):
    sim, node = running
    problems = []
    for var in sdo_vars(drive, node):
        if is_writable(var) or not is_readable(var):
            continue
        data = node.sdo.upload(var.index, var.subindex)
        if var.data_type not in (datatypes.VISIBLE_STRING, datatypes.OCTET_STRING,
                                 datatypes.UNICODE_STRING):
            data = var.encode_raw(var.decode_raw(data))  # exactly the type's size
        code = sdo_abort(node, var.index, var.subindex,
                         lambda: node.sdo.download(var.index, var.subindex, data))
        if code != 0x06010002:
            problems.append(f"write to read-only 0x{var.index:04X}:{var.subindex:02X} "
                            f"{var.name!r}: abort 0x{code:08X}")
    assert not problems, "\n".join(problems)


# --- PDOs ----------------------------------------------------------------------------------------------

def tpdo_candidates(drive, od):
    """Readable, TPDO-mappable application objects, small enough for one frame."""
    out = []
    for var in od_variables(od):
        if (var.pdo_mappable and var.index >= 0x2000 and is_readable(var)
                and var.access_type != "rww" and var.data_type in INT_RANGES
                and not drive.hidden(var.index) and len(var) <= 32):
            out.append(var)
    return out


def in_limits(var, value):
    return (var.min is None or value >= var.min) and (var.max is None or value <= var.max)


def test_tpdo_remap_through_python_canopen(running, drive, recorder):
    sim, node = running
    od = node.object_dictionary
    number = drive.tpdo_for_remap
    comm, mapping = od[0x1800 + number - 1], od[0x1A00 + number - 1]
    node.tpdo.read()
    tpdo = node.tpdo[number]
    if drive.static_pdos:
        # Fixed mapping: python-canopen reads it, a mapping write is refused, and the PDO is
        # received and decoded as read. Only the transmission parameters may change.
        code = sdo_abort(node, mapping.index, 0,
                         lambda: node.sdo.download(mapping.index, 0, b"\x00"))
        assert code == 0x06010002, f"mapping of a fixed PDO written: abort {code:#010x}"
        chosen = [pdo_var.od for pdo_var in tpdo]
        assert chosen, f"TPDO{number} has no mapping"
        if 5 in comm.subindices and is_writable(comm[5]):
            node.sdo[comm.index][5].raw = 100
    else:
        candidates = tpdo_candidates(drive, od)
        assert candidates, "no TPDO-mappable object in the EDS"
        chosen, bits = [], 0
        for var in reversed(candidates):  # profile objects (0x6xxx) first
            if bits + len(var) <= 64 and len(chosen) < 2:
                chosen.append(var)
                bits += len(var)
        tpdo.clear()
        for var in chosen:
            tpdo.add_variable(var.index, var.subindex)
        tpdo.trans_type = 254 if in_limits(comm[2], 254) else comm[2].default
        if 5 in comm.subindices and is_writable(comm[5]) and in_limits(comm[5], 100):
            tpdo.event_timer = 100
        tpdo.enabled = True
        tpdo.save()
        # The mapping reads back as written.
        assert node.sdo.upload(mapping.index, 0)[0] == len(chosen)
        for i, var in enumerate(chosen, 1):
            entry = struct.unpack("<I", node.sdo.upload(mapping.index, i)[:4])[0]
            assert entry == (var.index << 16) | (var.subindex << 8) | len(var)
    bits = sum(len(var) for var in chosen)
    mark = recorder.mark()
    node.nmt.state = "OPERATIONAL"
    frame = recorder.wait_frame(tpdo.cob_id, since=mark, timeout=TIMEOUT)
    assert frame.dlc >= bits // 8
    expected = b"".join(var.encode_raw(read_raw(node, var)) for var in chosen)
    if bytes(frame.data[:bits // 8]) != expected:  # a value moved meanwhile: the next must match
        frame = recorder.wait_frame(tpdo.cob_id, since=recorder.mark(), timeout=TIMEOUT)
    assert bytes(frame.data[:bits // 8]) == expected
    # python-canopen decodes it with the mapping it holds.
    assert [pdo_var.raw for pdo_var in tpdo] == [var.decode_raw(var.encode_raw(read_raw(node, var)))
                                                 for var in chosen]


def rpdo_candidate(drive, od):
    if drive.rpdo_object is not None:
        index, sub = drive.rpdo_object
        return od[index][sub] if sub or hasattr(od[index], "subindices") else od[index]
    for var in od_variables(od):
        if (var.pdo_mappable and var.index >= 0x2000 and "w" in var.access_type
                and var.access_type != "rwr" and var.data_type in INT_RANGES
                and (var.index, var.subindex) not in drive.commands
                and not drive.hidden(var.index) and len(var) <= 32):
            return var
    return None


def test_rpdo_remap_through_python_canopen(running, drive, recorder):
    sim, node = running
    od = node.object_dictionary
    number = drive.rpdo_for_remap
    node.rpdo.read()
    rpdo = node.rpdo[number]
    if drive.static_pdos:
        mapping = od[0x1600 + number - 1]
        code = sdo_abort(node, mapping.index, 0,
                         lambda: node.sdo.download(mapping.index, 0, b"\x00"))
        assert code == 0x06010002, f"mapping of a fixed PDO written: abort {code:#010x}"
        targets = [(i, v.od) for i, v in enumerate(rpdo)
                   if (v.od.index, v.od.subindex) not in drive.commands]
        assert targets, f"RPDO{number} maps nothing but commands"
        slot, var = targets[0]
    else:
        var = rpdo_candidate(drive, od)
        assert var is not None, "no RPDO-mappable application object in the EDS"
        rpdo.clear()
        rpdo.add_variable(var.index, var.subindex)
        rpdo.enabled = True
        rpdo.save()
        slot = 0
    lo, hi = INT_RANGES[var.data_type]
    lo = var.min if var.min is not None else lo
    hi = var.max if var.max is not None else hi
    value = (var.default or 0) + 1 if lo <= (var.default or 0) + 1 <= hi else lo
    node.nmt.state = "OPERATIONAL"
    for v in rpdo:
        v.raw = 0  # a controlword of 0 is "disable voltage": harmless in Switch on disabled
    rpdo[slot].raw = value
    rpdo.transmit()
    got = read_raw(node, var)  # the SDO request follows the RPDO on the bus: no race
    assert got == value, (f"RPDO 0x{rpdo.cob_id:03X} carrying 0x{var.index:04X}:"
                          f"{var.subindex:02X} = {value}, SDO reads {got}")


# --- NMT and error control ----------------------------------------------------------------------------

def heartbeat_states(recorder, node_id, since):
    return [m.data[0] for m in recorder.since(since, lambda m: m.arbitration_id == 0x700 + node_id
                                              and not m.is_remote_frame and m.dlc == 1)]


def wait_heartbeat(recorder, node_id, state, since, timeout=TIMEOUT):
    return recorder.wait_for(lambda m: m.arbitration_id == 0x700 + node_id and m.dlc == 1
                             and not m.is_remote_frame and m.data[0] == state, since, timeout,
                             f"heartbeat 0x{state:02X} from node {node_id}")


def guard(node, recorder):
    """One node guarding request; returns the reply byte."""
    mark = recorder.mark()
    node.network.send_message(0x700 + node.id, b"", remote=True)
    return recorder.wait_for(
        lambda m: m.arbitration_id == 0x700 + node.id and not m.is_remote_frame and m.dlc == 1,
        mark, what=f"guarding reply of node {node.id}").data[0]


def expect_state(node, recorder, state, since):
    """The node reports NMT state `state`: by heartbeat where it has one (0x1017 set to 100 ms
    by the test), else by node guarding."""
    if 0x1017 in node.object_dictionary:
        wait_heartbeat(recorder, node.id, state, since)
    else:
        assert guard(node, recorder) & 0x7F == state


def test_nmt_states_and_heartbeat(running, drive, recorder):
    sim, node = running
    nid = drive.node_id
    od = node.object_dictionary
    if 0x1017 in od:
        hb_default = od[0x1017].default
        mark = recorder.mark()
        node.sdo[0x1017].raw = 100
        first = wait_heartbeat(recorder, nid, 0x7F, mark)
        second = wait_heartbeat(recorder, nid, 0x7F, recorder.mark())
        assert 0.03 < second.timestamp - first.timestamp < 1.0
    else:
        assert guard(node, recorder) & 0x7F == 0x7F

    mark = recorder.mark()
    node.nmt.send_command(0x01)  # start
    expect_state(node, recorder, 0x05, mark)
    sim.wait_out(rf"node {nid} {drive.id}: NMT PRE-OPERATIONAL -> OPERATIONAL")
    assert node.sdo[0x1000].raw == od[0x1000].default  # SDO works in OPERATIONAL

    mark = recorder.mark()
    node.nmt.send_command(0x02)  # stop
    expect_state(node, recorder, 0x04, mark)
    node.sdo.RESPONSE_TIMEOUT = 0.5
    with pytest.raises(canopen.SdoCommunicationError):
        node.sdo.upload(0x1000, 0)  # no SDO in STOPPED, not even an abort
    node.sdo.RESPONSE_TIMEOUT = 2.0
    assert not recorder.since(mark, lambda m: m.arbitration_id == 0x580 + nid)

    mark = recorder.mark()
    node.nmt.send_command(0x80)  # pre-operational
    expect_state(node, recorder, 0x7F, mark)

    mark = recorder.mark()
    node.nmt.send_command(0x82)  # reset communication: boot-up, 0x1017 back to its default
    recorder.wait_frame(0x700 + nid, b"\x00", since=mark)
    if 0x1017 in od:
        assert node.sdo[0x1017].raw == hb_default

    mark, out = recorder.mark(), sim.out_mark()
    node.nmt.send_command(0x81)  # reset node
    recorder.wait_frame(0x700 + nid, b"\x00", since=mark)
    sim.wait_out(rf"node {nid} {drive.id}: NMT INITIALISING -> PRE-OPERATIONAL", since=out)
    assert node.sdo[0x1000].raw == od[0x1000].default


def test_node_guarding_answers_with_state_and_toggle(running, drive, recorder):
    sim, node = running
    if 0x100C not in node.object_dictionary:
        pytest.skip(f"{drive.id} has no node guarding (no 0x100C)")
    if 0x1017 in node.object_dictionary and node.object_dictionary[0x1017].default:
        node.sdo[0x1017].raw = 0  # guarding and heartbeat are exclusive
    replies = [guard(node, recorder) for _ in range(3)]
    assert all(r & 0x7F == 0x7F for r in replies), [hex(r) for r in replies]
    toggles = [r >> 7 for r in replies]
    assert toggles[0] != toggles[1] and toggles[1] != toggles[2], [hex(r) for r in replies]


# --- CiA 402 ---------------------------------------------------------------------------------------------

def setup_run_from_canopen(drive, node):
    for index, sub, value in drive.run_from_canopen:
        var = node.object_dictionary[index]
        var = var if sub == 0 and not hasattr(var, "subindices") else var[sub]
        write_raw(node, var, value)


def test_cia402_walk_with_base_node_402(running, drive, recorder):
    if not drive.cia402:
        pytest.skip(f"{drive.id} has no CiA 402 state machine (see test_sourcetronic_command_codes)")
    sim, node = running
    setup_run_from_canopen(drive, node)
    node.nmt.state = "PRE-OPERATIONAL"  # python-canopen only reads PDOs in a known state
    node.setup_402_state_machine()
    node.nmt.state = "OPERATIONAL"
    if 0x6041 in node.tpdo_values:  # BaseNode402 caches the statusword from TPDOs: seed it
        node.tpdo_values[0x6041] = node.sdo[0x6041].raw
    node.check_statusword()
    assert node.state == "SWITCH ON DISABLED"
    walk = ["READY TO SWITCH ON", "SWITCHED ON", "OPERATION ENABLED", "SWITCHED ON",
            "READY TO SWITCH ON", "SWITCH ON DISABLED", "OPERATION ENABLED",
            "SWITCH ON DISABLED"]
    for state in walk:
        node.state = state
        assert node.state == state
        sw = node.sdo[0x6041].raw
        assert node.state == state, f"statusword 0x{sw:04X} after asking for {state}"
    # The simulator logged the walk, one line per change.
    sim.wait_out(rf"node {drive.node_id} {drive.id}: .*OPERATION ENABLED")


def test_emcy_on_fault_and_fault_reset(running, drive, recorder):
    if drive.trip is None:
        pytest.skip("no trip code known")
    sim, node = running
    row = drive.fault_row(drive.trip)
    code = int(row["emcy_code"], 0)
    bit = int(row["error_register_bit"])
    node.nmt.state = "OPERATIONAL"
    for address, value in drive.gate_params:  # the drive's own commands need their gate open
        param_channel_write(node.network, recorder, drive.node_id, address, value)
    since = len(node.emcy.log)
    mark = sim.control.mark()
    sim.control.fault(drive.node_id, drive.trip)  # through the control socket (canopen_sim)
    emcy = wait_emcy(node, since, code)
    assert emcy.register & (1 << bit), f"error register 0x{emcy.register:02X} lacks bit {bit}"
    sim.control.wait_event(r"^fault: trip", node=drive.node_id, since=mark)
    fault = sim.control.state(drive.node_id)["fault"]
    assert (fault["trip"], fault["emcy"], fault["cause"]) == (drive.trip, code, True)
    assert node.sdo[0x1001].raw & (1 << bit)
    if 0x603F in node.object_dictionary:
        assert node.sdo[0x603F].raw == code
    if drive.cia402:
        assert node.sdo[0x6041].raw & 0x4F == 0x08, "statusword must show FAULT"
    # The cause goes away; the master resets the fault.
    since = len(node.emcy.log)
    sim.control.clear(drive.node_id)  # done when it answers: the cause is gone
    assert sim.control.state(drive.node_id)["fault"]["cause"] is False
    if drive.cia402:
        node.sdo[0x6040].raw = 0x0000
        node.sdo[0x6040].raw = 0x0080  # rising edge of bit 7
        wait_emcy(node, since, 0x0000)
        assert node.sdo[0x6041].raw & 0x4F == 0x40, "statusword must show SWITCH ON DISABLED"
    else:
        node.sdo[0x2101].raw = 7  # CW command 7: fault reset (B10)
        wait_emcy(node, since, 0x0000)
    assert node.sdo[0x1001].raw == 0
    assert sim.control.state(drive.node_id)["fault"] is None


# --- store / restore ------------------------------------------------------------------------------

def test_store_and_restore_across_a_restart(sims, nodes, drive, tmp_path, recorder):
    store = tmp_path / "store.bin"
    sim = sims.start([(drive.id, drive.node_id)], store=store)
    node = nodes(drive)
    od = node.object_dictionary
    probe = 0x1017 if 0x1017 in od else 0x100C  # a communication parameter every drive has
    hb = od[probe]
    if not drive.has_store:
        code = sdo_abort(node, 0x1010, 1, lambda: node.sdo.download(0x1010, 1,
                                                                        struct.pack("<I", SAVE)))
        assert code == 0x06020000, f"{drive.id} has no 0x1010: expected 0x06020000, got {code:#x}"
        node.sdo[probe].raw = 250
        assert sim.stop() == 0
        sim = sims.start([(drive.id, drive.node_id)], store=store)
        assert node.sdo[probe].raw == hb.default, "without 0x1010 nothing may survive a restart"
        return
    assert node.sdo[0x1010][1].raw & 0x1, "0x1010:01 must say it stores on command"
    node.sdo[0x1017].raw = 250
    bad = sdo_abort(node, 0x1010, 1, lambda: node.sdo.download(0x1010, 1, b"SAVE"))
    assert bad == 0x08000020, "only the 'save' signature stores"
    node.sdo.download(0x1010, 1, struct.pack("<I", SAVE))
    assert store.exists()
    assert sim.stop() == 0

    sim = sims.start([(drive.id, drive.node_id)], store=store)
    assert node.sdo[0x1017].raw == 250
    # Restore defaults: takes effect at the next reset.
    node.sdo.download(0x1011, 1, struct.pack("<I", LOAD))
    mark = recorder.mark()
    node.nmt.send_command(0x81)
    recorder.wait_frame(0x700 + drive.node_id, b"\x00", since=mark)
    assert node.sdo[0x1017].raw == hb.default
    assert sim.stop() == 0
    sim = sims.start([(drive.id, drive.node_id)], store=store)
    assert node.sdo[0x1017].raw == hb.default


def test_corrupt_store_file_gives_defaults_and_a_message(sims, nodes, drive, tmp_path):
    store = tmp_path / "store.bin"
    store.write_bytes(b"CODSTOR1" + b"\xff" * 40)
    sim = sims.start([(drive.id, drive.node_id)], store=store)
    sim.wait_err(r"store .*store\.bin: ignored: .*defaults")
    node = nodes(drive)
    assert node.sdo[0x1000].raw == node.object_dictionary[0x1000].default
