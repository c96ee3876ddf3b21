//! Flight-controller firmware for an STM32F405RG driving an IDU gimbal over CAN.
//!
//! * CAN1 on **PB8 (RX) / PB9 (TX)** at 1 Mbit/s with a filter passing only the postback,
//!   the clocks and the 1 kHz SysTick tick: see `examples/common/board.rs`.
//! * Logging through defmt-rtt, panics through panic-probe (over the debug probe).
//!
//! The main loop polls the driver, pushes vehicle data from a **stand-in source** (replace
//! [`vehicle_stand_in`] with your autopilot's estimates) and logs postbacks, link events and,
//! every 10 s, the counters.
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
mod fw {
    use cortex_m_rt::entry;
    use defmt_rtt as _;
    use panic_probe as _;
    use stm32f4xx_hal::pac;

    use crate::board::{self, now};
    use idu_gimbal::wire::vehicle::{Altitude, Attitude, Gps};
    use idu_gimbal::{Config, Gimbal, Instant};

    /// STAND-IN VEHICLE DATA. Replace with the autopilot's estimates (for example MAVLink
    /// `GLOBAL_POSITION_INT` and `ATTITUDE`, or your EKF outputs), each with the time it was
    /// measured. Here: a vehicle hovering over a fixed point while it slowly yaws.
    fn vehicle_stand_in(now: Instant) -> Option<(Gps, Altitude, Attitude)> {
        let t = now.as_millis();
        // One degree of yaw every 100 ms, in [-180, 180).
        let heading = ((t / 100) % 360) as f32 - 180.0;
        let gps = Gps::new(47.397_742, 8.545_594).ok()?;
        let altitude = Altitude::new(488.0).ok()?;
        let attitude = Attitude::new(1.5, -0.4, heading).ok()?;
        Some((gps, altitude, attitude))
    }

    #[entry]
    fn main() -> ! {
        let (Some(dp), Some(cp)) = (pac::Peripherals::take(), cortex_m::Peripherals::take()) else {
            panic!("peripherals taken twice");
        };

        let mut rcc = board::clocks(dp.RCC);
        board::start_tick(cp.SYST, &rcc);
        let can = board::can1(dp.CAN1, dp.GPIOB, &mut rcc);

        let mut gimbal: Gimbal<_> = Gimbal::new(can, Config::default());
        let mut next_vehicle = now();
        let mut next_stats = now().add_millis(10_000);

        loop {
            let now = now();

            // Vehicle data at 10 Hz; the driver pushes each at its own rate while fresh.
            if now.is_at_or_after(next_vehicle) {
                next_vehicle = now.add_millis(100);
                if let Some((gps, altitude, attitude)) = vehicle_stand_in(now) {
                    gimbal.set_gps(gps, now);
                    gimbal.set_altitude(altitude, now);
                    gimbal.set_attitude(attitude, now);
                }
            }

            // Busy polling: bxcan's receive FIFO holds 3 frames and a postback comes as 4
            // back-to-back frames (~0.5 ms at 1 Mbit/s), so do not sleep a whole tick here.
            if let Err(e) = gimbal.poll(now) {
                defmt::warn!("{}", e);
            }

            while let Some(event) = gimbal.next_event() {
                board::log_event(event, gimbal.latest_postback(now).map(|(p, _)| p));
            }

            if now.is_at_or_after(next_stats) {
                next_stats = now.add_millis(10_000);
                defmt::info!("stats: {}", gimbal.stats());
            }
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
