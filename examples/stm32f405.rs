//! Flight-controller firmware for an STM32F405RG driving an IDU gimbal over CAN.
//!
//! * CAN1 on **PB8 (RX) / PB9 (TX)** at 1 Mbit/s with a filter passing only the postback,
//!   the clocks and the 1 kHz SysTick tick: see `examples/common/board.rs`.
//! * Logging through defmt-rtt, panics through panic-probe (over the debug probe).
//!
//! The main loop (`examples/common/app.rs`, shared with the board crates under `boards/`)
//! polls the driver, pushes vehicle data from a **stand-in source** (replace
//! `vehicle_stand_in` in `examples/common/vehicle.rs` with your autopilot's estimates) and logs postbacks, link events
//! and, every 10 s, the counters.
//!
//! Build: `cargo build --release --target thumbv7em-none-eabihf --example stm32f405`
//! (alias `cargo fw`). Flash and watch the logs with a debug probe:
//! `cargo run --release --target thumbv7em-none-eabihf --example stm32f405` (alias
//! `cargo flash`; the runner calls `probe-rs run --chip STM32F405RGTx`).
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
#[path = "common/board.rs"]
mod board;

#[cfg(target_os = "none")]
#[path = "common/app.rs"]
mod app;

#[cfg(target_os = "none")]
#[path = "common/vehicle.rs"]
mod vehicle;

#[cfg(target_os = "none")]
mod fw {
    use cortex_m_rt::entry;
    use defmt_rtt as _;
    use panic_probe as _;
    use stm32f4xx_hal::pac;

    use crate::app::{App, Report};
    use crate::board::{self, now};
    use crate::vehicle::vehicle_stand_in;
    use idu_gimbal::{Config, Gimbal};

    #[entry]
    fn main() -> ! {
        let (Some(dp), Some(cp)) = (pac::Peripherals::take(), cortex_m::Peripherals::take()) else {
            panic!("peripherals taken twice");
        };

        let mut rcc = board::clocks(dp.RCC);
        board::start_tick(cp.SYST, &rcc);
        let can = board::can1(dp.CAN1, dp.GPIOB, &mut rcc);

        let mut gimbal: Gimbal<_> = Gimbal::new(can, Config::default());
        let mut app = App::new(now());
        // Busy polling: bxcan's receive FIFO holds 3 frames and a postback comes as 4
        // back-to-back frames (~0.5 ms at 1 Mbit/s), so do not sleep a whole tick here.
        loop {
            app.step(
                &mut gimbal,
                now(),
                vehicle_stand_in,
                |report| match report {
                    Report::Driver(e) => defmt::warn!("{}", e),
                    Report::Event(event, latest) => board::log_event(event, latest),
                    Report::Stats(stats) => defmt::info!("stats: {}", stats),
                },
            );
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
