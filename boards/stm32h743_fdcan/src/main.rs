//! STM32H743 (Pixhawk-class flight controller: Pixhawk 6X, Cube Orange, …) driving an IDU
//! gimbal on FDCAN1, through stm32h7xx-hal and `idu_gimbal_fdcan::FdCan`.
//!
//! * FDCAN1 on **PD0 (RX) / PD1 (TX)** (CAN1 on Pixhawk boards), classic CAN at 1 Mbit/s
//!   with extended IDs. The FDCAN's kernel clock is PLL1 Q at 32 MHz: 32 time quanta a bit,
//!   sample point at 87.5 %.
//! * Hardware filter: extended filter 0 stores the postback ID (and only it) in FIFO 0; the
//!   global filter rejects every other frame and every remote frame.
//! * Clocks: HSE at [`HSE_HZ`] (16 MHz on the Pixhawk 6X; set 24 MHz for a Cube Orange),
//!   400 MHz core. Millisecond tick: SysTick at 1 kHz.
//! * Logging through defmt-rtt, panics through panic-probe (over the debug probe).
//! * Bus-off is logged (the adapter reports it once) and not recovered from: the M_CAN
//!   core stays in initialisation until software restarts it (`idu_gimbal_fdcan`'s docs:
//!   release the controller, through configuration mode back to normal, wrap it again). A
//!   product restarts it there; this example leaves the link down until reset.
//!
//! The main loop points the gimbal 30° down once, pushes stand-in vehicle data at 10 Hz
//! (replace [`vehicle_stand_in`] with your autopilot's estimates), polls the driver and
//! logs postbacks, link events and, every 10 s, the counters.
//!
//! Build: `cargo build --release` in this directory. Flash and watch the logs:
//! `cargo run --release` (probe-rs; see memory.x about a Pixhawk's bootloader).
#![no_std]
#![no_main]

use core::num::{NonZeroU16, NonZeroU8};
use core::sync::atomic::{AtomicU32, Ordering};

use cortex_m::peripheral::syst::SystClkSource;
use cortex_m_rt::{entry, exception};
use defmt_rtt as _;
use fdcan::config::{FrameTransmissionConfig, GlobalFilter, NominalBitTiming};
use fdcan::filter::{Action, ExtendedFilter, ExtendedFilterSlot, FilterType};
use panic_probe as _;
use stm32h7xx_hal::gpio::Speed;
use stm32h7xx_hal::rcc::rec;
use stm32h7xx_hal::{pac, prelude::*};

use idu_gimbal::wire::control::{GimbalCommand, Pitch};
use idu_gimbal::{CanPort, Config, Event, Instant, Link};
use idu_gimbal_fdcan::FdCan;

// The main loop and the stand-in vehicle data shared with the other CAN firmware.
use idu_firmware_support::app::{App, Report};
use idu_firmware_support::vehicle::vehicle_stand_in;

/// The board's crystal.
const HSE_HZ: u32 = 16_000_000;
/// The core clock.
const SYS_HZ: u32 = 400_000_000;
/// The FDCAN kernel clock (PLL1 Q).
const FDCAN_HZ: u32 = 32_000_000;

/// 1 Mbit/s from 32 MHz: prescaler 1, 1 + 27 + 4 = 32 quanta, sample point 28/32 = 87.5 %.
const BIT_TIMING: NominalBitTiming = NominalBitTiming {
    prescaler: NonZeroU16::MIN,
    seg1: match NonZeroU8::new(27) {
        Some(n) => n,
        None => panic!(),
    },
    seg2: match NonZeroU8::new(4) {
        Some(n) => n,
        None => panic!(),
    },
    sync_jump_width: match NonZeroU8::new(4) {
        Some(n) => n,
        None => panic!(),
    },
};
const _: () = assert!(FDCAN_HZ / (1 + 27 + 4) == idu_gimbal::interface::CAN_BITRATE);

/// Milliseconds since boot, advanced by the SysTick interrupt (wraps after ~49.7 days, which
/// `Instant` handles).
static TICKS_MS: AtomicU32 = AtomicU32::new(0);

#[exception]
fn SysTick() {
    TICKS_MS.fetch_add(1, Ordering::Relaxed);
}

fn now() -> Instant {
    Instant::from_millis(TICKS_MS.load(Ordering::Relaxed))
}

defmt::timestamp!("{=u32:ms}", TICKS_MS.load(Ordering::Relaxed));

#[entry]
fn main() -> ! {
    let (Some(dp), Some(mut cp)) = (pac::Peripherals::take(), cortex_m::Peripherals::take()) else {
        panic!("peripherals taken twice");
    };

    let pwrcfg = dp.PWR.constrain().freeze();
    let ccdr = dp
        .RCC
        .constrain()
        .use_hse(HSE_HZ.Hz())
        .sys_ck(SYS_HZ.Hz())
        .pll1_strategy(stm32h7xx_hal::rcc::PllConfigStrategy::Iterative)
        .pll1_q_ck(FDCAN_HZ.Hz())
        .freeze(pwrcfg, &dp.SYSCFG);
    assert_eq!(
        ccdr.clocks.pll1_q_ck().map(|f| f.raw()),
        Some(FDCAN_HZ),
        "the CAN bit timing needs the FDCAN kernel clock at 32 MHz"
    );

    // SysTick at 1 kHz from the core clock.
    cp.SYST.set_clock_source(SystClkSource::Core);
    cp.SYST.set_reload(ccdr.clocks.c_ck().raw() / 1000 - 1);
    cp.SYST.clear_current();
    cp.SYST.enable_interrupt();
    cp.SYST.enable_counter();

    // FDCAN1 on PD0/PD1, configured in ConfigMode, then in normal operation.
    let fdcan_rec = ccdr
        .peripheral
        .FDCAN
        .kernel_clk_mux(rec::FdcanClkSel::Pll1Q);
    let gpiod = dp.GPIOD.split(ccdr.peripheral.GPIOD);
    let rx = gpiod.pd0.into_alternate().speed(Speed::VeryHigh);
    let tx = gpiod.pd1.into_alternate().speed(Speed::VeryHigh);
    let mut can = dp.FDCAN1.fdcan(tx, rx, fdcan_rec);
    can.set_protocol_exception_handling(false);
    can.set_nominal_bit_timing(BIT_TIMING);
    can.set_frame_transmit(FrameTransmissionConfig::ClassicCanOnly);
    can.set_automatic_retransmit(true);
    let Some(postback) = fdcan::id::ExtendedId::new(idu_gimbal::wire::ids::POSTBACK) else {
        panic!("the postback ID is a 29-bit ID");
    };
    can.set_extended_filter(
        ExtendedFilterSlot::_0,
        ExtendedFilter {
            filter: FilterType::DedicatedSingle(postback),
            action: Action::StoreInFifo0,
        },
    );
    // Everything else, remote frames included, is rejected in hardware (the fdcan crate's
    // default global filter would store every frame that matches no filter in FIFO 0).
    can.set_global_filter(GlobalFilter::reject_all());
    let can = FdCan::new(can.into_normal());
    defmt::info!(
        "FDCAN1 up: {=u32} bit/s, filter passes postbacks only",
        idu_gimbal::interface::CAN_BITRATE
    );

    let mut link: Link = Link::new(Config::default());
    let mut port = CanPort::new(can);
    if let Ok(pitch) = Pitch::new(-30.0) {
        // The queue is empty: this cannot be refused.
        let _ = link.send(GimbalCommand::Pitch(pitch));
    }

    // Busy polling: the adapter keeps one frame in flight, and the receive FIFO's three
    // slots (the message RAM's layout in stm32h7xx-hal) are read as a postback's four
    // frames come, each 130 µs on the bus; an overrun is counted.
    let mut app = App::new(now());
    loop {
        app.step(
            &mut link,
            &mut port,
            now(),
            vehicle_stand_in,
            |report| match report {
                Report::Driver(e) => defmt::warn!("{}", defmt::Display2Format(&e)),
                Report::Event(Event::Postback, Some(p)) => defmt::info!(
                    "postback: pitch {=f32} deg, heading {=f32} deg",
                    p.pitch_deg(),
                    p.heading_deg()
                ),
                Report::Event(Event::LinkUp, _) => defmt::info!("gimbal link up"),
                Report::Event(Event::LinkDown, _) => {
                    defmt::warn!("gimbal link down: no postback for 1.5 s")
                }
                Report::Event(event, _) => defmt::info!("event: {}", event),
                Report::Stats(link, port) => defmt::info!("stats: {} {}", link, port),
            },
        );
    }
}
