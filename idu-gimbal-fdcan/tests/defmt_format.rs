//! The `defmt` encoding of the adapter's frames, captured by a host logger.
#![cfg(feature = "defmt")]

#[path = "../../tests/common/defmt_capture.rs"]
mod defmt_capture;

use defmt_capture::record;

/// The FDCAN adapter's frames are logged with what tells them apart: the ID, its kind,
/// remote or data, and the bytes.
#[test]
fn fdcan_frames_encode_what_tells_them_apart() {
    use embedded_can::{ExtendedId, Frame as _, Id, StandardId};
    use idu_gimbal_fdcan::Frame;
    let ext = |raw| Id::Extended(ExtendedId::new(raw).unwrap());
    let frames = [
        Frame::new(ext(0x030F_0001), &[1, 2, 3]).unwrap(),
        Frame::new(ext(0x030F_0002), &[1, 2, 3]).unwrap(),
        Frame::new(Id::Standard(StandardId::new(0x001).unwrap()), &[1, 2, 3]).unwrap(),
        Frame::new(ext(0x001), &[1, 2, 3]).unwrap(),
        Frame::new(ext(0x030F_0001), &[1, 2, 4]).unwrap(),
        Frame::new_remote(ext(0x030F_0001), 3).unwrap(),
    ];
    let encoded: Vec<Vec<u8>> = frames.iter().map(record).collect();
    assert_eq!(record(&frames[0]), encoded[0]);
    for (i, a) in encoded.iter().enumerate() {
        assert!(!a.is_empty());
        for (j, b) in encoded.iter().enumerate().skip(i + 1) {
            assert_ne!(a, b, "{:?} and {:?} encode alike", frames[i], frames[j]);
        }
    }
}
