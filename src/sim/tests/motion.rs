//! The model's motion: slewing to angles and at rates, the mechanical limits, the heading
//! referenced to north while the vehicle's attitude is fresh, the yaw lock through a turn,
//! and time across the tick's wrap.

use super::*;

#[test]
fn angle_targets_are_reached_at_the_slew_rate_exactly() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    point(&mut sim, -45.0, 90.0, t(0));
    assert_eq!(sim.state().mode, ControlMode::Lock);
    assert_eq!(sim.state().target_pitch_deg, Some(-45.0));
    assert_eq!(sim.state().target_yaw_deg, Some(90.0));
    let mut prev = (0.0f32, 0.0f32);
    for ms in (10..=2000).step_by(10) {
        sim.poll(t(ms));
        let s = sim.state();
        // Never faster than 60°/s (0.6° per 10 ms), never past the target.
        assert!((s.pitch_deg - prev.0).abs() <= 0.6 + SNAP_DEG + 1e-4);
        assert!((s.motor_yaw_deg - prev.1).abs() <= 0.6 + SNAP_DEG + 1e-4);
        assert!(s.pitch_deg >= -45.0 && s.motor_yaw_deg <= 90.0);
        prev = (s.pitch_deg, s.motor_yaw_deg);
        match ms {
            500 => {
                assert!(close(s.pitch_deg, -30.0), "{}", s.pitch_deg);
                assert!(close(s.motor_yaw_deg, 30.0));
            }
            800 => assert_eq!(s.pitch_deg, -45.0),
            1000 => assert!(close(s.motor_yaw_deg, 60.0)),
            1500 => assert_eq!(s.motor_yaw_deg, 90.0),
            _ => {}
        }
    }
    assert_eq!(sim.state().pitch_deg, -45.0);
    assert_eq!(sim.state().heading_deg, 90.0);
}

#[test]
fn one_long_gap_reaches_the_target_without_overshoot() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    point(&mut sim, -100.0, 200.0, t(0));
    sim.poll(t(10 * 3600 * 1000)); // ten hours later
    assert_eq!(sim.state().pitch_deg, -100.0);
    assert_eq!(sim.state().motor_yaw_deg, -160.0); // 200° nose-relative is -160°
    assert_eq!(sim.state().heading_deg, 200.0);
}

#[test]
fn rate_integrates_only_while_commands_keep_coming() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    send(
        &mut sim,
        GimbalCommand::Pitch(Pitch::new(-20.0).unwrap()),
        t(0),
    );
    let rate = GimbalCommand::Rate(Rate::new(10.0, -5.0).unwrap());
    for ms in (0..=1000).step_by(50) {
        send(&mut sim, rate, t(1000 + ms));
        sim.poll(t(1000 + ms + 10));
    }
    // Rate cancelled the pitch target, which had been reached.
    assert_eq!(sim.state().target_pitch_deg, None);
    assert_eq!(sim.state().mode, ControlMode::FullLock);
    assert_eq!(sim.state().rate, (10.0, -5.0));
    // Last command at 2000: honoured until 2200.
    sim.poll(t(2150));
    assert!(close(sim.state().motor_yaw_deg, 11.5));
    assert_eq!(sim.state().rate, (10.0, -5.0));
    sim.poll(t(5000));
    assert!(
        close(sim.state().motor_yaw_deg, 12.0),
        "{}",
        sim.state().motor_yaw_deg
    );
    assert!(close(sim.state().pitch_deg, -26.0));
    assert_eq!(sim.state().rate, (0.0, 0.0));
    sim.poll(t(6000));
    assert!(close(sim.state().motor_yaw_deg, 12.0));

    // A single command followed by hours of silence moves for 200 ms only.
    send(
        &mut sim,
        GimbalCommand::Rate(Rate::new(-50.0, 0.0).unwrap()),
        t(7000),
    );
    sim.poll(t(7000 + 5 * 3600 * 1000));
    assert!(close(sim.state().motor_yaw_deg, 2.0));

    // A zero rate stops at once.
    let at = t(30_000_000);
    send(
        &mut sim,
        GimbalCommand::Rate(Rate::new(0.0, 20.0).unwrap()),
        at,
    );
    sim.poll(at.add_millis(100));
    assert!(close(sim.state().pitch_deg, -24.0));
    send(
        &mut sim,
        GimbalCommand::Rate(Rate::ZERO),
        at.add_millis(100),
    );
    assert_eq!(sim.state().rate, (0.0, 0.0));
    sim.poll(at.add_millis(200));
    assert!(close(sim.state().pitch_deg, -24.0));
    assert_eq!(sim.state().mode, ControlMode::FullLock);
}

#[test]
fn rates_stop_at_the_mechanical_limits_and_work_on_the_dual_light_peripheral() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    let rate = DualLightCommand::Rate(Rate::new(100.0, -100.0).unwrap());
    for ms in (0..3000).step_by(100) {
        send(&mut sim, rate, t(ms));
    }
    sim.poll(t(3000));
    assert_eq!(sim.state().motor_yaw_deg, 170.0);
    assert_eq!(sim.state().pitch_deg, -110.0);
    assert_eq!(sim.postback().motor_heading, 17_000);
    assert_eq!(sim.postback().pitch, -11_000);
}

#[test]
fn heading_is_north_referenced_only_while_attitude_is_fresh() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    // No attitude: nose-relative.
    send(
        &mut sim,
        GimbalCommand::Heading(Heading::new(90.0).unwrap()),
        t(0),
    );
    assert!(!sim.state().north_referenced);
    assert_eq!(sim.state().target_yaw_deg, Some(90.0));
    sim.poll(t(2000));
    assert_eq!(sim.state().heading_deg, 90.0);

    // Vehicle heading 30°: the reported heading is north-referenced.
    attitude(&mut sim, 30.0, t(2000));
    assert!(sim.state().north_referenced);
    assert_eq!(sim.state().heading_deg, 120.0);
    send(
        &mut sim,
        GimbalCommand::Heading(Heading::new(90.0).unwrap()),
        t(2000),
    );
    assert_eq!(sim.state().target_yaw_deg, Some(60.0));
    for ms in (2100..=3000).step_by(100) {
        attitude(&mut sim, 30.0, t(ms));
        sim.poll(t(ms));
    }
    assert_eq!(sim.state().motor_yaw_deg, 60.0);
    assert_eq!(sim.state().heading_deg, 90.0);
    assert_eq!(sim.postback().heading, 9000);
    assert_eq!(sim.postback().motor_heading, 6000);

    // Attitude frames stop: after the timeout the heading is nose-relative again.
    sim.poll(t(4000));
    assert!(sim.state().north_referenced);
    sim.poll(t(4001));
    assert!(!sim.state().north_referenced);
    assert_eq!(sim.state().heading_deg, 60.0);
    send(
        &mut sim,
        GimbalCommand::Heading(Heading::new(90.0).unwrap()),
        t(4001),
    );
    assert_eq!(sim.state().target_yaw_deg, Some(90.0));

    // North-referenced targets are normalised and kept within the motor's ±170°.
    attitude(&mut sim, -170.0, t(5000)); // vehicle heading 190°
    send(
        &mut sim,
        GimbalCommand::Heading(Heading::new(10.0).unwrap()),
        t(5000),
    );
    assert_eq!(sim.state().target_yaw_deg, Some(-170.0)); // 180° → -180° → -170°
    send(
        &mut sim,
        GimbalCommand::Heading(Heading::new(150.0).unwrap()),
        t(5000),
    );
    assert_eq!(sim.state().target_yaw_deg, Some(-40.0));
    send(
        &mut sim,
        GimbalCommand::Heading(Heading::new(360.0).unwrap()),
        t(5000),
    );
    assert_eq!(sim.state().target_yaw_deg, Some(170.0));
    sim.poll(t(5100));
    assert!(sim.state().heading_deg >= 0.0 && sim.state().heading_deg < 360.0);
}

/// A vehicle turning from `from` to `to` degrees at 30°/s, an attitude frame every
/// 100 ms, the simulator polled as it goes; then 3 s at `to` (time to slew 180°).
fn turn<const TX: usize>(sim: &mut Simulator<TX>, from: f32, to: f32, start: u32) -> u32 {
    let mut ms = start;
    let mut heading = from;
    while heading != to {
        ms += 100;
        heading = approach(heading, to, 3.0);
        attitude(sim, heading, t(ms));
        sim.poll(t(ms));
    }
    for _ in 0..30 {
        ms += 100;
        attitude(sim, to, t(ms));
        sim.poll(t(ms));
    }
    ms
}

#[test]
fn lock_holds_the_north_heading_or_the_motor_angle_as_the_vehicle_turns() {
    for (holds, motor, heading) in [
        // Heading 100 from north with the vehicle at 30: motor 70. The vehicle turns to
        // 120: holding north, the motor goes to -20; holding the motor, the camera
        // turns with the vehicle to 190.
        (LockHolds::North, -20.0, 100.0),
        (LockHolds::Motor, 70.0, 190.0),
    ] {
        let mut sim = Simulator::new(
            SimConfig {
                lock_holds: holds,
                ..SimConfig::default()
            },
            t(0),
        );
        attitude(&mut sim, 30.0, t(0));
        send(
            &mut sim,
            GimbalCommand::Heading(Heading::new(100.0).unwrap()),
            t(0),
        );
        let start = turn(&mut sim, 30.0, 30.0, 0);
        assert_eq!(sim.state().motor_yaw_deg, 70.0, "{holds:?}");
        let end = turn(&mut sim, 30.0, 120.0, start);
        let s = sim.state();
        assert_eq!(
            (s.motor_yaw_deg, s.heading_deg),
            (motor, heading),
            "{holds:?}"
        );
        assert_eq!(s.mode, ControlMode::Lock);
        // Heading follow follows in both: the motor stays where it was put.
        send(&mut sim, GimbalCommand::NoseFollowing, t(end));
        turn(&mut sim, 120.0, 60.0, end);
        assert_eq!(sim.state().motor_yaw_deg, 0.0, "{holds:?}");
    }
}

#[test]
fn holding_north_stops_at_the_motor_limit_and_keeps_the_heading_commanded() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    attitude(&mut sim, 0.0, t(0));
    // North 175 with the vehicle at 0 needs the motor at 175: it stops at 170.
    send(
        &mut sim,
        GimbalCommand::Heading(Heading::new(175.0).unwrap()),
        t(0),
    );
    let end = turn(&mut sim, 0.0, 0.0, 0);
    assert_eq!(sim.state().motor_yaw_deg, 170.0);
    // The vehicle turns right to 20: 155 is within reach, and the heading held is the
    // one commanded, not the limit's 170.
    let end = turn(&mut sim, 0.0, 20.0, end);
    assert_eq!(sim.state().motor_yaw_deg, 155.0);
    turn(&mut sim, 20.0, 0.0, end);
    assert_eq!(sim.state().motor_yaw_deg, 170.0);
}

#[test]
fn a_rate_or_a_recentre_sets_the_north_heading_held_from_where_it_leaves_the_yaw() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    attitude(&mut sim, 40.0, t(0));
    send(&mut sim, GimbalCommand::Recenter, t(0));
    send(
        &mut sim,
        GimbalCommand::Pitch(Pitch::new(-10.0).unwrap()),
        t(0),
    );
    // Lock, motor 0 with the vehicle at 40: north 40 is held.
    let end = turn(&mut sim, 40.0, 10.0, 0);
    assert_eq!(sim.state().motor_yaw_deg, 30.0);
    // A rate of 10°/s, refreshed every 100 ms for 1 s, honoured 200 ms past the last
    // (1.1 s in all), then it ends: where it stops (motor 41, north 51) is held.
    for ms in (end..end + 1000).step_by(100) {
        send(
            &mut sim,
            GimbalCommand::Rate(Rate::new(10.0, 0.0).unwrap()),
            t(ms),
        );
        attitude(&mut sim, 10.0, t(ms));
        sim.poll(t(ms));
    }
    let stopped = end + 1300;
    attitude(&mut sim, 10.0, t(stopped));
    sim.poll(t(stopped));
    assert_eq!(sim.state().mode, ControlMode::FullLock);
    // f32 steps of 10 × 0.1 s: within 1e-3° of the exact 41.
    let motor = sim.state().motor_yaw_deg;
    assert!((motor - 41.0).abs() < 1e-3, "{motor}");
    turn(&mut sim, 10.0, 0.0, stopped);
    let motor = sim.state().motor_yaw_deg;
    assert!((motor - 51.0).abs() < 1e-3, "{motor}");
}

#[test]
fn a_pointing_command_ends_a_rate_at_once() {
    let centre = TrackingBox::from_raw(ImagePoint::new(4096, 4096).unwrap(), 8, 8);
    let commands = [
        GimbalCommand::Pitch(Pitch::new(-10.0).unwrap()),
        GimbalCommand::Heading(Heading::new(0.0).unwrap()),
        GimbalCommand::NoseFollowing,
        GimbalCommand::Recenter,
        GimbalCommand::LookDown,
        GimbalCommand::StartTracking(centre),
    ];
    for command in commands {
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        send(
            &mut sim,
            GimbalCommand::Rate(Rate::new(20.0, 0.0).unwrap()),
            t(0),
        );
        sim.poll(t(100));
        assert_eq!(sim.state().rate, (20.0, 0.0));
        send(&mut sim, command, t(100));
        assert_eq!(sim.state().rate, (0.0, 0.0), "{command:?}");
        if let GimbalCommand::Pitch(_) = command {
            // 20°/s for 100 ms, then no more yaw (the pitch command sets no yaw target).
            sim.poll(t(1100));
            assert!(close(sim.state().motor_yaw_deg, 2.0), "{command:?}");
        }
    }
}

#[test]
fn time_never_goes_backwards() {
    let mut sim = Simulator::new(SimConfig::default(), t(1000));
    send(
        &mut sim,
        GimbalCommand::Pitch(Pitch::new(-60.0).unwrap()),
        t(1000),
    );
    sim.poll(t(1500));
    assert!(close(sim.state().pitch_deg, -30.0));
    sim.poll(t(1200)); // earlier: ignored
    assert!(close(sim.state().pitch_deg, -30.0));
    sim.poll(t(1600)); // 100 ms after 1500, not 400 ms after 1200
    assert!(close(sim.state().pitch_deg, -36.0));
}

#[test]
fn slew_rate_and_postbacks_are_correct_across_the_u32_wrap() {
    let t0 = Instant::from_millis(u32::MAX - 300);
    let mut sim = Simulator::new(SimConfig::default(), t0);
    send(
        &mut sim,
        GimbalCommand::Pitch(Pitch::new(-45.0).unwrap()),
        t0,
    );
    sim.poll(t0.add_millis(250));
    assert!(close(sim.state().pitch_deg, -15.0));
    let pb = sim.poll(t0.add_millis(500)).unwrap(); // tick 199, after the wrap
    assert!(t0.add_millis(500).as_millis() < 1000);
    assert_eq!(pb.pitch, -3000);
    sim.poll(t0.add_millis(800));
    assert_eq!(sim.state().pitch_deg, -45.0);
    assert!(sim.poll(t0.add_millis(999)).is_none());
    assert!(sim.poll(t0.add_millis(1000)).is_some());

    // A rate across the wrap.
    let t1 = Instant::from_millis(u32::MAX - 50);
    let mut sim = Simulator::new(SimConfig::default(), t1);
    send(
        &mut sim,
        GimbalCommand::Rate(Rate::new(10.0, 0.0).unwrap()),
        t1,
    );
    sim.poll(t1.add_millis(100));
    assert!(close(sim.state().motor_yaw_deg, 1.0));
    sim.poll(t1.add_millis(1000));
    assert!(close(sim.state().motor_yaw_deg, 2.0));
}
