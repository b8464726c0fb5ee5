//! The sculpt loader on arbitrary bytes: it must refuse or load, never panic, hang or
//! allocate what the bytes claim; what it loads must store and load again unchanged.

#![no_main]

use libfuzzer_sys::fuzz_target;

mod load_body;

fuzz_target!(|data: &[u8]| load_body::check(data));
