/* sampling.cl: random numbers, the sampling of directions and points, and the camera ray
 * of a sample (after camera.cl, whose functions it uses), mirrored by
 * src/render/sampling.rs so that the host reference and the devices draw the same numbers.
 * DIMS_PER_BOUNCE, LENS_DIM and LENS_TRIES come from the host (src/render/sampling.rs). */

/* Programs of sample kernels (RELAXED_SHADING, src/device/program.rs) hold their samples
 * to the host's within a tolerance, not to the bit: from here on their shading may fuse
 * multiply-adds and use the native sine and cosine (PoCL's accurate ones were the most
 * of it: 1.11-1.30x on 2 cores). The triangle test and the traversal, earlier in the
 * program, keep contraction off, and so stay watertight. */
#ifdef RELAXED_SHADING
#pragma OPENCL FP_CONTRACT ON
/* PoCL's headers define both as macros: redefining them without undefining warned on
 * every compile. */
#undef sin
#undef cos
#define sin native_sin
#define cos native_cos
#endif

/* Chris Wellons' lowbias32 integer hash. */
FORCE_INLINE uint hash_u32(uint x) {
    x ^= x >> 16; x *= 0x7feb352du;
    x ^= x >> 15; x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

/* A counter-based random stream: a number is a hash of (seed, pixel, sample, dimension). */
FORCE_INLINE uint sampler_key(uint seed, uint pixel, uint sample) {
    return hash_u32(hash_u32(hash_u32(seed ^ 0x9e3779b9u) ^ pixel) ^ sample);
}

/* Dimension `dim` of the stream `key`: a float in [0, 1). */
FORCE_INLINE float sample_1d(uint key, uint dim) {
    return (float)(hash_u32(key ^ (dim * 0x85ebca6bu)) >> 8) * (1.0f / 16777216.0f);
}

/* The first dimension of bounce b: 0-1 jitter the pixel, then DIMS_PER_BOUNCE per bounce. */
FORCE_INLINE uint bounce_dim(uint b) { return 2u + b * DIMS_PER_BOUNCE; }

/* A cosine-weighted unit direction about the unit normal n (Duff et al. 2017 basis). */
FORCE_INLINE float3 cosine_direction(float3 n, float u1, float u2) {
    float r = sqrt(u1);
    float phi = 2.0f * M_PI_F * u2;
    float x = r * cos(phi), y = r * sin(phi);
    float z = sqrt(fmax(1.0f - u1, 0.0f));
    float sign = n.z >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (sign + n.z);
    float b = n.x * n.y * a;
    float3 t = (float3)(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
    float3 bt = (float3)(b, sign + n.y * n.y * a, -n.y);
    return t * x + bt * y + n * z;
}

/* A uniform point on the triangle (a, b, c). */
FORCE_INLINE float3 triangle_point(float3 a, float3 b, float3 c, float u1, float u2) {
    float su = sqrt(u1);
    float w0 = 1.0f - su, w1 = u2 * su;
    return a * w0 + b * w1 + c * (1.0f - w0 - w1);
}


/* A uniform point of the unit disk from dimensions dim, dim + 1, ...: the first of
 * LENS_TRIES pairs in the square [-1, 1)^2 that falls inside it, else the centre (once in
 * about 5e10). Rejection rather than a polar map: no sin and cos, whose device versions
 * may differ from the host's in the last bit, so that lens rays are the host's bit for bit. */
FORCE_INLINE float2 disk_point(uint key, uint dim) {
    for (uint k = 0; k < LENS_TRIES; ++k) {
        float a = 2.0f * sample_1d(key, dim + 2 * k) - 1.0f;
        float b = 2.0f * sample_1d(key, dim + 2 * k + 1) - 1.0f;
        if (a * a + b * b < 1.0f) return (float2)(a, b);
    }
    return (float2)(0.0f, 0.0f);
}

/* The ray of pixel (x, y) jittered within the pixel and, with an open lens, from a point
 * of the lens drawn from dimensions LENS_DIM on (far above the bounces' dimensions, so a
 * pinhole's samples stay as they were): its direction returned, its origin in *org. */
FORCE_INLINE float3 jittered_ray(CAMERA_PARAMS, uint x, uint y, uint key, float3* org) {
    float fx = (float)x + sample_1d(key, 0u);
    float fy = (float)y + sample_1d(key, 1u);
    if (lens_u.w == 0.0f) return camera_ray_at(CAMERA, fx, fy, org);
    return lens_ray(CAMERA, fx, fy, disk_point(key, LENS_DIM), org);
}
