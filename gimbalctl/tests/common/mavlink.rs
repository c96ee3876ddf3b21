//! MAVLink 2 for the tests of `gimbalctl mavlink`, built with `mavio` (the bridge's re-export):
//! what an autopilot or a ground station sends the bridge.

use idu_gimbal_mavlink::mavio;
use mavio::dialects::common::enums::{MavAutopilot, MavCmd, MavModeFlag, MavState, MavType};
use mavio::dialects::common::messages::{CommandLong, GimbalDeviceInformation, Heartbeat};
use mavio::protocol::{Frame, V2};
use mavio::Message;

/// The gimbal device's component id.
pub const GIMBAL: u8 = 154;

/// One MAVLink 2 frame from `(system, component)`.
pub fn frame(from: (u8, u8), seq: u8, message: &dyn Message) -> Vec<u8> {
    let f = Frame::builder()
        .version(V2)
        .sequence(seq)
        .system_id(from.0)
        .component_id(from.1)
        .message(message)
        .expect("a message mavio encodes")
        .build();
    let mut buf = [0u8; 300];
    let n = f.serialize(&mut buf).expect("serialize");
    buf[..n].to_vec()
}

/// An active vehicle's or ground station's heartbeat.
pub fn heartbeat(type_: MavType, autopilot: MavAutopilot) -> Heartbeat {
    Heartbeat {
        type_,
        autopilot,
        base_mode: MavModeFlag::empty(),
        custom_mode: 0,
        system_status: MavState::Active,
        mavlink_version: 3,
    }
}

/// MAV_CMD_REQUEST_MESSAGE for GIMBAL_DEVICE_INFORMATION, to the gimbal of `target_system`
/// (0: of any system).
pub fn request_information(target_system: u8) -> CommandLong {
    CommandLong {
        target_system,
        target_component: GIMBAL,
        command: MavCmd::RequestMessage,
        param1: GimbalDeviceInformation::spec().id() as f32,
        ..Default::default()
    }
}
