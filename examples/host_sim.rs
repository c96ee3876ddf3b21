//! The link and its port against the simulated gimbal on the host: the scripted session of a few
//! simulated seconds with readable telemetry, over CAN and then over the serial line. Exits
//! non-zero if the gimbal did not do what was asked on either.
//!
//! ```sh
//! cargo run --example host_sim --features mock,std
//! ```

struct Stdout;

impl core::fmt::Write for Stdout {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        print!("{s}");
        Ok(())
    }
}

fn main() {
    // The session the QEMU demo (boards/stm32f405_qemu) plays too.
    use idu_firmware_support::session::{CanRig, DemoBus, DemoPipe, Script, SerialRig};
    use idu_gimbal::Instant;

    let bus = DemoBus::new(42);
    let can = CanRig::new(&bus, Instant::from_millis(0))
        .map_or(1, |rig| Script::new(rig, Stdout, 0).play());
    println!();
    let pipe = DemoPipe::new(42);
    let serial = SerialRig::new(&pipe, Instant::from_millis(0))
        .map_or(1, |rig| Script::new(rig, Stdout, 0).play());
    std::process::exit(i32::from(can + serial != 0));
}
