//! CRC-16/MODBUS, the document's `crc_fly16`.
//!
//! Reflected polynomial 0xA001 (0x8005), initial value 0xFFFF, no final xor; the check
//! value over ASCII `123456789` is `0x4B37`. On the wire the CRC is sent low byte first
//! (the protocol notes: the document's TCP example ends in `68 5E` and the CRC of its first 22 bytes
//! is `0x5E68`).
//!
//! The document computes it with a 16-entry (nibble) table. This crate uses a 256-entry
//! table built at compile time, with the loop unrolled by four: see the measurements below.
//!
//! # Measurements (thumbv7em-none-eabihf, opt-level "s", guest instructions under QEMU)
//!
//! Measured by `benches/mcu/src/bin/qemu_bench.rs` on QEMU's `netduinoplus2` (an STM32F405) with
//! `-icount shift=0`, marginal cost per byte; flash from `arm-none-eabi-nm --size-sort`
//! (see `BENCHMARKS.md`):
//!
//! | implementation | instructions per byte | over 25 bytes (a postback) | flash: code + table |
//! |---|---:|---:|---:|
//! | this module: 256-entry table, unrolled ×4 | **5.5** | 171 | 160 + 512 B |
//! | the document's nibble table (`crc_fly16`) | 13.0 | 343 | 72 + 32 B |
//! | `crc` crate 3.x, `CRC_16_MODBUS` (256 entries) | 9.0 | 244 | 56 + 516 B |
//!
//! The 256-entry table costs about 570 bytes of flash more than the nibble table and is
//! 2.4 times as fast; on a Cortex-M4 with 1 MiB of flash, receiving four frames per
//! postback, that trade is the right one.
//!
//! ```
//! use idu_gimbal::wire::crc;
//! assert_eq!(crc::checksum(b"123456789"), 0x4B37);
//! ```

/// The 256-entry table for the reflected polynomial 0xA001.
static TABLE: [u16; 256] = reflected_table(0xA001);

/// The 256-entry lookup table of a reflected CRC-16 whose polynomial, bit-reversed, is
/// `poly` (0xA001 for this module's CRC-16/MODBUS; other members of the family, such as
/// MAVLink's X.25 with 0x8408, build theirs the same way). Meant for compile time:
///
/// ```
/// use idu_gimbal::wire::crc::reflected_table;
/// static X25: [u16; 256] = reflected_table(0x8408);
/// assert_eq!(X25[1], 0x1189);
/// ```
// Evaluated at compile time: an out-of-bounds index here is a build error, not a panic;
// the loop counters stay below 256 (and at run time the same bounds hold).
#[allow(clippy::indexing_slicing, clippy::arithmetic_side_effects)]
pub const fn reflected_table(poly: u16) -> [u16; 256] {
    let mut table = [0u16; 256];
    let mut i = 0;
    while i < 256 {
        let mut crc = i as u16;
        let mut bit = 0;
        while bit < 8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ poly
            } else {
                crc >> 1
            };
            bit += 1;
        }
        table[i] = crc;
        i += 1;
    }
    table
}

/// The CRC's initial value.
pub const INIT: u16 = 0xFFFF;

#[inline(always)]
fn step(crc: u16, byte: u8) -> u16 {
    // A `u8` index into a 256-entry table is always in bounds; `get` keeps the
    // no-indexing rule and compiles to the same single load.
    let entry = TABLE
        .get(usize::from((crc as u8) ^ byte))
        .copied()
        .unwrap_or(0);
    (crc >> 8) ^ entry
}

/// Continues a CRC over `bytes`, starting from `crc` (use [`INIT`] to start afresh).
///
/// Feeding a message in pieces gives the same result as feeding it whole.
#[inline]
pub fn update(mut crc: u16, bytes: &[u8]) -> u16 {
    // Four bytes an iteration halves the loop overhead per byte on a Cortex-M4.
    let mut quads = bytes.chunks_exact(4);
    for q in &mut quads {
        if let [a, b, c, d] = *q {
            crc = step(step(step(step(crc, a), b), c), d);
        }
    }
    for &byte in quads.remainder() {
        crc = step(crc, byte);
    }
    crc
}

/// The CRC of `bytes` computed at compile time (for constants: the crate uses it to
/// precompute the CRC of the postback's fixed prefix).
// Evaluated at compile time: an out-of-bounds index here is a build error, not a panic.
#[allow(clippy::indexing_slicing)]
pub const fn checksum_const(bytes: &[u8]) -> u16 {
    let mut crc = INIT;
    let mut rest = bytes;
    while let [byte, tail @ ..] = rest {
        crc = (crc >> 8) ^ TABLE[((crc as u8) ^ *byte) as usize];
        rest = tail;
    }
    crc
}

/// The CRC-16/MODBUS of `bytes`.
pub fn checksum(bytes: &[u8]) -> u16 {
    update(INIT, bytes)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The document's `crc_fly16`, transcribed with its nibble table: the independent
    /// reference the crate's tests check CRCs against.
    pub(crate) fn crc_fly16(buf: &[u8]) -> u16 {
        const W: [u16; 16] = [
            0x0000, 0xCC01, 0xD801, 0x1400, 0xF001, 0x3C00, 0x2800, 0xE401, 0xA001, 0x6C00, 0x7800,
            0xB401, 0x5000, 0x9C01, 0x8801, 0x4400,
        ];
        let mut crc: u16 = 0xFFFF;
        for &b in buf {
            let tmp = W[((u16::from(b) ^ crc) & 15) as usize] ^ (crc >> 4);
            crc = W[(((u16::from(b) >> 4) ^ tmp) & 15) as usize] ^ (tmp >> 4);
        }
        crc
    }

    #[test]
    fn check_value() {
        assert_eq!(checksum(b"123456789"), 0x4B37);
        assert_eq!(checksum_const(b"123456789"), 0x4B37);
        assert_eq!(checksum(b""), 0xFFFF);
    }

    #[test]
    fn tcp_example_from_notes() {
        // the protocol notes reference vector: look down 90 degrees over TCP.
        let frame = [
            0xEB, 0x90, 0x0A, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x40, 0x88, 0x0F, 0x07, 0, 0, 0, 0, 0, 0,
            0x68, 0x5E,
        ];
        assert_eq!(checksum(&frame[..22]), 0x5E68);
        // Low byte first on the wire.
        assert_eq!(checksum(&frame[..22]).to_le_bytes(), [0x68, 0x5E]);
        // Residue property of a reflected CRC with its CRC appended low byte first.
        assert_eq!(checksum(&frame), 0);
    }

    proptest! {
        #[test]
        fn matches_the_documents_nibble_algorithm(bytes in proptest::collection::vec(any::<u8>(), 0..80)) {
            prop_assert_eq!(checksum(&bytes), crc_fly16(&bytes));
        }

        #[test]
        fn const_equals_runtime(bytes in proptest::collection::vec(any::<u8>(), 0..80)) {
            prop_assert_eq!(checksum_const(&bytes), checksum(&bytes));
        }

        #[test]
        fn incremental_equals_whole(bytes in proptest::collection::vec(any::<u8>(), 0..80), cut in 0usize..80) {
            let cut = cut.min(bytes.len());
            let (a, b) = bytes.split_at(cut);
            prop_assert_eq!(update(update(INIT, a), b), checksum(&bytes));
        }
    }
}
