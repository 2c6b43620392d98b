/* cwbvh.cl: the traversal of the compressed 8-wide layout (CwbvhNode: 80-byte nodes,
 * child boxes quantized to 8 bits; Ylitie et al. 2017), whose nodes src/bvh/cwbvh.rs
 * makes; CwbvhNode::fused_box_test there mirrors this file's box test and checks its
 * error bound. */

#ifndef LAYOUT_CWBVH
#error "cwbvh.cl is one layout's traversal: its program is built with -D LAYOUT_CWBVH (src/device/program.rs)"
#endif

#define SCENE_PARAMS __global const CwbvhNode* nodes, __global const Triangle* tris, __global uint* status, SURFACE_PARAMS
#define SCENE nodes, tris, status, SURFACE

/* Byte k of the 8 bytes (lo, hi), as a float. */
FORCE_INLINE float byte_of(uint lo, uint hi, uint k) {
    return (float)(((k < 4u ? lo : hi) >> (8u * (k & 3u))) & 0xFFu);
}

/* Compressed wide traversal (after Ylitie et al. 2017): a node visit tests all 8 child
 * boxes and yields a node group (the children still to visit, as bits) and the leaf
 * triangles hit (as bits); the current group's remainder is pushed as one stack entry, so
 * the stack holds one entry per level. Same contract as every trace (traverse.cl).
 *
 * Slot s's child lies towards corner s of its parent (bits x, y, z set: the maximum
 * side), and a ray meets first the corner of its negative direction components. Inner
 * children hit go to bit 24 + (s ^ order) and are visited from the highest bit down:
 * roughly front to back. */
FORCE_INLINE uint trace_from(SCENE_PARAMS, uint root, float3 org, float3 dir, float t_max, bool any_hit, bool incoherent, float* t_hit) {
    WatertightRay ray = watertight_ray(org, dir);
    float3 inv = safe_inverse(dir);
    uint order = 7u ^ ((signbit(dir.x) ? 4u : 0u) | (signbit(dir.y) ? 2u : 0u) | (signbit(dir.z) ? 1u : 0u));
    float t = t_max;
    uint best = MISS;
    uint2 stack[STACK_SIZE];
    uint sp = 0;
    /* A node group: .x its first node, .y the children to visit (bits 24-31) over their
     * parent's inner mask (bits 0-7). The node a traversal starts from (the root, or a
     * tile's entry node) is a group of one with an empty mask. */
    uint2 group = (uint2)(root, 0x80000000u);
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
             * plane instead of dequantizing first (measured faster on the H100:
             * docs/performance.md, "Kernel changes, measured"). The rounding of a, b, the
             * fma and the shift below stays under 7 FLT_EPSILON (255 |a| + |b|), so moving
             * near planes nearer and far planes farther by 8 FLT_EPSILON (255 |a| + |b|)
             * keeps the test conservative; the host mirrors it in
             * CwbvhNode::fused_box_test and tests the bound. An
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

TRACE_FROM_THE_ROOT

/* The contract of entry_node (traverse.cl): down from the root while a single slot's box
 * (as stored: quantized outward) may meet the frustum, and that slot is an inner node. */
FORCE_INLINE uint entry_node(__global const CwbvhNode* nodes, const Frustum* f) {
    uint node = 0;
    for (;;) {
        const __global CwbvhNode* n = &nodes[node];
        float3 origin = (float3)(n->origin[0], n->origin[1], n->origin[2]);
        float3 scale = (float3)(as_float((uint)n->exponent[0] << 23), as_float((uint)n->exponent[1] << 23),
                                as_float((uint)n->exponent[2] << 23));
        uint meeting = 0, only = 0;
        for (uint k = 0; k < 8u; ++k) {
            if (n->meta[k] == 0) continue;
            float3 lo = origin + scale * (float3)((float)n->lo_x[k], (float)n->lo_y[k], (float)n->lo_z[k]);
            float3 hi = origin + scale * (float3)((float)n->hi_x[k], (float)n->hi_y[k], (float)n->hi_z[k]);
            if (frustum_may_meet(f, lo, hi)) { ++meeting; only = k; }
        }
        if (meeting == 0) return MISS;
        if (meeting > 1 || !((n->inner_mask >> only) & 1u)) return node;
        node = n->child_base + popcount((uint)n->inner_mask & ((1u << only) - 1u));
    }
}
