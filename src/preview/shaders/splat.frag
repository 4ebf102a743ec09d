#version 450
//INCLUDE frame.glsl
layout(set = 0, binding = 1) uniform texture2D g_position;
layout(set = 0, binding = 2) uniform texture2D g_normal;
layout(set = 0, binding = 5) uniform sampler nearest;
layout(location = 0) flat in vec4 f_sphere;
layout(location = 1) flat in vec4 f_normal;
layout(location = 2) flat in vec4 f_radiance;
layout(location = 0) out vec4 o_accum;

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 p = texelFetch(sampler2D(g_position, nearest), px, 0);
    if (p.w == 0.0) {
        discard;
    }
    // Outside the footprint the weight is zero whatever the normals (most of the square's
    // fragments): leave before reading the normal.
    float d = distance(p.xyz, f_sphere.xyz) / f_sphere.w;
    if (d >= 1.0) {
        discard;
    }
    vec3 n = texelFetch(sampler2D(g_normal, nearest), px, 0).xyz;
    float c = dot(n, f_normal.xyz);
    c = f_normal.w < 0.5 ? 1.0 : (f_normal.w > 1.5 ? abs(c) : c);
    // Radiance cache splatting's weight (Gautron et al., spec section 9), less its
    // threshold so that it falls to zero at the footprint's rim.
    float den = d + sqrt(max(1.0 - c, 0.0));
    float w = 1.0 / max(den, 1.0 / frame.params.w) - frame.params.z;
    if (!(w > 0.0)) {
        discard;
    }
    o_accum = vec4(w * f_radiance.rgb, w);
}
