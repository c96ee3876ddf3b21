//! An in-memory CAN bus with fault injection, for host tests and emulated firmware; the
//! serial line's counterpart is [`serial::Pipe`].
//!
//! A [`Bus`] has `ENDPOINTS` nodes. Each node, taken once with [`Bus::endpoint`], is an
//! [`Endpoint`] that implements [`embedded_can::nb::Can`] and [`embedded_can::blocking::Can`]
//! with [`MockFrame`] and [`MockError`], so any driver written against `embedded-can` 0.4
//! runs on it unchanged. Nothing allocates, nothing is `unsafe`, nothing panics, and
//! the module works without `std`, so it also runs inside emulated firmware.
//!
//! # Model
//!
//! * Each endpoint has a set of TX mailboxes (3 by default, like bxcan; see
//!   [`Bus::set_mailboxes`]) and an RX FIFO of `QUEUE` frames.
//! * [`nb::Can::transmit`](embedded_can::nb::Can::transmit) puts the frame in a free
//!   mailbox. When all are full it replaces the lowest-priority pending frame if that one
//!   loses arbitration to the new frame, and returns it as `Ok(Some(displaced))`;
//!   otherwise it returns `Err(nb::Error::WouldBlock)`.
//! * With auto-delivery on (the default, [`Bus::set_auto_deliver`]) every successful
//!   transmit puts all pending frames on the wire at once, so mailboxes are never full.
//!   With it off, frames wait in their mailboxes until [`Bus::deliver`] or
//!   [`Bus::deliver_one`], which send them in CAN arbitration order
//!   ([`MockFrame::arbitration_key`], then transmission order).
//! * A frame on the wire is offered to every *other* endpoint that has been taken (an
//!   endpoint joins the bus when it is taken and never leaves; frames sent before are not
//!   queued for it). A frame never comes back to its sender.
//! * When a receiver's RX FIFO is full the frame is dropped for that receiver only, and
//!   its next `receive` returns `Err(MockError { kind: ErrorKind::Overrun })` once, like
//!   a hardware FIFO overrun; the frames already queued stay and are received after it.
//! * [`Faults`] inject loss, undetected corruption, duplication and bus errors with a
//!   deterministic PRNG seeded by [`Bus::new`]: the same seed, faults and sequence of
//!   calls give the same results.
//!
//! # Example
//!
//! ```
//! use embedded_can::{nb::Can, ExtendedId, Frame};
//! use idu_gimbal::mock::{Bus, MockFrame};
//!
//! let bus: Bus<2, 8> = Bus::new(42);
//! let mut flight_controller = bus.endpoint(0).unwrap();
//! let mut gimbal = bus.endpoint(1).unwrap();
//!
//! let id = ExtendedId::new(0x0000_0F01).unwrap();
//! let frame = MockFrame::new(id, &[1, 2, 3, 4, 5, 6, 7, 8]).unwrap();
//! assert_eq!(flight_controller.transmit(&frame), Ok(None));
//!
//! let received = gimbal.receive().unwrap();
//! assert!(received.is_extended());
//! assert_eq!(received.raw_id(), 0x0F01);
//! assert_eq!(received.data(), &[1, 2, 3, 4, 5, 6, 7, 8]);
//! // Not echoed back to the sender, and nothing more to receive.
//! assert_eq!(flight_controller.receive(), Err(nb::Error::WouldBlock));
//! assert_eq!(gimbal.receive(), Err(nb::Error::WouldBlock));
//! assert_eq!(bus.stats().delivered, 1);
//! ```

pub mod serial;

use core::cell::RefCell;
use core::fmt;

use embedded_can::{ErrorKind, ExtendedId, Id, StandardId};
use heapless::Deque;

/// The largest number of TX mailboxes an endpoint can have ([`Bus::set_mailboxes`]).
pub const MAX_MAILBOXES: usize = 8;

/// The number of TX mailboxes each endpoint starts with (as on bxcan).
pub const DEFAULT_MAILBOXES: usize = 3;

/// The largest standard (11-bit) identifier.
const STANDARD_MAX: u32 = 0x7FF;
/// The largest extended (29-bit) identifier.
const EXTENDED_MAX: u32 = 0x1FFF_FFFF;

/// Error kinds a random `tx_error` fault picks from: errors a transmitter detects.
const TX_ERROR_KINDS: [ErrorKind; 4] = [
    ErrorKind::Bit,
    ErrorKind::Stuff,
    ErrorKind::Form,
    ErrorKind::Acknowledge,
];
/// Error kinds a random `rx_error` fault picks from: errors a receiver detects.
const RX_ERROR_KINDS: [ErrorKind; 3] = [ErrorKind::Stuff, ErrorKind::Crc, ErrorKind::Form];

/// A classic CAN frame: standard or extended identifier, data or remote, DLC 0 to 8.
///
/// Implements [`embedded_can::Frame`]. The identifier is stored raw with an `extended`
/// flag (rather than as an [`embedded_can::Id`]) so that the frame can derive
/// `defmt::Format`. Data bytes past the DLC, and all data bytes of a remote frame, are
/// zero, so the derived equality compares exactly what is on the wire.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MockFrame {
    id: u32,
    extended: bool,
    remote: bool,
    dlc: u8,
    data: [u8; 8],
}

impl MockFrame {
    /// A data frame with a 29-bit extended identifier; `None` if `id` exceeds
    /// `0x1FFF_FFFF` or `data` is longer than 8 bytes.
    pub fn extended(id: u32, data: &[u8]) -> Option<Self> {
        if id > EXTENDED_MAX {
            return None;
        }
        Self::build(id, true, data)
    }

    /// A data frame with an 11-bit standard identifier; `None` if `id` exceeds `0x7FF`
    /// or `data` is longer than 8 bytes.
    pub fn standard(id: u16, data: &[u8]) -> Option<Self> {
        let id = u32::from(id);
        if id > STANDARD_MAX {
            return None;
        }
        Self::build(id, false, data)
    }

    /// The raw identifier: 11 bits for a standard frame, 29 bits for an extended one.
    pub const fn raw_id(&self) -> u32 {
        self.id
    }

    /// The frame's CAN arbitration priority: **the lower key wins** the bus.
    ///
    /// This is the bit sequence a controller sends during arbitration, so it orders
    /// frames exactly as a real bus does, mixed formats included: first the 11-bit base
    /// identifier (a standard identifier, or the top 11 bits of an extended one), then
    /// RTR of a standard frame (data beats remote) against SRR of an extended frame
    /// (always recessive), then IDE (standard beats extended), then the low 18 bits of an
    /// extended identifier, then its RTR. Within one format this is simply "lower raw id
    /// first, data before remote". Across formats, a standard frame beats an extended
    /// frame whose top 11 bits equal its identifier, but raw identifiers are not compared
    /// directly: standard `0x002` loses to extended `0x0004_0000` (base `0x001`), and
    /// extended `0x100` (base `0x000`) beats standard `0x100`.
    pub const fn arbitration_key(&self) -> u32 {
        let rtr = self.remote as u32;
        if self.extended {
            let base = self.id >> 18;
            let low = self.id & 0x3_FFFF;
            // base(11) | SRR=1 | IDE=1 | low(18) | RTR
            (base << 21) | (1 << 20) | (1 << 19) | (low << 1) | rtr
        } else {
            // base(11) | RTR | IDE=0 | nothing further is compared
            (self.id << 21) | (rtr << 20)
        }
    }

    fn build(id: u32, extended: bool, bytes: &[u8]) -> Option<Self> {
        let mut data = [0u8; 8];
        data.get_mut(..bytes.len())?.copy_from_slice(bytes);
        Some(MockFrame {
            id,
            extended,
            remote: false,
            dlc: u8::try_from(bytes.len()).ok()?,
            data,
        })
    }

    fn split_id(id: Id) -> (u32, bool) {
        match id {
            Id::Standard(id) => (u32::from(id.as_raw()), false),
            Id::Extended(id) => (id.as_raw(), true),
        }
    }

    /// Flips data bit `bit` (0 is the least significant bit of the first byte).
    fn flip_bit(&mut self, bit: usize) {
        if let Some(byte) = self.data.get_mut(bit / 8) {
            *byte ^= 1 << (bit % 8);
        }
    }
}

impl embedded_can::Frame for MockFrame {
    fn new(id: impl Into<Id>, data: &[u8]) -> Option<Self> {
        let (id, extended) = Self::split_id(id.into());
        Self::build(id, extended, data)
    }

    fn new_remote(id: impl Into<Id>, dlc: usize) -> Option<Self> {
        let (id, extended) = Self::split_id(id.into());
        if dlc > 8 {
            return None;
        }
        Some(MockFrame {
            id,
            extended,
            remote: true,
            dlc: u8::try_from(dlc).ok()?,
            data: [0; 8],
        })
    }

    fn is_extended(&self) -> bool {
        self.extended
    }

    fn is_remote_frame(&self) -> bool {
        self.remote
    }

    fn id(&self) -> Id {
        // The constructors validated the raw value, so the fallbacks are unreachable.
        if self.extended {
            Id::Extended(ExtendedId::new(self.id).unwrap_or(ExtendedId::MAX))
        } else {
            let raw = u16::try_from(self.id).unwrap_or(u16::MAX);
            Id::Standard(StandardId::new(raw).unwrap_or(StandardId::MAX))
        }
    }

    fn dlc(&self) -> usize {
        usize::from(self.dlc)
    }

    /// The data bytes; empty for a remote frame (whose DLC is only a request).
    fn data(&self) -> &[u8] {
        if self.remote {
            &[]
        } else {
            self.data.get(..usize::from(self.dlc)).unwrap_or(&[])
        }
    }
}

/// An error returned by an [`Endpoint`]: an injected bus error, an RX overrun, or
/// [`ErrorKind::Other`] from the mock itself.
///
/// Which kinds can occur:
/// * [`ErrorKind::Overrun`]: frames were dropped because this endpoint's RX FIFO was
///   full (reported once by the next `receive`), or injected with
///   [`Endpoint::inject_error`].
/// * [`ErrorKind::Bit`], [`Stuff`](ErrorKind::Stuff), [`Form`](ErrorKind::Form),
///   [`Acknowledge`](ErrorKind::Acknowledge): a random `tx_error` fault from `transmit`.
/// * [`ErrorKind::Stuff`], [`Crc`](ErrorKind::Crc), [`Form`](ErrorKind::Form): a random
///   `rx_error` fault from `receive`.
/// * [`ErrorKind::Other`]: never produced by random faults, only by
///   [`Endpoint::inject_error`], by a blocking `receive` with nothing to receive, or if
///   the bus state were ever found borrowed (which the design rules out).
/// * Any kind at all can be injected explicitly with [`Endpoint::inject_error`].
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub struct MockError {
    /// What went wrong.
    pub kind: ErrorKind,
}

impl MockError {
    /// An error of the given kind.
    pub const fn new(kind: ErrorKind) -> Self {
        MockError { kind }
    }
}

impl From<ErrorKind> for MockError {
    fn from(kind: ErrorKind) -> Self {
        MockError { kind }
    }
}

impl embedded_can::Error for MockError {
    fn kind(&self) -> ErrorKind {
        self.kind
    }
}

impl fmt::Display for MockError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "mock CAN bus: {}", self.kind)
    }
}

#[cfg(feature = "defmt")]
impl defmt::Format for MockError {
    fn format(&self, f: defmt::Formatter<'_>) {
        let kind = match self.kind {
            ErrorKind::Overrun => "Overrun",
            ErrorKind::Bit => "Bit",
            ErrorKind::Stuff => "Stuff",
            ErrorKind::Crc => "Crc",
            ErrorKind::Form => "Form",
            ErrorKind::Acknowledge => "Acknowledge",
            _ => "Other",
        };
        defmt::write!(f, "MockError {{ kind: {=str} }}", kind)
    }
}

#[cfg(feature = "std")]
impl std::error::Error for MockError {}

/// Fault probabilities, each in `[0, 1]`: 0 never happens, 1 always happens (values at
/// or below 0, and NaN, count as 0; values at or above 1 count as 1).
///
/// Faults on the wire are decided once per frame put on the wire, in this order: `loss`
/// (nobody receives it; nothing else is decided), then `corruption`, then `duplication`.
/// A PRNG draw is made only for faults whose probability is above 0.
#[derive(Clone, Copy, PartialEq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Faults {
    /// Probability that a frame on the wire reaches no receiver (counted in
    /// [`BusStats::lost`]).
    pub loss: f32,
    /// Probability that a data frame with DLC > 0 has one random data bit flipped, as if
    /// the bus CRC had missed it. Decided **per frame**: every receiver, and both copies
    /// of a duplicated frame, see the same corrupted data. Identifier, DLC and remote
    /// frames are never corrupted.
    pub corruption: f32,
    /// Probability that a frame is delivered twice in a row to every receiver (as when
    /// a transmitter misses the acknowledgement and resends).
    pub duplication: f32,
    /// Probability, per call of `transmit` (nb or blocking), that the call fails with a
    /// random transmitter error ([`ErrorKind::Bit`], `Stuff`, `Form` or `Acknowledge`)
    /// and the frame is not queued.
    pub tx_error: f32,
    /// Probability, per call of `receive` (nb or blocking, whether or not a frame is
    /// waiting), that the call fails with a random receiver error
    /// ([`ErrorKind::Stuff`], `Crc` or `Form`); no queued frame is consumed.
    pub rx_error: f32,
}

impl Faults {
    /// No faults at all (the default).
    pub const NONE: Faults = Faults {
        loss: 0.0,
        corruption: 0.0,
        duplication: 0.0,
        tx_error: 0.0,
        rx_error: 0.0,
    };
}

/// Counters of what happened on a [`Bus`] since it was created; each saturates at
/// `u32::MAX`.
///
/// With `R` receivers per frame (the taken endpoints other than the sender; constant when
/// every endpoint is taken before traffic starts), these always hold:
///
/// * `delivered + overruns == (sent - lost + duplicated) * R`
/// * frames accepted by `transmit` == `sent + displaced +` [`Bus::pending`]
/// * `lost + corrupted <= sent`, `lost + duplicated <= sent` (a lost frame is neither
///   corrupted nor duplicated)
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BusStats {
    /// Frames that left a TX mailbox and went on the wire (lost ones included).
    pub sent: u32,
    /// Frame copies placed into RX FIFOs (one per receiver, two per receiver for a
    /// duplicated frame).
    pub delivered: u32,
    /// Frames on the wire that the `loss` fault removed (each counted once, whatever the
    /// number of receivers).
    pub lost: u32,
    /// Frames on the wire that the `corruption` fault altered (counted once per frame).
    pub corrupted: u32,
    /// Frames on the wire that the `duplication` fault delivered twice (counted once per
    /// frame).
    pub duplicated: u32,
    /// Frame copies dropped because the receiver's RX FIFO was full (one per receiver per
    /// copy; the `Overrun` error is reported once however many were dropped).
    pub overruns: u32,
    /// Pending frames replaced in their mailbox by a higher-priority frame and handed
    /// back by `transmit` as `Ok(Some(displaced))`; they never went on the wire.
    pub displaced: u32,
    /// Errors returned because of the `tx_error` and `rx_error` faults or
    /// [`Endpoint::inject_error`] (not overruns, not the blocking receive's "nothing to
    /// receive").
    pub injected_errors: u32,
}

fn bump(counter: &mut u32) {
    *counter = counter.saturating_add(1);
}

/// A frame waiting in a TX mailbox; `seq` orders frames of equal priority.
#[derive(Clone, Copy, Debug)]
struct Pending {
    frame: MockFrame,
    seq: u64,
}

/// The state of one endpoint.
#[derive(Debug)]
struct Node<const QUEUE: usize> {
    taken: bool,
    mailboxes: usize,
    slots: [Option<Pending>; MAX_MAILBOXES],
    rx: Deque<MockFrame, QUEUE>,
    overrun: bool,
    injected: Option<ErrorKind>,
}

impl<const QUEUE: usize> Node<QUEUE> {
    const NEW: Self = Node {
        taken: false,
        mailboxes: DEFAULT_MAILBOXES,
        slots: [None; MAX_MAILBOXES],
        rx: Deque::new(),
        overrun: false,
        injected: None,
    };

    fn pending(&self) -> usize {
        self.slots.iter().flatten().count()
    }

    fn has_free_mailbox(&self) -> bool {
        self.pending() < self.mailboxes
    }
}

#[derive(Debug)]
struct State<const ENDPOINTS: usize, const QUEUE: usize> {
    rng: fastrand::Rng,
    faults: Faults,
    auto_deliver: bool,
    next_seq: u64,
    stats: BusStats,
    nodes: [Node<QUEUE>; ENDPOINTS],
}

/// Draws `true` with probability `p` (no draw when `p` is not above 0).
fn roll(rng: &mut fastrand::Rng, p: f32) -> bool {
    p > 0.0 && rng.f32() < p
}

fn pick(rng: &mut fastrand::Rng, kinds: &[ErrorKind]) -> ErrorKind {
    kinds
        .get(rng.usize(..kinds.len()))
        .copied()
        .unwrap_or(ErrorKind::Other)
}

const fn other() -> MockError {
    MockError::new(ErrorKind::Other)
}

impl<const ENDPOINTS: usize, const QUEUE: usize> State<ENDPOINTS, QUEUE> {
    /// The explicit injected error, else a random one; counts it.
    fn take_error(&mut self, index: usize, p: f32, kinds: &[ErrorKind]) -> Result<(), MockError> {
        let node = self.nodes.get_mut(index).ok_or(other())?;
        let kind = match node.injected.take() {
            Some(kind) => kind,
            None if roll(&mut self.rng, p) => pick(&mut self.rng, kinds),
            None => return Ok(()),
        };
        bump(&mut self.stats.injected_errors);
        Err(MockError::new(kind))
    }

    /// Puts `frame` in a mailbox of endpoint `index`, displacing if needed.
    fn enqueue(
        &mut self,
        index: usize,
        frame: MockFrame,
    ) -> nb::Result<Option<MockFrame>, MockError> {
        let seq = self.next_seq;
        let node = self.nodes.get_mut(index).ok_or(other())?;
        let new = Pending { frame, seq };
        let displaced = if node.has_free_mailbox() {
            let slot = node
                .slots
                .iter_mut()
                .find(|slot| slot.is_none())
                .ok_or(other())?;
            *slot = Some(new);
            None
        } else {
            let worst = node
                .slots
                .iter_mut()
                .flatten()
                .max_by_key(|p| (p.frame.arbitration_key(), p.seq))
                .filter(|p| p.frame.arbitration_key() > frame.arbitration_key())
                .ok_or(nb::Error::WouldBlock)?;
            let old = core::mem::replace(worst, new);
            bump(&mut self.stats.displaced);
            Some(old.frame)
        };
        self.next_seq = self.next_seq.wrapping_add(1);
        Ok(displaced)
    }

    /// Puts the highest-priority pending frame on the wire.
    fn deliver_one(&mut self) -> Option<MockFrame> {
        let mut best: Option<(u32, u64, usize, usize)> = None;
        for (i, node) in self.nodes.iter().enumerate() {
            for (j, slot) in node.slots.iter().enumerate() {
                if let Some(p) = slot {
                    let key = (p.frame.arbitration_key(), p.seq, i, j);
                    if best.is_none_or(|b| (key.0, key.1) < (b.0, b.1)) {
                        best = Some(key);
                    }
                }
            }
        }
        let (_, _, i, j) = best?;
        let pending = self.nodes.get_mut(i)?.slots.get_mut(j)?.take()?;
        bump(&mut self.stats.sent);
        self.broadcast(i, pending.frame);
        Some(pending.frame)
    }

    fn deliver_all(&mut self) -> usize {
        core::iter::from_fn(|| self.deliver_one()).count()
    }

    /// Applies the wire faults and queues the frame at every other taken endpoint.
    fn broadcast(&mut self, from: usize, mut frame: MockFrame) {
        let State {
            rng,
            faults,
            stats,
            nodes,
            ..
        } = self;
        if roll(rng, faults.loss) {
            bump(&mut stats.lost);
            return;
        }
        let bits = if frame.remote {
            0
        } else {
            usize::from(frame.dlc) * 8
        };
        if bits > 0 && roll(rng, faults.corruption) {
            frame.flip_bit(rng.usize(..bits));
            bump(&mut stats.corrupted);
        }
        let copies = if roll(rng, faults.duplication) {
            bump(&mut stats.duplicated);
            2
        } else {
            1
        };
        for _ in 0..copies {
            for (i, node) in nodes.iter_mut().enumerate() {
                if i == from || !node.taken {
                    continue;
                }
                if node.rx.push_back(frame).is_ok() {
                    bump(&mut stats.delivered);
                } else {
                    node.overrun = true;
                    bump(&mut stats.overruns);
                }
            }
        }
    }

    /// The checks every `receive` makes before looking at the FIFO.
    fn receive_errors(&mut self, index: usize) -> Result<(), MockError> {
        let p = self.faults.rx_error;
        // An explicitly injected error comes first, then a pending overrun, then faults.
        if self.nodes.get(index).is_some_and(|n| n.injected.is_some()) {
            return self.take_error(index, p, &RX_ERROR_KINDS);
        }
        let node = self.nodes.get_mut(index).ok_or(other())?;
        if core::mem::take(&mut node.overrun) {
            return Err(MockError::new(ErrorKind::Overrun));
        }
        self.take_error(index, p, &RX_ERROR_KINDS)
    }

    fn pop(&mut self, index: usize) -> Option<MockFrame> {
        self.nodes.get_mut(index)?.rx.pop_front()
    }
}

/// An in-memory CAN bus of `ENDPOINTS` nodes, each with an RX FIFO of `QUEUE` frames.
///
/// All methods take `&self`: the state lives in a [`RefCell`], and [`Endpoint`]s hold a
/// shared reference to the bus. The bus never runs caller code while its state is
/// borrowed, so the internal borrow cannot fail; should it ever, `transmit` and
/// `receive` return [`ErrorKind::Other`], queries return empty values and configuration
/// calls do nothing. `Bus` is not `Sync`: share it within one thread (or one
/// execution context of the firmware).
///
/// Memory: roughly `ENDPOINTS * (16 * QUEUE + 32 * MAX_MAILBOXES)` bytes plus a few
/// words, all inline; nothing is allocated.
#[derive(Debug)]
pub struct Bus<const ENDPOINTS: usize, const QUEUE: usize> {
    state: RefCell<State<ENDPOINTS, QUEUE>>,
}

impl<const ENDPOINTS: usize, const QUEUE: usize> Bus<ENDPOINTS, QUEUE> {
    /// A bus with no faults, auto-delivery on, [`DEFAULT_MAILBOXES`] mailboxes per
    /// endpoint, and its PRNG seeded with `seed`.
    pub const fn new(seed: u64) -> Self {
        Bus {
            state: RefCell::new(State {
                rng: fastrand::Rng::with_seed(seed),
                faults: Faults::NONE,
                auto_deliver: true,
                next_seq: 0,
                stats: BusStats {
                    sent: 0,
                    delivered: 0,
                    lost: 0,
                    corrupted: 0,
                    duplicated: 0,
                    overruns: 0,
                    displaced: 0,
                    injected_errors: 0,
                },
                nodes: [Node::NEW; ENDPOINTS],
            }),
        }
    }

    /// The bus with these faults (builder form of [`Bus::set_faults`]).
    #[must_use]
    pub fn with_faults(mut self, faults: Faults) -> Self {
        self.state.get_mut().faults = faults;
        self
    }

    /// Changes the faults; takes effect from the next call, so faults can change mid-run.
    pub fn set_faults(&self, faults: Faults) {
        if let Ok(mut state) = self.state.try_borrow_mut() {
            state.faults = faults;
        }
    }

    /// The faults in force.
    pub fn faults(&self) -> Faults {
        self.state
            .try_borrow()
            .map(|state| state.faults)
            .unwrap_or_default()
    }

    /// Sets the number of TX mailboxes of `endpoint` to `n` (1 to [`MAX_MAILBOXES`]).
    ///
    /// Returns `false`, changing nothing, if `endpoint` or `n` is out of range. Frames
    /// already pending stay pending even if there are now more of them than `n`; the
    /// mailboxes then count as full until enough have been delivered.
    pub fn set_mailboxes(&self, endpoint: usize, n: usize) -> bool {
        if !(1..=MAX_MAILBOXES).contains(&n) {
            return false;
        }
        let Ok(mut state) = self.state.try_borrow_mut() else {
            return false;
        };
        match state.nodes.get_mut(endpoint) {
            Some(node) => {
                node.mailboxes = n;
                true
            }
            None => false,
        }
    }

    /// Turns auto-delivery on (the default) or off.
    ///
    /// On: every successful `transmit` puts all pending frames on the wire before
    /// returning. Off: frames wait in their mailboxes for [`Bus::deliver`] or
    /// [`Bus::deliver_one`] (or a blocking call that needs room). Turning it on delivers
    /// whatever is pending at once.
    pub fn set_auto_deliver(&self, on: bool) {
        if let Ok(mut state) = self.state.try_borrow_mut() {
            state.auto_deliver = on;
            if on {
                state.deliver_all();
            }
        }
    }

    /// Takes endpoint `index`; `None` if it is out of range or was taken before.
    ///
    /// The endpoint joins the bus now: it receives the frames sent from now on. It stays
    /// on the bus when dropped (its RX FIFO keeps filling) and cannot be taken again.
    pub fn endpoint(&self, index: usize) -> Option<Endpoint<'_, ENDPOINTS, QUEUE>> {
        let mut state = self.state.try_borrow_mut().ok()?;
        let node = state.nodes.get_mut(index)?;
        if node.taken {
            return None;
        }
        node.taken = true;
        Some(Endpoint { bus: self, index })
    }

    /// Puts every pending frame of every endpoint on the wire, highest priority first
    /// (lowest [`MockFrame::arbitration_key`], then the order they were transmitted in).
    /// Returns how many frames went on the wire.
    pub fn deliver(&self) -> usize {
        self.state
            .try_borrow_mut()
            .map(|mut state| state.deliver_all())
            .unwrap_or(0)
    }

    /// Puts the single highest-priority pending frame on the wire and returns it as it
    /// was transmitted (before any wire fault); `None` if nothing was pending.
    pub fn deliver_one(&self) -> Option<MockFrame> {
        self.state.try_borrow_mut().ok()?.deliver_one()
    }

    /// Frames waiting in TX mailboxes, all endpoints together.
    pub fn pending(&self) -> usize {
        self.state
            .try_borrow()
            .map(|state| state.nodes.iter().map(Node::pending).sum())
            .unwrap_or(0)
    }

    /// Makes the next `transmit` or `receive` (nb or blocking, whichever comes first) of
    /// `endpoint` fail with exactly `kind`; see [`Endpoint::inject_error`]. For use once
    /// the endpoint has been moved into a driver. Returns `false` if `endpoint` is out of
    /// range.
    pub fn inject_error(&self, endpoint: usize, kind: ErrorKind) -> bool {
        let Ok(mut state) = self.state.try_borrow_mut() else {
            return false;
        };
        match state.nodes.get_mut(endpoint) {
            Some(node) => {
                node.injected = Some(kind);
                true
            }
            None => false,
        }
    }

    /// The counters so far.
    pub fn stats(&self) -> BusStats {
        self.state
            .try_borrow()
            .map(|state| state.stats)
            .unwrap_or_default()
    }
}

/// One node of a [`Bus`]: implements [`embedded_can::nb::Can`] and
/// [`embedded_can::blocking::Can`].
pub struct Endpoint<'a, const ENDPOINTS: usize, const QUEUE: usize> {
    bus: &'a Bus<ENDPOINTS, QUEUE>,
    index: usize,
}

impl<const ENDPOINTS: usize, const QUEUE: usize> fmt::Debug for Endpoint<'_, ENDPOINTS, QUEUE> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Endpoint")
            .field("index", &self.index)
            .finish_non_exhaustive()
    }
}

impl<const ENDPOINTS: usize, const QUEUE: usize> Endpoint<'_, ENDPOINTS, QUEUE> {
    /// This endpoint's index on the bus.
    pub fn index(&self) -> usize {
        self.index
    }

    /// Frames waiting in this endpoint's RX FIFO (what an interrupt line would signal).
    pub fn rx_pending(&self) -> usize {
        self.bus
            .state
            .try_borrow()
            .ok()
            .and_then(|s| s.nodes.get(self.index).map(|n| n.rx.len()))
            .unwrap_or(0)
    }

    /// Makes the next `transmit` or `receive` (nb or blocking, whichever comes first)
    /// fail with exactly `kind`, once; a frame being transmitted is not queued, a frame
    /// waiting to be received stays queued. A second injection before that call replaces
    /// the first. Counted in [`BusStats::injected_errors`].
    pub fn inject_error(&self, kind: ErrorKind) {
        self.bus.inject_error(self.index, kind);
    }
}

impl<const ENDPOINTS: usize, const QUEUE: usize> embedded_can::nb::Can
    for Endpoint<'_, ENDPOINTS, QUEUE>
{
    type Frame = MockFrame;
    type Error = MockError;

    /// Queues `frame` in a TX mailbox; see the [module documentation](crate::mock) for
    /// displacement and delivery. Fails first with an injected error, then with a
    /// `tx_error` fault.
    fn transmit(&mut self, frame: &MockFrame) -> nb::Result<Option<MockFrame>, MockError> {
        let mut state = self.bus.state.try_borrow_mut().map_err(|_| other())?;
        let p = state.faults.tx_error;
        state.take_error(self.index, p, &TX_ERROR_KINDS)?;
        let displaced = state.enqueue(self.index, *frame)?;
        if state.auto_deliver {
            state.deliver_all();
        }
        Ok(displaced)
    }

    /// Pops the oldest frame of the RX FIFO, or `Err(WouldBlock)` if it is empty.
    /// Before that, fails with an injected error, then once with `Overrun` after frames
    /// were dropped, then with an `rx_error` fault.
    fn receive(&mut self) -> nb::Result<MockFrame, MockError> {
        let mut state = self.bus.state.try_borrow_mut().map_err(|_| other())?;
        state.receive_errors(self.index)?;
        state.pop(self.index).ok_or(nb::Error::WouldBlock)
    }
}

impl<const ENDPOINTS: usize, const QUEUE: usize> embedded_can::blocking::Can
    for Endpoint<'_, ENDPOINTS, QUEUE>
{
    type Frame = MockFrame;
    type Error = MockError;

    /// Queues `frame`, never displacing another: if this endpoint's mailboxes are full
    /// (only possible with auto-delivery off), it first puts pending frames of the whole
    /// bus on the wire, in arbitration order, until one of its mailboxes is free, which
    /// is what waiting would achieve on a real bus. Errors as for the nb `transmit`.
    fn transmit(&mut self, frame: &MockFrame) -> Result<(), MockError> {
        let mut state = self.bus.state.try_borrow_mut().map_err(|_| other())?;
        let p = state.faults.tx_error;
        state.take_error(self.index, p, &TX_ERROR_KINDS)?;
        // Each round delivers one pending frame, so this ends.
        while !state
            .nodes
            .get(self.index)
            .ok_or(other())?
            .has_free_mailbox()
        {
            state.deliver_one().ok_or(other())?;
        }
        state.enqueue(self.index, *frame).map_err(|e| match e {
            nb::Error::Other(e) => e,
            nb::Error::WouldBlock => other(),
        })?;
        if state.auto_deliver {
            state.deliver_all();
        }
        Ok(())
    }

    /// Receives a frame without ever blocking forever: the errors are those of the nb
    /// `receive`; then, while the RX FIFO is empty, pending frames of the whole bus are
    /// put on the wire one at a time in arbitration order; if the FIFO is still empty
    /// when nothing is pending any more, returns `Err(MockError { kind: Other })`
    /// instead of waiting for a frame that cannot come.
    fn receive(&mut self) -> Result<MockFrame, MockError> {
        let mut state = self.bus.state.try_borrow_mut().map_err(|_| other())?;
        state.receive_errors(self.index)?;
        // Each round delivers one pending frame, so this ends.
        loop {
            if let Some(frame) = state.pop(self.index) {
                return Ok(frame);
            }
            state.deliver_one().ok_or(other())?;
        }
    }
}

#[cfg(test)]
mod tests;
