//! What `GIMBAL_DEVICE_ATTITUDE_STATUS` reports, and why in the vehicle frame.
//!
//! The status is always in the vehicle frame (`YAW_IN_VEHICLE_FRAME`): `q`'s yaw is the
//! gimbal's yaw motor angle relative to the nose, and `delta_yaw` is the vehicle's heading
//! from north (the autopilot's `AUTOPILOT_STATE_FOR_GIMBAL_DEVICE`), NaN when the bridge
//! has none. common.xml defines the pair by "q_earth = q_delta_yaw * q_vehicle", so a
//! reader gets the earth-frame yaw as motor + delta_yaw.
//!
//! Both are as of the status, not of the postback (2 Hz, so up to 500 ms old): QGroundControl
//! and ArduPilot ignore `delta_yaw` and add the vehicle's heading now to the yaw. While the
//! yaw is held in the earth frame the motor turns back by what the vehicle turns, so the
//! status's motor angle is the postback's less the vehicle's turn since ([`attitude_turned`]);
//! a yaw that follows the vehicle keeps its angle. A turn at 15°/s then reads within what
//! the gimbal lags; the postback's angle beside the heading now would be off by up to 7.5°.
//!
//! Why not the earth frame, though the gimbal knows its bearing while attitude is
//! pushed: ArduPilot's MAVLink gimbal v2 backend (`MNT1_TYPE` 6,
//! `libraries/AP_Mount/AP_Mount_Gremsy.cpp`, master 2598e9d) copies the device's quaternion
//! unchanged (`get_attitude_quaternion`, :123-127) and reads its yaw as body frame whatever
//! the flags say (`AP_Mount.cpp`:656-671), then re-publishes it labelled
//! `YAW_IN_VEHICLE_FRAME` (`AP_Mount_Backend.cpp`:806-849); its logs and points of
//! interest add the vehicle's yaw (`AP_Mount_Backend.cpp`:431-433, :538). An earth-frame
//! status puts all of those off by the vehicle heading. The vehicle-frame status reads
//! right everywhere: ArduPilot as it is, PX4 (which passes the flags through), and
//! QGroundControl, which adds the vehicle heading to a vehicle-frame yaw
//! (`src/Gimbal/GimbalController.cc`).
//!
//! Flags say what the device holds, as common.xml defines them and as PX4 (which copies
//! them into `GIMBAL_MANAGER_STATUS`, read by QGroundControl) passes them on:
//! - `YAW_IN_VEHICLE_FRAME` always: the quaternion's frame.
//! - `YAW_LOCK` while the yaw is held in the earth frame ("lock yaw angle to absolute
//!   angle relative to North"): an earth-frame setpoint, a region of interest, or an
//!   earth-frame rate hold, which the link's closed loop keeps whatever the gimbal does in
//!   lock; not while it follows the vehicle (a vehicle-frame setpoint, neutral, a
//!   vehicle-frame rate, nothing commanded). The postback's control mode does not decide
//!   it: the gimbal reports lock after any angle command, a vehicle-frame one included,
//!   and the document does not say whether its lock holds north.
//! - `ROLL_LOCK` and `PITCH_LOCK` always (no roll axis; pitch is held to the horizon).
//! - `NEUTRAL` and `RETRACT` while the pose last commanded is the one they name and nothing
//!   has moved the gimbal since.

use idu_gimbal::wire::postback::Postback;
use mavio::dialects::common::enums::GimbalDeviceFlags;

use crate::attitude::{wrap_pi, YawPitch};

/// The pose last commanded.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Pose {
    /// Re-centred (a setpoint with `NEUTRAL`), nothing since.
    Neutral,
    /// Looking down, the gimbal's stowed pose (a setpoint with `RETRACT`), nothing since.
    Retracted,
    /// Anything else: angles, rates, a region of interest.
    Other,
}

/// What the device holds, for the flags.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Held {
    /// The pose last commanded.
    pub pose: Pose,
    /// The yaw is held in the earth frame (an earth-frame aim or rate, a region of
    /// interest), not following the vehicle.
    pub earth_yaw: bool,
}

/// The status flags for what the device holds.
pub fn flags(held: Held) -> GimbalDeviceFlags {
    let mut f = GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME
        | GimbalDeviceFlags::ROLL_LOCK
        | GimbalDeviceFlags::PITCH_LOCK;
    if held.earth_yaw {
        f |= GimbalDeviceFlags::YAW_LOCK;
    }
    match held.pose {
        Pose::Neutral => f |= GimbalDeviceFlags::NEUTRAL,
        Pose::Retracted => f |= GimbalDeviceFlags::RETRACT,
        Pose::Other => {}
    }
    f
}

/// The status quaternion of a postback, in the vehicle frame (yaw = the motor angle from
/// the nose, pitch from the horizon).
pub fn attitude(p: &Postback) -> [f32; 4] {
    attitude_turned(p, 0.0)
}

/// The status quaternion of a postback in the vehicle frame, its motor angle turned by
/// `turned_rad`: what the motor has turned since the postback while the gimbal holds a yaw
/// in the earth frame (the vehicle's heading then, less its heading now).
pub fn attitude_turned(p: &Postback, turned_rad: f32) -> [f32; 4] {
    YawPitch {
        yaw_rad: wrap_pi(p.motor_heading_deg().to_radians() + turned_rad),
        pitch_rad: p.pitch_deg().to_radians(),
    }
    .to_quaternion()
}

/// The camera's attitude in the earth frame (NED): the postback's motor angle turned by the
/// vehicle's heading, `vehicle_yaw_rad`, and its pitch from the horizon (the gimbal holds
/// roll level); `q_earth = q_delta_yaw · q_vehicle`, as common.xml relates the status's two
/// frames.
pub fn earth_attitude(p: &Postback, vehicle_yaw_rad: f32) -> [f32; 4] {
    // The same sum as a turned motor angle's: the motor angle plus an angle.
    attitude_turned(p, vehicle_yaw_rad)
}

#[cfg(test)]
mod tests {
    use super::*;
    use idu_gimbal::wire::postback::{ControlMode, GimbalType};

    fn postback(mode: ControlMode, pitch: i16, heading: u16, motor: i16) -> Postback {
        Postback {
            gimbal_type: GimbalType::X30,
            mode,
            pitch,
            heading,
            motor_heading: motor,
            ..Postback::default()
        }
    }

    #[test]
    fn yaw_is_the_motor_angle_whatever_the_heading() {
        // Heading 100° (north-referenced) with the motor 30° right of the nose: the
        // vehicle points 70°; the status says 30° in the vehicle frame.
        let q = attitude(&postback(ControlMode::Lock, -4500, 10_000, 3_000));
        // By hand: yaw 30°, pitch −45°: w = cos15·cos(−22.5), x = −sin15·sin(−22.5),
        // y = cos15·sin(−22.5), z = sin15·cos(−22.5).
        let (c15, s15) = (0.965_925_8_f32, 0.258_819_04_f32);
        let (c22, s22) = (0.923_879_5_f32, -0.382_683_43_f32);
        let expected = [c15 * c22, -s15 * s22, c15 * s22, s15 * c22];
        for (a, b) in q.iter().zip(expected) {
            assert!((a - b).abs() < 1e-6, "{q:?} vs {expected:?}");
        }
    }

    #[test]
    fn the_earth_attitude_adds_the_vehicle_heading_to_the_motor() {
        // Motor 30° right, vehicle at 70°: the camera looks at 100° from north, 45° down.
        // By hand: yaw 100°, pitch −45°: w = cos50·cos(−22.5), x = −sin50·sin(−22.5),
        // y = cos50·sin(−22.5), z = sin50·cos(−22.5).
        let q = earth_attitude(
            &postback(ControlMode::Lock, -4500, 0, 3_000),
            70f32.to_radians(),
        );
        let (c50, s50) = (0.642_787_6_f32, 0.766_044_4_f32);
        let (c22, s22) = (0.923_879_5_f32, -0.382_683_43_f32);
        let expected = [c50 * c22, -s50 * s22, c50 * s22, s50 * c22];
        for (a, b) in q.iter().zip(expected) {
            // f32 sine and cosine of the half angles: within 1e-6.
            assert!((a - b).abs() < 1e-6, "{q:?} vs {expected:?}");
        }
        // Across north: motor −30°, vehicle at 10°: 340°, read back as −20°.
        let q = earth_attitude(
            &postback(ControlMode::Lock, 0, 0, -3_000),
            10f32.to_radians(),
        );
        let a = YawPitch::from_quaternion(q).unwrap();
        assert!((a.yaw_rad.to_degrees() + 20.0).abs() < 1e-4, "{a:?}");
    }

    #[test]
    fn yaw_lock_says_the_yaw_is_held_in_the_earth_frame_and_the_pose_its_flag() {
        let held = |pose, earth_yaw| flags(Held { pose, earth_yaw });
        let follow = held(Pose::Other, false);
        assert!(!follow.contains(GimbalDeviceFlags::YAW_LOCK));
        assert!(follow.contains(
            GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME
                | GimbalDeviceFlags::ROLL_LOCK
                | GimbalDeviceFlags::PITCH_LOCK
        ));
        assert!(!follow.contains(GimbalDeviceFlags::YAW_IN_EARTH_FRAME));
        let lock = held(Pose::Other, true);
        assert!(
            lock.contains(GimbalDeviceFlags::YAW_LOCK | GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME)
        );
        assert!(held(Pose::Neutral, false).contains(GimbalDeviceFlags::NEUTRAL));
        let r = held(Pose::Retracted, false);
        assert!(r.contains(GimbalDeviceFlags::RETRACT) && !r.contains(GimbalDeviceFlags::NEUTRAL));
        assert!(!follow.intersects(GimbalDeviceFlags::NEUTRAL | GimbalDeviceFlags::RETRACT));
    }

    #[test]
    fn the_whole_motor_range_and_pitch_past_minus_90_read_back() {
        for (motor, pitch) in [
            (-17_000, -10_000),
            (17_000, -9_000),
            (-32_500, 6_000),
            (0, -11_000),
        ] {
            let q = attitude(&postback(ControlMode::Lock, pitch, 0, motor));
            let a = YawPitch::from_quaternion(q).unwrap();
            // f32 trigonometry: within 1e-5 rad (0.0006°), as in `attitude`'s tests.
            let motor_rad = wrap_pi((f32::from(motor) / 100.0).to_radians());
            assert!(
                wrap_pi(a.yaw_rad - motor_rad).abs() < 1e-5,
                "{motor} {pitch}: {a:?}"
            );
            assert!((a.pitch_rad - (f32::from(pitch) / 100.0).to_radians()).abs() < 1e-5);
        }
    }
}
