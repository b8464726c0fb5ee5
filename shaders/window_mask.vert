#version 450
// The floating stereoscopic window: a full-screen triangle over everything but the heads-up
// display and the panels; the fragment shader keeps only the strips masked on this view's
// picture (see src/stereo/floating.rs).
layout(location = 0) in vec3 in_position;

layout(location = 0) out float x_ndc;

void main() {
    x_ndc = in_position.x;
    gl_Position = vec4(in_position.xy, 0.0, 1.0);
}
