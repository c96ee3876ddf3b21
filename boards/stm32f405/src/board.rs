//! Board support shared by the STM32F405 firmware (`stm32f405`, `stm32f405_uart`,
//! `stm32f405_mavlink`): clocks, the millisecond tick, and CAN1.
//!
//! * Clocks: 8 MHz HSE crystal, SYSCLK 168 MHz, APB1 (the CAN clock) 42 MHz.
//! * SysTick interrupts at 1 kHz: the millisecond tick the drivers run on; defmt log lines
//!   carry it.
//! * CAN1 on **PB8 (RX) / PB9 (TX)**, alternate function 9, to a 3.3 V CAN transceiver
//!   (e.g. SN65HVD230 or TJA1051T/3), 1 Mbit/s, 29-bit extended IDs. One 32-bit mask filter
//!   bank passes exactly the postback ID (`interface::mask_filter(Role::FlightController)`),
//!   data frames only, so the CPU never sees other traffic.

use core::sync::atomic::{AtomicU32, Ordering};

use bxcan::filter::Mask32;
use bxcan::{ExtendedId, Fifo};
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::SYST;
use cortex_m_rt::exception;
use stm32f4xx_hal::{pac, prelude::*, rcc::Config as RccConfig, rcc::Rcc};

use idu_gimbal::interface::{mask_filter, Role, CAN_BITRATE};
use idu_gimbal::wire::postback::Postback;
use idu_gimbal::{Event, Instant};

pub const HSE_HZ: u32 = 8_000_000;
pub const SYSCLK_HZ: u32 = 168_000_000;
/// APB1 clocks bxcan. 42 MHz is its maximum on the F405 and divides 1 Mbit/s evenly.
pub const PCLK1_HZ: u32 = 42_000_000;

/// bxcan bit timing for `CAN_BITRATE`: 14 time quanta a bit (1 sync + 11 + 2, sample
/// point 85.7 %, SJW 1), prescaler 3 from 42 MHz.
pub const CAN_BTR: u32 = {
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

/// The millisecond tick.
pub fn now() -> Instant {
    Instant::from_millis(TICKS_MS.load(Ordering::Relaxed))
}

defmt::timestamp!("{=u32:ms}", TICKS_MS.load(Ordering::Relaxed));

/// The clocks above; PCLK1 is checked (the CAN bit timing depends on it).
pub fn clocks(rcc: pac::RCC) -> Rcc {
    let rcc = rcc.freeze(
        RccConfig::hse(HSE_HZ.Hz())
            .sysclk(SYSCLK_HZ.Hz())
            .pclk1(PCLK1_HZ.Hz()),
    );
    assert_eq!(
        rcc.clocks.pclk1().raw(),
        PCLK1_HZ,
        "CAN bit timing needs PCLK1 = 42 MHz"
    );
    rcc
}

/// Starts the 1 kHz SysTick interrupt.
pub fn start_tick(mut syst: SYST, rcc: &Rcc) {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(rcc.clocks.hclk().raw() / 1000 - 1);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
}

/// CAN1 on PB8 (RX) / PB9 (TX), 1 Mbit/s, filtering for the postback.
pub fn can1(
    can1: pac::CAN1,
    gpiob: pac::GPIOB,
    rcc: &mut Rcc,
) -> bxcan::Can<stm32f4xx_hal::can::Can<pac::CAN1>> {
    let gpiob = gpiob.split(rcc);
    let can = can1.can((gpiob.pb9, gpiob.pb8), rcc);
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
    can
}

/// Logs a driver event; `latest` is the newest postback, for `Event::Postback`.
pub fn log_event(event: Event, latest: Option<Postback>) {
    match event {
        Event::Postback => {
            if let Some(p) = latest {
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
        Event::AimNotReached => defmt::warn!("the gimbal did not reach the aim held"),
    }
}
