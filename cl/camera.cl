/* camera.cl: the primary ray of a pixel, perspective or orthographic, with or without a
 * thin lens; mirrored operation for operation by Pinhole in src/camera.rs. */

/* The camera (Pinhole in src/camera.rs): at image position (fx, fy), in pixels, the point
 * pix = p0 + fx du + fy dv is the ray's direction from eye (perspective), or, when
 * forward.w is 1 (orthographic), the offset of its origin from eye, the direction being
 * forward. lens_u and lens_v are the lens radius along the image's right and up; lens_u.w
 * is the focus distance, 0 for a pinhole. */
#define CAMERA_PARAMS \
    float4 eye, float4 p0, float4 du, float4 dv, float4 forward, float4 lens_u, float4 lens_v
#define CAMERA eye, p0, du, dv, forward, lens_u, lens_v

/* What every image kernel takes after the scene's parameters (BandParams in
 * src/device/tracer.rs): the camera, the image width, and the band of rows
 * [row0, row_end) one launch covers. */
#define CAMERA_BAND_PARAMS CAMERA_PARAMS, uint width, uint row0, uint row_end

/* A perspective camera's ray through image position (fx, fy), which leaves from the eye:
 * its direction, unnormalised, the point of the image plane p0 + fx du + fy dv. */
FORCE_INLINE float3 camera_ray_at_eye(float4 p0, float4 du, float4 dv, float fx, float fy) {
    return (float3)((p0.x + fx * du.x) + fy * dv.x,
                    (p0.y + fx * du.y) + fy * dv.y,
                    (p0.z + fx * du.z) + fy * dv.z);
}

/* The ray through image position (fx, fy), the lens ignored: its direction, unnormalised,
 * returned, and its origin in *org. Pinhole::ray_at. */
FORCE_INLINE float3 camera_ray_at(CAMERA_PARAMS, float fx, float fy, float3* org) {
    float3 pix = camera_ray_at_eye(p0, du, dv, fx, fy);
    if (forward.w != 0.0f) {
        *org = eye.xyz + pix;
        return forward.xyz;
    }
    *org = eye.xyz;
    return pix;
}

/* Pixel (x, y)'s primary ray through its centre, the lens ignored. Pinhole::ray. */
FORCE_INLINE float3 camera_ray(CAMERA_PARAMS, uint x, uint y, float3* org) {
    return camera_ray_at(CAMERA, (float)x + 0.5f, (float)y + 0.5f, org);
}

/* The ray through image position (fx, fy) from the point lens of the unit disk: from the
 * lens there to where the pinhole ray meets the plane in focus. Pinhole::lens_ray. */
FORCE_INLINE float3 lens_ray(CAMERA_PARAMS, float fx, float fy, float2 lens, float3* org) {
    float3 o;
    float3 d = camera_ray_at(CAMERA, fx, fy, &o);
    if (lens_u.w == 0.0f) {
        *org = o;
        return d;
    }
    float3 off = (float3)(lens_u.x * lens.x + lens_v.x * lens.y,
                          lens_u.y * lens.x + lens_v.y * lens.y,
                          lens_u.z * lens.x + lens_v.z * lens.y);
    *org = o + off;
    return d * lens_u.w - off;
}

/* The pyramid from the eye that holds a perspective camera's rays through the centres of
 * the pixels [x0, x1) x [y0, y1), the rays of one work-group's tile (tile_entries,
 * cl/trace.cl): four planes through the eye, normals inward. It is widened by a quarter
 * of a pixel, far more than the rounding of the rays or of the planes: each normal is the
 * cross product of a corner ray with du or dv, not of two nearly parallel corner rays. */
typedef struct {
    float3 eye, top, bottom, left, right;
} Frustum;

FORCE_INLINE float3 facing(float3 n, float3 inside) { return dot(n, inside) < 0.0f ? -n : n; }

FORCE_INLINE Frustum tile_frustum(float4 eye, float4 p0, float4 du, float4 dv, uint x0, uint y0, uint x1, uint y1) {
    const float widen = 0.25f;
    float fx0 = (float)x0 + 0.5f - widen, fx1 = (float)x1 - 0.5f + widen;
    float fy0 = (float)y0 + 0.5f - widen, fy1 = (float)y1 - 0.5f + widen;
    float3 c00 = camera_ray_at_eye(p0, du, dv, fx0, fy0), c11 = camera_ray_at_eye(p0, du, dv, fx1, fy1);
    float3 inside = c00 + c11;
    Frustum f;
    f.eye = eye.xyz;
    f.top = facing(cross(c00, du.xyz), inside);
    f.bottom = facing(cross(c11, du.xyz), inside);
    f.left = facing(cross(c00, dv.xyz), inside);
    f.right = facing(cross(c11, dv.xyz), inside);
    return f;
}

FORCE_INLINE float max_abs3(float3 v) {
    v = fabs(v);
    return fmax(v.x, fmax(v.y, v.z));
}

/* Whether the box [lo, hi] may meet frustum f: false only when it lies wholly outside one
 * of its planes. Conservative: the box is first widened by 2^-16 of the largest coordinate
 * of it and the eye, far more than the rounding of the subtraction and of the products
 * here and in the triangle test (camera rays along a box face: tests/opencl_vs_cpu.rs). */
FORCE_INLINE bool frustum_may_meet(const Frustum* f, float3 lo, float3 hi) {
    float slack = 1.52587890625e-5f * fmax(max_abs3(f->eye), fmax(max_abs3(lo), max_abs3(hi)));
    lo = lo - f->eye - slack;
    hi = hi - f->eye + slack;
    return dot(f->top, select(lo, hi, f->top > 0.0f)) >= 0.0f &&
           dot(f->bottom, select(lo, hi, f->bottom > 0.0f)) >= 0.0f &&
           dot(f->left, select(lo, hi, f->left > 0.0f)) >= 0.0f &&
           dot(f->right, select(lo, hi, f->right > 0.0f)) >= 0.0f;
}
