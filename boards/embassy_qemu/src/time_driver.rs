//! embassy-time's driver on the Cortex-M SysTick: a 1 kHz SysTick interrupt counts
//! milliseconds (embassy's ticks, `tick-hz-1_000`) and, on each tick, wakes the timers that
//! have come, through the executor-integrated timer queue of `embassy-time-queue-utils`.
//!
//! Clock: SysTick on the processor clock (CSR.CLKSOURCE = 1). QEMU's netduinoplus2 wires
//! the ARMv7-M core's `cpuclk` to the SoC's `sysclk`, 168 MHz (`SYSCLK_FRQ` in
//! hw/arm/netduinoplus2.c; the `refclk` is HCLK / 8, hw/arm/stm32f405_soc.c). It does not
//! model the RCC, so the clock is 168 MHz from reset, as on a real board configured for
//! it. On a real STM32F405 left on the 16 MHz HSI, [`SYSCLK_HZ`] would be 16 MHz.

use core::cell::{Cell, RefCell};
use core::task::Waker;

use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::SYST;
use cortex_m_rt::exception;
use critical_section::Mutex;
use embassy_time_driver::Driver;
use embassy_time_queue_utils::Queue;

/// The processor clock, which SysTick counts.
pub const SYSCLK_HZ: u32 = 168_000_000;
/// SysTick interrupts a second: one a millisecond, embassy's tick.
const TICK_HZ: u32 = 1_000;

const _: () = assert!(embassy_time_driver::TICK_HZ == TICK_HZ as u64);
const _: () = assert!(SYSCLK_HZ.is_multiple_of(TICK_HZ) && SYSCLK_HZ / TICK_HZ <= 1 << 24);

struct SysTickDriver {
    /// Milliseconds since [`start`]: 64 bits never wrap.
    ticks: Mutex<Cell<u64>>,
    /// The tick at which the queue's earliest timer is due (`u64::MAX`: none).
    alarm: Mutex<Cell<u64>>,
    queue: Mutex<RefCell<Queue>>,
}

impl Driver for SysTickDriver {
    fn now(&self) -> u64 {
        critical_section::with(|cs| self.ticks.borrow(cs).get())
    }

    fn schedule_wake(&self, at: u64, waker: &Waker) {
        critical_section::with(|cs| {
            let mut queue = self.queue.borrow(cs).borrow_mut();
            if queue.schedule_wake(at, waker) {
                // Wakes what is already due; the rest waits for the tick of the earliest.
                let now = self.ticks.borrow(cs).get();
                self.alarm.borrow(cs).set(queue.next_expiration(now));
            }
        });
    }
}

impl SysTickDriver {
    fn on_tick(&self) {
        critical_section::with(|cs| {
            let ticks = self.ticks.borrow(cs);
            let now = ticks.get() + 1;
            ticks.set(now);
            let alarm = self.alarm.borrow(cs);
            if now >= alarm.get() {
                alarm.set(self.queue.borrow(cs).borrow_mut().next_expiration(now));
            }
        });
    }
}

embassy_time_driver::time_driver_impl!(static DRIVER: SysTickDriver = SysTickDriver {
    ticks: Mutex::new(Cell::new(0)),
    alarm: Mutex::new(Cell::new(u64::MAX)),
    queue: Mutex::new(RefCell::new(Queue::new())),
});

/// Starts the 1 kHz tick. Time reads 0 until the first tick.
pub fn start(mut syst: SYST) {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(SYSCLK_HZ / TICK_HZ - 1);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
}

#[exception]
fn SysTick() {
    DRIVER.on_tick();
}
