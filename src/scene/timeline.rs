//! The scripted hands: keyframes of tool poses, interpolated between keys.
//!
//! Between two keys of the same hand the pose is interpolated (linear position, spherical
//! rotation) and the tool is the earlier key's; the action is on over that interval when the
//! earlier key says `active`. Before a hand's first key and after its last, the hand rests at
//! that key with its action off.

use crate::math::Pose;

/// Which hand a key drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Hand {
    /// The left hand.
    Left,
    /// The right hand.
    Right,
}

impl Hand {
    /// Both hands, left first.
    pub const BOTH: [Hand; 2] = [Hand::Left, Hand::Right];
}

/// One keyframe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Key {
    /// Time, seconds.
    pub time_s: f32,
    /// Hand.
    pub hand: Hand,
    /// Index of the tool in the scene's tools.
    pub tool: usize,
    /// Tool pose.
    pub pose: Pose,
    /// Whether the action is on from this key to the next of the same hand.
    pub active: bool,
    /// The part the tool acts on (an index into the scene's parts).
    pub part: usize,
}

/// What a hand does at a given time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HandState {
    /// Tool index.
    pub tool: usize,
    /// Tool pose.
    pub pose: Pose,
    /// Whether the action is on.
    pub active: bool,
    /// The part the tool acts on.
    pub part: usize,
}

/// The keys of both hands, each hand's sorted by time.
#[derive(Clone, Debug, PartialEq)]
pub struct Timeline {
    left: Vec<Key>,
    right: Vec<Key>,
    step_s: f32,
}

impl Timeline {
    /// Builds a timeline; two keys of one hand at the same time are refused (the error holds
    /// the index of the second key in `keys` and a message).
    pub fn new(keys: Vec<Key>, step_s: f32) -> Result<Timeline, (usize, String)> {
        let mut tagged: Vec<(usize, Key)> = keys.into_iter().enumerate().collect();
        tagged.sort_by(|a, b| a.1.time_s.total_cmp(&b.1.time_s).then(a.0.cmp(&b.0)));
        let mut left = Vec::new();
        let mut right = Vec::new();
        for (i, key) in tagged {
            let list = if key.hand == Hand::Left { &mut left } else { &mut right };
            if list.last().is_some_and(|k: &Key| k.time_s == key.time_s) {
                return Err((
                    i,
                    format!("two keys of the {:?} hand at {} s", key.hand, key.time_s).to_lowercase(),
                ));
            }
            list.push(key);
        }
        Ok(Timeline { left, right, step_s })
    }

    /// Simulation step, seconds.
    pub fn step_s(&self) -> f32 {
        self.step_s
    }

    /// Time of the last key, seconds (0 with no keys).
    pub fn duration_s(&self) -> f32 {
        self.left.iter().chain(&self.right).map(|k| k.time_s).fold(0.0, f32::max)
    }

    /// Whether no key is defined.
    pub fn is_empty(&self) -> bool {
        self.left.is_empty() && self.right.is_empty()
    }

    /// The keys of one hand, by time.
    pub fn keys(&self, hand: Hand) -> &[Key] {
        match hand {
            Hand::Left => &self.left,
            Hand::Right => &self.right,
        }
    }

    /// The hand's state at `t`, or `None` if the hand has no key.
    pub fn state_at(&self, hand: Hand, t: f32) -> Option<HandState> {
        let keys = self.keys(hand);
        Some(match locate(keys, t, |k| k.time_s)? {
            Span::Rest(k) => HandState { tool: k.tool, pose: k.pose, active: false, part: k.part },
            Span::Between(k, next, u) => {
                HandState { tool: k.tool, pose: k.pose.lerp(&next.pose, u), active: k.active, part: k.part }
            }
        })
    }
}

/// Where a time falls among keys sorted by time.
pub(super) enum Span<'k, K> {
    /// Before the first key or after the last: resting at that key.
    Rest(&'k K),
    /// Between two keys, a fraction `u` in [0, 1) of the way.
    Between(&'k K, &'k K, f32),
}

/// Finds `t` among `keys` (sorted by `time`, no two at the same time); `None` without keys.
pub(super) fn locate<K>(keys: &[K], t: f32, time: impl Fn(&K) -> f32) -> Option<Span<'_, K>> {
    let first = keys.first()?;
    if t < time(first) {
        return Some(Span::Rest(first));
    }
    let i = keys.partition_point(|k| time(k) <= t) - 1;
    let k = &keys[i];
    Some(match keys.get(i + 1) {
        None => Span::Rest(k),
        Some(next) => Span::Between(k, next, (t - time(k)) / (time(next) - time(k))),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;

    fn key(t: f32, x: f32, active: bool) -> Key {
        Key {
            time_s: t,
            hand: Hand::Right,
            tool: 0,
            pose: Pose { position_m: Vec3::new(x, 0.0, 0.0), ..Pose::default() },
            part: 0,
            active,
        }
    }

    #[test]
    fn interpolates_and_switches_the_action_per_interval() {
        let tl = Timeline::new(vec![key(2.0, 2.0, false), key(0.0, 0.0, true), key(1.0, 1.0, true)], 0.01)
            .unwrap();
        assert_eq!(tl.duration_s(), 2.0);
        let s = tl.state_at(Hand::Right, 0.5).unwrap();
        assert!((s.pose.position_m.x - 0.5).abs() < 1e-6 && s.active);
        let s = tl.state_at(Hand::Right, 1.5).unwrap();
        assert!((s.pose.position_m.x - 1.5).abs() < 1e-6 && s.active);
        assert!(!tl.state_at(Hand::Right, 2.5).unwrap().active);
        assert!(tl.state_at(Hand::Left, 0.5).is_none());
    }

    #[test]
    fn refuses_two_keys_at_one_time() {
        let err = Timeline::new(vec![key(1.0, 0.0, true), key(1.0, 1.0, true)], 0.01).unwrap_err();
        assert_eq!(err.0, 1);
    }
}
