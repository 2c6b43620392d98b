"""Makes a copy of cl/ write, for each camera ray of the bin64 primary kernel, the nodes its
traversal visits (as the f32 distance) and the triangles it tests (as the u32 triangle) into
the hit records, for simt.py. Usage: cp -r cl /tmp/kc && python3 count-steps.py /tmp/kc &&
CLTRACE_KERNEL_DIR=/tmp/kc cltrace render MESH --camera bench --width 1920 --height 1080
--layout bin64 --shade normal -o x.png --hits MESH.hits (PoCL: the counts are the device's)."""
import sys
d = sys.argv[1]
def ed(p, a, b, n=1):
    s = open(f"{d}/{p}").read(); assert s.count(a) >= 1, (p, a); s = s.replace(a, b, n); open(f"{d}/{p}", "w").write(s)
sig = "FORCE_INLINE uint trace(SCENE_PARAMS, float3 org, float3 dir, float t_max, bool any_hit, bool incoherent, float* t_hit) {"
ed("bin64.cl", sig, "FORCE_INLINE uint trace_impl(SCENE_PARAMS, float3 org, float3 dir, float t_max, bool any_hit, bool incoherent, float* t_hit, uint* visits_, uint* tests_) {")
ed("bin64.cl", "        const __global float4* n = (const __global float4*)&nodes[node];\n", "        const __global float4* n = (const __global float4*)&nodes[node];\n        *visits_ += 1;\n")
ed("bin64.cl", "#define SCENE nodes, tris, status, SURFACE\n", "#define SCENE nodes, tris, status, SURFACE\n#define trace(...) trace_impl(__VA_ARGS__, &visits_, &tests_)\n")
ed("traverse.cl", "        uint j_ = (index);                                               \\\n", "        uint j_ = (index); *tests_ += 1;                                 \\\n")
ed("trace.cl", "    float t;\n    uint best = trace(", "    float t; uint visits_ = 0, tests_ = 0;\n    uint best = trace(")
ed("trace.cl", "    store_pixel(hits, hit_pitch, colors, color_pitch, x, y - row0, best, t, dir, tris, n, shade, near, far);\n",
   "    store_pixel(hits, hit_pitch, colors, color_pitch, x, y - row0, best, t, dir, tris, n, shade, near, far);\n    { Hit hh; hh.prim = tests_; hh.t = (float)visits_; hits[(y - row0) * hit_pitch + x] = hh; }\n")
