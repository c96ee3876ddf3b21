//! The `defmt` encoding of driver errors, captured by a host logger: every error kind must
//! come out distinct in the log, or an operator cannot tell an acknowledge error (no other
//! node on the bus) from a CRC error (noise).
#![cfg(feature = "defmt")]

use std::sync::Mutex;

use embedded_can::ErrorKind;
use idu_gimbal::driver::DriverError;

static LOG: Mutex<Vec<u8>> = Mutex::new(Vec::new());

#[defmt::global_logger]
struct Capture;

// SAFETY: one test in this binary logs, and the buffer is behind a mutex anyway.
unsafe impl defmt::Logger for Capture {
    fn acquire() {}
    unsafe fn flush() {}
    unsafe fn release() {}
    unsafe fn write(bytes: &[u8]) {
        LOG.lock().unwrap().extend_from_slice(bytes);
    }
}

// A constant timestamp, so that two records differ only by what they format.
defmt::timestamp!("{=u8}", 0);

fn encode(kind: ErrorKind) -> Vec<u8> {
    LOG.lock().unwrap().clear();
    // println: not filtered by DEFMT_LOG, unlike the log levels.
    defmt::println!("{}", DriverError(kind));
    LOG.lock().unwrap().clone()
}

#[test]
fn every_error_kind_has_its_own_encoding() {
    let kinds = [
        ErrorKind::Overrun,
        ErrorKind::Bit,
        ErrorKind::Stuff,
        ErrorKind::Crc,
        ErrorKind::Form,
        ErrorKind::Acknowledge,
        ErrorKind::Other,
    ];
    let encoded: Vec<Vec<u8>> = kinds.iter().map(|&k| encode(k)).collect();
    // The same kind twice encodes the same: the records differ by kind, not by chance.
    assert_eq!(encode(ErrorKind::Bit), encoded[1]);
    for (i, a) in encoded.iter().enumerate() {
        assert!(!a.is_empty());
        for (j, b) in encoded.iter().enumerate().skip(i + 1) {
            assert_ne!(a, b, "{:?} and {:?} encode alike", kinds[i], kinds[j]);
        }
    }
}
