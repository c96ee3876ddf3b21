//! RP2040 (Raspberry Pi Pico class) driving an IDU gimbal through an MCP2515 CAN controller
//! on SPI0.
//!
//! * MCP2515 with a **16 MHz crystal** (1 Mbit/s needs it: the 8 MHz modules top out at
//!   500 kbit/s) and a CAN transceiver (e.g. the common MCP2515 + TJA1050 module, or an
//!   MCP25625). Wiring: GP16 = MISO (SO), GP17 = CS, GP18 = SCK, GP19 = MOSI (SI), 3V3, GND.
//!   The INT pin is not needed: the driver polls the controller's status over SPI.
//! * 1 Mbit/s, extended IDs; the controller's acceptance filters pass only the postback ID
//!   (both receive buffers, every filter on it, masks on all 29 bits), RXB0 rolls over into
//!   RXB1, so the 4 back-to-back frames of a postback need the loop to come round once per
//!   two frames (~250 µs at 1 Mbit/s). (mcp25xx reads RXB0 before RXB1: a frame that
//!   arrives in RXB0 while an older one still waits in RXB1 is read first. Busy polling at
//!   10 MHz SPI empties both well within a frame time; a postback whose frames did come out
//!   of order fails its CRC and is counted, never delivered.)
//! * Transmit: one frame in flight ([`InOrder`]). mcp25xx loads the lowest free of the
//!   three transmit buffers at equal priority, and the MCP2515 sends equal ones highest
//!   buffer first: two frames queued behind a third would go out in reverse.
//! * Millisecond tick: the RP2040's 1 MHz 64-bit timer.
//! * GP25 (the Pico's LED) is on while the gimbal's link is up.
//!
//! The main loop points the gimbal 30° down once, pushes stand-in vehicle data at 10 Hz
//! (replace [`vehicle_stand_in`] with your autopilot's estimates) and polls the driver.
//!
//! Build: `cargo build --release` in this directory (the target comes from
//! `.cargo/config.toml`). Flash: `cargo run --release` with a debug probe (probe-rs), or
//! convert the ELF to UF2 (`elf2uf2-rs`, `picotool`) for the USB bootloader.
//!
//! Feature `wire-units`: the same program built with the integer (wire-unit) constructors
//! only (`Pitch::from_deci`, `Attitude::from_centideg`, `Gps::from_e7`, `Altitude::from_cm`)
//! instead of the `f32`/`f64` ones, to measure what soft-float costs on the Cortex-M0+.
#![no_std]
#![no_main]

use embedded_can::{ExtendedId, Id};
use embedded_hal::digital::OutputPin;
use embedded_hal::spi::SpiDevice;
use embedded_hal_bus::spi::ExclusiveDevice;
use mcp25xx::bitrates::clock_16mhz::CNF_1000K_BPS;
use mcp25xx::registers::{OperationMode, RXB0CTRL, RXB1CTRL, RXM};
use mcp25xx::{
    AcceptanceFilter, CanFrame, Config as McpConfig, IdHeader, MCP25xx, SpiError, TxBuffer,
};
use panic_halt as _;
use rp2040_hal::{self as hal, fugit::RateExtU32, pac, Clock};

use idu_gimbal::wire::control::{GimbalCommand, Pitch};
use idu_gimbal::{CanPort, Config, Instant, Link};

// The main loop shared with the other CAN firmware.
use idu_firmware_support::app::App;

/// The MCP2515 with one frame in flight, so that frames go out in the order the link
/// queued them: mcp25xx's `transmit` takes the lowest free of the three transmit buffers,
/// all at the same priority, and the controller sends equal ones highest buffer first
/// (datasheet, transmit priority). A frame takes ~130 µs at 1 Mbit/s and the protocol sends
/// a few dozen a second: one at a time costs nothing.
struct InOrder<SPI: SpiDevice>(MCP25xx<SPI>);

impl<SPI: SpiDevice> embedded_can::nb::Can for InOrder<SPI> {
    type Frame = CanFrame;
    type Error = SpiError<SPI::Error>;

    fn transmit(&mut self, frame: &CanFrame) -> nb::Result<Option<CanFrame>, Self::Error> {
        let status = self.0.read_status().map_err(SpiError)?;
        if status.txreq0() || status.txreq1() || status.txreq2() {
            return Err(nb::Error::WouldBlock);
        }
        self.0
            .load_tx_buffer(TxBuffer::TXB0, frame)
            .map_err(SpiError)?;
        self.0.request_to_send(TxBuffer::TXB0).map_err(SpiError)?;
        Ok(None)
    }

    fn receive(&mut self) -> nb::Result<CanFrame, Self::Error> {
        embedded_can::nb::Can::receive(&mut self.0)
    }
}

/// The second-stage bootloader for the Pico's W25Q080 flash (for other flash chips,
/// `rp2040_boot2::BOOT_LOADER_GENERIC_03H` works with any).
#[link_section = ".boot2"]
#[used]
pub static BOOT2: [u8; 256] = rp2040_boot2::BOOT_LOADER_W25Q080;

/// The Pico's crystal.
const XTAL_FREQ_HZ: u32 = 12_000_000;

// The stand-in vehicle data (replace with the autopilot's estimates) shared with the other
// firmware, built from f32 degrees and metres.
#[cfg(not(feature = "wire-units"))]
use idu_firmware_support::vehicle::vehicle_stand_in;

/// The same stand-in, built from wire units (1e-7 degree, cm, centi-degree): no floats.
#[cfg(feature = "wire-units")]
fn vehicle_stand_in(now: Instant) -> Option<idu_firmware_support::vehicle::Vehicle> {
    use idu_gimbal::wire::vehicle::{Altitude, Attitude, Gps};
    // In i32: 359 × 100 is past i16 (an overflow, a panic in a debug build).
    let heading = i16::try_from(((now.as_millis() / 100) % 360) as i32 * 100 - 18_000).ok()?;
    Some(idu_firmware_support::vehicle::Vehicle {
        gps: Gps::from_e7(473_977_420, 85_455_940).ok()?,
        altitude: Altitude::from_cm(48_800),
        attitude: Attitude::from_centideg(150, -40, heading).ok()?,
        stamp: now,
    })
}

/// The first command: look 30° down.
fn look_down() -> Option<Pitch> {
    #[cfg(not(feature = "wire-units"))]
    let pitch = Pitch::new(-30.0);
    #[cfg(feature = "wire-units")]
    let pitch = Pitch::from_deci(-300);
    pitch.ok()
}

#[hal::entry]
fn main() -> ! {
    let Some(mut pac) = pac::Peripherals::take() else {
        panic!("peripherals taken twice");
    };
    let mut watchdog = hal::Watchdog::new(pac.WATCHDOG);
    let Ok(clocks) = hal::clocks::init_clocks_and_plls(
        XTAL_FREQ_HZ,
        pac.XOSC,
        pac.CLOCKS,
        pac.PLL_SYS,
        pac.PLL_USB,
        &mut pac.RESETS,
        &mut watchdog,
    ) else {
        panic!("clock setup failed");
    };
    let timer = hal::Timer::new(pac.TIMER, &mut pac.RESETS, &clocks);
    // The 1 MHz, 64-bit timer in milliseconds; the u32 wraps after 49.7 days, as the driver's
    // `Instant` expects.
    let now = || Instant::from_millis((timer.get_counter().ticks() / 1_000) as u32);

    let sio = hal::Sio::new(pac.SIO);
    let pins = hal::gpio::Pins::new(
        pac.IO_BANK0,
        pac.PADS_BANK0,
        sio.gpio_bank0,
        &mut pac.RESETS,
    );
    let mut led = pins.gpio25.into_push_pull_output();

    // SPI0 at 10 MHz (the MCP2515's maximum), mode 0.
    let miso = pins.gpio16.into_function::<hal::gpio::FunctionSpi>();
    let sck = pins.gpio18.into_function::<hal::gpio::FunctionSpi>();
    let mosi = pins.gpio19.into_function::<hal::gpio::FunctionSpi>();
    let cs = pins
        .gpio17
        .into_push_pull_output_in_state(hal::gpio::PinState::High);
    let spi = hal::Spi::<_, _, _, 8>::new(pac.SPI0, (mosi, miso, sck)).init(
        &mut pac.RESETS,
        clocks.peripheral_clock.freq(),
        10.MHz(),
        embedded_hal::spi::MODE_0,
    );
    // The error type is `Infallible` (the RP2040's GPIOs cannot fail).
    let Ok(device) = ExclusiveDevice::new(spi, cs, timer);

    // Only the postback: masks on all 29 bits (and the extended-ID bit), every filter of both
    // receive buffers on the postback ID (a filter left at reset would pass standard ID 0).
    let postback: IdHeader = match ExtendedId::new(idu_gimbal::wire::ids::POSTBACK) {
        Some(id) => Id::Extended(id).into(),
        None => panic!("the postback ID is a 29-bit ID"),
    };
    let all_bits: IdHeader = Id::Extended(ExtendedId::MAX).into();
    let filters = [
        (AcceptanceFilter::Mask0, all_bits),
        (AcceptanceFilter::Mask1, all_bits),
        (AcceptanceFilter::Filter0, postback),
        (AcceptanceFilter::Filter1, postback),
        (AcceptanceFilter::Filter2, postback),
        (AcceptanceFilter::Filter3, postback),
        (AcceptanceFilter::Filter4, postback),
        (AcceptanceFilter::Filter5, postback),
    ];
    let config = McpConfig::default()
        .mode(OperationMode::NormalOperation)
        .bitrate(CNF_1000K_BPS)
        .receive_buffer_0(RXB0CTRL::default().with_rxm(RXM::Filter).with_bukt(true))
        .receive_buffer_1(RXB1CTRL::default())
        .filters(&filters);
    let mut mcp = MCP25xx { spi: device };
    if mcp.apply_config(&config).is_err() {
        panic!("MCP2515 configuration over SPI failed");
    }

    let mut link: Link = Link::new(Config::default());
    let mut port = CanPort::new(InOrder(mcp));
    if let Some(pitch) = look_down() {
        // The queue is empty: this cannot be refused.
        let _ = link.send(GimbalCommand::Pitch(pitch));
    }

    // A driver error (an SPI failure) is counted in port.stats(); there is no log here,
    // the LED shows the link.
    let mut app = App::new(now());
    loop {
        app.step(&mut link, &mut port, now(), vehicle_stand_in, |_| {});
        let _ = if link.is_link_up() {
            led.set_high()
        } else {
            led.set_low()
        };
    }
}
