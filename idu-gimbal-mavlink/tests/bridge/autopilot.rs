//! The autopilot the bridge follows: its heartbeat and system id, the configured ids and
//! periods, the first autopilot kept until silent, the information and acknowledgements it
//! is given, and the streams asked of it.

use super::*;

#[test]
fn heartbeats_at_1_hz_with_the_autopilots_system_id() {
    let mut b = fresh();
    let mut frames = Vec::new();
    for ms in 0..3_000 {
        if ms == 1_500 {
            b.receive_all(&frame(AP, 0, &heartbeat()), t(ms));
        }
        b.poll(t(ms));
        frames.extend(sent(&mut b));
    }
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

/// A configuration that would leave the bridge unaddressable is refused with what is wrong;
/// every other id is taken, the extremes included.
#[test]
fn a_zero_id_or_one_id_for_both_components_is_refused() {
    let with = |system_id: Option<u8>, gimbal: u8, camera: Option<u8>| BridgeConfig {
        system_id,
        gimbal_component: gimbal,
        camera: camera.map(|component| {
            let mut c = CameraConfig::new("rtsp://192.168.144.108:554/stream=0").unwrap();
            c.component = component;
            c
        }),
        ..BridgeConfig::default()
    };
    let refused = |config: BridgeConfig| config.check().err();
    assert_eq!(
        refused(with(Some(0), 154, Some(100))),
        Some(BridgeConfigError::SystemIdZero)
    );
    assert_eq!(
        refused(with(None, 0, None)),
        Some(BridgeConfigError::GimbalComponentZero)
    );
    assert_eq!(
        refused(with(None, 154, Some(0))),
        Some(BridgeConfigError::CameraComponentZero)
    );
    for id in [1, 100, 154, 255] {
        assert_eq!(
            refused(with(None, id, Some(id))),
            Some(BridgeConfigError::CameraComponentIsGimbals(id))
        );
    }
    for (system_id, gimbal, camera) in [
        (None, 154, None),
        (Some(1), 1, Some(255)),
        (Some(255), 255, Some(1)),
        (Some(7), 154, Some(155)),
    ] {
        let config = with(system_id, gimbal, camera);
        let checked = config.clone().check().unwrap();
        // Checked, not changed.
        assert_eq!(checked.get(), &config);
        let bridge = Bridge::new(checked);
        assert_eq!(bridge.system_id(), system_id.unwrap_or(1));
        assert_eq!(bridge.config(), &config);
    }
    // What each says: what is wrong and what is valid.
    assert_eq!(
        BridgeConfigError::SystemIdZero.to_string(),
        "system id 0 is the broadcast system: valid 1 to 255"
    );
    assert_eq!(
        BridgeConfigError::CameraComponentIsGimbals(154).to_string(),
        "camera component 154 is the gimbal device's: valid 1 to 255, other than 154"
    );
}

/// The times (ms after `start`, each poll 1 ms apart) at which `M` was sent in `polls`
/// polls.
fn sent_at<M>(b: &mut Firmware, start: u32, polls: u32) -> Vec<u32>
where
    M: mavio::mavspec::rust::spec::MessageSpecStatic
        + for<'a> TryFrom<&'a mavio::protocol::Payload, Error = mavio::error::SpecError>,
{
    (0..polls)
        .filter(|&i| {
            b.poll(t(start.wrapping_add(i)));
            !of::<M>(&sent(b)).is_empty()
        })
        .collect()
}

#[test]
fn configured_periods_hold_at_their_extremes_and_across_the_clocks_wrap() {
    let with = |heartbeat: Period, attitude_status: Option<Period>| {
        Firmware::new(
            Link::new(Config::default()),
            BridgeConfig {
                heartbeat,
                attitude_status,
                ..BridgeConfig::default()
            },
        )
    };
    let minute = Period::from_millis(Period::MAX_MS).unwrap();
    let ms = Period::MAX_MS;
    // The longest periods, from 70 s before the clock wraps: each message at once, then
    // exactly one period later, past the wrap.
    let start = 70_000u32.wrapping_neg();
    let mut b = with(minute, None);
    assert_eq!(
        sent_at::<Heartbeat>(&mut b, start, 125_000),
        [0, ms, 2 * ms]
    );
    let mut b = with(minute, Some(minute));
    assert_eq!(
        sent_at::<GimbalDeviceAttitudeStatus>(&mut b, start, 125_000),
        [0, ms, 2 * ms]
    );
    // The shortest: every poll; and a status not configured is not sent.
    let mut b = with(Period::from_millis(1).unwrap(), None);
    assert_eq!(sent_at::<Heartbeat>(&mut b, start, 5), [0, 1, 2, 3, 4]);
    assert!(sent_at::<GimbalDeviceAttitudeStatus>(&mut b, start, 2_000).is_empty());
}

/// The system id of the next gimbal heartbeat after `ms`.
fn system_id_after(b: &mut Firmware, ms: u32) -> u8 {
    for ms in ms..ms + 1_100 {
        b.poll(t(ms));
        if let Some(f) = sent(b).iter().find(|f| f.message_id() == 0) {
            return f.system_id();
        }
    }
    panic!("no heartbeat");
}

#[test]
fn the_first_autopilot_is_kept_until_it_falls_silent() {
    let mut b = fresh();
    let hb_at = |b: &mut Firmware, from: (u8, u8), ms: u32| {
        b.receive_all(&frame(from, 0, &heartbeat()), t(ms));
    };
    assert_eq!(b.system_id(), 1);
    hb_at(&mut b, AP, 0);
    assert_eq!(b.system_id(), AP.0);
    assert_eq!(system_id_after(&mut b, 0), AP.0);
    // Another autopilot, a forged heartbeat, system 0, or a component-1 heartbeat that says
    // it is no autopilot: the one followed is heard, so none moves the system id.
    hb_at(&mut b, (42, 1), 1_500);
    hb_at(&mut b, (0, 1), 1_600);
    let invalid = Heartbeat {
        autopilot: MavAutopilot::Invalid,
        ..heartbeat()
    };
    b.receive_all(&frame((43, 1), 0, &invalid), t(1_700));
    assert_eq!(system_id_after(&mut b, 1_800), AP.0);
    assert_eq!(b.stats().other_autopilots, 3);
    // The autopilot heard every second: system 42 keeps being ignored.
    for s in 2..10 {
        hb_at(&mut b, AP, s * 1_000);
        hb_at(&mut b, (42, 1), s * 1_000 + 500);
    }
    assert_eq!(system_id_after(&mut b, 10_000), AP.0);
    assert_eq!(b.stats().other_autopilots, 3 + 8);
    // Silent for AUTOPILOT_SILENCE_MS (last heard at 9 s): then another autopilot is taken.
    hb_at(&mut b, (42, 1), 9_000 + AUTOPILOT_SILENCE_MS - 1);
    assert_eq!(system_id_after(&mut b, 14_000), AP.0);
    hb_at(&mut b, (42, 1), 9_000 + AUTOPILOT_SILENCE_MS);
    assert_eq!(system_id_after(&mut b, 15_000), 42);
}

#[test]
fn no_autopilot_yet_and_a_heartbeat_of_system_0_or_of_no_autopilot_takes_nothing() {
    // Heard first, with no autopilot to keep: neither is one (system 0 is the broadcast
    // address; MAV_AUTOPILOT_INVALID says the sender is no autopilot).
    let mut b = fresh();
    b.receive_all(&frame((0, 1), 0, &heartbeat()), t(0));
    assert_eq!(system_id_after(&mut b, 0), 1);
    let invalid = Heartbeat {
        autopilot: MavAutopilot::Invalid,
        ..heartbeat()
    };
    b.receive_all(&frame((43, 1), 1, &invalid), t(1_200));
    assert_eq!(system_id_after(&mut b, 1_200), 1);
    assert_eq!(b.stats().other_autopilots, 2);
    // The real one is still taken at once.
    b.receive_all(&frame(AP, 0, &heartbeat()), t(2_400));
    assert_eq!(system_id_after(&mut b, 2_400), AP.0);
}

#[test]
fn a_configured_system_id_follows_only_its_own_autopilot() {
    let mut b = Firmware::new(
        Link::new(Config::default()),
        BridgeConfig {
            system_id: Some(9),
            ..BridgeConfig::default()
        },
    );
    b.receive_all(&frame(AP, 0, &heartbeat()), t(0));
    assert_eq!(system_id_after(&mut b, 0), 9);
    assert_eq!(b.stats().other_autopilots, 1);
    // System 9's autopilot is followed: its streams asked of it.
    b.receive_all(&frame((9, 1), 0, &heartbeat()), t(2_000));
    let asks = (2_000..3_000)
        .flat_map(|ms| {
            b.poll(t(ms));
            of::<CommandLong>(&sent(&mut b))
        })
        .filter(|c| c.command == MavCmd::SetMessageInterval)
        .map(|c| c.target_system)
        .collect::<Vec<_>>();
    assert!(!asks.is_empty() && asks.iter().all(|&s| s == 9), "{asks:?}");
}

#[test]
fn information_on_request_broadcast_or_addressed_and_an_ack_for_every_command() {
    let mut b = bridge();
    b.receive_all(&frame(AP, 0, &heartbeat()), t(0));
    let _ = sent(&mut b);
    // PX4 asks the broadcast component; ArduPilot the gimbal's.
    for (i, target) in [(AP.0, 0), (AP.0, 154), (0, 0)].into_iter().enumerate() {
        b.receive_all(
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
        // common.xml's GIMBAL_DEVICE_CAP_FLAGS: RETRACT 1, NEUTRAL 2, PITCH_AXIS 32,
        // PITCH_LOCK 128, YAW_AXIS 256, YAW_FOLLOW 512, YAW_LOCK 1024,
        // SUPPORTS_YAW_IN_EARTH_FRAME 4096; no roll axis, no infinite yaw, no RC inputs.
        assert_eq!(
            i.cap_flags.bits(),
            1 + 2 + 32 + 128 + 256 + 512 + 1024 + 4096
        );
        assert_eq!(i.gimbal_device_id, 0);
    }
    // Another component's request: not ours, no answer.
    b.receive_all(
        &frame(
            GCS,
            9,
            &command((AP.0, 100), MavCmd::RequestMessage, 283.0, 0.0),
        ),
        t(20),
    );
    assert!(sent(&mut b).is_empty());
    // A command the gimbal does not do, addressed to it: UNSUPPORTED, never silence.
    b.receive_all(
        &frame(GCS, 10, &command((AP.0, 154), MavCmd::DoSetMode, 1.0, 0.0)),
        t(30),
    );
    let acks: Vec<CommandAck> = of(&sent(&mut b));
    assert_eq!(acks.len(), 1);
    assert_eq!(acks[0].result, MavResult::Unsupported);
    // The same, broadcast: another component may own it; the gimbal stays quiet.
    b.receive_all(
        &frame(GCS, 11, &command((AP.0, 0), MavCmd::DoSetMode, 1.0, 0.0)),
        t(40),
    );
    assert!(of::<CommandAck>(&sent(&mut b)).is_empty());
    assert_eq!(b.stats().acks, 4);
}

#[test]
fn streams_are_asked_of_the_autopilot_until_they_come() {
    let mut b = fresh();
    let asks = |b: &mut Firmware, from: u32, to: u32| {
        let mut n = Vec::new();
        for ms in from..to {
            b.poll(t(ms));
            for c in of::<CommandLong>(&sent(b)) {
                assert_eq!(
                    (c.target_system, c.target_component, c.command),
                    (AP.0, AP.1, MavCmd::SetMessageInterval)
                );
                n.push((ms, c.param1 as u32, c.param2 as u32));
            }
        }
        n
    };
    assert!(asks(&mut b, 0, 100).is_empty(), "no autopilot yet");
    let px4 = Heartbeat {
        autopilot: MavAutopilot::Px4,
        ..heartbeat()
    };
    b.receive_all(&frame(AP, 0, &px4), t(100));
    // At once: the autopilot state at 20 Hz (PX4 streams it only in mode Gimbal), the
    // position at 5 Hz, and the setpoints at 20 Hz (once: PX4's Normal mode sends 5 Hz).
    // Then again after 5 s for the two that did not come.
    let a = asks(&mut b, 100, 6_000);
    assert_eq!(
        a,
        [
            (100, 286, 50_000),
            (100, 33, 200_000),
            (100, 284, 50_000),
            (5_100, 286, 50_000),
            (5_100, 33, 200_000)
        ]
    );
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
    b.receive_all(&frame(AP, 1, &pos), t(6_000));
    b.receive_all(&frame(AP, 2, &autopilot_state(10.0)), t(6_000));
    // Both keep coming: nothing asked.
    for s in 0..10u32 {
        let ms = 6_000 + s * 1_000;
        b.receive_all(&frame(AP, 3, &pos), t(ms));
        b.receive_all(&frame(AP, 4, &autopilot_state(10.0)), t(ms));
        assert!(asks(&mut b, ms, ms + 1_000).is_empty());
    }
    // The autopilot state stops (a rebooted autopilot forgets the intervals): asked again
    // 5 s after it was last heard (at 15 s), and every 5 s while it stays away, and the
    // setpoints with it (PX4 back at its 5 Hz).
    for s in 0..10u32 {
        let ms = 16_000 + s * 1_000;
        b.receive_all(&frame(AP, 5, &pos), t(ms));
        let a = asks(&mut b, ms, ms + 1_000);
        let expect: &[(u32, u32, u32)] = match ms {
            20_000 => &[(20_000, 286, 50_000), (20_000, 284, 50_000)],
            25_000 => &[(25_000, 286, 50_000), (25_000, 284, 50_000)],
            _ => &[],
        };
        assert_eq!(a, expect, "at {ms}");
    }
    // Back: nothing is asked again.
    for s in 0..10u32 {
        let ms = 26_000 + s * 1_000;
        b.receive_all(&frame(AP, 6, &pos), t(ms));
        b.receive_all(&frame(AP, 7, &autopilot_state(10.0)), t(ms));
        assert!(asks(&mut b, ms, ms + 1_000).is_empty(), "at {ms}");
    }
    // The core now holds and pushes the position, as the autopilot sent it.
    b.link.poll(t(35_200));
    let frames = queued_vehicle_frames(&mut b.link);
    assert!(
        frames.iter().any(|f| matches!(
            f,
            VehicleFrame::Gps(g) if (g.lat_e7(), g.lon_e7()) == (473_977_420, 85_455_940)
        )),
        "{frames:?}"
    );
}

#[test]
fn the_setpoints_are_not_asked_of_ardupilot() {
    // ArduPilot sends its setpoints at 50 Hz unasked; asked, it refuses and tells the
    // ground station. The other two streams are asked as of any autopilot.
    let mut b = fresh();
    b.receive_all(&frame(AP, 0, &heartbeat()), t(100));
    let mut asked = Vec::new();
    for ms in 100..6_000 {
        b.poll(t(ms));
        asked.extend(
            of::<CommandLong>(&sent(&mut b))
                .iter()
                .map(|c| c.param1 as u32),
        );
    }
    assert_eq!(asked, [286, 33, 286, 33]);
}
