//! The `defmt` encoding of driver errors, captured by a host logger: every error kind must
//! come out distinct in the log, or an operator cannot tell an acknowledge error (no other
//! node on the bus) from a CRC error (noise).
#![cfg(feature = "defmt")]

use std::sync::Mutex;

use embedded_can::ErrorKind;
use idu_gimbal::port::DriverError;

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

/// Tests take turns: they share the one global logger.
static TURN: Mutex<()> = Mutex::new(());

fn encode(kind: ErrorKind) -> Vec<u8> {
    LOG.lock().unwrap().clear();
    // println: not filtered by DEFMT_LOG, unlike the log levels.
    defmt::println!("{}", DriverError(kind));
    LOG.lock().unwrap().clone()
}

#[test]
fn every_error_kind_has_its_own_encoding() {
    let _turn = TURN.lock().unwrap_or_else(|e| e.into_inner());
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

/// A range error's defmt record carries its value: two out-of-range pitches encode
/// differently, and both differ from an empty record.
#[test]
fn a_range_error_encodes_its_value() {
    use idu_gimbal::wire::control::Pitch;
    let _turn = TURN.lock().unwrap_or_else(|e| e.into_inner());
    let record = |degrees: f32| {
        let e = Pitch::new(degrees).unwrap_err();
        LOG.lock().unwrap().clear();
        defmt::println!("{}", e);
        LOG.lock().unwrap().clone()
    };
    let empty = {
        LOG.lock().unwrap().clear();
        defmt::println!("{}", "");
        LOG.lock().unwrap().clone()
    };
    let (a, b) = (record(200.0), record(300.0));
    assert_ne!(a, b);
    assert!(
        a.len() > empty.len() + 3 * 8,
        "a name and three f64s: {a:?}"
    );
}
