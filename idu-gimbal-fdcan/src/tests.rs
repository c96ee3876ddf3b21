//! The adapter's tests, over a stand-in controller (`Chip`): IDs and error codes converted,
//! transmit headers, FD frames refused, errors reported before frames, one frame in flight
//! and displaced frames rebuilt, frames of one ID in order, what frames and errors say, and
//! a CAN port over the adapter against the simulated gimbal.

use super::*;
use embedded_can::nb::Can;
use embedded_can::{Error as _, Frame as _};
use idu_gimbal::port::{CanPort, Port};
use idu_gimbal::sim::{SimConfig, Simulator};
use idu_gimbal::wire::control::{GimbalCommand, Pitch};
use idu_gimbal::wire::ids;
use idu_gimbal::{Config, Instant, Link};
use std::cell::RefCell;
use std::collections::VecDeque;
use std::rc::Rc;
use std::vec::Vec;

fn ext(raw: u32) -> Id {
    Id::Extended(ExtendedId::new(raw).unwrap())
}

fn data_frame(raw: u32, data: &[u8]) -> Frame {
    Frame::new(ext(raw), data).unwrap()
}

fn rx_info(id: fdcan::id::Id, len: u8, format: FrameFormat, rtr: bool) -> RxFrameInfo {
    RxFrameInfo {
        len,
        frame_format: format,
        id,
        rtr,
        filter_match: None,
        bit_rate_switching: false,
        time_stamp: 0,
    }
}

fn fd_ext(raw: u32) -> fdcan::id::Id {
    fdcan::id::ExtendedId::new(raw).unwrap().into()
}

/// The fdcan crate and the FDCAN, in memory: three transmit buffers in queue mode (a
/// frame goes to the first free buffer; when all are pending, the first holding a
/// lower-priority frame is displaced through `keep`, `WouldBlock` when none is; the bus
/// sends the lowest ID first and, among equal IDs, the lowest buffer first); receive
/// FIFO 0 (`WouldBlock` when empty); the protocol status, whose last error code reads
/// back as "no change" once read.
#[derive(Default)]
struct Chip {
    mailboxes: [Option<(TxFrameHeader, [u32; 16])>; 3],
    /// Frames that left the buffers, in order.
    sent: Vec<Frame>,
    fifo: VecDeque<(RxFrameInfo, [u8; 64], bool)>,
    bus_off: bool,
    lec: Option<LastErrorCode>,
    /// The message-lost flag: set by a loss, reported with every frame taken until
    /// cleared, as the controller's `RF0L`.
    lost: bool,
}

fn raw_id(id: fdcan::id::Id) -> u32 {
    match id {
        fdcan::id::Id::Standard(id) => u32::from(id.as_raw()) << 18,
        fdcan::id::Id::Extended(id) => id.as_raw(),
    }
}

/// The adapter's handle on the chip; the test keeps another.
#[derive(Default, Clone)]
struct Stub(Rc<RefCell<Chip>>);

fn adapter() -> (Adapter<Stub>, Rc<RefCell<Chip>>) {
    let stub = Stub::default();
    let chip = stub.0.clone();
    (Adapter::new(stub), chip)
}

impl Chip {
    /// The bus sends the highest-priority pending frame.
    fn send_one(&mut self) -> bool {
        let best = self
            .mailboxes
            .iter()
            .enumerate()
            .filter_map(|(i, m)| m.map(|(h, _)| (raw_id(h.id), i)))
            .min();
        // (raw ID, buffer index): lowest ID, then lowest buffer, as the M_CAN does.
        let Some((_, i)) = best else { return false };
        let (h, words) = self.mailboxes[i].take().unwrap();
        self.sent.push(displaced_frame(h, &words).unwrap());
        true
    }

    fn push_rx(&mut self, frame: &Frame, overrun: bool) {
        let mut data = [0u8; 64];
        data[..frame.dlc()].copy_from_slice(frame.data());
        let info = rx_info(
            to_fdcan_id(frame.id()).unwrap(),
            frame.dlc() as u8,
            FrameFormat::Standard,
            frame.is_remote_frame(),
        );
        self.fifo.push_back((info, data, overrun));
    }

    /// A frame the adapter cannot carry (CAN FD), received with or without an overrun.
    fn push_rx_fd(&mut self, overrun: bool) {
        let info = rx_info(fd_ext(7), 12, FrameFormat::Fdcan, false);
        self.fifo.push_back((info, [0u8; 64], overrun));
    }
}

impl Controller for Stub {
    fn tx_pending(&mut self) -> bool {
        self.0.borrow().mailboxes.iter().any(Option::is_some)
    }

    fn status(&mut self) -> (bool, LastErrorCode) {
        let mut chip = self.0.borrow_mut();
        let lec = chip.lec.take().unwrap_or(LastErrorCode::NoChange);
        (chip.bus_off, lec)
    }

    fn receive0(&mut self, data: &mut [u8]) -> nb::Result<ReceiveOverrun<RxFrameInfo>, Infallible> {
        let popped = self.0.borrow_mut().fifo.pop_front();
        let (info, bytes, lost) = popped.ok_or(nb::Error::WouldBlock)?;
        let mut chip = self.0.borrow_mut();
        chip.lost |= lost;
        data[..info.len as usize].copy_from_slice(&bytes[..info.len as usize]);
        Ok(if chip.lost {
            ReceiveOverrun::Overrun(info)
        } else {
            ReceiveOverrun::NoOverrun(info)
        })
    }

    fn clear_overrun(&mut self) {
        self.0.borrow_mut().lost = false;
    }

    fn transmit(
        &mut self,
        header: TxFrameHeader,
        data: &[u8],
        keep: Keep<'_>,
    ) -> nb::Result<Option<Option<Frame>>, Infallible> {
        // The bytes in memory order, as the fdcan crate writes them.
        let mut bytes = [0u8; 64];
        bytes[..usize::from(header.len)].copy_from_slice(&data[..usize::from(header.len)]);
        let mut words = [0u32; 16];
        for (w, c) in words.iter_mut().zip(bytes.chunks(4)) {
            *w = u32::from_ne_bytes(c.try_into().unwrap());
        }
        let mut chip = self.0.borrow_mut();
        if let Some(free) = chip.mailboxes.iter().position(Option::is_none) {
            chip.mailboxes[free] = Some((header, words));
            return Ok(None);
        }
        let boxes = [Mailbox::_0, Mailbox::_1, Mailbox::_2];
        for (i, mailbox) in boxes.into_iter().enumerate() {
            let (old, old_words) = chip.mailboxes[i].unwrap();
            if raw_id(header.id) < raw_id(old.id) {
                let displaced = keep(mailbox, old, &old_words);
                chip.mailboxes[i] = Some((header, words));
                return Ok(Some(displaced));
            }
        }
        Err(nb::Error::WouldBlock)
    }
}

#[test]
fn ids_convert_both_ways_unchanged_at_every_width() {
    // The extremes of each width and the protocol's two IDs.
    let cases = [
        Id::Standard(StandardId::ZERO),
        Id::Standard(StandardId::MAX),
        ext(0),
        ext(ids::CONTROL),
        ext(ids::POSTBACK),
        Id::Extended(ExtendedId::MAX),
    ];
    for id in cases {
        let theirs = to_fdcan_id(id).unwrap();
        let raw = match theirs {
            fdcan::id::Id::Standard(s) => u32::from(s.as_raw()),
            fdcan::id::Id::Extended(e) => e.as_raw(),
        };
        let ours = match id {
            Id::Standard(s) => u32::from(s.as_raw()),
            Id::Extended(e) => e.as_raw(),
        };
        assert_eq!(raw, ours, "{id:?}");
        assert_eq!(
            matches!(theirs, fdcan::id::Id::Extended(_)),
            matches!(id, Id::Extended(_))
        );
        assert_eq!(from_fdcan_id(theirs), Some(id));
    }
}

#[test]
fn last_error_codes_map_to_their_kinds() {
    let table = [
        (LastErrorCode::NoError, None),
        (LastErrorCode::NoChange, None),
        (
            LastErrorCode::StuffError,
            Some((Error::Stuff, ErrorKind::Stuff)),
        ),
        (
            LastErrorCode::FormError,
            Some((Error::Form, ErrorKind::Form)),
        ),
        (
            LastErrorCode::AckError,
            Some((Error::Acknowledge, ErrorKind::Acknowledge)),
        ),
        (
            LastErrorCode::Bit1Error,
            Some((Error::Bit1, ErrorKind::Bit)),
        ),
        (
            LastErrorCode::Bit0Error,
            Some((Error::Bit0, ErrorKind::Bit)),
        ),
        (LastErrorCode::CRCError, Some((Error::Crc, ErrorKind::Crc))),
    ];
    for (lec, expected) in table {
        let got = lec_error(lec).map(|e| (e, e.kind()));
        assert_eq!(got, expected, "{lec:?}");
    }
    assert_eq!(Error::Overrun.kind(), ErrorKind::Overrun);
    for e in [Error::BusOff, Error::Unsupported, Error::NotClassic] {
        assert_eq!(e.kind(), ErrorKind::Other, "{e:?}");
    }
}

#[test]
fn transmit_headers_are_classic_with_the_frame_s_id_and_length() {
    let h = tx_header(&data_frame(ids::CONTROL, &[1, 2, 3, 4, 5, 6, 7, 8])).unwrap();
    assert_eq!(h.len, 8);
    assert_eq!(h.frame_format, FrameFormat::Standard);
    assert!(!h.bit_rate_switching);
    assert_eq!(h.id, fd_ext(ids::CONTROL));
    let std_id = StandardId::new(0x123).unwrap();
    let h = tx_header(&Frame::new(std_id, &[9; 3]).unwrap()).unwrap();
    assert_eq!(h.len, 3);
    assert_eq!(
        h.id,
        fdcan::id::Id::Standard(fdcan::id::StandardId::new(0x123).unwrap())
    );
    // A remote frame is length 0 to the fdcan crate; anything it cannot say is refused.
    let remote = Frame::new_remote(ext(5), 0).unwrap();
    assert_eq!(tx_header(&remote).unwrap().len, 0);
    let remote3 = Frame::new_remote(ext(5), 3).unwrap();
    assert_eq!(tx_header(&remote3).err(), Some(Error::Unsupported));
    assert_eq!(
        tx_header(&data_frame(5, &[])).err(),
        Some(Error::Unsupported)
    );
}

#[test]
fn received_frames_convert_and_fd_frames_are_refused() {
    let data = [0xA5u8; 64];
    let f = rx_frame(
        &rx_info(fd_ext(ids::POSTBACK), 8, FrameFormat::Standard, false),
        &data,
    )
    .unwrap();
    assert_eq!(f, data_frame(ids::POSTBACK, &[0xA5; 8]));
    let f = rx_frame(&rx_info(fd_ext(7), 2, FrameFormat::Standard, true), &data).unwrap();
    assert!(f.is_remote_frame());
    assert_eq!((f.dlc(), f.data()), (2, &[][..]));
    for (len, format) in [(8, FrameFormat::Fdcan), (12, FrameFormat::Standard)] {
        assert_eq!(
            rx_frame(&rx_info(fd_ext(7), len, format, false), &data),
            Err(Error::NotClassic)
        );
    }
}

#[test]
fn receive_reports_errors_then_frames_and_would_block_when_empty() {
    let (mut can, chip) = adapter();
    assert_eq!(can.receive(), Err(nb::Error::WouldBlock));
    let f = data_frame(ids::POSTBACK, &[1; 8]);
    chip.borrow_mut().push_rx(&f, false);
    chip.borrow_mut().lec = Some(LastErrorCode::AckError);
    // The error first (its code is cleared by the read), then the frame.
    assert_eq!(can.receive(), Err(nb::Error::Other(Error::Acknowledge)));
    assert_eq!(can.receive(), Ok(f));
    assert_eq!(can.receive(), Err(nb::Error::WouldBlock));
    // An overrun: the loss, then the frame that came with it.
    let g = data_frame(ids::POSTBACK, &[2; 8]);
    chip.borrow_mut().push_rx(&g, true);
    assert_eq!(can.receive(), Err(nb::Error::Other(Error::Overrun)));
    assert_eq!(can.receive(), Ok(g));
    assert_eq!(can.receive(), Err(nb::Error::WouldBlock));
    // The controller's flag stays set until cleared: the adapter clears it, so the
    // frames after are frames, not the same loss again.
    let h = data_frame(ids::POSTBACK, &[3; 8]);
    chip.borrow_mut().push_rx(&h, false);
    assert_eq!(can.receive(), Ok(h));
    assert!(!chip.borrow().lost);
    // An overrun with a frame the adapter cannot carry: the loss, then that error.
    chip.borrow_mut().push_rx_fd(true);
    assert_eq!(can.receive(), Err(nb::Error::Other(Error::Overrun)));
    assert_eq!(can.receive(), Err(nb::Error::Other(Error::NotClassic)));
    assert_eq!(can.receive(), Err(nb::Error::WouldBlock));
    // Bus-off is reported once, when it happens, and again after a recovery.
    chip.borrow_mut().bus_off = true;
    assert_eq!(can.receive(), Err(nb::Error::Other(Error::BusOff)));
    assert_eq!(can.receive(), Err(nb::Error::WouldBlock));
    chip.borrow_mut().bus_off = false;
    assert_eq!(can.receive(), Err(nb::Error::WouldBlock));
    chip.borrow_mut().bus_off = true;
    assert_eq!(can.receive(), Err(nb::Error::Other(Error::BusOff)));
    // The error code read with a bus-off is not lost: it comes next.
    {
        let mut c = chip.borrow_mut();
        c.bus_off = false;
    }
    assert_eq!(can.receive(), Err(nb::Error::WouldBlock));
    {
        let mut c = chip.borrow_mut();
        c.bus_off = true;
        c.lec = Some(LastErrorCode::Bit1Error);
    }
    assert_eq!(can.receive(), Err(nb::Error::Other(Error::BusOff)));
    assert_eq!(can.receive(), Err(nb::Error::Other(Error::Bit1)));
    assert_eq!(can.receive(), Err(nb::Error::WouldBlock));
}

#[test]
fn transmit_keeps_one_frame_in_flight() {
    let (mut can, chip) = adapter();
    let a = data_frame(0x100, &[1, 2, 3, 4, 5, 6, 7, 8]);
    assert_eq!(can.transmit(&a), Ok(None));
    // Pending: even a higher-priority frame waits (no displacement, no reordering).
    let b = data_frame(0x10, &[9; 8]);
    assert_eq!(can.transmit(&b), Err(nb::Error::WouldBlock));
    assert!(chip.borrow_mut().send_one());
    assert_eq!(can.transmit(&b), Ok(None));
    assert!(chip.borrow_mut().send_one());
    assert_eq!(chip.borrow().sent, [a, b]);
    // Short frames survive the trip through the buffer's words.
    let short = data_frame(0x300, &[0xAB, 0xCD, 0xEF]);
    assert_eq!(can.transmit(&short), Ok(None));
    assert!(chip.borrow_mut().send_one());
    assert_eq!(chip.borrow().sent.last(), Some(&short));
    // What the controller cannot carry is an error, not a silent change.
    assert_eq!(
        can.transmit(&Frame::new_remote(ext(1), 2).unwrap()),
        Err(nb::Error::Other(Error::Unsupported))
    );
}

#[test]
fn displaced_frames_are_rebuilt_from_the_buffer_words() {
    let (mut stub, chip) = {
        let s = Stub::default();
        let c = s.0.clone();
        (s, c)
    };
    let frames: Vec<Frame> = (0..3u8)
        .map(|i| data_frame(0x100 + u32::from(i), &[i, 1, 2, 3, 4, 5, 6, 0xF0 | i]))
        .collect();
    let mut keep = |_: Mailbox, h: TxFrameHeader, w: &[u32]| displaced_frame(h, w);
    for f in &frames {
        let h = tx_header(f).unwrap();
        assert_eq!(stub.transmit(h, f.data(), &mut keep), Ok(None));
    }
    let urgent = data_frame(0x10, &[7; 8]);
    let h = tx_header(&urgent).unwrap();
    assert_eq!(
        stub.transmit(h, urgent.data(), &mut keep),
        Ok(Some(Some(frames[0])))
    );
    let remote = Frame::new_remote(ext(0x1234), 0).unwrap();
    let h = tx_header(&remote).unwrap();
    assert_eq!(displaced_frame(h, &[0; 16]), Some(remote));
    assert_eq!(chip.borrow().mailboxes.iter().flatten().count(), 3);
}

#[test]
fn the_can_port_runs_over_the_adapter() {
    let (can, chip) = adapter();
    let mut link: Link = Link::new(Config::default());
    let mut port = CanPort::new(can);
    let mut sim = Simulator::new(SimConfig::default(), Instant::from_millis(0));
    // Six control commands at once: one goes out at a time, the rest wait their turn.
    let commands: Vec<GimbalCommand> = (0..6)
        .map(|i| GimbalCommand::Pitch(Pitch::from_deci(-100 * i).unwrap()))
        .collect();
    for &c in &commands {
        link.send(c).unwrap();
    }
    let mut busy = 0;
    for t in 0..1600u32 {
        let now = Instant::from_millis(t);
        port.poll(&mut link, now).unwrap();
        // Frames left waiting: the adapter answered WouldBlock.
        if link.has_transmit() {
            busy += 1;
        }
        // One frame a millisecond leaves the controller; the simulator takes it and its
        // postbacks arrive in the FIFO.
        let mut c = chip.borrow_mut();
        if c.send_one() {
            let f = *c.sent.last().unwrap();
            let Id::Extended(id) = f.id() else {
                panic!("standard ID sent")
            };
            sim.receive(id.as_raw(), f.data(), now).unwrap();
        }
        sim.poll(now);
        while let Some(f) = sim.pop_frame() {
            c.push_rx(&data_frame(f.id, &f.data), false);
        }
    }
    assert!(busy > 0, "the adapter never refused a frame");
    let sent: Vec<Frame> = chip.borrow().sent.clone();
    let expected: Vec<Frame> = commands
        .iter()
        .map(|c| {
            let f = idu_gimbal::wire::control::Command::from(*c).to_frame();
            data_frame(f.id, &f.data)
        })
        .collect();
    // Same ID: the controller keeps their order, nothing is displaced or lost.
    assert_eq!(sent, expected);
    assert_eq!(port.stats().driver_errors.total(), 0);
    let stats = link.stats();
    assert_eq!(stats.frames_sent, 6);
    assert_eq!(stats.postbacks, 3);
    assert_eq!(stats.frames_received, 12);
    assert!(link.is_link_up());
}

#[test]
fn frames_of_one_id_keep_their_order() {
    let (can, chip) = adapter();
    let mut link: Link = Link::new(Config::default());
    let mut port = CanPort::new(can);
    // Five text frames of one ID and two commands of another, queued at once.
    let text = b"0123456789abcdefghijklmnopqrstuvwxyz-+*/";
    link.send_text(text).unwrap();
    link.send(GimbalCommand::Zoom(idu_gimbal::wire::control::Zoom::In))
        .unwrap();
    link.send(GimbalCommand::Zoom(idu_gimbal::wire::control::Zoom::Stop))
        .unwrap();
    for t in 0..20 {
        port.poll(&mut link, Instant::from_millis(t)).unwrap();
        chip.borrow_mut().send_one();
    }
    let sent: Vec<(u32, [u8; 8])> = chip
        .borrow()
        .sent
        .iter()
        .map(|f| {
            let Id::Extended(id) = f.id() else {
                panic!("standard ID sent")
            };
            (id.as_raw(), f.data().try_into().unwrap())
        })
        .collect();
    let zoom = |z| {
        idu_gimbal::wire::control::Command::from(GimbalCommand::Zoom(z))
            .to_frame()
            .data
    };
    let mut expected = std::vec![
        (ids::CONTROL, zoom(idu_gimbal::wire::control::Zoom::In)),
        (ids::CONTROL, zoom(idu_gimbal::wire::control::Zoom::Stop)),
    ];
    for (i, chunk) in text.chunks(8).enumerate() {
        let id = if i == 4 { ids::TEXT_END } else { ids::TEXT };
        expected.push((id, chunk.try_into().unwrap()));
    }
    assert_eq!(sent, expected);
    assert_eq!(link.stats().frames_sent, 7);
    assert_eq!(port.stats().driver_errors.total(), 0);
}

#[test]
fn frames_say_what_they_are() {
    let std_id = Id::Standard(StandardId::new(0x123).unwrap());
    let standard = Frame::new(std_id, &[1, 2]).unwrap();
    assert!(!standard.is_extended());
    assert_eq!(
        (standard.id(), standard.dlc(), standard.data()),
        (std_id, 2, &[1u8, 2][..])
    );
    let extended = data_frame(ids::POSTBACK, &[9; 8]);
    assert!(extended.is_extended());
    assert!(!extended.is_remote_frame());
    assert_eq!(
        Frame::new(ext(1), &[0; 9]),
        None,
        "a classic frame carries 8 bytes at most"
    );
    // Remote frames: a length code of 0 to 8 and no data.
    for dlc in 0..=8 {
        let remote = Frame::new_remote(ext(ids::POSTBACK), dlc).unwrap();
        assert!(remote.is_remote_frame() && remote.is_extended());
        assert_eq!((remote.dlc(), remote.data()), (dlc, &[][..]), "dlc {dlc}");
    }
    assert_eq!(Frame::new_remote(ext(ids::POSTBACK), 9), None);
}

#[test]
fn errors_say_what_the_controller_saw() {
    let texts = [
        (Error::Stuff, "FDCAN: stuff error"),
        (Error::Form, "FDCAN: form error"),
        (Error::Acknowledge, "FDCAN: acknowledge error"),
        (Error::Bit1, "FDCAN: bit 1 error"),
        (Error::Bit0, "FDCAN: bit 0 error"),
        (Error::Crc, "FDCAN: CRC error"),
        (Error::Overrun, "FDCAN: receive FIFO overrun"),
        (Error::BusOff, "FDCAN: bus-off"),
        (Error::Unsupported, "FDCAN: frame not supported"),
        (Error::NotClassic, "FDCAN: CAN FD frame received"),
    ];
    for (e, text) in texts {
        assert_eq!(std::format!("{e}"), text);
    }
}
