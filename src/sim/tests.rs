//! The simulator's own tests: the model's motion, commands and postbacks.

use super::*;
use crate::wire::control::{Focus, Heading, ImageOffset, ImagePoint, Pitch, ZoomRatio};
use proptest::prelude::*;

fn t(ms: u32) -> Instant {
    Instant::from_millis(ms)
}

fn send<const TX: usize>(sim: &mut Simulator<TX>, c: impl Into<Command>, at: Instant) {
    let f = c.into().to_frame();
    sim.receive(f.id, &f.data, at).unwrap();
}

fn attitude<const TX: usize>(sim: &mut Simulator<TX>, heading: f32, at: Instant) {
    let f = VehicleFrame::from(Attitude::new(0.0, 0.0, heading).unwrap()).to_frame();
    sim.receive(f.id, &f.data, at).unwrap();
}

fn close(a: f32, b: f32) -> bool {
    (a - b).abs() < 1e-3
}

/// Pops the four frames of one postback and parses them.
fn pop_postback<const TX: usize>(sim: &mut Simulator<TX>) -> Postback {
    let mut bytes = [0u8; 32];
    for chunk in bytes.chunks_exact_mut(8) {
        let f = sim.pop_frame().unwrap();
        assert_eq!(f.id, ids::POSTBACK);
        chunk.copy_from_slice(&f.data);
    }
    Postback::parse(&bytes).unwrap()
}

#[test]
fn angle_targets_are_reached_at_the_slew_rate_exactly() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    send(
        &mut sim,
        GimbalCommand::Pitch(Pitch::new(-45.0).unwrap()),
        t(0),
    );
    send(
        &mut sim,
        GimbalCommand::Heading(Heading::new(90.0).unwrap()),
        t(0),
    );
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
    send(
        &mut sim,
        GimbalCommand::Pitch(Pitch::new(-100.0).unwrap()),
        t(0),
    );
    send(
        &mut sim,
        GimbalCommand::Heading(Heading::new(200.0).unwrap()),
        t(0),
    );
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
fn a_reboot_is_silent_for_its_boot_time_ignores_frames_and_comes_back_at_rest() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    attitude(&mut sim, 30.0, t(0));
    send(
        &mut sim,
        GimbalCommand::Pitch(Pitch::new(-45.0).unwrap()),
        t(0),
    );
    send(&mut sim, GimbalCommand::Zoom(Zoom::In), t(0));
    assert!(sim.poll(t(1000)).is_some());
    assert_eq!(sim.state().pitch_deg, -45.0);
    sim.reboot(t(1100));
    assert!(sim.is_booting());
    assert_eq!(sim.pending_frames(), 0, "frames not yet sent are lost");
    let s = sim.state();
    assert_eq!(
        (s.pitch_deg, s.motor_yaw_deg, s.zoom_ratio),
        (0.0, 0.0, 1.0)
    );
    assert_eq!(s.mode, ControlMode::HeadingFollow);
    assert!(
        !s.north_referenced && s.vehicle.is_none(),
        "the vehicle forgotten"
    );
    // 3 s of start-up: no postbacks, every frame ignored and counted.
    send(
        &mut sim,
        GimbalCommand::Pitch(Pitch::new(-20.0).unwrap()),
        t(2000),
    );
    attitude(&mut sim, 30.0, t(2000));
    for ms in (1100..4100).step_by(100) {
        assert_eq!(sim.poll(t(ms)), None, "at {ms}");
    }
    assert_eq!(sim.stats().while_booting, 2);
    assert_eq!(sim.state().pitch_deg, 0.0);
    // Back on the same postback grid, and obeying again.
    assert_eq!(sim.poll(t(4100)), None);
    assert!(sim.poll(t(4500)).is_some());
    assert!(!sim.is_booting());
    send(
        &mut sim,
        GimbalCommand::Pitch(Pitch::new(-20.0).unwrap()),
        t(4500),
    );
    sim.poll(t(5000));
    assert_eq!(sim.state().pitch_deg, -20.0);
    assert_eq!(sim.stats().reboots, 1);
}

#[test]
fn postbacks_come_every_500_ms_as_four_parsable_frames_matching_the_state() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    send(
        &mut sim,
        GimbalCommand::Pitch(Pitch::new(-80.0).unwrap()),
        t(0),
    );
    send(
        &mut sim,
        GimbalCommand::Heading(Heading::new(300.0).unwrap()),
        t(0),
    );
    let mut times = heapless::Vec::<u32, 32>::new();
    for ms in (0..=10_000).step_by(10) {
        if ms == 2000 {
            // On target by now: tracking the image centre keeps it there.
            send(
                &mut sim,
                GimbalCommand::StartTracking(TrackingBox::from_raw(
                    ImagePoint::new(4096, 4096).unwrap(),
                    8,
                    8,
                )),
                t(ms),
            );
        }
        if let Some(pb) = sim.poll(t(ms)) {
            times.push(ms).unwrap();
            assert_eq!(sim.pending_frames(), 4);
            let parsed = pop_postback(&mut sim);
            assert_eq!(parsed, pb);
            let s = sim.state();
            assert_eq!(pb.data_id, DataId::Attitude);
            assert_eq!(pb.gimbal_type, GimbalType::X30);
            assert_eq!(pb.tracking, ms >= 2000);
            assert_eq!(pb.mode, ControlMode::Lock);
            assert_eq!(f32::from(pb.pitch), libm::roundf(s.pitch_deg * 100.0));
            assert_eq!(f32::from(pb.heading), libm::roundf(s.heading_deg * 100.0));
            assert_eq!(
                f32::from(pb.motor_heading),
                libm::roundf(s.motor_yaw_deg * 100.0)
            );
        }
    }
    assert_eq!(times.len(), 20);
    assert!(times
        .iter()
        .enumerate()
        .all(|(i, &ms)| ms == 500 * (i as u32 + 1)));
    assert_eq!(sim.stats().postbacks, 20);
    assert_eq!(sim.pop_frame(), None);
    let last = sim.postback();
    assert_eq!(
        (last.pitch, last.heading, last.motor_heading),
        (-8000, 30_000, -6000)
    );
}

#[test]
fn postbacks_keep_to_the_deadline_grid_without_drift_or_bursts() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    let mut times = heapless::Vec::<u32, 32>::new();
    for ms in (0..=5010).step_by(7) {
        if sim.poll(t(ms)).is_some() {
            times.push(ms).unwrap();
            pop_postback(&mut sim);
        }
    }
    // The first poll at or after each multiple of 500.
    let expected: heapless::Vec<u32, 32> = (1..=10u32).map(|k| (500 * k).div_ceil(7) * 7).collect();
    assert_eq!(times, expected);
    // A long gap gives one postback, then the grid continues.
    assert!(sim.poll(t(60_123)).is_some());
    assert_eq!(sim.pending_frames(), 4);
    assert!(sim.poll(t(60_124)).is_none());
    assert!(sim.poll(t(60_499)).is_none());
    assert!(sim.poll(t(60_500)).is_some());
    assert_eq!(sim.stats().postbacks, 12);
}

#[test]
fn silent_mode_stops_postbacks_and_resumes_on_the_grid() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    sim.set_silent(true);
    assert!(sim.is_silent());
    for ms in (0..=2000).step_by(10) {
        assert_eq!(sim.poll(t(ms)), None);
    }
    assert_eq!(sim.pop_frame(), None);
    assert_eq!(sim.stats().postbacks, 0);
    sim.set_silent(false);
    assert_eq!(sim.poll(t(2010)), None);
    assert!(sim.poll(t(2500)).is_some());
    assert_eq!(sim.pending_frames(), 4);
}

#[test]
fn silence_is_reported_and_outlasts_a_reboot() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    assert!(!sim.is_silent());
    sim.set_silent(true);
    sim.reboot(t(100));
    assert!(sim.is_silent(), "a reboot carries the silence over");
    // Past the start-up (3 s) and then some: still nothing sent.
    for ms in (100..=6000).step_by(10) {
        assert_eq!(sim.poll(t(ms)), None, "at {ms}");
    }
    assert!(!sim.is_booting());
    sim.set_silent(false);
    assert!(!sim.is_silent());
    assert!(sim.poll(t(6500)).is_some());
}

#[test]
fn a_reboot_at_an_earlier_instant_keeps_the_clock() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    sim.poll(t(1000));
    // A stale instant (before the last one seen): the start-up still counts from 1000 ms.
    sim.reboot(t(400));
    sim.poll(t(1000 + 3000 - 1));
    assert!(sim.is_booting(), "1 ms of the start-up left");
    sim.poll(t(1000 + 3000));
    assert!(!sim.is_booting());
}

#[test]
fn the_postback_grid_restarts_after_a_gap_of_half_the_clock() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    assert!(sim.poll(t(500)).is_some());
    // Frames only, no poll, for more than 2^31 ms: the next postback's instant (1000 ms)
    // now reads as ahead of the clock by 2^31 - 500 ms. The grid restarts from the poll
    // that sees it: one period later, not 2^31 ms.
    attitude(&mut sim, 0.0, t(1 << 30));
    let now = (1u32 << 31) + 1500;
    attitude(&mut sim, 0.0, t(now));
    assert_eq!(sim.poll(t(now)), None);
    assert_eq!(sim.poll(t(now + 499)), None);
    assert!(sim.poll(t(now + 500)).is_some());
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
fn a_direction_behind_the_camera_is_in_no_image() {
    // Behind the camera the tangent comes round again: 180° off the axis would land on
    // the image centre, 170° near it, if either axis alone were checked.
    for direction in [(180.0, 0.0), (0.0, 180.0), (170.0, 0.0), (0.0, -170.0)] {
        assert_eq!(image_point(direction, 1.0), None, "{direction:?}");
    }
    assert_eq!(
        image_point((0.0, 0.0), 1.0),
        Some(ImagePoint::new(4096, 4096).unwrap())
    );
}

#[test]
fn stream_mode_queues_no_frames() {
    let config = SimConfig {
        emit_can_frames: false,
        gimbal_type: GimbalType::X30T,
        postback_period_ms: NonZeroU32::new(100).unwrap(),
        ..SimConfig::default()
    };
    let mut sim = Simulator::new(config, t(0));
    let pb = sim.poll(t(100)).unwrap();
    assert_eq!(pb.gimbal_type, GimbalType::X30T);
    assert_eq!(Postback::parse(&pb.to_stream_bytes()), Ok(pb));
    assert_eq!(sim.pop_frame(), None);
    assert!(sim.poll(t(200)).is_some());
}

#[test]
fn every_gimbal_command_changes_the_state_as_documented() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    let now = t(0);
    // Zoom ratio, reset, double, half, continuous.
    send(
        &mut sim,
        GimbalCommand::ZoomRatio(ZoomRatio::new(10.0).unwrap()),
        now,
    );
    assert_eq!(sim.state().zoom_ratio, 10.0);
    send(
        &mut sim,
        GimbalCommand::ZoomRatio(ZoomRatio::new(35.0).unwrap()),
        now,
    );
    assert_eq!(sim.state().zoom_ratio, 30.0);
    send(&mut sim, GimbalCommand::Zoom(Zoom::Reset), now);
    assert_eq!(sim.state().zoom_ratio, 1.0);
    send(&mut sim, GimbalCommand::Zoom(Zoom::Half), now);
    assert_eq!(sim.state().zoom_ratio, 1.0);
    send(&mut sim, GimbalCommand::Zoom(Zoom::Double), now);
    send(&mut sim, GimbalCommand::Zoom(Zoom::Double), now);
    assert_eq!(sim.state().zoom_ratio, 4.0);
    send(&mut sim, GimbalCommand::Zoom(Zoom::Half), now);
    assert_eq!(sim.state().zoom_ratio, 2.0);
    send(&mut sim, GimbalCommand::Zoom(Zoom::In), now);
    assert_eq!(sim.state().zooming, Some(Zoom::In));
    sim.poll(t(1000));
    assert!(close(sim.state().zoom_ratio, 7.0));
    send(&mut sim, GimbalCommand::Zoom(Zoom::Stop), t(1000));
    assert_eq!(sim.state().zooming, None);
    sim.poll(t(2000));
    assert!(close(sim.state().zoom_ratio, 7.0));
    send(&mut sim, GimbalCommand::Zoom(Zoom::In), t(2000));
    sim.poll(t(20_000));
    assert_eq!(sim.state().zoom_ratio, 30.0);
    send(&mut sim, GimbalCommand::Zoom(Zoom::Out), t(20_000));
    sim.poll(t(21_000));
    assert!(close(sim.state().zoom_ratio, 25.0));
    sim.poll(t(40_000));
    assert_eq!(sim.state().zoom_ratio, 1.0);
    send(
        &mut sim,
        GimbalCommand::PointingZoom(ImageOffset::new(100, -200).unwrap()),
        t(40_000),
    );
    assert_eq!(sim.state().zoom_ratio, 2.0);
    assert_eq!(sim.state().zooming, None);
    assert_eq!(sim.state().pointing_zooms, 1);
    let now = t(40_000);

    // Pointing: look down, recenter, nose-following.
    send(&mut sim, GimbalCommand::LookDown, now);
    assert_eq!(sim.state().target_pitch_deg, Some(-90.0));
    assert_eq!(sim.state().target_yaw_deg, None);
    assert_eq!(sim.state().mode, ControlMode::HeadingFollow);
    sim.poll(t(42_000));
    assert_eq!(sim.state().pitch_deg, -90.0);
    send(
        &mut sim,
        GimbalCommand::Rate(Rate::new(20.0, 0.0).unwrap()),
        t(42_000),
    );
    sim.poll(t(42_200));
    assert!(close(sim.state().motor_yaw_deg, 4.0));
    send(&mut sim, GimbalCommand::Recenter, t(42_200));
    assert_eq!(sim.state().mode, ControlMode::Lock);
    assert_eq!(
        (sim.state().target_pitch_deg, sim.state().target_yaw_deg),
        (Some(0.0), Some(0.0))
    );
    sim.poll(t(44_000));
    assert_eq!(
        (sim.state().pitch_deg, sim.state().motor_yaw_deg),
        (0.0, 0.0)
    );
    send(
        &mut sim,
        GimbalCommand::Heading(Heading::new(45.0).unwrap()),
        t(44_000),
    );
    sim.poll(t(46_000));
    send(&mut sim, GimbalCommand::NoseFollowing, t(46_000));
    assert_eq!(sim.state().mode, ControlMode::HeadingFollow);
    assert_eq!(sim.state().target_yaw_deg, Some(0.0));
    sim.poll(t(48_000));
    assert_eq!(sim.state().motor_yaw_deg, 0.0);
    let now = t(48_000);

    // Tracking.
    let b = TrackingBox::from_raw(ImagePoint::new(100, 200).unwrap(), 4, 5);
    send(&mut sim, GimbalCommand::StartTracking(b), now);
    assert!(sim.state().tracking);
    assert_eq!(sim.state().tracking_box, Some(b));
    assert!(sim.postback().tracking);
    send(&mut sim, GimbalCommand::StopTracking, now);
    assert!(!sim.state().tracking);
    assert_eq!(sim.state().tracking_box, None);

    // Video.
    send(&mut sim, GimbalCommand::Video(Video::Start), now);
    assert!(sim.state().recording);
    send(&mut sim, GimbalCommand::Video(Video::Stop), now);
    assert!(!sim.state().recording);

    // Photos: single, burst, timer, time-lapse, stop.
    send(&mut sim, GimbalCommand::Photo(Photo::Single), now);
    assert_eq!(sim.state().photos, 1);
    send(
        &mut sim,
        GimbalCommand::Photo(Photo::burst(5).unwrap()),
        now,
    );
    assert_eq!(sim.state().photos, 6);
    send(
        &mut sim,
        GimbalCommand::Photo(Photo::timer(3).unwrap()),
        now,
    );
    sim.poll(now.add_millis(2999));
    assert_eq!(sim.state().photos, 6);
    sim.poll(now.add_millis(3000));
    assert_eq!(sim.state().photos, 7);
    assert_eq!(sim.state().photo_mode, None);
    let now = now.add_millis(3000);
    send(
        &mut sim,
        GimbalCommand::Photo(Photo::time_lapse(2).unwrap()),
        now,
    );
    sim.poll(now.add_millis(1000));
    assert_eq!(sim.state().photos, 7);
    sim.poll(now.add_millis(2000));
    assert_eq!(sim.state().photos, 8);
    sim.poll(now.add_millis(9000)); // photos at 4, 6, 8 s
    assert_eq!(sim.state().photos, 11);
    // The step ran 1 s past the photo at 8 s: the next is still on the grid, at 10 s.
    sim.poll(now.add_millis(9999));
    assert_eq!(sim.state().photos, 11);
    sim.poll(now.add_millis(10_000));
    assert_eq!(sim.state().photos, 12);
    send(
        &mut sim,
        GimbalCommand::Photo(Photo::Stop),
        now.add_millis(10_000),
    );
    sim.poll(now.add_millis(60_000));
    assert_eq!(sim.state().photos, 12);
    let now = now.add_millis(60_000);

    // Focus and calibration are counted.
    send(&mut sim, GimbalCommand::Focus(Focus::Auto), now);
    send(
        &mut sim,
        GimbalCommand::PointingFocus(ImagePoint::new(1, 2).unwrap()),
        now,
    );
    send(&mut sim, GimbalCommand::FastCalibration, now);
    assert_eq!(sim.state().focus_commands, 2);
    assert!(sim.state().auto_focus);
    assert_eq!(sim.state().focus_point, ImagePoint::new(1, 2).ok());
    assert_eq!(sim.state().calibrations, 1);
    assert!(sim.state().calibrating);
    assert_eq!(
        sim.state().last_command,
        Some(Command::Gimbal(GimbalCommand::FastCalibration))
    );
    assert_eq!(sim.stats().commands, 29);
    assert_eq!(sim.stats().rejected, 0);
}

#[test]
fn every_dual_light_command_changes_the_state_as_documented() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    send(&mut sim, DualLightCommand::Palette(Palette::IceBlue), t(0));
    assert_eq!(sim.state().palette, Some(Palette::IceBlue));
    send(
        &mut sim,
        DualLightCommand::ElectronicZoom(ElectronicZoom::In),
        t(0),
    );
    assert_eq!(sim.state().electronic_zooming, Some(ElectronicZoom::In));
    send(
        &mut sim,
        DualLightCommand::ElectronicZoom(ElectronicZoom::Stop),
        t(0),
    );
    assert_eq!(sim.state().electronic_zooming, None);
    send(
        &mut sim,
        DualLightCommand::PointingZoom(ImageOffset::CENTRE),
        t(0),
    );
    assert_eq!(sim.state().pointing_zooms, 1);
    assert_eq!(sim.state().zoom_ratio, 1.0);
    let b = TrackingBox::from_raw(ImagePoint::new(8191, 0).unwrap(), 1, 1);
    send(&mut sim, DualLightCommand::StartTracking(b), t(0));
    assert!(sim.state().tracking);
    send(&mut sim, DualLightCommand::StopTracking, t(0));
    assert!(!sim.state().tracking);
    send(
        &mut sim,
        GimbalCommand::Pitch(Pitch::new(10.0).unwrap()),
        t(0),
    );
    send(
        &mut sim,
        DualLightCommand::Rate(Rate::new(0.0, 10.0).unwrap()),
        t(0),
    );
    assert_eq!(sim.state().target_pitch_deg, None);
    assert_eq!(sim.state().mode, ControlMode::FullLock);
    sim.poll(t(1000));
    assert!(close(sim.state().pitch_deg, 2.0));
}

#[test]
fn vehicle_frames_are_stored() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    let gps = Gps::new(47.3977, 8.5456).unwrap();
    let alt = Altitude::new(488.25).unwrap();
    for f in [VehicleFrame::from(gps), VehicleFrame::from(alt)] {
        let f = f.to_frame();
        sim.receive(f.id, &f.data, t(0)).unwrap();
    }
    attitude(&mut sim, 270.0, t(0));
    assert_eq!(sim.state().gps, Some(gps));
    assert_eq!(sim.state().altitude, Some(alt));
    assert_eq!(sim.state().vehicle.map(|a| a.heading_deg()), Some(-90.0));
    assert_eq!(sim.state().heading_deg, 270.0);
    assert_eq!(sim.stats().vehicle_frames, 3);
    assert_eq!(
        sim.receive(ids::ALTITUDE, &[0, 0, 0, 0, 1, 0, 0, 0], t(0)),
        Err(SimError::Vehicle(vehicle::VehicleError::NonZeroPadding {
            id: ids::ALTITUDE
        }))
    );
    assert_eq!(sim.stats().vehicle_errors, 1);
    assert_eq!(sim.state().altitude, Some(alt));
}

#[test]
fn texts_are_received_and_bad_frames_counted() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    for f in text::chunks(b"WAYPOINT 7 REACHED").unwrap() {
        sim.receive(f.id, &f.data, t(0)).unwrap();
    }
    assert_eq!(sim.state().last_text.as_str(), "WAYPOINT 7 REACHED");
    assert_eq!(sim.stats().texts, 1);
    let bad = sim.receive(ids::TEXT_END, &[b'A', 0x80, 0, 0, 0, 0, 0, 0], t(0));
    assert!(matches!(
        bad,
        Err(SimError::Text(text::TextError::InvalidByte { .. }))
    ));
    assert_eq!(sim.stats().text_errors, 1);
    assert_eq!(sim.state().last_text.as_str(), "WAYPOINT 7 REACHED");
    for f in text::chunks(b"HI").unwrap() {
        sim.receive(f.id, &f.data, t(0)).unwrap();
    }
    assert_eq!(sim.state().last_text.as_str(), "HI");
    assert_eq!(sim.stats().texts, 2);
}

#[test]
fn bad_control_frames_and_foreign_ids_change_nothing() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    let before = sim.state().clone();
    let err = sim.receive(ids::CONTROL, &[0x0F, 0x08, 0x02, 0x00, 0x80, 0, 0, 0], t(0));
    assert!(matches!(
        err,
        Err(SimError::Command(control::DecodeError::InvalidValue { .. }))
    ));
    let err = sim.receive(ids::CONTROL, &[0x0F, 0x07], t(0));
    assert_eq!(
        err,
        Err(SimError::Command(control::DecodeError::WrongLength {
            len: 2
        }))
    );
    assert_eq!(sim.receive(ids::POSTBACK, &[0; 8], t(0)), Ok(()));
    assert_eq!(sim.receive(0x123, &[], t(0)), Ok(()));
    assert_eq!(sim.state(), &before);
    let stats = sim.stats();
    assert_eq!((stats.rejected, stats.ignored, stats.commands), (2, 2, 0));
    #[cfg(feature = "std")]
    {
        let e: &dyn std::error::Error = &err.unwrap_err();
        assert!(e.source().is_some());
    }
    assert!(std::format!("{}", err.unwrap_err()).contains("8 bytes"));
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

#[test]
fn a_full_tx_queue_drops_whole_postbacks_and_counts_them() {
    let mut sim: Simulator<6> = Simulator::with_tx_capacity(SimConfig::default(), t(0));
    assert!(sim.poll(t(500)).is_some());
    assert_eq!(sim.pending_frames(), 4);
    send(
        &mut sim,
        GimbalCommand::Pitch(Pitch::new(-10.0).unwrap()),
        t(500),
    );
    assert_eq!(sim.poll(t(1000)), None); // two free slots: dropped whole
    assert_eq!(sim.stats().tx_overflows, 1);
    assert_eq!(sim.stats().postbacks, 1);
    assert_eq!(sim.pending_frames(), 4);
    assert_eq!(pop_postback(&mut sim).pitch, 0);
    assert_eq!(sim.pop_frame(), None);
    let pb = sim.poll(t(1500)).unwrap();
    assert_eq!(pop_postback(&mut sim), pb);
    assert_eq!(pb.pitch, -1000);

    // The default queue holds four postbacks; the fifth is dropped.
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    for k in 1..=5u32 {
        let pb = sim.poll(t(500 * k));
        assert_eq!(pb.is_some(), k <= 4);
    }
    assert_eq!(sim.pending_frames(), 16);
    assert_eq!(sim.stats().tx_overflows, 1);
    for _ in 0..4 {
        pop_postback(&mut sim);
    }
    assert_eq!(sim.pop_frame(), None);

    // A queue too small for one postback drops them all.
    let mut sim: Simulator<3> = Simulator::with_tx_capacity(SimConfig::default(), t(0));
    assert_eq!(sim.poll(t(500)), None);
    assert_eq!(sim.pop_frame(), None);
    assert_eq!(sim.stats().tx_overflows, 1);
}

/// The yaw and pitch offsets, degrees, of image point (x, y) for a camera of 60°
/// horizontal field of view at 1× and 16:9, at `zoom`: computed in f64 from the
/// field of view, independently of the simulator's code.
fn expected_offset(x: f64, y: f64, zoom: f64) -> (f64, f64) {
    let hfov = 2.0 * ((30f64).to_radians().tan() / zoom).atan();
    let vfov = 2.0 * ((hfov / 2.0).tan() * 9.0 / 16.0).atan();
    let nx = (x - 4096.0) / 4096.0;
    let ny = (y - 4096.0) / 4096.0;
    (
        (nx * (hfov / 2.0).tan()).atan().to_degrees(),
        -(ny * (vfov / 2.0).tan()).atan().to_degrees(),
    )
}

fn track<const TX: usize>(sim: &mut Simulator<TX>, x: i32, y: i32, at: Instant) {
    let b = TrackingBox::from_raw(ImagePoint::new(x, y).unwrap(), 4, 3);
    send(sim, GimbalCommand::StartTracking(b), at);
}

fn box_centre<const TX: usize>(sim: &Simulator<TX>) -> (u16, u16) {
    let c = sim.state().tracking_box.unwrap().centre();
    (c.x(), c.y())
}

#[test]
fn tracking_slews_toward_the_box_and_brings_it_back_to_the_centre() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    // Right of and below the centre, at 1×.
    track(&mut sim, 6144, 6144, t(0));
    let (yaw, pitch) = expected_offset(6144.0, 6144.0, 1.0);
    assert!((yaw - 16.102).abs() < 1e-3, "{yaw}"); // atan(0.5·tan 30°)
    assert!((pitch + 9.223).abs() < 1e-3, "{pitch}"); // −atan(0.5·tan 30°·9/16)
    let s = sim.state();
    assert!(s.tracking);
    assert_eq!(s.mode, ControlMode::Lock);
    assert!((f64::from(s.target_yaw_deg.unwrap()) - yaw).abs() < 1e-3);
    assert!((f64::from(s.target_pitch_deg.unwrap()) - pitch).abs() < 1e-3);
    assert_eq!(box_centre(&sim), (6144, 6144));
    assert!(sim.postback().tracking);

    // After 100 ms at 60°/s: 6° on each axis, the box centre where the rest is.
    sim.poll(t(100));
    assert!(close(sim.state().heading_deg, 6.0));
    assert!(close(sim.state().pitch_deg, -6.0));
    let tan30 = (30f64).to_radians().tan();
    let x = 4096.0 + 4096.0 * (yaw - 6.0).to_radians().tan() / tan30;
    let y = 4096.0 - 4096.0 * (pitch + 6.0).to_radians().tan() / (tan30 * 9.0 / 16.0);
    let (bx, by) = box_centre(&sim);
    assert!((f64::from(bx) - x).abs() <= 1.0, "{bx} {x}");
    assert!((f64::from(by) - y).abs() <= 1.0, "{by} {y}");

    // The heading rises and the box comes back to the centre, both monotonically.
    let mut prev = (sim.state().heading_deg, bx, by);
    for ms in (110..=1000).step_by(10) {
        if let Some(pb) = sim.poll(t(ms)) {
            assert!(pb.tracking);
        }
        let (bx, by) = box_centre(&sim);
        let heading = sim.state().heading_deg;
        assert!(heading >= prev.0 && bx <= prev.1 && by <= prev.2);
        assert!(bx >= 4096 && by >= 4096);
        prev = (heading, bx, by);
    }
    let s = sim.state();
    assert!((f64::from(s.heading_deg) - yaw).abs() < 1e-3);
    assert!((f64::from(s.pitch_deg) - pitch).abs() < 1e-3);
    assert_eq!(box_centre(&sim), (4096, 4096));
    assert_eq!(s.tracking_box.unwrap().width16(), 4); // the size is kept
    let pb = sim.postback();
    assert!(pb.tracking);
    assert_eq!((pb.heading, pb.pitch), (1610, -922));

    // Left of and above the centre by as much: back to where it started.
    track(&mut sim, 2048, 2048, t(1000));
    let s = sim.state();
    assert!(close(s.target_yaw_deg.unwrap(), 0.0));
    assert!(close(s.target_pitch_deg.unwrap(), 0.0));
    sim.poll(t(2000));
    assert!(close(sim.state().motor_yaw_deg, 0.0));
    assert_eq!(box_centre(&sim), (4096, 4096));
}

#[test]
fn zoom_narrows_the_field_of_view_so_the_same_box_is_a_smaller_angle() {
    let (h1, v1) = field_of_view_deg(1.0);
    assert!(close(h1, 60.0));
    let v1_expected = 2.0
        * ((30f64).to_radians().tan() * 9.0 / 16.0)
            .atan()
            .to_degrees();
    assert!((f64::from(v1) - v1_expected).abs() < 1e-3); // 35.98°
    let (h2, _) = field_of_view_deg(2.0);
    let h2_expected = 2.0 * ((30f64).to_radians().tan() / 2.0).atan().to_degrees();
    assert!((f64::from(h2) - h2_expected).abs() < 1e-3); // 32.20°
    assert_eq!(field_of_view_deg(0.5), field_of_view_deg(1.0));

    let target_yaw = |zoom: f32| {
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        send(
            &mut sim,
            GimbalCommand::ZoomRatio(ZoomRatio::new(zoom).unwrap()),
            t(0),
        );
        track(&mut sim, 6144, 4096, t(0));
        f64::from(sim.state().target_yaw_deg.unwrap())
    };
    let at_1 = target_yaw(1.0);
    let at_2 = target_yaw(2.0);
    let at_10 = target_yaw(10.0);
    assert!((at_1 - expected_offset(6144.0, 4096.0, 1.0).0).abs() < 1e-3);
    assert!((at_2 - expected_offset(6144.0, 4096.0, 2.0).0).abs() < 1e-3);
    assert!((at_2 - 8.213).abs() < 1e-3, "{at_2}"); // atan(0.5·tan 30° / 2)
    assert!((at_10 - expected_offset(6144.0, 4096.0, 10.0).0).abs() < 1e-3);
    assert!(at_1 > at_2 && at_2 > at_10);

    // Zooming while tracking moves the box away from the centre; out of the image,
    // the target is lost and the gimbal holds.
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    track(&mut sim, 6144, 4096, t(0));
    send(&mut sim, GimbalCommand::Zoom(Zoom::Double), t(0));
    assert!(sim.state().tracking);
    assert_eq!(box_centre(&sim), (8191, 4096)); // offset 0.5 × 2: the right edge
    sim.poll(t(100));
    assert!(close(sim.state().motor_yaw_deg, 6.0));
    send(&mut sim, GimbalCommand::Zoom(Zoom::Double), t(100));
    let s = sim.state();
    assert!(!s.tracking);
    assert_eq!(s.tracking_box, None);
    assert_eq!(s.targets_lost, 1);
    assert!(close(s.target_yaw_deg.unwrap(), 6.0));
    assert!(!sim.postback().tracking);
    sim.poll(t(1000));
    assert!(close(sim.state().motor_yaw_deg, 6.0));
}

#[test]
fn tracking_is_lost_after_tracking_lost_ms_exactly_across_the_tick_wrap() {
    let t0 = Instant::from_millis(u32::MAX - 3000);
    let mut sim = Simulator::new(SimConfig::default(), t0);
    track(&mut sim, 6144, 4096, t0);
    let yaw = expected_offset(6144.0, 4096.0, 1.0).0;
    sim.poll(t0.add_millis(9_999));
    assert!(sim.state().tracking);
    assert!(sim.postback().tracking);
    assert!(t0.add_millis(10_000).as_millis() < 10_000); // past the wrap
    let pb = sim.poll(t0.add_millis(10_000)).unwrap(); // a postback deadline too
    assert!(!pb.tracking);
    let s = sim.state();
    assert!(!s.tracking);
    assert_eq!(s.tracking_box, None);
    assert_eq!(s.targets_lost, 1);
    assert_eq!(s.mode, ControlMode::Lock);
    assert!((f64::from(s.target_yaw_deg.unwrap()) - yaw).abs() < 1e-3);

    // In one long step: the gimbal slews until the loss, then holds there.
    let config = SimConfig {
        slew_dps: 1.0,
        tracking_lost_ms: 5_000,
        ..SimConfig::default()
    };
    let mut sim = Simulator::new(config, t0);
    track(&mut sim, 6144, 4096, t0);
    sim.poll(t0.add_millis(60_000));
    assert!(!sim.state().tracking);
    assert!(close(sim.state().motor_yaw_deg, 5.0));
    assert_eq!(sim.state().target_yaw_deg, Some(sim.state().motor_yaw_deg));

    // A new start tracking restarts the time; 0 never loses the target.
    let mut sim = Simulator::new(SimConfig::default(), t0);
    track(&mut sim, 4096, 4096, t0);
    track(&mut sim, 4096, 4096, t0.add_millis(5_000));
    sim.poll(t0.add_millis(14_999));
    assert!(sim.state().tracking);
    sim.poll(t0.add_millis(15_000));
    assert!(!sim.state().tracking);
    let config = SimConfig {
        tracking_lost_ms: 0,
        ..SimConfig::default()
    };
    let mut sim = Simulator::new(config, t0);
    track(&mut sim, 6144, 4096, t0);
    sim.poll(t0.add_millis(3_600_000));
    assert!(sim.state().tracking);
    assert_eq!(box_centre(&sim), (4096, 4096));
    assert_eq!(sim.state().targets_lost, 0);
}

#[test]
fn manual_pointing_ends_tracking_but_a_zero_rate_and_zoom_do_not() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    track(&mut sim, 6144, 4096, t(0));
    let target = sim.state().target_yaw_deg;
    send(&mut sim, GimbalCommand::Rate(Rate::ZERO), t(0));
    send(&mut sim, DualLightCommand::Rate(Rate::ZERO), t(0));
    send(&mut sim, GimbalCommand::Zoom(Zoom::In), t(0));
    send(&mut sim, GimbalCommand::Zoom(Zoom::Stop), t(0));
    send(&mut sim, GimbalCommand::Photo(Photo::Single), t(0));
    assert!(sim.state().tracking);
    assert_eq!(sim.state().mode, ControlMode::Lock);
    assert_eq!(sim.state().target_yaw_deg, target);

    // A non-zero rate: the operator takes over.
    sim.poll(t(100));
    send(
        &mut sim,
        GimbalCommand::Rate(Rate::new(0.0, 10.0).unwrap()),
        t(100),
    );
    let s = sim.state();
    assert!(!s.tracking && s.tracking_box.is_none());
    assert_eq!(s.mode, ControlMode::FullLock);
    assert_eq!((s.target_yaw_deg, s.target_pitch_deg), (None, None));
    assert_eq!(s.rate, (0.0, 10.0));

    // An angle command: it acts, the other axis holds where it was.
    track(&mut sim, 6144, 4096, t(300));
    assert_eq!(sim.state().rate, (0.0, 0.0));
    assert_eq!(sim.state().mode, ControlMode::Lock);
    sim.poll(t(400));
    let yaw_now = sim.state().motor_yaw_deg;
    send(
        &mut sim,
        GimbalCommand::Pitch(Pitch::new(-30.0).unwrap()),
        t(400),
    );
    assert!(!sim.state().tracking);
    assert_eq!(sim.state().target_yaw_deg, Some(yaw_now));
    assert_eq!(sim.state().target_pitch_deg, Some(-30.0));

    // Stop tracking when not tracking changes nothing (the pitch slew goes on).
    send(&mut sim, GimbalCommand::StopTracking, t(400));
    assert_eq!(sim.state().target_pitch_deg, Some(-30.0));
    sim.poll(t(1000));
    assert!(close(sim.state().pitch_deg, -30.0));

    // Recenter, look down, nose-following and stop tracking all end it, not as a loss.
    let enders: [Command; 5] = [
        GimbalCommand::Recenter.into(),
        GimbalCommand::LookDown.into(),
        GimbalCommand::NoseFollowing.into(),
        GimbalCommand::StopTracking.into(),
        DualLightCommand::StopTracking.into(),
    ];
    for c in enders {
        track(&mut sim, 100, 100, t(1000));
        send(&mut sim, c, t(1000));
        assert!(!sim.state().tracking, "{c:?}");
    }
    assert_eq!(sim.state().targets_lost, 0);
}

#[test]
fn tracking_makes_up_for_a_vehicle_turn() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    attitude(&mut sim, 30.0, t(0));
    track(&mut sim, 4096, 4096, t(0));
    assert_eq!(sim.state().target_yaw_deg, Some(0.0));
    attitude(&mut sim, 40.0, t(0));
    assert!(close(sim.state().target_yaw_deg.unwrap(), -10.0));
    for ms in (100..=1000).step_by(100) {
        attitude(&mut sim, 40.0, t(ms));
    }
    sim.poll(t(1000));
    assert!(close(sim.state().motor_yaw_deg, -10.0));
    assert!(close(sim.state().heading_deg, 30.0));
    assert_eq!(box_centre(&sim), (4096, 4096));
    // A stale attitude moves nothing.
    sim.poll(t(5000));
    assert!(!sim.state().north_referenced);
    assert!(close(sim.state().motor_yaw_deg, -10.0));
    assert!(sim.state().tracking);
}

#[test]
fn focus_moves_at_its_speed_and_stops_at_the_ends_and_on_stop() {
    let mut sim = Simulator::new(SimConfig::default(), t(0));
    assert_eq!(sim.state().focus, FOCUS_INITIAL);
    assert!(!sim.state().auto_focus);
    send(&mut sim, GimbalCommand::Focus(Focus::Auto), t(0));
    assert!(sim.state().auto_focus);
    send(&mut sim, GimbalCommand::Focus(Focus::Plus), t(0));
    assert!(!sim.state().auto_focus);
    assert_eq!(sim.state().focusing, Some(Focus::Plus));
    sim.poll(t(500));
    assert!(close(sim.state().focus, 0.75));
    sim.poll(t(5000));
    assert_eq!(sim.state().focus, 1.0); // the far end
    send(&mut sim, GimbalCommand::Focus(Focus::Minus), t(5000));
    sim.poll(t(5400));
    assert!(close(sim.state().focus, 0.8));
    send(&mut sim, GimbalCommand::Focus(Focus::Stop), t(5400));
    assert_eq!(sim.state().focusing, None);
    sim.poll(t(9000));
    assert!(close(sim.state().focus, 0.8));
    send(&mut sim, GimbalCommand::Focus(Focus::Minus), t(9000));
    sim.poll(t(20_000));
    assert_eq!(sim.state().focus, 0.0); // the near end

    // Auto focus and pointing focus stop the motion and keep the focus where it is.
    let p = ImagePoint::new(1000, 7000).unwrap();
    send(&mut sim, GimbalCommand::PointingFocus(p), t(20_000));
    let s = sim.state();
    assert!(s.auto_focus);
    assert_eq!((s.focusing, s.focus_point), (None, Some(p)));
    send(&mut sim, GimbalCommand::Focus(Focus::Plus), t(20_000));
    assert_eq!(sim.state().focus_point, None);
    send(&mut sim, GimbalCommand::Focus(Focus::Auto), t(20_200));
    let s = sim.state();
    assert!(s.auto_focus && s.focusing.is_none() && s.focus_point.is_none());
    assert!(close(s.focus, 0.1));
    assert_eq!(s.focus_commands, 8);
}

#[test]
fn fast_calibration_lasts_two_seconds_across_the_tick_wrap() {
    let t0 = Instant::from_millis(u32::MAX - 500);
    let mut sim = Simulator::new(SimConfig::default(), t0);
    send(&mut sim, GimbalCommand::FastCalibration, t0);
    assert!(sim.state().calibrating);
    sim.poll(t0.add_millis(1000));
    send(
        &mut sim,
        GimbalCommand::FastCalibration,
        t0.add_millis(1000),
    );
    sim.poll(t0.add_millis(2999));
    assert!(sim.state().calibrating);
    sim.poll(t0.add_millis(3000));
    assert!(!sim.state().calibrating);
    assert_eq!(sim.state().calibrations, 2);
}

/// Bytes that often decode as control commands, sometimes not.
fn control_bytes() -> impl Strategy<Value = [u8; 8]> {
    let small = prop_oneof![3 => Just(0u8), 1 => 0u8..8, 1 => any::<u8>()];
    (
        prop_oneof![Just(0x0Fu8), Just(0x1F), any::<u8>()],
        prop_oneof![
            prop::sample::select(vec![
                1u8, 2, 3, 4, 5, 6, 7, 8, 0x10, 0x11, 0x12, 0x13, 0x14, 0xF0
            ]),
            any::<u8>()
        ],
        0u8..8,
        [
            small.clone(),
            small.clone(),
            small.clone(),
            small.clone(),
            small,
        ],
    )
        .prop_map(|(p, c, d1, rest)| {
            let [a, b, c2, d, e] = rest;
            [p, c, d1, a, b, c2, d, e]
        })
}

fn event() -> impl Strategy<Value = (u32, Vec<u8>, u32)> {
    let id = prop_oneof![
        Just(ids::CONTROL),
        Just(ids::ATTITUDE),
        Just(ids::GPS),
        Just(ids::ALTITUDE),
        Just(ids::TEXT),
        Just(ids::TEXT_END),
        any::<u32>(),
    ];
    let data = prop_oneof![
        3 => control_bytes().prop_map(|b| b.to_vec()),
        1 => prop::collection::vec(any::<u8>(), 0..12),
    ];
    let dt = prop_oneof![4 => 0u32..300, 1 => any::<u32>()];
    (id, data, dt)
}

proptest! {
    #[test]
    fn arbitrary_input_never_panics_and_keeps_invariants(
        slew in prop_oneof![Just(60.0f32), any::<f32>()],
        period in prop_oneof![Just(500u32), 1u32..50, 1u32..=u32::MAX],
        rate_timeout in prop_oneof![Just(200u32), any::<u32>()],
        attitude_timeout in any::<u32>(),
        emit in any::<bool>(),
        lost in prop_oneof![Just(10_000u32), Just(0), any::<u32>()],
        north in any::<bool>(),
        boot in prop_oneof![Just(3000u32), any::<u32>()],
        start in any::<u32>(),
        events in prop::collection::vec(event(), 0..60),
    ) {
        let config = SimConfig {
            slew_dps: slew,
            postback_period_ms: NonZeroU32::new(period).unwrap(),
            gimbal_type: GimbalType::Unknown(9),
            rate_timeout_ms: rate_timeout,
            attitude_timeout_ms: attitude_timeout,
            emit_can_frames: emit,
            tracking_lost_ms: lost,
            lock_holds: if north { LockHolds::North } else { LockHolds::Motor },
            boot_ms: boot,
        };
        let mut sim: Simulator<7> = Simulator::with_tx_capacity(config, t(start));
        let mut now = t(start);
        for (i, (id, data, dt)) in events.into_iter().enumerate() {
            now = now.add_millis(dt);
            let _ = sim.receive(id, &data, now);
            if i % 3 == 0 {
                sim.set_silent(i % 9 == 0);
            }
            if i % 17 == 16 {
                sim.reboot(now);
            }
            if let Some(pb) = sim.poll(now) {
                prop_assert_eq!(pb, sim.postback());
            }
            if i % 2 == 0 && sim.pending_frames() >= 4 {
                let pb = pop_postback(&mut sim);
                prop_assert_eq!(pb.gimbal_type, GimbalType::Unknown(9));
            }
            prop_assert_eq!(sim.pending_frames() % 4, 0);
            let s = sim.state();
            prop_assert!((PITCH_TRAVEL_MIN_DEG..=PITCH_TRAVEL_MAX_DEG).contains(&s.pitch_deg));
            prop_assert!(s.motor_yaw_deg.abs() <= MOTOR_YAW_LIMIT_DEG);
            prop_assert!((0.0..360.0).contains(&s.heading_deg));
            prop_assert!((ZOOM_MIN..=OPTICAL_ZOOM_MAX).contains(&s.zoom_ratio));
            prop_assert!(s.rate.0.is_finite() && s.rate.1.is_finite());
            prop_assert!((0.0..=1.0).contains(&s.focus));
            prop_assert_eq!(s.tracking, s.tracking_box.is_some());
            prop_assert!(!(s.tracking && s.rate != (0.0, 0.0)));
            prop_assert!(sim.pending_frames() <= 7);
            let pb = sim.postback();
            prop_assert!(pb.heading < 36_000);
            prop_assert!((-11_000..=6_000).contains(&pb.pitch));
            prop_assert!((-17_000..=17_000).contains(&pb.motor_heading));
        }
        // Whatever is queued is whole postbacks.
        while sim.pending_frames() >= 4 {
            pop_postback(&mut sim);
        }
        prop_assert_eq!(sim.pending_frames(), 0);
    }
}
