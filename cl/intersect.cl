/* intersect.cl: the watertight ray/triangle test (Woop, Benthin, Wald 2013) and the robust
 * slab test of boxes, mirrored operation for operation by src/intersect.rs
 * (WatertightRay, RayBox). ROBUST_EXIT comes from the host (src/intersect.rs). */

/* Component k (0: x, 1: y, 2: z) of v. */
FORCE_INLINE float pick(float3 v, int k) { return k == 0 ? v.x : (k == 1 ? v.y : v.z); }

/* Per-ray constants of the watertight ray/triangle test (Woop, Benthin, Wald 2013):
 * kz is the dominant axis of the direction, (kx, ky) the other two in an order that keeps
 * the winding, and the shear maps the ray onto +z.
 *
 * The triangle test reads each vertex's coordinates in the order (kx, ky, kz), in one of
 * two forms that give the same numbers (the host picks by device, src/device/program.rs):
 * by default the axes are two lane masks (lanes x, y, z for kx, ky, kz; is_x set where
 * the axis is x, is_y where it is y) and two selects permute a whole vertex, which ran
 * the gold and glass scenes 1.11-1.12x faster on Intel's CPU runtime and PoCL level
 * to 1.06x; AXIS_PICKS (GPUs) keeps the axes as numbers and picks coordinate by coordinate,
 * as the selects cost an H200 1-4% (docs/bench/2026-12-06-axis-selects.md). The three
 * numbers share one uint, two bits each: as three ints they made an H100's camera,
 * diffuse and path-traced rays 3-6% slower (docs/bench/2026-12-06-indexed-triangles.md). */
typedef struct {
    float3 org;
#ifdef AXIS_PICKS
    uint axes; /* kx in bits 0-1, ky in bits 2-3, kz in bits 4-5 */
#else
    int4 is_x, is_y;
#endif
    float sx, sy, sz;
} WatertightRay;

FORCE_INLINE WatertightRay watertight_ray(float3 org, float3 dir) {
    WatertightRay r;
    float ax = fabs(dir.x), ay = fabs(dir.y), az = fabs(dir.z);
    int kz = ax > ay ? (ax > az ? 0 : 2) : (ay > az ? 1 : 2);
    int kx = kz == 2 ? 0 : kz + 1;
    int ky = kx == 2 ? 0 : kx + 1;
    float dz = pick(dir, kz);
    if (dz < 0.0f) { int swap = kx; kx = ky; ky = swap; }
    r.org = org;
#ifdef AXIS_PICKS
    r.axes = (uint)kx | ((uint)ky << 2) | ((uint)kz << 4);
#else
    int4 k = (int4)(kx, ky, kz, 2);
    r.is_x = k == 0;
    r.is_y = k == 1;
#endif
    r.sx = pick(dir, kx) / dz;
    r.sy = pick(dir, ky) / dz;
    r.sz = 1.0f / dz;
    return r;
}

/* (v[kx], v[ky], v[kz]) of the ray r in lanes x, y, z. */
FORCE_INLINE float4 permute(const WatertightRay* r, float3 v) {
#ifdef AXIS_PICKS
    uint a = r->axes;
    return (float4)(pick(v, (int)(a & 3u)), pick(v, (int)((a >> 2) & 3u)), pick(v, (int)((a >> 4) & 3u)), 0.0f);
#else
    return select(select((float4)(v.z), (float4)(v.y), r->is_y), (float4)(v.x), r->is_x);
#endif
}

/* The watertight test's edge functions of triangle (v0, v1, v2) for the ray (u, v, w: the
 * unnormalised barycentrics of v0, v1, v2) and the vertices' sheared depths along it. */
typedef struct { float u, v, w, a_z, b_z, c_z; } EdgeFunctions;

FORCE_INLINE EdgeFunctions edge_functions(const WatertightRay* r, float3 v0, float3 v1, float3 v2) {
    float4 a = permute(r, v0 - r->org), b = permute(r, v1 - r->org), c = permute(r, v2 - r->org);
    EdgeFunctions e;
    e.a_z = a.z; e.b_z = b.z; e.c_z = c.z;
    float ax = a.x - r->sx * e.a_z, ay = a.y - r->sy * e.a_z;
    float bx = b.x - r->sx * e.b_z, by = b.y - r->sy * e.b_z;
    float cx = c.x - r->sx * e.c_z, cy = c.y - r->sy * e.c_z;
    e.u = cx * by - cy * bx;
    e.v = ax * cy - ay * cx;
    e.w = bx * ay - by * ax;
    return e;
}

/* Ray parameter of the hit with triangle (v0, v1, v2) if it is closer than t_max, else a
 * negative number. Watertight: a ray through a shared edge or vertex hits at least one of
 * the triangles. Zero-area triangles never hit. */
FORCE_INLINE float intersect_triangle(const WatertightRay* r, float3 v0, float3 v1, float3 v2, float t_max) {
    EdgeFunctions e = edge_functions(r, v0, v1, v2);
    float u = e.u, v = e.v, w = e.w;
    if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) return -1.0f;
    float det = u + v + w;
    if (det == 0.0f) return -1.0f;
    float t = u * (r->sz * e.a_z) + v * (r->sz * e.b_z) + w * (r->sz * e.c_z);
    if (det > 0.0f ? !(t > 0.0f && t < t_max * det) : !(t < 0.0f && t > t_max * det)) return -1.0f;
    return t / det;
}

/* The barycentric weights (of v0, v1, v2) of the ray's hit with tri, a triangle it hits:
 * the edge functions over their sum. Mirrored by WatertightRay::barycentrics in
 * src/intersect.rs. */
FORCE_INLINE float3 hit_barycentrics(const WatertightRay* r, const __global Triangle* tri) {
    const __global float4* row = (const __global float4*)tri;
    EdgeFunctions e = edge_functions(r, row[0].xyz, row[1].xyz, row[2].xyz);
    float det = e.u + e.v + e.w;
    return det == 0.0f ? (float3)(1.0f, 0.0f, 0.0f) : (float3)(e.u / det, e.v / det, e.w / det);
}

/* 1 / dir per component: a zero component gives an infinite inverse. Where the origin lies
 * in that slab's plane, 0 * inf makes the slab's distances NaN, which fmin and fmax skip, so
 * a ray lying in a box face's plane counts as inside the slab (RayBox in src/intersect.rs). */
FORCE_INLINE float3 safe_inverse(float3 d) {
    return (float3)(1.0f / d.x, 1.0f / d.y, 1.0f / d.z);
}

/* A stored triangle is three 16-byte rows (v0 prim, v1 material, v2 pad), 16-byte aligned
 * in its buffer: three vector loads instead of nine scalar ones. */
FORCE_INLINE float intersect_stored(const WatertightRay* r, const __global Triangle* tri, float t_max) {
    const __global float4* row = (const __global float4*)tri;
    return intersect_triangle(r, row[0].xyz, row[1].xyz, row[2].xyz, t_max);
}


/* The inverse used for near planes: where a subnormal (or zero) direction component made
 * the inverse infinite, +-FLT_MAX, an entry no later than the true one (the far planes keep
 * the infinity, an exit no earlier): both err towards visiting the box. */
FORCE_INLINE float3 near_inverse(float3 inv) {
    return select(inv, copysign((float3)(FLT_MAX), inv), isinf(inv));
}

/* Entry distance into the box [lo, hi] if the ray meets it before t_max, else -1: the
 * robust slab test of RayBox::hit in src/intersect.rs. */
FORCE_INLINE float box_entry(float3 lo, float3 hi, float3 org, float3 inv, float t_max) {
    /* Each slab's near and far planes are picked by the inverse's sign, not by comparing
     * distances, so that a NaN never stands in for the wrong one; fmin and fmax skip NaNs. */
    int3 back = signbit(inv);
    float3 tn = (select(lo, hi, back) - org) * near_inverse(inv);
    float3 tf = (select(hi, lo, back) - org) * inv;
    float near = fmax(fmax(tn.x, tn.y), fmax(tn.z, 0.0f));
    float far = fmin(fmin(fmin(tf.x, tf.y), tf.z) * ROBUST_EXIT, t_max);
    return near <= far ? near : -1.0f;
}
