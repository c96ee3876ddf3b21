//! `GIMBAL_DEVICE_SET_ATTITUDE`: angles, rates, neutral and retract, in the yaw frame the
//! setpoint names.
//!
//! - A quaternion becomes heading and pitch commands (re-sent only past the dead-band),
//!   converted from the setpoint's yaw frame to the gimbal's reference (north while the
//!   vehicle attitude is pushed, the nose otherwise) with the vehicle's yaw. Angular
//!   velocities given beside a valid quaternion (MAVSDK's gimbal_device_tester sends
//!   both) are a feed-forward the gimbal's angle command has no field for: the angle is
//!   followed.
//! - A NaN quaternion with angular velocities is a rate, held by the core (its dead-man
//!   stops the gimbal when the stream stops). Its yaw rate is in the frame the flags name;
//!   the gimbal's rate command turns the yaw motor, so an earth-frame yaw rate becomes a
//!   motor rate by taking away the vehicle's yaw rate, and is refused without one.
//! - Yaw is in the earth frame with `YAW_IN_EARTH_FRAME`, or with `YAW_LOCK` unless
//!   `YAW_IN_VEHICLE_FRAME` says otherwise (common.xml: YAW_LOCK "lock yaw angle to
//!   absolute angle relative to North", the older way to say earth frame).
//! - `NEUTRAL` re-centres and `RETRACT` looks down (the gimbal has no retracted pose),
//!   once each when the flag appears.

use idu_gimbal::wire::control::{GimbalCommand, Heading, Pitch, Rate};
use idu_gimbal::Instant;
use mavio::dialects::common::enums::GimbalDeviceFlags;
use mavio::dialects::common::messages::GimbalDeviceSetAttitude;

use crate::attitude::{is_nan_quaternion, wrap_pi, YawPitch};
use crate::bridge::{bump, State};
use crate::gimbal::GimbalControl;
use crate::status::Pose;

/// Whether `flags` put a setpoint's yaw in the earth frame.
fn earth_yaw(flags: GimbalDeviceFlags) -> bool {
    if flags.contains(GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME) {
        false
    } else {
        flags.intersects(GimbalDeviceFlags::YAW_IN_EARTH_FRAME | GimbalDeviceFlags::YAW_LOCK)
    }
}

impl State {
    pub(crate) fn set_attitude<G: GimbalControl>(
        &mut self,
        gimbal: &mut G,
        set: &GimbalDeviceSetAttitude,
        now: Instant,
    ) {
        let flags = set.flags;
        // Neutral and retract act once, when the flag appears.
        let edge = |f: GimbalDeviceFlags| flags.contains(f) && self.last_flags & f.bits() == 0;
        let neutral = edge(GimbalDeviceFlags::NEUTRAL);
        // No retracted position: the gimbal's stowed pose is looking straight down.
        let retract = edge(GimbalDeviceFlags::RETRACT);
        self.last_flags = flags.bits();
        if neutral || retract {
            let (c, pose) = if retract {
                (GimbalCommand::LookDown, Pose::Retracted)
            } else {
                (GimbalCommand::Recenter, Pose::Neutral)
            };
            if self.command_gimbal(gimbal, c) {
                self.pose = pose;
            }
            self.commanded = (None, None);
            return;
        }
        if flags.intersects(GimbalDeviceFlags::NEUTRAL | GimbalDeviceFlags::RETRACT) {
            return;
        }
        if is_nan_quaternion(set.q) {
            self.rate(gimbal, set, now);
            return;
        }
        let Some(a) = YawPitch::from_quaternion(set.q) else {
            bump(&mut self.stats.refused_setpoints);
            return;
        };
        // The gimbal has no roll: a setpoint rolled by more than about a degree
        // (sin(roll)·cos(pitch) over sin 1° = 0.01745) cannot be followed.
        if libm::fabsf(YawPitch::roll_of(set.q)) > 0.017_45 {
            bump(&mut self.stats.refused_setpoints);
            return;
        }
        let north = gimbal.north_referenced(now);
        // The heading command's frame is the gimbal's reference: north while attitude is
        // pushed, the nose otherwise.
        let heading_rad = match (earth_yaw(flags), north) {
            (true, true) | (false, false) => Some(a.yaw_rad),
            (false, true) => self.vehicle.yaw(now).map(|v| a.yaw_rad + v),
            (true, false) => self.vehicle.yaw(now).map(|v| a.yaw_rad - v),
        };
        // Rounded to the wire's 0.1° before the range check: an autopilot's −100°, through
        // its trigonometry and ours, arrives a few ulps beyond −100 (finite here, and any
        // |value| ≥ 32768 saturates the cast to a value `from_deci` refuses).
        let pitch = Pitch::from_deci(libm::roundf(a.pitch_rad.to_degrees() * 10.0) as i16);
        let heading = heading_rad.map(|h| {
            // (−180°, 180°] to the command's [0°, 360°].
            let d = wrap_pi(h).to_degrees();
            Heading::new(if d < 0.0 { d + 360.0 } else { d })
        });
        let (Ok(pitch), Some(Ok(heading))) = (pitch, heading) else {
            bump(&mut self.stats.refused_setpoints);
            return;
        };
        self.pose = Pose::Other;
        let band = i32::from(self.config.deadband_deci);
        let heading_moved = self.commanded.0.is_none_or(|h| {
            let d = (i32::from(heading.deci()) - i32::from(h)).rem_euclid(3600);
            d.min(3600 - d) > band
        });
        let pitch_moved = self
            .commanded
            .1
            .is_none_or(|p| (i32::from(pitch.deci()) - i32::from(p)).abs() > band);
        if heading_moved && self.command_gimbal(gimbal, GimbalCommand::Heading(heading)) {
            self.commanded.0 = Some(heading.deci());
        }
        if pitch_moved && self.command_gimbal(gimbal, GimbalCommand::Pitch(pitch)) {
            self.commanded.1 = Some(pitch.deci());
        }
    }

    fn rate<G: GimbalControl>(
        &mut self,
        gimbal: &mut G,
        set: &GimbalDeviceSetAttitude,
        now: Instant,
    ) {
        // Body rates in FRD: about y is pitch (positive raises the camera, as the wire's
        // positive pitch rate), about z is yaw (positive to the right, as the wire's).
        let pitch_rate = set.angular_velocity_y;
        let mut yaw_rate = set.angular_velocity_z;
        if earth_yaw(set.flags) {
            // An earth-frame yaw rate, to the motor's: minus the vehicle's own turn.
            let Some(vehicle) = self.vehicle.yaw_rate(now) else {
                bump(&mut self.stats.refused_setpoints);
                return;
            };
            yaw_rate -= vehicle;
        }
        let Ok(rate) = Rate::new(yaw_rate.to_degrees(), pitch_rate.to_degrees()) else {
            bump(&mut self.stats.refused_setpoints);
            return;
        };
        // A rate ends any angle: the next angle setpoint is sent whatever its value.
        self.commanded = (None, None);
        self.pose = Pose::Other;
        if gimbal.set_rate(rate, now).is_ok() {
            bump(&mut self.stats.rate_setpoints);
        } else {
            bump(&mut self.stats.queue_full);
        }
    }
}
