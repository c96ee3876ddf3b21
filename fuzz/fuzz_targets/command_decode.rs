//! Any bytes: decoding never panics, and whatever decodes re-encodes to the same bytes.
#![no_main]
use idu_gimbal::wire::control::Command;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(cmd) = Command::decode(data) {
        assert_eq!(&cmd.encode()[..], data);
    }
});
