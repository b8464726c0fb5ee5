//! Tool actions: how a tool's potential `T` combines with the clay (Galyean–Hughes 1991, §3;
//! Ferley et al. 1999, §4.2–4.3).
//!
//! | action | rule per sample (`d` density, `c` colour, `τ` the time applied) | kind |
//! | --- | --- | --- |
//! | [`Action::Add`] (toothpaste) | `d ← max(d, T)` | per stamp |
//! | [`Action::Remove`] (eraser) | `d ← min(d, 1 − T)` | per stamp |
//! | [`Action::SoftRemove`] (soft eraser, heat gun) | `d ← max(0, d − rate·τ·T)` | rate |
//! | [`Action::Build`] | `d ← min(1, d + rate·τ·T)` | rate |
//! | [`Action::Paint`] | `c ← c + T·(tool − c)`, `d` untouched | per stamp |
//! | [`Action::SoftPaint`] | `c ← c + min(1, rate·τ·T)·(tool − c)`, `d` untouched | rate |
//! | [`Action::Smooth`] (sandpaper) | `d ← d + min(1, rate·τ)·T·(avg − d)`, `avg = (w·d + Σ₆ dᵢ)/(w + 6)` | rate |
//! | [`Action::Stamp`] | `d ← clamp(d + def(1 − T), 0, 1)`, see [`crate::tool::Deformation`] | per stamp |
//! | [`Action::Inflate`] / [`Action::Deflate`] | `d ← clamp(d ± T·speed·τ·|∇d|, 0, 1)` | rate |
//! | [`Action::Push`] / [`Action::Support`] | none: the virtual clay (`crate::clay`) moves matter | — |
//!
//! Per-stamp actions act once per stamp, stamps being spaced along the tool's path; rate
//! actions act in proportion to the time the tool is held, in fixed ticks (see
//! [`crate::tool::Stroke`]), so neither depends on the frame rate. Every rule keeps density in
//! [0, 1] and never produces NaN. Added matter brings the tool's colour, mixed by mass.
//!
//! Inflate and deflate move the surface along its normal at `speed` (metres per second): the
//! level-set update `∂d/∂t = F·|∇d|` with `|∇d|` from central differences, so they act only
//! where there is a surface (the gradient vanishes inside the clay and in empty space), unlike
//! build and the heat gun, which change density wherever the tool is.

use super::deform::Deformation;

/// How a tool changes the clay where its potential `T` is not zero.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Action {
    /// Deposits matter: `d ← max(d, T)` (Ferley et al.'s toothpaste when moving).
    Add,
    /// Cuts matter away: `d ← min(d, 1 − T)` (the eraser).
    Remove,
    /// Removes matter at a rate while held: the soft eraser, or Galyean–Hughes' heat gun.
    SoftRemove {
        /// Density removed per second where `T = 1`.
        rate_per_s: f32,
    },
    /// Deposits matter at a rate while held (Galyean–Hughes' building tool).
    Build {
        /// Density added per second where `T = 1`.
        rate_per_s: f32,
    },
    /// Applies the tool's colour where the tool is, in proportion to `T`; density untouched.
    Paint,
    /// Applies the tool's colour gradually while held; density untouched.
    SoftPaint {
        /// Fraction of the way to the tool's colour per second where `T = 1`.
        rate_per_s: f32,
    },
    /// Sandpaper: blends each sample towards the weighted average of itself and its six
    /// neighbours.
    Smooth {
        /// Weight of the sample itself against 1 for each neighbour, 4 to 24 (clamped): the
        /// larger, the gentler each pass.
        centre_weight: f32,
        /// Passes per second where `T = 1`.
        rate_per_s: f32,
    },
    /// Prints the tool's shape into the clay with a bulge around the print (Ferley et al.'s
    /// deformation function `def(v)`).
    Stamp {
        /// The deformation function.
        deformation: Deformation,
        /// Width over which a hard-edged tool's potential falls from 1 to 0 across its surface
        /// (at least the field's band), so the bulge has room outside the print.
        falloff_m: f32,
    },
    /// Pushes the surface outwards along its normal.
    Inflate {
        /// Surface speed where `T = 1`, metres per second.
        speed_m_per_s: f32,
    },
    /// Pulls the surface inwards along its normal.
    Deflate {
        /// Surface speed where `T = 1`, metres per second.
        speed_m_per_s: f32,
    },
    /// Pushes the clay as a rigid body: the virtual clay of `crate::clay` moves, bends and
    /// dents it while conserving its matter. Stamping does nothing with it.
    Push,
    /// Holds the clay still where it touches it, as a support for pushes
    /// (`crate::clay`), while the hand holding it keeps it still. Stamping does nothing
    /// with it.
    Support,
}

impl Action {
    /// A short name for displays ("add", "soft remove", ...).
    pub fn name(&self) -> &'static str {
        match self {
            Action::Add => "add",
            Action::Remove => "remove",
            Action::SoftRemove { .. } => "soft remove",
            Action::Build { .. } => "build",
            Action::Paint => "paint",
            Action::SoftPaint { .. } => "soft paint",
            Action::Smooth { .. } => "smooth",
            Action::Stamp { .. } => "stamp",
            Action::Inflate { .. } => "inflate",
            Action::Deflate { .. } => "deflate",
            Action::Push => "push",
            Action::Support => "support",
        }
    }

    /// Whether the action works in proportion to time held (rather than once per stamp).
    pub fn is_rate_based(&self) -> bool {
        matches!(
            self,
            Action::SoftRemove { .. }
                | Action::Build { .. }
                | Action::SoftPaint { .. }
                | Action::Smooth { .. }
                | Action::Inflate { .. }
                | Action::Deflate { .. }
        )
    }

    /// Whether the action can only take matter away.
    pub fn only_removes(&self) -> bool {
        matches!(self, Action::Remove | Action::SoftRemove { .. } | Action::Deflate { .. })
    }

    /// Whether the action changes colour only.
    pub fn only_paints(&self) -> bool {
        matches!(self, Action::Paint | Action::SoftPaint { .. })
    }

    /// Whether the action may add matter where there is none yet (and so create bricks).
    pub fn may_create(&self) -> bool {
        match self {
            Action::Add | Action::Build { .. } | Action::Smooth { .. } | Action::Inflate { .. } => true,
            Action::Stamp { deformation, .. } => deformation.parameters().4 > 0.0,
            _ => false,
        }
    }

    /// Whether the tool acts through the virtual clay (pushing or holding) rather than by
    /// stamping.
    pub fn is_clay_body(&self) -> bool {
        matches!(self, Action::Push | Action::Support)
    }

    /// Whether the action reads each sample's six neighbours (and so needs a snapshot).
    pub fn reads_neighbours(&self) -> bool {
        matches!(self, Action::Smooth { .. } | Action::Inflate { .. } | Action::Deflate { .. })
    }
}
