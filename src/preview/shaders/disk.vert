#version 450
//INCLUDE frame.glsl
// One surfel per instance: its disc in its own plane (src/preview/cut.rs `Splat`).
layout(location = 0) in vec4 sphere;   // centre, disc radius
layout(location = 1) in vec4 normal;
layout(location = 2) in vec4 radiance;
layout(location = 0) out vec2 v_disc;
layout(location = 1) flat out vec4 f_radiance;

void main() {
    vec2 corner = vec2((gl_VertexIndex & 1) == 0 ? -1.0 : 1.0,
                       (gl_VertexIndex & 2) == 0 ? -1.0 : 1.0);
    // An orthonormal basis around the normal (Duff et al. 2017).
    vec3 n = normal.xyz;
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float b = n.x * n.y * a;
    vec3 t = vec3(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    vec3 bt = vec3(b, s + n.y * n.y * a, -n.y);
    v_disc = corner;
    f_radiance = radiance;
    gl_Position = frame.view_proj * vec4(sphere.xyz + sphere.w * (corner.x * t + corner.y * bt), 1.0);
}
