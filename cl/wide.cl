/* wide.cl: the traversal of the wide layouts, written once for both over the node type and
 * vector type the file before it in the program (a wide layout's own file) defines:
 * WIDE_NODE, and WIDE_F with its WIDE_LOAD and WIDE_STORE, one lane per slot. The host
 * passes WIDE_WIDTH, the slots of a node (WideNode::WIDTH of src/bvh/wide.rs, which makes
 * the nodes). */

#ifndef WIDE_NODE
#error "wide.cl follows a wide layout's file in its program (src/device/program.rs)"
#endif
#ifndef WIDE_WIDTH
#error "a wide program needs WIDE_WIDTH, its nodes' slots (src/device/program.rs passes it)"
#endif

/* WIDE_F has one lane per slot (a declaration only: no code). */
typedef char wide_lanes_are_slots[vec_step(WIDE_F) == WIDE_WIDTH ? 1 : -1];

#define SCENE_PARAMS __global const WIDE_NODE* nodes, __global const Triangle* tris, __global uint* status, SURFACE_PARAMS
#define SCENE nodes, tris, status, SURFACE

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

/* Wide traversal: each node's children boxes are tested plane by plane with one vector
 * operation per plane; leaf children are tested at once, the nearest inner one visited
 * next. Same contract as every trace (traverse.cl). */
FORCE_INLINE uint trace_from(SCENE_PARAMS, uint root, float3 org, float3 dir, float t_max, bool any_hit, bool incoherent, float* t_hit) {
    TRACE_START
    float3 inv_near = near_inverse(inv);
    uint stack_node[STACK_SIZE];
    float stack_entry[STACK_SIZE];
    for (;;) {
        const __global WIDE_NODE* n = &nodes[node];
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
        float near_a[WIDE_WIDTH], far_a[WIDE_WIDTH];
        WIDE_STORE(near, 0, near_a);
        WIDE_STORE(far, 0, far_a);
        /* Leaf children are tested at once; of the inner children hit, the nearest is
         * visited next and the others pushed. No sorted list: with the loop unrolled every
         * array index is a constant, so nothing but the stack leaves the registers. */
        uint next = EMPTY_SLOT;
        float next_entry = 0.0f;
#pragma unroll
        for (uint k = 0; k < WIDE_WIDTH; ++k) {
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

TRACE_FROM_THE_ROOT

/* The contract of entry_node (traverse.cl): down from the root while a single slot's box
 * may meet the frustum, and that slot is an inner node. */
FORCE_INLINE uint entry_node(__global const WIDE_NODE* nodes, const Frustum* f) {
    uint node = 0;
    for (;;) {
        const __global WIDE_NODE* n = &nodes[node];
        uint meeting = 0, only = 0;
        for (uint k = 0; k < WIDE_WIDTH; ++k) {
            if (n->count[k] == EMPTY_SLOT) continue;
            float3 lo = (float3)(n->min_x[k], n->min_y[k], n->min_z[k]);
            float3 hi = (float3)(n->max_x[k], n->max_y[k], n->max_z[k]);
            if (frustum_may_meet(f, lo, hi)) { ++meeting; only = k; }
        }
        if (meeting == 0) return MISS;
        if (meeting > 1 || n->count[only] != 0) return node;
        node = n->child[only];
    }
}
