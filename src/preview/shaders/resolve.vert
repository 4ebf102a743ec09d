#version 450
// One triangle that covers the screen.
void main() {
    vec2 p = vec2(float((gl_VertexIndex << 1) & 2), float(gl_VertexIndex & 2));
    gl_Position = vec4(2.0 * p - 1.0, 0.0, 1.0);
}
