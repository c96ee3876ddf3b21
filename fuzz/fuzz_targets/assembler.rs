//! Any sequence of (id, length, data, time step): the assembler never panics, never emits a
//! message whose CRC fails, and its frame accounting holds.
#![no_main]
use idu_gimbal::link::postback::PostbackAssembler;
use idu_gimbal::wire::{ids, postback::Postback};
use idu_gimbal::Instant;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut asm = PostbackAssembler::new();
    let mut t = 0u32;
    for chunk in data.chunks(11) {
        let [sel, dt, rest @ ..] = chunk else { break };
        t = t.wrapping_add(u32::from(*dt));
        let id = if sel & 1 == 0 { ids::POSTBACK } else { ids::CONTROL };
        let len = usize::from(sel >> 1) % (rest.len() + 1);
        if let Some(p) = asm.feed(id, &rest[..len], Instant::from_millis(t)) {
            assert!(Postback::parse(&p.to_can_bytes()).is_ok());
        }
    }
    let s = asm.stats();
    assert_eq!(s.frames, 4 * s.messages + s.discarded_frames + asm.pending() as u32);
});
