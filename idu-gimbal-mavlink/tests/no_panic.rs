//! The fuzz target's property (`fuzz/mavlink_properties.rs`), run by `cargo test` so CI
//! exercises it on every run.

#[path = "../../fuzz/mavlink_properties.rs"]
mod mavlink_properties;

mod common;
use common::*;

use idu_gimbal_mavlink::attitude::YawPitch;
use mavio::dialects::common::enums::{GimbalDeviceFlags, MavCmd};
use mavio::dialects::common::messages::GimbalDeviceSetAttitude;
use proptest::prelude::*;

fn setpoint(yaw: f32, pitch: f32) -> Vec<u8> {
    let q = YawPitch {
        yaw_rad: yaw.to_radians(),
        pitch_rad: pitch.to_radians(),
    }
    .to_quaternion();
    frame(
        AP,
        3,
        &GimbalDeviceSetAttitude {
            target_system: 0,
            target_component: 154,
            flags: GimbalDeviceFlags::YAW_LOCK,
            q,
            angular_velocity_x: f32::NAN,
            angular_velocity_y: f32::NAN,
            angular_velocity_z: f32::NAN,
        },
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1000))]

    /// Garbage mixed with real frames (and real frames with a flipped bit), cut anywhere.
    #[test]
    fn mavlink_bridge(parts in proptest::collection::vec(
        prop_oneof![
            proptest::collection::vec(any::<u8>(), 0..30),
            Just(frame(AP, 0, &heartbeat())),
            Just(frame(GCS, 1, &command((0, 0), MavCmd::RequestMessage, 283.0, 0.0))),
            Just(frame(GCS, 2, &command((0, 100), MavCmd::ImageStartCapture, 0.0, 0.0))),
            (-180f32..180.0, -100f32..60.0).prop_map(|(y, p)| setpoint(y, p)),
            (any::<u16>(), any::<u8>()).prop_map(|(at, bit)| {
                let mut f = frame(GCS, 4, &command((0, 154), MavCmd::RequestMessage, 285.0, 0.0));
                let i = usize::from(at) % f.len();
                f[i] ^= 1 << (bit % 8);
                f
            }),
        ],
        0..12,
    )) {
        mavlink_properties::mavlink_bridge(&parts.concat());
    }
}
