//! The fuzz targets' properties, run by `cargo test` so CI exercises them on every run.

use idu_gimbal::link::postback::PostbackAssembler;
use idu_gimbal::wire::control::Command;
use idu_gimbal::wire::serial::{control_frame, StreamItem, StreamParser, MAX_FRAME_LEN};
use idu_gimbal::wire::{ids, postback::Postback};
use idu_gimbal::Instant;
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn command_decode(data in proptest::collection::vec(any::<u8>(), 0..12)) {
        if let Ok(cmd) = Command::decode(&data) {
            prop_assert_eq!(&cmd.encode()[..], &data[..]);
        }
    }

    /// Bytes biased toward the stream's own vocabulary (`EB 90 0A/0C`), so that false
    /// headers and near-frames are common.
    #[test]
    fn stream_parser(
        data in proptest::collection::vec(prop_oneof![any::<u8>(), Just(0xEB), Just(0x90), Just(0x0A), Just(0x0C)], 0..300),
        cut in any::<usize>(),
    ) {
        let mut parser = StreamParser::new();
        let (a, b) = data.split_at(cut % (data.len() + 1));
        for part in [a, b] {
            for item in parser.feed(part) {
                if let StreamItem::Control(d) = item {
                    prop_assert!(data.windows(24).any(|w| w == control_frame(&d)));
                }
            }
            prop_assert!(parser.pending() < MAX_FRAME_LEN);
        }
    }

    #[test]
    fn assembler(data in proptest::collection::vec(prop_oneof![any::<u8>(), Just(0xEB), Just(0x90)], 0..400)) {
        let mut asm = PostbackAssembler::new();
        let mut t = 0u32;
        for chunk in data.chunks(11) {
            let [sel, dt, rest @ ..] = chunk else { break };
            t = t.wrapping_add(u32::from(*dt));
            let id = if sel & 1 == 0 { ids::POSTBACK } else { ids::CONTROL };
            let len = usize::from(sel >> 1) % (rest.len() + 1);
            if let Some(p) = asm.feed(id, &rest[..len], Instant::from_millis(t)) {
                prop_assert!(Postback::parse(&p.to_can_bytes()).is_ok());
            }
        }
        let s = asm.stats();
        prop_assert_eq!(s.frames, 4 * s.messages + s.discarded_frames + asm.pending() as u32);
    }
}
