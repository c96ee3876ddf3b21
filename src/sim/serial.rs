//! The simulated gimbal on its UART: bytes in, bytes out.
//!
//! [`SerialSimulator`] wraps a [`Simulator`] with the serial framing: control frames arrive
//! as the 24-byte serial frame, in any split, through a [`StreamParser`]; each postback
//! leaves as its 27-byte stream form. No vehicle frames exist on the serial link, so the
//! simulated gimbal references headings to the nose, as the real one does without a
//! vehicle attitude.
//!
//! ```
//! use idu_gimbal::sim::serial::SerialSimulator;
//! use idu_gimbal::sim::SimConfig;
//! use idu_gimbal::wire::{postback::Postback, serial::control_frame};
//! use idu_gimbal::Instant;
//!
//! let t0 = Instant::from_millis(0);
//! let mut sim: SerialSimulator = SerialSimulator::new(SimConfig::default(), t0);
//! // Look down 90°, the protocol notes' serial vector, split in two.
//! let frame = control_frame(&[0x0F, 0x07, 0, 0, 0, 0, 0, 0]);
//! sim.receive(&frame[..7], t0);
//! sim.receive(&frame[7..], t0);
//! assert_eq!(sim.sim().state().target_pitch_deg, Some(-90.0));
//!
//! let status = sim.poll(t0.add_millis(500)).unwrap();
//! assert_eq!(sim.transmit_bytes(), &status.to_stream_bytes()[..]);
//! ```

use heapless::Deque;

use super::{SimConfig, Simulator};
use crate::port::Uart;
use crate::time::Instant;
use crate::wire::ids;
use crate::wire::postback::{Postback, MESSAGE_LEN};
use crate::wire::serial::{StreamItem, StreamParser};

/// A simulated gimbal on a serial line with `OUT` bytes of transmit buffer (see the
/// [module docs](self)).
#[derive(Clone, Debug)]
pub struct SerialSimulator<const OUT: usize = 64> {
    // The CAN frame queue is unused here (no CAN frames); heapless needs at least one slot.
    sim: Simulator<1>,
    parser: StreamParser,
    out: Deque<u8, OUT>,
    out_overflows: u32,
    overlong_writes: u32,
}

impl<const OUT: usize> SerialSimulator<OUT> {
    /// A gimbal at rest (see [`Simulator::new`]); `emit_can_frames` is not used.
    pub fn new(config: SimConfig, now: Instant) -> Self {
        SerialSimulator {
            sim: Simulator::with_tx_capacity(
                SimConfig {
                    emit_can_frames: false,
                    ..config
                },
                now,
            ),
            parser: StreamParser::new(),
            out: Deque::new(),
            out_overflows: 0,
            overlong_writes: 0,
        }
    }

    /// Takes received bytes, in any split: each control frame acts on the model (a frame the
    /// simulator rejects is counted in its [`SimStats`](super::SimStats)). A postback
    /// arriving at the gimbal is not for it: it is counted by the parser only.
    pub fn receive(&mut self, bytes: &[u8], now: Instant) {
        for item in self.parser.feed(bytes) {
            if let StreamItem::Control(data) = item {
                // Rejections are counted by the simulator.
                let _ = self.sim.receive(ids::CONTROL, &data, now);
            }
        }
    }

    /// Advances the model to `now`; a postback due is queued as its 27 stream bytes and
    /// returned. When the transmit buffer lacks room for all 27 bytes the postback is
    /// dropped, counted in [`SerialSimulator::out_overflows`], and `None` is returned.
    pub fn poll(&mut self, now: Instant) -> Option<Postback> {
        let status = self.sim.poll(now)?;
        // `len <= OUT`: exact.
        if OUT.saturating_sub(self.out.len()) < MESSAGE_LEN {
            self.out_overflows = self.out_overflows.wrapping_add(1);
            return None;
        }
        for b in status.to_stream_bytes() {
            // Room for all of them was checked above.
            let _ = self.out.push_back(b);
        }
        Some(status)
    }

    /// The bytes to write next (a prefix of what waits); empty when nothing waits.
    pub fn transmit_bytes(&self) -> &[u8] {
        self.out.as_slices().0
    }

    /// `n` bytes of [`SerialSimulator::transmit_bytes`] were written. More than it gave
    /// (a port over-reporting) takes only what it gave, and is counted in
    /// [`SerialSimulator::overlong_writes`]: bytes it did not give were not written.
    pub fn transmit_written(&mut self, n: usize) {
        let given = self.transmit_bytes().len();
        if n > given {
            self.overlong_writes = self.overlong_writes.wrapping_add(1);
        }
        for _ in 0..n.min(given) {
            if self.out.pop_front().is_none() {
                break;
            }
        }
    }

    /// One exchange over a port: reads what waits, polls, writes what the port takes. A
    /// port error ends the exchange; it is returned, and nothing is lost.
    pub fn serve<P: Uart>(
        &mut self,
        port: &mut P,
        now: Instant,
    ) -> Result<Option<Postback>, crate::port::PortError<P::ReadError, P::WriteError>> {
        let mut buf = [0u8; 32];
        loop {
            match port.read(&mut buf) {
                Ok(0) => break,
                Ok(n) => self.receive(buf.get(..n).unwrap_or(&buf), now),
                Err(e) => return Err(crate::port::PortError::Read(e)),
            }
        }
        let status = self.poll(now);
        loop {
            let bytes = self.transmit_bytes();
            if bytes.is_empty() {
                break;
            }
            match port.write(bytes) {
                Ok(0) => break,
                Ok(n) => self.transmit_written(n),
                Err(e) => return Err(crate::port::PortError::Write(e)),
            }
        }
        Ok(status)
    }

    /// Postbacks dropped for lack of room in the transmit buffer (the model made them:
    /// they are among [`SimStats::postbacks`](super::SimStats::postbacks) too).
    pub fn out_overflows(&self) -> u32 {
        self.out_overflows
    }

    /// Writes reported as more bytes than [`SerialSimulator::transmit_bytes`] gave.
    pub fn overlong_writes(&self) -> u32 {
        self.overlong_writes
    }

    /// The simulated gimbal.
    pub fn sim(&self) -> &Simulator<1> {
        &self.sim
    }

    /// The simulated gimbal, mutably (e.g. [`Simulator::set_silent`]).
    pub fn sim_mut(&mut self) -> &mut Simulator<1> {
        &mut self.sim
    }

    /// The stream parser, for its counters.
    pub fn parser(&self) -> &StreamParser {
        &self.parser
    }

    /// Restarts the gimbal ([`Simulator::reboot`]): bytes not yet sent and a frame
    /// half-received are lost with it.
    pub fn reboot(&mut self, now: Instant) {
        self.sim.reboot(now);
        self.out.clear();
        self.parser = StreamParser::new();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mock::serial::{MockSerialError, Pipe, Rx, SerialFaults, Tx};
    use crate::port::{Io, PortError};
    use crate::wire::serial::control_frame;
    use embedded_io::{Read, Write};

    // The flight controller on the pipe's port 0, the gimbal on port 1; 128 bytes each way
    // hold every exchange below.
    const N: usize = 128;

    type GimbalPort<'a> = Io<Rx<'a, N>, Tx<'a, N>>;

    fn t(ms: u32) -> Instant {
        Instant::from_millis(ms)
    }

    /// Look down, as a 24-byte serial control frame (the protocol notes' serial vector).
    fn look_down() -> [u8; 24] {
        control_frame(&[0x0F, 0x07, 0, 0, 0, 0, 0, 0])
    }

    /// What waits for the flight controller on `rx`, read whole.
    fn drain(rx: &mut Rx<'_, N>) -> std::vec::Vec<u8> {
        let mut got = std::vec::Vec::new();
        let mut buf = [0u8; N];
        while let Ok(n @ 1..) = rx.read(&mut buf) {
            got.extend_from_slice(&buf[..n]);
        }
        got
    }

    /// The flight controller's port 0 of `pipe`, and a gimbal at rest on port 1 through `Io`.
    fn gimbal_on(pipe: &Pipe<N>) -> (Rx<'_, N>, Tx<'_, N>, GimbalPort<'_>, SerialSimulator) {
        let (fc_rx, fc_tx) = pipe.port(0).unwrap();
        let (rx, tx) = pipe.port(1).unwrap();
        let sim = SerialSimulator::new(SimConfig::default(), t(0));
        (fc_rx, fc_tx, Io::new(rx, tx), sim)
    }

    #[test]
    fn serve_reads_frames_in_pieces_polls_and_writes_the_postback() {
        // Split reads of 1 to 5 bytes: each frame arrives in at least five pieces, and two
        // frames (48 bytes) take more than one 32-byte read of `serve`'s buffer anyway.
        let pipe: Pipe<N> = Pipe::new(3).with_faults(SerialFaults {
            max_read: 5,
            ..SerialFaults::NONE
        });
        let (mut fc_rx, mut fc_tx, mut port, mut sim) = gimbal_on(&pipe);
        let mut two = look_down().to_vec();
        two.extend_from_slice(&look_down());
        assert_eq!(fc_tx.write(&two), Ok(48));
        assert_eq!(sim.serve(&mut port, t(0)), Ok(None));
        assert_eq!(pipe.pending(1), Some(0), "all read in one exchange");
        assert_eq!(sim.sim().stats().commands, 2);
        assert_eq!(sim.sim().state().target_pitch_deg, Some(-90.0));
        assert!(drain(&mut fc_rx).is_empty());
        let status = sim.serve(&mut port, t(500)).unwrap().unwrap();
        // Half a second at 60°/s: -30°, as the postback says.
        assert_eq!(status.pitch, -3000);
        assert_eq!(status, sim.sim().postback());
        assert_eq!(drain(&mut fc_rx), status.to_stream_bytes());
        assert!(sim.transmit_bytes().is_empty());
    }

    #[test]
    fn serve_writes_what_the_port_takes_and_the_rest_later() {
        // A port that takes nothing now (`write_ready` false): the postback waits whole.
        let pipe: Pipe<N> = Pipe::new(3).with_faults(SerialFaults {
            write_stall: 1.0,
            ..SerialFaults::NONE
        });
        let (mut fc_rx, _, mut port, mut sim) = gimbal_on(&pipe);
        let status = sim.serve(&mut port, t(500)).unwrap().unwrap();
        assert_eq!(pipe.stats(1).unwrap().written, 0);
        assert_eq!(sim.transmit_bytes().len(), MESSAGE_LEN);
        // A slow writer taking 1 to 10 bytes a write: all 27 in the next exchange.
        pipe.set_faults(SerialFaults {
            max_write: 10,
            ..SerialFaults::NONE
        });
        assert_eq!(sim.serve(&mut port, t(600)), Ok(None));
        assert!(sim.transmit_bytes().is_empty());
        assert_eq!(drain(&mut fc_rx), status.to_stream_bytes());
    }

    #[test]
    fn a_port_error_ends_the_exchange_and_loses_nothing() {
        let pipe: Pipe<N> = Pipe::new(3).with_faults(SerialFaults {
            rx_error: 1.0,
            ..SerialFaults::NONE
        });
        let (mut fc_rx, mut fc_tx, mut port, mut sim) = gimbal_on(&pipe);
        // A read error: returned before the poll, the frame behind it read at the next.
        assert_eq!(fc_tx.write(&look_down()), Ok(24));
        assert_eq!(
            sim.serve(&mut port, t(500)),
            Err(PortError::Read(MockSerialError::Noise))
        );
        assert_eq!(sim.sim().stats().postbacks, 0, "no poll after the error");
        assert_eq!(pipe.pending(1), Some(24));
        // A write error: after the poll; the postback's bytes wait for the next exchange.
        pipe.set_faults(SerialFaults {
            tx_error: 1.0,
            ..SerialFaults::NONE
        });
        assert_eq!(
            sim.serve(&mut port, t(500)),
            Err(PortError::Write(MockSerialError::Noise))
        );
        assert_eq!(sim.sim().state().target_pitch_deg, Some(-90.0));
        assert_eq!(sim.sim().stats().postbacks, 1);
        assert_eq!(sim.transmit_bytes().len(), MESSAGE_LEN);
        pipe.set_faults(SerialFaults::NONE);
        assert_eq!(sim.serve(&mut port, t(600)), Ok(None));
        assert_eq!(drain(&mut fc_rx).len(), MESSAGE_LEN);
    }

    #[test]
    fn a_postback_is_dropped_and_counted_only_when_its_27_bytes_do_not_fit() {
        // Room for exactly two postbacks.
        let mut sim: SerialSimulator<54> = SerialSimulator::new(SimConfig::default(), t(0));
        assert!(sim.poll(t(500)).is_some());
        assert!(sim.poll(t(1000)).is_some());
        assert_eq!(sim.out_overflows(), 0);
        assert_eq!(sim.transmit_bytes().len(), 2 * MESSAGE_LEN);
        assert_eq!(sim.poll(t(1500)), None);
        assert_eq!(sim.poll(t(2000)), None);
        assert_eq!(sim.out_overflows(), 2);
        assert_eq!(sim.sim().stats().postbacks, 4, "the model made all four");
        sim.transmit_written(MESSAGE_LEN);
        assert!(sim.poll(t(2500)).is_some());
        assert_eq!(sim.out_overflows(), 2);
    }
}
