//! An adapter that makes an `embedded_can::blocking::Can` driver a [`CanPort`](super::CanPort)'s
//! CAN driver: [`Blocking`], with a [`Classify`] to tell "would block" errors from faults.

use embedded_can::nb::Can;

/// Makes an `embedded_can::blocking::Can` driver (e.g. `mcp2515`) usable as an
/// `embedded_can::nb::Can` one.
///
/// A blocking `receive` waits for a frame, which would stall a [`CanPort`](super::CanPort)'s poll, so the
/// adapter asks `rx_ready` first (typically: the controller's interrupt pin is asserted)
/// and answers `WouldBlock` when it says no. `transmit` is the driver's own: one that
/// really blocks until a transmit buffer is free stalls the poll while none is (a bus
/// where no node acknowledges, a gimbal unpowered, keeps them full), so give the adapter
/// a driver whose `transmit` returns when it cannot queue, with a classifier for that
/// error.
///
/// Some drivers do not block at all: they return an error instead. The `mcp2515` crate
/// answers `Error::NoMessage` from `receive` when nothing is waiting and `Error::TxBusy`
/// from `transmit` when its three transmit buffers are full, and reports the
/// [`ErrorKind`](embedded_can::ErrorKind) of every error as `Other`. Without help the adapter would pass these on
/// as errors: the port would count "nothing received" and "try again later" as bus
/// faults and report them from every poll. A classifier ([`Blocking::with_classifier`], see [`Classify`])
/// tells such "would block" errors apart from real faults: they become
/// `nb::Error::WouldBlock`, so a refused frame goes back to the link's queue (it is
/// re-queued, not dropped, and sent on a later poll, in order) and an empty receive is
/// just "nothing waiting". Every other error stays `nb::Error::Other` and is counted.
///
/// ```
/// use idu_gimbal::port::{Blocking, CanPort};
///
/// /// What the `mcp2515` crate's errors look like.
/// #[derive(Debug)]
/// enum McpError { NoMessage, TxBusy, Spi }
/// impl embedded_can::Error for McpError {
///     fn kind(&self) -> embedded_can::ErrorKind { embedded_can::ErrorKind::Other }
/// }
///
/// fn port<B>(mcp: B) -> CanPort<impl embedded_can::nb::Can>
/// where
///     B: embedded_can::blocking::Can<Error = McpError>,
/// {
///     // `receive` never blocks (it answers NoMessage), so the adapter may always ask it.
///     let can = Blocking::with_classifier(mcp, |_: &mut B| true, |e: &McpError| {
///         matches!(e, McpError::NoMessage | McpError::TxBusy)
///     });
///     CanPort::new(can)
/// }
/// ```
pub struct Blocking<B, R, W = AllFaults> {
    can: B,
    rx_ready: R,
    would_block: W,
}

/// Tells a blocking driver's "would block" errors (nothing received, no transmit buffer
/// free) apart from real faults, for [`Blocking`].
///
/// Implemented by every `FnMut(&E) -> bool` (`true`: the error means "would block") and by
/// [`AllFaults`].
pub trait Classify<E> {
    /// Whether `error` only means that the operation would have to wait.
    fn would_block(&mut self, error: &E) -> bool;
}

impl<E, F: FnMut(&E) -> bool> Classify<E> for F {
    fn would_block(&mut self, error: &E) -> bool {
        self(error)
    }
}

/// The classifier of [`Blocking::new`]: every driver error is a fault. Right for drivers
/// that report only faults (a `receive` that really blocks is guarded by `rx_ready`; a
/// `transmit` that does is not, see [`Blocking`]).
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AllFaults;

impl<E> Classify<E> for AllFaults {
    fn would_block(&mut self, _error: &E) -> bool {
        false
    }
}

impl<B, R> Blocking<B, R>
where
    B: embedded_can::blocking::Can,
    R: FnMut(&mut B) -> bool,
{
    /// Wraps a blocking driver; `rx_ready` says whether a frame is waiting. Every error the
    /// driver returns is passed on as a fault ([`AllFaults`]).
    pub fn new(can: B, rx_ready: R) -> Self {
        Blocking {
            can,
            rx_ready,
            would_block: AllFaults,
        }
    }
}

impl<B, R, W> Blocking<B, R, W>
where
    B: embedded_can::blocking::Can,
    R: FnMut(&mut B) -> bool,
    W: Classify<B::Error>,
{
    /// Wraps a driver that returns errors instead of blocking; `rx_ready` says whether a
    /// frame may be waiting (it may always say yes when `receive` does not block), and
    /// `would_block` says which errors mean "would block" rather than a fault (for the
    /// `mcp2515` crate: `NoMessage` and `TxBusy`): a closure taking `&E` (its parameter's
    /// type written out), or any [`Classify`].
    pub fn with_classifier(can: B, rx_ready: R, would_block: W) -> Self {
        Blocking {
            can,
            rx_ready,
            would_block,
        }
    }
}

impl<B, R, W> Blocking<B, R, W>
where
    B: embedded_can::blocking::Can,
    W: Classify<B::Error>,
{
    /// Gives back the driver.
    pub fn release(self) -> B {
        self.can
    }

    /// The driver.
    pub fn can(&self) -> &B {
        &self.can
    }

    /// The driver, for what the adapter does not do with it (a controller's interrupt
    /// flags or error counters). Frames moved there pass the adapter, and its port's
    /// link, by.
    pub fn can_mut(&mut self) -> &mut B {
        &mut self.can
    }

    fn classify(&mut self, error: B::Error) -> nb::Error<B::Error> {
        if self.would_block.would_block(&error) {
            nb::Error::WouldBlock
        } else {
            nb::Error::Other(error)
        }
    }
}

impl<B, R, W> Can for Blocking<B, R, W>
where
    B: embedded_can::blocking::Can,
    R: FnMut(&mut B) -> bool,
    W: Classify<B::Error>,
{
    type Frame = B::Frame;
    type Error = B::Error;

    fn transmit(&mut self, frame: &Self::Frame) -> nb::Result<Option<Self::Frame>, Self::Error> {
        match self.can.transmit(frame) {
            // Queued in the controller: nothing is handed back.
            Ok(()) => Ok(None),
            Err(e) => Err(self.classify(e)),
        }
    }

    fn receive(&mut self) -> nb::Result<Self::Frame, Self::Error> {
        if !(self.rx_ready)(&mut self.can) {
            return Err(nb::Error::WouldBlock);
        }
        self.can.receive().map_err(|e| self.classify(e))
    }
}
