#version 450
// The panel's texel (sRGB, so sampled linear, premultiplied) tinted by the vertex colour;
// blended premultiplied over the scene.
layout(set = 1, binding = 0) uniform sampler2D panel_texture;

layout(location = 0) in vec4 colour;
layout(location = 1) in vec2 uv;
layout(location = 0) out vec4 out_colour;

void main() {
    out_colour = colour * texture(panel_texture, uv);
}
