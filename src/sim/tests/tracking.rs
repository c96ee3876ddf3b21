//! Tracking and optics: the box followed to the centre, the field of view by zoom, tracking
//! lost and ended, a vehicle's turn made up for, directions outside the image.

use super::*;

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
