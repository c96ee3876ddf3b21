//! Serial/TCP framing (chapter III): the same frames over the gimbal's UART (115200 8N1),
//! which the serial server bridges to TCP port 2000.
//!
//! A control command travels in a 24-byte frame:
//!
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 3 | `EB 90 0A` (header and length byte; `0x0A` counts bytes 12..=21) |
//! | 3 | 9 | zero |
//! | 12 | 2 | `40 88` |
//! | 14 | 8 | the CAN data bytes of the control frame |
//! | 22 | 2 | CRC-16/MODBUS over bytes 0..=21, low byte first |
//!
//! The postback is taken to travel as its 27 bytes without CAN padding (length byte `0x0C`;
//! the document does not show it, see [`super::postback`]).
//!
//! [`StreamParser`] reads a byte stream with fixed memory: it resyncs on garbage, accepts
//! input split at any byte boundary, and yields a frame only when its CRC holds.
//!
//! ```
//! use idu_gimbal::wire::serial::{self, StreamItem, StreamParser};
//! // Look down 90°, the protocol notes' reference vector.
//! let frame = serial::control_frame(&[0x0F, 0x07, 0, 0, 0, 0, 0, 0]);
//! assert_eq!(&frame[20..], &[0x00, 0x00, 0x68, 0x5E]);
//! let mut parser = StreamParser::new();
//! let mut got = None;
//! for &b in b"noise".iter().chain(frame.iter()) {
//!     got = parser.push(b).or(got);
//! }
//! assert_eq!(got, Some(StreamItem::Control([0x0F, 0x07, 0, 0, 0, 0, 0, 0])));
//! ```

use super::crc;
use super::postback::{self, Postback};

mod field {
    use core::ops::Range;
    // Written whole with the rest of `CONTROL_PREFIX`; named for the layout and its test.
    #[cfg_attr(not(test), allow(dead_code))]
    pub const HEADER: Range<usize> = 0..2;
    pub const LENGTH: usize = 2;
    pub const RESERVED: Range<usize> = 3..12;
    pub const MARKER: Range<usize> = 12..14;
    pub const DATA: Range<usize> = 14..22;
    pub const CHECKED: Range<usize> = 0..22;
    pub const CRC: Range<usize> = 22..24;
}

/// Length of a control frame on the stream.
pub const FRAME_LEN: usize = 24;
/// Length byte of a control frame.
pub const CONTROL_LENGTH_BYTE: u8 = 0x0A;
/// Bytes 12..=13 of a control frame.
pub const MARKER: [u8; 2] = [0x40, 0x88];
/// The longest frame the stream carries (a postback).
pub const MAX_FRAME_LEN: usize = postback::MESSAGE_LEN;

/// A control frame's first 14 bytes: header, length byte, nine zeros, marker.
const CONTROL_PREFIX: [u8; 14] = [
    postback::HEADER[0],
    postback::HEADER[1],
    CONTROL_LENGTH_BYTE,
    0,
    0,
    0,
    0,
    0,
    0,
    0,
    0,
    0,
    MARKER[0],
    MARKER[1],
];

/// The CRC state after [`CONTROL_PREFIX`], computed at compile time: a frame's CRC then
/// costs its 8 data bytes only.
const CONTROL_PREFIX_CRC: u16 = crc::checksum_const(&CONTROL_PREFIX);

/// The 24-byte serial/TCP frame that carries a control frame's 8 CAN data bytes.
pub fn control_frame(can_data: &[u8; 8]) -> [u8; FRAME_LEN] {
    let crc = crc::update(CONTROL_PREFIX_CRC, can_data).to_le_bytes();
    let mut f = [0u8; FRAME_LEN];
    let (prefix, rest) = f.split_at_mut(CONTROL_PREFIX.len());
    prefix.copy_from_slice(&CONTROL_PREFIX);
    let (data, tail) = rest.split_at_mut(can_data.len());
    data.copy_from_slice(can_data);
    tail.copy_from_slice(&crc);
    f
}

/// A frame recovered from the stream.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StreamItem {
    /// A control frame's 8 CAN data bytes (decode them with `control::Command::decode`).
    Control([u8; 8]),
    /// A postback.
    Postback(Postback),
}

/// Counters kept by a [`StreamParser`].
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StreamStats {
    /// Control frames yielded.
    pub control_frames: u32,
    /// Postbacks yielded.
    pub postbacks: u32,
    /// Frames whose header and length were right but whose CRC failed.
    pub crc_errors: u32,
    /// Control frames whose header and length were right but whose fixed bytes (nine
    /// zeros, `40 88`) were not: not a frame of this protocol, whatever the CRC says.
    pub invalid_frames: u32,
    /// Bytes discarded while looking for a header.
    pub skipped_bytes: u32,
    /// Partial frames discarded by [`StreamParser::finish`].
    pub truncated: u32,
}

enum Step {
    More,
    Item(StreamItem),
    /// The buffered bytes are not a frame: drop the first and look again in the rest.
    Resync,
}

/// A fixed-memory parser for the serial/TCP byte stream.
///
/// Feed it bytes in any split; it yields each control frame and postback whose header,
/// length byte and CRC hold. After a bad frame it looks for the next header inside the
/// bytes it already has, so a garbage `EB 90` cannot hide a real frame that follows it.
#[derive(Clone, Debug)]
pub struct StreamParser {
    buf: [u8; MAX_FRAME_LEN],
    len: usize,
    stats: StreamStats,
}

impl Default for StreamParser {
    fn default() -> Self {
        Self::new()
    }
}

impl StreamParser {
    /// A parser waiting for a header.
    pub const fn new() -> Self {
        StreamParser {
            buf: [0; MAX_FRAME_LEN],
            len: 0,
            stats: StreamStats {
                control_frames: 0,
                postbacks: 0,
                crc_errors: 0,
                invalid_frames: 0,
                skipped_bytes: 0,
                truncated: 0,
            },
        }
    }

    /// The counters so far.
    pub fn stats(&self) -> StreamStats {
        self.stats
    }

    /// Bytes of an incomplete frame held now.
    pub fn pending(&self) -> usize {
        self.len
    }

    /// Ends the stream: an incomplete frame is discarded and counted as truncated.
    pub fn finish(&mut self) {
        if self.len > 0 {
            self.stats.truncated = self.stats.truncated.saturating_add(1);
            self.len = 0;
        }
    }

    /// Takes one byte; returns a frame when this byte completes one.
    #[inline]
    pub fn push(&mut self, byte: u8) -> Option<StreamItem> {
        match self.step(byte) {
            Step::More => None,
            Step::Item(item) => Some(item),
            Step::Resync => self.resync(),
        }
    }

    /// The buffered bytes (the one just taken included) are not a frame: drops the first and
    /// examines the rest again, which may hold the start of a frame, or a whole one. Out of
    /// line, with its scratch space: a byte that needs no resync pays for neither (a
    /// parser that set up this space for every byte spent most of its time doing so).
    #[inline(never)]
    fn resync(&mut self) -> Option<StreamItem> {
        // Bytes still to examine: everything in play fits the buffer plus one byte.
        let mut todo = [0u8; MAX_FRAME_LEN + 1];
        let mut start = todo.len();
        let mut out = None;
        loop {
            // Hand back all buffered bytes but the first, ahead of those not yet seen.
            self.stats.skipped_bytes = self.stats.skipped_bytes.saturating_add(1);
            let kept = self.buf.get(1..self.len).unwrap_or(&[]);
            // They fit ahead of `start` (everything in play fits `todo`); the slices are of
            // one length, so the copy has no length check to fail.
            if let Some(new_start) = start.checked_sub(kept.len()) {
                if let Some(dst) = todo.get_mut(new_start..start) {
                    dst.copy_from_slice(kept);
                    start = new_start;
                }
            }
            self.len = 0;
            let mut again = false;
            while let Some(&b) = todo.get(start) {
                // Below `todo.len()` (the byte was there): exact.
                start = start.saturating_add(1);
                match self.step(b) {
                    Step::More => {}
                    Step::Item(item) => out = Some(item),
                    Step::Resync => {
                        again = true;
                        break;
                    }
                }
            }
            if !again {
                return out;
            }
        }
    }

    /// Takes a slice of bytes, yielding the frames it completes, in order.
    pub fn feed<'p, 'b>(&'p mut self, bytes: &'b [u8]) -> Feed<'p, 'b> {
        Feed {
            parser: self,
            bytes: bytes.iter(),
        }
    }

    fn step(&mut self, byte: u8) -> Step {
        let [h0, h1] = postback::HEADER;
        let at = self.len;
        let accept = match at {
            0 => byte == h0,
            1 => byte == h1,
            2 => byte == CONTROL_LENGTH_BYTE || byte == postback::LENGTH_BYTE,
            _ => true,
        };
        if !accept {
            if at == 0 {
                self.stats.skipped_bytes = self.stats.skipped_bytes.saturating_add(1);
                return Step::More;
            }
            // Keep the new byte in the buffer so the resync re-examines it.
            if let Some(slot) = self.buf.get_mut(at) {
                *slot = byte;
                // `at` indexed the buffer: the count stays within it.
                self.len = at.saturating_add(1);
            }
            return Step::Resync;
        }
        match self.buf.get_mut(at) {
            Some(slot) => *slot = byte,
            None => return Step::Resync,
        }
        // `at` indexed the buffer: the count stays within it.
        self.len = at.saturating_add(1);
        let expected = match self.buf.get(field::LENGTH) {
            Some(&CONTROL_LENGTH_BYTE) => FRAME_LEN,
            _ => postback::MESSAGE_LEN,
        };
        // Before the length byte is in, `len` <= 2 is below both frame lengths: the
        // length compare alone waits for it.
        if self.len < expected {
            return Step::More;
        }
        let frame = self.buf.get(..expected).unwrap_or(&[]);
        let item = if expected == FRAME_LEN {
            let fixed = frame
                .get(field::RESERVED)
                .is_some_and(|r| r.iter().all(|&b| b == 0))
                && frame.get(field::MARKER) == Some(&MARKER[..]);
            if !fixed {
                self.stats.invalid_frames = self.stats.invalid_frames.saturating_add(1);
                return Step::Resync;
            }
            let computed = frame.get(field::CHECKED).map_or(0, crc::checksum);
            let received = frame
                .get(field::CRC)
                .and_then(|c| c.try_into().ok())
                .map_or(0, u16::from_le_bytes);
            let data = frame.get(field::DATA).and_then(|d| d.try_into().ok());
            match data {
                Some(data) if computed == received => Some(StreamItem::Control(data)),
                _ => None,
            }
        } else {
            Postback::parse(frame).ok().map(StreamItem::Postback)
        };
        match item {
            Some(item) => {
                self.len = 0;
                match item {
                    StreamItem::Control(_) => {
                        self.stats.control_frames = self.stats.control_frames.saturating_add(1)
                    }
                    StreamItem::Postback(_) => {
                        self.stats.postbacks = self.stats.postbacks.saturating_add(1)
                    }
                }
                Step::Item(item)
            }
            None => {
                self.stats.crc_errors = self.stats.crc_errors.saturating_add(1);
                Step::Resync
            }
        }
    }
}

/// The frames completed by a slice of bytes: see [`StreamParser::feed`].
#[derive(Debug)]
pub struct Feed<'p, 'b> {
    parser: &'p mut StreamParser,
    bytes: core::slice::Iter<'b, u8>,
}

impl Iterator for Feed<'_, '_> {
    type Item = StreamItem;

    fn next(&mut self) -> Option<StreamItem> {
        for &b in self.bytes.by_ref() {
            if let Some(item) = self.parser.push(b) {
                return Some(item);
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wire::postback::tests::{arb_postback, sample};
    use crate::wire::postback::{ControlMode, DataId, GimbalType};
    use proptest::prelude::*;

    /// the protocol notes: look down 90° over TCP, 24 bytes.
    const LOOK_DOWN: [u8; 24] = [
        0xEB, 0x90, 0x0A, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x40, 0x88, 0x0F, 0x07, 0, 0, 0, 0, 0, 0,
        0x68, 0x5E,
    ];

    /// The parser as it was before the resync moved out of line: every byte set up the
    /// scratch space. Kept as the reference the fast path must equal.
    fn reference_push(p: &mut StreamParser, byte: u8) -> Option<StreamItem> {
        let mut todo = [0u8; MAX_FRAME_LEN + 1];
        let mut start = MAX_FRAME_LEN;
        todo[start] = byte;
        let mut out = None;
        while let Some(&b) = todo.get(start) {
            start += 1;
            match p.step(b) {
                Step::More => {}
                Step::Item(item) => out = Some(item),
                Step::Resync => {
                    let keep = p.len.saturating_sub(1);
                    p.stats.skipped_bytes = p.stats.skipped_bytes.saturating_add(1);
                    let new_start = start.saturating_sub(keep);
                    todo[new_start..start].copy_from_slice(&p.buf[1..p.len]);
                    start = new_start;
                    p.len = 0;
                }
            }
        }
        out
    }

    fn parse_all(bytes: &[u8]) -> (Vec<StreamItem>, StreamStats) {
        let mut p = StreamParser::new();
        let items: Vec<_> = p.feed(bytes).collect();
        (items, p.stats())
    }

    /// The precomputed prefix is the documented one, field by field.
    #[test]
    fn control_prefix_is_the_documented_layout() {
        let mut f = [0u8; 14];
        f[field::HEADER].copy_from_slice(&[0xEB, 0x90]);
        f[field::LENGTH] = 0x0A;
        f[field::MARKER].copy_from_slice(&[0x40, 0x88]);
        assert_eq!(CONTROL_PREFIX, f);
        assert_eq!(CONTROL_PREFIX_CRC, crc::checksum(&f));
    }

    proptest! {
        /// The frame's CRC is CRC-16/MODBUS over bytes 0..=21, low byte first, whatever the
        /// data (checked against the document's own nibble-table algorithm).
        #[test]
        fn control_frame_crc_over_any_data(data in any::<[u8; 8]>()) {
            let f = control_frame(&data);
            let crc = crate::wire::crc::tests::crc_fly16(&f[..22]);
            prop_assert_eq!(&f[22..], &crc.to_le_bytes()[..]);
            prop_assert_eq!(&f[14..22], &data[..]);
        }
    }

    #[test]
    fn notes_vector() {
        assert_eq!(control_frame(&[0x0F, 0x07, 0, 0, 0, 0, 0, 0]), LOOK_DOWN);
        let (items, stats) = parse_all(&LOOK_DOWN);
        assert_eq!(items, [StreamItem::Control([0x0F, 0x07, 0, 0, 0, 0, 0, 0])]);
        assert_eq!(stats.control_frames, 1);
    }

    #[test]
    fn the_documents_25_byte_typo_is_not_a_frame() {
        // The document prints ten zeros after 0A; with ten, the CRC cannot hold.
        let mut typo = vec![0xEB, 0x90, 0x0A];
        typo.extend([0u8; 10]);
        typo.extend([0x40, 0x88, 0x0F, 0x07, 0, 0, 0, 0, 0, 0, 0x68, 0x5E]);
        let (items, stats) = parse_all(&typo);
        assert!(items.is_empty());
        // The tenth zero sits where `40` belongs: the fixed bytes are wrong, the CRC never runs.
        assert_eq!((stats.invalid_frames, stats.crc_errors), (1, 0));
    }

    /// The hand-built sample (`wire::postback`'s, its CRC from the document's nibble table)
    /// on the stream: its fields as built.
    #[test]
    fn postback_on_the_stream() {
        let (items, _) = parse_all(&sample()[..27]);
        let [StreamItem::Postback(p)] = items[..] else {
            panic!("{items:?}")
        };
        assert_eq!(
            (p.data_id, p.gimbal_type, p.tracking, p.mode),
            (DataId::Attitude, GimbalType::X30T, true, ControlMode::Lock)
        );
        assert_eq!((p.pitch, p.heading, p.motor_heading), (-4500, 9000, -1234));
    }

    #[test]
    fn false_header_before_a_real_frame() {
        // A garbage `EB 90 0C` claims a postback; the real control frame inside it is found.
        let mut bytes = vec![0xEB, 0x90, 0x0C];
        bytes.extend(LOOK_DOWN);
        let (items, stats) = parse_all(&bytes);
        assert_eq!(items, [StreamItem::Control([0x0F, 0x07, 0, 0, 0, 0, 0, 0])]);
        assert_eq!(stats.crc_errors, 1);
        // EB EB 90 ...: the second EB starts the frame.
        let mut bytes = vec![0xEB];
        bytes.extend(LOOK_DOWN);
        assert_eq!(parse_all(&bytes).0.len(), 1);
    }

    /// Found by `cargo fuzz run stream_parser`: 24 bytes starting `EB 90 0A` whose CRC holds
    /// by chance (1 in 65 536) but whose fixed bytes are not nine zeros and `40 88`.
    #[test]
    fn a_chance_crc_match_with_wrong_fixed_bytes_is_not_a_frame() {
        let mut f = control_frame(&[0x0F, 0x07, 0, 0, 0, 0, 0, 0]);
        f[5] = 0x41; // a reserved byte
        let crc = crc::checksum(&f[..22]).to_le_bytes();
        f[22..].copy_from_slice(&crc); // the CRC holds
        let (items, stats) = parse_all(&f);
        assert!(items.is_empty());
        assert_eq!((stats.invalid_frames, stats.crc_errors), (1, 0));
        let mut g = control_frame(&[0x0F, 0x07, 0, 0, 0, 0, 0, 0]);
        g[13] = 0x89; // the marker
        let crc = crc::checksum(&g[..22]).to_le_bytes();
        g[22..].copy_from_slice(&crc);
        assert!(parse_all(&g).0.is_empty());
        // The fuzzer's input, whole.
        let data: &[u8] = &[
            39, 0, 0, 0, 46, 144, 235, 235, 144, 10, 0, 63, 29, 63, 31, 65, 46, 65, 1, 0, 0, 0,
            235, 144, 10, 0, 0, 65, 65, 235, 144, 10, 42, 235, 144, 10, 46, 144, 235, 144, 10, 0,
            0, 0, 0, 46, 144, 235, 235, 144, 10, 0, 65, 65, 235, 144, 10, 46, 235, 144, 65, 65,
            235, 144, 10, 46, 235, 144, 10, 46, 144, 144, 235, 10, 0, 0, 0, 0, 46, 144, 235, 235,
            144, 10, 0, 65, 65, 235, 144, 10, 46, 144, 235, 235, 144, 10, 0, 65, 65, 235, 144, 10,
            46, 235, 144, 65, 65, 235, 144, 10, 46, 235, 144, 10, 46, 144, 144, 235, 10, 0, 0, 0,
            0, 46, 144, 113, 235, 144, 144, 235, 144, 10, 0, 144, 235, 144, 10, 0, 0, 65,
        ];
        // None of its 15 candidate frames has the fixed bytes: no frame, no CRC run.
        let (items, stats) = parse_all(data);
        assert!(items.is_empty(), "{items:?}");
        assert_eq!((stats.invalid_frames, stats.crc_errors), (15, 0));
    }

    #[test]
    fn truncated_tail() {
        let mut p = StreamParser::new();
        assert_eq!(p.feed(&LOOK_DOWN[..20]).count(), 0);
        assert_eq!(p.pending(), 20);
        p.finish();
        assert_eq!((p.pending(), p.stats().truncated), (0, 1));
        // A new frame after it parses.
        assert_eq!(p.feed(&LOOK_DOWN).count(), 1);
    }

    #[test]
    fn finish_counts_only_a_partial_frame() {
        let mut p = StreamParser::new();
        p.finish();
        assert_eq!(p.stats().truncated, 0);
        assert_eq!(p.feed(&LOOK_DOWN).count(), 1);
        p.finish();
        assert_eq!(p.stats().truncated, 0);
        p.feed(&LOOK_DOWN[..1]).for_each(drop);
        p.finish();
        assert_eq!((p.pending(), p.stats().truncated), (0, 1));
    }

    /// A frame starts `EB 90` and then the length byte of a control frame (`0A`) or a
    /// postback (`0C`): 27 bytes that differ in one of those three, even with a CRC that
    /// holds over them, are skipped, and the frame after them is found.
    #[test]
    fn a_wrong_header_or_length_byte_is_not_a_frame_even_with_a_good_crc() {
        for (at, byte) in [(0, 0xEA), (1, 0x91), (2, 0x0B)] {
            let mut bad: [u8; 27] = sample()[..27].try_into().unwrap();
            bad[at] = byte;
            let crc = crc::checksum(&bad[..25]).to_le_bytes();
            bad[25..].copy_from_slice(&crc);
            let mut bytes = bad.to_vec();
            bytes.extend(LOOK_DOWN);
            let (items, stats) = parse_all(&bytes);
            assert_eq!(
                items,
                [StreamItem::Control([0x0F, 0x07, 0, 0, 0, 0, 0, 0])],
                "byte {at} = {byte:#04X}"
            );
            assert_eq!(
                (stats.postbacks, stats.crc_errors, stats.skipped_bytes),
                (0, 0, 27),
                "byte {at} = {byte:#04X}"
            );
        }
    }

    fn stream_of(frames: &[Vec<u8>], garbage: &[Vec<u8>]) -> Vec<u8> {
        let mut out = Vec::new();
        for (i, f) in frames.iter().enumerate() {
            if let Some(g) = garbage.get(i) {
                out.extend(g);
            }
            out.extend(f);
        }
        out
    }

    proptest! {
        #[test]
        fn every_split_point(cut in 0usize..=24, cut2 in 0usize..=27) {
            let mut p = StreamParser::new();
            let mut items: Vec<_> = p.feed(&LOOK_DOWN[..cut]).collect();
            items.extend(p.feed(&LOOK_DOWN[cut..]));
            let s = sample();
            items.extend(p.feed(&s[..cut2]));
            items.extend(p.feed(&s[cut2..27]));
            prop_assert_eq!(items.len(), 2);
        }

        #[test]
        fn garbage_between_frames(
            datas in proptest::collection::vec(any::<[u8; 8]>(), 1..6),
            pbs in proptest::collection::vec(arb_postback(), 0..4),
            garbage in proptest::collection::vec(proptest::collection::vec(any::<u8>(), 0..40), 10),
        ) {
            let mut frames: Vec<Vec<u8>> = datas.iter().map(|d| control_frame(d).to_vec()).collect();
            frames.extend(pbs.iter().map(|p| p.to_stream_bytes().to_vec()));
            let bytes = stream_of(&frames, &garbage);
            let (items, _) = parse_all(&bytes);
            // Every frame is recovered, in order; garbage may add frames only if it happens
            // to contain a valid one, so look for ours as a subsequence.
            let expected: Vec<StreamItem> = datas.iter().map(|d| StreamItem::Control(*d))
                .chain(pbs.iter().map(|p| StreamItem::Postback(*p))).collect();
            let mut it = items.iter();
            for e in &expected {
                prop_assert!(it.any(|i| i == e), "missing {:?}", e);
            }
        }

        /// The out-of-line resync changes nothing: the same items, counters and state as
        /// the reference, byte by byte, on streams rich in headers, frames and near-frames.
        #[test]
        fn equals_the_reference(parts in proptest::collection::vec(prop_oneof![
            proptest::collection::vec(prop_oneof![any::<u8>(), Just(0xEB), Just(0x90), Just(0x0A), Just(0x0C)], 0..30),
            any::<[u8; 8]>().prop_map(|d| control_frame(&d).to_vec()),
            arb_postback().prop_map(|p| p.to_stream_bytes().to_vec()),
        ], 0..12)) {
            let bytes = parts.concat();
            let (mut fast, mut reference) = (StreamParser::new(), StreamParser::new());
            for &b in &bytes {
                prop_assert_eq!(fast.push(b), reference_push(&mut reference, b));
                prop_assert_eq!(fast.stats(), reference.stats());
                prop_assert_eq!(fast.pending(), reference.pending());
            }
        }

        /// Frames, postbacks and near-frames with one bit flipped anywhere: whatever is
        /// yielded stands whole in the input with its CRC holding (a control frame equal to
        /// the one its data makes, a postback that parses from 27 bytes of the input).
        #[test]
        fn never_yields_a_bad_crc(
            parts in proptest::collection::vec(prop_oneof![
                proptest::collection::vec(prop_oneof![any::<u8>(), Just(0xEB), Just(0x90), Just(0x0A), Just(0x0C)], 0..30),
                any::<[u8; 8]>().prop_map(|d| control_frame(&d).to_vec()),
                arb_postback().prop_map(|p| p.to_stream_bytes().to_vec()),
            ], 1..12),
            flip in any::<(prop::sample::Index, u8)>(),
        ) {
            let mut bytes = parts.concat();
            if !bytes.is_empty() {
                let i = flip.0.index(bytes.len());
                bytes[i] ^= 1 << (flip.1 % 8);
            }
            let (items, _) = parse_all(&bytes);
            for item in items {
                match item {
                    StreamItem::Control(d) => {
                        let f = control_frame(&d);
                        prop_assert!(bytes.windows(24).any(|w| w == f), "{:?}", d);
                    }
                    StreamItem::Postback(p) => {
                        prop_assert!(bytes.windows(27).any(|w| Postback::parse(w) == Ok(p)), "{:?}", p);
                    }
                }
            }
        }

        #[test]
        fn bounded_and_panic_free(chunks in proptest::collection::vec(proptest::collection::vec(any::<u8>(), 0..50), 0..20)) {
            let mut p = StreamParser::new();
            for c in &chunks {
                for _ in p.feed(c) {}
                prop_assert!(p.pending() < MAX_FRAME_LEN);
            }
        }
    }
}
