//! The camera component as a ground station sees it.

mod common;
use common::*;

use idu_gimbal::link::{Config, Link};
use idu_gimbal::video::{Camera as VideoCamera, Family, Stream};
use idu_gimbal::wire::control::{GimbalCommand, Photo, Video, Zoom};
use idu_gimbal_mavlink::camera::{CameraConfig, UriTooLong};
use idu_gimbal_mavlink::{Bridge, BridgeConfig};
use mavio::dialects::common::enums::{
    CameraCapFlags, MavCmd, MavResult, MavType, StorageStatus, VideoStreamStatusFlags,
    VideoStreamType,
};
use mavio::dialects::common::messages::{
    CameraCaptureStatus, CameraImageCaptured, CameraInformation, CameraSettings, CommandAck,
    Heartbeat, StorageInformation, VideoStreamInformation, VideoStreamStatus,
};
use mavio::protocol::{Frame, V2};

const URI: &str = "rtsp://admin:admin@192.168.42.108:554/cam/realmonitor?channel=1&subtype=0";

fn bridge() -> Bridge<Link> {
    let camera = CameraConfig::new(
        VideoCamera::new(Family::DualLight)
            .url(Stream::Main)
            .unwrap()
            .as_str(),
    )
    .unwrap();
    let mut b = Bridge::new(
        Link::new(Config::default()),
        BridgeConfig {
            camera: Some(camera),
            ..BridgeConfig::default()
        },
    );
    b.receive(&frame(AP, 0, &heartbeat()), t(0));
    let _ = sent(&mut b);
    b
}

/// The ACK (from `component`) and the other frames a command produced.
fn ask(
    b: &mut Bridge<Link>,
    to: u8,
    cmd: MavCmd,
    p: [f32; 3],
    ms: u32,
) -> (CommandAck, Vec<Frame<V2>>) {
    let mut c = command((AP.0, to), cmd, p[0], p[1]);
    c.param3 = p[2];
    b.receive(&frame(GCS, 0, &c), t(ms));
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
fn camera_heartbeats_beside_the_gimbals() {
    let mut b = bridge();
    for ms in 0..2_000 {
        b.poll(t(ms));
    }
    let hbs: Vec<(u8, Heartbeat)> = sent(&mut b)
        .iter()
        .filter(|f| f.message_id() == 0)
        .map(|f| (f.component_id(), f.decode_message().unwrap()))
        .collect();
    let camera: Vec<_> = hbs.iter().filter(|h| h.0 == 100).collect();
    assert_eq!(camera.len(), 2);
    assert!(camera.iter().all(|h| h.1.type_ == MavType::Camera));
    assert_eq!(hbs.iter().filter(|h| h.0 == 154).count(), 2);
}

#[test]
fn information_by_request_message_and_by_the_legacy_command() {
    let mut b = bridge();
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
            CameraCapFlags::HAS_VIDEO_STREAM,
        ] {
            assert!(f.contains(flag), "{flag:?}");
        }
        assert!(!f.contains(CameraCapFlags::HAS_BASIC_FOCUS));
        assert_eq!(info[0].gimbal_device_id, 154);
    }
    // A gimbal request to the camera: not the camera's, said so.
    let (ack, _) = ask(&mut b, 100, MavCmd::RequestMessage, [283.0, 0.0, 0.0], 20);
    assert_eq!(ack.result, MavResult::Unsupported);
}

#[test]
fn single_burst_and_time_lapse_photos() {
    let mut b = bridge();
    let (ack, frames) = ask(&mut b, 100, MavCmd::ImageStartCapture, [0.0, 0.0, 1.0], 10);
    assert_eq!(ack.result, MavResult::Accepted);
    assert_eq!(
        queued(b.gimbal_mut()),
        [GimbalCommand::Photo(Photo::Single)]
    );
    let captured: Vec<CameraImageCaptured> = of(&frames);
    assert_eq!(
        captured.iter().map(|c| c.image_index).collect::<Vec<_>>(),
        [0]
    );
    assert_eq!(of::<CameraCaptureStatus>(&frames)[0].image_count, 1);

    let (_, frames) = ask(&mut b, 100, MavCmd::ImageStartCapture, [0.0, 0.0, 3.0], 20);
    assert_eq!(
        queued(b.gimbal_mut()),
        [GimbalCommand::Photo(Photo::burst(3).unwrap())]
    );
    let captured: Vec<CameraImageCaptured> = of(&frames);
    assert_eq!(
        captured.iter().map(|c| c.image_index).collect::<Vec<_>>(),
        [1, 2, 3]
    );

    // Unlimited images every 2 s: a time-lapse, one capture message per interval.
    let (_, frames) = ask(
        &mut b,
        100,
        MavCmd::ImageStartCapture,
        [0.0, 2.0, 0.0],
        1_000,
    );
    assert_eq!(
        queued(b.gimbal_mut()),
        [GimbalCommand::Photo(Photo::time_lapse(2).unwrap())]
    );
    let status = &of::<CameraCaptureStatus>(&frames)[0];
    assert_eq!((status.image_status, status.image_interval), (2, 2.0));
    let mut indices = Vec::new();
    for ms in 1_000..7_500 {
        b.poll(t(ms));
        indices.extend(
            of::<CameraImageCaptured>(&sent(&mut b))
                .iter()
                .map(|c| c.image_index),
        );
        if ms == 6_000 {
            let (_, _) = ask(&mut b, 100, MavCmd::ImageStopCapture, [0.0; 3], ms);
            assert_eq!(queued(b.gimbal_mut()), [GimbalCommand::Photo(Photo::Stop)]);
        }
    }
    // At 3, 5 s; stopped at 6 s.
    assert_eq!(indices, [4, 5]);
    // Nonsense is denied: 0 images at no interval, 1.5 images, 300 images.
    for p in [
        [0.0, 0.0, 0.0],
        [0.0, 0.0, 1.5],
        [0.0, 0.0, 300.0],
        [0.0, -1.0, 0.0],
    ] {
        let (ack, _) = ask(&mut b, 100, MavCmd::ImageStartCapture, p, 8_000);
        assert_eq!(ack.result, MavResult::Denied, "{p:?}");
    }
    assert!(queued(b.gimbal_mut()).is_empty());
}

#[test]
fn video_start_and_stop_with_the_capture_status() {
    let mut b = bridge();
    let (ack, frames) = ask(&mut b, 100, MavCmd::VideoStartCapture, [0.0; 3], 1_000);
    assert_eq!(ack.result, MavResult::Accepted);
    assert_eq!(of::<CameraCaptureStatus>(&frames)[0].video_status, 1);
    let (_, frames) = ask(
        &mut b,
        100,
        MavCmd::RequestCameraCaptureStatus,
        [1.0, 0.0, 0.0],
        3_500,
    );
    let s = &of::<CameraCaptureStatus>(&frames)[0];
    assert_eq!((s.video_status, s.recording_time_ms), (1, 2_500));
    assert!(s.available_capacity.is_nan(), "unknown, not invented");
    let (_, frames) = ask(&mut b, 100, MavCmd::VideoStopCapture, [0.0; 3], 4_000);
    assert_eq!(of::<CameraCaptureStatus>(&frames)[0].video_status, 0);
    assert_eq!(
        queued(b.gimbal_mut()),
        [
            GimbalCommand::Video(Video::Start),
            GimbalCommand::Video(Video::Stop)
        ]
    );
}

#[test]
fn zoom_by_range_continuous_and_step() {
    let mut b = bridge();
    // 50 % of 1×..30×: 15.5×.
    let (ack, frames) = ask(&mut b, 100, MavCmd::SetCameraZoom, [2.0, 50.0, 0.0], 10);
    assert_eq!(ack.result, MavResult::Accepted);
    match queued(b.gimbal_mut())[..] {
        [GimbalCommand::ZoomRatio(r)] => assert_eq!(r.centi(), 1550),
        ref other => panic!("{other:?}"),
    }
    assert_eq!(of::<CameraSettings>(&frames)[0].zoom_level, 50.0);
    for (v, z) in [(1.0, Zoom::In), (0.0, Zoom::Stop), (-1.0, Zoom::Out)] {
        let (ack, _) = ask(&mut b, 100, MavCmd::SetCameraZoom, [1.0, v, 0.0], 20);
        assert_eq!(ack.result, MavResult::Accepted);
        assert_eq!(queued(b.gimbal_mut()), [GimbalCommand::Zoom(z)]);
    }
    let (_, _) = ask(&mut b, 100, MavCmd::SetCameraZoom, [0.0, 2.0, 0.0], 30);
    assert_eq!(
        queued(b.gimbal_mut()),
        [GimbalCommand::Zoom(Zoom::Double); 2]
    );
    for (p, result) in [
        ([2.0, 150.0, 0.0], MavResult::Denied),
        ([1.0, 0.5, 0.0], MavResult::Denied),
        ([0.0, 9.0, 0.0], MavResult::Denied),
        ([3.0, 24.0, 0.0], MavResult::Unsupported),
    ] {
        let (ack, _) = ask(&mut b, 100, MavCmd::SetCameraZoom, p, 40);
        assert_eq!(ack.result, result, "{p:?}");
    }
    assert!(queued(b.gimbal_mut()).is_empty());
}

#[test]
fn the_stream_and_the_storage_are_said_as_they_are() {
    let mut b = bridge();
    for (cmd, p1) in [
        (MavCmd::RequestVideoStreamInformation, 1.0),
        (MavCmd::RequestMessage, 269.0),
    ] {
        let (_, frames) = ask(&mut b, 100, cmd, [p1, 0.0, 0.0], 10);
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
        let (ack, frames) = ask(&mut b, 100, cmd, [p1, 0.0, 0.0], 10);
        assert_eq!(ack.result, MavResult::Accepted);
        let s = &of::<VideoStreamStatus>(&frames)[0];
        assert_eq!(s.stream_id, 1);
        assert!(s.flags.contains(VideoStreamStatusFlags::RUNNING));
    }
    let (_, frames) = ask(&mut b, 100, MavCmd::RequestStorageInformation, [0.0; 3], 10);
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
}
