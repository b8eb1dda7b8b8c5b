#!/usr/bin/env python3
"""eds2sii.py - the SII EEPROM image and the ESI file of an EtherCAT (CoE) slave, from its EDS.

    python3 tools/eds2sii.py EDS --choices ecat.ini --id ID
                             [--out-c FILE.c] [--out-h FILE.h] [--out-xml FILE.xml] [--out-bin FILE]

The EDS is the CoE object dictionary (read exactly as tools/eds2c.py reads it, with the same
checks); the choices file (INI: [Device] [Esc] [Eeprom] [Mailbox] [ProcessData] [Fmmu] [CoE], see
od/vf-mb1-ecat/ecat.ini) holds what a dictionary cannot say: the ESC, the SyncManager layout,
names. Outputs, all deterministic:
  * FILE.c: `const uint8_t co_sii_<id>[]`, the EEPROM content from word 0 to the END category;
  * FILE.h: its declaration, its size and every layout value the ESC emulation and the CoE
    application layer must honour (identity, SyncManager addresses/lengths/control bytes, mailbox
    sizes, CoE details), as CO_SII_<ID>_* macros;
  * FILE.xml: an ETG.2000 EtherCATInfo (ESI) file describing the same device;
  * FILE (--out-bin): the raw image, for EEPROM tools.
On bad input it prints one `FILE:LINE: error: reason` line per problem (FILE is the EDS or the
choices file), writes nothing and exits with status 1.

SII LAYOUT (ETG.1000.6 §5.4, ETG.2010; all values little-endian)
  words 0x00-0x07  ESC configuration area: PDI control / ESC configuration, PDI configuration,
                   SYNC impulse length, extended PDI configuration, configured station alias,
                   2 reserved words, checksum (low byte: CRC-8, polynomial x^8+x^2+x+1 = 0x07,
                   initial value 0xFF, not reflected, no final XOR, over bytes 0-13)
  words 0x08-0x0F  vendor ID, product code, revision number, serial number (0x1018 sub 1-4)
  words 0x10-0x13  execution delay, port 0/1 delays, reserved: 0
  words 0x14-0x17  bootstrap mailbox offsets and sizes: 0 (no bootstrap)
  words 0x18-0x1B  standard receive (SM0) and send (SM1) mailbox offset and size
  word  0x1C       mailbox protocols (0x01 AoE, 0x02 EoE, 0x04 CoE, 0x08 FoE, 0x10 SoE, 0x20 VoE)
  words 0x1D-0x3D  reserved: 0
  word  0x3E       EEPROM size in KiBit - 1;   word 0x3F  version (1)
  from word 0x40   categories, each: type word, length word (data words), data:
                   STRINGS (10), GENERAL (30), FMMU (40), SYNCM (41), TXPDO (50), RXPDO (51),
                   then END (0xFFFF). A master reading past the image gets 0xFFFF words (an
                   unprogrammed EEPROM), so the image itself stops at END.

WHAT COMES FROM WHERE
  EDS 0x1018 sub 1-4   identity (sub 4 may be absent: serial 0); [DeviceInfo] VendorNumber,
                       ProductNumber, RevisionNumber must agree with it
  EDS [DeviceInfo]     ProductName -> device name, OrderCode -> order string, VendorName -> ESI
  EDS 0x1000           profile number (low 16 bits) and additional information (ESI Profile);
                       profile 402 -> GENERAL "DS402 channels" = 1
  EDS 0x1600-0x17FF,   RxPDOs / TxPDOs with their default mapping (the first sub 0 entries);
      0x1A00-0x1BFF    entry names and data types from the mapped objects
  EDS 0x1C12/0x1C13    the PDO assignment if present (then the choices file must not give one),
                       otherwise the choices' RxPdoAssign/TxPdoAssign; SM2/SM3 lengths are the
                       sizes of the assigned PDOs' default mappings
  EDS 0x1C00           if present, must give SM types 1, 2, 3, 4 for SM0-SM3
  CoE details          SDO always; SDO info, complete access, PDO upload from the choices; PDO
                       assign if 0x1C12 and 0x1C13 exist with a writable sub 0; PDO configuration
                       if every mapping object has a writable sub 0
"""

from __future__ import annotations

import argparse
import hashlib
import os
import re
import struct
import sys
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import eds2c  # noqa: E402  (the project's EDS reader: same checks, same error format)

# Category types (ETG.1000.6 §5.4)
CAT_STRINGS, CAT_GENERAL, CAT_FMMU, CAT_SYNCM, CAT_TXPDO, CAT_RXPDO = 10, 30, 40, 41, 50, 51
CAT_END = 0xFFFF

MBX_PROTOCOLS = {"AoE": 0x01, "EoE": 0x02, "CoE": 0x04, "FoE": 0x08, "SoE": 0x10, "VoE": 0x20}
FMMU_USAGE = {"Outputs": 1, "Inputs": 2, "MBoxState": 3}
PORT_TYPES = {"Unused": (0x0, " "), "MII": (0x1, "Y"), "EBUS": (0x3, "K")}
# SII GENERAL CoE details bits
COE_SDO, COE_SDO_INFO, COE_PDO_ASSIGN, COE_PDO_CONFIG, COE_PDO_UPLOAD, COE_COMPLETE = \
    0x01, 0x02, 0x04, 0x08, 0x10, 0x20
# SYNCM SM types, SyncManager n = index n
SM_MBX_OUT, SM_MBX_IN, SM_OUTPUTS, SM_INPUTS = 1, 2, 3, 4
# The largest mailbox one datagram carries in one Ethernet frame: 1500 - 2 (EtherCAT header)
# - 10 (datagram header) - 2 (working counter).
MAX_MAILBOX = 1486
# mailbox header 6 + CoE header 2 + SDO command, index, sub-index, data 8: one expedited SDO
MIN_MAILBOX = 16
# A master may cache only the first 4 KiB of the SII (SOEM's EC_MAXEEPBUF); keep all inside.
MAX_IMAGE = 4096
# Masters truncate the slave name (string 1); SOEM keeps 40 characters.
MAX_NAME = 40
ESC_RAM_START = 0x1000

# CoE data type -> ESI DataType name (ETG.2000 base types); strings get their length appended
ESI_TYPES = {
    0x01: "BOOL", 0x02: "SINT", 0x03: "INT", 0x04: "DINT", 0x05: "USINT", 0x06: "UINT",
    0x07: "UDINT", 0x08: "REAL", 0x09: "STRING", 0x0A: "OCTET_STRING", 0x0B: "UNICODE_STRING",
    0x10: "INT24", 0x11: "LREAL", 0x12: "INT40", 0x13: "INT48", 0x14: "INT56", 0x15: "LINT",
    0x16: "UINT24", 0x18: "UINT40", 0x19: "UINT48", 0x1A: "UINT56", 0x1B: "ULINT",
}


def crc8_sii(data):
    """The SII checksum (ETG.1000.6 §5.4): CRC-8, polynomial 0x07, initial value 0xFF, MSB first,
    no final XOR."""
    crc = 0xFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = ((crc << 1) ^ 0x07) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc


# --------------------------------------------------------------------------------------------
# The choices file.
# --------------------------------------------------------------------------------------------

def _int(lo, hi):
    def parse(text):
        v = int(text, 0)
        if not lo <= v <= hi:
            raise ValueError(f"{text} outside {lo}-{hi}")
        return v
    return parse


def _bool(text):
    if text not in ("0", "1"):
        raise ValueError(f"{text!r} is not 0 or 1")
    return text == "1"


def _text(limit):
    def parse(text):
        if not text:
            raise ValueError("empty")
        if not all(0x20 <= ord(c) < 0x7F for c in text):
            raise ValueError(f"{text!r} has characters outside printable ASCII")
        if len(text) > limit:
            raise ValueError(f"{text!r} is longer than {limit} characters")
        return text
    return parse


def _names(allowed, limit):
    def parse(text):
        items = [t.strip() for t in text.split(",")]
        for t in items:
            if t not in allowed:
                raise ValueError(f"{t!r} is not one of {', '.join(allowed)}")
        if len(items) > limit:
            raise ValueError(f"at most {limit} items")
        return items
    return parse


def _indices(lo, hi):
    def parse(text):
        out = []
        for t in text.split(","):
            v = int(t.strip(), 0)
            if not lo <= v <= hi:
                raise ValueError(f"{t.strip()} outside 0x{lo:04X}-0x{hi:04X}")
            if v in out:
                raise ValueError(f"0x{v:04X} listed twice")
            out.append(v)
        return out
    return parse


U8, U16 = _int(0, 0xFF), _int(0, 0xFFFF)
# section -> key -> (parser, required)
SCHEMA = {
    "Device": {"Type": (_text(MAX_NAME), True), "GroupType": (_text(255), True),
               "GroupName": (_text(255), True),
               "Ports": (_names(tuple(PORT_TYPES), 4), True)},
    "Esc": {"Type": (U8, True), "Revision": (U8, True), "Build": (U16, True),
            "Fmmus": (_int(1, 16), True), "SyncManagers": (_int(4, 16), True),
            "RamKiB": (_int(1, 60), True), "PdiControl": (U8, True), "EscConfig": (U8, True),
            "PdiConfig": (U16, True), "SyncImpulse": (U16, True), "PdiConfig2": (U16, True),
            "Alias": (U16, True)},
    "Eeprom": {"ByteSize": (_int(128, 0x10000), True), "Version": (U16, True)},
    "Mailbox": {"Protocols": (_names(tuple(MBX_PROTOCOLS), 6), True),
                "OutStart": (U16, True), "OutSize": (_int(MIN_MAILBOX, MAX_MAILBOX), True),
                "InStart": (U16, True), "InSize": (_int(MIN_MAILBOX, MAX_MAILBOX), True),
                "OutControl": (U8, True), "InControl": (U8, True)},
    "ProcessData": {"OutputsStart": (U16, True), "OutputsMaxSize": (_int(1, 0xFFFF), True),
                    "InputsStart": (U16, True), "InputsMaxSize": (_int(1, 0xFFFF), True),
                    "OutputsControl": (U8, True), "InputsControl": (U8, True),
                    "RxPdoAssign": (_indices(0x1600, 0x17FF), False),
                    "TxPdoAssign": (_indices(0x1A00, 0x1BFF), False)},
    "Fmmu": {"Usage": (_names(tuple(FMMU_USAGE), 16), True)},
    "CoE": {"SdoInfo": (_bool, True), "CompleteAccess": (_bool, True),
            "PdoUpload": (_bool, True)},
}


class Choices:
    """The parsed choices file: values[section][key], line(section, key)."""

    def __init__(self, path, problems):
        self.raw = eds2c.RawEds(path, problems)
        self.values = {}
        if problems.items:
            return
        for sec in self.raw.sections:
            if sec.name not in SCHEMA:
                problems.add(sec.line, f"unknown section [{sec.name}] (known: "
                             f"{', '.join(SCHEMA)})")
        for name, keys in SCHEMA.items():
            sec = self.raw.by_name.get(name)
            vals = self.values.setdefault(name, {})
            if sec is None:
                problems.add(1, f"missing section [{name}]")
                continue
            for key in sec.keys:
                if key not in keys:
                    problems.add(sec.line_of(key), f"[{name}] unknown key {key} (known: "
                                 f"{', '.join(keys)})")
            for key, (parse, required) in keys.items():
                if key not in sec.keys:
                    if required:
                        problems.add(sec.line, f"[{name}] lacks {key}")
                    continue
                try:
                    vals[key] = parse(sec.get(key))
                except ValueError as e:
                    problems.add(sec.line_of(key), f"[{name}] {key}: {e}")

    def __getitem__(self, section):
        return self.values[section]

    def line(self, section, key=None):
        sec = self.raw.by_name.get(section)
        if sec is None:
            return 1
        return sec.line_of(key) if key else sec.line


# --------------------------------------------------------------------------------------------
# The device model: EDS + choices, checked against each other.
# --------------------------------------------------------------------------------------------

class SyncManager:
    def __init__(self, number, kind, start, length, control, max_size, line):
        self.number = number
        self.kind = kind            # SM_MBX_OUT ... SM_INPUTS
        self.start = start
        self.length = length        # SII/ESI default length
        self.control = control
        self.max_size = max_size
        self.enable = 1 if length else 0
        self.line = line            # choices line of its start address

    @property
    def footprint(self):
        """ESC RAM the SyncManager occupies: a buffered one uses three buffers of its length
        (Beckhoff, EtherCAT Slave Controller Technology, section I, SyncManager buffered mode)."""
        return self.max_size * (3 if self.kind in (SM_OUTPUTS, SM_INPUTS) else 1)


class Pdo:
    def __init__(self, index, name, entries, sm):
        self.index = index
        self.name = name
        self.entries = entries      # [(index, sub, bits, data type, name)]
        self.sm = sm                # 2/3, or None when not assigned

    @property
    def bits(self):
        return sum(e[2] for e in self.entries)


class Device:
    pass


def _by_index(entries):
    return {e.index: e for e in entries}


def _sub(entry, subindex):
    for s in entry.subs:
        if s.subindex == subindex:
            return s
    return None


def model(eds_path, entries, ch, eds_problems, ch_problems):
    """Everything the outputs need, checked. Problems go to the file they concern."""
    d = Device()
    raw = eds2c.RawEds(eds_path, eds_problems)
    objs = _by_index(entries)
    info = raw.by_name.get("DeviceInfo")

    # --- identity: 0x1018 (eds2c checked the object and its sub 1) ---
    ident = objs[0x1018]
    names = {1: "vendor ID", 2: "product code", 3: "revision number", 4: "serial number"}
    d.identity = {}
    for sub, what in names.items():
        s = _sub(ident, sub)
        if s is None:
            if sub == 4:
                d.identity[sub] = 0
                continue
            eds_problems.add(ident.section.line, f"0x1018 sub {sub} ({what}) is missing: the SII "
                             "header and the ESI need it")
            continue
        if s.type != 0x07 or s.flags & eds2c.F_NODEID:
            eds_problems.add(s.section.line_of("DataType"), f"0x1018 sub {sub} ({what}) must be "
                             "an UNSIGNED32 without $NODEID")
            continue
        d.identity[sub] = s.default_int or 0
    for sub, key in ((1, "VendorNumber"), (2, "ProductNumber"), (3, "RevisionNumber")):
        if info is None or key not in info.keys or sub not in d.identity:
            continue
        try:
            v = eds2c.parse_int(info.get(key))
        except ValueError:
            continue  # eds2c reported it
        if v != d.identity[sub]:
            eds_problems.add(info.line_of(key), f"[DeviceInfo] {key}={info.get(key)} differs "
                             f"from 0x1018 sub {sub} (0x{d.identity[sub]:08X})")
    d.text = {}
    for key in ("VendorName", "ProductName", "OrderCode"):
        v = info.get(key) if info is not None else None
        line = info.line_of(key) if info is not None else 1
        if not v:
            eds_problems.add(line, f"[DeviceInfo] lacks {key}, which names the device in the SII "
                             "and the ESI")
            continue
        try:
            d.text[key] = _text(255)(v)
        except ValueError as e:
            eds_problems.add(line, f"[DeviceInfo] {key}: {e}")
    device_type = objs[0x1000].subs[0].default_int or 0
    d.profile, d.profile_info = device_type & 0xFFFF, device_type >> 16
    d.ds402_channels = 1 if d.profile == 402 else 0

    # --- PDOs with their default mapping (eds2c checked every mapping entry) ---
    subs = {(e.index, s.subindex): s for e in entries for s in e.subs}
    mapping = {}
    for e in entries:
        if not (0x1600 <= e.index <= 0x17FF or 0x1A00 <= e.index <= 0x1BFF):
            continue
        count = _sub(e, 0).default_int or 0
        items = []
        for n in range(1, count + 1):
            s = _sub(e, n)
            v = s.default_int
            index, sub, bits = v >> 16, (v >> 8) & 0xFF, v & 0xFF
            if 1 <= index <= 7:     # dummy entry: the data type is its index
                items.append((index, sub, bits, index, ""))
                continue
            target = subs[(index, sub)]
            if target.type not in ESI_TYPES:
                eds_problems.add(s.section.line_of("DefaultValue"), f"0x{e.index:04X} sub {n}: "
                                 f"the data type of 0x{index:04X} sub {sub} has no ESI name")
                continue
            name = target.name if target.subindex == 0 or index not in objs or \
                objs[index].code == eds2c.OBJ_VAR else f"{objs[index].name} {target.name}"
            items.append((index, sub, bits, target.type, name))
        mapping[e.index] = (e, items)

    # --- the PDO assignment: EDS 0x1C12/0x1C13, otherwise the choices ---
    pd = ch["ProcessData"]
    d.assign = {}
    for sm, obj, key, lo in ((2, 0x1C12, "RxPdoAssign", 0x1600),
                             (3, 0x1C13, "TxPdoAssign", 0x1A00)):
        e = objs.get(obj)
        if e is not None:
            if key in pd:
                ch_problems.add(ch.line("ProcessData", key), f"[ProcessData] {key}: the EDS has "
                                f"0x{obj:04X} (line {e.section.line}), whose defaults are the "
                                "assignment; remove the key")
            s0 = _sub(e, 0)
            if e.code == eds2c.OBJ_VAR or s0 is None:
                eds_problems.add(e.section.line, f"0x{obj:04X} (PDO assignment) must be an ARRAY")
                continue
            assigned = []
            for n in range(1, (s0.default_int or 0) + 1):
                s = _sub(e, n)
                if s is None:
                    eds_problems.add(s0.section.line_of("DefaultValue"), f"0x{obj:04X} sub 0 says "
                                     f"{s0.default_int} PDOs but sub {n} does not exist")
                    break
                v = s.default_int or 0
                if not lo <= v <= lo + 0x1FF or v not in mapping:
                    eds_problems.add(s.section.line_of("DefaultValue"), f"0x{obj:04X} sub {n}: "
                                     f"0x{v:04X} is not a PDO mapping object of this EDS "
                                     f"(0x{lo:04X}-0x{lo + 0x1FF:04X})")
                    continue
                assigned.append(v)
            d.assign[sm] = assigned
        elif key in pd:
            for v in pd[key]:
                if v not in mapping:
                    ch_problems.add(ch.line("ProcessData", key), f"[ProcessData] {key}: the EDS "
                                    f"has no PDO mapping object 0x{v:04X}")
            d.assign[sm] = [v for v in pd[key] if v in mapping]
        else:
            ch_problems.add(ch.line("ProcessData"), f"[ProcessData] lacks {key}, and the EDS has "
                            f"no 0x{obj:04X} to take the assignment from")
            d.assign[sm] = []
    sm_of = {idx: sm for sm, idxs in d.assign.items() for idx in idxs}
    d.pdos = [Pdo(i, e.name, items, sm_of.get(i)) for i, (e, items) in sorted(mapping.items())]

    e = objs.get(0x1C00)
    if e is not None:
        want = {1: SM_MBX_OUT, 2: SM_MBX_IN, 3: SM_OUTPUTS, 4: SM_INPUTS}
        for n, kind in want.items():
            s = _sub(e, n)
            if s is None or (s.default_int or 0) != kind:
                line = s.section.line_of("DefaultValue") if s else e.section.line
                eds_problems.add(line, f"0x1C00 sub {n} must be {kind} (SM{n - 1} is "
                                 f"{('mailbox out', 'mailbox in', 'outputs', 'inputs')[n - 1]})")

    # --- CoE details ---
    coe = ch["CoE"]
    d.coe = COE_SDO
    d.coe |= COE_SDO_INFO if coe.get("SdoInfo") else 0
    d.coe |= COE_COMPLETE if coe.get("CompleteAccess") else 0
    d.coe |= COE_PDO_UPLOAD if coe.get("PdoUpload") else 0

    def writable(index):
        e = objs.get(index)
        s = _sub(e, 0) if e is not None else None
        return s is not None and bool(s.flags & eds2c.F_WRITE)
    if writable(0x1C12) and writable(0x1C13):
        d.coe |= COE_PDO_ASSIGN
    if mapping and all(writable(i) for i in mapping):
        d.coe |= COE_PDO_CONFIG

    # --- ESC, mailbox, SyncManagers, FMMUs: the choices checked against each other ---
    esc, mbx = ch["Esc"], ch["Mailbox"]
    d.esc = esc
    if esc.get("EscConfig", 0) & 0x01:
        ch_problems.add(ch.line("Esc", "EscConfig"), "[Esc] EscConfig bit 0 (device emulation) "
                        "would let the ESC answer state requests by itself; the application "
                        "layer answers them")
    d.protocols = sum(MBX_PROTOCOLS[p] for p in mbx.get("Protocols", []))
    if mbx and not d.protocols & MBX_PROTOCOLS["CoE"]:
        ch_problems.add(ch.line("Mailbox", "Protocols"), "[Mailbox] Protocols must include CoE "
                        "(the device is described by its CoE dictionary)")
    d.device_choices = ch["Device"]
    d.eeprom = ch["Eeprom"]
    size = d.eeprom.get("ByteSize")
    if size is not None and (size % 128 or size & (size - 1)):
        ch_problems.add(ch.line("Eeprom", "ByteSize"), f"[Eeprom] ByteSize {size}: a power of two "
                        "of at least 128 bytes (word 0x3E counts KiBit)")

    def pd_length(sm):
        bits = sum(p.bits for p in d.pdos if p.sm == sm)
        return (bits + 7) // 8

    d.sms = []
    if not ch_problems.items:
        d.sms = [
            SyncManager(0, SM_MBX_OUT, mbx["OutStart"], mbx["OutSize"], mbx["OutControl"],
                        mbx["OutSize"], ch.line("Mailbox", "OutStart")),
            SyncManager(1, SM_MBX_IN, mbx["InStart"], mbx["InSize"], mbx["InControl"],
                        mbx["InSize"], ch.line("Mailbox", "InStart")),
            SyncManager(2, SM_OUTPUTS, pd["OutputsStart"], pd_length(2), pd["OutputsControl"],
                        pd["OutputsMaxSize"], ch.line("ProcessData", "OutputsStart")),
            SyncManager(3, SM_INPUTS, pd["InputsStart"], pd_length(3), pd["InputsControl"],
                        pd["InputsMaxSize"], ch.line("ProcessData", "InputsStart")),
        ]
        check_sync_managers(d, ch, ch_problems)
    d.fmmus = [FMMU_USAGE[u] for u in ch["Fmmu"].get("Usage", [])]
    if len(d.fmmus) > esc.get("Fmmus", 16):
        ch_problems.add(ch.line("Fmmu", "Usage"), f"[Fmmu] {len(d.fmmus)} FMMUs but the ESC has "
                        f"{esc['Fmmus']}")
    d.ports = ch["Device"].get("Ports", [])
    return d


def check_sync_managers(d, ch, problems):
    # control byte (ESC register 0x0804 + 8n): bits 1:0 mode (0 buffered, 2 mailbox),
    # bits 3:2 direction (0 master reads, 1 master writes)
    rules = {SM_MBX_OUT: (2, 1, "Mailbox", "OutControl", "mailbox, master writes"),
             SM_MBX_IN: (2, 0, "Mailbox", "InControl", "mailbox, master reads"),
             SM_OUTPUTS: (0, 1, "ProcessData", "OutputsControl", "buffered, master writes"),
             SM_INPUTS: (0, 0, "ProcessData", "InputsControl", "buffered, master reads")}
    for sm in d.sms:
        mode, direction, sec, key, what = rules[sm.kind]
        if sm.control & 0x03 != mode or (sm.control >> 2) & 0x03 != direction:
            problems.add(ch.line(sec, key), f"[{sec}] {key} 0x{sm.control:02X}: SM{sm.number} "
                         f"must be {what} (bits 1:0 = {mode}, bits 3:2 = {direction})")
    for sm, key in ((d.sms[2], "OutputsMaxSize"), (d.sms[3], "InputsMaxSize")):
        if sm.length > sm.max_size:
            problems.add(ch.line("ProcessData", key), f"[ProcessData] {key} {sm.max_size} is "
                         f"smaller than SM{sm.number}'s default PDOs ({sm.length} bytes)")
    ram_end = ESC_RAM_START + d.esc["RamKiB"] * 1024
    for sm in d.sms:
        if sm.start < ESC_RAM_START or sm.start + sm.footprint > ram_end:
            problems.add(sm.line, f"SM{sm.number} at 0x{sm.start:04X}-"
                         f"0x{sm.start + sm.footprint - 1:04X} is outside the ESC's process RAM "
                         f"0x{ESC_RAM_START:04X}-0x{ram_end - 1:04X}")
    for i, a in enumerate(d.sms):
        for b in d.sms[i + 1:]:
            if a.start < b.start + b.footprint and b.start < a.start + a.footprint:
                later = max(a, b, key=lambda s: s.line)
                problems.add(later.line, f"SM{a.number} (0x{a.start:04X}, {a.footprint} bytes) "
                             f"and SM{b.number} (0x{b.start:04X}, {b.footprint} bytes) overlap "
                             "(a buffered SyncManager occupies 3 x its maximum size)")


# --------------------------------------------------------------------------------------------
# The SII image.
# --------------------------------------------------------------------------------------------

class Strings:
    """The STRINGS category: 1-based indexes, each text stored once."""

    def __init__(self):
        self.items = []

    def index(self, text):
        if not text:
            return 0
        if text not in self.items:
            self.items.append(text)
        return self.items.index(text) + 1


def category(kind, data):
    if len(data) % 2:
        data += b"\x00"
    return struct.pack("<HH", kind, len(data) // 2) + data


def build_sii(d):
    """Returns (image bytes, [(byte offset, name, data words)] of the categories)."""
    strings = Strings()
    dc = d.device_choices
    s_type = strings.index(dc["Type"])            # string 1: the name masters show
    s_group = strings.index(dc["GroupType"])
    s_name = strings.index(d.text["ProductName"])
    s_order = strings.index(d.text["OrderCode"])

    pdo_data = {CAT_TXPDO: b"", CAT_RXPDO: b""}
    for pdo in d.pdos:
        kind = CAT_RXPDO if pdo.index < 0x1A00 else CAT_TXPDO
        body = struct.pack("<HBBBBH", pdo.index, len(pdo.entries),
                           pdo.sm if pdo.sm is not None else 0xFF, 0, strings.index(pdo.name), 0)
        for index, sub, bits, dtype, name in pdo.entries:
            body += struct.pack("<HBBBBH", index, sub, strings.index(name), dtype, bits, 0)
        pdo_data[kind] += body

    general = bytearray(32)
    general[0] = s_group
    general[1] = 0                                  # no image
    general[2] = s_order
    general[3] = s_name
    general[5] = d.coe
    general[6] = 1 if d.protocols & MBX_PROTOCOLS["FoE"] else 0
    general[7] = 1 if d.protocols & MBX_PROTOCOLS["EoE"] else 0
    general[8] = 0                                  # SoE channels
    general[9] = d.ds402_channels
    general[10] = 0                                 # SysmanClass
    general[11] = 0                                 # flags: none
    struct.pack_into("<h", general, 12, 0)          # current on E-Bus: own supply
    general[14] = s_group
    ports = 0
    for i, p in enumerate(d.ports):
        ports |= PORT_TYPES[p][0] << (4 * i)
    struct.pack_into("<H", general, 16, ports)

    text = bytes([len(strings.items)])
    for s in strings.items:
        text += bytes([len(s)]) + s.encode("ascii")
    fmmu = bytes(d.fmmus)
    syncm = b"".join(struct.pack("<HHBBBB", sm.start, sm.length, sm.control, 0, sm.enable, sm.kind)
                     for sm in d.sms)

    cats = [(CAT_STRINGS, "STRINGS", text), (CAT_GENERAL, "GENERAL", bytes(general)),
            (CAT_FMMU, "FMMU", fmmu), (CAT_SYNCM, "SYNCM", syncm)]
    for kind, name in ((CAT_TXPDO, "TXPDO"), (CAT_RXPDO, "RXPDO")):
        if pdo_data[kind]:
            cats.append((kind, name, pdo_data[kind]))

    words = [0] * 0x40
    words[0] = d.esc["PdiControl"] | d.esc["EscConfig"] << 8
    words[1] = d.esc["PdiConfig"]
    words[2] = d.esc["SyncImpulse"]
    words[3] = d.esc["PdiConfig2"]
    words[4] = d.esc["Alias"]
    head = struct.pack("<7H", *words[:7])
    words[7] = crc8_sii(head)
    for i, sub in ((0x08, 1), (0x0A, 2), (0x0C, 3), (0x0E, 4)):
        words[i], words[i + 1] = d.identity[sub] & 0xFFFF, d.identity[sub] >> 16
    sm0, sm1 = d.sms[0], d.sms[1]
    words[0x18], words[0x19] = sm0.start, sm0.max_size
    words[0x1A], words[0x1B] = sm1.start, sm1.max_size
    words[0x1C] = d.protocols
    words[0x3E] = d.eeprom["ByteSize"] * 8 // 1024 - 1
    words[0x3F] = d.eeprom["Version"]
    image = struct.pack("<64H", *words)
    layout = []
    for kind, name, data in cats:
        block = category(kind, data)
        layout.append((len(image), name, len(block) // 2 - 2))
        image += block
    layout.append((len(image), "END", 0))
    image += struct.pack("<H", CAT_END)
    return image, layout, strings


# --------------------------------------------------------------------------------------------
# Outputs.
# --------------------------------------------------------------------------------------------

HEADER_FIELDS = [
    (0x00, "PDI control (low byte), ESC configuration (high byte)"),
    (0x01, "PDI configuration"), (0x02, "SYNC impulse length (10 ns)"),
    (0x03, "extended PDI configuration"), (0x04, "configured station alias"),
    (0x05, "reserved"), (0x06, "reserved"), (0x07, "checksum: CRC-8 of bytes 0-13"),
    (0x08, "vendor ID (0x1018 sub 1)"), (0x0A, "product code (0x1018 sub 2)"),
    (0x0C, "revision number (0x1018 sub 3)"), (0x0E, "serial number (0x1018 sub 4)"),
    (0x10, "execution delay, port 0/1 delays, reserved"),
    (0x14, "bootstrap receive/send mailbox offset, size: none"),
    (0x18, "standard receive mailbox (SM0) offset, size"),
    (0x1A, "standard send mailbox (SM1) offset, size"),
    (0x1C, "mailbox protocols"), (0x1D, "reserved"),
    (0x3E, "EEPROM size (KiBit - 1)"), (0x3F, "version"), (0x40, None),
]


def c_bytes(data, indent="    "):
    return [indent + " ".join(f"0x{b:02X}," for b in data[i:i + 12])
            for i in range(0, len(data), 12)]


def generate_c(image, layout, d, sii_id, sources, header_name):
    sym = "co_sii_" + sii_id.replace("-", "_")
    up = sii_id.replace("-", "_").upper()
    out = [f"/* Generated by tools/eds2sii.py from {sources[0][0]} and {sources[1][0]} - "
           "do not edit.",
           f" * EDS SHA-256: {sources[0][1]}", f" * choices SHA-256: {sources[1][1]}",
           f" * SII EEPROM image (ETG.1000.6 §5.4, ETG.2010): {len(image)} of "
           f"{d.eeprom['ByteSize']} bytes; words past the image read as 0xFFFF. */",
           f'#include "{header_name}"', "",
           f"const uint8_t {sym}[CO_SII_{up}_SIZE] = {{"]
    for i, (word, what) in enumerate(HEADER_FIELDS[:-1]):
        end = HEADER_FIELDS[i + 1][0]
        out.append(f"    /* word 0x{word:02X}: {what} */")
        out.extend(c_bytes(image[word * 2:end * 2]))
    for i, (offset, name, length) in enumerate(layout):
        end = layout[i + 1][0] if i + 1 < len(layout) else len(image)
        tail = f", {length} data words" if name != "END" else ""
        out.append(f"    /* byte 0x{offset:04X} (word 0x{offset // 2:03X}): {name}{tail} */")
        out.extend(c_bytes(image[offset:end]))
    out[-1] = out[-1].rstrip(",")
    out += ["};", "", f"const uint16_t {sym}_size = CO_SII_{up}_SIZE;", ""]
    return "\n".join(out)


def generate_h(image, d, sii_id, sources):
    sym = "co_sii_" + sii_id.replace("-", "_")
    up = sii_id.replace("-", "_").upper()
    p = f"CO_SII_{up}"
    sm0, sm1, sm2, sm3 = d.sms
    lines = [
        f"/* Generated by tools/eds2sii.py from {sources[0][0]} and {sources[1][0]} - do not edit.",
        " * The SII EEPROM image of the slave and the layout values it announces: an ESC emulation",
        " * serving this image, and the CoE application layer behind it, must honour every value",
        " * below (a master configures the SyncManagers and the mailbox from the image). */",
        f"#ifndef {p}_H", f"#define {p}_H", "", "#include <stdint.h>", "",
        "/* The image: header words 0x00-0x3F, categories, END (ETG.1000.6 §5.4). An EEPROM read",
        " * beyond it returns 0xFFFF words, as an unprogrammed EEPROM does. */",
        f"#define {p}_SIZE {len(image)}u",
        f"#define {p}_EEPROM_BYTES {d.eeprom['ByteSize']}u",
        f"extern const uint8_t {sym}[{p}_SIZE];",
        f"extern const uint16_t {sym}_size; /* = {p}_SIZE */",
        "",
        "/* Identity (0x1018 sub 1-4 of the dictionary = SII words 0x08-0x0F) */",
        f"#define {p}_VENDOR_ID 0x{d.identity[1]:08X}u",
        f"#define {p}_PRODUCT_CODE 0x{d.identity[2]:08X}u",
        f"#define {p}_REVISION 0x{d.identity[3]:08X}u",
        f"#define {p}_SERIAL 0x{d.identity[4]:08X}u",
        "",
        "/* ESC information registers 0x0000-0x0006 and the SII configuration words 0x00-0x04 */",
        f"#define {p}_ESC_TYPE 0x{d.esc['Type']:02X}u",
        f"#define {p}_ESC_REVISION 0x{d.esc['Revision']:02X}u",
        f"#define {p}_ESC_BUILD 0x{d.esc['Build']:04X}u",
        f"#define {p}_ESC_FMMUS {d.esc['Fmmus']}u",
        f"#define {p}_ESC_SYNC_MANAGERS {d.esc['SyncManagers']}u",
        f"#define {p}_ESC_RAM_KIB {d.esc['RamKiB']}u",
        f"#define {p}_PDI_CONTROL 0x{d.esc['PdiControl']:02X}u",
        f"#define {p}_ESC_CONFIG 0x{d.esc['EscConfig']:02X}u",
        f"#define {p}_ALIAS {d.esc['Alias']}u",
        "",
        "/* SyncManagers (SII SYNCM category; control byte = ESC register 0x0804 + 8n). SM2/SM3",
        " * LENGTH is the size of the default PDO assignment, MAX_LENGTH the most the mapping",
        " * allows; a buffered SyncManager occupies 3 x its length of ESC RAM. */",
    ]
    for sm in d.sms:
        lines += [f"#define {p}_SM{sm.number}_START 0x{sm.start:04X}u",
                  f"#define {p}_SM{sm.number}_LENGTH {sm.length}u",
                  f"#define {p}_SM{sm.number}_CONTROL 0x{sm.control:02X}u"]
        if sm.kind in (SM_OUTPUTS, SM_INPUTS):
            lines.append(f"#define {p}_SM{sm.number}_MAX_LENGTH {sm.max_size}u")
    lines += [
        "",
        "/* Mailbox (SII words 0x18-0x1C) and the CoE services promised in GENERAL: bit 0 SDO,",
        " * 1 SDO information, 2 PDO assignment, 3 PDO configuration, 4 PDO upload at startup,",
        " * 5 complete access. */",
        f"#define {p}_MBX_OUT_SIZE {sm0.max_size}u",
        f"#define {p}_MBX_IN_SIZE {sm1.max_size}u",
        f"#define {p}_MBX_PROTOCOLS 0x{d.protocols:04X}u",
        f"#define {p}_COE_DETAILS 0x{d.coe:02X}u",
        "",
        "/* Default PDO assignment (0x1C12 = SM2, 0x1C13 = SM3) */",
        f"#define {p}_RXPDO_COUNT {len(d.assign[2])}u",
        f"#define {p}_TXPDO_COUNT {len(d.assign[3])}u",
    ]
    for sm, name in ((2, "RXPDO"), (3, "TXPDO")):
        for n, idx in enumerate(d.assign[sm], start=1):
            lines.append(f"#define {p}_{name}{n} 0x{idx:04X}u")
    lines += ["", "#endif", ""]
    return "\n".join(lines)


def hexnum(v, digits):
    return f"#x{v:0{digits}X}"


def generate_xml(image, d, sources):
    """An ETG.2000 EtherCATInfo file describing the same device as the SII image."""
    dc = d.device_choices
    root = ET.Element("EtherCATInfo", {"Version": "1.6"})
    vendor = ET.SubElement(root, "Vendor")
    ET.SubElement(vendor, "Id").text = hexnum(d.identity[1], 8)
    ET.SubElement(vendor, "Name", {"LcId": "1033"}).text = d.text["VendorName"]
    desc = ET.SubElement(root, "Descriptions")
    group = ET.SubElement(ET.SubElement(desc, "Groups"), "Group")
    ET.SubElement(group, "Type").text = dc["GroupType"]
    ET.SubElement(group, "Name", {"LcId": "1033"}).text = dc["GroupName"]
    physics = "".join(PORT_TYPES[p][1] for p in d.ports).rstrip()
    dev = ET.SubElement(ET.SubElement(desc, "Devices"), "Device", {"Physics": physics})
    ET.SubElement(dev, "Type", {"ProductCode": hexnum(d.identity[2], 8),
                                "RevisionNo": hexnum(d.identity[3], 8)}).text = dc["Type"]
    ET.SubElement(dev, "Name", {"LcId": "1033"}).text = d.text["ProductName"]
    ET.SubElement(dev, "GroupType").text = dc["GroupType"]
    profile = ET.SubElement(dev, "Profile")
    ET.SubElement(profile, "ProfileNo").text = str(d.profile)
    ET.SubElement(profile, "AddInfo").text = str(d.profile_info)
    flag = {True: "true", False: "false"}
    names = {v: k for k, v in FMMU_USAGE.items()}
    for f in d.fmmus:
        ET.SubElement(dev, "Fmmu").text = names[f]
    sm_names = {SM_MBX_OUT: "MBoxOut", SM_MBX_IN: "MBoxIn", SM_OUTPUTS: "Outputs",
                SM_INPUTS: "Inputs"}
    for sm in d.sms:
        attrs = {}
        if sm.kind in (SM_OUTPUTS, SM_INPUTS):
            attrs["MaxSize"] = str(sm.max_size)
        attrs.update({"DefaultSize": str(sm.length), "StartAddress": hexnum(sm.start, 4),
                      "ControlByte": hexnum(sm.control, 2), "Enable": str(sm.enable)})
        ET.SubElement(dev, "Sm", attrs).text = sm_names[sm.kind]
    for pdo in [p for p in d.pdos if p.index < 0x1A00] + [p for p in d.pdos if p.index >= 0x1A00]:
        # Fixed: the content cannot be changed (no PDO configuration); Mandatory: the PDO cannot
        # be left out of the assignment (no PDO assignment)
        attrs = {"Fixed": flag[not d.coe & COE_PDO_CONFIG],
                 "Mandatory": flag[not d.coe & COE_PDO_ASSIGN]}
        if pdo.sm is not None:
            attrs["Sm"] = str(pdo.sm)
        el = ET.SubElement(dev, "RxPdo" if pdo.index < 0x1A00 else "TxPdo", attrs)
        ET.SubElement(el, "Index").text = hexnum(pdo.index, 4)
        ET.SubElement(el, "Name").text = pdo.name
        for index, sub, bits, dtype, name in pdo.entries:
            entry = ET.SubElement(el, "Entry")
            ET.SubElement(entry, "Index").text = hexnum(index, 4)
            ET.SubElement(entry, "SubIndex").text = str(sub)
            ET.SubElement(entry, "BitLen").text = str(bits)
            if index > 7:  # a dummy entry (gap) has no name and no type
                ET.SubElement(entry, "Name").text = name
                t = ESI_TYPES[dtype]
                ET.SubElement(entry, "DataType").text = \
                    f"{t}({bits // 8})" if dtype in (0x09, 0x0A, 0x0B) else t
    mailbox = ET.SubElement(dev, "Mailbox")
    coe_attrs = {"SdoInfo": flag[bool(d.coe & COE_SDO_INFO)],
                 "PdoAssign": flag[bool(d.coe & COE_PDO_ASSIGN)],
                 "PdoConfig": flag[bool(d.coe & COE_PDO_CONFIG)],
                 "PdoUpload": flag[bool(d.coe & COE_PDO_UPLOAD)],
                 "CompleteAccess": flag[bool(d.coe & COE_COMPLETE)]}
    if d.ds402_channels:
        coe_attrs["DS402Channels"] = str(d.ds402_channels)
    for name in ("AoE", "EoE", "CoE", "FoE", "SoE", "VoE"):
        if d.protocols & MBX_PROTOCOLS[name]:
            ET.SubElement(mailbox, name, coe_attrs if name == "CoE" else {})
    eeprom = ET.SubElement(dev, "Eeprom")
    ET.SubElement(eeprom, "ByteSize").text = str(d.eeprom["ByteSize"])
    ET.SubElement(eeprom, "ConfigData").text = image[:14].hex().upper()
    ET.indent(root, space="  ")
    comment = (f" Generated by tools/eds2sii.py from {sources[0][0]} and {sources[1][0]} for the "
               "simulator - do not edit. It describes the simulated slave and matches its SII "
               "image; the real device's ESI comes from its vendor. ")
    return ('<?xml version="1.0" encoding="UTF-8"?>\n'
            f"<!--{comment}-->\n" + ET.tostring(root, encoding="unicode") + "\n")


def write_atomic(path, data):
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(data)
    os.replace(tmp, path)


def digest(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def main(argv=None):
    ap = argparse.ArgumentParser(description="EDS + EtherCAT choices -> SII image (C) and ESI")
    ap.add_argument("eds")
    ap.add_argument("--choices", required=True, help="EtherCAT choices (INI), e.g. ecat.ini")
    ap.add_argument("--id", required=True, help="device id, e.g. vf-mb1-ecat")
    ap.add_argument("--out-c", help="C file to write")
    ap.add_argument("--out-h", help="header to write")
    ap.add_argument("--out-xml", help="ESI file to write")
    ap.add_argument("--out-bin", help="raw SII image to write")
    args = ap.parse_args(argv)
    if not re.match(r"^[A-Za-z][A-Za-z0-9_-]*$", args.id):
        ap.error(f"--id {args.id!r}: letters, digits, '-' and '_' only, starting with a letter")

    eds_problems, ch_problems = eds2c.Problems(), eds2c.Problems()
    entries = None
    try:
        entries = eds2c.load(args.eds, eds_problems)
    except eds2c.EdsError as e:
        eds_problems.items = list(e.problems)
    ch = Choices(args.choices, ch_problems)
    d = None
    if entries is not None and not ch_problems.items:
        d = model(args.eds, entries, ch, eds_problems, ch_problems)
    image = None
    if d is not None and not eds_problems.items and not ch_problems.items:
        image, layout, _ = build_sii(d)
        limit = min(d.eeprom["ByteSize"], MAX_IMAGE)
        if len(image) > limit:
            ch_problems.add(ch.line("Eeprom", "ByteSize"), f"the SII image is {len(image)} bytes, "
                            f"more than {limit} (EEPROM size, or the 4 KiB a master caches)")
    failed = False
    for path, problems in ((args.eds, eds_problems), (args.choices, ch_problems)):
        for line, msg in sorted(set(problems.items)):
            print(f"{path}:{line}: error: {msg}", file=sys.stderr)
            failed = True
    if failed:
        return 1

    sources = [(os.path.basename(args.eds), digest(args.eds)),
               (os.path.basename(args.choices), digest(args.choices))]
    uid = args.id.replace("-", "_")
    header_name = os.path.basename(args.out_h) if args.out_h else f"sii_{uid}.h"
    if args.out_c:
        write_atomic(args.out_c, generate_c(image, layout, d, args.id, sources,
                                            header_name).encode())
    if args.out_h:
        write_atomic(args.out_h, generate_h(image, d, args.id, sources).encode())
    if args.out_xml:
        write_atomic(args.out_xml, generate_xml(image, d, sources).encode())
    if args.out_bin:
        write_atomic(args.out_bin, image)
    return 0


if __name__ == "__main__":
    sys.exit(main())
