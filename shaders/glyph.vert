#version 450
#extension GL_EXT_multiview : require
#include "frame.glsl"

layout(push_constant) uniform Glyph {
    mat4 model;   // unit shape -> world
    vec4 colour;  // linear rgb, a = opacity
    vec4 shape;   // x: tube radius of a torus (0 for the other shapes)
} glyph;

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;

layout(location = 0) out vec3 world_position;
layout(location = 1) out vec3 world_normal;

void main() {
    // The torus mesh is its spine (the unit ring) with normals across the tube: moving each
    // vertex along its normal by the tube radius makes the torus of any ratio; other shapes
    // move by 0.
    vec4 p = glyph.model * vec4(in_position + glyph.shape.x * in_normal, 1.0);
    world_position = p.xyz;
    world_normal = transpose(inverse(mat3(glyph.model))) * in_normal;
    gl_Position = frame.eyes[gl_ViewIndex].view_proj * p;
}
