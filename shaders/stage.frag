#version 450
// Stage walls: lit like matte clay, with an anti-aliased grid and the tools' crosshairs (the
// lines through each tool's projection onto the wall), which show where a tool is in depth.
#extension GL_EXT_multiview : require
#include "frame.glsl"

layout(push_constant) uniform Stage {
    vec4 min_corner;
    vec4 max_corner;
    vec4 colour;
} stage;

layout(location = 0) in vec3 world_position;
layout(location = 1) flat in int axis;
layout(location = 2) in vec3 inward;
layout(location = 0) out vec4 colour;

// Coverage of a line of `width` pixels at distance `d` (world units) with `w` world units per pixel.
float line(float d, float w, float width) {
    return 1.0 - smoothstep(0.5 * width - 0.5, 0.5 * width + 0.5, abs(d) / max(w, 1e-9));
}

void main() {
    vec3 p = world_position;
    vec3 n = normalize(inward);
    vec3 v = normalize(frame.eyes[gl_ViewIndex].position.xyz - p);
    vec3 albedo = stage.colour.rgb;
    vec3 c = direct_light(p, n, v, albedo, 0.0) + frame.material.w * albedo * irradiance(n) / PI;
    vec3 w = fwidth(p);
    float spacing = frame.params.w;
    float grid = 0.0;
    float cross_ = 0.0;
    for (int k = 0; k < 3; ++k) {
        if (k == axis) {
            continue;
        }
        if (spacing > 0.0) {
            float g = p[k] / spacing;
            grid = max(grid, line((g - round(g)) * spacing, w[k], 1.0));
        }
        for (int t = 0; t < MAX_TOOLS; ++t) {
            if (t < int(frame.params.z)) {
                cross_ = max(cross_, line(p[k] - frame.tools[t][k], w[k], 1.25));
            }
        }
    }
    c = mix(c, c * 1.6 + 0.01, 0.5 * grid);
    c = mix(c, vec3(0.9, 0.85, 0.3), 0.6 * cross_);
    colour = vec4(c, 1.0);
}
