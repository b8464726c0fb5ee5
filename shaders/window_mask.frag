#version 450
#extension GL_EXT_multiview : require

// Per view: x the strip from the left edge, y from the right edge, fractions of the width.
layout(push_constant) uniform WindowMask {
    vec4 strips[2];
} mask;

layout(location = 0) in float x_ndc;
layout(location = 0) out vec4 colour;

void main() {
    vec2 strip = mask.strips[gl_ViewIndex].xy;
    // Across the picture from 0 (left edge) to 1 (right edge).
    float x = 0.5 * (x_ndc + 1.0);
    if (x >= strip.x && x <= 1.0 - strip.y) {
        discard;
    }
    colour = vec4(0.0, 0.0, 0.0, 1.0);
}
