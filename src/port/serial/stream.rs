//! The serial stream: a [`SerialLink`](crate::link::SerialLink)'s bytes in and out, with no I/O.
//!
//! [`SerialStream`] is the sans-IO core of the serial port ([`SerialPort`](super::SerialPort)
//! is it plus a UART). The link keeps everything it keeps on CAN (queue and priorities,
//! rate hold and dead-man, aims and point-at, health, events, counters); the stream puts a
//! byte stream where CAN frames were:
//!
//! - **Out**: each control frame the link hands out becomes the 24-byte serial frame
//!   ([`wire::serial::control_frame`](crate::wire::serial::control_frame)). A frame of which
//!   any byte was written is finished before the next one starts, so frames are never
//!   interleaved; a frame of which nothing could be written goes back to the link's queue
//!   (the port was not ready), so a command queued meanwhile with a higher priority still
//!   goes first.
//! - **In**: bytes in any split go through a [`StreamParser`]; each postback is taken in its
//!   27-byte stream form (header, length byte `0x0C`, CRC), as the protocol notes assumes: the
//!   vendor document does not show the postback on the stream. Garbage is skipped and
//!   counted.
//!
//! What the serial link cannot carry (vehicle frames, text) is in its type: see
//! [`link::medium`](crate::link::medium).
//!
//! ```
//! use idu_gimbal::link::{Config, Event, SerialLink};
//! use idu_gimbal::port::SerialStream;
//! use idu_gimbal::wire::control::{GimbalCommand, Pitch};
//! use idu_gimbal::wire::postback::Postback;
//! use idu_gimbal::Instant;
//!
//! let mut link: SerialLink = SerialLink::new(Config::default());
//! let mut stream = SerialStream::new();
//! let now = Instant::from_millis(0);
//! link.send(GimbalCommand::Pitch(Pitch::new(-45.0)?)).unwrap();
//! link.poll(now);
//!
//! // A UART that takes 10 bytes now and the rest later: the frame is finished, not lost.
//! let bytes = stream.transmit_bytes(&mut link);
//! assert_eq!(bytes.len(), 24);
//! assert_eq!(&bytes[..3], &[0xEB, 0x90, 0x0A]);
//! assert_eq!(&bytes[14..22], &[0x0F, 0x08, 0x02, 0x3E, 0xFE, 0, 0, 0]);
//! stream.transmit_written(&mut link, 10);
//! assert_eq!(stream.transmit_bytes(&mut link).len(), 14);
//! stream.transmit_written(&mut link, 14);
//! assert!(stream.transmit_bytes(&mut link).is_empty());
//!
//! // A postback in its stream form, split anywhere, after line noise.
//! let bytes = Postback { pitch: -4500, ..Postback::default() }.to_stream_bytes();
//! stream.receive(&mut link, &[0x00, 0x13], now);
//! stream.receive(&mut link, &bytes[..5], now);
//! stream.receive(&mut link, &bytes[5..], now);
//! assert_eq!(link.next_event(), Some(Event::LinkUp));
//! assert_eq!(link.latest_postback(now).map(|(p, _age)| p.pitch), Some(-4500));
//! assert_eq!(stream.stats().stream.skipped_bytes, 2);
//! # Ok::<(), idu_gimbal::wire::RangeError>(())
//! ```

use crate::link::{Link, Serial};
use crate::time::Instant;
use crate::wire::serial::{control_frame, StreamItem, StreamParser, StreamStats, FRAME_LEN};
use crate::wire::{ids, Frame};

/// Where the frame being written stands.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Out {
    /// No frame: the next [`SerialStream::transmit_bytes`] takes one from the link.
    Idle,
    /// Taken from the link, nothing written yet: it can still go back to the queue.
    Taken,
    /// Partly written: it is finished before anything else goes out.
    Started,
}

/// What a [`SerialStream`] counts; the link counts the rest. The stream's counters
/// saturate, the byte counts wrap at `u32::MAX`.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SerialStreamStats {
    /// The stream parser's counters: frames, CRC errors, invalid frames, skipped bytes.
    /// Every byte received is in a frame yielded, skipped, or still pending.
    pub stream: StreamStats,
    /// Bytes received.
    pub bytes_received: u32,
    /// Bytes written.
    pub bytes_sent: u32,
}

/// The sans-IO serial stream of one [`SerialLink`](crate::link::SerialLink); see the [module docs](self).
#[derive(Clone, Debug)]
pub struct SerialStream {
    parser: StreamParser,
    out: [u8; FRAME_LEN],
    /// Bytes of `out` written (0..=24).
    written: u8,
    state: Out,
    bytes_received: u32,
    bytes_sent: u32,
}

impl Default for SerialStream {
    fn default() -> Self {
        Self::new()
    }
}

impl SerialStream {
    /// A stream with nothing received and nothing being written.
    pub const fn new() -> Self {
        SerialStream {
            parser: StreamParser::new(),
            out: [0; FRAME_LEN],
            written: 0,
            state: Out::Idle,
            bytes_received: 0,
            bytes_sent: 0,
        }
    }

    /// Takes received bytes, in any split: each complete postback reaches `link`.
    pub fn receive<const Q: usize, const T: usize>(
        &mut self,
        link: &mut Link<Q, T, Serial>,
        bytes: &[u8],
        now: Instant,
    ) {
        // `as`: a slice longer than u32::MAX bytes wraps the counter, as every counter does.
        self.bytes_received = self.bytes_received.wrapping_add(bytes.len() as u32);
        for item in self.parser.feed(bytes) {
            match item {
                StreamItem::Postback(p) => link.receive_whole_postback(p, now),
                // A gimbal sends no control frames: an echo or another controller.
                StreamItem::Control(_) => link.receive_ignored(),
            }
        }
    }

    /// The bytes to write next: the rest of the frame being written, or the next frame
    /// `link` hands out; empty when nothing waits. Report how many were written with
    /// [`SerialStream::transmit_written`].
    pub fn transmit_bytes<const Q: usize, const T: usize>(
        &mut self,
        link: &mut Link<Q, T, Serial>,
    ) -> &[u8] {
        if self.state == Out::Idle {
            // Only control frames are ever queued on a serial link: it schedules no
            // vehicle frames and has no text slots.
            if let Some(frame) = link.next_frame() {
                self.out = control_frame(&frame.data);
                self.written = 0;
                self.state = Out::Taken;
            }
        }
        match self.state {
            Out::Idle => &[],
            Out::Taken | Out::Started => self.out.get(usize::from(self.written)..).unwrap_or(&[]),
        }
    }

    /// `n` bytes of those [`SerialStream::transmit_bytes`] returned were written (more than
    /// it returned counts as all of them). With `n == 0` a frame of which nothing was
    /// written goes back to the front of the link's queue; once any byte of a frame is
    /// written the frame is the link's last word until finished. Report before sending
    /// anything more on `link`: a command sent in between can take the slot the frame
    /// left, and a frame that finds its class full is lost and counted in
    /// [`LinkStats::queue_full`](crate::link::LinkStats::queue_full).
    pub fn transmit_written<const Q: usize, const T: usize>(
        &mut self,
        link: &mut Link<Q, T, Serial>,
        n: usize,
    ) {
        match self.state {
            Out::Idle => {}
            Out::Taken if n == 0 => {
                self.state = Out::Idle;
                let mut data = [0u8; 8];
                if let Some(d) = self.out.get(14..22) {
                    data.copy_from_slice(d);
                }
                link.frame_refused(Frame::new(ids::CONTROL, data));
            }
            Out::Taken | Out::Started => {
                if self.state == Out::Taken {
                    link.frame_done(None);
                    self.state = Out::Started;
                }
                // `written <= FRAME_LEN`, and `n` is cut to what is left: the saturating
                // steps are exact, whatever `n` the caller says.
                let left = FRAME_LEN.saturating_sub(usize::from(self.written));
                let n = n.min(left);
                // n <= 24: both casts are exact.
                self.written = self.written.saturating_add(n as u8);
                self.bytes_sent = self.bytes_sent.wrapping_add(n as u32);
                if usize::from(self.written) == FRAME_LEN {
                    self.state = Out::Idle;
                }
            }
        }
    }

    /// Whether bytes wait to be written (a frame started, taken, or queued on `link`).
    #[inline]
    pub fn has_transmit<const Q: usize, const T: usize>(&self, link: &Link<Q, T, Serial>) -> bool {
        self.state != Out::Idle || link.has_transmit()
    }

    /// The stream parser, for its state ([`StreamParser::pending`]).
    pub fn parser(&self) -> &StreamParser {
        &self.parser
    }

    /// What the stream counts (the link counts the rest: postbacks, frames sent, ...).
    pub fn stats(&self) -> SerialStreamStats {
        SerialStreamStats {
            stream: self.parser.stats(),
            bytes_received: self.bytes_received,
            bytes_sent: self.bytes_sent,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::{Config, Event, SerialLink};
    use crate::wire::control::{Command, GimbalCommand, Photo, Pitch};
    use crate::wire::postback::Postback;
    use crate::wire::vehicle::{Altitude, Attitude, Gps};

    const T0: Instant = Instant::from_millis(0);

    fn pitch(deg: f32) -> GimbalCommand {
        GimbalCommand::Pitch(Pitch::new(deg).unwrap())
    }

    fn frame_of(c: GimbalCommand) -> [u8; FRAME_LEN] {
        control_frame(&Command::from(c).encode())
    }

    fn pair() -> (SerialLink, SerialStream) {
        (SerialLink::new(Config::default()), SerialStream::new())
    }

    #[test]
    fn a_frame_nothing_of_which_was_written_goes_back_to_the_queue() {
        let (mut l, mut s) = pair();
        l.send(pitch(-45.0)).unwrap();
        assert_eq!(s.transmit_bytes(&mut l), frame_of(pitch(-45.0)));
        s.transmit_written(&mut l, 0);
        // Back in the queue, not counted as sent; it comes out again whole.
        assert_eq!(l.stats().frames_sent, 0);
        assert!(s.has_transmit(&l));
        assert_eq!(s.transmit_bytes(&mut l), frame_of(pitch(-45.0)));
        s.transmit_written(&mut l, 24);
        assert_eq!((l.stats().frames_sent, s.stats().bytes_sent), (1, 24));
        assert!(!s.has_transmit(&l));
        assert!(s.transmit_bytes(&mut l).is_empty());
    }

    #[test]
    fn a_started_frame_is_finished_before_the_next() {
        let (mut l, mut s) = pair();
        l.send(pitch(-45.0)).unwrap();
        let first = frame_of(pitch(-45.0));
        let _ = s.transmit_bytes(&mut l);
        s.transmit_written(&mut l, 1);
        // Once one byte is out, the frame is committed: counted as sent, and a command
        // queued now waits for it to finish, even when the port takes nothing for a while.
        assert_eq!(l.stats().frames_sent, 1);
        l.send(GimbalCommand::Photo(Photo::Single)).unwrap();
        s.transmit_written(&mut l, 0);
        assert_eq!(s.transmit_bytes(&mut l), &first[1..]);
        s.transmit_written(&mut l, 22);
        assert_eq!(s.transmit_bytes(&mut l), &first[23..]);
        // More than offered counts as the rest.
        s.transmit_written(&mut l, 5);
        assert_eq!(
            s.transmit_bytes(&mut l),
            frame_of(GimbalCommand::Photo(Photo::Single))
        );
        s.transmit_written(&mut l, 24);
        assert_eq!(s.stats().bytes_sent, 48);
        assert_eq!(l.stats().frames_sent, 2);
    }

    #[test]
    fn written_with_nothing_offered_changes_nothing() {
        let (mut l, mut s) = pair();
        s.transmit_written(&mut l, 10);
        assert_eq!(l.stats(), crate::link::LinkStats::default());
        assert_eq!(s.stats(), SerialStreamStats::default());
    }

    #[test]
    fn postbacks_split_at_every_byte_and_control_echoes_are_ignored() {
        let p = Postback {
            pitch: -1234,
            heading: 27_000,
            ..Postback::default()
        };
        let stream = p.to_stream_bytes();
        for cut in 0..=stream.len() {
            let (mut l, mut s) = pair();
            s.receive(&mut l, &stream[..cut], T0);
            s.receive(&mut l, &stream[cut..], T0.add_millis(3));
            // Stamped when its last byte arrived.
            let age = if cut == stream.len() { 3 } else { 0 };
            assert_eq!(l.latest_postback(T0.add_millis(3)), Some((p, age)));
            assert_eq!(l.next_event(), Some(Event::LinkUp));
            assert_eq!(l.next_event(), Some(Event::Postback));
        }
        let (mut l, mut s) = pair();
        s.receive(&mut l, &frame_of(pitch(10.0)), T0);
        s.receive(&mut l, &[0xEB, 0x90, 0x0C, 0x55], T0);
        s.receive(&mut l, &stream, T0);
        let link = l.stats();
        assert_eq!(link.ignored_frames, 1);
        assert_eq!(link.frames_received, 2);
        assert_eq!(link.postbacks, 1);
        let s = s.stats();
        assert_eq!(s.bytes_received, 24 + 4 + 27);
        // The false header and its byte are skipped; the real postback after them is found.
        assert_eq!(s.stream.skipped_bytes, 4);
    }

    #[test]
    fn a_corrupt_postback_is_counted_not_delivered() {
        let mut stream = Postback::default().to_stream_bytes();
        stream[20] ^= 0x10;
        let (mut l, mut s) = pair();
        s.receive(&mut l, &stream, T0);
        assert_eq!(l.latest_postback(T0), None);
        // The stream's CRC failed: the port counts it, the link never saw a postback.
        assert_eq!(s.stats().stream.crc_errors, 1);
        assert_eq!(l.stats().postbacks, 0);
        assert!(!l.is_link_up());
    }

    #[test]
    fn vehicle_data_is_kept_for_point_at_and_never_sent() {
        // The default periods: the medium, not the configuration, keeps them unsent.
        let (mut l, s) = pair();
        assert_eq!(l.config().attitude_period_ms, 100);
        l.set_attitude(Attitude::new(0.0, 0.0, 30.0).unwrap(), T0);
        l.set_gps(Gps::new(47.0, 8.0).unwrap(), T0);
        l.set_altitude(Altitude::new(450.0).unwrap(), T0);
        for ms in 0..1_000 {
            l.poll(T0.add_millis(ms));
            assert!(!s.has_transmit(&l));
        }
        assert_eq!(l.attitude().map(|a| a.heading_centideg()), Some(3_000));
        // The gimbal gets no attitude, so it references headings to the nose.
        assert!(!l.north_referenced(T0));
    }
}
