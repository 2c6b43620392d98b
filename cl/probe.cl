/* probe.cl: reports how this device's compiler lays out the shared structs and sees the
 * constants the host writes in front of every program, so that tests/layout.rs can compare
 * them with the Rust side, and the camera rays the kernels trace (tests/camera.rs). Its
 * program is common.cl, texture.cl, nodes.cl (every struct), camera.cl, sampling.cl and
 * this. */

#define OFFSET(type, field) ((uint)((const char*)&probe_##type.field - (const char*)&probe_##type))

__kernel void probe_layout(__global uint* out) {
    Triangle probe_Triangle;
    Bin32Node probe_Bin32Node;
    Hit probe_Hit;
    Material probe_Material;
    TextureInfo probe_TextureInfo;
    Bin64Node probe_Bin64Node;
    Wide4Node probe_Wide4Node;
    Wide8Node probe_Wide8Node;
    CwbvhNode probe_CwbvhNode;
    uint i = 0;
    out[i++] = sizeof(Triangle);
    out[i++] = OFFSET(Triangle, v0);
    out[i++] = OFFSET(Triangle, prim);
    out[i++] = OFFSET(Triangle, v1);
    out[i++] = OFFSET(Triangle, material);
    out[i++] = OFFSET(Triangle, v2);
    out[i++] = sizeof(Bin32Node);
    out[i++] = OFFSET(Bin32Node, min);
    out[i++] = OFFSET(Bin32Node, left_or_first);
    out[i++] = OFFSET(Bin32Node, max);
    out[i++] = OFFSET(Bin32Node, right_or_count);
    out[i++] = sizeof(Hit);
    out[i++] = OFFSET(Hit, prim);
    out[i++] = OFFSET(Hit, t);
    out[i++] = sizeof(Material);
    out[i++] = OFFSET(Material, albedo);
    out[i++] = OFFSET(Material, base_texture);
    out[i++] = OFFSET(Material, emission);
    out[i++] = OFFSET(Material, emission_texture);
    out[i++] = OFFSET(Material, metallic);
    out[i++] = OFFSET(Material, normal_texture);
    out[i++] = OFFSET(Material, normal_scale);
    out[i++] = OFFSET(Material, alpha_texture);
    out[i++] = OFFSET(Material, alpha_cutoff);
    out[i++] = OFFSET(Material, occlusion_texture);
    out[i++] = OFFSET(Material, specular);
    out[i++] = OFFSET(Material, bsdf);
    out[i++] = OFFSET(Material, eta);
    out[i++] = OFFSET(Material, ior);
    out[i++] = OFFSET(Material, k);
    out[i++] = OFFSET(Material, reserved);
    out[i++] = sizeof(TextureInfo);
    out[i++] = OFFSET(TextureInfo, levels);
    out[i++] = OFFSET(TextureInfo, wrap_v);
    out[i++] = sizeof(Bin64Node);
    out[i++] = OFFSET(Bin64Node, right_xy);
    out[i++] = OFFSET(Bin64Node, z);
    out[i++] = OFFSET(Bin64Node, refs);
    out[i++] = sizeof(Wide4Node);
    out[i++] = OFFSET(Wide4Node, max_z);
    out[i++] = OFFSET(Wide4Node, child);
    out[i++] = OFFSET(Wide4Node, count);
    out[i++] = sizeof(Wide8Node);
    out[i++] = OFFSET(Wide8Node, max_z);
    out[i++] = OFFSET(Wide8Node, child);
    out[i++] = OFFSET(Wide8Node, count);
    out[i++] = sizeof(CwbvhNode);
    out[i++] = OFFSET(CwbvhNode, exponent);
    out[i++] = OFFSET(CwbvhNode, inner_mask);
    out[i++] = OFFSET(CwbvhNode, child_base);
    out[i++] = OFFSET(CwbvhNode, triangle_base);
    out[i++] = OFFSET(CwbvhNode, meta);
    out[i++] = OFFSET(CwbvhNode, lo_x);
    out[i++] = OFFSET(CwbvhNode, hi_x);
    out[i++] = OFFSET(CwbvhNode, hi_z);
}

/* The constants the host defines in front of every program, in the order tests/layout.rs
 * lists them: integers as uint, floats by their bits. */
__kernel void probe_constants(__global uint* out) {
    uint i = 0;
    out[i++] = MISS;
    out[i++] = LEAF_FLAG;
    out[i++] = EMPTY_SLOT;
    out[i++] = STATUS_STACK_OVERFLOW;
    out[i++] = (uint)SHADE_NORMAL;
    out[i++] = (uint)SHADE_DEPTH;
    out[i++] = (uint)SHADE_LAMBERT;
    out[i++] = DIMS_PER_BOUNCE;
    out[i++] = LENS_DIM;
    out[i++] = LENS_TRIES;
    out[i++] = as_uint(SHADOW_AMBIENT);
    out[i++] = ROULETTE_AFTER;
    out[i++] = as_uint(RADIANCE_SCALE);
    out[i++] = as_uint(MAX_SAMPLE_RADIANCE);
    out[i++] = as_uint(ROBUST_EXIT);
    out[i++] = (uint)NO_TEXTURE;
    out[i++] = WRAP_REPEAT;
    out[i++] = WRAP_CLAMP;
    out[i++] = WRAP_MIRROR;
    out[i++] = SURFACE_NORMALS;
    out[i++] = SURFACE_UVS;
    out[i++] = SURFACE_COLORS;
    out[i++] = TRIANGLE_MASKED;
    out[i++] = TRIANGLE_TWO_SIDED;
    out[i++] = as_uint(BOUNCE_CONE_SPREAD);
    out[i++] = as_uint(SMOOTH_ROUGHNESS);
    out[i++] = BSDF_DIFFUSE;
    out[i++] = BSDF_CONDUCTOR;
    out[i++] = BSDF_DIELECTRIC;
    out[i++] = BSDF_THIN_DIELECTRIC;
    out[i++] = BSDF_PLASTIC;
    out[i++] = LIGHT_DIRECTIONAL;
    out[i++] = LIGHT_POINT;
    out[i++] = LIGHT_SPOT;
}

/* The camera rays of every pixel of a width x height image, for tests/camera.rs: the camera
 * (Pinhole's seven float4, src/camera.rs) in cam; for pixel i, out[4i] and out[4i + 1] are
 * the origin and direction of its primary ray (camera_ray, as trace_primary traces it),
 * out[4i + 2] and out[4i + 3] those of the ray of sample `sample` (jittered_ray, as the
 * progressive modes trace it). */
__kernel void probe_camera_rays(__global const float4* cam, uint width, uint height,
                                uint seed, uint sample, __global float4* out) {
    uint x = get_global_id(0), y = get_global_id(1);
    if (x >= width || y >= height) return;
    float4 eye = cam[0], p0 = cam[1], du = cam[2], dv = cam[3];
    float4 forward = cam[4], lens_u = cam[5], lens_v = cam[6];
    uint i = 4 * (y * width + x);
    float3 org;
    float3 dir = camera_ray(CAMERA, x, y, &org);
    out[i] = (float4)(org, 0.0f);
    out[i + 1] = (float4)(dir, 0.0f);
    dir = jittered_ray(CAMERA, x, y, sampler_key(seed, y * width + x, sample), &org);
    out[i + 2] = (float4)(org, 0.0f);
    out[i + 3] = (float4)(dir, 0.0f);
}
