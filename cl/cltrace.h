/* cltrace.h: what every cltrace kernel shares. The structs mirror the #[repr(C)] Rust
 * structs of the same names (src/layout.rs, src/render/mod.rs); tests/layout.rs pins their
 * sizes and field offsets on both sides through probe.cl. The arithmetic mirrors the Rust
 * CPU reference (src/camera.rs, src/triangle.rs, src/render/shade.rs) operation for
 * operation, so that a device and the host pick the same triangle for every pixel. */
#ifndef CLTRACE_H
#define CLTRACE_H

/* a * b + c must round twice, exactly as on the host: no fused multiply-adds. */
#pragma OPENCL FP_CONTRACT OFF

#define MISS 0xFFFFFFFFu
#define LEAF_FLAG 0x80000000u

/* ---- device structs ------------------------------------------------------------------ */

/* A triangle as the intersector reads it: three corners, each padded to 16 bytes so that a
 * corner is one vector load. `prim` is the triangle's index in file order. */
typedef struct {
    float v0[3]; uint prim;
    float v1[3]; uint pad1;
    float v2[3]; uint pad2;
} Triangle;

/* A 32-byte BVH node, depth-first order. An inner node holds its children's indices; a
 * leaf holds its first triangle and, in `right_or_count`, LEAF_FLAG | triangle count. */
typedef struct {
    float min[3]; uint left_or_first;
    float max[3]; uint right_or_count;
} BvhNode;

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
inline float3 camera_ray(float4 p0, float4 du, float4 dv, uint x, uint y) {
    float fx = (float)x + 0.5f;
    float fy = (float)y + 0.5f;
    return (float3)((p0.x + fx * du.x) + fy * dv.x,
                    (p0.y + fx * du.y) + fy * dv.y,
                    (p0.z + fx * du.z) + fy * dv.z);
}

inline float pick(float3 v, int k) { return k == 0 ? v.x : (k == 1 ? v.y : v.z); }

/* Per-ray constants of the watertight ray/triangle test (Woop, Benthin, Wald 2013):
 * kz is the dominant axis of the direction, (kx, ky) the other two in an order that keeps
 * the winding, and the shear maps the ray onto +z. */
typedef struct {
    float3 org;
    int kx, ky, kz;
    float sx, sy, sz;
} WatertightRay;

inline WatertightRay watertight_ray(float3 org, float3 dir) {
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
inline float intersect_triangle(const WatertightRay* r, float3 v0, float3 v1, float3 v2, float t_max) {
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

inline float3 load3(const __global float* p) { return (float3)(p[0], p[1], p[2]); }

/* Widens a box's exit distance so that rounding in the slab test never culls a box the ray
 * touches: 1 + 2 gamma(3) (Ize 2013), exactly 1 + 3 ulp in float. */
#define ROBUST_EXIT (1.0f + 3.0f * FLT_EPSILON)

/* 1 / dir with zero components taken as +-1e-30: every slab product stays finite. */
inline float3 safe_inverse(float3 d) {
    float3 s = (float3)(fabs(d.x) < 1e-30f ? copysign(1e-30f, d.x) : d.x,
                        fabs(d.y) < 1e-30f ? copysign(1e-30f, d.y) : d.y,
                        fabs(d.z) < 1e-30f ? copysign(1e-30f, d.z) : d.z);
    return (float3)(1.0f / s.x, 1.0f / s.y, 1.0f / s.z);
}

inline float intersect_stored(const WatertightRay* r, const __global Triangle* tri, float t_max) {
    return intersect_triangle(r, load3(tri->v0), load3(tri->v1), load3(tri->v2), t_max);
}

/* ---- traversal ----------------------------------------------------------------------- */

/* A program is compiled for one of two scenes: with STACK_SIZE defined (the BVH's depth)
 * kernels traverse the BVH, without it they test every triangle. SCENE_PARAMS declares the
 * scene's kernel parameters and SCENE passes them on, so every kernel is written once. */

#define STATUS_STACK_OVERFLOW 1u

#ifdef STACK_SIZE

#define SCENE_PARAMS __global const BvhNode* nodes, __global const Triangle* tris, __global uint* status
#define SCENE nodes, tris, status

/* Entry distance into `node`'s box if the ray meets it before t_max, else -1. */
inline float hit_box(const __global BvhNode* node, float3 org, float3 inv, float t_max) {
    float t0x = (node->min[0] - org.x) * inv.x, t1x = (node->max[0] - org.x) * inv.x;
    float t0y = (node->min[1] - org.y) * inv.y, t1y = (node->max[1] - org.y) * inv.y;
    float t0z = (node->min[2] - org.z) * inv.z, t1z = (node->max[2] - org.z) * inv.z;
    float near = fmax(fmax(fmin(t0x, t1x), fmin(t0y, t1y)), fmax(fmin(t0z, t1z), 0.0f));
    float far = fmin(fmin(fmin(fmax(t0x, t1x), fmax(t0y, t1y)), fmax(t0z, t1z)) * ROBUST_EXIT, t_max);
    return near <= far ? near : -1.0f;
}

/* The triangle (index into tris) the ray (org, dir) hits first in (0, t_max), or with
 * any_hit the first one found at all; MISS for none. *t_hit gets the ray parameter.
 * A stack in private memory, nearer child first, boxes beyond the closest hit skipped;
 * mirrors src/bvh/traverse.rs step for step. The stack holds STACK_SIZE entries, the
 * tree's depth, which a traversal never needs more than; should it anyway, bit 0 of
 * *status is set and the ray reported as a miss, never written out of bounds. */
inline uint trace(SCENE_PARAMS, float3 org, float3 dir, float t_max, bool any_hit, float* t_hit) {
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
            uint first = n->left_or_first, end = first + (n->right_or_count & ~LEAF_FLAG);
            for (uint i = first; i < end; ++i) {
                float h = intersect_stored(&ray, &tris[i], t);
                if (h >= 0.0f) {
                    t = h;
                    best = i;
                    if (any_hit) { *t_hit = t; return best; }
                }
            }
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

#else

#define SCENE_PARAMS __global const Triangle* tris, uint tri_count
#define SCENE tris, tri_count

/* Brute force: every triangle, the first in order winning a tie (or, with any_hit, the
 * first hit at all). Same contract as the BVH's trace above. */
inline uint trace(SCENE_PARAMS, float3 org, float3 dir, float t_max, bool any_hit, float* t_hit) {
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

inline float length3(float3 d) { return sqrt(d.x * d.x + d.y * d.y + d.z * d.z); }

/* ---- shading and output -------------------------------------------------------------- */

inline uint quantize(float v) { return (uint)(clamp(v, 0.0f, 1.0f) * 255.0f + 0.5f); }

inline uint pack_rgba(float r, float g, float b) {
    return quantize(r) | (quantize(g) << 8) | (quantize(b) << 16) | (255u << 24);
}

/* The colour of a hit on `tri` seen along `dir`; black for a miss. Mirrors
 * src/render/shade.rs. */
inline uint shade_hit(int mode, float near, float far, const __global Triangle* tri, float distance, float3 dir) {
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
inline void store_pixel(__global Hit* hits, uint hit_pitch, __global uint* colors, uint color_pitch,
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
