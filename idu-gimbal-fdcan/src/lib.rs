//! An `embedded_can::nb::Can` adapter for the STM32 FDCAN peripheral, so that
//! `idu-gimbal`'s CAN port drives it.
//!
//! The [`fdcan`](https://docs.rs/fdcan/0.2) crate, which stm32h7xx-hal uses (feature `can`),
//! implements no `embedded-can` trait. [`FdCan`] wraps its
//! `fdcan::FdCan<I, NormalOperationMode>` and implements `embedded_can::nb::Can` for classic
//! CAN (8-byte frames, standard or extended IDs), so that `idu_gimbal::port::CanPort`
//! drives it like any other controller:
//!
//! - `transmit` puts the frame in a transmit buffer when none is pending, and answers
//!   `WouldBlock` otherwise: one frame in flight. The fdcan crate runs the transmit buffers
//!   as a priority queue, in which frames of equal ID leave lowest buffer first, not in the
//!   order they were written; with more than one in flight, a refilled buffer would
//!   overtake older frames of the same ID (the protocol's text chunks, or a zoom-in and
//!   its zoom-stop). One at a time is also what the gimbal needs: a frame takes about
//!   130 µs at 1 Mbit/s, and the protocol sends a few dozen a second.
//! - `receive` takes a frame from receive FIFO 0 (configure the filters to store the
//!   postback there), or answers `WouldBlock` when the FIFO is empty.
//! - Errors, each counted by the driver under its [`ErrorKind`]: the controller's last
//!   error code (read, and so cleared, once per `receive`: stuff, form, acknowledge, bit 0/1
//!   and CRC errors as their kinds), a receive FIFO overrun (`Overrun`, once a loss: the
//!   adapter clears the controller's message-lost flag; the frame that came with it, or
//!   why the adapter cannot carry it, is delivered by the next `receive`), the controller going bus-off, and frames the adapter cannot carry (both
//!   `Other`). See [`Error`].
//!
//! The fdcan crate's register layout is chosen by a feature of its own: this crate turns on
//! `fdcan/fdcan_h7` (the STM32H7's FDCAN, as stm32h7xx-hal does). Not for the G0/G4/L5
//! layout.
//!
//! Recovery from bus-off is left to the application (the M_CAN core stays in
//! initialisation until software restarts it): take the controller back with
//! [`FdCan::release`], move it through `into_config_mode()` and `into_normal()`, and wrap
//! it again.

#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    deny(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing,
        clippy::arithmetic_side_effects
    )
)]

#[cfg(feature = "std")]
extern crate std;

use core::convert::Infallible;
use core::fmt;

use embedded_can::{ErrorKind, ExtendedId, Id, StandardId};
use fdcan::frame::{FrameFormat, RxFrameInfo, TxFrameHeader};
use fdcan::{LastErrorCode, Mailbox, NormalOperationMode, ReceiveOverrun};

/// The largest frame the FDCAN's receive FIFO can hand out (CAN FD, 64 bytes): the buffer
/// given to it, so that it never panics on a long frame.
const RX_BUFFER: usize = 64;

/// A classic CAN frame for [`FdCan`]: a standard or extended ID, a data frame of 0 to 8
/// bytes or a remote frame.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Frame {
    id: Id,
    remote: bool,
    dlc: u8,
    data: [u8; 8],
}

impl embedded_can::Frame for Frame {
    fn new(id: impl Into<Id>, data: &[u8]) -> Option<Self> {
        let mut d = [0u8; 8];
        d.get_mut(..data.len())?.copy_from_slice(data);
        Some(Frame {
            id: id.into(),
            remote: false,
            dlc: u8::try_from(data.len()).ok()?,
            data: d,
        })
    }

    fn new_remote(id: impl Into<Id>, dlc: usize) -> Option<Self> {
        if dlc > 8 {
            return None;
        }
        Some(Frame {
            id: id.into(),
            remote: true,
            dlc: u8::try_from(dlc).ok()?,
            data: [0; 8],
        })
    }

    fn is_extended(&self) -> bool {
        matches!(self.id, Id::Extended(_))
    }

    fn is_remote_frame(&self) -> bool {
        self.remote
    }

    fn id(&self) -> Id {
        self.id
    }

    fn dlc(&self) -> usize {
        usize::from(self.dlc)
    }

    fn data(&self) -> &[u8] {
        if self.remote {
            return &[];
        }
        self.data.get(..usize::from(self.dlc)).unwrap_or(&[])
    }
}

#[cfg(feature = "defmt")]
impl defmt::Format for Frame {
    fn format(&self, f: defmt::Formatter<'_>) {
        let (raw, extended) = match self.id {
            Id::Standard(id) => (u32::from(id.as_raw()), false),
            Id::Extended(id) => (id.as_raw(), true),
        };
        defmt::write!(
            f,
            "Frame {{ id: {=u32:#x}, extended: {=bool}, remote: {=bool}, data: {=[u8]:x} }}",
            raw,
            extended,
            self.remote,
            embedded_can::Frame::data(self)
        )
    }
}

/// What [`FdCan`] reports. Its [`ErrorKind`] (through `embedded_can::Error`) is what the
/// driver counts.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// The controller saw a stuff error on the bus (`ErrorKind::Stuff`).
    Stuff,
    /// A form error (`ErrorKind::Form`).
    Form,
    /// A frame it sent was not acknowledged: no other node on the bus, or none at this bit
    /// rate (`ErrorKind::Acknowledge`).
    Acknowledge,
    /// It sent a recessive bit and read back a dominant one (`ErrorKind::Bit`).
    Bit1,
    /// It sent a dominant bit and read back a recessive one (`ErrorKind::Bit`).
    Bit0,
    /// A received frame's CRC did not match (`ErrorKind::Crc`).
    Crc,
    /// Receive FIFO 0 overran: frames were lost (`ErrorKind::Overrun`).
    Overrun,
    /// The controller went bus-off and stopped taking part in the bus (`ErrorKind::Other`).
    /// Reported once, when it happens.
    BusOff,
    /// A frame the controller cannot carry as asked (`ErrorKind::Other`): a data frame of no
    /// bytes or a remote frame with a DLC other than 0 (the fdcan crate sends a frame of
    /// length 0 as a remote frame and has no other way to ask for one). Also an ID that one
    /// crate's ID types cannot hold, sent or received (both are 11 and 29 bits: never seen).
    Unsupported,
    /// A CAN FD frame was received (`ErrorKind::Other`); the adapter carries classic frames
    /// only. It is dropped.
    NotClassic,
}

impl embedded_can::Error for Error {
    fn kind(&self) -> ErrorKind {
        match self {
            Error::Stuff => ErrorKind::Stuff,
            Error::Form => ErrorKind::Form,
            Error::Acknowledge => ErrorKind::Acknowledge,
            Error::Bit1 | Error::Bit0 => ErrorKind::Bit,
            Error::Crc => ErrorKind::Crc,
            Error::Overrun => ErrorKind::Overrun,
            Error::BusOff | Error::Unsupported | Error::NotClassic => ErrorKind::Other,
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Error::Stuff => "FDCAN: stuff error",
            Error::Form => "FDCAN: form error",
            Error::Acknowledge => "FDCAN: acknowledge error",
            Error::Bit1 => "FDCAN: bit 1 error",
            Error::Bit0 => "FDCAN: bit 0 error",
            Error::Crc => "FDCAN: CRC error",
            Error::Overrun => "FDCAN: receive FIFO overrun",
            Error::BusOff => "FDCAN: bus-off",
            Error::Unsupported => "FDCAN: frame not supported",
            Error::NotClassic => "FDCAN: CAN FD frame received",
        })
    }
}

#[cfg(feature = "std")]
impl std::error::Error for Error {}

/// The error a last error code stands for (none for "no error" and "no change").
fn lec_error(lec: LastErrorCode) -> Option<Error> {
    match lec {
        LastErrorCode::NoError | LastErrorCode::NoChange => None,
        LastErrorCode::StuffError => Some(Error::Stuff),
        LastErrorCode::FormError => Some(Error::Form),
        LastErrorCode::AckError => Some(Error::Acknowledge),
        LastErrorCode::Bit1Error => Some(Error::Bit1),
        LastErrorCode::Bit0Error => Some(Error::Bit0),
        LastErrorCode::CRCError => Some(Error::Crc),
    }
}

/// The fdcan crate's form of `id`. Both crates' IDs are 11 or 29 bits, so `None` would take
/// an ID one of them cannot hold: its callers report it as [`Error::Unsupported`].
fn to_fdcan_id(id: Id) -> Option<fdcan::id::Id> {
    Some(match id {
        Id::Standard(id) => fdcan::id::StandardId::new(id.as_raw())?.into(),
        Id::Extended(id) => fdcan::id::ExtendedId::new(id.as_raw())?.into(),
    })
}

/// `embedded-can`'s form of the fdcan crate's `id` (`None` as for [`to_fdcan_id`]).
fn from_fdcan_id(id: fdcan::id::Id) -> Option<Id> {
    Some(match id {
        fdcan::id::Id::Standard(id) => Id::Standard(StandardId::new(id.as_raw())?),
        fdcan::id::Id::Extended(id) => Id::Extended(ExtendedId::new(id.as_raw())?),
    })
}

/// The transmit header for a frame: classic format, no bit-rate switching. The fdcan crate
/// sends a remote frame exactly when the length is 0.
fn tx_header(frame: &Frame) -> Result<TxFrameHeader, Error> {
    let len = if frame.remote { 0 } else { frame.dlc };
    if (frame.remote && frame.dlc != 0) || (!frame.remote && frame.dlc == 0) {
        return Err(Error::Unsupported);
    }
    Ok(TxFrameHeader {
        len,
        frame_format: FrameFormat::Standard,
        id: to_fdcan_id(frame.id).ok_or(Error::Unsupported)?,
        bit_rate_switching: false,
        marker: None,
    })
}

/// The frame a transmit buffer held, from its header and data words (as the fdcan crate
/// wrote them: the bytes in memory order).
fn displaced_frame(header: TxFrameHeader, words: &[u32]) -> Option<Frame> {
    let id = from_fdcan_id(header.id)?;
    if header.len == 0 {
        return <Frame as embedded_can::Frame>::new_remote(id, 0);
    }
    let mut bytes = [0u8; 8];
    for (chunk, word) in bytes.chunks_mut(4).zip(words) {
        chunk.copy_from_slice(&word.to_ne_bytes());
    }
    let data = bytes.get(..usize::from(header.len))?;
    <Frame as embedded_can::Frame>::new(id, data)
}

/// The frame received with `info` and the bytes the FIFO wrote to `data`.
fn rx_frame(info: &RxFrameInfo, data: &[u8]) -> Result<Frame, Error> {
    if info.frame_format != FrameFormat::Standard || info.len > 8 {
        return Err(Error::NotClassic);
    }
    let id = from_fdcan_id(info.id).ok_or(Error::Unsupported)?;
    let frame = if info.rtr {
        <Frame as embedded_can::Frame>::new_remote(id, usize::from(info.len))
    } else {
        data.get(..usize::from(info.len))
            .and_then(|d| <Frame as embedded_can::Frame>::new(id, d))
    };
    frame.ok_or(Error::NotClassic)
}

/// The displaced-frame callback of the fdcan crate's `transmit_preserve`.
type Keep<'a> = &'a mut dyn FnMut(Mailbox, TxFrameHeader, &[u32]) -> Option<Frame>;

/// What the adapter needs of the controller: the fdcan crate's calls, so that the adapter's
/// logic can be tested against a stand-in.
trait Controller {
    /// Whether a frame waits in a transmit buffer.
    fn tx_pending(&mut self) -> bool;
    /// Bus-off, and the last error code (reading it clears it).
    fn status(&mut self) -> (bool, LastErrorCode);
    /// `receive0`: a frame from receive FIFO 0, its bytes written to `data`.
    fn receive0(&mut self, data: &mut [u8]) -> nb::Result<ReceiveOverrun<RxFrameInfo>, Infallible>;
    /// Clears FIFO 0's message-lost interrupt flag (`IR.RF0L`), of which the overrun
    /// `receive0` reports (`RXF0S.RF0L`) is a copy: set until software clears it, so that
    /// uncleared it would report every later frame as an overrun.
    fn clear_overrun(&mut self);
    /// `transmit_preserve`: `keep` is called with a pending frame the new one displaced.
    fn transmit(
        &mut self,
        header: TxFrameHeader,
        data: &[u8],
        keep: Keep<'_>,
    ) -> nb::Result<Option<Option<Frame>>, Infallible>;
}

impl<I: fdcan::Instance> Controller for fdcan::FdCan<I, NormalOperationMode> {
    fn tx_pending(&mut self) -> bool {
        !self.is_transmitter_idle()
    }

    fn status(&mut self) -> (bool, LastErrorCode) {
        let s = self.get_protocol_status();
        (s.bus_off_status, s.last_error)
    }

    fn receive0(&mut self, data: &mut [u8]) -> nb::Result<ReceiveOverrun<RxFrameInfo>, Infallible> {
        fdcan::FdCan::receive0(self, data)
    }

    fn clear_overrun(&mut self) {
        self.clear_interrupt(fdcan::interrupt::Interrupt::RxFifo0MsgLost);
    }

    fn transmit(
        &mut self,
        header: TxFrameHeader,
        data: &[u8],
        mut keep: Keep<'_>,
    ) -> nb::Result<Option<Option<Frame>>, Infallible> {
        self.transmit_preserve(header, data, &mut keep)
    }
}

/// The adapter over any [`Controller`]: the fdcan crate's, or a test's stand-in.
struct Adapter<C> {
    can: C,
    /// What came with an overrun, delivered by the next `receive`: the frame, or why the
    /// adapter cannot carry it (never dropped unreported).
    held: Option<Result<Frame, Error>>,
    /// Whether the controller was bus-off at the last look.
    bus_off: bool,
}

impl<C> Adapter<C> {
    fn new(can: C) -> Self {
        Adapter {
            can,
            held: None,
            bus_off: false,
        }
    }
}

impl<C: Controller> embedded_can::nb::Can for Adapter<C> {
    type Frame = Frame;
    type Error = Error;

    fn transmit(&mut self, frame: &Frame) -> nb::Result<Option<Frame>, Error> {
        let header = tx_header(frame).map_err(nb::Error::Other)?;
        // One frame in flight (see the module documentation): the order is kept.
        if self.can.tx_pending() {
            return Err(nb::Error::WouldBlock);
        }
        let mut keep =
            |_: Mailbox, header: TxFrameHeader, words: &[u32]| displaced_frame(header, words);
        match self
            .can
            .transmit(header, embedded_can::Frame::data(frame), &mut keep)
        {
            // Not with one frame in flight; were a frame displaced, it is handed back for the
            // driver to queue again.
            Ok(displaced) => Ok(displaced.flatten()),
            Err(nb::Error::WouldBlock) => Err(nb::Error::WouldBlock),
            Err(nb::Error::Other(never)) => match never {},
        }
    }

    fn receive(&mut self) -> nb::Result<Frame, Error> {
        if let Some(held) = self.held.take() {
            return held.map_err(nb::Error::Other);
        }
        let (bus_off, lec) = self.can.status();
        let went_off = bus_off && !self.bus_off;
        self.bus_off = bus_off;
        if went_off {
            // The error code read with it (likely what took the controller off) comes next.
            self.held = lec_error(lec).map(Err);
            return Err(nb::Error::Other(Error::BusOff));
        }
        if let Some(e) = lec_error(lec) {
            return Err(nb::Error::Other(e));
        }
        let mut data = [0u8; RX_BUFFER];
        match self.can.receive0(&mut data) {
            Ok(ReceiveOverrun::NoOverrun(info)) => rx_frame(&info, &data).map_err(nb::Error::Other),
            Ok(ReceiveOverrun::Overrun(info)) => {
                // Frames before this one were lost: the loss is reported first, then this
                // frame (or why it cannot be one). The flag cleared, the next loss is the
                // next report.
                self.can.clear_overrun();
                self.held = Some(rx_frame(&info, &data));
                Err(nb::Error::Other(Error::Overrun))
            }
            Err(nb::Error::WouldBlock) => Err(nb::Error::WouldBlock),
            Err(nb::Error::Other(never)) => match never {},
        }
    }
}

/// An STM32 FDCAN in normal operation as an `embedded_can::nb::Can` controller for classic
/// CAN. See the [module documentation](self) and `boards/stm32h743_fdcan/` in the
/// repository for a whole program.
///
/// The controller comes from the HAL (stm32h7xx-hal's `FDCAN1.fdcan(tx, rx, rec)`, feature
/// `can`) in configuration mode; what the port needs of it is set there, then it is wrapped
/// in normal operation:
///
/// ```
/// use fdcan::config::{GlobalFilter, NominalBitTiming};
/// use fdcan::filter::{Action, ExtendedFilter, ExtendedFilterSlot, FilterType};
/// use fdcan::{ConfigMode, Instance};
/// use idu_gimbal::port::CanPort;
/// use idu_gimbal_fdcan::FdCan;
///
/// /// `can` as the HAL hands it out; `timing` for 1 Mbit/s at its kernel clock.
/// fn gimbal_port<I: Instance>(
///     mut can: fdcan::FdCan<I, ConfigMode>,
///     timing: NominalBitTiming,
/// ) -> Option<CanPort<FdCan<I>>> {
///     can.set_nominal_bit_timing(timing);
///     // The postback in receive FIFO 0, where the adapter reads; every other frame
///     // rejected in hardware.
///     let postback = fdcan::id::ExtendedId::new(idu_gimbal::wire::ids::POSTBACK)?;
///     can.set_extended_filter(
///         ExtendedFilterSlot::_0,
///         ExtendedFilter {
///             filter: FilterType::DedicatedSingle(postback),
///             action: Action::StoreInFifo0,
///         },
///     );
///     can.set_global_filter(GlobalFilter::reject_all());
///     Some(CanPort::new(FdCan::new(can.into_normal())))
/// }
/// ```
pub struct FdCan<I: fdcan::Instance>(Adapter<fdcan::FdCan<I, NormalOperationMode>>);

impl<I: fdcan::Instance> FdCan<I> {
    /// Wraps a configured controller.
    pub fn new(can: fdcan::FdCan<I, NormalOperationMode>) -> Self {
        FdCan(Adapter::new(can))
    }

    /// The controller, for what the adapter does not wrap (error counters, interrupts);
    /// inside idu-gimbal's `CanPort`, through `port.can_mut().inner()`.
    pub fn inner(&mut self) -> &mut fdcan::FdCan<I, NormalOperationMode> {
        &mut self.0.can
    }

    /// Gives back the controller (what an overrun held back and no `receive` took yet is
    /// dropped).
    pub fn release(self) -> fdcan::FdCan<I, NormalOperationMode> {
        self.0.can
    }
}

impl<I: fdcan::Instance> embedded_can::nb::Can for FdCan<I> {
    type Frame = Frame;
    type Error = Error;

    fn transmit(&mut self, frame: &Frame) -> nb::Result<Option<Frame>, Error> {
        embedded_can::nb::Can::transmit(&mut self.0, frame)
    }

    fn receive(&mut self) -> nb::Result<Frame, Error> {
        embedded_can::nb::Can::receive(&mut self.0)
    }
}

#[cfg(test)]
mod tests;
