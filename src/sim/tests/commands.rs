//! Every command's effect on the state, vehicle frames and texts stored, bad frames
//! counted, focus and calibration over time.

use super::*;

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
