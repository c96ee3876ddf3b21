//! The fuzz target's property (`fuzz/mavlink_properties.rs`), run by `cargo test` so CI
//! exercises it on every run.

#[path = "../../fuzz/mavlink_properties.rs"]
mod mavlink_properties;

mod common;
use common::*;

use idu_gimbal_mavlink::attitude::YawPitch;
use mavio::dialects::common::enums::{GimbalDeviceFlags, MavCmd, MavParamExtType};
use mavio::dialects::common::messages::{
    FileTransferProtocol, GimbalDeviceSetAttitude, ParamExtRequestList, ParamExtSet,
};
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

/// A camera command with any parameters.
fn camera_command(cmd: MavCmd, p: [f32; 4]) -> Vec<u8> {
    frame(
        GCS,
        5,
        &command7((0, 100), cmd, [p[0], p[1], p[2], p[3], 0.0, 0.0, 0.0]),
    )
}

/// Any FTP packet to the camera, its opcode among those the server knows, to system 1 (the
/// bridge's before it hears the autopilot) or the autopilot's.
fn ftp(opcode: u8, head: [u8; 12], data: Vec<u8>, system: u8) -> Vec<u8> {
    let mut payload = [0u8; 251];
    payload[..12].copy_from_slice(&head);
    payload[3] = opcode;
    payload[12..12 + data.len()].copy_from_slice(&data);
    frame(
        GCS,
        6,
        &FileTransferProtocol {
            target_network: 0,
            target_system: system,
            target_component: 100,
            payload,
        },
    )
}

fn any_f32() -> impl Strategy<Value = f32> {
    prop_oneof![-2f32..2.0, any::<f32>(), Just(f32::NAN)]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1000))]

    /// Messages the bridge acts on, whole with good checksums, from any sender, with any
    /// payload (the fuzz target `mavlink_messages`; its ROI path when the `roi` feature is
    /// on, with the overflow checks of a test build).
    #[test]
    fn mavlink_messages(data in proptest::collection::vec(any::<u8>(), 0..600)) {
        mavlink_properties::mavlink_messages(&data);
    }

    /// Garbage mixed with real frames (and real frames with a flipped bit), cut anywhere.
    #[test]
    fn mavlink_bridge(parts in proptest::collection::vec(
        prop_oneof![
            proptest::collection::vec(any::<u8>(), 0..30),
            Just(frame(AP, 0, &heartbeat())),
            Just(frame(GCS, 1, &command((0, 0), MavCmd::RequestMessage, 283.0, 0.0))),
            Just(frame(GCS, 2, &command((0, 100), MavCmd::ImageStartCapture, 0.0, 0.0))),
            (-180f32..180.0, -100f32..60.0).prop_map(|(y, p)| setpoint(y, p)),
            (
                prop::sample::select(vec![
                    MavCmd::SetCameraFocus,
                    MavCmd::CameraTrackPoint,
                    MavCmd::CameraTrackRectangle,
                    MavCmd::CameraStopTracking,
                    MavCmd::SetCameraSource,
                    MavCmd::SetMessageInterval,
                    MavCmd::RequestMessage,
                    MavCmd::RequestVideoStreamInformation,
                    MavCmd::SetCameraZoom,
                ]),
                [any_f32(), any_f32(), any_f32(), any_f32()],
            )
                .prop_map(|(cmd, p)| camera_command(cmd, p)),
            (
                0u8..17,
                any::<[u8; 12]>(),
                proptest::collection::vec(any::<u8>(), 0..239),
                prop::sample::select(vec![1u8, AP.0]),
            )
                .prop_map(|(op, head, data, system)| ftp(op, head, data, system)),
            (any::<[u8; 16]>(), any::<u8>(), 1u8..12).prop_map(|(id, v, ty)| {
                let mut param_id = id;
                param_id[..10].copy_from_slice(b"IR_PALETTE");
                let mut param_value = [0u8; 128];
                param_value[0] = v;
                frame(GCS, 7, &ParamExtSet {
                    target_system: 0,
                    target_component: 100,
                    param_id: if v % 2 == 0 { param_id } else { id },
                    param_value,
                    param_type: MavParamExtType::try_from(ty).unwrap_or(MavParamExtType::Uint8),
                })
            }),
            Just(frame(GCS, 8, &ParamExtRequestList { target_system: 0, target_component: 100 })),
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
