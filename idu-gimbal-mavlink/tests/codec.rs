//! The hand-written codecs (`codec`) and the outbox's framing against `mavio`, the reference:
//! arbitrary messages (every bit of every field, NaN payloads included), each encoded by both
//! and compared byte for byte as whole frames; and each received payload, whole or cut
//! anywhere (as MAVLink 2 truncates trailing zeros), decoded by both and compared field by
//! field, bit for bit.

mod common;
// `mavio`'s frame of a message: the reference the codecs' frames are held to.
use common::frame;

use idu_gimbal_mavlink::codec;
use idu_gimbal_mavlink::framing::Outbox;
use mavio::dialects::common::enums::{
    CameraTrackingMode, CameraTrackingStatusFlags, CameraTrackingTargetData, EstimatorStatusFlags,
    GimbalDeviceErrorFlags, GimbalDeviceFlags, MavAutopilot, MavCmd, MavLandedState, MavModeFlag,
    MavParamExtType, MavResult, MavSeverity, MavState, MavType, ParamAck,
};
use mavio::dialects::common::messages::{
    AutopilotStateForGimbalDevice, CameraTrackingImageStatus, CommandAck,
    GimbalDeviceAttitudeStatus, GimbalDeviceSetAttitude, GlobalPositionInt, Heartbeat, ParamExtAck,
    ParamExtSet, Statustext,
};
use mavio::mavspec::rust::spec::{MavLinkVersion, MessageSpecStatic};
use mavio::Message;
use proptest::prelude::*;

/// `mavio`'s payload of `m`, MAVLink 2 (trailing zeros dropped).
fn mavio_payload(m: &dyn Message) -> Vec<u8> {
    m.encode(MavLinkVersion::V2).unwrap().bytes().to_vec()
}

/// The outbox's frame of `M` with the codec's payload, after `seq` frames of the same
/// component (each component's frames are numbered on their own).
fn codec_frame<M: MessageSpecStatic>(
    seq: u8,
    system: u8,
    component: u8,
    len: usize,
    encode: impl FnOnce(&mut [u8]),
) -> Vec<u8> {
    let mut out = Outbox::<600>::new();
    for _ in 0..seq {
        out.push_payload(0, component, 0, 0, &[1]).unwrap();
        let n = out.bytes().len();
        out.written(n);
    }
    out.push_with(
        system,
        component,
        M::message_id(),
        M::crc_extra(),
        len,
        encode,
    )
    .unwrap();
    out.bytes().to_vec()
}

fn f32_bits() -> impl Strategy<Value = f32> {
    // Any bit pattern: NaNs with payloads, infinities, subnormals, zeros of both signs.
    any::<u32>().prop_map(f32::from_bits)
}

fn quaternion() -> impl Strategy<Value = [f32; 4]> {
    [f32_bits(), f32_bits(), f32_bits(), f32_bits()]
}

fn bits_of(q: [f32; 4]) -> [u32; 4] {
    q.map(f32::to_bits)
}

prop_compose! {
    fn attitude_status()(
        time_boot_ms in any::<u32>(),
        flags in any::<u16>(),
        q in quaternion(),
        w in [f32_bits(), f32_bits(), f32_bits()],
        failure in any::<u16>(),
        delta in [f32_bits(), f32_bits()],
        ids in any::<[u8; 3]>(),
        // Mostly the bridge's own zeros, so that truncation is exercised.
        zeros in any::<u8>(),
    ) -> GimbalDeviceAttitudeStatus {
        let z = |v: f32, bit: u8| if zeros & bit != 0 { 0.0 } else { v };
        GimbalDeviceAttitudeStatus {
            target_system: ids[0],
            target_component: ids[1],
            time_boot_ms,
            flags: GimbalDeviceFlags::from_bits_truncate(flags),
            q,
            angular_velocity_x: w[0],
            angular_velocity_y: w[1],
            angular_velocity_z: w[2],
            failure_flags: GimbalDeviceErrorFlags::from_bits_truncate(failure),
            delta_yaw: z(delta[0], 1),
            delta_yaw_velocity: z(delta[1], 2),
            gimbal_device_id: if zeros & 4 != 0 { 0 } else { ids[2] },
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn the_status_frame_is_mavios(m in attitude_status(), seq in 0u8..4, sys in any::<u8>()) {
        let ours = codec_frame::<GimbalDeviceAttitudeStatus>(
            seq, sys, 154, codec::attitude_status::LEN,
            |p| codec::attitude_status::encode(&m, p),
        );
        prop_assert_eq!(ours, frame((sys, 154), seq, &m));
    }

    #[test]
    fn the_heartbeat_frame_is_mavios(
        type_ in 0u8..40, autopilot in 0u8..20, base in any::<u8>(), custom in any::<u32>(),
        state in 0u8..9, version in any::<u8>(),
    ) {
        let m = Heartbeat {
            type_: MavType::try_from(type_).unwrap_or(MavType::Gimbal),
            autopilot: MavAutopilot::try_from(autopilot).unwrap_or(MavAutopilot::Invalid),
            base_mode: MavModeFlag::from_bits_truncate(base),
            custom_mode: custom,
            system_status: MavState::try_from(state).unwrap_or(MavState::Active),
            mavlink_version: version,
        };
        let ours = codec_frame::<Heartbeat>(
            1, 7, 100, codec::heartbeat::LEN, |p| codec::heartbeat::encode(&m, p),
        );
        prop_assert_eq!(ours, frame((7, 100), 1, &m));
    }

    #[test]
    fn the_statustext_frame_is_mavios(
        severity in 0u8..8, text in proptest::collection::vec(any::<u8>(), 50),
        id in any::<u16>(), chunk in any::<u8>(),
    ) {
        let m = Statustext {
            severity: MavSeverity::try_from(severity).unwrap(),
            text: <[u8; 50]>::try_from(text).unwrap(),
            id,
            chunk_seq: chunk,
        };
        let ours = codec_frame::<Statustext>(
            2, 9, 154, codec::statustext::LEN, |p| codec::statustext::encode(&m, p),
        );
        prop_assert_eq!(ours, frame((9, 154), 2, &m));
    }

    #[test]
    fn the_tracking_status_frame_is_mavios(
        status in 0u8..3, mode in 0u8..3, data in any::<u8>(),
        v in [f32_bits(), f32_bits(), f32_bits(), f32_bits(), f32_bits(), f32_bits(), f32_bits()],
        id in any::<u8>(),
    ) {
        let m = CameraTrackingImageStatus {
            tracking_status: CameraTrackingStatusFlags::try_from(status).unwrap(),
            tracking_mode: CameraTrackingMode::try_from(mode).unwrap(),
            target_data: CameraTrackingTargetData::from_bits_truncate(data),
            point_x: v[0], point_y: v[1], radius: v[2],
            rec_top_x: v[3], rec_top_y: v[4], rec_bottom_x: v[5], rec_bottom_y: v[6],
            camera_device_id: id,
        };
        let ours = codec_frame::<CameraTrackingImageStatus>(
            2, 1, 100, codec::tracking_image_status::LEN,
            |p| codec::tracking_image_status::encode(&m, p),
        );
        prop_assert_eq!(ours, frame((1, 100), 2, &m));
    }

    #[test]
    fn the_command_ack_frame_is_mavios(
        command in prop::sample::select(vec![
            MavCmd::RequestMessage, MavCmd::SetMessageInterval, MavCmd::DoSetRoiLocation,
            MavCmd::ImageStartCapture, MavCmd::SetCameraZoom, MavCmd::CameraTrackPoint,
        ]),
        result in 0u8..7, to in any::<(u8, u8)>(),
    ) {
        let result = MavResult::try_from(result).unwrap();
        let m = CommandAck {
            command, result, progress: 0, result_param2: 0,
            target_system: to.0, target_component: to.1,
        };
        let ours = codec_frame::<CommandAck>(
            2, 1, 154, codec::command_ack::LEN,
            |p| codec::command_ack::encode(command as u16, result, to, p),
        );
        prop_assert_eq!(ours, frame((1, 154), 2, &m));
    }

    #[test]
    fn the_param_ext_ack_frame_and_set_decoding_are_mavios(
        id in prop::array::uniform16(any::<u8>()),
        value in prop::collection::vec(any::<u8>(), 128),
        ty in 1u8..=11, result in 0u8..=3, target in any::<(u8, u8)>(),
    ) {
        let value: [u8; 128] = value.try_into().unwrap();
        let param_type = MavParamExtType::try_from(ty).unwrap();
        let ack = ParamExtAck {
            param_id: id, param_value: value, param_type,
            param_result: ParamAck::try_from(result).unwrap(),
        };
        let ours = codec_frame::<ParamExtAck>(
            2, 1, 100, codec::param_ext::ACK_LEN,
            |p| codec::param_ext::encode_ack(&id, &value, ty, result, p),
        );
        prop_assert_eq!(ours, frame((1, 100), 2, &ack));
        // A set as mavio writes it (trailing zeros dropped) reads back field for field.
        let set = ParamExtSet {
            target_system: target.0, target_component: target.1,
            param_id: id, param_value: value, param_type,
        };
        let bytes = frame((1, 100), 2, &set);
        // MAVLink 2: a 10-byte header, its second byte the payload's length.
        let got = codec::param_ext::decode_set(&bytes[10..10 + usize::from(bytes[1])]);
        prop_assert_eq!(
            (got.target, got.param_id, got.param_value, got.param_type),
            (target, id, value, ty)
        );
    }

    #[test]
    fn any_message_through_the_outbox_is_mavios_frame(m in attitude_status(), seq in 0u8..3) {
        // The general path: mavio's payload, the outbox's header and checksum.
        let mut out = Outbox::<600>::new();
        for _ in 0..seq {
            out.push_payload(0, 154, 0, 0, &[1]).unwrap();
            let n = out.bytes().len();
            out.written(n);
        }
        out.push(9, 154, &m).unwrap();
        prop_assert_eq!(out.bytes().to_vec(), frame((9, 154), seq, &m));
    }

    #[test]
    fn a_setpoint_decodes_as_mavio_decodes_it(
        q in quaternion(), w in [f32_bits(), f32_bits(), f32_bits()],
        flags in any::<u16>(), ids in any::<[u8; 2]>(), cut in 1usize..=32,
    ) {
        let m = GimbalDeviceSetAttitude {
            target_system: ids[0], target_component: ids[1],
            flags: GimbalDeviceFlags::from_bits_retain(flags),
            q, angular_velocity_x: w[0], angular_velocity_y: w[1], angular_velocity_z: w[2],
        };
        let full = mavio_payload(&m);
        let payload = &full[..cut.min(full.len())];
        let theirs: GimbalDeviceSetAttitude = GimbalDeviceSetAttitude::try_from(
            &mavio::protocol::Payload::new(284, payload, MavLinkVersion::V2),
        ).unwrap();
        let ours = codec::set_attitude::decode(payload);
        prop_assert_eq!(bits_of(ours.q), bits_of(theirs.q));
        prop_assert_eq!(
            [ours.angular_velocity_x, ours.angular_velocity_y, ours.angular_velocity_z].map(f32::to_bits),
            [theirs.angular_velocity_x, theirs.angular_velocity_y, theirs.angular_velocity_z].map(f32::to_bits)
        );
        // Bits outside the dialect dropped by both (tests/bridge/setpoints.rs says why that
        // is safe).
        prop_assert_eq!(ours.flags, theirs.flags);
        prop_assert_eq!((ours.target_system, ours.target_component),
                        (theirs.target_system, theirs.target_component));
    }

    #[test]
    fn an_autopilot_state_decodes_as_mavio_decodes_it(
        time in any::<u64>(), q in quaternion(), v in [f32_bits(), f32_bits(), f32_bits(), f32_bits(), f32_bits()],
        delays in any::<[u32; 2]>(), status in any::<u16>(), ids in any::<[u8; 2]>(),
        landed in any::<u8>(), cut in 1usize..=57,
    ) {
        // Build the payload by hand at the wire offsets (a landed state outside the dialect
        // cannot be built as a mavio message), then let both decode it.
        let mut full = [0u8; 57];
        full[0..8].copy_from_slice(&time.to_le_bytes());
        for (i, x) in q.iter().enumerate() {
            full[8 + 4 * i..12 + 4 * i].copy_from_slice(&x.to_le_bytes());
        }
        full[24..28].copy_from_slice(&delays[0].to_le_bytes());
        full[28..32].copy_from_slice(&v[0].to_le_bytes());
        full[32..36].copy_from_slice(&v[1].to_le_bytes());
        full[36..40].copy_from_slice(&v[2].to_le_bytes());
        full[40..44].copy_from_slice(&delays[1].to_le_bytes());
        full[44..48].copy_from_slice(&v[3].to_le_bytes());
        full[48..50].copy_from_slice(&status.to_le_bytes());
        full[50] = ids[0];
        full[51] = ids[1];
        full[52] = landed % 6;
        full[53..57].copy_from_slice(&v[4].to_le_bytes());
        if landed >= 240 {
            full[52] = landed; // outside the dialect: both refuse
        }
        let payload = &full[..cut];
        let theirs = AutopilotStateForGimbalDevice::try_from(
            &mavio::protocol::Payload::new(286, payload, MavLinkVersion::V2),
        );
        let ours = codec::autopilot_state::decode(payload);
        match (ours, theirs) {
            (None, Err(_)) => {}
            (Some(o), Ok(t)) => {
                prop_assert_eq!(o.time_boot_us, t.time_boot_us);
                prop_assert_eq!(bits_of(o.q), bits_of(t.q));
                prop_assert_eq!(
                    [o.vx, o.vy, o.vz, o.feed_forward_angular_velocity_z, o.angular_velocity_z].map(f32::to_bits),
                    [t.vx, t.vy, t.vz, t.feed_forward_angular_velocity_z, t.angular_velocity_z].map(f32::to_bits)
                );
                prop_assert_eq!((o.q_estimated_delay_us, o.v_estimated_delay_us),
                                (t.q_estimated_delay_us, t.v_estimated_delay_us));
                prop_assert_eq!(o.estimator_status, t.estimator_status);
                prop_assert_eq!(o.landed_state, t.landed_state);
                prop_assert_eq!((o.target_system, o.target_component), (t.target_system, t.target_component));
            }
            (o, t) => prop_assert!(false, "ours {:?}, mavio {:?}", o.is_some(), t.is_ok()),
        }
    }

    #[test]
    fn a_position_decodes_as_mavio_decodes_it(
        v in any::<[i32; 5]>(), s in any::<[i16; 3]>(), hdg in any::<u16>(), cut in 1usize..=28,
    ) {
        let m = GlobalPositionInt {
            time_boot_ms: v[0] as u32, lat: v[1], lon: v[2], alt: v[3], relative_alt: v[4],
            vx: s[0], vy: s[1], vz: s[2], hdg,
        };
        let full = mavio_payload(&m);
        let payload = &full[..cut.min(full.len())];
        let theirs = GlobalPositionInt::try_from(
            &mavio::protocol::Payload::new(33, payload, MavLinkVersion::V2),
        ).unwrap();
        prop_assert_eq!(codec::global_position::decode(payload), theirs);
    }
}

#[test]
fn the_lengths_are_the_dialects() {
    // A message's full payload: mavio's encoding of one with no zero byte at its end.
    let status = GimbalDeviceAttitudeStatus {
        target_system: 1,
        target_component: 1,
        time_boot_ms: 1,
        flags: GimbalDeviceFlags::empty(),
        q: [1.0; 4],
        angular_velocity_x: 1.0,
        angular_velocity_y: 1.0,
        angular_velocity_z: 1.0,
        failure_flags: GimbalDeviceErrorFlags::empty(),
        delta_yaw: 1.0,
        delta_yaw_velocity: 1.0,
        gimbal_device_id: 1,
    };
    assert_eq!(mavio_payload(&status).len(), codec::attitude_status::LEN);
    let state = AutopilotStateForGimbalDevice {
        target_system: 1,
        target_component: 1,
        time_boot_us: 1,
        q: [1.0; 4],
        q_estimated_delay_us: 1,
        vx: 1.0,
        vy: 1.0,
        vz: 1.0,
        v_estimated_delay_us: 1,
        feed_forward_angular_velocity_z: 1.0,
        estimator_status: EstimatorStatusFlags::empty(),
        landed_state: MavLandedState::InAir,
        angular_velocity_z: 1.0,
    };
    assert_eq!(mavio_payload(&state).len(), codec::autopilot_state::LEN);
}
