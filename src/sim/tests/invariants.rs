//! The model's invariants under any sequence of frames, vehicle frames and instants.

use super::*;
use proptest::prelude::*;

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
