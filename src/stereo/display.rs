//! Display modes: how the two eyes' images reach a display, as one composed output image.
//!
//! Every mode starts from the same stereo pass (a 2-layer image, layer 0 the left eye, layer 1
//! the right, `w × h` each); the renderer's composition pass (`render/compose.rs`) turns it into
//! the mode's output. This module holds what the modes *are* — names, output sizes, interlace
//! parity, the anaglyph matrices, the quad-buffer capability decision — and knows no Vulkan
//! handle.
//!
//! ```text
//!  side-by-side (2w × h)     side-by-side-half (w × h)   top-bottom (w × 2h)   top-bottom-half (w × h)
//!  ┌──────┬──────┐           ┌───┬───┐                   ┌──────┐              ┌──────┐
//!  │ left │right │           │ L │ R │  each eye          │ left │              │  L   │ each eye
//!  └──────┴──────┘           └───┴───┘  squeezed ×½       ├──────┤              ├──────┤ squeezed ×½
//!                                        horizontally     │right │              │  R   │ vertically
//!                                                         └──────┘              └──────┘
//!  row-interlaced (w × h)    column-interlaced (w × h)   anaglyph (w × h)      mono (w × h)
//!  row 0  L L L L L          L R L R L R                  Dubois red–cyan mix   the left eye
//!  row 1  R R R R R          L R L R L R                  of both eyes at
//!  row 2  L L L L L          (parity `left-even`)         the same pixel        quad-buffer: both
//!  (parity `left-even`)                                                         layers, unchanged
//!
//!  anaglyph-green-magenta, anaglyph-amber-blue: the same mix with Dubois' matrices for those
//!  glasses. frame-sequential (w × h): one eye per presented frame, the left on even frames
//!  (parity `left-even`) or odd ones; the station counts the frames (see `Parity::for_frame`).
//! ```
//!
//! Squeezed modes average each pair of source pixels (a 2-tap box filter) in linear light;
//! every other mode copies source pixels exactly. All arithmetic on colours (averages, the
//! anaglyph matrices) is done on linear values: the pass reads the sRGB-encoded stereo image
//! through an sRGB view, which decodes, and writes through an sRGB view (or encodes itself when
//! the destination is a UNORM swapchain image).
//!
//! ## Interlace parity and the window's position
//!
//! Parity is defined in *output* pixel coordinates: [`Parity::LeftEven`] puts the left eye on
//! output rows (row-interlaced) or columns (column-interlaced) 0, 2, 4, … counted from the top
//! left of the composed image. A passive (polarised) display assigns eyes to *physical* screen
//! rows, so what matters is the output row's row on the screen: a window whose top edge sits on
//! an odd screen row sees the eyes swapped. [`Parity::for_origin`] gives the parity to compose
//! with for a window at a given screen position, so that the left eye keeps landing on the
//! screen rows the display gives the left eye; the station calls it again whenever the window
//! moves. An offscreen image (`argile render`) has no screen position: its parity is the
//! configured one.

use std::fmt;
use std::str::FromStr;

use crate::math::Vec2;

/// How a stereo pair is shown.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Deserialize)]
#[serde(try_from = "String")]
pub enum DisplayMode {
    /// Both eyes unchanged, in a 2-layer output (a stereo swapchain with `imageArrayLayers = 2`
    /// for shutter glasses on quad-buffer displays).
    QuadBuffer,
    /// Left image on the left, right image on the right, each at full size: `2w × h`.
    SideBySide,
    /// Left and right halves of a `w × h` image, each eye squeezed to half width (for 3D TVs
    /// that stretch each half back to full width).
    SideBySideHalf,
    /// Left image above the right one, each at full size: `w × 2h`.
    TopBottom,
    /// Top and bottom halves of a `w × h` image, each eye squeezed to half height.
    TopBottomHalf,
    /// Alternate rows from each eye (passive line-polarised 3D monitors, interlaced
    /// head-mounted displays).
    RowInterlaced,
    /// Alternate columns from each eye (column-polarised or column-interleaved displays).
    ColumnInterlaced,
    /// Red–cyan anaglyph (red filter on the left eye) with Dubois' least-squares matrices.
    Anaglyph,
    /// Green–magenta anaglyph (green filter on the left eye, as TriOviz glasses), Dubois'
    /// matrices.
    AnaglyphGreenMagenta,
    /// Amber–blue anaglyph (amber filter on the left eye, as ColorCode 3-D glasses), Dubois'
    /// matrices.
    AnaglyphAmberBlue,
    /// One eye per presented frame, alternately (DLP-Link projectors and 3D-ready displays whose
    /// glasses take their sync from the picture): the interlace parity names the phase, the
    /// left eye on even frames (`left-even`) or odd ones.
    FrameSequential,
    /// The left eye only.
    Mono,
}

impl DisplayMode {
    /// Every mode, in the order they are listed to users.
    pub const ALL: [DisplayMode; 12] = [
        DisplayMode::QuadBuffer,
        DisplayMode::SideBySide,
        DisplayMode::SideBySideHalf,
        DisplayMode::TopBottom,
        DisplayMode::TopBottomHalf,
        DisplayMode::RowInterlaced,
        DisplayMode::ColumnInterlaced,
        DisplayMode::Anaglyph,
        DisplayMode::AnaglyphGreenMagenta,
        DisplayMode::AnaglyphAmberBlue,
        DisplayMode::FrameSequential,
        DisplayMode::Mono,
    ];

    /// The name used on the command line, in scene and calibration files and in file names.
    pub fn name(self) -> &'static str {
        match self {
            DisplayMode::QuadBuffer => "quad-buffer",
            DisplayMode::SideBySide => "side-by-side",
            DisplayMode::SideBySideHalf => "side-by-side-half",
            DisplayMode::TopBottom => "top-bottom",
            DisplayMode::TopBottomHalf => "top-bottom-half",
            DisplayMode::RowInterlaced => "row-interlaced",
            DisplayMode::ColumnInterlaced => "column-interlaced",
            DisplayMode::Anaglyph => "anaglyph",
            DisplayMode::AnaglyphGreenMagenta => "anaglyph-green-magenta",
            DisplayMode::AnaglyphAmberBlue => "anaglyph-amber-blue",
            DisplayMode::FrameSequential => "frame-sequential",
            DisplayMode::Mono => "mono",
        }
    }

    /// Dubois' (left, right) matrices of an anaglyph mode, `None` for the others.
    pub fn anaglyph_matrices(self) -> Option<(&'static Matrix3, &'static Matrix3)> {
        match self {
            DisplayMode::Anaglyph => Some((&DUBOIS_RED_CYAN_LEFT, &DUBOIS_RED_CYAN_RIGHT)),
            DisplayMode::AnaglyphGreenMagenta => {
                Some((&DUBOIS_GREEN_MAGENTA_LEFT, &DUBOIS_GREEN_MAGENTA_RIGHT))
            }
            DisplayMode::AnaglyphAmberBlue => Some((&DUBOIS_AMBER_BLUE_LEFT, &DUBOIS_AMBER_BLUE_RIGHT)),
            _ => None,
        }
    }

    /// Every mode's name, comma-separated (for messages).
    pub fn names() -> String {
        DisplayMode::ALL.map(DisplayMode::name).join(", ")
    }

    /// Layers of the output image: 2 for quad-buffer, 1 otherwise.
    pub fn layers(self) -> u32 {
        if self == DisplayMode::QuadBuffer {
            2
        } else {
            1
        }
    }

    /// Size (width, height) of the output image for eyes of `eye` = (width, height) pixels.
    /// Squeezed modes drop an odd last column (side-by-side-half) or row (top-bottom-half), so
    /// that both eyes get the same number of output pixels.
    pub fn output_size(self, (w, h): (u32, u32)) -> (u32, u32) {
        match self {
            DisplayMode::SideBySide => (2 * w, h),
            DisplayMode::TopBottom => (w, 2 * h),
            DisplayMode::SideBySideHalf => (w - w % 2, h),
            DisplayMode::TopBottomHalf => (w, h - h % 2),
            DisplayMode::QuadBuffer
            | DisplayMode::RowInterlaced
            | DisplayMode::ColumnInterlaced
            | DisplayMode::Anaglyph
            | DisplayMode::AnaglyphGreenMagenta
            | DisplayMode::AnaglyphAmberBlue
            | DisplayMode::FrameSequential
            | DisplayMode::Mono => (w, h),
        }
    }

    /// The per-eye size that fills an output (a window) of `output` = (width, height) pixels:
    /// the inverse of [`output_size`](Self::output_size), up to one column or row left black
    /// when a side-by-side or top-bottom output has an odd size.
    pub fn eye_size_for_output(self, (w, h): (u32, u32)) -> (u32, u32) {
        match self {
            DisplayMode::SideBySide => (w / 2, h),
            DisplayMode::TopBottom => (w, h / 2),
            _ => (w, h),
        }
    }

    /// Where a window pixel (origin top left) falls in the picture of the eye it lies over,
    /// and the size of that picture in the same units, for a window of `window_px`: the pointer
    /// is read in the eye's own picture, whichever half of a side-by-side or top-bottom window
    /// it is over (a squeezed half read at the full width or height it stands for). Modes that
    /// show both eyes over the whole window leave the pixel as it is.
    pub fn pointer_in_eye(self, pixel: Vec2, window_px: (u32, u32)) -> (Vec2, Vec2) {
        let size = Vec2::new(window_px.0.max(1) as f32, window_px.1.max(1) as f32);
        let half = size * 0.5;
        match self {
            DisplayMode::SideBySide => {
                (Vec2::new(pixel.x.rem_euclid(half.x), pixel.y), Vec2::new(half.x, size.y))
            }
            DisplayMode::SideBySideHalf => (Vec2::new(pixel.x.rem_euclid(half.x) * 2.0, pixel.y), size),
            DisplayMode::TopBottom => {
                (Vec2::new(pixel.x, pixel.y.rem_euclid(half.y)), Vec2::new(size.x, half.y))
            }
            DisplayMode::TopBottomHalf => (Vec2::new(pixel.x, pixel.y.rem_euclid(half.y) * 2.0), size),
            _ => (pixel, size),
        }
    }
}

impl fmt::Display for DisplayMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for DisplayMode {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let s = s.trim();
        DisplayMode::ALL
            .into_iter()
            .find(|m| m.name().eq_ignore_ascii_case(s))
            .ok_or_else(|| format!("`{s}` is not a display mode; the modes are {}", DisplayMode::names()))
    }
}

impl TryFrom<String> for DisplayMode {
    type Error = String;

    fn try_from(s: String) -> Result<Self, String> {
        s.parse()
    }
}

impl clap::ValueEnum for DisplayMode {
    fn value_variants<'a>() -> &'a [Self] {
        &DisplayMode::ALL
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()))
    }
}

/// Which output rows (row-interlaced) or columns (column-interlaced) carry the left eye,
/// counted from 0 at the top left of the composed image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Deserialize)]
#[serde(try_from = "String")]
pub enum Parity {
    /// The left eye on rows (columns) 0, 2, 4, …
    #[default]
    LeftEven,
    /// The left eye on rows (columns) 1, 3, 5, …
    LeftOdd,
}

impl Parity {
    /// The name used in scene and calibration files.
    pub fn name(self) -> &'static str {
        match self {
            Parity::LeftEven => "left-even",
            Parity::LeftOdd => "left-odd",
        }
    }

    /// The other parity.
    pub fn flipped(self) -> Parity {
        match self {
            Parity::LeftEven => Parity::LeftOdd,
            Parity::LeftOdd => Parity::LeftEven,
        }
    }

    /// The parity to compose with when the output's row (or column) 0 lands on screen row (or
    /// column) `origin_px`, `self` being the parity of the display in screen coordinates
    /// (which screen rows its polariser gives the left eye). An odd origin flips it.
    pub fn for_origin(self, origin_px: i32) -> Parity {
        if origin_px.rem_euclid(2) == 1 {
            self.flipped()
        } else {
            self
        }
    }

    /// The parity to compose presented frame `frame` of a frame-sequential display with,
    /// `self` being its phase (which frames show the left eye): flipped on odd frames, so that
    /// the composed parity's [`offset`](Self::offset) is the eye the frame shows (0 left).
    pub fn for_frame(self, frame: u64) -> Parity {
        if frame % 2 == 1 {
            self.flipped()
        } else {
            self
        }
    }

    /// 0 for [`Parity::LeftEven`], 1 for [`Parity::LeftOdd`]: output row (column) `i` shows
    /// eye `(i + offset) mod 2` (0 left, 1 right).
    pub fn offset(self) -> u32 {
        match self {
            Parity::LeftEven => 0,
            Parity::LeftOdd => 1,
        }
    }
}

impl FromStr for Parity {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim() {
            "left-even" => Ok(Parity::LeftEven),
            "left-odd" => Ok(Parity::LeftOdd),
            other => Err(format!("`{other}` is not an interlace parity; use `left-even` or `left-odd`")),
        }
    }
}

impl TryFrom<String> for Parity {
    type Error = String;

    fn try_from(s: String) -> Result<Self, String> {
        s.parse()
    }
}

/// Dubois' least-squares matrix for the **left** eye of a red–cyan anaglyph: rows are the
/// output's linear R, G, B, columns the left eye's linear R, G, B.
///
/// From E. Dubois, "A projection method to generate anaglyph stereo images", Proc. IEEE ICASSP
/// 2001, vol. 3, pp. 1661–1664, as published for red–cyan glasses on his page "Conversion of a
/// stereo pair to anaglyph with the least-squares projection method" (University of Ottawa,
/// 2009, `LeastSquaresHowToPhotoshop.pdf`). Dubois derives them from the display primaries'
/// spectra and the filters' transmissions, so they act on *linear* intensities: he linearises
/// the inputs (gamma 2.2) before the product and clips to [0, 1] and re-applies the gamma
/// after. The composition pass does the same with the exact sRGB transfer functions.
pub const DUBOIS_RED_CYAN_LEFT: Matrix3 =
    [[0.437, 0.449, 0.164], [-0.062, -0.062, -0.024], [-0.048, -0.050, -0.017]];

/// Dubois' least-squares matrix for the **right** eye of a red–cyan anaglyph (see
/// [`DUBOIS_RED_CYAN_LEFT`]); the output is `clamp(left_matrix · left + right_matrix · right)`.
pub const DUBOIS_RED_CYAN_RIGHT: Matrix3 =
    [[-0.011, -0.032, -0.007], [0.377, 0.761, 0.009], [-0.026, -0.093, 1.234]];

/// Dubois' least-squares matrix for the **left** (green) eye of a green–magenta anaglyph, as
/// he published it for LCD primaries and green–magenta glasses on the same page (see
/// [`DUBOIS_RED_CYAN_LEFT`] for how the matrices are applied).
pub const DUBOIS_GREEN_MAGENTA_LEFT: Matrix3 =
    [[-0.062, -0.158, -0.039], [0.284, 0.668, 0.143], [-0.015, -0.027, 0.021]];

/// Dubois' matrix for the **right** (magenta) eye of a green–magenta anaglyph.
pub const DUBOIS_GREEN_MAGENTA_RIGHT: Matrix3 =
    [[0.529, 0.705, 0.024], [-0.016, -0.015, -0.065], [0.009, 0.075, 0.937]];

/// Dubois' least-squares matrix for the **left** (amber) eye of an amber–blue anaglyph
/// (ColorCode 3-D glasses), from the same page.
pub const DUBOIS_AMBER_BLUE_LEFT: Matrix3 =
    [[1.062, -0.205, 0.299], [-0.026, 0.908, 0.068], [-0.038, -0.173, 0.022]];

/// Dubois' matrix for the **right** (blue) eye of an amber–blue anaglyph.
pub const DUBOIS_AMBER_BLUE_RIGHT: Matrix3 =
    [[-0.016, -0.123, -0.017], [0.006, 0.062, -0.017], [0.094, 0.185, 0.911]];

/// A row-major 3×3 matrix: rows are the output's linear R, G, B, columns an eye's.
pub type Matrix3 = [[f32; 3]; 3];

/// What a window shows after the quad-buffer capability check.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ModeChoice {
    /// The mode to present in.
    pub mode: DisplayMode,
    /// Why it differs from the one asked for (for the user), when it does.
    pub notice: Option<String>,
}

/// Chooses the mode a window presents in. Quad-buffer stereo needs a swapchain of two array
/// layers, so a surface whose `maxImageArrayLayers` (on `device`) is below 2 cannot show it:
/// then `fallback` is used with a notice, or, when the user set no fallback, the choice fails
/// with a message naming the device and the modes that work there. Any other mode works on
/// every surface and is kept.
pub fn choose_mode(
    wanted: DisplayMode,
    fallback: Option<DisplayMode>,
    device: &str,
    max_image_array_layers: u32,
) -> Result<ModeChoice, String> {
    if wanted != DisplayMode::QuadBuffer || max_image_array_layers >= 2 {
        return Ok(ModeChoice { mode: wanted, notice: None });
    }
    let working: Vec<&str> = DisplayMode::ALL.iter().filter(|m| m.layers() == 1).map(|m| m.name()).collect();
    let why = format!(
        "{device} offers no stereo swapchain (maxImageArrayLayers is {max_image_array_layers}), so \
         quad-buffer stereo cannot be shown; the modes that work here are {}",
        working.join(", ")
    );
    match fallback {
        Some(mode) if mode != DisplayMode::QuadBuffer => {
            Ok(ModeChoice { mode, notice: Some(format!("{why}; showing {mode} (the display fallback)")) })
        }
        _ => Err(format!("{why}; choose one with --display-mode or the display fallback setting")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pointer_is_read_in_the_picture_of_the_eye_it_is_over() {
        let window = (480, 200);
        let at = |m: DisplayMode, x: f32, y: f32| m.pointer_in_eye(Vec2::new(x, y), window);
        // A click at x = 240 in side-by-side-half is the left edge of the right eye's picture,
        // not x = 119 of a picture as wide as the window.
        assert_eq!(
            at(DisplayMode::SideBySideHalf, 240.0, 50.0),
            (Vec2::new(0.0, 50.0), Vec2::new(480.0, 200.0))
        );
        assert_eq!(
            at(DisplayMode::SideBySideHalf, 120.0, 50.0).0,
            Vec2::new(240.0, 50.0),
            "the left eye's centre"
        );
        assert_eq!(
            at(DisplayMode::SideBySide, 360.0, 50.0),
            (Vec2::new(120.0, 50.0), Vec2::new(240.0, 200.0))
        );
        assert_eq!(at(DisplayMode::TopBottom, 10.0, 150.0), (Vec2::new(10.0, 50.0), Vec2::new(480.0, 100.0)));
        assert_eq!(at(DisplayMode::TopBottomHalf, 10.0, 150.0).0, Vec2::new(10.0, 100.0));
        for m in [
            DisplayMode::Anaglyph,
            DisplayMode::AnaglyphAmberBlue,
            DisplayMode::RowInterlaced,
            DisplayMode::FrameSequential,
            DisplayMode::Mono,
            DisplayMode::QuadBuffer,
        ] {
            assert_eq!(at(m, 300.0, 70.0), (Vec2::new(300.0, 70.0), Vec2::new(480.0, 200.0)));
        }
    }

    #[test]
    fn names_round_trip_and_bad_names_list_the_modes() {
        for m in DisplayMode::ALL {
            assert_eq!(m.name().parse::<DisplayMode>(), Ok(m));
            assert_eq!(m.to_string(), m.name());
            assert_eq!(DisplayMode::try_from(format!(" {} ", m.name().to_uppercase())), Ok(m));
        }
        let e = "anaglyph-green".parse::<DisplayMode>().unwrap_err();
        assert!(e.contains("`anaglyph-green`") && e.contains("row-interlaced, column-interlaced"), "{e}");
        let names: Vec<&str> = DisplayMode::ALL.map(DisplayMode::name).to_vec();
        let mut unique = names.clone();
        unique.sort_unstable();
        unique.dedup();
        assert_eq!(unique.len(), names.len());
        for m in DisplayMode::ALL {
            let v = clap::ValueEnum::to_possible_value(&m).unwrap();
            assert_eq!(<DisplayMode as clap::ValueEnum>::from_str(v.get_name(), false), Ok(m));
        }
    }

    #[test]
    fn output_sizes_per_mode() {
        let eye = (160, 120);
        let expected = [
            (DisplayMode::QuadBuffer, (160, 120), 2),
            (DisplayMode::SideBySide, (320, 120), 1),
            (DisplayMode::SideBySideHalf, (160, 120), 1),
            (DisplayMode::TopBottom, (160, 240), 1),
            (DisplayMode::TopBottomHalf, (160, 120), 1),
            (DisplayMode::RowInterlaced, (160, 120), 1),
            (DisplayMode::ColumnInterlaced, (160, 120), 1),
            (DisplayMode::Anaglyph, (160, 120), 1),
            (DisplayMode::AnaglyphGreenMagenta, (160, 120), 1),
            (DisplayMode::AnaglyphAmberBlue, (160, 120), 1),
            (DisplayMode::FrameSequential, (160, 120), 1),
            (DisplayMode::Mono, (160, 120), 1),
        ];
        for (mode, size, layers) in expected {
            assert_eq!(mode.output_size(eye), size, "{mode}");
            assert_eq!(mode.layers(), layers, "{mode}");
        }
        assert_eq!(DisplayMode::SideBySideHalf.output_size((161, 121)), (160, 121));
        assert_eq!(DisplayMode::TopBottomHalf.output_size((161, 121)), (161, 120));
    }

    #[test]
    fn eye_sizes_fill_the_output_up_to_one_odd_column_or_row() {
        for mode in DisplayMode::ALL {
            for window in [(1920, 1080), (1921, 1081), (640, 481)] {
                let eye = mode.eye_size_for_output(window);
                let out = mode.output_size(eye);
                assert!(out.0 <= window.0 && out.1 <= window.1, "{mode} {window:?}: {out:?}");
                assert!(window.0 - out.0 <= 1 && window.1 - out.1 <= 1, "{mode} {window:?}: {out:?}");
                if window.0 % 2 == 0 && window.1 % 2 == 0 {
                    assert_eq!(out, window, "{mode}: an even window is filled exactly");
                }
            }
        }
    }

    #[test]
    fn parity_flips_with_an_odd_window_origin() {
        assert_eq!(Parity::default(), Parity::LeftEven);
        for p in [Parity::LeftEven, Parity::LeftOdd] {
            assert_eq!(p.name().parse::<Parity>(), Ok(p));
            assert_eq!(p.flipped().flipped(), p);
            assert_ne!(p.flipped(), p);
            assert_eq!(p.for_origin(0), p);
            assert_eq!(p.for_origin(200), p);
            assert_eq!(p.for_origin(201), p.flipped());
            assert_eq!(p.for_origin(-1), p.flipped(), "a window partly off the left screen edge");
            assert_eq!(p.for_origin(-2), p);
            // A frame-sequential phase: the eye a frame shows alternates, starting from the
            // phase's own.
            let eyes: Vec<u32> = (0..4).map(|f| p.for_frame(f).offset()).collect();
            let first = p.offset();
            assert_eq!(eyes, [first, 1 - first, first, 1 - first], "{p:?}");
            assert_eq!(p.for_frame(1 << 40), p);
            // The screen row of the left eye stays the same wherever the window goes: output
            // row i sits on screen row origin + i and shows eye (i + offset) mod 2.
            for origin in -3..4 {
                let composed = p.for_origin(origin);
                for i in 0..4i32 {
                    let eye = (i + composed.offset() as i32).rem_euclid(2);
                    let screen_eye = (origin + i + p.offset() as i32).rem_euclid(2);
                    assert_eq!(eye, screen_eye, "parity {p:?}, origin {origin}, row {i}");
                }
            }
        }
        assert!("odd".parse::<Parity>().unwrap_err().contains("left-even"));
    }

    #[test]
    fn dubois_matrices_keep_white_near_white_and_send_each_eye_through_its_filter() {
        let anaglyphs: Vec<DisplayMode> =
            DisplayMode::ALL.into_iter().filter(|m| m.anaglyph_matrices().is_some()).collect();
        assert_eq!(
            anaglyphs,
            [DisplayMode::Anaglyph, DisplayMode::AnaglyphGreenMagenta, DisplayMode::AnaglyphAmberBlue]
        );
        for mode in anaglyphs {
            let (left, right) = mode.anaglyph_matrices().unwrap();
            // Dubois normalised the rows so that a white pair gives white (each row of left +
            // right sums to about 1).
            for row in 0..3 {
                let sum: f32 = (0..3).map(|k| left[row][k] + right[row][k]).sum();
                assert!((sum - 1.0).abs() < 0.01, "{mode}: row {row} sums to {sum}");
            }
        }
        let gain = |m: &Matrix3, row: usize| m[row].iter().sum::<f32>();
        // Red–cyan: the left eye drives red, the right eye green and blue.
        assert!(gain(&DUBOIS_RED_CYAN_LEFT, 0) > 0.9);
        assert!(gain(&DUBOIS_RED_CYAN_RIGHT, 1) > 0.9 && gain(&DUBOIS_RED_CYAN_RIGHT, 2) > 0.9);
        // Green–magenta: the left eye green, the right red and blue.
        assert!(gain(&DUBOIS_GREEN_MAGENTA_LEFT, 1) > 0.9);
        assert!(gain(&DUBOIS_GREEN_MAGENTA_LEFT, 0) < 0.0 && gain(&DUBOIS_GREEN_MAGENTA_LEFT, 2) < 0.0);
        assert!(gain(&DUBOIS_GREEN_MAGENTA_RIGHT, 0) > 0.9 && gain(&DUBOIS_GREEN_MAGENTA_RIGHT, 2) > 0.9);
        // Amber–blue: the left eye red and green (amber), the right eye blue.
        assert!(gain(&DUBOIS_AMBER_BLUE_LEFT, 0) > 0.9 && gain(&DUBOIS_AMBER_BLUE_LEFT, 1) > 0.9);
        assert!(gain(&DUBOIS_AMBER_BLUE_RIGHT, 2) > 0.9);
        assert!(gain(&DUBOIS_AMBER_BLUE_RIGHT, 0) < 0.0 && gain(&DUBOIS_AMBER_BLUE_LEFT, 2) < 0.0);
    }

    #[test]
    fn quad_buffer_falls_back_only_where_the_surface_lacks_layers() {
        let device = "llvmpipe (LLVM 15.0.6, 256 bits)";
        let ok = choose_mode(DisplayMode::QuadBuffer, Some(DisplayMode::Anaglyph), "Quadro RTX 6000", 2);
        assert_eq!(ok, Ok(ModeChoice { mode: DisplayMode::QuadBuffer, notice: None }));

        let fell = choose_mode(DisplayMode::QuadBuffer, Some(DisplayMode::RowInterlaced), device, 1).unwrap();
        assert_eq!(fell.mode, DisplayMode::RowInterlaced);
        let notice = fell.notice.unwrap();
        assert!(notice.contains(device) && notice.contains("maxImageArrayLayers is 1"), "{notice}");
        assert!(notice.contains("side-by-side, side-by-side-half") && notice.contains("mono"), "{notice}");
        assert!(!notice.contains("are quad-buffer"), "{notice}");
        assert!(notice.contains("showing row-interlaced"), "{notice}");

        for fallback in [None, Some(DisplayMode::QuadBuffer)] {
            let e = choose_mode(DisplayMode::QuadBuffer, fallback, device, 1).unwrap_err();
            assert!(e.contains(device) && e.contains("--display-mode") && e.contains("anaglyph"), "{e}");
        }
        for mode in DisplayMode::ALL.into_iter().filter(|&m| m != DisplayMode::QuadBuffer) {
            assert_eq!(choose_mode(mode, None, device, 1), Ok(ModeChoice { mode, notice: None }));
        }
    }
}
