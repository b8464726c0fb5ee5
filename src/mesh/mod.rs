//! Iso-surface extraction.

mod types;

pub use types::*;
