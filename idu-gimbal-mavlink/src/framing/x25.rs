//! MAVLink's checksum: CRC-16/MCRF4XX ("X.25" in the MAVLink docs; reflected polynomial
//! 0x1021, initial value 0xFFFF, no final XOR), one table lookup a byte.
//!
//! Stepped here rather than taken from a CRC crate because the frame reader runs it in
//! the same loop that copies each byte into its buffer (see the `framing` module docs);
//! the tests check it against the catalogue's check value and against `mavio`'s checksum.

/// The 256-entry table for the reflected polynomial 0x8408 (built by the core's
/// table builder for its own CRC-16).
static TABLE: [u16; 256] = idu_gimbal::wire::crc::reflected_table(0x8408);

/// The CRC's initial value.
pub const INIT: u16 = 0xFFFF;

/// The CRC continued over one byte.
#[inline(always)]
pub fn step(crc: u16, byte: u8) -> u16 {
    // A `u8` index into a 256-entry table is always in bounds; `get` keeps the
    // no-indexing rule and compiles to the same single load.
    let entry = TABLE
        .get(usize::from((crc as u8) ^ byte))
        .copied()
        .unwrap_or(0);
    (crc >> 8) ^ entry
}

/// The table entry for `index`'s low byte.
#[inline(always)]
fn entry(index: u32) -> u32 {
    TABLE
        .get(index as usize & 0xFF)
        .copied()
        .map_or(0, u32::from)
}

/// The CRC continued over `bytes`, four bytes a load where it can.
pub fn update(crc: u16, bytes: &[u8]) -> u16 {
    // In a u32: entries are below 2^16 and `crc >> 8` below 2^8, so the state never
    // leaves 16 bits, and the compiler need not truncate it at every byte.
    let mut crc = u32::from(crc);
    let words = bytes.chunks_exact(4);
    let rest = words.remainder();
    for w in words {
        let word = w.try_into().map_or(0, u32::from_le_bytes);
        crc = (crc >> 8) ^ entry(crc ^ word);
        crc = (crc >> 8) ^ entry(crc ^ (word >> 8));
        crc = (crc >> 8) ^ entry(crc ^ (word >> 16));
        crc = (crc >> 8) ^ entry(crc ^ (word >> 24));
    }
    for &b in rest {
        crc = (crc >> 8) ^ entry(crc ^ u32::from(b));
    }
    crc as u16
}

/// Copies `src` into `dst` (as many bytes as the shorter has) and continues the CRC over
/// them, in one pass: four bytes a load and a store where it can (the M4 takes unaligned
/// words), the table stepped over each byte of the word from a register.
#[inline(always)]
pub fn copy_update(crc: u16, dst: &mut [u8], src: &[u8]) -> u16 {
    let n = dst.len().min(src.len());
    let (Some(dst), Some(src)) = (dst.get_mut(..n), src.get(..n)) else {
        return crc;
    };
    let mut crc = u32::from(crc);
    let mut dst_words = dst.chunks_exact_mut(4);
    let mut src_words = src.chunks_exact(4);
    for (d, s) in (&mut dst_words).zip(&mut src_words) {
        let word = s.try_into().map_or(0, u32::from_le_bytes);
        d.copy_from_slice(&word.to_le_bytes());
        crc = (crc >> 8) ^ entry(crc ^ word);
        crc = (crc >> 8) ^ entry(crc ^ (word >> 8));
        crc = (crc >> 8) ^ entry(crc ^ (word >> 16));
        crc = (crc >> 8) ^ entry(crc ^ (word >> 24));
    }
    for (d, &b) in dst_words
        .into_remainder()
        .iter_mut()
        .zip(src_words.remainder())
    {
        *d = b;
        crc = (crc >> 8) ^ entry(crc ^ u32::from(b));
    }
    // Never above 16 bits (see `update`).
    crc as u16
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn catalogue_check_value() {
        // CRC-16/MCRF4XX in the CRC catalogue (reveng): check = 0x6F91 over "123456789".
        assert_eq!(update(INIT, b"123456789"), 0x6F91);
    }

    #[test]
    fn copy_update_is_update_and_a_copy() {
        let data: Vec<u8> = (0u8..=255).rev().collect();
        // Every length and every start (words and the bytes left over).
        for start in 0..8 {
            for len in 0..40 {
                let src = &data[start..start + len];
                let mut copy = vec![0u8; len];
                assert_eq!(copy_update(0x1234, &mut copy, src), update(0x1234, src));
                assert_eq!(copy, src);
            }
        }
        // Byte by byte (`step`), the reference the word-wise loops are held to.
        for len in 0..40 {
            let bytes = &data[3..3 + len];
            assert_eq!(
                update(INIT, bytes),
                bytes.iter().fold(INIT, |crc, &b| step(crc, b))
            );
        }
        // A shorter destination takes what fits.
        let mut short = [0u8; 5];
        assert_eq!(
            copy_update(INIT, &mut short, &data),
            update(INIT, &data[..5])
        );
        assert_eq!(
            data.iter().fold(INIT, |crc, &b| step(crc, b)),
            update(INIT, &data)
        );
    }

    #[test]
    fn split_anywhere_is_the_same() {
        let data: Vec<u8> = (0u8..=255).collect();
        let whole = update(INIT, &data);
        for cut in 0..data.len() {
            let (a, b) = data.split_at(cut);
            assert_eq!(update(update(INIT, a), b), whole);
        }
    }
}
