//! Aims held against the simulated gimbal through the rig, on CAN and on the UART and with
//! both lock behaviours: through turns, lost commands, reboots, a gimbal that does not move,
//! the motor's limit, trackers, rate holds and ground targets.

use super::*;

#[test]
fn an_earth_yaw_is_held_through_a_90_degree_turn() {
    for wire in WIRES {
        for holds in BOTH {
            let mut rig = Rig::new(wire, holds);
            rig.vehicle_deg = 60.0;
            rig.run(200);
            rig.aim(earth(20.0), -30.0).unwrap();
            rig.run(3000);
            let what = format!("{wire:?}, lock holds {holds:?}");
            assert!(
                off(rig.earth_yaw(), 20.0) < SETTLED_DEG,
                "{what}: {}",
                rig.earth_yaw()
            );
            assert!((rig.state().pitch_deg + 30.0).abs() < 0.01, "{what}");
            let mut worst = 0.0f32;
            rig.turn(150.0, 30.0, |r| worst = worst.max(off(r.earth_yaw(), 20.0)));
            assert!(
                worst < turn_lag(30.0),
                "{what}: {worst}° off during the turn"
            );
            rig.run(1000);
            assert!(
                off(rig.earth_yaw(), 20.0) < SETTLED_DEG,
                "{what}: {}",
                rig.earth_yaw()
            );
            assert!(
                off(rig.motor(), -130.0) < SETTLED_DEG,
                "{what}: motor {}",
                rig.motor()
            );
            let state = rig.aim_state().unwrap();
            assert!(
                state.on_target && !state.not_reached && !state.at_yaw_limit,
                "{what}: {state:?} {:?}",
                rig.stats()
            );
            let given = Aim {
                yaw: earth(20.0),
                pitch: Pitch::new(-30.0).unwrap(),
            };
            assert_eq!(state.aim, given, "{what}");
        }
    }
}

#[test]
fn a_vehicle_yaw_turns_with_the_vehicle() {
    for wire in WIRES {
        for holds in BOTH {
            let mut rig = Rig::new(wire, holds);
            rig.vehicle_deg = 60.0;
            rig.run(200);
            rig.aim(vehicle(40.0), -10.0).unwrap();
            rig.run(3000);
            let what = format!("{wire:?}, lock holds {holds:?}");
            assert!(
                off(rig.motor(), 40.0) < SETTLED_DEG,
                "{what}: {}",
                rig.motor()
            );
            let mut worst = 0.0f32;
            rig.turn(150.0, 30.0, |r| worst = worst.max(off(r.motor(), 40.0)));
            assert!(
                worst < turn_lag(30.0),
                "{what}: {worst}° off during the turn"
            );
            rig.run(1000);
            assert!(
                off(rig.motor(), 40.0) < SETTLED_DEG,
                "{what}: {}",
                rig.motor()
            );
            assert!(off(rig.earth_yaw(), 190.0) < SETTLED_DEG, "{what}");
            let given = Aim {
                yaw: vehicle(40.0),
                pitch: Pitch::new(-10.0).unwrap(),
            };
            assert_eq!(rig.aim_state().unwrap().aim, given, "{what}");
        }
    }
}

#[test]
fn the_first_aim_with_the_first_attitude_lands_in_the_gimbals_reference() {
    // The aim and the first attitude in the same millisecond, as when an autopilot starts
    // both streams together: on CAN the aim goes out nose-referenced ahead of the attitude
    // frame (control first), then north-referenced once the attitude is there.
    for wire in WIRES {
        for holds in BOTH {
            let mut rig = Rig::new(wire, holds);
            rig.vehicle_deg = 30.0;
            rig.set_vehicle();
            rig.aim(vehicle(40.0), 0.0).unwrap();
            rig.run(2000);
            let what = format!("{wire:?}, lock holds {holds:?}");
            assert!(
                off(rig.motor(), 40.0) < SETTLED_DEG,
                "{what}: motor {}",
                rig.motor()
            );
            let firsts: Vec<u16> = rig.headings.iter().map(|(_, h)| h.deci()).collect();
            match wire {
                // 40 from the nose, then 70 from north once the gimbal has the attitude.
                Wire::Can => assert_eq!(firsts, [400, 700], "{what}"),
                Wire::Uart => assert_eq!(firsts, [400], "{what}"),
            }
        }
    }
}

#[test]
fn a_lost_command_is_sent_again_from_the_postbacks() {
    for wire in WIRES {
        for holds in BOTH {
            let mut rig = Rig::new(wire, holds);
            rig.vehicle_deg = 10.0;
            rig.run(500);
            // Every heading command of the aim lost on the way but the third.
            rig.drop_headings = 2;
            rig.aim(earth(100.0), -20.0).unwrap();
            rig.run(6000);
            let what = format!("{wire:?}, lock holds {holds:?}");
            assert!(
                off(rig.earth_yaw(), 100.0) < SETTLED_DEG,
                "{what}: {}",
                rig.earth_yaw()
            );
            // The aim, then one re-command from the postbacks, both lost; the second
            // re-command arrives, and is the only heading that does.
            let stats = rig.stats();
            assert_eq!(stats.aim_recommands, 2, "{what}: {stats:?}");
            assert_eq!(rig.headings.len(), 1, "{what}: {:?}", rig.headings);
            assert_eq!(stats.aim_not_reached, 0, "{what}");
        }
    }
}

#[test]
fn a_gimbal_that_reboots_mid_hold_is_brought_back() {
    for wire in WIRES {
        for holds in BOTH {
            let mut rig = Rig::new(wire, holds);
            rig.vehicle_deg = 45.0;
            rig.run(200);
            rig.aim(earth(300.0), -45.0).unwrap();
            rig.run(4000);
            let what = format!("{wire:?}, lock holds {holds:?}");
            assert!(off(rig.earth_yaw(), 300.0) < SETTLED_DEG, "{what}");
            rig.reboot();
            rig.run(100);
            assert_eq!(rig.motor(), 0.0, "{what}: at rest after the restart");
            // 3 s of start-up, the link down after 1.5 s and up at the first postback,
            // which the loop judges at once; then the slew (255°... at most 170° of motor
            // at 60°/s).
            rig.run(3000 + 500 + 100 + 3500);
            assert!(
                off(rig.earth_yaw(), 300.0) < SETTLED_DEG,
                "{what}: {}",
                rig.earth_yaw()
            );
            assert!((rig.state().pitch_deg + 45.0).abs() < 0.01, "{what}");
            assert!(rig.events.contains(&Event::LinkDown), "{what}");
        }
    }
}

#[test]
fn a_gimbal_that_does_not_move_is_tried_three_times_then_reported() {
    for wire in WIRES {
        // A gimbal that takes commands and never moves.
        let mut rig = Rig::with(
            wire,
            SimConfig {
                slew_dps: 0.0,
                ..SimConfig::default()
            },
        );
        rig.vehicle_deg = 0.0;
        rig.run(200);
        rig.aim(vehicle(90.0), 0.0).unwrap();
        rig.run(20_000);
        let stats = rig.stats();
        assert_eq!(
            (stats.aim_recommands, stats.aim_not_reached),
            (aim::ATTEMPTS.into(), 1),
            "{wire:?}"
        );
        // The first command, then one a postback apart for each attempt: nothing more in
        // 20 s.
        assert_eq!(
            rig.headings.len(),
            1 + usize::from(aim::ATTEMPTS),
            "{wire:?}"
        );
        assert_eq!(
            rig.events
                .iter()
                .filter(|e| **e == Event::AimNotReached)
                .count(),
            1
        );
        let state = rig.aim_state().unwrap();
        assert!(state.not_reached && !state.on_target, "{wire:?}");
        // A new aim is a new chance.
        rig.aim(vehicle(80.0), 0.0).unwrap();
        rig.run(100);
        assert!(!rig.aim_state().unwrap().not_reached);
        assert_eq!(rig.headings.len(), 2 + usize::from(aim::ATTEMPTS));
        rig.run(20_000);
        assert!(rig.aim_state().unwrap().not_reached, "{wire:?}");
        assert_eq!(rig.stats().aim_not_reached, 2, "{wire:?}");
        // So is the gimbal restarting: its first postback, no closer than the last one
        // before, is the first of the attempts again, which end as before.
        rig.reboot();
        rig.run(3000 + 500 + 100);
        assert!(!rig.aim_state().unwrap().not_reached, "{wire:?}");
        rig.run(20_000);
        let stats = rig.stats();
        assert_eq!(
            (stats.aim_recommands, stats.aim_not_reached),
            (3 * u32::from(aim::ATTEMPTS), 3),
            "{wire:?}"
        );
        assert_eq!(
            rig.headings.len(),
            2 + 3 * usize::from(aim::ATTEMPTS),
            "{wire:?}"
        );
    }
}

#[test]
fn a_yaw_beyond_the_motors_travel_stops_at_the_limit_reported_and_not_hammered() {
    for wire in WIRES {
        for holds in BOTH {
            let mut rig = Rig::new(wire, holds);
            rig.vehicle_deg = 0.0;
            rig.run(200);
            // North 175 with the vehicle at 0: the motor stops at 170.
            rig.aim(earth(175.0), 0.0).unwrap();
            rig.run(10_000);
            let what = format!("{wire:?}, lock holds {holds:?}");
            assert_eq!(rig.motor(), 170.0, "{what}");
            let state = rig.aim_state().unwrap();
            assert!(state.at_yaw_limit && state.on_target, "{what}: {state:?}");
            assert_eq!(rig.headings.len(), 1, "{what}");
            assert_eq!(rig.stats().aim_not_reached, 0, "{what}");
            // The vehicle turns right: in reach again.
            rig.turn(30.0, 30.0, |_| {});
            rig.run(3000);
            assert!(off(rig.earth_yaw(), 175.0) < SETTLED_DEG, "{what}");
            assert!(!rig.aim_state().unwrap().at_yaw_limit, "{what}");
            // The limit itself is in reach; a tenth of a degree past it is not.
            rig.aim(vehicle(170.0), 0.0).unwrap();
            rig.run(1000);
            assert!(!rig.aim_state().unwrap().at_yaw_limit, "{what}");
            rig.aim(vehicle(-170.1), 0.0).unwrap();
            rig.run(1000);
            assert!(rig.aim_state().unwrap().at_yaw_limit, "{what}");
        }
    }
}

#[test]
fn a_3_5x_gimbal_reaches_a_yaw_behind_the_vehicle() {
    let mut rig = Rig::with(
        Wire::Can,
        SimConfig {
            gimbal_type: GimbalType::Zoom3_5x,
            ..SimConfig::default()
        },
    );
    rig.run(1000);
    rig.aim(vehicle(175.0), 0.0).unwrap();
    rig.run(1000);
    // The simulator's motor stops at 170 whatever the model; the 3.5x's 325 travel means
    // the link takes 175 as in reach (no limit reported).
    assert!(!rig.aim_state().unwrap().at_yaw_limit);
}

#[test]
fn the_tracker_owns_the_gimbal_while_it_tracks() {
    for wire in WIRES {
        for holds in BOTH {
            let what = format!("{wire:?}, lock holds {holds:?}");
            let mut rig = Rig::new(wire, holds);
            rig.run(200);
            rig.aim(vehicle(0.0), 0.0).unwrap();
            rig.run(1000);
            // Stop tracking with no tracker running changes nothing: no command goes.
            let sent = rig.headings.len();
            rig.send(GimbalCommand::StopTracking);
            rig.run(500);
            assert_eq!(rig.headings.len(), sent, "{what}");
            assert_eq!(rig.stats().aim_recommands, 0, "{what}");
            // Track a target right of the centre: the gimbal turns toward it. Started twice
            // (a ground station repeating itself), the tracker still owns the gimbal.
            let centre = ImagePoint::new(6000, 4096).unwrap();
            let track = TrackingBox::new(centre, 256.0, 256.0).unwrap();
            rig.send(GimbalCommand::StartTracking(track));
            rig.send(GimbalCommand::StartTracking(track));
            // The same aim again (a setpoint stream), and the vehicle turns.
            rig.aim(vehicle(0.0), 0.0).unwrap();
            rig.turn(20.0, 30.0, |_| {});
            rig.run(3000);
            rig.assert_tracker_owns(sent, &what);
            // The target, 15° right of the nose when tracking began, is 5° left of it once
            // the vehicle has turned 20° right: the tracker turned the gimbal there, on CAN,
            // where the simulated gimbal sees the vehicle turn (on the UART it cannot).
            let tracked = if wire == Wire::Can { -5.0 } else { 15.0 };
            assert!(off(rig.motor(), tracked) < 0.1, "{what}: {}", rig.motor());
            // Tracking stops: the aim takes the gimbal back.
            rig.send(GimbalCommand::StopTracking);
            rig.run(3000);
            assert!(!rig.aim_state().unwrap().yielded_to_tracker, "{what}");
            assert!(
                off(rig.motor(), 0.0) < SETTLED_DEG,
                "{what}: {}",
                rig.motor()
            );
            // A target lost lets go too.
            rig.send(GimbalCommand::StartTracking(track));
            rig.run(12_000);
            assert_eq!(rig.state().targets_lost, 1, "{what}");
            assert!(
                off(rig.motor(), 0.0) < SETTLED_DEG,
                "{what}: {}",
                rig.motor()
            );
            // Stopped before any postback showed it tracking: the aim is back at once.
            rig.send(GimbalCommand::StartTracking(track));
            assert!(rig.aim_state().unwrap().yielded_to_tracker, "{what}");
            rig.send(GimbalCommand::StopTracking);
            assert!(!rig.aim_state().unwrap().yielded_to_tracker, "{what}");
            rig.run(1000);
            // And a new aim takes the gimbal from the tracker, at once.
            rig.send(GimbalCommand::StartTracking(track));
            rig.run(1000);
            assert!(rig.aim_state().unwrap().yielded_to_tracker, "{what}");
            rig.aim(vehicle(10.0), 0.0).unwrap();
            assert!(!rig.aim_state().unwrap().yielded_to_tracker, "{what}");
            rig.run(1000);
            assert!(!rig.state().tracking, "{what}");
            assert!(
                off(rig.motor(), 10.0) < SETTLED_DEG,
                "{what}: {}",
                rig.motor()
            );
        }
    }
}

#[test]
fn an_aim_ends_a_rate_hold_and_a_rate_hold_that_ended_elsewhere_is_corrected() {
    for wire in WIRES {
        for holds in BOTH {
            let mut rig = Rig::new(wire, holds);
            rig.run(200);
            rig.aim(vehicle(0.0), 0.0).unwrap();
            rig.run(2000);
            // Someone else's rate hold moves the gimbal 20° (as a joystick on the gimbal's
            // own remote would), then stops.
            let rate = GimbalCommand::Rate(Rate::new(20.0, 0.0).unwrap());
            for _ in 0..10 {
                match wire {
                    Wire::Can => {
                        let f = Command::from(rate).to_frame();
                        let _ = rig.can_sim.receive(f.id, &f.data, rig.instant());
                    }
                    Wire::Uart => {
                        let frame =
                            idu_gimbal::wire::serial::control_frame(&Command::from(rate).encode());
                        rig.uart_sim.receive(&frame, rig.instant());
                    }
                }
                rig.run(100);
            }
            rig.run(300);
            let what = format!("{wire:?}, lock holds {holds:?}");
            assert!(rig.motor().abs() > 15.0, "{what}: {}", rig.motor());
            // The loop finds the gimbal off and not coming back: it sends the aim again.
            rig.run(3000);
            assert!(
                off(rig.motor(), 0.0) < SETTLED_DEG,
                "{what}: {}",
                rig.motor()
            );
        }
    }
}

#[test]
fn point_at_holds_a_ground_target_while_the_vehicle_turns_in_place() {
    // Hovering 100 m up, 200 m south of the target: the bearing is north whatever the
    // vehicle's heading. The vehicle turns through 180°.
    let target = Position::new(47.0018, 8.0, 400.0).unwrap();
    let here = Position::new(47.0, 8.0, 500.0).unwrap();
    let truth = look_at(&here, &target).unwrap();
    let (bearing, elevation) = (truth.bearing_deg as f32, truth.elevation_deg as f32);
    for wire in WIRES {
        for holds in BOTH {
            let what = format!("{wire:?}, lock holds {holds:?}");
            let mut rig = Rig::new(wire, holds);
            rig.position = Some((Gps::new(47.0, 8.0).unwrap(), Altitude::new(500.0).unwrap()));
            rig.vehicle_deg = -90.0;
            rig.run(100);
            match wire {
                Wire::Can => rig.can.point_at(target),
                Wire::Uart => rig.uart.point_at(target),
            }
            rig.run(3000);
            assert!(
                off(rig.earth_yaw(), bearing) < SETTLED_DEG,
                "{what}: {}",
                rig.earth_yaw()
            );
            let mut worst = 0.0f32;
            rig.turn(90.0, 30.0, |r| {
                worst = worst.max(off(r.earth_yaw(), bearing))
            });
            assert!(worst < turn_lag(30.0), "{what}: {worst}");
            rig.run(2000);
            assert!(
                off(rig.earth_yaw(), bearing) < SETTLED_DEG,
                "{what}: {}",
                rig.earth_yaw()
            );
            // The pitch command's 0.1°, and the postback's 0.01°.
            assert!((rig.state().pitch_deg - elevation).abs() < 0.06, "{what}");
            assert!(rig.aim_state().unwrap().aim.yaw.is_earth());
        }
    }
}

#[test]
fn a_point_at_moving_with_the_vehicle_leaves_the_gimbal_to_a_tracker_started_through_the_link() {
    // 200 m south of the target, then flying 100 m east in 3 s: the bearing turns from
    // north to about 26.6° west of it, far past the dead-band.
    let target = Position::new(47.0018, 8.0, 400.0).unwrap();
    let east = 8.0 + 100.0 / (111_320.0 * 47.0f64.to_radians().cos());
    for wire in WIRES {
        let what = format!("{wire:?}");
        let mut rig = Rig::new(wire, LockHolds::North);
        rig.position = Some((Gps::new(47.0, 8.0).unwrap(), Altitude::new(500.0).unwrap()));
        rig.run(100);
        match wire {
            Wire::Can => rig.can.point_at(target),
            Wire::Uart => rig.uart.point_at(target),
        }
        rig.run(3000);
        let sent = rig.headings.len();
        let centre = ImagePoint::new(4096, 4096).unwrap();
        rig.send(GimbalCommand::StartTracking(
            TrackingBox::new(centre, 256.0, 256.0).unwrap(),
        ));
        for ms in 1..=3000u32 {
            let lon = 8.0 + (east - 8.0) * f64::from(ms) / 3000.0;
            rig.position = Some((Gps::new(47.0, lon).unwrap(), Altitude::new(500.0).unwrap()));
            rig.tick();
        }
        rig.assert_tracker_owns(sent, &what);
        // The tracker stopped: the aim at the target from where the vehicle is now.
        rig.send(GimbalCommand::StopTracking);
        rig.run(3000);
        let here = Position::new(47.0, east, 500.0).unwrap();
        let bearing = wrap(look_at(&here, &target).unwrap().bearing_deg as f32);
        assert!(bearing < -26.0 && bearing > -27.0, "{bearing}");
        assert!(
            off(rig.earth_yaw(), bearing) < SETTLED_DEG,
            "{what}: {} against {bearing}",
            rig.earth_yaw()
        );
    }
}

#[test]
fn a_point_at_re_aims_only_past_the_dead_band() {
    // 200 m south of the target, 100 m above it: moving 0.45 m east turns the bearing by
    // 0.13° (within the 0.2° dead-band: nothing re-sent), 1.5 m by 0.43° (re-aimed).
    let target = Position::new(47.0018, 8.0, 400.0).unwrap();
    let metre_east = 1.0 / (111_320.0 * 47.0f64.to_radians().cos());
    let at = |east_m: f64| {
        (
            Gps::new(47.0, 8.0 + east_m * metre_east).unwrap(),
            Altitude::new(500.0).unwrap(),
        )
    };
    let mut rig = Rig::new(Wire::Can, LockHolds::North);
    rig.position = Some(at(0.0));
    rig.run(100);
    rig.can.point_at(target);
    rig.run(3000);
    let sent = rig.headings.len();
    rig.position = Some(at(0.45));
    rig.run(2000);
    assert_eq!(rig.headings.len(), sent, "0.13°: within the dead-band");
    rig.position = Some(at(1.5));
    rig.run(2000);
    assert_eq!(rig.headings.len(), sent + 1, "0.43°: past it");
}
