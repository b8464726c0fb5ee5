// The per-frame uniforms every pipeline reads (std140; mirrors `FrameUniforms` in
// src/render/renderer.rs), and the lighting shared by the clay and the stage.

const float PI = 3.14159265358979;
const int MAX_LIGHTS = 4;
const int MAX_TOOLS = 2;

struct Eye {
    mat4 view_proj;     // world -> clip (off-axis, Vulkan: y down, depth 0..1)
    mat4 inv_view_proj; // clip -> world
    vec4 position;      // eye position, world metres
};

layout(set = 0, binding = 0, std140) uniform FrameUniforms {
    Eye eyes[2];                     // indexed by gl_ViewIndex: 0 left, 1 right
    vec4 light_vector[MAX_LIGHTS];   // w = 0: xyz direction of travel; w = 1: xyz position
    vec4 light_radiance[MAX_LIGHTS]; // rgb radiance (point lights: at 1 m)
    vec4 sh[9];                      // irradiance as order-2 spherical harmonics, rgb
    vec4 material;                   // shininess, specular, reflectivity, ambient
    vec4 background;                 // rgb; a = 1 when the environment is the background
    vec4 params;                     // light count, reflection lod, tool count, stage grid (m)
    vec4 tools[MAX_TOOLS];           // xyz tool centre, w radius (for the stage crosshairs)
} frame;

layout(set = 0, binding = 1) uniform samplerCube radiance;

// Irradiance E(n) from the SH coefficients; basis order and constants as in
// src/render/environment.rs (`eval_sh9`).
vec3 irradiance(vec3 n) {
    return frame.sh[0].rgb * 0.282095
         + frame.sh[1].rgb * 0.488603 * n.y
         + frame.sh[2].rgb * 0.488603 * n.z
         + frame.sh[3].rgb * 0.488603 * n.x
         + frame.sh[4].rgb * 1.092548 * n.x * n.y
         + frame.sh[5].rgb * 1.092548 * n.y * n.z
         + frame.sh[6].rgb * 0.315392 * (3.0 * n.z * n.z - 1.0)
         + frame.sh[7].rgb * 1.092548 * n.x * n.z
         + frame.sh[8].rgb * 0.546274 * (n.x * n.x - n.y * n.y);
}

// Blinn-Phong from the scene's lights: Lambert diffuse (albedo / pi) plus a normalised
// specular lobe of the material's shininess.
vec3 direct_light(vec3 p, vec3 n, vec3 v, vec3 albedo, float specular) {
    float shininess = frame.material.x;
    vec3 sum = vec3(0.0);
    int count = int(frame.params.x);
    for (int i = 0; i < MAX_LIGHTS; ++i) {
        if (i >= count) {
            break;
        }
        vec4 lv = frame.light_vector[i];
        vec3 l;
        vec3 e = frame.light_radiance[i].rgb;
        if (lv.w == 0.0) {
            l = -normalize(lv.xyz);
        } else {
            vec3 d = lv.xyz - p;
            float d2 = max(dot(d, d), 1e-4);
            l = d * inversesqrt(d2);
            e /= d2;
        }
        float ndl = max(dot(n, l), 0.0);
        vec3 h = normalize(l + v);
        float spec = specular * (shininess + 8.0) / (8.0 * PI) * pow(max(dot(n, h), 0.0), shininess);
        sum += e * ndl * (albedo / PI + vec3(spec));
    }
    return sum;
}
