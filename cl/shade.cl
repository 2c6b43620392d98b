/* shade.cl: the colour of a primary hit in the single-hit shade modes (normal, depth,
 * lambert: SHADE_* from the host's Shade::code, src/render/mod.rs), from the shading
 * normal (cl/surface.cl), and the writing of a pixel's hit and colour; mirrored by
 * src/render/shade.rs. */

/* A colour channel in [0, 1] as a byte, rounded. */
FORCE_INLINE uint quantize(float v) { return (uint)(clamp(v, 0.0f, 1.0f) * 255.0f + 0.5f); }

/* An opaque RGBA8 colour, red in the low byte. */
FORCE_INLINE uint pack_rgba(float r, float g, float b) {
    return quantize(r) | (quantize(g) << 8) | (quantize(b) << 16) | (255u << 24);
}

/* The colour of a hit with unit normal n at `distance` along `dir`: ShadeParams::color. */
FORCE_INLINE uint shade_hit(int mode, float near, float far, float3 n, float distance, float3 dir) {
    if (mode == SHADE_NORMAL) {
        return pack_rgba(0.5f * n.x + 0.5f, 0.5f * n.y + 0.5f, 0.5f * n.z + 0.5f);
    }
    if (mode == SHADE_DEPTH) {
        float g = 1.0f - (distance - near) / (far - near);
        return pack_rgba(g, g, g);
    }
    float d_len = sqrt(dir.x * dir.x + dir.y * dir.y + dir.z * dir.z);
    float c = fabs(n.x * dir.x + n.y * dir.y + n.z * dir.z) / d_len;
    return pack_rgba(c, c, c);
}

/* Writes pixel (x, row) of the pitched output images, whose row 0 is the first image row of
 * the band being traced. Pitches count elements, not bytes. With colors null (a frame of
 * hits alone, as the benchmark's closest-hit query asks) no colour is shaded or stored. */
FORCE_INLINE void store_pixel(__global Hit* hits, uint hit_pitch, __global uint* colors, uint color_pitch,
                        uint x, uint row, uint best, float t, float3 dir, const __global Triangle* tris,
                        float3 n, int shade, float near, float far) {
    Hit h;
    uint color = 0xFF000000u;
    if (best == MISS) {
        h.prim = MISS;
        h.t = INFINITY;
    } else {
        float distance = t * length3(dir);
        h.prim = tris[best].prim;
        h.t = distance;
        if (colors != 0) color = shade_hit(shade, near, far, n, distance, dir);
    }
    hits[row * hit_pitch + x] = h;
    if (colors != 0) colors[row * color_pitch + x] = color;
}
