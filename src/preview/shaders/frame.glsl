// Included by hand into every shader by build.rs (naga's GLSL front end has no #include).
// The per-frame uniforms (std140), written by src/preview/view.rs (`FrameUniforms`).
layout(set = 0, binding = 0) uniform Frame {
    mat4 view_proj;
    // xyz: the eye (perspective) or the viewing direction (orthographic); w: 1 perspective.
    vec4 eye;
    // Unit camera axes, for billboards.
    vec4 right;
    vec4 up;
    vec4 forward;
    // x: how much emission to show, y: how much splatted radiance, z: the splat weight's
    // threshold W_MIN, w: its cap W_MAX.
    vec4 params;
} frame;
