//! `GIMBAL_DEVICE_SET_ATTITUDE`: angles, rates, neutral and retract, in the yaw frame the
//! setpoint names.
//!
//! - A quaternion becomes an aim for the core's link ([`Link::aim`]): its yaw in
//!   the setpoint's frame, its pitch. The link holds it closed loop: it sends the heading in
//!   the gimbal's reference (north once the attitude has reached the gimbal, the nose
//!   otherwise), sends it again when the vehicle turns, when the gimbal's reference changes
//!   or when a postback shows the gimbal off it, and ignores a setpoint within its dead-band
//!   of the one held (a stream re-sending it); see `idu_gimbal::link::aim`. So an earth yaw
//!   keeps its bearing while the vehicle turns and a vehicle yaw its angle from the nose,
//!   whether the gimbal in lock holds its north heading or its motor angle. Angular
//!   velocities given beside a valid quaternion (MAVSDK's gimbal_device_tester sends both)
//!   are a feed-forward the gimbal's angle command has no field for: the angle is followed.
//! - A NaN quaternion with angular velocities is a rate, held by the core (its dead-man
//!   stops the gimbal when the stream stops). Its yaw rate is in the frame the flags name;
//!   the gimbal's rate command turns the yaw motor, so an earth-frame yaw rate becomes a
//!   motor rate by taking away the vehicle's yaw rate, and is refused without one. An axis
//!   whose rate is NaN ("NaN to be ignored") is held; with both NaN, refused.
//! - Yaw is in the earth frame with `YAW_IN_EARTH_FRAME`, or with `YAW_LOCK` unless
//!   `YAW_IN_VEHICLE_FRAME` says otherwise (common.xml: YAW_LOCK "lock yaw angle to
//!   absolute angle relative to North", the older way to say earth frame).
//! - `NEUTRAL` holds the vehicle frame's forward and level (an aim, so that it stays
//!   forward whatever the gimbal holds in lock) and `RETRACT` looks down (the gimbal has no
//!   retracted pose), once each when the flag appears.

use idu_gimbal::link::{Aim, Link, Medium, Yaw};
use idu_gimbal::wire::control::{GimbalCommand, Heading, Pitch, Rate};
use idu_gimbal::Instant;
use mavio::dialects::common::enums::GimbalDeviceFlags;
use mavio::dialects::common::messages::GimbalDeviceSetAttitude;

use crate::attitude::{is_nan_quaternion, YawPitch};
use crate::bridge::State;
use crate::status::Pose;
use crate::tx::bump;

/// Whether `flags` put a setpoint's yaw in the earth frame.
fn earth_yaw(flags: GimbalDeviceFlags) -> bool {
    if flags.contains(GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME) {
        false
    } else {
        flags.intersects(GimbalDeviceFlags::YAW_IN_EARTH_FRAME | GimbalDeviceFlags::YAW_LOCK)
    }
}

impl State {
    pub(crate) fn set_attitude<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
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
        if retract {
            if self.command_gimbal(gimbal, GimbalCommand::LookDown) {
                self.pose = Pose::Retracted;
                self.rate_earth = false;
            } else {
                // No room (counted): the next setpoint with the flag is its edge again.
                self.last_flags &= !GimbalDeviceFlags::RETRACT.bits();
            }
            return;
        }
        if neutral {
            let forward = Aim {
                yaw: Yaw::Vehicle(Heading::NORTH),
                pitch: Pitch::LEVEL,
            };
            // A vehicle-frame aim needs no vehicle heading: never refused.
            if gimbal.aim(forward, now).is_ok() {
                self.pose = Pose::Neutral;
                self.rate_earth = false;
                bump(&mut self.stats.angle_setpoints);
            } else {
                self.last_flags &= !GimbalDeviceFlags::NEUTRAL.bits();
            }
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
        // Rounded to the wire's 0.1° before the range check: an autopilot's −100°, through
        // its trigonometry and ours, arrives a few ulps beyond −100 (finite here, and any
        // |value| ≥ 32768 saturates the cast to a value `from_deci` refuses).
        let Ok(pitch) = Pitch::from_deci(libm::roundf(a.pitch_rad.to_degrees() * 10.0) as i16)
        else {
            bump(&mut self.stats.refused_setpoints);
            return;
        };
        // (−180°, 180°] to [0°, 360°), in 0.01° (finite: from_quaternion's atan2).
        let heading =
            Heading::from_centideg_wrapped(libm::roundf(a.yaw_rad.to_degrees() * 100.0) as i32);
        let aim = Aim {
            yaw: if earth_yaw(flags) {
                Yaw::Earth(heading)
            } else {
                Yaw::Vehicle(heading)
            },
            pitch,
        };
        // Refused only for an earth yaw the gimbal's reference needs the vehicle's heading
        // for, when none is fresh.
        if gimbal.aim(aim, now).is_ok() {
            self.pose = Pose::Other;
            self.rate_earth = false;
            bump(&mut self.stats.angle_setpoints);
        } else {
            bump(&mut self.stats.refused_setpoints);
        }
    }

    fn rate<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
        set: &GimbalDeviceSetAttitude,
        now: Instant,
    ) {
        // Body rates in FRD: about y is pitch (positive raises the camera, as the wire's
        // positive pitch rate), about z is yaw (positive to the right, as the wire's).
        // common.xml: each "NaN to be ignored": that axis held (0), the other turned; with
        // both NaN the setpoint asks nothing.
        let (y, z) = (set.angular_velocity_y, set.angular_velocity_z);
        if y.is_nan() && z.is_nan() {
            bump(&mut self.stats.refused_setpoints);
            return;
        }
        let held = |r: f32| if r.is_nan() { 0.0 } else { r };
        let pitch_rate = held(y);
        let mut yaw_rate = held(z);
        let earth = earth_yaw(set.flags);
        if earth {
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
        if gimbal.set_rate(rate, now).is_ok() {
            self.pose = Pose::Other;
            self.rate_earth = earth;
            bump(&mut self.stats.rate_setpoints);
        } else {
            bump(&mut self.stats.queue_full);
        }
    }
}
