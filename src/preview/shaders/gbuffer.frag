#version 450
//INCLUDE frame.glsl
// Emitted radiance of the mesh drawn, from its front and from its back face.
layout(push_constant) uniform Mesh {
    vec4 front;
    vec4 back;
} mesh;
layout(location = 0) in vec3 v_position;
layout(location = 0) out vec4 o_position;
layout(location = 1) out vec4 o_normal;
layout(location = 2) out vec4 o_emission;

void main() {
    // The geometric normal, as surfels have it: the plane of the triangle from the
    // position's derivatives, turned to its front face (counter-clockwise, as glTF's).
    vec3 n = normalize(cross(dFdx(v_position), dFdy(v_position)));
    vec3 to_eye = frame.eye.w > 0.5 ? frame.eye.xyz - v_position : -frame.forward.xyz;
    if (dot(n, to_eye) < 0.0) {
        n = -n;
    }
    if (!gl_FrontFacing) {
        n = -n;
    }
    o_position = vec4(v_position, 1.0);
    o_normal = vec4(n, 0.0);
    o_emission = vec4(gl_FrontFacing ? mesh.front.rgb : mesh.back.rgb, 1.0);
}
