/* texture.cl: texture lookups, mirrored operation for operation by DeviceTextures::sample in
 * src/material/texture.rs. Every texture is a chain of mip levels of RGBA half texels, level
 * 0 first, in one buffer (texels); the table (textures) says where each chain starts.
 * WRAP_* come from the host (src/material/texture.rs). */

/* A texture's entry in the table (TextureInfo in src/material/texture.rs). */
typedef struct {
    uint offset; uint width; uint height; uint levels;
    uint wrap_u; uint wrap_v; uint pad0; uint pad1;
} TextureInfo;

/* Texel index i of an axis of n texels, wrapped by mode. */
FORCE_INLINE int wrap_texel(int i, int n, uint mode) {
    if (mode == WRAP_CLAMP) return clamp(i, 0, n - 1);
    if (mode == WRAP_MIRROR) {
        int m = i % (2 * n);
        if (m < 0) m += 2 * n;
        return m < n ? m : 2 * n - 1 - m;
    }
    int m = i % n;
    return m < 0 ? m + n : m;
}

/* A coordinate brought near [0, 1] first, so that texel indices stay small: the wrap
 * modes repeat with period 1 (mirror: 2), and a clamped coordinate beyond [-1, 2] reads
 * the same edge texel. */
FORCE_INLINE float reduce_coordinate(float u, uint mode) {
    if (!(fabs(u) < 1e7f)) u = 0.0f; /* NaN, infinite or too coarse to wrap */
    if (mode == WRAP_CLAMP) return clamp(u, -1.0f, 2.0f);
    if (mode == WRAP_MIRROR) return u - 2.0f * floor(u * 0.5f);
    return u - floor(u);
}

/* The bilinear lookup of level `level` at (u, v); v grows upwards, rows are stored from
 * the top. */
FORCE_INLINE float4 texture_bilinear(const __global TextureInfo* t, const __global half* texels,
                                     uint level, float u, float v) {
    uint offset = t->offset;
    int w = (int)t->width, h = (int)t->height;
    for (uint l = 0; l < level; ++l) {
        offset += (uint)(w * h);
        w = max(w / 2, 1);
        h = max(h / 2, 1);
    }
    float fx = reduce_coordinate(u, t->wrap_u) * (float)w - 0.5f;
    float fy = reduce_coordinate(1.0f - v, t->wrap_v) * (float)h - 0.5f;
    float x0 = floor(fx), y0 = floor(fy);
    float tx = fx - x0, ty = fy - y0;
    int xa = wrap_texel((int)x0, w, t->wrap_u), xb = wrap_texel((int)x0 + 1, w, t->wrap_u);
    int ya = wrap_texel((int)y0, h, t->wrap_v), yb = wrap_texel((int)y0 + 1, h, t->wrap_v);
    float4 a = vload_half4(offset + (uint)(ya * w + xa), texels);
    float4 b = vload_half4(offset + (uint)(ya * w + xb), texels);
    float4 c = vload_half4(offset + (uint)(yb * w + xa), texels);
    float4 d = vload_half4(offset + (uint)(yb * w + xb), texels);
    float4 top = a + (b - a) * tx;
    float4 bottom = c + (d - c) * tx;
    return top + (bottom - top) * ty;
}

/* Texture `index` at uv, trilinear between the mip levels around `lod` (0: the full
 * resolution; clamped to the chain). */
FORCE_INLINE float4 sample_texture(const __global TextureInfo* textures, const __global half* texels,
                                   int index, float2 uv, float lod) {
    const __global TextureInfo* t = &textures[index];
    lod = fmin(fmax(lod, 0.0f), (float)(t->levels - 1));
    float l0 = floor(lod);
    float f = lod - l0;
    float4 a = texture_bilinear(t, texels, (uint)l0, uv.x, uv.y);
    if (f > 0.0f) {
        float4 b = texture_bilinear(t, texels, (uint)l0 + 1u, uv.x, uv.y);
        a = a + (b - a) * f;
    }
    return a;
}
