//! What the bridge needs of the autopilot: the streams it asks for with
//! `MAV_CMD_SET_MESSAGE_INTERVAL` until they come, and the vehicle they describe (its
//! attitude pushed to the gimbal, its heading and yaw rate for the yaw frames, its
//! position).

use idu_gimbal::wire::vehicle::{Altitude, Attitude, Gps};
use idu_gimbal::Instant;
use mavio::dialects::common::enums::{MavAutopilot, MavCmd};
use mavio::dialects::common::messages::{
    AutopilotStateForGimbalDevice, CommandLong, GlobalPositionInt,
};

use super::{State, AUTOPILOT_COMPONENT, AUTOPILOT_SILENCE_MS};
use crate::attitude;
use crate::tx::bump;
use idu_gimbal::link::{Link, Medium};

/// How often to ask the autopilot again for a stream that does not come.
const STREAM_RETRY_MS: u32 = 5_000;

/// How often the streams are looked at, ms: an ask is at most this late.
const STREAM_CHECK_MS: u32 = 100;

/// A stream not heard for this long is asked for again (an autopilot that rebooted has
/// forgotten the interval it was asked for).
const STREAM_LOST_MS: u32 = 5_000;

/// A stream the bridge asks the autopilot for with `MAV_CMD_SET_MESSAGE_INTERVAL`.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) struct Wanted {
    /// The message id.
    id: u32,
    /// The interval asked for, µs.
    interval_us: u32,
    /// Asked for once per autopilot, whether it comes or not (a stream that comes anyway,
    /// but may come too slowly); otherwise until it comes.
    once: bool,
}

/// `GLOBAL_POSITION_INT` at 5 Hz: the vehicle position for the gimbal, point-at and the
/// captures. Neither autopilot sends it to a gimbal port unasked.
const POSITION_STREAM: Wanted = Wanted {
    id: 33,
    interval_us: 200_000,
    once: false,
};

/// `AUTOPILOT_STATE_FOR_GIMBAL_DEVICE` at 20 Hz: the vehicle attitude pushed to the
/// gimbal and the yaw that relates the setpoint and status frames. ArduPilot sends it to
/// a MAVLink gimbal by itself; PX4 streams it only on a port in mode Gimbal (its
/// `configure_streams`), so on any other port it must be asked for.
const AUTOPILOT_STATE_STREAM: Wanted = Wanted {
    id: 286,
    interval_us: 50_000,
    once: false,
};

/// `GIMBAL_DEVICE_SET_ATTITUDE` at 20 Hz, asked once, and again with the autopilot state
/// when that stream stops (a restarted autopilot forgets both): PX4 re-sends its latest setpoint at
/// the stream's rate, 5 Hz on a port in mode Normal (`configure_streams`), too slow for a
/// smooth rate or ROI. Not asked of ArduPilot (its heartbeat's autopilot): it sends its
/// setpoints at 50 Hz unasked and has no such stream, so it answers `DENIED`, and its SITL
/// tells the ground station too ("No ap_message for mavlink id (284)",
/// `GCS_Common.cpp` `set_message_interval`).
const SETPOINT_STREAM: Wanted = Wanted {
    id: 284,
    interval_us: 50_000,
    once: true,
};

/// A stream asked of the autopilot: when it was last asked for and last heard.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct StreamState {
    asked: Option<Instant>,
    heard: Option<Instant>,
}

impl StreamState {
    /// Whether to ask (again) at `now`: not heard lately, and not asked lately; a stream
    /// asked for once, when never asked.
    fn due(&self, wanted: &Wanted, now: Instant) -> bool {
        if wanted.once {
            return self.asked.is_none();
        }
        let lost = self
            .heard
            .is_none_or(|t| now.millis_since(t) >= STREAM_LOST_MS);
        lost && self
            .asked
            .is_none_or(|t| now.millis_since(t) >= STREAM_RETRY_MS)
    }
}

/// The vehicle, as the autopilot last described it.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Vehicle {
    /// Yaw (radians, NED: from north) and when it was measured.
    pub(crate) yaw: Option<(f32, Instant)>,
    /// Yaw rate (rad/s, about NED's down axis), the autopilot's or from its last two yaws.
    pub(crate) yaw_rate: Option<(f32, Instant)>,
    /// The last yaw (radians) and the autopilot's `time_boot_us` of it, its low 32 bits (a
    /// clock that wraps every 71 minutes, read across the wrap), for a rate.
    pub(crate) yaw_sample: Option<(f32, u32)>,
    /// From GLOBAL_POSITION_INT: lat, lon (1e-7°), alt and relative alt (mm).
    pub(crate) position: Option<[i32; 4]>,
}

/// A vehicle yaw older than this cannot convert a setpoint's yaw frame or be reported as
/// `delta_yaw` (as the core's vehicle data staleness, 1 s).
pub(crate) const VEHICLE_YAW_STALE_MS: u32 = 1_000;

impl Vehicle {
    /// The vehicle's yaw from north, radians, when fresh.
    pub(crate) fn yaw(&self, now: Instant) -> Option<f32> {
        fresh(self.yaw, now)
    }

    /// The vehicle's yaw rate, rad/s, when fresh.
    pub(crate) fn yaw_rate(&self, now: Instant) -> Option<f32> {
        fresh(self.yaw_rate, now)
    }
}

fn fresh(v: Option<(f32, Instant)>, now: Instant) -> Option<f32> {
    v.filter(|&(_, at)| now.millis_since(at) <= VEHICLE_YAW_STALE_MS)
        .map(|(v, _)| v)
}

impl State {
    /// A heartbeat: the autopilot's (component 1) gives the system id (unless configured)
    /// and, when it is a new one, asks it for the streams at once. `autopilot` is the
    /// heartbeat's `MAV_AUTOPILOT`.
    pub(super) fn heartbeat(&mut self, system: u8, component: u8, autopilot: u8, now: Instant) {
        if component != AUTOPILOT_COMPONENT {
            return;
        }
        // Who may be the autopilot (see `BridgeConfig::system_id`).
        let live = self
            .autopilot_heard
            .is_some_and(|t| now.millis_since(t) < AUTOPILOT_SILENCE_MS);
        if system == 0
            || autopilot == MavAutopilot::Invalid as u8
            || self.config.system_id.is_some_and(|id| id != system)
            || (live && self.autopilot != Some((system, component)))
        {
            bump(&mut self.stats.other_autopilots);
            return;
        }
        self.autopilot_heard = Some(now);
        if self.autopilot != Some((system, component)) {
            // A new autopilot: ask it for the streams at once.
            self.position_stream.asked = None;
            self.autopilot_state_stream.asked = None;
            // Taken as asked where the ask is refused (see `SETPOINT_STREAM`).
            self.setpoints_askable = autopilot != MavAutopilot::Ardupilotmega as u8;
            self.setpoint_stream.asked = (!self.setpoints_askable).then_some(now);
            self.next_stream_check = None;
        }
        self.autopilot = Some((system, component));
        if self.config.system_id.is_none() {
            self.out.system_id = system;
        }
    }

    pub(super) fn autopilot_state<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
        state: &AutopilotStateForGimbalDevice,
        rate_sent: bool,
        now: Instant,
    ) {
        self.autopilot_state_stream.heard = Some(now);
        // The vehicle's attitude: 3-2-1 Euler is right here (a vehicle does not pitch past
        // ±90° in flight, and the frame carries roll).
        let [w, x, y, z] = state.q;
        if !state.q.iter().all(|v| v.is_finite()) {
            bump(&mut self.stats.refused_vehicle_updates);
            return;
        }
        let roll = libm::atan2f(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y));
        let pitch = attitude::asin((2.0 * (w * y - z * x)).clamp(-1.0, 1.0));
        let yaw = libm::atan2f(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
        // atan2's π (a vehicle facing south) is normalised by `Attitude::new` into the
        // wire's [−180°, 180°), as −180.00°. A finite quaternion far from unit length can
        // still overflow to NaN: refused, its yaw not kept.
        let Ok(a) = Attitude::new(pitch.to_degrees(), roll.to_degrees(), yaw.to_degrees()) else {
            bump(&mut self.stats.refused_vehicle_updates);
            return;
        };
        self.vehicle.yaw = Some((yaw, now));
        // common.xml: "Z component of angular velocity in NED (North, East, Down). NaN if
        // unknown". Not sent (PX4 never sets it, and MAVLink 2 drops its zero): from the
        // last two yaws, at most a second apart on the autopilot's clock.
        // The low 32 bits: the difference of two is right across their wrap.
        let us = state.time_boot_us as u32;
        let rate = if rate_sent {
            Some(state.angular_velocity_z).filter(|r| r.is_finite())
        } else {
            self.vehicle.yaw_sample.and_then(|(last, at)| {
                let dt = Some(us.wrapping_sub(at)).filter(|&d| d > 0 && d <= 1_000_000)?;
                // `dt` <= 10^6: exact in f32.
                Some(attitude::wrap_pi(yaw - last) / (dt as f32 * 1e-6))
            })
        };
        self.vehicle.yaw_sample = Some((yaw, us));
        self.vehicle.yaw_rate = rate.map(|r| (r, now));
        gimbal.set_attitude(a, now);
        bump(&mut self.stats.vehicle_updates);
    }

    pub(super) fn position<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
        pos: &GlobalPositionInt,
        now: Instant,
    ) {
        self.position_stream.heard = Some(now);
        match Gps::from_e7(pos.lat, pos.lon) {
            Ok(g) => {
                // The images' position too: only one the gimbal takes.
                self.vehicle.position = Some([pos.lat, pos.lon, pos.alt, pos.relative_alt]);
                gimbal.set_gps(g, now);
                bump(&mut self.stats.vehicle_updates);
            }
            Err(_) => bump(&mut self.stats.refused_vehicle_updates),
        }
        // Millimetres above mean sea level to centimetres, rounded toward zero.
        gimbal.set_altitude(Altitude::from_cm(pos.alt / 10), now);
    }

    /// Asks the autopilot again for each stream that has not come, or has stopped: looked
    /// at every [`STREAM_CHECK_MS`].
    pub(super) fn ask_for_streams(&mut self, now: Instant) {
        let check_streams = self.next_stream_check.is_none_or(|t| now.is_at_or_after(t));
        let (Some(ap), true) = (self.autopilot, check_streams) else {
            return;
        };
        self.next_stream_check = Some(now.add_millis(STREAM_CHECK_MS));
        // The state came and has stopped: the autopilot restarted (or its link was down),
        // forgetting the intervals asked of it; the setpoints' is asked again with it.
        if self.setpoints_askable
            && self.autopilot_state_stream.heard.is_some()
            && self
                .autopilot_state_stream
                .due(&AUTOPILOT_STATE_STREAM, now)
        {
            self.setpoint_stream.asked = None;
        }
        for (wanted, stream) in [
            (AUTOPILOT_STATE_STREAM, &mut self.autopilot_state_stream),
            (POSITION_STREAM, &mut self.position_stream),
            (SETPOINT_STREAM, &mut self.setpoint_stream),
        ] {
            if !stream.due(&wanted, now) {
                continue;
            }
            stream.asked = Some(now);
            let ask = CommandLong {
                target_system: ap.0,
                target_component: ap.1,
                command: MavCmd::SetMessageInterval,
                confirmation: 0,
                param1: wanted.id as f32,
                param2: wanted.interval_us as f32,
                param3: 0.0,
                param4: 0.0,
                param5: 0.0,
                param6: 0.0,
                param7: 0.0,
            };
            self.out.send(self.config.gimbal_component, &ask);
        }
    }
}
