//! The bridge as an autopilot sees it: MAVLink frames built with `mavio` in, the bridge's
//! bytes parsed back, the gimbal's command queue (the core's sans-IO `Link`) read out.

mod common;
use common::*;

use idu_gimbal::link::SerialLink;
use idu_gimbal::link::{Aim, Config, Link, Yaw};
use idu_gimbal::wire::control::{Command, GimbalCommand, Heading, Pitch, Rate};
use idu_gimbal::wire::ids;
use idu_gimbal::wire::postback::Postback;
use idu_gimbal::wire::vehicle::{Altitude, VehicleFrame};
use idu_gimbal_mavlink::attitude::YawPitch;
use idu_gimbal_mavlink::camera::CameraConfig;
use idu_gimbal_mavlink::{Bridge, BridgeConfig, BridgeConfigError, Period, AUTOPILOT_SILENCE_MS};
use mavio::dialects::common::enums::{
    GimbalDeviceErrorFlags, GimbalDeviceFlags, MavAutopilot, MavCmd, MavResult, MavType,
};
use mavio::dialects::common::messages::{
    AutopilotStateForGimbalDevice, CommandAck, CommandLong, GimbalDeviceAttitudeStatus,
    GimbalDeviceInformation, GimbalDeviceSetAttitude, GlobalPositionInt, Heartbeat,
};

fn fresh() -> Firmware {
    Firmware::new(Link::new(Config::default()), BridgeConfig::default())
}

/// A bridge that has heard the autopilot's heartbeat (so its system id is the autopilot's),
/// its output so far drained.
fn bridge() -> Firmware {
    let mut b = fresh();
    b.receive_all(&frame(AP, 0, &heartbeat()), t(0));
    let _ = sent(&mut b);
    b
}

#[test]
fn heartbeats_at_1_hz_with_the_autopilots_system_id() {
    let mut b = fresh();
    let mut frames = Vec::new();
    for ms in 0..3_000 {
        if ms == 1_500 {
            b.receive_all(&frame(AP, 0, &heartbeat()), t(ms));
        }
        b.poll(t(ms));
        frames.extend(sent(&mut b));
    }
    let hbs: Vec<(u8, u8, Heartbeat)> = frames
        .iter()
        .filter(|f| f.message_id() == 0)
        .map(|f| (f.system_id(), f.component_id(), f.decode_message().unwrap()))
        .collect();
    assert_eq!(hbs.len(), 3);
    assert!(hbs.iter().all(|h| h.1 == 154
        && h.2.type_ == MavType::Gimbal
        && h.2.autopilot == MavAutopilot::Invalid));
    // System 1 until the autopilot's heartbeat, then the autopilot's.
    assert_eq!(hbs.iter().map(|h| h.0).collect::<Vec<_>>(), [1, 1, 7]);
}

/// A configuration that would leave the bridge unaddressable is refused with what is wrong;
/// every other id is taken, the extremes included.
#[test]
fn a_zero_id_or_one_id_for_both_components_is_refused() {
    let with = |system_id: Option<u8>, gimbal: u8, camera: Option<u8>| BridgeConfig {
        system_id,
        gimbal_component: gimbal,
        camera: camera.map(|component| {
            let mut c = CameraConfig::new("rtsp://192.168.144.108:554/stream=0").unwrap();
            c.component = component;
            c
        }),
        ..BridgeConfig::default()
    };
    let refused = |config: BridgeConfig| config.check().err();
    assert_eq!(
        refused(with(Some(0), 154, Some(100))),
        Some(BridgeConfigError::SystemIdZero)
    );
    assert_eq!(
        refused(with(None, 0, None)),
        Some(BridgeConfigError::GimbalComponentZero)
    );
    assert_eq!(
        refused(with(None, 154, Some(0))),
        Some(BridgeConfigError::CameraComponentZero)
    );
    for id in [1, 100, 154, 255] {
        assert_eq!(
            refused(with(None, id, Some(id))),
            Some(BridgeConfigError::CameraComponentIsGimbals(id))
        );
    }
    for (system_id, gimbal, camera) in [
        (None, 154, None),
        (Some(1), 1, Some(255)),
        (Some(255), 255, Some(1)),
        (Some(7), 154, Some(155)),
    ] {
        let config = with(system_id, gimbal, camera);
        let checked = config.clone().check().unwrap();
        // Checked, not changed.
        assert_eq!(checked.get(), &config);
        let bridge = Bridge::new(checked);
        assert_eq!(bridge.system_id(), system_id.unwrap_or(1));
        assert_eq!(bridge.config(), &config);
    }
    // What each says: what is wrong and what is valid.
    assert_eq!(
        BridgeConfigError::SystemIdZero.to_string(),
        "system id 0 is the broadcast system: valid 1 to 255"
    );
    assert_eq!(
        BridgeConfigError::CameraComponentIsGimbals(154).to_string(),
        "camera component 154 is the gimbal device's: valid 1 to 255, other than 154"
    );
}

/// The times (ms after `start`, each poll 1 ms apart) at which `M` was sent in `polls`
/// polls.
fn sent_at<M>(b: &mut Firmware, start: u32, polls: u32) -> Vec<u32>
where
    M: mavio::mavspec::rust::spec::MessageSpecStatic
        + for<'a> TryFrom<&'a mavio::protocol::Payload, Error = mavio::error::SpecError>,
{
    (0..polls)
        .filter(|&i| {
            b.poll(t(start.wrapping_add(i)));
            !of::<M>(&sent(b)).is_empty()
        })
        .collect()
}

#[test]
fn configured_periods_hold_at_their_extremes_and_across_the_clocks_wrap() {
    let with = |heartbeat: Period, attitude_status: Option<Period>| {
        Firmware::new(
            Link::new(Config::default()),
            BridgeConfig {
                heartbeat,
                attitude_status,
                ..BridgeConfig::default()
            },
        )
    };
    let minute = Period::from_millis(Period::MAX_MS).unwrap();
    let ms = Period::MAX_MS;
    // The longest periods, from 70 s before the clock wraps: each message at once, then
    // exactly one period later, past the wrap.
    let start = 70_000u32.wrapping_neg();
    let mut b = with(minute, None);
    assert_eq!(
        sent_at::<Heartbeat>(&mut b, start, 125_000),
        [0, ms, 2 * ms]
    );
    let mut b = with(minute, Some(minute));
    assert_eq!(
        sent_at::<GimbalDeviceAttitudeStatus>(&mut b, start, 125_000),
        [0, ms, 2 * ms]
    );
    // The shortest: every poll; and a status not configured is not sent.
    let mut b = with(Period::from_millis(1).unwrap(), None);
    assert_eq!(sent_at::<Heartbeat>(&mut b, start, 5), [0, 1, 2, 3, 4]);
    assert!(sent_at::<GimbalDeviceAttitudeStatus>(&mut b, start, 2_000).is_empty());
}

/// The system id of the next gimbal heartbeat after `ms`.
fn system_id_after(b: &mut Firmware, ms: u32) -> u8 {
    for ms in ms..ms + 1_100 {
        b.poll(t(ms));
        if let Some(f) = sent(b).iter().find(|f| f.message_id() == 0) {
            return f.system_id();
        }
    }
    panic!("no heartbeat");
}

#[test]
fn the_first_autopilot_is_kept_until_it_falls_silent() {
    let mut b = fresh();
    let hb_at = |b: &mut Firmware, from: (u8, u8), ms: u32| {
        b.receive_all(&frame(from, 0, &heartbeat()), t(ms));
    };
    assert_eq!(b.system_id(), 1);
    hb_at(&mut b, AP, 0);
    assert_eq!(b.system_id(), AP.0);
    assert_eq!(system_id_after(&mut b, 0), AP.0);
    // Another autopilot, a forged heartbeat, system 0, or a component-1 heartbeat that says
    // it is no autopilot: the one followed is heard, so none moves the system id.
    hb_at(&mut b, (42, 1), 1_500);
    hb_at(&mut b, (0, 1), 1_600);
    let invalid = Heartbeat {
        autopilot: MavAutopilot::Invalid,
        ..heartbeat()
    };
    b.receive_all(&frame((43, 1), 0, &invalid), t(1_700));
    assert_eq!(system_id_after(&mut b, 1_800), AP.0);
    assert_eq!(b.stats().other_autopilots, 3);
    // The autopilot heard every second: system 42 keeps being ignored.
    for s in 2..10 {
        hb_at(&mut b, AP, s * 1_000);
        hb_at(&mut b, (42, 1), s * 1_000 + 500);
    }
    assert_eq!(system_id_after(&mut b, 10_000), AP.0);
    assert_eq!(b.stats().other_autopilots, 3 + 8);
    // Silent for AUTOPILOT_SILENCE_MS (last heard at 9 s): then another autopilot is taken.
    hb_at(&mut b, (42, 1), 9_000 + AUTOPILOT_SILENCE_MS - 1);
    assert_eq!(system_id_after(&mut b, 14_000), AP.0);
    hb_at(&mut b, (42, 1), 9_000 + AUTOPILOT_SILENCE_MS);
    assert_eq!(system_id_after(&mut b, 15_000), 42);
}

#[test]
fn no_autopilot_yet_and_a_heartbeat_of_system_0_or_of_no_autopilot_takes_nothing() {
    // Heard first, with no autopilot to keep: neither is one (system 0 is the broadcast
    // address; MAV_AUTOPILOT_INVALID says the sender is no autopilot).
    let mut b = fresh();
    b.receive_all(&frame((0, 1), 0, &heartbeat()), t(0));
    assert_eq!(system_id_after(&mut b, 0), 1);
    let invalid = Heartbeat {
        autopilot: MavAutopilot::Invalid,
        ..heartbeat()
    };
    b.receive_all(&frame((43, 1), 1, &invalid), t(1_200));
    assert_eq!(system_id_after(&mut b, 1_200), 1);
    assert_eq!(b.stats().other_autopilots, 2);
    // The real one is still taken at once.
    b.receive_all(&frame(AP, 0, &heartbeat()), t(2_400));
    assert_eq!(system_id_after(&mut b, 2_400), AP.0);
}

/// The quaternion (w, x, y, z) of the 3-2-1 rotation: yaw about z, then pitch about y, then
/// roll about x (common.xml's vehicle attitude), from the half angles' products.
fn quaternion_321(roll_deg: f32, pitch_deg: f32, yaw_deg: f32) -> [f32; 4] {
    let (sr, cr) = (roll_deg.to_radians() / 2.0).sin_cos();
    let (sp, cp) = (pitch_deg.to_radians() / 2.0).sin_cos();
    let (sy, cy) = (yaw_deg.to_radians() / 2.0).sin_cos();
    [
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    ]
}

#[test]
fn the_vehicles_roll_pitch_and_heading_from_autopilot_state_reach_the_gimbal() {
    let mut b = fresh();
    b.receive_all(&frame(AP, 0, &heartbeat()), t(0));
    // Whole degrees: f32 trigonometry is good to about 1e-3° here (1e-5° near ±85° pitch
    // where asin's slope is 11), far from the 0.005° at which the wire's 0.01° rounds, so
    // the centidegrees are exact.
    for (i, (roll, pitch, yaw)) in [
        (10, -20, 30),
        (-35, 15, -120),
        (170, 5, 179),
        (-170, -5, -179),
        (0, 80, 45),
        (-5, -85, -170),
        (25, 0, 0),
        (0, 0, 90),
    ]
    .into_iter()
    .enumerate()
    {
        let state = AutopilotStateForGimbalDevice {
            target_system: AP.0,
            target_component: 154,
            q: quaternion_321(roll as f32, pitch as f32, yaw as f32),
            angular_velocity_z: f32::NAN,
            ..Default::default()
        };
        let ms = 100 * (i as u32 + 1);
        b.receive_all(&frame(AP, i as u8, &state), t(ms));
        let a = b.link.attitude().expect("an attitude");
        assert_eq!(
            (a.roll_centideg(), a.pitch_centideg(), a.heading_centideg()),
            (roll * 100, pitch * 100, yaw * 100),
            "roll {roll}, pitch {pitch}, yaw {yaw}"
        );
    }
}

/// A vehicle facing south: the wire's heading is in [−180°, 180°), so 180° is sent as
/// −180.00°, and so is any yaw that rounds to it (the wire's 0.01°), not one step short.
#[test]
fn a_vehicle_facing_south_is_sent_at_minus_180_degrees() {
    let mut b = fresh();
    b.receive_all(&frame(AP, 0, &heartbeat()), t(0));
    // [0, 0, 0, 1]: yaw exactly π. 179.996°: f32 trigonometry is good to about 1e-3° here,
    // so it rounds to 180.00° on the wire, as 179.994° (kept) rounds to 179.99°.
    for (i, (q, heading)) in [
        ([0.0, 0.0, 0.0, 1.0], -18000),
        (quaternion_321(0.0, 0.0, 179.996), -18000),
        (quaternion_321(0.0, 0.0, 179.994), 17999),
        (quaternion_321(0.0, 0.0, -179.996), -18000),
    ]
    .into_iter()
    .enumerate()
    {
        let state = AutopilotStateForGimbalDevice {
            target_system: AP.0,
            target_component: 154,
            q,
            angular_velocity_z: f32::NAN,
            ..Default::default()
        };
        b.receive_all(&frame(AP, i as u8, &state), t(100 * (i as u32 + 1)));
        let a = b.link.attitude().expect("an attitude");
        assert_eq!(a.heading_centideg(), heading, "{q:?}");
    }
}

/// A vehicle update the bridge cannot use is counted, never dropped without a word: a
/// quaternion with a NaN, one whose components overflow the arithmetic (1e20 each: their
/// products are infinite, and ∞ − ∞ is NaN), a latitude beyond ±90°. What the link held
/// stays as it was; the position's altitude is still passed on.
#[test]
fn vehicle_updates_the_bridge_cannot_use_are_counted() {
    let mut b = fresh();
    b.receive_all(&frame(AP, 0, &heartbeat()), t(0));
    b.receive_all(&frame(AP, 1, &autopilot_state(30.0)), t(10));
    let held = b.link.attitude().expect("an attitude");
    let before = b.stats();
    assert_eq!(
        (before.vehicle_updates, before.refused_vehicle_updates),
        (1, 0)
    );
    for (i, q) in [[f32::NAN, 0.0, 0.0, 1.0], [1e20; 4]]
        .into_iter()
        .enumerate()
    {
        let mut state = autopilot_state(90.0);
        state.q = q;
        b.receive_all(&frame(AP, 2 + i as u8, &state), t(20));
        assert_eq!(b.link.attitude(), Some(held), "{q:?}");
        // Nor is its yaw taken as the vehicle's (1e20 each gives a finite 135°): the
        // status's delta_yaw is still 30° (f32 quaternion to yaw and back: within 1e-3°).
        let _ = sent(&mut b);
        let c = command((0, 154), MavCmd::RequestMessage, 285.0, 0.0);
        b.receive_all(&frame(GCS, i as u8, &c), t(20));
        let status = of::<GimbalDeviceAttitudeStatus>(&sent(&mut b)).remove(0);
        let d = status.delta_yaw.to_degrees();
        assert!((d - 30.0).abs() < 1e-3, "{q:?}: {d}");
    }
    b.receive_all(
        &frame(AP, 4, &position(900_000_001, 85_455_940, 488_123, 0)),
        t(30),
    );
    // What the link pushes to the gimbal: the attitude held and the altitude, no GPS.
    b.link.poll(t(30));
    assert_eq!(
        queued_vehicle_frames(&mut b.link),
        [
            VehicleFrame::Attitude(held),
            VehicleFrame::Altitude(Altitude::from_cm(48_812))
        ]
    );
    let s = b.stats();
    assert_eq!((s.vehicle_updates, s.refused_vehicle_updates), (1, 3));
}

/// `GLOBAL_POSITION_INT` is broadcast: only the followed autopilot's moves the GPS the link
/// pushes. Another vehicle's on a shared link, and any before an autopilot is heard, are
/// counted as not for us.
#[test]
fn only_the_followed_autopilots_position_is_taken() {
    let gps_pushed = |b: &mut Firmware, ms: u32| {
        b.link.poll(t(ms));
        queued_vehicle_frames(&mut b.link)
            .into_iter()
            .filter_map(|f| match f {
                VehicleFrame::Gps(g) => Some((g.lat_e7(), g.lon_e7())),
                _ => None,
            })
            .collect::<Vec<_>>()
    };
    let mut b = fresh();
    b.receive_all(&frame(AP, 0, &position(10, 20, 0, 0)), t(0));
    assert_eq!(b.stats().not_for_us, 1, "before any heartbeat");
    assert!(gps_pushed(&mut b, 0).is_empty());
    b.receive_all(&frame(AP, 1, &heartbeat()), t(10));
    b.receive_all(&frame(AP, 2, &position(30, 40, 0, 0)), t(20));
    assert_eq!(gps_pushed(&mut b, 20), [(30, 40)]);
    // Another vehicle's autopilot, and another component of this one.
    b.receive_all(&frame((AP.0 + 1, 1), 0, &position(50, 60, 0, 0)), t(30));
    b.receive_all(&frame((AP.0, 2), 0, &position(70, 80, 0, 0)), t(30));
    assert_eq!(b.stats().not_for_us, 3);
    // Pushed again at its period (1 s): still the followed autopilot's.
    assert_eq!(gps_pushed(&mut b, 1_020), [(30, 40)]);
}

#[test]
fn a_configured_system_id_follows_only_its_own_autopilot() {
    let mut b = Firmware::new(
        Link::new(Config::default()),
        BridgeConfig {
            system_id: Some(9),
            ..BridgeConfig::default()
        },
    );
    b.receive_all(&frame(AP, 0, &heartbeat()), t(0));
    assert_eq!(system_id_after(&mut b, 0), 9);
    assert_eq!(b.stats().other_autopilots, 1);
    // System 9's autopilot is followed: its streams asked of it.
    b.receive_all(&frame((9, 1), 0, &heartbeat()), t(2_000));
    let asks = (2_000..3_000)
        .flat_map(|ms| {
            b.poll(t(ms));
            of::<CommandLong>(&sent(&mut b))
        })
        .filter(|c| c.command == MavCmd::SetMessageInterval)
        .map(|c| c.target_system)
        .collect::<Vec<_>>();
    assert!(!asks.is_empty() && asks.iter().all(|&s| s == 9), "{asks:?}");
}

#[test]
fn information_on_request_broadcast_or_addressed_and_an_ack_for_every_command() {
    let mut b = bridge();
    b.receive_all(&frame(AP, 0, &heartbeat()), t(0));
    let _ = sent(&mut b);
    // PX4 asks the broadcast component; ArduPilot the gimbal's.
    for (i, target) in [(AP.0, 0), (AP.0, 154), (0, 0)].into_iter().enumerate() {
        b.receive_all(
            &frame(
                GCS,
                i as u8,
                &command(target, MavCmd::RequestMessage, 283.0, 0.0),
            ),
            t(10),
        );
        let frames = sent(&mut b);
        let acks: Vec<CommandAck> = of(&frames);
        assert_eq!(acks.len(), 1, "{target:?}");
        assert_eq!(
            (acks[0].command, acks[0].result),
            (MavCmd::RequestMessage, MavResult::Accepted)
        );
        assert_eq!((acks[0].target_system, acks[0].target_component), GCS);
        let info: Vec<GimbalDeviceInformation> = of(&frames);
        assert_eq!(info.len(), 1);
        let i = &info[0];
        assert_eq!(&i.vendor_name[..4], b"IDU\0");
        assert!((i.pitch_min - (-100f32).to_radians()).abs() < 1e-6);
        assert!((i.pitch_max - 60f32.to_radians()).abs() < 1e-6);
        assert!((i.yaw_min - (-170f32).to_radians()).abs() < 1e-6);
        assert!((i.yaw_max - 170f32.to_radians()).abs() < 1e-6);
        assert!(i.roll_min.is_nan() && i.roll_max.is_nan());
        // common.xml's GIMBAL_DEVICE_CAP_FLAGS: RETRACT 1, NEUTRAL 2, PITCH_AXIS 32,
        // PITCH_LOCK 128, YAW_AXIS 256, YAW_FOLLOW 512, YAW_LOCK 1024,
        // SUPPORTS_YAW_IN_EARTH_FRAME 4096; no roll axis, no infinite yaw, no RC inputs.
        assert_eq!(
            i.cap_flags.bits(),
            1 + 2 + 32 + 128 + 256 + 512 + 1024 + 4096
        );
        assert_eq!(i.gimbal_device_id, 0);
    }
    // Another component's request: not ours, no answer.
    b.receive_all(
        &frame(
            GCS,
            9,
            &command((AP.0, 100), MavCmd::RequestMessage, 283.0, 0.0),
        ),
        t(20),
    );
    assert!(sent(&mut b).is_empty());
    // A command the gimbal does not do, addressed to it: UNSUPPORTED, never silence.
    b.receive_all(
        &frame(GCS, 10, &command((AP.0, 154), MavCmd::DoSetMode, 1.0, 0.0)),
        t(30),
    );
    let acks: Vec<CommandAck> = of(&sent(&mut b));
    assert_eq!(acks.len(), 1);
    assert_eq!(acks[0].result, MavResult::Unsupported);
    // The same, broadcast: another component may own it; the gimbal stays quiet.
    b.receive_all(
        &frame(GCS, 11, &command((AP.0, 0), MavCmd::DoSetMode, 1.0, 0.0)),
        t(40),
    );
    assert!(of::<CommandAck>(&sent(&mut b)).is_empty());
    assert_eq!(b.stats().acks, 4);
}

#[test]
fn the_attitude_status_interval_is_honoured() {
    let mut b = bridge();
    let status_times = |b: &mut Firmware, from: u32, to: u32| {
        let mut n = 0;
        for ms in from..to {
            b.poll(t(ms));
            n += of::<GimbalDeviceAttitudeStatus>(&sent(b)).len();
        }
        n
    };
    assert_eq!(status_times(&mut b, 0, 1_000), 10);
    b.receive_all(
        &frame(
            GCS,
            0,
            &command((0, 154), MavCmd::SetMessageInterval, 285.0, 250_000.0),
        ),
        t(1_000),
    );
    let acks: Vec<CommandAck> = of(&sent(&mut b));
    assert_eq!(acks[0].result, MavResult::Accepted);
    assert_eq!(status_times(&mut b, 1_000, 2_000), 4);
    // −1 stops it; 0 restores the default; nonsense is denied.
    b.receive_all(
        &frame(
            GCS,
            1,
            &command((0, 154), MavCmd::SetMessageInterval, 285.0, -1.0),
        ),
        t(2_000),
    );
    assert_eq!(status_times(&mut b, 2_000, 3_000), 0);
    b.receive_all(
        &frame(
            GCS,
            2,
            &command((0, 154), MavCmd::SetMessageInterval, 285.0, 0.0),
        ),
        t(3_000),
    );
    assert_eq!(status_times(&mut b, 3_000, 4_000), 10);
    b.receive_all(
        &frame(
            GCS,
            3,
            &command((0, 154), MavCmd::SetMessageInterval, 285.0, 10.0),
        ),
        t(4_000),
    );
    assert_eq!(of::<CommandAck>(&sent(&mut b))[0].result, MavResult::Denied);
}

/// The postback's frames into the link, and the status the bridge sends next.
fn status_after(b: &mut Firmware, p: &Postback, ms: u32) -> GimbalDeviceAttitudeStatus {
    for data in p.to_can_frames() {
        b.link.receive(ids::POSTBACK, &data, t(ms));
    }
    let _ = sent(b);
    b.receive_all(
        &frame(
            GCS,
            0,
            &command((0, 154), MavCmd::RequestMessage, 285.0, 0.0),
        ),
        t(ms),
    );
    of::<GimbalDeviceAttitudeStatus>(&sent(b)).remove(0)
}

/// The status says the motor angle and the vehicle's heading now, whatever the postback's
/// age: QGroundControl and ArduPilot add the heading now to its yaw, and `delta_yaw` relates
/// the frames now. A yaw held in the earth frame has the motor turn back by what the vehicle
/// turned since the postback; one that follows the vehicle keeps its angle.
#[test]
fn the_status_gives_the_motor_angle_and_the_heading_now() {
    let p = Postback {
        motor_heading: 1_000,
        ..Postback::default()
    };
    let postback_at = |b: &mut Firmware, ms: u32| {
        for data in p.to_can_frames() {
            b.link.receive(ids::POSTBACK, &data, t(ms));
        }
    };
    // (the status's yaw from the nose, its delta_yaw), degrees.
    let status_at = |b: &mut Firmware, ms: u32| {
        let _ = sent(b);
        let c = command((0, 154), MavCmd::RequestMessage, 285.0, 0.0);
        b.receive_all(&frame(GCS, 0, &c), t(ms));
        let s = of::<GimbalDeviceAttitudeStatus>(&sent(b)).remove(0);
        let yaw = YawPitch::from_quaternion(s.q).unwrap().yaw_rad.to_degrees();
        (yaw, s.delta_yaw.to_degrees())
    };
    // f32 quaternion to yaw and back: well within 1e-3°.
    let close = |(yaw, delta): (f32, f32), e: (f32, f32)| {
        (yaw - e.0).abs() < 1e-3 && (delta - e.1).abs() < 1e-3
    };
    for earth in [false, true] {
        let mut b = bridge();
        b.receive_all(&frame(AP, 0, &autopilot_state(0.0)), t(90));
        if earth {
            let aim = Aim {
                yaw: Yaw::Earth(Heading::new(10.0).unwrap()),
                pitch: Pitch::LEVEL,
            };
            b.link.aim(aim, t(95)).unwrap();
        }
        postback_at(&mut b, 100);
        b.poll(t(100));
        assert!(close(status_at(&mut b, 110), (10.0, 0.0)), "{earth}");
        // The vehicle turns to 30° with no postback since: held in the earth frame, the
        // motor is 20° left of the nose now; following the vehicle, still 10° right.
        let motor = if earth { -20.0 } else { 10.0 };
        b.receive_all(&frame(AP, 1, &autopilot_state(30.0)), t(150));
        let s = status_at(&mut b, 160);
        assert!(close(s, (motor, 30.0)), "{earth}: {s:?}");
        // A postback at 200 (the motor again 10° right, the heading 30°), then a turn to
        // 60°: 20° further back, or where it was.
        postback_at(&mut b, 200);
        b.poll(t(200));
        b.receive_all(&frame(AP, 2, &autopilot_state(60.0)), t(205));
        let s = status_at(&mut b, 210);
        assert!(close(s, (motor, 60.0)), "{earth}: {s:?}");
        // A postback not yet noted (asked before the next poll): taken as of now.
        postback_at(&mut b, 300);
        b.receive_all(&frame(AP, 3, &autopilot_state(90.0)), t(300));
        assert!(close(status_at(&mut b, 300), (10.0, 90.0)), "{earth}");
    }
}

#[test]
fn the_status_is_in_the_vehicle_frame_with_the_vehicle_heading_as_delta_yaw() {
    let mut b = bridge();
    let p = Postback {
        pitch: -9500,
        heading: 27_000,
        motor_heading: 4_500,
        ..Postback::default()
    };
    // No vehicle attitude yet: the motor angle, and delta_yaw unknown (NaN).
    let s = status_after(&mut b, &p, 0);
    assert!(s.flags.contains(GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME));
    assert!(!s.flags.contains(GimbalDeviceFlags::YAW_IN_EARTH_FRAME));
    // By hand, yaw 45°, pitch −95°: w = cos22.5·cos(−47.5), x = −sin22.5·sin(−47.5),
    // y = cos22.5·sin(−47.5), z = sin22.5·cos(−47.5).
    let (c1, s1) = (0.923_879_5_f32, 0.382_683_43_f32);
    let (c2, s2) = (0.675_590_2_f32, -0.737_277_3_f32);
    let q = [c1 * c2, -s1 * s2, c1 * s2, s1 * c2];
    for (a, e) in s.q.iter().zip(q) {
        // f32 sin/cos of the exact angles: a few ulps (1e-6 is 8 ulps at 1.0).
        assert!((a - e).abs() < 1e-6, "{:?} vs {q:?}", s.q);
    }
    assert!(s.delta_yaw.is_nan() && s.delta_yaw_velocity.is_nan());
    assert!(s.failure_flags.is_empty());
    // The vehicle heads 225° (−135°) turning at 0.1 rad/s: attitude is pushed, the
    // gimbal's heading is now north-referenced, and the status stays in the vehicle
    // frame with the motor angle; delta_yaw is the vehicle's heading.
    let mut state = autopilot_state(225.0 - 360.0);
    state.angular_velocity_z = 0.1;
    b.receive_all(&frame(AP, 0, &state), t(50));
    b.link.poll(t(100));
    let s = status_after(&mut b, &p, 100);
    assert!(s.flags.contains(GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME));
    let a = YawPitch::from_quaternion(s.q).unwrap();
    assert!((a.yaw_rad.to_degrees() - 45.0).abs() < 1e-3, "{a:?}");
    assert!((s.delta_yaw.to_degrees() + 135.0).abs() < 1e-3);
    assert_eq!(s.delta_yaw_velocity, 0.1);
    // q_earth = q_delta_yaw ⊗ q_vehicle (common.xml): yaw 45° + (−135°) = −90°, the
    // postback's north-referenced heading 270°.
    let earth = YawPitch {
        yaw_rad: a.yaw_rad + s.delta_yaw,
        pitch_rad: a.pitch_rad,
    };
    assert!(
        (idu_gimbal_mavlink::attitude::wrap_pi(earth.yaw_rad).to_degrees() + 90.0).abs() < 1e-3
    );
    // The vehicle heading goes stale after 1 s without AUTOPILOT_STATE: NaN again.
    let s = status_after(&mut b, &p, 1_051);
    assert!(s.delta_yaw.is_nan());
    // The link times out after 1.5 s without postbacks: COMMS_ERROR for pre-arm checks.
    b.link.poll(t(3_000));
    b.poll(t(3_000));
    let s = &of::<GimbalDeviceAttitudeStatus>(&sent(&mut b))[0];
    assert!(s
        .failure_flags
        .contains(GimbalDeviceErrorFlags::COMMS_ERROR));
}

/// PX4 never sets `angular_velocity_z` (its AUTOPILOT_STATE_FOR_GIMBAL_DEVICE stream,
/// zero-initialised): MAVLink 2 drops the zero, and a rate read as 0 would leave an
/// earth-frame rate uncompensated and report a still vehicle. A state without the rate
/// has it from the last two yaws and their `time_boot_us`.
#[test]
fn a_state_without_a_yaw_rate_has_it_from_the_last_two_yaws() {
    let mut b = bridge();
    let p = Postback::default();
    let px4 = |yaw_deg: f32, us: u64| {
        let mut s = autopilot_state(yaw_deg);
        s.angular_velocity_z = 0.0;
        s.time_boot_us = us;
        s
    };
    // One state: no rate yet.
    b.receive_all(&frame(AP, 0, &px4(10.0, 1_000_000)), t(0));
    let s = status_after(&mut b, &p, 0);
    assert!(s.delta_yaw_velocity.is_nan(), "{}", s.delta_yaw_velocity);
    // 2° in 20 ms: 100°/s. f32 yaws from quaternions: within 1e-5 rad each, 1e-3 rad/s
    // over 20 ms.
    b.receive_all(&frame(AP, 1, &px4(12.0, 1_020_000)), t(20));
    let s = status_after(&mut b, &p, 20);
    assert!(
        (s.delta_yaw_velocity - 100f32.to_radians()).abs() < 1e-3,
        "{}",
        s.delta_yaw_velocity
    );
    // Across ±180°: −179° after 179° is 2° on, not 358° back.
    b.receive_all(&frame(AP, 2, &px4(179.0, 2_000_000)), t(1_000));
    b.receive_all(&frame(AP, 3, &px4(-179.0, 2_020_000)), t(1_020));
    let s = status_after(&mut b, &p, 1_020);
    assert!((s.delta_yaw_velocity - 100f32.to_radians()).abs() < 1e-3);
    // A rate sent is taken as sent.
    let mut sent_rate = px4(-178.0, 2_040_000);
    sent_rate.angular_velocity_z = 0.25;
    b.receive_all(&frame(AP, 4, &sent_rate), t(1_040));
    assert_eq!(status_after(&mut b, &p, 1_040).delta_yaw_velocity, 0.25);
    // Samples more than a second apart give none.
    b.receive_all(&frame(AP, 5, &px4(0.0, 5_000_000)), t(1_500));
    b.receive_all(&frame(AP, 6, &px4(1.0, 6_500_000)), t(1_600));
    assert!(status_after(&mut b, &p, 1_600).delta_yaw_velocity.is_nan());
}

#[test]
fn the_status_flags_say_what_the_device_holds_not_the_postbacks_mode() {
    use idu_gimbal::wire::postback::ControlMode;
    let mut b = bridge();
    b.receive_all(&frame(AP, 0, &autopilot_state(30.0)), t(0));
    // The gimbal reports lock after any angle command; what it holds is the setpoint's.
    let lock = Postback {
        mode: ControlMode::Lock,
        ..Postback::default()
    };
    let yaw_lock = |s: &GimbalDeviceAttitudeStatus| s.flags.contains(GimbalDeviceFlags::YAW_LOCK);
    assert!(
        !yaw_lock(&status_after(&mut b, &lock, 0)),
        "nothing held yet"
    );
    // Flags 0 (ArduPilot's body frame): the yaw follows the vehicle.
    b.receive_all(
        &frame(
            AP,
            1,
            &set_attitude(GimbalDeviceFlags::empty(), 10.0, -10.0),
        ),
        t(10),
    );
    let s = status_after(&mut b, &lock, 10);
    assert!(!yaw_lock(&s), "{:?}", s.flags);
    assert!(s.flags.contains(
        GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME
            | GimbalDeviceFlags::ROLL_LOCK
            | GimbalDeviceFlags::PITCH_LOCK
    ));
    // PX4's yaw lock (YAW_LOCK | YAW_IN_EARTH_FRAME): held in the earth frame.
    let earth = GimbalDeviceFlags::YAW_LOCK | GimbalDeviceFlags::YAW_IN_EARTH_FRAME;
    b.receive_all(&frame(AP, 2, &set_attitude(earth, 10.0, -10.0)), t(20));
    assert!(yaw_lock(&status_after(&mut b, &Postback::default(), 20)));
    // A vehicle-frame rate follows; an earth-frame one locks while it holds.
    let mut rate = set_attitude(GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME, 0.0, 0.0);
    rate.q = [f32::NAN; 4];
    rate.angular_velocity_y = 0.0;
    rate.angular_velocity_z = 0.1;
    b.receive_all(&frame(AP, 3, &rate), t(30));
    assert!(!yaw_lock(&status_after(&mut b, &lock, 30)));
    rate.flags = earth;
    b.receive_all(&frame(AP, 4, &autopilot_state(30.0)), t(40));
    b.receive_all(&frame(AP, 5, &rate), t(40));
    assert!(yaw_lock(&status_after(&mut b, &lock, 40)));
    // The rate stream stops: the core's dead-man ends the hold, nothing is held.
    b.link.poll(t(400));
    assert!(!yaw_lock(&status_after(&mut b, &lock, 400)));
    // Neutral: forward in the vehicle frame, NEUTRAL and no YAW_LOCK.
    b.receive_all(
        &frame(AP, 6, &set_attitude(GimbalDeviceFlags::NEUTRAL, 0.0, 0.0)),
        t(500),
    );
    let f = status_after(&mut b, &lock, 500).flags;
    assert!(f.contains(GimbalDeviceFlags::NEUTRAL) && !f.contains(GimbalDeviceFlags::RETRACT));
    assert!(!f.contains(GimbalDeviceFlags::YAW_LOCK));
    // ArduPilot's retract: NaN quaternion, zero rates, RETRACT.
    let mut retract = set_attitude(GimbalDeviceFlags::RETRACT, 0.0, 0.0);
    retract.q = [f32::NAN; 4];
    retract.angular_velocity_x = 0.0;
    retract.angular_velocity_y = 0.0;
    retract.angular_velocity_z = 0.0;
    b.receive_all(&frame(AP, 7, &retract), t(510));
    let f = status_after(&mut b, &lock, 510).flags;
    assert!(f.contains(GimbalDeviceFlags::RETRACT) && !f.contains(GimbalDeviceFlags::NEUTRAL));
    // An angle moves it: neither any more.
    b.receive_all(&frame(AP, 8, &set_attitude(earth, 10.0, -10.0)), t(520));
    let f = status_after(&mut b, &lock, 520).flags;
    assert!(!f.intersects(GimbalDeviceFlags::NEUTRAL | GimbalDeviceFlags::RETRACT));
}

#[test]
fn a_yaw_beyond_the_motors_travel_is_reported_at_the_yaw_limit() {
    let mut b = bridge();
    b.receive_all(&frame(AP, 0, &autopilot_state(0.0)), t(0));
    b.link.poll(t(0));
    let _ = queued(&mut b.link);
    let limit = |s: &GimbalDeviceAttitudeStatus| {
        s.failure_flags
            .contains(GimbalDeviceErrorFlags::AT_YAW_LIMIT)
    };
    let earth = GimbalDeviceFlags::YAW_IN_EARTH_FRAME;
    // Earth 100 with the vehicle at 0: the motor at 100, within its ±170.
    b.receive_all(&frame(AP, 1, &set_attitude(earth, 100.0, 0.0)), t(10));
    assert!(!limit(&status_after(&mut b, &Postback::default(), 10)));
    // Earth -175 (185): beyond.
    b.receive_all(&frame(AP, 2, &set_attitude(earth, -175.0, 0.0)), t(20));
    b.link.poll(t(20));
    assert!(limit(&status_after(&mut b, &Postback::default(), 20)));
    assert_eq!(b.stats().refused_setpoints, 0, "followed as far as it goes");
}

#[test]
fn angle_setpoints_become_heading_and_pitch_in_the_gimbals_reference() {
    // North-referenced (attitude pushed, vehicle heading 45°).
    let mut b = bridge();
    b.receive_all(&frame(AP, 0, &autopilot_state(45.0)), t(0));
    b.link.poll(t(0));
    let _ = queued(&mut b.link);
    let cases = [
        // (flags, yaw, pitch) -> heading commanded
        (GimbalDeviceFlags::YAW_IN_EARTH_FRAME, 90.0, -30.0, 900),
        (GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME, 30.0, -30.0, 750),
        // Neither flag: YAW_LOCK means earth, none means vehicle (gimbal v2).
        (GimbalDeviceFlags::YAW_LOCK, -90.0, -30.0, 2700),
        (GimbalDeviceFlags::empty(), -60.0, -30.0, 3450),
    ];
    for (i, (flags, yaw, pitch, heading)) in cases.into_iter().enumerate() {
        // Alternate pitch so that the dead-band never hides the pitch command.
        let pitch = pitch - i as f32;
        b.receive_all(&frame(AP, i as u8, &set_attitude(flags, yaw, pitch)), t(10));
        let q = queued(&mut b.link);
        assert_eq!(q.len(), 2, "{flags:?}: {q:?}");
        match (q[0], q[1]) {
            (GimbalCommand::Heading(h), GimbalCommand::Pitch(p)) => {
                assert_eq!(h.deci(), heading, "{flags:?}");
                assert_eq!(p.deci(), (pitch * 10.0).round() as i16);
            }
            other => panic!("{other:?}"),
        }
    }
    // Nose-referenced (serial link: no attitude reaches the gimbal), vehicle heading 45°.
    let mut s = Firmware::new(
        SerialLink::<8>::new(Config::default()),
        BridgeConfig::default(),
    );
    s.receive_all(&frame(AP, 0, &heartbeat()), t(0));
    s.receive_all(&frame(AP, 0, &autopilot_state(45.0)), t(0));
    s.receive_all(
        &frame(
            AP,
            1,
            &set_attitude(GimbalDeviceFlags::YAW_IN_EARTH_FRAME, 90.0, -100.0),
        ),
        t(10),
    );
    let mut commands = Vec::new();
    let mut stream = idu_gimbal::port::SerialStream::new();
    while !stream.transmit_bytes(&mut s.link).is_empty() {
        let bytes = stream.transmit_bytes(&mut s.link).to_vec();
        stream.transmit_written(&mut s.link, bytes.len());
        let mut p = idu_gimbal::wire::serial::StreamParser::new();
        for item in p.feed(&bytes) {
            if let idu_gimbal::wire::serial::StreamItem::Control(d) = item {
                commands.push(Command::decode(&d).unwrap());
            }
        }
    }
    assert_eq!(
        commands,
        [
            Command::Gimbal(GimbalCommand::Heading(
                idu_gimbal::wire::control::Heading::from_deci(450).unwrap()
            )),
            Command::Gimbal(GimbalCommand::Pitch(
                idu_gimbal::wire::control::Pitch::from_deci(-1000).unwrap()
            )),
        ]
    );
}

#[test]
fn setpoints_within_the_dead_band_are_not_re_sent() {
    let mut b = bridge();
    let earth = GimbalDeviceFlags::YAW_LOCK;
    // The autopilot's state at 50 Hz, as autopilots send it, keeps attitude pushed.
    let at = |b: &mut Firmware, ms: u32, set: Option<GimbalDeviceSetAttitude>| {
        b.receive_all(&frame(AP, 0, &autopilot_state(0.0)), t(ms));
        if let Some(set) = set {
            b.receive_all(&frame(AP, 1, &set), t(ms));
        }
        b.link.poll(t(ms));
        queued(&mut b.link)
    };
    let angles = |q: Vec<GimbalCommand>| -> Vec<GimbalCommand> {
        q.into_iter()
            .filter(|c| matches!(c, GimbalCommand::Heading(_) | GimbalCommand::Pitch(_)))
            .collect()
    };
    let _ = at(&mut b, 0, None);
    assert_eq!(
        angles(at(&mut b, 20, Some(set_attitude(earth, 10.0, -20.0)))).len(),
        2
    );
    // 20 Hz of the same setpoint, and one 0.15° off: nothing new (the link's dead-band,
    // 0.2°), the vehicle still and no postback: nothing for the closed loop either.
    for i in 0..20 {
        let q = angles(at(
            &mut b,
            40 + 50 * i,
            Some(set_attitude(earth, 10.0, -20.0)),
        ));
        assert!(q.is_empty(), "{q:?}");
    }
    let q = angles(at(&mut b, 1_100, Some(set_attitude(earth, 10.15, -20.15))));
    assert!(q.is_empty(), "{q:?}");
    // 0.5° in pitch only: the aim again, both axes.
    let q = angles(at(&mut b, 1_150, Some(set_attitude(earth, 10.0, -20.5))));
    assert!(
        matches!(q[..], [GimbalCommand::Heading(h), GimbalCommand::Pitch(p)] if h.deci() == 100 && p.deci() == -205),
        "{q:?}"
    );
    assert_eq!(b.stats().refused_setpoints, 0);
    assert_eq!(b.stats().angle_setpoints, 23);
}

/// Without a fresh vehicle heading, a setpoint whose yaw frame differs from the gimbal's
/// reference cannot be converted: refused and counted, not guessed.
#[test]
fn a_yaw_frame_needing_a_stale_vehicle_heading_is_refused() {
    let mut b = bridge();
    b.receive_all(&frame(AP, 0, &autopilot_state(30.0)), t(0));
    b.link.poll(t(0));
    let _ = queued(&mut b.link);
    // 1.2 s later the vehicle state is stale: the gimbal is nose-referenced, and an
    // earth-frame yaw would need the vehicle heading.
    b.link.poll(t(1_200));
    b.receive_all(
        &frame(
            AP,
            1,
            &set_attitude(GimbalDeviceFlags::YAW_IN_EARTH_FRAME, 90.0, -10.0),
        ),
        t(1_200),
    );
    assert!(queued(&mut b.link).is_empty());
    assert_eq!(b.stats().refused_setpoints, 1);
    // A vehicle-frame yaw needs none.
    b.receive_all(
        &frame(
            AP,
            2,
            &set_attitude(GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME, 20.0, -10.0),
        ),
        t(1_210),
    );
    let q = queued(&mut b.link);
    assert!(
        matches!(q[0], GimbalCommand::Heading(h) if h.deci() == 200),
        "{q:?}"
    );
}

#[test]
fn rate_setpoints_hold_and_stop_with_the_core_dead_man() {
    let mut b = bridge();
    // ArduPilot's body-frame rate: flags 0.
    let mut set = set_attitude(GimbalDeviceFlags::empty(), 0.0, 0.0);
    set.q = [f32::NAN; 4];
    set.angular_velocity_y = 5f32.to_radians();
    set.angular_velocity_z = (-10f32).to_radians();
    let rate = Rate::new(-10.0, 5.0).unwrap();
    let zero = Rate::new(0.0, 0.0).unwrap();
    let mut rates = Vec::new();
    for ms in 0..1_000u32 {
        if ms < 500 && ms % 50 == 0 {
            b.receive_all(&frame(AP, (ms / 50) as u8, &set), t(ms));
        }
        b.link.poll(t(ms));
        for c in queued(&mut b.link) {
            if let GimbalCommand::Rate(r) = c {
                rates.push((ms, r));
            }
        }
    }
    // Repeated every 50 ms while the setpoints came (to 450 ms), then the core's dead-man
    // (250 ms after the last, at 701 ms) sends one zero rate, and nothing after it.
    assert!(rates.iter().filter(|r| r.1 == rate).count() >= 10);
    let last = *rates.last().unwrap();
    assert_eq!(last.1, zero);
    assert!((700..=702).contains(&last.0), "{last:?}");
    assert_eq!(rates.iter().filter(|r| r.1 == zero).count(), 1);
    assert_eq!(b.stats().rate_setpoints, 10);
}

#[test]
fn neutral_holds_forward_and_retract_looks_down_once_each() {
    let mut b = bridge();
    b.receive_all(&frame(AP, 0, &autopilot_state(40.0)), t(0));
    b.link.poll(t(0));
    let _ = queued(&mut b.link);
    // The quaternion of a neutral setpoint is not followed, neither at the flag's edge
    // nor while the flag stays.
    for i in 0..3 {
        b.receive_all(
            &frame(
                AP,
                i,
                &set_attitude(GimbalDeviceFlags::NEUTRAL, 30.0, -20.0),
            ),
            t(u32::from(i)),
        );
    }
    // Forward and level in the vehicle frame: north-referenced, the vehicle's 40°.
    let q = queued(&mut b.link);
    assert!(
        matches!(q[..], [GimbalCommand::Heading(h), GimbalCommand::Pitch(p)] if h.deci() == 400 && p.deci() == 0),
        "{q:?}"
    );
    b.receive_all(
        &frame(AP, 5, &set_attitude(GimbalDeviceFlags::RETRACT, 0.0, 0.0)),
        t(10),
    );
    assert_eq!(queued(&mut b.link), [GimbalCommand::LookDown]);
}

/// RETRACT acts when the flag appears; one the gimbal's queue had no room for is tried
/// again with the next setpoint that still carries it, not lost while it stays set.
#[test]
fn a_retract_the_queue_had_no_room_for_goes_with_the_next_setpoint() {
    let mut b = bridge();
    while b.link.send(GimbalCommand::Recenter).is_ok() {}
    let retract = set_attitude(GimbalDeviceFlags::RETRACT, 0.0, 0.0);
    b.receive_all(&frame(AP, 0, &retract), t(0));
    assert_eq!(b.stats().queue_full, 1);
    let _ = queued(&mut b.link);
    b.receive_all(&frame(AP, 1, &retract), t(20));
    assert_eq!(queued(&mut b.link), [GimbalCommand::LookDown]);
    // Once acted on, not again while the flag stays.
    b.receive_all(&frame(AP, 2, &retract), t(40));
    assert_eq!(queued(&mut b.link), []);
}

/// common.xml: each angular velocity is "NaN to be ignored": a rate setpoint with one axis
/// NaN turns the other and holds that one; with both NaN it asks nothing, refused.
#[test]
fn a_rate_setpoint_ignores_an_axis_given_as_nan() {
    let mut b = bridge();
    let mut rate = set_attitude(GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME, 0.0, 0.0);
    rate.q = [f32::NAN; 4];
    rate.angular_velocity_y = f32::NAN;
    rate.angular_velocity_z = 0.2;
    let before = b.stats();
    b.receive_all(&frame(AP, 0, &rate), t(0));
    let after = b.stats();
    assert_eq!(after.rate_setpoints, before.rate_setpoints + 1);
    assert_eq!(after.refused_setpoints, before.refused_setpoints);
    assert!(b.link.is_rate_holding());
    rate.angular_velocity_z = f32::NAN;
    b.receive_all(&frame(AP, 1, &rate), t(10));
    assert_eq!(b.stats().refused_setpoints, after.refused_setpoints + 1);
}

/// The vehicle's state is the followed autopilot's only: PX4 sends it to every component
/// (target 0, 0), and another vehicle's on a shared link would move this one's horizon and
/// north.
#[test]
fn another_vehicle_s_state_is_not_taken() {
    let mut b = bridge();
    let before = b.stats();
    b.receive_all(&frame((AP.0 + 1, 1), 0, &autopilot_state(90.0)), t(0));
    let after = b.stats();
    assert_eq!(after.vehicle_updates, before.vehicle_updates);
    assert_eq!(after.not_for_us, before.not_for_us + 1);
    b.receive_all(&frame(AP, 0, &autopilot_state(90.0)), t(10));
    assert_eq!(b.stats().vehicle_updates, after.vehicle_updates + 1);
}

#[test]
fn a_rolled_setpoint_is_refused() {
    let mut b = bridge();
    let mut rolled = set_attitude(GimbalDeviceFlags::empty(), 0.0, 0.0);
    // 10° of roll about the x axis, [w, x, y, z]: the gimbal has no roll.
    let half = 5f32.to_radians();
    rolled.q = [half.cos(), half.sin(), 0.0, 0.0];
    let before = b.stats();
    b.receive_all(&frame(AP, 0, &rolled), t(0));
    assert_eq!(b.stats().refused_setpoints, before.refused_setpoints + 1);
    assert_eq!(b.stats().angle_setpoints, before.angle_setpoints);
    assert!(queued(&mut b.link).is_empty());
}

#[test]
fn streams_are_asked_of_the_autopilot_until_they_come() {
    let mut b = fresh();
    let asks = |b: &mut Firmware, from: u32, to: u32| {
        let mut n = Vec::new();
        for ms in from..to {
            b.poll(t(ms));
            for c in of::<CommandLong>(&sent(b)) {
                assert_eq!(
                    (c.target_system, c.target_component, c.command),
                    (AP.0, AP.1, MavCmd::SetMessageInterval)
                );
                n.push((ms, c.param1 as u32, c.param2 as u32));
            }
        }
        n
    };
    assert!(asks(&mut b, 0, 100).is_empty(), "no autopilot yet");
    let px4 = Heartbeat {
        autopilot: MavAutopilot::Px4,
        ..heartbeat()
    };
    b.receive_all(&frame(AP, 0, &px4), t(100));
    // At once: the autopilot state at 20 Hz (PX4 streams it only in mode Gimbal), the
    // position at 5 Hz, and the setpoints at 20 Hz (once: PX4's Normal mode sends 5 Hz).
    // Then again after 5 s for the two that did not come.
    let a = asks(&mut b, 100, 6_000);
    assert_eq!(
        a,
        [
            (100, 286, 50_000),
            (100, 33, 200_000),
            (100, 284, 50_000),
            (5_100, 286, 50_000),
            (5_100, 33, 200_000)
        ]
    );
    let pos = GlobalPositionInt {
        time_boot_ms: 0,
        lat: 473_977_420,
        lon: 85_455_940,
        alt: 488_123,
        relative_alt: 0,
        vx: 0,
        vy: 0,
        vz: 0,
        hdg: 0,
    };
    b.receive_all(&frame(AP, 1, &pos), t(6_000));
    b.receive_all(&frame(AP, 2, &autopilot_state(10.0)), t(6_000));
    // Both keep coming: nothing asked.
    for s in 0..10u32 {
        let ms = 6_000 + s * 1_000;
        b.receive_all(&frame(AP, 3, &pos), t(ms));
        b.receive_all(&frame(AP, 4, &autopilot_state(10.0)), t(ms));
        assert!(asks(&mut b, ms, ms + 1_000).is_empty());
    }
    // The autopilot state stops (a rebooted autopilot forgets the intervals): asked again
    // 5 s after it was last heard (at 15 s), and every 5 s while it stays away, and the
    // setpoints with it (PX4 back at its 5 Hz).
    for s in 0..10u32 {
        let ms = 16_000 + s * 1_000;
        b.receive_all(&frame(AP, 5, &pos), t(ms));
        let a = asks(&mut b, ms, ms + 1_000);
        let expect: &[(u32, u32, u32)] = match ms {
            20_000 => &[(20_000, 286, 50_000), (20_000, 284, 50_000)],
            25_000 => &[(25_000, 286, 50_000), (25_000, 284, 50_000)],
            _ => &[],
        };
        assert_eq!(a, expect, "at {ms}");
    }
    // Back: nothing is asked again.
    for s in 0..10u32 {
        let ms = 26_000 + s * 1_000;
        b.receive_all(&frame(AP, 6, &pos), t(ms));
        b.receive_all(&frame(AP, 7, &autopilot_state(10.0)), t(ms));
        assert!(asks(&mut b, ms, ms + 1_000).is_empty(), "at {ms}");
    }
    // The core now holds and pushes the position, as the autopilot sent it.
    b.link.poll(t(35_200));
    let frames = queued_vehicle_frames(&mut b.link);
    assert!(
        frames.iter().any(|f| matches!(
            f,
            VehicleFrame::Gps(g) if (g.lat_e7(), g.lon_e7()) == (473_977_420, 85_455_940)
        )),
        "{frames:?}"
    );
}

#[test]
fn the_setpoints_are_not_asked_of_ardupilot() {
    // ArduPilot sends its setpoints at 50 Hz unasked; asked, it refuses and tells the
    // ground station. The other two streams are asked as of any autopilot.
    let mut b = fresh();
    b.receive_all(&frame(AP, 0, &heartbeat()), t(100));
    let mut asked = Vec::new();
    for ms in 100..6_000 {
        b.poll(t(ms));
        asked.extend(
            of::<CommandLong>(&sent(&mut b))
                .iter()
                .map(|c| c.param1 as u32),
        );
    }
    assert_eq!(asked, [286, 33, 286, 33]);
}

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
fn an_angle_with_rates_beside_it_is_followed_as_an_angle() {
    // MAVSDK's gimbal_device_tester and PX4's pass-through send both.
    let mut b = bridge();
    let mut set = set_attitude(GimbalDeviceFlags::empty(), 30.0, -20.0);
    set.angular_velocity_y = 0.2;
    set.angular_velocity_z = 0.0;
    b.receive_all(&frame(AP, 0, &set), t(10));
    let q = queued(&mut b.link);
    assert_eq!(q.len(), 2, "{q:?}");
    assert!(matches!(q[0], GimbalCommand::Heading(h) if h.deci() == 300));
    assert!(matches!(q[1], GimbalCommand::Pitch(p) if p.deci() == -200));
    assert_eq!(b.stats().rate_setpoints, 0);
}

#[test]
fn an_earth_frame_yaw_rate_becomes_a_motor_rate_or_is_refused() {
    let mut b = bridge();
    let mut set = set_attitude(GimbalDeviceFlags::YAW_LOCK, 0.0, 0.0);
    set.q = [f32::NAN; 4];
    set.angular_velocity_y = 0.0;
    set.angular_velocity_z = 0.5;
    // No vehicle yaw rate: refused, counted, nothing sent.
    b.receive_all(&frame(AP, 0, &set), t(10));
    assert!(queued(&mut b.link).is_empty());
    assert_eq!(b.stats().refused_setpoints, 1);
    // The vehicle turns right at 0.2 rad/s: the motor turns at 0.5 − 0.2 = 0.3 rad/s,
    // 17.19°/s (the wire's 0.01°/s: 1718.87 rounds to 1719).
    let mut state = autopilot_state(0.0);
    state.angular_velocity_z = 0.2;
    b.receive_all(&frame(AP, 1, &state), t(20));
    b.receive_all(&frame(AP, 2, &set), t(30));
    let rates: Vec<Rate> = queued(&mut b.link)
        .into_iter()
        .filter_map(|c| match c {
            GimbalCommand::Rate(r) => Some(r),
            _ => None,
        })
        .collect();
    assert_eq!(rates, [Rate::new(0.3f32.to_degrees(), 0.0).unwrap()]);
    // The same rate in the vehicle frame (YAW_IN_VEHICLE_FRAME wins over YAW_LOCK).
    set.flags = GimbalDeviceFlags::YAW_LOCK | GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME;
    b.receive_all(&frame(AP, 3, &set), t(40));
    let rates: Vec<GimbalCommand> = queued(&mut b.link);
    assert_eq!(
        rates,
        [GimbalCommand::Rate(
            Rate::new(0.5f32.to_degrees(), 0.0).unwrap()
        )]
    );
}

/// Flag bits outside the dialect (a newer autopilot's): `mavio` reads bitmasks with
/// `from_bits_truncate`, so they are dropped. None of the fields the bridge acts on can
/// carry a bit it must see: a setpoint's meaning is fixed by the bits it knows (RETRACT,
/// NEUTRAL, the locks and the two yaw frames; common.xml tells a receiver that knows no
/// frame flag to read YAW_LOCK), and the autopilot state's estimator flags are not acted on.
/// So a setpoint with unknown bits is followed exactly as the same setpoint without them,
/// never refused and never read as another.
#[test]
fn unknown_flag_bits_do_not_change_a_setpoint() {
    let known = GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME;
    let mut plain = bridge();
    plain.receive_all(&frame(AP, 0, &set_attitude(known, 30.0, -20.0)), t(10));
    let expected = queued(&mut plain.link);
    assert_eq!(expected.len(), 2);
    for unknown in [0x0400u16, 0x8000, 0xFC00] {
        let mut b = bridge();
        let flags = GimbalDeviceFlags::from_bits_retain(known.bits() | unknown);
        b.receive_all(&frame(AP, 0, &set_attitude(flags, 30.0, -20.0)), t(10));
        assert_eq!(b.stats().reader.bad_frames, 0, "{unknown:#x}");
        assert_eq!(b.stats().refused_setpoints, 0, "{unknown:#x}");
        assert_eq!(queued(&mut b.link), expected, "{unknown:#x}");
    }
}

#[test]
fn a_pitch_is_rounded_to_the_wires_tenth_before_its_range_is_checked() {
    let mut b = bridge();
    b.receive_all(&frame(AP, 0, &autopilot_state(0.0)), t(0));
    let _ = queued(&mut b.link);
    // −100.04° is −100.0° on the wire (a setpoint of −100° arrives a few ulps past it);
    // −100.06° is −100.1°, beyond the gimbal's range, refused.
    for (i, (pitch, expected)) in [(-100.04, Some(-1000)), (-100.06, None), (60.04, Some(600))]
        .into_iter()
        .enumerate()
    {
        let flags = GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME;
        let refused = b.stats().refused_setpoints;
        b.receive_all(
            &frame(AP, i as u8, &set_attitude(flags, 10.0 * i as f32, pitch)),
            t(10),
        );
        let pitches: Vec<i16> = queued(&mut b.link)
            .into_iter()
            .filter_map(|c| match c {
                GimbalCommand::Pitch(p) => Some(p.deci()),
                _ => None,
            })
            .collect();
        match expected {
            Some(deci) => assert_eq!(pitches, [deci], "{pitch}"),
            None => {
                assert!(pitches.is_empty(), "{pitch}");
                assert_eq!(b.stats().refused_setpoints, refused + 1);
            }
        }
    }
}

#[test]
fn setpoints_and_vehicle_states_for_another_gimbal_are_not_followed() {
    let mut b = fresh();
    b.receive_all(&frame(AP, 0, &heartbeat()), t(0));
    let _ = queued_all(&mut b.link);
    let mut set = set_attitude(GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME, 30.0, -20.0);
    let mut state = autopilot_state(45.0);
    // Another component of this system, and this component of another system.
    for (i, (system, component)) in [(AP.0, 155), (42, 154)].into_iter().enumerate() {
        set.target_system = system;
        set.target_component = component;
        state.target_system = system;
        state.target_component = component;
        b.receive_all(&frame(AP, 2 * i as u8, &set), t(10));
        b.receive_all(&frame(AP, 2 * i as u8 + 1, &state), t(10));
    }
    let s = b.stats();
    assert_eq!((s.angle_setpoints, s.vehicle_updates), (0, 0));
    assert_eq!(s.not_for_us, 4);
    assert!(queued_all(&mut b.link).is_empty());
    assert_eq!(b.link.attitude(), None);
    // To every component of every system, and to this one's: followed.
    for (i, (system, component)) in [(0, 0), (AP.0, 154)].into_iter().enumerate() {
        set.target_system = system;
        set.target_component = component;
        b.receive_all(&frame(AP, 10 + i as u8, &set), t(20));
    }
    assert_eq!(b.stats().angle_setpoints, 2);
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
