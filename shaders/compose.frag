#version 450
// The display-mode composition: one output pixel from the 2-layer stereo image (layer 0 the
// left eye, layer 1 the right). The mode is a specialization constant: each mode's pipeline
// keeps only its own branch (on lavapipe a mode chosen at run time made the pass 5 to 14 times
// slower, see BENCHMARKS.md). The source is read with texelFetch through an sRGB view, so the
// values are linear and exact (no filtering); averages and the anaglyph matrices work on linear
// values. Modes and their layouts: src/stereo/display.rs. Mode numbers: src/render/compose.rs.

layout(constant_id = 0) const uint MODE = 8u;

layout(set = 0, binding = 0) uniform sampler2DArray stereo;

layout(push_constant) uniform Compose {
    // Anaglyph matrices (red–cyan, green–magenta or amber–blue), one column per vec4 (w
    // unused): output = left * l + right * r.
    vec4 left[3];
    vec4 right[3];
    // x: interlace parity offset (0 or 1; frame-sequential: the eye this frame shows), y: encode sRGB in the shader (a UNORM destination),
    // z: the destination layer (quad-buffer), w: unused.
    uvec4 params;
} pc;

layout(location = 0) out vec4 colour;

const uint QUAD_BUFFER = 0u;
const uint SIDE_BY_SIDE = 1u;
const uint SIDE_BY_SIDE_HALF = 2u;
const uint TOP_BOTTOM = 3u;
const uint TOP_BOTTOM_HALF = 4u;
const uint ROW_INTERLACED = 5u;
const uint COLUMN_INTERLACED = 6u;
const uint ANAGLYPH = 7u;
const uint MONO = 8u;
const uint FRAME_SEQUENTIAL = 9u;

vec4 eye(uint layer, ivec2 p) {
    return texelFetch(stereo, ivec3(p, int(layer)), 0);
}

vec3 linear_to_srgb(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 size = textureSize(stereo, 0).xy;
    const uint mode = MODE;
    uint parity = pc.params.x;
    vec4 c;
    if (mode == QUAD_BUFFER) {
        c = eye(pc.params.z, p);
    } else if (mode == SIDE_BY_SIDE) {
        uint layer = p.x < size.x ? 0u : 1u;
        c = eye(layer, ivec2(p.x - int(layer) * size.x, p.y));
    } else if (mode == SIDE_BY_SIDE_HALF) {
        int half_width = size.x / 2;
        uint layer = p.x < half_width ? 0u : 1u;
        int x = 2 * (p.x - int(layer) * half_width);
        c = 0.5 * (eye(layer, ivec2(x, p.y)) + eye(layer, ivec2(x + 1, p.y)));
    } else if (mode == TOP_BOTTOM) {
        uint layer = p.y < size.y ? 0u : 1u;
        c = eye(layer, ivec2(p.x, p.y - int(layer) * size.y));
    } else if (mode == TOP_BOTTOM_HALF) {
        int half_height = size.y / 2;
        uint layer = p.y < half_height ? 0u : 1u;
        int y = 2 * (p.y - int(layer) * half_height);
        c = 0.5 * (eye(layer, ivec2(p.x, y)) + eye(layer, ivec2(p.x, y + 1)));
    } else if (mode == ROW_INTERLACED) {
        c = eye((uint(p.y) + parity) & 1u, p);
    } else if (mode == COLUMN_INTERLACED) {
        c = eye((uint(p.x) + parity) & 1u, p);
    } else if (mode == ANAGLYPH) {
        vec3 l = eye(0u, p).rgb;
        vec3 r = eye(1u, p).rgb;
        mat3 ml = mat3(pc.left[0].xyz, pc.left[1].xyz, pc.left[2].xyz);
        mat3 mr = mat3(pc.right[0].xyz, pc.right[1].xyz, pc.right[2].xyz);
        c = vec4(clamp(ml * l + mr * r, 0.0, 1.0), 1.0);
    } else if (mode == FRAME_SEQUENTIAL) {
        c = eye(parity, p);
    } else {
        c = eye(0u, p);
    }
    colour = pc.params.y != 0u ? vec4(linear_to_srgb(c.rgb), c.a) : c;
}
