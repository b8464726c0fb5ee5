//! The symmetry the strokes acted through when a sculpt was saved (version 7): the SYMM
//! chunk, JSON. A sculpt opens with the symmetry it was left with; a file of an older version
//! has none stored, and the station keeps the one in force.

use serde::{Deserialize, Serialize};

use crate::math::{Pose, Quat, Vec3};
use crate::parts::{Axis, Symmetry, MAX_RADIAL};

/// The largest SYMM chunk a reader accepts (a hundred bytes of JSON, with room).
const MAX_SYMMETRY_BYTES: usize = 4096;

/// How far from the origin a symmetry's frame may lie, metres (as a scene's positions).
const MAX_REACH_M: f32 = 100.0;

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct StoredSymmetry {
    /// The frame's origin, metres.
    position_m: [f32; 3],
    /// The frame's rotation (quaternion x, y, z, w).
    rotation: [f32; 4],
    /// Mirror across the planes normal to the frame's X, Y and Z.
    mirror: [bool; 3],
    /// Copies about the radial axis, the original included.
    radial: u32,
    /// The radial axis: "x", "y" or "z".
    axis: String,
}

/// The SYMM chunk's bytes for `symmetry`.
pub(super) fn put(symmetry: &Symmetry) -> Vec<u8> {
    let stored = StoredSymmetry {
        position_m: symmetry.frame.position_m.to_array(),
        rotation: symmetry.frame.rotation.to_array(),
        mirror: symmetry.mirror,
        radial: symmetry.radial,
        axis: symmetry.axis.name().to_owned(),
    };
    serde_json::to_vec(&stored).expect("plain values serialise")
}

/// Reads a SYMM chunk (number `index`), refusing what no symmetry can be.
pub(super) fn read(raw: &[u8], index: u32) -> Result<Symmetry, String> {
    if raw.len() > MAX_SYMMETRY_BYTES {
        return Err(format!("chunk {index} (SYMM) holds {} bytes, more than a symmetry takes", raw.len()));
    }
    let s: StoredSymmetry =
        serde_json::from_slice(raw).map_err(|e| format!("chunk {index} (SYMM) is not a symmetry: {e}"))?;
    let rotation = Quat::from_array(s.rotation);
    let fine = s.position_m.iter().all(|c| c.is_finite() && c.abs() <= MAX_REACH_M)
        && s.rotation.iter().all(|c| c.is_finite())
        && (rotation.length() - 1.0).abs() < 1e-3;
    if !fine {
        return Err(format!(
            "chunk {index} (SYMM) places its frame at {:?} turned by {:?}: not a point within ±{MAX_REACH_M} m and a rotation",
            s.position_m, s.rotation
        ));
    }
    if !(1..=MAX_RADIAL).contains(&s.radial) {
        return Err(format!("chunk {index} (SYMM) makes {} radial copies, not 1 to {MAX_RADIAL}", s.radial));
    }
    let Some(axis) = Axis::from_name(&s.axis) else {
        return Err(format!("chunk {index} (SYMM) names the axis \"{}\", not x, y or z", s.axis));
    };
    let frame = Pose { position_m: Vec3::from(s.position_m), rotation: rotation.normalize() };
    Ok(Symmetry { frame, mirror: s.mirror, radial: s.radial, axis })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_symmetry_comes_back_as_it_was_stored_and_bad_ones_are_refused_with_why() {
        let mut s = Symmetry::radial(6, Axis::Z);
        s.mirror = [true, false, true];
        s.frame = Pose { position_m: Vec3::new(0.1, -0.2, 0.3), rotation: Quat::from_rotation_y(0.4) };
        assert_eq!(read(&put(&s), 3).unwrap(), s);
        assert_eq!(read(&put(&Symmetry::NONE), 3).unwrap(), Symmetry::NONE);
        let json = |text: &str| read(text.as_bytes(), 3).unwrap_err();
        let base = r#""position_m":[0,0,0],"rotation":[0,0,0,1],"mirror":[true,false,false]"#;
        for (text, says) in [
            (format!(r#"{{{base},"radial":0,"axis":"y"}}"#), "makes 0 radial copies"),
            (format!(r#"{{{base},"radial":65,"axis":"y"}}"#), "makes 65 radial copies"),
            (format!(r#"{{{base},"radial":1,"axis":"w"}}"#), "names the axis \"w\""),
            (format!(r#"{{{base},"radial":1,"axis":"y","extra":1}}"#), "is not a symmetry"),
            (
                r#"{"position_m":[1e9,0,0],"rotation":[0,0,0,1],"mirror":[true,false,false],"radial":1,"axis":"y"}"#
                    .to_owned(),
                "not a point within",
            ),
            (
                r#"{"position_m":[0,0,0],"rotation":[0,0,0,2],"mirror":[true,false,false],"radial":1,"axis":"y"}"#
                    .to_owned(),
                "and a rotation",
            ),
            ("[1, 2]".to_owned(), "is not a symmetry"),
        ] {
            let e = json(&text);
            assert!(e.contains("chunk 3 (SYMM)") && e.contains(says), "{text}: {e}");
        }
        assert!(read(&vec![b' '; 5000], 3).unwrap_err().contains("more than a symmetry takes"));
    }
}
