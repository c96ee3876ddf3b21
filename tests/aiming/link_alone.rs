//! The link's aiming decisions alone, no gimbal: its postbacks given by hand, its heading
//! commands read off its queue (an earth yaw without a fresh heading, the dead band,
//! getting closer, a tracker started through the link, room in the queue, and point-at's
//! position, altitude and first aim).

use super::*;

#[test]
fn an_earth_yaw_without_a_fresh_vehicle_heading_is_refused() {
    let mut link = alone();
    let now = Instant::from_millis(5000);
    assert_eq!(
        link.aim(level(earth(10.0)), now),
        Err(AimError::NoVehicleHeading)
    );
    assert_eq!(link.aim_state(), None);
    link.set_attitude(
        Attitude::new(0.0, 0.0, 5.0).unwrap(),
        Instant::from_millis(3000),
    );
    assert_eq!(
        link.aim(level(earth(10.0)), now),
        Err(AimError::NoVehicleHeading),
        "stale (2 s old)"
    );
    // A vehicle yaw needs no heading on a nose-referenced gimbal.
    assert_eq!(link.aim(level(vehicle(10.0)), now), Ok(()));
}

#[test]
fn an_earth_yaw_waits_for_the_vehicle_heading_while_it_is_stale() {
    // The link alone: the aim's state as the attitude goes stale and comes back.
    let mut link = alone();
    link.set_attitude(Attitude::new(0.0, 0.0, 30.0).unwrap(), at(0));
    link.aim(level(earth(100.0)), at(0)).unwrap();
    // Nose-referenced (no attitude has reached the gimbal yet when the aim went): 100 - 30.
    assert_eq!(poll_headings(&mut link, 0), [700]);
    assert!(!link.aim_state().unwrap().waiting_for_heading);
    // No attitude since 0: stale past 1,000 ms (the default `vehicle_stale_ms`).
    for ms in (50..=1500).step_by(50) {
        poll_headings(&mut link, ms);
    }
    assert!(link.aim_state().unwrap().waiting_for_heading);
    link.set_attitude(Attitude::new(0.0, 0.0, 40.0).unwrap(), at(1510));
    for ms in (1510..=1600).step_by(10) {
        poll_headings(&mut link, ms);
    }
    assert!(!link.aim_state().unwrap().waiting_for_heading);
}

/// Polls the link alone at `ms`, every frame taken: the heading commands among them, 0.1°.
fn poll_headings(link: &mut Link, ms: u32) -> Vec<u16> {
    link.poll(Instant::from_millis(ms));
    let mut headings = Vec::new();
    while let Some(f) = link.next_transmit() {
        link.transmit_done(None);
        if let Ok(Command::Gimbal(GimbalCommand::Heading(h))) = Command::decode(&f.data) {
            headings.push(h.deci());
        }
    }
    headings
}

#[test]
fn getting_closer_means_by_more_than_the_tolerance() {
    // The link alone, its postbacks made here: a vehicle yaw of 10° (motor 1,000 in
    // 0.01°), the default tolerance 0.5° (50) and loop period 50 ms. The first postback
    // after the command is not judged (it may predate any movement); each later one is,
    // against the one before: an error that shrank by more than the tolerance is getting
    // closer; one that shrank by the tolerance or less is an attempt (a re-command).
    for (second_motor, recommands) in [(51, 0), (50, 1)] {
        let mut link = alone();
        postback(&mut link, 0, false, at(0));
        link.aim(level(vehicle(10.0)), at(0)).unwrap();
        assert_eq!(poll_headings(&mut link, 0), [100]);
        // Error 1,000 (not judged), then 1,000 - motor.
        postback(&mut link, 0, false, at(10));
        poll_headings(&mut link, 50);
        postback(&mut link, second_motor, false, at(60));
        poll_headings(&mut link, 100);
        poll_headings(&mut link, 150);
        assert_eq!(
            link.stats().aim_recommands,
            recommands,
            "motor {second_motor}"
        );
    }
}

#[test]
fn an_aim_within_the_dead_band_of_the_one_held_changes_nothing() {
    // The link alone; the default dead-band is 0.2° (`aim_deadband_mdeg` 200): an aim that
    // far from the one held on each axis is the same aim (a setpoint stream re-sending
    // it), a tenth of a degree more is a new one, commanded at once.
    let mut link = alone();
    let aim = |yaw: f32, pitch: f32| Aim {
        yaw: vehicle(yaw),
        pitch: Pitch::new(pitch).unwrap(),
    };
    let now = Instant::from_millis(0);
    link.aim(aim(10.0, -10.0), now).unwrap();
    assert_eq!(poll_headings(&mut link, 0), [100]);
    assert!(!link.holds_earth_yaw());
    for (yaw, pitch, new) in [
        (10.2, -10.0, false),
        (9.8, -10.0, false),
        (10.0, -10.2, false),
        (10.0, -9.8, false),
        (10.3, -10.0, true),
        (10.3, -10.3, true),
    ] {
        link.aim(aim(yaw, pitch), now).unwrap();
        assert_eq!(link.has_transmit(), new, "{yaw} {pitch}");
        poll_headings(&mut link, 0);
        let held = link.aim_state().unwrap().aim;
        let expected = if new { aim(yaw, pitch) } else { held };
        assert_eq!(held, expected, "{yaw} {pitch}");
    }
    // The frame is part of the aim: the same angle from north is a new aim, held in the
    // earth frame.
    link.set_attitude(Attitude::new(0.0, 0.0, 0.0).unwrap(), now);
    link.aim(
        Aim {
            yaw: earth(10.3),
            pitch: Pitch::new(-10.3).unwrap(),
        },
        now,
    )
    .unwrap();
    assert!(link.has_transmit());
    assert!(link.holds_earth_yaw());
    link.stop_aiming();
    assert!(!link.holds_earth_yaw());
    assert_eq!(link.aim_state(), None);
}

/// A postback of the gimbal holding its angle (lock mode), its motor at `motor_cdeg`, its
/// tracker tracking or not.
fn postback(link: &mut Link, motor_cdeg: i16, tracking: bool, now: Instant) {
    let p = Postback {
        mode: ControlMode::Lock,
        motor_heading: motor_cdeg,
        tracking,
        ..Postback::default()
    };
    for d in p.to_can_frames() {
        link.receive(ids::POSTBACK, &d, now);
    }
}

#[test]
fn a_tracker_started_through_the_link_owns_the_gimbal_until_its_postbacks_let_go() {
    // The link alone, the postbacks made here (the gimbal's motor stays at 0, 10° off the
    // aim, all along: the tracker holds it elsewhere).
    let mut link = alone();
    postback(&mut link, 0, false, at(0));
    link.aim(level(vehicle(10.0)), at(0)).unwrap();
    assert_eq!(poll_headings(&mut link, 0), [100]);
    let track = TrackingBox::new(ImagePoint::new(4096, 4096).unwrap(), 256.0, 256.0).unwrap();
    link.send(GimbalCommand::StartTracking(track)).unwrap();
    // Yielded, and nothing else about the aim changed.
    let state = link.aim_state().unwrap();
    assert!(
        state.yielded_to_tracker && !state.waiting_for_heading,
        "{state:?}"
    );
    poll_headings(&mut link, 0);
    // The first postback after the start may not say it tracks yet: still the tracker's.
    postback(&mut link, 0, false, at(10));
    assert_eq!(poll_headings(&mut link, 50), []);
    assert!(link.aim_state().unwrap().yielded_to_tracker);
    // It tracks for a while, the gimbal far off the aim: nothing is sent, nothing judged
    // (no attempt counted, nothing "not reached").
    for look in 2..10u32 {
        postback(&mut link, 0, true, at(look * 50 - 40));
        assert_eq!(poll_headings(&mut link, look * 50), [], "look {look}");
    }
    let state = link.aim_state().unwrap();
    assert!(state.yielded_to_tracker && !state.not_reached, "{state:?}");
    assert_eq!(link.stats().aim_not_reached, 0);
    assert_eq!(link.stats().aim_recommands, 0);
    // It lets go (target lost): the aim is sent again at the next look.
    postback(&mut link, 0, false, at(510));
    assert_eq!(poll_headings(&mut link, 550), [100]);
    assert!(!link.aim_state().unwrap().yielded_to_tracker);
    assert_eq!(link.stats().aim_recommands, 1);
}

#[test]
fn a_turn_within_the_dead_band_re_sends_nothing_and_one_past_it_re_sends_the_aim() {
    // The link alone, north-referenced (the attitude pushed): a vehicle yaw's command is
    // the yaw plus the vehicle's heading, so a turn must re-send it; a turn within the
    // dead-band (0.2°) need not.
    let mut link = aiming_north_referenced();
    // The gimbal is there (motor 10°): on target.
    postback(&mut link, 1000, false, at(10));
    poll_headings(&mut link, 50);
    assert!(link.aim_state().unwrap().on_target);
    let mut sent = Vec::new();
    // 0.1°, then exactly the dead-band: nothing.
    for (deg, from) in [(0.1, 60), (0.2, 610)] {
        for ms in (from..from + 550).step_by(10) {
            set_heading(&mut link, deg, ms);
            sent.extend(poll_headings(&mut link, ms));
        }
        assert_eq!(sent, [], "{deg}° of turn");
    }
    assert!(link.aim_state().unwrap().on_target);
    for ms in (1160..=1600).step_by(10) {
        set_heading(&mut link, 0.3, ms);
        sent.extend(poll_headings(&mut link, ms));
    }
    assert_eq!(sent, [103], "0.3° of turn");
    // Re-commanded: not on target until a postback says so.
    assert!(!link.aim_state().unwrap().on_target);
    assert_eq!(link.stats().aim_recommands, 1);
}

#[test]
fn an_aim_waiting_for_room_is_not_judged_before_it_is_sent() {
    // The link alone, its command queue (8) left with one slot: the aim's two commands wait
    // while postbacks (the gimbal far off the aim) come in at every look.
    let mut link = alone();
    for _ in 0..7 {
        link.send(GimbalCommand::Zoom(idu_gimbal::wire::control::Zoom::Stop))
            .unwrap();
    }
    link.aim(level(vehicle(10.0)), at(0)).unwrap();
    for look in 1..10u32 {
        postback(&mut link, 0, false, at(look * 50 - 40));
        link.poll(at(look * 50));
    }
    let state = link.aim_state().unwrap();
    assert!(!state.not_reached && !state.on_target, "{state:?}");
    assert_eq!(link.stats().aim_not_reached, 0);
    // Room again: the aim goes, as a first command (not a re-command).
    let mut headings = Vec::new();
    while let Some(f) = link.next_transmit() {
        link.transmit_done(None);
        if let Ok(Command::Gimbal(GimbalCommand::Heading(h))) = Command::decode(&f.data) {
            headings.push(h.deci());
        }
    }
    assert_eq!(headings, []);
    assert_eq!(poll_headings(&mut link, 500), [100]);
    assert_eq!(link.stats().aim_recommands, 0);
}

/// The link alone (no gimbal: the tests give its postbacks by hand), default configuration.
fn alone() -> Link {
    Link::new(Config::default())
}

/// The instant `ms` milliseconds from the start.
fn at(ms: u32) -> Instant {
    Instant::from_millis(ms)
}

#[test]
fn a_turn_and_an_off_postback_at_the_same_look_re_send_the_aim_at_that_look() {
    // The link alone, north-referenced, polled every 10 ms; the attitude is pushed every
    // 100 ms and the loop looks every 50. Two reasons to re-send at the 150 ms look: the
    // attitude frame taken at 100 ms carries a 0.3° turn, and the postback of 110 ms is off
    // the aim and no closer than the one before. One command goes, at that look.
    let mut link = aiming_north_referenced();
    let mut sent = Vec::new();
    for ms in (10..=300).step_by(10) {
        set_heading(&mut link, if ms < 95 { 0.0 } else { 0.3 }, ms);
        match ms {
            // On target, then 1° off.
            10 => postback(&mut link, 1000, false, at(ms)),
            110 => postback(&mut link, 900, false, at(ms)),
            _ => {}
        }
        sent.extend(poll_headings(&mut link, ms).into_iter().map(|h| (ms, h)));
    }
    assert_eq!(sent, [(150, 103)]);
}

#[test]
fn a_point_at_waits_for_both_the_position_and_the_altitude() {
    // The link alone: with only one of the two fresh, no aim is computed (it would take the
    // other from nothing); with both, the aim goes.
    let target = Position::new(47.0018, 8.0, 400.0).unwrap();
    let gps = Gps::new(47.0, 8.0).unwrap();
    let altitude = Altitude::new(500.0).unwrap();
    for gps_first in [true, false] {
        let mut link = alone();
        link.point_at(target);
        // A ground target is fixed in the earth frame, aim or not yet.
        assert!(link.holds_earth_yaw());
        let mut sent = Vec::new();
        for ms in (0..=1000).step_by(10) {
            link.set_attitude(Attitude::new(0.0, 0.0, 0.0).unwrap(), at(ms));
            if gps_first {
                link.set_gps(gps, at(ms));
            } else {
                link.set_altitude(altitude, at(ms));
            }
            sent.extend(poll_headings(&mut link, ms));
        }
        assert_eq!(sent, [], "gps first: {gps_first}");
        assert_eq!(link.aim_state(), None);
        link.set_gps(gps, at(1010));
        link.set_altitude(altitude, at(1010));
        for ms in (1010..=1200).step_by(10) {
            sent.extend(poll_headings(&mut link, ms));
        }
        // Due north of the vehicle, its heading 0: a heading command of 0.
        assert_eq!(sent, [0], "gps first: {gps_first}");
    }
}

#[test]
fn a_point_at_that_cannot_send_its_first_aim_sends_it_when_it_can_wherever_the_clock_is() {
    // The link alone, at a clock near 0 and at one more than 2^31 ms past 0 (a firmware's
    // clock may start anywhere, and runs past 2^31 ms after 24.8 days): the first aim is
    // computed but cannot go, once for want of the vehicle's heading (no attitude yet, the
    // gimbal nose-referenced), once for want of room in the queue. It goes at the first
    // look that can send it: within one point-at period (100 ms) of the heading, or at the
    // first poll after the queue drains.
    let target = Position::new(47.0018, 8.0, 400.0).unwrap();
    let gps = Gps::new(47.0, 8.0).unwrap();
    let altitude = Altitude::new(500.0).unwrap();
    for base in [1_000u32, 3_000_000_000] {
        let ms = |offset: u32| base.wrapping_add(offset);

        // No heading yet.
        let mut link = alone();
        link.point_at(target);
        link.set_gps(gps, at(ms(0)));
        link.set_altitude(altitude, at(ms(0)));
        assert_eq!(poll_headings(&mut link, ms(0)), [], "base {base}");
        assert!(link.aim_state().unwrap().waiting_for_heading, "base {base}");
        let mut sent = Vec::new();
        for offset in (10..=200).step_by(10) {
            set_heading(&mut link, 0.0, ms(offset));
            link.set_gps(gps, at(ms(offset)));
            link.set_altitude(altitude, at(ms(offset)));
            sent.extend(
                poll_headings(&mut link, ms(offset))
                    .into_iter()
                    .map(|h| (offset, h)),
            );
        }
        // Due north of the vehicle, its heading 0: a heading command of 0, at the look
        // 100 ms after the first.
        assert_eq!(sent, [(100, 0)], "base {base}");

        // No room in the queue.
        let mut link = alone();
        set_heading(&mut link, 0.0, ms(0));
        link.set_gps(gps, at(ms(0)));
        link.set_altitude(altitude, at(ms(0)));
        poll_headings(&mut link, ms(0));
        while link.send(GimbalCommand::LookDown).is_ok() {}
        link.point_at(target);
        let full = link.stats().queue_full;
        link.poll(at(ms(10)));
        assert!(link.stats().queue_full > full, "base {base}");
        let mut sent = poll_headings(&mut link, ms(20));
        sent.extend(poll_headings(&mut link, ms(30)));
        assert_eq!(sent, [0], "base {base}");
    }
}

#[test]
fn a_point_at_with_no_bearing_or_beyond_the_geodesys_altitude_sends_nothing() {
    // The target at the vehicle (no bearing), and a vehicle above ALT_MAX_M: no aim, no
    // command, whatever is fresh; a target 200 m north then aims at once.
    let gps = Gps::new(47.0, 8.0).unwrap();
    for (what, target, altitude) in [
        (
            "target at the vehicle",
            Position::new(47.0, 8.0, 500.0).unwrap(),
            Altitude::new(500.0).unwrap(),
        ),
        (
            "vehicle above the geodesy's range",
            Position::new(47.0018, 8.0, 400.0).unwrap(),
            Altitude::from_cm(10_000_001),
        ),
    ] {
        let mut link = alone();
        link.point_at(target);
        let mut sent = Vec::new();
        for ms in (0..=1000).step_by(10) {
            set_heading(&mut link, 0.0, ms);
            link.set_gps(gps, at(ms));
            link.set_altitude(altitude, at(ms));
            sent.extend(poll_headings(&mut link, ms));
        }
        assert_eq!(sent, [], "{what}");
        assert_eq!(link.aim_state(), None, "{what}");
        link.point_at(Position::new(47.0018, 8.0, 400.0).unwrap());
        link.set_altitude(Altitude::new(500.0).unwrap(), at(1010));
        assert_eq!(poll_headings(&mut link, 1010), [0], "{what}");
    }
}

/// The vehicle's heading `deg` from north, measured at `ms`, level.
fn set_heading(link: &mut Link, deg: f32, ms: u32) {
    link.set_attitude(Attitude::new(0.0, 0.0, deg).unwrap(), at(ms));
}

/// The link alone, north-referenced (an attitude of heading 0 pushed at 0 ms), holding a
/// vehicle yaw of 10°: its command, 10° from north, sent at 0 ms.
fn aiming_north_referenced() -> Link {
    let mut link = alone();
    set_heading(&mut link, 0.0, 0);
    poll_headings(&mut link, 0);
    assert!(link.north_referenced(at(0)));
    link.aim(level(vehicle(10.0)), at(0)).unwrap();
    assert_eq!(poll_headings(&mut link, 0), [100]);
    link
}
