//! The drivers: one [`Link`](crate::link::Link) over either of the gimbal's two control
//! paths.
//!
//! | transport | driver | sans-IO core | what it carries |
//! |---|---|---|---|
//! | CAN, 1 Mbit/s, extended IDs | [`Gimbal`] over any `embedded_can::nb::Can` ([`Blocking`] for `embedded_can::blocking::Can`) | [`Link`](crate::link::Link): frames in, frames out | control commands, postbacks, vehicle attitude, GPS and altitude, text |
//! | UART, 115200 8N1 | [`SerialGimbal`] over a [`SerialPort`] ([`Io`] for `embedded-io` 0.7, [`Nb`] for `embedded-hal-nb`) | [`SerialLink`](crate::link::serial::SerialLink): bytes in, bytes out | control commands and postbacks only |
//!
//! Both share the link: the transmit queue and its priorities, the rate hold and its
//! dead-man, point-at, link health, events and counters. The transport is the only
//! difference. The serial link carries no vehicle or text frames (the protocol document
//! defines none on it), so [`SerialGimbal`] offers no way to push them, and the gimbal's
//! heading reference over serial is the nose (see [`serial`]).
//!
//! CAN controllers whose HAL implements no `embedded-can` trait get an adapter here: the
//! `fdcan` module (feature `fdcan`) for the STM32H7's FDCAN through the `fdcan` crate.

pub mod can;
#[cfg(feature = "fdcan")]
pub mod fdcan;
pub mod serial;

#[cfg(all(test, feature = "mock"))]
mod idle_tests;

pub use can::{AllFaults, Blocking, Classify, DriverError, DriverErrors, Gimbal, GimbalStats};
pub use serial::{Io, Nb, PortError, PortErrors, SerialGimbal, SerialGimbalStats, SerialPort};
