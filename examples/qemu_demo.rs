//! The firmware on an emulated STM32F405 (QEMU `netduinoplus2`) driving a simulated gimbal.
//!
//! The board has no CAN peripheral in QEMU, so the link's port (`CanPort`) and the simulated
//! gimbal (`sim::Simulator`) exchange frames over the crate's in-memory CAN bus
//! (`mock::Bus`) inside the firmware. It plays the scripted session of
//! `idu_firmware_support::session` (shared with `host_sim`): re-center, pitch -45°, heading
//! 90°, a rate hold released to test the dead-man, zoom 10x, photo, recording on and off, a
//! text message, with vehicle data pushed throughout. Then it plays the same session over the
//! serial path: `SerialPort` and `sim::serial::SerialSimulator` on the in-memory serial
//! line (`mock::serial::Pipe`), where headings are nose-referenced and there is no text.
//! Telemetry goes to the host's stdout through semihosting.
//!
//! **Clock.** Time is simulated: each loop iteration advances the link's and the
//! simulator's millisecond tick by exactly 1. Without `-icount`, QEMU's virtual clock (and so
//! SysTick) follows the host's wall clock, which stalls and jumps with host load: a session
//! timed by it would be neither reproducible nor faithful to a real board's 1 kHz tick. The
//! simulated step makes every run identical, on any machine, and as fast as the emulator
//! goes. The real firmware (`boards/stm32f405`'s `stm32f405`) takes its tick from SysTick.
//!
//! Exit status (through semihosting `SYS_EXIT`): 0 only if every step's expected effect was
//! seen on both transports; 1 otherwise, on a panic, or on a HardFault.
//!
//! ```sh
//! scripts/demo.sh   # installs the target and qemu-system-arm when missing, then:
//! cargo run --release --example qemu_demo --target thumbv7em-none-eabihf
//! ```
//!
//! Built from the crate's root: `memory.x` there describes the STM32F405RG and
//! `.cargo/config.toml` links it with cortex-m-rt's `link.x` and runs it on QEMU. On the host
//! this example is a stub that says how to run it.
#![cfg_attr(target_os = "none", no_std, no_main)]

// The STM32F405's interrupt vector table (cortex-m-rt's `device` feature requires one).
#[cfg(target_os = "none")]
use stm32f4xx_hal as _;

/// On the host: what this program is and how to run it.
#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!(
        "qemu_demo is STM32F405 firmware: cargo run --release --example qemu_demo \
         --target thumbv7em-none-eabihf (or scripts/demo.sh, which installs what it needs)"
    );
    std::process::exit(2);
}

#[cfg(target_os = "none")]
mod fw {
    // The scripted session; semihosting output and exit (its panic and HardFault handlers
    // exit with status 1).
    use idu_firmware_support::session::{CanRig, DemoBus, DemoPipe, Script, SerialRig};
    use idu_firmware_support::{println, qemu};
    use idu_gimbal::Instant;

    #[cortex_m_rt::entry]
    fn main() -> ! {
        println!("qemu_demo: STM32F405 (QEMU netduinoplus2), link, port and simulated gimbal on an in-memory CAN bus");
        let out = qemu::Stdout::default;
        let bus = DemoBus::new(42);
        let Some(can) = CanRig::new(&bus, Instant::from_millis(0)) else {
            println!("qemu_demo: could not set up the bus");
            qemu::exit(false)
        };
        let can_failures = Script::new(can, out(), 0).play();
        println!("");
        let pipe = DemoPipe::new(42);
        let Some(serial) = SerialRig::new(&pipe, Instant::from_millis(0)) else {
            println!("qemu_demo: could not set up the serial line");
            qemu::exit(false)
        };
        let serial_failures = Script::new(serial, out(), 0).play();
        let failures = can_failures + serial_failures;
        if failures != 0 {
            println!(
                "qemu_demo: {} step(s) failed over CAN, {} over serial",
                can_failures, serial_failures
            );
        }
        qemu::exit(failures == 0)
    }
}
