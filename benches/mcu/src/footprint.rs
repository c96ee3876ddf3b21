//! The common part of the footprint builds (`footprint_base`, `footprint_driver`,
//! `footprint_serial`, `footprint_bridge`; and `footprint_generic`, whose code
//! `scripts/port-generic.sh` compares), a module of each.
//!
//! `scripts/size-report.sh` builds them and subtracts the base's sizes from each driver's:
//! what remains is what that driver costs a firmware (flash: code and constant data; RAM:
//! static data). All share this skeleton: the vector table, a panic handler, a CAN driver
//! and a serial port whose "hardware" is a handful of volatile reads and writes (so the
//! optimizer can fold nothing away), each used directly by [`skeleton`]. They are never run
//! (the runner refuses them); only their sizes matter.
//!
//! Each program includes this file as a module rather than linking it as a library: a
//! library is compiled apart from the program, which changes how the code around it is laid
//! out and inlined (measured: `footprint_base` alone grew by 8 bytes), and the difference
//! between two of these builds must be the driver's alone.

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

/// A serial port over opaque registers.
#[allow(dead_code)] // each build uses it directly or through its driver
pub struct RegPort;

impl idu_gimbal::port::Uart for RegPort {
    type ReadError = u32;
    type WriteError = u32;

    fn read(&mut self, buf: &mut [u8]) -> Result<usize, u32> {
        match input(11) & 3 {
            0 => Ok(0),
            1 => Err(input(12)),
            _ => {
                let n = (input(12) as usize).min(buf.len());
                for b in &mut buf[..n] {
                    *b = input(13) as u8;
                }
                Ok(n)
            }
        }
    }

    fn write(&mut self, bytes: &[u8]) -> Result<usize, u32> {
        match input(11) & 12 {
            0 => Ok(0),
            4 => Err(input(12)),
            _ => {
                for &b in bytes {
                    output(u32::from(b));
                }
                Ok(bytes.len())
            }
        }
    }
}

/// Uses the CAN stand-in directly, as a firmware's own code would. Each build has each
/// stand-in exactly once, directly or through its driver (base: both directly;
/// `footprint_driver`: the port directly; `footprint_serial`: the CAN driver directly), so
/// neither is charged to a driver.
#[inline(never)]
#[allow(dead_code)] // each build uses one or both
pub fn can_skeleton() {
    use embedded_can::nb::Can;

    match RegCan.receive() {
        Ok(frame) => {
            if let Some(data) = frame.data() {
                output(u32::from(data[0]));
            }
        }
        Err(nb::Error::Other(e)) => output(e as u32),
        Err(nb::Error::WouldBlock) => {}
    }
    if let Some(id) = bxcan::ExtendedId::new(input(5) & 0x1FFF_FFFF) {
        let _ = RegCan.transmit(&bxcan::Frame::new_data(id, input(6).to_le_bytes()));
    }
}

/// Uses the serial stand-in directly (see [`can_skeleton`]).
#[inline(never)]
#[allow(dead_code)] // each build uses one or both
pub fn port_skeleton() {
    use idu_gimbal::port::Uart;

    let mut buf = [0u8; 32];
    match RegPort.read(&mut buf) {
        Ok(n) => output(u32::from(buf[n & 31])),
        Err(e) => output(e),
    }
    let _ = RegPort.write(&input(7).to_le_bytes());
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

/// Drives a CAN link and its port with every kind of call: commands, a rate hold, text,
/// vehicle data, polling, events and counters (`footprint_driver`, and `footprint_bridge`
/// beneath its bridge).
#[allow(dead_code)] // not every build drives the CAN port
#[inline(never)]
pub fn drive(link: &mut idu_gimbal::Link, port: &mut idu_gimbal::CanPort<RegCan>) {
    use idu_gimbal::Port;
    let now = idu_gimbal::Instant::from_millis(input(4));
    command_surface(link, now, |l| l.send_text(b"survey leg 3 done").is_ok());
    output(u32::from(port.poll(link, now).is_ok()));
    events(link, now);
    output(link.stats().postbacks);
}

/// Every kind of call of the command surface, the same on every transport (`send_text`
/// where the transport carries text), chosen by an opaque input.
#[allow(dead_code)] // not every build uses it
#[inline(always)]
pub fn command_surface<const Q: usize, const T: usize, M: idu_gimbal::link::Medium>(
    gimbal: &mut idu_gimbal::Link<Q, T, M>,
    now: idu_gimbal::Instant,
    send_text: impl FnOnce(&mut idu_gimbal::Link<Q, T, M>) -> bool,
) {
    use idu_gimbal::wire::control::{GimbalCommand, Heading, Photo, Pitch, Rate, Video, ZoomRatio};
    use idu_gimbal::wire::vehicle::{Altitude, Attitude, Gps};

    let arg = input(6);
    let a = arg as i16;
    let b = (arg >> 16) as i16;
    let sent = match input(5) & 15 {
        0 => Pitch::from_deci(a).map(|p| gimbal.send(GimbalCommand::Pitch(p)).is_ok()),
        1 => Heading::from_deci(a as u16).map(|h| gimbal.send(GimbalCommand::Heading(h)).is_ok()),
        2 => Ok(gimbal.send(GimbalCommand::Recenter).is_ok()),
        3 => ZoomRatio::from_centi(a as u16)
            .map(|z| gimbal.send(GimbalCommand::ZoomRatio(z)).is_ok()),
        4 => Ok(gimbal.send(GimbalCommand::Photo(Photo::Single)).is_ok()),
        5 => Ok(gimbal.send(GimbalCommand::Video(Video::Start)).is_ok()),
        6 => Ok(gimbal.send(GimbalCommand::Video(Video::Stop)).is_ok()),
        7 => Rate::from_centi(a, b).map(|r| gimbal.set_rate(r, now).is_ok()),
        8 => {
            gimbal.stop_rate();
            Ok(true)
        }
        9 => Ok(send_text(gimbal)),
        10 => Attitude::from_centideg(a, b, 0).map(|att| {
            gimbal.set_attitude(att, now);
            true
        }),
        11 => Gps::from_e7(input(7) as i32, input(8) as i32).map(|g| {
            gimbal.set_gps(g, now);
            true
        }),
        12 => {
            gimbal.set_altitude(Altitude::from_cm(input(7) as i32), now);
            Ok(true)
        }
        _ => Ok(false),
    };
    output(u32::from(sent == Ok(true)));
}

/// The events and the link's state after a poll, the same on every transport.
#[allow(dead_code)] // not every build uses it
#[inline(always)]
pub fn events<const Q: usize, const T: usize, M: idu_gimbal::link::Medium>(
    gimbal: &mut idu_gimbal::Link<Q, T, M>,
    now: idu_gimbal::Instant,
) {
    use idu_gimbal::Event;
    while let Some(event) = gimbal.next_event() {
        output(match event {
            Event::Postback => gimbal
                .latest_postback(now)
                .map_or(0, |(p, _)| p.pitch as u32 ^ u32::from(p.heading)),
            Event::LinkUp => 1,
            Event::LinkDown => 2,
            Event::RateHoldExpired => 3,
            Event::TargetUnreachable { elevation_cdeg } => elevation_cdeg as u32,
            Event::AimNotReached => 4,
        });
    }
    output(u32::from(gimbal.is_link_up()));
}
