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

/// The CRC continued over `bytes`.
pub fn update(crc: u16, bytes: &[u8]) -> u16 {
    bytes.iter().fold(crc, |crc, &b| step(crc, b))
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
    fn split_anywhere_is_the_same() {
        let data: Vec<u8> = (0u8..=255).collect();
        let whole = update(INIT, &data);
        for cut in 0..data.len() {
            let (a, b) = data.split_at(cut);
            assert_eq!(update(update(INIT, a), b), whole);
        }
    }
}
