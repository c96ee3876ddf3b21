//! Time as the caller's wrapping millisecond tick.
//!
//! The crate never reads a clock: every call that needs the time takes an [`Instant`].
//! An `Instant` wraps around after `u32::MAX` milliseconds (about 49.7 days); comparisons
//! are made on the wrapping difference, so they stay correct across the wrap as long as
//! the two instants compared are less than 2^31 ms (about 24.8 days) apart.
//!
//! ```
//! use idu_gimbal::Instant;
//! let before = Instant::from_millis(u32::MAX - 10);
//! let after = before.add_millis(30); // wrapped to 19
//! assert_eq!(after.as_millis(), 19);
//! assert_eq!(after.millis_since(before), 30);
//! assert!(after.is_at_or_after(before));
//! assert!(!before.is_at_or_after(after));
//! ```

/// A point on the caller's monotonic millisecond clock, wrapping at `u32::MAX`.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Instant(u32);

impl Instant {
    /// The instant whose tick reads `millis`.
    pub const fn from_millis(millis: u32) -> Self {
        Instant(millis)
    }

    /// The raw tick, in milliseconds.
    pub const fn as_millis(self) -> u32 {
        self.0
    }

    /// Milliseconds from `earlier` to `self`, wrapping.
    ///
    /// If `earlier` is in fact later than `self`, the result is a huge number (the wrapped
    /// difference); use [`Instant::is_at_or_after`] to order two instants.
    pub const fn millis_since(self, earlier: Instant) -> u32 {
        self.0.wrapping_sub(earlier.0)
    }

    /// The instant `millis` after `self`, wrapping.
    pub const fn add_millis(self, millis: u32) -> Instant {
        Instant(self.0.wrapping_add(millis))
    }

    /// Whether `self` is at or after `other`, assuming they are less than 2^31 ms apart.
    pub const fn is_at_or_after(self, other: Instant) -> bool {
        // The wrapping difference read as signed: non-negative means "not before".
        (self.0.wrapping_sub(other.0) as i32) >= 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn ordering_holds_across_the_wrap(start: u32, delta in 0u32..(1 << 31)) {
            let a = Instant::from_millis(start);
            let b = a.add_millis(delta);
            prop_assert!(b.is_at_or_after(a));
            prop_assert_eq!(b.millis_since(a), delta);
            if delta != 0 {
                prop_assert!(!a.is_at_or_after(b));
            }
        }
    }
}
