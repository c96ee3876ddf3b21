//! The text stream: ASCII information written to the gimbal (section 2.4).
//!
//! A text goes out 8 bytes a frame. Every frame but the last uses ID `0x02008201`; the last
//! uses `0x02008202`. A last chunk shorter than 8 bytes is padded with `00`, which receivers
//! strip, so a text cannot carry `00` itself: [`chunks`] accepts bytes `0x01..=0x7F` only.
//! A text of length 8·k ends with a full frame on `0x02008202`. An empty text has no frame
//! to end it, so it is rejected too.
//!
//! ```
//! use idu_gimbal::wire::{ids, text};
//! let frames: Vec<_> = text::chunks(b"HELLO, GIMBAL")?.collect();
//! assert_eq!(frames.len(), 2);
//! assert_eq!((frames[0].id, &frames[0].data), (ids::TEXT, b"HELLO, G"));
//! assert_eq!((frames[1].id, &frames[1].data), (ids::TEXT_END, b"IMBAL\0\0\0"));
//! # Ok::<(), idu_gimbal::wire::text::TextError>(())
//! ```

use core::fmt;

use super::{ids, Frame};

/// Why a text cannot be sent, or a received text stream was not accepted.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TextError {
    /// The text is empty.
    Empty,
    /// A byte outside `0x01..=0x7F` (non-ASCII, or `00`, which receivers strip).
    InvalidByte {
        /// Position of the byte in the text (or, when receiving, in the message so far).
        index: usize,
        /// The byte.
        byte: u8,
    },
    /// A received text is longer than the assembler's capacity.
    Overflow {
        /// The assembler's capacity in bytes.
        capacity: usize,
    },
    /// A received frame that is not 8 bytes long.
    WrongLength {
        /// Its length.
        len: usize,
    },
    /// A frame whose ID is not a text ID.
    NotText {
        /// The ID.
        id: u32,
    },
}

impl fmt::Display for TextError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TextError::Empty => f.write_str("text is empty: it needs at least one byte"),
            TextError::InvalidByte { index, byte } => {
                write!(
                    f,
                    "byte {byte:#04X} at index {index} is not ASCII 0x01..=0x7F"
                )
            }
            TextError::Overflow { capacity } => write!(f, "text longer than {capacity} bytes"),
            TextError::WrongLength { len } => write!(f, "text frame has {len} bytes, expected 8"),
            TextError::NotText { id } => {
                write!(
                    f,
                    "CAN ID {id:#010X} is not a text ID (0x02008201, 0x02008202)"
                )
            }
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for TextError {}

/// Whether `byte` can travel in a text.
pub const fn is_valid_byte(byte: u8) -> bool {
    byte != 0 && byte.is_ascii()
}

/// Checks that `text` can be sent: non-empty, every byte in `0x01..=0x7F`.
pub fn validate(text: &[u8]) -> Result<(), TextError> {
    if text.is_empty() {
        return Err(TextError::Empty);
    }
    match text.iter().enumerate().find(|&(_, &b)| !is_valid_byte(b)) {
        Some((index, &byte)) => Err(TextError::InvalidByte { index, byte }),
        None => Ok(()),
    }
}

/// How many frames a valid text of `len` bytes takes.
pub const fn frame_count(len: usize) -> usize {
    len.div_ceil(8)
}

/// The frames of a text, in order; see [`chunks`].
#[derive(Clone, Debug)]
pub struct TextChunks<'a> {
    rest: &'a [u8],
}

/// Splits a text into its frames, after checking it with [`validate`].
pub fn chunks(text: &[u8]) -> Result<TextChunks<'_>, TextError> {
    validate(text)?;
    Ok(TextChunks { rest: text })
}

impl Iterator for TextChunks<'_> {
    type Item = Frame;

    fn next(&mut self) -> Option<Frame> {
        if self.rest.is_empty() {
            return None;
        }
        let take = self.rest.len().min(8);
        let (chunk, rest) = self.rest.split_at(take);
        self.rest = rest;
        let mut data = [0u8; 8];
        if let Some(dst) = data.get_mut(..take) {
            dst.copy_from_slice(chunk);
        }
        let id = if rest.is_empty() {
            ids::TEXT_END
        } else {
            ids::TEXT
        };
        Some(Frame::new(id, data))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let n = frame_count(self.rest.len());
        (n, Some(n))
    }
}

impl ExactSizeIterator for TextChunks<'_> {}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn frames_by_hand() {
        // Exactly 8 bytes: one full frame on the END id.
        let f: Vec<_> = chunks(b"ABCDEFGH").unwrap().collect();
        assert_eq!(f, [Frame::new(0x0200_8202, *b"ABCDEFGH")]);
        // 16 bytes: a full frame, then a full END frame.
        let f: Vec<_> = chunks(b"0123456789abcdef").unwrap().collect();
        assert_eq!(
            f,
            [
                Frame::new(0x0200_8201, *b"01234567"),
                Frame::new(0x0200_8202, *b"89abcdef")
            ]
        );
        // One byte: padded with zeros.
        let f: Vec<_> = chunks(b"x").unwrap().collect();
        assert_eq!(f, [Frame::new(0x0200_8202, [b'x', 0, 0, 0, 0, 0, 0, 0])]);
        assert_eq!(chunks(b"0123456789").unwrap().len(), 2);
    }

    #[test]
    fn rejects_empty_nul_and_non_ascii() {
        assert_eq!(chunks(b"").unwrap_err(), TextError::Empty);
        assert_eq!(
            chunks(b"ab\0c").unwrap_err(),
            TextError::InvalidByte { index: 2, byte: 0 }
        );
        assert_eq!(
            chunks("héllo".as_bytes()).unwrap_err(),
            TextError::InvalidByte {
                index: 1,
                byte: 0xC3
            }
        );
    }

    proptest! {
        #[test]
        fn frames_carry_the_text(text in proptest::collection::vec(1u8..=0x7F, 1..100)) {
            let frames: Vec<_> = chunks(&text).unwrap().collect();
            prop_assert_eq!(frames.len(), text.len().div_ceil(8));
            for (i, f) in frames.iter().enumerate() {
                let last = i + 1 == frames.len();
                prop_assert_eq!(f.id, if last { ids::TEXT_END } else { ids::TEXT });
            }
            let mut joined: Vec<u8> = frames.iter().flat_map(|f| f.data).collect();
            while joined.last() == Some(&0) {
                joined.pop();
            }
            prop_assert_eq!(joined, text);
        }
    }
}
