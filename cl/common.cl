/* common.cl: what every cltrace program starts with, after the constants the host writes
 * in front of it (MISS, LEAF_FLAG, SHADE_* and the rest: generated from their Rust
 * definitions by src/device/program.rs, pinned by tests/layout.rs). It holds the
 * floating-point contract, the inlining attribute, and the structs every kernel reads:
 * Triangle (src/intersect.rs), Material (src/material.rs) and Hit (src/render/mod.rs),
 * each mirroring the #[repr(C)] Rust struct of its name; tests/layout.rs pins their sizes
 * and field offsets on both sides through probe.cl. The arithmetic of every file mirrors
 * the Rust CPU reference operation for operation, so that a device and the host pick the
 * same triangle for every pixel. */

/* a * b + c must round twice, exactly as on the host: no fused multiply-adds. */
#pragma OPENCL FP_CONTRACT OFF

/* Every helper is inlined: PoCL 3.1 kept intersect_triangle a call inside the traversal
 * loop, and forcing it was measured faster there (docs/performance.md, "Kernel changes,
 * measured"); NVIDIA inlines them anyway. */
#define FORCE_INLINE inline __attribute__((always_inline))

/* Every kernel a render launches is declared KERNEL. Intel's CPU runtime packs work-items
 * into SIMD lanes wherever a work-group fills them (8 x 8 groups do on AVX2 CPUs): its
 * traversal and stack reads become gathers and every lane walks the longest loop, which
 * ran path tracing 4-5x and ray tracing 3x slower than the scalar kernel it builds when
 * told not to pack (docs/bench/2026-12-05-intel-scalar.md). */
#ifdef cl_intel_vec_len_hint
#define KERNEL __kernel __attribute__((intel_vec_len_hint(1)))
#else
#define KERNEL __kernel
#endif

/* A triangle as the intersector reads it: three corners, each padded to 16 bytes so that a
 * corner is one vector load. `prim` is the triangle's index in file order, `material` its
 * index into the Material array, `flags` TRIANGLE_MASKED for a cut-out material and
 * TRIANGLE_TWO_SIDED for an emitter shining from both faces. */
typedef struct {
    float v0[3]; uint prim;
    float v1[3]; uint material;
    float v2[3]; uint flags;
} Triangle;

/* A material (src/material/mod.rs): base colour and emission with their textures, the
 * glTF metallic-roughness factors, the normal map, the cut-out mask and the occlusion map,
 * then the scattering model (BSDF_*, cl/bsdf.cl) and its parameters. A texture slot is an
 * index into the texture table, or NO_TEXTURE. */
typedef struct {
    float albedo[3]; int base_texture;
    float emission[3]; int emission_texture;
    float metallic; float roughness; int metallic_roughness_texture; int normal_texture;
    float normal_scale; int alpha_texture; float alpha_cutoff; int occlusion_texture;
    float specular[3]; uint bsdf;
    float eta[3]; float ior;
    float k[3]; uint reserved;
} Material;

/* One pixel's closest hit: the triangle's index in file order (MISS for none) and the
 * distance from the eye along the ray (+inf for a miss). */
typedef struct {
    uint prim;
    float t;
} Hit;

/* The three floats from p, as one vector. */
FORCE_INLINE float3 load3(const __global float* p) { return (float3)(p[0], p[1], p[2]); }

/* |d|, summed in the host's order (src/render/cpu.rs scales distances by it). */
FORCE_INLINE float length3(float3 d) { return sqrt(d.x * d.x + d.y * d.y + d.z * d.z); }
