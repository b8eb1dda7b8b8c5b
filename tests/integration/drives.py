"""What the integration suite needs to know about each simulated drive, taken from its NOTES.md.

Everything generic (objects, defaults, limits, access, mappability) comes from the drive's EDS
through python-canopen; only the facts an EDS cannot say are listed here, each with its source.
"""
import csv
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Tuple

ROOT = Path(__file__).resolve().parents[2]


@dataclass
class Drive:
    id: str
    node_id: int                  # node-ID the suite gives it (several drives run together)
    cia402: bool                  # CiA 402 state machine on 0x6040/0x6041
    # SDO writes (index, sub, value) that hand run/stop and the reference to CANopen
    run_from_canopen: List[Tuple[int, int, int]] = field(default_factory=list)
    trip: Optional[int] = None    # a trip code for `fault NODE TRIP`
    has_store: bool = False       # 0x1010/0x1011 exist
    # Objects whose value at run time is not the EDS default, and why (NOTES.md)
    live: Dict[Tuple[int, int], str] = field(default_factory=dict)
    # Index ranges the SDO server hides (abort 0x06020000) although the EDS lists them
    sdo_hidden: List[Tuple[int, int]] = field(default_factory=list)
    # Objects a write-back sweep must not touch: writing them does something (a command)
    commands: Dict[Tuple[int, int], str] = field(default_factory=dict)
    tpdo_for_remap: int = 1       # the TPDO the remap test reconfigures
    rpdo_for_remap: int = 1       # the RPDO the remap test reconfigures
    rpdo_object: Optional[Tuple[int, int]] = None  # what it maps (default: the first candidate)
    static_pdos: bool = False     # PDO COB-IDs and mappings are fixed (read-only in the EDS)
    # SDO writes over the drive's own parameter channel that gate its commands (Sourcetronic)
    gate_params: List[Tuple[int, int]] = field(default_factory=list)
    notes: str = ""

    @property
    def eds(self) -> Path:
        return ROOT / "od" / self.id / f"{self.id}.eds"

    def faults(self) -> List[dict]:
        with open(ROOT / "od" / self.id / "faults.csv", newline="") as f:
            return list(csv.DictReader(f))

    def fault_row(self, trip: int) -> dict:
        for row in self.faults():
            if row["trip_code"] and int(row["trip_code"], 0) == trip:
                return row
        raise KeyError(f"{self.id}: no trip 0x{trip:X} in faults.csv")

    def hidden(self, index: int) -> bool:
        return any(lo <= index <= hi for lo, hi in self.sdo_hidden)


DRIVES = [
    Drive(
        id="vf-s15",
        node_id=5,
        cia402=True,
        # §3.1, §5, §7: CMOd = 3 (run/stop from CANopen), FMOd = 6 (frequency from CANopen)
        run_from_canopen=[(0x2003, 0, 3), (0x2004, 0, 6)],
        trip=0x01,                # OC1, EMCY 0x2310
        has_store=True,
        live={
            (0x6041, 0): "statusword: the state machine's state (B5)",
            (0x4701, 0): "C701 reads the commissioned node-ID (Choices 7)",
        },
        commands={
            (0x6040, 0): "controlword (B5)",
            (0x2899, 0): "F899 = 1 restarts the CANopen function (B6)",
            (0x2A00, 0): "FA00 reset command (B6)",
            (0x2A04, 0): "FA04 reset command (B6)",
            (0x2A06, 0): "FA06 reset command (B6)",
        },
    ),
    Drive(
        id="vf-mb1-ecat",
        node_id=6,
        cia402=True,
        # Modes/configurations: CiA 402 profile = CMOd 4, FMOd 7
        run_from_canopen=[(0x2003, 0, 4), (0x2004, 0, 7)],
        trip=0x01,                # OC1, EMCY 0x2310
        live={
            (0x6041, 0): "statusword",
            (0x2D01, 0): "FD01 inverter operating status, a real-time monitor",
            (0x4402, 0): "C402 reads the CAN node-ID (C24)",
        },
        commands={
            (0x6040, 0): "controlword",
            (0x2A00, 0): "FA00 reset command, reads back 0 (C22)",
            (0x2899, 0): "F899 = 1 restarts the communication function (B1.6)",
        },
    ),
    Drive(
        id="benshaw-rsi",
        node_id=7,
        cia402=True,
        # B10: dr.06 Cmd Source = 4 (FieldBus), dr.07 Freq Ref Src = 8 (Fieldbus)
        run_from_canopen=[(0x4010, 7, 4), (0x4010, 8, 8)],
        trip=0x2310,              # OverCurrent1
        static_pdos=True,         # mappings fixed by CM.11 (modes.csv), entries ro (B6.8)
        live={
            (0x6041, 0): "statusword",
            (0x4016, 0x07): "CM.07 FBus ID reads the active node-ID (B14)",
            (0x4016, 0x3D): "CM.61 Station ID alias of CM.07 (B14)",
        },
        commands={
            (0x6040, 0): "controlword",
            (0x4016, 0x5E): "CM.94 Comm Update applies pending CANopen settings (B14)",
            (0x4016, 0x43): "CM.67 Comm Update alias (B14)",
        },
    ),
    Drive(
        id="vacon-optc6",
        node_id=8,
        cia402=True,
        trip=53,                  # Fieldbus Fault, EMCY 0x8130
        static_pdos=True,         # COB-IDs and mappings are ro, set by the Operate mode (B4)
        tpdo_for_remap=6,         # TPDO6 (6041 + 6044): type and event timer are rw
        rpdo_for_remap=6,         # RPDO6 (6040 + 6042)
        live={
            (0x6041, 0): "statusword",
            (0x2836, 0): "NX status word, computed from the drive state (B8)",
        },
        commands={
            (0x6040, 0): "controlword",
            (0x2000, 0): "AnyParameter read request (B9)",
            (0x2002, 0): "AnyParameter write request (B9)",
        },
    ),
    Drive(
        id="sourcetronic-st600",
        node_id=3,                # the manual's examples use node 3
        cia402=False,             # own command codes in 0x2101, state codes in 0x2001 (B10)
        trip=0x01,                # OUT1, EMCY 0x3000 (§3.4.8 example)
        sdo_hidden=[(0x4000, 0x5FFF)],  # drive parameter image, not SDO-visible (B15)
        # B10 gate: P00.01 = 2 (run command from communication), P00.02 = 1 (CANopen channel)
        gate_params=[(0x0001, 2), (0x0002, 1)],
        commands={
            (0x2101, 0): "CW command code (B9)",
        },
        tpdo_for_remap=2,         # TPDO1 is fixed to type 255 with no event timer (B8)
        rpdo_for_remap=2,         # RPDO1 is the parameter channel and must have DLC 6 (B8)
        rpdo_object=(0x2100, 3),  # setting 1 (B10)
    ),
]

BY_ID = {d.id: d for d in DRIVES}
