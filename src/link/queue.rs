//! The transmit queue: control frames before vehicle frames before text.
//!
//! - Control frames wait in a FIFO of `Q` slots. A full FIFO is an error to the caller.
//! - The zero-rate frame that ends a rate hold needs no slot: it is a flag, sent once the
//!   control FIFO is empty (after the last rate repeats, and after any command queued
//!   behind it), so ending a hold cannot fail for want of room.
//! - Vehicle frames are a pending flag per kind (attitude, GPS, altitude): the frame is
//!   built from the latest value when it leaves, so a newer value always wins over one not
//!   yet sent. Within the class they leave in CAN priority order (attitude `FF13`, GPS
//!   `FF15`, altitude `FF16`).
//! - Text frames wait in a FIFO of `T` slots; a text is queued all or nothing.
//!
//! Slots hold only the 8 data bytes (and, for text, whether the frame ends its message):
//! the ID follows from the class. The two FIFOs are rings with one-byte indices, so `Q` and
//! `T` are at most 255 (checked at compile time).

use super::quiet::Quiet;
use super::ring::Ring;
use crate::wire::ids;

/// A vehicle frame's kind, in CAN priority order: the transmit queue's and the link's
/// vehicle slot.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub(crate) enum VehicleSlot {
    /// Attitude, `0x0000FF13`.
    Attitude = 0,
    /// GPS, `0x0000FF15`.
    Gps = 1,
    /// Altitude, `0x0000FF16`.
    Altitude = 2,
}

impl VehicleSlot {
    /// Every slot, in CAN priority order.
    pub(crate) const ALL: [VehicleSlot; 3] = [
        VehicleSlot::Attitude,
        VehicleSlot::Gps,
        VehicleSlot::Altitude,
    ];

    /// The slot's index (0 to 2), for per-slot arrays.
    #[inline(always)]
    pub(crate) const fn index(self) -> usize {
        self as usize
    }

    /// The slot's bit in a per-slot bit set (bit 0 attitude, 1 GPS, 2 altitude).
    #[inline(always)]
    pub(crate) const fn bit(self) -> u8 {
        1 << self as u8
    }

    /// The slot of the lowest bit set in `bits`, one of the three; what is above them
    /// reads as altitude.
    #[inline(always)]
    const fn lowest(bits: u8) -> VehicleSlot {
        // Tests of the bits, not a count of trailing zeros: the caller's match on the slot
        // then folds into these branches.
        if bits & 1 != 0 {
            VehicleSlot::Attitude
        } else if bits & 2 != 0 {
            VehicleSlot::Gps
        } else {
            VehicleSlot::Altitude
        }
    }
}

/// The priority class of a frame.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub(crate) enum Class {
    /// Control commands (`0x00000F01`).
    Control,
    /// Vehicle frames (attitude, GPS, altitude).
    Vehicle(VehicleSlot),
    /// Text frames.
    Text,
    /// Not a frame this crate sends.
    Foreign,
}

impl Class {
    /// The class of a frame with this ID.
    pub(crate) const fn of(id: u32) -> Class {
        match id {
            ids::CONTROL => Class::Control,
            ids::ATTITUDE => Class::Vehicle(VehicleSlot::Attitude),
            ids::GPS => Class::Vehicle(VehicleSlot::Gps),
            ids::ALTITUDE => Class::Vehicle(VehicleSlot::Altitude),
            ids::TEXT | ids::TEXT_END => Class::Text,
            _ => Class::Foreign,
        }
    }
}

/// One queued text frame.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) struct TextSlot {
    pub(crate) data: [u8; 8],
    /// The last frame of its text (sent on `0x02008202`).
    pub(crate) last: bool,
}

/// What leaves the queue next.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Next {
    Control([u8; 8]),
    ZeroRate,
    Vehicle(VehicleSlot),
    Text(TextSlot),
}

/// The transmit queue; see the [module docs](self).
#[derive(Clone, Debug)]
pub(crate) struct TxQueue<const Q: usize, const T: usize> {
    control: Ring<[u8; 8], Q>,
    text: Ring<TextSlot, T>,
    /// Bit `i` set (0 to 2): vehicle slot `i` waits; [`ZERO_RATE`]: the zero-rate frame
    /// waits.
    flags: u8,
    /// Frames waiting in all three classes, so that "anything to send?" is one compare.
    /// At most `Q + T + 4` (514), and counted with each push and pop: its saturating
    /// steps never saturate.
    waiting: u16,
}

impl<const Q: usize, const T: usize> Default for TxQueue<Q, T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const Q: usize, const T: usize> TxQueue<Q, T> {
    /// An empty queue.
    pub(crate) const fn new() -> Self {
        TxQueue {
            control: Ring::new([0; 8]),
            text: Ring::new(TextSlot {
                data: [0; 8],
                last: false,
            }),
            flags: 0,
            waiting: 0,
        }
    }

    /// Frames waiting.
    #[cfg(test)]
    pub(crate) fn len(&self) -> usize {
        usize::from(self.waiting)
    }

    /// Whether nothing is waiting.
    #[inline]
    pub(crate) fn is_empty(&self) -> bool {
        self.waiting == 0
    }

    /// Free control slots.
    pub(crate) fn control_free(&self) -> usize {
        self.control.free()
    }

    /// Free text slots.
    pub(crate) fn text_free(&self) -> usize {
        self.text.free()
    }

    // Every way in takes the link's quiet word and ends the driver's idle interval in it
    // (`Quiet::hold_idle`): a frame queued must never wait behind a driver's idle check,
    // and no caller can queue one and forget to say so.

    /// Queues a control frame's data; hands it back when the FIFO is full.
    pub(crate) fn push_control(&mut self, data: [u8; 8], quiet: &mut Quiet) -> Result<(), [u8; 8]> {
        self.control.push_back(data)?;
        self.waiting = self.waiting.saturating_add(1);
        quiet.hold_idle();
        Ok(())
    }

    /// Marks vehicle slot `slot` as waiting. Returns `true` when it already was (the value
    /// not yet sent is superseded by the latest).
    pub(crate) fn mark_vehicle(&mut self, slot: VehicleSlot, quiet: &mut Quiet) -> bool {
        quiet.hold_idle();
        self.mark(slot.bit())
    }

    /// Queues the zero-rate frame (once: it is one frame whenever it was asked for).
    /// Returns `true` when it already waited.
    pub(crate) fn mark_zero_rate(&mut self, quiet: &mut Quiet) -> bool {
        quiet.hold_idle();
        self.mark(ZERO_RATE)
    }

    /// Withdraws a waiting zero-rate frame (a newer pointing instruction replaces it).
    pub(crate) fn cancel_zero_rate(&mut self) {
        if self.flags & ZERO_RATE != 0 {
            self.flags &= !ZERO_RATE;
            self.waiting = self.waiting.saturating_sub(1);
        }
    }

    fn mark(&mut self, bit: u8) -> bool {
        let was = self.flags & bit != 0;
        if !was && bit != 0 {
            self.flags |= bit;
            self.waiting = self.waiting.saturating_add(1);
        }
        was
    }

    /// Queues a text's frames (8 data bytes each; the last one ends the text), all of them
    /// or none when they do not all fit. Gives back how many were needed on failure.
    pub(crate) fn push_text<I>(&mut self, frames: I, quiet: &mut Quiet) -> Result<(), usize>
    where
        I: ExactSizeIterator<Item = TextSlot>,
    {
        let need = frames.len();
        if need > self.text_free() {
            return Err(need);
        }
        for f in frames {
            // Room was checked above.
            if self.text.push_back(f).is_ok() {
                self.waiting = self.waiting.saturating_add(1);
            }
        }
        quiet.hold_idle();
        Ok(())
    }

    /// Takes the first control frame, if one waits: what [`TxQueue::pop`] takes first.
    #[inline]
    pub(crate) fn pop_control(&mut self) -> Option<[u8; 8]> {
        let d = self.control.pop_front()?;
        self.waiting = self.waiting.saturating_sub(1);
        Some(d)
    }

    /// Takes what leaves next.
    #[inline]
    pub(crate) fn pop(&mut self) -> Option<Next> {
        if self.waiting == 0 {
            return None;
        }
        let next = if let Some(d) = self.control.pop_front() {
            Next::Control(d)
        } else if self.flags != 0 {
            // The zero-rate frame is a control frame: it leaves before the vehicle frames,
            // though its bit is above theirs.
            if self.flags & ZERO_RATE != 0 {
                self.flags &= !ZERO_RATE;
                Next::ZeroRate
            } else {
                let slot = VehicleSlot::lowest(self.flags);
                self.flags &= !slot.bit();
                Next::Vehicle(slot)
            }
        } else {
            Next::Text(self.text.pop_front()?)
        };
        self.waiting = self.waiting.saturating_sub(1);
        Some(next)
    }

    /// Puts a frame back at the front of its class: for a frame popped and refused by the
    /// driver, or one the driver handed back from a mailbox. A full control or text FIFO
    /// cannot take it back (a frame just popped finds its slot, unless something was
    /// queued between the pop and the refusal), except the zero-rate frame, which needs
    /// no slot. A vehicle frame whose slot is already waiting
    /// again is superseded, not an error.
    pub(crate) fn requeue(&mut self, id: u32, data: [u8; 8], quiet: &mut Quiet) -> Requeued {
        quiet.hold_idle();
        match Class::of(id) {
            Class::Control => match self.control.push_front(data) {
                Ok(()) => {
                    self.waiting = self.waiting.saturating_add(1);
                    Requeued::Queued
                }
                // A zero-rate frame needs no slot.
                Err(data) if data == zero_rate() => {
                    if self.mark(ZERO_RATE) {
                        Requeued::Superseded
                    } else {
                        Requeued::Queued
                    }
                }
                Err(_) => Requeued::NoRoom,
            },
            Class::Text => match self.text.push_front(TextSlot {
                data,
                last: id == ids::TEXT_END,
            }) {
                Ok(()) => {
                    self.waiting = self.waiting.saturating_add(1);
                    Requeued::Queued
                }
                Err(_) => Requeued::NoRoom,
            },
            Class::Vehicle(slot) => {
                if self.mark(slot.bit()) {
                    Requeued::Superseded
                } else {
                    Requeued::Queued
                }
            }
            Class::Foreign => Requeued::Foreign,
        }
    }
}

/// The zero-rate frame's bit in [`TxQueue::flags`].
const ZERO_RATE: u8 = 0b1000;

/// The data of the zero-rate frame: `Command::Gimbal(GimbalCommand::Rate(Rate::ZERO))`
/// encoded (a test checks it), a constant so that comparing with it calls nothing.
const ZERO_RATE_DATA: [u8; 8] = [0x0F, 0x04, 0, 0, 0, 0, 0, 0];

/// The data of the zero-rate frame.
pub(crate) fn zero_rate() -> [u8; 8] {
    ZERO_RATE_DATA
}

/// What happened to a frame offered back to the queue.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Requeued {
    /// Back at the front of its class.
    Queued,
    /// A newer vehicle value of the same kind waits: the old one is superseded.
    Superseded,
    /// No room in its FIFO.
    NoRoom,
    /// Not a frame this crate sends.
    Foreign,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wire::control::{Command, GimbalCommand, Rate};
    use std::vec::Vec;

    /// A quiet word for the queue to hold (what it does with it is tested in `quiet`).
    fn quiet() -> Quiet {
        Quiet::NONE
    }

    fn text(tag: u8, last: bool) -> TextSlot {
        TextSlot {
            data: [tag; 8],
            last,
        }
    }

    fn drain<const Q: usize, const T: usize>(q: &mut TxQueue<Q, T>) -> Vec<Next> {
        core::iter::from_fn(|| q.pop()).collect()
    }

    #[test]
    fn priority_order_and_vehicle_flags() {
        let mut q = TxQueue::<4, 4>::new();
        q.push_text([text(1, false), text(2, true)].into_iter(), &mut quiet())
            .unwrap();
        assert!(!q.mark_vehicle(VehicleSlot::Altitude, &mut quiet()));
        assert!(!q.mark_vehicle(VehicleSlot::Gps, &mut quiet()));
        assert!(
            q.mark_vehicle(VehicleSlot::Gps, &mut quiet()),
            "already waiting: superseded"
        );
        assert!(!q.mark_vehicle(VehicleSlot::Attitude, &mut quiet()));
        q.push_control([7; 8], &mut quiet()).unwrap();
        q.push_control([8; 8], &mut quiet()).unwrap();
        assert_eq!(q.len(), 7); // 2 control, 3 vehicle, 2 text
        assert_eq!(
            drain(&mut q),
            [
                Next::Control([7; 8]),
                Next::Control([8; 8]),
                Next::Vehicle(VehicleSlot::Attitude),
                Next::Vehicle(VehicleSlot::Gps),
                Next::Vehicle(VehicleSlot::Altitude),
                Next::Text(text(1, false)),
                Next::Text(text(2, true)),
            ]
        );
        assert!(q.is_empty());
    }

    proptest::proptest! {
        /// The running count always equals what the three classes hold.
        #[test]
        fn waiting_count_is_exact(ops in proptest::collection::vec(0u8..7, 0..80)) {
            let mut q = TxQueue::<3, 4>::new();
            for op in ops {
                match op {
                    0 => { let _ = q.push_control([op; 8], &mut quiet()); }
                    1 | 2 => { q.mark_vehicle(VehicleSlot::ALL[usize::from(op)], &mut quiet()); }
                    3 => { let _ = q.push_text([text(1, false), text(2, true)].into_iter(), &mut quiet()); }
                    4 => { q.pop(); }
                    5 => { q.requeue(ids::CONTROL, [0; 8], &mut quiet()); }
                    _ => { q.requeue(ids::TEXT_END, [0; 8], &mut quiet()); }
                }
                let held = q.control.len() + q.flags.count_ones() as usize + q.text.len();
                proptest::prop_assert_eq!(q.len(), held);
                proptest::prop_assert_eq!(q.is_empty(), held == 0);
            }
        }
    }

    #[test]
    fn default_slots_are_the_136_bytes_the_size_report_subtracts() {
        use core::mem::size_of;
        assert_eq!(8 * size_of::<[u8; 8]>() + 8 * size_of::<TextSlot>(), 136);
        // Beyond the slots: two bytes of ring indices per FIFO, the flags, the count.
        assert_eq!(size_of::<TxQueue<8, 8>>(), 136 + 8);
    }

    #[test]
    fn zero_rate_data_is_the_zero_rate_command() {
        assert_eq!(
            zero_rate(),
            Command::from(GimbalCommand::Rate(Rate::ZERO)).encode()
        );
    }

    #[test]
    fn full_control_fifo_hands_the_frame_back() {
        let mut q = TxQueue::<2, 2>::new();
        q.push_control([1; 8], &mut quiet()).unwrap();
        q.push_control([2; 8], &mut quiet()).unwrap();
        assert_eq!(q.push_control([3; 8], &mut quiet()), Err([3; 8]));
    }

    #[test]
    fn text_is_all_or_nothing() {
        let mut q = TxQueue::<2, 3>::new();
        q.push_text([text(1, false), text(2, true)].into_iter(), &mut quiet())
            .unwrap();
        assert_eq!(
            q.push_text([text(3, false), text(4, true)].into_iter(), &mut quiet()),
            Err(2)
        );
        assert_eq!(q.len(), 2);
    }

    #[test]
    fn requeue_goes_to_the_front_of_its_class() {
        let mut q = TxQueue::<2, 2>::new();
        q.push_text([text(1, false), text(2, true)].into_iter(), &mut quiet())
            .unwrap();
        let Some(Next::Text(first)) = q.pop() else {
            panic!()
        };
        assert_eq!(
            q.requeue(ids::TEXT, first.data, &mut quiet()),
            Requeued::Queued
        );
        assert_eq!(q.pop(), Some(Next::Text(text(1, false))));
        // The end frame keeps its ID through a requeue.
        assert_eq!(q.pop(), Some(Next::Text(text(2, true))));
        assert_eq!(
            q.requeue(ids::TEXT_END, [2; 8], &mut quiet()),
            Requeued::Queued
        );
        assert_eq!(q.pop(), Some(Next::Text(text(2, true))));
        // A displaced vehicle frame whose slot waits again is superseded.
        q.mark_vehicle(VehicleSlot::Gps, &mut quiet());
        assert_eq!(
            q.requeue(ids::GPS, [0; 8], &mut quiet()),
            Requeued::Superseded
        );
        assert_eq!(q.pop(), Some(Next::Vehicle(VehicleSlot::Gps)));
        assert_eq!(q.requeue(ids::GPS, [0; 8], &mut quiet()), Requeued::Queued);
        // Control goes back in front of newer control frames.
        q.push_control([8; 8], &mut quiet()).unwrap();
        assert_eq!(
            q.requeue(ids::CONTROL, [7; 8], &mut quiet()),
            Requeued::Queued
        );
        assert_eq!(
            q.requeue(ids::CONTROL, [6; 8], &mut quiet()),
            Requeued::NoRoom
        );
        assert_eq!(q.pop(), Some(Next::Control([7; 8])));
        assert_eq!(q.requeue(0x123, [0; 8], &mut quiet()), Requeued::Foreign);
    }

    #[test]
    fn a_cancelled_zero_rate_frame_no_longer_waits() {
        let mut q = TxQueue::<4, 4>::new();
        assert!(!q.mark_zero_rate(&mut quiet()), "it did not wait before");
        assert_eq!(q.len(), 1);
        q.cancel_zero_rate();
        assert_eq!(q.len(), 0);
        assert!(q.is_empty());
        assert!(q.pop().is_none());
        q.cancel_zero_rate(); // nothing waiting: nothing to withdraw
        assert_eq!(q.len(), 0);
    }
}
