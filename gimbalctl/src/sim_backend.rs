//! The simulated gimbal behind `gimbalctl sim`.
//!
//! The server only needs "take a control frame" and "give me a postback when one is due";
//! [`SimGimbal`] is that seam. TEMPORARY: until the library's `sim::Simulator` is merged
//! into this branch, [`StandIn`] (a minimal gimbal that slews to angle commands) fills it.

use idu_gimbal::wire::control::{Command, GimbalCommand};
use idu_gimbal::wire::ids;
use idu_gimbal::wire::postback::Postback;
use idu_gimbal::Instant;

/// What the TCP server needs from a simulated gimbal.
pub trait SimGimbal {
    /// Takes a CAN frame addressed to the gimbal; an error is reported, never fatal.
    fn receive(&mut self, id: u32, data: &[u8], now: Instant) -> Result<(), String>;
    /// The postback due at `now`, if one is (every 500 ms).
    fn poll(&mut self, now: Instant) -> Option<Postback>;
}

/// The simulated gimbal `gimbalctl sim` runs.
pub fn new(now: Instant) -> impl SimGimbal {
    StandIn::new(now)
}

/// Stand-in gimbal: slews pitch and heading towards angle commands at 60 deg/s.
pub struct StandIn {
    pitch: f32,
    heading: f32,
    target_pitch: f32,
    target_heading: f32,
    last: Instant,
    next_postback: Instant,
}

impl StandIn {
    fn new(now: Instant) -> Self {
        StandIn {
            pitch: 0.0,
            heading: 0.0,
            target_pitch: 0.0,
            target_heading: 0.0,
            last: now,
            next_postback: now.add_millis(500),
        }
    }

    fn advance(&mut self, now: Instant) {
        let dt = now.millis_since(self.last) as f32 / 1000.0;
        self.last = now;
        let step = 60.0 * dt;
        let approach = |v: f32, t: f32| v + (t - v).clamp(-step, step);
        self.pitch = approach(self.pitch, self.target_pitch);
        self.heading = approach(self.heading, self.target_heading);
    }
}

impl SimGimbal for StandIn {
    fn receive(&mut self, id: u32, data: &[u8], now: Instant) -> Result<(), String> {
        self.advance(now);
        if id != ids::CONTROL {
            return Ok(());
        }
        match Command::decode(data).map_err(|e| e.to_string())? {
            Command::Gimbal(GimbalCommand::Pitch(p)) => self.target_pitch = p.degrees(),
            Command::Gimbal(GimbalCommand::Heading(h)) => self.target_heading = h.degrees(),
            Command::Gimbal(GimbalCommand::LookDown) => self.target_pitch = -90.0,
            Command::Gimbal(GimbalCommand::Recenter) => {
                self.target_pitch = 0.0;
                self.target_heading = 0.0;
            }
            _ => {}
        }
        Ok(())
    }

    fn poll(&mut self, now: Instant) -> Option<Postback> {
        self.advance(now);
        if !now.is_at_or_after(self.next_postback) {
            return None;
        }
        self.next_postback = self.next_postback.add_millis(500);
        Some(Postback {
            pitch: (self.pitch * 100.0).round() as i16,
            heading: (self.heading * 100.0).round() as u16,
            ..Postback::default()
        })
    }
}
