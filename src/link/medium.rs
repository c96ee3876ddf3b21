//! What a link's transport can carry, in its type.
//!
//! The gimbal has two control paths, and they do not carry the same frames: CAN carries
//! control commands, postbacks, the vehicle's attitude, GPS and altitude, and text; the
//! UART carries control commands and postbacks only (the protocol document defines no
//! vehicle or text frames on it). A [`Link`](super::Link) is built for one of them, so
//! what the transport cannot carry cannot be asked:
//!
//! - [`Link::send_text`](super::Link::send_text) and the frame-level I/O
//!   ([`Link::receive`](super::Link::receive), [`Link::next_transmit`](super::Link::next_transmit))
//!   exist on a [`Can`] link only;
//! - on a [`Serial`] link the vehicle's data is kept for point-at and aims and never
//!   scheduled for sending, and [`Link::north_referenced`](super::Link::north_referenced)
//!   is always false: the gimbal never gets the vehicle's heading, so it references
//!   headings to the nose.
//!
//! A serial link's frames leave only through its port, which frames them as bytes and
//! finishes what it starts; nothing can take one behind its back:
//!
//! ```compile_fail
//! use idu_gimbal::link::{Config, SerialLink};
//! let mut serial: SerialLink = SerialLink::new(Config::default());
//! let _ = serial.next_transmit();
//! ```
//!
//! ```
//! use idu_gimbal::link::{Config, SerialLink};
//! use idu_gimbal::wire::vehicle::Gps;
//! use idu_gimbal::Instant;
//!
//! let mut serial: SerialLink = SerialLink::new(Config::default());
//! let now = Instant::from_millis(0);
//! serial.poll(now);
//! // Kept for point-at, never queued: nothing for a poll to do.
//! serial.set_gps(Gps::new(47.0, 8.0).unwrap(), now);
//! assert!(serial.is_quiet(now) && !serial.has_transmit());
//! ```

/// A transport's capabilities; implemented by [`Can`] and [`Serial`] only.
pub trait Medium: sealed::Sealed + Copy + core::fmt::Debug + 'static {
    /// Whether the transport carries the vehicle's attitude, GPS and altitude frames.
    const VEHICLE_FRAMES: bool;
}

/// The CAN bus (1 Mbit/s, extended IDs): control commands, postbacks, vehicle frames and
/// text.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Can {}

/// The UART (115200 8N1): control commands and postbacks only.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Serial {}

impl Medium for Can {
    const VEHICLE_FRAMES: bool = true;
}

impl Medium for Serial {
    const VEHICLE_FRAMES: bool = false;
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for super::Can {}
    impl Sealed for super::Serial {}
}
