#!/usr/bin/env python3
"""gen_bench_eds.py - write the benchmark dictionaries (CiA 306 EDS).

    python3 tests/bench/gen_bench_eds.py > od/bench/bench.eds                 # the committed one
    python3 tests/bench/gen_bench_eds.py --pdos 64 --objects 1000 > scale.eds  # scaling runs

The default output is od/bench/bench.eds: a DS301-minimal dictionary shaped like CANopenNode's
example (example/DS301_profile.eds: 0x1000-0x1019, 4 RPDO + 4 TPDO with 8 mapping entries each,
COB-IDs invalid by default, 8 heartbeat consumers, a 16-deep 0x1003), so the headline footprint
row compares like with like, plus the few objects a benchmark needs:
  0x100C/0x100D  node guarding (CANopenNode's example has none; our feature set has it)
  0x1029         error behaviour
  0x2000         DOMAIN streamed by a hook: endless segmented/block transfers, one segment per
                 benchmark iteration
  0x2110         ARRAY of 8 INTEGER32, PDO-mappable both ways (CANopenNode v1's 'variable int32')
--pdos P adds P RPDOs and P TPDOs in total (valid, mapped onto 0x2110) and --objects N adds N
UNSIGNED16 manufacturer objects from 0x3000, for the "how cost grows" tables of docs/performance.md.
"""

import argparse
import sys


def var(index, name, dtype, access, default="", mapping=0, sub=None, extra=""):
    head = f"[{index:04X}]" if sub is None else f"[{index:04X}sub{sub:X}]"
    lines = [head, f"ParameterName={name}", "ObjectType=0x7", f"DataType=0x{dtype:04X}",
             f"AccessType={access}"]
    if default != "":
        lines.append(f"DefaultValue={default}")
    lines.append(f"PDOMapping={mapping}")
    if extra:
        lines.append(extra)
    return "\n".join(lines) + "\n"


def obj(index, name, code, subs):
    """subs: list of (sub, name, dtype, access, default, mapping)."""
    out = [f"[{index:04X}]\nParameterName={name}\nObjectType=0x{code:X}\nSubNumber={len(subs)}\n"]
    for s, sname, dtype, access, default, mapping in subs:
        out.append(var(index, sname, dtype, access, default, mapping, sub=s))
    return out


U8, U16, U32, I32, VSTR, DOMAIN = 0x5, 0x6, 0x7, 0x4, 0x9, 0xF


def build(pdos_extra, objects_extra):
    sections = []  # (index, text)

    def add(index, text):
        sections.append((index, text if isinstance(text, str) else "\n".join(text)))

    add(0x1000, var(0x1000, "Device type", U32, "ro", "0x00000000"))
    add(0x1001, var(0x1001, "Error register", U8, "ro", "0x00", mapping=1))
    add(0x1003, obj(0x1003, "Pre-defined error field", 0x8,
                    [(0, "Number of errors", U8, "rw", "0", 0)] +
                    [(i, f"Standard error field {i}", U32, "ro", "0", 0) for i in range(1, 17)]))
    add(0x1005, var(0x1005, "COB-ID SYNC message", U32, "rw", "0x00000080"))
    add(0x1006, var(0x1006, "Communication cycle period", U32, "rw", "0"))
    add(0x1007, var(0x1007, "Synchronous window length", U32, "rw", "0"))
    add(0x1008, var(0x1008, "Manufacturer device name", VSTR, "const", "canopen-drive bench"))
    add(0x100C, var(0x100C, "Guard time", U16, "rw", "0"))
    add(0x100D, var(0x100D, "Life time factor", U8, "rw", "0"))
    add(0x1010, obj(0x1010, "Store parameters", 0x8,
                    [(0, "Highest sub-index supported", U8, "ro", "0x04", 0)] +
                    [(i, n, U32, "rw", "0x00000001", 0) for i, n in
                     ((1, "Save all parameters"), (2, "Save communication parameters"),
                      (3, "Save application parameters"), (4, "Save manufacturer parameters"))]))
    add(0x1011, obj(0x1011, "Restore default parameters", 0x8,
                    [(0, "Highest sub-index supported", U8, "ro", "0x04", 0)] +
                    [(i, n, U32, "rw", "0x00000001", 0) for i, n in
                     ((1, "Restore all default parameters"),
                      (2, "Restore communication default parameters"),
                      (3, "Restore application default parameters"),
                      (4, "Restore manufacturer default parameters"))]))
    add(0x1014, var(0x1014, "COB-ID EMCY", U32, "rw", "$NODEID+0x80"))
    add(0x1015, var(0x1015, "Inhibit time EMCY", U16, "rw", "0"))
    add(0x1016, obj(0x1016, "Consumer heartbeat time", 0x8,
                    [(0, "Highest sub-index supported", U8, "ro", "0x08", 0)] +
                    [(i, "Consumer heartbeat time", U32, "rw", "0x00000000", 0)
                     for i in range(1, 9)]))
    add(0x1017, var(0x1017, "Producer heartbeat time", U16, "rw", "0"))
    add(0x1018, obj(0x1018, "Identity", 0x9,
                    [(0, "Highest sub-index supported", U8, "ro", "0x04", 0),
                     (1, "Vendor-ID", U32, "ro", "0x00000000", 0),
                     (2, "Product code", U32, "ro", "0x00000000", 0),
                     (3, "Revision number", U32, "ro", "0x00000000", 0),
                     (4, "Serial number", U32, "ro", "0x00000000", 0)]))
    add(0x1019, var(0x1019, "Synchronous counter overflow value", U8, "rw", "0"))
    add(0x1029, obj(0x1029, "Error behavior", 0x8,
                    [(0, "Highest sub-index supported", U8, "ro", "0x01", 0),
                     (1, "Communication error", U8, "rw", "0x00", 0)]))
    add(0x1200, obj(0x1200, "SDO server parameter", 0x9,
                    [(0, "Highest sub-index supported", U8, "ro", "2", 0),
                     (1, "COB-ID client to server (rx)", U32, "ro", "$NODEID+0x600", 0),
                     (2, "COB-ID server to client (tx)", U32, "ro", "$NODEID+0x580", 0)]))

    n_pdo = 4 + pdos_extra // 2
    for p in range(n_pdo):
        base = (0x200, 0x300, 0x400, 0x500)[p] if p < 4 else None
        cob = f"$NODEID+0x{0x80000000 + base:08X}" if base is not None else "0x80000000"
        add(0x1400 + p, obj(0x1400 + p, f"RPDO{p + 1} communication parameter", 0x9,
                            [(0, "Highest sub-index supported", U8, "ro", "0x05", 0),
                             (1, "COB-ID used by RPDO", U32, "rw", cob, 0),
                             (2, "Transmission type", U8, "rw", "254", 0),
                             (5, "Event timer", U16, "rw", "0", 0)]))
        add(0x1600 + p, obj(0x1600 + p, f"RPDO{p + 1} mapping parameter", 0x9,
                            [(0, "Number of mapped application objects in PDO", U8, "rw", "0", 0)] +
                            [(i, f"Application object {i}", U32, "rw", "0x00000000", 0)
                             for i in range(1, 9)]))
        tbase = (0x180, 0x280, 0x380, 0x480)[p] if p < 4 else None
        tcob = f"$NODEID+0x{0xC0000000 + tbase:08X}" if tbase is not None else "0xC0000000"
        add(0x1800 + p, obj(0x1800 + p, f"TPDO{p + 1} communication parameter", 0x9,
                            [(0, "Highest sub-index supported", U8, "ro", "0x06", 0),
                             (1, "COB-ID used by TPDO", U32, "rw", tcob, 0),
                             (2, "Transmission type", U8, "rw", "254", 0),
                             (3, "Inhibit time", U16, "rw", "0", 0),
                             (5, "Event timer", U16, "rw", "0", 0),
                             (6, "SYNC start value", U8, "rw", "0", 0)]))
        add(0x1A00 + p, obj(0x1A00 + p, f"TPDO{p + 1} mapping parameter", 0x9,
                            [(0, "Number of mapped application objects in PDO", U8, "rw", "0", 0)] +
                            [(i, f"Application object {i}", U32, "rw", "0x00000000", 0)
                             for i in range(1, 9)]))

    add(0x2000, var(0x2000, "Bench data (DOMAIN, streamed by a hook)", DOMAIN, "rw"))
    add(0x2110, obj(0x2110, "Variable int32", 0x8,
                    [(0, "Highest sub-index supported", U8, "ro", "0x08", 0)] +
                    [(i, f"Variable int32 {i}", I32, "rw", "0", 1) for i in range(1, 9)]))
    for k in range(objects_extra):
        add(0x3000 + k, var(0x3000 + k, f"Scale object {k}", U16, "rw", str(k & 0xFFFF)))

    sections.sort()
    return sections, n_pdo


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pdos", type=int, default=0, help="extra PDOs (RPDOs + TPDOs), even")
    ap.add_argument("--objects", type=int, default=0, help="extra UNSIGNED16 objects at 0x3000")
    args = ap.parse_args(argv)
    if args.pdos < 0 or args.pdos % 2 or 4 + args.pdos // 2 > 512:
        ap.error("--pdos: an even number, at most 1016")
    if not 0 <= args.objects <= 0x6000:
        ap.error("--objects: 0..24576")
    sections, n_pdo = build(args.pdos, args.objects)
    mandatory = [0x1000, 0x1001, 0x1018]
    optional = [i for i, _ in sections if i < 0x2000 and i not in mandatory]
    manufacturer = [i for i, _ in sections if i >= 0x2000]
    out = sys.stdout
    generated = "" if (args.pdos, args.objects) == (0, 0) else \
        f" (scaling variant: --pdos {args.pdos} --objects {args.objects})"
    out.write(f"""; od/bench/bench.eds - benchmark dictionary{generated}; written by
; tests/bench/gen_bench_eds.py, do not edit by hand. Not a drive: a DS301-minimal dictionary shaped
; like CANopenNode's example/DS301_profile.eds (4+4 PDOs of 8 entries, COB-IDs invalid by default,
; 8 heartbeat consumers, 16-deep 0x1003), for the side-by-side numbers of docs/performance.md.
; 0x100C/0x100D guarding and 0x1029 are added because our feature set has them; 0x2000 (DOMAIN)
; and 0x2110 (8 x INTEGER32, mappable) are what the benchmark transfers and maps.

[FileInfo]
FileName=bench.eds
FileVersion=1
FileRevision=0
EDSVersion=4.0
Description=Benchmark dictionary (DS301-minimal, CANopenNode-example-like), not a real drive
CreatedBy=canopen-drive project
ModifiedBy=canopen-drive project

[DeviceInfo]
VendorName=canopen-drive bench
VendorNumber=0x00000000
ProductName=Benchmark dictionary
ProductNumber=0x00000000
RevisionNumber=0x00000000
OrderCode=bench
BaudRate_10=1
BaudRate_20=1
BaudRate_50=1
BaudRate_125=1
BaudRate_250=1
BaudRate_500=1
BaudRate_800=1
BaudRate_1000=1
SimpleBootUpMaster=0
SimpleBootUpSlave=1
Granularity=8
DynamicChannelsSupported=0
CompactPDO=0
GroupMessaging=0
NrOfRXPDO={n_pdo}
NrOfTXPDO={n_pdo}
LSS_Supported=0

[DummyUsage]
Dummy0001=0
Dummy0002=0
Dummy0003=0
Dummy0004=0
Dummy0005=0
Dummy0006=0
Dummy0007=0

""")
    for title, lst in (("MandatoryObjects", mandatory), ("OptionalObjects", optional),
                       ("ManufacturerObjects", manufacturer)):
        out.write(f"[{title}]\nSupportedObjects={len(lst)}\n")
        for n, i in enumerate(lst, 1):
            out.write(f"{n}=0x{i:04X}\n")
        out.write("\n")
    for _, text in sections:
        out.write(text + "\n")


if __name__ == "__main__":
    main()
