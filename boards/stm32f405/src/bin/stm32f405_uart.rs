//! Flight-controller firmware for an STM32F405RG driving an IDU gimbal over its UART.
//!
//! * USART2 at **115200 8N1**: **PA2 (TX)** to the gimbal's connector pin 5 (USART RX),
//!   **PA3 (RX)** from pin 6 (USART TX), ground to pin 7. The document gives no logic level:
//!   check it is 3.3 V before wiring (use a level shifter otherwise).
//! * Receive is interrupt-driven (`src/usart2_ring.rs`): the USART2 interrupt
//!   (RXNE) moves every byte into a 1024-byte ring the main loop drains, so no byte is lost
//!   while the main loop is busy. A full ring or a line error (overrun, framing, parity,
//!   noise) is reported to the driver as a read error, which counts it; the stream parser
//!   resynchronises on the next header.
//! * Transmit is polled without blocking: the driver writes while the data register is
//!   empty and finishes a partly written frame at the next poll (a 24-byte frame takes
//!   about 2.1 ms at 115200 baud).
//! * Clocks and the 1 kHz SysTick tick: `src/board.rs`. Logging through
//!   defmt-rtt.
//!
//! The serial link carries control commands and postbacks only: no vehicle frames, so the
//! gimbal references headings to the nose; the vehicle state below is observed for
//! `point_at` only (see `idu_gimbal::port::serial`). `point_at` links the WGS84 solver
//! (f64, soft-float on the M4F): about 19 KB of the image; without it the image is 11.8 KB.
//!
//! Build: `cargo build --release --bin stm32f405_uart` in `boards/stm32f405`. Flash and
//! watch the logs with a debug probe: `cargo run --release --bin stm32f405_uart` (the runner
//! calls `probe-rs run`).
#![no_std]
#![no_main]

mod fw {
    use cortex_m_rt::entry;
    use defmt_rtt as _;
    use panic_probe as _;
    use stm32f4xx_hal::{interrupt, pac};

    use board_stm32f405::board::{self, now};
    use board_stm32f405::usart2_ring::{self, RingRx};
    use idu_firmware_support::vehicle::Vehicle;
    use idu_gimbal::geo::Position;
    use idu_gimbal::interface::UART_BAUD;
    use idu_gimbal::port::{Nb, Port, PortError};
    use idu_gimbal::wire::vehicle::{Altitude, Attitude, Gps};
    use idu_gimbal::{Config, Instant, SerialLink, SerialPort};

    /// USART2 receive into the ring.
    #[interrupt]
    fn USART2() {
        usart2_ring::on_interrupt();
    }

    /// STAND-IN VEHICLE DATA. Replace with the autopilot's estimates, each with the time it
    /// was measured. Used for point-at only: the serial link carries no vehicle frames.
    fn vehicle_stand_in(now: Instant) -> Option<Vehicle> {
        Some(Vehicle {
            gps: Gps::new(47.397_742, 8.545_594).ok()?,
            altitude: Altitude::new(488.0).ok()?,
            attitude: Attitude::new(0.0, 0.0, 30.0).ok()?,
            stamp: now,
        })
    }

    #[entry]
    fn main() -> ! {
        let (Some(dp), Some(cp)) = (pac::Peripherals::take(), cortex_m::Peripherals::take()) else {
            panic!("peripherals taken twice");
        };

        let mut rcc = board::clocks(dp.RCC);
        board::start_tick(cp.SYST, &rcc);

        // USART2 on PA2 (TX) / PA3 (RX), 115200 8N1 (the HAL's default framing).
        let tx = usart2_ring::open(dp.USART2, dp.GPIOA, UART_BAUD, &mut rcc);
        defmt::info!("USART2 up: {=u32} baud 8N1, PA2 TX, PA3 RX", UART_BAUD);

        let mut link: SerialLink = SerialLink::new(Config::default());
        let mut port = SerialPort::new(Nb::new(RingRx, tx));
        // An example target: look at a point on the ground 200 m north of the stand-in
        // position (nose-referenced over serial, from the observed vehicle heading). The
        // point-at aims pitch and heading both; a pointing command sent after it would end
        // it.
        if let Ok(target) = Position::new(47.399_541, 8.545_594, 440.0) {
            link.point_at(target);
        }
        let mut next_vehicle = now();
        let mut next_stats = now().add_millis(10_000);

        loop {
            let now = now();
            if now.is_at_or_after(next_vehicle) {
                next_vehicle = now.add_millis(100);
                if let Some(v) = vehicle_stand_in(now) {
                    v.push(&mut link);
                }
            }

            match port.poll(&mut link, now) {
                Ok(()) => {}
                Err(PortError::Read(e)) => {
                    defmt::warn!("UART receive: {}", defmt::Debug2Format(&e))
                }
                Err(PortError::Write(e)) => {
                    defmt::warn!("UART transmit: {}", defmt::Debug2Format(&e))
                }
            }

            while let Some(event) = link.next_event() {
                board::log_event(event, link.latest_postback(now).map(|(p, _)| p));
            }

            if now.is_at_or_after(next_stats) {
                next_stats = now.add_millis(10_000);
                defmt::info!(
                    "stats: {} {} {}",
                    link.stats(),
                    port.stats(),
                    usart2_ring::counts()
                );
            }
        }
    }
}
