/* camera.cl: the primary ray of a pixel, mirrored operation for operation by
 * Pinhole::ray in src/camera.rs. */

/* What every image kernel takes after the scene's parameters (BandParams in
 * src/device/tracer.rs): the eye, the pixel grid (pixel (x, y) lies at p0 + x du + y dv),
 * the image width, and the band of rows [row0, row_end) one launch covers. */
#define CAMERA_BAND_PARAMS \
    float4 eye, float4 p0, float4 du, float4 dv, uint width, uint row0, uint row_end

/* Pixel (x, y)'s primary ray direction, unnormalised: p0 + (x+0.5) du + (y+0.5) dv. */
FORCE_INLINE float3 camera_ray(float4 p0, float4 du, float4 dv, uint x, uint y) {
    float fx = (float)x + 0.5f;
    float fy = (float)y + 0.5f;
    return (float3)((p0.x + fx * du.x) + fy * dv.x,
                    (p0.y + fx * du.y) + fy * dv.y,
                    (p0.z + fx * du.z) + fy * dv.z);
}
