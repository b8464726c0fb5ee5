//! Colours as scene files write them: `"#rrggbb"` (sRGB, as colour pickers show) or
//! `[r, g, b]` (linear, 0..1). Stored linear, as everywhere in Argile.

use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::Deserialize;

/// A linear RGB colour read from a scene file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneColour(pub [f32; 3]);

impl SceneColour {
    /// The colour with an alpha.
    pub fn with_alpha(self, a: f32) -> [f32; 4] {
        [self.0[0], self.0[1], self.0[2], a]
    }
}

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Parses `#rrggbb` into linear RGB.
pub fn parse_hex(s: &str) -> Option<[f32; 3]> {
    let hex = s.strip_prefix('#')?;
    if hex.len() != 6 || !hex.is_ascii() {
        return None;
    }
    let byte = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).ok();
    Some([byte(0)?, byte(2)?, byte(4)?].map(|b| srgb_to_linear(f32::from(b) / 255.0)))
}

struct ColourVisitor;

const EXPECTED: &str = "a colour: \"#rrggbb\" (sRGB) or [r, g, b] (linear, each 0..1)";

impl<'de> Visitor<'de> for ColourVisitor {
    type Value = SceneColour;

    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(EXPECTED)
    }

    fn visit_str<E: de::Error>(self, s: &str) -> Result<SceneColour, E> {
        parse_hex(s).map(SceneColour).ok_or_else(|| E::custom(format!("`{s}` is not {EXPECTED}")))
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<SceneColour, A::Error> {
        let mut c = [0.0f32; 3];
        for (i, v) in c.iter_mut().enumerate() {
            *v = seq.next_element()?.ok_or_else(|| de::Error::invalid_length(i, &EXPECTED))?;
        }
        if seq.next_element::<f32>()?.is_some() {
            return Err(de::Error::custom(format!("too many components: expected {EXPECTED}")));
        }
        if c.iter().any(|v| !(0.0..=1.0).contains(v)) {
            return Err(de::Error::custom(format!("components must lie in 0..1: expected {EXPECTED}")));
        }
        Ok(SceneColour(c))
    }
}

impl<'de> Deserialize<'de> for SceneColour {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(ColourVisitor)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hex_is_srgb_and_decodes_to_linear() {
        let c = parse_hex("#ff8000").unwrap();
        assert_eq!(c[0], 1.0);
        assert!((c[1] - 0.2158).abs() < 1e-3);
        assert_eq!(c[2], 0.0);
        assert!(
            parse_hex("ff8000").is_none() && parse_hex("#ff80").is_none() && parse_hex("#gg0000").is_none()
        );
    }
}
