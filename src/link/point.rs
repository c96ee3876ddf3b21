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

use crate::geo::Position;
use crate::time::Instant;

/// State of an active point-at.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PointAt {
    pub(crate) target: Position,
    pub(crate) next: Instant,
    pub(crate) due: bool,
    /// Heading and pitch last sent, in wire units (0.1°).
    pub(crate) sent: Option<(u16, i16)>,
    pub(crate) unreachable: bool,
}

impl PointAt {
    pub(crate) fn new(target: Position) -> Self {
        PointAt {
            target,
            next: Instant::from_millis(0),
            due: true,
            sent: None,
            unreachable: false,
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
