#version 450
#extension GL_EXT_multiview : require
#include "frame.glsl"

layout(location = 0) in vec3 ray;
layout(location = 0) out vec4 colour;

void main() {
    vec3 c = frame.background.a > 0.5 ? textureLod(radiance, normalize(ray), 0.0).rgb : frame.background.rgb;
    colour = vec4(c, 1.0);
}
