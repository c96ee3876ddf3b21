//! The no-panic properties, written once: the cargo-fuzz targets call them, and
//! `tests/no_panic.rs` includes this file (`#[path]`) so that `cargo test` checks the same
//! properties on every run. Each panics (an `assert!`) when its property fails.

use idu_gimbal::geo::Position;
use idu_gimbal::link::postback::PostbackAssembler;
use idu_gimbal::link::SerialLink;
use idu_gimbal::link::{Config, Event, Link, RxId};
use idu_gimbal::port::SerialStream;
use idu_gimbal::wire::control::{Command, GimbalCommand, Pitch, Rate};
use idu_gimbal::wire::serial::{control_frame, StreamItem, StreamParser, MAX_FRAME_LEN};
use idu_gimbal::wire::vehicle::{Altitude, Attitude, Gps};
use idu_gimbal::wire::{ids, postback::Postback, Frame};
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
/// assembler never panics, emits only the message of the last four whole frames it was
/// given on the postback ID, their CRC holding, and every frame is accounted for.
pub fn assembler(data: &[u8]) {
    let mut asm = PostbackAssembler::new();
    let mut t = 0u32;
    // The last four whole frames on the postback ID, the newest last; `whole` of them so far.
    let mut last = [[0u8; 8]; 4];
    let mut whole = 0usize;
    for chunk in data.chunks(11) {
        let [sel, dt, rest @ ..] = chunk else { break };
        t = t.wrapping_add(u32::from(*dt));
        let id = if sel & 1 == 0 {
            ids::POSTBACK
        } else {
            ids::CONTROL
        };
        let len = usize::from(sel >> 1) % (rest.len() + 1);
        let frame = &rest[..len];
        if let (ids::POSTBACK, Ok(f)) = (id, <[u8; 8]>::try_from(frame)) {
            last.rotate_left(1);
            last[3] = f;
            whole += 1;
        }
        if let Some(p) = asm.feed(id, frame, Instant::from_millis(t)) {
            assert!(whole >= 4, "{p:?} from {whole} whole frames");
            assert_eq!(Postback::parse(&last.concat()), Ok(p));
        }
    }
    let s = asm.stats();
    assert_eq!(
        s.frames,
        4 * s.messages + s.discarded_frames + asm.pending() as u32
    );
}

/// Any sequence of operations on a [`Link`] with small queues, as 12-byte records (operation,
/// time step, two arguments, eight bytes): received frames of any ID and length, time,
/// commands, rate holds, texts, vehicle data, point-at, every transmit outcome, events. The
/// link never panics, and its accounting holds: every received frame is counted once,
/// `has_transmit` says whether a frame is waiting, and link transitions alternate and end in
/// the link's state.
pub fn link(data: &[u8]) {
    let mut link: Link<3, 4> = Link::new(Config::default());
    let mut t = 0u32;
    let mut received = 0u32;
    let mut told_up = false;
    let take_events = |link: &mut Link<3, 4>, told_up: &mut bool| {
        while let Some(e) = link.next_event() {
            match e {
                Event::LinkUp => assert!(!*told_up, "LinkUp twice"),
                Event::LinkDown => assert!(*told_up, "LinkDown twice"),
                _ => continue,
            }
            *told_up = !*told_up;
        }
    };
    for rec in data.chunks(12) {
        let [op, dt, a, b, rest @ ..] = rec else {
            break;
        };
        // Steps of up to about a second: every timeout is reached.
        t = t.wrapping_add(u32::from(*dt) * 4);
        let now = Instant::from_millis(t);
        let mut bytes = [0u8; 8];
        bytes[..rest.len()].copy_from_slice(rest);
        let (a, b) = (*a, *b);
        let centi = |x: u8| i16::from(x as i8) * 100;
        match op % 16 {
            0..=2 => {
                let id = match a % 4 {
                    0 | 1 => ids::POSTBACK,
                    2 => ids::CONTROL,
                    _ => u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]) & 0x1FFF_FFFF,
                };
                let len = usize::from(b % 10).min(rest.len());
                link.receive(id, &rest[..len], now);
                received += 1;
            }
            3 => {
                link.receive(RxId::Other, &[], now);
                received += 1;
            }
            4 => {
                if let Ok(c) = Command::decode(&bytes) {
                    let _ = link.send(c);
                }
            }
            5 => {
                if let Ok(r) = Rate::from_centi(centi(a), centi(b)) {
                    let _ = link.set_rate(r, now);
                }
            }
            6 => link.stop_rate(),
            7 => {
                let _ = link.send_text(&rest[..usize::from(b) % (rest.len() + 1)]);
            }
            8 => {
                // Stamps a little in the past, or (clock skew) in the future.
                let stamp = now
                    .add_millis(u32::from(b) * 16)
                    .add_millis(u32::MAX - 2047);
                match a % 3 {
                    0 => {
                        if let Ok(att) = Attitude::from_centideg(
                            centi(bytes[0]) / 2,
                            centi(bytes[1]),
                            centi(bytes[2]),
                        ) {
                            link.set_attitude(att, stamp);
                        }
                    }
                    1 => {
                        let lat = i32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]])
                            % 900_000_000;
                        let lon = i32::from_le_bytes([bytes[4], bytes[5], bytes[6], bytes[7]])
                            % 1_800_000_000;
                        if let Ok(g) = Gps::from_e7(lat, lon) {
                            link.set_gps(g, stamp);
                        }
                    }
                    _ => link.set_altitude(
                        Altitude::from_cm(i32::from(i16::from_le_bytes([bytes[0], bytes[1]])) * 10),
                        stamp,
                    ),
                }
            }
            9 => {
                if a & 1 == 0 {
                    let lat = f64::from(i16::from_le_bytes([bytes[0], bytes[1]])) / 400.0;
                    let lon = f64::from(i16::from_le_bytes([bytes[2], bytes[3]])) / 200.0;
                    let alt = f64::from(i16::from_le_bytes([bytes[4], bytes[5]]));
                    if let Ok(p) = Position::new(lat, lon, alt) {
                        link.point_at(p);
                    }
                } else {
                    link.stop_pointing();
                }
            }
            10..=12 => {
                let waiting = link.has_transmit();
                let frame = link.next_transmit();
                assert_eq!(
                    waiting,
                    frame.is_some(),
                    "has_transmit disagrees with the queue"
                );
                if let Some(f) = frame {
                    match b % 4 {
                        0 | 1 => link.transmit_done(None),
                        2 => link.transmit_refused(f),
                        _ => {
                            // The driver hands back a frame it displaced: one sent before,
                            // or anything at all.
                            let id = [
                                ids::CONTROL,
                                ids::ATTITUDE,
                                ids::GPS,
                                ids::ALTITUDE,
                                ids::TEXT,
                                ids::TEXT_END,
                                0x123,
                            ][usize::from(a) % 7];
                            let displaced = if a & 0x80 == 0 {
                                f
                            } else {
                                Frame::new(id, bytes)
                            };
                            link.transmit_done(Some(displaced));
                        }
                    }
                }
            }
            13 => take_events(&mut link, &mut told_up),
            _ => link.poll(now),
        }
    }
    take_events(&mut link, &mut told_up);
    assert_eq!(
        told_up,
        link.is_link_up(),
        "the last transition told is not the link's state"
    );
    assert_eq!(
        link.stats().frames_received,
        received,
        "a received frame was not counted once"
    );
}

/// Any sequence of operations on a [`SerialLink`] with a small queue, as 4-byte records
/// (operation, time step, two arguments): garbage bytes and real postbacks received in any
/// split, commands, rate holds, polls, and transmission with writes of any length. The link
/// never panics; every received byte is accounted for (in a frame, skipped, or pending);
/// and the bytes written, read back by an independent parser, are whole control frames,
/// never interleaved, one per frame the link counts as sent.
pub fn serial_link(data: &[u8]) {
    let mut link: SerialLink<3> = SerialLink::new(Config::default());
    let mut stream = SerialStream::new();
    let mut wire = StreamParser::new();
    let mut t = 0u32;
    // The rest of a postback whose first part was received.
    let mut tail: Option<([u8; 27], usize)> = None;
    let mut pitches = Vec::new();
    let mut on_wire = Vec::new();
    for rec in data.chunks(4) {
        let [op, dt, a, b] = *rec else {
            break;
        };
        t = t.wrapping_add(u32::from(dt) * 4);
        let now = Instant::from_millis(t);
        match op % 8 {
            0 => stream.receive(&mut link, rec, now),
            1 => {
                let p = Postback {
                    pitch: i16::from(a as i8) * 10,
                    heading: u16::from(b) * 100,
                    ..Postback::default()
                }
                .to_stream_bytes();
                let cut = usize::from(b) % 28;
                stream.receive(&mut link, &p[..cut], now);
                tail = Some((p, cut));
            }
            2 => {
                if let Some((p, cut)) = tail.take() {
                    stream.receive(&mut link, &p[cut..], now);
                }
            }
            3 => {
                if let Ok(p) = Pitch::from_deci(i16::from_le_bytes([a, b]) % 600) {
                    let c = GimbalCommand::Pitch(p);
                    if link.send(c).is_ok() {
                        pitches.push(Command::from(c).encode());
                    }
                }
            }
            4 => {
                if let Ok(r) = Rate::from_centi(i16::from(a as i8) * 100, i16::from(b as i8) * 100)
                {
                    let _ = link.set_rate(r, now);
                }
            }
            5 | 6 => {
                let bytes = stream.transmit_bytes(&mut link);
                let n = usize::from(a) % (bytes.len() + 2);
                on_wire.extend(wire.feed(&bytes[..n.min(bytes.len())]));
                stream.transmit_written(&mut link, n);
            }
            _ => link.poll(now),
        }
    }
    // Drain what waits: a started frame is finished.
    loop {
        let bytes = stream.transmit_bytes(&mut link);
        if bytes.is_empty() {
            break;
        }
        let n = bytes.len();
        on_wire.extend(wire.feed(bytes));
        stream.transmit_written(&mut link, n);
    }
    // Every pitch command accepted went out, once, in order (nothing else sends pitch).
    let pitch_frames: Vec<[u8; 8]> = on_wire
        .iter()
        .filter_map(|item| match item {
            StreamItem::Control(d) if d[1] == 0x08 && d[2] == 0x02 => Some(*d),
            _ => None,
        })
        .collect();
    assert_eq!(
        pitch_frames, pitches,
        "an accepted command was lost or repeated"
    );
    let w = wire.stats();
    assert_eq!(
        (
            w.skipped_bytes,
            w.crc_errors,
            w.invalid_frames,
            wire.pending()
        ),
        (0, 0, 0, 0),
        "the bytes written are not whole frames"
    );
    let (l, s) = (link.stats(), stream.stats());
    assert_eq!(
        w.control_frames, l.frames_sent,
        "a frame sent is not on the wire once"
    );
    assert_eq!(s.bytes_sent, 24 * w.control_frames);
    let r = s.stream;
    assert_eq!(
        s.bytes_received,
        24 * r.control_frames
            + 27 * r.postbacks
            + r.skipped_bytes
            + stream.parser().pending() as u32,
        "a received byte is not accounted for"
    );
    assert_eq!(l.postbacks, r.postbacks);
}
