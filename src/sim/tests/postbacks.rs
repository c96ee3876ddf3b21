//! Postbacks and the gimbal's life: the 500 ms grid as four frames, silence, reboots, the
//! stream mode, and a full transmit queue.

use super::*;

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
    point(&mut sim, -80.0, 300.0, t(0));
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
