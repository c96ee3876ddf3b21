//! What the repository's firmware programs share, so that each board crate (`boards/*`),
//! the MCU benchmarks (`benches/mcu`) and the host's `host_sim` use one copy.
//!
//! Portable (any target, no HAL, no runtime): the CAN firmware's main loop ([`app`]) and
//! its stand-in vehicle data ([`vehicle`]); these are what the RP2040 (thumbv6m) and
//! ESP32-C3 (RISC-V) boards use. Behind features:
//!
//! * `session`: the scripted session of the link and its port against the simulated gimbal, played by
//!   the QEMU demo and `host_sim`;
//! * `qemu`: semihosting output and exit, and the panic and HardFault handlers of the QEMU
//!   firmware (Cortex-M, cortex-m-rt);
//! * `bench`: the SysTick instruction meter and the result table of the QEMU benchmarks;
//! * `embassy`: the conversion between embassy-time and the core's millisecond tick.
#![no_std]

pub mod app;
pub mod vehicle;

#[cfg(feature = "session")]
pub mod session;

// Bare-metal ARM only (QEMU's netduinoplus2 is a Cortex-M4): the root workspace builds this
// crate for the host with every feature. `#[macro_use]`: the meter and the report table
// print too.
#[cfg(all(feature = "qemu", target_arch = "arm", target_os = "none"))]
#[macro_use]
pub mod qemu;

#[cfg(all(feature = "bench", target_arch = "arm", target_os = "none"))]
pub mod meter;
#[cfg(all(feature = "bench", target_arch = "arm", target_os = "none"))]
pub mod report;

#[cfg(feature = "embassy")]
pub mod embassy;
