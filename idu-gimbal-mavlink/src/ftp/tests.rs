//! The FTP server against its spec, with request packets written out byte by byte.
use super::*;
use proptest::prelude::*;

/// Bytes 0, 7, 14, …: any misplaced byte shows.
const fn pattern<const N: usize>() -> [u8; N] {
    let mut bytes = [0; N];
    let mut i = 0;
    while i < N {
        bytes[i] = (i * 7 + 3) as u8;
        i += 1;
    }
    bytes
}

static BIG: [u8; 1000] = pattern();
/// Two packets exactly.
static EXACT: [u8; 478] = pattern();

static FILES: [File<'static>; 6] = [
    File::new("/camera/idu-x30.xml", &BIG),
    File::new("/camera/idu-x30t.xml", b"<x30t/>"),
    File::new("/camera/lenses/wide.json", b"{}"),
    File::new("/readme.txt", b"hello"),
    File::new("/params/exact.bin", &EXACT),
    File::new("/empty.bin", b""),
];

// Opcodes and error codes as numbers, from mavlink.io's tables, not the module's.
/// The client of most tests (QGroundControl's ids).
const GCS: Client = (255, 190);
const OPEN: u8 = 4;
const READ: u8 = 5;
const BURST: u8 = 15;
const E_INVALID_DATA_SIZE: u8 = 3;
const E_INVALID_SESSION: u8 = 4;
const E_NO_SESSIONS: u8 = 5;
const E_EOF: u8 = 6;
const E_UNKNOWN: u8 = 7;
const E_PROTECTED: u8 = 9;
const E_NOT_FOUND: u8 = 10;

/// A server and the files its calls are given.
struct Served<const S: usize = 2> {
    server: FtpServer<S>,
    files: &'static [File<'static>],
}

impl<const S: usize> Served<S> {
    fn new(files: &'static [File<'static>]) -> Self {
        Served {
            server: FtpServer::new(),
            files,
        }
    }

    fn request(
        &mut self,
        client: Client,
        request: &[u8; 251],
        now: Instant,
        reply: &mut [u8; 251],
    ) -> bool {
        self.server.request(self.files, client, request, now, reply)
    }

    fn burst_next(&mut self, now: Instant, reply: &mut [u8; 251]) -> Option<Client> {
        self.server.burst_next(self.files, now, reply)
    }
}

impl<const S: usize> core::ops::Deref for Served<S> {
    type Target = FtpServer<S>;
    fn deref(&self) -> &FtpServer<S> {
        &self.server
    }
}

fn server() -> Served {
    Served::new(&FILES)
}

fn at(ms: u32) -> Instant {
    Instant::from_millis(ms)
}

/// A request packet, laid out by hand.
fn packet(seq: u16, session: u8, opcode: u8, size: u8, offset: u32, data: &[u8]) -> [u8; 251] {
    let mut p = [0u8; 251];
    p[0] = (seq & 0xFF) as u8;
    p[1] = (seq >> 8) as u8;
    p[2] = session;
    p[3] = opcode;
    p[4] = size;
    p[8] = (offset & 0xFF) as u8;
    p[9] = (offset >> 8 & 0xFF) as u8;
    p[10] = (offset >> 16 & 0xFF) as u8;
    p[11] = (offset >> 24) as u8;
    p[12..12 + data.len()].copy_from_slice(data);
    p
}

/// A request whose data is a path.
fn with_path(seq: u16, session: u8, opcode: u8, offset: u32, path: &str) -> [u8; 251] {
    packet(
        seq,
        session,
        opcode,
        path.len() as u8,
        offset,
        path.as_bytes(),
    )
}

#[derive(Debug, PartialEq, Eq)]
struct Reply {
    seq: u16,
    session: u8,
    opcode: u8,
    req_opcode: u8,
    burst_complete: u8,
    offset: u32,
    data: Vec<u8>,
}

/// Reads a reply; checks what every reply must hold.
fn parse(p: &[u8; 251]) -> Reply {
    let size = p[4] as usize;
    assert!(size <= 239, "size {size}");
    assert_eq!(p[7], 0, "padding");
    assert!(p[6] <= 1, "burst_complete {}", p[6]);
    assert!(p[12 + size..].iter().all(|&b| b == 0), "bytes past size");
    assert!(p[3] == 128 || p[3] == 129, "opcode {}", p[3]);
    if p[3] == 129 {
        assert_eq!(size, 1, "a NAK has one byte, its error code");
    }
    Reply {
        seq: p[0] as u16 | (p[1] as u16) << 8,
        session: p[2],
        opcode: p[3],
        req_opcode: p[5],
        burst_complete: p[6],
        offset: p[8] as u32 | (p[9] as u32) << 8 | (p[10] as u32) << 16 | (p[11] as u32) << 24,
        data: p[12..12 + size].to_vec(),
    }
}

fn send(s: &mut Served, request: &[u8; 251], now: u32) -> Reply {
    let mut reply = [0xAA; 251];
    assert!(s.request(GCS, request, at(now), &mut reply), "no reply");
    let r = parse(&reply);
    assert_eq!(
        r.seq,
        u16::from_le_bytes([request[0], request[1]]).wrapping_add(1)
    );
    assert_eq!(r.req_opcode, request[3]);
    r
}

fn assert_ack(r: &Reply) {
    assert_eq!(r.opcode, 128, "{r:?}");
}

fn assert_nak(r: &Reply, error: u8) {
    assert_eq!((r.opcode, r.data.as_slice()), (129, &[error][..]), "{r:?}");
}

fn open(s: &mut Served, seq: u16, path: &str, now: u32) -> Reply {
    open_in(s, 0, seq, path, now)
}

/// `OpenFileRO` in the client's session `session`.
fn open_in(s: &mut Served, session: u8, seq: u16, path: &str, now: u32) -> Reply {
    let r = send(s, &with_path(seq, session, OPEN, 0, path), now);
    // The client's session, echoed.
    assert_eq!(r.session, session);
    r
}

/// Every packet of a burst: the reply to the request, then `burst_next`'s.
fn burst(s: &mut Served, request: &[u8; 251], now: u32) -> Vec<Reply> {
    let mut packets = vec![send(s, request, now)];
    let mut reply = [0; 251];
    while s.burst_pending() {
        assert!(s.burst_next(at(now), &mut reply).is_some());
        packets.push(parse(&reply));
    }
    assert!(s.burst_next(at(now), &mut reply).is_none());
    packets
}

#[test]
fn packet_layout_literal() {
    let mut s = server();
    // OpenFileRO "/readme.txt", seq 0x0102, session 7 (the client's), size 11.
    let mut request = [0u8; 251];
    request[..23].copy_from_slice(&[
        0x02, 0x01, 0x07, 0x04, 0x0B, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, b'/', b'r', b'e',
        b'a', b'd', b'm', b'e', b'.', b't', b'x', b't',
    ]);
    let mut reply = [0xAA; 251];
    assert!(s.request(GCS, &request, at(0), &mut reply));
    let mut expected = [0u8; 251];
    // seq 0x0103, session 7, ACK, size 4, req_opcode 4, file size 5.
    expected[..16].copy_from_slice(&[
        0x03, 0x01, 0x07, 0x80, 0x04, 0x04, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x05, 0x00, 0x00,
        0x00,
    ]);
    assert_eq!(reply, expected);

    // ReadFile session 7, offset 1, size 3: "ell".
    let mut request = [0u8; 251];
    request[..12].copy_from_slice(&[
        0x03, 0x01, 0x07, 0x05, 0x03, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00,
    ]);
    assert!(s.request(GCS, &request, at(1), &mut reply));
    let mut expected = [0u8; 251];
    expected[..15].copy_from_slice(&[
        0x04, 0x01, 0x07, 0x80, 0x03, 0x05, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, b'e', b'l', b'l',
    ]);
    assert_eq!(reply, expected);

    // ReadFile at offset 5: NAK EOF, offset echoed.
    request[0] = 0x04;
    request[8] = 0x05;
    assert!(s.request(GCS, &request, at(2), &mut reply));
    let mut expected = [0u8; 251];
    expected[..13].copy_from_slice(&[
        0x05, 0x01, 0x07, 0x81, 0x01, 0x05, 0x00, 0x00, 0x05, 0x00, 0x00, 0x00, 0x06,
    ]);
    assert_eq!(reply, expected);
}

#[test]
fn none_is_acked() {
    let mut s = server();
    let r = send(&mut s, &packet(3, 9, 0, 0, 77, &[]), 0);
    assert_ack(&r);
    assert_eq!((r.session, r.offset, r.data.len()), (9, 77, 0));
}

#[test]
fn open_read_terminate() {
    let mut s = server();
    let r = open(&mut s, 1, "/readme.txt", 0);
    assert_ack(&r);
    assert_eq!((r.session, r.data.as_slice()), (0, &[5, 0, 0, 0][..]));

    let r = send(&mut s, &packet(2, 0, READ, 239, 0, &[]), 1);
    assert_ack(&r);
    assert_eq!(
        (r.session, r.offset, r.data.as_slice()),
        (0, 0, &b"hello"[..])
    );
    let r = send(&mut s, &packet(3, 0, READ, 2, 2, &[]), 2);
    assert_eq!((r.offset, r.data.as_slice()), (2, &b"ll"[..]));
    // Size 0 asks for nothing.
    let r = send(&mut s, &packet(4, 0, READ, 0, 1, &[]), 3);
    assert_ack(&r);
    assert!(r.data.is_empty());

    let r = send(&mut s, &packet(5, 0, 1, 0, 0, &[]), 4);
    assert_ack(&r);
    assert_eq!((r.session, r.data.len()), (0, 0));
    let r = send(&mut s, &packet(6, 0, READ, 10, 0, &[]), 5);
    assert_nak(&r, E_INVALID_SESSION);
    // Terminated twice (not a re-transmission: another seq): ACK, as ArduPilot's server
    // (a client's clean-up of a session it no longer has, MAVProxy's among them).
    let r = send(&mut s, &packet(7, 0, 1, 0, 0, &[]), 6);
    assert_ack(&r);
    assert_eq!(s.stats().sessions_opened, 1);
}

#[test]
fn read_whole_big_file_in_pieces() {
    let mut s = server();
    assert_ack(&open(&mut s, 0, "/camera/idu-x30.xml", 0));
    let mut got = Vec::new();
    let mut seq = 1;
    loop {
        let r = send(&mut s, &packet(seq, 0, READ, 239, got.len() as u32, &[]), 0);
        seq += 1;
        if r.opcode == 129 {
            assert_nak(&r, E_EOF);
            break;
        }
        assert_eq!(r.offset as usize, got.len());
        got.extend_from_slice(&r.data);
    }
    assert_eq!(got, BIG);
}

#[test]
fn read_at_or_past_end_is_eof() {
    let mut s = server();
    assert_ack(&open(&mut s, 0, "/readme.txt", 0));
    for (seq, offset) in [(1, 5), (2, 6), (3, 0x1_0000), (4, u32::MAX)] {
        let r = send(&mut s, &packet(seq, 0, READ, 239, offset, &[]), 0);
        assert_nak(&r, E_EOF);
        assert_eq!(r.offset, offset);
    }
    // An empty file: EOF at once, for reads and bursts.
    let r = open_in(&mut s, 1, 5, "/empty.bin", 0);
    assert_eq!((r.session, r.data.as_slice()), (1, &[0, 0, 0, 0][..]));
    assert_nak(&send(&mut s, &packet(6, 1, READ, 239, 0, &[]), 0), E_EOF);
    assert_nak(&send(&mut s, &packet(7, 1, BURST, 239, 0, &[]), 0), E_EOF);
    assert!(!s.burst_pending());
}

#[test]
fn bad_session_is_invalid_session() {
    let mut s = server();
    for (seq, session) in [(0u16, 0u8), (3, 1), (6, 2), (9, 255)] {
        assert_nak(
            &send(&mut s, &packet(seq, session, READ, 10, 0, &[]), 0),
            E_INVALID_SESSION,
        );
        assert_nak(
            &send(&mut s, &packet(seq + 1, session, BURST, 10, 0, &[]), 0),
            E_INVALID_SESSION,
        );
        // Terminating a session not open: ACK all the same.
        assert_ack(&send(&mut s, &packet(seq + 2, session, 1, 0, 0, &[]), 0));
    }
    // Session 1 open, session 0 not: 0 stays invalid.
    assert_ack(&open_in(&mut s, 0, 20, "/readme.txt", 0));
    assert_ack(&open_in(&mut s, 1, 21, "/readme.txt", 0));
    assert_ack(&send(&mut s, &packet(22, 0, 1, 0, 0, &[]), 0));
    assert_nak(
        &send(&mut s, &packet(23, 0, READ, 10, 0, &[]), 0),
        E_INVALID_SESSION,
    );
    assert_ack(&send(&mut s, &packet(24, 1, READ, 10, 0, &[]), 0));
    assert!(s.stats().naks >= 8);
}

#[test]
fn too_many_sessions() {
    let mut s = server();
    assert_ack(&open_in(&mut s, 0, 0, "/readme.txt", 0));
    assert_ack(&open_in(&mut s, 1, 1, "/camera/idu-x30t.xml", 0));
    assert_nak(&open_in(&mut s, 2, 2, "/readme.txt", 100), E_NO_SESSIONS);
    assert_ack(&send(&mut s, &packet(3, 0, 1, 0, 0, &[]), 100));
    let r = open(&mut s, 4, "/params/exact.bin", 100);
    assert_eq!((r.session, r.data.as_slice()), (0, &[0xDE, 0x01, 0, 0][..]));
    // Each session reads its own file.
    let r = send(&mut s, &packet(5, 1, READ, 239, 0, &[]), 100);
    assert_eq!(r.data, b"<x30t/>");
    let r = send(&mut s, &packet(6, 0, READ, 3, 0, &[]), 100);
    assert_eq!(r.data, EXACT[..3]);
    // More sessions, more files open.
    let mut four: Served<4> = Served::new(&FILES);
    for seq in 0..4u16 {
        let mut reply = [0; 251];
        assert!(four.request(
            GCS,
            &with_path(seq, seq as u8, OPEN, 0, "/readme.txt"),
            at(0),
            &mut reply
        ));
        assert_eq!((reply[3], reply[2]), (128, seq as u8));
    }
    let mut reply = [0; 251];
    assert!(four.request(
        GCS,
        &with_path(9, 9, OPEN, 0, "/readme.txt"),
        at(0),
        &mut reply
    ));
    assert_eq!((reply[3], reply[12]), (129, E_NO_SESSIONS));
}

/// Two sessions opened at `start`; session 1 used again 2 s later.
fn reclaim_from(start: u32) {
    let mut s = server();
    assert_ack(&open_in(&mut s, 0, 0, "/readme.txt", start));
    assert_ack(&open_in(&mut s, 1, 1, "/readme.txt", start));
    let later = start.wrapping_add(2_000);
    assert_ack(&send(&mut s, &packet(2, 1, READ, 1, 0, &[]), later));
    // Session 0 idle for exactly the timeout: not yet.
    let r = open_in(
        &mut s,
        2,
        3,
        "/camera/idu-x30t.xml",
        start.wrapping_add(5_000),
    );
    assert_nak(&r, E_NO_SESSIONS);
    assert_eq!(s.stats().sessions_reclaimed, 0);
    // One ms more: session 0 (idle longest) goes, session 1 stays.
    let r = open_in(
        &mut s,
        2,
        4,
        "/camera/idu-x30t.xml",
        start.wrapping_add(5_001),
    );
    assert_ack(&r);
    assert_eq!((r.session, r.data.as_slice()), (2, &[7, 0, 0, 0][..]));
    assert_eq!(s.stats().sessions_reclaimed, 1);
    let r = send(
        &mut s,
        &packet(5, 2, READ, 239, 0, &[]),
        start.wrapping_add(5_001),
    );
    assert_eq!(r.data, b"<x30t/>");
    // Session 0 was the one reclaimed.
    assert_nak(
        &send(&mut s, &packet(8, 0, READ, 1, 0, &[]), later),
        E_INVALID_SESSION,
    );
    assert_eq!(
        send(&mut s, &packet(6, 1, READ, 239, 0, &[]), later).data,
        b"hello"
    );
    // Both in use now.
    assert_nak(
        &open_in(&mut s, 3, 7, "/readme.txt", start.wrapping_add(6_000)),
        E_NO_SESSIONS,
    );
}

#[test]
fn idle_session_reclaimed_after_the_timeout_not_before() {
    reclaim_from(1_000);
}

#[test]
fn idle_session_reclaimed_across_the_tick_wrap() {
    reclaim_from(u32::MAX - 1_000);
    reclaim_from(u32::MAX - 5_000);
    reclaim_from(u32::MAX);
}

#[test]
fn reclaiming_the_burst_session_ends_the_burst() {
    let mut s = server();
    assert_ack(&open_in(&mut s, 0, 0, "/camera/idu-x30.xml", 0));
    assert_ack(&open_in(&mut s, 1, 1, "/readme.txt", 0));
    assert_ack(&send(&mut s, &packet(2, 0, BURST, 100, 0, &[]), 0));
    assert!(s.burst_pending());
    // Session 1 kept busy; session 0's burst not pulled for 6 s.
    assert_ack(&send(&mut s, &packet(3, 1, READ, 1, 0, &[]), 5_000));
    assert_ack(&open_in(&mut s, 2, 4, "/readme.txt", 6_000));
    assert!(!s.burst_pending());
    assert_eq!((s.stats().sessions_reclaimed, s.stats().bursts_cut), (1, 1));
}

#[test]
fn path_not_found() {
    let mut s = server();
    for (seq, path) in [
        "/nope",
        "/camera",
        "/camera/",
        "",
        "/",
        "/camera/idu-x30.xml/x",
        "/readme.txt.bak",
    ]
    .into_iter()
    .enumerate()
    {
        assert_nak(&open(&mut s, seq as u16 * 2, path, 0), E_NOT_FOUND);
        let crc = with_path(seq as u16 * 2 + 1, 0, 14, 0, path);
        assert_nak(&send(&mut s, &crc, 0), E_NOT_FOUND);
    }
    // Directories that are not: a file, an unknown path, a prefix of a name.
    for (seq, path) in ["/readme.txt", "/nope", "/cam", "/camera/lenses/wide.json/"]
        .into_iter()
        .enumerate()
    {
        assert_nak(
            &send(&mut s, &with_path(100 + seq as u16, 0, 3, 0, path), 0),
            E_NOT_FOUND,
        );
    }
    assert_eq!(s.stats().sessions_opened, 0);
}

#[test]
fn paths_are_read_up_to_a_nul_and_without_leading_or_trailing_slashes() {
    let mut s = server();
    // MAVSDK counts the terminating NUL in size; bytes after it are ignored.
    let r = send(&mut s, &packet(0, 0, OPEN, 14, 0, b"/readme.txt\0zz"), 0);
    assert_eq!(r.data, [5, 0, 0, 0]);
    let r = open(&mut s, 1, "camera/idu-x30t.xml", 0);
    assert_eq!(r.data, [7, 0, 0, 0]);
    // Only size bytes count: "/readme.txt" cut to "/readme".
    assert_nak(
        &send(&mut s, &packet(2, 0, OPEN, 7, 0, b"/readme.txt"), 0),
        E_NOT_FOUND,
    );
}

/// The entries a ListDirectory ACK holds, as pymavlink splits them.
fn entries(r: &Reply) -> Vec<String> {
    assert_eq!(r.data.last(), Some(&0), "entries end with a NUL");
    r.data
        .split(|&b| b == 0)
        .filter(|e| !e.is_empty())
        .map(|e| String::from_utf8(e.to_vec()).unwrap())
        .collect()
}

#[test]
fn list_root_and_subdirectories() {
    let mut s = server();
    let root_bytes = b"Dcamera\0Freadme.txt\t5\0Dparams\0Fempty.bin\t0\0";
    for (seq, path) in ["/", "", "//"].into_iter().enumerate() {
        let r = send(&mut s, &with_path(seq as u16, 4, 3, 0, path), 0);
        assert_ack(&r);
        assert_eq!(r.data, root_bytes, "{path:?}");
        assert_eq!(r.session, 4);
    }
    // From entry 2.
    let r = send(&mut s, &with_path(10, 0, 3, 2, "/"), 0);
    assert_eq!(entries(&r), ["Dparams", "Fempty.bin\t0"]);
    assert_eq!(r.offset, 2);
    let r = send(&mut s, &with_path(11, 0, 3, 3, "/"), 0);
    assert_eq!(entries(&r), ["Fempty.bin\t0"]);
    // Past the last entry: EOF.
    for (seq, offset) in [(12, 4), (13, 5), (14, u32::MAX)] {
        assert_nak(&send(&mut s, &with_path(seq, 0, 3, offset, "/"), 0), E_EOF);
    }

    let camera = ["Fidu-x30.xml\t1000", "Fidu-x30t.xml\t7", "Dlenses"];
    for (seq, path) in ["/camera", "/camera/", "camera"].into_iter().enumerate() {
        let r = send(&mut s, &with_path(20 + seq as u16, 0, 3, 0, path), 0);
        assert_eq!(entries(&r), camera, "{path:?}");
    }
    let r = send(&mut s, &with_path(30, 0, 3, 1, "/camera"), 0);
    assert_eq!(entries(&r), camera[1..]);
    assert_nak(&send(&mut s, &with_path(31, 0, 3, 3, "/camera"), 0), E_EOF);
    let r = send(&mut s, &with_path(32, 0, 3, 0, "/camera/lenses"), 0);
    assert_eq!(r.data, b"Fwide.json\t2\0");
    assert_nak(
        &send(&mut s, &with_path(33, 0, 3, 1, "/camera/lenses"), 0),
        E_EOF,
    );
}

#[test]
fn list_of_an_empty_table_is_eof() {
    static NO_FILES: [File<'static>; 0] = [];
    let mut s: Served = Served::new(&NO_FILES);
    assert_nak(&send(&mut s, &with_path(0, 0, 3, 0, "/"), 0), E_EOF);
    assert_nak(&send(&mut s, &with_path(1, 0, 3, 0, "/x"), 0), E_NOT_FOUND);
    assert_nak(
        &send(&mut s, &with_path(2, 0, OPEN, 0, "/x"), 0),
        E_NOT_FOUND,
    );
}

/// Files whose entries are 41 bytes (five fit in 239, not six), one whose entry fits in
/// no packet, and a short one.
static MANY: [File<'static>; 13] = {
    const NAMES: [&str; 13] = [
        "/logs/flight-log-number-000000000001.bin",
        "/logs/flight-log-number-000000000002.bin",
        "/logs/flight-log-number-000000000003.bin",
        "/logs/flight-log-number-000000000004.bin",
        "/logs/flight-log-number-000000000005.bin",
        "/logs/flight-log-number-000000000006.bin",
        "/logs/flight-log-number-000000000007.bin",
        "/logs/flight-log-number-000000000008.bin",
        "/logs/flight-log-number-000000000009.bin",
        "/logs/flight-log-number-000000000010.bin",
        "/logs/flight-log-number-000000000011.bin",
        "/logs/a-name-so-long-that-its-entry-cannot-fit-in-any-packet-of-two-hundred-and-thirty-nine-bytes-of-data-not-even-alone-in-an-otherwise-empty-packet-which-is-what-this-test-checks-the-server-survives-by-listing-it-as-skipped-xxxxxxxxxxxxxxxxxxx.bin",
        "/logs/last.bin",
    ];
    let mut files = [File::new("", b""); 13];
    let mut i = 0;
    while i < 13 {
        files[i] = File::new(NAMES[i], &BIG);
        i += 1;
    }
    files
};

#[test]
fn list_packs_whole_entries_and_skips_one_too_long() {
    let mut s: Served = Served::new(&MANY);
    let mut all = Vec::new();
    let mut seq = 0;
    // pymavlink's loop: the next offset is the count of entries received.
    loop {
        let r = send(&mut s, &with_path(seq, 0, 3, all.len() as u32, "/logs"), 0);
        seq += 1;
        if r.opcode == 129 {
            assert_nak(&r, E_EOF);
            break;
        }
        let got = entries(&r);
        if seq == 1 {
            assert_eq!(got.len(), 5, "whole entries, as many as fit");
        }
        assert!(!got.is_empty());
        assert!(r.data.len() <= 239);
        all.extend(got);
    }
    assert_eq!(seq, 6, "5 + 5 + 1, the skip, the last, then EOF");
    assert_eq!(all.len(), 13);
    for (i, entry) in all.iter().take(11).enumerate() {
        assert_eq!(
            *entry,
            format!("Fflight-log-number-{:012}.bin\t1000", i + 1)
        );
    }
    assert_eq!(all[11], "S");
    assert_eq!(all[12], "Flast.bin\t1000");
    assert_eq!(s.stats().entries_skipped, 1);
}

fn check_burst(path: &str, offset: u32, size: u8, seq: u16, expected: &[u8]) {
    let mut s = server();
    assert_ack(&open(&mut s, seq.wrapping_sub(1), path, 0));
    let packets = burst(&mut s, &packet(seq, 0, BURST, size, offset, &[]), 0);
    let chunk = if size == 0 { 239 } else { size as usize };
    assert_eq!(packets.len(), expected.len().div_ceil(chunk));
    let mut got = Vec::new();
    for (i, p) in packets.iter().enumerate() {
        assert_ack(p);
        assert_eq!(p.seq, seq.wrapping_add(1 + i as u16));
        assert_eq!(p.req_opcode, BURST);
        assert_eq!(p.session, 0);
        assert_eq!(p.offset as usize, offset as usize + got.len());
        let last = i + 1 == packets.len();
        assert_eq!(p.burst_complete, last as u8, "packet {i}");
        if !last {
            assert_eq!(p.data.len(), chunk);
        }
        got.extend_from_slice(&p.data);
    }
    assert_eq!(got, expected);
    let stats = s.stats();
    assert_eq!(
        (stats.bursts, stats.burst_packets, stats.bursts_cut),
        (1, packets.len() as u32 - 1, 0)
    );
}

#[test]
fn burst_reads_the_whole_file() {
    check_burst("/camera/idu-x30.xml", 0, 239, 10, &BIG);
    // pymavlink's default burst size.
    check_burst("/camera/idu-x30.xml", 0, 80, 10, &BIG);
    check_burst("/camera/idu-x30.xml", 0, 0, 10, &BIG);
    check_burst("/camera/idu-x30.xml", 1, 1, 10, &BIG[1..]);
    check_burst("/camera/idu-x30.xml", 900, 239, 10, &BIG[900..]);
    check_burst("/camera/idu-x30.xml", 999, 239, 10, &BIG[999..]);
    check_burst("/readme.txt", 0, 239, 10, b"hello");
    // The sequence numbers wrap.
    check_burst("/camera/idu-x30.xml", 0, 100, 0xFFFD, &BIG);
}

#[test]
fn burst_of_an_exact_multiple_then_eof() {
    check_burst("/params/exact.bin", 0, 239, 1, &EXACT);
    let mut s = server();
    assert_ack(&open(&mut s, 0, "/params/exact.bin", 0));
    let packets = burst(&mut s, &packet(1, 0, BURST, 239, 0, &[]), 0);
    assert_eq!(packets.len(), 2);
    assert_eq!((packets[1].data.len(), packets[1].burst_complete), (239, 1));
    // The client asks for more from the end: EOF, offset where it asked.
    let r = send(&mut s, &packet(3, 0, BURST, 239, 478, &[]), 0);
    assert_nak(&r, E_EOF);
    assert_eq!(r.offset, 478);
    assert!(!s.burst_pending());
}

#[test]
fn reads_between_burst_packets_leave_the_burst_running() {
    let mut s = server();
    assert_ack(&open(&mut s, 0, "/camera/idu-x30.xml", 0));
    let first = send(&mut s, &packet(1, 0, BURST, 100, 0, &[]), 0);
    let mut got = first.data.clone();
    let mut reply = [0; 251];
    let mut seq = 10;
    while s.burst_pending() {
        // A gap repair, a listing and a CRC between every two packets.
        let r = send(&mut s, &packet(seq, 0, READ, 10, 5, &[]), 0);
        assert_eq!(r.data, BIG[5..15]);
        assert_ack(&send(&mut s, &with_path(seq + 1, 0, 3, 0, "/"), 0));
        assert_ack(&send(
            &mut s,
            &with_path(seq + 2, 0, 14, 0, "/readme.txt"),
            0,
        ));
        seq += 3;
        assert!(s.burst_next(at(0), &mut reply).is_some());
        let p = parse(&reply);
        assert_eq!(p.offset as usize, got.len());
        got.extend_from_slice(&p.data);
    }
    assert_eq!(got, BIG);
    assert_eq!(s.stats().bursts_cut, 0);
}

#[test]
fn burst_ended_by_terminate_reset_or_another_burst() {
    let mut s = server();
    assert_ack(&open(&mut s, 0, "/camera/idu-x30.xml", 0));
    assert_ack(&open(&mut s, 1, "/camera/idu-x30.xml", 0));
    let mut reply = [0; 251];

    // Terminating another session leaves it; terminating its own ends it.
    assert_ack(&send(&mut s, &packet(2, 0, BURST, 100, 0, &[]), 0));
    assert_ack(&send(&mut s, &packet(3, 1, 1, 0, 0, &[]), 0));
    assert!(s.burst_pending());
    assert_ack(&send(&mut s, &packet(4, 0, 1, 0, 0, &[]), 0));
    assert!(!s.burst_pending());
    assert!(s.burst_next(at(0), &mut reply).is_none());
    assert_eq!(s.stats().bursts_cut, 1);

    // Another burst replaces it, numbered from its own request.
    assert_ack(&open(&mut s, 5, "/camera/idu-x30.xml", 0));
    assert_ack(&send(&mut s, &packet(6, 0, BURST, 100, 0, &[]), 0));
    let r = send(&mut s, &packet(20, 0, BURST, 100, 500, &[]), 0);
    assert_eq!(
        (r.offset, &r.data[..], r.burst_complete),
        (500, &BIG[500..600], 0)
    );
    assert!(s.burst_next(at(0), &mut reply).is_some());
    let p = parse(&reply);
    assert_eq!((p.seq, p.offset), (22, 600));
    assert_eq!(s.stats().bursts_cut, 2);
    // A new burst refused ends the old one too.
    assert_nak(
        &send(&mut s, &packet(21, 0, BURST, 100, 1000, &[]), 0),
        E_EOF,
    );
    assert!(!s.burst_pending());
    assert_eq!(s.stats().bursts_cut, 3);

    // ResetSessions.
    assert_ack(&send(&mut s, &packet(22, 0, BURST, 100, 0, &[]), 0));
    assert!(s.burst_pending());
    assert_ack(&send(&mut s, &packet(23, 0, 2, 0, 0, &[]), 0));
    assert!(!s.burst_pending());
    assert_eq!(s.stats().bursts_cut, 4);
}

#[test]
fn write_operations_are_refused_as_protected() {
    let mut s = server();
    assert_ack(&open(&mut s, 0, "/readme.txt", 0));
    for opcode in 6..=13u8 {
        let request = packet(opcode as u16 * 2, 0, opcode, 11, 0, b"/readme.txt");
        let r = send(&mut s, &request, 0);
        assert_nak(&r, E_PROTECTED);
        assert_eq!((r.req_opcode, r.session), (opcode, 0));
        // Rename with two paths, WriteFile with data: the same.
        let request = packet(
            opcode as u16 * 2 + 1,
            0,
            opcode,
            20,
            0,
            b"/readme.txt\0/new.txt",
        );
        assert_nak(&send(&mut s, &request, 0), E_PROTECTED);
    }
    // Nothing changed.
    assert_eq!(
        send(&mut s, &packet(40, 0, READ, 239, 0, &[]), 0).data,
        b"hello"
    );
    assert_eq!(s.stats().sessions_opened, 1);
}

#[test]
fn unknown_opcodes() {
    let mut s = server();
    for (seq, opcode) in [16u8, 17, 100, 127, 130, 200, 255].into_iter().enumerate() {
        assert_nak(
            &send(&mut s, &packet(seq as u16, 0, opcode, 0, 0, &[]), 0),
            E_UNKNOWN,
        );
    }
    assert_eq!(s.stats().bad_requests, 7);
}

#[test]
fn ack_and_nak_get_no_reply() {
    let mut s = server();
    for opcode in [128u8, 129] {
        let mut reply = [0x5A; 251];
        assert!(!s.request(
            GCS,
            &packet(1, 0, opcode, 4, 0, &[1, 2, 3, 4]),
            at(0),
            &mut reply
        ));
        assert_eq!(reply, [0x5A; 251]);
        // Even with a size beyond 239.
        assert!(!s.request(GCS, &packet(2, 0, opcode, 255, 0, &[]), at(0), &mut reply));
    }
    let stats = s.stats();
    assert_eq!(
        (stats.requests, stats.not_requests, stats.acks, stats.naks),
        (4, 4, 0, 0)
    );
}

#[test]
fn size_beyond_239_is_invalid_data_size() {
    let mut s = server();
    assert_ack(&open(&mut s, 0, "/readme.txt", 0));
    for (seq, opcode, size) in [
        (1u16, 0u8, 240u8),
        (2, OPEN, 255),
        (3, READ, 240),
        (4, 3, 241),
        (5, BURST, 250),
        (6, 1, 240),
        (7, 77, 240),
    ] {
        let r = send(&mut s, &packet(seq, 0, opcode, size, 0, b"/readme.txt"), 0);
        assert_nak(&r, E_INVALID_DATA_SIZE);
    }
    // Nothing executed: the session is still open, no burst.
    assert!(!s.burst_pending());
    assert_eq!(
        send(&mut s, &packet(8, 0, READ, 239, 0, &[]), 0).data,
        b"hello"
    );
    assert_eq!(s.stats().bad_requests, 7);
    // 239 itself is fine.
    assert_ack(&send(&mut s, &packet(9, 0, READ, 239, 0, &[]), 0));
}

#[test]
fn retransmitted_open_returns_the_same_session_and_opens_no_other() {
    let mut s = server();
    let request = with_path(10, 0, OPEN, 0, "/readme.txt");
    let mut first = [0; 251];
    assert!(s.request(GCS, &request, at(0), &mut first));
    let mut again = [0; 251];
    assert!(s.request(GCS, &request, at(50), &mut again));
    assert_eq!(first, again);
    assert_eq!(parse(&again).session, 0);
    assert_eq!(
        (s.stats().sessions_opened, s.stats().retransmissions),
        (1, 1)
    );
    // One more session only.
    assert_ack(&open_in(&mut s, 1, 11, "/readme.txt", 100));
    assert_nak(&open_in(&mut s, 2, 12, "/readme.txt", 100), E_NO_SESSIONS);
    // A refusal is repeated as it was, even once a session is free.
    assert_ack(&send(&mut s, &packet(13, 1, 1, 0, 0, &[]), 100));
    assert_nak(&open_in(&mut s, 2, 14, "/nope", 100), E_NOT_FOUND);
    assert_nak(&open_in(&mut s, 2, 14, "/nope", 100), E_NOT_FOUND);
}

#[test]
fn retransmitted_open_refusal_is_repeated() {
    let mut s = server();
    assert_ack(&open_in(&mut s, 0, 0, "/readme.txt", 0));
    assert_ack(&open_in(&mut s, 1, 1, "/readme.txt", 0));
    assert_nak(&open_in(&mut s, 2, 2, "/readme.txt", 100), E_NO_SESSIONS);
    // Same seq, same request, 6 s later: still the refusal, nothing reclaimed.
    assert_nak(&open_in(&mut s, 2, 2, "/readme.txt", 6_100), E_NO_SESSIONS);
    assert_eq!(s.stats().sessions_reclaimed, 0);
    // A new request reclaims.
    assert_ack(&open_in(&mut s, 2, 3, "/readme.txt", 6_100));
}

#[test]
fn retransmitted_terminate_is_acked_again() {
    let mut s = server();
    assert_ack(&open(&mut s, 0, "/readme.txt", 0));
    let terminate = packet(1, 0, 1, 0, 0, &[]);
    assert_ack(&send(&mut s, &terminate, 0));
    assert_ack(&send(&mut s, &terminate, 0));
    assert_ack(&send(&mut s, &terminate, 0));
    assert_eq!(s.stats().retransmissions, 2);
}

#[test]
fn same_seq_with_another_request_is_executed() {
    let mut s = server();
    assert_ack(&open_in(&mut s, 0, 10, "/readme.txt", 0));
    // Starting over at the same number, for another file: executed (session 0 re-opened).
    let r = open_in(&mut s, 0, 10, "/camera/idu-x30t.xml", 0);
    assert_eq!(r.data.as_slice(), &[7, 0, 0, 0][..]);
    assert_eq!(s.stats().sessions_opened, 2);
    // Same file, other session byte: another request too.
    assert_ack(&open_in(&mut s, 1, 10, "/camera/idu-x30t.xml", 0));
    let r = send(
        &mut s,
        &with_path(10, 2, OPEN, 0, "/camera/idu-x30t.xml"),
        0,
    );
    assert_nak(&r, E_NO_SESSIONS);
    assert_eq!(s.stats().retransmissions, 0);
    // The bytes the request does not use do not matter.
    let mut request = with_path(10, 2, OPEN, 0, "/camera/idu-x30t.xml");
    request[5] = 9;
    request[6] = 1;
    request[7] = 3;
    request[200] = 0xFF;
    assert_nak(&send(&mut s, &request, 0), E_NO_SESSIONS);
    assert_eq!(s.stats().retransmissions, 1);
}

#[test]
fn retransmitted_burst_restarts_it() {
    let mut s = server();
    assert_ack(&open(&mut s, 0, "/camera/idu-x30.xml", 0));
    let request = packet(1, 0, BURST, 239, 0, &[]);
    let first = burst(&mut s, &request, 0);
    let again = burst(&mut s, &request, 0);
    assert_eq!(first, again);
    assert_eq!(s.stats().bursts, 2);
}

#[test]
fn reset_sessions_closes_all() {
    let mut s = server();
    assert_ack(&open_in(&mut s, 0, 0, "/readme.txt", 0));
    assert_ack(&open_in(&mut s, 1, 1, "/readme.txt", 0));
    let r = send(&mut s, &packet(2, 5, 2, 0, 0, &[]), 0);
    assert_ack(&r);
    assert_eq!((r.session, r.data.len()), (5, 0));
    assert_nak(
        &send(&mut s, &packet(3, 0, READ, 1, 0, &[]), 0),
        E_INVALID_SESSION,
    );
    assert_nak(
        &send(&mut s, &packet(4, 1, READ, 1, 0, &[]), 0),
        E_INVALID_SESSION,
    );
    assert_ack(&open_in(&mut s, 0, 5, "/readme.txt", 0));
    assert_ack(&open_in(&mut s, 1, 6, "/readme.txt", 0));
    // With nothing open: ACK all the same.
    assert_ack(&send(&mut s, &packet(7, 0, 2, 0, 0, &[]), 0));
    assert_ack(&send(&mut s, &packet(8, 0, 2, 0, 0, &[]), 0));
}

/// MAVLink's CRC-32, bit by bit.
fn crc32_bitwise(bytes: &[u8]) -> u32 {
    let mut crc = 0u32;
    for &b in bytes {
        crc ^= b as u32;
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    crc
}

#[test]
fn calc_file_crc32() {
    // Check value of this CRC-32 variant (init 0, no final XOR).
    assert_eq!(crc32(0, b"123456789"), 0x2DFD_2D88);
    assert_eq!(crc32_bitwise(b"123456789"), 0x2DFD_2D88);
    assert_eq!(crc32(0, &BIG), crc32_bitwise(&BIG));
    let mut s = server();
    let r = send(&mut s, &with_path(0, 3, 14, 0, "/camera/idu-x30.xml"), 0);
    assert_ack(&r);
    assert_eq!(r.data, crc32_bitwise(&BIG).to_le_bytes());
    assert_eq!(r.session, 3);
    let r = send(&mut s, &with_path(1, 0, 14, 0, "/empty.bin"), 0);
    assert_eq!(r.data, [0, 0, 0, 0]);
    // No session is involved.
    assert_eq!(s.stats().sessions_opened, 0);
}

#[test]
fn a_file_in_parts_is_served_as_their_concatenation() {
    // BIG in three parts, cut inside packets: a read, a burst, the size, the listing and
    // the CRC see one file.
    let (head, rest) = BIG.split_at(100);
    let (middle, tail) = rest.split_at(600);
    let files: &'static [File<'static>] = Box::leak(Box::new([File {
        path: "/parts.bin",
        parts: [head, middle, tail],
    }]));
    let mut s: Served = Served::new(files);
    let r = open(&mut s, 0, "/parts.bin", 0);
    assert_eq!(r.data, 1000u32.to_le_bytes());
    // 20 bytes across the first cut, and across the second.
    let r = send(&mut s, &packet(1, 0, READ, 20, 90, &[]), 0);
    assert_eq!(r.data, &BIG[90..110]);
    let r = send(&mut s, &packet(2, 0, READ, 20, 690, &[]), 0);
    assert_eq!(r.data, &BIG[690..710]);
    let mut whole = Vec::new();
    for p in burst(&mut s, &packet(3, 0, BURST, 0, 0, &[]), 0) {
        assert_ack(&p);
        whole.extend_from_slice(&p.data);
    }
    assert_eq!(whole, BIG);
    let r = send(&mut s, &with_path(4, 0, 14, 0, "/parts.bin"), 0);
    assert_eq!(r.data, crc32_bitwise(&BIG).to_le_bytes());
    let r = send(&mut s, &with_path(5, 0, 3, 0, "/"), 0);
    assert_eq!(r.data, b"Fparts.bin\t1000\0");
    assert_nak(&send(&mut s, &packet(6, 0, READ, 1, 1000, &[]), 0), E_EOF);
}

#[test]
fn sequence_numbers_wrap() {
    let mut s = server();
    let r = send(&mut s, &packet(0xFFFF, 0, 0, 0, 0, &[]), 0);
    assert_eq!(r.seq, 0);
}

#[test]
fn stats_count_acks_and_naks() {
    let mut s = server();
    assert_ack(&open(&mut s, 0, "/readme.txt", 0));
    assert_nak(&open(&mut s, 1, "/nope", 0), E_NOT_FOUND);
    assert_ack(&send(&mut s, &packet(2, 0, READ, 3, 0, &[]), 0));
    let stats = s.stats();
    assert_eq!(
        stats,
        FtpStats {
            requests: 3,
            acks: 2,
            naks: 1,
            sessions_opened: 1,
            ..FtpStats::default()
        }
    );
}

#[test]
fn ram_size() {
    let size = core::mem::size_of::<FtpServer<2>>();
    println!("size_of::<FtpServer<2>>() = {size}");
    println!(
        "size_of::<FtpServer<4>>() = {}",
        core::mem::size_of::<FtpServer<4>>()
    );
    // The record of the last request is small: far below a kept 251-byte reply.
    assert!(size < 251, "{size}");
}

/// Requests likely to do something: valid opcodes, small sessions, paths of the table.
fn requests() -> impl Strategy<Value = [u8; 251]> {
    let opcode = prop_oneof![0u8..=16, Just(128u8), Just(129u8), any::<u8>()];
    let path = prop_oneof![
        Just(&b"/camera/idu-x30.xml"[..]),
        Just(&b"/"[..]),
        Just(&b"/camera"[..]),
        Just(&b"/readme.txt"[..]),
        Just(&b"/params/exact.bin"[..]),
    ];
    let size = prop_oneof![0u8..=20, 230u8..=255, any::<u8>()];
    let offset = prop_oneof![0u32..1100, any::<u32>(), (0u32..3).prop_map(|k| k * 239)];
    (
        any::<u16>(),
        0u8..4,
        opcode,
        size,
        offset,
        path,
        proptest::collection::vec(any::<u8>(), 239),
        any::<bool>(),
    )
        .prop_map(
            |(seq, session, opcode, size, offset, path, noise, use_path)| {
                let mut p = packet(seq, session, opcode, size, offset, &noise);
                if use_path {
                    p[12..12 + path.len()].copy_from_slice(path);
                    p[4] = if size <= 239 { path.len() as u8 } else { size };
                }
                p
            },
        )
}

proptest! {
    #[test]
    fn arbitrary_packets_never_panic(
        steps in proptest::collection::vec((requests(), 0u32..3_000, 0usize..4), 1..60),
        start: u32,
    ) {
        let mut s = server();
        let mut now = start;
        for (request, dt, pulls) in steps {
            now = now.wrapping_add(dt);
            let mut reply = [0; 251];
            let answered = s.request(GCS, &request, at(now), &mut reply);
            prop_assert_eq!(answered, request[3] != 128 && request[3] != 129);
            if answered {
                let r = parse(&reply);
                prop_assert_eq!(r.seq, u16::from_le_bytes([request[0], request[1]]).wrapping_add(1));
                prop_assert_eq!(r.req_opcode, request[3]);
            }
            let mut last_seq = None;
            for _ in 0..pulls {
                if s.burst_next(at(now), &mut reply).is_none() {
                    prop_assert!(!s.burst_pending());
                    break;
                }
                let p = parse(&reply);
                prop_assert_eq!((p.opcode, p.req_opcode), (128, 15));
                prop_assert!(!p.data.is_empty());
                if let Some(prev) = last_seq {
                    prop_assert_eq!(p.seq, u16::wrapping_add(prev, 1));
                }
                last_seq = Some(p.seq);
            }
        }
    }

    #[test]
    fn fully_random_packets_never_panic(packets in proptest::collection::vec(proptest::collection::vec(any::<u8>(), 251), 1..20)) {
        let mut s = server();
        for (i, bytes) in packets.iter().enumerate() {
            let request: [u8; 251] = bytes.as_slice().try_into().unwrap();
            let mut reply = [0; 251];
            if s.request(GCS, &request, at(i as u32), &mut reply) {
                parse(&reply);
            }
            while s.burst_next(at(i as u32), &mut reply).is_some() {
                parse(&reply);
            }
        }
    }
}

#[test]
fn sessions_are_the_clients_numbers_and_each_clients_own() {
    // MAVProxy picks a session number of its own and routes replies by it
    // (mavproxy_ftp.py); another client uses 0. Each is answered in its own.
    let mut s = server();
    const MAVPROXY: Client = (255, 230);
    let mut reply = [0; 251];
    assert!(s.request(
        MAVPROXY,
        &with_path(0, 173, OPEN, 0, "/readme.txt"),
        at(0),
        &mut reply
    ));
    let r = parse(&reply);
    assert_ack(&r);
    assert_eq!(r.session, 173);
    assert_ack(&open_in(&mut s, 0, 1, "/camera/idu-x30t.xml", 0));
    // The same number from another client is not its session.
    assert_nak(
        &send(&mut s, &packet(2, 173, READ, 5, 0, &[]), 0),
        E_INVALID_SESSION,
    );
    assert!(s.request(
        MAVPROXY,
        &packet(3, 173, READ, 5, 0, &[]),
        at(0),
        &mut reply
    ));
    assert_eq!(
        (parse(&reply).session, parse(&reply).data),
        (173, b"hello".to_vec())
    );
    // Its burst carries its number.
    assert!(s.request(
        MAVPROXY,
        &packet(4, 173, BURST, 2, 0, &[]),
        at(0),
        &mut reply
    ));
    assert_eq!(parse(&reply).session, 173);
    assert!(s.burst_next(at(0), &mut reply).is_some());
    assert_eq!(parse(&reply).session, 173);
    // A retried open (another seq, same session) after another request re-opens the
    // same session: no second slot.
    assert_ack(&send(&mut s, &packet(5, 0, READ, 1, 0, &[]), 0));
    assert_ack(&open_in(&mut s, 0, 6, "/camera/idu-x30t.xml", 0));
    assert_eq!(s.stats().sessions_reclaimed, 0);
    // Terminated, and terminated again: ACK both.
    assert!(s.request(MAVPROXY, &packet(7, 173, 1, 0, 0, &[]), at(0), &mut reply));
    assert_ack(&parse(&reply));
    assert!(s.request(MAVPROXY, &packet(8, 173, 1, 0, 0, &[]), at(0), &mut reply));
    assert_ack(&parse(&reply));
    // The client's own session 0 is untouched.
    assert_ack(&send(&mut s, &packet(9, 0, READ, 1, 0, &[]), 0));
}

#[test]
fn a_file_is_empty_only_when_every_part_is() {
    assert!(File::new("/a", b"").is_empty());
    assert!(!File::new("/a", b"x").is_empty());
    let last_part_only = File {
        path: "/a",
        parts: [b"", b"", b"x"],
    };
    assert!(!last_part_only.is_empty());
    assert_eq!(last_part_only.len(), 1);
}

#[test]
fn a_retransmitted_open_keeps_its_session_from_being_reclaimed() {
    let mut s = server();
    let request = with_path(10, 0, OPEN, 0, "/readme.txt");
    let mut reply = [0; 251];
    assert!(s.request(GCS, &request, at(0), &mut reply));
    // The open again at 4 s: session 0 was used then, not at 0.
    assert!(s.request(GCS, &request, at(4_000), &mut reply));
    assert_eq!(s.stats().retransmissions, 1);
    assert_ack(&open_in(&mut s, 1, 11, "/readme.txt", 4_000));
    // At 5.5 s neither session has been idle SESSION_IDLE_TIMEOUT_MS: none reclaimed.
    assert_nak(&open_in(&mut s, 2, 12, "/readme.txt", 5_500), E_NO_SESSIONS);
    assert_eq!(s.stats().sessions_reclaimed, 0);
}
