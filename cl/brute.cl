/* brute.cl: the scene of a program without a BVH (cl-brute): every triangle, in file order;
 * mirrored by src/brute.rs. It stands where a BVH program has its layout's files. */

#define SCENE_PARAMS __global const Triangle* tris, uint tri_count, SURFACE_PARAMS
#define SCENE tris, tri_count, SURFACE

/* Brute force: every triangle, the first in order winning a tie (or, with any_hit, the
 * first hit at all). Same contract as every trace (traverse.cl). */
FORCE_INLINE uint trace(SCENE_PARAMS, float3 org, float3 dir, float t_max, bool any_hit, bool incoherent, float* t_hit) {
    WatertightRay ray = watertight_ray(org, dir);
    float t = t_max;
    uint best = MISS;
    for (uint i = 0; i < tri_count; ++i) {
        float h = intersect_stored(&ray, &tris[i], t);
#ifdef ALPHA_MASKS
        if (h >= 0.0f && mask_keeps(SURFACE, &ray, &tris[i])) {
#else
        if (h >= 0.0f) {
#endif
            t = h;
            best = i;
            if (any_hit) break;
        }
    }
    *t_hit = t;
    return best;
}
