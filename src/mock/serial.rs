//! An in-memory serial line with fault injection: two UARTs wired back to back.
//!
//! A [`Pipe`] has two ports, 0 and 1. Each, taken once with [`Pipe::port`], is a receive
//! half [`Rx`] and a transmit half [`Tx`] that implement both `embedded-io` 0.7 (`Read` +
//! `ReadReady`, `Write` + `WriteReady`) and `embedded-hal-nb` 1.0 serial (`Read<u8>`,
//! `Write<u8>`), so a driver over either runs on it unchanged, through the adapters
//! [`Io`](crate::port::Io) and [`Nb`](crate::port::Nb). Nothing allocates, nothing is
//! `unsafe`, nothing panics, and it works without `std`.
//!
//! # Model
//!
//! * Each direction has a receive buffer of `N` bytes, like a UART's receive ring. A write
//!   is never held back by the receiver (a UART transmits regardless): a byte that finds the
//!   receive buffer full is dropped and the receiver's next read fails once with an
//!   overrun, like a hardware overrun. The bytes already buffered stay.
//! * [`SerialFaults`] injects, with a deterministic PRNG seeded by [`Pipe::new`]: byte loss
//!   and corruption on the wire, split reads (a read returns fewer bytes than wait), a slow
//!   writer (a write takes fewer bytes than offered, or none: `write_ready` is false), and
//!   read and write errors. The same seed, faults and calls give the same results.
//!
//! ```
//! use embedded_io::{Read, ReadReady, Write};
//! use idu_gimbal::mock::serial::Pipe;
//!
//! let pipe: Pipe<32> = Pipe::new(7);
//! let (_, mut fc_tx) = pipe.port(0).unwrap();
//! let (mut gimbal_rx, _) = pipe.port(1).unwrap();
//! assert_eq!(fc_tx.write(&[0xEB, 0x90, 0x0A]), Ok(3));
//! let mut buf = [0u8; 8];
//! assert_eq!(gimbal_rx.read(&mut buf), Ok(3));
//! assert_eq!(&buf[..3], &[0xEB, 0x90, 0x0A]);
//! assert_eq!(gimbal_rx.read_ready(), Ok(false));
//! assert_eq!(pipe.stats(0).unwrap().delivered, 3);
//! assert_eq!(pipe.stats(2), None);
//! ```

use core::cell::RefCell;
use core::fmt;

use heapless::Deque;

/// Fault settings. Probabilities are in `[0, 1]` (at or below 0, and NaN, count as 0; at or
/// above 1 as 1); a PRNG draw is made only for a fault that is on.
#[derive(Clone, Copy, PartialEq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SerialFaults {
    /// Probability that a byte written never reaches the receiver.
    pub loss: f32,
    /// Probability that a byte that is not lost has one random bit flipped.
    pub corruption: f32,
    /// Split reads: when above 0, a read returns at most a random 1 to `max_read` bytes.
    pub max_read: u8,
    /// A slow writer: when above 0, a write takes at most a random 1 to `max_write` bytes
    /// (`embedded-hal-nb`: a word is refused with `WouldBlock` once that many were taken
    /// since the port last reported `WouldBlock`).
    pub max_write: u8,
    /// Probability, per `write_ready` call and per `embedded-hal-nb` word written, that the
    /// port takes nothing now: `write_ready` is false, the word is `WouldBlock`.
    pub write_stall: f32,
    /// Probability, per read call, that it fails with a noise error (nothing consumed).
    pub rx_error: f32,
    /// Probability, per write call, that it fails with a noise error (nothing taken).
    pub tx_error: f32,
}

impl SerialFaults {
    /// No faults (the default).
    pub const NONE: SerialFaults = SerialFaults {
        loss: 0.0,
        corruption: 0.0,
        max_read: 0,
        max_write: 0,
        write_stall: 0.0,
        rx_error: 0.0,
        tx_error: 0.0,
    };
}

/// Counters of one direction of a [`Pipe`] (named by the port that writes), each
/// saturating at `u32::MAX`. Always: `written == delivered + lost + overruns + bytes still
/// buffered`.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PipeStats {
    /// Bytes the writer's port took.
    pub written: u32,
    /// Bytes read by the other port.
    pub delivered: u32,
    /// Bytes the `loss` fault removed.
    pub lost: u32,
    /// Bytes the `corruption` fault altered (and delivered).
    pub corrupted: u32,
    /// Bytes dropped because the receive buffer was full.
    pub overruns: u32,
    /// Errors returned by the `rx_error` and `tx_error` faults and overruns reported.
    pub errors: u32,
}

/// A serial error of the mock port.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MockSerialError {
    /// Bytes arrived to a full receive buffer and were dropped.
    Overrun,
    /// An injected line error.
    Noise,
}

impl fmt::Display for MockSerialError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            MockSerialError::Overrun => "receive overrun: bytes were dropped",
            MockSerialError::Noise => "line noise",
        })
    }
}

impl core::error::Error for MockSerialError {}

impl embedded_io::Error for MockSerialError {
    fn kind(&self) -> embedded_io::ErrorKind {
        embedded_io::ErrorKind::Other
    }
}

impl embedded_hal_nb::serial::Error for MockSerialError {
    fn kind(&self) -> embedded_hal_nb::serial::ErrorKind {
        match self {
            MockSerialError::Overrun => embedded_hal_nb::serial::ErrorKind::Overrun,
            MockSerialError::Noise => embedded_hal_nb::serial::ErrorKind::Noise,
        }
    }
}

fn bump(counter: &mut u32, n: usize) {
    *counter = counter.saturating_add(u32::try_from(n).unwrap_or(u32::MAX));
}

/// One direction: the receiver's buffer and its state.
#[derive(Debug)]
struct Line<const N: usize> {
    buf: Deque<u8, N>,
    overrun: bool,
    /// Bytes taken since the writer last saw `WouldBlock` (for `max_write` one word at a time).
    burst: u8,
    stats: PipeStats,
}

#[derive(Debug)]
struct State<const N: usize> {
    rng: fastrand::Rng,
    faults: SerialFaults,
    taken: [bool; 2],
    /// `lines[i]`: bytes written by port `i`.
    lines: [Line<N>; 2],
}

fn roll(rng: &mut fastrand::Rng, p: f32) -> bool {
    p > 0.0 && rng.f32() < p
}

/// At most a random 1..=max of `n` (all of `n` when `max` is 0).
fn limit(rng: &mut fastrand::Rng, max: u8, n: usize) -> usize {
    if max == 0 {
        n
    } else {
        n.min(usize::from(rng.u8(1..=max)))
    }
}

/// Two serial ports wired back to back, `N` bytes of receive buffer each way; see the
/// [module docs](self).
#[derive(Debug)]
pub struct Pipe<const N: usize> {
    state: RefCell<State<N>>,
}

impl<const N: usize> Pipe<N> {
    /// A pipe with no faults; `seed` seeds the fault PRNG.
    pub fn new(seed: u64) -> Self {
        let line = || Line {
            buf: Deque::new(),
            overrun: false,
            burst: 0,
            stats: PipeStats::default(),
        };
        Pipe {
            state: RefCell::new(State {
                rng: fastrand::Rng::with_seed(seed),
                faults: SerialFaults::NONE,
                taken: [false; 2],
                lines: [line(), line()],
            }),
        }
    }

    /// The pipe with these faults.
    pub fn with_faults(self, faults: SerialFaults) -> Self {
        self.set_faults(faults);
        self
    }

    /// Changes the faults from now on.
    pub fn set_faults(&self, faults: SerialFaults) {
        if let Ok(mut s) = self.state.try_borrow_mut() {
            s.faults = faults;
        }
    }

    /// Port `index` (0 or 1) as its receive and transmit halves; `None` if taken before or
    /// out of range.
    pub fn port(&self, index: usize) -> Option<(Rx<'_, N>, Tx<'_, N>)> {
        let mut s = self.state.try_borrow_mut().ok()?;
        let taken = s.taken.get_mut(index)?;
        if *taken {
            return None;
        }
        *taken = true;
        Some((
            Rx {
                pipe: self,
                // The line the other port writes (`index` is 0 or 1: checked above).
                line: index ^ 1,
            },
            Tx {
                pipe: self,
                line: index,
            },
        ))
    }

    /// The counters of the bytes port `writer` wrote; `None` unless `writer` is 0 or 1.
    pub fn stats(&self, writer: usize) -> Option<PipeStats> {
        let s = self.state.try_borrow().ok()?;
        s.lines.get(writer).map(|l| l.stats)
    }

    /// Bytes waiting for port `reader` to read; `None` unless `reader` is 0 or 1.
    pub fn pending(&self, reader: usize) -> Option<usize> {
        let s = self.state.try_borrow().ok()?;
        // Port `reader` reads the line the other port writes; `reader ^ 1` is 0 or 1 only
        // for a `reader` that is.
        s.lines.get(reader ^ 1).map(|l| l.buf.len())
    }

    fn with<R>(&self, f: impl FnOnce(&mut State<N>) -> R) -> Option<R> {
        self.state.try_borrow_mut().ok().map(|mut s| f(&mut s))
    }

    /// `f` on `line` with the fault generator and settings; `Ok(0)` (nothing moved) when the
    /// pipe is busy or there is no such line.
    fn on_line(
        &self,
        line: usize,
        f: impl FnOnce(
            &mut fastrand::Rng,
            &SerialFaults,
            &mut Line<N>,
        ) -> Result<usize, MockSerialError>,
    ) -> Result<usize, MockSerialError> {
        self.with(|s| {
            let State {
                rng, faults, lines, ..
            } = s;
            lines.get_mut(line).map_or(Ok(0), |l| f(rng, faults, l))
        })
        .unwrap_or(Ok(0))
    }

    /// Reads into `buf`: `Ok(0)` when nothing waits.
    fn read(&self, line: usize, buf: &mut [u8]) -> Result<usize, MockSerialError> {
        self.on_line(line, |rng, faults, l| {
            if l.overrun {
                l.overrun = false;
                bump(&mut l.stats.errors, 1);
                return Err(MockSerialError::Overrun);
            }
            if roll(rng, faults.rx_error) {
                bump(&mut l.stats.errors, 1);
                return Err(MockSerialError::Noise);
            }
            let n = limit(rng, faults.max_read, buf.len().min(l.buf.len()));
            for slot in buf.iter_mut().take(n) {
                *slot = l.buf.pop_front().unwrap_or(0);
            }
            bump(&mut l.stats.delivered, n);
            Ok(n)
        })
    }

    fn read_ready(&self, line: usize) -> bool {
        self.with(|s| {
            s.lines
                .get(line)
                .is_some_and(|l| l.overrun || !l.buf.is_empty())
        })
        .unwrap_or(false)
    }

    /// Whether the writer takes bytes now (one `write_stall` draw).
    fn write_ready(&self) -> bool {
        self.with(|s| !roll(&mut s.rng, s.faults.write_stall))
            .unwrap_or(false)
    }

    /// Writes up to `max` of `bytes` (after the slow-writer limit) onto the wire.
    fn write(&self, line: usize, bytes: &[u8]) -> Result<usize, MockSerialError> {
        self.on_line(line, |rng, faults, l| {
            if roll(rng, faults.tx_error) {
                bump(&mut l.stats.errors, 1);
                return Err(MockSerialError::Noise);
            }
            let n = limit(rng, faults.max_write, bytes.len());
            for &b in bytes.iter().take(n) {
                bump(&mut l.stats.written, 1);
                if roll(rng, faults.loss) {
                    bump(&mut l.stats.lost, 1);
                    continue;
                }
                let b = if roll(rng, faults.corruption) {
                    bump(&mut l.stats.corrupted, 1);
                    b ^ (1 << rng.u8(0..8))
                } else {
                    b
                };
                if l.buf.push_back(b).is_err() {
                    bump(&mut l.stats.overruns, 1);
                    l.overrun = true;
                }
            }
            Ok(n)
        })
    }

    /// One word, `embedded-hal-nb` style: the slow writer refuses a word once `max_write`
    /// were taken in a row, then takes words again.
    fn write_word(&self, line: usize, b: u8) -> nb::Result<(), MockSerialError> {
        let refused = self
            .with(|s| {
                let max = s.faults.max_write;
                let stall = roll(&mut s.rng, s.faults.write_stall);
                let l = s.lines.get_mut(line)?;
                if stall || (max > 0 && l.burst >= max) {
                    l.burst = 0;
                    return Some(true);
                }
                l.burst = l.burst.saturating_add(1);
                Some(false)
            })
            .flatten()
            .unwrap_or(true);
        if refused {
            return Err(nb::Error::WouldBlock);
        }
        match self.write(line, &[b]) {
            Ok(1) => Ok(()),
            Ok(_) => Err(nb::Error::WouldBlock),
            Err(e) => Err(nb::Error::Other(e)),
        }
    }
}

/// The receive half of a [`Pipe`] port.
pub struct Rx<'a, const N: usize> {
    pipe: &'a Pipe<N>,
    line: usize,
}

/// The transmit half of a [`Pipe`] port.
pub struct Tx<'a, const N: usize> {
    pipe: &'a Pipe<N>,
    line: usize,
}

impl<const N: usize> fmt::Debug for Rx<'_, N> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Rx")
            .field("line", &self.line)
            .finish_non_exhaustive()
    }
}

impl<const N: usize> fmt::Debug for Tx<'_, N> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Tx")
            .field("line", &self.line)
            .finish_non_exhaustive()
    }
}

impl<const N: usize> embedded_io::ErrorType for Rx<'_, N> {
    type Error = MockSerialError;
}

impl<const N: usize> embedded_io::ErrorType for Tx<'_, N> {
    type Error = MockSerialError;
}

impl<const N: usize> embedded_io::Read for Rx<'_, N> {
    /// Never blocks: `Ok(0)` when nothing waits (ask `read_ready` first, as
    /// [`Io`](crate::port::Io) does, for the `embedded-io` contract).
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, MockSerialError> {
        self.pipe.read(self.line, buf)
    }
}

impl<const N: usize> embedded_io::ReadReady for Rx<'_, N> {
    fn read_ready(&mut self) -> Result<bool, MockSerialError> {
        Ok(self.pipe.read_ready(self.line))
    }
}

impl<const N: usize> embedded_io::Write for Tx<'_, N> {
    /// Never blocks: takes what the slow writer takes, at least one byte of a non-empty
    /// `buf` (the stall is `write_ready`'s: ask it first, as [`Io`](crate::port::Io) does,
    /// for the `embedded-io` contract).
    fn write(&mut self, buf: &[u8]) -> Result<usize, MockSerialError> {
        self.pipe.write(self.line, buf)
    }

    fn flush(&mut self) -> Result<(), MockSerialError> {
        Ok(())
    }
}

impl<const N: usize> embedded_io::WriteReady for Tx<'_, N> {
    fn write_ready(&mut self) -> Result<bool, MockSerialError> {
        Ok(self.pipe.write_ready())
    }
}

impl<const N: usize> embedded_hal_nb::serial::ErrorType for Rx<'_, N> {
    type Error = MockSerialError;
}

impl<const N: usize> embedded_hal_nb::serial::ErrorType for Tx<'_, N> {
    type Error = MockSerialError;
}

impl<const N: usize> embedded_hal_nb::serial::Read<u8> for Rx<'_, N> {
    fn read(&mut self) -> nb::Result<u8, MockSerialError> {
        let mut buf = [0u8];
        match self.pipe.read(self.line, &mut buf) {
            Ok(1) => {
                let [b] = buf;
                Ok(b)
            }
            Ok(_) => Err(nb::Error::WouldBlock),
            Err(e) => Err(nb::Error::Other(e)),
        }
    }
}

impl<const N: usize> embedded_hal_nb::serial::Write<u8> for Tx<'_, N> {
    fn write(&mut self, word: u8) -> nb::Result<(), MockSerialError> {
        self.pipe.write_word(self.line, word)
    }

    fn flush(&mut self) -> nb::Result<(), MockSerialError> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_hal_nb::serial::{Read as NbRead, Write as NbWrite};
    use embedded_io::{Read, ReadReady, Write, WriteReady};

    #[test]
    fn ports_are_taken_once_and_lines_cross() {
        let pipe: Pipe<8> = Pipe::new(1);
        let (mut a_rx, mut a_tx) = pipe.port(0).unwrap();
        assert!(pipe.port(0).is_none());
        assert!(pipe.port(2).is_none());
        let (mut b_rx, mut b_tx) = pipe.port(1).unwrap();
        assert_eq!(Write::write(&mut a_tx, b"ab"), Ok(2));
        assert_eq!(Write::write(&mut b_tx, b"xyz"), Ok(3));
        let mut buf = [0u8; 8];
        assert_eq!(Read::read(&mut b_rx, &mut buf), Ok(2));
        assert_eq!(&buf[..2], b"ab");
        assert_eq!(Read::read(&mut a_rx, &mut buf), Ok(3));
        assert_eq!(&buf[..3], b"xyz");
        assert_eq!(Read::read(&mut a_rx, &mut buf), Ok(0));
        assert_eq!(a_rx.read_ready(), Ok(false));
        assert_eq!(pipe.stats(0).unwrap().delivered, 2);
        assert_eq!(pipe.stats(1).unwrap().delivered, 3);
    }

    #[test]
    fn pending_is_the_readers_and_a_port_beyond_1_is_none() {
        let pipe: Pipe<8> = Pipe::new(1);
        let (_, mut a_tx) = pipe.port(0).unwrap();
        assert_eq!(Write::write(&mut a_tx, b"abc"), Ok(3));
        // Port 0 wrote: port 1 has the bytes to read, port 0 none.
        assert_eq!((pipe.pending(0), pipe.pending(1)), (Some(0), Some(3)));
        for port in [2, 3, usize::MAX] {
            assert_eq!(pipe.pending(port), None, "{port}");
            assert_eq!(pipe.stats(port), None, "{port}");
        }
    }

    #[test]
    fn a_full_receive_buffer_drops_the_byte_and_reports_an_overrun_once() {
        let pipe: Pipe<4> = Pipe::new(1);
        let (_, mut tx) = pipe.port(0).unwrap();
        let (mut rx, _) = pipe.port(1).unwrap();
        // A UART transmits regardless of the receiver: all 6 are taken, 2 are dropped.
        assert_eq!(Write::write(&mut tx, &[1, 2, 3, 4, 5, 6]), Ok(6));
        assert_eq!(rx.read_ready(), Ok(true));
        let mut buf = [0u8; 8];
        assert_eq!(Read::read(&mut rx, &mut buf), Err(MockSerialError::Overrun));
        assert_eq!(Read::read(&mut rx, &mut buf), Ok(4));
        assert_eq!(&buf[..4], &[1, 2, 3, 4]);
        let s = pipe.stats(0).unwrap();
        assert_eq!((s.written, s.delivered, s.overruns, s.errors), (6, 4, 2, 1));
    }

    #[test]
    fn split_reads_and_slow_writes_stay_within_their_limits() {
        let pipe: Pipe<64> = Pipe::new(9).with_faults(SerialFaults {
            max_read: 3,
            max_write: 5,
            ..SerialFaults::NONE
        });
        let (_, mut tx) = pipe.port(0).unwrap();
        let (mut rx, _) = pipe.port(1).unwrap();
        let data: [u8; 40] = core::array::from_fn(|i| i as u8);
        let mut sent = 0;
        while sent < data.len() {
            let n = Write::write(&mut tx, &data[sent..]).unwrap();
            assert!((1..=5).contains(&n));
            sent += n;
        }
        let mut got = [0u8; 40];
        let mut have = 0;
        while have < got.len() {
            let n = Read::read(&mut rx, &mut got[have..]).unwrap();
            assert!((1..=3).contains(&n));
            have += n;
        }
        assert_eq!(got, data);
    }

    #[test]
    fn the_nb_writer_refuses_a_word_after_max_write_in_a_row() {
        let pipe: Pipe<64> = Pipe::new(3).with_faults(SerialFaults {
            max_write: 2,
            ..SerialFaults::NONE
        });
        let (_, mut tx) = pipe.port(0).unwrap();
        let (mut rx, _) = pipe.port(1).unwrap();
        assert_eq!(NbWrite::write(&mut tx, 1u8), Ok(()));
        assert_eq!(NbWrite::write(&mut tx, 2u8), Ok(()));
        assert_eq!(NbWrite::write(&mut tx, 3u8), Err(nb::Error::WouldBlock));
        assert_eq!(NbWrite::write(&mut tx, 3u8), Ok(()));
        assert_eq!(
            [
                NbRead::read(&mut rx),
                NbRead::read(&mut rx),
                NbRead::read(&mut rx),
                NbRead::read(&mut rx)
            ],
            [Ok(1), Ok(2), Ok(3), Err(nb::Error::WouldBlock)]
        );
    }

    #[test]
    fn faults_are_counted_and_every_byte_accounted_for() {
        let faults = SerialFaults {
            loss: 0.1,
            corruption: 0.1,
            write_stall: 0.3,
            rx_error: 0.1,
            tx_error: 0.1,
            ..SerialFaults::NONE
        };
        let run = |seed| {
            let pipe: Pipe<32> = Pipe::new(seed).with_faults(faults);
            let (_, mut tx) = pipe.port(0).unwrap();
            let (mut rx, _) = pipe.port(1).unwrap();
            let mut received = std::vec::Vec::new();
            let (mut errors, mut stalls) = (0u32, 0u32);
            for i in 0..2_000u32 {
                if !tx.write_ready().unwrap() {
                    stalls += 1;
                } else if Write::write(&mut tx, &[i as u8]).is_err() {
                    errors += 1;
                }
                let mut buf = [0u8; 4];
                match Read::read(&mut rx, &mut buf) {
                    Ok(n) => received.extend_from_slice(&buf[..n]),
                    Err(_) => errors += 1,
                }
            }
            let s = pipe.stats(0).unwrap();
            assert_eq!(
                s.written,
                s.delivered + s.lost + s.overruns + pipe.pending(1).unwrap() as u32
            );
            assert_eq!(s.errors, errors);
            assert_eq!(received.len() as u32, s.delivered);
            // About 10 % each (2,000 draws: a binomial's 5-sigma band is about ±7 %).
            assert!(s.lost > 40 && s.lost < 300, "{s:?}");
            assert!(s.corrupted > 40 && s.corrupted < 300, "{s:?}");
            assert!(stalls > 300, "{stalls}");
            (s, received)
        };
        // The same seed gives the same run; another seed another.
        assert_eq!(run(5), run(5));
        assert_ne!(run(5).1, run(6).1);
    }

    /// Each error says what happened in words (a test's failure message shows them).
    #[test]
    fn errors_say_what_happened() {
        use std::string::ToString;
        assert_eq!(
            MockSerialError::Overrun.to_string(),
            "receive overrun: bytes were dropped"
        );
        assert_eq!(MockSerialError::Noise.to_string(), "line noise");
    }

    /// A corrupted byte has exactly one bit flipped, any of the eight: bytes of all zeros
    /// and all ones, each flip seen as the one bit that differs (seeded: the same run every
    /// time; about 25 flips a bit position).
    #[test]
    fn corruption_flips_one_bit_of_the_byte() {
        let pipe: Pipe<8> = Pipe::new(3).with_faults(SerialFaults {
            corruption: 1.0,
            ..SerialFaults::NONE
        });
        let (_, mut tx) = pipe.port(0).unwrap();
        let (mut rx, _) = pipe.port(1).unwrap();
        let mut flipped = [0u32; 8];
        for i in 0..400 {
            let sent = if i % 2 == 0 { 0x00 } else { 0xFF };
            assert_eq!(Write::write(&mut tx, &[sent]), Ok(1));
            let mut got = [0u8; 1];
            assert_eq!(Read::read(&mut rx, &mut got), Ok(1));
            let diff = got[0] ^ sent;
            assert_eq!(diff.count_ones(), 1, "{sent:#04x} read as {:#04x}", got[0]);
            flipped[diff.trailing_zeros() as usize] += 1;
        }
        assert!(flipped.iter().all(|&n| n > 0), "{flipped:?}");
        assert_eq!(pipe.stats(0).unwrap().corrupted, 400);
    }

    /// The halves show their line, and nothing of the shared pipe.
    #[test]
    fn halves_debug_as_their_line() {
        let pipe: Pipe<8> = Pipe::new(1);
        let (rx, tx) = pipe.port(1).unwrap();
        assert_eq!(
            std::format!("{rx:?} {tx:?}"),
            "Rx { line: 0, .. } Tx { line: 1, .. }"
        );
    }
}
