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
