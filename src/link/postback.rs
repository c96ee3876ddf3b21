//! Reassembling postbacks from their four CAN frames.
//!
//! The frames carry no sequence number, and on a real bus frames are lost, repeated and
//! corrupted. The assembler treats the frames received on the postback ID as a sliding
//! window of four: whenever the window is full and its oldest frame begins with `EB 90`,
//! the window is a candidate message, and its CRC decides. A data frame that happens to
//! begin with `EB 90` therefore cannot abort a good message around it (a restart-on-header
//! state machine would lose that message), and a real header that follows a lost frame
//! still starts its own candidate. Frames more than `max_gap_ms` apart never belong to one
//! message: a longer gap discards the window.
//!
//! Only a window that starts with a header can ever become a candidate, so the assembler
//! keeps just that: a frame that arrives with nothing held is kept only if it begins with
//! `EB 90`, and after a failed candidate the window moves on to the next header it holds.
//! A good message costs four 8-byte copies and one CRC.
//!
//! Every frame fed on the postback ID ends in exactly one place, which the counters show:
//! `frames == 4 * messages + discarded_frames + pending()`.
//!
//! ```
//! use idu_gimbal::link::postback::PostbackAssembler;
//! use idu_gimbal::wire::{ids, postback::Postback};
//! use idu_gimbal::Instant;
//!
//! let sent = Postback { pitch: -3000, ..Postback::default() };
//! let mut asm = PostbackAssembler::new();
//! let mut got = None;
//! for (i, frame) in sent.to_can_frames().iter().enumerate() {
//!     got = asm.feed(ids::POSTBACK, frame, Instant::from_millis(1000 + i as u32));
//! }
//! assert_eq!(got, Some(sent));
//! assert_eq!(asm.stats().messages, 1);
//! ```

use crate::time::Instant;
use crate::wire::postback::{self, Postback};

/// Default bound on the gap between two frames of one message, in milliseconds.
pub const DEFAULT_MAX_GAP_MS: u16 = 100;

/// What the assembler has seen.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AssemblerStats {
    /// Frames fed on the postback ID (including malformed ones).
    pub frames: u32,
    /// Good messages emitted.
    pub messages: u32,
    /// Candidate messages (four frames, the first beginning `EB 90`) whose CRC failed.
    pub crc_errors: u32,
    /// Candidates that failed because a newer header arrived before they completed (a
    /// message restarted after lost frames); counted instead of `crc_errors`.
    pub restarts: u32,
    /// Incomplete messages discarded because the gap to the next frame, or to
    /// [`PostbackAssembler::expire`], exceeded the bound, or a malformed frame broke them.
    pub dropped_partials: u32,
    /// Frames fed on the postback ID whose length was not 8.
    pub malformed: u32,
    /// Frames that ended in no message.
    pub discarded_frames: u32,
}

fn is_header(frame: &[u8; 8]) -> bool {
    // One halfword compare rather than two byte compares.
    let [a, b, ..] = *frame;
    u16::from_le_bytes([a, b]) == u16::from_le_bytes(postback::HEADER)
}

/// Reassembles postbacks from CAN frames; see the [module docs](self).
#[derive(Clone, Debug)]
pub struct PostbackAssembler {
    /// The window; when `count > 0`, `frames[0]` begins with `EB 90`.
    frames: [[u8; 8]; postback::FRAMES],
    count: u8,
    last: Instant,
    max_gap_ms: u16,
    stats: Counters,
}

/// The counters kept; `frames` in [`AssemblerStats`] is derived from them.
#[derive(Clone, Copy, Debug)]
struct Counters {
    messages: u32,
    crc_errors: u32,
    restarts: u32,
    dropped_partials: u32,
    malformed: u32,
    discarded_frames: u32,
}

impl Default for PostbackAssembler {
    fn default() -> Self {
        Self::new()
    }
}

impl PostbackAssembler {
    /// An assembler with the default gap bound ([`DEFAULT_MAX_GAP_MS`]).
    pub const fn new() -> Self {
        Self::with_max_gap(DEFAULT_MAX_GAP_MS)
    }

    /// An assembler that discards a partial message when two of its frames are more than
    /// `max_gap_ms` apart.
    pub const fn with_max_gap(max_gap_ms: u16) -> Self {
        PostbackAssembler {
            frames: [[0; 8]; postback::FRAMES],
            count: 0,
            last: Instant::from_millis(0),
            max_gap_ms,
            stats: Counters {
                messages: 0,
                crc_errors: 0,
                restarts: 0,
                dropped_partials: 0,
                malformed: 0,
                discarded_frames: 0,
            },
        }
    }

    /// The counters so far.
    pub fn stats(&self) -> AssemblerStats {
        // Every frame ended in a message, was discarded, or waits: counting them once more
        // on the hot path would be redundant.
        let s = self.stats;
        AssemblerStats {
            frames: s
                .messages
                .wrapping_mul(4)
                .wrapping_add(s.discarded_frames)
                .wrapping_add(u32::from(self.count)),
            messages: s.messages,
            crc_errors: s.crc_errors,
            restarts: s.restarts,
            dropped_partials: s.dropped_partials,
            malformed: s.malformed,
            discarded_frames: s.discarded_frames,
        }
    }

    /// Frames held that may still become part of a message.
    pub fn pending(&self) -> usize {
        usize::from(self.count)
    }

    /// The gap bound in milliseconds.
    pub fn max_gap_ms(&self) -> u16 {
        self.max_gap_ms
    }

    /// Takes one received frame. Frames on other IDs are not the assembler's business and
    /// are ignored (not counted). Returns a postback when this frame completes a good one.
    #[inline]
    pub fn feed(&mut self, id: u32, data: &[u8], now: Instant) -> Option<Postback> {
        if id != postback::ID {
            return None;
        }
        let Ok(data) = <&[u8; 8]>::try_from(data) else {
            self.malformed();
            return None;
        };
        self.feed_data(data, now)
    }

    /// [`PostbackAssembler::feed`] for a frame of 8 bytes on the postback ID.
    #[inline]
    pub(crate) fn feed_data(&mut self, data: &[u8; 8], now: Instant) -> Option<Postback> {
        if self.push(data, now) {
            self.complete()
        } else {
            None
        }
    }

    /// Takes a frame of 8 bytes on the postback ID into the window. Returns whether the
    /// window is now full (four frames, the first a header): then
    /// [`PostbackAssembler::complete`] must be called before the next frame.
    #[inline]
    pub(crate) fn push(&mut self, data: &[u8; 8], now: Instant) -> bool {
        let mut count = self.count;
        if count != 0 && now.is_later_than(self.last, self.max_gap_ms) {
            self.discard(0);
            count = 0;
        }
        if count == 0 && !is_header(data) {
            self.stats.discarded_frames = self.stats.discarded_frames.wrapping_add(1);
            return false;
        }
        self.last = now;
        // `count` is below 4 here; the mask lets the compiler see it, without a check.
        if let Some(slot) = self.frames.get_mut(usize::from(count & 3)) {
            *slot = *data;
        }
        // Below 4 before: never wraps, and the plain addition keeps the per-frame path
        // short.
        let count = count.wrapping_add(1);
        self.count = count;
        usize::from(count) >= postback::FRAMES
    }

    /// The window is full and starts with a header: the CRC decides. Kept out of line so
    /// that the three frames before it pay nothing for its registers.
    #[inline(never)]
    pub(crate) fn complete(&mut self) -> Option<Postback> {
        if let Some(p) = postback::decode_checked(self.frames.as_flattened()) {
            self.stats.messages = self.stats.messages.wrapping_add(1);
            self.count = 0;
            return Some(p);
        }
        // Move on to the next header held, if any; the frames before it are discarded.
        let next = self
            .frames
            .iter()
            .enumerate()
            .skip(1)
            .find(|(_, f)| is_header(f));
        match next {
            Some((drop, _)) => {
                self.stats.restarts = self.stats.restarts.wrapping_add(1);
                // Four frames at most: a loop of word copies, no memmove.
                for (dst, src) in (drop..postback::FRAMES).enumerate() {
                    if let Some(&src) = self.frames.get(src) {
                        if let Some(dst) = self.frames.get_mut(dst) {
                            *dst = src;
                        }
                    }
                }
                // The window is full (4) and `drop` in 1..4.
                self.count = self.count.saturating_sub(drop as u8);
                self.stats.discarded_frames = self.stats.discarded_frames.wrapping_add(drop as u32);
            }
            None => {
                self.stats.crc_errors = self.stats.crc_errors.wrapping_add(1);
                self.count = 0;
                self.stats.discarded_frames = self
                    .stats
                    .discarded_frames
                    .wrapping_add(postback::FRAMES as u32);
            }
        }
        None
    }

    /// Counts a frame on the postback ID whose length is not 8 (it breaks a partial
    /// message).
    #[cold]
    pub(crate) fn malformed(&mut self) {
        self.stats.malformed = self.stats.malformed.wrapping_add(1);
        self.discard(1);
    }

    /// Drops the window (a message in progress: a dropped partial) and counts its frames,
    /// plus `extra`, as discarded.
    fn discard(&mut self, extra: u32) {
        if self.count != 0 {
            self.stats.dropped_partials = self.stats.dropped_partials.wrapping_add(1);
        }
        self.stats.discarded_frames = self
            .stats
            .discarded_frames
            .wrapping_add(u32::from(self.count))
            .wrapping_add(extra);
        self.count = 0;
    }

    /// When a partial message held now would expire, if one is held.
    pub fn expiry(&self) -> Option<Instant> {
        (self.count != 0).then(|| self.last.add_millis(u32::from(self.max_gap_ms) + 1))
    }

    /// Discards a partial message whose last frame is more than the gap bound before `now`
    /// (one stamped after it is kept: [`Instant::is_later_than`]).
    /// Call it periodically so that a message cut short is counted when it is, not when the
    /// next frame happens to arrive.
    pub fn expire(&mut self, now: Instant) {
        if self.count != 0 && now.is_later_than(self.last, self.max_gap_ms) {
            self.discard(0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wire::ids;
    use crate::wire::postback::tests::arb_postback;
    use crate::wire::postback::{ControlMode, DataId, GimbalType};
    use proptest::prelude::*;

    fn msg(pitch: i16) -> Postback {
        Postback {
            pitch,
            heading: 12345,
            motor_heading: -77,
            ..Postback::default()
        }
    }

    struct Run {
        asm: PostbackAssembler,
        t: u32,
        out: Vec<Postback>,
        /// The last four whole frames fed: what a message delivered must parse from.
        last: Vec<[u8; 8]>,
    }

    /// What the assembler delivered after `last`, the whole frames fed before (the newest
    /// last), is those frames' message, its CRC checked: the four frames that completed it
    /// are the last four whole ones.
    fn delivered_from(last: &[[u8; 8]], p: &Postback) -> bool {
        let tail = last.get(last.len().saturating_sub(4)..).unwrap_or(&[]);
        tail.len() == 4 && Postback::parse(&tail.concat()) == Ok(*p)
    }

    impl Run {
        fn new() -> Self {
            Run {
                asm: PostbackAssembler::new(),
                t: 5,
                out: Vec::new(),
                last: Vec::new(),
            }
        }
        fn frame(&mut self, data: &[u8], dt: u32) {
            self.t = self.t.wrapping_add(dt);
            if let Ok(whole) = <[u8; 8]>::try_from(data) {
                self.last.push(whole);
            }
            if let Some(p) = self
                .asm
                .feed(ids::POSTBACK, data, Instant::from_millis(self.t))
            {
                assert!(delivered_from(&self.last, &p), "{p:?} from {:?}", self.last);
                self.out.push(p);
            }
        }
        fn message(&mut self, p: &Postback) {
            for f in p.to_can_frames() {
                self.frame(&f, 1);
            }
            self.t = self.t.wrapping_add(500);
        }
        fn invariant(&self) {
            let s = self.asm.stats();
            assert_eq!(
                s.frames,
                4 * s.messages + s.discarded_frames + self.asm.pending() as u32,
                "{s:?}"
            );
        }
    }

    #[test]
    fn four_frames_make_a_message() {
        let mut r = Run::new();
        r.message(&msg(100));
        r.message(&msg(200));
        assert_eq!(r.out, [msg(100), msg(200)]);
        r.invariant();
    }

    #[test]
    fn loss_of_any_one_frame_loses_only_that_message() {
        for lost in 0..4 {
            let mut r = Run::new();
            let a = msg(1).to_can_frames();
            for (i, f) in a.iter().enumerate() {
                if i != lost {
                    r.frame(f, 1);
                }
            }
            // The next message arrives right away (worst case: no gap to help).
            r.message(&msg(2));
            assert_eq!(r.out, [msg(2)], "lost frame {lost}");
            r.invariant();
            let s = r.asm.stats();
            assert_eq!(s.messages, 1);
            if lost != 0 {
                // A's header was superseded by B's.
                assert_eq!(s.restarts, 1, "lost {lost}: {s:?}");
            }
        }
    }

    #[test]
    fn duplicated_frames() {
        for dup in 0..4 {
            let mut r = Run::new();
            let a = msg(1).to_can_frames();
            for (i, f) in a.iter().enumerate() {
                r.frame(f, 1);
                if i == dup {
                    r.frame(f, 1);
                }
            }
            r.t += 500;
            r.message(&msg(2));
            // A duplicated header is harmless: the window slides past the first copy (a
            // restart) and the second copy starts the real message. A duplicate of the last
            // frame comes after the message completed. A duplicated middle frame breaks A.
            // B always survives; no wrong message ever.
            if dup == 0 || dup == 3 {
                assert_eq!(r.out, [msg(1), msg(2)]);
            } else {
                assert_eq!(r.out, [msg(2)], "dup {dup}");
            }
            r.invariant();
        }
    }

    #[test]
    fn reordered_frames_are_not_delivered() {
        let mut r = Run::new();
        let a = msg(1).to_can_frames();
        for i in [0, 2, 1, 3] {
            r.frame(&a[i], 1);
        }
        assert!(r.out.is_empty());
        assert_eq!(r.asm.stats().crc_errors, 1);
        r.t += 500;
        r.message(&msg(2));
        assert_eq!(r.out, [msg(2)]);
        r.invariant();
    }

    #[test]
    fn data_frames_that_begin_with_eb90() {
        // gimbal type 0xEB, tracking 0x90: frame 2 begins with EB 90.
        let p = Postback {
            gimbal_type: crate::wire::postback::GimbalType::Unknown(0xEB),
            tracking: true,
            ..msg(5)
        };
        let mut frames = p.to_can_frames();
        frames[2][1] = 0x90; // tracking flag byte 0x90 (non-zero: tracking)
        let bytes: Vec<u8> = frames.concat();
        let mut fixed = [0u8; 32];
        fixed.copy_from_slice(&bytes);
        let crc = crate::wire::crc::checksum(&fixed[..25]).to_le_bytes();
        fixed[25..27].copy_from_slice(&crc);
        assert_eq!(&fixed[16..18], &[0xEB, 0x90]);
        let mut r = Run::new();
        for f in fixed.chunks(8) {
            r.frame(f, 1);
        }
        // The message as built, the tracking byte 0x90 read as "tracking".
        let [got] = r.out[..] else {
            panic!("{:?}", r.out)
        };
        assert_eq!(
            got,
            Postback {
                tracking: true,
                ..p
            }
        );
        assert_eq!(
            got.gimbal_type,
            crate::wire::postback::GimbalType::Unknown(0xEB)
        );
        assert_eq!(r.asm.stats().restarts + r.asm.stats().crc_errors, 0);
        r.invariant();
    }

    #[test]
    fn garbage_frames_between_messages() {
        let mut r = Run::new();
        r.frame(&[1, 2, 3, 4, 5, 6, 7, 8], 1);
        r.frame(&[0xEB, 0x90, 0, 0, 0, 0, 0, 0], 1); // a lone false header
        r.frame(&[0; 8], 1);
        r.message(&msg(3));
        r.frame(&[0xFF; 8], 1);
        r.frame(&[0xFF; 5], 1); // malformed length
        r.message(&msg(4));
        assert_eq!(r.out, [msg(3), msg(4)]);
        assert_eq!(r.asm.stats().malformed, 1);
        r.invariant();
    }

    #[test]
    fn stale_partial_is_dropped() {
        let mut r = Run::new();
        let a = msg(1).to_can_frames();
        r.frame(&a[0], 1);
        r.frame(&a[1], 1);
        r.frame(&a[2], 101); // gap > 100 ms: A is dropped, this frame alone remains
        r.frame(&a[3], 1);
        assert!(r.out.is_empty());
        assert_eq!(r.asm.stats().dropped_partials, 1);
        // Exactly at the bound still counts as one message.
        let b = msg(2).to_can_frames();
        r.t += 500;
        for f in &b {
            r.frame(f, 100);
        }
        assert_eq!(r.out, [msg(2)]);
        // expire() drops a message cut short without waiting for the next frame.
        r.frame(&a[0], 500);
        r.asm.expire(Instant::from_millis(r.t + 100));
        assert_eq!(r.asm.pending(), 1);
        r.asm.expire(Instant::from_millis(r.t + 101));
        assert_eq!((r.asm.pending(), r.asm.stats().dropped_partials), (0, 2));
        r.invariant();
    }

    #[test]
    fn tick_wraps_mid_message() {
        let mut r = Run::new();
        r.t = u32::MAX - 1;
        let a = msg(9).to_can_frames();
        for f in &a {
            r.frame(f, 1); // u32::MAX, 0, 1, 2
        }
        assert_eq!(r.out, [msg(9)]);
        assert_eq!(r.asm.stats().dropped_partials, 0);
        r.invariant();
    }

    #[test]
    fn other_ids_are_ignored() {
        let mut asm = PostbackAssembler::new();
        for f in msg(1).to_can_frames() {
            assert_eq!(asm.feed(ids::CONTROL, &f, Instant::from_millis(0)), None);
        }
        assert_eq!(asm.stats(), AssemblerStats::default());
    }

    #[derive(Debug, Clone)]
    enum Fault {
        None,
        Drop,
        Dup,
        Corrupt(usize),
        Garbage([u8; 8]),
        Gap,
    }

    fn arb_fault() -> impl Strategy<Value = Fault> {
        prop_oneof![
            6 => Just(Fault::None),
            1 => Just(Fault::Drop),
            1 => Just(Fault::Dup),
            1 => (0usize..64).prop_map(Fault::Corrupt),
            1 => any::<[u8; 8]>().prop_map(Fault::Garbage),
            1 => Just(Fault::Gap),
        ]
    }

    /// The limit of the protocol's check: the CRC is 16 bits, so a window mixing frames of
    /// different messages, duplicates and garbage passes it by chance once in 65 536. Found
    /// by the fault proptest below: after message A, message B arrives as B0 B0 G B1 B2 B3
    /// (a duplicated header, a garbage frame G); the window B0 B0 G B1 has CRC 0x0000 and
    /// carries 0x0000. the protocol notes makes the CRC the arbiter (the length byte, C_ID and the like
    /// may differ on newer firmware), so the assembler delivers it: documented here rather
    /// than hidden behind checks the document does not support.
    #[test]
    fn a_crc_16_collision_is_delivered() {
        let b = Postback {
            data_id: DataId::Unknown(0),
            gimbal_type: GimbalType::Unknown(0),
            mode: ControlMode::Unknown(0),
            ..msg(0)
        };
        let b = Postback {
            pitch: 0,
            heading: 0,
            motor_heading: 0,
            ..b
        };
        let [b0, b1, _, _] = b.to_can_frames();
        let g = [141, 42, 123, 67, 41, 179, 88, 206];
        let mut r = Run::new();
        for f in [b0, b0, g, b1] {
            r.frame(&f, 1);
        }
        let collision = r.out.pop().expect("the window's CRC holds by chance");
        assert_eq!(
            collision.gimbal_type,
            GimbalType::Unknown(141),
            "fields come from the garbage frame"
        );
        r.invariant();
    }

    proptest! {
        // Fresh random seeds every run. The 2^-16 chance of a CRC collision (above) is part
        // of the property, not pinned away with a fixed seed: a message that was not sent may
        // be delivered only where faults were injected, and only with a CRC that holds.
        #![proptest_config(ProptestConfig {
            cases: 512,
            failure_persistence: None,
            ..ProptestConfig::default()
        })]

        /// Whatever the faults, every message delivered is one that was sent, in order, or
        /// (the CRC's limit, `a_crc_16_collision_is_delivered`) a window of faulty frames
        /// whose CRC holds by chance; the frame accounting holds; with no faults, every
        /// message is delivered and nothing else.
        #[test]
        fn faults_never_yield_a_wrong_message(
            msgs in proptest::collection::vec(arb_postback(), 1..12),
            faults in proptest::collection::vec(arb_fault(), 48),
            start: u32,
        ) {
            let mut r = Run::new();
            r.t = start;
            let mut clean = true;
            for (m, p) in msgs.iter().enumerate() {
                for (i, f) in p.to_can_frames().iter().enumerate() {
                    match faults.get(m * 4 + i).cloned().unwrap_or(Fault::None) {
                        Fault::None => r.frame(f, 1),
                        Fault::Drop => clean = false,
                        Fault::Dup => { clean = false; r.frame(f, 1); r.frame(f, 1) }
                        Fault::Corrupt(bit) => { clean = false; let mut c = *f; c[bit / 8] ^= 1 << (bit % 8); r.frame(&c, 1) }
                        Fault::Garbage(g) => { clean = false; r.frame(&g, 1); r.frame(f, 1) }
                        Fault::Gap => { clean = false; r.frame(f, 150) }
                    }
                }
                r.t = r.t.wrapping_add(500);
            }
            let mut sent = msgs.iter();
            for got in &r.out {
                match sent.clone().position(|s| s == got) {
                    Some(k) => {
                        sent.nth(k);
                    }
                    None => {
                        // Not a sent message delivered twice or out of order: a new one.
                        // Its CRC held over the frames received (`Run::frame`).
                        prop_assert!(!clean && !msgs.contains(got), "delivered {:?} was not sent (in order)", got);
                    }
                }
            }
            if clean {
                prop_assert_eq!(&r.out, &msgs);
            }
            r.invariant();
        }

        #[test]
        fn arbitrary_input_never_panics(
            frames in proptest::collection::vec((any::<bool>(), proptest::collection::vec(any::<u8>(), 0..10), 0u32..300), 0..60)
        ) {
            let mut asm = PostbackAssembler::new();
            let mut t = 0u32;
            let mut last = Vec::new();
            for (on_id, data, dt) in frames {
                t = t.wrapping_add(dt);
                let id = if on_id { ids::POSTBACK } else { ids::CONTROL };
                if let (true, Ok(whole)) = (on_id, <[u8; 8]>::try_from(&data[..])) {
                    last.push(whole);
                }
                if let Some(p) = asm.feed(id, &data, Instant::from_millis(t)) {
                    // Anything delivered is the message of the frames received, CRC held.
                    prop_assert!(delivered_from(&last, &p), "{:?} from {:?}", p, last);
                }
            }
            let s = asm.stats();
            prop_assert_eq!(s.frames, 4 * s.messages + s.discarded_frames + asm.pending() as u32);
        }
    }
}
