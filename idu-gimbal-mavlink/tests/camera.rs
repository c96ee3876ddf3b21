//! The camera component as a ground station sees it.

mod common;
use common::*;

use idu_gimbal::link::{Config, Link};
use idu_gimbal::video::{Camera as VideoCamera, Credentials, Family, Stream, VideoError};
use idu_gimbal::wire::control::{GimbalCommand, Photo, Video, Zoom};
use idu_gimbal::wire::ids;
use idu_gimbal::wire::postback::{GimbalType, Postback};
use idu_gimbal_mavlink::camera::{camera_model, CameraConfig, StreamError, UriTooLong};
use idu_gimbal_mavlink::BridgeConfig;
use mavio::dialects::common::enums::{
    CameraCapFlags, CameraMode, MavCmd, MavResult, MavType, StorageStatus, VideoStreamStatusFlags,
    VideoStreamType,
};
use mavio::dialects::common::messages::{
    CameraCaptureStatus, CameraImageCaptured, CameraInformation, CameraSettings, CommandAck,
    GimbalDeviceInformation, Heartbeat, StorageInformation, SystemTime, VideoStreamInformation,
    VideoStreamStatus,
};
use mavio::protocol::{Frame, V2};

const URI: &str = "rtsp://admin:admin@192.168.42.108:554/cam/realmonitor?channel=1&subtype=0";

fn bridge() -> Firmware {
    camera_bridge(
        CameraConfig::new(
            VideoCamera::new(Family::DualLight)
                .url(Stream::Main)
                .unwrap()
                .as_str(),
        )
        .unwrap(),
    )
}

/// The ACK (from `component`) and the other frames a command produced.
fn ask(
    b: &mut Firmware,
    to: u8,
    cmd: MavCmd,
    p: [f32; 3],
    ms: u32,
) -> (CommandAck, Vec<Frame<V2>>) {
    ask4(b, to, cmd, [p[0], p[1], p[2], 0.0], ms)
}

/// [`ask`] of the camera (component 100).
fn ask_camera(b: &mut Firmware, cmd: MavCmd, p: [f32; 3], ms: u32) -> (CommandAck, Vec<Frame<V2>>) {
    ask(b, 100, cmd, p, ms)
}

/// [`ask`] with param4.
fn ask4(
    b: &mut Firmware,
    to: u8,
    cmd: MavCmd,
    p: [f32; 4],
    ms: u32,
) -> (CommandAck, Vec<Frame<V2>>) {
    let mut c = command((AP.0, to), cmd, p[0], p[1]);
    c.param3 = p[2];
    c.param4 = p[3];
    b.receive_all(&frame(GCS, 0, &c), t(ms));
    let frames = sent(b);
    let acks: Vec<(u8, CommandAck)> = frames
        .iter()
        .filter(|f| f.message_id() == 77)
        .map(|f| (f.component_id(), f.decode_message().unwrap()))
        .collect();
    assert_eq!(acks.len(), 1, "{cmd:?} to {to}: one ACK");
    // The ACK comes first, from the camera.
    assert_eq!(frames[0].message_id(), 77);
    assert_eq!(acks[0].0, 100);
    (acks[0].1.clone(), frames)
}

#[test]
fn camera_heartbeats_beside_the_gimbals_once_its_identity_is_known() {
    let mut b = bridge();
    let heartbeats = |b: &mut Firmware, from: u32, to: u32| {
        for ms in from..to {
            b.poll(t(ms));
        }
        sent(b)
            .iter()
            .filter(|f| f.message_id() == 0)
            .map(|f| (f.component_id(), f.decode_message().unwrap()))
            .collect::<Vec<(u8, Heartbeat)>>()
    };
    // No postback yet, so no model: a ground station reads a camera's identity once, at
    // its first heartbeat (QGCCameraManager.cc), and would keep a provisional one.
    let hbs = heartbeats(&mut b, 0, 2_000);
    assert!(hbs.iter().all(|h| h.0 == 154), "{hbs:?}");
    assert_eq!(hbs.len(), 2);
    postback(&mut b, GimbalType::X30, 2_000);
    let hbs = heartbeats(&mut b, 2_000, 4_000);
    let camera: Vec<_> = hbs.iter().filter(|h| h.0 == 100).collect();
    assert_eq!(camera.len(), 2);
    assert!(camera.iter().all(|h| h.1.type_ == MavType::Camera));
    assert_eq!(hbs.iter().filter(|h| h.0 == 154).count(), 2);
}

/// Each component numbers its own frames (pymavlink's and QGroundControl's loss counts are
/// per system and component): the camera's and the gimbal's sequences each go up by one,
/// whatever the other sends between them.
#[test]
fn the_camera_and_the_gimbal_number_their_frames_each_on_their_own() {
    let mut b = bridge();
    postback(&mut b, GimbalType::X30, 0);
    let mut frames = Vec::new();
    for ms in 0..5_000 {
        b.poll(t(ms));
        if ms % 500 == 0 {
            postback(&mut b, GimbalType::X30, ms);
        }
        frames.extend(sent(&mut b));
    }
    for component in [154, 100] {
        let seqs: Vec<u8> = frames
            .iter()
            .filter(|f| f.component_id() == component)
            .map(|f| f.sequence())
            .collect();
        assert!(seqs.len() >= 5, "{component}: {seqs:?}");
        assert!(
            seqs.windows(2).all(|w| w[1] == w[0].wrapping_add(1)),
            "component {component}: {seqs:?}"
        );
    }
}

#[test]
fn the_mode_is_set_and_told_back_in_the_settings() {
    let mut b = bridge();
    let mode = |frames: &[Frame<V2>]| of::<CameraSettings>(frames)[0].mode_id;
    let (_, frames) = ask_camera(&mut b, MavCmd::RequestCameraSettings, [1.0, 0.0, 0.0], 1);
    assert_eq!(mode(&frames), CameraMode::Image);
    // QGroundControl's photo/video switch: param2 0 or 1 (VehicleCameraControl.cc
    // setCameraMode); it reads the mode back only from CAMERA_SETTINGS, sent at once.
    let (ack, frames) = ask_camera(&mut b, MavCmd::SetCameraMode, [0.0, 1.0, 0.0], 2);
    assert_eq!(ack.result, MavResult::Accepted);
    assert_eq!(mode(&frames), CameraMode::Video);
    // Recording and a photo need no switch either way: nothing sent to the gimbal for it.
    assert!(queued(&mut b.link).is_empty());
    let (ack, _) = ask_camera(&mut b, MavCmd::SetCameraMode, [0.0, 2.0, 0.0], 3);
    assert_eq!(ack.result, MavResult::Denied, "survey: no such mode");
    let (_, frames) = ask_camera(&mut b, MavCmd::RequestCameraSettings, [1.0, 0.0, 0.0], 4);
    assert_eq!(mode(&frames), CameraMode::Video);
    let (ack, frames) = ask_camera(&mut b, MavCmd::SetCameraMode, [0.0, 0.0, 0.0], 5);
    assert_eq!(ack.result, MavResult::Accepted);
    assert_eq!(mode(&frames), CameraMode::Image);
}

#[test]
fn every_model_name_can_name_a_file() {
    // QGroundControl caches the definition as <vendor>_<model>_<version>.xml.
    for code in 0..=255u8 {
        let model = camera_model(GimbalType::from_code(code));
        assert!(!model.is_empty() && model.len() < 32, "{model:?}");
        assert!(
            model
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || " .-_".contains(c)),
            "{model:?}"
        );
    }
    assert_eq!(camera_model(GimbalType::X30), "X30-X30GT");
}

#[test]
fn information_by_request_message_and_by_the_legacy_command() {
    let mut b = bridge();
    // Before the postback gives the model: no provisional identity, asked again later.
    for (cmd, p1) in [
        (MavCmd::RequestMessage, 259.0),
        (MavCmd::RequestCameraInformation, 1.0),
    ] {
        let (ack, frames) = ask_camera(&mut b, cmd, [p1, 0.0, 0.0], 5);
        assert_eq!(ack.result, MavResult::TemporarilyRejected);
        assert!(of::<CameraInformation>(&frames).is_empty());
    }
    postback(&mut b, GimbalType::X30, 6);
    for (to, cmd, p1) in [
        (0, MavCmd::RequestMessage, 259.0),
        (100, MavCmd::RequestMessage, 259.0),
        (100, MavCmd::RequestCameraInformation, 1.0),
        (0, MavCmd::RequestCameraInformation, 1.0),
    ] {
        let (ack, frames) = ask(&mut b, to, cmd, [p1, 0.0, 0.0], 10);
        assert_eq!(ack.result, MavResult::Accepted);
        let info: Vec<CameraInformation> = of(&frames);
        assert_eq!(info.len(), 1);
        let f = info[0].flags;
        for flag in [
            CameraCapFlags::CAPTURE_IMAGE,
            CameraCapFlags::CAPTURE_VIDEO,
            CameraCapFlags::HAS_BASIC_ZOOM,
            CameraCapFlags::HAS_BASIC_FOCUS,
            CameraCapFlags::HAS_VIDEO_STREAM,
            CameraCapFlags::HAS_TRACKING_POINT,
            CameraCapFlags::HAS_TRACKING_RECTANGLE,
        ] {
            assert!(f.contains(flag), "{flag:?}");
        }
        // Modes, for QGroundControl's photo/video switch (both capture in either); no
        // geo-tracking status.
        assert!(f.contains(CameraCapFlags::HAS_MODES));
        assert!(f.contains(CameraCapFlags::CAN_CAPTURE_VIDEO_IN_IMAGE_MODE));
        assert!(f.contains(CameraCapFlags::CAN_CAPTURE_IMAGE_IN_VIDEO_MODE));
        assert!(!f.contains(CameraCapFlags::HAS_TRACKING_GEO_STATUS));
        // Exactly those (common.xml's CAMERA_CAP_FLAGS: VIDEO 1, IMAGE 2, MODES 4, IMAGE IN
        // VIDEO MODE 8, VIDEO IN IMAGE MODE 16, ZOOM 64, FOCUS 128, VIDEO_STREAM 256,
        // TRACKING_POINT 512, TRACKING_RECTANGLE 1024): no survey mode, no geo status.
        assert_eq!(f.bits(), 1 + 2 + 4 + 8 + 16 + 64 + 128 + 256 + 512 + 1024);
        assert_eq!(info[0].gimbal_device_id, 154);
        assert_eq!(&info[0].model_name[..10], b"X30-X30GT\0");
        // The definition, in the one form QGroundControl and MAVSDK both read.
        let uri = &info[0].cam_definition_uri;
        assert_eq!(&uri[..18], b"mftp://camera.xml\0");
        // Raised from 1 when the files' <model> became CAMERA_INFORMATION's: clients cache a
        // definition by vendor, model and version.
        assert_eq!(info[0].cam_definition_version, 2);
    }
    // A gimbal request to the camera: not the camera's, said so.
    let (ack, _) = ask_camera(&mut b, MavCmd::RequestMessage, [283.0, 0.0, 0.0], 20);
    assert_eq!(ack.result, MavResult::Unsupported);
}

/// The indexes of the CAMERA_IMAGE_CAPTURED in `frames`.
fn indexes(frames: &[Frame<V2>]) -> Vec<i32> {
    of::<CameraImageCaptured>(frames)
        .iter()
        .map(|c| c.image_index)
        .collect()
}

/// `MAV_CMD_IMAGE_START_CAPTURE` for one image with sequence number `seq`, from GCS at `ms`:
/// the ACK and the frames after it.
fn capture_one(b: &mut Firmware, seq: f32, ms: u32) -> (CommandAck, Vec<Frame<V2>>) {
    ask4(b, 100, MavCmd::ImageStartCapture, [0.0, 0.0, 1.0, seq], ms)
}

#[test]
fn a_single_capture_is_one_shot_and_a_retransmission_takes_no_second() {
    let mut b = bridge();
    // ArduPilot's take_picture: interval 0, count 1, sequence image_index + 1.
    let (ack, frames) = capture_one(&mut b, 1.0, 10);
    assert_eq!(ack.result, MavResult::Accepted);
    assert_eq!(queued(&mut b.link), [GimbalCommand::Photo(Photo::Single)]);
    // The ACK, then the image, then the status.
    let ids: Vec<u32> = frames.iter().map(|f| f.message_id()).collect();
    assert_eq!(ids, [77, 263, 262]);
    assert_eq!(indexes(&frames), [0]);
    assert_eq!(of::<CameraCaptureStatus>(&frames)[0].image_count, 1);
    // The same command again (its ACK was lost): ACKed, no picture, no image message.
    let (ack, frames) = capture_one(&mut b, 1.0, 20);
    assert_eq!(ack.result, MavResult::Accepted);
    assert!(queued(&mut b.link).is_empty());
    assert!(indexes(&frames).is_empty());
    // The next sequence number is a new picture; MAVSDK's first is 0 ("none"): always new.
    for (ms, seq, index) in [(30, 2.0, 1), (40, 0.0, 2), (50, 0.0, 3)] {
        let (_, frames) = capture_one(&mut b, seq, ms);
        assert_eq!(queued(&mut b.link), [GimbalCommand::Photo(Photo::Single)]);
        assert_eq!(indexes(&frames), [index]);
    }
}

/// An image is placed where the vehicle last was by a position the gimbal took: one out of
/// range (refused, counted) is not the image's.
#[test]
fn an_image_is_placed_by_the_last_position_in_range() {
    let mut b = bridge();
    b.receive_all(
        &frame(AP, 1, &position(473_977_420, 85_455_940, 488_000, 38_000)),
        t(0),
    );
    let refused = b.stats().refused_vehicle_updates;
    b.receive_all(
        &frame(AP, 2, &position(910_000_000, 85_455_940, 488_000, 38_000)),
        t(5),
    );
    assert_eq!(b.stats().refused_vehicle_updates, refused + 1);
    let (_, frames) = capture_one(&mut b, 1.0, 10);
    let image = &of::<CameraImageCaptured>(&frames)[0];
    assert_eq!((image.lat, image.lon), (473_977_420, 85_455_940));
}

#[test]
fn a_capture_number_is_whole_and_its_repeat_the_same_clients_soon_after() {
    let mut b = bridge();
    // A sequence number that is no whole number: refused, no picture.
    let (ack, _) = capture_one(&mut b, 1.5, 10);
    assert_eq!(ack.result, MavResult::Denied);
    assert!(queued(&mut b.link).is_empty());
    // GCS's number 1, then another ground station's number 1: two pictures.
    let (ack, _) = capture_one(&mut b, 1.0, 20);
    assert_eq!(ack.result, MavResult::Accepted);
    assert_eq!(queued(&mut b.link), [GimbalCommand::Photo(Photo::Single)]);
    let other = (GCS.0, GCS.1 + 1);
    let mut c = command((AP.0, 100), MavCmd::ImageStartCapture, 0.0, 0.0);
    (c.param3, c.param4) = (1.0, 1.0);
    b.receive_all(&frame(other, 0, &c), t(30));
    let acks: Vec<CommandAck> = of(&sent(&mut b));
    assert_eq!(acks[0].result, MavResult::Accepted);
    assert_eq!(queued(&mut b.link), [GimbalCommand::Photo(Photo::Single)]);
    // GCS's number 1 again a minute on (a restarted client numbering from 1): a picture.
    let (ack, _) = capture_one(&mut b, 1.0, 60_020);
    assert_eq!(ack.result, MavResult::Accepted);
    assert_eq!(queued(&mut b.link), [GimbalCommand::Photo(Photo::Single)]);
}

#[test]
fn images_at_an_interval_are_taken_and_reported_one_by_one_on_time() {
    let mut b = bridge();
    // Three images 0.5 s apart (under a second: the gimbal's single shot on the bridge's
    // schedule, not its time-lapse).
    let (ack, frames) = ask_camera(&mut b, MavCmd::ImageStartCapture, [0.0, 0.5, 3.0], 1_000);
    assert_eq!(ack.result, MavResult::Accepted);
    assert_eq!(indexes(&frames), [0]);
    let status = &of::<CameraCaptureStatus>(&frames)[0];
    assert_eq!((status.image_status, status.image_interval), (3, 0.5));
    let mut shots = vec![(1_000, queued(&mut b.link))];
    let mut images = Vec::new();
    for ms in 1_001..4_000 {
        b.poll(t(ms));
        let q = queued(&mut b.link);
        if !q.is_empty() {
            shots.push((ms, q));
        }
        for c in of::<CameraImageCaptured>(&sent(&mut b)) {
            assert_eq!(c.time_boot_ms, ms, "reported when taken");
            images.push((ms, c.image_index));
        }
    }
    let single = vec![GimbalCommand::Photo(Photo::Single)];
    assert_eq!(
        shots,
        [
            (1_000, single.clone()),
            (1_500, single.clone()),
            (2_000, single.clone())
        ]
    );
    assert_eq!(images, [(1_500, 1), (2_000, 2)]);
    // Until stopped, every 2 s, from 5 s; stopped at 9.5 s.
    let (_, frames) = ask_camera(&mut b, MavCmd::ImageStartCapture, [0.0, 2.0, 0.0], 5_000);
    assert_eq!(indexes(&frames), [3]);
    let _ = queued(&mut b.link);
    let mut images = Vec::new();
    for ms in 5_001..12_000 {
        if ms == 9_500 {
            let (ack, frames) = ask_camera(&mut b, MavCmd::ImageStopCapture, [0.0; 3], ms);
            assert_eq!(ack.result, MavResult::Accepted);
            assert_eq!(of::<CameraCaptureStatus>(&frames)[0].image_status, 0);
        }
        b.poll(t(ms));
        images.extend(indexes(&sent(&mut b)).into_iter().map(|i| (ms, i)));
    }
    assert_eq!(images, [(7_000, 4), (9_000, 5)]);
    assert_eq!(
        queued(&mut b.link),
        [GimbalCommand::Photo(Photo::Single); 2]
    );
    // Out of common.xml's ranges: denied, nothing taken.
    for p in [
        [0.0, 0.0, 3.0],  // several images with no interval
        [0.0, 0.05, 0.0], // under the 100 ms floor
        [0.0, 0.0, 1.5],  // a fraction of an image
        [0.0, -1.0, 0.0], // a negative interval
        [0.0, f32::NAN, 1.0],
    ] {
        let (ack, _) = ask_camera(&mut b, MavCmd::ImageStartCapture, p, 13_000);
        assert_eq!(ack.result, MavResult::Denied, "{p:?}");
    }
    assert!(queued(&mut b.link).is_empty());
}

/// `n` single images, 10 ms apart from 0, each one photo command for the gimbal.
fn take_single_images(b: &mut Firmware, n: u32) {
    for k in 0..n {
        let _ = ask4(
            b,
            100,
            MavCmd::ImageStartCapture,
            [0.0, 0.0, 1.0, 0.0],
            k * 10,
        );
        assert_eq!(queued(&mut b.link).len(), 1);
    }
}

#[test]
fn images_are_sent_again_on_request_from_the_kept_history() {
    let mut b = bridge();
    take_single_images(&mut b, 20);
    // By index (REQUEST_MESSAGE param2), and by the superseded command MAVSDK falls back to.
    let (ack, frames) = ask_camera(&mut b, MavCmd::RequestMessage, [263.0, 17.0, 0.0], 300);
    assert_eq!(ack.result, MavResult::Accepted);
    assert_eq!(indexes(&frames), [17]);
    assert_eq!(of::<CameraImageCaptured>(&frames)[0].time_boot_ms, 170);
    let (ack, frames) = ask_camera(
        &mut b,
        MavCmd::RequestCameraImageCapture,
        [5.0, 0.0, 0.0],
        310,
    );
    assert_eq!(ack.result, MavResult::Accepted);
    assert_eq!(indexes(&frames), [5]);
    // A range, and "all" (−1): the 16 kept, sent as the outbox makes room.
    let (_, frames) = ask_camera(&mut b, MavCmd::RequestMessage, [263.0, 10.0, 12.0], 320);
    assert_eq!(indexes(&frames), [10, 11, 12]);
    // From an index on (param3 −1).
    let (ack, frames) = ask_camera(&mut b, MavCmd::RequestMessage, [263.0, 17.0, -1.0], 325);
    assert_eq!(ack.result, MavResult::Accepted);
    assert_eq!(indexes(&frames), [17, 18, 19]);
    let (ack, mut frames) = ask_camera(&mut b, MavCmd::RequestMessage, [263.0, -1.0, 0.0], 330);
    assert_eq!(ack.result, MavResult::Accepted);
    for ms in 331..340 {
        b.poll(t(ms));
        frames.extend(sent(&mut b));
    }
    assert_eq!(indexes(&frames), (4..20).collect::<Vec<_>>());
    assert_eq!(b.stats().outbox_full, 0);
    // Not taken yet, no index given (MAVSDK's REQUEST_MESSAGE leaves param2 unset):
    // denied; no longer kept: failed.
    for (p, result) in [
        ([263.0, 20.0, 0.0], MavResult::Denied),
        ([263.0, f32::NAN, 0.0], MavResult::Denied),
        ([263.0, 3.0, 0.0], MavResult::Failed),
        ([263.0, 5.0, 2.0], MavResult::Denied),
        // Not whole, or past i32 (2^31, exact in f32): no index, not the nearest one.
        ([263.0, 17.5, 0.0], MavResult::Denied),
        ([263.0, 17.0, 18.5], MavResult::Denied),
        ([263.0, 17.0, 2_147_483_648.0], MavResult::Denied),
        ([263.0, 17.0, f32::INFINITY], MavResult::Denied),
        // −1 is "all"; other negative indexes are none.
        ([263.0, -2.0, 0.0], MavResult::Denied),
        ([263.0, -2.0, -1.0], MavResult::Denied),
    ] {
        let (ack, frames) = ask_camera(&mut b, MavCmd::RequestMessage, p, 400);
        assert_eq!(ack.result, result, "{p:?}");
        assert!(indexes(&frames).is_empty());
    }
}

#[test]
fn each_camera_message_by_request_message_is_that_message() {
    let mut b = bridge();
    postback(&mut b, GimbalType::X30, 5);
    // common.xml's ids: CAMERA_SETTINGS 260, STORAGE_INFORMATION 261,
    // CAMERA_CAPTURE_STATUS 262; param2 0 as QGroundControl sends it, which for a stream
    // request would mean every stream: none of those may come instead.
    for (id, ms) in [(260.0, 10), (261.0, 20), (262.0, 30)] {
        let (ack, frames) = ask_camera(&mut b, MavCmd::RequestMessage, [id, 0.0, 0.0], ms);
        assert_eq!(ack.result, MavResult::Accepted, "{id}");
        let got: Vec<u32> = frames
            .iter()
            .map(|f| f.message_id())
            .filter(|&m| m != 77)
            .collect();
        assert_eq!(got, [id as u32], "{id}: only the message asked for");
    }
}

#[test]
fn video_start_and_stop_with_the_capture_status() {
    let mut b = bridge();
    let (ack, frames) = ask_camera(&mut b, MavCmd::VideoStartCapture, [0.0; 3], 1_000);
    assert_eq!(ack.result, MavResult::Accepted);
    assert_eq!(of::<CameraCaptureStatus>(&frames)[0].video_status, 1);
    let (_, frames) = ask_camera(
        &mut b,
        MavCmd::RequestCameraCaptureStatus,
        [1.0, 0.0, 0.0],
        3_500,
    );
    let s = &of::<CameraCaptureStatus>(&frames)[0];
    assert_eq!((s.video_status, s.recording_time_ms), (1, 2_500));
    assert!(s.available_capacity.is_nan(), "unknown, not invented");
    let (_, frames) = ask_camera(&mut b, MavCmd::VideoStopCapture, [0.0; 3], 4_000);
    assert_eq!(of::<CameraCaptureStatus>(&frames)[0].video_status, 0);
    assert_eq!(
        queued(&mut b.link),
        [
            GimbalCommand::Video(Video::Start),
            GimbalCommand::Video(Video::Stop)
        ]
    );
}

#[test]
fn while_recording_the_capture_status_comes_at_the_rate_asked() {
    let mut b = bridge();
    // Statuses (their time and recording time) sent unasked between two instants.
    let unasked = |b: &mut Firmware, from: u32, to: u32| {
        let mut got = Vec::new();
        for ms in from..to {
            b.poll(t(ms));
            got.extend(
                of::<CameraCaptureStatus>(&sent(b))
                    .iter()
                    .map(|s| (s.time_boot_ms, s.video_status, s.recording_time_ms)),
            );
        }
        got
    };
    // common.xml: param2 the status's frequency while recording, Hz (MAVProxy sends 1).
    let (ack, _) = ask_camera(&mut b, MavCmd::VideoStartCapture, [0.0, 2.0, 0.0], 1_000);
    assert_eq!(ack.result, MavResult::Accepted);
    assert_eq!(
        unasked(&mut b, 1_001, 2_600),
        [(1_500, 1, 500), (2_000, 1, 1_000), (2_500, 1, 1_500)]
    );
    // Stopped: the stop's own status, then none.
    let (_, frames) = ask_camera(&mut b, MavCmd::VideoStopCapture, [0.0; 3], 2_600);
    assert_eq!(of::<CameraCaptureStatus>(&frames)[0].video_status, 0);
    assert!(unasked(&mut b, 2_601, 5_000).is_empty());
    // 0 (and NaN, a parameter left out): no status unasked.
    for hz in [0.0, f32::NAN] {
        let (ack, _) = ask_camera(&mut b, MavCmd::VideoStartCapture, [0.0, hz, 0.0], 5_000);
        assert_eq!(ack.result, MavResult::Accepted);
        assert!(unasked(&mut b, 5_001, 7_000).is_empty(), "{hz}");
    }
    // A negative rate, more than 1 kHz, or a period over 1000 s (beyond the tick's half
    // range at the smallest rates): refused, and the gimbal not told.
    let _ = queued(&mut b.link);
    for hz in [-1.0, 1_000.5, f32::INFINITY, 0.000_9, 1e-30] {
        let (ack, _) = ask_camera(&mut b, MavCmd::VideoStartCapture, [0.0, hz, 0.0], 7_000);
        assert_eq!(ack.result, MavResult::Denied, "{hz}");
    }
    // param1, the stream: 0 (all), NaN (left out) or the id of one of ours; the bridge's
    // camera here has one, id 1. Another id is refused, to start and to stop.
    for cmd in [MavCmd::VideoStartCapture, MavCmd::VideoStopCapture] {
        for stream in [2.0, -1.0, 1.5, f32::INFINITY] {
            let (ack, _) = ask_camera(&mut b, cmd, [stream, 0.0, 0.0], 7_000);
            assert_eq!(ack.result, MavResult::Denied, "{cmd:?} stream {stream}");
        }
    }
    assert!(queued(&mut b.link).is_empty());
    for stream in [0.0, f32::NAN, 1.0] {
        let (ack, _) = ask_camera(&mut b, MavCmd::VideoStartCapture, [stream, 0.0, 0.0], 7_000);
        assert_eq!(ack.result, MavResult::Accepted, "stream {stream}");
    }
}

/// A postback from a gimbal of type `gimbal_type` into the bridge's link.
fn postback(b: &mut Firmware, gimbal_type: GimbalType, ms: u32) {
    let p = Postback {
        gimbal_type,
        ..Postback::default()
    };
    for data in p.to_can_frames() {
        b.link.receive(ids::POSTBACK, &data, t(ms));
    }
}

#[test]
fn zoom_by_range_continuous_and_step() {
    let mut b = bridge();
    // No postback yet: the zoom range is not known.
    let (ack, _) = ask_camera(&mut b, MavCmd::SetCameraZoom, [2.0, 50.0, 0.0], 5);
    assert_eq!(ack.result, MavResult::TemporarilyRejected);
    postback(&mut b, GimbalType::X30, 6);
    // 50 % of 1×..30×: 15.5×.
    let (ack, frames) = ask_camera(&mut b, MavCmd::SetCameraZoom, [2.0, 50.0, 0.0], 10);
    assert_eq!(ack.result, MavResult::Accepted);
    match queued(&mut b.link)[..] {
        [GimbalCommand::ZoomRatio(r)] => assert_eq!(r.centi(), 1550),
        ref other => panic!("{other:?}"),
    }
    assert_eq!(of::<CameraSettings>(&frames)[0].zoom_level, 50.0);
    // Continuous zoom is a rate: its sign decides (common.xml: range −1..1).
    for (v, z) in [
        (1.0, Zoom::In),
        (0.5, Zoom::In),
        (0.0, Zoom::Stop),
        (-0.25, Zoom::Out),
        (-1.0, Zoom::Out),
    ] {
        let (ack, frames) = ask_camera(&mut b, MavCmd::SetCameraZoom, [1.0, v, 0.0], 20);
        assert_eq!(ack.result, MavResult::Accepted, "{v}");
        assert_eq!(queued(&mut b.link), [GimbalCommand::Zoom(z)]);
        // Where a continuous zoom stops is not reported: the level is unknown.
        assert!(of::<CameraSettings>(&frames)[0].zoom_level.is_nan());
    }
    // A step after a continuous zoom: still unknown, not 1×.
    let (_, frames) = ask_camera(&mut b, MavCmd::SetCameraZoom, [0.0, 2.0, 0.0], 30);
    assert_eq!(queued(&mut b.link), [GimbalCommand::Zoom(Zoom::Double); 2]);
    assert!(of::<CameraSettings>(&frames)[0].zoom_level.is_nan());
    // From a known level, steps double and halve it within the range.
    let _ = ask_camera(&mut b, MavCmd::SetCameraZoom, [2.0, 0.0, 0.0], 31);
    let _ = queued(&mut b.link);
    let (_, frames) = ask_camera(&mut b, MavCmd::SetCameraZoom, [0.0, 2.0, 0.0], 32);
    let _ = queued(&mut b.link);
    // 4× of 1×..30×: (4 − 1) / 29 = 10.34 %.
    let level = of::<CameraSettings>(&frames)[0].zoom_level;
    assert!((level - 300.0 / 29.0).abs() < 1e-4, "{level}");
    // A queue with room for four of five halvings: none sent, the level kept, the client
    // told to try again (a part would leave the lens where the level does not say).
    while b.link.command_room() > 4 {
        b.link.send(GimbalCommand::Recenter).unwrap();
    }
    let (ack, _) = ask_camera(&mut b, MavCmd::SetCameraZoom, [0.0, -10.0, 0.0], 33);
    assert_eq!(ack.result, MavResult::TemporarilyRejected);
    assert_eq!(queued(&mut b.link), [GimbalCommand::Recenter; 4]);
    let (_, frames) = ask_camera(&mut b, MavCmd::RequestCameraSettings, [1.0, 0.0, 0.0], 33);
    let kept = of::<CameraSettings>(&frames)[0].zoom_level;
    assert_eq!(kept, level);
    // QGroundControl's pinch out: round(scale × −10) steps (FlightDisplayViewVideo.qml), here
    // −10: five halvings take any level of the range to its wide end, 1×.
    // Room for exactly the five: taken.
    while b.link.command_room() > 5 {
        b.link.send(GimbalCommand::Recenter).unwrap();
    }
    let (ack, frames) = ask_camera(&mut b, MavCmd::SetCameraZoom, [0.0, -10.0, 0.0], 33);
    assert_eq!(ack.result, MavResult::Accepted);
    assert_eq!(
        queued(&mut b.link),
        [
            [GimbalCommand::Recenter; 3].as_slice(),
            &[GimbalCommand::Zoom(Zoom::Half); 5]
        ]
        .concat()
    );
    assert_eq!(of::<CameraSettings>(&frames)[0].zoom_level, 0.0);
    // And 7 steps in from 1×: five doublings, 30× (32 beyond the range's end).
    let (ack, frames) = ask_camera(&mut b, MavCmd::SetCameraZoom, [0.0, 7.0, 0.0], 34);
    assert_eq!(ack.result, MavResult::Accepted);
    assert_eq!(queued(&mut b.link), [GimbalCommand::Zoom(Zoom::Double); 5]);
    assert_eq!(of::<CameraSettings>(&frames)[0].zoom_level, 100.0);
    for (p, result) in [
        ([2.0, 150.0, 0.0], MavResult::Denied),
        ([1.0, f32::NAN, 0.0], MavResult::Denied),
        ([0.0, 0.0, 0.0], MavResult::Denied),
        ([0.0, 2.5, 0.0], MavResult::Denied),
        ([0.0, f32::INFINITY, 0.0], MavResult::Denied),
        ([3.0, 24.0, 0.0], MavResult::Unsupported),
    ] {
        let (ack, _) = ask_camera(&mut b, MavCmd::SetCameraZoom, p, 40);
        assert_eq!(ack.result, result, "{p:?}");
    }
    assert!(queued(&mut b.link).is_empty());
}

#[test]
fn the_zoom_range_and_the_model_follow_the_gimbal_type() {
    let mut b = bridge();
    postback(&mut b, GimbalType::Zoom3_5x, 0);
    // 100 % of a 3.5× camera is 3.5×, not 30×.
    let (_, frames) = ask_camera(&mut b, MavCmd::SetCameraZoom, [2.0, 100.0, 0.0], 10);
    match queued(&mut b.link)[..] {
        [GimbalCommand::ZoomRatio(r)] => assert_eq!(r.centi(), 350),
        ref other => panic!("{other:?}"),
    }
    assert_eq!(of::<CameraSettings>(&frames)[0].zoom_level, 100.0);
    let (_, frames) = ask_camera(
        &mut b,
        MavCmd::RequestCameraInformation,
        [1.0, 0.0, 0.0],
        20,
    );
    let info = &of::<CameraInformation>(&frames)[0];
    assert_eq!(&info.model_name[..5], b"3.5x\0");
    // The 3.5× yaw motor turns ±325° (the document's Motor_psi scope).
    b.receive_all(
        &frame(
            GCS,
            0,
            &command((AP.0, 154), MavCmd::RequestMessage, 283.0, 0.0),
        ),
        t(30),
    );
    let gi = &of::<GimbalDeviceInformation>(&sent(&mut b))[0];
    assert!((gi.yaw_max - 325f32.to_radians()).abs() < 1e-6);
    assert!((gi.yaw_min + 325f32.to_radians()).abs() < 1e-6);
    // A model the document gives no zoom for, none configured: range zoom unsupported.
    postback(&mut b, GimbalType::A2000, 40);
    let (ack, _) = ask_camera(&mut b, MavCmd::SetCameraZoom, [2.0, 10.0, 0.0], 50);
    assert_eq!(ack.result, MavResult::Unsupported);
}

#[test]
fn the_camera_names_its_gimbal_by_the_configured_component() {
    let camera = CameraConfig::new(URI).unwrap();
    let mut b = Firmware::new(
        Link::new(Config::default()),
        BridgeConfig {
            gimbal_component: 171,
            camera: Some(camera),
            ..BridgeConfig::default()
        },
    );
    b.receive_all(&frame(AP, 0, &heartbeat()), t(0));
    postback(&mut b, GimbalType::X30T, 10);
    let (_, frames) = ask_camera(
        &mut b,
        MavCmd::RequestCameraInformation,
        [1.0, 0.0, 0.0],
        20,
    );
    assert_eq!(of::<CameraInformation>(&frames)[0].gimbal_device_id, 171);
}

#[test]
fn the_stream_and_the_storage_are_said_as_they_are() {
    let mut b = bridge();
    for (cmd, p1) in [
        (MavCmd::RequestVideoStreamInformation, 1.0),
        (MavCmd::RequestMessage, 269.0),
    ] {
        let (_, frames) = ask_camera(&mut b, cmd, [p1, 0.0, 0.0], 10);
        let s = &of::<VideoStreamInformation>(&frames)[0];
        assert_eq!(
            (s.stream_id, s.count, s.type_),
            (1, 1, VideoStreamType::Rtsp)
        );
        assert!(s.flags.contains(VideoStreamStatusFlags::RUNNING));
        let end = s.uri.iter().position(|&c| c == 0).unwrap();
        assert_eq!(&s.uri[..end], URI.as_bytes());
    }
    // MAVSDK's camera plugin asks for the stream's status (every 5 s) as well.
    for (cmd, p1) in [
        (MavCmd::RequestVideoStreamStatus, 1.0),
        (MavCmd::RequestMessage, 270.0),
    ] {
        let (ack, frames) = ask_camera(&mut b, cmd, [p1, 0.0, 0.0], 10);
        assert_eq!(ack.result, MavResult::Accepted);
        let s = &of::<VideoStreamStatus>(&frames)[0];
        assert_eq!(s.stream_id, 1);
        assert!(s.flags.contains(VideoStreamStatusFlags::RUNNING));
    }
    let (_, frames) = ask_camera(&mut b, MavCmd::RequestStorageInformation, [0.0; 3], 10);
    assert_eq!(
        of::<StorageInformation>(&frames)[0].status,
        StorageStatus::NotSupported
    );
}

#[test]
fn a_uri_longer_than_the_field_is_a_configuration_error() {
    let long = format!("rtsp://192.168.42.108:554/{}", "x".repeat(140));
    assert_eq!(
        CameraConfig::new(&long),
        Err(UriTooLong {
            len: long.len(),
            max: 160
        })
    );
    assert!(CameraConfig::new(&long[..160]).is_ok());
    // What was wrong and what is valid, in words.
    let e = CameraConfig::new(&long).unwrap_err();
    let said = format!(
        "stream URI is {} bytes; VIDEO_STREAM_INFORMATION holds at most 160",
        long.len()
    );
    assert_eq!(e.to_string(), said);
    assert_eq!(StreamError::UriTooLong(e).to_string(), said);
    let video = VideoError::NoSuchStream {
        family: Family::A2000,
        stream: Stream::Infrared,
    };
    assert_eq!(StreamError::Video(video).to_string(), video.to_string());
    // The main stream's URI is the one given.
    assert_eq!(CameraConfig::new(URI).unwrap().uri(), URI);
}

#[test]
fn an_interval_for_a_message_neither_component_sends_is_left_to_others() {
    let mut b = bridge();
    postback(&mut b, GimbalType::X30, 5);
    let _ = sent(&mut b);
    // GLOBAL_POSITION_INT (33), to every component: another's to answer, not the camera's
    // nor the gimbal's.
    let c = command((AP.0, 0), MavCmd::SetMessageInterval, 33.0, 100_000.0);
    b.receive_all(&frame(GCS, 0, &c), t(10));
    assert!(of::<CommandAck>(&sent(&mut b)).is_empty());
    // CAMERA_FOV_STATUS (271) to every component: the camera's.
    let c = command((AP.0, 0), MavCmd::SetMessageInterval, 271.0, 100_000.0);
    b.receive_all(&frame(GCS, 1, &c), t(20));
    let frames = sent(&mut b);
    let acks: Vec<(u8, MavResult)> = frames
        .iter()
        .filter(|f| f.message_id() == 77)
        .map(|f| {
            let a: CommandAck = f.decode_message().unwrap();
            (f.component_id(), a.result)
        })
        .collect();
    assert_eq!(acks, [(100, MavResult::Accepted)]);
}

#[test]
fn messages_no_component_handles_are_neither_bad_nor_answered() {
    let mut b = bridge();
    postback(&mut b, GimbalType::X30, 5);
    let _ = sent(&mut b);
    let before = b.stats().reader;
    let time = SystemTime {
        time_unix_usec: 1_700_000_000_000_000,
        time_boot_ms: 2,
    };
    b.receive_all(&frame(AP, 1, &time), t(10));
    b.receive_all(&frame(GCS, 2, &time), t(10));
    let after = b.stats().reader;
    assert_eq!(after.frames - before.frames, 2);
    assert_eq!(after.bad_frames, before.bad_frames);
    assert!(sent(&mut b).is_empty());
}

/// Fills the outbox with 300 bytes or more of answers not yet sent (the gimbal's
/// information, asked again and again), still short of what a request waits for; the next
/// sequence number.
fn part_fill_outbox(b: &mut Firmware) -> u8 {
    let mut seq = 0;
    while b.transmit_bytes().len() < 300 {
        let c = command((AP.0, 154), MavCmd::RequestMessage, 283.0, 0.0);
        b.receive_all(&frame(GCS, seq, &c), t(200));
        seq += 1;
    }
    seq
}

#[test]
fn images_asked_again_beyond_the_outboxs_room_wait_for_it_and_none_is_lost() {
    let mut b = bridge();
    take_single_images(&mut b, 16);
    let _ = sent(&mut b);
    // The sixteen images cannot all follow at once.
    let seq = part_fill_outbox(&mut b);
    let c = command((AP.0, 100), MavCmd::RequestMessage, 263.0, -1.0);
    b.receive_all(&frame(GCS, seq, &c), t(300));
    let mut frames = sent(&mut b);
    assert!(indexes(&frames).len() < 16, "some wait for room");
    for ms in 301..310 {
        b.poll(t(ms));
        frames.extend(sent(&mut b));
    }
    assert_eq!(indexes(&frames), (0..16).collect::<Vec<_>>());
    assert_eq!(b.stats().outbox_full, 0);
}

#[test]
fn stream_information_beyond_the_outboxs_room_waits_for_it_and_none_is_lost() {
    // The longest credentials make URIs of 125 bytes: three VIDEO_STREAM_INFORMATION do
    // not fit behind a part-filled outbox at once.
    let (user, password) = ("u".repeat(32), "p".repeat(32));
    let camera = VideoCamera {
        credentials: Credentials::new(&user, &password),
        ..VideoCamera::new(Family::DualLight)
    };
    let mut b = camera_bridge(CameraConfig::with_streams_of(&camera).unwrap());
    postback(&mut b, GimbalType::DualLight30x, 5);
    let _ = sent(&mut b);
    let seq = part_fill_outbox(&mut b);
    // VIDEO_STREAM_INFORMATION (269), param2 0: every stream.
    let c = command((AP.0, 100), MavCmd::RequestMessage, 269.0, 0.0);
    b.receive_all(&frame(GCS, seq, &c), t(300));
    let mut frames = sent(&mut b);
    assert!(frames.iter().filter(|f| f.message_id() == 269).count() < 3);
    for ms in 301..310 {
        b.poll(t(ms));
        frames.extend(sent(&mut b));
    }
    let ids: Vec<u8> = of::<VideoStreamInformation>(&frames)
        .iter()
        .map(|s| s.stream_id)
        .collect();
    assert_eq!(ids, [1, 2, 3]);
    assert_eq!(b.stats().outbox_full, 0);
}

#[test]
fn an_image_taken_while_the_gimbal_link_is_down_has_no_attitude() {
    let mut b = bridge();
    // The image taken at `ms`, its report's quaternion.
    let image_q = |b: &mut Firmware, ms: u32| {
        let (_, mut frames) = ask4(b, 100, MavCmd::ImageStartCapture, [0.0, 0.0, 1.0, 0.0], ms);
        b.poll(t(ms));
        frames.extend(sent(b));
        let _ = queued(&mut b.link);
        of::<CameraImageCaptured>(&frames)[0].q
    };
    postback(&mut b, GimbalType::X30, 0);
    b.receive_all(&frame(AP, 0, &autopilot_state(0.0)), t(10));
    assert!(image_q(&mut b, 20).iter().all(|v| v.is_finite()));
    // No postback for longer than the link's timeout (1.5 s), the vehicle's heading fresh:
    // the last postback's angles are stale, the attitude unknown.
    b.receive_all(&frame(AP, 1, &autopilot_state(0.0)), t(1_600));
    b.link.poll(t(1_600));
    assert!(!b.link.is_link_up());
    assert!(image_q(&mut b, 1_610).iter().all(|v| v.is_nan()));
}
