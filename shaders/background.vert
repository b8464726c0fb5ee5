#version 450
// A full-screen triangle (positions in normalised device coordinates); the fragment shader
// looks the environment up along each pixel's ray.
#extension GL_EXT_multiview : require
#include "frame.glsl"

layout(location = 0) in vec3 in_position;

layout(location = 0) out vec3 ray;

void main() {
    Eye eye = frame.eyes[gl_ViewIndex];
    vec4 far_point = eye.inv_view_proj * vec4(in_position.xy, 1.0, 1.0);
    ray = far_point.xyz / far_point.w - eye.position.xyz;
    gl_Position = vec4(in_position.xy, 1.0, 1.0);
}
