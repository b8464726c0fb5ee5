#version 450
// The panel's texel (sRGB, so sampled linear, premultiplied) tinted by the vertex colour;
// blended premultiplied over the scene. A panel on a surface in the scene is clipped here to
// its batch's rectangle (a scissor cannot follow the surface); one on the screen plane is
// clipped by the scissor, its rectangle here spanning everything.
layout(set = 1, binding = 0) uniform sampler2D panel_texture;

layout(push_constant) uniform Panel {
    mat4 placement;
    vec4 clip;
    vec4 placed;
} panel;

layout(location = 0) in vec4 colour;
layout(location = 1) in vec2 uv;
layout(location = 2) in vec2 panel_px;
layout(location = 0) out vec4 out_colour;

void main() {
    if (any(lessThan(panel_px, panel.clip.xy)) || any(greaterThanEqual(panel_px, panel.clip.zw))) {
        discard;
    }
    out_colour = colour * texture(panel_texture, uv);
}
