//! Focus, click-to-track with its status, the tracking source and fast calibration, as
//! QGroundControl and MAVSDK send them (COMMAND_LONG to the camera, unset params NaN from
//! MAVSDK), checked against the commands the gimbal is sent.

mod common;
use common::*;

use idu_gimbal::video::{Camera as VideoCamera, Family};
use idu_gimbal::wire::control::{
    Command, DualLightCommand, Focus, GimbalCommand, ImagePoint, TrackingBox,
};
use idu_gimbal::wire::ids;
use idu_gimbal::wire::postback::{GimbalType, Postback};
use idu_gimbal_mavlink::camera::CameraConfig;
use mavio::dialects::common::enums::{
    CameraTrackingMode, CameraTrackingStatusFlags, CameraTrackingTargetData, MavCmd, MavResult,
};
use mavio::dialects::common::messages::{CameraSettings, CameraTrackingImageStatus, CommandAck};
use mavio::protocol::{Frame, V2};

const CAMERA: u8 = 100;
const GIMBAL: u8 = 154;

fn bridge(family: Family) -> Firmware {
    camera_bridge(CameraConfig::with_streams_of(&VideoCamera::new(family)).unwrap())
}

/// Sends `cmd` to `to` with params 1 to 7; the ACK's result, the frames after it and the
/// commands queued for the gimbal.
fn ask(
    b: &mut Firmware,
    to: u8,
    cmd: MavCmd,
    p: [f32; 7],
    ms: u32,
) -> (MavResult, Vec<Frame<V2>>, Vec<Command>) {
    b.receive_all(&frame(GCS, 0, &command7((AP.0, to), cmd, p)), t(ms));
    let frames = sent(b);
    let acks: Vec<CommandAck> = of(&frames);
    assert_eq!(acks.len(), 1, "{cmd:?}: one ACK");
    assert_eq!(frames[0].component_id(), to);
    assert_eq!(acks[0].command, cmd);
    let queued = queued_all(&mut b.link);
    (acks[0].result, frames, queued)
}

/// [`ask`] of the camera.
fn ask_camera(
    b: &mut Firmware,
    cmd: MavCmd,
    p: [f32; 7],
    ms: u32,
) -> (MavResult, Vec<Frame<V2>>, Vec<Command>) {
    ask(b, CAMERA, cmd, p, ms)
}

const N: f32 = f32::NAN;

/// Params 1 to 4 given, the rest unset (NaN, as MAVSDK sends them).
fn p4(a: f32, b: f32, c: f32, d: f32) -> [f32; 7] {
    [a, b, c, d, N, N, N]
}

fn focus(f: Focus) -> Vec<Command> {
    vec![Command::Gimbal(GimbalCommand::Focus(f))]
}

#[test]
fn focus_continuous_by_sign_and_auto_of_every_kind() {
    let mut b = bridge(Family::X3);
    // FOCUS_TYPE_CONTINUOUS (1): MAVSDK's focus_out_start (+1), focus_in_start (−1),
    // focus_stop (0); beyond ±1 only the sign counts ("clipped").
    for (v, f) in [
        (1.0, Focus::Plus),
        (-1.0, Focus::Minus),
        (0.0, Focus::Stop),
        (7.5, Focus::Plus),
        (-0.01, Focus::Minus),
    ] {
        let (r, frames, q) = ask_camera(&mut b, MavCmd::SetCameraFocus, p4(1.0, v, N, N), 10);
        assert_eq!((r, q), (MavResult::Accepted, focus(f)), "continuous {v}");
        // common.xml: the camera answers with CAMERA_SETTINGS on success.
        let s: Vec<CameraSettings> = of(&frames);
        assert_eq!(s.len(), 1);
        assert!(
            s[0].focus_level.is_nan(),
            "the gimbal reports no focus position"
        );
    }
    // FOCUS_TYPE_AUTO (4), AUTO_SINGLE (5), AUTO_CONTINUOUS (6): the one auto-focus.
    for kind in [4.0, 5.0, 6.0] {
        let (r, _, q) = ask_camera(&mut b, MavCmd::SetCameraFocus, p4(kind, 0.0, N, N), 10);
        assert_eq!(
            (r, q),
            (MavResult::Accepted, focus(Focus::Auto)),
            "type {kind}"
        );
    }
}

#[test]
fn focus_that_needs_a_position_is_denied_and_sends_nothing() {
    let mut b = bridge(Family::X3);
    // STEP (0), RANGE (2), METERS (3), an unknown type (7), NaN: supported command, values
    // it cannot do (common.xml's MAV_RESULT_DENIED).
    for (kind, v) in [
        (0.0, 1.0),
        (0.0, -1.0),
        (2.0, 50.0),
        (3.0, 10.0),
        (7.0, 0.0),
        (N, 0.0),
        (1.0, N),
    ] {
        let (r, frames, q) = ask_camera(&mut b, MavCmd::SetCameraFocus, p4(kind, v, N, N), 10);
        assert_eq!(r, MavResult::Denied, "type {kind} value {v}");
        assert!(q.is_empty());
        assert!(of::<CameraSettings>(&frames).is_empty());
    }
}

fn track(b: TrackingBox) -> Vec<Command> {
    vec![Command::Gimbal(GimbalCommand::StartTracking(b))]
}

fn tbox(x: i32, y: i32, w16: u8, h16: u8) -> TrackingBox {
    TrackingBox::from_raw(ImagePoint::new(x, y).unwrap(), w16, h16)
}

#[test]
fn a_rectangle_becomes_the_documents_centre_and_sixteenths() {
    let mut b = bridge(Family::X3);
    // Hand-computed: centre = midpoint × 8191 rounded; side × 8192 / 16 rounded.
    for (rect, expected) in [
        // A drag from (0.25, 0.25) to (0.5, 0.5): centre 0.375 × 8191 = 3071.6 → 3072;
        // sides 0.25 × 8192 / 16 = 128.
        ([0.25, 0.25, 0.5, 0.5], tbox(3072, 3072, 128, 128)),
        // The corners in either order are the same rectangle.
        ([0.5, 0.5, 0.25, 0.25], tbox(3072, 3072, 128, 128)),
        // The top-left corner of the image, a zero box.
        ([0.0, 0.0, 0.0, 0.0], tbox(0, 0, 0, 0)),
        // The bottom-right corner.
        ([1.0, 1.0, 1.0, 1.0], tbox(8191, 8191, 0, 0)),
        // The largest side the byte holds: 255 × 16 = 4080 units = 0.498046875.
        // Centre 0.2490234375 × 8191 = 2039.75 → 2040.
        (
            [0.0, 0.0, 4080.0 / 8192.0, 4080.0 / 8192.0],
            tbox(2040, 2040, 255, 255),
        ),
        // 1/32 of the image: 256 units → 16; centre 0.515625 × 8191 = 4223.48 → 4223.
        ([0.5, 0.5, 0.531_25, 0.531_25], tbox(4223, 4223, 16, 16)),
    ] {
        let (r, _, q) = ask_camera(
            &mut b,
            MavCmd::CameraTrackRectangle,
            [rect[0], rect[1], rect[2], rect[3], N, N, N],
            10,
        );
        assert_eq!((r, q), (MavResult::Accepted, track(expected)), "{rect:?}");
    }
}

#[test]
fn a_box_too_large_for_the_byte_or_outside_the_image_is_denied_never_shrunk() {
    let mut b = bridge(Family::X3);
    for rect in [
        // 0.5 of the image is 4096 units: 256 sixteenths, one more than the byte holds.
        [0.0, 0.0, 0.5, 0.1],
        [0.0, 0.0, 0.1, 0.5],
        [0.0, 0.0, 1.0, 1.0],
        // Outside 0..1, or not a number.
        [-0.01, 0.2, 0.3, 0.3],
        [0.2, 0.2, 1.01, 0.3],
        [N, 0.2, 0.3, 0.3],
        [0.2, 0.2, 0.3, f32::INFINITY],
    ] {
        let (r, _, q) = ask_camera(
            &mut b,
            MavCmd::CameraTrackRectangle,
            [rect[0], rect[1], rect[2], rect[3], N, N, N],
            10,
        );
        assert_eq!(r, MavResult::Denied, "{rect:?}");
        assert!(q.is_empty());
    }
}

#[test]
fn a_point_becomes_a_box_of_twice_its_radius_and_at_least_a_thirty_second() {
    let mut b = bridge(Family::X3);
    for (p, expected) in [
        // QGroundControl's click: radius 20 px of a 1280 px wide video = 0.015625; the box
        // 2r = 0.03125 of the image = 256 units = 16 sixteenths.
        ([0.5, 0.5, 0.015_625], tbox(4096, 4096, 16, 16)),
        // Radius 0 ("one pixel"): the smallest box, 256 units.
        ([0.0, 1.0, 0.0], tbox(0, 8191, 16, 16)),
        // Radius 0.1: 0.2 × 8192 = 1638.4 units → 102.4 → 102.
        ([0.25, 0.75, 0.1], tbox(2048, 6143, 102, 102)),
    ] {
        let (r, _, q) = ask_camera(
            &mut b,
            MavCmd::CameraTrackPoint,
            p4(p[0], p[1], p[2], N),
            10,
        );
        assert_eq!((r, q), (MavResult::Accepted, track(expected)), "{p:?}");
    }
    // A radius whose box the byte cannot hold, a point outside the image: denied.
    for p in [
        [0.5, 0.5, 0.25],
        [1.5, 0.5, 0.01],
        [0.5, N, 0.01],
        [0.5, 0.5, -0.1],
    ] {
        let (r, _, q) = ask_camera(
            &mut b,
            MavCmd::CameraTrackPoint,
            p4(p[0], p[1], p[2], N),
            10,
        );
        assert_eq!(r, MavResult::Denied, "{p:?}");
        assert!(q.is_empty());
    }
}

#[test]
fn stop_tracking_goes_to_the_image_tracking_was_started_on() {
    let mut b = bridge(Family::DualLight);
    let stop = MavCmd::CameraStopTracking;
    let (r, _, q) = ask_camera(&mut b, stop, [N; 7], 10);
    assert_eq!(
        (r, q),
        (
            MavResult::Accepted,
            vec![GimbalCommand::StopTracking.into()]
        )
    );
    // The infrared image as the source (MAV_CMD_SET_CAMERA_SOURCE, param2 IR = 2): tracking
    // is the dual light's.
    let (r, _, _) = ask_camera(&mut b, MavCmd::SetCameraSource, p4(0.0, 2.0, 0.0, N), 10);
    assert_eq!(r, MavResult::Accepted);
    let (r, _, q) = ask_camera(
        &mut b,
        MavCmd::CameraTrackPoint,
        p4(0.5, 0.5, 0.015_625, N),
        10,
    );
    assert_eq!(r, MavResult::Accepted);
    assert_eq!(
        q,
        vec![DualLightCommand::StartTracking(tbox(4096, 4096, 16, 16)).into()]
    );
    // Back to the visible image: the stop still goes where tracking runs.
    let (r, _, _) = ask_camera(&mut b, MavCmd::SetCameraSource, p4(0.0, 1.0, 0.0, N), 10);
    assert_eq!(r, MavResult::Accepted);
    let (_, _, q) = ask_camera(&mut b, stop, [N; 7], 10);
    assert_eq!(q, vec![DualLightCommand::StopTracking.into()]);
    // A secondary source (picture in picture) and NDVI cannot be had.
    for p in [p4(0.0, 1.0, 2.0, N), p4(0.0, 3.0, 0.0, N)] {
        let (r, _, _) = ask_camera(&mut b, MavCmd::SetCameraSource, p, 10);
        assert_eq!(r, MavResult::Denied, "{p:?}");
    }
}

#[test]
fn the_infrared_source_needs_a_thermal_sensor() {
    let mut b = bridge(Family::X3);
    let (r, _, _) = ask_camera(&mut b, MavCmd::SetCameraSource, p4(0.0, 2.0, 0.0, N), 10);
    assert_eq!(r, MavResult::Denied);
}

/// A postback with the tracking flag as given, into the link.
fn postback(b: &mut Firmware, tracking: bool, ms: u32) {
    let p = Postback {
        gimbal_type: GimbalType::X30,
        tracking,
        ..Postback::default()
    };
    for data in p.to_can_frames() {
        b.link.receive(ids::POSTBACK, &data, t(ms));
    }
}

/// Polls every 10 ms over `span`, the gimbal saying `tracking` in a postback at `at`;
/// what `pick` takes of each poll's frames, with its time.
fn poll_over<T>(
    b: &mut Firmware,
    span: std::ops::RangeInclusive<u32>,
    (at, tracking): (u32, bool),
    pick: impl Fn(&[Frame<V2>]) -> Vec<T>,
) -> Vec<(u32, T)> {
    let mut seen = Vec::new();
    for ms in span.step_by(10) {
        if ms == at {
            postback(b, tracking, ms);
        }
        b.poll(t(ms));
        seen.extend(pick(&sent(b)).into_iter().map(|x| (ms, x)));
    }
    seen
}

fn statuses(frames: &[Frame<V2>]) -> Vec<(CameraTrackingStatusFlags, CameraTrackingMode)> {
    of::<CameraTrackingImageStatus>(frames)
        .iter()
        .map(|s| {
            // Where the target is: said only for tracking the bridge started, at the centre
            // (checked in the_target_is_at_the_centre_with_the_box_it_was_given).
            if s.target_data.is_empty() {
                assert!(s.point_x.is_nan() && s.rec_top_x.is_nan() && s.radius.is_nan());
            }
            (s.tracking_status, s.tracking_mode)
        })
        .collect()
}

#[test]
fn the_tracking_status_follows_the_postback_at_the_interval_asked() {
    let mut b = bridge(Family::X3);
    let idle = (CameraTrackingStatusFlags::Idle, CameraTrackingMode::None);
    // None until asked, or tracking.
    b.poll(t(1000));
    assert!(statuses(&sent(&mut b)).is_empty());
    // QGroundControl: SET_MESSAGE_INTERVAL(275, 500000) after its track command.
    let (r, frames, _) = ask_camera(
        &mut b,
        MavCmd::SetMessageInterval,
        p4(275.0, 500_000.0, N, N),
        1000,
    );
    assert_eq!(r, MavResult::Accepted);
    assert!(statuses(&frames).is_empty());
    b.poll(t(1000));
    assert_eq!(statuses(&sent(&mut b)), vec![idle]);
    let (r, _, _) = ask_camera(
        &mut b,
        MavCmd::CameraTrackRectangle,
        p4(0.4, 0.4, 0.5, 0.5),
        1100,
    );
    assert_eq!(r, MavResult::Accepted);
    // At once, then every 500 ms: idle until the gimbal says it tracks (at 1701).
    let seen = poll_over(&mut b, 1101..=2600, (1701, true), statuses);
    let active = (
        CameraTrackingStatusFlags::Active,
        CameraTrackingMode::Rectangle,
    );
    assert_eq!(seen, vec![(1101, idle), (1601, idle), (2101, active)]);
    // The gimbal loses the target: idle again, asked for once by REQUEST_MESSAGE.
    postback(&mut b, false, 2600);
    let (r, frames, _) = ask_camera(&mut b, MavCmd::RequestMessage, p4(275.0, N, N, N), 2600);
    assert_eq!(r, MavResult::Accepted);
    assert_eq!(statuses(&frames), vec![idle]);
    // −1 stops the stream (QGroundControl's stop); an interval out of range is denied.
    let (r, _, _) = ask_camera(
        &mut b,
        MavCmd::SetMessageInterval,
        p4(275.0, -1.0, N, N),
        2600,
    );
    assert_eq!(r, MavResult::Accepted);
    for ms in 2601..4000 {
        b.poll(t(ms));
    }
    assert!(statuses(&sent(&mut b)).is_empty());
    for bad in [500.0, 61_000_000.0, N] {
        let (r, _, _) = ask_camera(
            &mut b,
            MavCmd::SetMessageInterval,
            p4(275.0, bad, N, N),
            4000,
        );
        assert_eq!(r, MavResult::Denied, "{bad}");
    }
}

#[test]
fn fast_calibration_is_the_gyroscope_calibration_addressed_to_the_gimbal() {
    let mut b = bridge(Family::X3);
    let cal = MavCmd::PreflightCalibration;
    let (r, _, q) = ask(&mut b, GIMBAL, cal, [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 10);
    assert_eq!(
        (r, q),
        (
            MavResult::Accepted,
            vec![GimbalCommand::FastCalibration.into()]
        )
    );
    // MAVSDK's unset params are NaN.
    let (r, _, q) = ask(&mut b, GIMBAL, cal, [1.0, N, N, N, N, N, N], 10);
    assert_eq!(
        (r, q),
        (
            MavResult::Accepted,
            vec![GimbalCommand::FastCalibration.into()]
        )
    );
    assert_eq!(b.stats().queue_full, 0);
    // No room in the gimbal's queue: try again, and counted.
    while b.link.send(GimbalCommand::Recenter).is_ok() {}
    let (r, _, _) = ask(&mut b, GIMBAL, cal, [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 10);
    assert_eq!(r, MavResult::TemporarilyRejected);
    assert_eq!(b.stats().queue_full, 1);
    let _ = queued_all(&mut b.link);
    // Any other calibration, or more than the gyroscope's: denied, nothing sent.
    for p in [
        [0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
        [3.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    ] {
        let (r, _, q) = ask(&mut b, GIMBAL, cal, p, 10);
        assert_eq!(r, MavResult::Denied, "{p:?}");
        assert!(q.is_empty());
    }
    // Broadcast, it is the autopilot's (QGroundControl sends it to component 1): the
    // bridge does not answer.
    let mut c = command((AP.0, 0), cal, 1.0, 0.0);
    c.param5 = 0.0;
    b.receive_all(&frame(GCS, 0, &c), t(20));
    assert!(of::<CommandAck>(&sent(&mut b)).is_empty());
    assert!(queued_all(&mut b.link).is_empty());
}

#[test]
fn the_target_is_at_the_centre_with_the_box_it_was_given_streamed_unasked() {
    // QGroundControl 5.0 never asks for the status (its _requestTrackingStatus has no
    // caller): while tracking what the bridge started it comes every 500 ms unasked.
    let mut b = bridge(Family::X3);
    postback(&mut b, false, 0);
    let (r, _, _) = ask_camera(
        &mut b,
        MavCmd::CameraTrackPoint,
        p4(0.3, 0.6, 0.05, N),
        1000,
    );
    assert_eq!(r, MavResult::Accepted);
    let seen = poll_over(
        &mut b,
        1001..=3000,
        (1201, true),
        of::<CameraTrackingImageStatus>,
    );
    let times: Vec<u32> = seen.iter().map(|(ms, _)| *ms).collect();
    assert_eq!(times, [1001, 1501, 2001, 2501]);
    assert_eq!(seen[0].1.tracking_status, CameraTrackingStatusFlags::Idle);
    for (_, s) in &seen[1..] {
        assert_eq!(s.tracking_status, CameraTrackingStatusFlags::Active);
        assert_eq!(s.tracking_mode, CameraTrackingMode::Point);
        assert_eq!(s.target_data, CameraTrackingTargetData::IN_STATUS);
        // The tracker brings its target to the centre; the radius is the one given.
        assert_eq!((s.point_x, s.point_y, s.radius), (0.5, 0.5, 0.05));
    }
    // A rectangle: the box given, centred.
    let (r, _, _) = ask_camera(
        &mut b,
        MavCmd::CameraTrackRectangle,
        p4(0.1, 0.2, 0.3, 0.6),
        3000,
    );
    assert_eq!(r, MavResult::Accepted);
    b.poll(t(3001));
    let s = &of::<CameraTrackingImageStatus>(&sent(&mut b))[0];
    assert_eq!(s.tracking_mode, CameraTrackingMode::Rectangle);
    let close = |a: f32, e: f32| (a - e).abs() < 1e-6;
    assert!(close(s.rec_top_x, 0.4) && close(s.rec_top_y, 0.3), "{s:?}");
    assert!(
        close(s.rec_bottom_x, 0.6) && close(s.rec_bottom_y, 0.7),
        "{s:?}"
    );
    // Stopped: IDLE once the gimbal says it no longer tracks, then nothing.
    let (r, _, _) = ask_camera(&mut b, MavCmd::CameraStopTracking, p4(N, N, N, N), 3100);
    assert_eq!(r, MavResult::Accepted);
    let after = poll_over(&mut b, 3101..=5000, (3301, false), statuses);
    let idle = (CameraTrackingStatusFlags::Idle, CameraTrackingMode::None);
    let active_unknown = (CameraTrackingStatusFlags::Active, CameraTrackingMode::None);
    assert_eq!(after, [(3101, active_unknown), (3601, idle)]);
}
