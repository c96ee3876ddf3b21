//! Reassembling text messages from the text stream (section 2.4).
//!
//! ```
//! use idu_gimbal::link::text::TextAssembler;
//! use idu_gimbal::wire::text;
//!
//! let mut asm = TextAssembler::<64>::new();
//! let mut got = None;
//! for frame in text::chunks(b"WAYPOINT 7 REACHED")? {
//!     if let Some(t) = asm.feed(frame.id, &frame.data)? {
//!         got = Some(heapless::String::<64>::try_from(t).unwrap());
//!     }
//! }
//! assert_eq!(got.as_deref(), Some("WAYPOINT 7 REACHED"));
//! # Ok::<(), idu_gimbal::wire::text::TextError>(())
//! ```

use crate::wire::ids;
use crate::wire::text::{is_valid_byte, TextError};

/// What a text assembler has seen.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TextStats {
    /// Complete texts delivered.
    pub messages: u32,
    /// Texts discarded because they were longer than the capacity.
    pub overflows: u32,
    /// Texts discarded because a frame carried an invalid byte or had the wrong length.
    pub invalid: u32,
}

/// Reassembles texts of up to `N` bytes.
///
/// A text longer than `N`, or one with an invalid frame, is discarded up to its end frame:
/// the first error is returned once and counted, and the frames after it are dropped
/// quietly until the end frame, after which the assembler starts afresh.
#[derive(Clone, Debug)]
pub struct TextAssembler<const N: usize> {
    buf: heapless::Vec<u8, N>,
    /// The current text is being discarded up to its end frame.
    skipping: bool,
    /// `buf` holds a text already delivered; clear it before the next frame.
    delivered: bool,
    stats: TextStats,
}

impl<const N: usize> Default for TextAssembler<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> TextAssembler<N> {
    /// An empty assembler.
    pub const fn new() -> Self {
        TextAssembler {
            buf: heapless::Vec::new(),
            skipping: false,
            delivered: false,
            stats: TextStats {
                messages: 0,
                overflows: 0,
                invalid: 0,
            },
        }
    }

    /// The counters so far.
    pub fn stats(&self) -> TextStats {
        self.stats
    }

    /// Bytes of an incomplete text held now.
    pub fn pending(&self) -> usize {
        if self.delivered {
            0
        } else {
            self.buf.len()
        }
    }

    /// Takes one frame. Returns the text when this frame ends one.
    pub fn feed(&mut self, id: u32, data: &[u8]) -> Result<Option<&str>, TextError> {
        let last = match id {
            ids::TEXT => false,
            ids::TEXT_END => true,
            _ => return Err(TextError::NotText { id }),
        };
        if self.delivered {
            self.buf.clear();
            self.delivered = false;
        }
        let result = self.take(data, last);
        if last {
            let skipped = core::mem::take(&mut self.skipping);
            if result.is_ok() && !skipped {
                self.delivered = true;
                self.stats.messages = self.stats.messages.wrapping_add(1);
                return Ok(core::str::from_utf8(&self.buf).ok());
            }
            self.buf.clear();
        }
        result.map(|()| None)
    }

    fn take(&mut self, data: &[u8], last: bool) -> Result<(), TextError> {
        if self.skipping {
            return Ok(());
        }
        let fail = |this: &mut Self, e: TextError| {
            this.skipping = true;
            this.buf.clear();
            match e {
                TextError::Overflow { .. } => {
                    this.stats.overflows = this.stats.overflows.wrapping_add(1)
                }
                _ => this.stats.invalid = this.stats.invalid.wrapping_add(1),
            }
            Err(e)
        };
        let Ok(data) = <&[u8; 8]>::try_from(data) else {
            return fail(self, TextError::WrongLength { len: data.len() });
        };
        // Only the last frame is padded: strip its trailing zeros.
        let mut used: &[u8] = data;
        if last {
            while let [rest @ .., 0] = used {
                used = rest;
            }
        }
        for &byte in used {
            if !is_valid_byte(byte) {
                let index = self.buf.len();
                return fail(self, TextError::InvalidByte { index, byte });
            }
            if self.buf.push(byte).is_err() {
                return fail(self, TextError::Overflow { capacity: N });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wire::text::chunks;
    use proptest::prelude::*;

    fn send<const N: usize>(
        asm: &mut TextAssembler<N>,
        text: &[u8],
    ) -> Vec<Result<Option<String>, TextError>> {
        chunks(text)
            .unwrap()
            .map(|f| asm.feed(f.id, &f.data).map(|o| o.map(String::from)))
            .collect()
    }

    #[test]
    fn overflow_is_an_error_once_and_counted() {
        let mut asm = TextAssembler::<10>::new();
        let r = send(&mut asm, b"0123456789ABCDEFGHIJ");
        assert_eq!(
            r,
            [
                Ok(None),
                Err(TextError::Overflow { capacity: 10 }),
                Ok(None)
            ]
        );
        assert_eq!(
            asm.stats(),
            TextStats {
                messages: 0,
                overflows: 1,
                invalid: 0
            }
        );
        // Exactly the capacity fits, and the assembler starts afresh after the overflow.
        let r = send(&mut asm, b"0123456789");
        assert_eq!(r.last().unwrap(), &Ok(Some("0123456789".into())));
        assert_eq!(asm.stats().messages, 1);
    }

    #[test]
    fn invalid_bytes_and_lengths() {
        let mut asm = TextAssembler::<32>::new();
        assert_eq!(
            asm.feed(ids::TEXT, b"ab\xC3defgh"),
            Err(TextError::InvalidByte {
                index: 2,
                byte: 0xC3
            })
        );
        assert_eq!(asm.feed(ids::TEXT_END, b"zzzzzzzz"), Ok(None)); // rest of the bad text
        assert_eq!(
            asm.feed(ids::TEXT, b"abc"),
            Err(TextError::WrongLength { len: 3 })
        );
        assert_eq!(asm.feed(ids::TEXT_END, b"ok\0\0\0\0\0\0"), Ok(None));
        assert_eq!(asm.feed(ids::TEXT_END, b"ok\0\0\0\0\0\0"), Ok(Some("ok")));
        // A zero inside a middle frame is invalid (only the last frame is padded).
        assert_eq!(
            asm.feed(ids::TEXT, b"ab\0\0\0\0\0\0"),
            Err(TextError::InvalidByte { index: 2, byte: 0 })
        );
        assert_eq!(asm.stats().invalid, 3);
        assert_eq!(
            asm.feed(0x123, b"abcdefgh"),
            Err(TextError::NotText { id: 0x123 })
        );
    }

    #[test]
    fn pending_counts_the_bytes_of_an_incomplete_text() {
        let mut asm = TextAssembler::<32>::new();
        assert_eq!(asm.pending(), 0);
        // Middle frames carry 8 bytes each.
        assert_eq!(asm.feed(ids::TEXT, b"WAYPOINT"), Ok(None));
        assert_eq!(asm.pending(), 8);
        assert_eq!(asm.feed(ids::TEXT, b" 7 REACH"), Ok(None));
        assert_eq!(asm.pending(), 16);
        // A delivered text is not pending, though its bytes are still borrowed.
        assert_eq!(
            asm.feed(ids::TEXT_END, b"ED\0\0\0\0\0\0"),
            Ok(Some("WAYPOINT 7 REACHED"))
        );
        assert_eq!(asm.pending(), 0);
        // A discarded text leaves nothing pending.
        assert_eq!(
            asm.feed(ids::TEXT, b"abc"),
            Err(TextError::WrongLength { len: 3 })
        );
        assert_eq!(asm.pending(), 0);
    }

    proptest! {
        #[test]
        fn round_trip(texts in proptest::collection::vec(proptest::collection::vec(1u8..=0x7F, 1..64), 1..5)) {
            let mut asm = TextAssembler::<64>::new();
            for t in &texts {
                let r = send(&mut asm, t);
                let (last, rest) = r.split_last().unwrap();
                prop_assert!(rest.iter().all(|x| x == &Ok(None)));
                prop_assert_eq!(last, &Ok(Some(String::from_utf8(t.clone()).unwrap())));
            }
            prop_assert_eq!(asm.stats().messages as usize, texts.len());
        }

        #[test]
        fn arbitrary_frames_never_panic(frames in proptest::collection::vec((any::<bool>(), proptest::collection::vec(any::<u8>(), 0..10)), 0..40)) {
            let mut asm = TextAssembler::<16>::new();
            for (end, data) in frames {
                let id = if end { ids::TEXT_END } else { ids::TEXT };
                if let Ok(Some(t)) = asm.feed(id, &data) {
                    prop_assert!(t.len() <= 16 && t.bytes().all(is_valid_byte));
                }
            }
        }
    }
}
