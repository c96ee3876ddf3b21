//! The period of a message the bridge sends on its own: checked when it is made, so that a
//! period of 0, or one too long to be told from a deadline already past, cannot be
//! configured.

use core::fmt;
use core::num::NonZeroU32;

/// How often a message is sent: 1 ms to a minute ([`Period::MAX_MS`]), the range
/// `MAV_CMD_SET_MESSAGE_INTERVAL` takes at run time.
///
/// ```
/// use idu_gimbal_mavlink::{Period, PeriodOutOfRange};
///
/// assert_eq!(Period::from_millis(250).map(Period::millis), Ok(250));
/// assert_eq!(Period::from_millis(0), Err(PeriodOutOfRange(0)));
/// assert_eq!(Period::from_millis(60_001), Err(PeriodOutOfRange(60_001)));
/// ```
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Period(NonZeroU32);

impl Period {
    /// The longest period, ms: a minute.
    pub const MAX_MS: u32 = 60_000;

    /// A period of `ms` milliseconds; an error unless `ms` is 1 to [`Period::MAX_MS`].
    pub const fn from_millis(ms: u32) -> Result<Self, PeriodOutOfRange> {
        match NonZeroU32::new(ms) {
            Some(p) if ms <= Self::MAX_MS => Ok(Period(p)),
            _ => Err(PeriodOutOfRange(ms)),
        }
    }

    /// The period in milliseconds, 1 to [`Period::MAX_MS`].
    pub const fn millis(self) -> u32 {
        self.0.get()
    }
}

/// A period, in milliseconds, outside 1 to [`Period::MAX_MS`].
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PeriodOutOfRange(pub u32);

impl fmt::Display for PeriodOutOfRange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "period of {} ms out of range: 1 to {} ms",
            self.0,
            Period::MAX_MS
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_range_is_1_ms_to_a_minute_inclusive() {
        for ms in [1, 2, 1_000, 59_999, 60_000] {
            assert_eq!(Period::from_millis(ms).map(Period::millis), Ok(ms));
        }
        for ms in [0, 60_001, 1 << 31, u32::MAX] {
            assert_eq!(Period::from_millis(ms), Err(PeriodOutOfRange(ms)));
        }
        assert_eq!(
            PeriodOutOfRange(0).to_string(),
            "period of 0 ms out of range: 1 to 60000 ms"
        );
    }
}
