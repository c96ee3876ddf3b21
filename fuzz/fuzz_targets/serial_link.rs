//! See `fuzz/properties.rs`: `serial_link`.
#![no_main]

// Each target calls one of the shared properties.
#[allow(dead_code)]
#[path = "../properties.rs"]
mod properties;

libfuzzer_sys::fuzz_target!(|data: &[u8]| properties::serial_link(data));
