"""A DBC file of simulated drives' PDOs, so cantools or SavvyCAN decode a --trace.

    python -m canopen_sim.dbc --eds od/vf-s15/vf-s15.eds --node-id 5 > vf-s15.dbc
    python -m canopen_sim.dbc --eds od/vf-s15/vf-s15.eds --node-id 5 --control /tmp/sim.sock

The layout is the EDS's default mapping, or with --control (or `layout=`) the mapping in force in
a running simulator (its `pdo NODE` command). One message per valid PDO: TPDOs are sent by the
drive, RPDOs by the master; one signal per mapped object, little-endian as CANopen packs them,
signed and float types as the object's data type says. Dummy entries (0x0001-0x0007) leave a gap.
Needs python-canopen to read the EDS.
"""
import argparse
import re
import sys

PDO_KINDS = (("rpdo", 0x1400, 0x1600), ("tpdo", 0x1800, 0x1A00))
_SIGNED = {0x02, 0x03, 0x04, 0x10, 0x12, 0x13, 0x14, 0x15}   # INTEGER8..64
_FLOAT = {0x08: 1, 0x11: 2}                                  # REAL32, REAL64


def default_layout(od):
    """[(kind, number, cob_id_word, [mapping words])] from a python-canopen dictionary's
    defaults (import_od with the node-ID, so $NODEID is applied)."""
    out = []
    for kind, comm, mapping in PDO_KINDS:
        for i in range(512):
            if comm + i not in od or mapping + i not in od:
                continue
            c, m = od[comm + i], od[mapping + i]
            cob = c[1].default if 1 in c.subindices else 0x80000000
            count = m[0].default if 0 in m.subindices else 0
            words = [m[s].default for s in range(1, count + 1) if s in m.subindices]
            out.append((kind, i + 1, int(cob), [int(w) for w in words]))
    return out


def parse_layout(lines):
    """The same from a simulator's `pdo NODE` answer ("tpdo 1 0x00000185 0x60410010 ...")."""
    out = []
    for line in lines:
        words = line.split()
        out.append((words[0], int(words[1]), int(words[2], 16), [int(w, 16) for w in words[3:]]))
    return out


def _ident(text, limit=40):
    name = re.sub(r"[^A-Za-z0-9_]+", "_", text).strip("_") or "x"
    if name[0].isdigit():
        name = "_" + name
    return name[:limit]


def _object(od, index, sub):
    try:
        obj = od[index]
    except KeyError:
        return None
    if hasattr(obj, "subindices") and obj.subindices:
        return obj.subindices.get(sub)
    return obj


def messages(od, node_id, drive_name, layout):
    """DBC message blocks (strings) of one node."""
    node = _ident(f"{drive_name}_{node_id}")
    blocks = []
    for kind, number, cob, words in layout:
        if cob & 0x80000000 or not words:
            continue  # not valid, or nothing mapped
        sender, receiver = (node, "Master") if kind == "tpdo" else ("Master", node)
        signals, bit, seen = [], 0, set()
        for word in words:
            index, sub, bits = word >> 16, (word >> 8) & 0xFF, word & 0xFF
            var = _object(od, index, sub) if index >= 0x1000 else None
            if var is not None and bits:
                name = _ident(f"{var.name}_{index:04X}" + (f"_{sub}" if sub else ""))
                base, k = name, 2
                while name in seen:
                    name, k = f"{base}_{k}", k + 1
                seen.add(name)
                signed = var.data_type in _SIGNED
                if signed:
                    lo, hi = -(1 << (bits - 1)), (1 << (bits - 1)) - 1
                else:
                    lo, hi = 0, (1 << bits) - 1
                sign = "-" if signed else "+"
                signals.append((f' SG_ {name} : {bit}|{bits}@1{sign} (1,0) [{lo}|{hi}] "" '
                                f'{receiver}', _FLOAT.get(var.data_type), name))
            bit += bits
        length = (bit + 7) // 8
        can_id = cob & 0x7FF
        msg = _ident(f"{kind.upper()}{number}_{node}")
        lines = [f"BO_ {can_id} {msg}: {length} {sender}"] + [s for s, _, _ in signals]
        floats = [(can_id, name, kind_) for _, kind_, name in signals if kind_]
        blocks.append(("\n".join(lines), floats))
    return node, blocks


def make_dbc(nodes):
    """A DBC file's text. nodes: [(od, node_id, drive_name, layout or None), ...]; layout None
    is the dictionary's default mapping."""
    names, bodies, floats = [], [], []
    for od, node_id, drive_name, layout in nodes:
        name, blocks = messages(od, node_id, drive_name,
                                default_layout(od) if layout is None else layout)
        names.append(name)
        for text, fl in blocks:
            bodies.append(text)
            floats += fl
    out = ['VERSION ""', "", "NS_ :", "", "BS_:", "", "BU_: Master " + " ".join(names), ""]
    for body in bodies:
        out += [body, ""]
    for can_id, name, kind in floats:
        out.append(f"SIG_VALTYPE_ {can_id} {name} : {kind};")
    return "\n".join(out) + "\n"


def main(argv=None):
    p = argparse.ArgumentParser(description="DBC of simulated drives' PDOs (stdout)")
    p.add_argument("--eds", action="append", required=True, help="the drive's EDS (repeatable)")
    p.add_argument("--node-id", action="append", type=lambda s: int(s, 0), required=True,
                   help="its node-ID (one per --eds)")
    p.add_argument("--control", help="a running simulator's control socket: the mapping in "
                                     "force instead of the EDS default")
    args = p.parse_args(argv)
    if len(args.eds) != len(args.node_id):
        p.error("give one --node-id per --eds")
    import canopen  # the EDS reader
    from pathlib import Path
    ctl = None
    if args.control:
        from .control import Control
        ctl = Control(args.control, subscribe=False)
    nodes = []
    for eds, node_id in zip(args.eds, args.node_id):
        od = canopen.import_od(eds, node_id)
        layout = parse_layout(ctl.command(f"pdo {node_id}")) if ctl else None
        nodes.append((od, node_id, Path(eds).stem, layout))
    sys.stdout.write(make_dbc(nodes))
    if ctl:
        ctl.close()


if __name__ == "__main__":
    main()
