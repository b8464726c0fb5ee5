#version 450
// The workspace box: the unit cube [0, 1]^3 scaled onto the stage. Its faces are
// counter-clockwise seen from outside, so culling front faces leaves the far walls (seen from
// inside), as in Galyean-Hughes's stage.
#extension GL_EXT_multiview : require
#include "frame.glsl"

layout(push_constant) uniform Stage {
    vec4 min_corner;
    vec4 max_corner;
    vec4 colour;
} stage;

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;

layout(location = 0) out vec3 world_position;
layout(location = 1) flat out int axis;
layout(location = 2) out vec3 inward;

void main() {
    world_position = mix(stage.min_corner.xyz, stage.max_corner.xyz, in_position);
    vec3 a = abs(in_normal);
    axis = a.x > 0.5 ? 0 : (a.y > 0.5 ? 1 : 2);
    inward = -in_normal;
    gl_Position = frame.eyes[gl_ViewIndex].view_proj * vec4(world_position, 1.0);
}
