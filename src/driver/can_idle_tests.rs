//! `Gimbal::poll`'s idle check (nothing due and nothing waiting, one compare) against a
//! poll that never takes it: the same frames on the bus, events and counters, whatever is
//! queued, refused by full mailboxes or received in between.

use super::*;
use crate::geo::Position;
use crate::mock::{Bus, Endpoint};
use crate::wire::control::{GimbalCommand, Pitch, Rate};
use crate::wire::ids;
use crate::wire::postback::Postback;
use crate::wire::vehicle::{Altitude, Attitude, Gps};
use crate::Event;
use proptest::prelude::*;
use std::vec::Vec;

type Mock<'a> = Endpoint<'a, 2, 16>;
/// What the peer received (ID, data), the events taken, the counters.
type Observed = (Vec<(Id, Vec<u8>)>, Vec<Event>, Stats);

#[derive(Clone, Debug)]
enum Op {
    Wait(u32),
    Send,
    Text,
    Rate(i16),
    StopRate,
    Vehicle {
        stamp_back: u32,
    },
    PointAt,
    /// The peer sends a whole postback (delivered at once when the bus delivers).
    Postback,
    /// The peer sends one frame of a postback: a partial one expires.
    PostbackFrame(u8),
    /// The bus stops (`false`) or resumes (`true`) delivering: with one mailbox, frames
    /// are refused and re-queued while it is stopped.
    Deliver(bool),
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        8 => (0u32..300).prop_map(Op::Wait),
        2 => (300u32..3000).prop_map(Op::Wait),
        3 => Just(Op::Send),
        1 => Just(Op::Text),
        2 => (-500i16..500).prop_map(Op::Rate),
        1 => Just(Op::StopRate),
        2 => (0u32..1500).prop_map(|stamp_back| Op::Vehicle { stamp_back }),
        1 => Just(Op::PointAt),
        2 => Just(Op::Postback),
        1 => (0u8..4).prop_map(Op::PostbackFrame),
        2 => any::<bool>().prop_map(Op::Deliver),
    ]
}

struct Side<'a> {
    bus: &'a Bus<2, 16>,
    gimbal: Gimbal<Mock<'a>>,
    peer: Mock<'a>,
}

impl<'a> Side<'a> {
    fn new(bus: &'a Bus<2, 16>) -> Self {
        bus.set_auto_deliver(true);
        assert!(bus.set_mailboxes(0, 1));
        let gimbal = Gimbal::new(bus.endpoint(0).unwrap(), Config::default());
        Side {
            bus,
            gimbal,
            peer: bus.endpoint(1).unwrap(),
        }
    }

    fn apply(&mut self, op: &Op, now: Instant) {
        let g = &mut self.gimbal;
        match *op {
            Op::Wait(_) => {}
            Op::Send => {
                let _ = g.send(GimbalCommand::Pitch(Pitch::new(-10.0).unwrap()));
            }
            Op::Text => {
                let _ = g.send_text(b"HELLO");
            }
            Op::Rate(r) => {
                let _ = g.set_rate(Rate::from_centi(r, 0).unwrap(), now);
            }
            Op::StopRate => g.stop_rate(),
            Op::Vehicle { stamp_back } => {
                let stamp = Instant::from_millis(now.as_millis().wrapping_sub(stamp_back));
                g.set_attitude(Attitude::new(0.0, 0.0, 10.0).unwrap(), stamp);
                g.set_gps(Gps::new(47.0, 8.0).unwrap(), stamp);
                g.set_altitude(Altitude::new(500.0).unwrap(), stamp);
            }
            Op::PointAt => g.point_at(Position::new(47.001, 8.001, 400.0).unwrap()),
            Op::Postback | Op::PostbackFrame(_) => {
                let frames = Postback::default().to_can_frames();
                let frames = match *op {
                    Op::PostbackFrame(i) => &frames[usize::from(i)..=usize::from(i)],
                    _ => &frames[..],
                };
                for d in frames {
                    let id = ExtendedId::new(ids::POSTBACK).unwrap();
                    let frame =
                        <crate::mock::MockFrame as embedded_can::Frame>::new(id, d).unwrap();
                    // The peer sends nothing else: when its mailboxes are full (the bus
                    // stopped), the bus delivers, the same on both sides.
                    loop {
                        match self.peer.transmit(&frame) {
                            Ok(None) => break,
                            Err(nb::Error::WouldBlock) => {
                                self.bus.deliver();
                            }
                            other => panic!("peer transmit: {other:?}"),
                        }
                    }
                }
            }
            Op::Deliver(on) => self.bus.set_auto_deliver(on),
        }
    }

    /// What the peer received since the last call, the events, the counters.
    fn observe(&mut self) -> Observed {
        let frames = core::iter::from_fn(|| self.peer.receive().ok())
            .map(|f| (f.id(), f.data().to_vec()))
            .collect();
        let events = core::iter::from_fn(|| self.gimbal.next_event()).collect();
        (frames, events, self.gimbal.stats())
    }
}

fn check(ops: &[Op], start: u32) -> Result<(), TestCaseError> {
    let (bus_fast, bus_full): (Bus<2, 16>, Bus<2, 16>) = (Bus::new(1), Bus::new(1));
    let (mut fast, mut full) = (Side::new(&bus_fast), Side::new(&bus_full));
    let mut t = start;
    for op in ops {
        let steps = if let Op::Wait(ms) = *op { ms } else { 1 };
        fast.apply(op, Instant::from_millis(t));
        full.apply(op, Instant::from_millis(t));
        for _ in 0..steps {
            let now = Instant::from_millis(t);
            let a = fast.gimbal.poll(now);
            let first_error = full.gimbal.receive_all(now);
            let b = full.gimbal.poll_busy(now, first_error);
            prop_assert_eq!(a, b, "at {}", t);
            prop_assert_eq!(fast.observe(), full.observe(), "at {}", t);
            t = t.wrapping_add(1);
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Polling every millisecond, the idle check skips nothing a full poll would do.
    #[test]
    fn idle_check_skips_nothing(ops in proptest::collection::vec(op(), 1..40), start: u32) {
        check(&ops, start)?;
    }
}

/// The check does skip: after a command is sent, one more poll finds the queue empty and
/// releases it; from then on, polls skip until the next deadline.
#[test]
fn idle_check_holds_between_deadlines_and_ends_when_a_frame_is_queued() {
    let bus: Bus<2, 16> = Bus::new(1);
    let mut side = Side::new(&bus);
    let at = Instant::from_millis;
    side.gimbal.poll(at(0)).unwrap();
    assert!(side.gimbal.link.is_idle(at(1)));
    assert!(
        !side.gimbal.link.is_idle(at(60_000)),
        "the longest interval"
    );
    side.gimbal
        .send(GimbalCommand::Pitch(Pitch::new(-10.0).unwrap()))
        .unwrap();
    assert!(!side.gimbal.link.is_idle(at(1)), "a frame waits");
    side.gimbal.poll(at(1)).unwrap();
    assert_eq!(side.observe().0.len(), 1);
    assert!(
        !side.gimbal.link.is_idle(at(2)),
        "released by the next poll only"
    );
    side.gimbal.poll(at(2)).unwrap();
    assert!(side.gimbal.link.is_idle(at(3)));
    // A refused frame is re-queued: the check does not hold while it waits.
    bus.set_auto_deliver(false);
    side.gimbal
        .send(GimbalCommand::Pitch(Pitch::new(-10.0).unwrap()))
        .unwrap();
    side.gimbal.send_text(b"HI").unwrap();
    side.gimbal.poll(at(3)).unwrap();
    assert_eq!(side.gimbal.stats().link.requeued, 0);
    side.gimbal.poll(at(4)).unwrap();
    assert!(side.gimbal.link.has_transmit());
    assert!(!side.gimbal.link.is_idle(at(5)));
}
