/* bin32.cl: the traversal of the thesis's layout, 32-byte binary nodes (Bin32Node) in
 * depth-first order; mirrored step for step by the host's traversal in src/bvh/bin32.rs. */

#ifndef LAYOUT_BIN32
#error "bin32.cl is one layout's traversal: its program is built with -D LAYOUT_BIN32 (src/device/program.rs)"
#endif

#define SCENE_PARAMS __global const Bin32Node* nodes, __global const Triangle* tris, __global uint* status, SURFACE_PARAMS
#define SCENE nodes, tris, status, SURFACE

/* Entry distance into `node`'s box if the ray meets it before t_max, else -1. */
FORCE_INLINE float hit_box(const __global Bin32Node* node, float3 org, float3 inv, float t_max) {
    const __global float4* row = (const __global float4*)node;
    return box_entry(row[0].xyz, row[1].xyz, org, inv, t_max);
}

/* The contract of every trace (traverse.cl), with a stack in private memory, nearer child
 * first, boxes beyond the closest hit skipped; mirrors src/bvh/bin32.rs step for step.
 * The stack holds STACK_SIZE entries, the tree's depth, which a traversal never needs
 * more than; should it anyway, STATUS_STACK_OVERFLOW is set and the ray reported a miss. */
FORCE_INLINE uint trace_from(SCENE_PARAMS, uint root, float3 org, float3 dir, float t_max, bool any_hit, bool incoherent, float* t_hit) {
    TRACE_START
    uint stack_node[STACK_SIZE];
    float stack_entry[STACK_SIZE];
    bool live = hit_box(&nodes[root], org, inv, t) >= 0.0f;
    while (live) {
        const __global Bin32Node* n = &nodes[node];
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

TRACE_FROM_THE_ROOT

/* Whether `node`'s box may meet frustum f (hit_box's counterpart for a tile's rays). */
FORCE_INLINE bool box_may_meet(const __global Bin32Node* node, const Frustum* f) {
    const __global float4* row = (const __global float4*)node;
    return frustum_may_meet(f, row[0].xyz, row[1].xyz);
}

/* The contract of entry_node (traverse.cl): down from the root while a single child's
 * box may meet the frustum. */
FORCE_INLINE uint entry_node(__global const Bin32Node* nodes, const Frustum* f) {
    if (!box_may_meet(&nodes[0], f)) return MISS;
    uint node = 0;
    while (!(nodes[node].right_or_count & LEAF_FLAG)) {
        uint l = nodes[node].left_or_first, r = nodes[node].right_or_count;
        bool ml = box_may_meet(&nodes[l], f), mr = box_may_meet(&nodes[r], f);
        if (ml && mr) break;
        if (!ml && !mr) return MISS;
        node = ml ? l : r;
    }
    return node;
}
