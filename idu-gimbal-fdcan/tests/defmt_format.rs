//! The `defmt` encoding of the adapter's frames, captured by a host logger.
#![cfg(feature = "defmt")]

use std::sync::Mutex;

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

/// The FDCAN adapter's frames are logged with what tells them apart: the ID, its kind,
/// remote or data, and the bytes.
#[test]
fn fdcan_frames_encode_what_tells_them_apart() {
    use embedded_can::{ExtendedId, Frame as _, Id, StandardId};
    use idu_gimbal_fdcan::Frame;
    let _turn = TURN.lock().unwrap_or_else(|e| e.into_inner());
    let record = |frame: Frame| {
        LOG.lock().unwrap().clear();
        defmt::println!("{}", frame);
        LOG.lock().unwrap().clone()
    };
    let ext = |raw| Id::Extended(ExtendedId::new(raw).unwrap());
    let frames = [
        Frame::new(ext(0x030F_0001), &[1, 2, 3]).unwrap(),
        Frame::new(ext(0x030F_0002), &[1, 2, 3]).unwrap(),
        Frame::new(Id::Standard(StandardId::new(0x001).unwrap()), &[1, 2, 3]).unwrap(),
        Frame::new(ext(0x001), &[1, 2, 3]).unwrap(),
        Frame::new(ext(0x030F_0001), &[1, 2, 4]).unwrap(),
        Frame::new_remote(ext(0x030F_0001), 3).unwrap(),
    ];
    let encoded: Vec<Vec<u8>> = frames.iter().map(|&f| record(f)).collect();
    assert_eq!(record(frames[0]), encoded[0]);
    for (i, a) in encoded.iter().enumerate() {
        assert!(!a.is_empty());
        for (j, b) in encoded.iter().enumerate().skip(i + 1) {
            assert_ne!(a, b, "{:?} and {:?} encode alike", frames[i], frames[j]);
        }
    }
}
