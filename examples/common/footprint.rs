//! The common part of the two footprint builds (`footprint_base`, `footprint_driver`).
//!
//! `scripts/size-report.sh` builds both and subtracts their sizes: what remains is what the
//! driver costs a firmware (flash: code and constant data; RAM: static data). Both builds
//! share this skeleton: the vector table, a panic handler, and a CAN driver whose "hardware"
//! is a handful of volatile reads and writes, so the optimizer can fold nothing away.
//! They are never run (the runner refuses them); only their sizes matter.

use core::ptr::{read_volatile, write_volatile};

use bxcan::{ExtendedId, Frame};
use embedded_can::ErrorKind;
// The STM32F405's interrupt vector table.
use stm32f4xx_hal as _;

/// bxcan's CAN1 registers stand in for an opaque source of inputs and sink of outputs.
const IO: *mut u32 = 0x4000_6400 as *mut u32;

/// An opaque input word.
#[inline(always)]
pub fn input(i: usize) -> u32 {
    // SAFETY: a volatile read of a peripheral register (the binary is never run).
    unsafe { read_volatile(IO.add(i & 15)) }
}

/// An opaque output word.
#[inline(always)]
pub fn output(x: u32) {
    // SAFETY: a volatile write to a peripheral register (the binary is never run).
    unsafe { write_volatile(IO.add(16), x) }
}

/// A CAN driver over opaque registers, with bxcan's frame type.
pub struct RegCan;

impl embedded_can::nb::Can for RegCan {
    type Frame = Frame;
    type Error = ErrorKind;

    fn transmit(&mut self, frame: &Frame) -> nb::Result<Option<Frame>, ErrorKind> {
        if input(0) & 4 != 0 {
            return Err(nb::Error::WouldBlock);
        }
        if let bxcan::Id::Extended(id) = frame.id() {
            output(id.as_raw());
        }
        if let Some(data) = frame.data() {
            for &b in data.iter() {
                output(u32::from(b));
            }
        }
        Ok(None)
    }

    fn receive(&mut self) -> nb::Result<Frame, ErrorKind> {
        match input(0) & 3 {
            0 => Err(nb::Error::WouldBlock),
            1 => Err(nb::Error::Other(ErrorKind::Overrun)),
            _ => {
                let id = ExtendedId::new(input(1) & 0x1FFF_FFFF).unwrap_or(ExtendedId::MAX);
                let lo = input(2).to_le_bytes();
                let hi = input(3).to_le_bytes();
                let data = [lo[0], lo[1], lo[2], lo[3], hi[0], hi[1], hi[2], hi[3]];
                Ok(Frame::new_data(id, data))
            }
        }
    }
}

/// Links `memcpy` and `memmove` (compiler-builtins), as virtually every firmware does, so
/// that the difference between the two builds does not charge them to the driver.
#[inline(never)]
pub fn use_mem_builtins() {
    let mut buf = [0u8; 64];
    for (i, b) in buf.iter_mut().enumerate() {
        *b = input(i) as u8;
    }
    let n = input(9) as usize & 31;
    let mut out = [0u8; 64];
    // SAFETY: n <= 31, both ranges lie inside the 64-byte buffers.
    unsafe {
        core::ptr::copy_nonoverlapping(buf.as_ptr(), out.as_mut_ptr(), n);
        core::ptr::copy(
            out.as_ptr(),
            out.as_mut_ptr().add(input(10) as usize & 31),
            n,
        );
    }
    for b in out {
        output(u32::from(b));
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo<'_>) -> ! {
    cortex_m::asm::udf()
}
