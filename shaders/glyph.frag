#version 450
// A translucent tool: its colour, lit softly, more opaque at the silhouette so that its
// outline reads against clay of the same colour.
#extension GL_EXT_multiview : require
#include "frame.glsl"

layout(push_constant) uniform Glyph {
    mat4 model;
    vec4 colour;
    vec4 shape;
} glyph;

layout(location = 0) in vec3 world_position;
layout(location = 1) in vec3 world_normal;
layout(location = 0) out vec4 colour;

void main() {
    vec3 n = normalize(world_normal);
    vec3 v = normalize(frame.eyes[gl_ViewIndex].position.xyz - world_position);
    float rim = pow(1.0 - max(dot(n, v), 0.0), 2.0);
    vec3 c = glyph.colour.rgb * (0.35 + 0.65 * irradiance(n) / PI) + direct_light(world_position, n, v, vec3(0.0), 0.6);
    colour = vec4(c + 0.3 * rim, clamp(glyph.colour.a * (0.6 + 0.8 * rim), 0.0, 1.0));
}
