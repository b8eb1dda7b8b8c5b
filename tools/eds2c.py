#!/usr/bin/env python3
"""eds2c.py - turn a CiA 306 EDS into the const C tables of include/canopen/od.h.

    python3 tools/eds2c.py EDS --id ID --out-c FILE.c --out-h FILE.h

writes a deterministic C file (byte-identical on re-runs: no timestamps, no absolute paths, every
table sorted) defining `const co_od co_od_<id>` (id with '-' replaced by '_') and a header that
declares it with `#define CO_OD_<ID>_VALUE_SIZE n`. On a bad EDS it prints one
`FILE:LINE: error: reason` line per problem to stderr, writes nothing and exits with status 1.

VALUE BLOCK LAYOUT (od.h)
    [0, comm_persist_size)            persistent values of 0x1000-0x1FFF
    [comm_persist_size, persist_size) persistent values of 0x2000-0x9FFF
    [persist_size, value_size)        values that are never stored
  Each value is aligned to its natural size (1, 2, 4 or 8 bytes; 3-byte types to 4, 5/6/7-byte
  types to 8; strings to 1), and value_size is rounded up to 8, so a value block that is itself
  8-byte aligned never needs an unaligned access (the core reads little-endian bytes anyway).
  DOMAIN sub-entries have size 0 and no value.

SHARED DESCRIPTORS (od.h co_od_entry.value_base)
  A sub-entry's offset counts from its entry's value_base. Objects of one shape - the same
  sub-indices, types, flags, sizes, limits and regions, with at least two values (the PDO
  parameters, 0x1010/0x1011, ...) - get their values laid out alike: in each region the values of
  one object form a record (by decreasing alignment, then sub-index), and the objects' records are
  one stride apart (the largest record, rounded up to its alignment), in every region the same,
  so one run of descriptors serves them all; value_base is the start of the object's record in its
  first region. Every other object's value_base is its lowest value's offset. Identical runs of
  descriptors are emitted once (the single-value objects of one type and flags share too).
  Inside each region the shape groups come first, by decreasing alignment, then every other value
  by decreasing alignment, then (index, sub-index), each at the lowest free place that fits: the
  holes a record leaves in the other regions' stride get filled.

WHICH VALUES ARE PERSISTENT (CO_OD_PERSIST)
    A sub-entry is persistent - saved by 0x1010, reloaded at reset - if and only if
    1. its AccessType is rw, rww or rwr (ro, const and wo are never persistent: ro/const cannot be
       changed by the network, wo values are commands that cannot be read back), and
    2. its PDOMapping is 0 (a mappable object is process data - controlword 0x6040, statusword
       0x6041, vl target/demand/actual 0x6042-0x6044 and everything else a PDO carries - not a
       parameter), and
    3. its index is in 0x1000-0x1FFF but not 0x1001 (error register), 0x1003 (error history),
       0x1010 (store) or 0x1011 (restore) - i.e. the CiA 301 communication parameters 0x1010
       stores - or its index is in 0x2000-0x9FFF (manufacturer and device-profile parameters).
       0xA000-0xFFFF is never stored.

DEFAULTS
    Little-endian bytes of DefaultValue in one const default image (value_size bytes). A missing
    or empty DefaultValue means 0 / empty. `$NODEID+x` (or `x+$NODEID`) sets
    CO_OD_NODEID and stores x; the core adds the node-ID. VISIBLE_STRING capacity is the longer of
    the default's length and 32 bytes, unless a `; capacity: N` comment gives N - inline after
    the DefaultValue, on a comment line between the section's header and its last key, or in the
    comment block just above its header (comments belong to the section that follows them) -
    in which case a longer default is an error. UNICODE_STRING the same, in bytes of UTF-16LE.
    OCTET_STRING size is the default's length (so it must have one). DOMAIN: size 0, no value.

FLAGS (od.h): ro -> READ; wo -> WRITE; rw -> READ|WRITE; rww -> READ|WRITE(+RPDO);
    rwr -> READ|WRITE(+TPDO); const -> READ|CONST. PDOMapping=1 adds TPDO to ro/const/rwr, RPDO to
    wo/rww, and both to rw (the EDS does not say which direction). rww/rwr with PDOMapping=0 are
    plain rw: PDOMapping alone decides mappability, as it does for a master.
    LowLimit/HighLimit -> one co_od_limit entry (deduplicated, sorted) + CO_OD_LIMITS; a missing
    bound is the type's own bound.

LAYOUT HASH: 32-bit FNV-1a over (index u16, sub u8, type u8, offset u32, size u16), little-endian,
    of every persistent sub-entry in (index, sub) order, then comm_persist_size and persist_size
    (u32 each). A stored image whose hash differs from the tables' is refused by the core.

WHAT COMES FROM PYTHON-CANOPEN, WHAT FROM THE FILE
    The objects - which indices and sub-indices exist, ObjectType, DataType, the (lower-cased)
    AccessType, PDOMapping, ParameterName and the verbatim DefaultValue string (`default_raw`) -
    come from `canopen.objectdictionary.import_od`, because that is what masters load: the
    generated slave cannot disagree with them on what exists. python-canopen drops or hides some
    things, which this script therefore reads from the file itself (see `RawEds`):
      * line numbers (configparser keeps none) - needed for `FILE:LINE: error:`;
      * comments (configparser strips them) - the `; source:` lines go into the C file for
        traceability, and `; capacity: N` sizes a string;
      * failures: python-canopen swallows a ValueError in DefaultValue/LowLimit/HighLimit and just
        leaves the value unset, and resolves `$NODEID+x` to a number (or to nothing when no node-ID
        is given). So numbers are parsed here from `default_raw` and from the raw LowLimit/HighLimit
        strings, with python-canopen's own rules (int(x, 0); two's complement for hex limits of
        signed types; float(); bytes.fromhex()), so that "unparsable" can be reported;
      * limits of REAL32/REAL64 and of INTEGER24/40/48/56, which python-canopen never reads;
      * the raw DataType: python-canopen turns an unknown type above 0x1B into DOMAIN (with only a
        warning) and keeps an unknown one below it;
      * duplicate sections that configparser does not see (`[100a]` vs `[100A]`, `[2000sub1]` vs
        `[2000sub01]`: python-canopen silently keeps the last one);
      * SubNumber and the [Mandatory/Optional/ManufacturerObjects] lists, which it ignores.
"""

from __future__ import annotations

import argparse
import configparser
import hashlib
import logging
import math
import os
import re
import struct
import sys
import warnings

DEFAULT_STRING_CAPACITY = 32
MAX_PDO_BITS = 64
OD_PAGES = 31  # CO_OD_PAGES, include/canopen/od.h

# CiA 301 data types: code -> (C enumerator, size in bytes or None for variable, kind)
TYPES = {
    0x01: ("CO_BOOLEAN", 1, "bool"),
    0x02: ("CO_INTEGER8", 1, "int"),
    0x03: ("CO_INTEGER16", 2, "int"),
    0x04: ("CO_INTEGER32", 4, "int"),
    0x05: ("CO_UNSIGNED8", 1, "uint"),
    0x06: ("CO_UNSIGNED16", 2, "uint"),
    0x07: ("CO_UNSIGNED32", 4, "uint"),
    0x08: ("CO_REAL32", 4, "real"),
    0x09: ("CO_VISIBLE_STRING", None, "vstring"),
    0x0A: ("CO_OCTET_STRING", None, "ostring"),
    0x0B: ("CO_UNICODE_STRING", None, "ustring"),
    0x0C: ("CO_TIME_OF_DAY", 6, "uint"),
    0x0D: ("CO_TIME_DIFFERENCE", 6, "uint"),
    0x0F: ("CO_DOMAIN", 0, "domain"),
    0x10: ("CO_INTEGER24", 3, "int"),
    0x11: ("CO_REAL64", 8, "real"),
    0x12: ("CO_INTEGER40", 5, "int"),
    0x13: ("CO_INTEGER48", 6, "int"),
    0x14: ("CO_INTEGER56", 7, "int"),
    0x15: ("CO_INTEGER64", 8, "int"),
    0x16: ("CO_UNSIGNED24", 3, "uint"),
    0x18: ("CO_UNSIGNED40", 5, "uint"),
    0x19: ("CO_UNSIGNED48", 6, "uint"),
    0x1A: ("CO_UNSIGNED56", 7, "uint"),
    0x1B: ("CO_UNSIGNED64", 8, "uint"),
}

ACCESS_TYPES = ("ro", "wo", "rw", "rww", "rwr", "const")
OBJ_VAR, OBJ_ARRAY, OBJ_RECORD = 0x07, 0x08, 0x09
OBJ_DOMAIN = 0x02  # CiA 301 object code DOMAIN: python-canopen reads it as a VAR, so do we
OBJECT_CODES = {OBJ_VAR: "CO_OBJ_VAR", OBJ_ARRAY: "CO_OBJ_ARRAY", OBJ_RECORD: "CO_OBJ_RECORD"}

F_READ, F_WRITE, F_TPDO, F_RPDO = 0x01, 0x02, 0x04, 0x08
F_CONST, F_PERSIST, F_NODEID, F_LIMITS = 0x10, 0x20, 0x40, 0x80
FLAG_NAMES = [(F_READ, "CO_OD_READ"), (F_WRITE, "CO_OD_WRITE"), (F_TPDO, "CO_OD_TPDO"),
              (F_RPDO, "CO_OD_RPDO"), (F_CONST, "CO_OD_CONST"), (F_PERSIST, "CO_OD_PERSIST"),
              (F_NODEID, "CO_OD_NODEID"), (F_LIMITS, "CO_OD_LIMITS")]

NOT_STORED_COMM = {0x1001, 0x1003, 0x1010, 0x1011}

# Keys CiA 306 defines for object sections; a differently-cased spelling is invisible to
# python-canopen (it reads keys case-sensitively), so it is reported.
KNOWN_KEYS = ("ParameterName", "ObjectType", "DataType", "AccessType", "DefaultValue",
              "PDOMapping", "LowLimit", "HighLimit", "SubNumber", "CompactSubObj",
              "ObjFlags", "ParameterValue", "Denotation", "StorageLocation")

CAPACITY_RE = re.compile(r"\bcapacity\s*:\s*(\d+)\b", re.IGNORECASE)
OBJ_SECTION_RE = re.compile(r"^[0-9A-Fa-f]{4}$")
# python-canopen's own pattern for sub-index sections (sic: "[S|s]ub")
SUB_SECTION_RE = re.compile(r"^([0-9A-Fa-f]{4})[S|s]ub([0-9A-Fa-f]+)$")
NAME_SECTION_RE = re.compile(r"^([0-9A-Fa-f]{4})Name")
# A section name that can only be meant as an object or sub-index section: all hex digits, or a
# leading digit. Unless it matches the patterns above, python-canopen ignores it without a word.
INDEX_LIKE_RE = re.compile(r"^(?:[0-9A-Fa-f]+|[0-9].*)$")
# Bytes that have no place in an EDS line (tab is whitespace)
CONTROL_RE = re.compile(r"[\x00-\x08\x0b-\x1f\x7f]")


class EdsError(Exception):
    """A list of (line, message) problems in one EDS."""

    def __init__(self, problems):
        super().__init__("bad EDS")
        self.problems = problems


class Problems:
    def __init__(self):
        self.items = []

    def add(self, line, msg):
        self.items.append((line or 1, msg))

    def check(self):
        if self.items:
            raise EdsError(sorted(set(self.items)))


# --------------------------------------------------------------------------------------------
# The raw file: line numbers, comments, verbatim strings (configparser keeps none of these).
# --------------------------------------------------------------------------------------------

class RawSection:
    def __init__(self, name, line):
        self.name = name
        self.line = line
        self.keys = {}          # key -> (value, line)
        self.inline = {}        # key -> inline comment text
        self.comments = []      # comment lines above the header and inside the section

    def line_of(self, key):
        return self.keys[key][1] if key in self.keys else self.line

    def get(self, key, default=None):
        return self.keys[key][0] if key in self.keys else default


def _strip_inline_comment(line):
    """configparser's inline-comment rule for prefix ';': at column 0 or after whitespace."""
    index = -1
    while True:
        index = line.find(";", index + 1)
        if index == -1:
            return line, ""
        if index == 0 or line[index - 1].isspace():
            return line[:index], line[index + 1:].strip()


class RawEds:
    """A line-oriented reading of the EDS that mirrors configparser's syntax (as python-canopen
    configures it: inline ';' comments, ':' or '=' delimiters, case-sensitive keys)."""

    def __init__(self, path, problems):
        self.sections = []
        self.by_name = {}
        try:
            with open(path, "rb") as f:
                data = f.read()
        except OSError as e:
            problems.add(1, f"cannot read: {e.strerror}")
            return
        if data.startswith(b"\xef\xbb\xbf"):
            problems.add(1, "file starts with a UTF-8 byte order mark (python-canopen cannot "
                         "read it)")
            return
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError as e:
            line = data[:e.start].count(b"\n") + 1
            problems.add(line, "not valid UTF-8")
            return
        current = None
        pending = []
        seen_exact = {}
        # universal newlines, as open() gives configparser (str.splitlines would also split on
        # \f, \v, U+2028... and shift the line numbers)
        text = text.replace("\r\n", "\n").replace("\r", "\n")
        for lineno, line in enumerate(text.split("\n"), start=1):
            control = CONTROL_RE.search(line)
            if control:
                # python-canopen keeps it (a NUL ends the name in every C string made of it)
                key = line.split("=", 1)[0].strip() if "=" in line else ""
                problems.add(lineno, f"control character 0x{ord(control.group()):02X} in "
                             f"{key if key else 'the line'}")
                continue
            stripped = line.strip()
            if not stripped:
                continue
            if stripped.startswith(";") or stripped.startswith("#"):
                pending.append(stripped.lstrip(";#").strip())
                continue
            if line[0].isspace():
                problems.add(lineno, "indented line (configparser would join it to the previous "
                             "value as a continuation)")
                continue
            body, inline = _strip_inline_comment(line)
            body = body.strip()
            if not body:
                continue
            m = re.match(r"\[(?P<header>.+)\]", body)
            if m:
                name = m.group("header")
                if name in seen_exact:
                    problems.add(lineno, f"duplicate section [{name}] (first at line "
                                 f"{seen_exact[name]})")
                    current = RawSection(name, lineno)  # parse it, but do not register it
                    current.comments.extend(pending)
                    pending = []
                    continue
                seen_exact[name] = lineno
                current = RawSection(name, lineno)
                current.comments.extend(pending)
                if inline:
                    current.comments.append(inline)
                pending = []
                self.sections.append(current)
                self.by_name[name] = current
                continue
            m = re.match(r"(?P<option>.*?)\s*[=:]\s*(?P<value>.*)$", body)
            if not m or not m.group("option"):
                problems.add(lineno, f"cannot parse line: {body!r}")
                continue
            if current is None:
                problems.add(lineno, "key outside of any section")
                continue
            key, value = m.group("option"), m.group("value").strip()
            current.comments.extend(pending)
            pending = []
            if key in current.keys:
                problems.add(lineno, f"duplicate key {key} in [{current.name}] (first at line "
                             f"{current.keys[key][1]})")
                continue
            current.keys[key] = (value, lineno)
            if inline:
                current.inline[key] = inline


# --------------------------------------------------------------------------------------------
# Number parsing with python-canopen's rules, but reporting what it would silently drop.
# --------------------------------------------------------------------------------------------

def int_range(code):
    _, size, kind = TYPES[code]
    bits = 1 if kind == "bool" else size * 8
    if kind == "int":
        return -(1 << (bits - 1)), (1 << (bits - 1)) - 1
    return 0, (1 << bits) - 1


def parse_int(text):
    """python-canopen: int(value.replace(' ', '').upper(), 0)."""
    return int(text.replace(" ", "").upper(), 0)


# `$NODEID+x` or `x+$NODEID`. A bare `$NODEID` is refused: python-canopen reads it as int("") and
# drops the default, so a master would not know it.
NODEID_RE = re.compile(r"^\$NODEID\+(?P<a>.+)$|^(?P<b>.+)\+\$NODEID$")


def parse_default_int(text):
    """Returns (value, relative). Raises ValueError."""
    t = text.replace(" ", "").upper()
    if "$NODEID" in t:
        m = NODEID_RE.match(t)
        if not m:
            raise ValueError(text)
        return int(m.group("a") or m.group("b"), 0), True
    return int(t, 0), False


def parse_limit(text, code):
    """python-canopen's limit rule: int(x, 0), and for signed types a value above the positive
    maximum is two's complement (so 0xFFFF is -1 for INTEGER16). Floats: float(x)."""
    kind = TYPES[code][2]
    if kind == "real":
        v = float(text)
        if not math.isfinite(v):
            raise ValueError(text)
        return v
    v = int(text, 0)
    if kind == "int":
        bits = TYPES[code][1] * 8
        hexa = text.strip().lower().lstrip("+").startswith("0x")
        if hexa and (1 << (bits - 1)) <= v < (1 << bits):
            v -= 1 << bits
    return v


def limit_pattern(value, code):
    """The 64-bit raw pattern od.h wants: sign-extended, zero-extended or IEEE 754 double."""
    kind = TYPES[code][2]
    if kind == "real":
        return struct.unpack("<Q", struct.pack("<d", value))[0]
    return value & 0xFFFFFFFFFFFFFFFF


def encode_number(value, code):
    _, size, kind = TYPES[code]
    if kind == "real":
        return struct.pack("<f" if size == 4 else "<d", value)
    return (value & ((1 << (size * 8)) - 1)).to_bytes(size, "little")


def type_name(code):
    return TYPES[code][0][3:]


def hexidx(index, sub=None):
    return f"0x{index:04X}" if sub is None else f"0x{index:04X} sub {sub}"


# --------------------------------------------------------------------------------------------
# The model.
# --------------------------------------------------------------------------------------------

class Sub:
    def __init__(self, index, subindex, name, section):
        self.index = index
        self.subindex = subindex
        self.name = name
        self.section = section      # RawSection
        self.type = 0
        self.access = "ro"
        self.pdo = False
        self.value = b""            # default bytes (without padding for strings)
        self.default_int = None     # numeric default (ints), x of $NODEID+x
        self.size = 0
        self.flags = 0
        self.limit = None           # (low pattern, high pattern)
        self.limit_index = 0
        self.offset = 0

    @property
    def align(self):
        if self.size == 0 or TYPES[self.type][1] is None:
            return 1
        s = self.size
        return 1 if s == 1 else 2 if s == 2 else 4 if s <= 4 else 8


class Entry:
    def __init__(self, index, code, name, section):
        self.index = index
        self.code = code
        self.name = name
        self.section = section
        self.subs = []
        self.value_base = 0         # co_od_entry.value_base (layout)


def load(path, problems):
    raw = RawEds(path, problems)
    problems.check()

    # --- raw structure checks, before python-canopen (which would crash or stay silent) ---
    objects, subsecs = {}, {}
    dummies = set()
    for sec in raw.sections:
        if OBJ_SECTION_RE.match(sec.name):
            index = int(sec.name, 16)
            if index == 0:
                problems.add(sec.line, "object 0x0000 cannot exist: CiA 301 leaves index 0x0000 "
                             "unused")
                continue
            if index in objects:
                problems.add(sec.line, f"duplicate section [{sec.name}] for object "
                             f"{hexidx(index)} (first at line {objects[index].line})")
                continue
            objects[index] = sec
            continue
        m = SUB_SECTION_RE.match(sec.name)
        if m:
            index, sub = int(m.group(1), 16), int(m.group(2), 16)
            if sub > 0xFE:
                problems.add(sec.line, f"sub-index 0x{sub:X} out of range (0x00-0xFE)")
                continue
            if (index, sub) in subsecs:
                problems.add(sec.line, f"duplicate section [{sec.name}] for "
                             f"{hexidx(index, sub)} (first at line {subsecs[(index, sub)].line})")
                continue
            if index not in objects:
                problems.add(sec.line, f"sub-index section [{sec.name}] before (or without) "
                             f"its object section [{index:04X}]")
                continue
            subsecs[(index, sub)] = sec
            continue
        m = NAME_SECTION_RE.match(sec.name)
        if m:
            problems.add(sec.line, f"[{sec.name}]: CompactSubObj name sections are not supported")
            continue
        if INDEX_LIKE_RE.match(sec.name):
            problems.add(sec.line, f"section [{sec.name}] is neither an object section (4 hex "
                         "digits, e.g. [2000]) nor a sub-index section (e.g. [2000sub1]): "
                         "python-canopen would ignore it")
            continue
        if re.match(r"^[Dd]ummy[Uu]sage$", sec.name):
            for i in range(1, 8):
                key = f"Dummy{i:04d}"
                v = sec.get(key)
                if v is None:
                    problems.add(sec.line, f"[{sec.name}] lacks {key} (python-canopen requires it)")
                    continue
                try:
                    if parse_int(v) == 1:
                        dummies.add(i)
                except ValueError:
                    problems.add(sec.line_of(key), f"{key}: unparsable number {v!r}")
    first_line = raw.sections[0].line if raw.sections else 1
    if "FileInfo" not in raw.by_name:
        # CiA 306 requires it; python-canopen reads a file without it silently
        problems.add(first_line, "missing [FileInfo] section (CiA 306: file name, version and "
                     "EDS version)")
    if "DeviceInfo" not in raw.by_name:
        problems.add(1, "missing [DeviceInfo] section")
    # numbers python-canopen reads with int(x, 0) and would crash on without a line number
    numeric = [("DeviceInfo", k) for k in ("VendorNumber", "ProductNumber", "RevisionNumber",
                                           "SimpleBootUpMaster", "SimpleBootUpSlave",
                                           "Granularity", "DynamicChannelsSupported",
                                           "GroupMessaging", "NrOfRXPDO", "NrOfTXPDO",
                                           "LSS_Supported")]
    numeric += [("DeviceInfo", f"BaudRate_{r}") for r in (10, 20, 50, 125, 250, 500, 800, 1000)]
    numeric += [("Comments", "Lines")]
    for name, key in numeric:
        sec = raw.by_name.get(name)
        if sec is not None and key in sec.keys:
            try:
                parse_int(sec.get(key))
            except ValueError:
                problems.add(sec.line_of(key), f"[{name}] {key}: unparsable number "
                             f"{sec.get(key)!r}")

    for sec in list(objects.values()) + list(subsecs.values()):
        for key in sec.keys:
            for known in KNOWN_KEYS:
                if key != known and key.lower() == known.lower():
                    problems.add(sec.line_of(key), f"key {key} must be spelled {known} "
                                 "(python-canopen reads keys case-sensitively)")
    for index, sec in objects.items():
        code_text = sec.get("ObjectType", "0x7")
        try:
            code = parse_int(code_text)
        except ValueError:
            problems.add(sec.line_of("ObjectType"), f"ObjectType: unparsable number {code_text!r}")
            continue
        if "ParameterName" not in sec.keys:
            problems.add(sec.line, f"[{sec.name}] has no ParameterName")
        if "CompactSubObj" in sec.keys:
            problems.add(sec.line_of("CompactSubObj"), "CompactSubObj is not supported: write "
                         "SubNumber and one section per sub-index")
        if index < 0x1000:
            continue
        if code in (OBJ_VAR, OBJ_DOMAIN):
            check_var_keys(sec, problems)
            for (i, s), ssec in subsecs.items():
                if i == index:
                    problems.add(ssec.line, f"[{ssec.name}]: {hexidx(index)} is a VAR, it has no "
                                 "sub-index sections")
        elif code in (OBJ_ARRAY, OBJ_RECORD):
            mine = sorted(s for (i, s) in subsecs if i == index)
            for s in mine:
                ssec = subsecs[(index, s)]
                if "ParameterName" not in ssec.keys:
                    problems.add(ssec.line, f"[{ssec.name}] has no ParameterName")
                check_var_keys(ssec, problems)
            if 0 not in mine:
                problems.add(sec.line, f"{'ARRAY' if code == OBJ_ARRAY else 'RECORD'} "
                             f"{hexidx(index)} has no sub-index 0 section [{index:04X}sub0]")
            sn = sec.get("SubNumber")
            if sn is None:
                problems.add(sec.line, f"{hexidx(index)} lacks SubNumber")
            else:
                try:
                    n = parse_int(sn)
                    if n != len(mine):
                        problems.add(sec.line_of("SubNumber"), f"SubNumber={sn} but {hexidx(index)}"
                                     f" has {len(mine)} sub-index sections")
                except ValueError:
                    problems.add(sec.line_of("SubNumber"), f"SubNumber: unparsable number {sn!r}")
        else:
            problems.add(sec.line_of("ObjectType"), f"unsupported ObjectType {code_text} "
                         "(only 0x7 VAR, 0x8 ARRAY, 0x9 RECORD)")
    check_object_lists(raw, objects, problems)
    problems.check()

    # --- python-canopen: what a master sees ---
    od = import_with_canopen(path, problems)
    problems.check()

    entries = []
    for index in sorted(od.indices):
        if index < 0x1000:
            continue  # dummy-usage objects and data type definitions: no storage
        obj = od.indices[index]
        sec = objects[index]
        code = parse_int(sec.get("ObjectType", "0x7"))
        code = OBJ_VAR if code == OBJ_DOMAIN else code
        entry = Entry(index, code, obj.name, sec)
        if code == OBJ_VAR:
            entry.subs.append(build_sub(obj, sec, 0, problems))
        else:
            for s in sorted(obj.subindices):
                var = obj.subindices[s]
                sub = build_sub(var, subsecs[(index, s)], s, problems)
                # CiA 301 makes sub 0 an UNSIGNED8 count, and the core relies on it in the
                # communication area (PDO mapping counts, 0x1003, 0x1010...). Outside it a drive
                # may really deviate (sourcetronic-st600 0x2000 sub 0 is a 16-bit data word), and
                # the simulation must follow the drive, so there it is allowed.
                if s == 0 and sub.type and sub.type != 0x05 and index < 0x2000:
                    problems.add(sub.section.line_of("DataType"), f"{hexidx(index, 0)} (highest "
                                 "sub-index supported) must be UNSIGNED8")
                entry.subs.append(sub)
        entries.append(entry)
    check_mandatory(raw, entries, problems)
    problems.check()
    check_pdo_mappings(entries, dummies, problems)
    problems.check()
    return entries


def check_var_keys(sec, problems):
    for key in ("DataType", "AccessType"):
        if key not in sec.keys:
            problems.add(sec.line, f"[{sec.name}] has no {key}")
    # python-canopen would raise a ValueError naming no line
    pm = sec.get("PDOMapping")
    if pm is not None:
        try:
            parse_int(pm)
        except ValueError:
            problems.add(sec.line_of("PDOMapping"), f"[{sec.name}] PDOMapping: unparsable number "
                         f"{pm!r}")
    # Checked before python-canopen runs: it turns a type above 0x1B into DOMAIN with a warning
    # that names no line, and keeps an unknown one below it.
    text = sec.get("DataType")
    if text is not None:
        try:
            code = parse_int(text)
        except ValueError:
            problems.add(sec.line_of("DataType"), f"[{sec.name}] DataType: unparsable number "
                         f"{text!r}")
            return
        if code not in TYPES:
            problems.add(sec.line_of("DataType"), f"[{sec.name}] unknown data type {text}")


def check_object_lists(raw, objects, problems):
    listed = {}
    for name in ("MandatoryObjects", "OptionalObjects", "ManufacturerObjects"):
        sec = raw.by_name.get(name)
        if sec is None:
            continue
        count_text = sec.get("SupportedObjects")
        keys = [k for k in sec.keys if k != "SupportedObjects"]
        if count_text is None:
            problems.add(sec.line, f"[{name}] lacks SupportedObjects")
        else:
            try:
                if parse_int(count_text) != len(keys):
                    problems.add(sec.line_of("SupportedObjects"), f"SupportedObjects={count_text} "
                                 f"but [{name}] lists {len(keys)} objects")
            except ValueError:
                problems.add(sec.line_of("SupportedObjects"), f"SupportedObjects: unparsable "
                             f"number {count_text!r}")
        for k in keys:
            v = sec.get(k)
            try:
                index = parse_int(v)
            except ValueError:
                problems.add(sec.line_of(k), f"[{name}] {k}: unparsable number {v!r}")
                continue
            if index in listed:
                problems.add(sec.line_of(k), f"{hexidx(index)} listed twice (also at line "
                             f"{listed[index]})")
                continue
            listed[index] = sec.line_of(k)
            if index not in objects:
                problems.add(sec.line_of(k), f"[{name}] lists {hexidx(index)} but there is no "
                             f"section [{index:04X}]")
    if listed:
        for index, sec in sorted(objects.items()):
            if index >= 0x1000 and index not in listed:
                problems.add(sec.line, f"object [{sec.name}] is not listed in [MandatoryObjects], "
                             "[OptionalObjects] or [ManufacturerObjects]")


class _Capture(logging.Handler):
    def __init__(self):
        super().__init__(logging.WARNING)
        self.messages = []

    def emit(self, record):
        self.messages.append(record.getMessage())


def import_with_canopen(path, problems):
    import canopen  # noqa: F401  (python-canopen 2.x)
    from canopen.objectdictionary import import_od

    log = logging.getLogger("canopen")
    capture = _Capture()
    log.addHandler(capture)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            # node_id=None: python-canopen then keeps `$NODEID+x` only in default_raw
            od = import_od(path, node_id=None)
    except configparser.Error as e:
        problems.add(getattr(e, "lineno", 1), f"python-canopen cannot parse the file: {e}")
        return None
    except Exception as e:  # noqa: BLE001 - any crash of the parser is a bad EDS
        problems.add(1, f"python-canopen cannot load the file: {type(e).__name__}: {e}")
        return None
    finally:
        log.removeHandler(capture)
    for msg in capture.messages:
        problems.add(1, f"python-canopen warns: {msg}")
    return od


def build_sub(var, sec, subindex, problems):
    sub = Sub(var.index, subindex, var.name, sec)
    where = hexidx(var.index, subindex)
    # DataType: raw, because python-canopen rewrites unknown types > 0x1B to DOMAIN
    dt_text = sec.get("DataType")
    try:
        code = parse_int(dt_text)
    except ValueError:
        problems.add(sec.line_of("DataType"), f"{where}: DataType: unparsable number {dt_text!r}")
        return sub
    if code not in TYPES:
        problems.add(sec.line_of("DataType"), f"{where}: unknown data type {dt_text}")
        return sub
    sub.type = code
    kind = TYPES[code][2]

    access = (var.access_type or "").lower()
    if access not in ACCESS_TYPES:
        problems.add(sec.line_of("AccessType"), f"{where}: unknown AccessType "
                     f"{sec.get('AccessType')!r} (ro, wo, rw, rww, rwr, const)")
        return sub
    sub.access = access

    pm_text = sec.get("PDOMapping", "0")
    try:
        pm = parse_int(pm_text)
    except ValueError:
        pm = None
    if pm not in (0, 1):
        problems.add(sec.line_of("PDOMapping"), f"{where}: PDOMapping must be 0 or 1, not "
                     f"{pm_text!r}")
        return sub
    sub.pdo = bool(pm)
    if sub.pdo and kind == "domain":
        problems.add(sec.line_of("PDOMapping"), f"{where}: a DOMAIN cannot be PDO-mapped")

    # Default: parsed here from python-canopen's verbatim default_raw (see module docstring)
    raw_default = getattr(var, "default_raw", None)
    raw_default = raw_default if raw_default not in (None, "") else None
    dline = sec.line_of("DefaultValue")
    capacity = None
    for text in sec.comments + [sec.inline.get("DefaultValue", "")]:
        m = CAPACITY_RE.search(text)
        if m:
            capacity = int(m.group(1))
    if kind in ("bool", "int", "uint"):
        lo, hi = int_range(code)
        value, rel = 0, False
        if raw_default is not None:
            try:
                value, rel = parse_default_int(raw_default)
            except ValueError:
                problems.add(dline, f"{where}: DefaultValue: unparsable number {raw_default!r}")
                return sub
        if rel:
            if kind != "uint":
                problems.add(dline, f"{where}: $NODEID default needs an unsigned type, not "
                             f"{type_name(code)}")
                return sub
            sub.flags |= F_NODEID
            if not (lo <= value + 1 and value + 127 <= hi and value >= 0):
                problems.add(dline, f"{where}: DefaultValue {raw_default} does not fit "
                             f"{type_name(code)} for node-IDs 1-127")
                return sub
        elif not lo <= value <= hi:
            problems.add(dline, f"{where}: DefaultValue {raw_default} does not fit "
                         f"{type_name(code)} ({lo}..{hi})")
            return sub
        sub.default_int = value
        sub.value = encode_number(value, code)
        sub.size = TYPES[code][1]
    elif kind == "real":
        value = 0.0
        if raw_default is not None:
            try:
                value = float(raw_default)
                if not math.isfinite(value):
                    raise ValueError(raw_default)
            except ValueError:
                problems.add(dline, f"{where}: DefaultValue: unparsable number {raw_default!r}")
                return sub
        if TYPES[code][1] == 4 and abs(value) > 3.4028234663852886e38:
            problems.add(dline, f"{where}: DefaultValue {raw_default} does not fit REAL32")
            return sub
        sub.default_int = value
        sub.value = encode_number(value, code)
        sub.size = TYPES[code][1]
    elif kind in ("vstring", "ustring"):
        text = raw_default or ""
        if kind == "vstring":
            try:
                data = text.encode("ascii")
            except UnicodeEncodeError:
                problems.add(dline, f"{where}: VISIBLE_STRING default is not ASCII")
                return sub
        else:
            data = text.encode("utf-16-le")
        if capacity is not None:
            if len(data) > capacity:
                problems.add(dline, f"{where}: default string is {len(data)} bytes, longer than "
                             f"its capacity {capacity}")
                return sub
            size = capacity
        else:
            size = max(len(data), DEFAULT_STRING_CAPACITY)
        if size > 0xFFFF:
            problems.add(dline, f"{where}: string capacity {size} exceeds 65535")
            return sub
        sub.value, sub.size = data, size
    elif kind == "ostring":
        try:
            data = bytes.fromhex(raw_default or "")
        except ValueError:
            problems.add(dline, f"{where}: OCTET_STRING DefaultValue is not hex bytes: "
                         f"{raw_default!r}")
            return sub
        if not data:
            problems.add(dline, f"{where}: OCTET_STRING needs a DefaultValue: its size is the "
                         "default's length")
            return sub
        if len(data) > 0xFFFF:
            problems.add(dline, f"{where}: OCTET_STRING longer than 65535 bytes")
            return sub
        sub.value, sub.size = data, len(data)
    else:  # DOMAIN
        sub.size = 0

    # Limits: raw strings (python-canopen drops unparsable ones, float ones and 24/40/48/56-bit
    # signed ones without a word)
    lows = sec.get("LowLimit")
    highs = sec.get("HighLimit")
    for key, text in (("LowLimit", lows), ("HighLimit", highs)):
        if text == "":
            # python-canopen drops it, and with it the limit the author meant to give
            problems.add(sec.line_of(key), f"{where}: {key} is empty (give a value, or leave "
                         "the key out for no limit)")
            return sub
    if lows is not None or highs is not None:
        if kind not in ("bool", "int", "uint", "real"):
            problems.add(sec.line_of("LowLimit" if lows is not None else "HighLimit"),
                         f"{where}: LowLimit/HighLimit on a {type_name(code)}")
            return sub
        bounds = []
        for key, text in (("LowLimit", lows), ("HighLimit", highs)):
            if text is None:
                bounds.append(None)
                continue
            try:
                v = parse_limit(text, code)
            except ValueError:
                problems.add(sec.line_of(key), f"{where}: {key}: unparsable number {text!r}")
                return sub
            if kind != "real":
                lo, hi = int_range(code)
                if not lo <= v <= hi:
                    problems.add(sec.line_of(key), f"{where}: {key} {text} does not fit "
                                 f"{type_name(code)} ({lo}..{hi})")
                    return sub
            bounds.append(v)
        if kind == "real":
            tmax = 3.4028234663852886e38 if TYPES[code][1] == 4 else sys.float_info.max
            tlo, thi = -tmax, tmax
        else:
            tlo, thi = int_range(code)
        low = tlo if bounds[0] is None else bounds[0]
        high = thi if bounds[1] is None else bounds[1]
        if low > high:
            problems.add(sec.line_of("LowLimit"), f"{where}: LowLimit {lows} > HighLimit {highs}")
            return sub
        dv = sub.default_int
        if sub.flags & F_NODEID:
            if not (low <= dv + 1 and dv + 127 <= high):
                problems.add(dline, f"{where}: DefaultValue {raw_default} outside LowLimit/"
                             f"HighLimit [{lows}, {highs}] for some node-ID 1-127")
                return sub
        elif not low <= dv <= high:
            problems.add(dline, f"{where}: DefaultValue {raw_default if raw_default else 0} "
                         f"outside LowLimit/HighLimit [{lows}, {highs}]")
            return sub
        sub.limit = (limit_pattern(low, code), limit_pattern(high, code))
        sub.flags |= F_LIMITS

    # Flags
    f = {"ro": F_READ, "wo": F_WRITE, "rw": F_READ | F_WRITE, "rww": F_READ | F_WRITE,
         "rwr": F_READ | F_WRITE, "const": F_READ | F_CONST}[access]
    if sub.pdo:
        f |= {"ro": F_TPDO, "const": F_TPDO, "rwr": F_TPDO, "wo": F_RPDO, "rww": F_RPDO,
              "rw": F_TPDO | F_RPDO}[access]
    index = var.index
    stored_area = (0x1000 <= index <= 0x1FFF and index not in NOT_STORED_COMM) or \
        (0x2000 <= index <= 0x9FFF)
    if access in ("rw", "rww", "rwr") and not sub.pdo and stored_area and sub.size > 0:
        f |= F_PERSIST
    sub.flags |= f
    return sub


def check_mandatory(raw, entries, problems):
    by_index = {e.index: e for e in entries}
    sec = raw.by_name.get("MandatoryObjects")
    line = sec.line if sec else 1
    for index in (0x1000, 0x1001, 0x1018):
        if index not in by_index:
            problems.add(line, f"missing mandatory object {hexidx(index)}")
    e = by_index.get(0x1018)
    if e is not None:
        if e.code != OBJ_RECORD:
            problems.add(e.section.line_of("ObjectType"), "0x1018 (identity) must be a RECORD")
        elif not any(s.subindex == 1 for s in e.subs):
            problems.add(e.section.line, "missing mandatory 0x1018 sub 1 (vendor-ID)")
    for index, code in ((0x1000, 0x07), (0x1001, 0x05)):
        e = by_index.get(index)
        if e is not None and (e.code != OBJ_VAR or e.subs[0].type != code):
            problems.add(e.section.line, f"{hexidx(index)} must be a VAR of type {type_name(code)}")


def check_pdo_mappings(entries, dummies, problems):
    subs = {(e.index, s.subindex): s for e in entries for s in e.subs}
    for e in entries:
        if 0x1600 <= e.index <= 0x17FF:
            direction, need = "RPDO", F_RPDO
        elif 0x1A00 <= e.index <= 0x1BFF:
            direction, need = "TPDO", F_TPDO
        else:
            continue
        if e.code == OBJ_VAR:
            problems.add(e.section.line, f"PDO mapping {hexidx(e.index)} must be a RECORD or ARRAY")
            continue
        by_sub = {s.subindex: s for s in e.subs}
        count = by_sub[0].default_int or 0
        if count > 0x40:
            problems.add(by_sub[0].section.line_of("DefaultValue"),
                         f"{hexidx(e.index, 0)}: {count} mapped objects (at most 64)")
            continue
        total = 0
        for s in e.subs:
            if s.subindex == 0:
                continue
            if s.type != 0x07 or s.flags & F_NODEID:
                problems.add(s.section.line_of("DataType"), f"{hexidx(e.index, s.subindex)}: a "
                             "mapping entry must be an UNSIGNED32 without $NODEID")
                continue
            v = s.default_int or 0
            if v == 0:
                if s.subindex <= count:
                    problems.add(s.section.line_of("DefaultValue"),
                                 f"{hexidx(e.index, s.subindex)}: sub 0 says {count} mapped "
                                 "objects but this entry is empty")
                continue
            line = s.section.line_of("DefaultValue")
            tindex, tsub, bits = v >> 16, (v >> 8) & 0xFF, v & 0xFF
            what = f"{hexidx(e.index, s.subindex)}: mapping entry 0x{v:08X}"
            if bits == 0:
                problems.add(line, f"{what} has length 0")
                continue
            if 1 <= tindex <= 7:
                tsize = TYPES[tindex][1] * 8
                if direction != "RPDO":
                    problems.add(line, f"{what} maps dummy {hexidx(tindex)}: only an RPDO can "
                                 "map dummy entries")
                    continue
                if tindex not in dummies:
                    problems.add(line, f"{what} maps dummy {hexidx(tindex)}, which [DummyUsage] "
                                 "does not enable")
                    continue
                if bits != tsize and not (tindex == 1 and bits == 1):
                    problems.add(line, f"{what}: length {bits} bits does not match "
                                 f"{type_name(tindex)} ({tsize} bits)")
                    continue
            else:
                target = subs.get((tindex, tsub))
                if target is None:
                    problems.add(line, f"{what} points at {hexidx(tindex, tsub)}, which does not "
                                 "exist")
                    continue
                if not target.pdo:
                    problems.add(line, f"{what} points at {hexidx(tindex, tsub)}, which is not "
                                 "PDO-mappable (PDOMapping=0)")
                    continue
                if not target.flags & need:
                    problems.add(line, f"{what} points at {hexidx(tindex, tsub)}, which is not "
                                 f"{direction}-mappable (AccessType {target.access})")
                    continue
                kind = TYPES[target.type][2]
                if kind in ("vstring", "ostring", "ustring"):
                    if bits % 8 or bits > target.size * 8:
                        problems.add(line, f"{what}: length {bits} bits does not fit the "
                                     f"{target.size}-byte string")
                        continue
                elif bits != target.size * 8:
                    problems.add(line, f"{what}: length {bits} bits does not match "
                                 f"{type_name(target.type)} ({target.size * 8} bits)")
                    continue
            if s.subindex <= count:
                total += bits
                if total > MAX_PDO_BITS:
                    problems.add(line, f"{hexidx(e.index)}: mapped objects add up to {total} "
                                 f"bits, more than {MAX_PDO_BITS}")
        if count > len(e.subs) - 1 or any(i not in by_sub for i in range(1, count + 1)):
            problems.add(by_sub[0].section.line_of("DefaultValue"),
                         f"{hexidx(e.index, 0)}: {count} mapped objects but sub-indices 1..{count} "
                         "do not all exist")


# --------------------------------------------------------------------------------------------
# Layout and output.
# --------------------------------------------------------------------------------------------

def fnv1a(data, h=0x811C9DC5):
    for b in data:
        h = ((h ^ b) * 0x01000193) & 0xFFFFFFFF
    return h


def region_of(s):
    """The value-block region of a sub-entry (od.h), None for a DOMAIN (no value)."""
    if not s.size:
        return None
    if s.flags & F_PERSIST:
        return 0 if s.index < 0x2000 else 1
    return 2


def shape_groups(entries):
    """Entries whose sub-entries agree in everything but where their values are (sub-index, type,
    flags, size, limits, region), with at least two values: laid out as equal records one stride
    apart, so they share one descriptor run (co_od_entry.value_base)."""
    groups = {}
    for e in entries:
        if sum(1 for s in e.subs if s.size) < 2:
            continue
        key = tuple((s.subindex, s.type, s.flags, s.size, s.limit, region_of(s)) for s in e.subs)
        groups.setdefault(key, []).append(e)
    return [g for g in groups.values() if len(g) > 1]


def layout(entries):
    subs = [s for e in entries for s in e.subs]
    groups = shape_groups(entries)
    grouped = {id(s) for g in groups for e in g for s in e.subs}
    # per region: items (align, sort key, occupied bytes, place(offset)); a value is one item, so is
    # the block of records of a shape group in that region (sort key ending in 1: placed first)
    items = [[], [], []]
    for s in subs:
        r = region_of(s)
        if r is not None and id(s) not in grouped:
            def place(off, s=s):
                s.offset = off
            items[r].append((s.align, (s.index, s.subindex, 0), b"\x01" * s.size, place))
    group_info = []
    for g in groups:
        first = g[0]
        a = max(s.align for s in first.subs if s.size)
        within = {}
        rec = {}
        for r in sorted({region_of(s) for s in first.subs if s.size}):
            off = 0
            for k, s in sorted(((k, s) for k, s in enumerate(first.subs) if region_of(s) == r),
                               key=lambda ks: (-ks[1].align, ks[1].subindex)):
                off = (off + s.align - 1) // s.align * s.align
                within[k] = off
                off += s.size
            rec[r] = off
        stride = (max(rec.values()) + a - 1) // a * a
        starts = {}
        for r in rec:
            def place(off, r=r, starts=starts):
                starts[r] = off
            mask = bytearray(stride * len(g))
            for i in range(len(g)):
                for k, s in enumerate(first.subs):
                    if region_of(s) == r:
                        at = i * stride + within[k]
                        mask[at:at + s.size] = b"\x01" * s.size
            items[r].append((a, (first.index, -1, 1), bytes(mask), place))
        group_info.append((g, within, stride, starts))
    # Each region: the records of the groups first (by decreasing alignment), then every other
    # value by decreasing alignment, then (index, sub-index), at the first free place that fits:
    # a record that spans regions leaves holes one stride apart, which the others fill.
    offset = 0
    bounds = []
    for r, region in enumerate(items):
        if region:
            top = max(it[0] for it in region)
            offset = (offset + top - 1) // top * top
        start = offset
        used = bytearray()
        for al, _, mask, place in sorted(region, key=lambda it: (-it[1][2], -it[0], it[1])):
            at = start  # first fit, in steps of the alignment (start is aligned to the largest)
            while True:
                rel = at - start
                if rel + len(mask) > len(used):
                    used.extend(bytes(rel + len(mask) - len(used)))
                if not any(u and m for u, m in zip(used[rel:rel + len(mask)], mask)):
                    break
                at += al
            place(at)
            for k, m in enumerate(mask):
                if m:
                    used[rel + k] = 1
            offset = max(offset, at + max((k + 1 for k, m in enumerate(mask) if m), default=0))
        bounds.append(offset)
    for e in entries:
        sized = [s.offset for s in e.subs if s.size]
        e.value_base = min(sized) if sized else 0
    for g, within, stride, starts in group_info:
        r0 = min(starts)
        for i, e in enumerate(g):
            e.value_base = starts[r0] + i * stride
            for k, s in enumerate(e.subs):
                if s.size:
                    s.offset = starts[region_of(s)] + i * stride + within[k]
    comm, persist = bounds[0], bounds[1]
    value_size = (bounds[2] + 7) // 8 * 8
    h = 0x811C9DC5
    for s in sorted((s for s in subs if region_of(s) in (0, 1)),
                    key=lambda s: (s.index, s.subindex)):
        h = fnv1a(struct.pack("<HBBIH", s.index, s.subindex, s.type, s.offset, s.size), h)
    h = fnv1a(struct.pack("<II", comm, persist), h)
    defaults = bytearray(value_size)
    for s in subs:
        if s.size:
            defaults[s.offset:s.offset + len(s.value)] = s.value
    limits = sorted({s.limit for s in subs if s.limit is not None})
    limit_index = {lim: i for i, lim in enumerate(limits)}
    for s in subs:
        if s.limit is not None:
            s.limit_index = limit_index[s.limit]
    if len(limits) > 0xFFFF or len(entries) > 0xFFFF:
        raise EdsError([(1, "too many objects or limits for the 16-bit counts of od.h")])
    if len(limits) > 0x100:
        raise EdsError([(1, f"{len(limits)} different LowLimit/HighLimit pairs: od.h indexes at "
                            "most 256 (co_od_sub.limit is 8 bits)")])
    if value_size > 0xFFFF:
        raise EdsError([(1, f"value block of {value_size} bytes: od.h offsets are 16 bits "
                            "(at most 65535 bytes of values)")])
    return {"comm": comm, "persist": persist, "value_size": value_size, "hash": h,
            "defaults": bytes(defaults), "limits": limits}


def pack_defaults(block):
    """The default value block as co_od.packed_defaults: one control byte per piece, the number
    of zero bytes before it in its high 5 bits (0..31) and the number of bytes that follow it in
    its low 3 (0..7); a control byte of 0 ends the list (written as three zero bytes). The zero
    bytes after the last non-zero one are left out."""
    out = bytearray()
    n = len(block)
    while n > 0 and block[n - 1] == 0:
        n -= 1
    at = 0
    while at < n:
        zeros = 0
        while block[at] == 0 and zeros < 31:
            zeros += 1
            at += 1
        count = 0
        while at + count < n and count < 7 and block[at + count] != 0:
            count += 1
        out.append(zeros << 3 | count)
        out += block[at:at + count]
        at += count
    out += bytes((0, 0, 0))
    return bytes(out)


def unpack_defaults(packed, size):
    """The value block packed_defaults describes (the inverse of pack_defaults)."""
    block = bytearray(size)
    at, i = 0, 0
    while packed[i] != 0:
        at += packed[i] >> 3
        n = packed[i] & 7
        block[at:at + n] = packed[i + 1:i + 1 + n]
        i += 1 + n
        at += n
    assert len(block) == size
    return bytes(block)


def c_string(text):
    out = []
    for ch in text.encode("utf-8"):
        c = chr(ch)
        if c in '"\\?':
            out.append("\\" + c)
        elif 0x20 <= ch < 0x7F:
            out.append(c)
        else:
            out.append(f"\\{ch:03o}")
    return '"' + "".join(out) + '"'


def c_comment(text):
    text = text.replace("*/", "* /").replace("/*", "/ *").replace("??", "? ?")
    return text.rstrip("\\").replace("\r", " ")


def flags_expr(flags):
    names = [n for bit, n in FLAG_NAMES if flags & bit]
    return " | ".join(names) if names else "0u"


def source_comments(sec):
    return [c for c in sec.comments if c.lower().startswith("source")]


def compact_problems(entries):
    """Why the dictionary cannot have 6-byte sub-entries (--compact): a string longer than the
    one byte that holds its capacity, limits on a string (that byte is the limits' index only
    for the other types), or tables too large for an entry's 16-bit distance back to its
    descriptors."""
    subs = [s for e in entries for s in e.subs]
    return ([(1, f"0x{s.index:04X} sub {s.subindex}: a string of {s.size} bytes; --compact "
                 "holds a string's capacity in one byte (at most 255)")
             for s in subs if TYPES[s.type][1] is None and s.size > 0xFF] +
            [(1, f"0x{s.index:04X} sub {s.subindex}: limits on a string or DOMAIN cannot be "
                 "kept with --compact")
             for s in subs if not TYPES[s.type][1] and s.limit is not None] +
            [(1, f"{len(entries)} objects with {len(subs)} sub-entries: --compact finds an "
                 "object's descriptors at most 65535 bytes before it (at most 8 bytes per object: "
                 "its entry and a run header, and 6 per sub-entry)")
             for _ in [0] if 6 * len(subs) + 8 * len(entries) > 0xFFFF])


def generate(entries, lay, od_id, eds_name, eds_digest, header_name, packed_defaults=False,
             compact=False, pages=True):
    sym = "co_od_" + od_id.replace("-", "_")
    subs = [s for e in entries for s in e.subs]
    total_subs = len(subs)
    out = []
    w = out.append
    w(f"/* Generated by tools/eds2c.py from {c_comment(eds_name)} - do not edit.")
    w(f" * EDS SHA-256: {eds_digest}")
    w(f" * {len(entries)} objects, {total_subs} sub-entries, {len(lay['limits'])} limits;")
    w(f" * value block: {lay['value_size']} bytes, persistent 0x1000-0x1FFF [0, {lay['comm']}), "
      f"0x2000+ [{lay['comm']}, {lay['persist']}). */")
    w(f'#include "{header_name}"')
    w("")
    if compact:
        # 6-byte sub-entries (od.h, CO_CONFIG_OD_COMPACT): a numeric value's size is its type's,
        # one byte holds the limits' index or a string's capacity.
        w("#if !CO_CONFIG_OD_COMPACT")
        w('#error "generated with --compact: build with CO_CONFIG_OD_COMPACT=1"')
        w("#endif")
        w("")
    # one descriptor run per distinct (relative offsets, sizes, limits, sub-indices, types,
    # flags): entries of the same shape share it
    runs = {}
    rows = []
    starts = []
    run_list = []  # (object code, first row, row count) of each run, in order
    for e in entries:
        run = []
        for s in e.subs:
            rel = s.offset - e.value_base if s.size else 0
            if compact:
                aux = s.size if TYPES[s.type][1] is None else s.limit_index
                fields = f"{rel}u, {aux}u"
            else:
                fields = f"{rel}u, {s.size}u, {s.limit_index}u"
            run.append((f"{{{fields}, 0x{s.subindex:02X}u, {TYPES[s.type][0]}, "
                        f"{flags_expr(s.flags)}}}", f"0x{s.index:04X} sub {s.subindex} {s.access}"))
        key = tuple(r[0] for r in run)
        if key not in runs:
            runs[key] = len(rows)
            run_list.append((len(rows), len(run)))
            rows.extend(run)
        starts.append(runs[key])
    if compact:
        # Descriptors and entries in one object, so that an entry finds its descriptors by a
        # 16-bit distance back from itself (co_od_entry.subs_back, co_od_entry_subs()), and each
        # run of descriptors after a 2-byte header (co_od_run: the number of descriptors) that the
        # entries sharing the run share: 6-byte entries instead of 12 (the object code, which no
        # code of a compact build reads, is not kept).
        entry_bytes = 6
        at = {}  # first row of a run -> its byte offset in the tables
        pos = 0
        for first, count in run_list:
            at[first] = pos + 2
            pos += 2 + 6 * count
        run_bytes = pos
        w(f"static const struct {sym}_tables {{")
        for r, (first, count) in enumerate(run_list):
            w(f"    co_od_run h{r};")
            w(f"    co_od_sub s{r}[{count}];")
        w(f"    co_od_entry entries[{len(entries)}];")
        w(f"}} {sym}_tables = {{")
        w("    /* each run: {descriptors}, then its descriptors: offset from the "
          "entry's value_base, limit or string capacity, subindex, type, flags */")
        for r, (first, count) in enumerate(run_list):
            w(f"    {{{count}u}}, /* h{r}: subs[{first}] */")
            w("    {")
            for text, comment in rows[first:first + count]:
                w(f"        {text}, /* {comment} */")
            w("    },")
        w("    .entries = {")
        w("        /* index, value_base, bytes back to the first descriptor */")
        for i, (e, k) in enumerate(zip(entries, starts)):
            for c in source_comments(e.section):
                w(f"        /* {c_comment(c)} */")
            back = run_bytes + entry_bytes * i - at[k]
            w(f"        {{0x{e.index:04X}u, {e.value_base}u, {back}u}}, /* subs[{k}] */")
        w("    },")
        w("};")
        w("/* the layout the distances above count on (a negative array size otherwise) */")
        w(f"typedef char {sym}_tables_layout[offsetof(struct {sym}_tables, entries) == "
          f"{run_bytes}u && sizeof(co_od_run) == 2u && sizeof(co_od_sub) == 6u && "
          f"sizeof(co_od_entry) == {entry_bytes}u ? 1 : -1];")
        w("")
    else:
        w(f"static const co_od_sub {sym}_subs[{len(rows)}] = {{")
        w("    /* offset from the entry's value_base, size, limit, subindex, type, flags */")
        for text, comment in rows:
            w(f"    {text}, /* {comment} */")
        w("};")
        w("")
        w(f"static const co_od_entry {sym}_entries[{len(entries)}] = {{")
        for e, k in zip(entries, starts):
            for c in source_comments(e.section):
                w(f"    /* {c_comment(c)} */")
            w(f"    {{0x{e.index:04X}u, {OBJECT_CODES[e.code]}, {len(e.subs)}u, {e.value_base}u, "
              f"&{sym}_subs[{k}]}},")
        w("};")
        w("")
    if lay["limits"]:
        w(f"static const co_od_limit {sym}_limits[{len(lay['limits'])}] = {{")
        for low, high in lay["limits"]:
            w(f"    {{0x{low:016X}u, 0x{high:016X}u}},")
        w("};")
        w("")
    packed = pack_defaults(lay["defaults"]) if packed_defaults and lay["value_size"] else None
    if packed is not None:
        w(f"/* The default value block, its zero bytes counted (co_od.packed_defaults): "
          f"{len(packed)} bytes for {lay['value_size']}. */")
        w(f"static const uint8_t {sym}_packed_defaults[{len(packed)}] = {{")
        for i in range(0, len(packed), 16):
            w("    " + " ".join(f"0x{b:02X}," for b in packed[i:i + 16]))
        w("};")
        w("")
    elif lay["value_size"]:
        w(f"static const uint8_t {sym}_defaults[{lay['value_size']}] = {{")
        d = lay["defaults"]
        for i in range(0, len(d), 16):
            w("    " + " ".join(f"0x{b:02X}," for b in d[i:i + 16]) + f" /* {i} */")
        w("};")
        w("")
    # co_od.pages: the first entry of each index page (co_od_page_of in src/od_internal.h)
    def page_of(index):
        high = index >> 12
        if high == 1:
            return 1 + ((index >> 8) & 0xF)
        return 0 if high == 0 else high + 15
    if pages:
        firsts = []
        for p in range(OD_PAGES + 1):
            firsts.append(next((i for i, e in enumerate(entries) if page_of(e.index) >= p),
                               len(entries)))
        w(f"/* The first entry of each index page (co_od.pages). */")
        w(f"static const uint16_t {sym}_pages[{OD_PAGES + 1}] = {{")
        for i in range(0, len(firsts), 16):
            w("    " + " ".join(f"{v}u," for v in firsts[i:i + 16]))
        w("};")
        w("")
    w(f"const co_od {sym} = {{")
    w(f'    {c_string(od_id)},')
    w(f"    {sym}_tables.entries," if compact else f"    {sym}_entries,")
    w(f"    {sym + '_limits' if lay['limits'] else 'NULL'},")
    w(f"    {sym + '_defaults' if lay['value_size'] and packed is None else 'NULL'},")
    w(f"    {len(entries)}u, /* entry_count */")
    w(f"    {len(lay['limits'])}u, /* limit_count */")
    w(f"    {lay['value_size']}u, /* value_size */")
    w(f"    {lay['comm']}u, /* comm_persist_size */")
    w(f"    {lay['persist']}u, /* persist_size */")
    w(f"    0x{lay['hash']:08X}u, /* layout_hash */")
    w(f"    {sym + '_packed_defaults' if packed is not None else 'NULL'}, /* packed_defaults */")
    w(f"    {sym}_pages" if pages else "    NULL /* pages: every lookup searches all entries */")
    w("};")
    w("")
    w("#if !defined(CO_OD_NO_NAMES)")
    w(f"const char *const {sym}_entry_names[{len(entries)}] = {{")
    for e in entries:
        w(f"    {c_string(e.name)},")
    w("};")
    w("")
    w(f"const char *const {sym}_sub_names[{total_subs}] = {{")
    for s in subs:
        w(f"    {c_string(s.name)},")
    w("};")
    w("#endif")
    return "\n".join(out) + "\n"


def generate_header(entries, lay, od_id, eds_name):
    sym = "co_od_" + od_id.replace("-", "_")
    up = od_id.replace("-", "_").upper()
    guard = f"CO_OD_{up}_H"
    total_subs = sum(len(e.subs) for e in entries)
    return f"""/* Generated by tools/eds2c.py from {c_comment(eds_name)} - do not edit. */
#ifndef {guard}
#define {guard}

#include "canopen/od.h"

/* Sizes of the value block (see od.h): declare it 8-byte aligned, e.g.
 * uint64_t block[(CO_OD_{up}_VALUE_SIZE + 7u) / 8u]. */
#define CO_OD_{up}_VALUE_SIZE {lay['value_size']}u
#define CO_OD_{up}_COMM_PERSIST_SIZE {lay['comm']}u
#define CO_OD_{up}_PERSIST_SIZE {lay['persist']}u
#define CO_OD_{up}_LAYOUT_HASH 0x{lay['hash']:08X}u
#define CO_OD_{up}_ENTRY_COUNT {len(entries)}u
#define CO_OD_{up}_SUB_COUNT {total_subs}u

#ifdef __cplusplus
extern "C" {{
#endif

extern const co_od {sym};

#if !defined(CO_OD_NO_NAMES)
/* Names, for tools and diagnostics only (the core never needs them; build with -DCO_OD_NO_NAMES
 * or let the linker drop them). entry_names[i] names {sym}.entries[i]; sub_names[k] names the
 * k-th sub-entry, counted across all entries in table order (not the k-th descriptor: entries
 * of one shape share their descriptors). */
extern const char *const {sym}_entry_names[{len(entries)}];
extern const char *const {sym}_sub_names[{total_subs}];
#endif

#ifdef __cplusplus
}}
#endif

#endif
"""


def write_atomic(path, text):
    tmp = path + ".tmp"
    with open(tmp, "w", encoding="utf-8", newline="\n") as f:
        f.write(text)
    os.replace(tmp, path)


def main(argv=None):
    ap = argparse.ArgumentParser(description="CiA 306 EDS -> const C object dictionary tables")
    ap.add_argument("eds")
    ap.add_argument("--id", required=True, help="drive id, e.g. vf-s15")
    ap.add_argument("--out-c", help="C file to write")
    ap.add_argument("--out-h", help="header to write")
    ap.add_argument("--packed-defaults", action="store_true",
                    help="store the default values as runs of non-zero bytes (smaller; for "
                         "microcontrollers) instead of the whole value block")
    ap.add_argument("--compact", action="store_true",
                    help="6-byte sub-entries (od.h CO_CONFIG_OD_COMPACT: the size of a numeric "
                         "value from its type, strings of at most 255 bytes; for "
                         "microcontrollers)")
    ap.add_argument("--no-pages", action="store_true",
                    help="no index page table (co_od.pages NULL): a lookup is a binary search "
                         "of all entries; 64 bytes less, for a small dictionary on a "
                         "microcontroller")
    args = ap.parse_args(argv)
    if not re.match(r"^[A-Za-z][A-Za-z0-9_-]*$", args.id):
        ap.error(f"--id {args.id!r}: letters, digits, '-' and '_' only, starting with a letter")
    problems = Problems()
    try:
        entries = load(args.eds, problems)
        lay = layout(entries)
        if args.compact and compact_problems(entries):
            raise EdsError(compact_problems(entries))
    except EdsError as e:
        for line, msg in e.problems:
            print(f"{args.eds}:{line}: error: {msg}", file=sys.stderr)
        return 1
    with open(args.eds, "rb") as f:
        digest = hashlib.sha256(f.read()).hexdigest()
    eds_name = os.path.basename(args.eds)
    header_name = os.path.basename(args.out_h) if args.out_h else \
        "od_" + args.id.replace("-", "_") + ".h"
    if args.out_c:
        write_atomic(args.out_c, generate(entries, lay, args.id, eds_name, digest, header_name,
                                             args.packed_defaults, args.compact,
                                             not args.no_pages))
    if args.out_h:
        write_atomic(args.out_h, generate_header(entries, lay, args.id, eds_name))
    return 0


if __name__ == "__main__":
    sys.exit(main())
