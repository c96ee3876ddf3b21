//! The transmit queue's FIFOs: a ring of `N` slots with one-byte indices.
//!
//! Why not heapless: its `Deque` keeps two `usize` indices and a flag, 12 bytes per FIFO on
//! a 32-bit MCU where this keeps 2 (the two FIFOs were 20 of the 92 bytes the crate had to
//! cut to meet its RAM goal). `heapless::Vec` with a `u8` length is as small, but taking
//! from its front moves the rest with `memmove`, and its length conversions carry unwraps
//! whose panic messages format: 2.5 KB more flash in the STM32F405 firmware, measured.
//!
//! `N` is at most 255, checked at compile time.

/// A FIFO that can also take an element back at its front; see the [module docs](self).
#[derive(Clone, Debug)]
pub(crate) struct Ring<T, const N: usize> {
    slots: [T; N],
    /// Index of the first element; below `N` whenever `len > 0`.
    head: u8,
    len: u8,
}

impl<T: Copy, const N: usize> Ring<T, N> {
    /// Fails the build for rings whose indices would not fit a byte.
    const FITS_A_BYTE: () = assert!(N <= 255, "a transmit FIFO has at most 255 slots");

    /// An empty ring; `fill` only initialises the slots.
    pub(crate) const fn new(fill: T) -> Self {
        #[allow(clippy::let_unit_value)] // evaluating the constant is the check
        let () = Self::FITS_A_BYTE;
        Ring {
            slots: [fill; N],
            head: 0,
            len: 0,
        }
    }

    pub(crate) fn len(&self) -> usize {
        usize::from(self.len)
    }

    pub(crate) fn free(&self) -> usize {
        // `len <= N`: exact.
        N.saturating_sub(self.len())
    }

    /// `i` reduced into `0..N`, for `i < 2 * N` (no division). For a power of two (the
    /// default queues) a mask, which also shows the compiler that the index is in bounds.
    #[inline(always)]
    fn wrap(i: usize) -> usize {
        if N.is_power_of_two() {
            // N >= 1: the mask is the constant N - 1.
            i & N.saturating_sub(1)
        } else {
            // One subtraction reduces any `i < 2 * N`.
            i.checked_sub(N).unwrap_or(i)
        }
    }

    /// Appends `x`; hands it back when the ring is full.
    pub(crate) fn push_back(&mut self, x: T) -> Result<(), T> {
        if self.len() >= N {
            return Err(x);
        }
        // Both below 256: the saturating adds here and below never saturate, and fold
        // into plain adds.
        let tail = Self::wrap(usize::from(self.head).saturating_add(self.len()));
        let Some(slot) = self.slots.get_mut(tail) else {
            return Err(x);
        };
        *slot = x;
        self.len = self.len.saturating_add(1);
        Ok(())
    }

    /// Puts `x` before the first element; hands it back when the ring is full.
    pub(crate) fn push_front(&mut self, x: T) -> Result<(), T> {
        if self.len() >= N {
            return Err(x);
        }
        // N > 0 here: the ring is not full. `head + N - 1 < 2 * N`.
        let head = Self::wrap(usize::from(self.head).saturating_add(N.saturating_sub(1)));
        let Some(slot) = self.slots.get_mut(head) else {
            return Err(x);
        };
        *slot = x;
        // head < N <= 255.
        self.head = head as u8;
        self.len = self.len.saturating_add(1);
        Ok(())
    }

    /// Takes the first element.
    pub(crate) fn pop_front(&mut self) -> Option<T> {
        if self.len == 0 {
            return None;
        }
        // `head < N`: `wrap` changes nothing, but for a power of two its mask shows the
        // compiler that the index is in bounds (no bounds check).
        let x = *self.slots.get(Self::wrap(usize::from(self.head)))?;
        self.head = Self::wrap(usize::from(self.head).saturating_add(1)) as u8;
        // Not empty (checked above).
        self.len = self.len.saturating_sub(1);
        Some(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::collections::VecDeque;

    /// Runs `ops` on a ring of `N` and on a `VecDeque` bounded to `N` by hand: every answer
    /// and the contents must agree.
    fn agrees_with_vecdeque<const N: usize>(ops: &[(u8, u16)]) -> Result<(), TestCaseError> {
        let mut ring = Ring::<u16, N>::new(0);
        let mut model = VecDeque::new();
        for &(op, x) in ops {
            match op % 3 {
                push @ (0 | 1) => {
                    let back = push == 0;
                    let expected = if model.len() >= N {
                        Err(x)
                    } else if back {
                        model.push_back(x);
                        Ok(())
                    } else {
                        model.push_front(x);
                        Ok(())
                    };
                    let got = if back {
                        ring.push_back(x)
                    } else {
                        ring.push_front(x)
                    };
                    prop_assert_eq!(got, expected);
                }
                _ => prop_assert_eq!(ring.pop_front(), model.pop_front()),
            }
            prop_assert_eq!(ring.len(), model.len());
            prop_assert_eq!(ring.free(), N - model.len());
        }
        let mut rest = Vec::new();
        while let Some(x) = ring.pop_front() {
            rest.push(x);
        }
        prop_assert_eq!(rest, Vec::from(model));
        Ok(())
    }

    proptest! {
        #[test]
        fn behaves_as_a_bounded_deque(ops in proptest::collection::vec((0u8..3, any::<u16>()), 0..200)) {
            agrees_with_vecdeque::<0>(&ops)?;
            agrees_with_vecdeque::<1>(&ops)?;
            agrees_with_vecdeque::<3>(&ops)?;
            agrees_with_vecdeque::<8>(&ops)?;
            agrees_with_vecdeque::<255>(&ops)?;
        }
    }

    #[test]
    fn wraps_around_the_end() {
        let mut r = Ring::<u8, 3>::new(0);
        for round in 0..10u8 {
            r.push_back(round).unwrap();
            r.push_back(round + 100).unwrap();
            assert_eq!(r.pop_front(), Some(round));
            r.push_front(round + 50).unwrap();
            r.push_back(7).unwrap();
            assert_eq!(r.push_back(0), Err(0)); // full: 3 of 3
            assert_eq!(r.push_front(0), Err(0));
            assert_eq!(r.pop_front(), Some(round + 50));
            assert_eq!(r.pop_front(), Some(round + 100));
            assert_eq!(r.pop_front(), Some(7));
            assert_eq!(r.len(), 0);
        }
    }
}
