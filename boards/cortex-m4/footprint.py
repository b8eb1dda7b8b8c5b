#!/usr/bin/env python3
"""footprint.py - sizes and worst stack depth of the Cortex-M4 firmwares (docs/performance.md).

    python3 boards/cortex-m4/footprint.py BUILD_DIR [--json]

reads BUILD_DIR/firmware.json (written by boards/cortex-m4/CMakeLists.txt) and reports, per
firmware:
  text, data, bss      arm-none-eabi-size (Berkeley: text = code + read-only data, which includes
                       the dictionary's const tables), minus the empty-main baseline, as
                       CANopenNode was measured (docs/performance.md, "Method")
  ram                  data + bss minus the baseline, minus the dictionary's value block
                       (`od_values`): the static RAM of the stack itself, which is what
                       CANopenNode's 4.6 kB counts (its OD values are .data, counted apart)
  od_values, node      the value block and the co_node, from the symbol table
  breakdown            bytes per source (each core .c, the dictionary tables, the board, libgcc's
                       soft-float, newlib), from the linker map, after --gc-sections
  stack                the deepest path from main through the call graph gcc writes with
                       -fcallgraph-info=su, each function counted with its -fstack-usage frame.
                       Approximations, on the safe side: a call through a pointer (driver send,
                       storage, hooks, event callbacks) is taken to reach the deepest of the
                       functions that take as many arguments as the call passes and that the
                       sources store in a struct member of that name (`hook->write(...)` reaches
                       the functions put in a `.write` member, by assignment or positional
                       initializer of a typedef'd struct) or somewhere the sources do not tell;
                       recursion is counted once;
                       a tail call counts as a call; library functions without
                       stack data (memcpy, the soft-float helpers) count LIBRARY_FRAME bytes; a
                       'dynamic' frame (alloca, VLAs) is flagged. Exceptions and interrupts are
                       not in the graph (a port adds its ISR depth).
"""

import argparse
import json
import re
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

LIBRARY_FRAME = 32  # bytes assumed for a library function without -fstack-usage data
TOOL_PREFIX = "arm-none-eabi-"


def run(cmd):
    return subprocess.run(cmd, check=True, capture_output=True, text=True).stdout


def berkeley_size(elf):
    out = run([TOOL_PREFIX + "size", "-B", str(elf)]).splitlines()
    text, data, bss = (int(x) for x in out[1].split()[:3])
    return {"text": text, "data": data, "bss": bss}


def symbols(elf):
    """name -> (size, type letter) for every sized symbol."""
    syms = {}
    for line in run([TOOL_PREFIX + "nm", "-S", "--size-sort", str(elf)]).splitlines():
        parts = line.split()
        if len(parts) == 4:
            syms.setdefault(parts[3], (int(parts[1], 16), parts[2]))
    return syms


def section_kinds(elf):
    """Output section name -> 'text' | 'data' | 'bss' | None, as Berkeley size counts them."""
    kinds = {}
    lines = run([TOOL_PREFIX + "objdump", "-h", str(elf)]).splitlines()
    for i, line in enumerate(lines):
        m = re.match(r"\s*\d+\s+(\S+)\s+([0-9a-f]+)", line)
        if not m or i + 1 >= len(lines):
            continue
        flags = lines[i + 1]
        if "ALLOC" not in flags:
            kinds[m.group(1)] = None
        elif "READONLY" in flags or "CODE" in flags:
            kinds[m.group(1)] = "text"
        elif "LOAD" in flags:
            kinds[m.group(1)] = "data"
        else:
            kinds[m.group(1)] = "bss"
    return kinds


def source_label(origin):
    """A short name for where an input section came from."""
    m = re.search(r"lib(core_[^/]*|canopen[^/]*)\.a\(([^)]+?)(\.c)?\.obj\)", origin)
    if m:
        return f"core {m.group(2)}" + ("" if m.group(2).endswith(".c") else ".c")
    m = re.search(r"libcm4_drive_runtime\.a\(([^)]+?)\.obj\)", origin)
    if m:
        return f"drive runtime {m.group(1)}"
    m = re.search(r"libcm4_drive_[^/]*\.a\(([^)]+?)\.obj\)", origin)
    if m:
        return f"drive description {m.group(1)}"
    if re.search(r"(cm4_)?od_[^/]*\.a\(|/od_[^/]*\.c\.obj", origin):
        return "dictionary tables"
    m = re.search(r"libgcc\.a\(([^)]+)\)", origin)
    if m:
        member = m.group(1)
        if re.search(r"(df|sf|_dv|_fix|_float|_cmp|_addsub|_mul|_div|arm_)", member):
            return "libgcc (soft-float/helpers)"
        return "libgcc"
    m = re.search(r"libc_nano\.a\((?:libc?_a-)?([^)]+?)\.o\)", origin)
    if m:
        name = m.group(1)
        return f"newlib-nano {name}" if name in ("memcpy", "memset", "memmove", "memcmp") else \
            "newlib-nano (start-up, exit)"
    if re.search(r"libnosys", origin):
        return "newlib-nano (start-up, exit)"
    if re.search(r"crt\w*\.o", origin):
        return "start-up (crt)"
    m = re.search(r"CMakeFiles/[^/]+\.dir/(.+?)\.obj$", origin)
    if m:
        return f"board {Path(m.group(1)).name}"
    return origin


def map_breakdown(map_path, kinds):
    """{label: {'text': n, 'data': n, 'bss': n}} from the linker map's memory map part."""
    lines = Path(map_path).read_text().splitlines()
    try:
        start = lines.index("Linker script and memory map")
    except ValueError:
        return {}
    out = defaultdict(lambda: {"text": 0, "data": 0, "bss": 0})
    current = None
    pending = None  # an input section name whose address/size is on the next line
    for line in lines[start + 1:]:
        m = re.match(r"^(\.\S+)(\s+0x[0-9a-f]+\s+0x[0-9a-f]+)?", line)
        if m and not line.startswith(" "):
            current = m.group(1)
            pending = None
            continue
        kind = kinds.get(current)
        if kind is None:
            pending = None
            continue
        m = re.match(r"^ (\.\S+|COMMON)\s*$", line)
        if m:
            pending = m.group(1)
            continue
        m = re.match(r"^ (\.\S+|COMMON)\s+0x[0-9a-f]+\s+0x([0-9a-f]+)\s+(\S.*)$", line)
        if m:
            out[source_label(m.group(3))][kind] += int(m.group(2), 16)
            pending = None
            continue
        m = re.match(r"^\s+0x[0-9a-f]+\s+0x([0-9a-f]+)\s+(\S.*)$", line)
        if m and pending is not None:
            out[source_label(m.group(2))][kind] += int(m.group(1), 16)
            pending = None
            continue
        m = re.match(r"^ \*fill\*\s+0x[0-9a-f]+\s+0x([0-9a-f]+)", line)
        if m:
            out["alignment fill"][kind] += int(m.group(1), 16)
    return {k: dict(v) for k, v in out.items()}


# --- stack ----------------------------------------------------------------------------------------

_SOURCES = {}


def _source_from(location):
    """The source text from a 'file:line:col' location to the end of the file, or ''."""
    m = re.match(r"(.+):(\d+):(\d+)$", location)
    if not m:
        return ""
    path, line, col = m.group(1), int(m.group(2)), int(m.group(3))
    if path not in _SOURCES:
        try:
            _SOURCES[path] = Path(path).read_text().splitlines()
        except OSError:
            _SOURCES[path] = []
    lines = _SOURCES[path]
    if line < 1 or line > len(lines):
        return ""
    return "\n".join([lines[line - 1][col - 1:]] + lines[line:line + 40])


def _arity(text):
    """(name before the first '(', number of top-level arguments) of a call or a definition."""
    m = re.match(r"([\w\s\->.\[\]*]*?)\(", text, re.S)
    if not m:
        return None, None
    name = re.findall(r"\w+", m.group(1))
    depth, args, seen = 0, 0, False
    for ch in text[m.end():]:
        if ch in "([{":
            depth += 1
        elif ch in ")]}":
            if depth == 0:
                break
            depth -= 1
        elif ch == "," and depth == 0:
            args += 1
        elif not ch.isspace():
            seen = True
    inner = text[m.end():m.end() + 6].strip()
    if not seen or inner.startswith("void)"):
        return (name[-1] if name else None), 0
    return (name[-1] if name else None), args + 1


def _strip_comments(text):
    text = re.sub(r"/\*.*?\*/", lambda m: " " * len(m.group(0)), text, flags=re.S)
    return re.sub(r"//[^\n]*", "", text)


def struct_members(headers):
    """{struct type name: [member names in declaration order]} from typedef'd structs."""
    out = {}
    for h in headers:
        try:
            text = _strip_comments(Path(h).read_text())
        except OSError:
            continue
        for m in re.finditer(r"typedef\s+struct\s+\w*\s*\{(.*?)\}\s*(\w+)\s*;", text, re.S):
            body, name = m.groups()
            members = []
            for decl in body.split(";"):
                decl = decl.strip()
                if not decl:
                    continue
                fp = re.search(r"\(\s*\*\s*(\w+)\s*\)", decl)
                if fp:
                    members.append(fp.group(1))
                    continue
                # 'type a, b[4], *c' -> a, b, c
                head = re.sub(r"\[[^\]]*\]", "", decl)
                parts = head.split(",")
                first = re.findall(r"\w+", parts[0])
                if first:
                    members.append(first[-1])
                for extra in parts[1:]:
                    ids = re.findall(r"\w+", extra)
                    if ids:
                        members.append(ids[-1])
            out[name] = members
    return out


def pointer_members(functions, sources, structs):
    """{function name: set of struct members its address is stored in} ('?' when unknown)."""
    found = defaultdict(set)
    names = set(functions)
    for src in sources:
        try:
            text = _strip_comments(Path(src).read_text())
        except OSError:
            continue
        for m in re.finditer(r"\b(\w+)\b", text):
            name = m.group(1)
            if name not in names:
                continue
            after = text[m.end():m.end() + 40].lstrip()
            before = text[max(0, m.start() - 200):m.start()]
            if after.startswith("(") or re.search(r"([\w*]|\.|->)\s*$", before):
                continue  # a call, the definition, a declaration, or a member of that name
            am = re.search(r"(?:\.|->)\s*(\w+)\s*=\s*&?\s*$", before)
            if am:
                found[name].add(am.group(1))
                continue
            # Positional initializer: count the top-level commas back to its '{'.
            depth, commas, i = 0, 0, m.start() - 1
            while i >= 0:
                ch = text[i]
                if ch in ")]}":
                    depth += 1
                elif ch in "([":
                    depth -= 1 if depth else 0
                elif ch == "{":
                    if depth == 0:
                        break
                    depth -= 1
                elif ch == "," and depth == 0:
                    commas += 1
                elif ch == ";" and depth == 0:
                    i = -1
                    break
                i -= 1
            if i < 0:
                found[name].add("?")
                continue
            if re.search(r"(\)|\belse|;)\s*$", text[max(0, i - 40):i]):
                found[name].add("?")  # inside a block: passed or stored some other way
                continue
            tm = re.search(r"(\w+)\s+\**\s*\w+\s*(?:\[[^\]]*\])?\s*=\s*$|\((\w+)\)\s*$",
                           text[max(0, i - 120):i])
            stype = tm and (tm.group(1) or tm.group(2))
            members = structs.get(stype or "", [])
            found[name].add(members[commas] if commas < len(members) else "?")
    return found


_LOCATIONS = {}


def read_callgraph(dirs):
    """nodes: title -> (name, bytes or None, qualifier, arity); edges: title -> [targets], an
    indirect call being ('__indirect_call', member, arity)."""
    nodes, edges = {}, defaultdict(list)
    for d in dirs:
        for ci in sorted(Path(d).rglob("*.ci")):
            for line in ci.read_text().splitlines():
                m = re.match(r'node: \{ title: "([^"]+)" label: "([^"]*)"', line)
                if m:
                    title, label = m.groups()
                    parts = label.split("\\n")
                    frame, qual, arity = None, "", None
                    if len(parts) >= 3:
                        fm = re.match(r"(\d+) bytes \(([^)]*)\)", parts[2])
                        if fm:
                            frame, qual = int(fm.group(1)), fm.group(2)
                            arity = _arity(_source_from(parts[1]))[1]
                            _LOCATIONS[title] = parts[1]
                    old = nodes.get(title)
                    if old is None or (old[1] is None and frame is not None):
                        nodes[title] = (parts[0], frame, qual, arity)
                    continue
                m = re.match(r'edge: \{ sourcename: "([^"]+)" targetname: "([^"]+)"'
                             r'(?: label: "([^"]*)")?', line)
                if m:
                    src, dst, where = m.groups()
                    if dst == "__indirect_call":
                        member, arity = _arity(_source_from(where or ""))
                        edges[src].append(("__indirect_call", member, arity))
                    else:
                        edges[src].append(dst)
    return nodes, edges


def linked_functions(map_path):
    """{(object file name, function name)} of every .text.<function> section the link kept."""
    kept = set()
    lines = Path(map_path).read_text().splitlines()
    try:
        start = lines.index("Linker script and memory map")
    except ValueError:
        return kept
    pending = None
    for line in lines[start + 1:]:
        m = re.match(r"^ \.text\.(\S+?)(?:\s+0x[0-9a-f]+\s+0x([0-9a-f]+)\s+(\S.*))?$", line)
        if m:
            name = re.sub(r"^(startup|unlikely|hot|exit)\.", "", m.group(1))
            if m.group(3):
                kept.add((_object_source(m.group(3)), name))
                pending = None
            else:
                pending = name
            continue
        m = re.match(r"^\s+0x[0-9a-f]+\s+0x[0-9a-f]+\s+(\S.*)$", line)
        if m and pending is not None:
            kept.add((_object_source(m.group(1)), pending))
        pending = None
    return kept


def _object_source(origin):
    """'libcore_4x4.a(node.c.obj)' or '.../main.c.obj' -> 'node.c' / 'main.c'."""
    m = re.search(r"([\w.-]+?\.c)\.obj\)?$", origin)
    return m.group(1) if m else origin


def worst_stack(dirs, map_path):
    nodes, edges = read_callgraph(dirs)
    kept = linked_functions(map_path)
    kept_names = {name for _, name in kept}

    def short(title):
        return title.rsplit(":", 1)[-1]

    def is_linked(title):
        if ":" in title:  # a static function: 'path/file.c:name'
            path, name = title.rsplit(":", 1)
            return (Path(path).name, name) in kept
        return title in kept_names

    defined = {t for t, n in nodes.items() if n[1] is not None and is_linked(t)}
    called = {dst for src in defined for dst in edges.get(src, []) if isinstance(dst, str)}
    by_short = defaultdict(list)
    for t in defined:
        by_short[short(t)].append(t)
    # Functions reached only through pointers: linked, never called directly; and the struct
    # members their addresses are stored in, read from the sources.
    pointer_targets = sorted(t for t in defined if t not in called and short(t) != "main")
    sources = {t.rsplit(":", 1)[0] for t in nodes if ":" in t}
    sources |= {re.sub(r":\d+:\d+$", "", lbl) for lbl in _LOCATIONS.values()}
    roots = {Path(p).parent for p in sources}
    headers = [h for r in roots for h in r.glob("*.h")]
    headers += [h for r in roots for h in (r.parent / "include").rglob("*.h")]
    members = pointer_members({short(t) for t in pointer_targets}, sorted(sources),
                              struct_members(headers))
    notes = set()
    memo, on_path = {}, set()

    def depth(title):
        """(bytes, path) of the deepest chain starting at title."""
        if isinstance(title, tuple):  # an indirect call: the deepest pointer target of its arity
            _, member, arity = title
            key = ("indirect", member, arity)
            if key in memo:
                return memo[key]
            def fits(t):
                got = members.get(short(t), {"?"})
                if arity is not None and nodes[t][3] not in (None, arity):
                    return False
                return "?" in got or member is None or member in got
            cands = [t for t in pointer_targets if fits(t)]
            best = (0, [])
            for t in cands:
                d = depth(t)
                if d[0] > best[0]:
                    best = d
            if arity is None:
                notes.add("an indirect call whose arguments could not be read reaches any target")
            memo[key] = (best[0], [f"->{member or '?'}()"] + best[1])
            return memo[key]
        if title in memo:
            return memo[title]
        if title in on_path:
            notes.add(f"recursion through {short(title)}: counted once")
            return (0, [])
        if title not in defined:
            if title in by_short:  # a call to a function of another file
                return max((depth(t) for t in by_short[title]), key=lambda x: x[0])
            label = nodes.get(title, (short(title),))[0].replace("__builtin_", "")
            notes.add(f"library functions without stack data count {LIBRARY_FRAME} B each")
            return (LIBRARY_FRAME, [f"{label} (library, ~{LIBRARY_FRAME})"])
        name, frame, qual, _ = nodes[title]
        if "dynamic" in qual:
            notes.add(f"{name}: dynamic stack ({qual})")
        on_path.add(title)
        best = (0, [])
        for dst in edges.get(title, []):
            d = depth(dst)
            if d[0] > best[0]:
                best = d
        on_path.discard(title)
        memo[title] = (frame + best[0], [f"{name} ({frame})"] + best[1])
        return memo[title]

    roots = by_short.get("main", [])
    if not roots:
        return {"bytes": None, "path": [], "notes": ["no call graph for main"]}
    total, path = max((depth(r) for r in roots), key=lambda x: x[0])
    return {"bytes": total, "path": path, "notes": sorted(notes),
            "pointer_targets": sorted({short(t) for t in pointer_targets})}


def net_breakdown(breakdown, baseline):
    """The breakdown minus what the empty-main baseline has under the same label."""
    out = {}
    for label, v in breakdown.items():
        b = baseline.get(label, {})
        net = {k: v[k] - b.get(k, 0) for k in v}
        if any(net.values()):
            out[label] = net
    return out


def analyse(build_dir):
    manifest = json.loads((Path(build_dir) / "firmware.json").read_text())
    fw = {f["name"]: f for f in manifest["firmwares"]}
    base_fw = fw[manifest["baseline"]]
    base = berkeley_size(base_fw["elf"])
    base_breakdown = map_breakdown(base_fw["map"], section_kinds(base_fw["elf"]))
    results = {"baseline": base, "firmwares": {}}
    for name, f in fw.items():
        if name == manifest["baseline"]:
            continue
        size = berkeley_size(f["elf"])
        syms = symbols(f["elf"])
        od_values = syms.get("od_values", (0, ""))[0]
        node = syms.get("node", syms.get("drive", (0, "")))[0]
        net = {k: size[k] - base[k] for k in size}
        r = {
            "description": f["description"],
            "elf": size,
            "text": net["text"], "data": net["data"], "bss": net["bss"],
            "od_values": od_values, "node": node,
            "ram": net["data"] + net["bss"] - od_values,
            "ram_total": net["data"] + net["bss"],
            "breakdown": net_breakdown(map_breakdown(f["map"], section_kinds(f["elf"])),
                                       base_breakdown),
            "stack": (worst_stack(f["object_dirs"], f["map"]) if "lto" not in name else
                      {"bytes": None, "path": [], "notes": ["not analysed with -flto"]}),
        }
        results["firmwares"][name] = r
    return results


def print_report(res, out=sys.stdout, detail=("bench", "vf_s15", "vf_s15_drive")):
    base = res["baseline"]
    out.write(f"baseline (empty main): text {base['text']}  data {base['data']}  "
              f"bss {base['bss']}\n\n")
    out.write(f"{'firmware':<14} {'text':>7} {'data':>6} {'bss':>6} {'ram':>6} "
              f"{'od vals':>7} {'node':>6} {'stack':>6}  description\n")
    for name, r in res["firmwares"].items():
        out.write(f"{name:<14} {r['text']:>7} {r['data']:>6} {r['bss']:>6} {r['ram']:>6} "
                  f"{r['od_values']:>7} {r['node']:>6} {r['stack']['bytes'] or '-':>6}  "
                  f"{r['description']}\n")
    for name, r in res["firmwares"].items():
        if detail and name not in detail:
            continue
        out.write(f"\n{name}: bytes by source, after --gc-sections, minus the baseline\n")
        rows = sorted(r["breakdown"].items(), key=lambda kv: (-kv[1]["text"], -kv[1]["bss"]))
        for label, v in rows:
            if sum(v.values()):
                out.write(f"  {label:<36} text {v['text']:>6}  data {v['data']:>5}  "
                          f"bss {v['bss']:>5}\n")
        s = r["stack"]
        out.write(f"  worst stack {s['bytes']} B: {' -> '.join(s['path'])}\n")
        for n in s.get("notes", []):
            out.write(f"    note: {n}\n")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("build_dir")
    ap.add_argument("--json", action="store_true", help="print the results as JSON")
    args = ap.parse_args(argv)
    res = analyse(args.build_dir)
    if args.json:
        json.dump(res, sys.stdout, indent=1)
        sys.stdout.write("\n")
    else:
        print_report(res, detail=())


if __name__ == "__main__":
    main()
