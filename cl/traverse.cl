/* traverse.cl: what the traversals of every BVH layout share: the scene's stack size and
 * error flag, and the leaf tests, written as macros over the traversal's own variables
 * (ray, tris, t, best, any_hit, t_hit); the host's traversal (Bin32Bvh, src/bvh/) does the
 * same inline. STATUS_STACK_OVERFLOW comes from the host (src/device/tracer.rs).
 *
 * A program is compiled for one scene: a BVH program has STACK_SIZE defined (the
 * traversal stack's entries) and one layout's files after this one, a brute-force program
 * brute.cl instead. Each defines SCENE_PARAMS, the scene's kernel parameters, and SCENE,
 * which passes them on, so that every kernel is written once; and the scene's trace:
 *
 *   uint trace(SCENE_PARAMS, float3 org, float3 dir, float t_max, bool any_hit,
 *              bool incoherent, float* t_hit)
 *
 * returns the triangle (index into tris) the ray (org, dir) hits first in (0, t_max), or
 * with any_hit the first one found at all; MISS for none; *t_hit gets the ray parameter.
 * `incoherent` (a constant at every call) says whether the rays of neighbouring work-items
 * go different ways (bounces, ambient occlusion, arbitrary rays) rather than together
 * (camera rays): a layout may pick its traversal by it; the result is the same either way.
 * A traversal whose stack would overflow sets STATUS_STACK_OVERFLOW in *status and reports
 * a miss, never writing out of bounds. */

#ifndef STACK_SIZE
#error "a BVH program needs STACK_SIZE (src/device/program.rs passes it)"
#endif

/* A BVH layout's file defines trace through
 *
 *   uint trace_from(SCENE_PARAMS, uint root, float3 org, float3 dir, float t_max,
 *                   bool any_hit, bool incoherent, float* t_hit)
 *
 * which searches the subtree of node `root` alone (trace: from node 0, the root, by
 * TRACE_FROM_THE_ROOT, written after it; OpenCL C has no variadic macros); and, for
 * camera rays,
 *
 *   uint entry_node(__global const NODE* nodes, const Frustum* f)
 *
 * the deepest node it finds (by one walk down from the root, stopping where two children
 * may meet f) whose subtree holds every leaf whose box may meet frustum f (camera.cl), or
 * MISS if none may. Every ray inside f then finds in the subtree of that node the hit it
 * would find from the root, by the same steps: outside it, the traversal from the root
 * meets no leaf. tile_entries (trace.cl) finds it for each work-group's tile of pixels,
 * and camera rays start there. */
#define TRACE_FROM_THE_ROOT                                              \
    FORCE_INLINE uint trace(SCENE_PARAMS, float3 org, float3 dir, float t_max, bool any_hit, \
                            bool incoherent, float* t_hit) {             \
        return trace_from(SCENE, 0u, org, dir, t_max, any_hit, incoherent, t_hit); \
    }

/* What the binary and wide traversals start with: the ray's constants for the triangle and
 * box tests, no hit before t_max yet, and an empty stack below the node `root`. */
#define TRACE_START                                                      \
    WatertightRay ray = watertight_ray(org, dir);                        \
    float3 inv = safe_inverse(dir);                                      \
    float t = t_max;                                                     \
    uint best = MISS;                                                    \
    uint sp = 0;                                                         \
    uint node = root;

/* Keeps a triangle test's result h (negative: no hit) for triangle `index` as the closest
 * hit so far (t, best); with any_hit, the first hit ends the traversal. */
#ifdef ALPHA_MASKS
/* Programs for scenes with cut-out materials (ALPHA_MASKS defined) look a hit's mask up
 * before keeping it (mask_keeps, cl/surface.cl); others never pay for it. */
#define HIT_COUNTS(h, index) ((h) >= 0.0f && mask_keeps(SURFACE, &ray, &tris[index]))
#else
#define HIT_COUNTS(h, index) ((h) >= 0.0f)
#endif

#define KEEP_HIT(h, index)                                               \
    if (HIT_COUNTS(h, index)) {                                          \
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
