#!/usr/bin/env python3
"""Exact instruction counts of a PoCL kernel by source line, function and file.

Reads a callgrind profile taken with --dump-instr=yes (kernel-lines.sh takes one) and the
kernel's shared object from PoCL's cache. PoCL runs a kernel through its work-group
function, `_pocl_kernel_<name>_workgroup`, which carries no line table; the plain
`_pocl_kernel_<name>` beside it does, and is compiled from the same code. So the two
functions' instructions are aligned (difflib, on opcodes with registers and addresses
masked), and each counted instruction of the work-group function takes the line of its
match, or of the last matched one before it. The counts are exact; their lines near.

    kernel_lines.py PROFILE KERNEL_SO CL_DIR KERNEL SAMPLES [LINES]
"""
import bisect
import collections
import difflib
import re
import subprocess
import sys


def costs(profile, so):
    """Self instruction counts by address inside `so`, from a callgrind profile."""
    objects, cost = {}, collections.Counter()
    inside, addr, after_call = False, 0, False
    for line in open(profile):
        line = line.rstrip("\n")
        if line.startswith(("ob=", "cob=")):
            # An object is named where it first appears, in either form.
            m = re.match(r"c?ob=\((\d+)\)\s*(.*)", line)
            if m and m.group(2):
                objects[m.group(1)] = m.group(2)
            if line.startswith("ob="):
                inside = bool(m) and so in objects.get(m.group(1), "")
            continue
        if line.startswith("calls="):
            after_call = True  # the next line is the call's inclusive cost
            continue
        if not inside or not line or line[0] not in "+-*0":
            continue
        fields = line.split()
        a = fields[0]
        if a.startswith("0x"):
            addr = int(a, 16)
        elif a[0] in "+-":
            step = int(a[1:], 16) if a[1:].startswith("0x") else int(a[1:])
            addr += step if a[0] == "+" else -step
        if after_call:
            after_call = False
        elif len(fields) >= 3:
            cost[addr] += int(fields[2])
    return cost


def functions(so):
    """Each function's instructions as (address, opcode and operands, registers masked)."""
    text = subprocess.run(["objdump", "-d", "--no-show-raw-insn", so], capture_output=True, text=True, check=True).stdout
    found, current = {}, None
    for line in text.splitlines():
        m = re.match(r"^[0-9a-f]+ <(\S+)>:", line)
        if m:
            current = found.setdefault(m.group(1), [])
            continue
        m = re.match(r"^\s+([0-9a-f]+):\s+(\S+)\s*(.*)$", line)
        if m and current is not None:
            ops = re.sub(r"<[^>]*>", "", re.sub(r"%[a-z0-9]+", "R", re.sub(r"0x[0-9a-f]+", "N", m.group(3))))
            current.append((int(m.group(1), 16), m.group(2) + " " + ops))
    return found


def line_table(so):
    text = subprocess.run(["objdump", "--dwarf=decodedline", so], capture_output=True, text=True, check=True).stdout
    rows = sorted((int(m.group(3), 16), m.group(1), int(m.group(2)))
                  for m in re.finditer(r"^(\S+\.(?:cl|h))\s+(\d+)\s+(0x[0-9a-f]+)", text, re.M))
    return [r[0] for r in rows], rows


def enclosing_functions(path):
    """(first line, name) of each top-level function of a kernel file, and its lines."""
    try:
        src = open(path).read().splitlines()
    except OSError:
        return [], []
    heads = []
    for i, s in enumerate(src, 1):
        m = re.match(r"^(?:FORCE_INLINE |KERNEL )*[A-Za-z_][A-Za-z0-9_ *]*?\b([a-z_][a-z0-9_]*)\(", s)
        if m and not s.startswith(("#", " ", "}", "/")):
            heads.append((i, m.group(1)))
    return heads, src


def main():
    profile, so, cl_dir, kernel, samples = sys.argv[1:6]
    shown = int(sys.argv[6]) if len(sys.argv) > 6 else 40
    samples = int(samples)
    cost = costs(profile, so)
    funcs = functions(so)
    plain, group = funcs[f"_pocl_kernel_{kernel}"], funcs[f"_pocl_kernel_{kernel}_workgroup"]
    match = difflib.SequenceMatcher(None, [i[1] for i in plain], [i[1] for i in group], autojunk=False)
    source_of = {}
    for a, b, n in match.get_matching_blocks():
        for k in range(n):
            source_of[group[b + k][0]] = plain[a + k][0]
    starts, rows = line_table(so)
    by_line, last, matched = collections.Counter(), None, 0
    for addr, _ in group:
        c = cost.get(addr, 0)
        if addr in source_of:
            last, matched = source_of[addr], matched + c
        i = bisect.bisect_right(starts, last) - 1 if last is not None else -1
        by_line[(rows[i][1], rows[i][2]) if i >= 0 else ("?", 0)] += c
    total = sum(cost.values())
    print(f"{total:,} instructions, {total / samples:.0f} a sample; {100 * matched / max(total, 1):.0f}% of them matched exactly")
    files, by_func, by_file = {}, collections.Counter(), collections.Counter()
    for (f, ln), c in by_line.items():
        heads, _ = files.setdefault(f, enclosing_functions(f"{cl_dir}/{f}"))
        name = next((n for i, n in reversed(heads) if i <= ln), "?")
        by_func[f"{f}:{name}"] += c
        by_file[f] += c
    for title, table in (("file", by_file), ("function", by_func)):
        print(f"== by {title} (a sample, share)")
        for k, c in table.most_common(shown):
            print(f"{c / samples:8.1f} {100 * c / total:5.1f}%  {k}")
    print("== by line (a sample, share; line 0: no line of its own)")
    for (f, ln), c in by_line.most_common(shown):
        src = files.get(f, ([], []))[1]
        text = src[ln - 1].strip()[:80] if 0 < ln <= len(src) else ""
        print(f"{c / samples:8.1f} {100 * c / total:5.1f}%  {f}:{ln}  {text}")


if __name__ == "__main__":
    main()
