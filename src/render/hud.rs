//! The heads-up display: lines of text drawn at zero parallax over both eyes.
//!
//! Text is laid out on the CPU with the 8×8 public-domain bitmap font of the `font8x8` crate:
//! each horizontal run of lit font pixels becomes one quad, on a translucent dark panel, in
//! Vulkan's normalised device coordinates (x right, y down). The HUD vertex shader passes those
//! coordinates through unchanged for both views, so each letter lands on the same pixel in the
//! left and the right eye: zero disparity, the text sits on the screen plane whatever the
//! convergence. Only ASCII is drawn; other characters show as `?`.
//!
//! Besides the text, [`EyeMark`]s are rectangles at zero parallax drawn over one eye's picture
//! only, or over both (a calibration pattern's L and R, its crosstalk squares).
//!
//! The quads use the mesh [`Vertex`] layout, read as three attributes: `position` holds the
//! NDC x and y and, in z, the opacity; `normal` holds the linear RGB colour; `colour.x` the
//! views drawn into, as a bit mask (1 the left eye, 2 the right, 3 both).

use crate::mesh::Vertex;

/// The view mask of the left eye's picture.
pub const LEFT_VIEW: u32 = 1;
/// The view mask of the right eye's picture.
pub const RIGHT_VIEW: u32 = 2;
/// Both pictures.
pub const BOTH_VIEWS: u32 = LEFT_VIEW | RIGHT_VIEW;

/// An opaque rectangle at zero parallax over the pictures `views` names (a mask of
/// [`LEFT_VIEW`] and [`RIGHT_VIEW`]), in Vulkan's normalised device coordinates (y down).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyeMark {
    /// The pictures it is drawn over.
    pub views: u32,
    /// Its corner of least x and y.
    pub min: [f32; 2],
    /// Its corner of greatest x and y.
    pub max: [f32; 2],
    /// Linear RGB.
    pub colour: [f32; 3],
}

impl EyeMark {
    /// `text` in the 8×8 font as marks, its top left at `at`, each font pixel `pixel` across
    /// and down (device coordinates).
    pub fn text(text: &str, views: u32, at: [f32; 2], pixel: [f32; 2], colour: [f32; 3]) -> Vec<EyeMark> {
        let mut marks = Vec::new();
        for (column, c) in text.chars().enumerate() {
            let code = if c.is_ascii() { c as usize } else { '?' as usize };
            let left = at[0] + column as f32 * 8.0 * pixel[0];
            for (row, bits) in font8x8::legacy::BASIC_LEGACY[code].iter().enumerate() {
                let top = at[1] + row as f32 * pixel[1];
                for_each_run(*bits, |start, end| {
                    marks.push(EyeMark {
                        views,
                        min: [left + start as f32 * pixel[0], top],
                        max: [left + end as f32 * pixel[0], top + pixel[1]],
                        colour,
                    })
                });
            }
        }
        marks
    }
}

/// Calls `run(start, end)` for each run of lit pixels of a font row (bit 0 the leftmost).
fn for_each_run(bits: u8, mut run: impl FnMut(u32, u32)) {
    let mut x = 0;
    while x < 8 {
        if bits & (1 << x) == 0 {
            x += 1;
            continue;
        }
        let start = x;
        while x < 8 && bits & (1 << x) != 0 {
            x += 1;
        }
        run(start, x);
    }
}

/// Screen pixels per font pixel for an image `width` pixels wide: 1 below 1280 pixels, then
/// one more per 640 pixels (at most 4), so the text keeps about the same share of the width.
pub(crate) fn scale_for(width: u32) -> u32 {
    (width / 640).clamp(1, 4)
}
/// Margin around the text and from the window's corner, screen pixels.
const MARGIN_PX: u32 = 6;
/// Text colour (linear RGBA) and the panel's.
const TEXT: [f32; 4] = [0.95, 0.95, 0.85, 1.0];
const PANEL: [f32; 4] = [0.0, 0.0, 0.0, 0.55];

/// `lines` broken at spaces (a word longer than a line, within it) so that none is longer than
/// `columns` characters.
fn wrapped(lines: &[String], columns: usize) -> Vec<String> {
    let columns = columns.max(1);
    let mut out = Vec::new();
    for line in lines {
        let mut current = String::new();
        for word in line.split(' ') {
            let mut word: Vec<char> = word.chars().collect();
            loop {
                let used = current.chars().count();
                let room = if used == 0 { columns } else { columns.saturating_sub(used + 1) };
                if word.len() <= room {
                    if used > 0 {
                        current.push(' ');
                    }
                    current.extend(word.iter());
                    break;
                }
                if used > 0 {
                    out.push(std::mem::take(&mut current));
                    continue;
                }
                // A word longer than a whole line: cut.
                current.extend(word.drain(..columns));
                out.push(std::mem::take(&mut current));
            }
        }
        out.push(current);
    }
    out
}

/// The quads of `marks` then of `lines` in the top-left corner of a `width` × `height` image:
/// vertices and indices, empty when there is nothing to draw. Lines wider than the image are
/// broken at spaces, so that every eye's image holds all the text (each eye of a side-by-side
/// window too).
pub(crate) fn layout(
    lines: &[String],
    marks: &[EyeMark],
    width: u32,
    height: u32,
) -> (Vec<Vertex>, Vec<u32>) {
    let mut vertices = Vec::new();
    let mut indices = Vec::new();
    if width == 0 || height == 0 {
        return (vertices, indices);
    }
    for mark in marks {
        let base = vertices.len() as u32;
        let views = [mark.views as f32, 0.0, 0.0, 0.0];
        for (x, y) in [(0, 0), (1, 0), (1, 1), (0, 1)] {
            let corner = [[mark.min[0], mark.max[0]][x], [mark.min[1], mark.max[1]][y], 1.0];
            vertices.push(Vertex { position: corner, normal: mark.colour, colour: views });
        }
        indices.extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
    }
    let scale = scale_for(width);
    let glyph = 8 * scale;
    let fits = (width.saturating_sub(MARGIN_PX * 2) / glyph).max(1) as usize;
    let lines = wrapped(lines, fits);
    let columns = lines.iter().map(|l| l.chars().count()).max().unwrap_or(0) as u32;
    if columns == 0 {
        return (vertices, indices);
    }
    let (w, h) = (width as f32, height as f32);
    let mut quad = |x0: u32, y0: u32, x1: u32, y1: u32, colour: [f32; 4]| {
        let ndc = |x: u32, y: u32| [2.0 * x as f32 / w - 1.0, 2.0 * y as f32 / h - 1.0, colour[3]];
        let base = vertices.len() as u32;
        let rgb = [colour[0], colour[1], colour[2]];
        for (x, y) in [(x0, y0), (x1, y0), (x1, y1), (x0, y1)] {
            vertices.push(Vertex {
                position: ndc(x, y),
                normal: rgb,
                colour: [BOTH_VIEWS as f32, 0.0, 0.0, 0.0],
            });
        }
        indices.extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
    };
    let right = MARGIN_PX * 2 + columns * glyph;
    let bottom = MARGIN_PX * 2 + lines.len() as u32 * (glyph + scale);
    quad(MARGIN_PX / 2, MARGIN_PX / 2, right, bottom, PANEL);
    for (row, line) in lines.iter().enumerate() {
        let top = MARGIN_PX + row as u32 * (glyph + scale);
        for (column, c) in line.chars().enumerate() {
            let code = if c.is_ascii() { c as usize } else { '?' as usize };
            let bitmap = font8x8::legacy::BASIC_LEGACY[code];
            let left = MARGIN_PX + column as u32 * glyph;
            for (y, bits) in bitmap.iter().enumerate() {
                // One quad per run of lit pixels.
                let (y0, y1) = (top + y as u32 * scale, top + (y as u32 + 1) * scale);
                for_each_run(*bits, |start, end| {
                    quad(left + start * scale, y0, left + end * scale, y1, TEXT)
                });
            }
        }
    }
    (vertices, indices)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_text_draws_nothing() {
        assert!(layout(&[], &[], 100, 100).0.is_empty());
        assert!(layout(&[String::new()], &[], 100, 100).0.is_empty());
    }

    #[test]
    fn letters_are_runs_of_font_pixels_inside_a_panel_in_the_top_left_corner() {
        let (v, i) = layout(&["I".to_owned()], &[], 200, 100);
        assert_eq!(i.len() % 6, 0);
        assert_eq!(v.len() / 4 * 6, i.len());
        // The panel, then the letter's runs: font8x8's `I` has 7 lit rows.
        let runs = v.len() / 4 - 1;
        assert_eq!(runs, 7, "one run per lit row of I");
        for p in &v {
            assert!(
                p.position[0] >= -1.0
                    && p.position[0] <= 1.0
                    && p.position[1] >= -1.0
                    && p.position[1] <= 1.0
            );
            assert!(p.position[0] < 0.0 && p.position[1] < 0.0, "top-left (y down): {:?}", p.position);
        }
        // Text pixels are `scale` screen pixels apart on the grid.
        let (v2, _) = layout(&["I".to_owned()], &[], 1400, 100);
        let px = |x: f32| ((x + 1.0) * 700.0).round() as u32;
        for quad in v2[4..].chunks(4) {
            assert_eq!((px(quad[1].position[0]) - px(quad[0].position[0])) % scale_for(1400), 0);
        }
        assert_eq!(scale_for(1400), 2);
        assert_eq!(scale_for(200), 1);
    }

    #[test]
    fn lines_wider_than_the_image_are_broken_at_spaces() {
        let line = "over the parallax budget: -0.98 to 1.54 deg".to_owned();
        assert_eq!(
            wrapped(std::slice::from_ref(&line), 20),
            ["over the parallax", "budget: -0.98 to", "1.54 deg"]
        );
        assert_eq!(wrapped(&["abcdefghij".to_owned()], 4), ["abcd", "efgh", "ij"]);
        assert_eq!(wrapped(&["short".to_owned()], 40), ["short"]);
        // Every quad inside a 160-pixel image (one eye of a 320-pixel side-by-side window).
        let (v, _) = layout(&[line], &[], 160, 120);
        assert!(v.iter().all(|p| p.position[0] <= 1.0), "nothing beyond the right edge");
    }

    #[test]
    fn non_ascii_shows_as_a_question_mark() {
        assert_eq!(layout(&["é".to_owned()], &[], 64, 64), layout(&["?".to_owned()], &[], 64, 64));
    }
}
