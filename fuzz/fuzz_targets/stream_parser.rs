//! See `fuzz/properties.rs`: `stream_parser`.
#![no_main]

#[path = "../properties.rs"]
mod properties;

libfuzzer_sys::fuzz_target!(|data: &[u8]| properties::stream_parser(data));
