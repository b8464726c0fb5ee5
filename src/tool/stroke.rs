//! Strokes: a tool dragged along a path leaves stamps at regular arc-length spacing.

use super::stamp::{stamp_sphere, Action};
use crate::field::{Colour, Field};
use crate::math::Vec3;

/// A sculpting tool: a band-limited sphere with an action and a colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tool {
    /// Radius in metres.
    pub radius_m: f32,
    /// What it does to the clay.
    pub action: Action,
    /// Linear RGBA of the matter it adds.
    pub colour: Colour,
    /// Distance between stamps along a stroke, as a fraction of the radius.
    pub spacing: f32,
}

/// A stroke in progress: remembers where the last stamp fell so that stamps stay evenly
/// spaced whatever the frame or simulation rate.
#[derive(Clone, Debug)]
pub struct Stroke {
    tool: Tool,
    last_stamp_m: Option<Vec3>,
    stamps: usize,
}

impl Stroke {
    /// Starts a stroke; nothing is stamped until the first [`Stroke::move_to`].
    pub fn new(tool: Tool) -> Self {
        Self { tool, last_stamp_m: None, stamps: 0 }
    }

    /// The stroke's tool.
    pub fn tool(&self) -> &Tool {
        &self.tool
    }

    /// Stamps made so far.
    pub fn stamp_count(&self) -> usize {
        self.stamps
    }

    /// Moves the tool to `position_m`, stamping along the straight path from the last stamp
    /// every `spacing × radius`. The first call stamps at the position itself.
    pub fn move_to(&mut self, field: &mut Field, position_m: Vec3) {
        let step = (self.tool.spacing * self.tool.radius_m).max(field.transform().voxel_size_m * 0.25);
        let Some(mut last) = self.last_stamp_m else {
            self.stamp(field, position_m);
            return;
        };
        let mut remaining = position_m - last;
        // The tolerance keeps a stamp that lands on the target despite rounding.
        while remaining.length() >= step * (1.0 - 1e-4) {
            last += remaining.normalize() * step;
            self.stamp(field, last);
            remaining = position_m - last;
        }
    }

    fn stamp(&mut self, field: &mut Field, at: Vec3) {
        stamp_sphere(field, at, self.tool.radius_m, self.tool.action, self.tool.colour);
        self.last_stamp_m = Some(at);
        self.stamps += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stamps_are_evenly_spaced_whatever_the_step_size() {
        let tool = Tool { radius_m: 0.004, action: Action::Add, colour: [1.0; 4], spacing: 0.25 };
        let mut coarse = Field::new(0.001, 0.5);
        let mut fine = Field::new(0.001, 0.5);
        let mut a = Stroke::new(tool);
        let mut b = Stroke::new(tool);
        a.move_to(&mut coarse, Vec3::ZERO);
        a.move_to(&mut coarse, Vec3::new(0.02, 0.0, 0.0));
        b.move_to(&mut fine, Vec3::ZERO);
        for i in 1..=37 {
            b.move_to(&mut fine, Vec3::new(0.02 * i as f32 / 37.0, 0.0, 0.0));
        }
        assert_eq!(a.stamp_count(), 21);
        assert_eq!(a.stamp_count(), b.stamp_count());
        assert!((coarse.mass() - fine.mass()).abs() < 1e-3 * coarse.mass());
    }
}
