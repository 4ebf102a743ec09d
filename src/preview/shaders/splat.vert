#version 450
//INCLUDE frame.glsl
// One cut node per instance (src/preview/cut.rs `Splat`).
layout(location = 0) in vec4 sphere;   // centre, footprint radius R
layout(location = 1) in vec4 normal;   // axis; w: 0 no normal, 1 one-sided, 2 two-sided
layout(location = 2) in vec4 radiance; // rgb towards the eye
layout(location = 0) flat out vec4 f_sphere;
layout(location = 1) flat out vec4 f_normal;
layout(location = 2) flat out vec4 f_radiance;

void main() {
    f_sphere = sphere;
    f_normal = normal;
    f_radiance = radiance;
    vec2 corner = vec2((gl_VertexIndex & 1) == 0 ? -1.0 : 1.0,
                       (gl_VertexIndex & 2) == 0 ? -1.0 : 1.0);
    vec3 c = sphere.xyz;
    float r = sphere.w;
    bool perspective = frame.eye.w > 0.5;
    vec3 to = c - frame.eye.xyz;
    float d = length(to);
    if (perspective && d <= 1.01 * r) {
        // The eye is inside the footprint: it covers the whole screen.
        gl_Position = vec4(corner, 0.5, 1.0);
        return;
    }
    // A square facing the eye whose inscribed circle covers the sphere's outline: half
    // side r d / sqrt(d^2 - r^2) at distance d.
    vec3 dir = perspective ? to / d : frame.forward.xyz;
    vec3 u = cross(dir, frame.up.xyz);
    u = dot(u, u) > 1e-12 ? normalize(u) : frame.right.xyz;
    vec3 v = cross(u, dir);
    float s = perspective ? r * d / sqrt(d * d - r * r) : r;
    vec4 clip = frame.view_proj * vec4(c + s * (corner.x * u + corner.y * v), 1.0);
    // Splats are not depth tested: keep every one inside the depth range.
    gl_Position = vec4(clip.xy, 0.5 * clip.w, clip.w);
}
