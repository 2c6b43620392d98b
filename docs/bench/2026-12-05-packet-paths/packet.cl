/* EXPERIMENT: sample_path with 8 paths per work-item (8 pixels of a row), the shading's
 * arithmetic in float8 across them; traversal, surface points and the emitter pick per
 * lane. Lambert and conductor models only; emitters with MIS; no textures or metallic. */
#define NL 8
typedef float8 F8;
typedef int8 I8;
typedef struct { F8 x, y, z; } V3;
#define V(a, b, c) ((V3){(a), (b), (c)})
FORCE_INLINE V3 vadd(V3 a, V3 b) { return V(a.x + b.x, a.y + b.y, a.z + b.z); }
FORCE_INLINE V3 vsub(V3 a, V3 b) { return V(a.x - b.x, a.y - b.y, a.z - b.z); }
FORCE_INLINE V3 vmul(V3 a, V3 b) { return V(a.x * b.x, a.y * b.y, a.z * b.z); }
FORCE_INLINE V3 vsc(V3 a, F8 s) { return V(a.x * s, a.y * s, a.z * s); }
FORCE_INLINE V3 vneg(V3 a) { return V(-a.x, -a.y, -a.z); }
FORCE_INLINE F8 vdot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
FORCE_INLINE V3 vnorm(V3 a) { F8 l = sqrt(vdot(a, a)); return V(a.x / l, a.y / l, a.z / l); }
FORCE_INLINE V3 vsel(V3 a, V3 b, I8 m) { return V(select(a.x, b.x, m), select(a.y, b.y, m), select(a.z, b.z, m)); }
FORCE_INLINE V3 vsplat(float s) { return V((F8)(s), (F8)(s), (F8)(s)); }
FORCE_INLINE V3 vcross(V3 a, V3 b) { return V(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x); }
FORCE_INLINE F8 vmax3(V3 a) { return fmax(fmax(a.x, a.y), a.z); }
/* Arrays of a lane's components, in and out of registers. */
#define LD(a) vload8(0, a)
#define LD3(a) V(vload8(0, a[0]), vload8(0, a[1]), vload8(0, a[2]))
#define ST(v, a) vstore8(v, 0, a)
#define ST3(v, a) { vstore8((v).x, 0, a[0]); vstore8((v).y, 0, a[1]); vstore8((v).z, 0, a[2]); }
#define PUT3(a, l, v) { a[0][l] = (v).x; a[1][l] = (v).y; a[2][l] = (v).z; }
#define GET3(a, l) ((float3)(a[0][l], a[1][l], a[2][l]))

FORCE_INLINE F8 s1d8(uint8 key, uint8 dim) {
    uint8 x = key ^ (dim * 0x85ebca6bu);
    x ^= x >> 16; x *= 0x7feb352du;
    x ^= x >> 15; x *= 0x846ca68bu;
    x ^= x >> 16;
    return convert_float8(x >> 8) * (1.0f / 16777216.0f);
}

FORCE_INLINE V3 fresnel_conductor8(F8 c, V3 eta, V3 k) {
    c = clamp(c, 0.0f, 1.0f);
    F8 c2 = c * c, s2 = 1.0f - c2;
    V3 r;
#define FC(X) { F8 t0 = eta.X * eta.X - k.X * k.X - s2;                         \
        F8 a2b2 = sqrt(fmax(t0 * t0 + eta.X * eta.X * k.X * k.X * 4.0f, 0.0f)); \
        F8 t1 = a2b2 + c2; F8 a = sqrt(fmax((a2b2 + t0) * 0.5f, 0.0f));          \
        F8 t2 = a * (2.0f * c); F8 rs = (t1 - t2) / fmax(t1 + t2, 1e-12f);       \
        F8 t3 = a2b2 * c2 + s2 * s2; F8 t4 = t2 * s2;                            \
        F8 rp = rs * (t3 - t4) / fmax(t3 + t4, 1e-12f); r.X = (rp + rs) * 0.5f; }
    FC(x) FC(y) FC(z)
#undef FC
    return r;
}
FORCE_INLINE F8 ggx_d8(F8 hz, F8 alpha) {
    F8 a2 = alpha * alpha; F8 d = hz * hz * (a2 - 1.0f) + 1.0f;
    return a2 / (M_PI_F * d * d);
}
FORCE_INLINE F8 ggx_lambda8(F8 wz, F8 alpha) {
    F8 c2 = wz * wz;
    F8 t2 = fmax(1.0f - c2, 0.0f) / c2;
    return select(0.5f * (-1.0f + sqrt(1.0f + alpha * alpha * t2)), (F8)(INFINITY), c2 <= 0.0f);
}
/* Conductor lobe: f cos and pdf (microfacet_reflection, FRESNEL_CONDUCTOR). */
FORCE_INLINE V3 conductor_eval8(V3 spec, V3 albedo, V3 eta, V3 k, F8 alpha, V3 wo, V3 wi, F8* pdf) {
    V3 h = vadd(wo, wi);
    I8 zero = (wi.z <= 0.0f) | ((h.x == 0.0f) & (h.y == 0.0f) & (h.z == 0.0f)) | (wo.z <= 0.0f);
    h = vnorm(h);
    F8 oh = vdot(wo, h);
    zero |= oh <= 0.0f;
    F8 d = ggx_d8(h.z, alpha);
    V3 fr = vmul(fresnel_conductor8(oh, eta, k), spec);
    F8 m = clamp(1.0f - oh, 0.0f, 1.0f), m5 = m * m * m * m * m;
    V3 f0 = vmul(albedo, spec);
    V3 sch = V(f0.x + (1.0f - f0.x) * m5, f0.y + (1.0f - f0.y) * m5, f0.z + (1.0f - f0.z) * m5);
    fr = vsel(sch, fr, eta.x > 0.0f);
    F8 lo = ggx_lambda8(wo.z, alpha);
    F8 g2 = 1.0f / (1.0f + lo + ggx_lambda8(wi.z, alpha));
    V3 f = vsc(fr, d * g2 / (4.0f * wo.z));
    F8 vis = (1.0f / (1.0f + lo)) * fmax(oh, 0.0f) * d / wo.z;
    *pdf = select(vis / (4.0f * oh), (F8)(0.0f), zero);
    return vsel(f, vsplat(0.0f), zero);
}
FORCE_INLINE V3 ggx_visible_normal8(V3 wo, F8 alpha, F8 u1, F8 u2) {
    V3 vh = vnorm(V(alpha * wo.x, alpha * wo.y, wo.z));
    F8 len2 = vh.x * vh.x + vh.y * vh.y;
    F8 il = 1.0f / sqrt(len2);
    I8 pos = len2 > 0.0f;
    V3 t1 = V(select((F8)(1.0f), -vh.y * il, pos), select((F8)(0.0f), vh.x * il, pos), (F8)(0.0f));
    V3 t2 = vcross(vh, t1);
    F8 r = sqrt(u1), phi = 2.0f * M_PI_F * u2;
    F8 p1 = r * cos(phi);
    F8 s = 0.5f * (1.0f + vh.z);
    F8 p2 = (1.0f - s) * sqrt(fmax(1.0f - p1 * p1, 0.0f)) + s * (r * sin(phi));
    V3 nh = vadd(vadd(vsc(t1, p1), vsc(t2, p2)), vsc(vh, sqrt(fmax(1.0f - p1 * p1 - p2 * p2, 0.0f))));
    return vnorm(V(alpha * nh.x, alpha * nh.y, fmax(nh.z, 0.0f)));
}

#define BW 8
#define BH 8
/* The next job of the block's pixels x samples for lane l: false when none is left. */
#define NEXT_JOB(l)                                                               \
    {                                                                             \
        alive[l] = false;                                                         \
        while (next_job < BW * BH * sample_count) {                               \
            uint j_ = next_job++;                                                 \
            uint px_ = bx + (j_ % (BW * BH)) % BW, py_ = by + (j_ % (BW * BH)) / BW; \
            if (px_ < col0 || px_ >= col_end || py_ < row0 || py_ >= row_end) continue; \
            lx[l] = px_; ly[l] = py_;                                             \
            key[l] = sampler_key(seed, py_ * width + px_, sample + j_ / (BW * BH)); \
            float3 o_;                                                            \
            float3 d_ = jittered_ray(CAMERA, px_, py_, key[l], &o_);              \
            PUT3(org, l, o_); PUT3(dir, l, d_);                                   \
            PUT3(rad, l, (float3)(0.0f)); PUT3(thr, l, (float3)(1.0f));           \
            count[l] = 1; cone[l] = 0.0f; lpdf[l] = 0.0f; bounce[l] = 0;          \
            alive[l] = true;                                                      \
            break;                                                                \
        }                                                                         \
    }

KERNEL void sample_path(SAMPLE_PARAMS) {
    uint gx = get_global_id(0), gy = get_global_id(1);
    uint ox = get_global_offset(0), oy = get_global_offset(1);
    if ((gx - ox) % BW != 0u || (gy - oy) % BH != 0u) return;
    uint bx = gx, by = gy;
    uint next_job = 0;
    /* Path state, lane by lane. */
    float org[3][NL], dir[3][NL], rad[3][NL], thr[3][NL], cone[NL], lpdf[NL];
    uint bounce[NL], count[NL], key[NL], lx[NL], ly[NL];
    bool alive[NL];
    /* The vertex's scalar part, lane by lane. */
    float sp_o[3][NL], sp_th[3][NL], sp_ng[3][NL], sp_ns[3][NL], sp_alb[3][NL], sp_em[3][NL];
    float m_spec[3][NL], m_eta[3][NL], m_k[3][NL], m_alpha[NL], m_lam[NL], tt[NL], edens[NL];
    float e_q[3][NL], e_n[3][NL], e_le[3][NL], e_dens[NL];
    int shade[NL], has_e[NL];
    for (uint l = 0; l < NL; ++l) NEXT_JOB(l)
    for (;;) {
        bool live = false;
        for (uint l = 0; l < NL; ++l) {
            shade[l] = 0; has_e[l] = 0;
            if (!alive[l]) continue;
            live = true;
            float t;
            float3 o = GET3(org, l), d = GET3(dir, l);
            uint hit = trace(SCENE, o, d, INFINITY, false, true, &t);
            if (hit == MISS) {
                if (emitter_count == 0) {
                    float3 r = GET3(rad, l) + GET3(thr, l) * sky(d);
                    PUT3(rad, l, r);
                }
                continue;
            }
            const __global Triangle* tri = &tris[hit];
            cone[l] = bounce[l] == 0 ? camera_cone(du, t) : cone[l] + BOUNCE_CONE_SPREAD * t;
            SurfacePoint sp = surface_point(SURFACE, tri, o, d, t, offset, cone[l]);
            const __global Material* m = &materials[tri->material];
            PUT3(sp_o, l, sp.origin); PUT3(sp_th, l, sp.through); PUT3(sp_ng, l, sp.ng); PUT3(sp_ns, l, sp.ns);
            PUT3(sp_alb, l, sp.albedo); PUT3(sp_em, l, sp.emission);
            PUT3(m_spec, l, load3(m->specular)); PUT3(m_eta, l, load3(m->eta)); PUT3(m_k, l, load3(m->k));
            m_alpha[l] = sp.roughness * sp.roughness;
            m_lam[l] = m->bsdf == BSDF_DIFFUSE ? 1.0f : 0.0f;
            tt[l] = t;
            edens[l] = emitter_density(materials, tri, emitter_power);
            shade[l] = 1;
            if (emitter_count > 0) {
                uint dd = bounce_dim(bounce[l]);
                const __global Triangle* e = &tris[emitters[cdf_find(emitter_cdf, emitter_count, sample_1d(key[l], dd))]];
                float u1 = sample_1d(key[l], dd + 1), u2 = sample_1d(key[l], dd + 2);
                float3 q = triangle_point(load3(e->v0), load3(e->v1), load3(e->v2), u1, u2);
                float3 l3 = normalize(q - sp.origin);
                PUT3(e_q, l, q);
                PUT3(e_n, l, emitting_normal(e, l3));
                float su = sqrt(u1);
                PUT3(e_le, l, emitted(SURFACE, e, 1.0f - su, u2 * su));
                e_dens[l] = emitter_density(materials, e, emitter_power);
                has_e[l] = 1;
            }
        }
        if (!live) break;
        /* The vertex's arithmetic, 8 lanes at once. */
        I8 sh = vload8(0, shade) != 0;
        V3 d = LD3(dir), tp = LD3(thr), r = LD3(rad);
        V3 ng = LD3(sp_ng), n = LD3(sp_ns), em = LD3(sp_em), origin = LD3(sp_o);
        F8 t = LD(tt), lp = LD(lpdf);
        uint8 b = vload8(0, bounce), k8 = vload8(0, key);
        I8 going = sh;
        /* Emission found, weighed against light sampling. */
        F8 rr = t * t * LD(edens) / fabs(vdot(ng, d)) / lp;
        F8 wem = select(1.0f / (1.0f + rr * rr), (F8)(1.0f), lp == 0.0f);
        r = vsel(r, vadd(r, vsc(vmul(tp, em), wem)), sh & ((lp > 0.0f & vmax3(em) > 0.0f) | (lp == 0.0f)));
        going &= as_int8(b) <= (int)max_bounces;
        I8 lam = LD(m_lam) > 0.0f;
        V3 albedo = LD3(sp_alb), spec = LD3(m_spec), eta = LD3(m_eta), kk = LD3(m_k);
        F8 alpha = LD(m_alpha);
        I8 smooth = alpha < SMOOTH_ROUGHNESS * SMOOTH_ROUGHNESS;
        /* basis */
        F8 sign = select((F8)(-1.0f), (F8)(1.0f), n.z >= 0.0f);
        F8 ba = -1.0f / (sign + n.z), bc = n.x * n.y * ba;
        V3 tn = V(1.0f + sign * n.x * n.x * ba, sign * bc, -sign * n.x);
        V3 bn = V(bc, sign + n.y * n.y * ba, -n.y);
        V3 wo = vneg(vnorm(d));
        V3 wol = V(vdot(wo, tn), vdot(wo, bn), vdot(wo, n));
        uint8 dd = 2u + b * DIMS_PER_BOUNCE;
        I8 lit = lam | ~smooth;
        /* Light sample. */
        V3 q = LD3(e_q);
        V3 w = vsub(q, origin);
        F8 d2 = vdot(w, w);
        V3 l = vsc(w, 1.0f / sqrt(d2));
        F8 cos_there = vdot(LD3(e_n), vneg(l));
        I8 ok = going & (vload8(0, has_e) != 0) & lit & (cos_there > 0.0f) & (vdot(l, ng) > 0.0f);
        F8 pdf_l = 0.0f;
        V3 fl = vsplat(0.0f);
#ifdef BSDFS
        bool any_c = any(sh & ~lam);
        if (any_c) fl = conductor_eval8(spec, albedo, eta, kk, alpha, wol, V(vdot(l, tn), vdot(l, bn), vdot(l, n)), &pdf_l);
#endif
        F8 cos_here = fmax(vdot(n, l), 0.0f);
        fl = vsel(fl, vsc(albedo, cos_here / M_PI_F), lam);
        pdf_l = select(pdf_l, cos_here / M_PI_F, lam);
        ok &= vmax3(fl) > 0.0f;
        F8 light_pdf = d2 * LD(e_dens) / cos_there;
        F8 ratio = pdf_l / light_pdf;
        F8 weight = 1.0f / (1.0f + ratio * ratio);
        V3 sl = vmul(vmul(tp, fl), vsc(LD3(e_le), weight / light_pdf));
        F8 reach = sqrt(d2) * (1.0f - 1e-4f);
        /* Next direction. */
        F8 u1 = s1d8(k8, dd + 4u), u2 = s1d8(k8, dd + 5u);
        F8 cr = sqrt(u1), phi = 2.0f * M_PI_F * u2;
        F8 cx = cr * cos(phi), cy = cr * sin(phi), cz = sqrt(fmax(1.0f - u1, 0.0f));
        V3 wi_lam = vadd(vadd(vsc(tn, cx), vsc(bn, cy)), vsc(n, cz));
        V3 wic = vsplat(0.0f), wc = vsplat(0.0f);
        I8 c_ok = (I8)(0);
        F8 pdf_next = 0.0f;
#ifdef BSDFS
        if (any_c) {
        V3 hv = ggx_visible_normal8(wol, alpha, u1, u2);
        V3 wil = vsub(vsc(hv, 2.0f * vdot(wol, hv)), wol);
        F8 pdf_c;
        V3 fc = conductor_eval8(spec, albedo, eta, kk, alpha, wol, wil, &pdf_c);
        c_ok = (wol.z > 0.0f) & (wil.z > 0.0f) & (pdf_c > 0.0f);
        wc = vsc(fc, 1.0f / pdf_c);
        /* smooth conductor: a mirror */
        V3 fm = vmul(fresnel_conductor8(wol.z, eta, kk), spec);
        F8 mm = clamp(1.0f - wol.z, 0.0f, 1.0f), m5 = mm * mm * mm * mm * mm;
        V3 f0 = vmul(albedo, spec);
        fm = vsel(V(f0.x + (1.0f - f0.x) * m5, f0.y + (1.0f - f0.y) * m5, f0.z + (1.0f - f0.z) * m5), fm, eta.x > 0.0f);
        wil = vsel(wil, V(-wol.x, -wol.y, wol.z), smooth);
        wc = vsel(wc, fm, smooth);
        c_ok = select(c_ok, wol.z > 0.0f, smooth);
        pdf_next = select(pdf_c, (F8)(0.0f), smooth);
        wic = vadd(vadd(vsc(tn, wil.x), vsc(bn, wil.y)), vsc(n, wil.z));
        }
#endif
        V3 wi = vsel(wic, wi_lam, lam);
        V3 bw = vsel(wc, albedo, lam);
        F8 pdf_lam = fmax(vdot(wi_lam, n), 0.0f) / M_PI_F;
        pdf_next = select(pdf_next, pdf_lam, lam);
        going &= lam | c_ok;
        tp = vmul(tp, bw);
        F8 keep = fmin(vmax3(tp), 0.95f);
        I8 roul = as_int8(b) >= (int)ROULETTE_AFTER;
        going &= ~roul | (s1d8(k8, dd + 3u) < keep);
        tp = vsel(tp, vsc(tp, 1.0f / keep), roul);
        going &= vdot(wi, ng) > 0.0f;
        ST3(r, rad); ST3(tp, thr); ST3(wi, dir); ST3(origin, org);
        ST(select(pdf_next, (F8)(0.0f), ~lam & smooth), lpdf);
        int go[NL], shadow[NL];
        vstore8(going, 0, go);
        vstore8(ok, 0, shadow);
        float slr[3][NL], ldir[3][NL], reach_a[NL];
        ST3(sl, slr); ST3(l, ldir); ST(reach, reach_a);
        for (uint j = 0; j < NL; ++j) {
            if (!alive[j]) continue;
            if (shade[j] && shadow[j]) {
                count[j] += 1;
                if (!occluded(SCENE, GET3(sp_o, j), GET3(ldir, j), reach_a[j])) {
                    rad[0][j] += slr[0][j]; rad[1][j] += slr[1][j]; rad[2][j] += slr[2][j];
                }
            }
            if (shade[j] && go[j]) {
                count[j] += 1;
                bounce[j] += 1;
                continue;
            }
            /* The path ends. */
            uint i = (ly[j] - row0) * accum_pitch + (lx[j] - col0);
            accum[i] += (long4)(fixed3(GET3(rad, j)), 0);
            rays[i] += count[j];
            NEXT_JOB(j)
        }
    }
    for (uint py = by; py < by + BH; ++py)
        for (uint px = bx; px < bx + BW; ++px)
            if (px >= col0 && px < col_end && py >= row0 && py < row_end)
                accum[(py - row0) * accum_pitch + (px - col0)] += (long4)(0, 0, 0, (long)sample_count);
}
