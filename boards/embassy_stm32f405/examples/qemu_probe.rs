//! What QEMU's `netduinoplus2` (an emulated STM32F405) lacks for this firmware, shown
//! rather than said. Build with `cargo build --release --example qemu_probe`, run with
//!
//! ```sh
//! timeout 10 qemu-system-arm -cpu cortex-m4 -machine netduinoplus2 -nographic \
//!     -semihosting-config enable=on,target=native -d unimp \
//!     -kernel target/thumbv7em-none-eabihf/release/examples/qemu_probe
//! ```
//!
//! 1. TIM2, the timer of embassy-time's driver (`time-driver-tim2`): QEMU 7.2 models it
//!    (`stm32f2xx_timer`), but only its update event: the counter runs and UIF is set,
//!    CC1IF never is, although the counter passes CCR1 on every period. embassy's driver
//!    counts half periods and fires alarms with capture/compare interrupts.
//! 2. `embassy_stm32::init`: RCC (0x4002_3800) is an unimplemented device in QEMU (reads
//!    0, writes ignored, as `-d unimp` logs): `init` writes RCC_CR.HSION and then spins
//!    forever reading RCC_CR (offset 0x000) for HSIRDY (bit 1). "after" is never printed.
#![no_std]
#![no_main]
use core::ptr::{read_volatile, write_volatile};

use cortex_m_semihosting::{debug, hprintln};
use defmt_rtt as _;
use panic_probe as _;

const TIM2: usize = 0x4000_0000;
const CR1: usize = 0x00;
const DIER: usize = 0x0C;
const SR: usize = 0x10;
const CNT: usize = 0x24;
const PSC: usize = 0x28;
const ARR: usize = 0x2C;
const CCR1: usize = 0x34;

fn reg(offset: usize) -> *mut u32 {
    (TIM2 + offset) as *mut u32
}

#[cortex_m_rt::entry]
fn main() -> ! {
    // SAFETY: TIM2's registers, nothing else uses them yet.
    unsafe {
        write_volatile(reg(PSC), 0);
        write_volatile(reg(ARR), 0xFFFF);
        write_volatile(reg(CCR1), 0x100);
        write_volatile(reg(DIER), 0b11); // UIE | CC1IE
        write_volatile(reg(SR), 0);
        write_volatile(reg(CR1), 1); // CEN
        let mut seen = 0u32;
        let mut cnt_moved = false;
        let first = read_volatile(reg(CNT));
        for _ in 0..2_000_000 {
            seen |= read_volatile(reg(SR));
            cnt_moved |= read_volatile(reg(CNT)) != first;
        }
        hprintln!(
            "TIM2: CNT moves: {}, SR seen {:#06x} (UIF {}, CC1IF {})",
            cnt_moved,
            seen,
            seen & 1 != 0,
            seen & 2 != 0
        );
    }
    hprintln!("before embassy_stm32::init");
    let _p = embassy_stm32::init(Default::default());
    hprintln!("after embassy_stm32::init");
    debug::exit(debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::bkpt();
    }
}
