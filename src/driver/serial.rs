//! The serial transport: a [`SerialLink`] over the gimbal's UART (115200 8N1, SATA pins 5
//! and 6 on the gimbal side; see [`interface::UART_BAUD`](crate::interface::UART_BAUD)).
//!
//! [`SerialGimbal`] moves bytes between a [`SerialPort`] and the link, and never blocks: a
//! poll reads what is waiting and writes what the port takes now. Two adapters make the
//! field's serial traits a [`SerialPort`]:
//!
//! - [`Io`]: `embedded-io` **0.7** `Read + ReadReady` and `Write + WriteReady` (the `Ready`
//!   traits are what make a poll non-blocking: a plain `Read` or `Write` may wait). 0.7 is
//!   the current release, with `core::error::Error` errors; a HAL still on 0.6 (embassy and
//!   esp-hal releases of 2024, for example) can be wrapped in a few lines, or through
//!   [`Nb`] when it implements `embedded-hal-nb`.
//! - [`Nb`]: `embedded-hal-nb` 1.0 serial `Read<u8>` and `Write<u8>`, one word at a time,
//!   as stm32f4xx-hal 0.23 and most HALs implement for their UARTs (stm32f4xx-hal's
//!   `embedded-io` support is 0.6 and `Write` only, which cannot read).
//!
//! Each adapter takes the receive and transmit halves separately, as HALs split them (an
//! interrupt-driven receiver is often a ring buffer of the application's own).
//!
//! # What the serial path carries
//!
//! Control commands and postbacks only: [`SerialGimbal`] has no vehicle push and no text,
//! and the gimbal references headings to the nose (see [`link::serial`](crate::link::serial)).
//! Through the command surface ([`GimbalControl`](crate::GimbalControl)) the vehicle's
//! attitude, GPS and altitude give [`point_at`](crate::GimbalControl::point_at) the state
//! it aims from; none of it is sent ([`GimbalControl::north_referenced`](crate::GimbalControl::north_referenced)
//! is always false here).
//!
//! ```
//! # #[cfg(feature = "mock")] {
//! use idu_gimbal::driver::{Io, SerialGimbal};
//! use idu_gimbal::mock::serial::Pipe;
//! use idu_gimbal::wire::control::{GimbalCommand, Pitch};
//! use idu_gimbal::wire::serial::{StreamItem, StreamParser};
//! use idu_gimbal::{Config, GimbalControl, Instant};
//!
//! // On a board: the HAL's UART halves (or your interrupt-driven ring buffer).
//! let pipe: Pipe<64> = Pipe::new(1);
//! let (rx, tx) = pipe.port(0).unwrap();
//! let mut gimbal: SerialGimbal<_> = SerialGimbal::new(Io::new(rx, tx), Config::default());
//!
//! gimbal.send(GimbalCommand::Pitch(Pitch::new(-45.0).unwrap())).unwrap();
//! gimbal.poll(Instant::from_millis(0)).unwrap();
//!
//! // The other end of the wire sees one 24-byte frame.
//! let (mut gimbal_rx, _) = pipe.port(1).unwrap();
//! let mut bytes = [0u8; 64];
//! let n = embedded_io::Read::read(&mut gimbal_rx, &mut bytes).unwrap();
//! let mut parser = StreamParser::new();
//! let items: Vec<_> = parser.feed(&bytes[..n]).collect();
//! assert_eq!(items, [StreamItem::Control([0x0F, 0x08, 0x02, 0x3E, 0xFE, 0, 0, 0])]);
//! # }
//! ```

use core::fmt;

use crate::control::Transport;
use crate::link::serial::{SerialLink, SerialStats};
use crate::link::{Config, LinkStats};
use crate::time::Instant;
use crate::wire::serial::StreamStats;

/// A byte stream that never blocks: the contract [`SerialGimbal`] needs of a UART.
pub trait SerialPort {
    /// What a read can fail with.
    type ReadError;
    /// What a write can fail with.
    type WriteError;

    /// Reads bytes that are waiting, at most `buf.len()`, without blocking: `Ok(0)` when
    /// none are.
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::ReadError>;

    /// Writes the first bytes of `bytes` that the port takes now, without blocking, and
    /// says how many: `Ok(0)` when it takes none now.
    fn write(&mut self, bytes: &[u8]) -> Result<usize, Self::WriteError>;
}

/// `embedded-io` 0.7 halves as a [`SerialPort`]: a read or write happens only when
/// `read_ready` or `write_ready` says it will not block.
#[derive(Debug)]
pub struct Io<R, W> {
    rx: R,
    tx: W,
}

impl<R, W> Io<R, W>
where
    R: embedded_io::Read + embedded_io::ReadReady,
    W: embedded_io::Write + embedded_io::WriteReady,
{
    /// Wraps the receive and transmit halves.
    pub fn new(rx: R, tx: W) -> Self {
        Io { rx, tx }
    }

    /// Gives back the halves.
    pub fn release(self) -> (R, W) {
        (self.rx, self.tx)
    }
}

impl<R, W> SerialPort for Io<R, W>
where
    R: embedded_io::Read + embedded_io::ReadReady,
    W: embedded_io::Write + embedded_io::WriteReady,
{
    type ReadError = R::Error;
    type WriteError = W::Error;

    fn read(&mut self, buf: &mut [u8]) -> Result<usize, R::Error> {
        if buf.is_empty() || !self.rx.read_ready()? {
            return Ok(0);
        }
        // Ok(0) here would be end of stream, which a UART does not have: nothing read.
        self.rx.read(buf)
    }

    fn write(&mut self, bytes: &[u8]) -> Result<usize, W::Error> {
        if bytes.is_empty() || !self.tx.write_ready()? {
            return Ok(0);
        }
        self.tx.write(bytes)
    }
}

/// `embedded-hal-nb` 1.0 serial halves as a [`SerialPort`], one word at a time.
///
/// An error after some bytes were moved in the same call is kept and returned by the next
/// call, so neither the bytes nor the error are lost.
#[derive(Debug)]
pub struct Nb<R: embedded_hal_nb::serial::ErrorType, W: embedded_hal_nb::serial::ErrorType> {
    rx: R,
    tx: W,
    rx_error: Option<R::Error>,
    tx_error: Option<W::Error>,
}

impl<R, W> Nb<R, W>
where
    R: embedded_hal_nb::serial::Read<u8>,
    W: embedded_hal_nb::serial::Write<u8>,
{
    /// Wraps the receive and transmit halves.
    pub fn new(rx: R, tx: W) -> Self {
        Nb {
            rx,
            tx,
            rx_error: None,
            tx_error: None,
        }
    }

    /// Gives back the halves.
    pub fn release(self) -> (R, W) {
        (self.rx, self.tx)
    }
}

impl<R, W> SerialPort for Nb<R, W>
where
    R: embedded_hal_nb::serial::Read<u8>,
    W: embedded_hal_nb::serial::Write<u8>,
{
    type ReadError = R::Error;
    type WriteError = W::Error;

    fn read(&mut self, buf: &mut [u8]) -> Result<usize, R::Error> {
        if let Some(e) = self.rx_error.take() {
            return Err(e);
        }
        // `n`: the bytes read before this one.
        for (n, slot) in buf.iter_mut().enumerate() {
            match self.rx.read() {
                Ok(b) => *slot = b,
                Err(nb::Error::WouldBlock) => return Ok(n),
                Err(nb::Error::Other(e)) if n == 0 => return Err(e),
                Err(nb::Error::Other(e)) => {
                    self.rx_error = Some(e);
                    return Ok(n);
                }
            }
        }
        Ok(buf.len())
    }

    fn write(&mut self, bytes: &[u8]) -> Result<usize, W::Error> {
        if let Some(e) = self.tx_error.take() {
            return Err(e);
        }
        // `n`: the bytes written before this one.
        for (n, &b) in bytes.iter().enumerate() {
            match self.tx.write(b) {
                Ok(()) => {}
                Err(nb::Error::WouldBlock) => return Ok(n),
                Err(nb::Error::Other(e)) if n == 0 => return Err(e),
                Err(nb::Error::Other(e)) => {
                    self.tx_error = Some(e);
                    return Ok(n);
                }
            }
        }
        Ok(bytes.len())
    }
}

/// A port error seen during [`SerialGimbal::poll`]. The poll still did all its work.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PortError<R, W> {
    /// Reading failed (an overrun, framing or parity error, a noisy line, …).
    Read(R),
    /// Writing failed; the frame being written is finished at a later poll.
    Write(W),
}

impl<R: fmt::Debug, W: fmt::Debug> fmt::Display for PortError<R, W> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PortError::Read(e) => write!(f, "serial read error: {e:?}"),
            PortError::Write(e) => write!(f, "serial write error: {e:?}"),
        }
    }
}

#[cfg(feature = "std")]
impl<R: fmt::Debug, W: fmt::Debug> std::error::Error for PortError<R, W> {}

/// Port errors counted by [`SerialGimbal`].
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PortErrors {
    /// Failed reads.
    pub read: u32,
    /// Failed writes.
    pub write: u32,
}

/// Everything [`SerialGimbal`] counts: the link's counters, then the serial port's (the
/// shape of every driver's `stats()`: `link`, then what its transport adds).
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SerialGimbalStats {
    /// The link's counters (as [`SerialStats::link`]: postbacks and CRC errors come from the
    /// stream parser).
    pub link: LinkStats,
    /// The stream parser's counters: frames, CRC errors, invalid frames, skipped bytes.
    pub stream: StreamStats,
    /// Bytes received.
    pub bytes_received: u32,
    /// Bytes written.
    pub bytes_sent: u32,
    /// Port errors by direction.
    pub port_errors: PortErrors,
}

/// How many bytes one read asks for: two control frames, or a postback and change.
const READ_CHUNK: usize = 32;

/// A gimbal on a serial port, driven through `P`.
///
/// `Q` is the number of queued control commands. The command API is
/// [`Gimbal`](crate::Gimbal)'s without what the serial link cannot carry (vehicle pushes,
/// text).
pub struct SerialGimbal<P: SerialPort, const Q: usize = 8> {
    port: P,
    link: SerialLink<Q>,
    /// Kept between polls so that an idle poll need not clear it.
    rx_buf: [u8; READ_CHUNK],
    errors: PortErrors,
}

impl<P: SerialPort, const Q: usize> SerialGimbal<P, Q> {
    /// A driver over `port` with the given timing (its vehicle push periods are not used;
    /// see [`SerialLink::new`]).
    pub fn new(port: P, config: Config) -> Self {
        SerialGimbal {
            port,
            link: SerialLink::new(config),
            rx_buf: [0; READ_CHUNK],
            errors: PortErrors::default(),
        }
    }

    /// Reads what is waiting (at most [`Config::max_rx_per_poll`] reads of 32 bytes), runs
    /// the schedules, and writes until the port takes no more.
    ///
    /// A port error is counted and does not stop the work: the poll goes on, and the first
    /// error seen is returned at the end.
    pub fn poll(&mut self, now: Instant) -> Result<(), PortError<P::ReadError, P::WriteError>> {
        let mut first_error = None;
        self.receive_all(now, &mut first_error);
        // Unless nothing is due and nothing waits to be written (one compare for both).
        if !self.link.link().is_idle(now) {
            self.poll_busy(now, &mut first_error);
        }
        first_error.map_or(Ok(()), Err)
    }

    /// [`SerialGimbal::poll`]'s reads: the first inline, the rest out of line (an idle
    /// poll pays for one read).
    #[inline(always)]
    fn receive_all(
        &mut self,
        now: Instant,
        first_error: &mut Option<PortError<P::ReadError, P::WriteError>>,
    ) {
        match self.port.read(&mut self.rx_buf) {
            Ok(0) => {}
            first => self.receive(first, now, first_error),
        }
    }

    /// [`SerialGimbal::poll`] as if its idle check never held: what the check is tested
    /// against.
    #[cfg(test)]
    pub(super) fn poll_without_idle_check(
        &mut self,
        now: Instant,
    ) -> Result<(), PortError<P::ReadError, P::WriteError>> {
        let mut first_error = None;
        self.receive_all(now, &mut first_error);
        self.poll_busy(now, &mut first_error);
        first_error.map_or(Ok(()), Err)
    }

    /// Whether the idle check would skip the poll at `now`.
    #[cfg(test)]
    pub(super) fn is_idle(&self, now: Instant) -> bool {
        self.link.link().is_idle(now)
    }

    /// [`SerialGimbal::poll`] past its reads when the idle check did not hold: the link's
    /// schedules, then whatever waits to be written.
    #[inline(always)]
    fn poll_busy(
        &mut self,
        now: Instant,
        first_error: &mut Option<PortError<P::ReadError, P::WriteError>>,
    ) {
        self.link.poll(now);
        if self.link.has_transmit() {
            if let Some(e) = self.transmit() {
                first_error.get_or_insert(e);
            }
        } else {
            self.link.link_mut().release_idle();
        }
    }

    /// The instant by which [`SerialGimbal::poll`] must next be called if no byte is
    /// received before then, as seen from `now`: the link's
    /// [`next_deadline`](SerialLink::next_deadline), or `now` while bytes wait to be
    /// written (the port took no more at the last poll). The result is at or after `now`
    /// and less than 2^31 ms ahead of it.
    pub fn next_deadline(&self, now: Instant) -> Instant {
        if self.link.has_transmit() {
            now
        } else {
            self.link.next_deadline(now)
        }
    }

    /// Takes the result of the poll's first read, then reads on until nothing waits or
    /// [`Config::max_rx_per_poll`] reads were made.
    #[inline(never)]
    fn receive(
        &mut self,
        mut read: Result<usize, P::ReadError>,
        now: Instant,
        first_error: &mut Option<PortError<P::ReadError, P::WriteError>>,
    ) {
        let mut left = self.link.link().config().max_rx_per_poll.get();
        loop {
            match read {
                Ok(0) => return,
                Ok(n) => self
                    .link
                    .receive(self.rx_buf.get(..n).unwrap_or(&self.rx_buf), now),
                Err(e) => {
                    self.errors.read = self.errors.read.wrapping_add(1);
                    first_error.get_or_insert(PortError::Read(e));
                }
            }
            // At least 1 here: the bound is not zero, and the loop ends at 0.
            left = left.saturating_sub(1);
            if left == 0 {
                return;
            }
            read = self.port.read(&mut self.rx_buf);
        }
    }

    #[inline(never)]
    fn transmit(&mut self) -> Option<PortError<P::ReadError, P::WriteError>> {
        loop {
            let bytes = self.link.transmit_bytes();
            if bytes.is_empty() {
                return None;
            }
            match self.port.write(bytes) {
                Ok(0) => {
                    self.link.transmit_written(0);
                    // Bytes wait (a frame part-written stays out of the link's queue):
                    // the idle check must not skip the next poll.
                    self.link.link_mut().hold_idle();
                    return None;
                }
                Ok(n) => self.link.transmit_written(n),
                Err(e) => {
                    self.link.transmit_written(0);
                    self.link.link_mut().hold_idle();
                    self.errors.write = self.errors.write.wrapping_add(1);
                    return Some(PortError::Write(e));
                }
            }
        }
    }

    /// All counters.
    pub fn stats(&self) -> SerialGimbalStats {
        let SerialStats {
            link,
            stream,
            bytes_received,
            bytes_sent,
        } = self.link.stats();
        SerialGimbalStats {
            link,
            stream,
            bytes_received,
            bytes_sent,
            port_errors: self.errors,
        }
    }

    /// Gives back the port.
    pub fn release(self) -> P {
        self.port
    }
}

/// The command surface ([`GimbalControl`](crate::GimbalControl)) is the serial link's. The
/// vehicle's data is kept for point-at only (the serial link carries no vehicle frames), so
/// headings are nose-referenced.
impl<P: SerialPort, const Q: usize> crate::control::Transport for SerialGimbal<P, Q> {
    type Link = SerialLink<Q>;

    #[inline]
    fn link(&self) -> &SerialLink<Q> {
        &self.link
    }

    #[inline]
    fn link_mut(&mut self) -> &mut SerialLink<Q> {
        &mut self.link
    }
}
