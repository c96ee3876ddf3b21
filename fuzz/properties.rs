//! The no-panic properties, written once: the cargo-fuzz targets call them, and
//! `tests/no_panic.rs` includes this file (`#[path]`) so that `cargo test` checks the same
//! properties on every run. Each panics (an `assert!`) when its property fails.

use idu_gimbal::link::postback::PostbackAssembler;
use idu_gimbal::wire::control::Command;
use idu_gimbal::wire::serial::{control_frame, StreamItem, StreamParser, MAX_FRAME_LEN};
use idu_gimbal::wire::{ids, postback::Postback};
use idu_gimbal::Instant;

/// Any bytes: decoding never panics, and whatever decodes re-encodes to the same bytes.
pub fn command_decode(data: &[u8]) {
    if let Ok(cmd) = Command::decode(data) {
        assert_eq!(&cmd.encode()[..], data);
    }
}

/// Any byte stream, split where its first byte says: the parser never panics, stays within
/// its buffer, and yields only control frames that stand in the input whole.
pub fn stream_parser(data: &[u8]) {
    let mut parser = StreamParser::new();
    let cut = data
        .first()
        .map_or(0, |&n| usize::from(n) % (data.len() + 1));
    let (a, b) = data.split_at(cut);
    for part in [a, b] {
        for item in parser.feed(part) {
            if let StreamItem::Control(d) = item {
                assert!(data.windows(24).any(|w| w == control_frame(&d)));
            }
        }
        assert!(parser.pending() < MAX_FRAME_LEN);
    }
}

/// Any sequence of (ID selector and length, time step, data) records of 11 bytes: the
/// assembler never panics, never emits a message whose CRC fails, and every frame is
/// accounted for.
pub fn assembler(data: &[u8]) {
    let mut asm = PostbackAssembler::new();
    let mut t = 0u32;
    for chunk in data.chunks(11) {
        let [sel, dt, rest @ ..] = chunk else { break };
        t = t.wrapping_add(u32::from(*dt));
        let id = if sel & 1 == 0 {
            ids::POSTBACK
        } else {
            ids::CONTROL
        };
        let len = usize::from(sel >> 1) % (rest.len() + 1);
        if let Some(p) = asm.feed(id, &rest[..len], Instant::from_millis(t)) {
            assert!(Postback::parse(&p.to_can_bytes()).is_ok());
        }
    }
    let s = asm.stats();
    assert_eq!(
        s.frames,
        4 * s.messages + s.discarded_frames + asm.pending() as u32
    );
}
