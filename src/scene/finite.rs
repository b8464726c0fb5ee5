//! NaN and infinities are refused wherever a TOML file writes them (`nan`, `inf`, or a number
//! too large for its type), at the value's own line and column: a number that is no number
//! would otherwise travel into poses, radii and loops that never end.

use std::ops::Range;

use toml_edit::{Item, Value};

/// The first value of `text` that is not a finite number: its byte range and dotted key
/// path. `Ok` for text without one, and for text TOML cannot parse (its parser says why).
pub fn check_finite(text: &str) -> Result<(), (Range<usize>, String)> {
    let Ok(doc) = toml_edit::ImDocument::parse(text) else { return Ok(()) };
    item(doc.as_item(), &mut Vec::new())
}

fn item(it: &Item, path: &mut Vec<String>) -> Result<(), (Range<usize>, String)> {
    match it {
        Item::Value(v) => value(v, path),
        Item::Table(t) => {
            for (k, i) in t.iter() {
                path.push(k.to_owned());
                item(i, path)?;
                path.pop();
            }
            Ok(())
        }
        Item::ArrayOfTables(a) => {
            for (n, t) in a.iter().enumerate() {
                path.push(format!("[{}]", n + 1));
                for (k, i) in t.iter() {
                    path.push(k.to_owned());
                    item(i, path)?;
                    path.pop();
                }
                path.pop();
            }
            Ok(())
        }
        Item::None => Ok(()),
    }
}

fn value(v: &Value, path: &mut Vec<String>) -> Result<(), (Range<usize>, String)> {
    match v {
        // An f32 overflows where an f64 does not: both are refused.
        Value::Float(f) if !(f.value().is_finite() && f.value().abs() <= f64::from(f32::MAX)) => {
            Err((v.span().unwrap_or(0..0), name(path)))
        }
        Value::Array(a) => {
            for (n, x) in a.iter().enumerate() {
                path.push(format!("[{n}]"));
                value(x, path)?;
                path.pop();
            }
            Ok(())
        }
        Value::InlineTable(t) => {
            for (k, x) in t.iter() {
                path.push(k.to_owned());
                value(x, path)?;
                path.pop();
            }
            Ok(())
        }
        _ => Ok(()),
    }
}

/// The byte range of the value at the dotted key `path` of TOML `text` (`camera.fov_y_deg`),
/// else of the deepest table on the path that the text writes (its header), else `None`: where
/// an error about a value belongs when the value is defaulted.
pub fn span_of(text: &str, path: &str) -> Option<Range<usize>> {
    let doc = toml_edit::ImDocument::parse(text).ok()?;
    let mut table = doc.as_table();
    let mut found = None;
    let mut parts = path.split('.').peekable();
    while let Some(part) = parts.next() {
        let Some(item) = table.get(part) else { return found };
        match item {
            Item::Table(t) if parts.peek().is_some() => {
                found = t.span().or(found);
                table = t;
            }
            Item::Value(v) if parts.peek().is_none() => return v.span().or(found),
            _ => return found,
        }
    }
    found
}

fn name(path: &[String]) -> String {
    path.iter().fold(String::new(), |mut s, p| {
        if !s.is_empty() && !p.starts_with('[') {
            s.push('.');
        }
        s.push_str(p);
        s
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nan_infinity_and_overflow_are_found_with_their_place() {
        assert!(check_finite("[a]\nb = 1.5\nc = [1.0, -2e30]\n").is_ok());
        let text = "[camera]\nup = [0.0, nan, 0.0]\n";
        let (span, key) = check_finite(text).unwrap_err();
        assert_eq!((key.as_str(), &text[span]), ("camera.up[1]", "nan"));
        let (_, key) =
            check_finite("[[clay]]\nshape = \"box\"\n[[clay]]\nposition_m = { x = -inf }\n").unwrap_err();
        assert_eq!(key, "clay[2].position_m.x");
        let text = "[environment]\nintensity = 1e39\n";
        let (span, key) = check_finite(text).unwrap_err();
        assert_eq!((key.as_str(), span.start), ("environment.intensity", text.find("1e39").unwrap()));
    }
}
