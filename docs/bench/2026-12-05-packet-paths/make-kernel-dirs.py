#!/usr/bin/env python3
"""Makes the kernel directories (CLTRACE_KERNEL_DIR) of the 2026-12-05 packet-paths runs
from main's cl/ and the files beside this script: packet (packet.cl in place of
sample_path), packet-4 and packet-16 (the same 4 and 16 lanes wide), packet-bsdf-twice
and packet-lane-part-twice (its vector BSDF work, or its per-lane surface point and
emitter pick, done twice), movemask and ordered-leaves (cl/wide.cl variants),
ray-setup-twice (every traversal's ray constants computed twice) and vector-divisions
(their six divisions as two vector ones), shuffle (the watertight test's axis picks as
one shuffle a vertex) and shuffle-movemask (both), select (the picks as
two branch-free selects of a vector per vertex); each of the traversal variants also
with a "-noinline" twin whose trace is a function of its own, for cachegrind's counts. Usage: make-kernel-dirs.py CL_DIR OUT_DIR"""
import os, shutil, subprocess, sys
here = os.path.dirname(os.path.abspath(__file__))
cl, out = sys.argv[1], sys.argv[2]
def copy(name):
    d = os.path.join(out, name)
    shutil.rmtree(d, ignore_errors=True)
    shutil.copytree(cl, d)
    return d
def patch(d, diff):
    subprocess.run(["patch", "-s", "-p2", "-d", d, "-i", os.path.join(here, diff)], check=True)
d = copy("packet")
p = os.path.join(d, "integrator.cl")
s = open(p).read()
a = s.index("/* The launch's samples of a pixel are traced one path after another")
b = s.rindex("#endif")
pk = open(os.path.join(here, "packet.cl")).read()
s = "#define PACKET_PATHS\n" + s[:a] + "#ifdef PACKET_PATHS\n" + pk + "#else\n" + s[a:b] + "#endif\n" + s[b:]
open(p, "w").write(s)
d2 = copy("packet-bsdf-twice")
shutil.copy(p, os.path.join(d2, "integrator.cl"))
patch(d2, "packet-bsdf-twice.diff")
patch(copy("movemask"), "wide-movemask.diff")
patch(copy("ordered-leaves"), "wide-ordered-leaves.diff")
d3 = copy("packet-lane-part-twice")
shutil.copy(p, os.path.join(d3, "integrator.cl"))
patch(d3, "packet-lane-part-twice.diff")
patch(copy("ray-setup-twice"), "ray-setup-twice.diff")
patch(copy("vector-divisions"), "vector-divisions.diff")
patch(copy("shuffle"), "intersect-shuffle.diff")
patch(copy("select"), "intersect-select.diff")
d4 = copy("shuffle-movemask")
patch(d4, "intersect-shuffle.diff")
patch(d4, "wide-movemask.diff")
for name in ("main", "movemask", "ordered-leaves", "vector-divisions", "shuffle", "shuffle-movemask"):
    src = cl if name == "main" else os.path.join(out, name)
    d = os.path.join(out, name + "-noinline")
    shutil.rmtree(d, ignore_errors=True)
    shutil.copytree(src, d)
    w = os.path.join(d, "wide.cl")
    t = open(w).read()
    old = "FORCE_INLINE uint trace(SCENE_PARAMS"
    assert old in t
    open(w, "w").write(t.replace(old, "__attribute__((noinline)) uint trace(SCENE_PARAMS"))
# The packet kernel 4 and 16 lanes wide: its vector types renamed.
import re
for n in (4, 16):
    d = copy(f"packet-{n}")
    s = open(os.path.join(out, "packet", "integrator.cl")).read()
    for t in ("float", "int", "uint"):
        s = re.sub(rf"\b{t}8\b", f"{t}{n}", s)
    for f in ("vload", "vstore", "as_int", "convert_float"):
        s = s.replace(f"{f}8", f"{f}{n}")
    s = s.replace("#define NL 8", f"#define NL {n}")
    open(os.path.join(d, "integrator.cl"), "w").write(s)
