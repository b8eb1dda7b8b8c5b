#!/usr/bin/env python3
"""Writes the seed corpus of the libFuzzer targets (tests/fuzz/corpus/<target>/<name>): real
exchanges - SDO expedited, segmented and block transfers both ways, NMT, PDO, SYNC, heartbeat and
guarding, the drive manuals' example sequences (VF-S15 §7.1/§7.2, VF-MB1 §8.14, Vacon §7.5,
Sourcetronic §3.5.3, Benshaw fieldbus control) - encoded in the harness's input format
(fuzz_harness.h). Deterministic: run it again after changing the format or adding a drive.

    tests/fuzz/make_corpus.py            # rewrites tests/fuzz/corpus/
"""
import os
import shutil
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
CORPUS = os.path.join(HERE, "corpus")

# Opcodes (enum fz_op in fuzz_harness.h).
RAW, REL, SDO, NMT, TIME, PROCESS, BUS, SDO_WRITE, SDO_READ, LIMIT, SEG_WRITE, BLOCK_WRITE, \
    UPLOAD, REMAP, SYNC, RPDO, TPDO_RTR, HEARTBEAT, GUARD, APP, DRIVE = range(21)

BASE = {RAW, REL, SDO, NMT, TIME, PROCESS, BUS}
# The operations each target enables (the fz_target tables of fuzz_*.c).
ENABLED = {
    "fuzz_nmt": BASE | {SDO_WRITE, SDO_READ, HEARTBEAT, GUARD, SYNC, SEG_WRITE},
    "fuzz_sdo": BASE | {SDO_WRITE, SDO_READ, LIMIT, SEG_WRITE, BLOCK_WRITE, UPLOAD},
    "fuzz_pdo_sync": BASE | {SDO_WRITE, REMAP, SYNC, RPDO, TPDO_RTR, APP},
    "fuzz_errctl": BASE | {SDO_WRITE, SDO_READ, HEARTBEAT, GUARD, APP},
}

# Header h1 values of the protocol targets: 0 test.eds, 1 test_sparse.eds, 2 + k drive k of the
# registry (drives sorted by directory name, as cmake/Drives.cmake lists them).
DRIVES = sorted(d for d in os.listdir(os.path.join(HERE, "..", "..", "od"))
                if os.path.exists(os.path.join(HERE, "..", "..", "od", d, "drive.c")))
DICT_TEST, DICT_SPARSE = 0, 1


def dict_of(drive):
    return 2 + DRIVES.index(drive)


def header(node_id=1, dictionary=0, flags=0, options=0, pdo_flags=0, dummy=0, units=0,
           settings=(), domain=0):
    h = bytes([(node_id - 1) % 127, dictionary, flags, options, pdo_flags, dummy, units,
               len(settings) if settings else domain])
    for sel, value in settings:
        h += struct.pack("<Bi", sel, value)
    return h


class Seq:
    """An input under construction: operations appended in the harness's encoding."""

    def __init__(self, node_id=1, **kw):
        self.node_id = node_id
        self.ops = set()
        self.b = bytearray(header(node_id, **kw))

    def op(self, code, *payload):
        self.ops.add(code)
        self.b.append(code)
        for p in payload:
            if isinstance(p, (bytes, bytearray)):
                self.b += p
            else:
                self.b.append(p & 0xFF)
        return self

    # frames
    def raw(self, cob, data=b"", rtr=False, dlc=None):
        dlc = len(data) if dlc is None else dlc
        return self.op(RAW, cob & 0xFF, cob >> 8, 1 if rtr else 0, dlc, b"" if rtr else data)

    def sdo(self, *req):
        req = bytes(req) + bytes(8 - len(req))
        return self.op(SDO, req)

    def write(self, index, sub, value, size):
        cmd = {1: 0x2F, 2: 0x2B, 3: 0x27, 4: 0x23}[size]
        return self.sdo(cmd, index & 0xFF, index >> 8, sub, *struct.pack("<I", value & 0xFFFFFFFF))

    def read(self, index, sub):
        return self.sdo(0x40, index & 0xFF, index >> 8, sub)

    def nmt(self, command, node=None):
        node = self.node_id if node is None else node
        return self.raw(0x000, bytes([command, node]))

    def time(self, us):
        """Moves the clock by exactly us: a coarse step (16 bits << 2k) and the rest."""
        while us > 0:
            shift = 0
            while (us >> (2 * shift)) > 0xFFFF:
                shift += 1
            v = us >> (2 * shift)
            self.op(TIME, 2 | (shift << 2), v & 0xFF, v >> 8)
            us -= v << (2 * shift)
        return self

    def to_next_deadline(self):
        return self.op(TIME, 0, 0, 0)

    def process(self):
        return self.op(PROCESS)

    def sync(self, counter=None):
        return self.raw(0x080, b"" if counter is None else bytes([counter]))

    def rpdo(self, cob, data):
        return self.raw(cob, data)

    def rtr(self, cob, dlc=0):
        return self.raw(cob, b"", rtr=True, dlc=dlc)

    def heartbeat(self, producer, state):
        return self.raw(0x700 + producer, bytes([state]))

    def guard(self, dlc=0):
        return self.op(GUARD, dlc)

    # whole SDO transfers, frame for frame as a client sends them
    def segmented_download(self, index, sub, data):
        self.sdo(0x21, index & 0xFF, index >> 8, sub, *struct.pack("<I", len(data)))
        toggle = 0
        for pos in range(0, max(len(data), 1), 7):
            chunk = data[pos:pos + 7]
            last = pos + 7 >= len(data)
            self.sdo((toggle << 4) | ((7 - len(chunk)) << 1) | (1 if last else 0), *chunk)
            toggle ^= 1
        return self

    def segmented_upload(self, index, sub, segments):
        self.read(index, sub)
        for i in range(segments):
            self.sdo(0x60 | ((i & 1) << 4))
        return self

    def block_download(self, index, sub, data, crc=True):
        self.sdo(0xC2 | (0x04 if crc else 0), index & 0xFF, index >> 8, sub,
                 *struct.pack("<I", len(data)))
        chunks = [data[i:i + 7] for i in range(0, len(data), 7)] or [b""]
        for seq, chunk in enumerate(chunks, 1):
            last = seq == len(chunks)
            self.sdo(seq | (0x80 if last else 0), *(chunk + bytes(7 - len(chunk))))
        n = 7 - len(chunks[-1])
        c = crc16(data) if crc else 0
        return self.sdo(0xC1 | (n << 2), c & 0xFF, c >> 8)

    def block_upload(self, index, sub, blksize=127, crc=True):
        self.sdo(0xA0 | (0x04 if crc else 0), index & 0xFF, index >> 8, sub, blksize, 0)
        self.sdo(0xA3)
        self.sdo(0xA2, 1, blksize)  # one-segment objects: acknowledge segment 1
        return self.sdo(0xA1)

    def save_all(self):
        return self.write(0x1010, 1, 0x65766173, 4)

    def restore_all(self):
        return self.write(0x1011, 1, 0x64616F6C, 4)


def crc16(data):
    crc = 0
    for b in data:
        crc ^= b << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
    return crc


# --- seeds per concern ---------------------------------------------------------------------

def nmt_seeds(dictionary, node_id=5):
    s = {}
    q = Seq(node_id, dictionary=dictionary)
    for cmd in (0x01, 0x80, 0x01, 0x02, 0x01, 0x82, 0x01, 0x81):
        q.nmt(cmd).process()
    s["nmt_every_command"] = q
    q = Seq(node_id, dictionary=dictionary)
    q.nmt(0x01, 0).nmt(0x02, node_id + 1).nmt(0x02, 0).nmt(0x80, 0).raw(0x000, b"\x01").raw(
        0x000, b"\x01\x00\x00").raw(0x000, b"\x05\x00").rtr(0x000, 2)
    s["nmt_broadcast_other_and_malformed"] = q
    q = Seq(node_id, dictionary=dictionary)
    q.write(0x1017, 0, 100, 2).time(100000).time(100000).nmt(0x02).time(100000).nmt(
        0x82).time(100000)
    s["nmt_heartbeat_across_states"] = q
    q = Seq(node_id, dictionary=dictionary)
    q.write(0x1017, 0, 50, 2).save_all().nmt(0x81).time(60000).restore_all().nmt(0x81).time(60000)
    s["nmt_store_then_reset_node"] = q
    q = Seq(node_id, dictionary=dictionary, flags=0x08)
    for sub in (2, 3, 4):
        q.write(0x1010, sub, 0x65766173, 4)
    q.nmt(0x82).nmt(0x81)
    for sub in (2, 3, 4, 1):
        q.write(0x1011, sub, 0x64616F6C, 4)
    q.nmt(0x81).nmt(0x01)
    s["nmt_store_groups_and_restore"] = q
    return s


def sdo_seeds(dictionary, node_id=5):
    s = {}
    q = Seq(node_id, dictionary=dictionary)
    q.read(0x1000, 0).read(0x1018, 1).write(0x1017, 0, 1000, 2).read(0x1017, 0).read(
        0x1017, 0).write(0x1017, 0, 0, 2)
    s["sdo_expedited"] = q
    q = Seq(node_id, dictionary=dictionary)
    q.segmented_upload(0x1008, 0, 6).segmented_upload(0x1009, 0, 3)
    s["sdo_segmented_upload"] = q
    q = Seq(node_id, dictionary=dictionary)
    q.segmented_download(0x1017, 0, b"\x10\x00").segmented_download(0x1016, 1, b"\x64\x00\x07\x00")
    s["sdo_segmented_download"] = q
    q = Seq(node_id, dictionary=dictionary)
    q.block_download(0x1017, 0, b"\x20\x00").block_download(0x1016, 1, b"\x64\x00\x07\x00", False)
    s["sdo_block_download"] = q
    q = Seq(node_id, dictionary=dictionary)
    q.block_upload(0x1018, 1).block_upload(0x1000, 0, 4, False)
    q.op(UPLOAD, 0x00, 0x00, 0x00, 0x01, 0x7F, 0x00)  # harness client: block upload, entry 0
    s["sdo_block_upload"] = q
    q = Seq(node_id, dictionary=dictionary)
    q.sdo(0x2B, 0x17, 0x10, 0x00).sdo(0x00, 1, 2).sdo(0x60).sdo(0x80, 0x17, 0x10).sdo(
        0xE0).sdo(0x23, 0xFF, 0xFF, 0x00, 1).sdo(0x40, 0x00, 0x10, 0x07).raw(
        0x600 + node_id, b"\x40\x00\x10").time(2000000)
    s["sdo_malformed"] = q
    q = Seq(node_id, dictionary=dictionary)
    for sel in range(8):
        q.op(LIMIT, sel, 0, 0).op(LIMIT, sel, 0, 1)
    s["sdo_limit_probe"] = q
    q = Seq(node_id, dictionary=dictionary, flags=0x10)
    q.sdo(0x21, 0x08, 0x10, 0x00, 20).time(60000).sdo(0x00, 1, 2, 3, 4, 5, 6, 7)
    s["sdo_timeout_midway"] = q
    if dictionary == DICT_TEST:  # strings, u64 and a DOMAIN streamed by the application
        text = b"a string of twenty-five b"
        q = Seq(node_id, dictionary=dictionary, domain=20)
        q.segmented_download(0x200D, 0, text).segmented_upload(0x200D, 0, 4)
        q.block_download(0x200E, 0, text[:16]).block_upload(0x200E, 0, 3)
        q.segmented_download(0x2010, 0, bytes(range(40)))
        q.block_download(0x2010, 0, bytes(range(200)), crc=True)
        q.segmented_upload(0x2010, 0, 30)
        q.op(UPLOAD, 0, 0, 0, 0x03, 127, 0)
        s["sdo_strings_and_domain"] = q
    return s


def pdo_seeds(dictionary, node_id=5):
    s = {}
    q = Seq(node_id, dictionary=dictionary, flags=0x08)
    for n in range(4):
        q.rpdo(0x200 + 0x100 * n + node_id, bytes(range(8))).rtr(0x180 + 0x100 * n + node_id)
    q.to_next_deadline().to_next_deadline()
    s["pdo_every_default_cob"] = q
    q = Seq(node_id, dictionary=dictionary, flags=0x08)
    q.sync().sync(1).write(0x1006, 0, 10000, 4).write(0x1005, 0, 0x40000080, 4).time(
        10000).time(10000).write(0x1019, 0, 5, 1).sync(3)
    s["sync_consumer_and_producer"] = q
    q = Seq(node_id, dictionary=dictionary)
    q.write(0x1800, 1, 0x80000180 + node_id, 4).write(0x1A00, 0, 0, 1).write(
        0x1A00, 1, 0x60410010, 4).write(0x1A00, 0, 1, 1).write(0x1800, 2, 1, 1).write(
        0x1800, 1, 0x180 + node_id, 4).nmt(0x01).sync().sync()
    s["tpdo_remap_through_sdo"] = q
    q = Seq(node_id, dictionary=dictionary, flags=0x08)
    q.op(REMAP, 0, 0x07, 2, 0, 0, 0, 1, 0, 0, 255, 0, 0).op(REMAP, 0, 0x06, 1, 3, 0, 0, 1, 0, 0)
    q.op(RPDO, 0, 0x0F, *range(8)).op(TPDO_RTR, 0, 0).op(SYNC, 0, 0)
    s["pdo_remap_ops"] = q
    return s


def errctl_seeds(dictionary, node_id=5):
    s = {}
    q = Seq(node_id, dictionary=dictionary)
    q.write(0x1016, 1, (9 << 16) | 100, 4).heartbeat(9, 0x05).time(50000).heartbeat(
        9, 0x05).time(150000).heartbeat(9, 0x7F).heartbeat(9, 0x00).heartbeat(9, 0x05)
    s["heartbeat_consumer_loss_and_back"] = q
    q = Seq(node_id, dictionary=dictionary)
    q.write(0x100C, 0, 100, 2).write(0x100D, 0, 3, 1).guard(0).guard(1).time(100000).guard(
        0).time(400000).guard(0)
    s["node_and_life_guarding"] = q
    q = Seq(node_id, dictionary=dictionary, flags=0x08)
    q.op(BUS, 0x10 | (1 << 2)).op(BUS, 0x10 | (2 << 2)).op(BUS, 0x10).op(BUS, 0x20 | 0xC0)
    q.write(0x1029, 1, 2, 1).op(BUS, 0x10 | (2 << 2)).op(BUS, 0x10)
    s["bus_off_passive_overrun"] = q
    q = Seq(node_id, dictionary=dictionary)
    q.write(0x1017, 0, 10, 2).op(BUS, 1).time(30000).op(BUS, 2).time(30000).guard(0)
    s["port_queue_full_then_ready"] = q
    return s


def drive_seeds(drive, node_id=1):
    s = {}
    if drive == "vf-s15":
        q = Seq(node_id).write(0x2003, 0, 3, 2).write(0x2004, 0, 6, 2).nmt(0x01)
        for cw, target in ((0x0006, 0), (0x0007, 0), (0x000F, 0x05DC)):
            q.rpdo(0x201, struct.pack("<Hh", cw, target))
        q.time(10000000).rtr(0x181)
        s["manual_7_1_asynchronous"] = q
        q = Seq(node_id).write(0x4713, 0, 1, 2).write(0x4716, 0, 1, 2).nmt(0x81)
        q.write(0x2003, 0, 3, 2).write(0x2004, 0, 6, 2).write(0x6048, 2, 1, 2).nmt(0x01)
        for cw, target in ((0x0006, 0), (0x0007, 0), (0x000F, 0x05DC)):
            q.rpdo(0x201, struct.pack("<Hh", cw, target)).sync()
        q.time(10000000).sync().rtr(0x181)
        s["manual_7_2_synchronous"] = q
        q = Seq(node_id).write(0x2003, 0, 3, 2).write(0x2004, 0, 6, 2)
        q.write(0x1016, 1, (0x7F << 16) | 100, 4).write(0x4101, 0, 4, 2).heartbeat(0x7F, 5)
        q.nmt(0x01).write(0x6040, 0, 6, 2).write(0x6040, 0, 0xF, 2).write(0x6042, 0, 1500, 2)
        q.time(2000000).time(300000).time(300000)
        s["heartbeat_loss_c101"] = q
    elif drive == "vf-mb1-ecat":
        for c101 in (2, 3, 4):
            q = Seq(node_id).write(0x4101, 0, c101, 2).write(0x2003, 0, 4, 2)
            q.write(0x2004, 0, 7, 2).nmt(0x81).write(0x1400, 5, 100, 2).nmt(0x01)
            for cw, target in ((0x0006, 0), (0x0007, 0), (0x000F, 1500)):
                q.rpdo(0x202, struct.pack("<Hh", cw, target))
            q.time(1000000).time(300000).time(5000000)
            q.rpdo(0x202, struct.pack("<Hh", 0x000F, 1500)).write(0x6040, 0, 0x80, 2)
            s[f"rpdo_deadline_c101_{c101}"] = q
        q = Seq(node_id).write(0x2003, 0, 4, 2).write(0x2004, 0, 7, 2).nmt(0x81).nmt(0x01)
        q.write(0x6040, 0, 6, 2).write(0x6040, 0, 0xF, 2).write(0x6042, 0, 900, 2).time(1000000)
        q.write(0x2A06, 0, 0x1000, 2).time(1000).write(0x2A06, 0, 0x0000, 2)
        q.write(0x2A06, 0, 0x2000, 2)
        s["fa06_emergency_stop"] = q
        q = Seq(node_id).write(0x2003, 0, 4, 2).write(0x2004, 0, 7, 2).nmt(0x81).nmt(0x01)
        for cw, target in ((0x0006, 0), (0x0007, 0), (0x000F, 0), (0x000F, 0x05DC)):
            q.rpdo(0x202, struct.pack("<Hh", cw, target))
        q.time(10000000).rpdo(0x202, struct.pack("<Hh", 0, 0x05DC)).process()
        s["manual_8_14_start_and_stop"] = q
    elif drive == "vacon-optc6":
        for mode in (2, 3, 5):  # operate_mode: bypass and its PDO sets
            q = Seq(node_id, settings=[(0, mode)]).nmt(0x81).nmt(0x01)
            q.rpdo(0x401, struct.pack("<Hh", 0x0001, 5000) + bytes(4)).time(1000000)
            q.rpdo(0x401, struct.pack("<Hh", 0x0003, 10000) + bytes(4)).time(1000000)
            q.rpdo(0x401, struct.pack("<Hh", 0x0000, 0) + bytes(4)).time(1000000)
            q.op(DRIVE, 0, 3, 0).rpdo(0x401, struct.pack("<Hh", 0x0004, 0) + bytes(4))
            s[f"bypass_mode_{mode}"] = q
        q = Seq(node_id).write(0x2000, 0, 102, 2).read(0x2001, 0).time(10000).read(0x2001, 0)
        q.write(0x2002, 0, (103 << 16) | 30, 4).write(0x2002, 0, (104 << 16) | 5, 4).time(10000)
        q.write(0x2000, 0, 103, 2).time(10000).read(0x2001, 0)
        s["anyparameter_read_write"] = q
        q = Seq(node_id).nmt(0x01)
        for cw, target in ((0x0006, 0), (0x0007, 0), (0x000F, 1500)):
            q.rpdo(0x301, struct.pack("<Hh", cw, target))
        q.time(500000).time(500000).rtr(0x281)
        s["manual_7_5_prepare_ready_run"] = q
        q = Seq(node_id).write(0x100C, 0, 100, 2).write(0x100D, 0, 3, 1).guard().nmt(0x01)
        q.rpdo(0x301, struct.pack("<Hh", 0x6, 0)).rpdo(0x301, struct.pack("<Hh", 0xF, 900))
        q.time(200000).time(400000)
        s["life_guarding_fieldbus_fault"] = q
    elif drive == "sourcetronic-st600":
        node_id = 3
        q = Seq(node_id).nmt(0x01)
        for address, value in ((0x0001, 2), (0x0002, 1), (0x0006, 9), (0x0F03, 1), (0x0F0D, 1)):
            q.rpdo(0x203, struct.pack("<HHH", 2, address, value)).time(500000)
        q.rpdo(0x303, struct.pack("<HHHH", 1, 0, 0x1388, 0)).time(5000000).time(5000000)
        q.rpdo(0x303, struct.pack("<HHHH", 5, 0, 0x1388, 0)).time(10000000)
        q.op(DRIVE, 1, 1, 0).rpdo(0x303, struct.pack("<HHHH", 7, 0, 0, 0)).op(DRIVE, 2, 0, 0)
        q.rpdo(0x303, struct.pack("<HHHH", 7, 0, 0, 0))
        s["manual_3_5_3_recipe_and_fault"] = q
    elif drive == "benshaw-rsi":
        q = Seq(node_id).write(0x4010, 7, 4, 2).write(0x4010, 8, 8, 2).time(1)
        q.write(0x6040, 0, 6, 2).write(0x6040, 0, 0xF, 2).write(0x6042, 0, 900, 2).time(2000000)
        q.write(0x6040, 0, 0x2, 2).time(2000000)
        s["fieldbus_control_run_quick_stop"] = q
        for mode in range(1, 6):
            q = Seq(node_id).write(0x4010, 7, 4, 2).write(0x4010, 8, 8, 2).time(1)
            q.write(0x6040, 0, 6, 2).write(0x6040, 0, 0xF, 2).write(0x6042, 0, 900, 2)
            q.time(2000000).nmt(0x01).write(0x401A, 12, mode, 2).nmt(0x80).time(1000000)
            q.time(1000000).nmt(0x01).write(0x6040, 0, 0x80, 2)
            s[f"lost_command_mode_{mode}"] = q
        q = Seq(node_id).write(0x4016, 11, 1, 2).write(0x4016, 94, 1, 2).nmt(0x01)
        q.write(0x4016, 0x3D, 9, 2).write(0x4016, 0x43, 1, 2).nmt(0x01)
        s["comm_update_pdo3_and_node_id"] = q
    # every drive: the CiA 402 walk by SDO, a fault and its reset, NMT around it
    q = Seq(node_id)
    q.write(0x6040, 0, 0x06, 2).write(0x6040, 0, 0x07, 2).write(0x6040, 0, 0x0F, 2)
    q.write(0x6042, 0, 300, 2).time(1000000).op(DRIVE, 0, 0, 0).time(1000000)
    q.op(DRIVE, 2, 0, 0).write(0x6040, 0, 0x80, 2).write(0x6040, 0, 0x06, 2).nmt(0x82).nmt(0x81)
    s["cia402_walk_fault_reset"] = q
    q = Seq(node_id, flags=0x08)
    for sel in range(12):
        q.op(LIMIT, sel, 0, 0).op(LIMIT, sel, 0, 1)
    s["limit_probe"] = q
    q = Seq(node_id)
    q.read(0x1000, 0).segmented_upload(0x1008, 0, 4).block_upload(0x1018, 1)
    q.save_all().nmt(0x81).restore_all().nmt(0x81)
    s["sdo_and_store"] = q
    return s


# ---- fuzz_esc_frame (its own input format: tests/fuzz/fuzz_esc_frame.c) ----

def esc_op(op, payload=b""):
    return bytes([op]) + struct.pack("<H", len(payload)) + payload


def ecat_frame(cmd, adp, ado, data):
    dg = struct.pack("<BBHHHH", cmd, 0, adp, ado, len(data), 0) + data + b"\0\0"
    frame = b"\xff" * 6 + b"\x02" * 6 + b"\x88\xa4" + struct.pack("<H", 0x1000 | len(dg)) + dg
    return frame + b"\0" * max(0, 60 - len(frame))


def esc_seeds():
    """A master's way through the slave application layer (setup: SOEM's SM/FMMU layout, SII
    checksum right, application layer on): AL requests, CoE in the 128-byte SM0, SM1 reads, LRW
    cycles, clock steps (the SM watchdog)."""
    setup = bytes([8 | 16 | 32])
    counter = [0]

    def al(state):
        if state < 16:  # the canned AL control frame
            return esc_op((2 | state << 2) << 2)
        return esc_op(0, ecat_frame(2, 0, 0x0120, struct.pack("<H", state)))

    def tick(ns):
        return esc_op(3, struct.pack("<I", ns))

    lrw, read_mbx = esc_op(4), esc_op(12)

    def coe(service, body):
        counter[0] = counter[0] % 7 + 1
        msg = struct.pack("<HHBB", 2 + len(body), 0, 0, 3 | counter[0] << 4) + \
            struct.pack("<H", service << 12) + body
        return esc_op(0, ecat_frame(2, 0, 0x1000, msg + b"\0" * (128 - len(msg)))) + read_mbx

    def upload(index, sub, ca=False):
        return coe(2, struct.pack("<BHBI", 0x50 if ca else 0x40, index, sub, 0))

    def download(index, sub, value, size):
        return coe(2, struct.pack("<BHBI", 0x23 | (4 - size) << 2, index, sub, value))

    preop = setup + al(2)
    op = al(4) + lrw + al(8) + lrw + tick(1000000) + lrw
    seeds = {
        "app-walk-to-op": preop + upload(0x1018, 1) + op,
        "app-sdo": preop + upload(0x1008, 0) + upload(0x1600, 0, True) + upload(0x1C12, 0, True) +
        download(0x6042, 0, 1500, 2) + download(0x2899, 0, 1, 2) + upload(0x1234, 0),
        "app-segmented": preop + coe(2, struct.pack("<BHBI", 0x21, 0x6042, 0, 2)) +
        coe(2, bytes([0x0B, 0x34, 0x12, 0, 0, 0, 0, 0])),
        "app-sdo-info": preop + coe(8, struct.pack("<BBHH", 1, 0, 0, 1)) + read_mbx * 8 +
        coe(8, struct.pack("<BBHH", 3, 0, 0, 0x1018)) +
        coe(8, struct.pack("<BBHHBB", 5, 0, 0, 0x6040, 0, 7)),
        "app-watchdog": preop + op + tick(150000000) + tick(150000000) + al(0x14),
        "app-refusals": setup + al(4) + al(0x13) + al(5) + al(1) + al(2) + al(8) + al(3),
        "esc-only": bytes([8 | 16]) + lrw + esc_op(0) + read_mbx + tick(200000000),
        # complete-access downloads of the mapping (a good one, then one the core refuses on the
        # way), a segmented one, then SAFE-OP with the new mapping
        "app-ca-download": preop +
        coe(2, struct.pack("<BHBIBBI", 0x31, 0x1600, 0, 6, 1, 0, 0x60400010)) +
        coe(2, struct.pack("<BHBIBBII", 0x31, 0x1600, 0, 10, 2, 0, 0x60420010, 0x10180010)) +
        coe(2, struct.pack("<BHBI", 0x31, 0x1A00, 0, 6)) +
        coe(2, bytes([0x00, 1, 0, 0x10, 0x00, 0x41, 0x60, 0])) +
        coe(2, bytes([0x10 | 0x01 | 6 << 1, 0x60, 0, 0, 0, 0, 0, 0])) +
        upload(0x1600, 0, True) + al(4),
        # the repeat request: SM1 activate bit 1 toggled after a read
        "app-repeat": preop + upload(0x1018, 1) +
        esc_op(0, ecat_frame(2, 0, 0x080E, bytes([0x03]))) + read_mbx +
        esc_op(0, ecat_frame(2, 0, 0x080E, bytes([0x01]))) + read_mbx,
    }
    return seeds


def write_raw(target, seeds):
    d = os.path.join(CORPUS, target)
    os.makedirs(d, exist_ok=True)
    for name, data in sorted(seeds.items()):
        with open(os.path.join(d, name), "wb") as f:
            f.write(data)


def write(target, seeds):
    d = os.path.join(CORPUS, target)
    os.makedirs(d, exist_ok=True)
    for name, seq in sorted(seeds.items()):
        missing = seq.ops - ENABLED.get(target, set(range(21)))
        assert not missing, f"{target}/{name} uses operations the target skips: {missing}"
        with open(os.path.join(d, name), "wb") as f:
            f.write(bytes(seq.b))


def main():
    if os.path.isdir(CORPUS):
        shutil.rmtree(CORPUS)
    dictionaries = [("test", DICT_TEST), ("sparse", DICT_SPARSE)] + \
        [(d, dict_of(d)) for d in DRIVES]
    for target, make in (("fuzz_nmt", nmt_seeds), ("fuzz_sdo", sdo_seeds),
                         ("fuzz_pdo_sync", pdo_seeds), ("fuzz_errctl", errctl_seeds)):
        seeds = {}
        for label, dictionary in dictionaries:
            for name, seq in make(dictionary).items():
                seeds[f"{name}-{label}"] = seq
        write(target, seeds)
    for drive in DRIVES:
        write("fuzz_drive_" + drive.replace("-", "_"), drive_seeds(drive))
    write_raw("fuzz_esc_frame", esc_seeds())
    print(f"corpus written to {os.path.relpath(CORPUS)} ({len(DRIVES)} drives)", file=sys.stderr)


if __name__ == "__main__":
    main()
