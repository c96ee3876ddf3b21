//! A host `defmt` logger that keeps what its test binary logs, for the tests of each
//! crate's `defmt` encoding (included by path from the other crates' tests).

use std::sync::Mutex;

static LOG: Mutex<Vec<u8>> = Mutex::new(Vec::new());

/// Records are taken one at a time: the tests of a binary share the one global logger.
static TURN: Mutex<()> = Mutex::new(());

#[defmt::global_logger]
struct Capture;

// SAFETY: `record` logs one value at a time, and the buffer is behind a mutex anyway.
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

/// The bytes `value` logs as.
pub fn record(value: &impl defmt::Format) -> Vec<u8> {
    let _turn = TURN.lock().unwrap_or_else(|e| e.into_inner());
    LOG.lock().unwrap().clear();
    // println: not filtered by DEFMT_LOG, unlike the log levels.
    defmt::println!("{}", value);
    LOG.lock().unwrap().clone()
}
