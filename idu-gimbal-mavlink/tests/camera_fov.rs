//! The camera's field of view: its angles in the streams' information and in
//! `CAMERA_FOV_STATUS`, and where the image centre meets the ground.

mod common;
use common::*;

use idu_gimbal::geo::{look_at, Position};
use idu_gimbal::video::{Camera as VideoCamera, Family};
use idu_gimbal::wire::ids;
use idu_gimbal::wire::postback::{GimbalType, Postback};
use idu_gimbal_mavlink::attitude::YawPitch;
use idu_gimbal_mavlink::camera::fov::FieldOfView;
use idu_gimbal_mavlink::camera::CameraConfig;
use mavio::dialects::common::enums::{MavCmd, MavResult};
use mavio::dialects::common::messages::{
    CameraCaptureStatus, CameraFovStatus, CameraTrackingImageStatus, CommandAck, GlobalPositionInt,
    VideoStreamInformation,
};

const FOV_STATUS: f32 = 271.0;
const STREAM_INFORMATION: f32 = 269.0;
/// The lens the tests configure: 60° × 34° at 1×.
const LENS: (f64, f64) = (60.0, 34.0);

/// A dual light (a visible stream and the infrared one among its three), with `lens`.
fn bridge(lens: Option<FieldOfView>) -> Firmware {
    let mut camera = CameraConfig::with_streams_of(&VideoCamera::new(Family::DualLight)).unwrap();
    camera.fov = lens;
    camera.resolution = Some((1920, 1080));
    camera_bridge(camera)
}

fn lens() -> Option<FieldOfView> {
    Some(FieldOfView::from_degrees(LENS.0 as f32, LENS.1 as f32).unwrap())
}

/// The postback: a 30× gimbal, its camera at `pitch_cdeg` and its motor at `motor_cdeg`.
fn postback(b: &mut Firmware, pitch_cdeg: i16, motor_cdeg: i16, ms: u32) {
    let p = Postback {
        gimbal_type: GimbalType::X30,
        pitch: pitch_cdeg,
        motor_heading: motor_cdeg,
        ..Postback::default()
    };
    for data in p.to_can_frames() {
        b.link.receive(ids::POSTBACK, &data, t(ms));
    }
    b.poll(t(ms));
}

/// `COMMAND_LONG` to the camera: its one ACK's result.
fn ask(b: &mut Firmware, cmd: MavCmd, p1: f32, p2: f32, ms: u32) -> MavResult {
    b.receive_all(&frame(GCS, 0, &command((AP.0, 100), cmd, p1, p2)), t(ms));
    let acks = of::<CommandAck>(&sent(b));
    assert_eq!(acks.len(), 1, "{cmd:?}: one ACK");
    acks[0].result
}

/// `CAMERA_FOV_STATUS` asked for: ACCEPTED, then the one status.
fn fov_status(b: &mut Firmware, ms: u32) -> CameraFovStatus {
    b.receive_all(
        &frame(
            GCS,
            0,
            &command((AP.0, 100), MavCmd::RequestMessage, FOV_STATUS, 0.0),
        ),
        t(ms),
    );
    let frames = sent(b);
    assert_eq!(of::<CommandAck>(&frames)[0].result, MavResult::Accepted);
    let s = of::<CameraFovStatus>(&frames);
    assert_eq!(s.len(), 1);
    s[0].clone()
}

/// The visible (main) stream's and the infrared stream's `hfov`.
fn stream_hfov(b: &mut Firmware, ms: u32) -> (u16, u16) {
    b.receive_all(
        &frame(
            GCS,
            0,
            &command((AP.0, 100), MavCmd::RequestMessage, STREAM_INFORMATION, 0.0),
        ),
        t(ms),
    );
    let mut info = of::<VideoStreamInformation>(&sent(b));
    for ms in ms + 1..ms + 5 {
        b.poll(t(ms));
        info.extend(of::<VideoStreamInformation>(&sent(b)));
    }
    assert_eq!(info.len(), 3, "the dual light's three streams");
    assert!(info
        .iter()
        .all(|i| (i.resolution_h, i.resolution_v) == (1920, 1080)));
    let ir = info.iter().find(|i| i.flags.bits() & 2 != 0).unwrap();
    (info[0].hfov, ir.hfov)
}

/// The angle at zoom `z` of one that is `a` degrees at 1×, for an optical zoom.
/// `SET_CAMERA_ZOOM` of `zoom_type` to `value`, accepted.
fn zoom(b: &mut Firmware, zoom_type: f32, value: f32, ms: u32) {
    assert_eq!(
        ask(b, MavCmd::SetCameraZoom, zoom_type, value, ms),
        MavResult::Accepted
    );
}

fn at_zoom(a: f64, z: f64) -> f64 {
    2.0 * ((a / 2.0).to_radians().tan() / z).atan().to_degrees()
}

#[test]
fn without_a_lens_the_angles_are_unknown_and_the_status_still_answered() {
    let mut b = bridge(None);
    let s = fov_status(&mut b, 10);
    assert!(s.hfov.is_nan() && s.vfov.is_nan());
    // No position from the autopilot yet, no postback: nothing known.
    assert_eq!([s.lat_camera, s.lon_camera, s.alt_camera], [i32::MAX; 3]);
    assert_eq!([s.lat_image, s.lon_image, s.alt_image], [i32::MAX; 3]);
    assert!(s.q.iter().all(|v| v.is_nan()));
    assert_eq!(s.time_boot_ms, 10);
    postback(&mut b, 0, 0, 20);
    assert_eq!(stream_hfov(&mut b, 30), (0, 0));
}

#[test]
fn the_angles_follow_the_zoom() {
    let mut b = bridge(lens());
    postback(&mut b, 0, 0, 5);
    // f32 trigonometry: within 1e-4° of the f64 expectation.
    let near = |got: f32, want: f64| (f64::from(got) - want).abs() < 1e-4;
    let s = fov_status(&mut b, 10);
    assert!(near(s.hfov, LENS.0) && near(s.vfov, LENS.1), "{s:?}");
    assert_eq!(stream_hfov(&mut b, 20), (60, 0));
    // One zoom step in: 2× (ZOOM_TYPE_STEP), told in CAMERA_SETTINGS.
    zoom(&mut b, 0.0, 1.0, 30);
    let s = fov_status(&mut b, 40);
    assert!(near(s.hfov, at_zoom(LENS.0, 2.0)), "{} vs 32.204", s.hfov);
    assert!(near(s.vfov, at_zoom(LENS.1, 2.0)), "{}", s.vfov);
    assert_eq!(stream_hfov(&mut b, 50), (32, 0));
    // To 30× (ZOOM_TYPE_RANGE 100 %): 2 atan(tan 30° / 30) = 2.205°.
    zoom(&mut b, 2.0, 100.0, 60);
    let s = fov_status(&mut b, 70);
    assert!(near(s.hfov, at_zoom(LENS.0, 30.0)), "{}", s.hfov);
    assert_eq!(stream_hfov(&mut b, 80), (2, 0));
    // A continuous zoom: the ratio, so the angles, no longer known.
    zoom(&mut b, 1.0, 1.0, 90);
    let s = fov_status(&mut b, 100);
    assert!(s.hfov.is_nan() && s.vfov.is_nan());
    assert_eq!(stream_hfov(&mut b, 110), (0, 0));
}

#[test]
fn a_field_of_view_must_be_an_angle_between_0_and_180() {
    for (h, v) in [
        (0.0, 30.0),
        (180.0, 30.0),
        (60.0, -1.0),
        (f32::NAN, 30.0),
        (60.0, 200.0),
    ] {
        let e = FieldOfView::from_degrees(h, v).unwrap_err();
        let which = if h > 0.0 && h < 180.0 {
            "vertical"
        } else {
            "horizontal"
        };
        assert_eq!(e.which, which, "{h} {v}");
        assert!(
            e.to_string().contains("more than 0 and less than 180"),
            "{e}"
        );
    }
}

/// A bridge that has the autopilot's position and heading, and a postback.
fn placed(
    pos: GlobalPositionInt,
    vehicle_yaw_deg: f32,
    pitch_cdeg: i16,
    motor_cdeg: i16,
) -> Firmware {
    let mut b = bridge(lens());
    b.receive_all(&frame(AP, 1, &pos), t(10));
    b.receive_all(&frame(AP, 2, &autopilot_state(vehicle_yaw_deg)), t(10));
    postback(&mut b, pitch_cdeg, motor_cdeg, 20);
    let _ = sent(&mut b);
    b
}

#[test]
fn the_image_centre_is_where_the_line_of_sight_meets_the_ground() {
    // 100 m over its home (488.123 m above sea level, so the ground at 388.123 m), the
    // vehicle heading east, the camera straight ahead and 45° down: the ground 100 m east.
    let (lat, lon) = (473_977_420, 85_455_940);
    let mut b = placed(position(lat, lon, 488_123, 100_000), 90.0, -4_500, 0);
    let s = fov_status(&mut b, 30);
    assert_eq!(
        [s.lat_camera, s.lon_camera, s.alt_camera],
        [lat, lon, 488_123]
    );
    assert_eq!(s.alt_image, 388_123);
    // By hand: 100 m east over the radius of the parallel, N cos φ, with N the prime
    // vertical radius at the ground (a / √(1 − e² sin² φ) + 388 m); the ground's curvature
    // moves the point by under a millimetre at 100 m. 1e-7° of longitude is 7.5 mm here,
    // of latitude 11 mm: ±2 units is ±2 cm.
    let phi = (f64::from(lat) * 1e-7).to_radians();
    let e2 = 6.694_379_990_14e-3;
    let n = 6_378_137.0 / (1.0 - e2 * phi.sin().powi(2)).sqrt() + 388.123;
    let dlon = (100.0 / (n * phi.cos())).to_degrees() * 1e7;
    assert!((s.lat_image - lat).abs() <= 2, "{}", s.lat_image - lat);
    assert!(
        (f64::from(s.lon_image - lon) - dlon).abs() <= 2.0,
        "{} vs {dlon}",
        s.lon_image - lon
    );
    // And the exact WGS84 look-at from the camera to that point sees it where the camera
    // looks: 0.01° is 2.5 cm at 141 m, the integers' own resolution.
    let deg = |v: i32| f64::from(v) * 1e-7;
    let look = look_at(
        &Position::new(deg(lat), deg(lon), 488.123).unwrap(),
        &Position::new(deg(s.lat_image), deg(s.lon_image), 388.123).unwrap(),
    )
    .unwrap();
    assert!((look.bearing_deg - 90.0).abs() < 0.01, "{look:?}");
    assert!((look.elevation_deg + 45.0).abs() < 0.01, "{look:?}");
    // The camera's earth-frame attitude.
    let q = YawPitch::from_quaternion(s.q).unwrap();
    assert!((q.yaw_rad.to_degrees() - 90.0).abs() < 1e-3, "{q:?}");
    assert!((q.pitch_rad.to_degrees() + 45.0).abs() < 1e-3, "{q:?}");
}

#[test]
fn the_motor_angle_turns_with_the_vehicle_and_the_longitude_wraps() {
    // Just west of the antimeridian, the vehicle heading north and the motor 90° right:
    // the camera looks east, 500 m out at 45° down, across 180°.
    let lon = 1_799_999_990;
    let mut b = placed(position(0, lon, 500_000, 500_000), 0.0, -4_500, 9_000);
    let s = fov_status(&mut b, 30);
    // 500 m at the equator, and 2 cm more where the ground curves away under the line
    // (d² / 2a), is 0.00449175° of longitude (a = 6 378 137 m): past 180 by that less
    // 1e-6°, so at −180 + 0.00449075°.
    let want = -1_800_000_000 + 44_908;
    assert!((s.lon_image - want).abs() <= 2, "{} vs {want}", s.lon_image);
    assert!(s.lat_image.abs() <= 2, "{}", s.lat_image);
    assert_eq!(s.alt_image, 0);
    // The mirror image: just east of it, the motor 90° left, across −180°.
    let mut b = placed(position(0, -lon, 500_000, 500_000), 0.0, -4_500, -9_000);
    let s = fov_status(&mut b, 30);
    assert!(
        (s.lon_image + want).abs() <= 2,
        "{} vs {}",
        s.lon_image,
        -want
    );
    assert!(s.lat_image.abs() <= 2, "{}", s.lat_image);
}

#[test]
fn at_or_above_the_horizon_the_centre_is_at_infinity_and_below_home_unknown() {
    let pos = position(473_977_420, 85_455_940, 488_123, 100_000);
    // 10° up: common.xml's INT32_MIN, "at infinity, not intersecting with horizon".
    let mut b = placed(pos.clone(), 0.0, 1_000, 0);
    let s = fov_status(&mut b, 30);
    assert_eq!([s.lat_image, s.lon_image, s.alt_image], [i32::MIN; 3]);
    assert_eq!(s.lat_camera, 473_977_420);
    // Level, from 100 m: the horizon is 0.32° down, so a level line misses.
    let mut b = placed(pos, 0.0, 0, 0);
    assert_eq!(fov_status(&mut b, 30).lat_image, i32::MIN);
    // Below the home altitude (a valley), flat ground at home is above the camera: no
    // answer, INT32_MAX.
    let mut b = placed(
        position(473_977_420, 85_455_940, 388_123, -5_000),
        0.0,
        -4_500,
        0,
    );
    let s = fov_status(&mut b, 30);
    assert_eq!([s.lat_image, s.lon_image, s.alt_image], [i32::MAX; 3]);
    // Altitudes at the ends of i32 (alt − relative_alt overflows i32): unknown, never a
    // wrapped ground.
    let mut b = placed(position(0, 0, i32::MAX, -1), 0.0, -4_500, 0);
    assert_eq!(fov_status(&mut b, 30).lat_image, i32::MAX);
    let mut b = placed(position(0, 0, i32::MIN, i32::MAX), 0.0, -4_500, 0);
    assert_eq!(fov_status(&mut b, 30).alt_image, i32::MAX);
    // 11 m from the north pole: beyond the ±85° the ground hit is computed for
    // (`geo::GROUND_HIT_LAT_MAX_DEG`), unknown rather than a point past the pole.
    let mut b = placed(position(899_999_000, 0, 100_000, 100_000), 0.0, -4_500, 0);
    let s = fov_status(&mut b, 30);
    assert_eq!([s.lat_image, s.lon_image, s.alt_image], [i32::MAX; 3]);
}

#[test]
fn the_status_is_streamed_at_the_interval_asked_and_stops() {
    let mut b = bridge(lens());
    postback(&mut b, 0, 0, 0);
    let _ = sent(&mut b);
    // Nothing unasked: common.xml gives the message no default rate.
    let count = |b: &mut Firmware, from: u32, to: u32| {
        let mut times = Vec::new();
        for ms in from..to {
            b.poll(t(ms));
            times.extend(
                of::<CameraFovStatus>(&sent(b))
                    .iter()
                    .map(|s| s.time_boot_ms),
            );
        }
        times
    };
    assert!(count(&mut b, 1, 1_000).is_empty());
    let r = ask(
        &mut b,
        MavCmd::SetMessageInterval,
        FOV_STATUS,
        200_000.0,
        1_000,
    );
    assert_eq!(r, MavResult::Accepted);
    assert_eq!(
        count(&mut b, 1_000, 2_000),
        [1_000, 1_200, 1_400, 1_600, 1_800]
    );
    // Below a millisecond: out of range, and the interval set stays.
    let r = ask(&mut b, MavCmd::SetMessageInterval, FOV_STATUS, 500.0, 2_000);
    assert_eq!(r, MavResult::Denied);
    assert_eq!(count(&mut b, 2_000, 2_401), [2_000, 2_200, 2_400]);
    let r = ask(&mut b, MavCmd::SetMessageInterval, FOV_STATUS, -1.0, 2_401);
    assert_eq!(r, MavResult::Accepted);
    assert!(count(&mut b, 2_401, 4_000).is_empty());
}

/// Two periodic messages at once, each at its own rate: the field of view every 200 ms, the
/// capture status while recording once a second (VIDEO_START_CAPTURE's param2, in Hz); no
/// tracking status, nothing being tracked.
#[test]
fn each_periodic_message_keeps_its_own_rate() {
    let mut b = bridge(lens());
    postback(&mut b, 0, 0, 0);
    let _ = sent(&mut b);
    let r = ask(&mut b, MavCmd::VideoStartCapture, 0.0, 1.0, 1_000);
    assert_eq!(r, MavResult::Accepted);
    let r = ask(
        &mut b,
        MavCmd::SetMessageInterval,
        FOV_STATUS,
        200_000.0,
        1_000,
    );
    assert_eq!(r, MavResult::Accepted);
    let (mut fov, mut capture, mut tracking) = (Vec::new(), Vec::new(), 0);
    for ms in 1_001..3_000 {
        b.poll(t(ms));
        let frames = sent(&mut b);
        fov.extend(
            of::<CameraFovStatus>(&frames)
                .iter()
                .map(|s| s.time_boot_ms),
        );
        capture.extend(
            of::<CameraCaptureStatus>(&frames)
                .iter()
                .map(|s| s.time_boot_ms),
        );
        tracking += of::<CameraTrackingImageStatus>(&frames).len();
    }
    // Due from the request at 1,000, first sent at the next poll, then every 200 ms.
    assert_eq!(
        fov,
        [1_001, 1_201, 1_401, 1_601, 1_801, 2_001, 2_201, 2_401, 2_601, 2_801]
    );
    assert_eq!(capture, [2_000]);
    assert_eq!(tracking, 0);
}

#[test]
fn looking_north_the_image_centre_is_north() {
    // As above, the vehicle heading north: the ground 100 m north.
    let (lat, lon) = (473_977_420, 85_455_940);
    let mut b = placed(position(lat, lon, 488_123, 100_000), 0.0, -4_500, 0);
    let s = fov_status(&mut b, 30);
    // By hand: 100 m over the meridian's radius of curvature, a (1 − e²) / (1 − e² sin² φ)^1.5
    // + 388 m; 1e-7° of latitude is 11 mm: ±2 units is ±2 cm.
    let phi = (f64::from(lat) * 1e-7).to_radians();
    let e2 = 6.694_379_990_14e-3;
    let m = 6_378_137.0 * (1.0 - e2) / (1.0 - e2 * phi.sin().powi(2)).powf(1.5) + 388.123;
    let dlat = (100.0 / m).to_degrees() * 1e7;
    assert!(
        (f64::from(s.lat_image - lat) - dlat).abs() <= 2.0,
        "{} vs {dlat}",
        s.lat_image - lat
    );
    assert!((s.lon_image - lon).abs() <= 2, "{}", s.lon_image - lon);
}
