"""Crash-safe storage over vcan: canopen-drive itself is killed with SIGKILL at random moments
around a store command (0x1010 sub 1, 'save'), 100 times, and the store file must always give
back either the values before that save or the new ones, never a mix or a corrupt file.

One process per kill: its start-up with the same store file is the check of the previous kill
(the heartbeat time 0x1017 read back by SDO, no 'store ... ignored' message on stderr), then a
new value is written and the save is sent as a raw frame; the kill follows after a seeded random
delay scaled to the save's measured round trip and steered towards the file write, so that a
good share land inside it.
The file's state at the kill says where it landed:
  before  the file and no "<store>.tmp": the save had not started writing;
  during  "<store>.tmp" exists: written (partly) but not yet renamed over the store;
  after   the store file changed: renamed (the acknowledgement may or may not have gone out).

Environment: CANOPEN_STORE_KILLS (default 100), CANOPEN_STORE_KILL_SEED (default 1010).
"""
import os
import random
import signal
import struct
import time
from collections import Counter

from conftest import IFACE, TIMEOUT, Sim, make_node, remove_node
from drives import BY_ID

SAVE = 0x65766173  # "save"
KILLS = int(os.environ.get("CANOPEN_STORE_KILLS", "100"))
SEED = int(os.environ.get("CANOPEN_STORE_KILL_SEED", "1010"))
SAVER = 5          # node whose values are saved and killed around
BYSTANDER = 9      # node saved once at the start: its image must never change
BYSTANDER_HB = 777
SAVE_REQUEST = bytes([0x23, 0x10, 0x10, 0x01]) + struct.pack("<I", SAVE)


def start(store, recorder):
    mark = recorder.mark()
    sim = Sim(["--iface", IFACE, "--drive", "vf-s15", "--node-id", str(SAVER),
               "--drive", "vf-s15", "--node-id", str(BYSTANDER), "--store", str(store)])
    for nid in (SAVER, BYSTANDER):
        recorder.wait_frame(0x700 + nid, b"\x00", since=mark)
    return sim


def kill(sim):
    sim.proc.send_signal(signal.SIGKILL)
    rc = sim.proc.wait(TIMEOUT)
    for t in sim.threads:  # every stderr line of the process is in sim.err after this
        t.join(TIMEOUT)
    sim.proc.stdin.close()
    assert rc == -signal.SIGKILL, f"canopen-drive ended with {rc} before the kill"


def save_round_trip(network, recorder):
    """Seconds from sending the save request to its acknowledgement."""
    mark = recorder.mark()
    t0 = time.monotonic()
    network.send_message(0x600 + SAVER, SAVE_REQUEST)
    reply = recorder.wait_frame(0x580 + SAVER, since=mark)
    elapsed = time.monotonic() - t0
    assert reply.data[0] == 0x60, f"save refused: {bytes(reply.data).hex()}"
    return elapsed


def test_sigkill_around_saves_leaves_the_old_or_the_new_values(network, recorder, tmp_path,
                                                               capsys):
    drive = BY_ID["vf-s15"]
    store = tmp_path / "store.bin"
    tmp = tmp_path / "store.bin.tmp"
    saver = make_node(network, drive, SAVER)
    bystander = make_node(network, drive, BYSTANDER)
    rng = random.Random(SEED)
    try:
        # A first image for both nodes, and the save's round trip on this machine.
        sim = start(store, recorder)
        bystander.sdo[0x1017].raw = BYSTANDER_HB
        bystander.sdo.download(0x1010, 1, struct.pack("<I", SAVE))
        value = 1000
        saver.sdo[0x1017].raw = value
        trips = sorted(save_round_trip(network, recorder) for _ in range(7))
        save_time = trips[0]  # the fastest: the others carry scheduling noise
        kill(sim)
        tmp.unlink(missing_ok=True)

        # Delays are drawn from 0.5..1.5 times a centre that follows where the kills land
        # (shorter after a kill past the rename, longer after one before the write), so that
        # they gather around the write whatever the machine's load; the first is half the round
        # trip.
        centre = save_time / 2
        centres = []
        where = Counter()
        acked = 0
        t_begin = time.monotonic()
        for i in range(KILLS + 1):
            sim = start(store, recorder)
            got = saver.sdo[0x1017].raw
            assert got == value, (f"kill {i}: 0x1017 reads {got} after a restart, expected "
                                  f"{value} (seed {SEED})")
            assert bystander.sdo[0x1017].raw == BYSTANDER_HB, f"kill {i}: bystander changed"
            if i == KILLS:
                kill(sim)
                assert not any("store" in line for line in sim.err), sim.err
                break
            old, new = value, 1001 + i
            saver.sdo[0x1017].raw = new
            before = store.read_bytes()
            delay = centre * rng.uniform(0.5, 1.5)
            mark = recorder.mark()
            network.send_message(0x600 + SAVER, SAVE_REQUEST)
            time.sleep(delay)  # the kill moment, not a wait for anything
            kill(sim)
            # the start of this process read the file cleanly (its stderr is complete now)
            assert not any("store" in line for line in sim.err), (i, sim.err)
            if tmp.exists():
                state = "during"
                # a later save truncates it anyway; removed so the next kill is judged alone
                tmp.unlink()
            elif store.read_bytes() != before:
                state = "after"
            else:
                state = "before"
            where[state] += 1
            ack = recorder.since(mark, lambda m: m.arbitration_id == 0x580 + SAVER)
            if ack:
                acked += 1
                assert ack[0].data[0] == 0x60 and state == "after", (i, state, ack[0])
            value = new if state == "after" else old
            centres.append(centre)
            centre *= {"before": 1.1, "during": 1.0, "after": 0.9}[state]
        elapsed = time.monotonic() - t_begin
    finally:
        if sim.proc.poll() is None:
            kill(sim)
        remove_node(network, saver)
        remove_node(network, bystander)

    with capsys.disabled():
        print(f"\nstore kill: seed {SEED}, {KILLS} kills in {elapsed:.1f} s, save round trip "
              f"{save_time * 1e3:.2f} ms (delays around {min(centres) * 1e3:.2f} to "
              f"{max(centres) * 1e3:.2f} ms); landed "
              f"before the write {where['before']}, during it {where['during']}, after the "
              f"rename {where['after']} ({acked} acknowledged)")
    # The delays must really have exercised the write, not only its two sides (runs so far:
    # 18-39 of 100 during it; the bound leaves room for a loaded machine's scheduling).
    assert where["during"] >= KILLS // 20, where
    assert where["before"] > 0 and where["after"] > 0, where
