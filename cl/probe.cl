/* probe.cl: reports how this device's compiler lays out the shared structs, so that
 * tests/layout.rs can compare them with the Rust side. */
#include "cltrace.h"

#define OFFSET(type, field) ((uint)((const char*)&probe_##type.field - (const char*)&probe_##type))

__kernel void probe_layout(__global uint* out) {
    Triangle probe_Triangle;
    BvhNode probe_BvhNode;
    Hit probe_Hit;
    Material probe_Material;
    Bvh64Node probe_Bvh64Node;
    Wide4Node probe_Wide4Node;
    Wide8Node probe_Wide8Node;
    CompressedNode probe_CompressedNode;
    uint i = 0;
    out[i++] = sizeof(Triangle);
    out[i++] = OFFSET(Triangle, v0);
    out[i++] = OFFSET(Triangle, prim);
    out[i++] = OFFSET(Triangle, v1);
    out[i++] = OFFSET(Triangle, material);
    out[i++] = OFFSET(Triangle, v2);
    out[i++] = sizeof(BvhNode);
    out[i++] = OFFSET(BvhNode, min);
    out[i++] = OFFSET(BvhNode, left_or_first);
    out[i++] = OFFSET(BvhNode, max);
    out[i++] = OFFSET(BvhNode, right_or_count);
    out[i++] = sizeof(Hit);
    out[i++] = OFFSET(Hit, prim);
    out[i++] = OFFSET(Hit, t);
    out[i++] = sizeof(Material);
    out[i++] = OFFSET(Material, albedo);
    out[i++] = OFFSET(Material, emission);
    out[i++] = sizeof(Bvh64Node);
    out[i++] = OFFSET(Bvh64Node, right_xy);
    out[i++] = OFFSET(Bvh64Node, z);
    out[i++] = OFFSET(Bvh64Node, refs);
    out[i++] = sizeof(Wide4Node);
    out[i++] = OFFSET(Wide4Node, max_z);
    out[i++] = OFFSET(Wide4Node, child);
    out[i++] = OFFSET(Wide4Node, count);
    out[i++] = sizeof(Wide8Node);
    out[i++] = OFFSET(Wide8Node, max_z);
    out[i++] = OFFSET(Wide8Node, child);
    out[i++] = OFFSET(Wide8Node, count);
    out[i++] = sizeof(CompressedNode);
    out[i++] = OFFSET(CompressedNode, exponent);
    out[i++] = OFFSET(CompressedNode, inner_mask);
    out[i++] = OFFSET(CompressedNode, child_base);
    out[i++] = OFFSET(CompressedNode, triangle_base);
    out[i++] = OFFSET(CompressedNode, meta);
    out[i++] = OFFSET(CompressedNode, lo_x);
    out[i++] = OFFSET(CompressedNode, hi_x);
    out[i++] = OFFSET(CompressedNode, hi_z);
}
