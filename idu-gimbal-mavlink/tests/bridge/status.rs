//! The gimbal device attitude status: its interval, the motor angle and heading now, the
//! vehicle frame, the yaw rate, the flags and the yaw limit.

use super::*;

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
