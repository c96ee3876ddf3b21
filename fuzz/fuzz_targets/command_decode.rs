//! See `fuzz/properties.rs`: `command_decode`.
#![no_main]

#[path = "../properties.rs"]
mod properties;

libfuzzer_sys::fuzz_target!(|data: &[u8]| properties::command_decode(data));
