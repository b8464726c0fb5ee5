//! How tools, controllers and a headset's palette are drawn: the glyph of a tool's own shape at
//! its pose and size, a colour per action, a controller's handle, and the palette beside the
//! hand that holds no tool.
//!
//! A tool is drawn as the renderer's glyph shape that matches it:
//!
//! | tool shape | glyph |
//! | --- | --- |
//! | sphere, ellipsoid (either falloff) | sphere scaled to its radii (the influence region) |
//! | box, rounded box | box of its half sizes (the rounding is not drawn) |
//! | cylinder | cylinder |
//! | torus | torus of the same ring and tube radii |
//! | bar (capsule along X) | cylinder along X over its whole length (flat ends) |
//! | freeform | its bounding box (the region of clay it was copied from) |
//!
//! Controllers and the palette are sized in room metres; [`XrSculptor`] takes them into the
//! scene with the sculpture's placement.
//!
//! ```text
//!   palette, seen from above the hand that holds no tool (grip frame: −Z forward, +X right)
//!
//!   symmetry undo redo recentre save quit lattice panel   buttons: BUTTON_AHEAD_M in front
//!     (▮)    (●)  (●)    (◎)    [■]  [■]    (○)   [▭]     of the grip, the tool hand pokes
//!                                                          one and pulls its trigger
//!
//!        shape   action   size bar (its length: the tool's largest extent)
//!        ( ◇ )    (●)     ══════════►  +X
//!                  ▲  PALETTE_AHEAD_M in front of the grip, PALETTE_ABOVE_M above it
//!                ┌─┴─┐
//!                │   │  handle: a slim cylinder along the grip's Z axis
//!                └───┘
//! ```
//!
//! | button | glyph | what the trigger does on it |
//! | --- | --- | --- |
//! | undo | amber ball | undoes the last stroke |
//! | redo | teal ball | redoes it |
//! | recentre | blue ring | brings the sculpture back in front of the head, at scale 1 |
//! | save | green cube | saves the sculpt |
//! | quit | red cube | saves the sculpt and ends the headset session |
//! | lattice | violet ring | opens a lattice over the active part's clay; pressed again, applies it |
//! | panel | pale slab | shows the panel above the palette, or hides it |
//!
//! The panel ([`panel_placement`]) stands on the palette like a board held in the hand: its
//! lower edge [`PANEL_ABOVE_M`] above the grip and [`PANEL_AHEAD_M`] in front of it, leaning
//! back by [`PANEL_LEAN_RAD`] so that it faces a head above and behind the hand. The tool hand
//! points at it with a ray ([`ray_glyphs`]).
//!
//! [`XrSculptor`]: super::XrSculptor

use std::f32::consts::FRAC_PI_2;

use crate::math::{Mat4, Pose, Vec3, Vec4};
use crate::render::{GlyphShape, ToolGlyph};
use crate::tool::{Action, Solid, Tool, ToolShape};

/// A controller's handle: radius and half length, room metres.
pub const HANDLE_RADIUS_M: f32 = 0.012;
/// Half the length of a controller's handle along the grip's Z axis, room metres.
pub const HANDLE_HALF_LENGTH_M: f32 = 0.055;
/// A controller's colour (linear RGB) and opacity.
pub const HANDLE_COLOUR: Vec4 = Vec4::new(0.1, 0.1, 0.12, 0.7);
/// How far in front of the grip (along its −Z) the palette is, room metres.
pub const PALETTE_AHEAD_M: f32 = 0.08;
/// How far above the grip (along its +Y) the palette is, room metres.
pub const PALETTE_ABOVE_M: f32 = 0.03;
/// Distance between the palette's items along the grip's X axis, room metres.
pub const PALETTE_STEP_M: f32 = 0.03;
/// The largest half extent of the palette's shape item, room metres.
pub const PALETTE_SHAPE_M: f32 = 0.011;
/// Radius of the palette's action swatch, room metres.
pub const PALETTE_SWATCH_M: f32 = 0.008;
/// Radius of the palette's size bar, room metres.
pub const PALETTE_BAR_RADIUS_M: f32 = 0.0025;
/// The shortest and longest size bar, room metres (its length is the tool's largest extent).
pub const PALETTE_BAR_RANGE_M: (f32, f32) = (0.004, 0.15);
/// The colour and opacity of the palette's shape and size items.
pub const PALETTE_COLOUR: Vec4 = Vec4::new(0.85, 0.85, 0.82, 0.8);

/// The colour regions are drawn in while a hand carries them, the region button's, and the
/// tool's while it is a region tool: a warm yellow.
pub const REGION_RGB: [f32; 3] = [0.95, 0.82, 0.35];

/// How far in front of the grip (along its −Z) the row of buttons is, room metres.
pub const BUTTON_AHEAD_M: f32 = 0.125;
/// Distance between two buttons along the grip's X axis, room metres.
pub const BUTTON_STEP_M: f32 = 0.035;
/// A button's radius as drawn, room metres.
pub const BUTTON_RADIUS_M: f32 = 0.01;
/// How near a button the tool hand's grip must be to point at it, room metres.
pub const BUTTON_REACH_M: f32 = 0.02;

/// The headset panel's width in the hand, room metres (its height follows its image's
/// aspect).
pub const PANEL_WIDTH_M: f32 = 0.18;
/// How far above the grip (its +Y) the panel's lower edge is, room metres.
pub const PANEL_ABOVE_M: f32 = 0.06;
/// How far in front of the grip (its −Z) the panel's lower edge is, room metres.
pub const PANEL_AHEAD_M: f32 = 0.11;
/// How far the panel leans back from upright, radians.
pub const PANEL_LEAN_RAD: f32 = 0.35;
/// The ray's radius and colour, and the radius of the dot where it meets the panel.
pub const RAY_RADIUS_M: f32 = 0.0012;
/// The ray's colour and opacity.
pub const RAY_COLOUR: Vec4 = Vec4::new(0.9, 0.95, 1.0, 0.7);
/// The dot where the ray meets the panel, radius, room metres.
pub const RAY_DOT_M: f32 = 0.003;

/// Where the panel of `size_px` pixels lies for the hand at `grip` (room): the matrix taking
/// its pixels (x right, y down, z 0) into the room. Its lower edge's middle is the point
/// [`PANEL_ABOVE_M`] above and [`PANEL_AHEAD_M`] in front of the grip; it spans
/// [`PANEL_WIDTH_M`] along the grip's X, and rises from there leaning back.
pub fn panel_placement(grip: Pose, size_px: (u32, u32)) -> Mat4 {
    let (w, h) = (size_px.0.max(1) as f32, size_px.1.max(1) as f32);
    let m_per_px = PANEL_WIDTH_M / w;
    grip.to_matrix()
        * Mat4::from_translation(Vec3::new(0.0, PANEL_ABOVE_M, -PANEL_AHEAD_M))
        * Mat4::from_rotation_x(-PANEL_LEAN_RAD)
        * Mat4::from_scale(Vec3::new(m_per_px, -m_per_px, 1.0))
        * Mat4::from_translation(Vec3::new(-0.5 * w, -h, 0.0))
}

/// Where a ray from `from` along `direction` (room) meets the panel placed by `placement` (see
/// [`panel_placement`]) of `size_px` pixels, within `reach_m`: the pixel it meets and the
/// point in the room. `None` when it misses the panel or runs along it.
pub fn ray_on_panel(
    placement: Mat4,
    size_px: (u32, u32),
    from: Vec3,
    direction: Vec3,
    reach_m: f32,
) -> Option<([f32; 2], Vec3)> {
    let direction = direction.try_normalize()?;
    let to_panel = placement.inverse();
    let (o, d) = (to_panel.transform_point3(from), to_panel.transform_vector3(direction));
    if d.z.abs() < 1e-12 {
        return None;
    }
    // Room metres along the ray: the panel's matrix is affine, so its parameter is the room's.
    let t = -o.z / d.z;
    let px = o + t * d;
    let inside = (0.0..size_px.0 as f32).contains(&px.x) && (0.0..size_px.1 as f32).contains(&px.y);
    (t >= 0.0 && t <= reach_m && inside && px.is_finite()).then(|| ([px.x, px.y], from + t * direction))
}

/// The ray from `from` to `to` (room) as a thin cylinder, with a dot where it ends.
pub fn ray_glyphs(from: Vec3, to: Vec3) -> [ToolGlyph; 2] {
    let along = to - from;
    let length = along.length();
    let turn = crate::math::Quat::from_rotation_arc(Vec3::Y, along.try_normalize().unwrap_or(Vec3::Y));
    let ray = ToolGlyph {
        shape: GlyphShape::Cylinder,
        model: Mat4::from_rotation_translation(turn, from + 0.5 * along)
            * Mat4::from_scale(Vec3::new(RAY_RADIUS_M, 0.5 * length, RAY_RADIUS_M)),
        colour: RAY_COLOUR,
    };
    let dot = ToolGlyph::sphere(
        Mat4::from_translation(to) * Mat4::from_scale(Vec3::splat(RAY_DOT_M)),
        RAY_COLOUR.truncate().extend(1.0),
    );
    [ray, dot]
}

/// A button of the headset's palette.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Button {
    /// Undo the last stroke.
    Undo,
    /// Redo it.
    Redo,
    /// Bring the sculpture back in front of the head.
    Recentre,
    /// Save the sculpt.
    Save,
    /// Save and end the headset session.
    Quit,
    /// Step the symmetry: off, mirror X, mirror X and Z, radial 6, kaleidoscope, off.
    Symmetry,
    /// Open a lattice over the active part's clay; with one open, apply it.
    Lattice,
    /// Show the panel, or hide it.
    Panel,
    /// Step the tool hand's region tool: move, copy, bend, inflate, deflate, then sculpting.
    Region,
}

impl Button {
    /// The buttons in their row, from the grip's −X to its +X.
    pub const ALL: [Button; 9] = [
        Button::Symmetry,
        Button::Undo,
        Button::Redo,
        Button::Recentre,
        Button::Save,
        Button::Quit,
        Button::Lattice,
        Button::Panel,
        Button::Region,
    ];

    /// What the button is called.
    pub fn name(self) -> &'static str {
        match self {
            Button::Undo => "undo",
            Button::Redo => "redo",
            Button::Recentre => "recentre",
            Button::Save => "save",
            Button::Quit => "quit",
            Button::Symmetry => "symmetry",
            Button::Lattice => "lattice",
            Button::Panel => "panel",
            Button::Region => "region",
        }
    }

    /// The button's centre in the room for the palette of the hand at `grip`.
    pub fn centre(self, grip: Pose) -> Vec3 {
        let i = Button::ALL.iter().position(|b| *b == self).unwrap_or(0) as f32;
        let x = (i - 0.5 * (Button::ALL.len() - 1) as f32) * BUTTON_STEP_M;
        grip.position_m + grip.rotation * Vec3::new(x, PALETTE_ABOVE_M, -BUTTON_AHEAD_M)
    }

    /// The button the point `p` (room) is on, for the palette of the hand at `grip`.
    pub fn at(grip: Pose, p: Vec3) -> Option<Button> {
        Button::ALL
            .into_iter()
            .map(|b| (b, b.centre(grip).distance(p)))
            .filter(|(_, d)| *d <= BUTTON_REACH_M)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(b, _)| b)
    }

    /// The button's glyph for the palette of the hand at `grip`; the button pointed at is
    /// drawn larger and opaque.
    pub fn glyph(self, grip: Pose, pointed: bool) -> ToolGlyph {
        let (shape, rgb) = match self {
            Button::Undo => (GlyphShape::Sphere, [0.95, 0.65, 0.2]),
            Button::Redo => (GlyphShape::Sphere, [0.2, 0.8, 0.7]),
            Button::Recentre => (GlyphShape::Torus { tube: 0.35 }, [0.3, 0.5, 1.0]),
            Button::Save => (GlyphShape::Box, [0.3, 0.85, 0.35]),
            Button::Quit => (GlyphShape::Box, [0.9, 0.2, 0.2]),
            Button::Symmetry => (GlyphShape::Cylinder, [0.45, 0.7, 1.0]),
            Button::Lattice => (GlyphShape::Torus { tube: 0.2 }, [0.7, 0.45, 0.95]),
            Button::Panel => (GlyphShape::Box, [0.85, 0.87, 0.92]),
            // The colour carried regions are drawn in.
            Button::Region => (GlyphShape::Box, REGION_RGB),
        };
        let (size, opacity) = if pointed { (1.3 * BUTTON_RADIUS_M, 1.0) } else { (BUTTON_RADIUS_M, 0.75) };
        // The ring faces the viewer: its axis along the grip's Z.
        let turn = match shape {
            GlyphShape::Torus { .. } => Mat4::from_rotation_x(FRAC_PI_2),
            _ => Mat4::IDENTITY,
        };
        let at = Pose { position_m: self.centre(grip), rotation: grip.rotation };
        let half = match self {
            // A slab, as the panel is.
            Button::Panel => Vec3::new(0.8 * size, size, 0.25 * size),
            _ if shape == GlyphShape::Box => Vec3::splat(0.8 * size),
            _ => Vec3::splat(size),
        };
        ToolGlyph {
            shape,
            model: at.to_matrix() * turn * Mat4::from_scale(half),
            colour: Vec3::from(rgb).extend(opacity),
        }
    }
}

/// The palette's buttons for the hand at `grip`, `pointed` drawn as pointed at.
pub fn buttons(grip: Pose, pointed: Option<Button>) -> [ToolGlyph; Button::ALL.len()] {
    Button::ALL.map(|b| b.glyph(grip, pointed == Some(b)))
}

/// The glyph of a tool of `shape` scaled by `scale` along its local axes at `pose` (see the
/// module's table), in `colour`.
pub fn tool_glyph(shape: &ToolShape, pose: Pose, scale: Vec3, colour: Vec4) -> ToolGlyph {
    let placed =
        |glyph: GlyphShape, local: Mat4| ToolGlyph { shape: glyph, model: pose.to_matrix() * local, colour };
    let half = shape.half_extents_m() * scale;
    match shape {
        ToolShape::Solid(Solid::Sphere { .. }) | ToolShape::Ellipsoid(_) => {
            placed(GlyphShape::Sphere, Mat4::from_scale(half))
        }
        ToolShape::Solid(Solid::Box { .. } | Solid::RoundedBox { .. }) | ToolShape::Freeform(_) => {
            placed(GlyphShape::Box, Mat4::from_scale(half))
        }
        ToolShape::Solid(Solid::Cylinder { .. }) => placed(GlyphShape::Cylinder, Mat4::from_scale(half)),
        ToolShape::Solid(Solid::Torus { major_m, minor_m }) => placed(
            GlyphShape::Torus { tube: minor_m / major_m.max(f32::MIN_POSITIVE) },
            Mat4::from_scale(scale * *major_m),
        ),
        // The unit cylinder turned from Y onto X, then stretched to the bar's half sizes.
        ToolShape::Solid(Solid::Bar { .. }) => {
            placed(GlyphShape::Cylinder, Mat4::from_scale(half) * Mat4::from_rotation_z(-FRAC_PI_2))
        }
    }
}

/// How a lattice is drawn (ESM §4.1): each control point a sphere coloured by its function
/// value ([`value_colour`]), its radius growing with its NURBS weight (`w^⅓`), a weight above 1
/// marked with a "+" and one below with a "−" (thin bars across the sphere); and the lines
/// between neighbouring control points.
pub fn lattice_glyphs(volume: &crate::spline::SplineVolume, iso: f64) -> Vec<ToolGlyph> {
    let counts = volume.counts();
    let radius = control_radius(volume);
    let line = 0.12 * radius;
    let mut glyphs = Vec::with_capacity(4 * volume.controls().len());
    let at = |i: usize, j: usize, k: usize| volume.controls()[i + counts[0] * (j + counts[1] * k)];
    for k in 0..counts[2] {
        for j in 0..counts[1] {
            for i in 0..counts[0] {
                let c = at(i, j, k);
                let r = radius * weight_size(c.weight);
                let place = Mat4::from_translation(c.position_m);
                glyphs.push(ToolGlyph::sphere(
                    place * Mat4::from_scale(Vec3::splat(r)),
                    value_colour(c.value, iso).extend(0.9),
                ));
                if c.weight != 1.0 {
                    let bar = |half: Vec3| ToolGlyph {
                        shape: GlyphShape::Box,
                        model: place * Mat4::from_scale(half),
                        colour: Vec4::new(0.05, 0.05, 0.05, 1.0),
                    };
                    glyphs.push(bar(Vec3::new(1.3 * r, 0.15 * r, 0.15 * r)));
                    if c.weight > 1.0 {
                        glyphs.push(bar(Vec3::new(0.15 * r, 1.3 * r, 0.15 * r)));
                    }
                }
                for (a, next) in [
                    (i + 1 < counts[0], (i + 1, j, k)),
                    (j + 1 < counts[1], (i, j + 1, k)),
                    (k + 1 < counts[2], (i, j, k + 1)),
                ] {
                    if a {
                        let n = at(next.0, next.1, next.2).position_m;
                        glyphs.push(segment(c.position_m, n, line, Vec4::new(0.8, 0.8, 0.85, 0.6)));
                    }
                }
            }
        }
    }
    glyphs
}

/// The radius of a lattice's control spheres of weight 1, metres: an eighth of the nearest
/// controls' spacing, at most a centimetre.
pub fn control_radius(volume: &crate::spline::SplineVolume) -> f32 {
    let counts = volume.counts();
    let spacing = (0..3)
        .map(|a| volume.region().size()[a] / (counts[a].max(2) - 1) as f32)
        .fold(f32::INFINITY, f32::min);
    (0.12 * spacing).min(0.01)
}

/// How much a NURBS weight scales its control's sphere (its cube root, within 0.3 to 3).
pub fn weight_size(weight: f64) -> f32 {
    (weight as f32).cbrt().clamp(0.3, 3.0)
}

/// The colour of a lattice slice's zero contour: a bright red, as ESM's Fig. 5 draws it.
pub const CONTOUR_COLOUR: Vec4 = Vec4::new(1.0, 0.12, 0.08, 1.0);

/// How a slice of a lattice is drawn (ESM §4.2): the `l × m` patch of controls `k` each with a
/// stem along the patch's normal (the rest box's Z) as long as its value's distance from the
/// iso-level (a quarter of the controls' spacing per unit, up for full, down for empty) in
/// its value's colour, and the function's zero contour on the slice (`F = iso`) in red.
pub fn lattice_slice_glyphs(volume: &crate::spline::SplineVolume, k: usize, iso: f64) -> Vec<ToolGlyph> {
    let [l, m, n] = volume.counts();
    let radius = control_radius(volume);
    let length = 0.25 * (volume.region().size().z / (n.max(2) - 1) as f32);
    let mut glyphs = Vec::with_capacity(l * m);
    for j in 0..m {
        for i in 0..l {
            let Ok(c) = volume.control(i, j, k.min(n - 1)) else { continue };
            let tip = c.position_m + Vec3::Z * ((c.value - iso) as f32 * length);
            glyphs.push(segment(c.position_m, tip, 0.25 * radius, value_colour(c.value, iso).extend(0.9)));
        }
    }
    let w = volume.slice_w(k);
    glyphs.extend(
        volume
            .slice_contour(w, iso, crate::spline::SLICE_SAMPLES)
            .into_iter()
            .map(|[a, b]| segment(a, b, 0.4 * radius, CONTOUR_COLOUR)),
    );
    glyphs
}

/// The colour of the symmetry's planes and axis: a faint cool blue.
pub const SYMMETRY_COLOUR: Vec4 = Vec4::new(0.45, 0.7, 1.0, 0.14);

/// The glyphs of a symmetry over the world box `around`: each mirror plane as a thin square
/// through the symmetry's centre spanning the box, the radial axis as a line through it.
pub fn symmetry_glyphs(symmetry: &crate::parts::Symmetry, around: crate::math::Aabb) -> Vec<ToolGlyph> {
    let half = 0.5 * around.size().max_element().max(1e-3);
    // The square lies where the box is, moved onto the plane.
    let mut glyphs = Vec::new();
    for (point, normal) in symmetry.planes() {
        let middle = around.centre() - normal * normal.dot(around.centre() - point);
        let turn = crate::math::Quat::from_rotation_arc(Vec3::Z, normal);
        let model = Mat4::from_scale_rotation_translation(Vec3::new(half, half, 0.002 * half), turn, middle);
        glyphs.push(ToolGlyph { shape: GlyphShape::Box, model, colour: SYMMETRY_COLOUR });
    }
    if let Some((point, axis)) = symmetry.radial_axis() {
        let middle = point + axis * axis.dot(around.centre() - point);
        let colour = SYMMETRY_COLOUR.truncate().extend(0.5);
        glyphs.push(segment(middle - axis * 1.2 * half, middle + axis * 1.2 * half, 0.006 * half, colour));
    }
    glyphs
}

/// A thin cylinder of `radius` from `a` to `b`.
pub fn segment(a: Vec3, b: Vec3, radius: f32, colour: Vec4) -> ToolGlyph {
    let d = b - a;
    let len = d.length();
    let turn = if len > 0.0 {
        crate::math::Quat::from_rotation_arc(Vec3::Y, d / len)
    } else {
        crate::math::Quat::IDENTITY
    };
    let model =
        Mat4::from_scale_rotation_translation(Vec3::new(radius, 0.5 * len, radius), turn, 0.5 * (a + b));
    ToolGlyph { shape: GlyphShape::Cylinder, model, colour }
}

/// The colour scale of control values (linear RGB): blue for empty (0), white at the
/// iso-level, the clay's terracotta for full (1), saturated beyond the ends.
pub fn value_colour(value: f64, iso: f64) -> Vec3 {
    let (empty, surface, full) = (Vec3::new(0.1, 0.3, 1.0), Vec3::splat(0.95), Vec3::new(0.85, 0.3, 0.08));
    if value <= iso {
        let t = (value / iso.max(1e-6)).clamp(0.0, 1.0) as f32;
        empty.lerp(surface, t)
    } else {
        let t = ((value - iso) / (1.0 - iso).max(1e-6)).clamp(0.0, 1.0) as f32;
        surface.lerp(full, t)
    }
}

/// The colour (linear RGB) a headset shows an action in: on the tool and on the palette.
pub fn action_colour(action: &Action) -> Vec3 {
    let rgb = match action {
        Action::Add => [0.25, 0.8, 0.3],
        Action::Remove => [0.9, 0.2, 0.15],
        Action::SoftRemove { .. } => [0.95, 0.5, 0.1],
        Action::Build { .. } => [0.2, 0.75, 0.75],
        Action::Paint => [0.85, 0.3, 0.9],
        Action::SoftPaint { .. } => [0.95, 0.6, 0.8],
        Action::Smooth { .. } => [0.35, 0.55, 1.0],
        Action::Stamp { .. } => [0.95, 0.85, 0.2],
        Action::Inflate { .. } => [0.65, 1.0, 0.45],
        Action::Deflate { .. } => [0.5, 0.3, 0.8],
        Action::Push => [0.9, 0.9, 0.95],
        Action::Support => [0.45, 0.5, 0.6],
    };
    Vec3::from(rgb)
}

/// A controller held at `grip` (room): its handle, a slim cylinder along the grip's Z axis
/// (OpenXR's grip space runs −Z forward through the closed hand), centred on the grip.
pub fn controller_glyph(grip: Pose) -> ToolGlyph {
    let along_z = Mat4::from_rotation_x(FRAC_PI_2);
    let size = Vec3::new(HANDLE_RADIUS_M, HANDLE_HALF_LENGTH_M, HANDLE_RADIUS_M);
    ToolGlyph {
        shape: GlyphShape::Cylinder,
        model: grip.to_matrix() * along_z * Mat4::from_scale(size),
        colour: HANDLE_COLOUR,
    }
}

/// The palette beside the hand at `grip` (room) for the tool the other hand holds, `tool`
/// (room sizes): `[shape, action, size]`, in a row along the grip's X axis in front of the
/// controller. The shape item is the tool's own shape shrunk to [`PALETTE_SHAPE_M`], the
/// action item a ball in [`action_colour`], the size item a bar along X as long as the tool's
/// largest extent (clamped to [`PALETTE_BAR_RANGE_M`]).
pub fn palette(grip: Pose, tool: &Tool) -> [ToolGlyph; 3] {
    let slot = |x: f32| Pose {
        position_m: grip.position_m + grip.rotation * Vec3::new(x, PALETTE_ABOVE_M, -PALETTE_AHEAD_M),
        rotation: grip.rotation,
    };
    let largest = tool.half_extents_m().max_element().max(f32::MIN_POSITIVE);
    let shape = tool_glyph(
        &tool.shape,
        slot(-PALETTE_STEP_M),
        tool.scale * (PALETTE_SHAPE_M / largest),
        PALETTE_COLOUR,
    );
    let swatch = ToolGlyph::sphere(
        slot(0.0).to_matrix() * Mat4::from_scale(Vec3::splat(PALETTE_SWATCH_M)),
        action_colour(&tool.action).extend(0.9),
    );
    let (shortest, longest) = PALETTE_BAR_RANGE_M;
    let length = (2.0 * largest).clamp(shortest, longest);
    let bar = ToolGlyph {
        shape: GlyphShape::Cylinder,
        model: slot(PALETTE_STEP_M + 0.5 * length).to_matrix()
            * Mat4::from_rotation_z(-FRAC_PI_2)
            * Mat4::from_scale(Vec3::new(PALETTE_BAR_RADIUS_M, 0.5 * length, PALETTE_BAR_RADIUS_M)),
        colour: PALETTE_COLOUR,
    };
    [shape, swatch, bar]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Quat;
    use crate::tool::{Ellipsoid, Falloff};

    fn at(x: f32) -> Pose {
        Pose { position_m: Vec3::new(x, 0.0, 0.0), rotation: Quat::from_rotation_y(0.4) }
    }

    /// Where the glyph takes a local point of its unit shape.
    fn local(g: &ToolGlyph, p: Vec3) -> Vec3 {
        g.model.transform_point3(p)
    }

    #[test]
    fn each_button_is_found_where_it_is_drawn_and_only_there() {
        let grip = at(0.3);
        for b in Button::ALL {
            let g = b.glyph(grip, false);
            let centre = g.model.w_axis.truncate();
            assert!(centre.distance(b.centre(grip)) < 1e-6, "{}", b.name());
            assert_eq!(Button::at(grip, centre), Some(b));
            let beside = centre + grip.rotation * Vec3::new(0.0, BUTTON_REACH_M + 1e-3, 0.0);
            assert_eq!(Button::at(grip, beside), None, "{} reaches too far", b.name());
            // In front of the palette's first row, clear of the size bar.
            let local = grip.rotation.inverse() * (centre - grip.position_m);
            assert!(local.z < -PALETTE_AHEAD_M - 2.0 * BUTTON_REACH_M, "{local}");
        }
        let pointed = buttons(grip, Some(Button::Save));
        let save = Button::ALL.iter().position(|b| *b == Button::Save).unwrap();
        assert_eq!(pointed[save].colour.w, 1.0);
        assert!(pointed.iter().filter(|g| g.colour.w < 1.0).count() == Button::ALL.len() - 1);
        // Between two buttons, the nearer one is pointed at.
        let between = Button::Undo.centre(grip).lerp(Button::Redo.centre(grip), 0.4);
        assert_eq!(Button::at(grip, between), Some(Button::Undo));
    }

    #[test]
    fn each_tool_shape_is_drawn_as_its_own_shape_and_size() {
        let white = Vec4::ONE;
        let scale = Vec3::new(1.0, 2.0, 1.0);
        let pose = at(0.1);
        let world = |p: Vec3| pose.position_m + pose.rotation * p;
        let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-6;

        let sphere = tool_glyph(&ToolShape::sphere(0.01), pose, scale, white);
        assert_eq!(sphere.shape, GlyphShape::Sphere);
        assert_eq!(
            sphere.model,
            pose.to_matrix() * Mat4::from_scale(Vec3::new(0.01, 0.02, 0.01)),
            "as before"
        );

        let cube = ToolShape::Solid(Solid::Box { half_m: Vec3::new(0.01, 0.02, 0.03) });
        let g = tool_glyph(&cube, pose, scale, white);
        assert_eq!(g.shape, GlyphShape::Box);
        assert!(close(local(&g, Vec3::ONE), world(Vec3::new(0.01, 0.04, 0.03))), "the corner");

        let cylinder = ToolShape::Solid(Solid::Cylinder { radius_m: 0.01, half_height_m: 0.03 });
        let g = tool_glyph(&cylinder, pose, scale, white);
        assert_eq!(g.shape, GlyphShape::Cylinder);
        assert!(close(local(&g, Vec3::new(1.0, 1.0, 0.0)), world(Vec3::new(0.01, 0.06, 0.0))));

        let torus = ToolShape::Solid(Solid::Torus { major_m: 0.02, minor_m: 0.005 });
        let g = tool_glyph(&torus, pose, Vec3::ONE, white);
        assert_eq!(g.shape, GlyphShape::Torus { tube: 0.25 });
        assert!(close(local(&g, Vec3::X * 1.25), world(Vec3::X * 0.025)), "the outer rim");

        let bar = ToolShape::Solid(Solid::Bar { half_length_m: 0.05, radius_m: 0.01 });
        let g = tool_glyph(&bar, pose, Vec3::ONE, white);
        assert_eq!(g.shape, GlyphShape::Cylinder);
        assert!(close(local(&g, Vec3::Y), world(Vec3::X * 0.05)), "the cylinder's axis lies along the bar");
        assert!(
            close(local(&g, Vec3::X), world(Vec3::Y * 0.01))
                || close(local(&g, Vec3::X), world(-Vec3::Y * 0.01))
        );

        let soft = ToolShape::Ellipsoid(Ellipsoid {
            radii_m: Vec3::new(0.02, 0.01, 0.01),
            falloff: Falloff::Wyvill,
        });
        let g = tool_glyph(&soft, pose, Vec3::ONE, white);
        assert_eq!(g.shape, GlyphShape::Sphere);
        assert!(close(local(&g, Vec3::X), world(Vec3::X * 0.02)), "the radii");
    }

    #[test]
    fn actions_have_distinct_colours() {
        let actions = [
            Action::Add,
            Action::Remove,
            Action::SoftRemove { rate_per_s: 1.0 },
            Action::Build { rate_per_s: 1.0 },
            Action::Paint,
            Action::SoftPaint { rate_per_s: 1.0 },
            Action::Smooth { centre_weight: 6.0, rate_per_s: 1.0 },
            Action::Inflate { speed_m_per_s: 0.01 },
            Action::Deflate { speed_m_per_s: 0.01 },
            Action::Push,
            Action::Support,
        ];
        for (i, a) in actions.iter().enumerate() {
            for b in &actions[i + 1..] {
                let d = (action_colour(a) - action_colour(b)).abs().max_element();
                assert!(d >= 0.1, "{} and {} look alike", a.name(), b.name());
            }
        }
    }

    #[test]
    fn the_handle_lies_along_the_grip_z_axis_and_the_palette_in_front_of_the_controller() {
        let grip = at(0.3);
        let h = controller_glyph(grip);
        assert_eq!(h.shape, GlyphShape::Cylinder);
        let end = h.model.transform_point3(Vec3::Y);
        let axis = grip.rotation * Vec3::Z;
        assert!((end - grip.position_m).dot(axis).abs() > HANDLE_HALF_LENGTH_M - 1e-6, "{end}");

        let tool = Tool::new(ToolShape::sphere(0.02), Action::Remove, [1.0; 4]);
        let [shape, swatch, bar] = palette(grip, &tool);
        let ahead = |g: &ToolGlyph| grip.world_to_local(g.model.w_axis.truncate());
        for g in [&shape, &swatch] {
            let p = ahead(g);
            assert!((p.z + PALETTE_AHEAD_M).abs() < 1e-6 && (p.y - PALETTE_ABOVE_M).abs() < 1e-6, "{p}");
        }
        assert!(ahead(&shape).x < ahead(&swatch).x && ahead(&swatch).x < ahead(&bar).x, "in a row along X");
        assert_eq!(swatch.colour.truncate(), action_colour(&Action::Remove));
        // The bar is as long as the tool's diameter (4 cm), along the grip's X axis.
        let (a, b) = (bar.model.transform_point3(-Vec3::Y), bar.model.transform_point3(Vec3::Y));
        let along = grip.rotation.inverse() * (b - a);
        assert!((along.length() - 0.04).abs() < 1e-6 && along.x.abs() > 0.04 - 1e-6, "{along}");
        // The shape item is the tool's shape, small.
        assert_eq!(shape.shape, GlyphShape::Sphere);
        assert!((shape.model.x_axis.truncate().length() - PALETTE_SHAPE_M).abs() < 1e-7);
        // A torus shows as a torus; a huge tool's bar stops at the longest.
        let mut ring =
            Tool::new(ToolShape::Solid(Solid::Torus { major_m: 0.02, minor_m: 0.01 }), Action::Add, [1.0; 4]);
        ring.scale = Vec3::splat(10.0);
        let [shape, _, bar] = palette(grip, &ring);
        assert_eq!(shape.shape, GlyphShape::Torus { tube: 0.5 });
        assert!((bar.model.y_axis.truncate().length() - 0.5 * PALETTE_BAR_RANGE_M.1).abs() < 1e-6);
    }
}
