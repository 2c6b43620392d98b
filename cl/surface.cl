/* surface.cl: what a hit looks like: the shading normal interpolated from the vertex
 * normals (and bent by a normal map), the shadow-terminator fix, the textured base colour
 * and emission, and the cut-out masks that the traversals consult. Mirrored by
 * src/material/surface.rs. SURFACE_* and TRIANGLE_MASKED come from the host. */

/* The per-vertex data and textures (Surface in src/material/surface.rs), which every
 * kernel takes with the scene: corners[3 prim + k] is corner k of triangle prim (file
 * order) as an index into normals (3 floats each), uvs (2) and vertex_colors (3); which of them
 * exist is in surface_flags. */
#define SURFACE_PARAMS __global const Material* materials, __global const uint* corners, \
    __global const float* normals, __global const float* uvs, __global const float* vertex_colors, \
    __global const TextureInfo* textures, __global const half* texels, uint surface_flags
#define SURFACE materials, corners, normals, uvs, vertex_colors, textures, texels, surface_flags

/* Dot and cross products and lengths written out: the built-ins may fuse multiply-adds,
 * which the host does not (the shade modes' colours match the host's to the bit). */
FORCE_INLINE float dot3(float3 a, float3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
FORCE_INLINE float3 cross3(float3 a, float3 b) {
    return (float3)(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

/* The barycentric interpolation of three values. */
#define LERP3(a, b, c, w) ((a) * (w).x + (b) * (w).y + (c) * (w).z)

/* The texture coordinates at barycentrics w of triangle prim (0 without coordinates). */
FORCE_INLINE float2 surface_uv(SURFACE_PARAMS, uint prim, float3 w) {
    if ((surface_flags & SURFACE_UVS) == 0u) return (float2)(0.0f);
    uint i0 = corners[3 * prim], i1 = corners[3 * prim + 1], i2 = corners[3 * prim + 2];
    return LERP3(vload2(i0, uvs), vload2(i1, uvs), vload2(i2, uvs), w);
}

/* Whether a hit on tri, a triangle the ray r found, counts: not where a cut-out mask's
 * alpha is below the material's cutoff. Read at full resolution: every ray sees the same
 * holes. */
FORCE_INLINE bool mask_keeps(SURFACE_PARAMS, const WatertightRay* r, const __global Triangle* tri) {
    if ((tri->flags & TRIANGLE_MASKED) == 0u) return true;
    const __global Material* m = &materials[tri->material];
    float2 uv = surface_uv(SURFACE, tri->prim, hit_barycentrics(r, tri));
    return sample_texture(textures, texels, m->alpha_texture, uv, 0.0f).w >= m->alpha_cutoff;
}

/* The unit shading normal at a primary hit, as the mesh orients it, for the single-hit
 * shade modes: the vertex normals interpolated (normal maps are left to the progressive
 * modes, so that the primary-ray kernel stays as lean as the traversal needs: the texture
 * code took registers from it and slowed the wide layouts on the H200 by 15%). Even this
 * much costs them 8 registers and 12% there, so it is compiled in only for scenes with
 * vertex normals (SHADING_NORMALS; SurfaceFeatures in src/material/surface.rs). */
FORCE_INLINE float3 shading_normal(SURFACE_PARAMS, const __global Triangle* tri, float3 org, float3 dir) {
    float3 v0 = load3(tri->v0);
    float3 cross_e = cross3(load3(tri->v1) - v0, load3(tri->v2) - v0);
    float3 front = cross_e / length3(cross_e);
#ifndef SHADING_NORMALS
    return front;
#else
    if ((surface_flags & SURFACE_NORMALS) == 0u) return front;
    WatertightRay r = watertight_ray(org, dir);
    float3 w = hit_barycentrics(&r, tri);
    uint prim = tri->prim;
    uint i0 = corners[3 * prim], i1 = corners[3 * prim + 1], i2 = corners[3 * prim + 2];
    float3 n0 = vload3(i0, normals), n1 = vload3(i1, normals), n2 = vload3(i2, normals);
    if (!(dot3(n0, n0) > 0.0f && dot3(n1, n1) > 0.0f && dot3(n2, n2) > 0.0f)) return front;
    float3 mixed = LERP3(n0, n1, n2, w);
    float len = length3(mixed);
    return len > 0.0f ? mixed / len : front;
#endif
}

/* What the integrator needs of a hit. */
typedef struct {
    float3 origin;   /* where rays leave from: off the surface on the ray's side */
    float3 through;  /* where refracted rays leave from: off the plain hit point, far side */
    float3 ng;       /* unit geometric normal, on the ray's side */
    float3 ns;       /* unit shading normal, on the ray's side */
    float3 normal;   /* unit shading normal as the mesh orients it (the normal shade mode) */
    float3 albedo;   /* base colour: factor x texture x vertex colour */
    float3 emission; /* emitted radiance: factor x texture */
    float roughness; /* perceptual roughness: factor x texture (green) */
    float metallic;  /* metalness: factor x texture (blue) */
    bool front_face; /* whether the ray hit the side the winding's normal points to */
} SurfacePoint;

/* Texture `index` at uv for a ray cone of lod_base (log2 of the footprint in texture
 * space units, SurfacePoint's caller's), the texture's own resolution added. */
FORCE_INLINE float4 sample_footprint(SURFACE_PARAMS, int index, float2 uv, float lod_base) {
    const __global TextureInfo* t = &textures[index];
    float lod = lod_base + 0.5f * log2((float)t->width * (float)t->height);
    return sample_texture(textures, texels, index, uv, lod);
}

/* The surface at the hit of the ray (org, dir) on tri at ray parameter t, with the ray
 * cone `cone_width` wide there (world units; 0 reads full-resolution textures) and the
 * ray offset `offset` along the geometric normal. */
FORCE_INLINE SurfacePoint surface_point(SURFACE_PARAMS, const __global Triangle* tri, float3 org, float3 dir,
                                        float t, float offset, float cone_width) {
    SurfacePoint s;
    const __global Material* m = &materials[tri->material];
    float3 v0 = load3(tri->v0), v1 = load3(tri->v1), v2 = load3(tri->v2);
    float3 e1 = v1 - v0, e2 = v2 - v0;
    float3 cross_e = cross3(e1, e2);
    float area2 = length3(cross_e);
    float3 front = cross_e / area2;
    bool back = dot3(front, dir) > 0.0f;
    s.ng = back ? -front : front;
    s.albedo = load3(m->albedo);
    /* An emitter shines from its front face only, unless two-sided (TRIANGLE_TWO_SIDED). */
    bool shines = !back || (tri->flags & TRIANGLE_TWO_SIDED) != 0u;
    s.emission = shines ? load3(m->emission) : (float3)(0.0f);
    s.roughness = m->roughness;
    s.metallic = m->metallic;
    s.front_face = !back;
    uint prim = tri->prim;
    if (surface_flags == 0u) {
        /* Flat and untextured: the plain hit point, as before shading data existed. */
        s.ns = s.ng;
        s.normal = front;
        float3 hit = org + dir * t;
        s.origin = hit + s.ng * offset;
        s.through = hit - s.ng * offset;
        return s;
    }
    WatertightRay r = watertight_ray(org, dir);
    float3 w = hit_barycentrics(&r, tri);
    uint i0 = corners[3 * prim], i1 = corners[3 * prim + 1], i2 = corners[3 * prim + 2];
    float3 n = front;
    bool smooth = false;
    float3 n0 = front, n1 = front, n2 = front;
    if ((surface_flags & SURFACE_NORMALS) != 0u) {
        n0 = vload3(i0, normals); n1 = vload3(i1, normals); n2 = vload3(i2, normals);
        /* A zero normal at a corner means the file gave none there: stay flat. */
        smooth = dot3(n0, n0) > 0.0f && dot3(n1, n1) > 0.0f && dot3(n2, n2) > 0.0f;
        if (smooth) {
            float3 mixed = LERP3(n0, n1, n2, w);
            float len = length3(mixed);
            smooth = len > 0.0f;
            if (smooth) n = mixed / len;
        }
    }
    /* Programs of scenes whose materials read no texture (TEXTURES undefined) leave the
     * lookups out: they are much of the progressive kernels' code and compile time. */
#ifdef TEXTURES
    if ((surface_flags & SURFACE_UVS) != 0u) {
        float2 t0 = vload2(i0, uvs), t1 = vload2(i1, uvs), t2 = vload2(i2, uvs);
        float2 uv = LERP3(t0, t1, t2, w);
        float2 d1 = t1 - t0, d2 = t2 - t0;
        float uv_det = d1.x * d2.y - d1.y * d2.x;
        /* Ray cones (Akenine-Moller et al. 2019): the footprint's width over the
         * texture-space scale of this triangle, widened by the grazing angle. */
        float cos_view = fabs(dot3(front, dir)) / length3(dir);
        float lod_base = log2(cone_width / fmax(cos_view, 1e-4f))
                 + 0.5f * log2(fabs(uv_det) / area2);
        if (m->normal_texture != NO_TEXTURE && uv_det != 0.0f) {
            float3 tangent = (e1 * d2.y - e2 * d1.y) / uv_det;
            float3 bitangent = (e2 * d1.x - e1 * d2.x) / uv_det;
            float3 tn = sample_footprint(SURFACE, m->normal_texture, uv, lod_base).xyz * 2.0f - 1.0f;
            tn.x *= m->normal_scale;
            tn.y *= m->normal_scale;
            float3 tt = tangent - n * dot3(n, tangent);
            float tt_len = length3(tt);
            if (tt_len > 0.0f) {
                tt = tt / tt_len;
                float3 bt = cross3(n, tt);
                if (dot3(bt, bitangent) < 0.0f) bt = -bt;
                float3 mapped = tt * tn.x + bt * tn.y + n * tn.z;
                float mapped_len = length3(mapped);
                if (mapped_len > 0.0f) n = mapped / mapped_len;
            }
        }
        if (m->base_texture != NO_TEXTURE) {
            s.albedo = s.albedo * sample_footprint(SURFACE, m->base_texture, uv, lod_base).xyz;
        }
        if (m->emission_texture != NO_TEXTURE && shines) {
            s.emission = s.emission * sample_footprint(SURFACE, m->emission_texture, uv, lod_base).xyz;
        }
        if (m->metallic_roughness_texture != NO_TEXTURE) {
            float4 mr = sample_footprint(SURFACE, m->metallic_roughness_texture, uv, lod_base);
            s.roughness *= mr.y;
            s.metallic *= mr.z;
        }
    }
#endif
    if ((surface_flags & SURFACE_COLORS) != 0u) {
        s.albedo = s.albedo * LERP3(vload3(i0, vertex_colors), vload3(i1, vertex_colors), vload3(i2, vertex_colors), w);
    }
    s.normal = n;
    s.ns = dot3(n, s.ng) < 0.0f ? -n : n;
    float3 p = LERP3(v0, v1, v2, w);
    /* Refracted rays leave from the plain point: lifted, they would meet this triangle again. */
    s.through = p - s.ng * offset;
    if (smooth) {
        /* Hanika 2021, "Hacking the shadow terminator": the point lifted onto the curved
         * surface the vertex normals describe (each corner's tangent plane, blended), so
         * that shadow rays from a coarse smooth mesh do not start in its facets' shadow. */
        float flip = back ? -1.0f : 1.0f;
        float3 m0 = n0 * flip, m1 = n1 * flip, m2 = n2 * flip;
        float d0 = fmin(0.0f, dot3(p - v0, m0)), d1 = fmin(0.0f, dot3(p - v1, m1));
        float d2 = fmin(0.0f, dot3(p - v2, m2));
        p = p - (m0 * (d0 * w.x) + m1 * (d1 * w.y) + m2 * (d2 * w.z));
    }
    s.origin = p + s.ng * offset;
    return s;
}
