//! Tools and strokes: a tool dragged along a path leaves stamps at regular arc-length spacing,
//! or, for rate actions, acts in fixed time ticks, so a stroke's result depends on the path
//! and its timing, not on how often the caller samples them.
//!
//! ```text
//!   per-stamp actions:   ●───●───●───●──▸     a stamp every spacing × size along the path
//!   rate actions:        ●─●─●─●─●─●─●──▸     an application every TICK_S of held time, at the
//!                        (faster motion → sparser)  pose interpolated at that instant
//! ```

use super::action::Action;
use super::apply::{apply_tool, apply_tool_mirrored, StampCounters};
use super::shapes::ToolShape;
use crate::field::{Colour, Field};
use crate::math::{Isometry, Pose, Vec3};

/// The time step of rate actions, seconds: they act once per tick of held time, whatever the
/// caller's frame rate. 1/120 s keeps an inflating surface well under a voxel per tick at
/// sculpting speeds (the explicit level-set step's stability limit).
pub const TICK_S: f32 = 1.0 / 120.0;

/// A sculpting tool: a shape scaled along its three axes, an action and a colour.
#[derive(Clone, Debug, PartialEq)]
pub struct Tool {
    /// Shape in its local frame.
    pub shape: ToolShape,
    /// Scale along the local X, Y and Z axes (1 keeps the shape's own size).
    pub scale: Vec3,
    /// What it does to the clay.
    pub action: Action,
    /// Linear RGBA of the matter it adds or the paint it applies.
    pub colour: Colour,
    /// Distance between stamps along a stroke, as a fraction of [`Tool::size_m`].
    pub spacing: f32,
    /// The resolution level it edits: `None`, the finest; `Some(n)`, the finest level on which
    /// its size spans at most `n` voxels (see [`super::edit_level_for`]), so that a large tool
    /// costs about what a small one does.
    pub level_samples: Option<f32>,
}

impl Tool {
    /// A tool of unit scale and the default spacing (a quarter of its size).
    pub fn new(shape: ToolShape, action: Action, colour: Colour) -> Self {
        Self { shape, scale: Vec3::ONE, action, colour, spacing: 0.25, level_samples: None }
    }

    /// The tool editing by its size with at most `samples` voxels across it (`None`: the
    /// finest level), unless it says which level it edits already.
    pub fn by_size_unless_set(mut self, samples: Option<f32>) -> Self {
        self.level_samples = self.level_samples.or(samples);
        self
    }

    /// The tool's size for stamp spacing: its smallest half extent after scaling, metres (a
    /// sphere's radius).
    pub fn size_m(&self) -> f32 {
        (self.shape.half_extents_m() * self.scale).min_element()
    }

    /// Half the size of the tool's influence box along its local axes after scaling, metres
    /// (what a glyph of the tool spans).
    pub fn half_extents_m(&self) -> Vec3 {
        self.shape.half_extents_m() * self.scale
    }
}

/// A stroke in progress: remembers where the last stamp fell and how much held time has not
/// yet been applied.
#[derive(Clone, Debug)]
pub struct Stroke {
    tool: Tool,
    /// The symmetry's images other than the identity: every stamp also acts at each.
    images: Vec<Isometry>,
    last_stamp: Option<Pose>,
    last_pose: Option<Pose>,
    since_tick_s: f64,
    stamps: usize,
    last_counters: StampCounters,
    total: StampCounters,
}

impl Stroke {
    /// Starts a stroke; nothing is applied until the first [`Stroke::advance`].
    pub fn new(tool: Tool) -> Self {
        Self {
            tool,
            images: Vec::new(),
            last_stamp: None,
            last_pose: None,
            since_tick_s: 0.0,
            stamps: 0,
            last_counters: StampCounters::default(),
            total: StampCounters::default(),
        }
    }

    /// Starts a stroke whose every stamp also acts at the images of its pose under `images`
    /// (a symmetry's images; the identity among them is the stroke itself).
    pub fn with_images(tool: Tool, images: &[Isometry]) -> Self {
        let mut stroke = Self::new(tool);
        stroke.images = images.iter().copied().filter(|i| !i.is_identity()).collect();
        stroke
    }

    /// The stroke's tool.
    pub fn tool(&self) -> &Tool {
        &self.tool
    }

    /// Changes the tool mid-stroke (a controller's trigger pressure changes a soft action's
    /// rate); the path and the time not yet applied carry on.
    pub fn set_tool(&mut self, tool: Tool) {
        self.tool = tool;
    }

    /// Stamps (or ticks) applied so far.
    pub fn stamp_count(&self) -> usize {
        self.stamps
    }

    /// The counters of the latest stamp.
    pub fn last_counters(&self) -> StampCounters {
        self.last_counters
    }

    /// The counters summed over the stroke.
    pub fn total_counters(&self) -> StampCounters {
        self.total
    }

    /// Moves the tool to `pose`, `dt_s` seconds after the previous call, along the straight
    /// path (spherical in rotation) from the previous pose.
    ///
    /// Per-stamp actions stamp every `spacing × size` of that path, the first call stamping at
    /// `pose` itself; rate actions act once per [`TICK_S`] of time since the stroke began, at
    /// the pose interpolated at that instant.
    pub fn advance(&mut self, field: &mut Field, pose: Pose, dt_s: f32) {
        if self.tool.action.is_rate_based() {
            self.advance_in_time(field, pose, dt_s);
        } else {
            self.advance_along_path(field, pose);
        }
    }

    fn advance_along_path(&mut self, field: &mut Field, pose: Pose) {
        let step = (self.tool.spacing * self.tool.size_m()).max(field.transform().voxel_size_m * 0.25);
        let Some(mut last) = self.last_stamp else {
            self.stamp(field, pose, 0.0);
            return;
        };
        let mut remaining = pose.position_m - last.position_m;
        // The tolerance keeps a stamp that lands on the target despite rounding.
        while remaining.length() >= step * (1.0 - 1e-4) {
            let u = step / remaining.length();
            last = last.lerp(&pose, u.min(1.0));
            self.stamp(field, last, 0.0);
            remaining = pose.position_m - last.position_m;
        }
    }

    fn advance_in_time(&mut self, field: &mut Field, pose: Pose, dt_s: f32) {
        let Some(from) = self.last_pose else {
            self.last_pose = Some(pose);
            return;
        };
        let dt = f64::from(dt_s.max(0.0));
        let tick = f64::from(TICK_S);
        // Time into this interval of the next tick; a tick within a microsecond of the
        // interval's end belongs to it, so rounding in the callers' sums of time never moves a
        // tick from one call to the next.
        let mut t = tick - self.since_tick_s;
        while t <= dt + 1e-6 {
            let u = (t / dt).min(1.0) as f32;
            self.stamp(field, from.lerp(&pose, u), TICK_S);
            t += tick;
        }
        self.since_tick_s = (dt - (t - tick)).max(0.0);
        self.last_pose = Some(pose);
    }

    fn stamp(&mut self, field: &mut Field, at: Pose, dt_s: f32) {
        let mut c = apply_tool(field, &self.tool, at, dt_s);
        for image in &self.images {
            let (pose, mirrored) = image.pose(&at);
            c += apply_tool_mirrored(field, &self.tool, pose, mirrored, dt_s);
        }
        self.last_counters = c;
        self.total += c;
        self.last_stamp = Some(at);
        self.stamps += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(x: f32) -> Pose {
        Pose { position_m: Vec3::new(x, 0.0, 0.0), ..Pose::default() }
    }

    #[test]
    fn stamps_are_evenly_spaced_whatever_the_step_size() {
        let tool = Tool { spacing: 0.25, ..Tool::new(ToolShape::sphere(0.004), Action::Add, [1.0; 4]) };
        let mut coarse = Field::new(0.001, 0.5);
        let mut fine = Field::new(0.001, 0.5);
        let mut a = Stroke::new(tool.clone());
        let mut b = Stroke::new(tool);
        a.advance(&mut coarse, at(0.0), 0.0);
        a.advance(&mut coarse, at(0.02), 1.0);
        b.advance(&mut fine, at(0.0), 0.0);
        for i in 1..=37 {
            b.advance(&mut fine, at(0.02 * i as f32 / 37.0), 1.0 / 37.0);
        }
        assert_eq!(a.stamp_count(), 21);
        assert_eq!(a.stamp_count(), b.stamp_count());
        assert!((coarse.mass() - fine.mass()).abs() < 1e-3 * coarse.mass());
    }

    #[test]
    fn rate_actions_act_once_per_tick_of_held_time() {
        let tool = Tool::new(ToolShape::sphere(0.004), Action::Build { rate_per_s: 0.5 }, [1.0; 4]);
        let mut f = Field::new(0.001, 0.5);
        let mut s = Stroke::new(tool);
        s.advance(&mut f, at(0.0), 0.0);
        // Held still for one second in uneven frames: 120 ticks, half the density at the core.
        for dt in [0.3, 0.013, 0.2, 0.187, 0.3] {
            s.advance(&mut f, at(0.0), dt);
        }
        assert_eq!(s.stamp_count(), 120);
        // Each tick's density is stored to the nearest step: the error adds up over the ticks.
        let tolerance = 120.0 * crate::field::DENSITY_TOLERANCE;
        assert!((f.density(crate::math::IVec3::ZERO) - 0.5).abs() < tolerance);
        let c = s.total_counters();
        assert!(c.visited >= c.computed && c.computed >= c.dirtied && c.dirtied > 0 && c.bricks > 0);
    }
}
