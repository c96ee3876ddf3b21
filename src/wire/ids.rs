//! The protocol's CAN identifiers (all 29-bit extended, DLC 8).

/// Control commands to the gimbal or the dual-light camera (section 2.1).
///
/// Section 1.2 prints it as `0x0000F01`; it is the same ID.
pub const CONTROL: u32 = 0x0000_0F01;
/// Postback from the gimbal: one message in four frames every 500 ms (section 2.2).
pub const POSTBACK: u32 = 0x030F_0001;
/// Vehicle attitude pushed by the flight controller (section 2.3.3).
pub const ATTITUDE: u32 = 0x0000_FF13;
/// Vehicle GPS position pushed by the flight controller (section 2.3.1).
pub const GPS: u32 = 0x0000_FF15;
/// Vehicle altitude pushed by the flight controller (section 2.3.2).
pub const ALTITUDE: u32 = 0x0000_FF16;
/// Text stream: every frame of a text message but the last (section 2.4).
pub const TEXT: u32 = 0x0200_8201;
/// Text stream: the last frame of a text message (section 2.4).
pub const TEXT_END: u32 = 0x0200_8202;

/// The largest valid 29-bit extended identifier.
pub const EXTENDED_MAX: u32 = 0x1FFF_FFFF;

/// Every identifier the protocol uses, in ascending order.
pub const ALL: [u32; 7] = [CONTROL, ATTITUDE, GPS, ALTITUDE, TEXT, TEXT_END, POSTBACK];

/// Identifiers a flight controller receives: what its hardware filters must pass.
pub const FROM_GIMBAL: [u32; 1] = [POSTBACK];

/// Identifiers the gimbal receives: what a simulated gimbal's hardware filters must pass.
pub const TO_GIMBAL: [u32; 6] = [CONTROL, ATTITUDE, GPS, ALTITUDE, TEXT, TEXT_END];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_the_documented_values_and_extended() {
        // Values straight from sections 1.2 and 2.1-2.4 of the vendor document.
        assert_eq!(CONTROL, 0xF01);
        assert_eq!(POSTBACK, 0x030F0001);
        assert_eq!((GPS, ALTITUDE, ATTITUDE), (0xFF15, 0xFF16, 0xFF13));
        assert_eq!((TEXT, TEXT_END), (0x02008201, 0x02008202));
        for id in ALL {
            assert!(id <= EXTENDED_MAX);
        }
        assert!(ALL.windows(2).all(|w| w[0] < w[1]));
        let mut both: heapless::Vec<u32, 7> = heapless::Vec::new();
        for id in FROM_GIMBAL.iter().chain(TO_GIMBAL.iter()) {
            assert!(!both.contains(id));
            both.push(*id).unwrap();
        }
        both.sort_unstable();
        assert_eq!(both.as_slice(), &ALL);
    }
}
