//! `idu-gimbal`: drive an IDU camera gimbal over CAN from a flight controller.
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    deny(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing
    )
)]

#[cfg(feature = "std")]
extern crate std;

pub mod geo;
pub mod interface;
pub mod link;
#[cfg(feature = "mock")]
pub mod mock;
pub mod sim;
pub mod time;
pub mod video;
pub mod wire;

pub use time::Instant;
