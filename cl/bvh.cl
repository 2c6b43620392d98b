/* bvh.cl: the thesis's GPU SAH-BVH traversal. One ray per work-item walks the 32-byte
 * depth-first nodes with a stack in private memory, nearer child first, skipping boxes
 * farther than the closest hit so far. Mirrors src/bvh/traverse.rs step for step.
 *
 * STACK_SIZE (a build define) is the tree's depth, which bounds the stack: a traversal
 * never holds more than depth - 1 entries. Should it ever be exceeded, the kernel sets
 * bit 0 of *status and drops the ray rather than write out of bounds. */
#include "cltrace.h"

#ifndef STACK_SIZE
#error "STACK_SIZE must be defined to the BVH's depth"
#endif

#define STATUS_STACK_OVERFLOW 1u

/* Entry distance into `node`'s box if the ray meets it before t_max, else -1. */
inline float hit_box(const __global BvhNode* node, float3 org, float3 inv, float t_max) {
    float t0x = (node->min[0] - org.x) * inv.x, t1x = (node->max[0] - org.x) * inv.x;
    float t0y = (node->min[1] - org.y) * inv.y, t1y = (node->max[1] - org.y) * inv.y;
    float t0z = (node->min[2] - org.z) * inv.z, t1z = (node->max[2] - org.z) * inv.z;
    float near = fmax(fmax(fmin(t0x, t1x), fmin(t0y, t1y)), fmax(fmin(t0z, t1z), 0.0f));
    float far = fmin(fmin(fmin(fmax(t0x, t1x), fmax(t0y, t1y)), fmax(t0z, t1z)) * ROBUST_EXIT, t_max);
    return near <= far ? near : -1.0f;
}

__kernel void trace_bvh(__global const BvhNode* nodes, __global const Triangle* tris,
                        __global uint* status,
                        float4 eye, float4 p0, float4 du, float4 dv,
                        uint width, uint row0, uint row_end,
                        int shade, float near, float far,
                        __global Hit* hits, uint hit_pitch,
                        __global uint* colors, uint color_pitch) {
    uint x = get_global_id(0), y = get_global_id(1);
    if (x >= width || y < row0 || y >= row_end) return;
    float3 dir = camera_ray(p0, du, dv, x, y);
    float3 org = eye.xyz;
    WatertightRay ray = watertight_ray(org, dir);
    float3 inv = safe_inverse(dir);

    float t = INFINITY;
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
                if (h >= 0.0f) { t = h; best = i; }
            }
        } else {
            uint l = n->left_or_first, r = n->right_or_count;
            float tl = hit_box(&nodes[l], org, inv, t);
            float tr = hit_box(&nodes[r], org, inv, t);
            if (tl >= 0.0f && tr >= 0.0f) {
                if (sp >= STACK_SIZE) { atomic_or(status, STATUS_STACK_OVERFLOW); best = MISS; break; }
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
    store_pixel(hits, hit_pitch, colors, color_pitch, x, y - row0, best, t, dir, tris, shade, near, far);
}
