//! Any byte stream, split anywhere: the parser never panics, stays within its buffer, and
//! yields only frames whose CRC holds.
#![no_main]
use idu_gimbal::wire::serial::{control_frame, StreamItem, StreamParser, MAX_FRAME_LEN};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut parser = StreamParser::new();
    let (a, b) = data.split_at(data.first().map_or(0, |&n| usize::from(n) % (data.len() + 1)));
    for part in [a, b] {
        for item in parser.feed(part) {
            if let StreamItem::Control(d) = item {
                assert!(data.windows(24).any(|w| w == control_frame(&d)));
            }
        }
        assert!(parser.pending() < MAX_FRAME_LEN);
    }
});
