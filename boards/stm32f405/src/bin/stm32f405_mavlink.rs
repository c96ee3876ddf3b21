//! Co-processor firmware for an STM32F405RG: the IDU gimbal (on CAN) as a MAVLink gimbal
//! device and camera for the autopilot (on a UART).
//!
//! * To the autopilot: USART2, **PA2 (TX) / PA3 (RX)**, MAVLink 2 at **921600 baud** 8N1
//!   (set the autopilot's serial port to MAVLink 2 at the same rate). Receive is
//!   interrupt-driven into a 1024-byte ring (`src/usart2_ring.rs`): at 921600
//!   baud 92 bytes arrive a millisecond, and the ring holds 11 ms of them while the main
//!   loop is busy. A full ring's dropped bytes and the line errors are counted by the ring
//!   and logged as they grow (the frame they broke fails its CRC and is skipped, counted by
//!   the bridge's reader); transmit is polled without blocking.
//! * To the gimbal: CAN1 on **PB8 (RX) / PB9 (TX)** at 1 Mbit/s with a filter passing only
//!   the postback, clocks and the 1 kHz tick (`src/board.rs`).
//! * The bridge (`idu_gimbal_mavlink::Bridge`) owns the CAN driver; the main loop polls the
//!   driver, feeds the bridge what the UART received, polls the bridge and writes what it
//!   sends. Logging through defmt-rtt.
//!
//! Build: `cargo build --release --bin stm32f405_mavlink` in `boards/stm32f405`; `cargo run`
//! with the same arguments flashes it through `probe-rs run`.
#![no_std]
#![no_main]

mod fw {
    use cortex_m_rt::entry;
    use defmt_rtt as _;
    use panic_probe as _;
    use stm32f4xx_hal::{interrupt, pac};

    use board_stm32f405::board::{self, now};
    use board_stm32f405::usart2_ring::{self, RingRx};
    use idu_gimbal::port::{Nb, Port, Uart};
    use idu_gimbal::video::{Camera, Family};
    use idu_gimbal::{CanPort, Config, Link};
    use idu_gimbal_mavlink::camera::CameraConfig;
    use idu_gimbal_mavlink::{Bridge, BridgeConfig, SerialInput};

    /// The autopilot link's rate.
    const MAVLINK_BAUD: u32 = 921_600;

    /// USART2 receive into the ring.
    #[interrupt]
    fn USART2() {
        usart2_ring::on_interrupt();
    }

    #[entry]
    fn main() -> ! {
        let (Some(dp), Some(cp)) = (pac::Peripherals::take(), cortex_m::Peripherals::take()) else {
            panic!("peripherals taken twice");
        };
        let mut rcc = board::clocks(dp.RCC);
        board::start_tick(cp.SYST, &rcc);
        let can = board::can1(dp.CAN1, dp.GPIOB, &mut rcc);

        let tx = usart2_ring::open(dp.USART2, dp.GPIOA, MAVLINK_BAUD, &mut rcc);
        // The same non-blocking UART adapter the gimbal's serial port uses.
        let mut autopilot = Nb::new(RingRx, tx);
        defmt::info!(
            "USART2 up: MAVLink 2 at {=u32} baud, PA2 TX, PA3 RX",
            MAVLINK_BAUD
        );

        // The camera's streams, as QGroundControl will play them (set the family and the IP
        // of your camera here; `Family::DualLight` adds the thermal stream and settings).
        let camera = CameraConfig::with_streams_of(&Camera::new(Family::X3)).ok();
        let mut link: Link = Link::new(Config::default());
        let mut port = CanPort::new(can);
        let mut bridge = match (BridgeConfig {
            camera,
            ..BridgeConfig::default()
        })
        .check()
        {
            Ok(config) => Bridge::new(config),
            // Only a configuration with a zero id or one id for both components is refused.
            Err(_) => defmt::panic!("the MAVLink bridge's configuration is refused"),
        };
        // What the bridge has not taken of the UART's bytes is held there, offered again
        // once what the bridge holds is sent.
        let mut input: SerialInput<64> = SerialInput::new();
        let mut was_up = false;
        loop {
            let now = now();
            if let Err(e) = port.poll(&mut link, now) {
                defmt::warn!("{}", e);
            }
            // What a line error or a full ring lost is counted by the ring (the frame it
            // broke fails its CRC, counted by the bridge's reader), said as it grows.
            if input
                .receive(&mut bridge, &mut link, now, |buf| autopilot.read(buf))
                .is_err()
            {
                defmt::warn!("autopilot UART: {}", usart2_ring::counts());
            }
            bridge.poll(&mut link, now);
            loop {
                let bytes = bridge.transmit_bytes();
                if bytes.is_empty() {
                    break;
                }
                match autopilot.write(bytes) {
                    Ok(0) | Err(_) => break,
                    Ok(n) => bridge.transmit_written(n),
                }
            }
            let up = link.is_link_up();
            if up != was_up {
                was_up = up;
                defmt::info!("gimbal link {}", if up { "up" } else { "down" });
            }
        }
    }
}
