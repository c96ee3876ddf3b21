//! Footprint baseline: the skeleton of `footprint_driver` without the driver. See
//! `examples/common/footprint.rs` and `scripts/size-report.sh`.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
#[path = "common/footprint.rs"]
mod footprint;

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn main() -> ! {
    use embedded_can::nb::Can;
    use footprint::{input, output, RegCan};

    let mut can = RegCan;
    footprint::use_mem_builtins();
    loop {
        output(input(4));
        match can.receive() {
            Ok(frame) => {
                if let Some(data) = frame.data() {
                    output(u32::from(data[0]));
                }
            }
            Err(nb::Error::Other(e)) => output(e as u32),
            Err(nb::Error::WouldBlock) => {}
        }
        if let Some(id) = bxcan::ExtendedId::new(input(5) & 0x1FFF_FFFF) {
            let _ = can.transmit(&bxcan::Frame::new_data(id, input(6).to_le_bytes()));
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
