/* cltrace.h: what every cltrace kernel shares. The structs mirror the #[repr(C)] Rust
 * structs of the same names (src/layout/, src/material.rs, src/render/mod.rs); tests/layout.rs pins their
 * sizes and field offsets on both sides through probe.cl. The arithmetic mirrors the Rust
 * CPU reference (src/camera.rs, src/triangle.rs, src/render/shade.rs) operation for
 * operation, so that a device and the host pick the same triangle for every pixel. */
#ifndef CLTRACE_H
#define CLTRACE_H

/* a * b + c must round twice, exactly as on the host: no fused multiply-adds. */
#pragma OPENCL FP_CONTRACT OFF

/* Every helper is inlined: PoCL 3.1 kept intersect_triangle a call inside the traversal
 * loop, and forcing it measured up to 19% faster there (README, Performance); NVIDIA
 * inlines them anyway. */
#define FORCE_INLINE inline __attribute__((always_inline))

#define MISS 0xFFFFFFFFu
#define LEAF_FLAG 0x80000000u

/* ---- device structs ------------------------------------------------------------------ */

/* A triangle as the intersector reads it: three corners, each padded to 16 bytes so that a
 * corner is one vector load. `prim` is the triangle's index in file order, `material` its
 * index into the Material array. */
typedef struct {
    float v0[3]; uint prim;
    float v1[3]; uint material;
    float v2[3]; uint pad;
} Triangle;

/* A diffuse material: albedo and emitted radiance. */
typedef struct {
    float albedo[3]; float pad0;
    float emission[3]; float pad1;
} Material;

/* A 32-byte BVH node, depth-first order. An inner node holds its children's indices; a
 * leaf holds its first triangle and, in `right_or_count`, LEAF_FLAG | triangle count. */
typedef struct {
    float min[3]; uint left_or_first;
    float max[3]; uint right_or_count;
} BvhNode;

/* The Aila-Laine layout: a 64-byte node holding both children's boxes. refs: left child,
 * right child, left count, right count; a child with count 0 is an inner node (its index),
 * with count > 0 a leaf of that many triangles from its index. */
typedef struct {
    float left_xy[4];   /* min.x, max.x, min.y, max.y */
    float right_xy[4];
    float z[4];         /* left min.z, max.z, right min.z, max.z */
    uint refs[4];
} Bvh64Node;

/* Wide nodes: the children's boxes plane by plane, then their references (count 0: inner
 * node; count > 0: leaf; EMPTY_SLOT: unused). */
#define EMPTY_SLOT 0xFFFFFFFFu
typedef struct {
    float min_x[4], max_x[4], min_y[4], max_y[4], min_z[4], max_z[4];
    uint child[4], count[4];
} Wide4Node;
typedef struct {
    float min_x[8], max_x[8], min_y[8], max_y[8], min_z[8], max_z[8];
    uint child[8], count[8];
} Wide8Node;

/* A compressed 8-wide node (Ylitie et al. 2017; src/layout/compressed.rs): slot k's box on
 * axis a is origin[a] + q * 2^(exponent[a] - 127) for q = lo_a[k] and hi_a[k]. Inner
 * children are contiguous from child_base in slot order (inner_mask bit k: slot k is inner);
 * leaf children's triangles are contiguous from triangle_base. meta[k]: 0 empty; inner
 * 0x38 | k; a leaf of n triangles (2^n - 1) << 5 | offset from triangle_base. */
typedef struct {
    float origin[3];
    uchar exponent[3]; uchar inner_mask;
    uint child_base;
    uint triangle_base;
    uchar meta[8];
    uchar lo_x[8], lo_y[8], lo_z[8], hi_x[8], hi_y[8], hi_z[8];
} CompressedNode;

/* One pixel's closest hit: the triangle's index in file order (MISS for none) and the
 * distance from the eye along the ray (+inf for a miss). */
typedef struct {
    uint prim;
    float t;
} Hit;

/* Shade modes, as numbered by the Rust `Shade` enum. */
#define SHADE_NORMAL 0
#define SHADE_DEPTH 1
#define SHADE_LAMBERT 2

/* ---- rays ---------------------------------------------------------------------------- */

/* Pixel (x, y)'s primary ray direction, unnormalised: p0 + (x+0.5) du + (y+0.5) dv. */
FORCE_INLINE float3 camera_ray(float4 p0, float4 du, float4 dv, uint x, uint y) {
    float fx = (float)x + 0.5f;
    float fy = (float)y + 0.5f;
    return (float3)((p0.x + fx * du.x) + fy * dv.x,
                    (p0.y + fx * du.y) + fy * dv.y,
                    (p0.z + fx * du.z) + fy * dv.z);
}

FORCE_INLINE float pick(float3 v, int k) { return k == 0 ? v.x : (k == 1 ? v.y : v.z); }

/* Per-ray constants of the watertight ray/triangle test (Woop, Benthin, Wald 2013):
 * kz is the dominant axis of the direction, (kx, ky) the other two in an order that keeps
 * the winding, and the shear maps the ray onto +z. */
typedef struct {
    float3 org;
    int kx, ky, kz;
    float sx, sy, sz;
} WatertightRay;

FORCE_INLINE WatertightRay watertight_ray(float3 org, float3 dir) {
    WatertightRay r;
    float ax = fabs(dir.x), ay = fabs(dir.y), az = fabs(dir.z);
    int kz = ax > ay ? (ax > az ? 0 : 2) : (ay > az ? 1 : 2);
    int kx = kz == 2 ? 0 : kz + 1;
    int ky = kx == 2 ? 0 : kx + 1;
    float dz = pick(dir, kz);
    if (dz < 0.0f) { int swap = kx; kx = ky; ky = swap; }
    r.org = org;
    r.kx = kx; r.ky = ky; r.kz = kz;
    r.sx = pick(dir, kx) / dz;
    r.sy = pick(dir, ky) / dz;
    r.sz = 1.0f / dz;
    return r;
}

/* Ray parameter of the hit with triangle (v0, v1, v2) if it is closer than t_max, else a
 * negative number. Watertight: a ray through a shared edge or vertex hits at least one of
 * the triangles. Zero-area triangles never hit. */
FORCE_INLINE float intersect_triangle(const WatertightRay* r, float3 v0, float3 v1, float3 v2, float t_max) {
    float3 a = v0 - r->org, b = v1 - r->org, c = v2 - r->org;
    float a_z = pick(a, r->kz), b_z = pick(b, r->kz), c_z = pick(c, r->kz);
    float ax = pick(a, r->kx) - r->sx * a_z, ay = pick(a, r->ky) - r->sy * a_z;
    float bx = pick(b, r->kx) - r->sx * b_z, by = pick(b, r->ky) - r->sy * b_z;
    float cx = pick(c, r->kx) - r->sx * c_z, cy = pick(c, r->ky) - r->sy * c_z;
    float u = cx * by - cy * bx;
    float v = ax * cy - ay * cx;
    float w = bx * ay - by * ax;
    if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) return -1.0f;
    float det = u + v + w;
    if (det == 0.0f) return -1.0f;
    float t = u * (r->sz * a_z) + v * (r->sz * b_z) + w * (r->sz * c_z);
    if (det > 0.0f ? !(t > 0.0f && t < t_max * det) : !(t < 0.0f && t > t_max * det)) return -1.0f;
    return t / det;
}

FORCE_INLINE float3 load3(const __global float* p) { return (float3)(p[0], p[1], p[2]); }

/* Widens a box's exit distance so that rounding in the slab test never culls a box the ray
 * touches: 1 + 2 gamma(3) (Ize 2013), exactly 1 + 3 ulp in float. */
#define ROBUST_EXIT (1.0f + 3.0f * FLT_EPSILON)

/* 1 / dir per component: a zero component gives an infinite inverse. Where the origin lies
 * in that slab's plane, 0 * inf makes the slab's distances NaN, which fmin and fmax skip, so
 * a ray lying in a box face's plane counts as inside the slab (src/bvh/traverse.rs). */
FORCE_INLINE float3 safe_inverse(float3 d) {
    return (float3)(1.0f / d.x, 1.0f / d.y, 1.0f / d.z);
}

/* A stored triangle is three 16-byte rows (v0 prim, v1 material, v2 pad), 16-byte aligned
 * in its buffer: three vector loads instead of nine scalar ones. */
FORCE_INLINE float intersect_stored(const WatertightRay* r, const __global Triangle* tri, float t_max) {
    const __global float4* row = (const __global float4*)tri;
    return intersect_triangle(r, row[0].xyz, row[1].xyz, row[2].xyz, t_max);
}

/* ---- traversal ----------------------------------------------------------------------- */

/* A program is compiled for one of two scenes: with STACK_SIZE defined (the BVH's depth)
 * kernels traverse the BVH, without it they test every triangle. SCENE_PARAMS declares the
 * scene's kernel parameters and SCENE passes them on, so every kernel is written once. */

#define STATUS_STACK_OVERFLOW 1u

/* LAYOUT selects the node format of a BVH program: 32 (the thesis's node, the default),
 * 64 (Aila-Laine), 4 or 8 (wide), 80 (compressed 8-wide). */
#if defined(STACK_SIZE) && !defined(LAYOUT)
#define LAYOUT 32
#endif

#ifdef LAYOUT
#if LAYOUT == 32
#define NODE BvhNode
#elif LAYOUT == 64
#define NODE Bvh64Node
#elif LAYOUT == 4
#define NODE Wide4Node
#elif LAYOUT == 8
#define NODE Wide8Node
#elif LAYOUT == 80
#define NODE CompressedNode
#else
#error "LAYOUT must be 32, 64, 4, 8 or 80"
#endif
#ifndef STACK_SIZE
#error "a BVH program needs STACK_SIZE"
#endif
#define SCENE_PARAMS __global const NODE* nodes, __global const Triangle* tris, __global uint* status
#define SCENE nodes, tris, status
#endif

/* The inverse used for near planes: where a subnormal (or zero) direction component made
 * the inverse infinite, +-FLT_MAX, an entry no later than the true one (the far planes keep
 * the infinity, an exit no earlier): both err towards visiting the box. */
FORCE_INLINE float3 near_inverse(float3 inv) {
    return select(inv, copysign((float3)(FLT_MAX), inv), isinf(inv));
}

/* Entry distance into the box [lo, hi] if the ray meets it before t_max, else -1: the
 * robust slab test of src/bvh/traverse.rs. */
FORCE_INLINE float box_entry(float3 lo, float3 hi, float3 org, float3 inv, float t_max) {
    /* Each slab's near and far planes are picked by the inverse's sign, not by comparing
     * distances, so that a NaN never stands in for the wrong one; fmin and fmax skip NaNs. */
    int3 back = signbit(inv);
    float3 tn = (select(lo, hi, back) - org) * near_inverse(inv);
    float3 tf = (select(hi, lo, back) - org) * inv;
    float near = fmax(fmax(tn.x, tn.y), fmax(tn.z, 0.0f));
    float far = fmin(fmin(fmin(tf.x, tf.y), tf.z) * ROBUST_EXIT, t_max);
    return near <= far ? near : -1.0f;
}

/* Keeps a triangle test's result h (negative: no hit) for triangle `index` as the closest
 * hit so far (t, best); with any_hit, the first hit ends the traversal. */
#define KEEP_HIT(h, index)                                               \
    if ((h) >= 0.0f) {                                                   \
        t = (h);                                                         \
        best = (index);                                                  \
        if (any_hit) { *t_hit = t; return best; }                        \
    }

/* Tests triangle `index` against the closest hit so far. */
#define TEST_TRIANGLE(index)                                             \
    {                                                                    \
        uint j_ = (index);                                               \
        float h_ = intersect_stored(&ray, &tris[j_], t);                 \
        KEEP_HIT(h_, j_)                                                 \
    }

/* Tests a leaf's triangles [first, first + count). */
#define TEST_LEAF(first, count)                                          \
    for (uint i_ = (first), end_ = (first) + (count); i_ < end_; ++i_) TEST_TRIANGLE(i_)

/* TEST_LEAF for count >= 1 with the next triangle's rows loading while one is tested, so
 * that a leaf costs one memory latency instead of one per triangle. On the H100 it makes
 * bin64's incoherent rays 7-10% faster at 1920x1080 (20% at 960x540, where the slowest
 * rays set the time) but coherent ones 2-5% slower, and the other layouts slower still
 * (README, "Kernel changes, measured"): bin64 uses it for incoherent rays only. */
#define TEST_LEAF_PIPELINED(first, count)                                \
    {                                                                    \
        uint i_ = (first), end_ = i_ + (count);                          \
        const __global float4* row_ = (const __global float4*)&tris[i_]; \
        float4 a_ = row_[0], b_ = row_[1], c_ = row_[2];                 \
        for (; i_ < end_; ++i_) {                                        \
            row_ = (const __global float4*)&tris[min(i_ + 1, end_ - 1)]; \
            float4 next_a_ = row_[0], next_b_ = row_[1], next_c_ = row_[2]; \
            float h_ = intersect_triangle(&ray, a_.xyz, b_.xyz, c_.xyz, t); \
            KEEP_HIT(h_, i_)                                             \
            a_ = next_a_; b_ = next_b_; c_ = next_c_;                    \
        }                                                                \
    }

/* Pops the next stacked node still nearer than the closest hit into `node`, or leaves the
 * traversal loop when none is left. */
#define POP_OR_BREAK                                                     \
    {                                                                    \
        bool found_ = false;                                             \
        while (sp > 0) {                                                 \
            --sp;                                                        \
            if (stack_entry[sp] <= t) { node = stack_node[sp]; found_ = true; break; } \
        }                                                                \
        if (!found_) break;                                              \
    }

#if defined(LAYOUT) && LAYOUT == 32

/* Entry distance into `node`'s box if the ray meets it before t_max, else -1. */
FORCE_INLINE float hit_box(const __global BvhNode* node, float3 org, float3 inv, float t_max) {
    const __global float4* row = (const __global float4*)node;
    return box_entry(row[0].xyz, row[1].xyz, org, inv, t_max);
}

/* The triangle (index into tris) the ray (org, dir) hits first in (0, t_max), or with
 * any_hit the first one found at all; MISS for none. *t_hit gets the ray parameter.
 * A stack in private memory, nearer child first, boxes beyond the closest hit skipped;
 * mirrors src/bvh/traverse.rs step for step. The stack holds STACK_SIZE entries, the
 * tree's depth, which a traversal never needs more than; should it anyway, bit 0 of
 * *status is set and the ray reported as a miss, never written out of bounds.
 * `incoherent` (a constant at every call) says the rays of neighbouring work-items go
 * different ways (bounces, ambient occlusion, arbitrary rays) rather than together (camera
 * rays): a layout may pick its traversal by it; the result is the same either way. */
FORCE_INLINE uint trace(SCENE_PARAMS, float3 org, float3 dir, float t_max, bool any_hit, bool incoherent, float* t_hit) {
    WatertightRay ray = watertight_ray(org, dir);
    float3 inv = safe_inverse(dir);
    float t = t_max;
    uint best = MISS;
    uint stack_node[STACK_SIZE];
    float stack_entry[STACK_SIZE];
    uint sp = 0;
    uint node = 0;
    bool live = hit_box(&nodes[0], org, inv, t) >= 0.0f;
    while (live) {
        const __global BvhNode* n = &nodes[node];
        bool descend = false;
        if (n->right_or_count & LEAF_FLAG) {
            TEST_LEAF(n->left_or_first, n->right_or_count & ~LEAF_FLAG);
        } else {
            uint l = n->left_or_first, r = n->right_or_count;
            float tl = hit_box(&nodes[l], org, inv, t);
            float tr = hit_box(&nodes[r], org, inv, t);
            if (tl >= 0.0f && tr >= 0.0f) {
                if (sp >= STACK_SIZE) { atomic_or(status, STATUS_STACK_OVERFLOW); return MISS; }
                bool right_first = tr < tl;
                stack_node[sp] = right_first ? l : r;
                stack_entry[sp] = right_first ? tl : tr;
                ++sp;
                node = right_first ? r : l;
                descend = true;
            } else if (tl >= 0.0f) {
                node = l;
                descend = true;
            } else if (tr >= 0.0f) {
                node = r;
                descend = true;
            }
        }
        if (!descend) {
            /* Pop the next node still nearer than the closest hit. */
            live = false;
            while (sp > 0) {
                --sp;
                if (stack_entry[sp] <= t) { node = stack_node[sp]; live = true; break; }
            }
        }
    }
    *t_hit = t;
    return best;
}

#elif defined(LAYOUT) && LAYOUT == 64

/* Aila-Laine traversal: one 64-byte fetch tests both children; leaf children are tested at
 * once, inner ones visited nearer first. Same contract as the LAYOUT 32 trace. The stack
 * keeps node indices only: a popped node's children are tested against the closest hit
 * anyway, and halving the stack traffic measured 3-5% faster on the H100 than culling
 * popped nodes by a stored entry distance. */
FORCE_INLINE uint trace(SCENE_PARAMS, float3 org, float3 dir, float t_max, bool any_hit, bool incoherent, float* t_hit) {
    WatertightRay ray = watertight_ray(org, dir);
    float3 inv = safe_inverse(dir);
    float t = t_max;
    uint best = MISS;
    uint stack_node[STACK_SIZE];
    uint sp = 0;
    uint node = 0;
    for (;;) {
        const __global float4* n = (const __global float4*)&nodes[node];
        float4 lxy = n[0], rxy = n[1], z = n[2];
        uint4 refs = as_uint4(n[3]);
        float tl = box_entry((float3)(lxy.x, lxy.z, z.x), (float3)(lxy.y, lxy.w, z.y), org, inv, t);
        float tr = box_entry((float3)(rxy.x, rxy.z, z.z), (float3)(rxy.y, rxy.w, z.w), org, inv, t);
        bool hl = tl >= 0.0f, hr = tr >= 0.0f;
        if (incoherent) {
            if (hl && refs.z != 0) { TEST_LEAF_PIPELINED(refs.x, refs.z); hl = false; }
            if (hr && refs.w != 0) { TEST_LEAF_PIPELINED(refs.y, refs.w); hr = false; }
        } else {
            if (hl && refs.z != 0) { TEST_LEAF(refs.x, refs.z); hl = false; }
            if (hr && refs.w != 0) { TEST_LEAF(refs.y, refs.w); hr = false; }
        }
        if (hl && hr) {
            if (sp >= STACK_SIZE) { atomic_or(status, STATUS_STACK_OVERFLOW); return MISS; }
            bool right_first = tr < tl;
            stack_node[sp++] = right_first ? refs.x : refs.y;
            node = right_first ? refs.y : refs.x;
        } else if (hl) {
            node = refs.x;
        } else if (hr) {
            node = refs.y;
        } else if (sp > 0) {
            node = stack_node[--sp];
        } else {
            break;
        }
    }
    *t_hit = t;
    return best;
}

#elif defined(LAYOUT) && (LAYOUT == 4 || LAYOUT == 8)

#if LAYOUT == 4
#define WIDE_F float4
#define WIDE_LOAD vload4
#define WIDE_STORE vstore4
#else
#define WIDE_F float8
#define WIDE_LOAD vload8
#define WIDE_STORE vstore8
#endif

/* Wide traversal: each node's children boxes are tested plane by plane with one vector
 * operation per plane; leaf children are tested at once, the nearest inner one visited
 * next. Same contract as the LAYOUT 32 trace. */
FORCE_INLINE uint trace(SCENE_PARAMS, float3 org, float3 dir, float t_max, bool any_hit, bool incoherent, float* t_hit) {
    WatertightRay ray = watertight_ray(org, dir);
    float3 inv = safe_inverse(dir);
    float3 inv_near = near_inverse(inv);
    float t = t_max;
    uint best = MISS;
    uint stack_node[STACK_SIZE];
    float stack_entry[STACK_SIZE];
    uint sp = 0;
    uint node = 0;
    for (;;) {
        const __global NODE* n = &nodes[node];
        /* The near and far planes of each slab, picked by the ray's direction as in box_entry. */
        const __global float* nx = signbit(inv.x) ? n->max_x : n->min_x;
        const __global float* fx = signbit(inv.x) ? n->min_x : n->max_x;
        const __global float* ny = signbit(inv.y) ? n->max_y : n->min_y;
        const __global float* fy = signbit(inv.y) ? n->min_y : n->max_y;
        const __global float* nz = signbit(inv.z) ? n->max_z : n->min_z;
        const __global float* fz = signbit(inv.z) ? n->min_z : n->max_z;
        WIDE_F tnx = (WIDE_LOAD(0, nx) - org.x) * inv_near.x, tfx = (WIDE_LOAD(0, fx) - org.x) * inv.x;
        WIDE_F tny = (WIDE_LOAD(0, ny) - org.y) * inv_near.y, tfy = (WIDE_LOAD(0, fy) - org.y) * inv.y;
        WIDE_F tnz = (WIDE_LOAD(0, nz) - org.z) * inv_near.z, tfz = (WIDE_LOAD(0, fz) - org.z) * inv.z;
        WIDE_F near = fmax(fmax(tnx, tny), fmax(tnz, (WIDE_F)(0.0f)));
        WIDE_F far = fmin(fmin(fmin(tfx, tfy), tfz) * ROBUST_EXIT, (WIDE_F)(t));
        float near_a[LAYOUT], far_a[LAYOUT];
        WIDE_STORE(near, 0, near_a);
        WIDE_STORE(far, 0, far_a);
        /* Leaf children are tested at once; of the inner children hit, the nearest is
         * visited next and the others pushed. No sorted list: with the loop unrolled every
         * array index is a constant, so nothing but the stack leaves the registers. */
        uint next = EMPTY_SLOT;
        float next_entry = 0.0f;
#pragma unroll
        for (uint k = 0; k < LAYOUT; ++k) {
            uint count = n->count[k];
            if (count == EMPTY_SLOT || !(near_a[k] <= far_a[k])) continue;
            if (count != 0) {
                TEST_LEAF(n->child[k], count);
            } else if (next == EMPTY_SLOT) {
                next = n->child[k];
                next_entry = near_a[k];
            } else {
                if (sp >= STACK_SIZE) { atomic_or(status, STATUS_STACK_OVERFLOW); return MISS; }
                bool nearer = near_a[k] < next_entry;
                stack_node[sp] = nearer ? next : n->child[k];
                stack_entry[sp] = nearer ? next_entry : near_a[k];
                ++sp;
                if (nearer) { next = n->child[k]; next_entry = near_a[k]; }
            }
        }
        if (next != EMPTY_SLOT && next_entry <= t) {
            node = next;
        } else POP_OR_BREAK
    }
    *t_hit = t;
    return best;
}

#elif defined(LAYOUT) && LAYOUT == 80

/* Byte k of the 8 bytes (lo, hi), as a float. */
FORCE_INLINE float byte_of(uint lo, uint hi, uint k) {
    return (float)(((k < 4u ? lo : hi) >> (8u * (k & 3u))) & 0xFFu);
}

/* Compressed wide traversal (after Ylitie et al. 2017): a node visit tests all 8 child
 * boxes and yields a node group (the children still to visit, as bits) and the leaf
 * triangles hit (as bits); the current group's remainder is pushed as one stack entry, so
 * the stack holds one entry per level. Same contract as the LAYOUT 32 trace.
 *
 * Slot s's child lies towards corner s of its parent (bits x, y, z set: the maximum
 * side), and a ray meets first the corner of its negative direction components. Inner
 * children hit go to bit 24 + (s ^ order) and are visited from the highest bit down:
 * roughly front to back. */
FORCE_INLINE uint trace(SCENE_PARAMS, float3 org, float3 dir, float t_max, bool any_hit, bool incoherent, float* t_hit) {
    WatertightRay ray = watertight_ray(org, dir);
    float3 inv = safe_inverse(dir);
    uint order = 7u ^ ((signbit(dir.x) ? 4u : 0u) | (signbit(dir.y) ? 2u : 0u) | (signbit(dir.z) ? 1u : 0u));
    float t = t_max;
    uint best = MISS;
    uint2 stack[STACK_SIZE];
    uint sp = 0;
    /* A node group: .x its first node, .y the children to visit (bits 24-31) over their
     * parent's inner mask (bits 0-7). The root is a group of one with an empty mask. */
    uint2 group = (uint2)(0u, 0x80000000u);
    for (;;) {
        uint tri_base = 0u, tri_hits = 0u;
        if (group.y > 0x00FFFFFFu) {
            uint bit = 31u - clz(group.y);
            group.y &= ~(1u << bit);
            uint slot = (bit - 24u) ^ order;
            uint index = group.x + popcount(group.y & ((1u << slot) - 1u));
            if (group.y > 0x00FFFFFFu) {
                if (sp >= STACK_SIZE) { atomic_or(status, STATUS_STACK_OVERFLOW); return MISS; }
                stack[sp++] = group;
            }
            const __global uint4* row = (const __global uint4*)&nodes[index];
            uint4 r0 = row[0], r1 = row[1], r2 = row[2], r3 = row[3], r4 = row[4];
            float3 origin = (float3)(as_float(r0.x), as_float(r0.y), as_float(r0.z));
            float3 scale = (float3)(as_float((r0.w & 0xFFu) << 23), as_float(((r0.w >> 8) & 0xFFu) << 23),
                                    as_float(((r0.w >> 16) & 0xFFu) << 23));
            /* Plane q of an axis lies at q * a + b along the ray: one fused multiply-add per
             * plane instead of dequantizing first (measured 20-30% faster on the H100). The
             * rounding of a, b, the fma and the shift below stays under
             * 7 FLT_EPSILON (255 |a| + |b|), so moving near planes nearer and far planes
             * farther by 8 FLT_EPSILON (255 |a| + |b|) keeps the test conservative; the
             * host mirrors it in CompressedNode::fused_box_test and tests the bound. An
             * infinite inverse makes that axis NaN, which fmin and fmax skip: the slab then
             * never culls, as in box_entry. */
            float3 a = scale * inv;
            float3 b = (origin - org) * inv;
            float3 err = (255.0f * fabs(a) + fabs(b)) * (8.0f * FLT_EPSILON) + FLT_MIN;
            float3 b_near = b - err, b_far = b + err;
            /* Each axis's near planes are its lo bytes for a positive direction, hi bytes for
             * a negative one. */
            uint2 nx = signbit(inv.x) ? r3.zw : r2.xy, fx = signbit(inv.x) ? r2.xy : r3.zw;
            uint2 ny = signbit(inv.y) ? r4.xy : r2.zw, fy = signbit(inv.y) ? r2.zw : r4.xy;
            uint2 nz = signbit(inv.z) ? r4.zw : r3.xy, fz = signbit(inv.z) ? r3.xy : r4.zw;
            uint hits = 0u;
#pragma unroll
            for (uint k = 0; k < 8u; ++k) {
                float near = fmax(fmax(fma(byte_of(nx.x, nx.y, k), a.x, b_near.x),
                                       fma(byte_of(ny.x, ny.y, k), a.y, b_near.y)),
                                  fmax(fma(byte_of(nz.x, nz.y, k), a.z, b_near.z), 0.0f));
                float far = fmin(fmin(fma(byte_of(fx.x, fx.y, k), a.x, b_far.x),
                                      fma(byte_of(fy.x, fy.y, k), a.y, b_far.y)),
                                 fmin(fma(byte_of(fz.x, fz.y, k), a.z, b_far.z), t));
                /* An empty slot's meta is 0: whatever its box, it sets no bit. */
                uint meta = ((k < 4u ? r1.z : r1.w) >> (8u * (k & 3u))) & 0xFFu;
                if (near <= far) {
                    hits |= (meta & 0x18u) == 0x18u ? 1u << (24u + (k ^ order)) : (meta >> 5) << (meta & 0x1Fu);
                }
            }
            group = (uint2)(r1.x, (hits & 0xFF000000u) | (r0.w >> 24));
            tri_base = r1.y;
            tri_hits = hits & 0x00FFFFFFu;
        }
        while (tri_hits != 0u) {
            uint lowest = 31u - clz(tri_hits & (0u - tri_hits));
            tri_hits &= tri_hits - 1u;
            TEST_TRIANGLE(tri_base + lowest);
        }
        if (group.y <= 0x00FFFFFFu) {
            if (sp == 0) break;
            group = stack[--sp];
        }
    }
    *t_hit = t;
    return best;
}

#else

#define SCENE_PARAMS __global const Triangle* tris, uint tri_count
#define SCENE tris, tri_count

/* Brute force: every triangle, the first in order winning a tie (or, with any_hit, the
 * first hit at all). Same contract as the BVH's trace above. */
FORCE_INLINE uint trace(SCENE_PARAMS, float3 org, float3 dir, float t_max, bool any_hit, bool incoherent, float* t_hit) {
    WatertightRay ray = watertight_ray(org, dir);
    float t = t_max;
    uint best = MISS;
    for (uint i = 0; i < tri_count; ++i) {
        float h = intersect_stored(&ray, &tris[i], t);
        if (h >= 0.0f) {
            t = h;
            best = i;
            if (any_hit) break;
        }
    }
    *t_hit = t;
    return best;
}

#endif

FORCE_INLINE float length3(float3 d) { return sqrt(d.x * d.x + d.y * d.y + d.z * d.z); }

/* ---- sampling (mirrors src/render/sampling.rs) ---------------------------------------- */

/* Chris Wellons' lowbias32 integer hash. */
FORCE_INLINE uint hash_u32(uint x) {
    x ^= x >> 16; x *= 0x7feb352du;
    x ^= x >> 15; x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

/* A counter-based random stream: a number is a hash of (seed, pixel, sample, dimension). */
FORCE_INLINE uint sampler_key(uint seed, uint pixel, uint sample) {
    return hash_u32(hash_u32(hash_u32(seed ^ 0x9e3779b9u) ^ pixel) ^ sample);
}

FORCE_INLINE float sample_1d(uint key, uint dim) {
    return (float)(hash_u32(key ^ (dim * 0x85ebca6bu)) >> 8) * (1.0f / 16777216.0f);
}

#define DIMS_PER_BOUNCE 8u
FORCE_INLINE uint bounce_dim(uint b) { return 2u + b * DIMS_PER_BOUNCE; }

/* A cosine-weighted unit direction about the unit normal n (Duff et al. 2017 basis). */
FORCE_INLINE float3 cosine_direction(float3 n, float u1, float u2) {
    float r = sqrt(u1);
    float phi = 2.0f * M_PI_F * u2;
    float x = r * cos(phi), y = r * sin(phi);
    float z = sqrt(fmax(1.0f - u1, 0.0f));
    float sign = n.z >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (sign + n.z);
    float b = n.x * n.y * a;
    float3 t = (float3)(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
    float3 bt = (float3)(b, sign + n.y * n.y * a, -n.y);
    return t * x + bt * y + n * z;
}

/* A uniform point on the triangle (a, b, c). */
FORCE_INLINE float3 triangle_point(float3 a, float3 b, float3 c, float u1, float u2) {
    float su = sqrt(u1);
    float w0 = 1.0f - su, w1 = u2 * su;
    return a * w0 + b * w1 + c * (1.0f - w0 - w1);
}

/* The ray direction of pixel (x, y) jittered within the pixel. */
FORCE_INLINE float3 jittered_ray(float4 p0, float4 du, float4 dv, uint x, uint y, uint key) {
    float fx = (float)x + sample_1d(key, 0u);
    float fy = (float)y + sample_1d(key, 1u);
    return (float3)((p0.x + fx * du.x) + fy * dv.x,
                    (p0.y + fx * du.y) + fy * dv.y,
                    (p0.z + fx * du.z) + fy * dv.z);
}

/* The unit geometric normal of tri, turned to face dir's origin side. */
FORCE_INLINE float3 facing_normal(const __global Triangle* tri, float3 dir) {
    float3 v0 = load3(tri->v0);
    float3 n = normalize(cross(load3(tri->v1) - v0, load3(tri->v2) - v0));
    return dot(n, dir) > 0.0f ? -n : n;
}

/* The sky of scenes without emitters: white at the horizon, blue overhead, grey below. */
FORCE_INLINE float3 sky(float3 d) {
    float up = d.y / length(d);
    return up >= 0.0f ? mix((float3)(1.0f), (float3)(0.45f, 0.65f, 1.0f), up)
                      : mix((float3)(1.0f), (float3)(0.35f), -up);
}

/* ---- shading and output -------------------------------------------------------------- */

FORCE_INLINE uint quantize(float v) { return (uint)(clamp(v, 0.0f, 1.0f) * 255.0f + 0.5f); }

FORCE_INLINE uint pack_rgba(float r, float g, float b) {
    return quantize(r) | (quantize(g) << 8) | (quantize(b) << 16) | (255u << 24);
}

/* The colour of a hit on `tri` seen along `dir`; black for a miss. Mirrors
 * src/render/shade.rs. */
FORCE_INLINE uint shade_hit(int mode, float near, float far, const __global Triangle* tri, float distance, float3 dir) {
    float3 v0 = load3(tri->v0);
    float3 e1 = load3(tri->v1) - v0, e2 = load3(tri->v2) - v0;
    float3 n = (float3)(e1.y * e2.z - e1.z * e2.y, e1.z * e2.x - e1.x * e2.z, e1.x * e2.y - e1.y * e2.x);
    float n_len = sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
    n = n / n_len;
    if (mode == SHADE_NORMAL) {
        return pack_rgba(0.5f * n.x + 0.5f, 0.5f * n.y + 0.5f, 0.5f * n.z + 0.5f);
    }
    if (mode == SHADE_DEPTH) {
        float g = 1.0f - (distance - near) / (far - near);
        return pack_rgba(g, g, g);
    }
    float d_len = sqrt(dir.x * dir.x + dir.y * dir.y + dir.z * dir.z);
    float c = fabs(n.x * dir.x + n.y * dir.y + n.z * dir.z) / d_len;
    return pack_rgba(c, c, c);
}

/* Writes pixel (x, row) of the pitched output images, whose row 0 is the first image row of
 * the band being traced. Pitches count elements, not bytes. */
FORCE_INLINE void store_pixel(__global Hit* hits, uint hit_pitch, __global uint* colors, uint color_pitch,
                        uint x, uint row, uint best, float t, float3 dir, const __global Triangle* tris,
                        int shade, float near, float far) {
    Hit h;
    uint color = 0xFF000000u;
    if (best == MISS) {
        h.prim = MISS;
        h.t = INFINITY;
    } else {
        float distance = t * length3(dir);
        h.prim = tris[best].prim;
        h.t = distance;
        color = shade_hit(shade, near, far, &tris[best], distance, dir);
    }
    hits[row * hit_pitch + x] = h;
    colors[row * color_pitch + x] = color;
}

#endif
