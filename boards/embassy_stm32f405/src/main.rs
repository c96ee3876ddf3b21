//! idu-gimbal on an STM32F405RG under embassy: the sans-IO [`Link`] driven by an async task
//! over bxCAN.
//!
//! * CAN1 on **PB8 (RX) / PB9 (TX)** at 1 Mbit/s, 29-bit extended IDs, to a 3.3 V CAN
//!   transceiver. One filter bank (32-bit list mode) passes exactly the postback ID
//!   ([`ids::POSTBACK`]), data frames only.
//! * Clocks: 8 MHz HSE crystal, SYSCLK 168 MHz, APB1 (the CAN clock) 42 MHz.
//! * embassy-time on TIM2 is the millisecond tick; defmt-rtt logging, panic-probe.
//!
//! The gimbal task sleeps until a frame arrives, vehicle data arrives, a transmit mailbox
//! frees up (only while frames wait for one), or the link's [`Link::next_deadline`] comes,
//! whichever is first (as embassy-net drives smoltcp with `poll_at`); then it feeds the
//! link, polls it, and hands it the frames it has to send. It never polls on a fixed
//! period. Vehicle data comes from a second task through an [`embassy_sync`] channel: here a
//! **stand-in** ([`vehicle_task`]); replace it with your autopilot's estimates.
//!
//! Build: `cargo build --release` in this directory (target and linker script from its
//! `.cargo/config.toml`). Flash and watch the logs: `cargo run --release` (probe-rs).
#![no_std]
#![no_main]

use defmt::{info, unwrap, warn};
use defmt_rtt as _;
use embassy_executor::Spawner;
use embassy_futures::select::{select4, Either4};
use embassy_stm32::can::enums::TryReadError;
use embassy_stm32::can::filter::ListEntry32;
use embassy_stm32::can::frame::Envelope;
use embassy_stm32::can::{
    self, Can, CanTx, ExtendedId, Fifo, Id, Rx0InterruptHandler, Rx1InterruptHandler, RxBuf,
    SceInterruptHandler, TryWriteError, TxInterruptHandler,
};
use embassy_stm32::peripherals::CAN1;
use embassy_stm32::time::Hertz;
use embassy_stm32::{bind_interrupts, rcc};
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::channel::{Channel, Receiver, Sender};
use embassy_time::Timer;
use panic_probe as _;
use static_cell::StaticCell;

use idu_gimbal::interface::CAN_BITRATE;
use idu_gimbal::link::{Config, Event, Link, RxId};
use idu_gimbal::wire::ids;
use idu_gimbal::Instant;
// Between embassy-time and the core's clock; the stand-in vehicle data shared with the other
// firmware.
use idu_firmware_support::embassy::{embassy_at, next_wake, tick};
use idu_firmware_support::vehicle::{vehicle_stand_in, Vehicle};

bind_interrupts!(struct Irqs {
    CAN1_TX => TxInterruptHandler<CAN1>;
    CAN1_RX0 => Rx0InterruptHandler<CAN1>;
    CAN1_RX1 => Rx1InterruptHandler<CAN1>;
    CAN1_SCE => SceInterruptHandler<CAN1>;
});

/// The postback's ID, checked at compile time to be a 29-bit ID.
const POSTBACK: ExtendedId = match ExtendedId::new(ids::POSTBACK) {
    Some(id) => id,
    None => panic!("the postback ID is a 29-bit ID"),
};

/// Received frames, queued by the CAN RX interrupt: bxCAN's FIFO holds 3 frames and a
/// postback is 4 back-to-back frames (~0.5 ms at 1 Mbit/s), so the interrupt, not the task,
/// empties it. A frame that finds this queue full is dropped inside embassy-stm32, which
/// counts nothing (16 frames are four postbacks: the task would have to stall for 2 s).
const RX_QUEUE: usize = 16;
static RX_BUF: StaticCell<RxBuf<RX_QUEUE>> = StaticCell::new();

static VEHICLE: Channel<CriticalSectionRawMutex, Vehicle, 4> = Channel::new();

// ---- the gimbal task ----

/// Hands the link's frames to the transmit mailboxes until they are full.
fn transmit(tx: &mut CanTx<'_>, link: &mut Link) {
    while let Some(frame) = link.next_transmit() {
        let Ok(can_frame) = can::Frame::new_extended(frame.id, &frame.data) else {
            // Every frame the link hands out is a valid 29-bit, 8-byte frame: never here.
            // Told done all the same, so that the link does not wait on it.
            warn!("frame {=u32:#x} not representable, dropped", frame.id);
            link.transmit_done(None);
            continue;
        };
        match tx.try_write(&can_frame) {
            Ok(status) => {
                // Only in priority scheduling: a lower-priority frame taken out of a
                // mailbox for this one. The link re-queues it.
                let displaced = status.dequeued_frame().and_then(|d| match d.id() {
                    Id::Extended(id) => <[u8; 8]>::try_from(d.data())
                        .ok()
                        .map(|data| idu_gimbal::wire::Frame::new(id.as_raw(), data)),
                    Id::Standard(_) => None,
                });
                link.transmit_done(displaced);
            }
            Err(TryWriteError::Full) => {
                link.transmit_refused(frame);
                return;
            }
        }
    }
}

/// Feeds one received frame to the link.
fn receive(link: &mut Link, envelope: Envelope, now: Instant) {
    let (frame, _timestamp) = envelope.parts();
    match frame.id() {
        Id::Extended(id) if !frame.header().rtr() => link.receive(id.as_raw(), frame.data(), now),
        // Standard IDs and remote frames are not for this node (the filter passes none).
        _ => link.receive(RxId::Other, &[], now),
    }
}

fn log_event(link: &Link, event: Event, now: Instant) {
    match event {
        Event::Postback => {
            if let Some((p, _age)) = link.latest_postback(now) {
                info!(
                    "postback: pitch {=f32} deg, heading {=f32} deg, {}, tracking {=bool}",
                    p.pitch_deg(),
                    p.heading_deg(),
                    p.mode,
                    p.tracking
                );
            }
        }
        Event::LinkUp => info!("gimbal link up"),
        Event::LinkDown => warn!("gimbal link down: no postback for 1.5 s"),
        Event::RateHoldExpired => info!("rate hold expired: gimbal stopped"),
        Event::TargetUnreachable { elevation_cdeg } => {
            warn!(
                "target out of the pitch range (needs {=i16} cdeg)",
                elevation_cdeg
            )
        }
        Event::AimNotReached => warn!("the gimbal did not reach the aim held"),
    }
}

/// Drives the link over CAN1: never returns.
#[embassy_executor::task]
async fn gimbal_task(
    mut can: Can<'static>,
    vehicle: Receiver<'static, CriticalSectionRawMutex, Vehicle, 4>,
) {
    let (mut tx, rx) = can.split();
    let mut rx = rx.buffered(RX_BUF.init(RxBuf::new()));
    let mut link: Link = Link::new(Config::default());
    let max_rx = link.config().max_rx_per_poll.get();
    let mut bus_errors = 0u32;
    let mut next_stats = tick(embassy_time::Instant::now()).add_millis(10_000);

    loop {
        let at = embassy_time::Instant::now();
        let now = tick(at);
        link.poll(now);
        if link.has_transmit() {
            transmit(&mut tx, &mut link);
        }
        while let Some(event) = link.next_event() {
            log_event(&link, event, now);
        }
        if now.is_at_or_after(next_stats) {
            next_stats = now.add_millis(10_000);
            info!("stats: {}, bus errors {=u32}", link.stats(), bus_errors);
        }

        // Sleep until the first of: a frame, the link's deadline (or the next stats line),
        // vehicle data, a free mailbox (only while frames wait for one).
        let deadline = next_wake(&link, now);
        let wake = if next_stats.millis_since(now) < deadline.millis_since(now) {
            next_stats
        } else {
            deadline
        };
        let waiting = link.has_transmit();
        let room = async {
            if waiting {
                tx.flush_any().await
            } else {
                core::future::pending().await
            }
        };
        match select4(
            rx.read(),
            Timer::at(embassy_at(wake, at)),
            vehicle.receive(),
            room,
        )
        .await
        {
            Either4::First(first) => {
                let now = tick(embassy_time::Instant::now());
                let mut next = Ok(first);
                // This frame and those queued behind it, at most `max_rx_per_poll`.
                for _ in 0..max_rx {
                    match next {
                        Ok(Ok(envelope)) => receive(&mut link, envelope, now),
                        Ok(Err(_)) | Err(TryReadError::BusError(_)) => {
                            bus_errors = bus_errors.wrapping_add(1)
                        }
                        Err(TryReadError::Empty) => break,
                    }
                    next = match rx.try_read() {
                        Ok(envelope) => Ok(Ok(envelope)),
                        Err(e) => Err(e),
                    };
                }
            }
            Either4::Second(()) | Either4::Fourth(()) => {}
            Either4::Third(sample) => {
                sample.push(&mut link);
            }
        }
    }
}

// ---- the vehicle data ----

/// Vehicle data at 10 Hz, from the stand-in the other firmware uses
/// (`idu_firmware_support::vehicle`: replace it with the autopilot's estimates).
#[embassy_executor::task]
async fn vehicle_task(vehicle: Sender<'static, CriticalSectionRawMutex, Vehicle, 4>) {
    let mut ticker = embassy_time::Ticker::every(embassy_time::Duration::from_millis(100));
    loop {
        ticker.next().await;
        let stamp = tick(embassy_time::Instant::now());
        if let Some(v) = vehicle_stand_in(stamp) {
            vehicle.send(v).await;
        }
    }
}

// ---- start-up ----

fn clocks() -> embassy_stm32::Config {
    let mut config = embassy_stm32::Config::default();
    config.rcc.hse = Some(rcc::Hse {
        freq: Hertz(8_000_000),
        mode: rcc::HseMode::Oscillator,
    });
    config.rcc.pll_src = rcc::PllSource::HSE;
    // 8 MHz / 4 * 168 / 2 = 168 MHz; 336 MHz / 7 = 48 MHz for USB.
    config.rcc.pll = Some(rcc::Pll {
        prediv: rcc::PllPreDiv::DIV4,
        mul: rcc::PllMul::MUL168,
        divp: Some(rcc::PllPDiv::DIV2),
        divq: Some(rcc::PllQDiv::DIV7),
        divr: None,
    });
    config.rcc.sys = rcc::Sysclk::PLL1_P;
    config.rcc.ahb_pre = rcc::AHBPrescaler::DIV1;
    // APB1 at 42 MHz (its maximum): 1 Mbit/s is 42 MHz / 3 / 14 time quanta.
    config.rcc.apb1_pre = rcc::APBPrescaler::DIV4;
    config.rcc.apb2_pre = rcc::APBPrescaler::DIV2;
    config
}

#[embassy_executor::main]
async fn main(spawner: Spawner) {
    let p = embassy_stm32::init(clocks());

    let mut can = Can::new(p.CAN1, p.PB8, p.PB9, Irqs);
    can.modify_filters().enable_bank(
        0,
        Fifo::Fifo0,
        [ListEntry32::data_frames_with_id(POSTBACK); 2],
    );
    // From the CAN clock embassy configured (APB1, 42 MHz): prescaler 6, 7 time quanta a
    // bit (1 + 5 + 1), sample point 85.7 % (as boards/stm32f405/src/board.rs's 14 quanta).
    can.modify_config()
        .set_bitrate(CAN_BITRATE)
        .set_automatic_retransmit(true);
    // Mailboxes in the order frames are written (the link hands them out by priority):
    // then a free mailbox (`flush_any`) is always room for the next frame.
    can.set_tx_fifo_scheduling(true);
    can.enable().await;
    info!(
        "CAN1 up: {=u32} bit/s, filter passes postbacks only",
        CAN_BITRATE
    );

    spawner.spawn(unwrap!(gimbal_task(can, VEHICLE.receiver())));
    spawner.spawn(unwrap!(vehicle_task(VEHICLE.sender())));
}
