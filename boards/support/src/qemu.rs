//! Support shared by the QEMU firmware (the root crate's example `qemu_demo`,
//! `boards/stm32f405_qemu`'s `qemu_mavlink`, `benches/mcu`'s `qemu_bench` and `qemu_bench_mavlink`,
//! `boards/embassy_qemu`): semihosting output and exit, a panic handler and a HardFault
//! handler that both exit with status 1. Each program brings the STM32F405's interrupt
//! vector table if its cortex-m-rt needs one.
//!
//! QEMU's `netduinoplus2` machine is an STM32F405 without a CAN peripheral. Output goes to
//! the host through ARM semihosting (`-semihosting-config enable=on,target=native`), and
//! `SYS_EXIT` ends QEMU with status 0 (application exit) or 1 (any other reason).

use core::fmt::Write as _;

use cortex_m_rt::{exception, ExceptionFrame};
use cortex_m_semihosting::{debug, hio};

/// Ends the emulation: status 0 when `success`, 1 otherwise.
pub fn exit(success: bool) -> ! {
    debug::exit(if success {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    // Only reached when not running under a semihosting debugger or emulator.
    loop {
        cortex_m::asm::bkpt();
    }
}

/// Writes formatted text to the host's stdout. Output is best effort: a failing host
/// stream must not change the outcome of a run.
pub fn print(args: core::fmt::Arguments<'_>) {
    if let Ok(mut out) = hio::hstdout() {
        let _ = out.write_fmt(args);
    }
}

/// The host's stdout as a `core::fmt::Write`, line-buffered: one host call per line rather
/// than per fragment.
#[derive(Default)]
pub struct Stdout {
    line: heapless::String<256>,
}

impl Stdout {
    fn flush(&mut self) {
        print(format_args!("{}", self.line));
        self.line.clear();
    }
}

impl core::fmt::Write for Stdout {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        for c in s.chars() {
            if self.line.push(c).is_err() {
                self.flush();
                let _ = self.line.push(c);
            }
            if c == '\n' {
                self.flush();
            }
        }
        Ok(())
    }
}

/// `println!` over semihosting.
#[macro_export]
macro_rules! println {
    () => { $crate::qemu::print(format_args!("\n")) };
    ($($arg:tt)*) => { $crate::qemu::print(format_args!("{}\n", format_args!($($arg)*))) };
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo<'_>) -> ! {
    if let Ok(mut err) = hio::hstderr() {
        let _ = writeln!(err, "PANIC: {info}");
    }
    exit(false)
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    if let Ok(mut err) = hio::hstderr() {
        let _ = writeln!(err, "HARD FAULT at pc={:#010x}", frame.pc());
    }
    exit(false)
}
