//! The composition pass, pixel by pixel: every display mode's output pixel comes from the eye
//! pixel the mode's layout says (exactly, or as the linear-light average or anaglyph mix of
//! the expected pixels), for both interlace parities and an odd eye size. Rendered offscreen
//! on the pinned Vulkan device with the validation layer on; fails (never skips) without one.
//! The per-mode golden images are in `tests/golden_stereo.rs`.

use argile::app::{build_frame, renderer_for, Playback};
use argile::mesh::mesh_all;
use argile::render::Renderer;
use argile::scene::Scene;
use argile::stereo::display::{
    DisplayMode, Parity, DUBOIS_AMBER_BLUE_LEFT, DUBOIS_AMBER_BLUE_RIGHT, DUBOIS_GREEN_MAGENTA_LEFT,
    DUBOIS_GREEN_MAGENTA_RIGHT, DUBOIS_RED_CYAN_LEFT, DUBOIS_RED_CYAN_RIGHT,
};
use image::{Rgba, RgbaImage};

/// The sRGB transfer functions (IEC 61966-2-1), the reference the GPU's sRGB views follow.
fn to_linear(c: u8) -> f32 {
    let c = f32::from(c) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn to_srgb(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    255.0 * if c <= 0.003_130_8 { c * 12.92 } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 }
}

/// How far (in 8-bit steps) a computed colour may land from the exact sRGB encoding of its
/// linear value. llvmpipe (Mesa 22.3.6) encodes sRGB approximately: the worst measured is 1.68
/// steps on a near-black anaglyph pixel, 0.86 on the squeezed modes' averages.
const MAX_ENCODING_ERROR: f32 = 2.0; // llvmpipe, Mesa 22.3.6

/// What a mode's output pixel must be: an eye's pixel exactly, or a colour (sRGB, 0..=255)
/// that 8-bit rounding may miss by one.
enum Expected {
    Exact(Rgba<u8>),
    Near([f32; 3]),
}

/// The expected output pixel (x, y) of `mode` for eyes `left` and `right`: each mode's layout
/// as `src/stereo/display.rs` draws it, written out independently of the shader.
fn expected(mode: DisplayMode, parity: Parity, eyes: [&RgbaImage; 2], x: u32, y: u32) -> Expected {
    let (w, h) = eyes[0].dimensions();
    let eye_of = |i: u32| (i + parity.offset()) as usize % 2;
    let average = |eye: &RgbaImage, a: (u32, u32), b: (u32, u32)| {
        let (p, q) = (eye.get_pixel(a.0, a.1), eye.get_pixel(b.0, b.1));
        Expected::Near([0, 1, 2].map(|c| to_srgb(0.5 * (to_linear(p[c]) + to_linear(q[c])))))
    };
    match mode {
        DisplayMode::QuadBuffer | DisplayMode::Mono => Expected::Exact(*eyes[0].get_pixel(x, y)),
        DisplayMode::SideBySide => Expected::Exact(*eyes[(x >= w) as usize].get_pixel(x % w, y)),
        DisplayMode::TopBottom => Expected::Exact(*eyes[(y >= h) as usize].get_pixel(x, y % h)),
        DisplayMode::SideBySideHalf => {
            let (eye, sx) = if x < w / 2 { (0, 2 * x) } else { (1, 2 * (x - w / 2)) };
            average(eyes[eye], (sx, y), (sx + 1, y))
        }
        DisplayMode::TopBottomHalf => {
            let (eye, sy) = if y < h / 2 { (0, 2 * y) } else { (1, 2 * (y - h / 2)) };
            average(eyes[eye], (x, sy), (x, sy + 1))
        }
        DisplayMode::RowInterlaced => Expected::Exact(*eyes[eye_of(y)].get_pixel(x, y)),
        DisplayMode::ColumnInterlaced => Expected::Exact(*eyes[eye_of(x)].get_pixel(x, y)),
        DisplayMode::FrameSequential => Expected::Exact(*eyes[parity.offset() as usize].get_pixel(x, y)),
        DisplayMode::Anaglyph | DisplayMode::AnaglyphGreenMagenta | DisplayMode::AnaglyphAmberBlue => {
            // Dubois' matrices for each pair of glasses, named here rather than asked of the mode.
            let (ml, mr) = match mode {
                DisplayMode::Anaglyph => (DUBOIS_RED_CYAN_LEFT, DUBOIS_RED_CYAN_RIGHT),
                DisplayMode::AnaglyphGreenMagenta => (DUBOIS_GREEN_MAGENTA_LEFT, DUBOIS_GREEN_MAGENTA_RIGHT),
                _ => (DUBOIS_AMBER_BLUE_LEFT, DUBOIS_AMBER_BLUE_RIGHT),
            };
            let l = eyes[0].get_pixel(x, y).0.map(to_linear);
            let r = eyes[1].get_pixel(x, y).0.map(to_linear);
            Expected::Near(
                [0, 1, 2].map(|row| to_srgb((0..3).map(|k| ml[row][k] * l[k] + mr[row][k] * r[k]).sum())),
            )
        }
    }
}

/// The parallax scene (two coloured balls on black) at an odd per-eye size, drawn once.
fn draw_pair(size: (u32, u32)) -> (Renderer, RgbaImage, RgbaImage) {
    let mut scene =
        Scene::load(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/tests/parallax.toml"))
            .expect("the parallax scene loads");
    (scene.output.width_px, scene.output.height_px) = size;
    scene.output.samples = 1;
    let mut renderer = renderer_for(&scene, None, true, None).expect("a Vulkan device");
    let playback = Playback::new(&scene);
    renderer.apply(&mesh_all(playback.field())).expect("mesh upload");
    renderer.draw(&build_frame(&scene, &[], false)).expect("stereo frame");
    let pair = renderer.read_back().expect("stereo read-back");
    (renderer, pair.left, pair.right)
}

fn check_mode(renderer: &mut Renderer, eyes: [&RgbaImage; 2], mode: DisplayMode, parity: Parity) -> usize {
    renderer.compose(mode, parity).expect("composition");
    let layers = renderer.read_back_composed().expect("composed read-back");
    assert_eq!(layers.len(), mode.layers() as usize, "{mode}");
    let size = mode.output_size(eyes[0].dimensions());
    let mut checked = 0;
    for (layer, out) in layers.iter().enumerate() {
        assert_eq!(out.dimensions(), size, "{mode}");
        if mode == DisplayMode::QuadBuffer {
            assert_eq!(out, eyes[layer], "quad-buffer layer {layer} is that eye unchanged");
            checked += (size.0 * size.1) as usize;
            continue;
        }
        for (x, y, p) in out.enumerate_pixels() {
            assert_eq!(p[3], 255, "{mode} ({x}, {y}) is opaque");
            match expected(mode, parity, eyes, x, y) {
                Expected::Exact(e) => assert_eq!(*p, e, "{mode} {parity:?} pixel ({x}, {y})"),
                Expected::Near(e) => {
                    for c in 0..3 {
                        let error = (f32::from(p[c]) - e[c]).abs();
                        assert!(
                            error <= MAX_ENCODING_ERROR,
                            "{mode} pixel ({x}, {y}) channel {c}: {} against {:.2}",
                            p[c],
                            e[c]
                        );
                    }
                }
            }
            checked += 1;
        }
    }
    checked
}

#[test]
fn every_output_pixel_comes_from_the_expected_eye_pixels() {
    // Odd on both axes: the squeezed modes drop the last column or row.
    let (mut renderer, left, right) = draw_pair((67, 49));
    let log = renderer.validation_log();
    // The eyes differ wherever a ball is, so a mode that took the wrong eye fails.
    let differing = left.pixels().zip(right.pixels()).filter(|(l, r)| l != r).count();
    assert!(differing > 100, "the eyes differ in {differing} pixels");
    let eyes = [&left, &right];
    for mode in DisplayMode::ALL {
        let checked = check_mode(&mut renderer, eyes, mode, Parity::LeftEven);
        let (w, h) = mode.output_size((67, 49));
        assert_eq!(checked, (w * h * mode.layers()) as usize, "{mode}: every pixel checked");
    }
    // The odd parity: the other rows or columns, and the frames of the other phase (the right
    // eye in frame 0).
    for mode in [DisplayMode::RowInterlaced, DisplayMode::ColumnInterlaced, DisplayMode::FrameSequential] {
        check_mode(&mut renderer, eyes, mode, Parity::LeftOdd);
    }
    // The stereo pair is left as it was: composing does not disturb the next read-back.
    let again = renderer.read_back().expect("stereo read-back");
    assert_eq!((again.left, again.right), (left, right));
    drop(renderer);
    let messages = log.take();
    assert!(messages.is_empty(), "the validation layer reported: {messages:#?}");
}
