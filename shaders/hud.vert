#version 450
// The heads-up display: positions are already Vulkan normalised device coordinates, the same
// for both views, so the text has zero parallax (it sits on the screen plane). The vertex
// carries its opacity in position.z and its linear RGB colour in the normal slot.
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_colour;

layout(location = 0) out vec4 colour;

void main() {
    colour = vec4(in_colour, in_position.z);
    gl_Position = vec4(in_position.xy, 0.0, 1.0);
}
