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

/* The entry node (entry_node, traverse.cl) of the camera rays of pixels [x0, x1) x [y0, y1)
 * of the band: MISS where none of them can hit anything. */
#ifdef STACK_SIZE
FORCE_INLINE uint tile_entry(SCENE_PARAMS, CAMERA_BAND_PARAMS, uint x0, uint y0, uint x1, uint y1) {
    Frustum f = tile_frustum(eye, p0, du, dv, x0, y0, min(x1, width), min(y1, row_end));
    return entry_node(nodes, &f);
}

/* The node this work-item's camera ray starts from: its work-group's tile's entry node,
 * or the root (0) where the host passes no entries. With GROUP_ENTRIES (the host's choice
 * by device and layout, src/device/program.rs) the work-group's first work-item finds it
 * and shares it through group_entry: every work-item of the group must call this. Else the
 * host's tile_entries pass has put it in entries. */
FORCE_INLINE uint tile_root(PRIMARY_PARAMS, __local uint* group_entry) {
#ifdef GROUP_ENTRIES
    if (get_local_id(0) == 0 && get_local_id(1) == 0) {
        uint x0 = get_group_id(0) * get_local_size(0);
        uint y0 = row0 + get_group_id(1) * get_local_size(1);
        *group_entry = tile_entry(SCENE, CAMERA, width, row0, row_end, x0, y0,
                                  x0 + get_local_size(0), y0 + get_local_size(1));
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    return *group_entry;
#else
    return entries != 0 ? entries[get_group_id(1) * get_num_groups(0) + get_group_id(0)] : 0u;
#endif
}
#endif

FORCE_INLINE void primary_pixel(PRIMARY_PARAMS, const bool general, __local uint* group_entry) {
    uint x = get_global_id(0), y = get_global_id(1);
#ifdef STACK_SIZE
    /* Before any work-item returns: tile_root may wait for the whole work-group. */
    uint root = general ? 0u : tile_root(PRIMARY, group_entry);
#endif
    if (x >= width || y < row0 || y >= row_end) return;
    float3 org = eye.xyz;
    float3 dir = general ? camera_ray(CAMERA, x, y, &org)
                         : camera_ray_at_eye(p0, du, dv, (float)x + 0.5f, (float)y + 0.5f);
    float t = INFINITY;
    uint best = MISS;
#ifdef STACK_SIZE
    if (root != MISS) best = trace_from(SCENE, root, org, dir, INFINITY, false, false, &t);
#else
    best = trace(SCENE, org, dir, INFINITY, false, false, &t);
#endif
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
    entries[i] = tile_entry(SCENE, CAMERA, width, row0, row_end, x0, y0, x0 + tile_width,
                            y0 + tile_height);
}
#endif

/* A perspective camera's primary rays, without barycentrics (barycentrics is not read);
 * in a BVH program each work-group's from its tile's entry node (tile_root). */
#ifdef KERNEL_TRACE_PRIMARY
KERNEL void trace_primary(PRIMARY_PARAMS) {
    __local uint group_entry;
    primary_pixel(PRIMARY, false, &group_entry);
}
#endif

/* Any camera's primary rays, with barycentrics where they are asked for. */
#ifdef KERNEL_TRACE_PRIMARY_GENERAL
KERNEL void trace_primary_general(PRIMARY_PARAMS) { primary_pixel(PRIMARY, true, 0); }
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
