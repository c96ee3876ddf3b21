//! The ports' idle check ("nothing due and nothing waiting to be sent", one compare)
//! against polls that never take it: two ports get the same operations and are polled
//! every millisecond, one with the check and one without, and must put the same frames or
//! bytes on the line, raise the same events, count the same and return the same.

use super::*;
use crate::geo::Position;
use crate::link::{Config, Event};
use crate::link::{Link, LinkStats, SerialLink};
use crate::mock::serial::{Pipe, Rx, SerialFaults, Tx};
use crate::mock::{Bus, Endpoint, MockFrame};
use crate::time::Instant;
use crate::wire::control::{GimbalCommand, Pitch, Rate};
use crate::wire::ids;
use crate::wire::postback::Postback;
use crate::wire::vehicle::{Altitude, Attitude, Gps};
use core::fmt::Debug;
use embedded_can::nb::Can as _;
use embedded_can::{ExtendedId, Frame as _, Id};
use proptest::prelude::*;
use std::vec::Vec;

#[derive(Clone, Debug)]
enum Op {
    Wait(u32),
    Send,
    Rate(i16),
    StopRate,
    PointAt,
    /// An aim held closed loop (earth or vehicle frame, yaw in 0.1°).
    Aim(bool, u16),
    /// Start (`true`) or stop the gimbal's tracker, which an aim yields to.
    Tracking(bool),
    /// CAN only (the serial link carries neither).
    Text,
    /// Pushed on CAN; kept for point-at on serial.
    Vehicle {
        stamp_back: u32,
    },
    /// The peer sends a whole postback.
    Postback,
    /// The peer sends a quarter of one (a CAN frame, 7 of the 27 stream bytes): a partial
    /// postback expires.
    PostbackPart(u8),
    /// The line takes nothing (`true`: CAN delivery stops, with one mailbox; the serial
    /// port stalls) or resumes: frames are refused and queued again, or wait part-written.
    Stall(bool),
    /// The application polls the link itself, beside its port's polls.
    LinkPoll,
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        8 => (0u32..300).prop_map(Op::Wait),
        2 => (300u32..3000).prop_map(Op::Wait),
        3 => Just(Op::Send),
        2 => (-500i16..500).prop_map(Op::Rate),
        1 => Just(Op::StopRate),
        1 => Just(Op::PointAt),
        2 => (any::<bool>(), 0u16..=3600).prop_map(|(earth, yaw)| Op::Aim(earth, yaw)),
        1 => any::<bool>().prop_map(Op::Tracking),
        1 => Just(Op::Text),
        2 => (0u32..1500).prop_map(|stamp_back| Op::Vehicle { stamp_back }),
        2 => Just(Op::Postback),
        1 => (0u8..4).prop_map(Op::PostbackPart),
        2 => any::<bool>().prop_map(Op::Stall),
        1 => Just(Op::LinkPoll),
    ]
}

fn pitch() -> GimbalCommand {
    GimbalCommand::Pitch(Pitch::new(-10.0).unwrap())
}

/// One driver with its line and the peer at the other end.
trait Side {
    type Poll: PartialEq + Debug;
    type Observed: PartialEq + Debug;
    fn apply(&mut self, op: &Op, now: Instant);
    /// A poll with the idle check, or one that never takes it.
    fn poll(&mut self, now: Instant, idle_check: bool) -> Self::Poll;
    /// What the peer received since the last call, the events taken, the counters.
    fn observe(&mut self) -> Self::Observed;
}

/// The operations both drivers take alike; `false` for the others.
macro_rules! apply_common {
    ($gimbal:expr, $op:expr, $now:expr) => {
        match *$op {
            Op::Wait(_) => true,
            Op::LinkPoll => {
                $gimbal.poll($now);
                true
            }
            Op::Send => {
                let _ = $gimbal.send(pitch());
                true
            }
            Op::Rate(r) => {
                let _ = $gimbal.set_rate(Rate::from_centi(r, 0).unwrap(), $now);
                true
            }
            Op::StopRate => {
                $gimbal.stop_rate();
                true
            }
            Op::Vehicle { stamp_back } => {
                let stamp = Instant::from_millis($now.as_millis().wrapping_sub(stamp_back));
                $gimbal.set_attitude(Attitude::new(0.0, 0.0, 10.0).unwrap(), stamp);
                $gimbal.set_gps(Gps::new(47.0, 8.0).unwrap(), stamp);
                $gimbal.set_altitude(Altitude::new(500.0).unwrap(), stamp);
                true
            }
            Op::PointAt => {
                $gimbal.point_at(Position::new(47.001, 8.001, 400.0).unwrap());
                true
            }
            Op::Aim(earth, yaw) => {
                let yaw = crate::wire::control::Heading::from_deci(yaw).unwrap();
                let aim = crate::link::Aim {
                    yaw: if earth {
                        crate::link::Yaw::Earth(yaw)
                    } else {
                        crate::link::Yaw::Vehicle(yaw)
                    },
                    pitch: Pitch::new(-20.0).unwrap(),
                };
                let _ = $gimbal.aim(aim, $now);
                true
            }
            Op::Tracking(start) => {
                let _ = $gimbal.send(if start {
                    GimbalCommand::StartTracking(crate::wire::control::TrackingBox::from_raw(
                        crate::wire::control::ImagePoint::new(4096, 4096).unwrap(),
                        16,
                        16,
                    ))
                } else {
                    GimbalCommand::StopTracking
                });
                true
            }
            _ => false,
        }
    };
}

/// `Side::poll` for a side whose link is `self.link` and port `self.port` (both ports name
/// the two polls alike).
macro_rules! poll_through_port {
    () => {
        fn poll(&mut self, now: Instant, idle_check: bool) -> Self::Poll {
            match idle_check {
                true => self.port.poll(&mut self.link, now),
                false => self.port.poll_without_idle_check(&mut self.link, now),
            }
        }
    };
}

fn check<S: Side>(fast: &mut S, full: &mut S, ops: &[Op], start: u32) -> Result<(), TestCaseError> {
    let mut t = start;
    for op in ops {
        let steps = if let Op::Wait(ms) = *op { ms } else { 1 };
        fast.apply(op, Instant::from_millis(t));
        full.apply(op, Instant::from_millis(t));
        for _ in 0..steps {
            let now = Instant::from_millis(t);
            let a = fast.poll(now, true);
            let b = full.poll(now, false);
            prop_assert_eq!(a, b, "at {}", t);
            prop_assert_eq!(fast.observe(), full.observe(), "at {}", t);
            t = t.wrapping_add(1);
        }
    }
    Ok(())
}

// ---- CAN ----

type Driver<'a> = Endpoint<'a, 2, 16>;

struct CanSide<'a> {
    bus: &'a Bus<2, 16>,
    link: Link,
    port: CanPort<Driver<'a>>,
    peer: Driver<'a>,
}

impl<'a> CanSide<'a> {
    fn new(bus: &'a Bus<2, 16>) -> Self {
        assert!(bus.set_mailboxes(0, 1));
        CanSide {
            bus,
            link: Link::new(Config::default()),
            port: CanPort::new(bus.endpoint(0).unwrap()),
            peer: bus.endpoint(1).unwrap(),
        }
    }

    fn peer_sends(&mut self, data: &[u8; 8]) {
        let id = ExtendedId::new(ids::POSTBACK).unwrap();
        let frame = MockFrame::new(id, data).unwrap();
        // The peer sends nothing else: when its mailboxes are full (delivery stopped), the
        // bus delivers, the same on both sides.
        loop {
            match self.peer.transmit(&frame) {
                Ok(None) => return,
                Err(nb::Error::WouldBlock) => {
                    self.bus.deliver();
                }
                other => panic!("peer transmit: {other:?}"),
            }
        }
    }
}

impl Side for CanSide<'_> {
    type Poll = Result<(), DriverError>;
    type Observed = (Vec<(Id, Vec<u8>)>, Vec<Event>, LinkStats, CanPortStats);

    fn apply(&mut self, op: &Op, now: Instant) {
        if apply_common!(self.link, op, now) {
            return;
        }
        let frames = Postback::default().to_can_frames();
        match *op {
            Op::Text => {
                let _ = self.link.send_text(b"HELLO");
            }
            Op::Postback => frames.iter().for_each(|d| self.peer_sends(d)),
            Op::PostbackPart(i) => self.peer_sends(&frames[usize::from(i)]),
            Op::Stall(on) => self.bus.set_auto_deliver(!on),
            _ => unreachable!("a common operation"),
        }
    }

    poll_through_port!();

    fn observe(&mut self) -> Self::Observed {
        let frames = core::iter::from_fn(|| self.peer.receive().ok())
            .map(|f| (f.id(), f.data().to_vec()))
            .collect();
        let events = core::iter::from_fn(|| self.link.next_event()).collect();
        (frames, events, self.link.stats(), self.port.stats())
    }
}

// ---- serial ----

const PIPE: usize = 256;
type UartOf<'a> = Io<Rx<'a, PIPE>, Tx<'a, PIPE>>;

/// A slow writer that fails now and then: at most 5 bytes a write and one write in 20
/// fails (PRNG draws per write call, so both sides draw alike as long as they write alike);
/// `stall`: it takes nothing.
fn port_faults(stall: bool) -> SerialFaults {
    SerialFaults {
        max_write: 5,
        tx_error: 0.05,
        write_stall: if stall { 1.0 } else { 0.0 },
        ..SerialFaults::NONE
    }
}

struct SerialSide<'a> {
    pipe: &'a Pipe<PIPE>,
    link: SerialLink,
    port: SerialPort<UartOf<'a>>,
    peer: UartOf<'a>,
    stalled: bool,
}

impl<'a> SerialSide<'a> {
    fn new(pipe: &'a Pipe<PIPE>) -> Self {
        pipe.set_faults(port_faults(false));
        let (rx, tx) = pipe.port(0).unwrap();
        let (peer_rx, peer_tx) = pipe.port(1).unwrap();
        SerialSide {
            pipe,
            link: SerialLink::new(Config::default()),
            port: SerialPort::new(Io::new(rx, tx)),
            peer: Io::new(peer_rx, peer_tx),
            stalled: false,
        }
    }

    fn peer_writes(&mut self, bytes: &[u8]) {
        // With no faults for the peer's own write, then the gimbal's port's back.
        self.pipe.set_faults(SerialFaults::NONE);
        let written = Uart::write(&mut self.peer, bytes);
        assert_eq!(written.ok(), Some(bytes.len()));
        self.pipe.set_faults(port_faults(self.stalled));
    }
}

impl Side for SerialSide<'_> {
    type Poll = Result<
        (),
        PortError<crate::mock::serial::MockSerialError, crate::mock::serial::MockSerialError>,
    >;
    type Observed = (Vec<u8>, Vec<Event>, LinkStats, SerialPortStats);

    fn apply(&mut self, op: &Op, now: Instant) {
        if apply_common!(self.link, op, now) {
            return;
        }
        let bytes = Postback::default().to_stream_bytes();
        match *op {
            Op::Text => {}
            Op::Postback => self.peer_writes(&bytes),
            Op::PostbackPart(i) => {
                let from = usize::from(i) * 7;
                self.peer_writes(&bytes[from..(from + 7).min(bytes.len())]);
            }
            Op::Stall(on) => {
                self.stalled = on;
                self.pipe.set_faults(port_faults(on));
            }
            _ => unreachable!("a common operation"),
        }
    }

    poll_through_port!();

    fn observe(&mut self) -> Self::Observed {
        let mut line = Vec::new();
        let mut buf = [0u8; 64];
        while let Ok(n @ 1..) = Uart::read(&mut self.peer, &mut buf) {
            line.extend_from_slice(&buf[..n]);
        }
        let events = core::iter::from_fn(|| self.link.next_event()).collect();
        (line, events, self.link.stats(), self.port.stats())
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Over a bus that stops delivering at times (one mailbox: frames are refused and
    /// queued again), the CAN driver's idle check skips nothing a full poll would do.
    #[test]
    fn can_idle_check_skips_nothing(ops in proptest::collection::vec(op(), 1..40), start: u32) {
        let (bus_fast, bus_full): (Bus<2, 16>, Bus<2, 16>) = (Bus::new(1), Bus::new(1));
        check(&mut CanSide::new(&bus_fast), &mut CanSide::new(&bus_full), &ops, start)?;
    }

    /// Over a slow port that stalls and fails at times (frames wait part-written), the
    /// serial driver's idle check skips nothing a full poll would do.
    #[test]
    fn serial_idle_check_skips_nothing(ops in proptest::collection::vec(op(), 1..40), start: u32) {
        let (pipe_fast, pipe_full): (Pipe<PIPE>, Pipe<PIPE>) = (Pipe::new(7), Pipe::new(7));
        check(&mut SerialSide::new(&pipe_fast), &mut SerialSide::new(&pipe_full), &ops, start)?;
    }
}

/// The check does skip: after a command is sent, the next poll finds the queue empty and
/// releases it, and polls skip until the next deadline; a refused frame holds it.
#[test]
fn can_idle_check_holds_between_deadlines_and_ends_while_a_frame_waits() {
    let bus: Bus<2, 16> = Bus::new(1);
    let mut side = CanSide::new(&bus);
    let at = Instant::from_millis;
    side.port.poll(&mut side.link, at(0)).unwrap();
    assert!(side.link.is_idle(at(1)));
    assert!(!side.link.is_idle(at(60_000)), "the longest interval");
    side.link.send(pitch()).unwrap();
    assert!(!side.link.is_idle(at(1)), "a frame waits");
    side.port.poll(&mut side.link, at(1)).unwrap();
    assert_eq!(side.observe().0.len(), 1);
    assert!(!side.link.is_idle(at(2)), "released by the next poll only");
    side.port.poll(&mut side.link, at(2)).unwrap();
    assert!(side.link.is_idle(at(3)));
    // Delivery stops: with one mailbox the text frame is refused and queued again.
    bus.set_auto_deliver(false);
    side.link.send(pitch()).unwrap();
    side.link.send_text(b"HI").unwrap();
    side.port.poll(&mut side.link, at(3)).unwrap();
    side.port.poll(&mut side.link, at(4)).unwrap();
    assert!(side.link.has_transmit());
    assert!(!side.link.is_idle(at(5)));
    // The application polls the link itself at its next deadline (a full poll), then
    // delivery resumes: the port's next poll still sends what waits.
    let _ = side.observe();
    side.link.poll(at(60_004));
    assert!(
        !side.link.is_idle(at(60_004)),
        "the full poll keeps the hold"
    );
    bus.set_auto_deliver(true);
    side.port.poll(&mut side.link, at(60_004)).unwrap();
    assert!(!side.link.has_transmit());
    assert!(!side.observe().0.is_empty());
}

/// A frame part-written when the port stalls waits outside the link's queue: the idle
/// check does not hold until it is written out.
#[test]
fn serial_a_part_written_frame_ends_the_idle_check() {
    let pipe: Pipe<PIPE> = Pipe::new(7);
    let mut side = SerialSide::new(&pipe);
    let at = Instant::from_millis;
    let slow = SerialFaults {
        max_write: 5,
        ..SerialFaults::NONE
    };
    pipe.set_faults(slow);
    side.port.poll(&mut side.link, at(0)).unwrap();
    assert!(side.link.is_idle(at(1)));
    side.link.send(pitch()).unwrap();
    side.port.poll(&mut side.link, at(1)).unwrap(); // at most 5 of its 24 bytes a write, then more
    assert_eq!(side.observe().0.len(), 24);
    // A UART that takes at most 5 bytes a write and stalls half the time (the pipe's seeded
    // faults): polled with one frame at a time until a poll ends with that frame part-written
    // (out of the link's queue, not finished).
    pipe.set_faults(SerialFaults {
        max_write: 5,
        write_stall: 0.5,
        ..SerialFaults::NONE
    });
    let mut t = 2;
    let part_written = (0..100).any(|_| {
        if !side.port.stream().has_transmit(&side.link) {
            side.link.send(pitch()).unwrap();
        }
        side.port.poll(&mut side.link, at(t)).unwrap();
        t += 1;
        !side.link.has_transmit() && side.port.stream().has_transmit(&side.link)
    });
    assert!(part_written, "no poll left a frame part-written");
    assert!(!side.link.is_idle(at(t)));
    // The application polls the link itself at its next deadline (a full poll): the
    // part-written frame still ends the idle check.
    side.link.poll(at(60_002));
    assert!(
        !side.link.is_idle(at(60_002)),
        "the full poll keeps the hold"
    );
    pipe.set_faults(slow);
    side.port.poll(&mut side.link, at(60_002)).unwrap();
    // Whole frames only, the part-written one finished.
    let written = side.observe().0.len();
    assert!(written > 0 && written.is_multiple_of(24), "{written} bytes");
    side.port.poll(&mut side.link, at(60_003)).unwrap();
    assert!(side.link.is_idle(at(60_004)));
}
