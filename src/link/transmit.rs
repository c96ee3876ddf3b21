//! Transmitting: what leaves next, and what the driver did with it.

use super::*;

/// The frame-level I/O of a CAN link: what a CAN port (or an async or non-`embedded-can`
/// stack of the application's own) moves between the link and the bus. A serial link's
/// frames leave as bytes, through its port, and have no such methods.
impl<const Q: usize, const T: usize> Link<Q, T, Can> {
    /// Takes the next frame to transmit, highest priority first. Report what happened to
    /// it with [`Link::transmit_done`] or [`Link::transmit_refused`].
    #[inline]
    pub fn next_transmit(&mut self) -> Option<Frame> {
        self.next_frame()
    }

    /// The CAN driver accepted the frame last taken. `displaced` is a frame it handed back
    /// (a pending lower-priority frame it took out of a mailbox): it is re-queued, at the
    /// front of its class. A text frame finds no room when texts queued since fill the
    /// text slots: it is counted in [`LinkStats::queue_full`] and lost, and the gimbal may
    /// join the rest of that text to the next. Where texts are queued back to back, keep
    /// `T` above the longest text by the controller's mailboxes (3 on bxCAN).
    #[inline]
    pub fn transmit_done(&mut self, displaced: Option<Frame>) {
        self.frame_done(displaced)
    }

    /// The CAN driver did not take the frame last taken (it was busy or failed): it goes
    /// back to the front of its class. Report it before sending anything more: a command
    /// sent in between can take the slot the frame left, and the frame, finding its class
    /// full, is then lost and counted in [`LinkStats::queue_full`].
    #[inline]
    pub fn transmit_refused(&mut self, frame: Frame) {
        self.frame_refused(frame)
    }

    /// [`Link::transmit_done`] with a frame handed back that no link sends (a standard ID, a
    /// remote frame, not 8 bytes), for a port: it cannot be re-queued, and is counted as a
    /// frame handed back that was not this link's.
    #[cold]
    #[inline(never)]
    pub(crate) fn transmit_done_foreign(&mut self) {
        // Sent, with nothing to re-queue; counted as `displaced` counts a foreign frame.
        self.frame_done(None);
        self.stats.queue_full = self.stats.queue_full.wrapping_add(1);
    }
}

impl<const Q: usize, const T: usize, M: Medium> Link<Q, T, M> {
    /// [`Link::next_transmit`] on any medium, for a port.
    #[inline]
    pub(crate) fn next_frame(&mut self) -> Option<Frame> {
        // Inline: nothing waiting, or a control frame (what most polls that send send).
        if let Some(data) = self.next_control() {
            return Some(Frame::new(ids::CONTROL, data));
        }
        self.next_transmit_after_control()
    }

    /// [`Link::next_transmit`] when it is a control frame (ID [`ids::CONTROL`]): its data.
    /// `None` when nothing waits or the next frame is of another class.
    #[inline]
    pub(crate) fn next_control(&mut self) -> Option<[u8; 8]> {
        if !self.has_transmit() {
            return None;
        }
        self.tx.pop_control()
    }

    /// [`Link::next_transmit`] once [`Link::next_control`] has found no control frame:
    /// `None` in line when nothing waits, the other classes out of line.
    #[inline]
    pub(crate) fn next_transmit_after_control(&mut self) -> Option<Frame> {
        if !self.has_transmit() {
            return None;
        }
        self.next_transmit_other()
    }

    /// [`Link::next_transmit`] past the control frames, out of line: a driver's transmit
    /// loop then keeps nothing of the vehicle values or the text FIFO in registers.
    #[inline(never)]
    pub(super) fn next_transmit_other(&mut self) -> Option<Frame> {
        loop {
            let frame = match self.tx.pop()? {
                queue::Next::Control(data) => Some(Frame::new(ids::CONTROL, data)),
                queue::Next::ZeroRate => Some(Frame::new(ids::CONTROL, queue::zero_rate())),
                // Only a slot holding a value is ever marked (see `requeue`); were one not,
                // the frames behind it would still come out now.
                queue::Next::Vehicle(slot) => {
                    if slot == ATTITUDE {
                        self.attitude_taken();
                    }
                    self.vehicle.value(slot).map(|v| v.to_frame())
                }
                queue::Next::Text(t) => Some(Frame::new(
                    if t.last { ids::TEXT_END } else { ids::TEXT },
                    t.data,
                )),
            };
            if frame.is_some() {
                return frame;
            }
        }
    }

    /// Whether frames wait for transmission.
    #[inline]
    pub fn has_transmit(&self) -> bool {
        !self.tx.is_empty()
    }

    /// [`Link::transmit_done`] on any medium, for a port.
    #[inline]
    pub(crate) fn frame_done(&mut self, displaced: Option<Frame>) {
        self.stats.frames_sent = self.stats.frames_sent.wrapping_add(1);
        if let Some(frame) = displaced {
            self.displaced(frame);
        }
    }

    /// A frame the driver handed back (see [`Link::transmit_done`]), out of line: rare.
    #[inline(never)]
    pub(super) fn displaced(&mut self, frame: Frame) {
        let requeued = self.requeue(frame);
        if requeued != Requeued::Foreign {
            // The displaced frame had been counted as sent; it is not yet.
            self.stats.frames_sent = self.stats.frames_sent.wrapping_sub(1);
        }
        match requeued {
            Requeued::Queued => self.stats.requeued = self.stats.requeued.wrapping_add(1),
            Requeued::Superseded => self.stats.superseded = self.stats.superseded.wrapping_add(1),
            Requeued::NoRoom | Requeued::Foreign => {
                self.stats.queue_full = self.stats.queue_full.wrapping_add(1)
            }
        }
    }

    /// [`Link::transmit_refused`] on any medium, for a port.
    pub(crate) fn frame_refused(&mut self, frame: Frame) {
        if frame.id == ids::ATTITUDE {
            self.attitude_refused();
        }
        match self.requeue(frame) {
            Requeued::Queued => {}
            Requeued::Superseded => self.stats.superseded = self.stats.superseded.wrapping_add(1),
            Requeued::NoRoom | Requeued::Foreign => {
                self.stats.queue_full = self.stats.queue_full.wrapping_add(1)
            }
        }
    }

    pub(super) fn requeue(&mut self, frame: Frame) -> Requeued {
        // A vehicle frame is re-sent from the value the link holds: with none, the frame
        // cannot have been this link's.
        if let queue::Class::Vehicle(slot) = queue::Class::of(frame.id) {
            if !self.vehicle.has(slot) {
                return Requeued::Foreign;
            }
        }
        self.tx.requeue(frame.id, frame.data, &mut self.quiet)
    }
}
