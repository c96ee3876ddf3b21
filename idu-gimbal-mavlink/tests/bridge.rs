//! The bridge as an autopilot sees it: MAVLink frames built with `mavio` in, the bridge's
//! bytes parsed back, the gimbal's command queue (the core's sans-IO `Link`) read out.

mod common;
use common::*;

use idu_gimbal::link::serial::SerialLink;
use idu_gimbal::link::{Config, Link};
use idu_gimbal::wire::control::{Command, GimbalCommand, Rate};
use idu_gimbal::wire::ids;
use idu_gimbal::wire::postback::Postback;
use idu_gimbal_mavlink::attitude::YawPitch;
use idu_gimbal_mavlink::{Bridge, BridgeConfig};
use mavio::dialects::common::enums::{
    GimbalDeviceErrorFlags, GimbalDeviceFlags, MavAutopilot, MavCmd, MavResult, MavType,
};
use mavio::dialects::common::messages::{
    AutopilotStateForGimbalDevice, CommandAck, CommandLong, GimbalDeviceAttitudeStatus,
    GimbalDeviceInformation, GimbalDeviceSetAttitude, GlobalPositionInt, Heartbeat,
};

fn set_attitude(flags: GimbalDeviceFlags, yaw_deg: f32, pitch_deg: f32) -> GimbalDeviceSetAttitude {
    GimbalDeviceSetAttitude {
        target_system: AP.0,
        target_component: 154,
        flags,
        q: YawPitch {
            yaw_rad: yaw_deg.to_radians(),
            pitch_rad: pitch_deg.to_radians(),
        }
        .to_quaternion(),
        angular_velocity_x: f32::NAN,
        angular_velocity_y: f32::NAN,
        angular_velocity_z: f32::NAN,
    }
}

fn autopilot_state(yaw_deg: f32) -> AutopilotStateForGimbalDevice {
    AutopilotStateForGimbalDevice {
        target_system: AP.0,
        target_component: 154,
        time_boot_us: 0,
        q: YawPitch {
            yaw_rad: yaw_deg.to_radians(),
            pitch_rad: 0.0,
        }
        .to_quaternion(),
        q_estimated_delay_us: 0,
        vx: 0.0,
        vy: 0.0,
        vz: 0.0,
        v_estimated_delay_us: 0,
        feed_forward_angular_velocity_z: 0.0,
        estimator_status: Default::default(),
        landed_state: Default::default(),
        angular_velocity_z: 0.0,
    }
}

fn fresh() -> Bridge<Link> {
    Bridge::new(Link::new(Config::default()), BridgeConfig::default())
}

/// A bridge that has heard the autopilot's heartbeat (so its system id is the autopilot's),
/// its output so far drained.
fn bridge() -> Bridge<Link> {
    let mut b = fresh();
    b.receive(&frame(AP, 0, &heartbeat()), t(0));
    let _ = sent(&mut b);
    b
}

#[test]
fn heartbeats_at_1_hz_with_the_autopilots_system_id() {
    let mut b = fresh();
    for ms in 0..3_000 {
        if ms == 1_500 {
            b.receive(&frame(AP, 0, &heartbeat()), t(ms));
        }
        b.poll(t(ms));
    }
    let frames = sent(&mut b);
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

#[test]
fn information_on_request_broadcast_or_addressed_and_an_ack_for_every_command() {
    let mut b = bridge();
    b.receive(&frame(AP, 0, &heartbeat()), t(0));
    let _ = sent(&mut b);
    // PX4 asks the broadcast component; ArduPilot the gimbal's.
    for (i, target) in [(AP.0, 0), (AP.0, 154), (0, 0)].into_iter().enumerate() {
        b.receive(
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
        assert_eq!(i.gimbal_device_id, 0);
    }
    // Another component's request: not ours, no answer.
    b.receive(
        &frame(
            GCS,
            9,
            &command((AP.0, 100), MavCmd::RequestMessage, 283.0, 0.0),
        ),
        t(20),
    );
    assert!(sent(&mut b).is_empty());
    // A command the gimbal does not do, addressed to it: UNSUPPORTED, never silence.
    b.receive(
        &frame(GCS, 10, &command((AP.0, 154), MavCmd::DoSetMode, 1.0, 0.0)),
        t(30),
    );
    let acks: Vec<CommandAck> = of(&sent(&mut b));
    assert_eq!(acks.len(), 1);
    assert_eq!(acks[0].result, MavResult::Unsupported);
    // The same, broadcast: another component may own it; the gimbal stays quiet.
    b.receive(
        &frame(GCS, 11, &command((AP.0, 0), MavCmd::DoSetMode, 1.0, 0.0)),
        t(40),
    );
    assert!(of::<CommandAck>(&sent(&mut b)).is_empty());
    assert_eq!(b.stats().acks, 4);
}

#[test]
fn the_attitude_status_interval_is_honoured() {
    let mut b = bridge();
    let status_times = |b: &mut Bridge<Link>, from: u32, to: u32| {
        let mut n = 0;
        for ms in from..to {
            b.poll(t(ms));
            n += of::<GimbalDeviceAttitudeStatus>(&sent(b)).len();
        }
        n
    };
    assert_eq!(status_times(&mut b, 0, 1_000), 10);
    b.receive(
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
    b.receive(
        &frame(
            GCS,
            1,
            &command((0, 154), MavCmd::SetMessageInterval, 285.0, -1.0),
        ),
        t(2_000),
    );
    assert_eq!(status_times(&mut b, 2_000, 3_000), 0);
    b.receive(
        &frame(
            GCS,
            2,
            &command((0, 154), MavCmd::SetMessageInterval, 285.0, 0.0),
        ),
        t(3_000),
    );
    assert_eq!(status_times(&mut b, 3_000, 4_000), 10);
    b.receive(
        &frame(
            GCS,
            3,
            &command((0, 154), MavCmd::SetMessageInterval, 285.0, 10.0),
        ),
        t(4_000),
    );
    assert_eq!(of::<CommandAck>(&sent(&mut b))[0].result, MavResult::Denied);
}

#[test]
fn the_status_reports_the_postback_in_the_frame_of_the_gimbals_reference() {
    let mut b = bridge();
    let p = Postback {
        pitch: -9500,
        heading: 27_000,
        motor_heading: 4_500,
        ..Postback::default()
    };
    for data in p.to_can_frames() {
        b.gimbal_mut().receive(ids::POSTBACK, &data, t(0));
    }
    b.poll(t(0));
    let s = &of::<GimbalDeviceAttitudeStatus>(&sent(&mut b))[0];
    // No attitude pushed: nose-referenced, the yaw is the motor angle in the vehicle frame.
    assert!(s.flags.contains(GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME));
    let a = YawPitch::from_quaternion(s.q).unwrap();
    assert!((a.pitch_rad.to_degrees() + 95.0).abs() < 1e-3);
    assert!((a.yaw_rad.to_degrees() - 45.0).abs() < 1e-3);
    assert!((s.delta_yaw.to_degrees() - 45.0).abs() < 1e-3);
    assert!(s.failure_flags.is_empty());
    // With attitude pushed the postback's heading is north-referenced: earth frame.
    b.receive(&frame(AP, 0, &autopilot_state(225.0 - 360.0)), t(50));
    b.gimbal_mut().poll(t(100));
    let _ = sent(&mut b);
    b.poll(t(100));
    let s = &of::<GimbalDeviceAttitudeStatus>(&sent(&mut b))[0];
    assert!(s.flags.contains(GimbalDeviceFlags::YAW_IN_EARTH_FRAME));
    let a = YawPitch::from_quaternion(s.q).unwrap();
    assert!((a.yaw_rad.to_degrees() + 90.0).abs() < 1e-3, "{a:?}");
    // The link times out after 1.5 s without postbacks: COMMS_ERROR for pre-arm checks.
    b.gimbal_mut().poll(t(1_600));
    b.poll(t(1_600));
    let s = &of::<GimbalDeviceAttitudeStatus>(&sent(&mut b))[0];
    assert!(s
        .failure_flags
        .contains(GimbalDeviceErrorFlags::COMMS_ERROR));
}

#[test]
fn angle_setpoints_become_heading_and_pitch_in_the_gimbals_reference() {
    // North-referenced (attitude pushed, vehicle heading 45°).
    let mut b = bridge();
    b.receive(&frame(AP, 0, &autopilot_state(45.0)), t(0));
    b.gimbal_mut().poll(t(0));
    let _ = queued(b.gimbal_mut());
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
        b.receive(&frame(AP, i as u8, &set_attitude(flags, yaw, pitch)), t(10));
        let q = queued(b.gimbal_mut());
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
    let mut s = Bridge::new(
        SerialLink::<8>::new(Config::default()),
        BridgeConfig::default(),
    );
    s.receive(&frame(AP, 0, &heartbeat()), t(0));
    s.receive(&frame(AP, 0, &autopilot_state(45.0)), t(0));
    s.receive(
        &frame(
            AP,
            1,
            &set_attitude(GimbalDeviceFlags::YAW_IN_EARTH_FRAME, 90.0, -100.0),
        ),
        t(10),
    );
    let mut commands = Vec::new();
    while !s.gimbal_mut().transmit_bytes().is_empty() {
        let bytes = s.gimbal_mut().transmit_bytes().to_vec();
        s.gimbal_mut().transmit_written(bytes.len());
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
    let at = |b: &mut Bridge<Link>, ms: u32, set: Option<GimbalDeviceSetAttitude>| {
        b.receive(&frame(AP, 0, &autopilot_state(0.0)), t(ms));
        if let Some(set) = set {
            b.receive(&frame(AP, 1, &set), t(ms));
        }
        b.gimbal_mut().poll(t(ms));
        queued(b.gimbal_mut())
    };
    let _ = at(&mut b, 0, None);
    assert_eq!(
        at(&mut b, 20, Some(set_attitude(earth, 10.0, -20.0))).len(),
        2
    );
    // 20 Hz of the same setpoint, and one 0.15° off: nothing new (dead-band 0.2°).
    for i in 0..20 {
        let q = at(&mut b, 40 + 50 * i, Some(set_attitude(earth, 10.0, -20.0)));
        assert!(
            q.iter()
                .all(|c| !matches!(c, GimbalCommand::Heading(_) | GimbalCommand::Pitch(_))),
            "{q:?}"
        );
    }
    let q = at(&mut b, 1_100, Some(set_attitude(earth, 10.15, -20.15)));
    assert!(
        q.iter()
            .all(|c| !matches!(c, GimbalCommand::Heading(_) | GimbalCommand::Pitch(_))),
        "{q:?}"
    );
    // 0.5° in pitch only: the pitch alone.
    let q = at(&mut b, 1_150, Some(set_attitude(earth, 10.0, -20.5)));
    let angles: Vec<_> = q
        .into_iter()
        .filter(|c| matches!(c, GimbalCommand::Heading(_) | GimbalCommand::Pitch(_)))
        .collect();
    assert!(
        matches!(angles[..], [GimbalCommand::Pitch(p)] if p.deci() == -205),
        "{angles:?}"
    );
    assert_eq!(b.stats().refused_setpoints, 0);
    assert_eq!(b.stats().angle_commands, 3);
}

/// Without a fresh vehicle heading, a setpoint whose yaw frame differs from the gimbal's
/// reference cannot be converted: refused and counted, not guessed.
#[test]
fn a_yaw_frame_needing_a_stale_vehicle_heading_is_refused() {
    let mut b = bridge();
    b.receive(&frame(AP, 0, &autopilot_state(30.0)), t(0));
    b.gimbal_mut().poll(t(0));
    let _ = queued(b.gimbal_mut());
    // 1.2 s later the vehicle state is stale: the gimbal is nose-referenced, and an
    // earth-frame yaw would need the vehicle heading.
    b.gimbal_mut().poll(t(1_200));
    b.receive(
        &frame(
            AP,
            1,
            &set_attitude(GimbalDeviceFlags::YAW_IN_EARTH_FRAME, 90.0, -10.0),
        ),
        t(1_200),
    );
    assert!(queued(b.gimbal_mut()).is_empty());
    assert_eq!(b.stats().refused_setpoints, 1);
    // A vehicle-frame yaw needs none.
    b.receive(
        &frame(
            AP,
            2,
            &set_attitude(GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME, 20.0, -10.0),
        ),
        t(1_210),
    );
    let q = queued(b.gimbal_mut());
    assert!(
        matches!(q[0], GimbalCommand::Heading(h) if h.deci() == 200),
        "{q:?}"
    );
}

#[test]
fn rate_setpoints_hold_and_stop_with_the_core_dead_man() {
    let mut b = bridge();
    let mut set = set_attitude(GimbalDeviceFlags::YAW_LOCK, 0.0, 0.0);
    set.q = [f32::NAN; 4];
    set.angular_velocity_y = 5f32.to_radians();
    set.angular_velocity_z = (-10f32).to_radians();
    let rate = Rate::new(-10.0, 5.0).unwrap();
    let zero = Rate::new(0.0, 0.0).unwrap();
    let mut rates = Vec::new();
    for ms in 0..1_000u32 {
        if ms < 500 && ms % 50 == 0 {
            b.receive(&frame(AP, (ms / 50) as u8, &set), t(ms));
        }
        b.gimbal_mut().poll(t(ms));
        for c in queued(b.gimbal_mut()) {
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
fn neutral_recentres_and_retract_looks_down_once_each() {
    let mut b = bridge();
    for i in 0..3 {
        b.receive(
            &frame(AP, i, &set_attitude(GimbalDeviceFlags::NEUTRAL, 0.0, 0.0)),
            t(u32::from(i)),
        );
    }
    assert_eq!(queued(b.gimbal_mut()), [GimbalCommand::Recenter]);
    b.receive(
        &frame(AP, 5, &set_attitude(GimbalDeviceFlags::RETRACT, 0.0, 0.0)),
        t(10),
    );
    assert_eq!(queued(b.gimbal_mut()), [GimbalCommand::LookDown]);
}

#[test]
fn the_position_is_asked_of_the_autopilot_until_it_comes() {
    let mut b = fresh();
    let asks = |b: &mut Bridge<Link>, from: u32, to: u32| {
        let mut n = Vec::new();
        for ms in from..to {
            b.poll(t(ms));
            for c in of::<CommandLong>(&sent(b)) {
                n.push((ms, c));
            }
        }
        n
    };
    assert!(asks(&mut b, 0, 100).is_empty(), "no autopilot yet");
    b.receive(&frame(AP, 0, &heartbeat()), t(100));
    let a = asks(&mut b, 100, 6_000);
    assert_eq!(a.len(), 2, "at once, then after 5 s");
    let c = &a[0].1;
    assert_eq!(
        (c.target_system, c.target_component, c.command),
        (AP.0, AP.1, MavCmd::SetMessageInterval)
    );
    assert_eq!((c.param1, c.param2), (33.0, 200_000.0));
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
    b.receive(&frame(AP, 1, &pos), t(6_000));
    assert!(asks(&mut b, 6_000, 20_000).is_empty());
    // The core now holds and pushes it.
    b.gimbal_mut().poll(t(20_000));
    let _ = queued(b.gimbal_mut());
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
        b.receive(&stream[..cut], t(0));
        b.receive(&stream[cut..], t(0));
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
            b.receive(&bytes[..cut], t(0));
            b.receive(&bytes[cut..], t(1));
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
        b.receive(&chunk, t(i));
        assert!(b.reader().pending() < MAX_FRAME_LEN);
    }
    let s = b.stats();
    assert_eq!(
        s.acks + s.angle_commands + s.rate_setpoints + s.vehicle_updates,
        0
    );
    // A 12-byte MAVLink 2 frame with a matching CRC could occur by chance (2^-16 once the
    // header parses); the counters say how the bytes went either way.
    assert!(s.reader.bad_frames > 0 || s.reader.unsupported > 0);
    assert!(s.reader.skipped_bytes > 0);
}
