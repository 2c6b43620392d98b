/* trace.cl: the closest-hit kernels, compiled against a BVH in one layout (cl-bvh) or the
 * plain triangle list (cl-brute), whichever scene file the program has before this one:
 * the thesis's GPU brute force and GPU SAH-BVH stages from one source. Their frames are
 * compared pixel by pixel with the host's (src/render/cpu.rs). The host binds their
 * parameters by name (src/device/tracer.rs; tests/layout.rs compares the two lists). Like
 * every kernel, each is compiled only into programs that define its KERNEL_<NAME> (the
 * host's Kernels): a cold compile costs about as much per kernel. */

/* One primary ray per pixel of the band [row0, row_end), written to pitched images whose
 * row 0 is image row row0; with `general`, from any camera (an orthographic one's rays
 * leave from the image plane) and, with barycentrics not null, also the hit's barycentric
 * weights of the triangle's vertices 1 and 2 (0 for a miss), for version 2 of the hit
 * records. Without `general` every ray leaves from the eye and no barycentrics are
 * written: that code, though it would not run, costs PoCL 4-9% of primary-ray speed
 * (docs/bench/2026-12-04-primary-rays-pocl.md), so it is a kernel of its own. With colors
 * null the frame is hits alone: no normal is fetched and no colour shaded (store_pixel). */
#define PRIMARY_PARAMS SCENE_PARAMS, CAMERA_BAND_PARAMS,                 \
    int shade, float near, float far,                                   \
    __global Hit* hits, uint hit_pitch,                                 \
    __global uint* colors, uint color_pitch,                            \
    __global float2* barycentrics, uint barycentric_pitch, __global const uint* entries
#define PRIMARY SCENE, CAMERA, width, row0, row_end, shade, near, far, hits, hit_pitch, \
    colors, color_pitch, barycentrics, barycentric_pitch, entries

FORCE_INLINE void primary_pixel(PRIMARY_PARAMS, const bool general) {
    uint x = get_global_id(0), y = get_global_id(1);
    if (x >= width || y < row0 || y >= row_end) return;
    float3 org = eye.xyz;
    float3 dir = general ? camera_ray(CAMERA, x, y, &org)
                         : camera_ray_at_eye(p0, du, dv, (float)x + 0.5f, (float)y + 0.5f);
    float t = INFINITY;
    uint best = MISS;
#ifdef STACK_SIZE
    if (entries != 0) {
        uint root = entries[get_group_id(1) * get_num_groups(0) + get_group_id(0)];
        if (root != MISS) best = trace_from(SCENE, root, org, dir, INFINITY, false, false, &t);
    } else
#endif
        best = trace(SCENE, org, dir, INFINITY, false, false, &t);
    float3 n = (float3)(0.0f);
    if (best != MISS && shade != SHADE_DEPTH && colors != 0) {
        n = shading_normal(SURFACE, &tris[best], org, dir);
    }
    store_pixel(hits, hit_pitch, colors, color_pitch, x, y - row0, best, t, dir, tris, n, shade, near, far);
    if (general && barycentrics != 0) {
        float2 b = (float2)(0.0f);
        if (best != MISS) {
            WatertightRay r = watertight_ray(org, dir);
            b = hit_barycentrics(&r, &tris[best]).yz;
        }
        barycentrics[(y - row0) * barycentric_pitch + x] = b;
    }
}

/* The node each work-group's camera rays start from in a BVH (entry_node, traverse.cl):
 * entries[i] for work-group (i % tiles_x, i / tiles_x) of trace_primary's launch over the
 * band, whose work-groups are tile_width x tile_height pixels; MISS where no ray of the
 * tile can hit anything. Below the root its rays skip the top of the tree, where every
 * ray of the tile would test the same boxes. A perspective camera's only (the rays leave
 * from the eye). */
#if defined(KERNEL_TRACE_PRIMARY) && defined(STACK_SIZE)
KERNEL void tile_entries(SCENE_PARAMS, CAMERA_BAND_PARAMS, uint tile_width, uint tile_height,
                         uint tiles_x, uint tiles, __global uint* entries) {
    uint i = get_global_id(0);
    if (i >= tiles) return;
    uint x0 = (i % tiles_x) * tile_width, y0 = row0 + (i / tiles_x) * tile_height;
    Frustum f = tile_frustum(eye, p0, du, dv, x0, y0, min(x0 + tile_width, width),
                             min(y0 + tile_height, row_end));
    entries[i] = entry_node(nodes, &f);
}
#endif

/* A perspective camera's primary rays, without barycentrics (barycentrics is not read);
 * with entries not null (a BVH program's), each work-group's from its tile's entry node. */
#ifdef KERNEL_TRACE_PRIMARY
KERNEL void trace_primary(PRIMARY_PARAMS) { primary_pixel(PRIMARY, false); }
#endif

/* Any camera's primary rays, with barycentrics where they are asked for. */
#ifdef KERNEL_TRACE_PRIMARY_GENERAL
KERNEL void trace_primary_general(PRIMARY_PARAMS) { primary_pixel(PRIMARY, true); }
#endif

/* Arbitrary rays: origin and t_max in rays[2i] (xyz, w), direction in rays[2i + 1]. With
 * any_hit set, any hit before t_max is reported, not necessarily the closest. */
#ifdef KERNEL_TRACE_RAYS
KERNEL void trace_rays(SCENE_PARAMS, __global const float4* rays, uint count, int any_hit,
                         __global Hit* hits) {
    uint i = get_global_id(0);
    if (i >= count) return;
    float4 o = rays[2 * i];
    float3 dir = rays[2 * i + 1].xyz;
    float t;
    uint best = trace(SCENE, o.xyz, dir, o.w, any_hit != 0, true, &t);
    Hit h;
    h.prim = best == MISS ? MISS : tris[best].prim;
    h.t = best == MISS ? INFINITY : t * length3(dir);
    hits[i] = h;
}
#endif
