#version 450
// The heads-up display: positions are already Vulkan normalised device coordinates, the same
// for both views, so the text has zero parallax (it sits on the screen plane). The vertex
// carries its opacity in position.z, its linear RGB colour in the normal slot and, in the
// colour slot's x, the views it is drawn into (bit 0 the left eye, bit 1 the right): an eye's
// mark is moved out of the other view's clip volume.
#extension GL_EXT_multiview : require

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_colour;
layout(location = 2) in vec4 in_views;

layout(location = 0) out vec4 colour;

void main() {
    colour = vec4(in_colour, in_position.z);
    bool drawn = (uint(in_views.x) & (1u << gl_ViewIndex)) != 0u;
    gl_Position = drawn ? vec4(in_position.xy, 0.0, 1.0) : vec4(0.0, 0.0, 2.0, 1.0);
}
