//! `gimbalctl mavlink --sim` over real UDP sockets: clients that reconnect from new ports
//! are always answered, garbage senders never become peers nor hide a good client, and each
//! datagram is parsed on its own.
//!
//! Frames are built with `mavio` (re-exported by the bridge) and every reply is checked to be
//! exactly one valid MAVLink 2 frame. Answers normally come within ~10 ms (the attitude
//! status within 100 ms); the deadlines are 2 to 3 s so that a loaded machine does not fail
//! the test. Every wait is bounded, and the bridge is killed when a test ends.

mod common;

use common::mavlink::{frame, heartbeat, request_information, GIMBAL};
use common::{hex, start, Guard, Log};

use std::collections::HashSet;
use std::io::ErrorKind;
use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;
use std::thread;
use std::time::{Duration, Instant};

use idu_gimbal_mavlink::framing::{Check, FrameReader};
use idu_gimbal_mavlink::mavio;
use mavio::dialects::common::enums::{MavAutopilot, MavCmd, MavResult, MavType};
use mavio::dialects::common::messages::{
    AutopilotStateForGimbalDevice, CommandAck, CommandLong, FileTransferProtocol,
    GimbalDeviceInformation, GimbalDeviceSetAttitude, GlobalPositionInt, Heartbeat,
};
use mavio::dialects::common::Common;
use mavio::protocol::{Frame, V2};
use mavio::Message;

/// A ground station: system 255, component 190 (MAV_COMP_ID_MISSIONPLANNER).
const GCS: (u8, u8) = (255, 190);
/// The bridge's camera (MAV_COMP_ID_CAMERA).
const CAMERA: u8 = 100;
/// How long a client waits for the bridge's heartbeat or status (sent every 100 ms).
const TRAFFIC: Duration = Duration::from_secs(3);
/// How long a client waits for the answers to a request (normally ~10 ms).
const ANSWERS: Duration = Duration::from_secs(2);
/// The bridge's own limit on a run: far beyond any test, in case a kill were missed.
const RUN_LIMIT_MS: &str = "60000";

/// `gimbalctl mavlink --sim` on an ephemeral loopback port, killed when dropped.
struct Bridge {
    guard: Guard,
    addr: SocketAddr,
    stderr: Log,
}

impl Bridge {
    fn start() -> Bridge {
        Bridge::start_with(&[])
    }

    /// The bridge with `extra` arguments.
    fn start_with(extra: &[&str]) -> Bridge {
        let mut args = vec![
            "mavlink",
            "--sim",
            "--listen",
            "127.0.0.1:0",
            "--exit-after-ms",
            RUN_LIMIT_MS,
        ];
        args.extend_from_slice(extra);
        let (guard, line, stderr) = start(
            &args,
            "gimbalctl mavlink: listening on ",
            Duration::from_secs(10),
        );
        let addr = line
            .split("listening on ")
            .nth(1)
            .and_then(|rest| rest.split(',').next())
            .and_then(|a| a.parse().ok())
            .unwrap_or_else(|| panic!("no address in {line:?}"));
        Bridge {
            guard,
            addr,
            stderr,
        }
    }

    /// Kills the bridge; what it wrote on stderr.
    fn stop(self) -> String {
        let Bridge { guard, stderr, .. } = self;
        drop(guard);
        stderr.finish()
    }
}

fn socket() -> UdpSocket {
    UdpSocket::bind("127.0.0.1:0").expect("bind a client socket")
}

/// A ground station's heartbeat.
fn gcs_heartbeat() -> Heartbeat {
    heartbeat(MavType::Gcs, MavAutopilot::Invalid)
}

/// The one frame a datagram from the bridge must hold: whole, and valid in the common
/// dialect (CRC included).
fn one_frame(datagram: &[u8]) -> Frame<V2> {
    let mut frames = Vec::new();
    let mut reader = FrameReader::new();
    reader.feed(datagram, |f| {
        frames.push(f.to_frame());
        Check::Unhandled
    });
    assert_eq!(reader.pending(), 0, "a cut frame: {}", hex(datagram));
    assert_eq!(
        reader.stats().skipped_bytes,
        0,
        "garbage: {}",
        hex(datagram)
    );
    assert_eq!(frames.len(), 1, "one frame a datagram: {}", hex(datagram));
    let f = frames
        .pop()
        .flatten()
        .unwrap_or_else(|| panic!("mavio refuses {}", hex(datagram)));
    if let Err(e) = f.decode::<Common>() {
        panic!("not a valid MAVLink 2 frame ({e:?}): {}", hex(datagram));
    }
    f
}

/// The next frame sent to `sock`, or `None` once `deadline` has passed.
fn recv_frame(sock: &UdpSocket, deadline: Instant) -> Option<Frame<V2>> {
    let mut buf = [0u8; 2048];
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return None;
        }
        sock.set_read_timeout(Some(left)).expect("read timeout");
        match sock.recv(&mut buf) {
            Ok(n) => return Some(one_frame(&buf[..n])),
            Err(e)
                if matches!(
                    e.kind(),
                    ErrorKind::WouldBlock | ErrorKind::TimedOut | ErrorKind::Interrupted
                ) => {}
            Err(e) => panic!("recv: {e}"),
        }
    }
}

/// Whether `sock` hears anything from the gimbal component before `deadline`.
fn hears_gimbal(sock: &UdpSocket, deadline: Instant) -> bool {
    while let Some(f) = recv_frame(sock, deadline) {
        if f.component_id() == GIMBAL {
            return true;
        }
    }
    false
}

/// What a client has of the answers to [`request_information`] (of any system).
#[derive(Default, Debug)]
struct Answers {
    /// COMMAND_ACK, MAV_RESULT_ACCEPTED, addressed to the client.
    ack: bool,
    /// GIMBAL_DEVICE_INFORMATION from the gimbal.
    information: bool,
}

impl Answers {
    fn all(&self) -> bool {
        self.ack && self.information
    }

    /// Takes the frames sent to `sock` (client `me`) until both answers are in or
    /// `deadline` has passed.
    fn collect(&mut self, sock: &UdpSocket, me: (u8, u8), deadline: Instant) {
        while !self.all() {
            let Some(f) = recv_frame(sock, deadline) else {
                return;
            };
            if f.component_id() != GIMBAL {
                continue;
            }
            if f.message_id() == CommandAck::ID {
                let ack: CommandAck = f.decode_message().expect("COMMAND_ACK");
                if ack.command == MavCmd::RequestMessage
                    && (ack.target_system, ack.target_component) == me
                {
                    assert_eq!(ack.result, MavResult::Accepted, "{ack:?}");
                    self.ack = true;
                }
            } else if f.message_id() == GimbalDeviceInformation::ID {
                let info: GimbalDeviceInformation =
                    f.decode_message().expect("GIMBAL_DEVICE_INFORMATION");
                assert_eq!(&info.vendor_name[..3], b"IDU", "{info:?}");
                self.information = true;
            }
        }
    }
}

/// How many peer lines of `kind` (`joined`, `left`, `refused`) stderr tells of: said, or
/// held back (at most 10 lines a second) and summed up by kind.
fn peer_events(stderr: &str, kind: &str) -> usize {
    let said = stderr
        .lines()
        .filter(|l| {
            l.contains("gimbalctl mavlink: ")
                && l.contains(" peer ")
                && l.contains(&format!(" {kind}"))
        })
        .filter(|l| !l.contains("held back"))
        .count();
    let held: usize = stderr
        .lines()
        .filter(|l| l.contains("peer lines held back (at most 10 a second)"))
        .map(|l| {
            let n = l.split(&format!(" {kind}")).next().unwrap();
            n.rsplit(' ').next().unwrap().parse::<usize>().unwrap()
        })
        .sum();
    said + held
}

/// The table holds 64 peers and keeps a silent one 10 s: 20 clients in a row, each from a
/// new port and gone after its answer, each answered (the old fixed list of 8 ignored the
/// ninth on).
#[test]
fn twenty_clients_in_a_row_from_new_ports_are_all_answered() {
    let bridge = Bridge::start();
    let mut ports = HashSet::new();
    // A port the kernel hands out again is held open aside, so that each client's is new
    // and the joins are exactly countable.
    let mut reused = Vec::new();
    for i in 1..=20 {
        let client = loop {
            let s = socket();
            if ports.insert(s.local_addr().expect("local address").port()) {
                break s;
            }
            reused.push(s);
        };
        let sent = Instant::now();
        client
            .send_to(&frame(GCS, 0, &gcs_heartbeat()), bridge.addr)
            .expect("send");
        assert!(
            hears_gimbal(&client, sent + TRAFFIC),
            "client {i} heard nothing from the gimbal within {TRAFFIC:?}"
        );
        // Gone: its port closed, as a ground station that reconnects leaves it.
        drop(client);
    }
    // Peer lines past ten a second are summed when the second ends: the last joins may be
    // said a second after the last client's answer.
    let deadline = Instant::now() + Duration::from_secs(3);
    while peer_events(&bridge.stderr.text(), "joined") < 20 && Instant::now() < deadline {
        thread::sleep(Duration::from_millis(20));
    }
    let stderr = bridge.stop();
    // 20 distinct ports: 20 joins into free slots, none refused, none left (all within the
    // 10 s a silent peer is kept).
    assert_eq!(ports.len(), 20);
    assert_eq!(peer_events(&stderr, "joined"), 20, "{stderr}");
    assert_eq!(peer_events(&stderr, "refused"), 0, "{stderr}");
    assert_eq!(peer_events(&stderr, "left"), 0, "{stderr}");
    drop(reused);
}

/// A ground station beating at 1 Hz among 70 sockets beating at 2 Hz, more than the 64
/// slots: it joined first and is live, so it is never evicted and hears the gimbal every
/// second (it once heard nothing for 6 s, and QGroundControl drops a link after 3.5 s);
/// the sockets beyond the table are refused, said once each, the lines at most 10 a second.
#[test]
fn a_live_ground_station_keeps_its_slot_in_a_crowd() {
    let bridge = Bridge::start();
    let gcs = socket();
    gcs.send_to(&frame(GCS, 0, &gcs_heartbeat()), bridge.addr)
        .expect("send");
    assert!(hears_gimbal(&gcs, Instant::now() + TRAFFIC));
    let crowd: Vec<UdpSocket> = (0..70)
        .map(|_| {
            let s = socket();
            s.set_nonblocking(true).expect("non-blocking");
            s
        })
        .collect();
    let start = Instant::now();
    let mut heard_at = Vec::new();
    let mut next_gcs = start;
    let mut next_crowd = start;
    while start.elapsed() < Duration::from_secs(6) {
        let now = Instant::now();
        if now >= next_crowd {
            for (i, s) in crowd.iter().enumerate() {
                let from = (200, 10 + (i % 100) as u8);
                let _ = s.send_to(&frame(from, 0, &gcs_heartbeat()), bridge.addr);
                // Drain what the bridge sends them, so their buffers never fill.
                let mut buf = [0u8; 300];
                while s.recv_from(&mut buf).is_ok() {}
            }
            next_crowd += Duration::from_millis(500);
        }
        if now >= next_gcs {
            gcs.send_to(&frame(GCS, 0, &gcs_heartbeat()), bridge.addr)
                .expect("send");
            next_gcs += Duration::from_secs(1);
        }
        if let Some(f) = recv_frame(&gcs, now + Duration::from_millis(20)) {
            if f.component_id() == GIMBAL && f.message_id() == 0 {
                heard_at.push(start.elapsed());
            }
        }
    }
    let stderr = bridge.stop();
    // The gimbal's heartbeat is 1 Hz: at least 5 in 6 s, none more than 2.5 s apart as
    // read here (a second, and up to 1.5 s that this thread or the bridge stalls on a
    // loaded machine), under the 3.5 s after which QGroundControl drops the link.
    assert!(heard_at.len() >= 5, "{heard_at:?}\n{stderr}");
    let gaps = heard_at.windows(2).map(|w| w[1] - w[0]);
    assert!(
        gaps.clone().all(|g| g < Duration::from_millis(2_500)),
        "{heard_at:?}"
    );
    // 63 of the crowd joined beside it; 7 were refused, once each. At most 10 peer lines a
    // second: the rest summed up by kind.
    assert_eq!(peer_events(&stderr, "joined"), 64, "{stderr}");
    assert_eq!(peer_events(&stderr, "refused"), 7, "{stderr}");
    assert_eq!(stderr.matches("replacing").count(), 0, "{stderr}");
    let per_second = stderr
        .lines()
        .filter(|l| l.contains("gimbalctl mavlink: peer "))
        .count();
    assert!(
        per_second <= 10 * 7,
        "{per_second} peer lines in 6 s\n{stderr}"
    );
}

/// One datagram of garbage, never a frame the bridge would take: random bytes; a MAVLink 2
/// start (0xFD, a length, a header) cut short of that length; a real frame cut short; a
/// real frame with a damaged CRC.
fn garbage(rng: &mut fastrand::Rng, seq: u8) -> Vec<u8> {
    let real = |rng: &mut fastrand::Rng| {
        if rng.bool() {
            frame(GCS, seq, &gcs_heartbeat())
        } else {
            frame(GCS, seq, &request_information(0))
        }
    };
    match rng.u8(..4) {
        0 => {
            let n = rng.usize(1..=300);
            std::iter::repeat_with(|| rng.u8(..)).take(n).collect()
        }
        1 => {
            let len = rng.usize(20..256);
            // Message ids the bridge handles among others: HEARTBEAT, COMMAND_LONG,
            // GIMBAL_DEVICE_SET_ATTITUDE, AUTOPILOT_STATE_FOR_GIMBAL_DEVICE, random.
            let id = [0u32, 76, 284, 286, rng.u32(..=0xFF_FFFF)][rng.usize(..5)];
            let mut d = vec![0xFD, len as u8, 0, 0, seq, rng.u8(..), rng.u8(..)];
            d.extend_from_slice(&id.to_le_bytes()[..3]);
            // At most the payload: the CRC and some payload are always missing.
            let have = rng.usize(..len);
            d.extend(std::iter::repeat_with(|| rng.u8(..)).take(have));
            d
        }
        2 => {
            let mut f = real(rng);
            let cut = rng.usize(1..f.len());
            f.truncate(cut);
            f
        }
        _ => {
            let mut f = real(rng);
            let last = f.len() - 1;
            f[last] ^= 0xA5;
            f
        }
    }
}

/// 50 sockets flood the bridge with garbage while a good client asks for the gimbal's
/// information: the client gets its COMMAND_ACK and GIMBAL_DEVICE_INFORMATION within 2 s,
/// during the flood, and no garbage socket ever hears anything (none became a peer).
#[test]
fn garbage_floods_never_become_peers_nor_hide_a_good_client() {
    /// Datagrams per socket between pauses: 50 sockets make a burst of 50 a millisecond,
    /// several times what a busy MAVLink link carries, yet below what the bridge's socket
    /// buffer holds, so the kernel seldom has to drop the good client's datagrams.
    const SOCKETS: usize = 50;
    /// The flood goes on at least this long (in datagrams) and at most this long.
    const FLOOD_MIN: usize = 2_000;
    const FLOOD_MAX: usize = 200_000;
    const FLOOD_TIME: Duration = Duration::from_secs(4);
    /// A ground station resends an unanswered command; here after 250 ms, only because
    /// the kernel may drop a datagram when the flood fills the bridge's socket buffer.
    const RESEND: Duration = Duration::from_millis(250);

    let bridge = Bridge::start();
    let flooders: Vec<UdpSocket> = (0..SOCKETS).map(|_| socket()).collect();
    let client = socket();
    let answered = AtomicBool::new(false);
    let sent = AtomicUsize::new(0);
    let (started_tx, started) = mpsc::channel();
    let (at_answer, flood_total, answers, waited) = thread::scope(|s| {
        let flood = s.spawn(|| {
            // Seeded: the same flood every run.
            let mut rng = fastrand::Rng::with_seed(0x9E37_79B9_7F4A_7C15);
            let begin = Instant::now();
            let mut n = 0usize;
            while n < FLOOD_MAX && begin.elapsed() < FLOOD_TIME {
                // Answered: one more burst, so that the flood is seen to go on past the
                // answers however late they came.
                let last = n >= FLOOD_MIN && answered.load(Ordering::Acquire);
                for sock in &flooders {
                    // UDP: a datagram the kernel drops is as good as sent.
                    let _ = sock.send_to(&garbage(&mut rng, n as u8), bridge.addr);
                    n += 1;
                }
                sent.store(n, Ordering::Release);
                if n == 10 * SOCKETS {
                    let _ = started_tx.send(());
                }
                if last {
                    break;
                }
                thread::sleep(Duration::from_millis(1));
            }
            n
        });
        started
            .recv_timeout(Duration::from_secs(10))
            .expect("the flood started");
        let begin = Instant::now();
        let deadline = begin + ANSWERS;
        let mut answers = Answers::default();
        let mut seq = 0u8;
        while !answers.all() && Instant::now() < deadline {
            for m in [&gcs_heartbeat() as &dyn Message, &request_information(0)] {
                client
                    .send_to(&frame(GCS, seq, m), bridge.addr)
                    .expect("send");
                seq = seq.wrapping_add(1);
            }
            answers.collect(&client, GCS, (Instant::now() + RESEND).min(deadline));
        }
        let waited = begin.elapsed();
        let at_answer = sent.load(Ordering::Acquire);
        answered.store(true, Ordering::Release);
        let total = flood.join().expect("flood thread");
        (at_answer, total, answers, waited)
    });
    assert!(
        answers.all(),
        "within {ANSWERS:?} during the flood: {answers:?}"
    );
    assert!(waited < ANSWERS, "{waited:?}");
    assert!(
        flood_total > at_answer && flood_total >= FLOOD_MIN,
        "the flood went on past the answers: {at_answer} then {flood_total} datagrams"
    );
    // A peer is sent the attitude status every 100 ms: had any garbage socket become one,
    // 300 ms after the flood its buffer would hold frames (whatever it was sent earlier
    // is still there too).
    thread::sleep(Duration::from_millis(300));
    let mut buf = [0u8; 2048];
    for (i, sock) in flooders.iter().enumerate() {
        sock.set_nonblocking(true).expect("non-blocking");
        match sock.recv(&mut buf) {
            Err(e) if e.kind() == ErrorKind::WouldBlock => {}
            other => panic!("garbage socket {i} was sent something: {other:?}"),
        }
    }
    let stderr = bridge.stop();
    assert_eq!(
        stderr.matches(" joined").count(),
        1,
        "only the good client joined: {stderr}"
    );
}

/// A datagram ending in half a frame, then a datagram from another sender with a whole
/// HEARTBEAT and REQUEST_MESSAGE, shorter than what the half frame lacks: parsed as one
/// byte stream, the second datagram would go to finish the first's frame and be lost.
/// Parsed each on its own, the second sender is answered, and the first one's whole
/// heartbeat still counts.
#[test]
fn each_datagram_is_parsed_on_its_own() {
    let bridge = Bridge::start();
    let first = socket();
    let second = socket();
    let (a, b) = ((250, 190), (251, 190));
    // A whole heartbeat, then the first half of a 266-byte FILE_TRANSFER_PROTOCOL frame.
    let ftp = frame(
        a,
        1,
        &FileTransferProtocol {
            target_network: 0,
            target_system: 1,
            target_component: 1,
            payload: [0x55; 251],
        },
    );
    let half = ftp.len() / 2;
    let mut cut = frame(a, 0, &gcs_heartbeat());
    cut.extend_from_slice(&ftp[..half]);
    let mut whole = frame(b, 0, &gcs_heartbeat());
    whole.extend(frame(b, 1, &request_information(0)));
    assert!(
        whole.len() < ftp.len() - half,
        "{} bytes would all go into the cut frame ({} missing)",
        whole.len(),
        ftp.len() - half
    );
    first.send_to(&cut, bridge.addr).expect("send");
    second.send_to(&whole, bridge.addr).expect("send");
    // No resend here: on an idle loopback two datagrams are not lost, and a resend would
    // hide a byte stream that swallowed the first.
    let mut answers = Answers::default();
    answers.collect(&second, b, Instant::now() + ANSWERS);
    assert!(answers.all(), "the second sender: {answers:?}");
    assert!(
        hears_gimbal(&first, Instant::now() + TRAFFIC),
        "the first sender's whole heartbeat made it a peer"
    );
    let stderr = bridge.stop();
    assert_eq!(stderr.matches(" joined").count(), 2, "{stderr}");
}

/// Requests back to back, as a ground station starting up sends them, and a datagram of
/// more requests than the outbox holds answers for: every one answered ACCEPTED with its
/// message. (Each tick once read up to 256 datagrams into the 1,024-byte outbox before
/// sending: 16 requests got 11 ACKs and 9 messages; then six in one datagram got three
/// ACCEPTED and three TEMPORARILY_REJECTED.)
#[test]
fn a_burst_of_requests_is_answered_in_full() {
    let bridge = Bridge::start();
    let client = socket();
    // The bridge's system id: the autopilot's, 1 until one is heard.
    let burst: Vec<Vec<u8>> = (0..16)
        .map(|seq| frame(GCS, seq, &request_information(1)))
        .collect();
    for d in &burst {
        client.send_to(d, bridge.addr).expect("send");
    }
    // Twelve in one datagram: the bridge takes it in parts, sending as it goes.
    let twelve: Vec<u8> = (16..28)
        .flat_map(|seq| frame(GCS, seq, &request_information(1)))
        .collect();
    client.send_to(&twelve, bridge.addr).expect("send");
    let (mut accepted, mut other, mut information) = (0, 0, 0);
    let deadline = Instant::now() + ANSWERS;
    while let Some(f) = recv_frame(&client, deadline) {
        if f.component_id() != GIMBAL {
            continue;
        }
        match f.decode::<Common>() {
            Ok(Common::CommandAck(a)) if a.result == MavResult::Accepted => accepted += 1,
            Ok(Common::CommandAck(_)) => other += 1,
            Ok(Common::GimbalDeviceInformation(_)) => information += 1,
            _ => {}
        }
    }
    let stderr = bridge.stop();
    assert_eq!(
        (accepted, other),
        (28, 0),
        "every request ACCEPTED\n{stderr}"
    );
    assert_eq!(information, 28, "every ACCEPTED its message\n{stderr}");
}

/// Zoom steps back to back, as QGroundControl's pinch sends them (each SET_CAMERA_ZOOM
/// ZOOM_TYPE_STEP −10 is five halvings for the gimbal's eight-command queue): every one
/// ACCEPTED. (The gimbal side once moved only after all of a tick's datagrams were read:
/// the second step of a tick found three slots and was TEMPORARILY_REJECTED.)
#[test]
fn zoom_steps_back_to_back_are_each_accepted() {
    let bridge = Bridge::start();
    let client = socket();
    let step = CommandLong {
        target_system: 1,
        target_component: CAMERA,
        command: MavCmd::SetCameraZoom,
        // ZOOM_TYPE_STEP, −10 steps: the bridge sends the gimbal five halvings.
        param1: 0.0,
        param2: -10.0,
        ..Default::default()
    };
    const STEPS: usize = 6;
    for seq in 0..STEPS {
        client
            .send_to(&frame(GCS, seq as u8, &step), bridge.addr)
            .expect("send");
    }
    let mut results = Vec::new();
    let deadline = Instant::now() + ANSWERS;
    while let Some(f) = recv_frame(&client, deadline) {
        if f.component_id() != CAMERA {
            continue;
        }
        if let Ok(Common::CommandAck(a)) = f.decode::<Common>() {
            if a.command == MavCmd::SetCameraZoom {
                results.push(a.result);
            }
        }
    }
    let stderr = bridge.stop();
    assert_eq!(
        results,
        [MavResult::Accepted; STEPS],
        "every step ACCEPTED\n{stderr}"
    );
}

/// The counts of the "warning: N ..." lines on `stderr` that hold `mark`, summed.
fn said(stderr: &str, mark: &str) -> u64 {
    stderr
        .lines()
        .filter(|l| l.contains(mark))
        .filter_map(|l| {
            l.split("warning: ")
                .nth(1)?
                .split(' ')
                .next()?
                .parse::<u64>()
                .ok()
        })
        .sum()
}

/// The counts of the "N datagram(s) to ADDR not sent: ..." lines on `stderr` for `to`,
/// summed.
fn said_unsent(stderr: &str, to: &str) -> u64 {
    said(stderr, &format!(" to {to} not sent: "))
}

/// Datagrams the socket refuses are counted by destination and said, never lost without a
/// word: a `--to` address beyond a loopback socket's reach (with the remedy) and a
/// broadcast address are each refused every frame the bridge sends, which a `--to` socket
/// that can be reached receives; and the total said at the end is their sum.
#[test]
fn datagrams_the_socket_refuses_are_counted_and_said() {
    let sink = socket();
    let sink_addr = sink.local_addr().expect("sink address").to_string();
    // A loopback socket cannot send beyond this host (Linux: EINVAL) nor to a broadcast
    // address without SO_BROADCAST (EACCES).
    const BEYOND: &str = "10.255.255.1:14550";
    const BROADCAST: &str = "127.255.255.255:14550";
    let out = common::run_timeout(
        &[
            "mavlink",
            "--sim",
            "--listen",
            "127.0.0.1:0",
            "--to",
            &sink_addr,
            "--to",
            BEYOND,
            "--to",
            BROADCAST,
            "--exit-after-ms",
            "1500",
        ],
        b"",
        Duration::from_secs(30),
    );
    assert_eq!(out.code, 0, "{}", out.stderr);
    // Every datagram the sink was sent is waiting in its buffer (a few dozen, on loopback).
    sink.set_nonblocking(true).expect("non-blocking");
    let mut buf = [0u8; 512];
    let mut received = 0u64;
    while sink.recv_from(&mut buf).is_ok() {
        received += 1;
    }
    assert!(
        received > 0,
        "the reachable --to address is sent to\n{}",
        out.stderr
    );
    assert_eq!(
        said_unsent(&out.stderr, BEYOND),
        received,
        "every frame refused for the address beyond reach\n{}",
        out.stderr
    );
    assert_eq!(
        said_unsent(&out.stderr, BROADCAST),
        received,
        "every frame refused for the broadcast address\n{}",
        out.stderr
    );
    assert_eq!(said_unsent(&out.stderr, &sink_addr), 0, "{}", out.stderr);
    assert!(
        out.stderr
            .contains("a loopback address: --listen 0.0.0.0:PORT reaches other hosts")
            && out.stderr.contains("(a broadcast address is not sent to)"),
        "the reasons are said with the remedy\n{}",
        out.stderr
    );
    assert!(
        out.stderr
            .contains(&format!("{} datagrams not sent in all", 2 * received)),
        "the total\n{}",
        out.stderr
    );
}

/// What the bridge does not act on from an autopilot is said, never ignored without a
/// word: a state whose quaternion is not finite and a position whose latitude is beyond
/// 90° (two vehicle updates not passed on), and the heartbeat of a second autopilot
/// while the first is followed.
#[test]
fn vehicle_updates_and_autopilots_not_followed_are_said() {
    let bridge = Bridge::start();
    let client = socket();
    const AUTOPILOT: (u8, u8) = (1, 1);
    let state = AutopilotStateForGimbalDevice {
        target_system: AUTOPILOT.0,
        target_component: GIMBAL,
        q: [f32::NAN, 0.0, 0.0, 1.0],
        angular_velocity_z: f32::NAN,
        ..Default::default()
    };
    let position = GlobalPositionInt {
        lat: 900_000_001,
        lon: 85_455_940,
        ..Default::default()
    };
    let quadrotor = heartbeat(MavType::Quadrotor, MavAutopilot::Px4);
    let datagrams = [
        frame(AUTOPILOT, 0, &quadrotor),
        frame(AUTOPILOT, 1, &state),
        frame(AUTOPILOT, 2, &position),
        frame((2, 1), 0, &quadrotor),
    ];
    for d in &datagrams {
        client.send_to(d, bridge.addr).expect("send");
    }
    // Said at the once-a-second note, as the counts grow: the two updates in one line or,
    // should a note fall between their datagrams, in two.
    bridge.stderr.wait(
        "warning: 1 heartbeat of another autopilot ignored: following system 1 (--system-id pins it)",
        Duration::from_secs(5),
    );
    let deadline = Instant::now() + Duration::from_secs(5);
    while said_refused(&bridge.stderr.text()) < 2 && Instant::now() < deadline {
        thread::sleep(Duration::from_millis(5));
    }
    let stderr = bridge.stop();
    assert_eq!(said_refused(&stderr), 2, "{stderr}");
    assert!(
        stderr.contains(" not passed to the gimbal: a quaternion that gives no finite attitude, or a latitude or longitude out of range\n"),
        "the reason\n{stderr}"
    );
}

/// The counts of the "warning: N vehicle update(s) not passed to the gimbal: ..." lines on
/// `stderr`, summed.
fn said_refused(stderr: &str) -> u64 {
    said(stderr, " not passed to the gimbal: ")
}

/// What held no frame for the bridge, and a setpoint it cannot follow, are said, never
/// dropped without a word: a MAVLink 1 heartbeat (17 bytes the MAVLink 2 reader skips), a
/// MAVLink 2 frame whose checksum is broken, and a setpoint pitched 80° up (the gimbal
/// reaches 60°).
#[test]
fn what_the_bridge_cannot_read_or_follow_is_said() {
    let bridge = Bridge::start();
    let client = socket();
    const AUTOPILOT: (u8, u8) = (1, 1);
    let quadrotor = heartbeat(MavType::Quadrotor, MavAutopilot::Px4);
    // MAVLink 1: STX 0xFE, length 9, sequence, system, component, message 0, the payload,
    // a checksum (not checked: the reader never takes it for a frame).
    let mut mavlink1 = vec![0xFE, 9, 0, AUTOPILOT.0, AUTOPILOT.1, 0];
    mavlink1.extend([0u8; 9]);
    mavlink1.extend([0x12, 0x34]);
    let mut broken = frame(AUTOPILOT, 1, &quadrotor);
    *broken.last_mut().expect("a frame") ^= 0xFF;
    // Pitch 80° up: a rotation of 80° about y, [cos 40°, 0, sin 40°, 0].
    let half = 40f32.to_radians();
    let setpoint = GimbalDeviceSetAttitude {
        target_system: AUTOPILOT.0,
        target_component: GIMBAL,
        q: [half.cos(), 0.0, half.sin(), 0.0],
        angular_velocity_x: f32::NAN,
        angular_velocity_y: f32::NAN,
        angular_velocity_z: f32::NAN,
        ..Default::default()
    };
    for d in [
        frame(AUTOPILOT, 0, &quadrotor),
        mavlink1,
        broken,
        frame(AUTOPILOT, 2, &setpoint),
    ] {
        client.send_to(&d, bridge.addr).expect("send");
    }
    let deadline = Instant::now() + Duration::from_secs(5);
    let counts = |stderr: &str| {
        (
            said_after(stderr, "from the autopilot's link", ": "),
            said_after(stderr, " that held no frame (", ", "),
            said(stderr, " not followed ("),
        )
    };
    // Bytes: the MAVLink 1 frame's 17 and the broken frame's 21 (10 of header, 9 of
    // payload, 2 of checksum), whose start byte is dropped and the rest searched for one.
    let want = (17 + 21, 1, 1);
    while counts(&bridge.stderr.text()) != want && Instant::now() < deadline {
        thread::sleep(Duration::from_millis(5));
    }
    let stderr = bridge.stop();
    assert_eq!(counts(&stderr), want, "{stderr}");
    assert!(
        stderr.contains(" whose checksum failed, 0 frames with flags the bridge cannot read\n"),
        "{stderr}"
    );
}

/// The counts that follow `before` up to `after` on the "warning:" lines holding `before`,
/// summed: the second count of a line that gives several.
fn said_after(stderr: &str, before: &str, after: &str) -> u64 {
    stderr
        .lines()
        .filter(|l| l.contains("warning: "))
        .filter_map(|l| {
            let rest = l.split(before).nth(1)?;
            let rest = rest.split(after).nth(1)?;
            rest.split(' ').next()?.parse::<u64>().ok()
        })
        .sum()
}

/// `--system-id` pins the autopilot followed: another's heartbeat, though heard first, is
/// ignored and said; the pinned one's is not.
#[test]
fn system_id_pins_the_autopilot_followed() {
    let bridge = Bridge::start_with(&["--system-id", "2"]);
    let client = socket();
    let quadrotor = heartbeat(MavType::Quadrotor, MavAutopilot::Px4);
    for d in [frame((1, 1), 0, &quadrotor), frame((2, 1), 0, &quadrotor)] {
        client.send_to(&d, bridge.addr).expect("send");
    }
    bridge.stderr.wait(
        "warning: 1 heartbeat of another autopilot ignored: following system 2 (--system-id pins it)",
        Duration::from_secs(5),
    );
    client
        .send_to(&frame((2, 1), 1, &quadrotor), bridge.addr)
        .expect("send");
    let stderr = bridge.stop();
    assert!(!stderr.contains("following system 1"), "{stderr}");
    assert!(!stderr.contains("2 heartbeats of another"), "{stderr}");
}

/// With a signing key, unsigned frames are turned away and said at the notes (once a
/// second) as their count grows, with what signing has counted.
#[test]
fn signing_says_the_frames_it_turns_away() {
    let bridge = Bridge::start_with(&["--signing-passphrase", "correct horse"]);
    let client = socket();
    let quadrotor = heartbeat(MavType::Quadrotor, MavAutopilot::Px4);
    let said = |unsigned: u32| {
        format!(
            "warning: signing: frames accepted: 0; turned away: {unsigned} unsigned, 0 with a \
             bad signature, 0 replayed, 0 from a new stream while {} were remembered",
            idu_gimbal_mavlink::signing::STREAMS
        )
    };
    // Two batches of five, each within 100 ms, the second just after a note: each said
    // in one line, or two should a note fall among its frames.
    for batch in 0..2u8 {
        for seq in 0..5 {
            client
                .send_to(&frame((1, 1), 5 * batch + seq, &quadrotor), bridge.addr)
                .expect("send");
            thread::sleep(Duration::from_millis(20));
        }
        let total = 5 * (u32::from(batch) + 1);
        bridge.stderr.wait(&said(total), Duration::from_secs(5));
    }
    let stderr = bridge.stop();
    let lines = stderr.matches("warning: signing:").count();
    assert!((2..=4).contains(&lines), "{stderr}");
}

/// `--camera dual-light` simulates a gimbal of that family: its postback names the 30×
/// dual light, and GIMBAL_DEVICE_INFORMATION its model.
#[test]
fn the_simulated_gimbal_is_of_the_cameras_family() {
    let bridge = Bridge::start_with(&["--camera", "dual-light"]);
    bridge.stderr.wait("gimbal link up", Duration::from_secs(5));
    let client = socket();
    client
        .send_to(&frame(GCS, 0, &request_information(1)), bridge.addr)
        .expect("send");
    let deadline = Instant::now() + Duration::from_secs(5);
    let info = loop {
        let f = recv_frame(&client, deadline).expect("GIMBAL_DEVICE_INFORMATION");
        if f.message_id() == GimbalDeviceInformation::ID {
            let info: GimbalDeviceInformation = f.decode_message().expect("decodes");
            break info;
        }
    };
    let model = b"30x dual light";
    assert_eq!(&info.model_name[..model.len()], model, "{info:?}");
    assert!(info.model_name[model.len()..].iter().all(|&b| b == 0));
    bridge.stop();
}
