#version 450
//INCLUDE frame.glsl
layout(location = 0) in vec3 position;
layout(location = 0) out vec3 v_position;

void main() {
    v_position = position;
    gl_Position = frame.view_proj * vec4(position, 1.0);
}
