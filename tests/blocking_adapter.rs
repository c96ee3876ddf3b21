//! The `Blocking` adapter over a driver that returns errors instead of blocking, as the
//! `mcp2515` crate does: `receive` answers `NoMessage` when nothing is waiting, `transmit`
//! answers `TxBusy` when its three transmit buffers are full, and every error's `kind()` is
//! `Other`. With a classifier these are "would block", not faults: nothing is counted, every
//! frame goes out, in order. Real faults are still counted.

use idu_gimbal::{CanPort, Link, Port};
use std::cell::RefCell;
use std::collections::VecDeque;
use std::rc::Rc;

use embedded_can::{ErrorKind, ExtendedId, Frame as _, Id};
use idu_gimbal::port::{Blocking, Classify, DriverErrors};
use idu_gimbal::sim::{SimConfig, Simulator};
use idu_gimbal::wire::control::{Command, Focus, GimbalCommand, Heading, Pitch, Zoom};
use idu_gimbal::wire::{ids, Frame};
use idu_gimbal::{Config, Instant};

/// The errors of the `mcp2515` crate that matter here.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum McpError {
    /// `receive` with both receive buffers empty.
    NoMessage,
    /// `transmit` with all three transmit buffers pending.
    TxBusy,
    /// The SPI transfer failed: a real fault.
    Spi,
}

impl embedded_can::Error for McpError {
    fn kind(&self) -> ErrorKind {
        // As the mcp2515 crate: every error is `Other`, so the kind cannot tell them apart.
        ErrorKind::Other
    }
}

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
struct StubFrame {
    id: Id,
    data: [u8; 8],
    len: usize,
}

impl embedded_can::Frame for StubFrame {
    fn new(id: impl Into<Id>, data: &[u8]) -> Option<Self> {
        let mut d = [0; 8];
        d.get_mut(..data.len())?.copy_from_slice(data);
        Some(StubFrame {
            id: id.into(),
            data: d,
            len: data.len(),
        })
    }
    fn new_remote(_id: impl Into<Id>, _dlc: usize) -> Option<Self> {
        None
    }
    fn is_extended(&self) -> bool {
        matches!(self.id, Id::Extended(_))
    }
    fn is_remote_frame(&self) -> bool {
        false
    }
    fn id(&self) -> Id {
        self.id
    }
    fn dlc(&self) -> usize {
        self.len
    }
    fn data(&self) -> &[u8] {
        &self.data[..self.len]
    }
}

fn raw(frame: &StubFrame) -> Frame {
    let Id::Extended(id) = frame.id else {
        panic!("the driver sends extended IDs only")
    };
    Frame::new(id.as_raw(), frame.data)
}

/// An MCP2515 as the `mcp2515` crate drives it: `transmit` loads one of three transmit
/// buffers or answers `TxBusy`, `receive` takes a frame or answers `NoMessage`. Frames leave
/// the buffers only when the test lets the bus run (`bus`).
#[derive(Default)]
struct Chip {
    tx_buffers: VecDeque<StubFrame>,
    /// Frames that went out on the bus, in order.
    on_bus: Vec<Frame>,
    rx: VecDeque<StubFrame>,
    /// The next transmit / receive fails with `Spi`.
    fail_tx: bool,
    fail_rx: bool,
    tx_busy: u32,
    no_message: u32,
    spi_errors: u32,
}

impl Chip {
    /// The bus sends up to `n` frames from the transmit buffers.
    fn bus(&mut self, n: usize) {
        for _ in 0..n {
            match self.tx_buffers.pop_front() {
                Some(f) => self.on_bus.push(raw(&f)),
                None => break,
            }
        }
    }
}

/// The driver's handle on the chip; the test keeps another.
#[derive(Clone, Default)]
struct Mcp2515Like(Rc<RefCell<Chip>>);

impl embedded_can::blocking::Can for Mcp2515Like {
    type Frame = StubFrame;
    type Error = McpError;

    fn transmit(&mut self, frame: &StubFrame) -> Result<(), McpError> {
        let mut chip = self.0.borrow_mut();
        if std::mem::take(&mut chip.fail_tx) {
            chip.spi_errors += 1;
            return Err(McpError::Spi);
        }
        if chip.tx_buffers.len() == 3 {
            chip.tx_busy += 1;
            return Err(McpError::TxBusy);
        }
        chip.tx_buffers.push_back(*frame);
        Ok(())
    }

    fn receive(&mut self) -> Result<StubFrame, McpError> {
        let mut chip = self.0.borrow_mut();
        if std::mem::take(&mut chip.fail_rx) {
            chip.spi_errors += 1;
            return Err(McpError::Spi);
        }
        match chip.rx.pop_front() {
            Some(f) => Ok(f),
            None => {
                chip.no_message += 1;
                Err(McpError::NoMessage)
            }
        }
    }
}

/// The classifier for the mcp2515 crate's errors.
fn would_block(e: &McpError) -> bool {
    matches!(e, McpError::NoMessage | McpError::TxBusy)
}

/// `mcp2515`'s receive does not block: the adapter may always call it.
fn always(_: &mut Mcp2515Like) -> bool {
    true
}

/// Eight control commands (the driver's default queue), all queued before the first poll.
fn commands() -> Vec<Command> {
    vec![
        GimbalCommand::Pitch(Pitch::from_deci(-450).unwrap()).into(),
        GimbalCommand::Heading(Heading::from_deci(900).unwrap()).into(),
        GimbalCommand::Zoom(Zoom::In).into(),
        GimbalCommand::Zoom(Zoom::Stop).into(),
        GimbalCommand::Focus(Focus::Auto).into(),
        GimbalCommand::Recenter.into(),
        GimbalCommand::Pitch(Pitch::from_deci(-900).unwrap()).into(),
        GimbalCommand::Heading(Heading::from_deci(0).unwrap()).into(),
    ]
}

/// 40 bytes: five text frames.
const TEXT: &[u8] = b"IDU over MCP2515: 40 bytes of text here.";

type Driver<W = fn(&McpError) -> bool> =
    CanPort<Blocking<Mcp2515Like, fn(&mut Mcp2515Like) -> bool, W>>;

/// A link with the commands and the text queued, and a port over the stub with the
/// classifier.
fn setup<W: Classify<McpError>>(classifier: W) -> (Link, Driver<W>, Rc<RefCell<Chip>>) {
    let chip = Mcp2515Like::default();
    let handle = chip.0.clone();
    let can = Blocking::with_classifier(chip, always as fn(&mut Mcp2515Like) -> bool, classifier);
    let mut link: Link = Link::new(Config::default());
    for c in commands() {
        link.send(c).unwrap();
    }
    link.send_text(TEXT).unwrap();
    (link, CanPort::new(can), handle)
}

/// Runs the gimbal over `[from, to)` ms against a simulated gimbal: each millisecond the bus
/// sends one frame from the transmit buffers (the simulator takes it), the simulator's
/// postbacks arrive in the receive buffer, then the driver polls. Returns the polls that
/// returned an error.
fn run<W: Classify<McpError>>(
    gimbal: &mut Link,
    port: &mut Driver<W>,
    chip: &Rc<RefCell<Chip>>,
    sim: &mut Simulator,
    from: u32,
    to: u32,
) -> u32 {
    let mut failed = 0;
    let mut delivered = chip.borrow().on_bus.len();
    for t in from..to {
        let now = Instant::from_millis(t);
        chip.borrow_mut().bus(1);
        {
            let c = chip.borrow();
            while let Some(f) = c.on_bus.get(delivered).copied() {
                delivered += 1;
                sim.receive(f.id, &f.data, now).unwrap();
            }
        }
        sim.poll(now);
        while let Some(f) = sim.pop_frame() {
            let id = ExtendedId::new(f.id).unwrap();
            chip.borrow_mut()
                .rx
                .push_back(StubFrame::new(id, &f.data).unwrap());
        }
        if port.poll(gimbal, now).is_err() {
            failed += 1;
        }
    }
    failed
}

/// The frames the driver should put on the bus, in order: the commands, then the text.
fn expected_frames() -> Vec<Frame> {
    let mut frames: Vec<Frame> = commands().iter().map(|c| c.to_frame()).collect();
    let chunks: Vec<&[u8]> = TEXT.chunks(8).collect();
    for (i, chunk) in chunks.iter().enumerate() {
        let mut data = [0u8; 8];
        data[..chunk.len()].copy_from_slice(chunk);
        let id = if i + 1 == chunks.len() {
            ids::TEXT_END
        } else {
            ids::TEXT
        };
        frames.push(Frame::new(id, data));
    }
    frames
}

#[test]
fn would_block_errors_are_not_faults_and_every_frame_goes_out_in_order() {
    let (mut gimbal, mut port, chip) = setup(would_block);
    let mut sim = Simulator::new(SimConfig::default(), Instant::from_millis(0));
    // 1.6 s: the 13 frames go out in the first 13 ms; the simulator's postbacks (every
    // 500 ms) come in.
    let failed = run(&mut gimbal, &mut port, &chip, &mut sim, 0, 1600);

    let c = chip.borrow();
    // The stub did refuse: the transmit buffers were full and the receive buffer empty.
    assert!(c.tx_busy >= 10, "TxBusy {}", c.tx_busy);
    assert!(c.no_message >= 1000, "NoMessage {}", c.no_message);
    assert_eq!(c.spi_errors, 0);
    // None of it was a fault.
    assert_eq!(failed, 0);
    assert_eq!(port.stats().driver_errors, DriverErrors::default());
    // Every frame, once each, in order.
    assert_eq!(c.on_bus, expected_frames());
    assert!(c.tx_buffers.is_empty());
    let link = gimbal.stats();
    assert_eq!(link.frames_sent, 13);
    assert_eq!(link.queue_full, 0);
    assert_eq!(link.requeued, 0);
    assert_eq!(link.superseded, 0);
    // The simulator took every command and the text.
    assert_eq!(sim.stats().commands, 8);
    assert_eq!(sim.stats().texts, 1);
    assert_eq!(sim.stats().rejected + sim.stats().text_errors, 0);
    // The postbacks: three, of four frames each, none lost.
    assert_eq!(sim.stats().postbacks, 3);
    assert_eq!(link.postbacks, 3);
    assert_eq!(link.frames_received, 12);
    assert_eq!(link.crc_errors + link.dropped_partials + link.malformed, 0);
    assert_eq!(link.ignored_frames, 0);
    assert!(gimbal.is_link_up());
}

#[test]
fn a_frame_refused_as_busy_is_requeued_not_dropped() {
    let (mut gimbal, mut port, chip) = setup(would_block);
    // The bus is stopped: three frames fit, the fourth is refused.
    port.poll(&mut gimbal, Instant::from_millis(0)).unwrap();
    assert_eq!(chip.borrow().tx_busy, 1);
    assert_eq!(gimbal.stats().frames_sent, 3);
    assert!(gimbal.has_transmit());
    // Refused again on every poll while the bus is stopped, never counted, never lost.
    for t in 1..10 {
        port.poll(&mut gimbal, Instant::from_millis(t)).unwrap();
    }
    assert_eq!(chip.borrow().tx_busy, 10);
    assert_eq!(gimbal.stats().frames_sent, 3);
    assert_eq!(port.stats().driver_errors.total(), 0);
    // The bus runs: the rest follows, in order.
    for t in 10..30 {
        chip.borrow_mut().bus(3);
        port.poll(&mut gimbal, Instant::from_millis(t)).unwrap();
    }
    chip.borrow_mut().bus(3);
    assert_eq!(chip.borrow().on_bus, expected_frames());
    assert_eq!(gimbal.stats().frames_sent, 13);
}

#[test]
fn real_faults_are_still_counted() {
    let (mut gimbal, mut port, chip) = setup(would_block);
    let mut sim = Simulator::new(SimConfig::default(), Instant::from_millis(0));
    // An SPI failure on the first transmit and on the first receive.
    chip.borrow_mut().fail_tx = true;
    chip.borrow_mut().fail_rx = true;
    let e = port.poll(&mut gimbal, Instant::from_millis(0)).unwrap_err();
    assert_eq!(e.0, ErrorKind::Other);
    assert_eq!(
        port.stats().driver_errors,
        DriverErrors {
            other: 2,
            ..DriverErrors::default()
        }
    );
    // The frame the failed transmit refused is kept: every frame still goes out, in order,
    // and no further error is counted.
    let failed = run(&mut gimbal, &mut port, &chip, &mut sim, 1, 1600);
    assert_eq!(failed, 0);
    assert_eq!(port.stats().driver_errors.other, 2);
    assert_eq!(port.stats().driver_errors.total(), 2);
    assert_eq!(chip.borrow().spi_errors, 2);
    assert_eq!(chip.borrow().on_bus, expected_frames());
    assert_eq!(gimbal.stats().frames_sent, 13);
    assert_eq!(gimbal.stats().postbacks, 3);
}

#[test]
fn without_the_classifier_every_error_is_a_fault() {
    // What the adapter did before the classifier, and still does with `Blocking::new`
    // (right for drivers that really block): NoMessage and TxBusy count as faults.
    let chip = Mcp2515Like::default();
    let handle = chip.0.clone();
    let mut gimbal: Link = Link::new(Config::default());
    let mut port = CanPort::new(Blocking::new(chip, always));
    for c in commands() {
        gimbal.send(c).unwrap();
    }
    let e = port.poll(&mut gimbal, Instant::from_millis(0)).unwrap_err();
    assert_eq!(e.0, ErrorKind::Other);
    let no_message = handle.borrow().no_message;
    let tx_busy = handle.borrow().tx_busy;
    assert_eq!(
        (no_message, tx_busy),
        (u32::from(Config::default().max_rx_per_poll.get()), 1)
    );
    assert_eq!(port.stats().driver_errors.other, no_message + tx_busy);
    // A classifier that calls nothing "would block" is the same.
    let (mut gimbal, mut port, _chip) = setup(|_: &McpError| false);
    assert!(port.poll(&mut gimbal, Instant::from_millis(0)).is_err());
    assert!(port.stats().driver_errors.other > 0);
}

/// The driver behind the adapter, reached through the port: a frame its transmit buffers
/// take there is not the link's.
#[test]
fn the_driver_is_reachable_through_the_adapter() {
    let (gimbal, mut port, chip) = setup(would_block);
    assert!(Rc::ptr_eq(&port.can().can().0, &chip));
    let id = ExtendedId::new(0x123).unwrap();
    let frame = StubFrame::new(id, &[1, 2]).unwrap();
    embedded_can::blocking::Can::transmit(port.can_mut().can_mut(), &frame).unwrap();
    assert_eq!(chip.borrow().tx_buffers.len(), 1);
    assert_eq!(gimbal.stats().frames_sent, 0);
}

/// A classifier of a type of its own, as a firmware keeping state in it would write: it
/// counts the "would block" errors it saw.
#[derive(Default)]
struct CountingClassifier(Rc<RefCell<u32>>);

impl Classify<McpError> for CountingClassifier {
    fn would_block(&mut self, error: &McpError) -> bool {
        let would = would_block(error);
        if would {
            *self.0.borrow_mut() += 1;
        }
        would
    }
}

#[test]
fn a_classifier_of_a_type_of_its_own_is_taken() {
    let classifier = CountingClassifier::default();
    let seen = classifier.0.clone();
    let (mut gimbal, mut port, chip) = setup(classifier);
    let mut sim = Simulator::new(SimConfig::default(), Instant::from_millis(0));
    assert_eq!(run(&mut gimbal, &mut port, &chip, &mut sim, 0, 1600), 0);
    let c = chip.borrow();
    assert_eq!(c.on_bus, expected_frames());
    assert_eq!(port.stats().driver_errors, DriverErrors::default());
    // It was asked about every error the stub returned, and took them all as would-block.
    assert_eq!(*seen.borrow(), c.tx_busy + c.no_message);
}
