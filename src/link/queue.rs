//! The transmit queue: control frames before vehicle frames before text.
//!
//! - Control frames wait in a FIFO of `Q` slots. A full FIFO is an error to the caller.
//! - Vehicle frames have one slot per kind (attitude, GPS, altitude): the latest value
//!   wins, so a newer frame replaces one not yet sent (counted as superseded). Within the
//!   class they leave in CAN priority order (attitude `FF13`, GPS `FF15`, altitude `FF16`).
//! - Text frames wait in a FIFO of `T` slots; a text is queued all or nothing.
//!
//! A frame taken for transmission and not accepted by the CAN driver goes back to the front
//! of its class; a frame the driver hands back, displaced from a mailbox, is re-queued the
//! same way (see [`Link::transmit_refused`](super::Link::transmit_refused) and
//! [`Link::transmit_done`](super::Link::transmit_done)).

use crate::wire::{ids, Frame};
use heapless::Deque;

/// The priority class of a frame.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Class {
    /// Control commands (`0x00000F01`).
    Control,
    /// Vehicle frames (attitude, GPS, altitude).
    Vehicle,
    /// Text frames and anything else.
    Text,
}

impl Class {
    /// The class of a frame with this ID.
    pub const fn of(id: u32) -> Class {
        match id {
            ids::CONTROL => Class::Control,
            ids::ATTITUDE | ids::GPS | ids::ALTITUDE => Class::Vehicle,
            _ => Class::Text,
        }
    }
}

const VEHICLE_IDS: [u32; 3] = [ids::ATTITUDE, ids::GPS, ids::ALTITUDE];

fn vehicle_slot(id: u32) -> Option<usize> {
    VEHICLE_IDS.iter().position(|&v| v == id)
}

/// What happened to a frame offered back to the queue.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Requeued {
    /// Back at the front of its class.
    Queued,
    /// A newer vehicle frame of the same kind is waiting: the old one is superseded.
    Superseded,
    /// No room (cannot happen for a frame just popped; see `TxQueue::unpop`).
    NoRoom,
}

/// The transmit queue; see the [module docs](self).
#[derive(Clone, Debug)]
pub struct TxQueue<const Q: usize, const T: usize> {
    control: Deque<Frame, Q>,
    vehicle: [Option<Frame>; 3],
    text: Deque<Frame, T>,
}

impl<const Q: usize, const T: usize> Default for TxQueue<Q, T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const Q: usize, const T: usize> TxQueue<Q, T> {
    /// An empty queue.
    pub const fn new() -> Self {
        TxQueue {
            control: Deque::new(),
            vehicle: [None; 3],
            text: Deque::new(),
        }
    }

    /// Frames waiting.
    pub fn len(&self) -> usize {
        self.control.len() + self.vehicle.iter().flatten().count() + self.text.len()
    }

    /// Whether nothing is waiting.
    pub fn is_empty(&self) -> bool {
        self.control.is_empty() && self.text.is_empty() && self.vehicle.iter().all(Option::is_none)
    }

    /// Free control slots.
    pub fn control_free(&self) -> usize {
        Q - self.control.len()
    }

    /// Free text slots.
    pub fn text_free(&self) -> usize {
        T - self.text.len()
    }

    /// Queues a control frame; hands it back when the FIFO is full.
    pub fn push_control(&mut self, frame: Frame) -> Result<(), Frame> {
        self.control.push_back(frame)
    }

    /// Puts a vehicle frame in its slot. Returns `true` when it replaced an unsent one.
    /// A frame that is not a vehicle frame is handed back.
    pub fn put_vehicle(&mut self, frame: Frame) -> Result<bool, Frame> {
        match vehicle_slot(frame.id).and_then(|i| self.vehicle.get_mut(i)) {
            Some(slot) => Ok(slot.replace(frame).is_some()),
            None => Err(frame),
        }
    }

    /// Queues all of `frames` as text, or none of them when they do not all fit.
    pub fn push_text<I>(&mut self, frames: I) -> Result<(), usize>
    where
        I: ExactSizeIterator<Item = Frame>,
    {
        let need = frames.len();
        if need > self.text_free() {
            return Err(need);
        }
        for f in frames {
            // Room was checked above.
            let _ = self.text.push_back(f);
        }
        Ok(())
    }

    /// The next frame to transmit, removed from the queue.
    pub fn pop(&mut self) -> Option<Frame> {
        if let Some(f) = self.control.pop_front() {
            return Some(f);
        }
        if let Some(f) = self.vehicle.iter_mut().find_map(Option::take) {
            return Some(f);
        }
        self.text.pop_front()
    }

    /// Puts a frame back at the front of its class: for a frame popped and then refused by
    /// the driver (there is always room for it, since it was just popped).
    pub(crate) fn unpop(&mut self, frame: Frame) -> Requeued {
        self.requeue(frame)
    }

    /// Re-queues a frame the CAN driver handed back at the front of its class.
    pub(crate) fn requeue(&mut self, frame: Frame) -> Requeued {
        let result = match Class::of(frame.id) {
            Class::Control => self.control.push_front(frame).map(|()| Requeued::Queued),
            Class::Text => self.text.push_front(frame).map(|()| Requeued::Queued),
            Class::Vehicle => match vehicle_slot(frame.id).and_then(|i| self.vehicle.get_mut(i)) {
                Some(slot @ None) => {
                    *slot = Some(frame);
                    Ok(Requeued::Queued)
                }
                Some(Some(_)) => Ok(Requeued::Superseded),
                None => Err(frame),
            },
        };
        result.unwrap_or(Requeued::NoRoom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f(id: u32, tag: u8) -> Frame {
        Frame::new(id, [tag; 8])
    }

    #[test]
    fn priority_order_and_latest_vehicle_wins() {
        let mut q = TxQueue::<4, 4>::new();
        q.push_text([f(ids::TEXT, 1), f(ids::TEXT_END, 2)].into_iter())
            .unwrap();
        assert_eq!(q.put_vehicle(f(ids::ALTITUDE, 3)), Ok(false));
        assert_eq!(q.put_vehicle(f(ids::GPS, 4)), Ok(false));
        assert_eq!(q.put_vehicle(f(ids::GPS, 5)), Ok(true)); // replaces 4
        assert_eq!(q.put_vehicle(f(ids::ATTITUDE, 6)), Ok(false));
        q.push_control(f(ids::CONTROL, 7)).unwrap();
        q.push_control(f(ids::CONTROL, 8)).unwrap();
        assert_eq!(q.len(), 7); // 2 text, 3 vehicle (GPS replaced in place), 2 control
        let order: Vec<u8> = core::iter::from_fn(|| q.pop()).map(|f| f.data[0]).collect();
        assert_eq!(order, [7, 8, 6, 5, 3, 1, 2]);
        assert!(q.is_empty());
    }

    #[test]
    fn full_control_fifo_hands_the_frame_back() {
        let mut q = TxQueue::<2, 2>::new();
        q.push_control(f(ids::CONTROL, 1)).unwrap();
        q.push_control(f(ids::CONTROL, 2)).unwrap();
        assert_eq!(q.push_control(f(ids::CONTROL, 3)), Err(f(ids::CONTROL, 3)));
        assert_eq!(q.put_vehicle(f(ids::CONTROL, 9)), Err(f(ids::CONTROL, 9)));
    }

    #[test]
    fn text_is_all_or_nothing() {
        let mut q = TxQueue::<2, 3>::new();
        q.push_text([f(ids::TEXT, 1), f(ids::TEXT_END, 2)].into_iter())
            .unwrap();
        assert_eq!(
            q.push_text([f(ids::TEXT, 3), f(ids::TEXT_END, 4)].into_iter()),
            Err(2)
        );
        assert_eq!(q.len(), 2);
    }

    #[test]
    fn requeue_goes_to_the_front_of_its_class() {
        let mut q = TxQueue::<2, 2>::new();
        q.push_text([f(ids::TEXT, 1), f(ids::TEXT_END, 2)].into_iter())
            .unwrap();
        let first = q.pop().unwrap();
        assert_eq!(q.requeue(first), Requeued::Queued);
        assert_eq!(q.pop().unwrap().data[0], 1);
        // A displaced vehicle frame whose slot holds a newer one is superseded.
        q.put_vehicle(f(ids::GPS, 5)).unwrap();
        assert_eq!(q.requeue(f(ids::GPS, 4)), Requeued::Superseded);
        assert_eq!(q.pop(), Some(f(ids::GPS, 5)));
        assert_eq!(q.requeue(f(ids::GPS, 4)), Requeued::Queued);
        // Control back in front of newer control frames.
        q.push_control(f(ids::CONTROL, 8)).unwrap();
        assert_eq!(q.requeue(f(ids::CONTROL, 7)), Requeued::Queued);
        assert_eq!(q.requeue(f(ids::CONTROL, 6)), Requeued::NoRoom);
        assert_eq!(q.pop().unwrap().data[0], 7);
    }
}
