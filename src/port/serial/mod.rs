//! The serial port: a [`SerialLink`](crate::link::SerialLink) over the gimbal's UART (115200 8N1, SATA pins 5 and 6
//! on the gimbal side; see [`interface::UART_BAUD`](crate::interface::UART_BAUD)).
//!
//! [`SerialPort`] moves bytes between a [`Uart`] ([`Io`] for `embedded-io` 0.7, [`Nb`] for
//! `embedded-hal-nb`; see [`uart`]) and the link through a [`SerialStream`], and never
//! blocks: a poll reads what is waiting and writes what the UART takes now.
//!
//! # What the serial path carries
//!
//! Control commands and postbacks only, as the link's type says (see
//! [`link::medium`](crate::link::medium)): the vehicle's attitude, GPS and altitude given
//! to a [`SerialLink`](crate::link::SerialLink) give [`point_at`](crate::Link::point_at) and aims the state they aim
//! from; none of it is sent, and the gimbal references headings to the nose.
//!
//! ```
//! # #[cfg(feature = "mock")] {
//! use idu_gimbal::link::SerialLink;
//! use idu_gimbal::mock::serial::Pipe;
//! use idu_gimbal::port::{Io, Port, SerialPort};
//! use idu_gimbal::wire::control::{GimbalCommand, Pitch};
//! use idu_gimbal::wire::serial::{StreamItem, StreamParser};
//! use idu_gimbal::{Config, Instant};
//!
//! // On a board: the HAL's UART halves (or your interrupt-driven ring buffer).
//! let pipe: Pipe<64> = Pipe::new(1);
//! let (rx, tx) = pipe.port(0).unwrap();
//! let mut link: SerialLink = SerialLink::new(Config::default());
//! let mut port = SerialPort::new(Io::new(rx, tx));
//!
//! link.send(GimbalCommand::Pitch(Pitch::new(-45.0).unwrap())).unwrap();
//! port.poll(&mut link, Instant::from_millis(0)).unwrap();
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

pub mod stream;
pub mod uart;

use core::fmt;

use super::Port;
use crate::link::{Link, Serial};
use crate::time::Instant;
use crate::wire::serial::StreamStats;
pub use stream::{SerialStream, SerialStreamStats};
pub use uart::{Io, Nb, Uart};

/// A UART error seen during a [`SerialPort`]'s poll. The poll still did all its work.
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

/// UART errors counted by a [`SerialPort`].
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PortErrors {
    /// Failed reads.
    pub read: u32,
    /// Failed writes.
    pub write: u32,
    /// Reads and writes the UART said were longer than the buffer it was given, which
    /// breaks the [`Uart`] contract: taken as the whole buffer, and counted here.
    pub overlong: u32,
}

/// What a [`SerialPort`] counts; the link counts the rest ([`Link::stats`](crate::Link::stats)).
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SerialPortStats {
    /// The stream parser's counters: frames, CRC errors, invalid frames, skipped bytes.
    pub stream: StreamStats,
    /// Bytes received.
    pub bytes_received: u32,
    /// Bytes written.
    pub bytes_sent: u32,
    /// UART errors by direction.
    pub port_errors: PortErrors,
}

/// How many bytes one read asks for: two control frames, or a postback and change.
const READ_CHUNK: usize = 32;

/// The serial port: a gimbal's [`SerialLink`](crate::link::SerialLink) on a UART, driven through `U`.
pub struct SerialPort<U: Uart> {
    uart: U,
    stream: SerialStream,
    /// Kept between polls so that an idle poll need not clear it.
    rx_buf: [u8; READ_CHUNK],
    errors: PortErrors,
}

type UartError<U> = PortError<<U as Uart>::ReadError, <U as Uart>::WriteError>;

impl<U: Uart> SerialPort<U> {
    /// A port over `uart`.
    pub fn new(uart: U) -> Self {
        SerialPort {
            uart,
            stream: SerialStream::new(),
            rx_buf: [0; READ_CHUNK],
            errors: PortErrors::default(),
        }
    }

    /// [`Port::poll`]'s reads: the first inline, the rest out of line (an idle poll pays
    /// for one read).
    #[inline(always)]
    fn receive_all<const Q: usize, const T: usize>(
        &mut self,
        link: &mut Link<Q, T, Serial>,
        now: Instant,
        first_error: &mut Option<UartError<U>>,
    ) {
        match self.uart.read(&mut self.rx_buf) {
            Ok(0) => {}
            first => self.receive(link, first, now, first_error),
        }
    }

    /// [`Port::poll`] as if its idle check never held: what the check is tested against.
    #[cfg(test)]
    pub(in crate::port) fn poll_without_idle_check<const Q: usize, const T: usize>(
        &mut self,
        link: &mut Link<Q, T, Serial>,
        now: Instant,
    ) -> Result<(), UartError<U>> {
        let mut first_error = None;
        self.receive_all(link, now, &mut first_error);
        self.poll_busy(link, now, &mut first_error);
        first_error.map_or(Ok(()), Err)
    }

    /// [`Port::poll`] past its reads when the idle check did not hold: the link's
    /// schedules, then whatever waits to be written.
    #[inline(always)]
    fn poll_busy<const Q: usize, const T: usize>(
        &mut self,
        link: &mut Link<Q, T, Serial>,
        now: Instant,
        first_error: &mut Option<UartError<U>>,
    ) {
        link.poll_for_port(now);
        if self.stream.has_transmit(link) {
            if let Some(e) = self.transmit(link) {
                first_error.get_or_insert(e);
            }
        } else {
            link.release_idle();
        }
    }

    /// Takes the result of the poll's first read, then reads on until nothing waits or
    /// [`Config::max_rx_per_poll`](crate::Config) reads were made.
    #[inline(never)]
    fn receive<const Q: usize, const T: usize>(
        &mut self,
        link: &mut Link<Q, T, Serial>,
        mut read: Result<usize, U::ReadError>,
        now: Instant,
        first_error: &mut Option<UartError<U>>,
    ) {
        let mut left = link.config().max_rx_per_poll.get();
        loop {
            match read {
                Ok(0) => return,
                Ok(n) => {
                    let bytes = match self.rx_buf.get(..n) {
                        Some(bytes) => bytes,
                        None => {
                            self.errors.overlong = self.errors.overlong.wrapping_add(1);
                            &self.rx_buf
                        }
                    };
                    self.stream.receive(link, bytes, now)
                }
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
            read = self.uart.read(&mut self.rx_buf);
        }
    }

    #[inline(never)]
    fn transmit<const Q: usize, const T: usize>(
        &mut self,
        link: &mut Link<Q, T, Serial>,
    ) -> Option<UartError<U>> {
        loop {
            let bytes = self.stream.transmit_bytes(link);
            if bytes.is_empty() {
                return None;
            }
            let len = bytes.len();
            match self.uart.write(bytes) {
                Ok(0) => {
                    self.stream.transmit_written(link, 0);
                    // Bytes wait (a frame part-written stays out of the link's queue):
                    // the idle check must not skip the next poll.
                    link.hold_idle();
                    return None;
                }
                Ok(n) => {
                    if n > len {
                        self.errors.overlong = self.errors.overlong.wrapping_add(1);
                    }
                    self.stream.transmit_written(link, n)
                }
                Err(e) => {
                    self.stream.transmit_written(link, 0);
                    link.hold_idle();
                    self.errors.write = self.errors.write.wrapping_add(1);
                    return Some(PortError::Write(e));
                }
            }
        }
    }

    /// What the port counts (the link counts the rest).
    pub fn stats(&self) -> SerialPortStats {
        let SerialStreamStats {
            stream,
            bytes_received,
            bytes_sent,
        } = self.stream.stats();
        SerialPortStats {
            stream,
            bytes_received,
            bytes_sent,
            port_errors: self.errors,
        }
    }

    /// The serial stream, for its state ([`SerialStream::parser`]).
    pub fn stream(&self) -> &SerialStream {
        &self.stream
    }

    /// The UART.
    pub fn uart(&self) -> &U {
        &self.uart
    }

    /// The UART, for what the port does not do with it. Bytes read or written through it
    /// pass the link by: what is read here never reaches the stream parser, and bytes
    /// written here could fall inside a frame the port has part-written.
    pub fn uart_mut(&mut self) -> &mut U {
        &mut self.uart
    }

    /// Gives back the UART.
    pub fn release(self) -> U {
        self.uart
    }
}

impl<U: Uart> Port for SerialPort<U> {
    type Medium = Serial;
    type Error = UartError<U>;

    /// Reads what is waiting (at most [`Config::max_rx_per_poll`](crate::Config) reads of
    /// 32 bytes), runs the link's schedules, and writes until the UART takes no more.
    ///
    /// A UART error is counted and the poll goes on: after a read error it runs the
    /// schedules; a write error ends this poll's writing (a frame part-written is finished
    /// at the next poll). The first error seen is returned at the end.
    #[inline]
    fn poll<const Q: usize, const T: usize>(
        &mut self,
        link: &mut Link<Q, T, Serial>,
        now: Instant,
    ) -> Result<(), UartError<U>> {
        let mut first_error = None;
        self.receive_all(link, now, &mut first_error);
        // Unless nothing is due and nothing waits to be written (one compare for both).
        if !link.is_idle(now) {
            self.poll_busy(link, now, &mut first_error);
        }
        first_error.map_or(Ok(()), Err)
    }

    fn next_deadline<const Q: usize, const T: usize>(
        &self,
        link: &Link<Q, T, Serial>,
        now: Instant,
    ) -> Instant {
        if self.stream.has_transmit(link) {
            now
        } else {
            link.next_deadline(now)
        }
    }
}
