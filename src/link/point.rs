//! Pointing at a location: keeping the gimbal on a ground target while the vehicle moves.
//!
//! Every `point_at_period_ms` (default 100 ms, 10 Hz) the link computes the exact WGS84
//! bearing and elevation from the vehicle's latest fresh GPS position and altitude to the
//! target ([`crate::geo::look_at`]), and sends a heading and a pitch angle command only
//! when either differs from what it last sent by more than the dead-band (default 0.1°):
//! gimbals jitter when re-commanded needlessly.
//!
//! - While attitude is being pushed (its push enabled and the data fresh), the gimbal
//!   references headings to north, so the heading sent is the true bearing. Otherwise (the
//!   attitude push disabled with a period of 0) it references them to the vehicle's nose,
//!   and the heading sent is the bearing minus the heading of the fresh attitude the
//!   application set. Without fresh attitude nothing is sent: the heading cannot be known.
//! - A target whose elevation is outside the gimbal's pitch range [-100°, 60°] raises
//!   [`Event::TargetUnreachable`](super::Event::TargetUnreachable) once, and the gimbal
//!   holds the last reachable aim: nothing is clamped.
//! - Without fresh GPS and altitude nothing is sent.
//! - Any other pointing command, a rate hold, or [`Link::stop_pointing`](super::Link::stop_pointing)
//!   cancels it.

use crate::geo::{look_at, Position};
use crate::time::Instant;
use crate::wire::control::{Heading, Pitch};
use crate::wire::vehicle::{Altitude, Gps};

/// What the heading command is relative to.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Reference {
    /// True north (attitude is pushed).
    North,
    /// The vehicle's nose, whose heading is given in 0.01°.
    Nose(i16),
}

/// The outcome of one aim computation.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Aim {
    /// Heading and pitch commands to send.
    At(Heading, Pitch),
    /// The target needs this elevation (0.01°), outside the pitch range.
    Unreachable { elevation_cdeg: i16 },
    /// No aim (vehicle position invalid, or the target at the vehicle).
    Unknown,
}

/// Computes the aim from the vehicle's latest GPS position and altitude (reached only from
/// the point-at step, see [`PointAt::step`]).
pub(crate) fn solve(target: &Target, gps: &Gps, alt: &Altitude, reference: Reference) -> Aim {
    let Ok(vehicle) = Position::new(gps.lat_deg(), gps.lon_deg(), alt.metres()) else {
        return Aim::Unknown;
    };
    let Some(target) = target.position() else {
        return Aim::Unknown;
    };
    let Ok(angles) = look_at(&vehicle, &target) else {
        return Aim::Unknown;
    };
    let bearing = match reference {
        Reference::North => angles.bearing_deg,
        Reference::Nose(heading_cdeg) => angles.bearing_deg - f64::from(heading_cdeg) / 100.0,
    };
    let Ok(pitch) = Pitch::new(angles.elevation_deg as f32) else {
        // |elevation| <= 90°, so the centidegrees fit an i16.
        return Aim::Unreachable {
            elevation_cdeg: libm::round(angles.elevation_deg * 100.0) as i16,
        };
    };
    match Heading::new(wrap_360(bearing) as f32) {
        Ok(heading) => Aim::At(heading, pitch),
        Err(_) => Aim::Unknown,
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
pub(crate) struct PointAt<const Q: usize, const T: usize> {
    pub(crate) target: Target,
    pub(crate) next: Instant,
    pub(crate) due: bool,
    /// Heading and pitch last sent, in wire units (0.1°).
    pub(crate) sent: Option<(u16, i16)>,
    pub(crate) unreachable: bool,
    /// The whole point-at step, reached only through this pointer, which
    /// [`Link::point_at`](super::Link::point_at) stores: firmware that never points at a
    /// location links none of it, nor the double-precision geodesy behind it.
    pub(crate) step: fn(&mut super::Link<Q, T>, Instant, &mut super::Earliest),
}

impl<const Q: usize, const T: usize> PointAt<Q, T> {
    pub(crate) fn new(target: Position) -> Self {
        PointAt {
            target: Target::new(&target),
            next: Instant::from_millis(0),
            due: true,
            sent: None,
            unreachable: false,
            step: super::Link::point_step,
        }
    }
}

/// Whether `new` differs from `old` by more than `deadband_mdeg`, in wire units of 0.1°;
/// headings compare around the circle.
pub(crate) fn moved(old: Option<(u16, i16)>, new: (u16, i16), deadband_mdeg: u32) -> bool {
    let Some((h0, p0)) = old else { return true };
    let dh = (i32::from(new.0) - i32::from(h0)).rem_euclid(3600);
    let dh = dh.min(3600 - dh).unsigned_abs();
    let dp = (i32::from(new.1) - i32::from(p0)).unsigned_abs();
    dh.max(dp).saturating_mul(100) > deadband_mdeg
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

impl<const Q: usize, const T: usize> Link<Q, T> {
    /// Keeps the gimbal pointed at `target` while the vehicle moves: every
    /// `point_at_period_ms` ([`Config`]) the exact WGS84 bearing and elevation from the
    /// vehicle's fresh GPS and altitude are sent as heading and pitch commands, past a
    /// dead-band; a target out of the pitch range raises [`Event::TargetUnreachable`] once.
    /// Ends a rate hold (the heading and pitch commands that follow replace it).
    pub fn point_at(&mut self, target: Position) {
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

    pub(super) fn poll_point(&mut self, now: Instant, earliest: &mut Earliest) {
        if let Steering::Point(p) = self.steering {
            (p.step)(self, now, earliest);
        }
    }

    /// One point-at step; see [`PointAt::step`].
    pub(super) fn point_step(&mut self, now: Instant, earliest: &mut Earliest) {
        let Steering::Point(mut p) = self.steering else {
            return;
        };
        if p.due || now.is_at_or_after(p.next) {
            let period = u32::from(self.config.point_at_period_ms);
            p.next = if p.due {
                now.add_millis(period)
            } else {
                advance(p.next, period, now)
            };
            p.due = false;
            // North-referenced while attitude is pushed; otherwise nose-referenced, which
            // needs the vehicle heading (none fresh: the aim cannot be known).
            let reference = if self.attitude_is_pushed(now) {
                Some(Reference::North)
            } else {
                self.is_fresh(ATTITUDE, now)
                    .then(|| Reference::Nose(self.vehicle.attitude.heading_centideg()))
            };
            if let (true, true, Some(reference)) = (
                self.is_fresh(GPS, now),
                self.is_fresh(ALTITUDE, now),
                reference,
            ) {
                let aim = solve(
                    &p.target,
                    &self.vehicle.gps,
                    &self.vehicle.altitude,
                    reference,
                );
                self.aim(&mut p, aim);
            }
        }
        // Due again (no room for the aim): the next poll retries.
        earliest.offer(if p.due { now } else { p.next });
        self.steering = Steering::Point(p);
    }

    pub(super) fn aim(&mut self, p: &mut PointAt<Q, T>, aim: Aim) {
        match aim {
            Aim::Unknown => {}
            Aim::Unreachable { elevation_cdeg } => {
                if !p.unreachable {
                    p.unreachable = true;
                    self.status
                        .raise(Event::TargetUnreachable { elevation_cdeg });
                }
            }
            Aim::At(heading, pitch) => {
                p.unreachable = false;
                let wire = (heading.deci(), pitch.deci());
                if !moved(p.sent, wire, u32::from(self.config.point_at_deadband_mdeg)) {
                    return;
                }
                if self.tx.control_free() < 2 {
                    // Both or neither; try again at the next poll.
                    self.stats.queue_full = self.stats.queue_full.wrapping_add(1);
                    p.due = true;
                    return;
                }
                let _ = self.tx.push_control(
                    Command::from(GimbalCommand::Heading(heading)).encode(),
                    &mut self.quiet,
                );
                let _ = self.tx.push_control(
                    Command::from(GimbalCommand::Pitch(pitch)).encode(),
                    &mut self.quiet,
                );
                p.sent = Some(wire);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dead_band_compares_around_the_circle() {
        assert!(moved(None, (0, 0), 100));
        assert!(
            !moved(Some((3599, 0)), (0, 0), 100),
            "0.1° across north is within 0.1°"
        );
        assert!(
            !moved(Some((0, 0)), (3599, 0), 100),
            "and back across north the other way"
        );
        assert!(moved(Some((3598, 0)), (0, 0), 100));
        assert!(!moved(Some((100, -450)), (101, -451), 100));
        assert!(moved(Some((100, -450)), (100, -452), 100));
        assert!(!moved(Some((100, -450)), (103, -450), 300));
    }

    #[test]
    fn wrap() {
        assert_eq!(wrap_360(-10.0), 350.0);
        assert_eq!(wrap_360(370.0), 10.0);
        assert_eq!(wrap_360(0.0), 0.0);
    }
}
