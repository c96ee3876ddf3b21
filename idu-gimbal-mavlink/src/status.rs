//! What `GIMBAL_DEVICE_ATTITUDE_STATUS` reports, and why in the vehicle frame.
//!
//! The status is always in the vehicle frame (`YAW_IN_VEHICLE_FRAME`): `q`'s yaw is the
//! gimbal's yaw motor angle relative to the nose, from the postback, and `delta_yaw` is
//! the vehicle's heading from north (the autopilot's `AUTOPILOT_STATE_FOR_GIMBAL_DEVICE`),
//! NaN when the bridge has none. common.xml defines the pair by "q_earth = q_delta_yaw *
//! q_vehicle", so a reader gets the earth-frame yaw as motor + delta_yaw.
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
//! Flags: `ROLL_LOCK` and `PITCH_LOCK` always (no roll axis; pitch is held to the
//! horizon), `YAW_LOCK` while the postback's control mode holds the heading against the
//! vehicle's turns (lock or full lock, not heading follow), `NEUTRAL` and `RETRACT` while
//! the pose last commanded is the one they name and nothing has moved the gimbal since.

use idu_gimbal::wire::postback::{ControlMode, Postback};
use mavio::dialects::common::enums::GimbalDeviceFlags;

use crate::attitude::{wrap_pi, YawPitch};

/// The pose last commanded.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Pose {
    /// Re-centred (a setpoint with `NEUTRAL`), nothing since.
    Neutral,
    /// Looking down, the gimbal's stowed pose (a setpoint with `RETRACT`), nothing since.
    Retracted,
    /// Anything else: angles, rates, a region of interest.
    Other,
}

/// The status flags for the latest postback (`None`: none yet) and the pose.
pub fn flags(postback: Option<&Postback>, pose: Pose) -> GimbalDeviceFlags {
    let mut f = GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME
        | GimbalDeviceFlags::ROLL_LOCK
        | GimbalDeviceFlags::PITCH_LOCK;
    if postback.is_some_and(|p| matches!(p.mode, ControlMode::Lock | ControlMode::FullLock)) {
        f |= GimbalDeviceFlags::YAW_LOCK;
    }
    match pose {
        Pose::Neutral => f |= GimbalDeviceFlags::NEUTRAL,
        Pose::Retracted => f |= GimbalDeviceFlags::RETRACT,
        Pose::Other => {}
    }
    f
}

/// The status quaternion of a postback, in the vehicle frame (yaw = the motor angle from
/// the nose, pitch from the horizon), and the flags.
pub fn attitude(p: &Postback, pose: Pose) -> ([f32; 4], GimbalDeviceFlags) {
    let q = YawPitch {
        yaw_rad: wrap_pi(p.motor_heading_deg().to_radians()),
        pitch_rad: p.pitch_deg().to_radians(),
    }
    .to_quaternion();
    (q, flags(Some(p), pose))
}

#[cfg(test)]
mod tests {
    use super::*;
    use idu_gimbal::wire::postback::GimbalType;

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
        let (q, f) = attitude(
            &postback(ControlMode::Lock, -4500, 10_000, 3_000),
            Pose::Other,
        );
        // By hand: yaw 30°, pitch −45°: w = cos15·cos(−22.5), x = −sin15·sin(−22.5),
        // y = cos15·sin(−22.5), z = sin15·cos(−22.5).
        let (c15, s15) = (0.965_925_8_f32, 0.258_819_04_f32);
        let (c22, s22) = (0.923_879_5_f32, -0.382_683_43_f32);
        let expected = [c15 * c22, -s15 * s22, c15 * s22, s15 * c22];
        for (a, b) in q.iter().zip(expected) {
            assert!((a - b).abs() < 1e-6, "{q:?} vs {expected:?}");
        }
        assert!(f.contains(GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME));
        assert!(!f.contains(GimbalDeviceFlags::YAW_IN_EARTH_FRAME));
        assert!(f.contains(GimbalDeviceFlags::YAW_LOCK));
    }

    #[test]
    fn yaw_lock_follows_the_postbacks_mode_and_the_pose_its_flag() {
        let follow = postback(ControlMode::HeadingFollow, 0, 0, 0);
        assert!(!flags(Some(&follow), Pose::Other).contains(GimbalDeviceFlags::YAW_LOCK));
        let full = postback(ControlMode::FullLock, 0, 0, 0);
        assert!(flags(Some(&full), Pose::Other).contains(GimbalDeviceFlags::YAW_LOCK));
        let unknown = postback(ControlMode::Unknown(9), 0, 0, 0);
        assert!(!flags(Some(&unknown), Pose::Other).contains(GimbalDeviceFlags::YAW_LOCK));
        assert!(flags(None, Pose::Neutral).contains(GimbalDeviceFlags::NEUTRAL));
        let r = flags(None, Pose::Retracted);
        assert!(r.contains(GimbalDeviceFlags::RETRACT) && !r.contains(GimbalDeviceFlags::NEUTRAL));
        assert!(!flags(None, Pose::Other)
            .intersects(GimbalDeviceFlags::NEUTRAL | GimbalDeviceFlags::RETRACT));
    }

    #[test]
    fn the_whole_motor_range_and_pitch_past_minus_90_read_back() {
        for (motor, pitch) in [
            (-17_000, -10_000),
            (17_000, -9_000),
            (-32_500, 6_000),
            (0, -11_000),
        ] {
            let (q, _) = attitude(&postback(ControlMode::Lock, pitch, 0, motor), Pose::Other);
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
