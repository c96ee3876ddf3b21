//! The frame reader's own parse (header fields in place, the checksum taken while bytes are
//! copied in) against `mavio`'s parse of the same bytes: every field, every checksum
//! verdict and every decoded message must agree, for valid frames, corrupted frames and
//! garbage, split anywhere.

mod common;

use common::*;
use idu_gimbal_mavlink::framing::{Check, DecodeError, FrameReader, ReceivedFrame};
use mavio::dialects::common::enums::{GimbalDeviceFlags, MavCmd};
use mavio::dialects::common::messages::{
    AutopilotStateForGimbalDevice, CommandLong, GimbalDeviceSetAttitude, GlobalPositionInt,
    Heartbeat,
};
use mavio::mavspec::rust::spec::MessageSpecStatic;
use mavio::protocol::{Frame, Payload, V2};
use proptest::prelude::*;

/// `frame.decode::<M>()` against mavio's `decode_message::<M>()` of its own parse.
fn same_decode<M>(f: &ReceivedFrame<'_>, m: &Frame<V2>)
where
    M: MessageSpecStatic
        + for<'p> TryFrom<&'p Payload, Error = mavio::error::SpecError>
        + std::fmt::Debug,
{
    let ours = f.decode::<M>();
    if m.message_id() != M::message_id() {
        assert_eq!(ours.err(), Some(DecodeError::OtherMessage(m.message_id())));
        return;
    }
    match m.decode_message::<M>() {
        // Compared as text: NaN fields (rates left out) are not equal to themselves.
        Ok(theirs) => assert_eq!(format!("{:?}", ours.ok()), format!("{:?}", Some(theirs))),
        // mavio's decode_message checks the checksum, then decodes: either may fail.
        Err(_) => assert!(ours.is_err(), "mavio refused, we decoded {ours:?}"),
    }
}

/// Feeds `bytes` in the given pieces; checks every frame against mavio and returns the
/// (system, component, message id) of each frame whose checksum held for its message.
fn read_and_compare(bytes: &[u8], cuts: &[usize], extra: u8) -> Vec<(u8, u8, u32)> {
    let mut good = Vec::new();
    let mut reader = FrameReader::new();
    let mut check = |f: &ReceivedFrame<'_>| {
        let m = f
            .to_frame()
            .expect("mavio parses every frame the reader hands out");
        assert_eq!(f.bytes().len(), m.size());
        assert_eq!(f.sequence(), m.sequence());
        assert_eq!(f.system_id(), m.system_id());
        assert_eq!(f.component_id(), m.component_id());
        assert_eq!(f.message_id(), m.message_id());
        assert_eq!(f.is_signed(), m.is_signed());
        assert_eq!(f.checksum(), m.checksum());
        // The same payload up to MAVLink 2's zero-extension: mavio keeps it without trailing
        // zeros but never empty (a length-0 frame, which only damage makes, reads as [0]).
        let (ours, theirs) = (f.payload(), m.payload().bytes());
        let n = ours.len().min(theirs.len());
        assert_eq!(ours[..n], theirs[..n]);
        assert!(ours[n..].iter().chain(&theirs[n..]).all(|&b| b == 0));
        for x in [
            extra,
            Heartbeat::crc_extra(),
            CommandLong::crc_extra(),
            GimbalDeviceSetAttitude::crc_extra(),
            AutopilotStateForGimbalDevice::crc_extra(),
            GlobalPositionInt::crc_extra(),
        ] {
            assert_eq!(
                f.checksum_holds(x),
                m.validate_checksum_with_crc_extra(x).is_ok(),
                "CRC_EXTRA {x}"
            );
        }
        same_decode::<Heartbeat>(f, &m);
        same_decode::<CommandLong>(f, &m);
        same_decode::<GimbalDeviceSetAttitude>(f, &m);
        same_decode::<AutopilotStateForGimbalDevice>(f, &m);
        same_decode::<GlobalPositionInt>(f, &m);
        let own = match f.message_id() {
            0 => Heartbeat::crc_extra(),
            76 => CommandLong::crc_extra(),
            284 => GimbalDeviceSetAttitude::crc_extra(),
            286 => AutopilotStateForGimbalDevice::crc_extra(),
            33 => GlobalPositionInt::crc_extra(),
            _ => return Check::Unhandled,
        };
        if f.checksum_holds(own) {
            good.push((f.system_id(), f.component_id(), f.message_id()));
            Check::Handled
        } else {
            Check::Bad
        }
    };
    let mut at = 0;
    for &cut in cuts {
        let cut = cut.clamp(at, bytes.len());
        reader.feed(&bytes[at..cut], &mut check);
        at = cut;
    }
    reader.feed(&bytes[at..], &mut check);
    good
}

fn message(kind: u8, v: f32, w: u32) -> Vec<u8> {
    let from = ((w >> 8) as u8, (w >> 16) as u8);
    let seq = w as u8;
    match kind % 5 {
        0 => frame(from, seq, &heartbeat()),
        1 => frame(
            from,
            seq,
            &command((0, 154), MavCmd::RequestMessage, v, v * 2.0),
        ),
        2 => frame(
            from,
            seq,
            &GimbalDeviceSetAttitude {
                target_system: 1,
                target_component: 154,
                flags: GimbalDeviceFlags::YAW_LOCK,
                q: [v, -v, 0.5, 0.0],
                angular_velocity_x: f32::NAN,
                angular_velocity_y: v,
                angular_velocity_z: 0.0,
            },
        ),
        3 => frame(
            from,
            seq,
            &AutopilotStateForGimbalDevice {
                target_system: 1,
                target_component: 154,
                time_boot_us: u64::from(w) << 20,
                q: [1.0, v, 0.0, -v],
                vx: v,
                ..Default::default()
            },
        ),
        _ => frame(
            from,
            seq,
            &GlobalPositionInt {
                time_boot_ms: w,
                lat: w as i32,
                lon: -(w as i32),
                alt: 1000,
                hdg: 0,
                ..Default::default()
            },
        ),
    }
}

proptest! {
    /// Valid frames: every one found, in order, its checksum holding, all fields as mavio
    /// reads them, whatever the split.
    #[test]
    fn valid_frames_read_as_mavio_reads_them(
        msgs in proptest::collection::vec((any::<u8>(), -2.0f32..2.0, any::<u32>()), 1..12),
        cuts in proptest::collection::vec(0usize..600, 0..12),
        extra in any::<u8>(),
    ) {
        let mut bytes = Vec::new();
        let mut expected = Vec::new();
        for &(kind, v, w) in &msgs {
            let f = message(kind, v, w);
            expected.push((f[5], f[6], u32::from_le_bytes([f[7], f[8], f[9], 0])));
            bytes.extend(f);
        }
        let mut cuts = cuts;
        cuts.sort_unstable();
        prop_assert_eq!(read_and_compare(&bytes, &cuts, extra), expected);
    }

    /// Corrupted frames among garbage: the same fields and checksum verdicts as mavio's,
    /// for every frame the reader hands out (damaged ones included).
    #[test]
    fn damaged_streams_agree_with_mavio(
        items in proptest::collection::vec(prop_oneof![
            (any::<u8>(), -2.0f32..2.0, any::<u32>()).prop_map(|(k, v, w)| message(k, v, w)),
            ((any::<u8>(), -2.0f32..2.0, any::<u32>()), any::<prop::sample::Index>(), 1u8..=255)
                .prop_map(|((k, v, w), at, x)| {
                    let mut f = message(k, v, w);
                    let i = at.index(f.len());
                    f[i] ^= x;
                    f
                }),
            proptest::collection::vec(any::<u8>(), 0..30),
            Just(vec![0xFD]),
        ], 1..16),
        cuts in proptest::collection::vec(0usize..800, 0..16),
        extra in any::<u8>(),
    ) {
        let bytes: Vec<u8> = items.concat();
        let mut cuts = cuts;
        cuts.sort_unstable();
        read_and_compare(&bytes, &cuts, extra);
    }
}

#[test]
fn a_frame_of_another_message_is_not_decoded() {
    let bytes = frame(AP, 0, &heartbeat());
    let mut reader = FrameReader::new();
    let mut seen = 0;
    reader.feed(&bytes, |f| {
        seen += 1;
        assert_eq!(f.decode::<CommandLong>(), Err(DecodeError::OtherMessage(0)));
        assert!(f.decode::<Heartbeat>().is_ok());
        Check::Handled
    });
    assert_eq!(seen, 1);
}

#[test]
fn a_corrupt_payload_fails_its_checksum() {
    let mut bytes = frame(AP, 0, &heartbeat());
    bytes[12] ^= 0x01;
    let mut reader = FrameReader::new();
    let mut seen = 0;
    reader.feed(&bytes, |f| {
        seen += 1;
        assert_eq!(f.decode::<Heartbeat>(), Err(DecodeError::Checksum));
        Check::Bad
    });
    assert_eq!(seen, 1);
    assert_eq!(reader.stats().bad_frames, 1);
}

/// A bad frame whose bytes hold a good frame, then garbage, then another good frame: both
/// good frames are read, and the garbage between them is skipped, not taken for the start
/// of a frame of some unknown message that would swallow the next one. Every byte is
/// accounted for. (Found by `damaged_streams_agree_with_mavio` in a release build.)
#[test]
fn garbage_after_a_frame_found_inside_a_bad_one_is_skipped() {
    let good = frame(AP, 1, &heartbeat());
    let garbage = [0xFC, 14, 0, 0, 7, 1, 1, 2, 3, 0]; // reads as an unknown message, id 770
    let tail = frame(AP, 2, &heartbeat());
    let inside = good.len() + garbage.len() + tail.len();
    // A GLOBAL_POSITION_INT header whose length covers all of it; its checksum fails.
    let mut bytes = vec![0xFD, (inside - 2) as u8, 0, 0, 0, 0, 0, 33, 0, 0];
    bytes.extend(&good);
    bytes.extend(garbage);
    bytes.extend(&tail);
    let mut reader = FrameReader::new();
    let mut seqs = Vec::new();
    reader.feed(&bytes, |f| match f.message_id() {
        0 | 33 => match f.decode::<Heartbeat>() {
            Ok(_) => {
                seqs.push(f.sequence());
                Check::Handled
            }
            Err(_) => Check::Bad,
        },
        _ => Check::Unhandled,
    });
    assert_eq!(seqs, [1, 2]);
    let s = reader.stats();
    assert_eq!((s.frames, s.bad_frames), (2, 1));
    assert_eq!(reader.pending(), 0);
    assert_eq!(
        s.skipped_bytes as usize + good.len() + tail.len(),
        bytes.len(),
        "every byte is in a frame or skipped"
    );
}

/// The (system, message id) of each frame whose checksum held, reading `datagrams` each
/// with `end_datagram` after it.
fn read_datagrams(datagrams: &[Vec<u8>]) -> (Vec<(u8, u32)>, FrameReader) {
    let mut good = Vec::new();
    let mut reader = FrameReader::new();
    let mut check = |f: &ReceivedFrame<'_>| {
        if f.decode::<Heartbeat>().is_ok() {
            good.push((f.system_id(), f.message_id()));
            Check::Handled
        } else {
            Check::Unhandled
        }
    };
    for d in datagrams {
        reader.feed(d, &mut check);
        reader.end_datagram(&mut check);
        assert_eq!(
            reader.pending(),
            0,
            "nothing carried into the next datagram"
        );
    }
    (good, reader)
}

#[test]
fn a_frame_cut_at_a_datagrams_end_never_swallows_the_next_datagram() {
    let hb = |sys: u8| frame((sys, 190), 0, &heartbeat());
    // Sender 1's datagram ends with half a heartbeat; sender 2's whole heartbeat follows.
    let mut first = hb(1);
    let half = hb(3);
    first.extend_from_slice(&half[..half.len() / 2]);
    let (good, reader) = read_datagrams(&[first, hb(2)]);
    assert_eq!(good, [(1, 0), (2, 0)]);
    // The half frame's bytes are counted, none silently lost.
    assert_eq!(reader.stats().skipped_bytes as usize, half.len() / 2);
    // A stray start byte claiming a long payload in front of a whole frame, in one
    // datagram: the frame inside it is still found at the datagram's end.
    let mut d = vec![0xFD, 200, 0, 0, 0, 1, 1, 0, 0, 0];
    d.extend_from_slice(&hb(4));
    let (good, reader) = read_datagrams(&[d]);
    assert_eq!(good, [(4, 0)]);
    assert_eq!(reader.stats().skipped_bytes, 10);
}

proptest! {
    /// Whole frames in any number of datagrams, each maybe followed by a cut-off frame:
    /// every whole frame is read, whatever the cut-off bytes were.
    #[test]
    fn every_whole_frame_of_every_datagram_is_read(
        datagrams in proptest::collection::vec((1u8..4, 0usize..40), 1..12),
    ) {
        let mut bytes = Vec::new();
        let mut expected = Vec::new();
        let mut sys = 0u8;
        for (whole, cut) in &datagrams {
            let mut d = Vec::new();
            for _ in 0..*whole {
                sys = sys.wrapping_add(1);
                d.extend_from_slice(&frame((sys, 190), 0, &heartbeat()));
                expected.push((sys, 0));
            }
            let tail = frame((0xEE, 190), 0, &heartbeat());
            d.extend_from_slice(&tail[..(*cut).min(tail.len() - 1)]);
            bytes.push(d);
        }
        let (good, _) = read_datagrams(&bytes);
        prop_assert_eq!(good, expected);
    }
}

proptest! {
    /// A caller that says `Wait` to some frames, in a stream split anywhere: each waiting
    /// frame is kept whole and offered again first, no byte after it is taken while it
    /// waits, and in the end every frame is handed out once, in order, nothing skipped.
    #[test]
    fn a_waiting_frame_is_offered_again_first_and_nothing_after_it_is_taken(
        count in 1usize..12,
        waits in prop::collection::vec(0u8..3, 1..30),
        cuts in prop::collection::vec(1usize..60, 1..30),
    ) {
        let frames: Vec<Vec<u8>> = (0..count)
            .map(|i| frame((i as u8 + 1, 190), i as u8, &heartbeat()))
            .collect();
        let bytes = frames.concat();
        let mut reader = FrameReader::new();
        let mut seen = Vec::new();
        let mut waits = waits.iter().cycle();
        let mut at = 0;
        // Waits in a row: at most two, so that the run ends.
        let mut in_a_row = 0;
        for &len in cuts.iter().cycle() {
            let end = (at + len).min(bytes.len());
            let taken = reader.feed(&bytes[at..end], |f| {
                if *waits.next().unwrap_or(&0) == 0 || in_a_row == 2 {
                    in_a_row = 0;
                    seen.push(f.system_id());
                    Check::Handled
                } else {
                    in_a_row += 1;
                    Check::Wait
                }
            });
            prop_assert!(taken <= end - at);
            if reader.is_waiting() {
                // It holds exactly the frame that waits: the bytes taken end with it.
                let held = reader.pending();
                prop_assert_eq!(held, frames[0].len());
                let next = usize::from(seen.len() as u8);
                prop_assert_eq!(&bytes[at + taken - held..at + taken], &frames[next][..]);
            } else {
                prop_assert_eq!(taken, end - at);
            }
            at += taken;
            if at == bytes.len() && !reader.is_waiting() {
                break;
            }
        }
        prop_assert_eq!(seen, (1..=count as u8).collect::<Vec<_>>());
        prop_assert_eq!(reader.stats().skipped_bytes, 0);
        prop_assert_eq!(reader.stats().frames as usize, count);
    }
}

#[test]
fn a_frame_waiting_at_a_datagrams_end_stays_and_clear_forgets_it() {
    let hb = frame((1, 190), 0, &heartbeat());
    let mut reader = FrameReader::new();
    assert_eq!(reader.feed(&hb, |_| Check::Wait), hb.len());
    reader.end_datagram(|_| Check::Wait);
    // Not dropped as an unfinished frame: it waits whole.
    assert!(reader.is_waiting());
    assert_eq!(reader.pending(), hb.len());
    reader.clear();
    assert!(!reader.is_waiting());
    assert_eq!(reader.pending(), 0);
    assert_eq!(reader.stats().skipped_bytes, 0);
    assert_eq!(reader.stats().frames, 0);
    // Offered again, it is read as new.
    let mut n = 0;
    assert_eq!(
        reader.feed(&hb, |_| {
            n += 1;
            Check::Handled
        }),
        hb.len()
    );
    assert_eq!(n, 1);
}

#[test]
fn the_longest_frame_is_280_bytes_and_decode_errors_say_what_failed() {
    // MAVLink 2: a 10-byte header, 255 of payload, the checksum, a 13-byte signature.
    assert_eq!(idu_gimbal_mavlink::framing::MAX_FRAME_LEN, 280);
    assert_eq!(
        DecodeError::OtherMessage(77).to_string(),
        "the frame carries message id 77"
    );
    assert!(DecodeError::Checksum.to_string().contains("checksum"));
    assert!(!DecodeError::Payload.to_string().is_empty());
}

#[test]
fn to_frame_gives_mavio_s_frame_of_the_same_bytes() {
    let bytes = frame((7, 190), 42, &heartbeat());
    let mut reader = FrameReader::new();
    let mut seen = 0;
    reader.feed(&bytes, |f| {
        let ours = f.to_frame().expect("mavio reads a whole frame");
        assert_eq!(
            (
                ours.system_id(),
                ours.component_id(),
                ours.sequence(),
                ours.message_id()
            ),
            (7, 190, 42, 0)
        );
        // Its own fields, not the reader's: the heartbeat sent, the checksum's bytes.
        let decoded: Heartbeat = ours.decode_message().unwrap();
        assert_eq!(format!("{decoded:?}"), format!("{:?}", heartbeat()));
        let crc = &bytes[bytes.len() - 2..];
        assert_eq!(ours.checksum(), u16::from_le_bytes([crc[0], crc[1]]));
        seen += 1;
        Check::Unhandled
    });
    assert_eq!(seen, 1);
}

#[test]
fn an_outbox_is_empty_until_a_frame_is_queued_and_again_once_it_is_written() {
    let mut out = idu_gimbal_mavlink::framing::Outbox::<300>::new();
    assert!(out.is_empty());
    out.push_payload(1, 154, 0, 50, &[1, 2, 3]).unwrap();
    assert!(!out.is_empty());
    let n = out.bytes().len();
    out.written(n);
    assert!(out.is_empty());
}

#[test]
fn a_frame_inside_a_datagram_s_unfinished_tail_is_read_and_the_rest_dropped() {
    // The datagram ends in a header that claims 255 bytes of payload; inside what follows
    // it, a whole heartbeat, then half of another.
    let hb = frame((3, 190), 0, &heartbeat());
    let mut datagram = vec![0xFD, 255, 0, 0, 0, 1, 1, 0, 0, 0];
    datagram.extend_from_slice(&hb);
    datagram.extend_from_slice(&hb[..hb.len() / 2]);
    let (good, reader) = read_datagrams(&[datagram.clone()]);
    assert_eq!(good, [(3, 0)]);
    assert_eq!(reader.pending(), 0);
    // Everything but the heartbeat was skipped, each byte counted once.
    assert_eq!(
        reader.stats().skipped_bytes as usize,
        datagram.len() - hb.len()
    );
}

/// MAVLink numbers each component's frames on its own (pymavlink and QGroundControl count
/// loss per system and component): frames from 154 and 100 interleaved are each 0, 1, 2 …
/// in their own component; a component past the outbox's [`COMPONENTS`] is refused, its
/// frame not queued.
#[test]
fn an_outbox_numbers_each_component_s_frames_on_their_own() {
    use idu_gimbal_mavlink::framing::{Outbox, OutboxError, COMPONENTS};
    let mut out = Outbox::<4096>::new();
    for from in [154, 100, 154, 154, 100, 154] {
        out.push_payload(1, from, 0, 50, &[1, 2, 3]).unwrap();
    }
    let mut seqs: Vec<(u8, u8)> = Vec::new();
    FrameReader::new().feed(out.bytes(), |f| {
        seqs.push((f.component_id(), f.sequence()));
        Check::Unhandled
    });
    assert_eq!(
        seqs,
        [(154, 0), (100, 0), (154, 1), (154, 2), (100, 1), (154, 3)]
    );
    let mut out = Outbox::<4096>::new();
    for c in 1..=COMPONENTS as u8 {
        out.push_payload(1, c, 0, 50, &[1]).unwrap();
    }
    let held = out.bytes().len();
    assert_eq!(
        out.push_payload(1, 200, 0, 50, &[1]),
        Err(OutboxError::Components)
    );
    assert_eq!(out.bytes().len(), held, "nothing of it queued");
    // The components it numbers go on.
    out.push_payload(1, 1, 0, 50, &[1]).unwrap();
}
