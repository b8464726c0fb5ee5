#version 450
#extension GL_EXT_multiview : require
#include "frame.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec4 in_colour;

layout(location = 0) out vec3 world_position;
layout(location = 1) out vec3 world_normal;
layout(location = 2) out vec4 albedo;

void main() {
    world_position = in_position;
    world_normal = in_normal;
    albedo = in_colour;
    gl_Position = frame.eyes[gl_ViewIndex].view_proj * vec4(in_position, 1.0);
}
