//! The CAN port: a [`Link`] over any `embedded-can` 0.4 driver.
//!
//! [`CanPort`] is thin: it moves frames between the CAN driver and the link, converts them
//! to and from the driver's frame type, and counts what the driver reports.

use core::fmt;

use embedded_can::{nb::Can, ErrorKind, ExtendedId, Frame as _, Id};

use super::Port;
use crate::link::{Can as CanMedium, Link};
use crate::time::Instant;
use crate::wire::Frame;

/// The one ID the port takes frames on; every other frame is counted as ignored.
const POSTBACK_ID: Id = match ExtendedId::new(crate::wire::ids::POSTBACK) {
    Some(id) => Id::Extended(id),
    // Evaluated at compile time: an ID beyond 29 bits would not build.
    None => panic!("the postback ID is a 29-bit ID"),
};

/// The ID of control frames, checked once (at compile time): the transmit path builds the
/// CAN driver's frame with it and need not check it again.
const CONTROL_ID: ExtendedId = match ExtendedId::new(crate::wire::ids::CONTROL) {
    Some(id) => id,
    // Evaluated at compile time: an ID beyond 29 bits would not build.
    None => panic!("the control ID is a 29-bit ID"),
};

/// CAN driver errors by kind.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DriverErrors {
    /// `ErrorKind::Overrun`.
    pub overrun: u32,
    /// `ErrorKind::Bit`.
    pub bit: u32,
    /// `ErrorKind::Stuff`.
    pub stuff: u32,
    /// `ErrorKind::Crc`.
    pub crc: u32,
    /// `ErrorKind::Form`.
    pub form: u32,
    /// `ErrorKind::Acknowledge`.
    pub acknowledge: u32,
    /// `ErrorKind::Other` and kinds added to `embedded-can` later.
    pub other: u32,
}

impl DriverErrors {
    fn count(&mut self, kind: ErrorKind) {
        let c = match kind {
            ErrorKind::Overrun => &mut self.overrun,
            ErrorKind::Bit => &mut self.bit,
            ErrorKind::Stuff => &mut self.stuff,
            ErrorKind::Crc => &mut self.crc,
            ErrorKind::Form => &mut self.form,
            ErrorKind::Acknowledge => &mut self.acknowledge,
            _ => &mut self.other,
        };
        *c = c.wrapping_add(1);
    }

    /// All errors counted.
    pub fn total(&self) -> u32 {
        [
            self.overrun,
            self.bit,
            self.stuff,
            self.crc,
            self.form,
            self.acknowledge,
            self.other,
        ]
        .iter()
        .fold(0u32, |a, &b| a.wrapping_add(b))
    }
}

/// What a [`CanPort`] counts; the link counts the rest ([`Link::stats`]).
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CanPortStats {
    /// CAN driver errors by kind.
    pub driver_errors: DriverErrors,
}

/// A CAN driver error seen during [`CanPort::poll`](Port::poll). The poll still did all
/// its work.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct DriverError(pub ErrorKind);

impl fmt::Display for DriverError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "CAN driver error: {}", self.0)
    }
}

#[cfg(feature = "defmt")]
impl defmt::Format for DriverError {
    fn format(&self, f: defmt::Formatter<'_>) {
        let kind = match self.0 {
            ErrorKind::Overrun => "overrun",
            ErrorKind::Bit => "bit",
            ErrorKind::Stuff => "stuff",
            ErrorKind::Crc => "crc",
            ErrorKind::Form => "form",
            ErrorKind::Acknowledge => "acknowledge",
            _ => "other",
        };
        defmt::write!(f, "CAN driver error: {=str}", kind)
    }
}

#[cfg(feature = "std")]
impl std::error::Error for DriverError {}

/// The CAN port: a gimbal's [`Link`] on a CAN bus, driven through `C`.
///
/// ```
/// # #[cfg(feature = "mock")] {
/// use idu_gimbal::mock::Bus;
/// use idu_gimbal::port::{CanPort, Port};
/// use idu_gimbal::wire::control::{GimbalCommand, Pitch};
/// use idu_gimbal::{Config, Instant, Link};
///
/// let bus: Bus<2, 16> = Bus::new(1);
/// let mut link: Link = Link::new(Config::default());
/// let mut port = CanPort::new(bus.endpoint(0).unwrap());
/// link.send(GimbalCommand::Pitch(Pitch::new(-45.0).unwrap())).unwrap();
/// port.poll(&mut link, Instant::from_millis(0)).unwrap();
/// assert_eq!(link.stats().frames_sent, 1);
/// assert_eq!(port.stats().driver_errors.total(), 0);
/// # }
/// ```
pub struct CanPort<C> {
    can: C,
    errors: DriverErrors,
}

impl<C: Can> CanPort<C> {
    /// A port over the CAN driver `can`.
    pub fn new(can: C) -> Self {
        CanPort {
            can,
            errors: DriverErrors::default(),
        }
    }

    /// [`Port::poll`]'s receive loop: every frame the CAN driver has, up to the bound;
    /// the first error it reported.
    #[inline(always)]
    fn receive_all<const Q: usize, const T: usize>(
        &mut self,
        link: &mut Link<Q, T, CanMedium>,
        now: Instant,
    ) -> Option<DriverError> {
        let mut first_error = None;
        // At least one receive (the bound is not zero): no guard before the first. One
        // call site only, so that the CAN driver's `receive` can be inlined.
        let mut left = u32::from(link.config().max_rx_per_poll.get());
        loop {
            match self.can.receive() {
                // The ID first: a foreign frame costs one compare and a count.
                Ok(frame) if frame.id() == POSTBACK_ID && frame.is_data_frame() => {
                    let data = frame.data();
                    match <&[u8; 8]>::try_from(data) {
                        // In registers: the frame need not be copied to the stack.
                        Ok(d) => link.receive_postback_u64(now, u64::from_le_bytes(*d)),
                        Err(_) => link.receive_malformed(),
                    }
                }
                Ok(_) => link.receive_ignored(),
                Err(nb::Error::WouldBlock) => break,
                Err(nb::Error::Other(e)) => {
                    let e = self.driver_error(&e);
                    first_error.get_or_insert(e);
                }
            }
            // At least 1 here (the bound is not zero, and the loop ends at 0): never wraps,
            // and the plain subtraction keeps the per-frame path short.
            left = left.wrapping_sub(1);
            if left == 0 {
                break;
            }
        }
        first_error
    }

    /// [`Port::poll`] as if its idle check never held: what the check is tested against.
    #[cfg(test)]
    pub(super) fn poll_without_idle_check<const Q: usize, const T: usize>(
        &mut self,
        link: &mut Link<Q, T, CanMedium>,
        now: Instant,
    ) -> Result<(), DriverError> {
        let first_error = self.receive_all(link, now);
        self.poll_busy(link, now, first_error)
    }

    /// [`Port::poll`] past its receive loop when the idle check did not hold: the link's
    /// schedules, then whatever waits to be sent.
    #[inline(always)]
    fn poll_busy<const Q: usize, const T: usize>(
        &mut self,
        link: &mut Link<Q, T, CanMedium>,
        now: Instant,
        first_error: Option<DriverError>,
    ) -> Result<(), DriverError> {
        link.poll_for_port(now);
        if link.has_transmit() {
            // A tail call: the result is `transmit`'s.
            return self.transmit(link, first_error);
        }
        link.release_idle();
        first_error.map_or(Ok(()), Err)
    }

    /// Transmits until the queue is empty or the CAN driver is busy; the poll's result
    /// given `first_error`, the first error its receive loop saw (it wins over any seen
    /// here). Out of line: an idle poll then saves only the registers the receive loop
    /// needs.
    #[inline(never)]
    fn transmit<const Q: usize, const T: usize>(
        &mut self,
        link: &mut Link<Q, T, CanMedium>,
        first_error: Option<DriverError>,
    ) -> Result<(), DriverError> {
        loop {
            // A control frame (what most polls that send send) with its ID known valid;
            // then the others, in the order of `Link::next_transmit`, with theirs checked.
            let (id, data) = if let Some(data) = link.next_control() {
                (CONTROL_ID, data)
            } else if let Some(frame) = link.next_transmit_after_control() {
                let Some(id) = ExtendedId::new(frame.id) else {
                    // Every queued frame has a valid 29-bit extended ID. Counted whatever
                    // the receive loop saw; its first error still wins.
                    let e = self.unsendable();
                    return Err(first_error.unwrap_or(e));
                };
                (id, frame.data)
            } else {
                return first_error.map_or(Ok(()), Err);
            };
            if let Err(e) = self.transmit_frame(link, id, data) {
                return first_error.or(e).map_or(Ok(()), Err);
            }
        }
    }

    /// Hands one frame, just taken from the link, to the CAN driver and reports to the
    /// link. `Err` ends the transmission: the CAN driver is busy (`None`; the frame is back
    /// in the queue) or failed (the frame is back in the queue too), or its frame type
    /// cannot hold the frame (dropped and counted: queued again, it would stop every frame
    /// behind it at every poll).
    #[inline(always)]
    fn transmit_frame<const Q: usize, const T: usize>(
        &mut self,
        link: &mut Link<Q, T, CanMedium>,
        id: ExtendedId,
        data: [u8; 8],
    ) -> Result<(), Option<DriverError>> {
        let Some(can_frame) = C::Frame::new(id, &data) else {
            // A CAN driver whose frame type refuses an extended frame of 8 bytes cannot
            // send it. The frames behind it go at the next poll, however soon.
            link.hold_idle();
            return Err(Some(self.unsendable()));
        };
        match self.can.transmit(&can_frame) {
            Ok(None) => {
                link.transmit_done(None);
                Ok(())
            }
            Ok(Some(displaced)) => {
                match displaced.id() {
                    Id::Extended(id) => match <[u8; 8]>::try_from(displaced.data()) {
                        Ok(data) => link.transmit_done(Some(Frame::new(id.as_raw(), data))),
                        Err(_) => link.transmit_done_foreign(),
                    },
                    Id::Standard(_) => link.transmit_done_foreign(),
                }
                Ok(())
            }
            Err(e) => Err(self.refused(link, Frame::new(id.as_raw(), data), e)),
        }
    }

    /// The CAN driver did not take `frame`: it goes back to the queue, and an error is
    /// counted. Out of line: rare.
    #[inline(never)]
    fn refused<const Q: usize, const T: usize>(
        &mut self,
        link: &mut Link<Q, T, CanMedium>,
        frame: Frame,
        e: nb::Error<C::Error>,
    ) -> Option<DriverError> {
        link.transmit_refused(frame);
        match e {
            nb::Error::WouldBlock => None,
            nb::Error::Other(e) => Some(self.driver_error(&e)),
        }
    }

    /// A CAN driver error, from a receive or a transmit: counted. Out of line, so that the
    /// receive loop keeps no counter in a register.
    #[cold]
    #[inline(never)]
    fn driver_error(&mut self, e: &C::Error) -> DriverError {
        let kind = embedded_can::Error::kind(e);
        self.errors.count(kind);
        DriverError(kind)
    }

    /// A frame the CAN driver's frame type cannot represent: counted, never silent.
    #[cold]
    fn unsendable(&mut self) -> DriverError {
        self.errors.count(ErrorKind::Other);
        DriverError(ErrorKind::Other)
    }

    /// What the port counts (the link counts the rest).
    pub fn stats(&self) -> CanPortStats {
        CanPortStats {
            driver_errors: self.errors,
        }
    }

    /// The CAN driver.
    pub fn can(&self) -> &C {
        &self.can
    }

    /// The CAN driver, for what the port does not do with it: its controller's error
    /// counters, interrupts, filters (`idu_gimbal_fdcan::FdCan::inner`, say). Frames
    /// received or sent through it pass the link by: a postback taken here never reaches
    /// it, and a frame sent here is not in its counts.
    pub fn can_mut(&mut self) -> &mut C {
        &mut self.can
    }

    /// Gives back the CAN driver.
    pub fn release(self) -> C {
        self.can
    }
}

impl<C: Can> Port for CanPort<C> {
    type Medium = CanMedium;
    type Error = DriverError;

    /// Receives pending frames (at most [`Config::max_rx_per_poll`](crate::Config)), runs
    /// the link's schedules, and transmits queued frames until the CAN driver is busy.
    ///
    /// A CAN driver error is counted and the poll goes on: after a receive error it
    /// receives on and runs the schedules; a transmit error ends this poll's transmitting
    /// (the frame is queued again for the next poll). A frame the CAN driver's frame type
    /// refuses to build (`Frame::new` gives `None` for an extended ID and 8 bytes, a driver
    /// defect) is dropped, counted as `other` and reported as `ErrorKind::Other`: queued
    /// again, it would stop every frame behind it. The first error seen is returned at
    /// the end.
    #[inline]
    fn poll<const Q: usize, const T: usize>(
        &mut self,
        link: &mut Link<Q, T, CanMedium>,
        now: Instant,
    ) -> Result<(), DriverError> {
        let first_error = self.receive_all(link, now);
        // Unless nothing is due and nothing waits to be sent (one compare for both).
        if !link.is_idle(now) {
            return self.poll_busy(link, now, first_error);
        }
        first_error.map_or(Ok(()), Err)
    }

    fn next_deadline<const Q: usize, const T: usize>(
        &self,
        link: &Link<Q, T, CanMedium>,
        now: Instant,
    ) -> Instant {
        if link.has_transmit() {
            now
        } else {
            link.next_deadline(now)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_id_constant_is_the_control_id() {
        assert_eq!(
            CONTROL_ID,
            ExtendedId::new(crate::wire::ids::CONTROL).unwrap()
        );
    }

    /// A CAN driver that takes every frame and hands back, each time, the next of `back`
    /// (as a driver hands back a lower-priority frame it took out of a mailbox).
    #[cfg(feature = "mock")]
    struct HandsBack {
        back: std::vec::Vec<crate::mock::MockFrame>,
        sent: std::vec::Vec<crate::mock::MockFrame>,
    }

    #[cfg(feature = "mock")]
    impl Can for HandsBack {
        type Frame = crate::mock::MockFrame;
        type Error = ErrorKind;

        fn transmit(
            &mut self,
            frame: &Self::Frame,
        ) -> nb::Result<Option<Self::Frame>, Self::Error> {
            self.sent.push(*frame);
            Ok(if self.back.is_empty() {
                None
            } else {
                Some(self.back.remove(0))
            })
        }

        fn receive(&mut self) -> nb::Result<Self::Frame, Self::Error> {
            Err(nb::Error::WouldBlock)
        }
    }

    /// A frame handed back that no link sends (a standard ID, a remote frame, fewer than 8
    /// bytes) cannot be re-queued: it is counted with the frames handed back that were not
    /// the link's (`queue_full`), never dropped without a word; the link's own frame
    /// handed back is re-queued and sent again.
    #[cfg(feature = "mock")]
    #[test]
    fn a_handed_back_frame_no_link_sends_is_counted() {
        use crate::link::Config;
        use crate::mock::MockFrame;
        use crate::wire::control::{Command, GimbalCommand, Pitch};

        let pitch = |deg| GimbalCommand::Pitch(Pitch::new(deg).unwrap());
        let remote = <MockFrame as embedded_can::Frame>::new_remote(
            ExtendedId::new(crate::wire::ids::CONTROL).unwrap(),
            8,
        )
        .unwrap();
        // The first command, handed back after the driver took it.
        let own = MockFrame::extended(
            crate::wire::ids::CONTROL,
            &Command::from(pitch(-10.0)).encode(),
        )
        .unwrap();
        let mut port = CanPort::new(HandsBack {
            back: std::vec![
                MockFrame::standard(0x123, &[0; 8]).unwrap(),
                remote,
                MockFrame::extended(crate::wire::ids::CONTROL, &[1, 2, 3, 4]).unwrap(),
                own,
            ],
            sent: std::vec::Vec::new(),
        });
        let mut link: Link = Link::new(Config::default());
        for deg in [-10.0, -20.0, -30.0, -40.0] {
            link.send(pitch(deg)).unwrap();
        }
        port.poll(&mut link, Instant::from_millis(0)).unwrap();

        let stats = link.stats();
        assert_eq!(stats.queue_full, 3, "the three frames no link sends");
        assert_eq!(stats.requeued, 1, "the link's own frame");
        // Four commands, the first taken again after it was handed back; counted as sent
        // once each.
        assert_eq!(port.can().sent.len(), 5);
        assert_eq!(port.can().sent.first(), Some(&own));
        assert_eq!(port.can().sent.last(), Some(&own));
        assert_eq!(stats.frames_sent, 4);
        assert_eq!(port.stats().driver_errors.total(), 0);
        assert!(!link.has_transmit());
    }

    /// A frame type that holds no extended frame of 8 bytes: a defective CAN driver.
    #[derive(Debug)]
    struct NoExtendedFrame;

    impl embedded_can::Frame for NoExtendedFrame {
        fn new(id: impl Into<Id>, _data: &[u8]) -> Option<Self> {
            match id.into() {
                Id::Extended(_) => None,
                Id::Standard(_) => Some(NoExtendedFrame),
            }
        }
        fn new_remote(_id: impl Into<Id>, _dlc: usize) -> Option<Self> {
            None
        }
        fn is_extended(&self) -> bool {
            false
        }
        fn is_remote_frame(&self) -> bool {
            false
        }
        fn id(&self) -> Id {
            Id::Standard(embedded_can::StandardId::ZERO)
        }
        fn dlc(&self) -> usize {
            0
        }
        fn data(&self) -> &[u8] {
            &[]
        }
    }

    /// A CAN driver whose frame type cannot hold the link's frames; it sends nothing.
    struct CannotHold {
        transmits: usize,
    }

    impl Can for CannotHold {
        type Frame = NoExtendedFrame;
        type Error = ErrorKind;

        fn transmit(
            &mut self,
            _frame: &Self::Frame,
        ) -> nb::Result<Option<Self::Frame>, Self::Error> {
            self.transmits += 1;
            Ok(None)
        }

        fn receive(&mut self) -> nb::Result<Self::Frame, Self::Error> {
            Err(nb::Error::WouldBlock)
        }
    }

    /// A frame the CAN driver's frame type cannot build is dropped, counted as `other` and
    /// reported, one per poll: queued again, it would stop the frames behind it forever.
    /// The next poll, however soon (`next_deadline` is `now` while a frame waits), takes
    /// the next frame.
    #[test]
    fn a_frame_the_drivers_frame_type_cannot_hold_is_dropped_and_counted() {
        use crate::link::Config;
        use crate::wire::control::{GimbalCommand, Pitch};

        let mut port = CanPort::new(CannotHold { transmits: 0 });
        let mut link: Link = Link::new(Config::default());
        for deg in [-10.0, -20.0] {
            link.send(GimbalCommand::Pitch(Pitch::new(deg).unwrap()))
                .unwrap();
        }
        let other = DriverError(ErrorKind::Other);
        assert_eq!(port.poll(&mut link, Instant::from_millis(0)), Err(other));
        assert_eq!(port.stats().driver_errors.other, 1);
        assert_eq!(port.stats().driver_errors.total(), 1);
        assert!(link.has_transmit(), "the second waits for the next poll");
        assert_eq!(port.poll(&mut link, Instant::from_millis(1)), Err(other));
        assert_eq!(port.stats().driver_errors.other, 2);
        assert!(!link.has_transmit());
        assert_eq!(port.poll(&mut link, Instant::from_millis(2)), Ok(()));
        assert_eq!(port.can().transmits, 0, "nothing reached the driver");
        assert_eq!(link.stats().frames_sent, 0);
    }

    #[test]
    fn postback_id_constant_is_the_postback_id() {
        assert_eq!(
            POSTBACK_ID,
            Id::Extended(ExtendedId::new(crate::wire::ids::POSTBACK).unwrap())
        );
    }
}
