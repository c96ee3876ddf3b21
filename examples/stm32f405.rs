//! Flight-controller firmware for an STM32F405RG driving an IDU gimbal over CAN.
//!
//! * CAN1 on **PB8 (RX) / PB9 (TX)**, alternate function 9, to a 3.3 V CAN transceiver
//!   (e.g. SN65HVD230 or TJA1051T/3), 1 Mbit/s, 29-bit extended IDs. One 32-bit mask filter
//!   bank passes exactly the postback ID (`interface::mask_filter(Role::FlightController)`),
//!   data frames only, so the CPU never sees other traffic.
//! * Clocks: 8 MHz HSE crystal, SYSCLK 168 MHz, APB1 (the CAN clock) 42 MHz.
//! * SysTick interrupts at 1 kHz: the millisecond tick the driver runs on.
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
mod fw {
    use core::sync::atomic::{AtomicU32, Ordering};

    use bxcan::filter::Mask32;
    use bxcan::{ExtendedId, Fifo};
    use cortex_m::peripheral::syst::SystClkSource;
    use cortex_m_rt::{entry, exception};
    use defmt_rtt as _;
    use panic_probe as _;
    use stm32f4xx_hal::{pac, prelude::*, rcc::Config as RccConfig};

    use idu_gimbal::interface::{mask_filter, Role, CAN_BITRATE};
    use idu_gimbal::wire::vehicle::{Altitude, Attitude, Gps};
    use idu_gimbal::{Config, Event, Gimbal, Instant};

    const HSE_HZ: u32 = 8_000_000;
    const SYSCLK_HZ: u32 = 168_000_000;
    /// APB1 clocks bxcan. 42 MHz is its maximum on the F405 and divides 1 Mbit/s evenly.
    const PCLK1_HZ: u32 = 42_000_000;

    /// bxcan bit timing for `CAN_BITRATE`: 14 time quanta a bit (1 sync + 11 + 2, sample
    /// point 85.7 %, SJW 1), prescaler 3 from 42 MHz.
    const CAN_BTR: u32 = {
        const TQ_PER_BIT: u32 = 14;
        const BS1: u32 = 11;
        const BS2: u32 = 2;
        const SJW: u32 = 1;
        assert!(1 + BS1 + BS2 == TQ_PER_BIT);
        let prescaler = PCLK1_HZ / (CAN_BITRATE * TQ_PER_BIT);
        assert!(
            prescaler * CAN_BITRATE * TQ_PER_BIT == PCLK1_HZ,
            "bit rate not exact"
        );
        ((SJW - 1) << 24) | ((BS2 - 1) << 20) | ((BS1 - 1) << 16) | (prescaler - 1)
    };

    /// Milliseconds since boot, advanced by the SysTick interrupt. Wraps after ~49.7 days,
    /// which `Instant` handles.
    static TICKS_MS: AtomicU32 = AtomicU32::new(0);

    #[exception]
    fn SysTick() {
        TICKS_MS.fetch_add(1, Ordering::Relaxed);
    }

    fn now() -> Instant {
        Instant::from_millis(TICKS_MS.load(Ordering::Relaxed))
    }

    defmt::timestamp!("{=u32:ms}", TICKS_MS.load(Ordering::Relaxed));

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

        let mut rcc = dp.RCC.freeze(
            RccConfig::hse(HSE_HZ.Hz())
                .sysclk(SYSCLK_HZ.Hz())
                .pclk1(PCLK1_HZ.Hz()),
        );
        assert_eq!(
            rcc.clocks.pclk1().raw(),
            PCLK1_HZ,
            "CAN bit timing needs PCLK1 = 42 MHz"
        );

        // The millisecond tick.
        let mut syst = cp.SYST;
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(rcc.clocks.hclk().raw() / 1000 - 1);
        syst.clear_current();
        syst.enable_interrupt();
        syst.enable_counter();

        // CAN1 on PB8 (RX) / PB9 (TX).
        let gpiob = dp.GPIOB.split(&mut rcc);
        let can = dp.CAN1.can((gpiob.pb9, gpiob.pb8), &mut rcc);
        let mut can = bxcan::Can::builder(can)
            .set_bit_timing(CAN_BTR)
            .set_automatic_retransmit(true)
            .enable();
        {
            let (id, mask) = mask_filter(Role::FlightController);
            let (Some(id), Some(mask)) = (ExtendedId::new(id), ExtendedId::new(mask)) else {
                panic!("filter ids are 29-bit");
            };
            let mut filter = Mask32::frames_with_ext_id(id, mask);
            filter.data_frames_only();
            // Dropping the handle leaves filter initialisation mode.
            can.modify_filters().enable_bank(0, Fifo::Fifo0, filter);
        }
        defmt::info!(
            "CAN1 up: {=u32} bit/s, BTR {=u32:#010x}, filter passes postbacks only",
            CAN_BITRATE,
            CAN_BTR
        );

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
                match event {
                    Event::Postback => {
                        if let Some((p, _age_ms)) = gimbal.latest_postback(now) {
                            defmt::info!(
                                "postback: pitch {=f32} deg, heading {=f32} deg, motor {=f32} deg, {}, {}, tracking {=bool}",
                                p.pitch_deg(),
                                p.heading_deg(),
                                p.motor_heading_deg(),
                                p.mode,
                                p.gimbal_type,
                                p.tracking
                            )
                        }
                    }
                    Event::LinkUp => defmt::info!("gimbal link up"),
                    Event::LinkDown => defmt::warn!("gimbal link down: no postback for 1.5 s"),
                    Event::RateHoldExpired => defmt::info!("rate hold expired: gimbal stopped"),
                    Event::TargetUnreachable { elevation_cdeg } => defmt::warn!(
                        "look-at target out of the gimbal's pitch range (needs {=i16} cdeg)",
                        elevation_cdeg
                    ),
                }
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
