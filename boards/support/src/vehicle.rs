//! The stand-in vehicle data of the firmware (`boards/stm32f405`'s `stm32f405` and the other
//! board crates under `boards/`).

use idu_gimbal::wire::vehicle::{Altitude, Attitude, Gps};
use idu_gimbal::{Instant, Link};

/// The vehicle's position, altitude and attitude, measured at one instant.
pub type Vehicle = (Gps, Altitude, Attitude);

/// STAND-IN VEHICLE DATA. Replace with the autopilot's estimates (for example MAVLink
/// `GLOBAL_POSITION_INT` and `ATTITUDE`, or your EKF outputs), each with the time it was
/// measured. Here: a vehicle hovering over a fixed point while it slowly yaws.
pub fn vehicle_stand_in(now: Instant) -> Option<Vehicle> {
    // One degree of yaw every 100 ms, in [-180, 180).
    let heading = ((now.as_millis() / 100) % 360) as f32 - 180.0;
    let gps = Gps::new(47.397_742, 8.545_594).ok()?;
    let altitude = Altitude::new(488.0).ok()?;
    let attitude = Attitude::new(1.5, -0.4, heading).ok()?;
    Some((gps, altitude, attitude))
}

/// One vehicle state with the time it was measured: what a vehicle task hands the task
/// that owns the link (the embassy boards send it through a channel).
#[derive(Clone, Copy)]
pub struct Sample {
    /// The vehicle's attitude.
    pub attitude: Attitude,
    /// The vehicle's position.
    pub gps: Gps,
    /// The vehicle's altitude.
    pub altitude: Altitude,
    /// When it was measured.
    pub stamp: Instant,
}

impl Sample {
    /// Gives the link each value, measured at the sample's stamp.
    pub fn push<const Q: usize, const T: usize>(&self, link: &mut Link<Q, T>) {
        link.set_attitude(self.attitude, self.stamp);
        link.set_gps(self.gps, self.stamp);
        link.set_altitude(self.altitude, self.stamp);
    }
}
