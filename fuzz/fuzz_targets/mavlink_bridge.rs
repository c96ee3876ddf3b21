//! See `fuzz/mavlink_properties.rs`: `mavlink_bridge`.
#![no_main]

// The file holds both MAVLink targets' properties; each target calls one.
#[allow(dead_code)]
#[path = "../mavlink_properties.rs"]
mod mavlink_properties;

libfuzzer_sys::fuzz_target!(|data: &[u8]| mavlink_properties::mavlink_bridge(data));
