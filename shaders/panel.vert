#version 450
#extension GL_EXT_multiview : require
#include "frame.glsl"
// The panels. On the screen plane (`placed.w == 0`) the positions are already Vulkan
// normalised device coordinates, the same for both views, so the panel has zero parallax. On a
// surface in the scene (a headset's panel held in the hand) they are the panel's pixels, which
// `placement` takes to scene metres, seen by each eye through its own view. The normal slot
// carries the texture coordinates; the colour is linear and premultiplied by its alpha.
layout(push_constant) uniform Panel {
    mat4 placement; // panel pixels (x right, y down, z 0) -> scene metres
    vec4 clip;      // the batch's clip rectangle, panel pixels: x0, y0, x1, y1
    vec4 placed;    // w: 1 on a surface in the scene, 0 on the screen plane
} panel;

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_uv;
layout(location = 2) in vec4 in_colour;

layout(location = 0) out vec4 colour;
layout(location = 1) out vec2 uv;
layout(location = 2) out vec2 panel_px;

void main() {
    colour = in_colour;
    uv = in_uv.xy;
    panel_px = in_position.xy;
    if (panel.placed.w != 0.0) {
        gl_Position = frame.eyes[gl_ViewIndex].view_proj * (panel.placement * vec4(in_position.xy, 0.0, 1.0));
    } else {
        gl_Position = vec4(in_position.xy, 0.0, 1.0);
    }
}
