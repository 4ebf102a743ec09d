#version 450
//INCLUDE frame.glsl
layout(set = 0, binding = 3) uniform texture2D g_emission;
layout(set = 0, binding = 4) uniform texture2D accum;
layout(set = 0, binding = 5) uniform sampler nearest;
layout(location = 0) out vec4 o_color;

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 a = texelFetch(sampler2D(accum, nearest), px, 0);
    vec3 e = texelFetch(sampler2D(g_emission, nearest), px, 0).rgb;
    vec3 splatted = a.w > 0.0 ? a.rgb / a.w : vec3(0.0);
    o_color = vec4(frame.params.x * e + frame.params.y * splatted, 1.0);
}
