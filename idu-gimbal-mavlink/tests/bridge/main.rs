//! The bridge as an autopilot sees it: MAVLink frames built with `mavio` in, the bridge's
//! bytes parsed back, the gimbal's command queue (the core's sans-IO `Link`) read out.

#[path = "../common/mod.rs"]
mod common;
use common::*;

use idu_gimbal::link::SerialLink;
use idu_gimbal::link::{Aim, Config, Link, Yaw};
use idu_gimbal::wire::control::{Command, GimbalCommand, Heading, Pitch, Rate};
use idu_gimbal::wire::ids;
use idu_gimbal::wire::postback::Postback;
use idu_gimbal::wire::vehicle::{Altitude, VehicleFrame};
use idu_gimbal_mavlink::attitude::YawPitch;
use idu_gimbal_mavlink::camera::CameraConfig;
use idu_gimbal_mavlink::{Bridge, BridgeConfig, BridgeConfigError, Period, AUTOPILOT_SILENCE_MS};
use mavio::dialects::common::enums::{
    GimbalDeviceErrorFlags, GimbalDeviceFlags, MavAutopilot, MavCmd, MavResult, MavType,
};
use mavio::dialects::common::messages::{
    AutopilotStateForGimbalDevice, CommandAck, CommandLong, GimbalDeviceAttitudeStatus,
    GimbalDeviceInformation, GimbalDeviceSetAttitude, GlobalPositionInt, Heartbeat,
};

mod autopilot;
mod faults;
mod setpoints;
mod status;
mod vehicle;

fn fresh() -> Firmware {
    Firmware::new(Link::new(Config::default()), BridgeConfig::default())
}

/// A bridge that has heard the autopilot's heartbeat (so its system id is the autopilot's),
/// its output so far drained.
fn bridge() -> Firmware {
    let mut b = fresh();
    b.receive_all(&frame(AP, 0, &heartbeat()), t(0));
    let _ = sent(&mut b);
    b
}
