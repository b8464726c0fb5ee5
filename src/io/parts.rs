//! A sculpt's parts in its file (version 5): the PRTS chunk (every part's layout, JSON) and the
//! PART chunks (the bricks of the parts after the first; the first part's are the file's own
//! BRKS and BRKL chunks).

use std::collections::HashSet;

use serde::{Deserialize, Serialize};

use super::{put_brick, put_chunk, read_brick, u32_at, BRICKS_PER_CHUNK, BRICK_RECORD};
use crate::field::{Brick, Field, LevelKey, LEVELS, VOXEL_SIZE_RANGE_M};

/// The most parts a sculpt may have.
pub const MAX_PARTS: usize = 256;

/// The operators a part may be composed with (see `parts::Csg`).
pub const PART_OPS: [&str; 3] = ["union", "difference", "intersection"];

/// Where a part sits and how it composes, as a sculpt stores it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartLayout {
    /// Its name, unique in the sculpt.
    pub name: String,
    /// Its field's finest voxel in its own frame, metres.
    pub voxel_size_m: f32,
    /// Its turn (quaternion x, y, z, w).
    pub rotation: [f32; 4],
    /// Where its origin sits, metres.
    pub translation_m: [f32; 3],
    /// Its uniform scale.
    pub scale: f32,
    /// `"union"`, `"difference"` or `"intersection"` with the parts before it.
    pub op: String,
    /// Whether it is composed.
    pub visible: bool,
    /// Whether tools leave it alone.
    pub locked: bool,
}

impl PartLayout {
    /// Refuses a layout no part can have.
    fn check(&self, i: usize) -> Result<(), String> {
        let unit = (crate::math::Quat::from_array(self.rotation).length() - 1.0).abs() < 1e-3;
        let fine = !self.name.is_empty()
            && self.name.chars().count() <= 64
            && !self.name.chars().any(char::is_control)
            && VOXEL_SIZE_RANGE_M.contains(&self.voxel_size_m)
            && self.rotation.iter().chain(&self.translation_m).all(|v| v.is_finite())
            && unit
            && self.translation_m.iter().all(|v| v.abs() <= 1e3)
            && self.scale.is_finite()
            && (1e-3..=1e3).contains(&self.scale)
            && PART_OPS.contains(&self.op.as_str());
        if fine {
            Ok(())
        } else {
            Err(format!("its part {i} has a layout no part can have: {self:?}"))
        }
    }
}

/// The PRTS chunk's bytes.
pub(super) fn put_layouts(layouts: &[PartLayout]) -> Vec<u8> {
    serde_json::to_vec(layouts).expect("plain values serialise")
}

/// Reads a PRTS chunk (number `index`): at least two parts, or one not at rest; each a layout
/// a part can have, and no name twice.
pub(super) fn read_layouts(raw: &[u8], index: u32) -> Result<Vec<PartLayout>, String> {
    let layouts: Vec<PartLayout> = serde_json::from_slice(raw)
        .map_err(|e| format!("chunk {index} (PRTS) is not a list of parts: {e}"))?;
    if layouts.is_empty() || layouts.len() > MAX_PARTS {
        return Err(format!("chunk {index} (PRTS) lists {} parts, not 1 to {MAX_PARTS}", layouts.len()));
    }
    let mut names = HashSet::new();
    for (i, l) in layouts.iter().enumerate() {
        l.check(i)?;
        if !names.insert(l.name.as_str()) {
            return Err(format!("chunk {index} (PRTS) names two parts \"{}\"", l.name.escape_debug()));
        }
    }
    Ok(layouts)
}

/// The PART chunks of the parts after the first (`bricks`: each with its part's index, 1 and
/// up, in any order): per chunk, the part's index u32, the level u8, then up to
/// [`BRICKS_PER_CHUNK`] bricks of that part and level as BRKS holds them. Returns how many.
pub(super) fn put_part_chunks(out: &mut Vec<u8>, bricks: &mut [(u32, LevelKey, &Brick)]) -> u32 {
    let mut count = 0;
    let mut raw = Vec::new();
    bricks.sort_unstable_by_key(|(p, k, _)| (*p, k.sort_key()));
    let groups =
        bricks.chunk_by(|a, b| (a.0, a.1.level) == (b.0, b.1.level)).flat_map(|g| g.chunks(BRICKS_PER_CHUNK));
    for group in groups {
        raw.clear();
        raw.extend_from_slice(&group[0].0.to_le_bytes());
        raw.push(group[0].1.level);
        for (_, key, brick) in group {
            put_brick(&mut raw, key.key, brick);
        }
        put_chunk(out, *b"PART", &raw);
        count += 1;
    }
    count
}

/// The PART chunks' fields as they are read: one per part after the first, of its layout's
/// voxel size, and the keys each holds.
pub(super) struct PartsReader {
    pub(super) fields: Vec<Field>,
    keys: Vec<HashSet<LevelKey>>,
}

impl PartsReader {
    /// Empty fields for the parts after the first of `layouts`, at the iso-level `iso`.
    pub(super) fn new(layouts: &[PartLayout], iso: f32) -> Self {
        let fields: Vec<Field> = layouts.iter().skip(1).map(|l| Field::new(l.voxel_size_m, iso)).collect();
        let keys = fields.iter().map(|_| HashSet::new()).collect();
        Self { fields, keys }
    }

    /// Bricks read so far.
    pub(super) fn bricks(&self) -> usize {
        self.keys.iter().map(HashSet::len).sum()
    }

    /// Reads PART chunk number `index`, refusing a part the PRTS chunk does not list, a level
    /// beyond the field, a partial brick or a brick stored twice.
    pub(super) fn read(&mut self, raw: &[u8], index: u32) -> Result<(), String> {
        if raw.len() < 5 {
            return Err(format!("chunk {index} (PART) is too short"));
        }
        let part = u32_at(raw, 0) as usize;
        let level = usize::from(raw[4]);
        if part == 0 || part > self.fields.len() {
            return Err(format!(
                "chunk {index} (PART) holds bricks of part {part}; the sculpt's parts after the first are 1 to {}",
                self.fields.len()
            ));
        }
        if level >= LEVELS {
            return Err(format!("chunk {index} (PART) is of level {level}, beyond the field's {LEVELS}"));
        }
        let records = &raw[5..];
        if records.len() % BRICK_RECORD != 0 || records.len() / BRICK_RECORD > BRICKS_PER_CHUNK {
            return Err(format!(
                "chunk {index} (PART) holds a partial brick or more than {BRICKS_PER_CHUNK}"
            ));
        }
        for record in records.chunks_exact(BRICK_RECORD) {
            let (key, brick) = read_brick(record)?;
            let key = LevelKey::new(level, key);
            if !self.keys[part - 1].insert(key) {
                return Err(format!("brick {key} of part {part} is stored twice"));
            }
            self.fields[part - 1].insert_brick(key, brick);
        }
        Ok(())
    }

    /// The fields read, their dirty sets empty.
    pub(super) fn finish(mut self) -> Vec<Field> {
        for f in &mut self.fields {
            f.take_dirty();
        }
        self.fields
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::{decode, encode_sculpt, EncodeOptions, SceneParts};
    use crate::math::IVec3;

    fn layout(name: &str) -> PartLayout {
        PartLayout {
            name: name.into(),
            voxel_size_m: 0.002,
            rotation: [0.0, 0.0, 0.0, 1.0],
            translation_m: [0.01, 0.0, 0.0],
            scale: 1.5,
            op: "difference".into(),
            visible: true,
            locked: false,
        }
    }

    fn clay(voxel: f32, seed: i32) -> Field {
        let mut f = Field::new(voxel, 0.5);
        f.edit_box(IVec3::splat(-5 - seed), IVec3::splat(9 + seed), true, |p, d, c| {
            *d = ((p.x * 3 + p.y - p.z + seed) as f32 * 0.07).sin().abs();
            *c = [0.2, 0.1 * (p.y & 3) as f32, 0.5, 1.0];
        });
        f
    }

    #[test]
    fn parts_read_back_bit_for_bit_with_their_layouts() {
        let first = clay(0.001, 0);
        let others = [clay(0.002, 1), clay(0.0015, 3)];
        let layouts = [
            PartLayout { voxel_size_m: 0.001, op: "union".into(), ..layout("a") },
            layout("b"),
            PartLayout { voxel_size_m: 0.0015, op: "intersection".into(), ..layout("c") },
        ];
        let scene = SceneParts { layouts: &layouts, others: &others, ..SceneParts::default() };
        let bytes = encode_sculpt(&first, scene, EncodeOptions::default(), &mut |_| {});
        let back = decode(&bytes, "parts.argile", &mut |_| {}).unwrap();
        assert!(back.field.same_samples(&first));
        assert_eq!(back.parts, layouts);
        assert_eq!(back.others.len(), 2);
        for (read, written) in back.others.iter().zip(&others) {
            assert!(read.same_samples(written));
            assert_eq!(read.transform(), written.transform());
        }
        // Without parts, the file is the one it always was.
        let plain = encode_sculpt(&first, SceneParts::default(), EncodeOptions::default(), &mut |_| {});
        assert!(decode(&plain, "plain.argile", &mut |_| {}).unwrap().parts.is_empty());
    }

    #[test]
    fn layouts_no_part_can_have_and_bricks_of_no_listed_part_are_refused() {
        let twice = put_layouts(&[layout("a"), layout("a")]);
        assert!(read_layouts(&twice, 3).unwrap_err().contains("names two parts \"a\""));
        for bad in [
            PartLayout { scale: 0.0, ..layout("s") },
            PartLayout { voxel_size_m: 1.0, ..layout("s") },
            PartLayout { rotation: [0.0; 4], ..layout("s") },
            PartLayout { op: "xor".into(), ..layout("s") },
            PartLayout { name: String::new(), ..layout("s") },
        ] {
            let e = read_layouts(&put_layouts(&[layout("a"), bad]), 3).unwrap_err();
            assert!(e.contains("has a layout no part can have"), "{e}");
        }
        assert!(read_layouts(&put_layouts(&[PartLayout { scale: f32::NAN, ..layout("s") }]), 3).is_err());
        assert!(read_layouts(b"[]", 3).unwrap_err().contains("lists 0 parts"));
        let mut reader = PartsReader::new(&[layout("a"), layout("b")], 0.5);
        let mut raw = 2u32.to_le_bytes().to_vec();
        raw.push(0);
        assert!(reader
            .read(&raw, 7)
            .unwrap_err()
            .contains("part 2; the sculpt's parts after the first are 1 to 1"));
        let mut raw = 1u32.to_le_bytes().to_vec();
        raw.push(9);
        assert!(reader.read(&raw, 7).unwrap_err().contains("level 9"));
        let mut raw = 1u32.to_le_bytes().to_vec();
        raw.extend_from_slice(&[0, 1, 2, 3]);
        assert!(reader.read(&raw, 7).unwrap_err().contains("partial brick"));
    }
}
