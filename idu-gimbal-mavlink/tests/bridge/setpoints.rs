//! Setpoints: angles and rates into the gimbal's reference, the dead band, stale headings,
//! neutral and retract, refused and ignored axes, flags, and another gimbal's setpoints.

use super::*;

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
