#version 450
// Clay: Blinn-Phong from the scene's lights, diffuse light from the environment's irradiance,
// and the environment's reflection weighted by Schlick's Fresnel term.
#extension GL_EXT_multiview : require
#include "frame.glsl"

layout(location = 0) in vec3 world_position;
layout(location = 1) in vec3 world_normal;
layout(location = 2) in vec4 albedo;
layout(location = 0) out vec4 colour;

void main() {
    vec3 n = normalize(world_normal);
    vec3 v = normalize(frame.eyes[gl_ViewIndex].position.xyz - world_position);
    float ambient = frame.material.w;
    vec3 lit = direct_light(world_position, n, v, albedo.rgb, frame.material.y)
             + ambient * albedo.rgb * irradiance(n) / PI;
    float f0 = frame.material.z;
    float fresnel = f0 + (1.0 - f0) * pow(1.0 - max(dot(n, v), 0.0), 5.0);
    vec3 reflected = textureLod(radiance, reflect(-v, n), frame.params.y).rgb;
    colour = vec4(mix(lit, reflected, fresnel), 1.0);
}
