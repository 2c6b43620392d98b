/* bin64.cl: the traversal of the Aila-Laine layout, 64-byte binary nodes holding both
 * children's boxes (Bin64Node, made from the binary tree by src/bvh/bin64.rs). */

#ifndef LAYOUT_BIN64
#error "bin64.cl is one layout's traversal: its program is built with -D LAYOUT_BIN64 (src/device/program.rs)"
#endif

#define SCENE_PARAMS __global const Bin64Node* nodes, __global const Triangle* tris, __global uint* status, SURFACE_PARAMS
#define SCENE nodes, tris, status, SURFACE

/* TEST_LEAF for count >= 1 with the next triangle's rows loading while one is tested, so
 * that a leaf costs one memory latency instead of one per triangle. Measured on the H100,
 * it makes this layout's incoherent rays faster but its coherent ones slower, and the other
 * layouts slower still (docs/performance.md, "Kernel changes, measured"): bin64 uses it
 * for incoherent rays only. */
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

/* Aila-Laine traversal: one 64-byte fetch tests both children; leaf children are tested at
 * once, inner ones visited nearer first. Same contract as every trace (traverse.cl). The
 * stack keeps node indices only: a popped node's children are tested against the closest
 * hit anyway, and halving the stack traffic was measured faster on the H100 than culling
 * popped nodes by a stored entry distance (docs/performance.md, "Kernel changes,
 * measured"). */
FORCE_INLINE uint trace_from(SCENE_PARAMS, uint root, float3 org, float3 dir, float t_max, bool any_hit, bool incoherent, float* t_hit) {
    TRACE_START
    uint stack_node[STACK_SIZE];
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

TRACE_FROM_THE_ROOT

/* The contract of entry_node (traverse.cl): down from the root while a single child's
 * box may meet the frustum, and that child is an inner node (a traversal starts at one). */
FORCE_INLINE uint entry_node(__global const Bin64Node* nodes, const Frustum* f) {
    uint node = 0;
    for (;;) {
        const __global float4* n = (const __global float4*)&nodes[node];
        float4 lxy = n[0], rxy = n[1], z = n[2];
        uint4 refs = as_uint4(n[3]);
        bool ml = frustum_may_meet(f, (float3)(lxy.x, lxy.z, z.x), (float3)(lxy.y, lxy.w, z.y));
        bool mr = frustum_may_meet(f, (float3)(rxy.x, rxy.z, z.z), (float3)(rxy.y, rxy.w, z.w));
        if (!ml && !mr) return MISS;
        if ((ml && mr) || (ml ? refs.z : refs.w) != 0) return node;
        node = ml ? refs.x : refs.y;
    }
}
