//! An IDU gimbal as a standard MAVLink **Gimbal Device** (gimbal protocol v2) and **Camera**
//! (camera protocol v2), so that PX4 (`MNT_MODE_OUT` = MAVLink gimbal v2) and ArduPilot
//! (`MNTx_TYPE` = MAVLink) drive it and a ground station sees its camera, with no autopilot
//! code changed.
//!
//! `no_std`, allocation-free, `forbid(unsafe_code)`, and sans-IO like the core: MAVLink 2
//! bytes in ([`Bridge::receive`]), MAVLink 2 bytes out ([`Bridge::transmit_bytes`]), time
//! passed in ([`Bridge::poll`]); it drives the gimbal through the application's
//! [`Link`](idu_gimbal::Link), handed to each of those calls, on either transport (CAN or
//! UART), and never reads a clock. Where the transport carries no vehicle frames (a
//! [`SerialLink`](idu_gimbal::SerialLink)), the vehicle's data is kept for point-at and
//! headings stay nose-referenced, which the status and the setpoint conversion read from
//! [`Link::north_referenced`](idu_gimbal::Link::north_referenced).
//!
//! # What it does
//!
//! - HEARTBEAT at 1 Hz as `MAV_TYPE_GIMBAL`, `MAV_AUTOPILOT_INVALID`, component 154
//!   (configurable); system id configured, or the first autopilot's from its HEARTBEAT,
//!   kept while it is heard (see [`BridgeConfig::system_id`]).
//! - `MAV_CMD_REQUEST_MESSAGE` → `GIMBAL_DEVICE_INFORMATION` (model from the postback's
//!   gimbal type; pitch and yaw axes, no roll; limits in radians) or an attitude status;
//!   `MAV_CMD_SET_MESSAGE_INTERVAL` for the attitude status. Every `COMMAND_LONG` and
//!   `COMMAND_INT` addressed to one of its components gets one `COMMAND_ACK`
//!   (`UNSUPPORTED` for what it does not do); a broadcast command another component owns
//!   is left to it (see [`command`]).
//! - `GIMBAL_DEVICE_SET_ATTITUDE`: angles, rates, neutral and retract in the yaw frame the
//!   flags name (see [Setpoints](crate#setpoints) below).
//! - `AUTOPILOT_STATE_FOR_GIMBAL_DEVICE` → the core's attitude push and the vehicle's
//!   heading; `GLOBAL_POSITION_INT` → GPS and altitude. Both are asked of the autopilot with
//!   `MAV_CMD_SET_MESSAGE_INTERVAL` until they come (PX4 streams neither to a port in mode
//!   Normal), and the setpoints at 20 Hz once (not of ArduPilot, which sends them unasked).
//! - `GIMBAL_DEVICE_ATTITUDE_STATUS` at 10 Hz from the latest postback, in the vehicle
//!   frame with `delta_yaw` the vehicle's heading (see [`status`] for why), with
//!   `COMMS_ERROR` while the gimbal link is down.
//! - With the `roi` feature, `MAV_CMD_DO_SET_ROI_LOCATION` / `DO_SET_ROI_NONE` addressed to
//!   the gimbal component drive the core's point-at.
//! - The camera (component 100, when configured): capture (see [`capture`]), zoom and focus,
//!   click-to-track with `CAMERA_TRACKING_IMAGE_STATUS`, every video stream of the family
//!   (the infrared one thermal), and a camera definition file served by a read-only MAVLink
//!   FTP server (see [`ftp`]) whose settings (focus, the thermal palette and zoom) are set
//!   with the extended parameter protocol: see [`camera`].
//! - `MAV_CMD_PREFLIGHT_CALIBRATION` (gyroscope) addressed to the gimbal device: the
//!   gimbal's fast calibration.
//! - On UDP, [`Bridge::receive_datagram`] reads each datagram on its own.
//!
//! # Setpoints
//!
//! A quaternion becomes heading and pitch commands (re-sent only past a dead-band),
//! converted from the setpoint's yaw frame to the gimbal's reference (north while vehicle
//! attitude is pushed, nose otherwise); angular velocities beside it are not followed. A NaN
//! quaternion with angular velocities becomes the core's rate hold, whose dead-man stops the
//! gimbal when the stream stops; an earth-frame yaw rate is taken less the vehicle's yaw
//! rate. NEUTRAL holds forward and level in the vehicle frame, RETRACT looks down (the
//! gimbal has no retracted pose).
//!
//! Quaternions are built and read from the gimbal's axis rotations (see [`attitude`]), so
//! the whole pitch range, past −90° down to −100°, is exact.
//!
//! # Choice of MAVLink crate
//!
//! The message types, ids and `CRC_EXTRA`s are `mavio`'s (0.5, `dlct-common`), and so is
//! the (de)serialization of every message but the few on the hot paths, which have codecs
//! of their own held to `mavio`'s by proptests (see [`codec`]); only the messages handled
//! are decoded, each through its own type. Received frames are found and checksummed by
//! [`framing::FrameReader`] in one pass over their bytes, and frames sent are written in
//! place by [`framing::Outbox`], for speed (see [`framing`] and [`codec`] for the
//! measurements, beside the C MAVLink library's, and the tests that hold them to `mavio`).
//! The `mavlink` crate (0.21) was
//! the first choice, but with `default-features = false` and the features `embedded`,
//! `dialect-common` and `mav2-message-extensions` it does not build for a no_std target:
//! that last feature is written `mavlink-bindgen/mav2-message-extensions`, which turns the
//! optional code generator `mavlink-bindgen` (regex, quick-xml, memchr with `std`) into a
//! normal dependency. Without the feature, GIMBAL_DEVICE_ATTITUDE_STATUS lacks `delta_yaw`
//! and `gimbal_device_id`. `mavio` builds for `thumbv7em-none-eabihf` with every extension
//! field.
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

pub mod attitude;
pub mod bridge;
pub mod camera;
pub mod capture;
pub mod codec;
pub mod command;
pub mod framing;
pub mod ftp;
mod setpoint;
#[cfg(feature = "signing")]
pub mod signing;
pub mod status;
mod tx;

pub use bridge::{
    Bridge, BridgeConfig, BridgeConfigError, BridgeStats, CheckedConfig, Period, PeriodOutOfRange,
    SerialInput, ANSWER_ROOM, ATTITUDE_STATUS, AUTOPILOT_SILENCE_MS, HEARTBEAT,
};
pub use mavio;
