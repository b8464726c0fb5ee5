//! The per-frame snapshot the renderer reads: plain values, never the live field.

use crate::math::{Mat4, Vec3, Vec4};

/// One eye's camera, ready for the GPU.
///
/// `projection` maps view space to Vulkan clip space: x right, y *down*, depth in [0, 1]
/// (near → 0). The y flip is baked in, so images read back top row first come out upright.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyeView {
    /// World → eye (view) space.
    pub view: Mat4,
    /// Eye → Vulkan clip space (off-axis for stereo).
    pub projection: Mat4,
    /// Eye position in world space, metres (for specular and reflection vectors).
    pub position_m: Vec3,
}

/// Both eyes, left then right: multiview layer 0 is the left eye, layer 1 the right eye.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StereoViews {
    /// `[left, right]`.
    pub eyes: [EyeView; 2],
}

/// A light in world space; the caller has already resolved lights attached to the viewer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// Light arriving along `direction` (pointing from the light towards the scene).
    Directional {
        /// Direction of travel of the light, world space (need not be normalised).
        direction: Vec3,
        /// Linear RGB radiance scale (colour × intensity).
        radiance: Vec3,
    },
    /// A point light with inverse-square falloff.
    Point {
        /// World position, metres.
        position_m: Vec3,
        /// Linear RGB intensity (colour × intensity), in radiance at 1 m.
        radiance: Vec3,
    },
}

/// The unit shapes a glyph is drawn with, each centred at the origin with half extents 1 (the
/// renderer makes one small closed mesh of each when it is created).
///
/// ```text
///   Sphere         Box            Cylinder          Torus { tube }
///   radius 1       [-1, 1]³       radius 1 about Y, ring radius 1 about Y (in XZ),
///                                 y in [-1, 1]      tube radius `tube`
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GlyphShape {
    /// The unit ball.
    Sphere,
    /// The box `[-1, 1]³`.
    Box,
    /// The capped cylinder of radius 1 along Y, from y = −1 to 1.
    Cylinder,
    /// The ring of radius 1 around Y, lying in the XZ plane.
    Torus {
        /// Radius of the tube, in units of the ring's radius (a tool's minor / major radius).
        tube: f32,
    },
}

/// A translucent glyph: a tool where it acts, a controller, an item of the palette. A unit
/// [`GlyphShape`] placed by `model` (which carries the size and pose).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToolGlyph {
    /// The unit shape drawn.
    pub shape: GlyphShape,
    /// Unit shape → world.
    pub model: Mat4,
    /// Linear RGBA; alpha is the opacity of the glyph.
    pub colour: Vec4,
}

impl ToolGlyph {
    /// A unit sphere placed by `model`.
    pub fn sphere(model: Mat4, colour: Vec4) -> Self {
        Self { shape: GlyphShape::Sphere, model, colour }
    }
}

/// The workspace box, drawn as a stage: only its back faces (seen from inside), as in
/// Galyean–Hughes, so it never hides the clay.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stage {
    /// Minimum corner, world metres.
    pub min_m: Vec3,
    /// Maximum corner, world metres.
    pub max_m: Vec3,
    /// Linear RGB of the stage walls.
    pub colour: Vec3,
}

/// Clay material parameters for Blinn–Phong plus environment reflection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Blinn–Phong specular exponent.
    pub shininess: f32,
    /// Specular strength in [0, 1].
    pub specular: f32,
    /// Strength of the environment reflection at normal incidence, in [0, 1]; Schlick's
    /// Fresnel raises it at grazing angles.
    pub reflectivity: f32,
    /// Strength of the diffuse (irradiance) environment lighting.
    pub ambient: f32,
}

impl Default for Material {
    fn default() -> Self {
        Self { shininess: 48.0, specular: 0.35, reflectivity: 0.08, ambient: 0.35 }
    }
}

/// Everything one stereo frame draws besides the mesh chunks the renderer already holds.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Per-eye cameras.
    pub views: StereoViews,
    /// Scene lights in world space (at most [`MAX_LIGHTS`] are used).
    pub lights: Vec<Light>,
    /// Clay material.
    pub material: Material,
    /// Tools to draw translucent, after the opaque clay; the stage marks the first
    /// two with crosshairs.
    pub tools: Vec<ToolGlyph>,
    /// Controllers and what they carry besides tools (a headset's palette): drawn like the
    /// tools, after them, and never marked on the stage.
    pub controllers: Vec<ToolGlyph>,
    /// The workspace stage, if shown.
    pub stage: Option<Stage>,
    /// Whether the environment is drawn as the background (otherwise `background` is).
    pub show_environment: bool,
    /// Linear RGB background when the environment is not drawn.
    pub background: Vec3,
    /// Heads-up display lines (ASCII), drawn at zero parallax in the top-left corner; none
    /// draws nothing.
    pub hud: Vec<String>,
    /// The panels, drawn over everything at zero parallax; none draws nothing.
    pub panel: Option<super::PanelPaint>,
    /// The strips masked on each eye's picture (over the scene, under the HUD and panels);
    /// [`FloatingWindow::NONE`] masks nothing.
    pub floating_window: crate::stereo::floating::FloatingWindow,
    /// Rectangles at zero parallax over one eye's picture or both, under the HUD's text.
    pub eye_marks: Vec<super::EyeMark>,
}

/// The number of lights the clay shader evaluates.
pub const MAX_LIGHTS: usize = 4;

/// The light surrounding the scene, from which the renderer builds its cube maps (radiance
/// for reflections and background, irradiance for diffuse ambient light).
#[derive(Clone, Debug, PartialEq)]
pub enum Environment {
    /// The built-in procedural studio: a soft key light box overhead, a warm horizon and a dark
    /// floor; needs no file.
    Studio,
    /// An equirectangular (latitude–longitude) image in linear RGB, row-major, top row looking
    /// up (+Y), the image's horizontal centre looking down −Z.
    Equirect {
        /// Width in texels (twice the height for a full sphere).
        width: u32,
        /// Height in texels.
        height: u32,
        /// `width * height` linear RGB texels.
        texels: Vec<[f32; 3]>,
    },
}
