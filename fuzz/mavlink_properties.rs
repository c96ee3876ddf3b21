//! The MAVLink bridge's no-panic property, written once: the cargo-fuzz target
//! `mavlink_bridge` calls it, and `idu-gimbal-mavlink/tests/no_panic.rs` includes this file
//! (`#[path]`) so that `cargo test` checks it on every run.

use idu_gimbal::link::{Config, Link};
use idu_gimbal::video::{Camera, Family};
use idu_gimbal::Instant;
use idu_gimbal_mavlink::camera::CameraConfig;
use idu_gimbal_mavlink::framing::{Check, FrameReader, Outbox};
use idu_gimbal_mavlink::{Bridge, BridgeConfig};

/// The bridge and the link it drives, with a small queue.
struct Firmware {
    bridge: Bridge,
    link: Link<3, 4>,
}

/// Everything the bridge has to send, read by `out`, an independent frame reader.
fn drain(bridge: &mut Bridge, out: &mut FrameReader) {
    loop {
        let bytes = bridge.transmit_bytes();
        if bytes.is_empty() {
            break;
        }
        let n = bytes.len();
        out.feed(bytes, |_| Check::Unhandled);
        bridge.transmit_written(n);
    }
}

/// `bytes` into the bridge at `now`, its answers drained into `out` whenever a frame waits
/// for room: every byte is taken, and a drained outbox always takes the frame that waited
/// (no frame waits for ever). The reader may hold more whole frames behind it (found again
/// in the bytes of a frame that failed its checksum): the next one may then wait for the
/// room the first one's answers took, and each drain takes at least one more.
fn receive_all(fw: &mut Firmware, bytes: &[u8], now: Instant, out: &mut FrameReader) {
    let Firmware { bridge, link } = fw;
    let mut rest = bytes;
    loop {
        let taken = bridge.receive(link, rest, now);
        assert!(taken <= rest.len(), "took more than it was given");
        rest = rest.get(taken..).unwrap_or(&[]);
        link.poll(now);
        bridge.poll(link, now);
        let waiting = bridge.reader().is_waiting();
        drain(bridge, out);
        if rest.is_empty() && !waiting {
            return;
        }
        // The outbox is empty now: the frame that waited goes at once.
        let held = bridge.reader().pending();
        let taken = bridge.receive(link, &[], now);
        assert_eq!(taken, 0);
        assert!(
            !bridge.reader().is_waiting() || bridge.reader().pending() < held,
            "a frame still waits with the outbox empty"
        );
    }
}

/// What the bridge sent was whole MAVLink 2 frames: `out` skipped nothing and is left with
/// nothing pending.
fn assert_whole_frames(out: &FrameReader) {
    let s = out.stats();
    assert_eq!(
        (s.skipped_bytes, s.bad_frames, out.pending()),
        (0, 0, 0),
        "the bridge sent something that is not whole MAVLink 2 frames"
    );
}

/// A bridge with the dual light's camera: every camera message has something to act on
/// (three streams, the thermal settings, the infrared tracking source).
fn dual_light_bridge() -> Firmware {
    let camera = CameraConfig::with_streams_of(&Camera::new(Family::DualLight)).ok();
    Firmware {
        bridge: Bridge::new(
            BridgeConfig {
                camera,
                ..BridgeConfig::default()
            }
            .check()
            .unwrap(),
        ),
        link: Link::new(Config::default()),
    }
}

/// Any bytes from the autopilot, split where the first byte says, with time passing: the
/// bridge never panics, and everything it sends is whole MAVLink 2 frames (an independent
/// reader skips nothing and is left with nothing pending).
pub fn mavlink_bridge(data: &[u8]) {
    let mut bridge = dual_light_bridge();
    let cut = data
        .first()
        .map_or(0, |&n| usize::from(n) % (data.len() + 1));
    let (a, b) = data.split_at(cut);
    let mut out = FrameReader::new();
    for (i, part) in [a, b].into_iter().enumerate() {
        let now = Instant::from_millis(1_000 * i as u32);
        receive_all(&mut bridge, part, now, &mut out);
        bridge.link.poll(now);
        bridge.bridge.poll(&mut bridge.link, now);
        drain(&mut bridge.bridge, &mut out);
    }
    assert_whole_frames(&out);
}

/// The messages the bridge acts on, as (id, CRC_EXTRA), so that [`mavlink_messages`]
/// reaches what they do rather than stopping at the checksum.
fn handled() -> [(u32, u8); 10] {
    use idu_gimbal_mavlink::mavio::dialects::common::messages as m;
    use idu_gimbal_mavlink::mavio::mavspec::rust::spec::MessageSpecStatic;
    fn of<M: MessageSpecStatic>() -> (u32, u8) {
        (M::message_id(), M::crc_extra())
    }
    [
        of::<m::Heartbeat>(),
        of::<m::GlobalPositionInt>(),
        of::<m::CommandInt>(),
        of::<m::CommandLong>(),
        of::<m::FileTransferProtocol>(),
        of::<m::GimbalDeviceSetAttitude>(),
        of::<m::AutopilotStateForGimbalDevice>(),
        of::<m::ParamExtRequestRead>(),
        of::<m::ParamExtRequestList>(),
        of::<m::ParamExtSet>(),
    ]
}

/// Any sequence of messages the bridge acts on, each whole with a good checksum, from any
/// sender, with any payload (its length and bytes from the input), with time passing, to a
/// bridge with every feature the build has (`roi` in the fuzz build): the bridge never
/// panics (the fuzz build keeps overflow checks), and what it sends is whole MAVLink 2
/// frames. Each message is `[which, len, system, component, payload...]`.
pub fn mavlink_messages(data: &[u8]) {
    let mut bridge = dual_light_bridge();
    let handled = handled();
    let mut out = FrameReader::new();
    let mut rest = data;
    let mut ms = 0u32;
    // The frames are written by the bridge's own outbox (held to mavio's frames by
    // tests/framing.rs): whole, with their checksum, trailing zeros dropped.
    let mut frames = Outbox::<300>::new();
    while let [which, len, system, component, tail @ ..] = rest {
        let (id, crc_extra) = handled[usize::from(*which) % handled.len()];
        let len = usize::from(*len).min(tail.len());
        let (payload, after) = tail.split_at(len);
        rest = after;
        // An empty payload is no MAVLink 2 frame: nothing to send.
        if frames
            .push_payload(*system, *component, id, crc_extra, payload)
            .is_err()
        {
            continue;
        }
        let frame = frames.bytes().to_vec();
        frames.written(frame.len());
        // Time passes by the first payload byte's worth of milliseconds, across the wrap.
        ms = ms.wrapping_add(u32::from(payload.first().copied().unwrap_or(0)) * 16);
        let now = Instant::from_millis(ms.wrapping_sub(1_000));
        receive_all(&mut bridge, &frame, now, &mut out);
        bridge.link.poll(now);
        bridge.bridge.poll(&mut bridge.link, now);
        drain(&mut bridge.bridge, &mut out);
    }
    assert_whole_frames(&out);
}
