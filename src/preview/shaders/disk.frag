#version 450
layout(location = 0) in vec2 v_disc;
layout(location = 1) flat in vec4 f_radiance;
layout(location = 0) out vec4 o_accum;

void main() {
    if (dot(v_disc, v_disc) > 1.0) {
        discard;
    }
    o_accum = vec4(f_radiance.rgb, 1.0);
}
