"""Makes a copy of cl/ count the nodes each traversal visits into the sample programs' ray
counts (`render --json`'s `rays`), for `bin64` and the wide layouts. Usage: cp -r cl /tmp/k &&
python3 count-visits.py /tmp/k && CLTRACE_KERNEL_DIR=/tmp/k cltrace render ... --json r.json.
count-triangles.diff (on top of it) counts triangle tests instead, in bin64."""
import sys
d = sys.argv[1]
def ed(p, a, b, count=1):
    s = open(f"{d}/{p}").read(); assert a in s, (p, a); s = s.replace(a, b, count); open(f"{d}/{p}", "w").write(s)
sig = "FORCE_INLINE uint trace(SCENE_PARAMS, float3 org, float3 dir, float t_max, bool any_hit, bool incoherent, float* t_hit) {"
new = "FORCE_INLINE uint trace_impl(SCENE_PARAMS, float3 org, float3 dir, float t_max, bool any_hit, bool incoherent, float* t_hit, uint* visits_) {"
for f in ["wide.cl", "bin64.cl"]:
    ed(f, sig, new)
ed("wide.cl", "        const __global WIDE_NODE* n = &nodes[node];\n", "        const __global WIDE_NODE* n = &nodes[node];\n        *visits_ += 1;\n")
ed("bin64.cl", "        const __global float4* n = (const __global float4*)&nodes[node];\n", "        const __global float4* n = (const __global float4*)&nodes[node];\n        *visits_ += 1;\n")
# leaf triangle tests counted separately in the high 16 bits? keep node visits only
for f in ["wide.cl", "bin64.cl"]:
    ed(f, "#define SCENE nodes, tris, status, SURFACE\n", "#define SCENE nodes, tris, status, SURFACE\n#define trace(...) trace_impl(__VA_ARGS__, &visits_)\n")
ed("integrator.cl", "FORCE_INLINE bool occluded(SCENE_PARAMS, float3 org, float3 dir, float t_max) {\n    float t;\n", "FORCE_INLINE bool occluded(SCENE_PARAMS, float3 org, float3 dir, float t_max) {\n    float t; uint visits_ = 0;\n")
ed("integrator.cl", "    uint rays_traced = 0;\n", "    uint rays_traced = 0; uint visits_ = 0;\n")
ed("integrator.cl", "        rays_traced += p.count;\n", "")
ed("integrator.cl", "(long3)(0), sample_count, rays_traced);", "(long3)(0), sample_count, visits_);")
ed("integrator.cl", "__kernel void sample_ao(SAMPLE_PARAMS) {\n    SAMPLE_PIXEL\n", "__kernel void sample_ao(SAMPLE_PARAMS) {\n    SAMPLE_PIXEL\n    uint visits_ = 0;\n")
ed("integrator.cl", "__kernel void sample_shadow(SAMPLE_PARAMS) {\n    SAMPLE_PIXEL\n", "__kernel void sample_shadow(SAMPLE_PARAMS) {\n    SAMPLE_PIXEL\n    uint visits_ = 0;\n")
ed("trace.cl", "    float t;\n    uint best = trace(", "    float t; uint visits_ = 0;\n    uint best = trace(", 2)
