/* punctual.cl: lights without area (point, spot, directional), which only light samples
 * reach. Each is four float4, as src/light/punctual.rs packs them (and mirrors this): the
 * position (or the direction the light travels) and the kind (LIGHT_*); the intensity (or
 * irradiance) and cos cutoff; the spot's axis and cos beam; the cutoff angle and the
 * inverse width of the falloff band (radians: Mitsuba's spot falls linearly in angle).
 * Compiled in only for scenes with such lights (PUNCTUAL). */

#define PUNCTUAL_PARAMS __global const float4* punctual, uint punctual_count

/* For light k and a point x: the irradiance it brings to a surface facing it at x, the
 * unit direction towards it in *l, and its distance (INFINITY for a directional light) in
 * *reach. */
FORCE_INLINE float3 punctual_incident(__global const float4* punctual, uint k, float3 x,
                                      float3* l, float* reach) {
    float4 p = punctual[4 * k], i = punctual[4 * k + 1];
    uint kind = (uint)p.w;
    if (kind == LIGHT_DIRECTIONAL) {
        *l = -p.xyz;
        *reach = INFINITY;
        return i.xyz;
    }
    float3 w = p.xyz - x;
    float d2 = dot(w, w);
    float dist = sqrt(d2);
    float3 dir = w / dist;
    float falloff = 1.0f;
    if (kind == LIGHT_SPOT) {
        float4 a = punctual[4 * k + 2], c = punctual[4 * k + 3];
        float cos_axis = -(dir.x * a.x + dir.y * a.y + dir.z * a.z);
        falloff = cos_axis <= i.w ? 0.0f
                : cos_axis >= a.w ? 1.0f
                : (c.x - acos(fmin(cos_axis, 1.0f))) * c.y;
    }
    *l = dir;
    *reach = dist;
    return i.xyz * (falloff / d2);
}
