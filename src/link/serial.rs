//! The link over the gimbal's UART: bytes in, bytes out.
//!
//! [`SerialLink`] is the sans-IO core of the serial transport. It owns the same [`Link`] as
//! the CAN driver (queue and priorities, rate hold and dead-man, point-at, health, events,
//! counters) and puts a byte stream where CAN frames were:
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
//! # What the serial link cannot carry
//!
//! The protocol document defines no vehicle (attitude, GPS, altitude) or text frames on the
//! serial link. So the vehicle pushes are off here ([`SerialLink::new`] sets their periods to
//! 0), and the gimbal, never receiving the vehicle attitude, references headings to the
//! **nose**. Vehicle data given to the link (see [`Link::set_attitude`]) is kept for
//! [`Link::point_at`] only, which then aims relative to the nose from the vehicle heading.
//! The link has no text slots (a `Link<Q, 0>`), so [`Link::send_text`] on it does not
//! build.
//!
//! ```
//! use idu_gimbal::link::serial::SerialLink;
//! use idu_gimbal::link::{Config, Event};
//! use idu_gimbal::wire::control::{GimbalCommand, Pitch};
//! use idu_gimbal::wire::postback::Postback;
//! use idu_gimbal::{GimbalControl, Instant};
//!
//! let mut link: SerialLink = SerialLink::new(Config::default());
//! let now = Instant::from_millis(0);
//! link.send(GimbalCommand::Pitch(Pitch::new(-45.0)?)).unwrap();
//! link.poll(now);
//!
//! // A UART that takes 10 bytes now and the rest later: the frame is finished, not lost.
//! let bytes = link.transmit_bytes();
//! assert_eq!(bytes.len(), 24);
//! assert_eq!(&bytes[..3], &[0xEB, 0x90, 0x0A]);
//! assert_eq!(&bytes[14..22], &[0x0F, 0x08, 0x02, 0x3E, 0xFE, 0, 0, 0]);
//! link.transmit_written(10);
//! assert_eq!(link.transmit_bytes().len(), 14);
//! link.transmit_written(14);
//! assert!(link.transmit_bytes().is_empty());
//!
//! // A postback in its stream form, split anywhere, after line noise.
//! let stream = Postback { pitch: -4500, ..Postback::default() }.to_stream_bytes();
//! link.receive(&[0x00, 0x13], now);
//! link.receive(&stream[..5], now);
//! link.receive(&stream[5..], now);
//! assert_eq!(link.next_event(), Some(Event::LinkUp));
//! assert_eq!(link.latest_postback(now).map(|(p, _age)| p.pitch), Some(-4500));
//! assert_eq!(link.stats().stream.skipped_bytes, 2);
//! # Ok::<(), idu_gimbal::wire::RangeError>(())
//! ```

use crate::link::{Config, Link, LinkStats};
use crate::time::Instant;
use crate::wire::serial::{control_frame, StreamItem, StreamParser, StreamStats, FRAME_LEN};
use crate::wire::{ids, Frame};

/// Where the frame being written stands.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Out {
    /// No frame: the next [`SerialLink::transmit_bytes`] takes one from the link.
    Idle,
    /// Taken from the link, nothing written yet: it can still go back to the queue.
    Taken,
    /// Partly written: it is finished before anything else goes out.
    Started,
}

/// Counters of the serial link. All wrap at `u32::MAX` except `stream`'s, which saturate.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SerialStats {
    /// The link's counters. On the serial link `postbacks` and `crc_errors` come from the
    /// stream parser, and `frames_received` counts the postbacks and the control frames
    /// seen on the stream (the latter also in `ignored_frames`: a gimbal sends none).
    pub link: LinkStats,
    /// The stream parser's counters: frames, CRC errors, invalid frames, skipped bytes.
    /// Every byte received is in a frame yielded, skipped, or still pending.
    pub stream: StreamStats,
    /// Bytes received.
    pub bytes_received: u32,
    /// Bytes written.
    pub bytes_sent: u32,
}

/// The sans-IO link to a gimbal over its UART; see the [module docs](self).
///
/// `Q` is the number of control-frame slots (see [`Link`]); the link has no text slots.
#[derive(Clone, Debug)]
pub struct SerialLink<const Q: usize = 8> {
    link: Link<Q, 0>,
    parser: StreamParser,
    out: [u8; FRAME_LEN],
    /// Bytes of `out` written (0..=24).
    written: u8,
    state: Out,
    bytes_received: u32,
    bytes_sent: u32,
}

impl<const Q: usize> SerialLink<Q> {
    /// A serial link with the given timing, link down, nothing queued.
    ///
    /// The vehicle push periods of `config` are set to 0: the serial link has no vehicle
    /// frames (see the [module docs](self)). `postback_max_gap_ms` is unused: a postback
    /// arrives whole.
    pub fn new(config: Config) -> Self {
        let config = Config {
            attitude_period_ms: 0,
            gps_period_ms: 0,
            altitude_period_ms: 0,
            ..config
        };
        SerialLink {
            link: Link::new(config),
            parser: StreamParser::new(),
            out: [0; FRAME_LEN],
            written: 0,
            state: Out::Idle,
            bytes_received: 0,
            bytes_sent: 0,
        }
    }

    /// Takes received bytes, in any split: each complete postback reaches the link.
    pub fn receive(&mut self, bytes: &[u8], now: Instant) {
        // `as`: a slice longer than u32::MAX bytes wraps the counter, as every counter does.
        self.bytes_received = self.bytes_received.wrapping_add(bytes.len() as u32);
        for item in self.parser.feed(bytes) {
            match item {
                StreamItem::Postback(p) => self.link.receive_postback(p, now),
                // A gimbal sends no control frames: an echo or another controller.
                StreamItem::Control(_) => self.link.receive_ignored(),
            }
        }
    }

    /// Runs the link's schedules up to `now` (see [`Link::poll`]).
    #[inline]
    pub fn poll(&mut self, now: Instant) {
        self.link.poll(now);
    }

    /// The instant by which [`SerialLink::poll`] must next be called if nothing is received
    /// and nothing else is asked of the link before then, as seen from `now`: see
    /// [`Link::next_deadline`]. Bytes waiting to be written are not a deadline of `poll`
    /// (see [`SerialLink::has_transmit`]).
    pub fn next_deadline(&self, now: Instant) -> Instant {
        self.link.next_deadline(now)
    }

    /// The bytes to write next: the rest of the frame being written, or the next frame the
    /// link hands out; empty when nothing waits. Report how many were written with
    /// [`SerialLink::transmit_written`].
    pub fn transmit_bytes(&mut self) -> &[u8] {
        if self.state == Out::Idle {
            // Only control frames are ever queued here: the vehicle pushes are off and there
            // are no text slots.
            if let Some(frame) = self.link.next_transmit() {
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

    /// `n` bytes of those [`SerialLink::transmit_bytes`] returned were written (more than it
    /// returned counts as all of them). With `n == 0` a frame of which nothing was written
    /// goes back to the front of the link's queue; once any byte of a frame is written the
    /// frame is the link's last word until finished.
    pub fn transmit_written(&mut self, n: usize) {
        match self.state {
            Out::Idle => {}
            Out::Taken if n == 0 => {
                self.state = Out::Idle;
                let mut data = [0u8; 8];
                if let Some(d) = self.out.get(14..22) {
                    data.copy_from_slice(d);
                }
                self.link.transmit_refused(Frame::new(ids::CONTROL, data));
            }
            Out::Taken | Out::Started => {
                if self.state == Out::Taken {
                    self.link.transmit_done(None);
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

    /// Whether bytes wait to be written (a frame started, taken, or queued).
    #[inline]
    pub fn has_transmit(&self) -> bool {
        self.state != Out::Idle || self.link.has_transmit()
    }

    /// The stream parser, for its state ([`StreamParser::pending`]).
    pub fn parser(&self) -> &StreamParser {
        &self.parser
    }

    /// All counters.
    pub fn stats(&self) -> SerialStats {
        let stream = self.parser.stats();
        let link = self.link.stats();
        SerialStats {
            link: LinkStats {
                frames_received: link.frames_received.wrapping_add(stream.postbacks),
                postbacks: stream.postbacks,
                crc_errors: stream.crc_errors,
                ..link
            },
            stream,
            bytes_received: self.bytes_received,
            bytes_sent: self.bytes_sent,
        }
    }
}

/// The command surface ([`GimbalControl`](crate::GimbalControl)) is the link's; its
/// vehicle push is off, so the vehicle's data is kept for point-at only.
impl<const Q: usize> crate::control::Transport for SerialLink<Q> {
    type Link = Link<Q, 0>;

    #[inline]
    fn link(&self) -> &Link<Q, 0> {
        &self.link
    }

    #[inline]
    fn link_mut(&mut self) -> &mut Link<Q, 0> {
        &mut self.link
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::Event;
    use crate::wire::control::{Command, GimbalCommand, Photo, Pitch};
    use crate::wire::postback::Postback;
    use crate::wire::vehicle::{Altitude, Attitude, Gps};
    use crate::Transport;

    const T0: Instant = Instant::from_millis(0);

    fn pitch(deg: f32) -> GimbalCommand {
        GimbalCommand::Pitch(Pitch::new(deg).unwrap())
    }

    fn frame_of(c: GimbalCommand) -> [u8; FRAME_LEN] {
        control_frame(&Command::from(c).encode())
    }

    #[test]
    fn a_frame_nothing_of_which_was_written_goes_back_to_the_queue() {
        let mut l: SerialLink = SerialLink::new(Config::default());
        l.link_mut().send(pitch(-45.0)).unwrap();
        assert_eq!(l.transmit_bytes(), frame_of(pitch(-45.0)));
        l.transmit_written(0);
        // Back in the queue, not counted as sent; it comes out again whole.
        assert_eq!(l.stats().link.frames_sent, 0);
        assert!(l.has_transmit());
        assert_eq!(l.transmit_bytes(), frame_of(pitch(-45.0)));
        l.transmit_written(24);
        assert_eq!((l.stats().link.frames_sent, l.stats().bytes_sent), (1, 24));
        assert!(!l.has_transmit());
        assert!(l.transmit_bytes().is_empty());
    }

    #[test]
    fn a_started_frame_is_finished_before_the_next() {
        let mut l: SerialLink = SerialLink::new(Config::default());
        l.link_mut().send(pitch(-45.0)).unwrap();
        let first = frame_of(pitch(-45.0));
        let _ = l.transmit_bytes();
        l.transmit_written(1);
        // Once one byte is out, the frame is committed: counted as sent, and a command
        // queued now waits for it to finish, even when the port takes nothing for a while.
        assert_eq!(l.stats().link.frames_sent, 1);
        l.link_mut()
            .send(GimbalCommand::Photo(Photo::Single))
            .unwrap();
        l.transmit_written(0);
        assert_eq!(l.transmit_bytes(), &first[1..]);
        l.transmit_written(22);
        assert_eq!(l.transmit_bytes(), &first[23..]);
        // More than offered counts as the rest.
        l.transmit_written(5);
        assert_eq!(
            l.transmit_bytes(),
            frame_of(GimbalCommand::Photo(Photo::Single))
        );
        l.transmit_written(24);
        assert_eq!(l.stats().bytes_sent, 48);
        assert_eq!(l.stats().link.frames_sent, 2);
    }

    #[test]
    fn written_with_nothing_offered_changes_nothing() {
        let mut l: SerialLink = SerialLink::new(Config::default());
        l.transmit_written(10);
        assert_eq!(l.stats(), SerialStats::default());
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
            let mut l: SerialLink = SerialLink::new(Config::default());
            l.receive(&stream[..cut], T0);
            l.receive(&stream[cut..], T0.add_millis(3));
            // Stamped when its last byte arrived.
            let age = if cut == stream.len() { 3 } else { 0 };
            assert_eq!(l.link().latest_postback(T0.add_millis(3)), Some((p, age)));
            assert_eq!(l.link_mut().next_event(), Some(Event::LinkUp));
            assert_eq!(l.link_mut().next_event(), Some(Event::Postback));
        }
        let mut l: SerialLink = SerialLink::new(Config::default());
        l.receive(&frame_of(pitch(10.0)), T0);
        l.receive(&[0xEB, 0x90, 0x0C, 0x55], T0);
        l.receive(&stream, T0);
        let s = l.stats();
        assert_eq!(s.link.ignored_frames, 1);
        assert_eq!(s.link.frames_received, 2);
        assert_eq!(s.link.postbacks, 1);
        assert_eq!(s.bytes_received, 24 + 4 + 27);
        // The false header and its byte are skipped; the real postback after them is found.
        assert_eq!(s.stream.skipped_bytes, 4);
    }

    #[test]
    fn a_corrupt_postback_is_counted_not_delivered() {
        let mut stream = Postback::default().to_stream_bytes();
        stream[20] ^= 0x10;
        let mut l: SerialLink = SerialLink::new(Config::default());
        l.receive(&stream, T0);
        assert_eq!(l.link().latest_postback(T0), None);
        assert_eq!(l.stats().link.crc_errors, 1);
        assert_eq!(l.stats().link.postbacks, 0);
        assert!(!l.link().is_link_up());
    }

    #[test]
    fn vehicle_data_is_kept_for_point_at_and_never_sent() {
        let mut l: SerialLink = SerialLink::new(Config::default());
        assert_eq!(l.link().config().attitude_period_ms, 0);
        l.link_mut()
            .set_attitude(Attitude::new(0.0, 0.0, 30.0).unwrap(), T0);
        l.link_mut().set_gps(Gps::new(47.0, 8.0).unwrap(), T0);
        l.link_mut().set_altitude(Altitude::new(450.0).unwrap(), T0);
        for ms in 0..1_000 {
            l.poll(T0.add_millis(ms));
            assert!(!l.has_transmit());
        }
        assert_eq!(
            l.link().attitude().map(|a| a.heading_centideg()),
            Some(3_000)
        );
        // The gimbal gets no attitude, so it references headings to the nose.
        assert!(!l.link().north_referenced(T0));
    }
}
