//! Pointing at a location: keeping the gimbal on a ground target while the vehicle moves.
//!
//! Every `point_at_period_ms` (default 100 ms, 10 Hz) the link computes the exact WGS84
//! bearing and elevation from the vehicle's latest fresh GPS position and altitude to the
//! target ([`crate::geo::look_at`]): an aim in the earth frame (bearing from north, pitch
//! the elevation), held by the link's closed loop ([`super::aim`]) exactly as an aim given
//! to [`Link::aim`](super::Link::aim) is. So the aim is sent in the gimbal's reference (north
//! once the attitude has reached it, the nose otherwise, converted with the vehicle's
//! heading), again when the vehicle turns, and again when a postback shows the gimbal off
//! it; a new bearing or elevation is sent only past the dead-band
//! ([`Config::aim_deadband_mdeg`](super::Config::aim_deadband_mdeg)).
//!
//! - A target whose elevation is outside the gimbal's pitch range [-100°, 60°] raises
//!   [`Event::TargetUnreachable`] once, and the gimbal holds the last reachable aim:
//!   nothing is clamped.
//! - Without fresh GPS and altitude no new aim is computed; without a fresh vehicle
//!   heading where the gimbal is nose-referenced nothing is sent.
//! - Any other pointing command, a rate hold, an aim, or
//!   [`Link::stop_pointing`](super::Link::stop_pointing) cancels it.

use super::aim::{Aim, Hold, Yaw};
use crate::geo::{look_at, Position};
use crate::time::Instant;
use crate::wire::control::{Heading, Pitch};
use crate::wire::vehicle::{Altitude, Gps};

/// The outcome of one aim computation.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Solution {
    /// The bearing from north and the pitch that point at the target.
    At(Heading, Pitch),
    /// The target needs this elevation (0.01°), outside the pitch range.
    Unreachable { elevation_cdeg: i16 },
    /// No aim (vehicle position invalid, or the target at the vehicle).
    Unknown,
}

/// Computes the aim from the vehicle's latest GPS position and altitude (reached only from
/// the point-at step, see [`Link::point_step`](super::Link::point_step)).
pub(crate) fn solve(target: &Target, gps: &Gps, alt: &Altitude) -> Solution {
    let Ok(vehicle) = Position::new(gps.lat_deg(), gps.lon_deg(), alt.metres()) else {
        return Solution::Unknown;
    };
    let Some(target) = target.position() else {
        return Solution::Unknown;
    };
    let Ok(angles) = look_at(&vehicle, &target) else {
        return Solution::Unknown;
    };
    let Ok(pitch) = Pitch::new(angles.elevation_deg as f32) else {
        // |elevation| <= 90°, so the centidegrees fit an i16.
        return Solution::Unreachable {
            elevation_cdeg: libm::round(angles.elevation_deg * 100.0) as i16,
        };
    };
    match Heading::new(wrap_360(angles.bearing_deg) as f32) {
        Ok(bearing) => Solution::At(bearing, pitch),
        Err(_) => Solution::Unknown,
    }
}

/// A target kept in the units of the vehicle frames (1e-7°, cm): 12 bytes instead of three
/// `f64`, at a resolution (about 1 cm) far below a gimbal's pointing resolution.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Target {
    lat_e7: i32,
    lon_e7: i32,
    alt_cm: i32,
}

impl Target {
    pub(crate) fn new(p: &Position) -> Self {
        // A valid Position's latitude, longitude and altitude fit these units.
        Target {
            lat_e7: libm::round(p.lat_deg() * 1e7) as i32,
            lon_e7: libm::round(p.lon_deg() * 1e7) as i32,
            alt_cm: libm::round(p.alt_m() * 100.0) as i32,
        }
    }

    pub(crate) fn position(&self) -> Option<Position> {
        Position::new(
            f64::from(self.lat_e7) / 1e7,
            f64::from(self.lon_e7) / 1e7,
            f64::from(self.alt_cm) / 100.0,
        )
        .ok()
    }
}

/// State of an active point-at.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PointAt<const Q: usize, const T: usize, M: Medium> {
    pub(crate) target: Target,
    /// Compute the aim at the next step, whatever the grid says (the first, or a retry).
    pub(crate) due: bool,
    pub(crate) unreachable: bool,
    /// The aim at the target, held closed loop, once one was computed. Its step is the
    /// point-at's: the whole point-at, reached only through this pointer, which
    /// [`Link::point_at`](super::Link::point_at) stores, so that firmware that never points
    /// at a location links none of it, nor the double-precision geodesy behind it.
    pub(crate) hold: Hold<Q, T, M>,
    pub(crate) aiming: bool,
}

impl<const Q: usize, const T: usize, M: Medium> PointAt<Q, T, M> {
    pub(crate) fn new(target: Position) -> Self {
        let placeholder = Aim {
            yaw: Yaw::Earth(Heading::NORTH),
            pitch: Pitch::LEVEL,
        };
        PointAt {
            target: Target::new(&target),
            due: true,
            unreachable: false,
            // Its first look is unread: the first step (`due`) sets it.
            hold: Hold::new(
                placeholder,
                super::Link::point_step,
                Instant::from_millis(0),
            ),
            aiming: false,
        }
    }

    /// The aim held, once one was computed.
    pub(crate) fn aim_hold(&self) -> Option<&Hold<Q, T, M>> {
        self.aiming.then_some(&self.hold)
    }
}

/// `deg` normalised into [0, 360).
pub(crate) fn wrap_360(deg: f64) -> f64 {
    let d = libm::fmod(deg, 360.0);
    if d < 0.0 {
        d + 360.0
    } else {
        d
    }
}

// The link's side of pointing: starting, stopping, and the step each poll takes.
use super::*;

impl<const Q: usize, const T: usize, M: Medium> Link<Q, T, M> {
    /// Keeps the gimbal pointed at `target` while the vehicle moves: every
    /// `point_at_period_ms` ([`Config`]) the exact WGS84 bearing and elevation from the
    /// vehicle's fresh GPS and altitude become an earth-frame aim, held closed loop (see
    /// [`aim`]); a target out of the pitch range raises
    /// [`Event::TargetUnreachable`] once. Ends a rate hold or an aim (the heading and pitch
    /// commands that follow replace it).
    ///
    /// No aim is computed while the vehicle's GPS or altitude is stale, while its altitude
    /// is outside the geodesy's range ([`ALT_MIN_M`](crate::geo::ALT_MIN_M) to
    /// [`ALT_MAX_M`](crate::geo::ALT_MAX_M)), or while the target is within
    /// [`MIN_RANGE_M`](crate::geo::MIN_RANGE_M) of the vehicle (no bearing): the aim held
    /// before stays, and until the first one [`Link::aim_state`] is `None`.
    ///
    /// Its aims' heading and pitch go together, as [`Link::aim`]'s: with `Q` below 2 a call
    /// does not compile.
    pub fn point_at(&mut self, target: Position) {
        const {
            assert!(
                Q >= 2,
                "an aim sends a heading and a pitch together: Q >= 2"
            )
        };
        self.quiet = quiet::Quiet::NONE;
        // A zero-rate frame still waiting would arrive after the aim and could undo it.
        self.tx.cancel_zero_rate();
        self.steering = Steering::Point(PointAt::new(target));
    }

    /// Stops pointing at a location (the gimbal keeps its last aim).
    pub fn stop_pointing(&mut self) {
        if let Steering::Point(_) = self.steering {
            self.steering = Steering::Manual;
        }
    }

    /// The target being pointed at, if any (kept to 1e-7° and 1 cm).
    pub fn pointing_target(&self) -> Option<Position> {
        match self.steering {
            Steering::Point(p) => p.target.position(),
            _ => None,
        }
    }

    /// The steering's step at a poll: an aim's or a point-at's, through the pointer each
    /// stored when it started.
    pub(super) fn poll_steering(&mut self, now: Instant, earliest: &mut Earliest) {
        match self.steering {
            Steering::Point(p) => (p.hold.step)(self, now, earliest),
            Steering::Aim(h) => (h.step)(self, now, earliest),
            Steering::Manual | Steering::Rate(_) => {}
        }
    }

    /// One point-at step, on the closed loop's grid at `point_at_period_ms`: a new aim at
    /// the target, and the loop's step.
    pub(super) fn point_step(&mut self, now: Instant, earliest: &mut Earliest) {
        let Steering::Point(mut p) = self.steering else {
            return;
        };
        let period = u32::from(self.config.point_at_period_ms.get());
        if p.due || now.is_at_or_after(p.hold.next) {
            let first = p.due;
            p.due = false;
            if self.is_fresh(GPS, now) && self.is_fresh(ALTITUDE, now) {
                let solution = solve(&p.target, &self.vehicle.gps, &self.vehicle.altitude);
                self.aim_at(&mut p, solution, now);
            }
            if p.aiming {
                // The loop looks on the point-at's grid (it sets the next look).
                self.hold_look(&mut p.hold, now, period, earliest);
            } else {
                // No aim yet: look again a period on.
                p.hold.next = if first {
                    now.add_millis(period)
                } else {
                    advance(p.hold.next, period, now)
                };
                earliest.offer(p.hold.next);
            }
        } else {
            earliest.offer(p.hold.next);
        }
        self.steering = Steering::Point(p);
    }

    pub(super) fn aim_at(&mut self, p: &mut PointAt<Q, T, M>, solution: Solution, now: Instant) {
        match solution {
            Solution::Unknown => {}
            Solution::Unreachable { elevation_cdeg } => {
                if !p.unreachable {
                    p.unreachable = true;
                    self.status
                        .raise(Event::TargetUnreachable { elevation_cdeg });
                }
            }
            Solution::At(bearing, pitch) => {
                p.unreachable = false;
                let aim = Aim {
                    yaw: Yaw::Earth(bearing),
                    pitch,
                };
                if p.aiming {
                    p.hold
                        .update(aim, i32::from(self.config.aim_deadband_mdeg) / 10);
                } else {
                    p.hold = Hold::new(aim, Self::point_step, now);
                    p.aiming = true;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap() {
        assert_eq!(wrap_360(-10.0), 350.0);
        assert_eq!(wrap_360(370.0), 10.0);
        assert_eq!(wrap_360(0.0), 0.0);
    }
}
