//! USART2 receive by interrupt into a ring the main loop drains (shared by the
//! `stm32f405_uart` and `stm32f405_mavlink` firmware).
//!
//! The USART2 interrupt (RXNE, handled by [`on_interrupt`]) moves every byte into a
//! `RING`-byte ring, so no byte is lost while the main loop is busy. A full ring or a line
//! error (overrun, framing, parity, noise) is reported by the next read as an error, which
//! the driver counts (one for all that came between two reads); the parser above
//! resynchronises on the next frame. Every byte the full ring dropped and every line error
//! is counted here ([`counts`]).

use core::cell::RefCell;
use core::sync::atomic::{AtomicU32, Ordering};

use cortex_m::interrupt::Mutex;
use heapless::Deque;
use stm32f4xx_hal::rcc::Rcc;
use stm32f4xx_hal::serial::{Config as SerialConfig, Error as LineError, Rx, RxListen, Serial, Tx};
use stm32f4xx_hal::{pac, prelude::*};

/// Bytes received and not yet taken by the main loop.
pub const RING: usize = 1024;

/// The receive half, owned by the interrupt once set up.
static UART_RX: Mutex<RefCell<Option<Rx<pac::USART2>>>> = Mutex::new(RefCell::new(None));
static RECEIVED: Mutex<RefCell<Deque<u8, RING>>> = Mutex::new(RefCell::new(Deque::new()));
/// The latest line error or ring overflow not yet reported.
static LINE_ERROR: Mutex<RefCell<Option<LineError>>> = Mutex::new(RefCell::new(None));
/// Bytes the full ring dropped, and line errors, since start (wrapping).
static DROPPED: AtomicU32 = AtomicU32::new(0);
static LINE_ERRORS: AtomicU32 = AtomicU32::new(0);

/// What the receive side lost since start, each wrapping at `u32::MAX`.
#[derive(Clone, Copy, Debug, defmt::Format)]
pub struct Counts {
    /// Bytes received while the ring was full, dropped.
    pub dropped_bytes: u32,
    /// Line errors the USART reported (overrun, framing, parity, noise).
    pub line_errors: u32,
}

/// The counts so far.
pub fn counts() -> Counts {
    Counts {
        dropped_bytes: DROPPED.load(Ordering::Relaxed),
        line_errors: LINE_ERRORS.load(Ordering::Relaxed),
    }
}

/// The USART2 interrupt's work. The program defines the handler (`#[interrupt] fn USART2()`)
/// and calls this: a handler defined here would sit in the vector table of every program
/// linking this crate, the CAN firmware's too.
pub fn on_interrupt() {
    cortex_m::interrupt::free(|cs| {
        let mut rx = UART_RX.borrow(cs).borrow_mut();
        let Some(rx) = rx.as_mut() else { return };
        let mut ring = RECEIVED.borrow(cs).borrow_mut();
        loop {
            match embedded_hal_nb::serial::Read::read(rx) {
                Ok(byte) => {
                    if ring.push_back(byte).is_err() {
                        // The main loop fell behind: the byte is lost, and said so.
                        DROPPED.fetch_add(1, Ordering::Relaxed);
                        LINE_ERROR.borrow(cs).replace(Some(LineError::Overrun));
                    }
                }
                Err(nb::Error::WouldBlock) => break,
                // The HAL read the data register to clear the error flag.
                Err(nb::Error::Other(e)) => {
                    LINE_ERRORS.fetch_add(1, Ordering::Relaxed);
                    LINE_ERROR.borrow(cs).replace(Some(e));
                }
            }
        }
    });
}

/// Opens USART2 on PA2 (TX) / PA3 (RX) at `baud`, 8N1 (the HAL's default framing), and
/// starts the receive ring ([`start`]); gives back the transmit half.
pub fn open(usart: pac::USART2, gpioa: pac::GPIOA, baud: u32, rcc: &mut Rcc) -> Tx<pac::USART2> {
    let gpioa = gpioa.split(rcc);
    let Ok(serial) = Serial::new(
        usart,
        (gpioa.pa2, gpioa.pa3),
        SerialConfig::default().baudrate(baud.bps()),
        rcc,
    ) else {
        panic!("USART2 configuration refused");
    };
    let (tx, rx) = serial.split();
    start(rx);
    tx
}

/// Hands the receive half to the interrupt and enables it (the program's USART2 handler
/// calls [`on_interrupt`]).
pub fn start(mut rx: Rx<pac::USART2>) {
    rx.listen();
    cortex_m::interrupt::free(|cs| UART_RX.borrow(cs).replace(Some(rx)));
    // SAFETY: the handler only touches state behind `cortex_m::interrupt::Mutex`.
    unsafe { cortex_m::peripheral::NVIC::unmask(pac::Interrupt::USART2) };
}

/// The main loop's end of the receive ring, as an `embedded-hal-nb` reader.
pub struct RingRx;

impl embedded_hal_nb::serial::ErrorType for RingRx {
    type Error = LineError;
}

impl embedded_hal_nb::serial::Read<u8> for RingRx {
    fn read(&mut self) -> nb::Result<u8, LineError> {
        cortex_m::interrupt::free(|cs| {
            if let Some(e) = LINE_ERROR.borrow(cs).take() {
                return Err(nb::Error::Other(e));
            }
            RECEIVED
                .borrow(cs)
                .borrow_mut()
                .pop_front()
                .ok_or(nb::Error::WouldBlock)
        })
    }
}
