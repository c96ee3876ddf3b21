//! The MAVLink bridge's no-panic property, written once: the cargo-fuzz target
//! `mavlink_bridge` calls it, and `idu-gimbal-mavlink/tests/no_panic.rs` includes this file
//! (`#[path]`) so that `cargo test` checks it on every run.

use idu_gimbal::link::{Config, Link};
use idu_gimbal::video::{Camera, Family};
use idu_gimbal::Instant;
use idu_gimbal_mavlink::camera::CameraConfig;
use idu_gimbal_mavlink::framing::{Check, FrameReader};
use idu_gimbal_mavlink::{Bridge, BridgeConfig};

/// Any bytes from the autopilot, split where the first byte says, with time passing: the
/// bridge never panics, and everything it sends is whole MAVLink 2 frames (an independent
/// reader skips nothing and is left with nothing pending).
pub fn mavlink_bridge(data: &[u8]) {
    // The dual light: every camera message has something to act on (three streams, the
    // thermal settings, the infrared tracking source).
    let camera = CameraConfig::with_streams_of(&Camera::new(Family::DualLight)).ok();
    let mut bridge = Bridge::new(
        Link::<3, 4>::new(Config::default()),
        BridgeConfig {
            camera,
            ..BridgeConfig::default()
        },
    );
    let cut = data
        .first()
        .map_or(0, |&n| usize::from(n) % (data.len() + 1));
    let (a, b) = data.split_at(cut);
    let mut out = FrameReader::new();
    for (i, part) in [a, b].into_iter().enumerate() {
        let now = Instant::from_millis(1_000 * i as u32);
        bridge.receive(part, now);
        bridge.gimbal_mut().poll(now);
        bridge.poll(now);
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
    let s = out.stats();
    assert_eq!(
        (s.skipped_bytes, s.bad_frames, out.pending()),
        (0, 0, 0),
        "the bridge sent something that is not whole MAVLink 2 frames"
    );
}
