//! What the link's property tests do to a link between polls: one set of operations, each
//! test drawing them with its own weights.

use super::*;
use crate::geo::Position;
use crate::wire::control::{Heading, ImagePoint, Pitch, Rate, TrackingBox};
use crate::wire::vehicle::{Altitude, Attitude, Gps};

#[derive(Clone, Debug)]
pub(super) enum Op {
    /// Nothing for this many milliseconds (the test's loop polls through them).
    Wait(u32),
    Rate(i16),
    StopRate,
    Pitch,
    /// Attitude, GPS and altitude measured this long ago.
    Vehicle {
        stamp_back: u32,
    },
    Gps {
        stamp_back: u32,
    },
    Postback,
    /// A postback whose CRC fails.
    BadPostback,
    PostbackFrame(u8),
    /// A postback taken with a time behind the last poll's (a late-processed frame, a
    /// clock stepped back): the deadlines it brings are before the idle interval ends.
    LatePostback(u32),
    PointAt,
    StopPointing,
    Text,
    Aim {
        earth: bool,
        yaw: u16,
        pitch: i16,
    },
    StopAim,
    /// A postback with these angles, mode and tracking flag: judged by an aim held.
    PostbackOf {
        motor: i16,
        pitch: i16,
        mode: u8,
        tracking: bool,
    },
    /// Start (a small box) or stop the gimbal's tracker.
    Tracking(bool),
}

/// Does `op` to `link` at `now`.
pub(super) fn apply<const Q: usize, const T: usize>(link: &mut Link<Q, T>, op: &Op, now: Instant) {
    let back = |ms: u32| Instant::from_millis(now.as_millis().wrapping_sub(ms));
    let receive = |link: &mut Link<Q, T>, p: &Postback, at: Instant| {
        for d in p.to_can_frames() {
            link.receive(ids::POSTBACK, &d, at);
        }
    };
    match *op {
        Op::Wait(_) => {}
        Op::Rate(r) => {
            let _ = link.set_rate(Rate::from_centi(r, 0).unwrap(), now);
        }
        Op::StopRate => link.stop_rate(),
        Op::Pitch => {
            let _ = link.send(GimbalCommand::Pitch(Pitch::new(-10.0).unwrap()));
        }
        Op::Vehicle { stamp_back } => {
            link.set_attitude(Attitude::new(0.0, 0.0, 10.0).unwrap(), back(stamp_back));
            link.set_gps(Gps::new(47.0, 8.0).unwrap(), back(stamp_back));
            link.set_altitude(Altitude::new(500.0).unwrap(), back(stamp_back));
        }
        Op::Gps { stamp_back } => link.set_gps(Gps::new(47.0, 8.0).unwrap(), back(stamp_back)),
        Op::Postback => receive(link, &Postback::default(), now),
        Op::BadPostback => {
            let mut frames = Postback::default().to_can_frames();
            frames[2][3] ^= 0x40;
            for d in frames {
                link.receive(ids::POSTBACK, &d, now);
            }
        }
        Op::LatePostback(ms) => receive(link, &Postback::default(), back(ms)),
        Op::PostbackFrame(i) => {
            let d = Postback::default().to_can_frames()[usize::from(i)];
            link.receive(ids::POSTBACK, &d, now);
        }
        Op::PointAt => link.point_at(Position::new(47.001, 8.001, 400.0).unwrap()),
        Op::StopPointing => link.stop_pointing(),
        Op::Text => {
            let _ = link.send_text(b"HELLO");
        }
        Op::Aim { earth, yaw, pitch } => {
            let h = Heading::from_deci(yaw).unwrap();
            let aim = Aim {
                yaw: if earth {
                    Yaw::Earth(h)
                } else {
                    Yaw::Vehicle(h)
                },
                pitch: Pitch::from_deci(pitch).unwrap(),
            };
            let _ = link.aim(aim, now);
        }
        Op::StopAim => link.stop_aiming(),
        Op::PostbackOf {
            motor,
            pitch,
            mode,
            tracking,
        } => {
            let p = Postback {
                motor_heading: motor,
                pitch,
                mode: crate::wire::postback::ControlMode::from_code(mode),
                tracking,
                ..Postback::default()
            };
            receive(link, &p, now);
        }
        Op::Tracking(start) => {
            let c = if start {
                GimbalCommand::StartTracking(TrackingBox::from_raw(
                    ImagePoint::new(100, 100).unwrap(),
                    1,
                    1,
                ))
            } else {
                GimbalCommand::StopTracking
            };
            let _ = link.send(c);
        }
    }
}
