//! A lattice held open when a sculpt was saved (version 6): the LATT chunk, JSON. The file's
//! clay is the clay as it was when the lattice opened; a reader that reopens the lattice over
//! it and puts its controls in place has the sculpt as it was left, and one that only wants the
//! shape (an export, a render) applies it.

use serde::{Deserialize, Serialize};

/// The largest LATT chunk a reader accepts: 16³ controls of a few dozen bytes each, with room.
pub const MAX_LATTICE_BYTES: usize = 2 << 20;

/// The lattice kinds a file names (see `spline::SplineKind`).
pub const LATTICE_KINDS: [&str; 3] = ["bezier", "bspline", "nurbs"];

/// The knot styles a file names (see `spline::KnotStyle`).
pub const KNOT_STYLES: [&str; 2] = ["clamped", "uniform"];

/// One control point as stored.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StoredControl {
    /// Where it is, metres (its part's frame).
    pub position_m: [f32; 3],
    /// Its function value.
    pub value: f64,
    /// Its NURBS weight (1 for the other kinds).
    pub weight: f64,
}

/// A lattice held open over a part's clay, as a sculpt stores it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StoredLattice {
    /// The part whose clay it deforms (0: the first).
    pub part: usize,
    /// The box its rest lattice spans, metres (its part's frame).
    pub min_m: [f32; 3],
    /// See `min_m`.
    pub max_m: [f32; 3],
    /// Control points per axis, 2 to 16.
    pub counts: [usize; 3],
    /// `"bezier"`, `"bspline"` or `"nurbs"`.
    pub kind: String,
    /// The B-spline order (degree + 1), 2 to 16.
    pub order: usize,
    /// `"clamped"` or `"uniform"`.
    pub knots: String,
    /// Samples per knot span of its fit, if set.
    pub samples_per_span: Option<usize>,
    /// Its controls, `i` fastest, then `j`, then `k`.
    pub controls: Vec<StoredControl>,
    /// The control picked when it was saved.
    pub picked: [usize; 3],
}

impl StoredLattice {
    /// The LATT chunk's bytes.
    pub(super) fn put(&self) -> Vec<u8> {
        serde_json::to_vec(self).expect("plain values serialise")
    }

    /// Reads a LATT chunk (number `index`), refusing what no lattice can be; the part it names
    /// is checked against the parts once they are known ([`StoredLattice::check_part`]).
    pub(super) fn read(raw: &[u8], index: u32) -> Result<Self, String> {
        if raw.len() > MAX_LATTICE_BYTES {
            return Err(format!("chunk {index} (LATT) holds {} bytes, more than a lattice takes", raw.len()));
        }
        let l: StoredLattice =
            serde_json::from_slice(raw).map_err(|e| format!("chunk {index} (LATT) is not a lattice: {e}"))?;
        let counts_fit = l.counts.iter().all(|n| (2..=16).contains(n));
        let controls = l.counts.iter().product::<usize>();
        let finite = l.min_m.iter().chain(&l.max_m).all(|v| v.is_finite() && v.abs() <= 1e3)
            && l.controls.iter().all(|c| {
                c.position_m.iter().all(|v| v.is_finite() && v.abs() <= 1e3)
                    && c.value.is_finite()
                    && c.weight.is_finite()
                    && c.weight > 0.0
            });
        let fine = counts_fit
            && l.controls.len() == controls
            && finite
            && (0..3).all(|a| l.min_m[a] < l.max_m[a])
            && (2..=16).contains(&l.order)
            && LATTICE_KINDS.contains(&l.kind.as_str())
            && KNOT_STYLES.contains(&l.knots.as_str())
            && l.samples_per_span.is_none_or(|s| (1..=64).contains(&s))
            && (0..3).all(|a| l.picked[a] < l.counts[a])
            && l.part < super::MAX_PARTS;
        if !fine {
            return Err(format!(
                "chunk {index} (LATT) holds a lattice no station opens: {} controls of {:?}, box {:?} to {:?}, \
                 kind {:?}, order {}, knots {:?}",
                l.controls.len(),
                l.counts,
                l.min_m,
                l.max_m,
                l.kind,
                l.order,
                l.knots
            ));
        }
        Ok(l)
    }

    /// Refuses a lattice over a part the sculpt has not (`parts`: how many it has).
    pub(super) fn check_part(&self, parts: usize) -> Result<(), String> {
        if self.part >= parts {
            return Err(format!("its open lattice lies over part {}; it has {parts}", self.part));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::Field;
    use crate::io::{decode, encode_sculpt, EncodeOptions, SceneParts};
    use crate::math::IVec3;

    fn lattice() -> StoredLattice {
        let controls = (0..27)
            .map(|n| StoredControl {
                position_m: [(n % 3) as f32 * 0.01, ((n / 3) % 3) as f32 * 0.01, (n / 9) as f32 * 0.01],
                value: 0.25 + 0.01 * n as f64,
                weight: 1.0 + 0.5 * (n == 13) as u8 as f64,
            })
            .collect();
        StoredLattice {
            part: 0,
            min_m: [0.0; 3],
            max_m: [0.02; 3],
            counts: [3, 3, 3],
            kind: "nurbs".into(),
            order: 3,
            knots: "clamped".into(),
            samples_per_span: None,
            controls,
            picked: [1, 1, 1],
        }
    }

    #[test]
    fn an_open_lattice_reads_back_as_written_and_older_versions_leave_it_out() {
        let mut field = Field::new(0.001, 0.5);
        field.edit_box(IVec3::ZERO, IVec3::splat(12), true, |_, d, _| *d = 1.0);
        let stored = lattice();
        let scene = SceneParts { lattice: Some(&stored), ..SceneParts::default() };
        let bytes = encode_sculpt(&field, scene, EncodeOptions::default(), &mut |_| {});
        let back = decode(&bytes, "lattice.argile", &mut |_| {}).unwrap();
        assert_eq!(back.lattice.as_ref(), Some(&stored));
        assert!(back.field.same_samples(&field));
        let v5 = encode_sculpt(&field, scene, EncodeOptions { version: 5, history: true }, &mut |_| {});
        assert_eq!(decode(&v5, "v5.argile", &mut |_| {}).unwrap().lattice, None);
    }

    #[test]
    fn lattices_no_station_opens_are_refused() {
        let good = lattice();
        assert_eq!(StoredLattice::read(&good.put(), 4).unwrap(), good);
        let mut few = good.clone();
        few.controls.pop();
        let mut nan = good.clone();
        nan.controls[3].value = f64::NAN;
        for bad in [
            few,
            StoredLattice { counts: [1, 27, 1], ..good.clone() },
            StoredLattice { kind: "spline".into(), ..good.clone() },
            StoredLattice { max_m: [0.0; 3], ..good.clone() },
            StoredLattice { picked: [3, 0, 0], ..good.clone() },
            StoredLattice { order: 1, ..good.clone() },
        ] {
            let e = StoredLattice::read(&bad.put(), 4).unwrap_err();
            assert!(e.contains("chunk 4 (LATT) holds a lattice no station opens"), "{e}");
        }
        // NaN is written as null by JSON: not a number at all.
        assert!(StoredLattice::read(&nan.put(), 4).is_err());
        assert!(StoredLattice::read(b"{}", 4).unwrap_err().contains("is not a lattice"));
        let over = StoredLattice { part: 2, ..good };
        assert!(over.check_part(2).unwrap_err().contains("over part 2; it has 2"));
        // A file whose lattice lies over a part it has not is refused whole.
        let field = Field::new(0.001, 0.5);
        let scene = SceneParts { lattice: Some(&over), ..SceneParts::default() };
        let bytes = encode_sculpt(&field, scene, EncodeOptions::default(), &mut |_| {});
        let e = decode(&bytes, "over.argile", &mut |_| {}).unwrap_err().to_string();
        assert!(e.contains("over.argile") && e.contains("over part 2; it has 1"), "{e}");
    }
}
