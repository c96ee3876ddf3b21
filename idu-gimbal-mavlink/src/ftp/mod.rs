//! A read-only MAVLink FTP server (`FILE_TRANSFER_PROTOCOL`, message 110) over files kept
//! in flash, such as a camera definition file a ground station fetches by its
//! `mftp://` address.
//!
//! Sans-IO like the rest of the crate: [`FtpServer::request`] takes the message's 251-byte
//! `payload` (the FTP packet) and writes the reply packet; [`FtpServer::burst_next`] writes
//! the packets of a burst read, at the caller's pace. Addressing (`target_system`,
//! `target_component`) is the caller's to check. The files are the caller's too: the
//! server knows no file names.
//!
//! # The packet
//!
//! Little-endian, as mavlink.io's FTP page lays it out: `seq_number` u16 (bytes 0–1),
//! `session` (2), `opcode` (3), `size` (4), `req_opcode` (5), `burst_complete` (6),
//! padding (7), `offset` u32 (8–11), `data` (12–250, 239 bytes). A reply's `seq_number` is
//! the request's plus one, `req_opcode` the request's opcode, `session` and `offset` the
//! request's; bytes past `size` are zero.
//!
//! # What it answers
//!
//! | opcode | reply |
//! |---|---|
//! | 0 None | ACK ("Ignored, always ACKed") |
//! | 1 TerminateSession | ACK, also for a session not open (as ArduPilot: the client's clean-up of a session reclaimed or never opened) |
//! | 2 ResetSessions | ACK; every session closed, a burst in progress ended |
//! | 3 ListDirectory | ACK with entries from index `offset`: `F<name>\t<size>\0` for a file, `D<name>\0` for a sub-directory, as many whole entries as fit; NAK `EOF` past the last; NAK `FileNotFound` for a path that is not a directory |
//! | 4 OpenFileRO | ACK in the client's session with the file's size (u32, `size` 4); NAK `FileNotFound`, `NoSessionsAvailable` |
//! | 5 ReadFile | ACK with up to `size` bytes from `offset`; NAK `EOF` at or past the end, `InvalidSession` |
//! | 15 BurstReadFile | ACK packets from `offset` to the end (see [Bursts](#bursts)); NAK `EOF`, `InvalidSession` |
//! | 14 CalcFileCRC32 | ACK with the file's CRC-32 (u32), MAVLink's variant (mavlink.io "MAVLink CRC": start at 0, no final XOR); NAK `FileNotFound` |
//! | 6–13 (create, write, remove, mkdir, rmdir, open for writing, truncate, rename) | NAK `FileProtected` |
//! | 128 ACK, 129 NAK | no reply (they are replies, maybe our own echoed back; replying could loop); counted |
//! | any other | NAK `UnknownCommand` |
//!
//! A `size` beyond 239 is answered NAK `InvalidDataSize`, whatever the opcode (as PX4
//! does, before anything else). Write operations get `FileProtected`, the spec's
//! "File/directory is write protected", which is what PX4 answers for a path it will not
//! write (`_validatePathIsWritable`); `UnknownCommand` would tell a client the command is
//! not understood, which is not the case.
//!
//! Paths are taken up to the first NUL within `size` (clients differ on sending one);
//! leading and trailing `/` do not matter, so `"/"` and `""` are the root and
//! `"camera/x.xml"` is `"/camera/x.xml"`.
//!
//! # Sessions
//!
//! `SESSIONS` read sessions (2 by default). A session is the client's: its number is the
//! one the client's `OpenFileRO` carries, echoed in every reply, and it is known by that
//! number and the client's system and component ids. MAVProxy picks its own session
//! number and routes replies by it (`mavproxy_ftp.py`), as ArduPilot's server allows
//! (`GCS_FTP.cpp`); QGroundControl, MAVSDK and pymavlink use 0. An `OpenFileRO` in a session
//! the client already has open re-opens it (a retried open takes no second slot). A client
//! that vanishes never sends `TerminateSession`, so when an `OpenFileRO` finds none free,
//! the session idle longest is reclaimed if it has been idle for more than
//! [`SESSION_IDLE_TIMEOUT_MS`] (reads, bursts and their packets count as use), and counted.
//!
//! # Re-transmission
//!
//! mavlink.io: "If the drone receives a message with the same sequence number then it
//! assumes that its ACK/NAK response was lost. In this case it should resend the
//! response". Keeping the last reply would cost 251 bytes of RAM (more than the rest of
//! the server: 100 bytes with two sessions on a Cortex-M); instead the server keeps a
//! record of the last request (its `seq_number`, a CRC-32 of its content and, for the two
//! requests that change state, their outcome: a few bytes) and rebuilds the reply. A request is a re-transmission when its `seq_number` and those bytes (`session`,
//! `opcode`, `size`, `offset`, `data[..size]`) are the last request's: a new client
//! reusing the number with another request is not mistaken for one. `OpenFileRO` and
//! `TerminateSession` are answered from the record, so a lost ACK does not open a second
//! session and is answered as the first was; every other request changes nothing a second
//! execution would see (files are read-only), so it is executed again, and a repeated
//! `BurstReadFile` restarts its burst, which is what a client that lost it wants.
//!
//! # Bursts
//!
//! `BurstReadFile` (which mavlink.io leaves "TBD"; this follows PX4, which pymavlink and
//! QGroundControl are written against): the reply to the request is the first packet, the
//! others come from [`FtpServer::burst_next`]. Every packet is an ACK with `req_opcode`
//! BurstReadFile, `seq_number` the request's plus 1, 2, 3, …, `offset` where its data
//! starts and `size` bytes of data: the request's `size`, or 239 for 0; the packet that
//! reaches the end of the file has `burst_complete` 1 and ends the burst. One burst runs at
//! a time. It is ended early (and counted) by `TerminateSession` of its session,
//! `ResetSessions`, another `BurstReadFile`, or its session being reclaimed; other
//! requests are answered between its packets without ending it, because clients repair
//! gaps with `ReadFile` while a burst is still arriving (pymavlink does).

use idu_gimbal::Instant;

mod directory;

use directory::{decimal, find_file, path, trim_slashes, Entries, Entry, Writer};

/// Bytes in `FILE_TRANSFER_PROTOCOL.payload`: one FTP packet.
pub const PAYLOAD_LEN: usize = 251;
/// Bytes of `data` in a packet (the payload less the 12-byte header).
pub const MAX_DATA_LEN: usize = 239;
/// The same, as the `size` field's type.
const MAX_DATA: u8 = MAX_DATA_LEN as u8;
/// How long a session must have been idle, ms, to be reclaimed for a new `OpenFileRO` when
/// none is free. Clients retry a lost reply within about a second (mavlink.io recommends
/// 50 ms, pymavlink waits 0.5 to 1 s), so 5 s of silence means the client has gone.
pub const SESSION_IDLE_TIMEOUT_MS: u32 = 5_000;

const NONE: u8 = 0;
const TERMINATE_SESSION: u8 = 1;
const RESET_SESSIONS: u8 = 2;
const LIST_DIRECTORY: u8 = 3;
const OPEN_FILE_RO: u8 = 4;
const READ_FILE: u8 = 5;
const CREATE_FILE: u8 = 6;
const RENAME: u8 = 13;
const CALC_FILE_CRC32: u8 = 14;
pub(crate) const BURST_READ_FILE: u8 = 15;
const ACK: u8 = 128;
const NAK: u8 = 129;

/// NAK error codes (`data[0]`), those this server sends.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum ErrorCode {
    InvalidDataSize = 3,
    InvalidSession = 4,
    NoSessionsAvailable = 5,
    Eof = 6,
    UnknownCommand = 7,
    FileProtected = 9,
    FileNotFound = 10,
}

/// A file served read-only: its contents are its parts one after the other, so that a file
/// kept in flash can have a piece filled in as it is served (the camera definition's model
/// name) without a copy in RAM.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct File<'a> {
    /// Its absolute path, such as `"/camera/idu-x30.xml"`: components separated by `/`;
    /// the directories are those the paths name.
    pub path: &'a str,
    /// Its contents, in parts.
    pub parts: [&'a [u8]; 3],
}

impl<'a> File<'a> {
    /// A file of one part.
    pub const fn new(path: &'a str, bytes: &'a [u8]) -> Self {
        File {
            path,
            parts: [bytes, &[], &[]],
        }
    }

    /// Its length, bytes.
    pub fn len(&self) -> usize {
        self.parts.iter().map(|p| p.len()).sum()
    }

    /// Whether it is empty.
    pub fn is_empty(&self) -> bool {
        self.parts.iter().all(|p| p.is_empty())
    }
}

/// Counters of the FTP server, each wrapping at `u32::MAX`.
#[derive(Clone, Copy, Default, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FtpStats {
    /// Packets passed to [`FtpServer::request`].
    pub requests: u32,
    /// ACKs sent in reply to requests (burst packets after the first not included).
    pub acks: u32,
    /// NAKs sent.
    pub naks: u32,
    /// Requests with a `size` beyond 239 or an opcode the protocol does not define.
    pub bad_requests: u32,
    /// ACK and NAK packets received as requests: not answered.
    pub not_requests: u32,
    /// Re-transmitted requests (same `seq_number` and content as the last one).
    pub retransmissions: u32,
    /// Sessions opened.
    pub sessions_opened: u32,
    /// Idle sessions closed to open another.
    pub sessions_reclaimed: u32,
    /// Bursts started (the first packet sent, not the last).
    pub bursts: u32,
    /// Bursts ended before the end of their file (see [Bursts](self#bursts)).
    pub bursts_cut: u32,
    /// Packets written by [`FtpServer::burst_next`].
    pub burst_packets: u32,
    /// Directory entries too long for a packet on their own, listed as skipped (`S`).
    pub entries_skipped: u32,
}

/// Who sent a request: its system and component ids.
pub type Client = (u8, u8);

/// An open read session.
#[derive(Clone, Copy, Debug)]
struct Session {
    /// Its number, the client's.
    id: u8,
    client: Client,
    /// Index in the file table.
    file: usize,
    last_used: Instant,
}

/// A burst in progress: what its next packet is.
#[derive(Clone, Copy, Debug)]
struct Burst {
    /// Its session's slot.
    slot: usize,
    /// The session's number, in every packet.
    session: u8,
    offset: u32,
    seq_number: u16,
    /// Data bytes a packet.
    chunk: u8,
}

/// How to answer the last request again.
#[derive(Clone, Copy, Debug)]
enum Replay {
    /// Execute it again: it changed nothing a second execution sees.
    Execute,
    /// ACK without data (a session terminated).
    Ack,
    /// ACK of an `OpenFileRO`.
    Opened { file: usize },
    /// NAK with this code.
    Nak(ErrorCode),
}

/// The last request executed, to recognise its re-transmission.
#[derive(Clone, Copy, Debug)]
struct LastRequest {
    seq_number: u16,
    /// CRC-32 of its `session`, `opcode`, `size`, `offset` and `data[..size]`.
    key: u32,
    replay: Replay,
}

/// A request's header fields.
#[derive(Clone, Copy, Debug)]
struct Header {
    seq_number: u16,
    session: u8,
    opcode: u8,
    size: u8,
    offset: u32,
}

impl Header {
    /// The header and the data of `packet`.
    fn read(packet: &[u8; PAYLOAD_LEN]) -> (Header, &[u8; MAX_DATA_LEN]) {
        let [s0, s1, session, opcode, size, _, _, _, o0, o1, o2, o3, data @ ..] = packet;
        let header = Header {
            seq_number: u16::from_le_bytes([*s0, *s1]),
            session: *session,
            opcode: *opcode,
            size: *size,
            offset: u32::from_le_bytes([*o0, *o1, *o2, *o3]),
        };
        (header, data)
    }

    /// The request's content and who sent it, to tell a re-transmission: the fields that
    /// mean something in a request (not `req_opcode`, `burst_complete`, padding or bytes
    /// past `size`).
    fn key(&self, client: Client, data: &[u8; MAX_DATA_LEN]) -> u32 {
        let crc = crc32(
            0,
            &[client.0, client.1, self.session, self.opcode, self.size],
        );
        let crc = crc32(crc, &self.offset.to_le_bytes());
        crc32(crc, data.get(..usize::from(self.size)).unwrap_or(&[]))
    }
}

/// A successful reply's fields.
#[derive(Clone, Copy, Debug)]
struct Ack {
    size: u8,
    session: u8,
    burst_complete: bool,
}

impl Ack {
    fn new(size: u8, session: u8) -> Self {
        Ack {
            size,
            session,
            burst_complete: false,
        }
    }
}

/// Writes a packet's header and returns its data.
#[allow(clippy::too_many_arguments)] // the packet's fields, in its order
fn write_header(
    packet: &mut [u8; PAYLOAD_LEN],
    seq_number: u16,
    session: u8,
    opcode: u8,
    size: u8,
    req_opcode: u8,
    burst_complete: bool,
    offset: u32,
) -> &mut [u8; MAX_DATA_LEN] {
    let [s0, s1, sess, op, sz, req, complete, _, o0, o1, o2, o3, data @ ..] = packet;
    [*s0, *s1] = seq_number.to_le_bytes();
    *sess = session;
    *op = opcode;
    *sz = size;
    *req = req_opcode;
    *complete = u8::from(burst_complete);
    [*o0, *o1, *o2, *o3] = offset.to_le_bytes();
    data
}

/// The data of `packet`.
fn data_mut(packet: &mut [u8; PAYLOAD_LEN]) -> &mut [u8; MAX_DATA_LEN] {
    let [_, _, _, _, _, _, _, _, _, _, _, _, data @ ..] = packet;
    data
}

/// A read-only MAVLink FTP server with `SESSIONS` read sessions (at most 256), over the
/// files each call is given; see the [module docs](self).
#[derive(Clone, Debug)]
pub struct FtpServer<const SESSIONS: usize = 2> {
    sessions: [Option<Session>; SESSIONS],
    burst: Option<Burst>,
    last: Option<LastRequest>,
    stats: FtpStats,
}

impl<const SESSIONS: usize> Default for FtpServer<SESSIONS> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const SESSIONS: usize> FtpServer<SESSIONS> {
    /// A server, no session open.
    pub const fn new() -> Self {
        // Session ids are one byte.
        const { assert!(SESSIONS >= 1 && SESSIONS <= 256) };
        FtpServer {
            sessions: [None; SESSIONS],
            burst: None,
            last: None,
            stats: FtpStats {
                requests: 0,
                acks: 0,
                naks: 0,
                bad_requests: 0,
                not_requests: 0,
                retransmissions: 0,
                sessions_opened: 0,
                sessions_reclaimed: 0,
                bursts: 0,
                bursts_cut: 0,
                burst_packets: 0,
                entries_skipped: 0,
            },
        }
    }

    /// The counters.
    pub fn stats(&self) -> FtpStats {
        self.stats
    }

    /// Whether a burst has packets left for [`FtpServer::burst_next`].
    pub fn burst_pending(&self) -> bool {
        self.burst.is_some()
    }

    /// Handles one request packet (`FILE_TRANSFER_PROTOCOL.payload`) from `client` at
    /// `now`, over `files` (the same files, in the same order, at every call: a session
    /// knows its file by its index). Returns whether to send `reply` (then written in
    /// full, to `client`); `false` only for an ACK or NAK received as a request, with
    /// `reply` untouched.
    pub fn request(
        &mut self,
        files: &[File<'_>],
        client: Client,
        request: &[u8; PAYLOAD_LEN],
        now: Instant,
        reply: &mut [u8; PAYLOAD_LEN],
    ) -> bool {
        self.stats.requests = self.stats.requests.wrapping_add(1);
        let (header, data) = Header::read(request);
        if header.opcode == ACK || header.opcode == NAK {
            self.stats.not_requests = self.stats.not_requests.wrapping_add(1);
            return false;
        }
        *reply = [0; PAYLOAD_LEN];
        let result = if usize::from(header.size) > MAX_DATA_LEN {
            self.stats.bad_requests = self.stats.bad_requests.wrapping_add(1);
            Err(ErrorCode::InvalidDataSize)
        } else {
            let key = header.key(client, data);
            let replay = self
                .last
                .filter(|last| last.seq_number == header.seq_number && last.key == key)
                .map(|last| last.replay);
            if replay.is_some() {
                self.stats.retransmissions = self.stats.retransmissions.wrapping_add(1);
            }
            match replay {
                Some(Replay::Ack) => Ok(Ack::new(0, header.session)),
                Some(Replay::Nak(code)) => Err(code),
                Some(Replay::Opened { file }) => {
                    self.reopened(files, client, header.session, file, now, data_mut(reply))
                }
                Some(Replay::Execute) | None => {
                    let (result, replay) =
                        self.execute(files, client, &header, data, now, data_mut(reply));
                    self.last = Some(LastRequest {
                        seq_number: header.seq_number,
                        key,
                        replay,
                    });
                    result
                }
            }
        };
        let seq_number = header.seq_number.wrapping_add(1);
        match result {
            Ok(ack) => {
                self.stats.acks = self.stats.acks.wrapping_add(1);
                write_header(
                    reply,
                    seq_number,
                    ack.session,
                    ACK,
                    ack.size,
                    header.opcode,
                    ack.burst_complete,
                    header.offset,
                );
            }
            Err(code) => {
                self.stats.naks = self.stats.naks.wrapping_add(1);
                let data = write_header(
                    reply,
                    seq_number,
                    header.session,
                    NAK,
                    1,
                    header.opcode,
                    false,
                    header.offset,
                );
                // Whatever the handler wrote before failing goes.
                *data = [0; MAX_DATA_LEN];
                let [error, ..] = data;
                *error = code as u8;
            }
        }
        true
    }

    /// Writes the next packet of the burst in progress at `now`, over the files
    /// [`FtpServer::request`] was given, and returns the client it goes to: the one whose
    /// session the burst reads, whoever sent the requests answered since. `None` (and
    /// `reply` untouched) when there is none.
    pub fn burst_next(
        &mut self,
        files: &[File<'_>],
        now: Instant,
        reply: &mut [u8; PAYLOAD_LEN],
    ) -> Option<Client> {
        let burst = self.burst?;
        let Ok((file, client)) = self.slot_file(files, burst.slot, now) else {
            // Not reached: whatever closes the session ends its burst.
            self.burst = None;
            return None;
        };
        let mut packet = [0; PAYLOAD_LEN];
        let Some((size, complete)) =
            read_chunk(&file, burst.offset, burst.chunk, data_mut(&mut packet))
        else {
            // Not reached: a burst is kept only while its offset is inside the file.
            self.burst = None;
            return None;
        };
        *reply = packet;
        write_header(
            reply,
            burst.seq_number,
            burst.session,
            ACK,
            size,
            BURST_READ_FILE,
            complete,
            burst.offset,
        );
        self.stats.burst_packets = self.stats.burst_packets.wrapping_add(1);
        self.burst = (!complete).then_some(Burst {
            offset: burst.offset.saturating_add(u32::from(size)),
            seq_number: burst.seq_number.wrapping_add(1),
            ..burst
        });
        Some(client)
    }

    /// Executes a request whose `size` is valid; writes the reply's data. Returns the
    /// outcome and how to answer its re-transmission.
    fn execute(
        &mut self,
        files: &[File<'_>],
        client: Client,
        header: &Header,
        data: &[u8; MAX_DATA_LEN],
        now: Instant,
        reply: &mut [u8; MAX_DATA_LEN],
    ) -> (Result<Ack, ErrorCode>, Replay) {
        let session = header.session;
        let result = match header.opcode {
            NONE => Ok(Ack::new(0, session)),
            TERMINATE_SESSION => {
                let result = self.terminate(client, session);
                let replay = match result {
                    Ok(_) => Replay::Ack,
                    Err(code) => Replay::Nak(code),
                };
                return (result, replay);
            }
            RESET_SESSIONS => {
                self.sessions = [None; SESSIONS];
                self.end_burst();
                Ok(Ack::new(0, session))
            }
            LIST_DIRECTORY => self
                .list(files, path(data, header.size), header.offset, reply)
                .map(|size| Ack::new(size, session)),
            OPEN_FILE_RO => {
                let path = path(data, header.size);
                return match self.open(files, client, session, path, now, reply) {
                    Ok((ack, file)) => (Ok(ack), Replay::Opened { file }),
                    Err(code) => (Err(code), Replay::Nak(code)),
                };
            }
            READ_FILE => self.read(files, client, header, now, reply),
            BURST_READ_FILE => self.start_burst(files, client, header, now, reply),
            CALC_FILE_CRC32 => find_file(files, path(data, header.size))
                .and_then(|index| files.get(index))
                .map(|file| {
                    put_u32(reply, file.parts.iter().fold(0, |crc, p| crc32(crc, p)));
                    Ack::new(4, session)
                })
                .ok_or(ErrorCode::FileNotFound),
            CREATE_FILE..=RENAME => Err(ErrorCode::FileProtected),
            _ => {
                self.stats.bad_requests = self.stats.bad_requests.wrapping_add(1);
                Err(ErrorCode::UnknownCommand)
            }
        };
        (result, Replay::Execute)
    }

    /// The slot of `client`'s session `id`, if open.
    fn slot_of(&self, client: Client, id: u8) -> Option<usize> {
        self.sessions
            .iter()
            .position(|s| s.is_some_and(|s| s.id == id && s.client == client))
    }

    /// Ends the burst in progress, if any, before its end.
    fn end_burst(&mut self) {
        if self.burst.take().is_some() {
            self.stats.bursts_cut = self.stats.bursts_cut.wrapping_add(1);
        }
    }

    /// Closes `client`'s session `id`; ACK whether or not it was open.
    fn terminate(&mut self, client: Client, id: u8) -> Result<Ack, ErrorCode> {
        if let Some(slot) = self.slot_of(client, id) {
            self.close(slot);
        }
        Ok(Ack::new(0, id))
    }

    /// Closes the session in `slot`, and its burst.
    fn close(&mut self, slot: usize) {
        if let Some(entry) = self.sessions.get_mut(slot) {
            *entry = None;
        }
        if self.burst.is_some_and(|b| b.slot == slot) {
            self.end_burst();
        }
    }

    /// Opens the file at `path` in `client`'s session `id`: the one it has open under that
    /// number (re-opened), a free one, or one reclaimed; the ACK and the file's index.
    fn open(
        &mut self,
        files: &[File<'_>],
        client: Client,
        id: u8,
        path: &[u8],
        now: Instant,
        reply: &mut [u8; MAX_DATA_LEN],
    ) -> Result<(Ack, usize), ErrorCode> {
        let file = find_file(files, path).ok_or(ErrorCode::FileNotFound)?;
        let slot = match self.slot_of(client, id) {
            Some(own) => {
                self.close(own);
                own
            }
            None => match self.sessions.iter().position(Option::is_none) {
                Some(free) => free,
                None => self.reclaim(now).ok_or(ErrorCode::NoSessionsAvailable)?,
            },
        };
        let entry = self
            .sessions
            .get_mut(slot)
            .ok_or(ErrorCode::NoSessionsAvailable)?;
        *entry = Some(Session {
            id,
            client,
            file,
            last_used: now,
        });
        self.stats.sessions_opened = self.stats.sessions_opened.wrapping_add(1);
        Ok((file_size_ack(files, id, file, reply), file))
    }

    /// Closes the session idle longest if idle more than [`SESSION_IDLE_TIMEOUT_MS`];
    /// its slot.
    fn reclaim(&mut self, now: Instant) -> Option<usize> {
        // Wrapping differences: right across the tick's wrap for sessions used within
        // the last 2^32 ms.
        let (slot, _) = self
            .sessions
            .iter()
            .enumerate()
            .filter_map(|(slot, s)| s.map(|s| (slot, now.millis_since(s.last_used))))
            .filter(|&(_, idle)| idle > SESSION_IDLE_TIMEOUT_MS)
            .max_by_key(|&(_, idle)| idle)?;
        self.close(slot);
        self.stats.sessions_reclaimed = self.stats.sessions_reclaimed.wrapping_add(1);
        Some(slot)
    }

    /// The ACK of an `OpenFileRO` re-transmitted: the same session and size again.
    fn reopened(
        &mut self,
        files: &[File<'_>],
        client: Client,
        id: u8,
        file: usize,
        now: Instant,
        reply: &mut [u8; MAX_DATA_LEN],
    ) -> Result<Ack, ErrorCode> {
        if let Some(session) = self
            .slot_of(client, id)
            .and_then(|slot| self.sessions.get_mut(slot))
            .and_then(Option::as_mut)
            .filter(|s| s.file == file)
        {
            session.last_used = now;
        }
        Ok(file_size_ack(files, id, file, reply))
    }

    /// The file of the session in `slot`, marked used at `now`.
    fn slot_file<'f>(
        &mut self,
        files: &[File<'f>],
        slot: usize,
        now: Instant,
    ) -> Result<(File<'f>, Client), ErrorCode> {
        let session = self
            .sessions
            .get_mut(slot)
            .and_then(Option::as_mut)
            .ok_or(ErrorCode::InvalidSession)?;
        session.last_used = now;
        let file = files
            .get(session.file)
            .copied()
            .unwrap_or(File::new("", &[]));
        Ok((file, session.client))
    }

    /// `client`'s session `id`'s slot and file, marked used at `now`.
    fn session_file<'f>(
        &mut self,
        files: &[File<'f>],
        client: Client,
        id: u8,
        now: Instant,
    ) -> Result<(usize, File<'f>), ErrorCode> {
        let slot = self.slot_of(client, id).ok_or(ErrorCode::InvalidSession)?;
        Ok((slot, self.slot_file(files, slot, now)?.0))
    }

    fn read(
        &mut self,
        files: &[File<'_>],
        client: Client,
        header: &Header,
        now: Instant,
        reply: &mut [u8; MAX_DATA_LEN],
    ) -> Result<Ack, ErrorCode> {
        let (_, file) = self.session_file(files, client, header.session, now)?;
        let (size, _) =
            read_chunk(&file, header.offset, header.size, reply).ok_or(ErrorCode::Eof)?;
        Ok(Ack::new(size, header.session))
    }

    fn start_burst(
        &mut self,
        files: &[File<'_>],
        client: Client,
        header: &Header,
        now: Instant,
        reply: &mut [u8; MAX_DATA_LEN],
    ) -> Result<Ack, ErrorCode> {
        // One burst at a time: a new request replaces the one in progress.
        self.end_burst();
        let (slot, file) = self.session_file(files, client, header.session, now)?;
        // Size 0 would never advance.
        let chunk = match header.size {
            0 => MAX_DATA,
            size => size,
        };
        let (size, complete) =
            read_chunk(&file, header.offset, chunk, reply).ok_or(ErrorCode::Eof)?;
        self.stats.bursts = self.stats.bursts.wrapping_add(1);
        self.burst = (!complete).then_some(Burst {
            slot,
            session: header.session,
            offset: header.offset.saturating_add(u32::from(size)),
            seq_number: header.seq_number.wrapping_add(2),
            chunk,
        });
        Ok(Ack {
            size,
            session: header.session,
            burst_complete: complete,
        })
    }

    /// Lists the directory `dir` from entry `offset`; the data's size.
    fn list(
        &mut self,
        files: &[File<'_>],
        dir: &[u8],
        offset: u32,
        reply: &mut [u8; MAX_DATA_LEN],
    ) -> Result<u8, ErrorCode> {
        let dir = trim_slashes(dir);
        if !dir.is_empty() && Entries::new(files, dir).next().is_none() {
            return Err(ErrorCode::FileNotFound);
        }
        let first = usize::try_from(offset).unwrap_or(usize::MAX);
        let mut out = Writer { buf: reply, len: 0 };
        let mut listed = 0u32;
        let mut digits = [0; 20];
        for entry in Entries::new(files, dir).skip(first) {
            let fits = match entry {
                Entry::File { name, size } => {
                    out.put_all(&[b"F", name, b"\t", decimal(size, &mut digits), b"\0"])
                }
                Entry::Directory { name } => out.put_all(&[b"D", name, b"\0"]),
            };
            if !fits {
                if listed == 0 {
                    // Too long for any packet: a skip entry keeps the client's index
                    // moving.
                    out.put_all(&[b"S\0"]);
                    self.stats.entries_skipped = self.stats.entries_skipped.wrapping_add(1);
                    listed = 1;
                }
                break;
            }
            listed = listed.wrapping_add(1);
        }
        if listed == 0 {
            return Err(ErrorCode::Eof);
        }
        // At most MAX_DATA_LEN.
        Ok(u8::try_from(out.len).unwrap_or(0))
    }
}

/// The ACK of an `OpenFileRO`: the file's size.
fn file_size_ack(files: &[File<'_>], id: u8, file: usize, reply: &mut [u8; MAX_DATA_LEN]) -> Ack {
    let len = files.get(file).map_or(0, File::len);
    // Offsets are u32: a file in a 32-bit MCU's flash is shorter.
    put_u32(reply, u32::try_from(len).unwrap_or(u32::MAX));
    Ack::new(4, id)
}

/// Copies up to `max` bytes of `file` from `offset` into `data`; the count and whether
/// they reach the end. `None` at or past the end.
fn read_chunk(
    file: &File<'_>,
    offset: u32,
    max: u8,
    data: &mut [u8; MAX_DATA_LEN],
) -> Option<(u8, bool)> {
    let mut skip = usize::try_from(offset).ok()?;
    let rest = file.len().checked_sub(skip).filter(|&r| r > 0)?;
    let size = u8::try_from(rest).unwrap_or(u8::MAX).min(max).min(MAX_DATA);
    // Part by part, a slice at a time.
    let mut out = data.get_mut(..usize::from(size)).unwrap_or(&mut []);
    for part in file.parts {
        let Some(from) = part.get(skip..) else {
            skip = skip.saturating_sub(part.len());
            continue;
        };
        skip = 0;
        let n = from.len().min(out.len());
        let Some((to, later)) = core::mem::take(&mut out).split_at_mut_checked(n) else {
            break;
        };
        for (to, from) in to.iter_mut().zip(from) {
            *to = *from;
        }
        out = later;
    }
    Some((size, rest <= usize::from(size)))
}

fn put_u32(data: &mut [u8; MAX_DATA_LEN], value: u32) {
    let [d0, d1, d2, d3, ..] = data;
    [*d0, *d1, *d2, *d3] = value.to_le_bytes();
}

/// CRC-32 as MAVLink uses it (reflected polynomial 0x04C11DB7, from `crc`, no final
/// XOR), a nibble at a time: a 64-byte table instead of 1 KiB.
fn crc32(mut crc: u32, bytes: &[u8]) -> u32 {
    const TABLE: [u32; 16] = [
        0x0000_0000,
        0x1DB7_1064,
        0x3B6E_20C8,
        0x26D9_30AC,
        0x76DC_4190,
        0x6B6B_51F4,
        0x4DB2_6158,
        0x5005_713C,
        0xEDB8_8320,
        0xF00F_9344,
        0xD6D6_A3E8,
        0xCB61_B38C,
        0x9B64_C2B0,
        0x86D3_D2D4,
        0xA00A_E278,
        0xBDBD_F21C,
    ];
    let step = |crc: u32| (crc >> 4) ^ TABLE.get((crc & 0xF) as usize).copied().unwrap_or(0);
    for &byte in bytes {
        crc ^= u32::from(byte);
        crc = step(step(crc));
    }
    crc
}

#[cfg(test)]
mod tests;
