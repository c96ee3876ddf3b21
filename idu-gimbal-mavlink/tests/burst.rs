//! Bursts of requests: every request answered exactly once, in full (its ACK and the message
//! it promises), whatever the outbox has room for and however the bytes are split: a frame
//! whose answer would not fit waits in the bridge, and the bytes after it are handed back.

mod common;
use common::*;

use idu_gimbal::video::{Camera as VideoCamera, Family};
use idu_gimbal::wire::ids;
use idu_gimbal::wire::postback::{GimbalType, Postback};
use idu_gimbal_mavlink::camera::CameraConfig;
use idu_gimbal_mavlink::{SerialInput, ANSWER_ROOM};
use mavio::dialects::common::enums::{MavCmd, MavResult};
use mavio::dialects::common::messages::CommandAck;
use proptest::prelude::*;

/// Requests that promise one message: (component, message id).
const REQUESTS: [(u8, u32); 5] = [(100, 259), (100, 260), (100, 261), (100, 262), (154, 283)];
/// The clients sending them.
const CLIENTS: [(u8, u8); 3] = [(255, 190), (255, 191), (1, 191)];

/// A camera bridge whose gimbal type is known (so CAMERA_INFORMATION is answered).
fn bridge() -> Firmware {
    let mut b =
        camera_bridge(CameraConfig::with_streams_of(&VideoCamera::new(Family::X3)).unwrap());
    let p = Postback {
        gimbal_type: GimbalType::X30,
        ..Postback::default()
    };
    for data in p.to_can_frames() {
        b.link.receive(ids::POSTBACK, &data, t(1));
    }
    b.poll(t(1));
    let _ = sent(&mut b);
    b
}

fn request(client: usize, seq: u8, which: usize) -> Vec<u8> {
    let (component, id) = REQUESTS[which];
    frame(
        CLIENTS[client],
        seq,
        &command((AP.0, component), MavCmd::RequestMessage, id as f32, 0.0),
    )
}

/// What came out: per client, the results of its ACKs in order; per message id, how many.
#[derive(Default, Debug)]
struct Answers {
    acks: Vec<Vec<MavResult>>,
    messages: std::collections::HashMap<u32, usize>,
}

impl Answers {
    fn take(&mut self, b: &mut Firmware) {
        if self.acks.is_empty() {
            self.acks = vec![Vec::new(); CLIENTS.len()];
        }
        for f in sent(b) {
            if f.message_id() == 77 {
                let ack: CommandAck = f.decode_message().unwrap();
                let c = CLIENTS
                    .iter()
                    .position(|&c| c == (ack.target_system, ack.target_component))
                    .unwrap();
                self.acks[c].push(ack.result);
            } else {
                *self.messages.entry(f.message_id()).or_default() += 1;
            }
        }
    }
}

/// The answers to `requests` (client, which of `REQUESTS`): each client one ACCEPTED ACK a
/// request of its own, and each message asked for as many times as it was, nothing dropped.
fn assert_all_answered(a: &Answers, requests: &[(usize, usize)], b: &Firmware) {
    for c in 0..CLIENTS.len() {
        let n = requests.iter().filter(|r| r.0 == c).count();
        let acks = a.acks.get(c).map_or(&[][..], |v| &v[..]);
        assert_eq!(acks, vec![MavResult::Accepted; n], "client {c}: {a:?}");
    }
    for (which, &(_, id)) in REQUESTS.iter().enumerate() {
        let n = requests.iter().filter(|r| r.1 == which).count();
        let got = a.messages.get(&id).copied().unwrap_or(0);
        assert_eq!(got, n, "message {id}: {a:?}");
    }
    assert_eq!(b.stats().outbox_full, 0, "{:?}", b.stats());
    assert!(!b.reader().is_waiting());
}

#[test]
fn six_information_requests_in_one_chunk_wait_for_room_and_are_all_answered() {
    // Six REQUEST_MESSAGE(CAMERA_INFORMATION) in one read once got six ACCEPTED and three
    // messages; then three ACCEPTED and three TEMPORARILY_REJECTED, a refusal's ACK lost
    // whenever not even it fitted.
    let mut b = bridge();
    let one = request(0, 0, 0).len();
    let burst: Vec<u8> = (0..6).flat_map(|i| request(0, i, 0)).collect();
    let taken = b.receive(&burst, t(10));
    // Each answer is an ACK and a CAMERA_INFORMATION; a request is acted on only with
    // ANSWER_ROOM free of the 1,024 bytes: the third waits, the bytes after it handed back.
    let answer = sent_len_of_one_answer();
    assert!(1024 - 2 * answer < ANSWER_ROOM && 1024 - answer >= ANSWER_ROOM);
    assert_eq!(taken, 3 * one, "the third frame waits whole in the bridge");
    assert!(b.reader().is_waiting());
    let mut a = Answers::default();
    a.take(&mut b);
    assert_eq!(a.acks[0], vec![MavResult::Accepted; 2]);
    // A poll takes the frame that waited once the outbox drained; then the rest.
    b.poll(t(11));
    assert!(!b.reader().is_waiting());
    a.take(&mut b);
    let mut rest = &burst[taken..];
    while !rest.is_empty() {
        let n = b.receive(rest, t(12));
        rest = &rest[n..];
        a.take(&mut b);
    }
    b.poll(t(13));
    a.take(&mut b);
    assert_all_answered(&a, &[(0, 0); 6], &b);
}

/// The bytes of one CAMERA_INFORMATION request's answer (its ACK and the message).
fn sent_len_of_one_answer() -> usize {
    let mut b = bridge();
    b.receive_all(&request(0, 0, 0), t(10));
    b.transmit_bytes().len()
}

#[test]
fn a_burst_read_from_a_serial_line_through_serial_input_is_answered_in_full() {
    // 40 requests from three clients, read 37 bytes at a time into a 64-byte input; what
    // the bridge holds is sent between reads, as a firmware's loop does.
    let mut b = bridge();
    let requests: Vec<(usize, usize)> = (0..40).map(|i| (i % 3, i % 5)).collect();
    let frames = burst_of(&requests);
    let line: Vec<u8> = frames.concat();
    let mut input: SerialInput<64> = SerialInput::new();
    let mut at = 0;
    let mut a = Answers::default();
    for call in 0.. {
        assert!(call < 1000, "the burst is not taken");
        let read = |buf: &mut [u8]| {
            let n = buf.len().min(37).min(line.len() - at);
            buf[..n].copy_from_slice(&line[at..at + n]);
            at += n;
            Ok::<usize, ()>(n)
        };
        input
            .receive(&mut b.bridge, &mut b.link, t(10), read)
            .unwrap();
        a.take(&mut b);
        if at == line.len() && input.held() == 0 && !b.reader().is_waiting() {
            break;
        }
        b.poll(t(11));
        a.take(&mut b);
    }
    assert_all_answered(&a, &requests, &b);
    assert_eq!(input.overlong_reads(), 0);
    // A read error ends the call, and is the caller's; nothing held is lost.
    assert_eq!(
        input.receive(&mut b.bridge, &mut b.link, t(12), |_| Err("overrun")),
        Err("overrun")
    );
}

/// A read that says it gave more bytes than the buffer holds breaks its contract: the
/// buffer is taken whole (the request in it answered) and the read counted, never silently.
#[test]
fn a_read_claiming_more_than_the_buffer_is_counted() {
    let mut b = bridge();
    let frame = request(0, 0, 0);
    let mut input: SerialInput<64> = SerialInput::new();
    let mut reads = 0;
    let read = |buf: &mut [u8]| {
        reads += 1;
        if reads > 1 {
            return Ok::<usize, ()>(0);
        }
        buf.fill(0);
        buf[..frame.len()].copy_from_slice(&frame);
        Ok(buf.len() + 5)
    };
    input
        .receive(&mut b.bridge, &mut b.link, t(10), read)
        .unwrap();
    assert_eq!(input.overlong_reads(), 1);
    assert_eq!(input.held(), 0);
    let mut a = Answers::default();
    a.take(&mut b);
    assert_all_answered(&a, &[(0, 0)], &b);
}

#[test]
fn six_information_requests_in_one_datagram_are_handed_back_and_all_answered() {
    let mut b = bridge();
    let one = request(0, 0, 0).len();
    let datagram: Vec<u8> = (0..6).flat_map(|i| request(0, i, 0)).collect();
    let mut a = Answers::default();
    let mut at = 0;
    let mut takes = Vec::new();
    while at < datagram.len() {
        let taken = b.receive_datagram(&datagram[at..], t(10));
        assert_eq!(taken.bytes % one, 0, "handed back at a frame's start");
        assert_eq!(taken.good as usize, taken.bytes / one);
        takes.push(taken.bytes / one);
        at += taken.bytes;
        // Nothing of the datagram stays in the bridge: the next sender's datagram starts
        // clean.
        assert_eq!(b.reader().pending(), 0);
        a.take(&mut b);
    }
    // Two answers fit the outbox at a time.
    assert_eq!(takes, [2, 2, 2]);
    assert_all_answered(&a, &[(0, 0); 6], &b);
}

#[test]
fn a_waiting_frame_holds_back_the_frames_after_it_in_order() {
    // A request waits; the heartbeat after it is not taken before it.
    let mut b = bridge();
    let mut bytes: Vec<u8> = (0..3).flat_map(|i| request(0, i, 0)).collect();
    let three = bytes.len();
    bytes.extend(frame(CLIENTS[1], 9, &heartbeat()));
    let before = b.stats().reader.frames;
    assert_eq!(b.receive(&bytes, t(10)), three);
    // Two requests taken, the third waits (not yet counted), the heartbeat not read.
    assert_eq!(b.stats().reader.frames - before, 2);
    // Without a drain, nothing moves.
    assert_eq!(b.receive(&bytes[three..], t(11)), 0);
    b.poll(t(11));
    assert!(b.reader().is_waiting());
    let _ = sent(&mut b);
    assert_eq!(b.receive(&bytes[three..], t(12)), bytes.len() - three);
    assert_eq!(b.stats().reader.frames - before, 4);
}

/// Requests as (client, which of [`REQUESTS`]), and where to cut and whether to drain there.
type Burst = (Vec<(usize, usize)>, Vec<(usize, bool)>);

/// Requests and where to cut and drain, for the properties below.
fn requests_and_cuts() -> impl Strategy<Value = Burst> {
    (
        prop::collection::vec((0..CLIENTS.len(), 0..REQUESTS.len()), 1..40),
        prop::collection::vec((1usize..400, any::<bool>()), 1..40),
    )
}

fn burst_of(requests: &[(usize, usize)]) -> Vec<Vec<u8>> {
    requests
        .iter()
        .enumerate()
        .map(|(i, &(client, which))| request(client, i as u8, which))
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Any interleaving of requests from three clients, as a byte stream fed in any split,
    /// the outbox drained at any points (and whenever nothing was taken): every request is
    /// answered exactly once, ACCEPTED with its message, and nothing is dropped.
    #[test]
    fn every_request_in_a_stream_is_answered_once_in_full(
        (requests, cuts) in requests_and_cuts(),
    ) {
        let mut b = bridge();
        let frames = burst_of(&requests);
        let bytes = frames.concat();
        let mut a = Answers::default();
        let mut at = 0;
        for (ms, &(len, drain)) in (10..).zip(cuts.iter().cycle()) {
            if at >= bytes.len() {
                break;
            }
            let end = (at + len).min(bytes.len());
            let taken = b.receive(&bytes[at..end], t(ms));
            prop_assert!(taken <= end - at);
            at += taken;
            if drain || taken == 0 {
                a.take(&mut b);
                b.poll(t(ms));
            }
        }
        a.take(&mut b);
        b.poll(t(1_000));
        a.take(&mut b);
        assert_all_answered(&a, &requests, &b);
    }

    /// The same requests in datagrams of any number of frames: each datagram taken up to a
    /// frame that waits, offered again after a drain, every request answered once in full.
    #[test]
    fn every_request_in_datagrams_is_answered_once_in_full(
        (requests, cuts) in requests_and_cuts(),
    ) {
        let mut b = bridge();
        let frames = burst_of(&requests);
        let mut a = Answers::default();
        let mut frames = frames.as_slice();
        for (ms, &(len, drain)) in (10..).zip(cuts.iter().cycle()) {
            if frames.is_empty() {
                break;
            }
            let (these, rest) = frames.split_at((len % 8 + 1).min(frames.len()));
            frames = rest;
            let datagram = these.concat();
            let mut at = 0;
            while at < datagram.len() {
                let taken = b.receive_datagram(&datagram[at..], t(ms));
                at += taken.bytes;
                prop_assert_eq!(b.reader().pending(), 0);
                if drain || at < datagram.len() {
                    a.take(&mut b);
                }
            }
        }
        a.take(&mut b);
        assert_all_answered(&a, &requests, &b);
    }
}

#[test]
fn the_room_a_frame_waits_for_is_a_signed_ack_and_two_whole_frames() {
    // MAVLink 2: a 10-byte header, COMMAND_ACK's 10-byte payload (command u16, result,
    // progress, result_param2 i32, target system and component), a 2-byte checksum and a
    // 13-byte signature: 35; the largest frame is 280 bytes, signed.
    assert_eq!(ANSWER_ROOM, 35 + 2 * 280);
}
