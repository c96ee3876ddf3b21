//! The stand-in vehicle data of the firmware (`boards/stm32f405`'s `stm32f405` and the other
//! board crates under `boards/`).

use idu_gimbal::link::{Link, Medium};
use idu_gimbal::wire::vehicle::{Altitude, Attitude, Gps};
use idu_gimbal::Instant;

/// The vehicle's position, altitude and attitude, measured at one instant: what a firmware
/// hands its link, directly or from a vehicle task through a channel (the embassy boards).
#[derive(Clone, Copy)]
pub struct Vehicle {
    /// The vehicle's position.
    pub gps: Gps,
    /// The vehicle's altitude.
    pub altitude: Altitude,
    /// The vehicle's attitude.
    pub attitude: Attitude,
    /// When they were measured.
    pub stamp: Instant,
}

impl Vehicle {
    /// Gives the link each value, measured at the stamp.
    pub fn push<const Q: usize, const T: usize, M: Medium>(&self, link: &mut Link<Q, T, M>) {
        link.set_gps(self.gps, self.stamp);
        link.set_altitude(self.altitude, self.stamp);
        link.set_attitude(self.attitude, self.stamp);
    }
}

/// STAND-IN VEHICLE DATA. Replace with the autopilot's estimates (for example MAVLink
/// `GLOBAL_POSITION_INT` and `ATTITUDE`, or your EKF outputs), each with the time it was
/// measured. Here: a vehicle hovering over a fixed point while it slowly yaws, measured at
/// `now`.
pub fn vehicle_stand_in(now: Instant) -> Option<Vehicle> {
    // One degree of yaw every 100 ms, in [-180, 180).
    let heading = ((now.as_millis() / 100) % 360) as f32 - 180.0;
    Some(Vehicle {
        gps: Gps::new(47.397_742, 8.545_594).ok()?,
        altitude: Altitude::new(488.0).ok()?,
        attitude: Attitude::new(1.5, -0.4, heading).ok()?,
        stamp: now,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The stand-in yaws a degree every 100 ms from −180°, round to −180° again every 36 s,
    /// at a fixed place, height and tilt, stamped when asked.
    #[test]
    fn the_stand_in_yaws_a_degree_every_100_ms() {
        let heading = |ms| {
            let v = vehicle_stand_in(Instant::from_millis(ms)).unwrap();
            assert_eq!(v.stamp, Instant::from_millis(ms));
            assert_eq!((v.gps.lat_e7(), v.gps.lon_e7()), (473_977_420, 85_455_940));
            assert_eq!(v.altitude.cm(), 48_800);
            assert_eq!(v.attitude.pitch_centideg(), 150);
            assert_eq!(v.attitude.roll_centideg(), -40);
            v.attitude.heading_centideg()
        };
        assert_eq!(heading(0), -18_000);
        assert_eq!(heading(99), -18_000);
        assert_eq!(heading(100), -17_900);
        assert_eq!(heading(18_000), 0);
        assert_eq!(heading(35_999), 17_900);
        assert_eq!(heading(36_000), -18_000);
    }
}
