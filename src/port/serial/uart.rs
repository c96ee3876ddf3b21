//! The UART a [`SerialPort`](super::SerialPort) drives: the [`Uart`] contract, and the
//! adapters that make the field's serial traits one.
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

/// A byte stream that never blocks: the contract a [`SerialPort`](super::SerialPort) needs of a UART.
pub trait Uart {
    /// What a read can fail with.
    type ReadError;
    /// What a write can fail with.
    type WriteError;

    /// Reads bytes that are waiting, at most `buf.len()`, without blocking: `Ok(0)` when
    /// none are. (A [`SerialPort`](super::SerialPort) told more takes the whole buffer and
    /// counts it: [`PortErrors::overlong`](super::PortErrors::overlong).)
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::ReadError>;

    /// Writes the first bytes of `bytes` that the port takes now, without blocking, and
    /// says how many: `Ok(0)` when it takes none now. (More than `bytes.len()` is taken as
    /// all of them and counted, as for a read.)
    fn write(&mut self, bytes: &[u8]) -> Result<usize, Self::WriteError>;
}

/// `embedded-io` 0.7 halves as a [`Uart`]: a read or write happens only when
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

    /// The halves, for what the adapter does not do with them (a HAL's interrupts, say).
    /// What is read or written there passes the adapter, and its port's link, by.
    pub fn halves_mut(&mut self) -> (&mut R, &mut W) {
        (&mut self.rx, &mut self.tx)
    }
}

impl<R, W> Uart for Io<R, W>
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

/// `embedded-hal-nb` 1.0 serial halves as a [`Uart`], one word at a time.
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

    /// Gives back the halves. An error kept for the next call (above) goes with the
    /// adapter: an empty `read` or `write` first hands it out and moves nothing.
    pub fn release(self) -> (R, W) {
        (self.rx, self.tx)
    }

    /// The halves, for what the adapter does not do with them (a HAL's interrupts, say).
    /// What is read or written there passes the adapter, and its port's link, by.
    pub fn halves_mut(&mut self) -> (&mut R, &mut W) {
        (&mut self.rx, &mut self.tx)
    }
}

impl<R, W> Uart for Nb<R, W>
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
