/* integrator.cl: the progressive shade modes (ambient occlusion, a light with hard
 * shadows, path tracing through cl/bsdf.cl's models), sample_count samples per pixel per
 * launch, added to a pitched long4 accumulation image (fixed-point radiance sums, and the
 * sample count in w) over a region of the image. Mirrored by
 * src/render/integrator.rs, whence SHADOW_AMBIENT and ROULETTE_AFTER come. Compiled, like
 * trace.cl, against a BVH or every triangle, into programs built with sampling; the host
 * binds the parameters by name (src/device/tracer.rs; tests/layout.rs compares them). Each
 * kernel is compiled only where its KERNEL_<NAME> is defined, as in trace.cl. */

/* jittered_ray, the camera ray of a sample, is in sampling.cl (so the probe program can
 * compare it with the host's). */

/* The unit normal along which emitter tri shines towards a point in direction -dir from
 * it: its front face's (the winding's), or for a two-sided emitter the one turned to face
 * dir's origin side. */
FORCE_INLINE float3 emitting_normal(const __global Triangle* tri, float3 dir) {
    float3 v0 = load3(tri->v0);
    float3 n = normalize(cross(load3(tri->v1) - v0, load3(tri->v2) - v0));
    return (tri->flags & TRIANGLE_TWO_SIDED) != 0u && dot(n, dir) > 0.0f ? -n : n;
}

/* The sky of scenes without emitters or other lights: white at the horizon, blue
 * overhead, grey below. */
FORCE_INLINE float3 sky(float3 d) {
    float up = d.y / length(d);
    return up >= 0.0f ? mix((float3)(1.0f), (float3)(0.45f, 0.65f, 1.0f), up)
                      : mix((float3)(1.0f), (float3)(0.35f), -up);
}

/* What the shade modes read besides the scene and its surfaces: the emitting triangles
 * (indices into tris) with the cumulative distribution of their power and its total; the
 * environment (environment.cl) and the punctual lights (punctual.cl), read only by programs
 * compiled for them (ENVIRONMENT, PUNCTUAL) and one dummy element otherwise. */
#define LIGHT_PARAMS __global const uint* emitters, \
    __global const float* emitter_cdf, uint emitter_count, float emitter_power, \
    ENV_PARAMS, PUNCTUAL_PARAMS
/* Passes LIGHT_PARAMS on. */
#define LIGHTS emitters, emitter_cdf, emitter_count, emitter_power, ENV, punctual, punctual_count

/* Every sample kernel takes the same arguments; each mode reads the ones it needs. The
 * launch covers columns [col0, col_end) and rows [global offset, row_end); the
 * accumulation image's pixel (0, 0) is image pixel (col0, row0). */
#define SAMPLE_PARAMS SCENE_PARAMS, LIGHT_PARAMS, CAMERA_BAND_PARAMS, \
    float offset, uint seed, uint sample, uint sample_count, \
    uint ao_samples, float ao_distance, float4 light, uint max_bounces, \
    __global long4* accum, __global uint* rays, uint accum_pitch, uint col0, uint col_end

/* A radiance component as the sums take it: clamped (NaN to 0), then fixed-point. Integer
 * sums are exact in any order, so split and merged renders equal one-shot ones. Mirrored by
 * to_fixed in src/render/integrator.rs. */
FORCE_INLINE long to_fixed(float v) {
    v = v >= 0.0f ? fmin(v, MAX_SAMPLE_RADIANCE) : 0.0f;
#ifdef POCL_DEVICE_ADDRESS_BITS
    /* PoCL (whose compiler alone defines that) builds convert_long_rte, and rint, from
     * about 27 instructions with branches: 3-4% of a sample's instructions, 2-4% of its
     * time on 2 cores (docs/bench/2026-12-08-cpu-rounding.md). So there the sum is
     * rounded to the nearest integer, ties to even, by adding and taking away 2^23, which
     * does it to a float below 2^23 in the default rounding mode; larger ones are
     * integers already. Other compilers round in an instruction or two. */
    float s = v * RADIANCE_SCALE;
    return convert_long(s < 8388608.0f ? (s + 8388608.0f) - 8388608.0f : s);
#else
    return convert_long_rte(v * RADIANCE_SCALE);
#endif
}

FORCE_INLINE long3 fixed3(float3 radiance) {
    return (long3)(to_fixed(radiance.x), to_fixed(radiance.y), to_fixed(radiance.z));
}

/* A work-item's sums of its launch's samples, added to its pixel's once. */
FORCE_INLINE void add_samples(__global long4* accum, __global uint* rays, uint accum_pitch,
                              uint x, uint row, long3 sums, uint samples, uint ray_count) {
    uint i = row * accum_pitch + x;
    accum[i] += (long4)(sums, (long)samples);
    rays[i] += ray_count;
}

/* What every sample kernel starts with: the work-item's pixel, leaving at once outside the
 * band. Sample s of the launch draws from the stream sampler_key(seed, pixel, sample + s). */
#define SAMPLE_PIXEL                                                     \
    uint x = get_global_id(0), y = get_global_id(1);                     \
    if (x < col0 || x >= col_end || y < row0 || y >= row_end) return;

/* The closest hit of the jittered camera ray (from org along dir) of the sample whose
 * stream is key: where the ambient occlusion and shadow samples start from. */
#define SAMPLE_CAMERA_HIT                                                \
    float3 org;                                                          \
    float3 dir = jittered_ray(CAMERA, x, y, key, &org);                  \
    float t;                                                             \
    uint hit = trace(SCENE, org, dir, INFINITY, false, false, &t);

FORCE_INLINE bool occluded(SCENE_PARAMS, float3 org, float3 dir, float t_max) {
    float t;
    return trace(SCENE, org, dir, t_max, true, true, &t) != MISS;
}

/* The width of a camera ray's cone at ray parameter t (of the unnormalised pixel ray):
 * one pixel's footprint there. */
FORCE_INLINE float camera_cone(float4 du, float t) { return t * length3(du.xyz); }

#ifdef KERNEL_SAMPLE_AO
KERNEL void sample_ao(SAMPLE_PARAMS) {
    SAMPLE_PIXEL
    long3 sums = (long3)(0);
    uint count = 0;
    for (uint s = 0; s < sample_count; ++s) {
        uint key = sampler_key(seed, y * width + x, sample + s);
        SAMPLE_CAMERA_HIT
        float3 radiance = (float3)(0.0f);
        count += 1;
        if (hit != MISS) {
            SurfacePoint sp = surface_point(SURFACE, &tris[hit], org, dir, t, offset, camera_cone(du, t));
            uint open = 0;
            for (uint k = 0; k < ao_samples; ++k) {
                float3 d = cosine_direction(sp.ns, sample_1d(key, bounce_dim(0) + 2 * k), sample_1d(key, bounce_dim(0) + 2 * k + 1));
                /* Below the geometric surface a shading-normal direction is blocked. */
                open += dot3(d, sp.ng) > 0.0f && !occluded(SCENE, sp.origin, d, ao_distance);
            }
            count += ao_samples;
            radiance = (float3)((float)open / (float)max(ao_samples, 1u));
        }
        sums += fixed3(radiance);
    }
    add_samples(accum, rays, accum_pitch, x - col0, y - row0, sums, sample_count, count);
}
#endif

#ifdef KERNEL_SAMPLE_SHADOW
KERNEL void sample_shadow(SAMPLE_PARAMS) {
    SAMPLE_PIXEL
    long3 sums = (long3)(0);
    uint count = 0;
    for (uint s = 0; s < sample_count; ++s) {
        uint key = sampler_key(seed, y * width + x, sample + s);
        SAMPLE_CAMERA_HIT
        float3 radiance = (float3)(0.0f);
        count += 1;
        if (hit != MISS) {
            SurfacePoint sp = surface_point(SURFACE, &tris[hit], org, dir, t, offset, camera_cone(du, t));
            float3 origin = sp.origin;
            /* light.w: 0 for a direction towards the light, 1 for the light's position. */
            float3 l = light.w == 0.0f ? normalize(light.xyz) : normalize(light.xyz - origin);
            float reach = light.w == 0.0f ? INFINITY : length(light.xyz - origin);
            float c = dot(sp.ns, l);
            float direct = 0.0f;
            if (c > 0.0f && dot3(l, sp.ng) > 0.0f) {
                count += 1;
                if (!occluded(SCENE, origin, l, reach)) direct = c;
            }
            radiance = sp.albedo * (SHADOW_AMBIENT + (1.0f - SHADOW_AMBIENT) * direct) + sp.emission;
        }
        sums += fixed3(radiance);
    }
    add_samples(accum, rays, accum_pitch, x - col0, y - row0, sums, sample_count, count);
}
#endif

/* The radiance an emitter e sends from its point with barycentrics (w0, w1, 1 - w0 - w1):
 * its material's emission, times its emission texture there (full resolution). */
FORCE_INLINE float3 emitted(SURFACE_PARAMS, const __global Triangle* e, float w0, float w1) {
    const __global Material* m = &materials[e->material];
    float3 le = load3(m->emission);
#ifdef TEXTURES
    if (m->emission_texture != NO_TEXTURE && (surface_flags & SURFACE_UVS) != 0u) {
        float2 uv = surface_uv(SURFACE, e->prim, (float3)(w0, w1, 1.0f - w0 - w1));
        le = le * sample_texture(textures, texels, m->emission_texture, uv, 0.0f).xyz;
    }
#endif
    return le;
}

/* The density per area with which light samples pick a point of emitter tri: its
 * material's mean emission (its power per area) over all emitters' power. */
FORCE_INLINE float emitter_density(__global const Material* materials,
                                   const __global Triangle* tri, float emitter_power) {
    float3 le = load3(materials[tri->material].emission);
    return (le.x + le.y + le.z) * (1.0f / 3.0f) / emitter_power;
}

/* What the shading point scatters towards the eye of light arriving from unit direction
 * l, per unit of irradiance, and in *pdf the density with which BSDF sampling picks l. */
FORCE_INLINE float3 scatter_from(const Shading* sh, bool lambert, float3 n, float3 tn,
                                 float3 bn, float3 wo_l, float3 l, float* pdf) {
    if (lambert) {
        float cos_here = fmax(dot(n, l), 0.0f);
        *pdf = cos_here / M_PI_F;
        return sh->albedo * (cos_here / M_PI_F);
    }
    return bsdf_eval(sh, wo_l, (float3)(dot(l, tn), dot(l, bn), dot(l, n)), pdf);
}

#ifdef KERNEL_SAMPLE_PATH
/* A light sample of the vertex: `light` reaches it unless something blocks the shadow ray
 * from `from` along unit `towards` before `reach`. Where the host defines DEFERRED_SHADOW
 * (src/device/program.rs: a vertex takes at most one light sample), the shadow ray waits
 * in the path's state for the loop's next turn (sample_path); elsewhere it is traced
 * here. */
#ifdef DEFERRED_SHADOW
#if defined(ENVIRONMENT) && defined(EMITTERS) || defined(PUNCTUAL)
#error "DEFERRED_SHADOW holds one light sample a vertex: emitters or an environment, not both, no punctual lights"
#endif
#define SHADOW_RAY(from, towards, reach, light)                          \
    {                                                                    \
        p->shadow_org = (from);                                          \
        p->shadow_dir = (towards);                                       \
        p->shadow_reach = (reach);                                       \
        p->shadow_light = (light);                                       \
        p->shadow = true;                                                \
    }
#else
#define SHADOW_RAY(from, towards, reach, light)                          \
    if (!occluded(SCENE, from, towards, reach)) p->radiance += (light);
#endif

/* A path between its vertices: the ray it goes on along (from org along dir), what it has
 * gathered, what its vertices so far pass on, and its sample's stream. */
typedef struct {
    float3 org, dir, radiance, throughput;
    /* The ray cone's width at the last hit (0 at the eye), for texture filtering. */
    float cone;
    /* The density of the last bounce's direction, to weigh an emitter it hits against
     * light sampling (the power heuristic); 0 where light sampling could not have found
     * it: camera rays, delta lobes, light through the surface. */
    float last_pdf;
    uint bounce, count, key;
#ifdef DEFERRED_SHADOW
    /* The vertex's light sample, whose shadow ray the loop traces next (SHADOW_RAY). */
    float3 shadow_org, shadow_dir, shadow_light;
    float shadow_reach;
    bool shadow;
#endif
} PathState;

/* A path's start: the camera ray of the sample whose stream is key. */
FORCE_INLINE void path_begin(CAMERA_PARAMS, uint x, uint y, uint key, PathState* p) {
    p->key = key;
    p->dir = jittered_ray(CAMERA, x, y, key, &p->org);
    p->radiance = (float3)(0.0f);
    p->throughput = (float3)(1.0f);
    p->count = 1;
    p->cone = 0.0f;
    p->last_pdf = 0.0f;
    p->bounce = 0;
#ifdef DEFERRED_SHADOW
    p->shadow = false;
#endif
}

/* The path's vertex at its ray's hit (triangle hit at ray parameter t, or MISS): emission
 * found, light sampled, and the next direction drawn. Returns whether the path goes on
 * (p's ray is then the next one); every false ends it. */
FORCE_INLINE bool path_vertex(SCENE_PARAMS, LIGHT_PARAMS, float4 du, float offset,
                              uint max_bounces, uint hit, float t, PathState* p) {
    uint key = p->key;
    float3 dir = p->dir;
    if (hit == MISS) {
#if defined(ENVIRONMENT)
        float env_pdf;
        float3 le = env_radiance(ENV, normalize(dir), &env_pdf);
        /* Weighed against the environment's light samples, which could have found it. */
        if (p->last_pdf > 0.0f) {
            float r = env_pdf / p->last_pdf;
            le *= 1.0f / (1.0f + r * r);
        }
        p->radiance += p->throughput * le;
#elif !defined(PUNCTUAL) && defined(EMITTERS)
        if (emitter_count == 0) p->radiance += p->throughput * sky(dir);
#elif !defined(PUNCTUAL)
        p->radiance += p->throughput * sky(dir);
#endif
        return false;
    }
    const __global Triangle* tri = &tris[hit];
    p->cone = p->bounce == 0 ? camera_cone(du, t) : p->cone + BOUNCE_CONE_SPREAD * t;
    SurfacePoint sp = surface_point(SURFACE, tri, p->org, dir, t, offset, p->cone);
#ifdef MIS
    if (p->last_pdf > 0.0f && max3(sp.emission) > 0.0f) {
        /* dir is a unit vector after the camera ray, so t is the distance. */
        float r = t * t * emitter_density(materials, tri, emitter_power)
                / fabs(dot3(sp.ng, dir)) / p->last_pdf;
        p->radiance += p->throughput * sp.emission * (1.0f / (1.0f + r * r));
    } else if (p->last_pdf == 0.0f) {
        p->radiance += p->throughput * sp.emission;
    }
    /* The last bounce's direction was traced only for the emitter it might hit. */
    if (p->bounce > max_bounces) return false;
#else
    /* Lambertian scenes: after the camera ray, emitters are reached by light samples
     * alone (no MIS), which for diffuse bounces off small lights loses nothing and
     * saves the weights and the last bounce's ray. */
    if (p->bounce == 0) p->radiance += p->throughput * sp.emission;
#endif
    Shading sh = shading_at(&materials[tri->material], &sp);
    /* Lambert alone takes the short way, without a local frame. Programs of scenes whose
     * every material is Lambertian leave the other models out (BSDFS undefined): they
     * cost registers, and so speed, even where no ray reaches them. */
#ifdef BSDFS
    bool lambert = sh.bsdf == BSDF_DIFFUSE && sh.metallic <= 0.0f;
#else
    const bool lambert = true;
#endif
    float3 origin = sp.origin;
    float3 n = sp.ns;
    float3 tn = (float3)(0.0f), bn = (float3)(0.0f), wo_l = (float3)(0.0f);
    if (!lambert) {
        basis(n, &tn, &bn);
        float3 wo = -normalize(dir);
        wo_l = (float3)(dot(wo, tn), dot(wo, bn), dot(wo, n));
    }
    uint d = bounce_dim(p->bounce);
    bool lit = lambert || !shading_all_delta(&sh);
    /* Programs of scenes without emitting materials (EMITTERS undefined) leave the
     * emitters' light samples out. */
#ifdef EMITTERS
    if (emitter_count > 0 && lit) {
        const __global Triangle* e = &tris[emitters[cdf_find(emitter_cdf, emitter_count, sample_1d(key, d))]];
        float u1 = sample_1d(key, d + 1), u2 = sample_1d(key, d + 2);
        float3 q = triangle_point(load3(e->v0), load3(e->v1), load3(e->v2), u1, u2);
        float3 w = q - origin;
        float d2 = dot(w, w);
        float3 l = w / sqrt(d2);
        float cos_there = dot(emitting_normal(e, l), -l);
        if (cos_there > 0.0f && dot3(l, sp.ng) > 0.0f) {
            float bsdf_pdf;
            float3 f = scatter_from(&sh, lambert, n, tn, bn, wo_l, l, &bsdf_pdf);
            if (max3(f) > 0.0f) {
                p->count += 1;
                float su = sqrt(u1);
                float light_pdf = d2 * emitter_density(materials, e, emitter_power) / cos_there;
#ifdef MIS
                float r = bsdf_pdf / light_pdf;
                float weight = 1.0f / (1.0f + r * r);
#else
                float weight = 1.0f;
#endif
                SHADOW_RAY(origin, l, sqrt(d2) * (1.0f - 1e-4f),
                           p->throughput * f * emitted(SURFACE, e, 1.0f - su, u2 * su) * (weight / light_pdf))
            }
        }
    }
#endif
#ifdef ENVIRONMENT
    if (lit) {
        float3 l;
        float env_pdf;
        float3 le = env_sample(ENV, sample_1d(key, d + 8), sample_1d(key, d + 9), &l, &env_pdf);
        if (env_pdf > 0.0f && dot3(l, sp.ng) > 0.0f) {
            float bsdf_pdf;
            float3 f = scatter_from(&sh, lambert, n, tn, bn, wo_l, l, &bsdf_pdf);
            if (max3(f) > 0.0f) {
                p->count += 1;
                float r = bsdf_pdf / env_pdf;
                SHADOW_RAY(origin, l, INFINITY, p->throughput * f * le * (1.0f / (1.0f + r * r) / env_pdf))
            }
        }
    }
#endif
#ifdef PUNCTUAL
    /* Every punctual light, each by one shadow ray: nothing else can find them. */
    for (uint k = 0; lit && k < punctual_count; ++k) {
        float3 l;
        float reach;
        float3 e = punctual_incident(punctual, k, origin, &l, &reach);
        if (max3(e) > 0.0f && dot3(l, sp.ng) > 0.0f) {
            float bsdf_pdf;
            float3 f = scatter_from(&sh, lambert, n, tn, bn, wo_l, l, &bsdf_pdf);
            if (max3(f) > 0.0f) {
                p->count += 1;
                SHADOW_RAY(origin, l, reach * (1.0f - 1e-4f), p->throughput * f * e)
            }
        }
    }
#endif
#ifndef MIS
    if (p->bounce == max_bounces) return false;
#endif
    float u1 = sample_1d(key, d + 4), u2 = sample_1d(key, d + 5);
    BsdfSample bs;
    if (lambert) {
        bs.wi = cosine_direction(n, u1, u2);
        bs.weight = sh.albedo;
        bs.pdf = fmax(dot(bs.wi, n), 0.0f) / M_PI_F;
        bs.delta = false;
        bs.transmitted = false;
    } else {
        if (!bsdf_sample(&sh, wo_l, sample_1d(key, d + 6), u1, u2, sample_1d(key, d + 7), &bs)) return false;
        bs.wi = tn * bs.wi.x + bn * bs.wi.y + n * bs.wi.z;
    }
    p->throughput *= bs.weight;
    if (p->bounce >= ROULETTE_AFTER) {
        float keep = fmin(max3(p->throughput), 0.95f);
        if (sample_1d(key, d + 3) >= keep) return false;
        p->throughput /= keep;
    }
    /* A reflected direction below the geometric surface would leave through it, a
     * refracted one above it would not. */
    float side = dot3(bs.wi, sp.ng);
    if (bs.transmitted ? side >= 0.0f : side <= 0.0f) return false;
    p->org = bs.transmitted ? sp.through : origin;
    p->dir = bs.wi;
    p->last_pdf = bs.delta || bs.transmitted ? 0.0f : bs.pdf;
    p->count += 1;
    p->bounce += 1;
    return true;
}

/* The launch's samples of a pixel are traced one path after another in one loop, each turn
 * of which traces one ray of the current path: a work-item whose path ends starts its next
 * sample in the next turn (path regeneration), so that the work-items of a SIMD group keep
 * tracing together instead of waiting, sample by sample, for their longest path. */
KERNEL void sample_path(SAMPLE_PARAMS) {
    SAMPLE_PIXEL
    /* Each sample's sums go to the pixel's as it ends, not kept in registers across every
     * traversal: on the H200 that made path tracing 1-12% faster
     * (docs/bench/2026-12-04-wavefront.md). */
    __global long4* pixel_sums = &accum[(y - row0) * accum_pitch + (x - col0)];
    uint rays_traced = 0;
    uint s = 0;
    PathState p;
#ifdef DEFERRED_SHADOW
    bool going_on = false, shadow_turn = false;
#endif
    path_begin(CAMERA, x, y, sampler_key(seed, y * width + x, sample), &p);
    for (;;) {
        /* One call site for the camera ray and every bounce: each inlined traversal costs
         * compile time, and on the H200 the one site also ran 1.4-4.4% faster
         * (docs/bench/2026-12-04-first-image.md). */
        float t;
#ifdef DEFERRED_SHADOW
        /* The light sample's shadow ray goes through the same call site, in the turn
         * after its vertex: no second traversal is inlined, and none runs while the
         * vertex's shading state is live. Its light is added before the next vertex's, as
         * an inline test would. */
        uint hit = MISS;
        if (!shadow_turn || p.shadow) {
            hit = trace(SCENE, shadow_turn ? p.shadow_org : p.org, shadow_turn ? p.shadow_dir : p.dir,
                        shadow_turn ? p.shadow_reach : INFINITY, shadow_turn, true, &t);
        }
        if (!shadow_turn) {
            going_on = path_vertex(SCENE, LIGHTS, du, offset, max_bounces, hit, t, &p);
#ifdef LOCKSTEP_SHADOW
            /* Where the host defines it (SIMD devices), every vertex is followed by a
             * shadow turn, with or without a ray, so that the work-items of a SIMD group
             * keep shading in the same turns; a CPU's work-items run one at a time and skip
             * the empty turns. */
            shadow_turn = true;
#else
            shadow_turn = p.shadow;
#endif
            if (shadow_turn || going_on) continue;
        } else {
            shadow_turn = false;
            if (p.shadow && hit == MISS) p.radiance += p.shadow_light;
            p.shadow = false;
            if (going_on) continue;
        }
#else
        uint hit = trace(SCENE, p.org, p.dir, INFINITY, false, true, &t);
        if (path_vertex(SCENE, LIGHTS, du, offset, max_bounces, hit, t, &p)) continue;
#endif
        /* The path has ended: its sample is summed and, if the launch has more, the next
         * sample's camera ray is where the loop goes on. */
        *pixel_sums += (long4)(fixed3(p.radiance), 0);
        rays_traced += p.count;
        if (++s == sample_count) break;
        path_begin(CAMERA, x, y, sampler_key(seed, y * width + x, sample + s), &p);
    }
    add_samples(accum, rays, accum_pitch, x - col0, y - row0, (long3)(0), sample_count, rays_traced);
}
#endif
