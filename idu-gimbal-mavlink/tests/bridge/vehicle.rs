//! The vehicle's state from the followed autopilot: attitude and heading to the gimbal,
//! updates it cannot use counted, other vehicles' states and positions not taken.

use super::*;

/// The quaternion (w, x, y, z) of the 3-2-1 rotation: yaw about z, then pitch about y, then
/// roll about x (common.xml's vehicle attitude), from the half angles' products.
fn quaternion_321(roll_deg: f32, pitch_deg: f32, yaw_deg: f32) -> [f32; 4] {
    let (sr, cr) = (roll_deg.to_radians() / 2.0).sin_cos();
    let (sp, cp) = (pitch_deg.to_radians() / 2.0).sin_cos();
    let (sy, cy) = (yaw_deg.to_radians() / 2.0).sin_cos();
    [
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    ]
}

#[test]
fn the_vehicles_roll_pitch_and_heading_from_autopilot_state_reach_the_gimbal() {
    let mut b = fresh();
    b.receive_all(&frame(AP, 0, &heartbeat()), t(0));
    // Whole degrees: f32 trigonometry is good to about 1e-3° here (1e-5° near ±85° pitch
    // where asin's slope is 11), far from the 0.005° at which the wire's 0.01° rounds, so
    // the centidegrees are exact.
    for (i, (roll, pitch, yaw)) in [
        (10, -20, 30),
        (-35, 15, -120),
        (170, 5, 179),
        (-170, -5, -179),
        (0, 80, 45),
        (-5, -85, -170),
        (25, 0, 0),
        (0, 0, 90),
    ]
    .into_iter()
    .enumerate()
    {
        let state = AutopilotStateForGimbalDevice {
            target_system: AP.0,
            target_component: 154,
            q: quaternion_321(roll as f32, pitch as f32, yaw as f32),
            angular_velocity_z: f32::NAN,
            ..Default::default()
        };
        let ms = 100 * (i as u32 + 1);
        b.receive_all(&frame(AP, i as u8, &state), t(ms));
        let a = b.link.attitude().expect("an attitude");
        assert_eq!(
            (a.roll_centideg(), a.pitch_centideg(), a.heading_centideg()),
            (roll * 100, pitch * 100, yaw * 100),
            "roll {roll}, pitch {pitch}, yaw {yaw}"
        );
    }
}

/// A vehicle facing south: the wire's heading is in [−180°, 180°), so 180° is sent as
/// −180.00°, and so is any yaw that rounds to it (the wire's 0.01°), not one step short.
#[test]
fn a_vehicle_facing_south_is_sent_at_minus_180_degrees() {
    let mut b = fresh();
    b.receive_all(&frame(AP, 0, &heartbeat()), t(0));
    // [0, 0, 0, 1]: yaw exactly π. 179.996°: f32 trigonometry is good to about 1e-3° here,
    // so it rounds to 180.00° on the wire, as 179.994° (kept) rounds to 179.99°.
    for (i, (q, heading)) in [
        ([0.0, 0.0, 0.0, 1.0], -18000),
        (quaternion_321(0.0, 0.0, 179.996), -18000),
        (quaternion_321(0.0, 0.0, 179.994), 17999),
        (quaternion_321(0.0, 0.0, -179.996), -18000),
    ]
    .into_iter()
    .enumerate()
    {
        let state = AutopilotStateForGimbalDevice {
            target_system: AP.0,
            target_component: 154,
            q,
            angular_velocity_z: f32::NAN,
            ..Default::default()
        };
        b.receive_all(&frame(AP, i as u8, &state), t(100 * (i as u32 + 1)));
        let a = b.link.attitude().expect("an attitude");
        assert_eq!(a.heading_centideg(), heading, "{q:?}");
    }
}

/// A vehicle update the bridge cannot use is counted, never dropped without a word: a
/// quaternion with a NaN, one whose components overflow the arithmetic (1e20 each: their
/// products are infinite, and ∞ − ∞ is NaN), a latitude beyond ±90°. What the link held
/// stays as it was; the position's altitude is still passed on.
#[test]
fn vehicle_updates_the_bridge_cannot_use_are_counted() {
    let mut b = fresh();
    b.receive_all(&frame(AP, 0, &heartbeat()), t(0));
    b.receive_all(&frame(AP, 1, &autopilot_state(30.0)), t(10));
    let held = b.link.attitude().expect("an attitude");
    let before = b.stats();
    assert_eq!(
        (before.vehicle_updates, before.refused_vehicle_updates),
        (1, 0)
    );
    for (i, q) in [[f32::NAN, 0.0, 0.0, 1.0], [1e20; 4]]
        .into_iter()
        .enumerate()
    {
        let mut state = autopilot_state(90.0);
        state.q = q;
        b.receive_all(&frame(AP, 2 + i as u8, &state), t(20));
        assert_eq!(b.link.attitude(), Some(held), "{q:?}");
        // Nor is its yaw taken as the vehicle's (1e20 each gives a finite 135°): the
        // status's delta_yaw is still 30° (f32 quaternion to yaw and back: within 1e-3°).
        let _ = sent(&mut b);
        let c = command((0, 154), MavCmd::RequestMessage, 285.0, 0.0);
        b.receive_all(&frame(GCS, i as u8, &c), t(20));
        let status = of::<GimbalDeviceAttitudeStatus>(&sent(&mut b)).remove(0);
        let d = status.delta_yaw.to_degrees();
        assert!((d - 30.0).abs() < 1e-3, "{q:?}: {d}");
    }
    b.receive_all(
        &frame(AP, 4, &position(900_000_001, 85_455_940, 488_123, 0)),
        t(30),
    );
    // What the link pushes to the gimbal: the attitude held and the altitude, no GPS.
    b.link.poll(t(30));
    assert_eq!(
        queued_vehicle_frames(&mut b.link),
        [
            VehicleFrame::Attitude(held),
            VehicleFrame::Altitude(Altitude::from_cm(48_812))
        ]
    );
    let s = b.stats();
    assert_eq!((s.vehicle_updates, s.refused_vehicle_updates), (1, 3));
}

/// `GLOBAL_POSITION_INT` is broadcast: only the followed autopilot's moves the GPS the link
/// pushes. Another vehicle's on a shared link, and any before an autopilot is heard, are
/// counted as not for us.
#[test]
fn only_the_followed_autopilots_position_is_taken() {
    let gps_pushed = |b: &mut Firmware, ms: u32| {
        b.link.poll(t(ms));
        queued_vehicle_frames(&mut b.link)
            .into_iter()
            .filter_map(|f| match f {
                VehicleFrame::Gps(g) => Some((g.lat_e7(), g.lon_e7())),
                _ => None,
            })
            .collect::<Vec<_>>()
    };
    let mut b = fresh();
    b.receive_all(&frame(AP, 0, &position(10, 20, 0, 0)), t(0));
    assert_eq!(b.stats().not_for_us, 1, "before any heartbeat");
    assert!(gps_pushed(&mut b, 0).is_empty());
    b.receive_all(&frame(AP, 1, &heartbeat()), t(10));
    b.receive_all(&frame(AP, 2, &position(30, 40, 0, 0)), t(20));
    assert_eq!(gps_pushed(&mut b, 20), [(30, 40)]);
    // Another vehicle's autopilot, and another component of this one.
    b.receive_all(&frame((AP.0 + 1, 1), 0, &position(50, 60, 0, 0)), t(30));
    b.receive_all(&frame((AP.0, 2), 0, &position(70, 80, 0, 0)), t(30));
    assert_eq!(b.stats().not_for_us, 3);
    // Pushed again at its period (1 s): still the followed autopilot's.
    assert_eq!(gps_pushed(&mut b, 1_020), [(30, 40)]);
}

/// The vehicle's state is the followed autopilot's only: PX4 sends it to every component
/// (target 0, 0), and another vehicle's on a shared link would move this one's horizon and
/// north.
#[test]
fn another_vehicle_s_state_is_not_taken() {
    let mut b = bridge();
    let before = b.stats();
    b.receive_all(&frame((AP.0 + 1, 1), 0, &autopilot_state(90.0)), t(0));
    let after = b.stats();
    assert_eq!(after.vehicle_updates, before.vehicle_updates);
    assert_eq!(after.not_for_us, before.not_for_us + 1);
    b.receive_all(&frame(AP, 0, &autopilot_state(90.0)), t(10));
    assert_eq!(b.stats().vehicle_updates, after.vehicle_updates + 1);
}
