//! Mirror and radial symmetry: the images a tool acts at.
//!
//! ```text
//!   mirror X:        radial 3 about Y:      mirror X + radial 3 (kaleidoscope):
//!     ●  |  ●             ●                      ● ●
//!        |             ●  +  ●                 ●  +  ●
//!                                                 ● ●        (the dihedral group, 6 images)
//! ```
//!
//! The images are every product of a rotation `R_k` (by `2πk/N` about the axis) and a
//! mirror `M_S` (the product of the chosen planes' reflections), with duplicates removed: a
//! mirror plane perpendicular to the axis and N rotations give 2N images, as do N rotations
//! and a plane containing the axis. A mirrored stroke lands on the field's lattice mirrored
//! when the plane passes through lattice points, as the origin of the default frame does.

use crate::math::{Isometry, Pose, Vec3};

/// The most radial copies about the axis.
pub const MAX_RADIAL: u32 = 64;
/// The most images a symmetry can have: radial copies × the 8 products of three mirrors.
pub const MAX_IMAGES: usize = MAX_RADIAL as usize * 8;

/// One of the symmetry frame's axes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Axis {
    /// X.
    X,
    /// Y (up in the default frame).
    #[default]
    Y,
    /// Z.
    Z,
}

impl Axis {
    /// The three, in order.
    pub const ALL: [Axis; 3] = [Axis::X, Axis::Y, Axis::Z];

    /// Its unit vector in the frame.
    pub fn unit(self) -> Vec3 {
        match self {
            Axis::X => Vec3::X,
            Axis::Y => Vec3::Y,
            Axis::Z => Vec3::Z,
        }
    }

    /// Its name, as scene files write it.
    pub fn name(self) -> &'static str {
        match self {
            Axis::X => "x",
            Axis::Y => "y",
            Axis::Z => "z",
        }
    }

    /// The axis a scene file's name stands for.
    pub fn from_name(name: &str) -> Option<Axis> {
        Axis::ALL.into_iter().find(|a| a.name().eq_ignore_ascii_case(name))
    }
}

/// Mirror planes and radial copies in a frame of the sculpt.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Symmetry {
    /// The frame: its origin lies on every plane and on the radial axis.
    pub frame: Pose,
    /// Mirror across the plane normal to the frame's X, Y, Z axis.
    pub mirror: [bool; 3],
    /// Copies about the radial axis, the original included (1: none).
    pub radial: u32,
    /// The axis of the radial copies.
    pub axis: Axis,
}

impl Default for Symmetry {
    fn default() -> Self {
        Self::NONE
    }
}

impl Symmetry {
    /// No symmetry: the tool acts once.
    pub const NONE: Symmetry = Symmetry {
        frame: Pose { position_m: Vec3::ZERO, rotation: crate::math::Quat::IDENTITY },
        mirror: [false; 3],
        radial: 1,
        axis: Axis::Y,
    };

    /// Mirror across the plane normal to `axis` through the frame's origin.
    pub fn mirror(axis: Axis) -> Symmetry {
        let mut s = Symmetry::NONE;
        s.mirror[axis as usize] = true;
        s
    }

    /// `count` copies about `axis` (clamped to 1..=[`MAX_RADIAL`]).
    pub fn radial(count: u32, axis: Axis) -> Symmetry {
        Symmetry { radial: count.clamp(1, MAX_RADIAL), axis, ..Symmetry::NONE }
    }

    /// The same symmetry in another frame.
    pub fn in_frame(self, frame: Pose) -> Symmetry {
        Symmetry { frame, ..self }
    }

    /// Whether the tool acts once only.
    pub fn is_none(&self) -> bool {
        self.radial <= 1 && !self.mirror.iter().any(|&m| m)
    }

    /// The mirror planes in the world: (a point on it, its unit normal).
    pub fn planes(&self) -> Vec<(Vec3, Vec3)> {
        Axis::ALL
            .into_iter()
            .filter(|a| self.mirror[*a as usize])
            .map(|a| (self.frame.position_m, self.frame.rotation * a.unit()))
            .collect()
    }

    /// The radial axis in the world (a point on it, its unit direction), when there are copies.
    pub fn radial_axis(&self) -> Option<(Vec3, Vec3)> {
        (self.radial > 1).then(|| (self.frame.position_m, self.frame.rotation * self.axis.unit()))
    }

    /// Every image, the identity first, each once.
    pub fn images(&self) -> Vec<Isometry> {
        let mut mirrors = vec![Isometry::IDENTITY];
        for (point, normal) in self.planes() {
            let m = Isometry::reflection(point, normal);
            let more: Vec<Isometry> = mirrors.iter().map(|i| m.after(i)).collect();
            mirrors.extend(more);
        }
        let radial = self.radial.clamp(1, MAX_RADIAL);
        let mut images: Vec<Isometry> = Vec::with_capacity(mirrors.len() * radial as usize);
        for k in 0..radial {
            let angle = std::f32::consts::TAU * k as f32 / radial as f32;
            let r = match self.radial_axis() {
                Some((point, axis)) => Isometry::rotation_about(point, axis, angle),
                None => Isometry::IDENTITY,
            };
            for m in &mirrors {
                let image = r.after(m);
                if !images.iter().any(|i| i.distance(&image) < 1e-4) {
                    images.push(image);
                }
            }
        }
        images
    }

    /// What it is, for messages and the panel: "off", "mirror x", "radial 6 about y", ...
    pub fn describe(&self) -> String {
        if self.is_none() {
            return "off".into();
        }
        let mut parts = Vec::new();
        let planes: Vec<&str> =
            Axis::ALL.into_iter().filter(|a| self.mirror[*a as usize]).map(Axis::name).collect();
        if !planes.is_empty() {
            parts.push(format!("mirror {}", planes.join("+")));
        }
        if self.radial > 1 {
            parts.push(format!("radial {} about {}", self.radial, self.axis.name()));
        }
        parts.join(", ")
    }

    /// The symmetries the station's key and the headset's button step through, after the
    /// scene's own: off, mirror X, mirror X and Z, radial 6 about Y, and mirror X with
    /// radial 6 (a kaleidoscope), all in `frame`.
    pub fn cycle(frame: Pose) -> [Symmetry; 5] {
        let mut xz = Symmetry::mirror(Axis::X);
        xz.mirror[Axis::Z as usize] = true;
        let mut kaleidoscope = Symmetry::radial(6, Axis::Y);
        kaleidoscope.mirror[Axis::X as usize] = true;
        [Symmetry::NONE, Symmetry::mirror(Axis::X), xz, Symmetry::radial(6, Axis::Y), kaleidoscope]
            .map(|s| s.in_frame(frame))
    }
}

/// The symmetry a station acts through, switched on and off and stepped through its choices
/// (a key at the desk, a button in the headset): the scene's own symmetry first, then
/// [`Symmetry::cycle`]'s, in the scene symmetry's frame.
#[derive(Clone, Debug, PartialEq)]
pub struct SymmetrySwitch {
    choices: Vec<Symmetry>,
    index: usize,
    on: bool,
}

impl SymmetrySwitch {
    /// The switch for a scene whose symmetry is `scene`: on when the scene has one.
    pub fn new(scene: Symmetry) -> Self {
        let mut choices: Vec<Symmetry> = Vec::new();
        for s in std::iter::once(scene).chain(Symmetry::cycle(scene.frame)) {
            if !s.is_none() && !choices.contains(&s) {
                choices.push(s);
            }
        }
        Self { choices, index: 0, on: !scene.is_none() }
    }

    /// The symmetry in force.
    pub fn current(&self) -> Symmetry {
        match self.on {
            true => self.choices[self.index],
            false => Symmetry { frame: self.choices[self.index].frame, ..Symmetry::NONE },
        }
    }

    /// Switches the chosen symmetry on or off; returns the symmetry now in force.
    pub fn toggle(&mut self) -> Symmetry {
        self.on = !self.on;
        self.current()
    }

    /// One button for all: off → the first choice → each next one → off again.
    pub fn step(&mut self) -> Symmetry {
        match (self.on, self.index + 1 < self.choices.len()) {
            (false, _) => {
                self.on = true;
                self.index = 0;
            }
            (true, true) => self.index += 1,
            (true, false) => {
                self.on = false;
                self.index = 0;
            }
        }
        self.current()
    }

    /// The next choice, switched on (the chosen one itself when it was off).
    pub fn next_choice(&mut self) -> Symmetry {
        if self.on {
            self.index = (self.index + 1) % self.choices.len();
        }
        self.on = true;
        self.current()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Quat;

    #[test]
    fn image_counts_are_the_groups_orders() {
        assert_eq!(Symmetry::NONE.images().len(), 1);
        assert_eq!(Symmetry::mirror(Axis::X).images().len(), 2);
        let mut three = Symmetry::mirror(Axis::X);
        three.mirror = [true; 3];
        assert_eq!(three.images().len(), 8);
        assert_eq!(Symmetry::radial(5, Axis::Y).images().len(), 5);
        // A plane containing the axis: the dihedral group. A plane across it: 2N as well.
        let mut d = Symmetry::radial(6, Axis::Y);
        d.mirror[0] = true;
        assert_eq!(d.images().len(), 12);
        let mut across = Symmetry::radial(6, Axis::Y);
        across.mirror[1] = true;
        assert_eq!(across.images().len(), 12);
        // Radial 2 about Y with mirrors X and Z: the rotation by π is their product.
        let mut klein = Symmetry::radial(2, Axis::Y);
        klein.mirror = [true, false, true];
        assert_eq!(klein.images().len(), 4);
        assert!(Symmetry::radial(1000, Axis::Z).images().len() <= MAX_IMAGES);
    }

    #[test]
    fn images_form_a_group_and_map_the_frame_to_itself() {
        let frame = Pose { position_m: Vec3::new(0.1, -0.2, 0.05), rotation: Quat::from_rotation_z(0.4) };
        let mut s = Symmetry::radial(4, Axis::X).in_frame(frame);
        s.mirror[1] = true;
        let images = s.images();
        assert_eq!(images[0], Isometry::IDENTITY);
        for a in &images {
            assert!(a.point(frame.position_m).distance(frame.position_m) < 1e-5);
            for b in &images {
                let ab = a.after(b);
                assert!(images.iter().any(|i| i.distance(&ab) < 1e-4), "not closed under composition");
            }
        }
        assert_eq!(images.iter().filter(|i| i.mirrors()).count(), images.len() / 2);
    }

    #[test]
    fn a_mirror_takes_a_point_to_its_reflection() {
        let s = Symmetry::mirror(Axis::X)
            .in_frame(Pose { position_m: Vec3::new(0.01, 0.0, 0.0), ..Pose::default() });
        let images = s.images();
        assert!(images[1].point(Vec3::new(0.05, 0.2, 0.3)).distance(Vec3::new(-0.03, 0.2, 0.3)) < 1e-6);
        assert_eq!(s.describe(), "mirror x");
        assert_eq!(Symmetry::radial(6, Axis::Y).describe(), "radial 6 about y");
        assert_eq!(Symmetry::NONE.describe(), "off");
    }

    #[test]
    fn the_switch_starts_with_the_scenes_symmetry_and_steps_through_the_others() {
        let mut off = SymmetrySwitch::new(Symmetry::NONE);
        assert!(off.current().is_none());
        assert_eq!(off.toggle(), Symmetry::mirror(Axis::X));
        assert!(off.toggle().is_none());
        // From off, the next choice is the chosen one, switched on.
        assert_eq!(off.next_choice(), Symmetry::mirror(Axis::X));
        let seen: Vec<usize> = (0..3).map(|_| off.next_choice().images().len()).collect();
        assert_eq!(seen, [4, 6, 12], "mirror X and Z, radial 6, the kaleidoscope");
        assert_eq!(off.next_choice(), Symmetry::mirror(Axis::X), "four choices, then round again");
        let mut button = SymmetrySwitch::new(Symmetry::NONE);
        let round: Vec<usize> = (0..6).map(|_| button.step().images().len()).collect();
        assert_eq!(round, [2, 4, 6, 12, 1, 2], "one button reaches every choice and off");
        let scene = Symmetry::radial(3, Axis::Z).in_frame(Pose { position_m: Vec3::Y, ..Pose::default() });
        let mut own = SymmetrySwitch::new(scene);
        assert_eq!(own.current(), scene);
        let next = own.next_choice();
        assert_eq!(next.frame, scene.frame, "the other choices lie in the scene's frame");
        assert_eq!(next.mirror, [true, false, false]);
    }
}
