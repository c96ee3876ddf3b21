//! Flight-controller firmware for an STM32F405RG driving an IDU gimbal over CAN.
//!
//! * CAN1 on **PB8 (RX) / PB9 (TX)** at 1 Mbit/s with a filter passing only the postback,
//!   the clocks and the 1 kHz SysTick tick: see `src/board.rs`.
//! * Logging through defmt-rtt, panics through panic-probe (over the debug probe).
//!
//! The main loop (`idu_firmware_support::app`, shared with the other board crates under
//! `boards/`) polls the driver, pushes vehicle data from a **stand-in source** (replace
//! `vehicle_stand_in`, `idu_firmware_support::vehicle`, with your autopilot's estimates) and
//! logs postbacks, link events and, every 10 s, the counters.
//!
//! Build: `cargo build --release --bin stm32f405` in `boards/stm32f405` (from the repository
//! root: `cargo fw`). Flash and watch the logs with a debug probe: `cargo run --release --bin
//! stm32f405` (from the root: `cargo flash`; the runner calls `probe-rs run --chip
//! STM32F405RGTx`).
#![no_std]
#![no_main]

mod fw {
    use cortex_m_rt::entry;
    use defmt_rtt as _;
    use panic_probe as _;
    use stm32f4xx_hal::pac;

    use board_stm32f405::board::{self, now};
    use idu_firmware_support::app::{App, Report};
    use idu_firmware_support::vehicle::vehicle_stand_in;
    use idu_gimbal::{CanPort, Config, Link};

    #[entry]
    fn main() -> ! {
        let (Some(dp), Some(cp)) = (pac::Peripherals::take(), cortex_m::Peripherals::take()) else {
            panic!("peripherals taken twice");
        };

        let mut rcc = board::clocks(dp.RCC);
        board::start_tick(cp.SYST, &rcc);
        let can = board::can1(dp.CAN1, dp.GPIOB, &mut rcc);

        let mut link: Link = Link::new(Config::default());
        let mut port = CanPort::new(can);
        let mut app = App::new(now());
        // Busy polling: bxcan's receive FIFO holds 3 frames and a postback comes as 4
        // back-to-back frames (~0.5 ms at 1 Mbit/s), so do not sleep a whole tick here.
        loop {
            app.step(
                &mut link,
                &mut port,
                now(),
                vehicle_stand_in,
                |report| match report {
                    Report::Driver(e) => defmt::warn!("{}", e),
                    Report::Event(event, latest) => board::log_event(event, latest),
                    Report::Stats(link, port) => defmt::info!("stats: {} {}", link, port),
                },
            );
        }
    }
}
