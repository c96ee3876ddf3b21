//! `SerialGimbal::poll`'s idle check (nothing due and nothing waiting to be written, one
//! compare) against a poll that never takes it: the same bytes on the line, events and
//! counters, with a port that takes a few bytes a write and stalls at times.

use super::*;
use crate::geo::Position;
use crate::mock::serial::{Pipe, Rx, SerialFaults, Tx};
use crate::wire::control::{GimbalCommand, Pitch};
use embedded_io::Read as _;
use proptest::prelude::*;
use std::vec::Vec;

const N: usize = 256;
type Port<'a> = Io<Rx<'a, N>, Tx<'a, N>>;
/// What the peer read, the events taken, the counters and port errors.
type Observed = (Vec<u8>, Vec<Event>, SerialStats, PortErrors);

#[derive(Clone, Debug)]
enum Op {
    Wait(u32),
    Send,
    Rate(i16),
    StopRate,
    PointAt,
    /// The peer writes a whole postback.
    Postback,
    /// The port takes nothing (`true`) or resumes (`false`): a frame part-written waits.
    Stall(bool),
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        8 => (0u32..300).prop_map(Op::Wait),
        2 => (300u32..3000).prop_map(Op::Wait),
        3 => Just(Op::Send),
        2 => (-500i16..500).prop_map(Op::Rate),
        1 => Just(Op::StopRate),
        1 => Just(Op::PointAt),
        2 => Just(Op::Postback),
        2 => any::<bool>().prop_map(Op::Stall),
    ]
}

/// A slow writer that fails now and then: at most 5 bytes a write, and one write in 20
/// fails (PRNG draws per write call, so both sides draw alike as long as they write alike).
fn faults(stall: bool) -> SerialFaults {
    SerialFaults {
        max_write: 5,
        tx_error: 0.05,
        write_stall: if stall { 1.0 } else { 0.0 },
        ..SerialFaults::NONE
    }
}

struct Side<'a> {
    pipe: &'a Pipe<N>,
    gimbal: SerialGimbal<Port<'a>>,
    peer: Port<'a>,
}

impl<'a> Side<'a> {
    fn new(pipe: &'a Pipe<N>) -> Self {
        pipe.set_faults(faults(false));
        let (rx, tx) = pipe.port(0).unwrap();
        let (peer_rx, peer_tx) = pipe.port(1).unwrap();
        Side {
            pipe,
            gimbal: SerialGimbal::new(Io::new(rx, tx), Config::default()),
            peer: Io::new(peer_rx, peer_tx),
        }
    }

    fn apply(&mut self, op: &Op, now: Instant) {
        let g = &mut self.gimbal;
        match *op {
            Op::Wait(_) => {}
            Op::Send => {
                let _ = g.send(GimbalCommand::Pitch(Pitch::new(-10.0).unwrap()));
            }
            Op::Rate(r) => {
                let _ = g.set_rate(Rate::from_centi(r, 0).unwrap(), now);
            }
            Op::StopRate => g.stop_rate(),
            Op::PointAt => g.point_at(Position::new(47.001, 8.001, 400.0).unwrap()),
            Op::Postback => {
                let bytes = Postback::default().to_stream_bytes();
                // Written whole with no faults, which also ends a stall (on both sides
                // alike).
                self.pipe.set_faults(SerialFaults::NONE);
                assert_eq!(
                    embedded_io::Write::write(&mut self.peer.tx, &bytes).ok(),
                    Some(bytes.len())
                );
                self.pipe.set_faults(faults(false));
            }
            Op::Stall(on) => self.pipe.set_faults(faults(on)),
        }
    }

    fn observe(&mut self) -> Observed {
        let mut line = Vec::new();
        let mut buf = [0u8; 64];
        while let Ok(n @ 1..) = self.peer.rx.read(&mut buf) {
            line.extend_from_slice(&buf[..n]);
        }
        let events = core::iter::from_fn(|| self.gimbal.next_event()).collect();
        (line, events, self.gimbal.stats(), self.gimbal.port_errors())
    }
}

fn check(ops: &[Op], start: u32) -> Result<(), TestCaseError> {
    let (pipe_fast, pipe_full): (Pipe<N>, Pipe<N>) = (Pipe::new(7), Pipe::new(7));
    let (mut fast, mut full) = (Side::new(&pipe_fast), Side::new(&pipe_full));
    let mut t = start;
    for op in ops {
        let steps = if let Op::Wait(ms) = *op { ms } else { 1 };
        fast.apply(op, Instant::from_millis(t));
        full.apply(op, Instant::from_millis(t));
        for _ in 0..steps {
            let now = Instant::from_millis(t);
            let a = fast.gimbal.poll(now);
            let mut first_error = None;
            full.gimbal.receive_all(now, &mut first_error);
            full.gimbal.poll_busy(now, &mut first_error);
            prop_assert_eq!(a, first_error.map_or(Ok(()), Err), "at {}", t);
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

/// A frame part-written when the port stalls waits outside the link's queue: the idle
/// check does not hold until it is written out.
#[test]
fn a_part_written_frame_ends_the_idle_check() {
    let pipe: Pipe<N> = Pipe::new(7);
    let mut side = Side::new(&pipe);
    let at = Instant::from_millis;
    side.gimbal.poll(at(0)).unwrap();
    assert!(side.gimbal.link.link().is_idle(at(1)));
    side.gimbal
        .send(GimbalCommand::Pitch(Pitch::new(-10.0).unwrap()))
        .unwrap();
    side.gimbal.poll(at(1)).unwrap(); // at most 5 of its 24 bytes a write, then more
    let written = side.observe().0.len();
    assert_eq!(
        written, 24,
        "the slow writer finishes while the port takes bytes"
    );
    pipe.set_faults(faults(true));
    side.gimbal
        .send(GimbalCommand::Pitch(Pitch::new(-10.0).unwrap()))
        .unwrap();
    side.gimbal.poll(at(2)).unwrap();
    assert!(side.gimbal.link.has_transmit());
    assert!(!side.gimbal.link.link().is_idle(at(3)));
    pipe.set_faults(SerialFaults::NONE);
    side.gimbal.poll(at(3)).unwrap();
    assert_eq!(side.observe().0.len(), 24);
    side.gimbal.poll(at(4)).unwrap();
    assert!(side.gimbal.link.link().is_idle(at(5)));
}
