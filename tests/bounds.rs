//! Resource bounds of the inputs the crate takes from outside (the table in TESTING.md):
//! whatever arrives, memory stays fixed and a call's work is bounded, and what is dropped
//! is counted.
#![cfg(feature = "mock")]

use embedded_can::{nb::Can, ExtendedId, Frame as _};
use idu_gimbal::link::postback::PostbackAssembler;
use idu_gimbal::link::text::TextAssembler;
use idu_gimbal::link::Config;
use idu_gimbal::mock::{Bus, MockFrame};
use idu_gimbal::wire::ids;
use idu_gimbal::wire::postback::Postback;
use idu_gimbal::wire::serial::{StreamParser, MAX_FRAME_LEN};
use idu_gimbal::Instant;
use idu_gimbal::{CanPort, Link, Port};

/// 10^6 garbage bytes, heavy in the stream's own vocabulary (`EB 90 0A/0C`): the parser
/// holds less than one frame at all times, yields nothing, and every byte is skipped or
/// pending.
#[test]
fn a_million_garbage_bytes_into_the_stream_parser() {
    let mut rng = fastrand::Rng::with_seed(12);
    let vocabulary = [0xEB, 0x90, 0x0A, 0x0C, 0x00, 0x40, 0x88];
    let mut p = StreamParser::new();
    let mut items = 0;
    let mut fed = 0u32;
    for _ in 0..1_000 {
        let chunk: Vec<u8> = (0..1_000)
            .map(|_| {
                if rng.bool() {
                    vocabulary[rng.usize(..vocabulary.len())]
                } else {
                    rng.u8(..)
                }
            })
            .collect();
        items += p.feed(&chunk).count();
        fed += chunk.len() as u32;
        assert!(p.pending() < MAX_FRAME_LEN);
    }
    let s = p.stats();
    // A 24-byte frame whose CRC and fixed bytes all hold by chance is possible in principle
    // (2^-16 for the CRC alone, times the 11 fixed bytes); with this seed none does.
    assert_eq!(items, 0);
    assert_eq!((s.control_frames, s.postbacks), (0, 0));
    assert_eq!(s.skipped_bytes + p.pending() as u32, fed);
    assert!(
        s.crc_errors + s.invalid_frames > 0,
        "the vocabulary made candidates"
    );
}

/// A flood of frames on the bus: one poll takes at most `max_rx_per_poll` of them, so a
/// babbling node cannot stall the main loop; the rest wait in the controller's FIFO (or are
/// lost to its overrun, which the driver counts), and later polls take them.
#[test]
fn one_poll_takes_at_most_max_rx_per_poll_frames() {
    let bus: Bus<2, 256> = Bus::new(3);
    let config = Config {
        max_rx_per_poll: core::num::NonZeroU16::new(8).unwrap(),
        ..Config::default()
    };
    let mut gimbal: Link = Link::new(config);
    let mut port = CanPort::new(bus.endpoint(0).unwrap());
    let mut babbler = bus.endpoint(1).unwrap();
    let id = ExtendedId::new(0x1234).unwrap();
    for i in 0..300u32 {
        let _ = babbler.transmit(&MockFrame::new(id, &i.to_le_bytes()).unwrap());
    }
    let _ = port.poll(&mut gimbal, Instant::from_millis(0));
    // Eight receive calls: the FIFO's overrun (reported once, by the first) and 7 frames.
    let errors = port.stats().driver_errors;
    assert_eq!(gimbal.stats().frames_received + errors.total(), 8);
    assert_eq!(errors.overrun, 1);
    for ms in 1..40 {
        let _ = port.poll(&mut gimbal, Instant::from_millis(ms));
    }
    // 256 fit the receive FIFO; the other 44 overran it, counted once as an overrun error.
    assert_eq!(gimbal.stats().frames_received, 256);
    assert_eq!(gimbal.stats().ignored_frames, 256);
    assert_eq!(port.stats().driver_errors.overrun, 1);
}

/// Garbage dense in the stream's own vocabulary, so false headers are frequent.
fn garbage_byte(rng: &mut fastrand::Rng) -> u8 {
    match rng.u8(..8) {
        0 => 0xEB,
        1 => 0x90,
        2 => 0x0A,
        3 => 0x0C,
        _ => rng.u8(..),
    }
}

#[test]
fn a_hundred_thousand_random_frames_through_the_assembler() {
    // Seeded: the same frames every run.
    let mut rng = fastrand::Rng::with_seed(0xD1B5_4A32_D192_ED03);
    let mut asm = PostbackAssembler::new();
    let mut t = 0u32;
    let good = Postback::default().to_can_frames();
    let mut fed_good = 0u32;
    for i in 0..100_000u32 {
        t = t.wrapping_add(rng.u32(..64));
        // A good message every 50 frames, random frames otherwise.
        if i % 50 == 0 {
            for f in &good {
                assert!(asm.pending() <= 3);
                let _ = asm.feed(ids::POSTBACK, f, Instant::from_millis(t));
            }
            fed_good += 1;
            continue;
        }
        let id = if rng.bool() {
            ids::POSTBACK
        } else {
            rng.u32(..=0x1FFF_FFFF)
        };
        let mut data = [0u8; 9];
        for b in &mut data {
            *b = garbage_byte(&mut rng);
        }
        let len = rng.usize(..=9);
        let _ = asm.feed(id, &data[..len], Instant::from_millis(t));
        assert!(asm.pending() <= 3, "{}", asm.pending());
    }
    let s = asm.stats();
    assert_eq!(
        s.frames,
        4 * s.messages + s.discarded_frames + asm.pending() as u32
    );
    assert!(s.messages >= fed_good, "{s:?}");
}

/// A text stream with no end frame, 800 kB long: the assembler holds at most its capacity,
/// refuses the text once with an error, counts it, and takes the next text after the end.
#[test]
fn an_endless_text_stays_within_capacity() {
    let mut text: TextAssembler<64> = TextAssembler::new();
    let mut errors = 0;
    for i in 0..100_000u32 {
        let chunk = [b'a' + (i % 26) as u8; 8];
        if text.feed(ids::TEXT, &chunk).is_err() {
            errors += 1;
        }
        assert!(text.pending() <= 64, "{}", text.pending());
    }
    assert_eq!(text.feed(ids::TEXT_END, b"end\0\0\0\0\0"), Ok(None));
    assert_eq!(errors, 1);
    assert_eq!((text.stats().overflows, text.stats().messages), (1, 0));
    assert_eq!(text.feed(ids::TEXT_END, b"next\0\0\0\0"), Ok(Some("next")));
}
