//! The ports: what moves a [`Link`]'s frames over one of the gimbal's two control paths.
//!
//! The application owns the [`Link`], the one command surface, and hands it to its port's
//! [`Port::poll`], as smoltcp's sockets are handed to `Interface::poll` with a device. The
//! port keeps only what is its transport's: the CAN controller or the UART, the bytes of a
//! serial frame part-written, and the transport's own counters.
//!
//! | transport | port | link | what it carries |
//! |---|---|---|---|
//! | CAN, 1 Mbit/s, extended IDs | [`CanPort`] over any `embedded_can::nb::Can` ([`Blocking`] for `embedded_can::blocking::Can`) | [`Link`] (medium [`Can`](crate::link::Can)) | control commands, postbacks, vehicle attitude, GPS and altitude, text |
//! | UART, 115200 8N1 | [`SerialPort`] over a [`Uart`] ([`Io`] for `embedded-io` 0.7, [`Nb`] for `embedded-hal-nb`) | [`SerialLink`](crate::link::SerialLink) (medium [`Serial`](crate::link::Serial)) | control commands and postbacks only |
//!
//! What a transport can carry is in the link's type (see [`link::medium`]): a port takes
//! only the link of its medium, and a serial link has no text and no frame-level I/O.
//! Without a port, a CAN link's frames are moved by hand ([`Link::next_transmit`],
//! [`Link::receive`]) and a serial link's bytes through [`SerialStream`], the serial port's
//! sans-IO core.
//!
//! CAN controllers whose HAL implements no `embedded-can` trait get an adapter of their
//! own: the `idu-gimbal-fdcan` crate, for the STM32H7's FDCAN.
//!
//! ```
//! # #[cfg(feature = "mock")] {
//! use idu_gimbal::mock::Bus;
//! use idu_gimbal::port::{CanPort, Port};
//! use idu_gimbal::wire::control::{GimbalCommand, Pitch};
//! use idu_gimbal::{Config, Instant, Link};
//!
//! /// One turn of a main loop, the same for either port.
//! fn turn<P: Port>(link: &mut idu_gimbal::Link<8, 0, P::Medium>, port: &mut P, now: Instant)
//! where
//!     P::Error: core::fmt::Debug,
//! {
//!     port.poll(link, now).unwrap();
//!     while let Some(_event) = link.next_event() {}
//! }
//!
//! let bus: Bus<2, 16> = Bus::new(1);
//! let mut link: Link<8, 0> = Link::new(Config::default());
//! let mut port = CanPort::new(bus.endpoint(0).unwrap());
//! link.send(GimbalCommand::Pitch(Pitch::new(-45.0).unwrap())).unwrap();
//! turn(&mut link, &mut port, Instant::from_millis(0));
//! assert_eq!(link.stats().frames_sent, 1);
//! # }
//! ```
//!
//! [`link::medium`]: crate::link::medium

mod blocking;
pub mod can;
pub mod serial;

#[cfg(all(test, feature = "mock"))]
mod idle_tests;

use crate::link::{Link, Medium};
use crate::time::Instant;

pub use blocking::{AllFaults, Blocking, Classify};
pub use can::{CanPort, CanPortStats, DriverError, DriverErrors};
pub use serial::{
    Io, Nb, PortError, PortErrors, SerialPort, SerialPortStats, SerialStream, SerialStreamStats,
    Uart,
};

/// A transport's port: it moves the frames of a link of its [`Medium`] between the link
/// and the hardware. See the [module docs](self).
pub trait Port {
    /// The medium whose links this port carries.
    type Medium: Medium;
    /// What a poll reports of the hardware (the poll still does all its work).
    type Error;

    /// Receives what is waiting (bounded by [`Config::max_rx_per_poll`](crate::Config)),
    /// runs the link's schedules, and transmits what the link queued until the hardware
    /// takes no more. An error is counted in the port's stats and the poll goes on, but a
    /// transmit error ends this poll's transmitting (what waits goes at the next poll); the
    /// first error seen is returned at the end.
    fn poll<const Q: usize, const T: usize>(
        &mut self,
        link: &mut Link<Q, T, Self::Medium>,
        now: Instant,
    ) -> Result<(), Self::Error>;

    /// The instant by which [`Port::poll`] must next be called if nothing is received
    /// before then, as seen from `now`: the link's
    /// [`next_deadline`](Link::next_deadline), or `now` while something waits to be sent
    /// (the hardware took no more at the last poll; poll again when it has room).
    ///
    /// A firmware that sleeps between polls sleeps until this instant or until a receive
    /// (or transmit-ready) interrupt, whichever comes first. Every command or vehicle value
    /// given to the link can move the deadline earlier: ask again after one. The result is
    /// at or after `now` and less than 2^31 ms ahead of it.
    fn next_deadline<const Q: usize, const T: usize>(
        &self,
        link: &Link<Q, T, Self::Medium>,
        now: Instant,
    ) -> Instant;
}
