#!/usr/bin/env python3
"""Per-instruction execution counts of one function from a callgrind file written with
--dump-instr=yes --branch-sim=yes, printed beside objdump's disassembly of the object it ran
in. Usage: callgrind-counts.py CALLGRIND_OUT FUNCTION OBJECT.so"""
import sys, re, subprocess, collections
out, fname, so = sys.argv[1], sys.argv[2], sys.argv[3]
counts = collections.defaultdict(lambda: [0,0,0])
cur_fn = None; addr = 0; skip = False
for line in open(out):
    line = line.rstrip('\n')
    if line.startswith('fn='):
        cur_fn = line.split(')',1)[-1].strip() if ')' in line else line[3:]
        continue
    if line.startswith(('ob=','fl=','fi=','fe=','cob=','cfi=','cfl=','cfn=')): continue
    if line.startswith('calls='): skip = True; continue
    if not line or not (line[0] in '0123456789+-*'): continue
    parts = line.split()
    a = parts[0]
    if a.startswith('0x'): addr = int(a, 16)
    elif a.startswith('+'): addr += int(a[1:])
    elif a.startswith('-'): addr -= int(a[1:])
    if skip: skip = False; continue
    if cur_fn != fname: continue
    vals = [int(x) for x in parts[2:]] + [0,0,0,0,0]
    c = counts[addr]; c[0] += vals[0]; c[1] += vals[1]; c[2] += vals[2]
dis = subprocess.run(['objdump','-d','--no-show-raw-insn',so], capture_output=True, text=True).stdout
for l in dis.split('\n'):
    m = re.match(r'\s+([0-9a-f]+):\s+(.*)', l)
    if not m: continue
    a = int(m.group(1), 16)
    if a in counts:
        c = counts[a]
        print(f"{a:6x} {c[0]:10d} {c[2]:9d}  {re.sub(r'<[^>]*>','',m.group(2))[:60]}")
