//! The driver against the simulated gimbal on the host: a scripted session of a few
//! simulated seconds with readable telemetry. Exits non-zero if the gimbal did not do what
//! was asked.
//!
//! ```sh
//! cargo run --example host_sim --features mock,std
//! ```

#[path = "common/session.rs"]
mod session;

struct Stdout;

impl core::fmt::Write for Stdout {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        print!("{s}");
        Ok(())
    }
}

fn main() {
    let bus = session::DemoBus::new(42);
    let failures = session::Session::new(&bus, Stdout, 0).map_or(1, session::Session::play);
    std::process::exit(i32::from(failures != 0));
}
