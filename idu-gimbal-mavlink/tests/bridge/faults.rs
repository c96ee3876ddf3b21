//! Damaged input and a full output: garbage, corruption and any split, a frame cut at a
//! datagram's end, and every frame a full outbox refuses, counted.

use super::*;

#[test]
fn garbage_corruption_and_any_split_lose_only_what_was_damaged() {
    let mut stream = Vec::new();
    stream.extend_from_slice(&[0x00, 0xFD, 0x13, 0x55]);
    stream.extend(frame(
        GCS,
        0,
        &command((0, 154), MavCmd::RequestMessage, 283.0, 0.0),
    ));
    let mut bad = frame(
        GCS,
        1,
        &command((0, 154), MavCmd::RequestMessage, 283.0, 0.0),
    );
    bad[20] ^= 0x40;
    stream.extend(bad);
    stream.extend(frame(
        GCS,
        2,
        &command((0, 154), MavCmd::DoSetMode, 0.0, 0.0),
    ));
    for cut in 0..stream.len() {
        let mut b = fresh();
        b.receive_all(&stream[..cut], t(0));
        b.receive_all(&stream[cut..], t(0));
        let acks: Vec<CommandAck> = of(&sent(&mut b));
        let results: Vec<MavResult> = acks.iter().map(|a| a.result).collect();
        assert_eq!(
            results,
            [MavResult::Accepted, MavResult::Unsupported],
            "cut at {cut}"
        );
        assert_eq!(b.stats().reader.bad_frames, 1, "cut at {cut}");
    }
}

mod no_panic {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Any bytes, biased toward MAVLink 2's start byte and real frames cut anywhere:
        /// never a panic, and no more frames than the bytes can hold (12 bytes at least each).
        #[test]
        fn any_bytes(chunks in proptest::collection::vec(
            prop_oneof![
                proptest::collection::vec(any::<u8>(), 0..40),
                Just(vec![0xFD]),
                Just(frame(GCS, 0, &command((0, 154), MavCmd::RequestMessage, 283.0, 0.0))),
                Just(frame(AP, 0, &set_attitude(GimbalDeviceFlags::YAW_LOCK, 10.0, -95.0))),
                Just(frame(AP, 0, &heartbeat())),
            ],
            0..30,
        ), cut in 0usize..40) {
            let mut b = fresh();
            let bytes: Vec<u8> = chunks.concat();
            let cut = cut.min(bytes.len());
            let _ = receive_draining(&mut b, &bytes[..cut], t(0));
            let _ = receive_draining(&mut b, &bytes[cut..], t(1));
            b.poll(t(2));
            let _ = sent(&mut b);
            prop_assert!(b.stats().reader.frames as usize <= bytes.len() / 12 + 1);
        }
    }
}

/// 10^6 garbage bytes, half of them MAVLink 2 start bytes and plausible headers: the reader
/// holds less than one frame at all times and the bridge acts on nothing.
#[test]
fn a_million_garbage_bytes_into_the_bridge() {
    use idu_gimbal_mavlink::framing::MAX_FRAME_LEN;
    let mut b = fresh();
    let mut x = 0x2545_F491_u32;
    let mut chunk = [0u8; 1000];
    for i in 0..1000 {
        for byte in chunk.iter_mut() {
            // xorshift: cheap, deterministic noise.
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            *byte = if x & 1 == 0 { 0xFD } else { (x >> 8) as u8 };
        }
        b.receive_all(&chunk, t(i));
        assert!(b.reader().pending() < MAX_FRAME_LEN);
    }
    let s = b.stats();
    assert_eq!(
        s.acks + s.angle_setpoints + s.rate_setpoints + s.vehicle_updates,
        0
    );
    // A 12-byte MAVLink 2 frame with a matching CRC could occur by chance (2^-16 once the
    // header parses); the counters say how the bytes went either way.
    assert!(s.reader.bad_frames > 0 || s.reader.unsupported > 0);
    assert!(s.reader.skipped_bytes > 0);
}

#[test]
fn a_frame_cut_at_a_datagrams_end_is_dropped_there_and_counted() {
    let mut b = fresh();
    let whole = frame(
        GCS,
        0,
        &command((0, 154), MavCmd::RequestMessage, 283.0, 0.0),
    );
    // Its first 20 bytes alone: nothing acted on, the 20 dropped at the datagram's end.
    let taken = b.receive_datagram(&whole[..20], t(0));
    assert_eq!((taken.bytes, taken.good), (20, 0));
    assert_eq!(b.stats().reader.skipped_bytes, 20);
    // The next datagram starts afresh: the whole request, answered once.
    let taken = b.receive_datagram(&whole, t(1));
    assert_eq!((taken.bytes, taken.good), (whole.len(), 1));
    assert_eq!(of::<CommandAck>(&sent(&mut b)).len(), 1);
    assert_eq!(b.stats().reader.skipped_bytes, 20);
}

/// Nothing is lost quietly: with its output never taken, the bridge's outbox fills, and
/// every frame it then refuses is counted. A twin whose output is taken every poll says how
/// many frames the same polls send.
#[test]
fn every_frame_a_full_outbox_refuses_is_counted() {
    let (mut taken, mut full) = (bridge(), bridge());
    let mut sent_by_taken = 0;
    for ms in (10..200_000).step_by(10) {
        taken.poll(t(ms));
        full.poll(t(ms));
        sent_by_taken += sent(&mut taken).len();
    }
    let kept = sent(&mut full).len();
    let refused = full.stats().outbox_full as usize;
    assert!(kept > 0 && refused > 0, "kept {kept}, refused {refused}");
    assert_eq!(kept + refused, sent_by_taken);
    assert_eq!(taken.stats().outbox_full, 0);
}
