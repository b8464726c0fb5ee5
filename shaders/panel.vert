#version 450
// The panels: positions are already Vulkan normalised device coordinates, the same for both
// views, so the panel has zero parallax (it sits on the screen plane). The normal slot carries
// the texture coordinates; the colour is linear and premultiplied by its alpha.
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_uv;
layout(location = 2) in vec4 in_colour;

layout(location = 0) out vec4 colour;
layout(location = 1) out vec2 uv;

void main() {
    colour = in_colour;
    uv = in_uv.xy;
    gl_Position = vec4(in_position.xy, 0.0, 1.0);
}
