"""Frame sequences printed in the manuals, reproduced on the bus byte for byte.

- VF-S15 CANopen manual §7.1 (asynchronous) and §7.2 (SYNC): controlword 0x0006, 0x0007, 0x000F
  with target 0x05DC over RPDO1; TxPDO1 answers `37 06 DC 05` once the drive is at 1500 min^-1.
- Sourcetronic EC-TX105 §3.5.3 / §3.4.8 / §3.4.9: parameters over the PDO1 channel, the SDO
  write and read of 0x1801:03, run forward through RPDO2, the EMCY of fault 1 (OUT1) `00 30 04 01 00 00 00 00` and its reset by command code 7.
"""
import struct

import pytest

from conftest import TIMEOUT, param_channel_write
from drives import BY_ID

VF_S15 = BY_ID["vf-s15"]
ST600 = BY_ID["sourcetronic-st600"]
NODE = 1  # the manual's node


def sdo_write(network, recorder, node_id, index, sub, value, size):
    cmd = {1: 0x2F, 2: 0x2B, 4: 0x23}[size]
    mark = recorder.mark()
    network.send_message(0x600 + node_id, struct.pack("<BHBI", cmd, index, sub, value))
    reply = recorder.wait_frame(0x580 + node_id, since=mark)
    assert reply.data[0] == 0x60, f"SDO write 0x{index:04X}:{sub} aborted: {bytes(reply.data).hex()}"


def wait_data(recorder, cob_id, data, since, timeout):
    return recorder.wait_frame(cob_id, data, since=since, timeout=timeout)


@pytest.fixture
def vf_s15(sims, network, recorder):
    sim = sims.start([("vf-s15", NODE)])
    # §7 table: command and frequency from CANopen; a 1 s ramp instead of the factory 10 s so
    # the test does not wait (6048: 1500 min^-1 per 1 s).
    sdo_write(network, recorder, NODE, 0x2003, 0, 3, 2)
    sdo_write(network, recorder, NODE, 0x2004, 0, 6, 2)
    sdo_write(network, recorder, NODE, 0x6048, 2, 1, 2)
    return sim


def send_and_see_state(network, recorder, cob_id, data, pattern):
    """Sends an RPDO and waits for TxPDO1 (type 255: sent on change) to show the state."""
    mark = recorder.mark()
    network.send_message(cob_id, data)
    recorder.wait_for(lambda m: m.arbitration_id == 0x181 and not m.is_remote_frame
                      and struct.unpack("<H", bytes(m.data[:2]))[0] & 0x6F == pattern, mark,
                      what=f"TxPDO1 with statusword pattern 0x{pattern:02X}")


def test_vf_s15_section_7_1_asynchronous(vf_s15, network, recorder):
    mark = recorder.mark()
    network.send_message(0x000, b"\x01\x01")                       # 2. NMT start node 1
    recorder.wait_frame(0x181, since=mark)                          # TxPDO1 on entering OP
    send_and_see_state(network, recorder, 0x201, b"\x06\x00\x00\x00", 0x21)  # 4. Ready
    send_and_see_state(network, recorder, 0x201, b"\x07\x00\x00\x00", 0x23)  # 5. Switched on
    mark = recorder.mark()
    send_and_see_state(network, recorder, 0x201, b"\x0F\x00\xDC\x05", 0x27)  # 6. Enabled
    # TxPDO1 (type 255) follows every change while the drive ramps up to 1500 min^-1.
    wait_data(recorder, 0x181, b"\x37\x06\xDC\x05", mark, timeout=TIMEOUT + 10)
    # 7./8. RTR TxPDO1 -> status word 0x0637, speed 0x05DC.
    rtr = recorder.mark()
    network.send_message(0x181, b"", remote=True)
    reply = recorder.wait_frame(0x181, since=rtr)
    assert bytes(reply.data) == b"\x37\x06\xDC\x05" and reply.dlc == 4
    # The ramp is visible on the way: 6044 rises through intermediate speeds to 1500.
    speeds = [struct.unpack("<h", bytes(m.data[2:4]))[0]
              for m in recorder.since(mark, lambda m: m.arbitration_id == 0x181
                                      and not m.is_remote_frame and m.dlc == 4)]
    assert speeds == sorted(speeds) and speeds[-1] == 1500
    assert len([v for v in speeds if 0 < v < 1500]) >= 3, speeds


def test_vf_s15_section_7_2_sync(vf_s15, network, recorder):
    # C713 = C716 = 1 (synchronous); they take effect at the next reset (§3.2).
    sdo_write(network, recorder, NODE, 0x4713, 0, 1, 2)
    sdo_write(network, recorder, NODE, 0x4716, 0, 1, 2)
    mark = recorder.mark()
    network.send_message(0x000, b"\x81\x01")
    recorder.wait_frame(0x701, b"\x00", since=mark)
    sdo_write(network, recorder, NODE, 0x2003, 0, 3, 2)
    sdo_write(network, recorder, NODE, 0x2004, 0, 6, 2)
    sdo_write(network, recorder, NODE, 0x6048, 2, 1, 2)
    network.send_message(0x000, b"\x01\x01")
    for cw in (b"\x06\x00\x00\x00", b"\x07\x00\x00\x00", b"\x0F\x00\xDC\x05"):
        network.send_message(0x201, cw)
        mark = recorder.mark()
        network.send_message(0x080, b"")                            # SYNC applies the RPDO
        recorder.wait_frame(0x181, since=mark)                      # type 1: TxPDO every SYNC
    # The master's SYNC producer runs until TxPDO1 shows the drive at speed.
    mark = recorder.mark()
    network.sync.start(0.05)
    try:
        wait_data(recorder, 0x181, b"\x37\x06\xDC\x05", mark, timeout=TIMEOUT + 10)
    finally:
        network.sync.stop()
    # 10./11. RTR TxPDO1 (answered for every type, B4).
    rtr = recorder.mark()
    network.send_message(0x181, b"", remote=True)
    reply = recorder.wait_frame(0x181, since=rtr)
    assert bytes(reply.data) == b"\x37\x06\xDC\x05"


# --- Sourcetronic ST600: its own command codes -------------------------------------------------

ST = 3


def st_param_write(network, recorder, address, value):
    """PDO1 parameter channel write (B11): RPDO1 `02 00 addr value` -> TPDO1 response, DLC 8."""
    reply = param_channel_write(network, recorder, ST, address, value)
    assert bytes(reply.data) == struct.pack("<HHHH", 1, 0, value, 0), bytes(reply.data).hex()


def test_sourcetronic_command_codes(sims, network, recorder, nodes):
    sim = sims.start([("sourcetronic-st600", ST)])
    node = nodes(ST600)
    network.send_message(0x000, bytes([0x01, ST]))
    # §3.5.3 recipe: P00.01 = 2, P00.02 = 1, P00.06 = 9, P15.03 = 1 (setting 2 = set frequency).
    for address, value in ((0x0001, 2), (0x0002, 1), (0x0006, 9), (0x0F03, 1)):
        st_param_write(network, recorder, address, value)
    # The manual's example of §3.5.2.1: P15.13 := 1 -> `183: 01 00 00 00 01 00 00 00`.
    st_param_write(network, recorder, 0x0F0D, 1)
    # §3.4.9: the disabled time of PDO2 Tx written to 1000 ms while TPDO2 is in use, then read:
    # `583: 60 01 18 03 00 00 ...`, `583: 43 01 18 03 E8 03 00 00` (4 bytes for the U16).
    for request, answer in (("2B 01 18 03 E8 03 00 00", "60 01 18 03 00 00 00 00"),
                            ("40 01 18 03 00 00 00 00", "43 01 18 03 E8 03 00 00")):
        mark = recorder.mark()
        network.send_message(0x600 + ST, bytes.fromhex(request))
        reply = recorder.wait_frame(0x580 + ST, since=mark)
        assert bytes(reply.data) == bytes.fromhex(answer), bytes(reply.data).hex()
    # RPDO2: CW 1 (forward running), setting 1, setting 2 = 5000 (50.00 Hz).
    mark = recorder.mark()
    network.send_message(0x300 + ST, struct.pack("<HHHH", 1, 0, 0x1388, 0))
    running = recorder.wait_for(lambda m: m.arbitration_id == 0x280 + ST
                                and m.data[0] == 1, since=mark, what="SW: forward running")
    assert struct.unpack("<H", bytes(running.data[:2]))[0] == 0x4101
    # CW 5: ramp to a stop; SW state code 3.
    mark = recorder.mark()
    network.send_message(0x300 + ST, struct.pack("<HHHH", 5, 0, 0x1388, 0))
    recorder.wait_for(lambda m: m.arbitration_id == 0x280 + ST and m.data[0] == 3, since=mark,
                      timeout=TIMEOUT + 20, what="SW: stopped")
    # Fault 1 (OUT1): EMCY as printed in §3.4.8, SW state 4 (faulty).
    mark = recorder.mark()
    sim.send(f"fault {ST} 1")
    emcy = recorder.wait_frame(0x80 + ST, since=mark)
    assert bytes(emcy.data) == bytes.fromhex("00 30 04 01 00 00 00 00")
    assert node.sdo[0x2001].raw & 0xFF == 4
    # Cause gone, CW 7 resets: all-zero EMCY, SW state 3.
    # stdin and CAN are separate paths: a reset that overtakes the clear is refused
    out = sim.out_mark()
    sim.send(f"clear {ST}")
    sim.wait_out(r"fault cause cleared", since=out)
    mark = recorder.mark()
    network.send_message(0x300 + ST, struct.pack("<HHHH", 7, 0, 0, 0))
    emcy = recorder.wait_frame(0x80 + ST, since=mark)
    assert bytes(emcy.data) == bytes(8)
    assert node.sdo[0x2001].raw & 0xFF == 3
