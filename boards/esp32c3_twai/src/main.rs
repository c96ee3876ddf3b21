//! ESP32-C3 driving an IDU gimbal through its TWAI (CAN 2.0) controller and esp-hal.
//!
//! * TWAI0 on **GPIO4 (TX) / GPIO5 (RX)** to a 3.3 V CAN transceiver (SN65HVD230, TJA1051T/3
//!   or similar); any free GPIOs will do (the GPIO matrix routes them).
//! * 1 Mbit/s, extended IDs. Hardware filter: a single extended acceptance filter on all 29
//!   bits of the postback ID, data frames only (the TWAI's single filter also lets standard
//!   frames whose bits happen to match through; the driver ignores those).
//! * Millisecond tick: esp-hal's `time::Instant` (the system timer).
//! * Logging over the USB serial/JTAG console with esp-println.
//! * Bus-off is not recovered from: esp-hal's TWAI stays in reset mode, every receive
//!   answering bus-off (each counted, each poll logging the first), until
//!   `initiate_recovery`. A product recovers there; this example leaves the link down until
//!   reset.
//!
//! The main loop points the gimbal 30° down once, pushes stand-in vehicle data at 10 Hz
//! (replace [`vehicle_stand_in`] with your autopilot's estimates), polls the driver and
//! logs postbacks, link events and, every 10 s, the counters.
//!
//! Build: `cargo build --release` in this directory. Flash and watch the console:
//! `cargo run --release` (the runner is `espflash flash --monitor`; the ESP-IDF
//! second-stage bootloader checks the application descriptor that `esp_app_desc!` emits).
#![no_std]
#![no_main]

use esp_hal::time::Instant as EspInstant;
use esp_hal::twai::filter::SingleExtendedFilter;
use esp_hal::twai::{BaudRate, ExtendedId, TwaiConfiguration, TwaiMode};
use esp_println::println;

use idu_gimbal::wire::control::{GimbalCommand, Pitch};
use idu_gimbal::{CanPort, Config, Event, Instant, Link};

// The main loop and the stand-in vehicle data shared with the other CAN firmware.
use idu_firmware_support::app::{App, Report};
use idu_firmware_support::vehicle::vehicle_stand_in;

esp_bootloader_esp_idf::esp_app_desc!();

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    println!("panic: {}", info);
    loop {}
}

/// Milliseconds since boot from the system timer, wrapping as the driver's `Instant` expects.
fn now() -> Instant {
    Instant::from_millis(EspInstant::now().duration_since_epoch().as_millis() as u32)
}

#[esp_hal::main]
fn main() -> ! {
    let peripherals = esp_hal::init(esp_hal::Config::default());

    let mut config = TwaiConfiguration::new(
        peripherals.TWAI0,
        peripherals.GPIO5,
        peripherals.GPIO4,
        BaudRate::B1000K,
        TwaiMode::Normal,
    );
    // The postback only: every ID bit compared, RTR compared and 0 (data frames).
    let (Some(postback), Some(all_bits)) = (
        ExtendedId::new(idu_gimbal::wire::ids::POSTBACK),
        ExtendedId::new(idu_gimbal::wire::ids::EXTENDED_MAX),
    ) else {
        panic!("the postback ID is a 29-bit ID");
    };
    config.set_filter(SingleExtendedFilter::new_from_code_mask(
        postback, all_bits, false, true,
    ));
    // esp-hal's `Twai` implements `embedded_can::nb::Can` (feature `unstable`).
    let twai = config.start();
    println!("TWAI up: 1 Mbit/s, filter passes postbacks only");

    let mut link: Link = Link::new(Config::default());
    let mut port = CanPort::new(twai);
    if let Ok(pitch) = Pitch::new(-30.0) {
        // The queue is empty: this cannot be refused.
        let _ = link.send(GimbalCommand::Pitch(pitch));
    }

    // Busy polling: the TWAI's receive FIFO (64 bytes) holds the four frames of a
    // postback, and it has one transmit buffer.
    let mut app = App::new(now());
    loop {
        app.step(
            &mut link,
            &mut port,
            now(),
            vehicle_stand_in,
            |report| match report {
                Report::Driver(e) => println!("{}", e),
                Report::Event(Event::Postback, Some(p)) => println!(
                    "postback: pitch {} deg, heading {} deg",
                    p.pitch_deg(),
                    p.heading_deg()
                ),
                Report::Event(event, _) => println!("event: {:?}", event),
                Report::Stats(link, port) => println!("stats: {:?} {:?}", link, port),
            },
        );
    }
}
