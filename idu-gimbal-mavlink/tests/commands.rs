//! Commands as `COMMAND_INT` as well as `COMMAND_LONG`: every one addressed to the bridge
//! acknowledged once, location commands read from x/y/z in their frame.

mod common;
use common::*;

use idu_gimbal::link::{Config, Link};
use idu_gimbal::wire::control::{GimbalCommand, Photo};
use idu_gimbal_mavlink::camera::CameraConfig;
use idu_gimbal_mavlink::BridgeConfig;
use mavio::dialects::common::enums::{MavCmd, MavFrame, MavResult};
use mavio::dialects::common::messages::{
    CameraImageCaptured, CommandAck, CommandInt, CommandLong, GimbalDeviceInformation,
};
use mavio::protocol::{Frame, V2};

fn bridge() -> Firmware {
    let mut b = Firmware::new(
        Link::new(Config::default()),
        BridgeConfig {
            camera: Some(CameraConfig::new("rtsp://192.168.42.108:554/live").unwrap()),
            ..BridgeConfig::default()
        },
    );
    b.receive_all(&frame(AP, 0, &heartbeat()), t(0));
    let _ = sent(&mut b);
    b
}

fn int(
    target: (u8, u8),
    command: MavCmd,
    frame_: MavFrame,
    p: [f32; 4],
    xyz: (i32, i32, f32),
) -> CommandInt {
    CommandInt {
        target_system: target.0,
        target_component: target.1,
        frame: frame_,
        command,
        current: 0,
        autocontinue: 0,
        param1: p[0],
        param2: p[1],
        param3: p[2],
        param4: p[3],
        x: xyz.0,
        y: xyz.1,
        z: xyz.2,
    }
}

/// The region of interest every ROI test points at, 1e-7°: 0.001° north and east (111 m,
/// 75 m) of the vehicle's position in them.
#[cfg(feature = "roi")]
const ROI: (i32, i32) = (473_987_420, 85_465_940);

/// `DO_SET_ROI_LOCATION` to the gimbal as `COMMAND_INT`: [`ROI`] at `alt_m` metres in
/// `frame_`.
#[cfg(feature = "roi")]
fn roi(frame_: MavFrame, alt_m: f32) -> CommandInt {
    let (lat, lon) = ROI;
    int(
        (AP.0, 154),
        MavCmd::DoSetRoiLocation,
        frame_,
        [0.0; 4],
        (lat, lon, alt_m),
    )
}

/// An ACK as (from component, command, result).
type Ack = (u8, MavCmd, MavResult);

/// The ACKs a message produced, and all frames.
fn acks_of(b: &mut Firmware, bytes: &[u8], ms: u32) -> (Vec<Ack>, Vec<Frame<V2>>) {
    b.receive_all(bytes, t(ms));
    let frames = sent(b);
    let acks = frames
        .iter()
        .filter(|f| f.message_id() == 77)
        .map(|f| {
            let a: CommandAck = f.decode_message().unwrap();
            assert_eq!((a.target_system, a.target_component), GCS);
            (f.component_id(), a.command, a.result)
        })
        .collect();
    (acks, frames)
}

#[test]
fn command_int_is_answered_for_both_components() {
    let mut b = bridge();
    // The gimbal's information, asked by COMMAND_INT.
    let c = int(
        (AP.0, 154),
        MavCmd::RequestMessage,
        MavFrame::Global,
        [283.0, 0.0, 0.0, 0.0],
        (0, 0, 0.0),
    );
    let (acks, frames) = acks_of(&mut b, &frame(GCS, 0, &c), 10);
    assert_eq!(acks, [(154, MavCmd::RequestMessage, MavResult::Accepted)]);
    assert_eq!(of::<GimbalDeviceInformation>(&frames).len(), 1);
    // A photo, by COMMAND_INT to the camera.
    let c = int(
        (AP.0, 100),
        MavCmd::ImageStartCapture,
        MavFrame::Global,
        [0.0, 0.0, 1.0, 1.0],
        (0, 0, 0.0),
    );
    let (acks, frames) = acks_of(&mut b, &frame(GCS, 1, &c), 20);
    assert_eq!(
        acks,
        [(100, MavCmd::ImageStartCapture, MavResult::Accepted)]
    );
    assert_eq!(of::<CameraImageCaptured>(&frames).len(), 1);
    assert_eq!(queued(&mut b.link), [GimbalCommand::Photo(Photo::Single)]);
    // Anything else addressed to either: UNSUPPORTED, never silence.
    for to in [154, 100] {
        let c = int(
            (AP.0, to),
            MavCmd::DoSetHome,
            MavFrame::Global,
            [0.0; 4],
            (0, 0, 0.0),
        );
        let (acks, _) = acks_of(&mut b, &frame(GCS, 2, &c), 30);
        assert_eq!(acks, [(to, MavCmd::DoSetHome, MavResult::Unsupported)]);
    }
    // Broadcast and not owned, or for another component: left alone.
    for to in [(0, 0), (AP.0, 1)] {
        let c = int(
            to,
            MavCmd::DoSetHome,
            MavFrame::Global,
            [0.0; 4],
            (0, 0, 0.0),
        );
        assert!(acks_of(&mut b, &frame(GCS, 3, &c), 40).0.is_empty());
    }
}

#[cfg(feature = "roi")]
#[test]
fn a_region_of_interest_addressed_to_the_gimbal_is_pointed_at() {
    let mut b = bridge();
    // 47.3977420 N, 8.5455940 E, 488.123 m AMSL; home 400 m AMSL (relative_alt 88.123 m).
    b.receive_all(
        &frame(AP, 1, &position(473_977_420, 85_455_940, 488_123, 88_123)),
        t(5),
    );
    // Absolute altitude (MAV_FRAME_GLOBAL_INT): as given.
    let c = roi(MavFrame::GlobalInt, 420.5);
    let (acks, _) = acks_of(&mut b, &frame(GCS, 0, &c), 10);
    assert_eq!(acks, [(154, MavCmd::DoSetRoiLocation, MavResult::Accepted)]);
    let p = b.link.pointing_target().unwrap();
    assert!(
        (p.lat_deg() - 47.398_742).abs() < 1e-7 && (p.lon_deg() - 8.546_594).abs() < 1e-7,
        "{p:?}"
    );
    // Kept to 1 cm (the core's Position).
    assert!((p.alt_m() - 420.5).abs() < 0.01, "{}", p.alt_m());
    // Relative to home: + home's 400 m. COMMAND_LONG's altitude is relative (param5..7).
    let c = int(
        (AP.0, 154),
        MavCmd::DoSetRoiLocation,
        MavFrame::GlobalRelativeAltInt,
        [154.0, 0.0, 0.0, 0.0],
        (473_987_420, 85_465_940, 20.0),
    );
    assert_eq!(
        acks_of(&mut b, &frame(GCS, 1, &c), 20).0[0].2,
        MavResult::Accepted
    );
    assert!((b.link.pointing_target().unwrap().alt_m() - 420.0).abs() < 0.01);
    let mut long = command((AP.0, 154), MavCmd::DoSetRoiLocation, 0.0, 0.0);
    long.param5 = 47.5;
    long.param6 = -122.25;
    long.param7 = 30.0;
    assert_eq!(
        acks_of(&mut b, &frame(GCS, 2, &long), 30).0[0].2,
        MavResult::Accepted
    );
    let p = b.link.pointing_target().unwrap();
    assert!((p.lat_deg() - 47.5).abs() < 1e-7 && (p.lon_deg() + 122.25).abs() < 1e-7);
    assert!((p.alt_m() - 430.0).abs() < 0.01);
    // ROI none: the point-at ends, the gimbal keeps its aim.
    let c = int(
        (AP.0, 154),
        MavCmd::DoSetRoiNone,
        MavFrame::Global,
        [0.0; 4],
        (0, 0, 0.0),
    );
    assert_eq!(
        acks_of(&mut b, &frame(GCS, 3, &c), 40).0,
        [(154, MavCmd::DoSetRoiNone, MavResult::Accepted)]
    );
    assert!(b.link.pointing_target().is_none());
    // Refused, and nothing pointed at: above terrain (unknown here), another gimbal
    // (param1), a latitude out of range.
    for (frame_, p1, x) in [
        (MavFrame::GlobalTerrainAltInt, 0.0, 473_987_420),
        (MavFrame::GlobalInt, 155.0, 473_987_420),
        (MavFrame::GlobalInt, 0.0, 910_000_000),
    ] {
        let c = int(
            (AP.0, 154),
            MavCmd::DoSetRoiLocation,
            frame_,
            [p1, 0.0, 0.0, 0.0],
            (x, 85_465_940, 20.0),
        );
        assert_eq!(
            acks_of(&mut b, &frame(GCS, 4, &c), 50).0[0].2,
            MavResult::Denied,
            "{frame_:?} {p1}"
        );
        assert!(b.link.pointing_target().is_none());
    }
    // Broadcast: the autopilot's gimbal manager owns ROI (common.xml: "not to a gimbal
    // device"); the device leaves it alone.
    let c = int(
        (0, 0),
        MavCmd::DoSetRoiLocation,
        MavFrame::GlobalInt,
        [0.0; 4],
        (473_987_420, 85_465_940, 20.0),
    );
    assert!(acks_of(&mut b, &frame(GCS, 5, &c), 60).0.is_empty());
    assert!(b.link.pointing_target().is_none());
}

#[cfg(feature = "roi")]
#[test]
fn a_relative_roi_waits_for_home_s_height() {
    let mut b = bridge();
    let c = roi(MavFrame::GlobalRelativeAltInt, 20.0);
    let (acks, _) = acks_of(&mut b, &frame(GCS, 0, &c), 10);
    assert_eq!(
        acks,
        [(
            154,
            MavCmd::DoSetRoiLocation,
            MavResult::TemporarilyRejected
        )]
    );
    assert!(b.link.pointing_target().is_none());
}

#[cfg(feature = "roi")]
#[test]
fn home_s_height_from_extreme_altitudes_is_refused_never_wrapped() {
    // alt − relative_alt beyond i32: in i32 it overflowed (a debug build panicked, a
    // release build wrapped to a home 4,295 km up and accepted it).
    for (alt, relative) in [(i32::MAX, -1), (i32::MIN, 1), (i32::MIN, i32::MAX)] {
        let mut b = bridge();
        b.receive_all(
            &frame(AP, 1, &position(473_977_420, 85_455_940, alt, relative)),
            t(5),
        );
        let c = roi(MavFrame::GlobalRelativeAltInt, 20.0);
        let (acks, _) = acks_of(&mut b, &frame(GCS, 0, &c), 10);
        assert_eq!(
            acks,
            [(154, MavCmd::DoSetRoiLocation, MavResult::Denied)],
            "{alt} {relative}"
        );
        assert!(b.link.pointing_target().is_none());
    }
}

#[cfg(not(feature = "roi"))]
#[test]
fn without_the_roi_feature_a_region_of_interest_is_unsupported() {
    let mut b = bridge();
    for cmd in [MavCmd::DoSetRoiLocation, MavCmd::DoSetRoiNone] {
        let c = int(
            (AP.0, 154),
            cmd,
            MavFrame::GlobalInt,
            [0.0; 4],
            (473_987_420, 85_465_940, 20.0),
        );
        assert_eq!(
            acks_of(&mut b, &frame(GCS, 0, &c), 10).0,
            [(154, cmd, MavResult::Unsupported)]
        );
        assert!(b.link.pointing_target().is_none());
    }
}

/// The ACKs (from component, raw command id, result byte) among the bridge's frames.
fn raw_acks(b: &mut Firmware) -> Vec<(u8, u16, u8)> {
    sent(b)
        .iter()
        .filter(|f| f.message_id() == 77)
        .map(|f| {
            let p = f.payload().bytes();
            (f.component_id(), u16::from_le_bytes([p[0], p[1]]), p[2])
        })
        .collect()
}

#[test]
fn a_command_the_dialect_does_not_know_is_answered_unsupported() {
    let mut b = bridge();
    let unsupported = MavResult::Unsupported as u8;
    // Ids outside mavio's common.xml, and ones a newer common.xml has.
    for command in [
        1u16, 2, 35, 36, 12_345, 29_999, 40_000, 43_000, 43_002, 65_535,
    ] {
        for component in [154u8, 100] {
            // COMMAND_LONG: params 0..28, command 28, target 30 and 31, confirmation 32.
            let mut long = vec![0u8; 33];
            long[28..30].copy_from_slice(&command.to_le_bytes());
            (long[30], long[31]) = (AP.0, component);
            b.receive_all(&raw_frame(GCS, 76, CommandLong::crc_extra(), &long), t(10));
            assert_eq!(
                raw_acks(&mut b),
                [(component, command, unsupported)],
                "LONG {command}"
            );
            // COMMAND_INT: the same offsets, then frame 32, current 33, autocontinue 34.
            let mut int = vec![0u8; 35];
            int[28..30].copy_from_slice(&command.to_le_bytes());
            (int[30], int[31], int[32]) = (AP.0, component, 6);
            b.receive_all(&raw_frame(GCS, 75, CommandInt::crc_extra(), &int), t(10));
            assert_eq!(
                raw_acks(&mut b),
                [(component, command, unsupported)],
                "INT {command}"
            );
        }
        // Broadcast, or another system's: not ours to answer.
        for target in [(AP.0, 0u8), (AP.0 + 1, 154)] {
            let mut long = vec![0u8; 33];
            long[28..30].copy_from_slice(&command.to_le_bytes());
            (long[30], long[31]) = target;
            b.receive_all(&raw_frame(GCS, 76, CommandLong::crc_extra(), &long), t(10));
            assert!(raw_acks(&mut b).is_empty(), "{command} to {target:?}");
        }
    }
    // A known command in a frame outside MAV_FRAME (200): its ACK carries its id.
    let mut int = vec![0u8; 35];
    int[28..30].copy_from_slice(&(MavCmd::DoSetRoiLocation as u16).to_le_bytes());
    (int[30], int[31], int[32]) = (AP.0, 154, 200);
    b.receive_all(&raw_frame(GCS, 75, CommandInt::crc_extra(), &int), t(10));
    assert_eq!(
        raw_acks(&mut b),
        [(154, MavCmd::DoSetRoiLocation as u16, unsupported)]
    );
    // A checksum that does not hold: nothing (it is no command at all).
    let mut bad = raw_frame(GCS, 76, CommandLong::crc_extra(), &[0u8; 33]);
    let n = bad.len();
    bad[n - 1] ^= 1;
    b.receive_all(&bad, t(10));
    assert!(raw_acks(&mut b).is_empty());
}
