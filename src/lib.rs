//! Drive an IDU camera gimbal over CAN or its UART from a flight controller.
//!
//! `no_std`, allocation-free and panic-free, over any [`embedded_can`] 0.4 driver, or any
//! UART through `embedded-io` 0.7 or `embedded-hal-nb`.
//!
//! # Layers
//!
//! - [`wire`]: pure codecs, bytes to typed values and back: [`wire::control`] (every
//!   command of both peripherals), [`wire::vehicle`], [`wire::postback`], [`wire::text`],
//!   [`wire::serial`] (the 24-byte serial/TCP frame and a stream parser), [`wire::crc`],
//!   [`wire::ids`].
//! - [`link`]: the sans-IO state machine and the one command surface: transmit queue,
//!   vehicle push, rate hold with dead-man, aims and point-at, postback and text
//!   reassembly, link health, counters. What its transport can carry is in its type
//!   ([`link::medium`]): a [`Link`] on CAN, a [`SerialLink`] on the UART. Frames in, frames
//!   out, time passed in: usable from async or non-`embedded-can` stacks.
//! - [`port`]: one module per transport, each moving a link's frames and counting its own
//!   faults. [`CanPort`] over an `embedded_can::nb::Can` driver ([`port::Blocking`] adapts
//!   `embedded_can::blocking::Can` drivers); [`SerialPort`] over a UART ([`port::Io`] for
//!   `embedded-io` 0.7, [`port::Nb`] for `embedded-hal-nb`), around the sans-IO
//!   [`port::SerialStream`]. The application owns the link and hands it to its port's
//!   [`Port::poll`].
//! - Beside them, the test doubles (feature `mock`): `sim` (a simulated gimbal, on CAN or
//!   serial) and `mock` (an in-memory CAN bus and serial pipe with fault injection); [`geo`]
//!   (WGS84 look-at and where a line of sight meets the ground), [`math`] (`f32` sine and
//!   cosine), [`video`] (RTSP addresses) and [`interface`] (network, UART and CAN defaults,
//!   filter helpers).
//!
//! # Time
//!
//! The crate never reads a clock. Every call that needs the time takes an [`Instant`], a
//! wrapping `u32` millisecond tick from the caller; schedules are kept by deadline and are
//! correct across the wrap.
//!
//! # A firmware main loop
//!
//! ```
//! # #[cfg(feature = "mock")] {
//! use idu_gimbal::mock::Bus;
//! use idu_gimbal::wire::control::{GimbalCommand, Heading};
//! use idu_gimbal::wire::vehicle::Gps;
//! use idu_gimbal::{CanPort, Config, Event, Instant, Link, Port};
//!
//! // On a real board `can` is the HAL's CAN peripheral (e.g. bxcan on an STM32F4).
//! let bus: Bus<2, 32> = Bus::new(7);
//! let mut port = CanPort::new(bus.endpoint(0).unwrap());
//! let mut link: Link = Link::new(Config::default());
//!
//! link.send(GimbalCommand::Heading(Heading::new(90.0).unwrap())).unwrap();
//! for ms in 0..300u32 {
//!     let now = Instant::from_millis(ms);
//!     link.set_gps(Gps::new(47.397_742, 8.545_594).unwrap(), now);
//!     port.poll(&mut link, now).unwrap();
//!     while let Some(event) = link.next_event() {
//!         if event == Event::Postback {
//!             let (status, _age_ms) = link.latest_postback(now).unwrap();
//!             let _ = status.heading_deg();
//!         }
//!     }
//! }
//! // The heading command, then GPS at 0, 200 ms.
//! assert_eq!(link.stats().frames_sent, 3);
//! # }
//! ```
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

/// `$n` as the `core::num` non-zero type `$ty`, checked at compile time: a 0 does not build.
/// Defined before the modules, so that all of them can use it.
macro_rules! non_zero {
    ($ty:ty, $n:literal) => {
        const {
            match <$ty>::new($n) {
                Some(n) => n,
                None => panic!("a non-zero constant is zero"),
            }
        }
    };
}

pub mod geo;
pub mod interface;
pub mod link;
pub mod math;
#[cfg(feature = "mock")]
pub mod mock;
pub mod port;
#[cfg(feature = "mock")]
pub mod sim;
pub mod time;
pub mod video;
pub mod wire;

// The README's and the integration guide's examples are compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
#[cfg(doctest)]
#[doc = include_str!("../docs/integration.md")]
pub struct IntegrationDoctests;
pub use link::{Config, Event, Link, SerialLink};
pub use port::{CanPort, Port, SerialPort};
pub use time::Instant;
