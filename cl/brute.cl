/* brute.cl: the thesis's GPU brute force. Every pixel's ray is tested against every
 * triangle; the closest hit wins, the first in file order on a tie. */
#include "cltrace.h"

__kernel void trace_brute(__global const Triangle* tris, uint tri_count,
                          float4 eye, float4 p0, float4 du, float4 dv,
                          uint width, uint row0, uint row_end,
                          int shade, float near, float far,
                          __global Hit* hits, uint hit_pitch,
                          __global uint* colors, uint color_pitch) {
    uint x = get_global_id(0), y = get_global_id(1);
    if (x >= width || y < row0 || y >= row_end) return;
    float3 dir = camera_ray(p0, du, dv, x, y);
    WatertightRay ray = watertight_ray(eye.xyz, dir);
    float t = INFINITY;
    uint best = MISS;
    for (uint i = 0; i < tri_count; ++i) {
        float h = intersect_stored(&ray, &tris[i], t);
        if (h >= 0.0f) { t = h; best = i; }
    }
    store_pixel(hits, hit_pitch, colors, color_pitch, x, y - row0, best, t, dir, tris, shade, near, far);
}
