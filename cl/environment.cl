/* environment.cl: light from every direction at infinity, an equirectangular map looked up
 * by nearest texel and sampled by luminance, in Mitsuba 3's orientation (+y up, u =
 * atan2(d.x, -d.z) / 2 pi, v = acos(d.y) / pi), turned about +y. Mirrored by
 * src/light/environment.rs, which builds the arrays: per texel the radiance and, in w, the
 * density over (u, v); the rows' cumulative distribution (marginal) and each row's
 * (conditional). Compiled in only for scenes with an environment (ENVIRONMENT). */

#define ENV_PARAMS __global const float4* env_texels, __global const float* env_marginal, \
    __global const float* env_conditional, uint env_width, uint env_height, float2 env_rotation
#define ENV env_texels, env_marginal, env_conditional, env_width, env_height, env_rotation

/* The index whose interval of the cumulative distribution cdf[0..n) holds u (also how
 * light samples pick an emitter, cl/integrator.cl). */
FORCE_INLINE uint cdf_find(__global const float* cdf, uint n, float u) {
    uint lo = 0, hi = n - 1;
    while (lo < hi) {
        uint mid = (lo + hi) / 2;
        if (u < cdf[mid]) hi = mid; else lo = mid + 1;
    }
    return lo;
}

/* Where u falls within interval i of cdf, in [0, 1). */
FORCE_INLINE float cdf_within(__global const float* cdf, uint i, float u) {
    float lo = i == 0 ? 0.0f : cdf[i - 1];
    float width = cdf[i] - lo;
    return width > 0.0f ? clamp((u - lo) / width, 0.0f, 0.99999994f) : 0.5f;
}

/* The density per solid angle of a texel's samples where sin(theta) is sin. */
FORCE_INLINE float env_density(float4 texel, float sin_theta) {
    return sin_theta > 0.0f ? texel.w / (2.0f * M_PI_F * M_PI_F * sin_theta) : 0.0f;
}

/* The radiance arriving from unit direction d, and in *pdf the density with which
 * env_sample picks d. */
FORCE_INLINE float3 env_radiance(ENV_PARAMS, float3 d, float* pdf) {
    float c = env_rotation.x, s = env_rotation.y;
    float3 m = (float3)(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
    float u = atan2(m.x, -m.z) * (0.5f / M_PI_F);
    if (u < 0.0f) u += 1.0f;
    float y = clamp(m.y, -1.0f, 1.0f);
    float v = acos(y) * (1.0f / M_PI_F);
    uint i = min((uint)(u * (float)env_width), env_width - 1);
    uint j = min((uint)(v * (float)env_height), env_height - 1);
    float4 t = env_texels[j * env_width + i];
    *pdf = env_density(t, sqrt(fmax(1.0f - y * y, 0.0f)));
    return t.xyz;
}

/* A direction drawn by luminance times solid angle from (u1, u2), in *wi, with its
 * density in *pdf (0 at a pole: drop the sample); returns its radiance. */
FORCE_INLINE float3 env_sample(ENV_PARAMS, float u1, float u2, float3* wi, float* pdf) {
    uint j = cdf_find(env_marginal, env_height, u1);
    __global const float* row = env_conditional + j * env_width;
    uint i = cdf_find(row, env_width, u2);
    float v = ((float)j + cdf_within(env_marginal, j, u1)) / (float)env_height;
    float u = ((float)i + cdf_within(row, i, u2)) / (float)env_width;
    float theta = M_PI_F * v, phi = 2.0f * M_PI_F * u;
    float st = sin(theta);
    float3 m = (float3)(st * sin(phi), cos(theta), -st * cos(phi));
    float c = env_rotation.x, s = env_rotation.y;
    *wi = (float3)(c * m.x + s * m.z, m.y, -s * m.x + c * m.z);
    float4 t = env_texels[j * env_width + i];
    *pdf = env_density(t, st);
    return t.xyz;
}
