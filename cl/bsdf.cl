/* bsdf.cl: the scattering models (BSDF_* codes, src/material/mod.rs's Bsdf), mirrored by
 * src/render/bsdf.rs, which documents them: evaluation for light samples, sampling for the
 * next bounce, and the density of each for multiple importance sampling. Directions are in
 * a frame about the shading normal (z up), both pointing away from the surface: wo towards
 * the viewer, wi towards the light. SMOOTH_ROUGHNESS comes from the host. */

/* The models a program holds: BSDF_MODELS has a bit per BSDF_* code of the scene's
 * materials and METALLIC is defined where one has metalness (every model where
 * BSDF_MODELS is not defined, as in the probe program). The models a scene does not use
 * cost code and registers all the same: without them a conductor's or a glass scene's
 * paths ran 24-29% faster on 2 cores (PoCL) and 3% on the H200
 * (docs/bench/2026-12-04-gpu-path.md). */
#ifndef BSDF_MODELS
#define BSDF_MODELS 0xffffffffu
#define METALLIC
#endif
#define IS_MODEL(s, code) ((((BSDF_MODELS) >> (code)) & 1u) != 0u && (s)->bsdf == (code))

/* A material at one hit. */
typedef struct {
    uint bsdf;
    float3 albedo, specular, eta, k;
    float ior;      /* the far side's index over the near side's */
    float alpha;    /* GGX alpha: roughness squared */
    float metallic; /* share of the Schlick metal of the base colour */
} Shading;

typedef struct {
    float3 wi;
    float3 weight; /* f |cos| / pdf */
    float pdf;     /* 0 for a delta lobe */
    bool delta;
    bool transmitted;
} BsdfSample;

FORCE_INLINE bool shading_smooth(const Shading* s) {
    return s->alpha < SMOOTH_ROUGHNESS * SMOOTH_ROUGHNESS;
}

/* Whether every lobe is a delta lobe: light samples cannot reach it. */
FORCE_INLINE bool shading_all_delta(const Shading* s) {
    bool smooth = shading_smooth(s);
    bool base = IS_MODEL(s, BSDF_THIN_DIELECTRIC)
             || (smooth && (IS_MODEL(s, BSDF_CONDUCTOR) || IS_MODEL(s, BSDF_DIELECTRIC)));
    return base && (s->metallic <= 0.0f || smooth);
}

FORCE_INLINE float max3(float3 v) { return fmax(fmax(v.x, v.y), v.z); }

FORCE_INLINE float fresnel_dielectric(float cos_i, float eta) {
    cos_i = clamp(cos_i, 0.0f, 1.0f);
    float sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.0f) return 1.0f;
    float cos_t = sqrt(1.0f - sin2_t);
    float rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    float rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    return 0.5f * (rs * rs + rp * rp);
}

FORCE_INLINE float3 fresnel_conductor(float c, float3 eta, float3 k) {
    c = clamp(c, 0.0f, 1.0f);
    float c2 = c * c;
    float s2 = 1.0f - c2;
    float3 t0 = eta * eta - k * k - (float3)(s2);
    float3 a2b2 = sqrt(fmax(t0 * t0 + eta * eta * k * k * 4.0f, (float3)(0.0f)));
    float3 t1 = a2b2 + (float3)(c2);
    float3 a = sqrt(fmax((a2b2 + t0) * 0.5f, (float3)(0.0f)));
    float3 t2 = a * (2.0f * c);
    float3 rs = (t1 - t2) / fmax(t1 + t2, (float3)(1e-12f));
    float3 t3 = a2b2 * c2 + (float3)(s2 * s2);
    float3 t4 = t2 * s2;
    float3 rp = rs * (t3 - t4) / fmax(t3 + t4, (float3)(1e-12f));
    return (rp + rs) * 0.5f;
}

FORCE_INLINE float3 schlick(float3 f0, float c) {
    float m = clamp(1.0f - c, 0.0f, 1.0f);
    float m5 = m * m * m * m * m;
    return f0 + ((float3)(1.0f) - f0) * m5;
}

FORCE_INLINE float ggx_d(float3 h, float alpha) {
    float a2 = alpha * alpha;
    float d = h.z * h.z * (a2 - 1.0f) + 1.0f;
    return a2 / (M_PI_F * d * d);
}

FORCE_INLINE float ggx_lambda(float3 w, float alpha) {
    float c2 = w.z * w.z;
    if (c2 <= 0.0f) return INFINITY;
    float t2 = fmax(1.0f - c2, 0.0f) / c2;
    return 0.5f * (-1.0f + sqrt(1.0f + alpha * alpha * t2));
}

FORCE_INLINE float ggx_g1(float3 w, float alpha) { return 1.0f / (1.0f + ggx_lambda(w, alpha)); }

FORCE_INLINE float ggx_g2(float3 wo, float3 wi, float alpha) {
    return 1.0f / (1.0f + ggx_lambda(wo, alpha) + ggx_lambda(wi, alpha));
}

FORCE_INLINE float ggx_visible_pdf(float3 wo, float3 h, float alpha) {
    return ggx_g1(wo, alpha) * fmax(dot(wo, h), 0.0f) * ggx_d(h, alpha) / wo.z;
}

/* A GGX normal visible from wo (Heitz 2018). */
FORCE_INLINE float3 ggx_visible_normal(float3 wo, float alpha, float u1, float u2) {
    float3 vh = normalize((float3)(alpha * wo.x, alpha * wo.y, wo.z));
    float len2 = vh.x * vh.x + vh.y * vh.y;
    float3 t1 = len2 > 0.0f ? (float3)(-vh.y, vh.x, 0.0f) / sqrt(len2) : (float3)(1.0f, 0.0f, 0.0f);
    float3 t2 = cross(vh, t1);
    float r = sqrt(u1);
    float phi = 2.0f * M_PI_F * u2;
    float p1 = r * cos(phi);
    float s = 0.5f * (1.0f + vh.z);
    float p2 = (1.0f - s) * sqrt(fmax(1.0f - p1 * p1, 0.0f)) + s * (r * sin(phi));
    float3 nh = t1 * p1 + t2 * p2 + vh * sqrt(fmax(1.0f - p1 * p1 - p2 * p2, 0.0f));
    return normalize((float3)(alpha * nh.x, alpha * nh.y, fmax(nh.z, 0.0f)));
}

/* wo refracted through normal n (on wo's side) into relative index eta; false under
 * total internal reflection. */
FORCE_INLINE bool refract_dir(float3 wo, float3 n, float eta, float3* wt) {
    float cos_i = dot(n, wo);
    float sin2_t = fmax(1.0f - cos_i * cos_i, 0.0f) / (eta * eta);
    if (sin2_t >= 1.0f) return false;
    float cos_t = sqrt(1.0f - sin2_t);
    *wt = -wo / eta + n * (cos_i / eta - cos_t);
    return true;
}

/* The lobes' Fresnel terms, by which one microfacet_reflection reads. */
#define FRESNEL_METAL 0
#define FRESNEL_CONDUCTOR 1
#define FRESNEL_COATING 2

FORCE_INLINE float3 lobe_fresnel(const Shading* s, int which, float c) {
    if (which == FRESNEL_METAL) return schlick(s->albedo, c);
    if (which == FRESNEL_COATING) return s->specular * fresnel_dielectric(c, s->ior);
    if (s->eta.x > 0.0f) return fresnel_conductor(c, s->eta, s->k) * s->specular;
    return schlick(s->albedo * s->specular, c);
}

/* f cos(wi) of a GGX reflection lobe, its density in *pdf. */
FORCE_INLINE float3 microfacet_reflection(const Shading* s, int which, float3 wo, float3 wi, float* pdf) {
    float3 h = wo + wi;
    *pdf = 0.0f;
    if (wi.z <= 0.0f || (h.x == 0.0f && h.y == 0.0f && h.z == 0.0f)) return (float3)(0.0f);
    h = normalize(h);
    float oh = dot(wo, h);
    if (oh <= 0.0f) return (float3)(0.0f);
    float d = ggx_d(h, s->alpha);
    float3 f = lobe_fresnel(s, which, oh) * (d * ggx_g2(wo, wi, s->alpha) / (4.0f * wo.z));
    *pdf = ggx_visible_pdf(wo, h, s->alpha) / (4.0f * oh);
    return f;
}

/* f |cos(wi)| of a rough dielectric (Walter et al. 2007), its density in *pdf. */
FORCE_INLINE float3 rough_dielectric(const Shading* s, float3 wo, float3 wi, float* pdf) {
    float alpha = s->alpha, eta = s->ior;
    bool reflect = wi.z > 0.0f;
    float etap = reflect ? 1.0f : eta;
    float3 h = wi * etap + wo;
    *pdf = 0.0f;
    if (wi.z == 0.0f || (h.x == 0.0f && h.y == 0.0f && h.z == 0.0f)) return (float3)(0.0f);
    h = normalize(h);
    if (h.z < 0.0f) h = -h;
    float ih = dot(wi, h), oh = dot(wo, h);
    if (ih * wi.z < 0.0f || oh < 0.0f) return (float3)(0.0f);
    float f = fresnel_dielectric(oh, eta);
    float d = ggx_d(h, alpha);
    float g = ggx_g2(wo, wi, alpha);
    float vis = ggx_visible_pdf(wo, h, alpha);
    if (reflect) {
        *pdf = vis / (4.0f * oh) * f;
        return (float3)(f * d * g / (4.0f * wo.z));
    }
    float denom = (ih + oh / etap) * (ih + oh / etap);
    float ft = (1.0f - f) * d * g * fabs(ih * oh / (wo.z * denom)) / (etap * etap);
    *pdf = vis * (fabs(ih) / denom) * (1.0f - f);
    return s->specular * ft;
}

FORCE_INLINE float fresnel_diffuse_reflectance(float eta) {
    if (eta < 1.0f) return -1.4399f * eta * eta + 0.7099f * eta + 0.6681f + 0.0636f / eta;
    float i = 1.0f / eta;
    float i2 = i * i, i3 = i * i * i;
    return 0.919317f - 3.4793f * i + 6.75335f * i2 - 7.80989f * i3 + 4.98554f * i2 * i2 - 1.36881f * i2 * i3;
}

/* The share of the plastic's base that comes out between cosines cos_i and cos_o. */
FORCE_INLINE float plastic_base(const Shading* s, float cos_o, float cos_i) {
    float eta = s->ior;
    float through = (1.0f - fresnel_dielectric(cos_i, eta)) * (1.0f - fresnel_dielectric(cos_o, eta));
    return through / (eta * eta * (1.0f - fresnel_diffuse_reflectance(1.0f / eta)));
}

FORCE_INLINE float coating_share(const Shading* s, float cos_o) {
    float f = fresnel_dielectric(cos_o, s->ior);
    float sp = f * max3(s->specular);
    float d = (1.0f - f) * max3(s->albedo);
    return sp + d > 0.0f ? sp / (sp + d) : 1.0f;
}

/* f cos(wi) over every lobe that is not a delta, the density of sampling wi in *pdf. */
FORCE_INLINE float3 bsdf_eval(const Shading* s, float3 wo, float3 wi, float* pdf) {
    float3 f = (float3)(0.0f);
    *pdf = 0.0f;
    if (wo.z <= 0.0f) return f;
    bool smooth = shading_smooth(s);
    float m = s->metallic;
    float p;
    if (m > 0.0f && !smooth && wi.z > 0.0f) {
        float3 fm = microfacet_reflection(s, FRESNEL_METAL, wo, wi, &p);
        f += fm * m;
        *pdf += p * m;
    }
    float b = 1.0f - m;
    if (b <= 0.0f) return f;
    if (IS_MODEL(s, BSDF_CONDUCTOR)) {
        if (!smooth && wi.z > 0.0f) {
            float3 fc = microfacet_reflection(s, FRESNEL_CONDUCTOR, wo, wi, &p);
            f += fc * b;
            *pdf += p * b;
        }
    } else if (IS_MODEL(s, BSDF_DIELECTRIC)) {
        if (!smooth) {
            float3 fd = rough_dielectric(s, wo, wi, &p);
            f += fd * b;
            *pdf += p * b;
        }
    } else if (IS_MODEL(s, BSDF_PLASTIC)) {
        if (wi.z > 0.0f) {
            float share = coating_share(s, wo.z);
            if (!smooth) {
                float3 fs = microfacet_reflection(s, FRESNEL_COATING, wo, wi, &p);
                f += fs * b;
                *pdf += p * (b * share);
            }
            f += s->albedo * (plastic_base(s, wo.z, wi.z) * wi.z / M_PI_F * b);
            *pdf += wi.z / M_PI_F * (b * (1.0f - share));
        }
    } else if (IS_MODEL(s, BSDF_DIFFUSE)) {
        if (wi.z > 0.0f) {
            f += s->albedo * (wi.z / M_PI_F * b);
            *pdf += wi.z / M_PI_F * b;
        }
    }
    return f;
}

FORCE_INLINE float3 local_cosine(float u1, float u2) {
    float r = sqrt(u1);
    float phi = 2.0f * M_PI_F * u2;
    return (float3)(r * cos(phi), r * sin(phi), sqrt(fmax(1.0f - u1, 0.0f)));
}

FORCE_INLINE bool sample_delta(float3 wi, float3 weight, bool transmitted, BsdfSample* out) {
    out->wi = wi; out->weight = weight; out->pdf = 0.0f;
    out->delta = true; out->transmitted = transmitted;
    return true;
}

/* A direction of a lobe that is not a delta, weighed by every such lobe. */
FORCE_INLINE bool sample_mixed(const Shading* s, float3 wo, float3 wi, BsdfSample* out) {
    float pdf;
    float3 f = bsdf_eval(s, wo, wi, &pdf);
    if (!(pdf > 0.0f)) return false;
    out->wi = wi; out->weight = f / pdf; out->pdf = pdf;
    out->delta = false; out->transmitted = wi.z < 0.0f;
    return true;
}

FORCE_INLINE float3 reflect_about(float3 wo, float3 h) { return h * (2.0f * dot(wo, h)) - wo; }

/* The next bounce's direction: u_lobe picks the lobe, u1 and u2 the direction in it,
 * u_rt reflection or refraction; false where the sample is lost. */
FORCE_INLINE bool bsdf_sample(const Shading* s, float3 wo, float u_lobe, float u1, float u2, float u_rt,
                              BsdfSample* out) {
    if (wo.z <= 0.0f) return false;
    bool smooth = shading_smooth(s);
    float m = s->metallic;
    float3 mirror = (float3)(-wo.x, -wo.y, wo.z);
    float3 wi;
    if (u_lobe < m) {
        if (smooth) return sample_delta(mirror, schlick(s->albedo, wo.z), false, out);
        wi = reflect_about(wo, ggx_visible_normal(wo, s->alpha, u1, u2));
        return wi.z > 0.0f && sample_mixed(s, wo, wi, out);
    }
    float u = (u_lobe - m) / (1.0f - m);
    if (IS_MODEL(s, BSDF_CONDUCTOR)) {
        if (smooth) return sample_delta(mirror, lobe_fresnel(s, FRESNEL_CONDUCTOR, wo.z), false, out);
        wi = reflect_about(wo, ggx_visible_normal(wo, s->alpha, u1, u2));
        return wi.z > 0.0f && sample_mixed(s, wo, wi, out);
    }
    if (IS_MODEL(s, BSDF_DIELECTRIC)) {
        if (smooth) {
            float f = fresnel_dielectric(wo.z, s->ior);
            if (u_rt < f) return sample_delta(mirror, (float3)(1.0f), false, out);
            if (!refract_dir(wo, (float3)(0.0f, 0.0f, 1.0f), s->ior, &wi)) return false;
            return sample_delta(wi, s->specular / (s->ior * s->ior), true, out);
        }
        float3 h = ggx_visible_normal(wo, s->alpha, u1, u2);
        float f = fresnel_dielectric(dot(wo, h), s->ior);
        if (u_rt < f) {
            wi = reflect_about(wo, h);
            if (!(wi.z > 0.0f)) return false;
        } else {
            if (!refract_dir(wo, h, s->ior, &wi) || !(wi.z < 0.0f)) return false;
        }
        return sample_mixed(s, wo, wi, out);
    }
    if (IS_MODEL(s, BSDF_THIN_DIELECTRIC)) {
        float r = fresnel_dielectric(wo.z, s->ior);
        if (r < 1.0f) {
            float t = 1.0f - r;
            r += t * t * r / (1.0f - r * r);
        }
        if (u_rt < r) return sample_delta(mirror, (float3)(1.0f), false, out);
        return sample_delta(-wo, s->specular, true, out);
    }
    if (IS_MODEL(s, BSDF_PLASTIC)) {
        float share = coating_share(s, wo.z);
        if (u < share) {
            if (smooth) {
                float f = fresnel_dielectric(wo.z, s->ior);
                return sample_delta(mirror, s->specular * (f / share), false, out);
            }
            wi = reflect_about(wo, ggx_visible_normal(wo, s->alpha, u1, u2));
            return wi.z > 0.0f && sample_mixed(s, wo, wi, out);
        }
    }
    return sample_mixed(s, wo, local_cosine(u1, u2), out);
}

/* The orthonormal basis about unit n of Duff et al. (JCGT 2017), as cosine_direction
 * builds it. */
FORCE_INLINE void basis(float3 n, float3* t, float3* b) {
    float sign = n.z >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (sign + n.z);
    float c = n.x * n.y * a;
    *t = (float3)(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
    *b = (float3)(c, sign + n.y * n.y * a, -n.y);
}

/* The material of sp's hit as the models read it. */
FORCE_INLINE Shading shading_at(const __global Material* m, const SurfacePoint* sp) {
    Shading s;
    s.bsdf = m->bsdf;
    s.albedo = sp->albedo;
    s.specular = load3(m->specular);
    s.eta = load3(m->eta);
    s.k = load3(m->k);
    s.ior = m->bsdf == BSDF_DIELECTRIC && !sp->front_face ? 1.0f / m->ior : m->ior;
    s.alpha = sp->roughness * sp->roughness;
#ifdef METALLIC
    s.metallic = sp->metallic > 0.0f ? fmin(sp->metallic, 1.0f) : 0.0f; /* NaN as 0 */
#else
    s.metallic = 0.0f;
#endif
    return s;
}
