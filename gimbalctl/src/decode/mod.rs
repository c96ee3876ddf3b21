//! `gimbalctl decode`: CAN logs (three text forms) or a serial/TCP byte capture to JSON
//! lines.
//!
//! One decoder per input form ([`LogDecoder`], [`StreamDecoder`]) turns the input into
//! [`Record`]s: frames with their timestamps, messages, and the faults found (CRC errors,
//! lost frames), while keeping the `--stats` counters. Records go to a [`Sink`]: the JSON
//! lines written here ([`JsonLines`]) and the plot's trace are two sinks of the same
//! decoding, so the two always agree on what a log holds.
//!
//! Built for long logs: input is read through one fixed buffer and processed a line at a
//! time in place (a line is copied only when it straddles two reads, lines are found with
//! `memchr`), the canonical `candump -L` line takes a one-pass fast path that falls back to
//! the general three-form parser for anything else, hex is parsed through a table, and
//! JSON is appended to a reused output buffer that goes to a locked stdout in large writes.
//! The output is also handed over whenever a read returns less than a full block, or
//! returned a full one but the next would block (`poll(2)` with no wait): on a file that
//! happens only at its end, so long logs keep their large writes, while a pipe or a
//! terminal fed a line at a time (`candump -L can0 | gimbalctl decode`) sees each result as
//! soon as its line is complete. `benches/host/compare.sh` measures it against cantools.
//! Memory stays constant whatever the input size: a line longer than [`MAX_LINE`] is
//! counted as malformed without being buffered.
//!
//! Every byte is interpreted by the library: control frames by `Command::decode`, vehicle
//! frames by `VehicleFrame::decode`, postbacks by the `PostbackAssembler` (CAN) or the
//! `StreamParser` (stream), texts by the `TextAssembler`.

use std::io::{BufRead, Read, Write};

use idu_gimbal::link::postback::PostbackAssembler;
use idu_gimbal::link::text::TextAssembler;
use idu_gimbal::wire::control::Command;
use idu_gimbal::wire::ids;
use idu_gimbal::wire::postback::Postback;
use idu_gimbal::wire::serial::{StreamItem, StreamParser};
use idu_gimbal::wire::vehicle::VehicleFrame;
use idu_gimbal::Instant;

use crate::error::Failure;
use crate::json::Obj;
use crate::spec;

mod candump;

use candump::{parse_line, timestamp_millis, Line};

/// The longest line kept; longer lines are malformed (no candump line comes close).
pub const MAX_LINE: usize = 4096;
/// The longest text message reassembled.
const TEXT_CAPACITY: usize = 4096;
/// Output is handed to stdout when this much has accumulated.
const FLUSH_AT: usize = 1 << 16;
/// Input is read in blocks of this size.
const READ_BLOCK: usize = 1 << 16;

/// The `--stats` counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Input lines (0 for `--stream`).
    pub lines: u64,
    /// CAN frames read (any ID), or frames recognised on the stream (good or bad CRC).
    pub frames: u64,
    /// JSON messages written (not counting the stats line).
    pub messages: u64,
    /// Postbacks whose CRC failed (and serial frames, with `--stream`).
    pub crc_errors: u64,
    /// Messages started but never completed: postbacks with lost frames, texts with no
    /// end frame, a partial frame at the end of a stream.
    pub incomplete: u64,
    /// Lines that are no CAN frame in any of the three forms, and frames on the protocol's
    /// IDs whose content does not decode (wrong length, value out of range, bad text byte).
    pub malformed_lines: u64,
    /// Frames of other devices: other IDs, standard IDs, remote, CAN FD and error frames.
    pub foreign_frames: u64,
}

impl Stats {
    fn write(&self, out: &mut Vec<u8>) {
        let mut o = Obj::bare(out, "stats");
        o.int("lines", self.lines as i64)
            .int("frames", self.frames as i64)
            .int("messages", self.messages as i64)
            .int("crc_errors", self.crc_errors as i64)
            .int("incomplete", self.incomplete as i64)
            .int("malformed_lines", self.malformed_lines as i64)
            .int("foreign_frames", self.foreign_frames as i64);
        o.end();
    }
}

// ---------------------------------------------------------------------------------------
// Records and sinks

/// Where a record was found: the log line's timestamp (as written) and the frame's CAN ID.
/// A stream capture has neither.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Origin<'a> {
    pub ts: Option<&'a [u8]>,
    pub id: Option<u32>,
}

/// What a decoder finds, in input order. A log line gives its [`Record::Frame`] first, then
/// the faults its frame revealed, then the message it completed, if any.
#[derive(Clone, Copy, Debug)]
pub enum Record<'a> {
    /// A data frame with an extended ID, of any device, read from a log line: a sink sees
    /// the time of every line, not only of the lines that complete a message.
    Frame(Origin<'a>),
    /// A whole postback with a good CRC.
    Postback(Origin<'a>, Postback),
    /// A control frame's command.
    Command(Origin<'a>, Command),
    /// A GPS, altitude or attitude frame.
    Vehicle(Origin<'a>, VehicleFrame),
    /// A whole text message.
    Text(Origin<'a>, &'a str),
    /// A message whose CRC failed.
    CrcError(Origin<'a>),
    /// Frames lost here: on a CAN log, up to four postback frames that ended in no message
    /// and that no CRC error or malformed frame explains; on a stream, a run of bytes skipped
    /// that no CRC error explains, or a frame cut short by the end of the input.
    Lost(Origin<'a>),
}

/// Where a decoder's records go: the JSON lines of `decode`, the plot's trace.
pub trait Sink {
    /// Takes the next record.
    fn record(&mut self, record: Record<'_>) -> Result<(), Failure>;

    /// The input has nothing more for now (a pipe or terminal would block): a sink that
    /// writes should hand over what it has, so that a live capture is seen as it comes.
    fn input_paused(&mut self) -> Result<(), Failure> {
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------
// Messages to JSON

/// Writes a postback object.
pub fn write_postback(out: &mut Vec<u8>, t: Option<&[u8]>, id: Option<u32>, pb: &Postback) {
    let mut o = Obj::start(out, "postback", t, id);
    o.int("gimbal_type", pb.gimbal_type.code().into())
        .str_or_null("gimbal_model", pb.gimbal_type.model_name())
        .bool("tracking", pb.tracking)
        .int("mode", pb.mode.code().into())
        .str_or_null("mode_name", pb.mode.name())
        .fixed("pitch_deg", pb.pitch.into(), 2)
        .fixed("heading_deg", pb.heading.into(), 2)
        .fixed("motor_heading_deg", pb.motor_heading.into(), 2);
    o.end();
}

/// Writes a command object.
pub fn write_command(out: &mut Vec<u8>, t: Option<&[u8]>, id: Option<u32>, cmd: &Command) {
    let mut o = Obj::start(out, "command", t, id);
    spec::write_command_fields(&mut o, cmd);
    o.end();
}

/// Writes a GPS, altitude or attitude object.
pub fn write_vehicle(out: &mut Vec<u8>, t: Option<&[u8]>, id: Option<u32>, v: &VehicleFrame) {
    match v {
        VehicleFrame::Gps(g) => {
            let mut o = Obj::start(out, "gps", t, id);
            o.fixed("lat_deg", g.lat_e7().into(), 7)
                .fixed("lon_deg", g.lon_e7().into(), 7);
            o.end();
        }
        VehicleFrame::Altitude(a) => {
            let mut o = Obj::start(out, "altitude", t, id);
            o.fixed("alt_m", a.cm().into(), 2);
            o.end();
        }
        VehicleFrame::Attitude(a) => {
            let mut o = Obj::start(out, "attitude", t, id);
            o.fixed("pitch_deg", a.pitch_centideg().into(), 2)
                .fixed("roll_deg", a.roll_centideg().into(), 2)
                .fixed("heading_deg", a.heading_centideg().into(), 2);
            o.end();
        }
    }
}

/// The sink of `gimbalctl decode`: each message as a JSON line, gathered in a reused buffer
/// and handed to `w` in large writes, or as soon as the input pauses.
pub struct JsonLines<W: Write> {
    out: Vec<u8>,
    w: W,
}

impl<W: Write> JsonLines<W> {
    pub fn new(w: W) -> Self {
        JsonLines {
            out: Vec::with_capacity(FLUSH_AT + 4096),
            w,
        }
    }

    /// Writes the stats line when asked for, then everything still held.
    pub fn finish(mut self, stats: Option<&Stats>) -> Result<(), Failure> {
        if let Some(stats) = stats {
            stats.write(&mut self.out);
        }
        self.w.write_all(&self.out).map_err(Failure::stdout)?;
        self.w.flush().map_err(Failure::stdout)
    }

    fn write(&mut self, record: Record<'_>) -> Result<(), Failure> {
        let out = &mut self.out;
        match record {
            Record::Postback(at, pb) => write_postback(out, at.ts, at.id, &pb),
            Record::Command(at, cmd) => write_command(out, at.ts, at.id, &cmd),
            Record::Vehicle(at, v) => write_vehicle(out, at.ts, at.id, &v),
            Record::Text(at, text) => {
                let mut o = Obj::start(out, "text", at.ts, at.id);
                o.str("text", text);
                o.end();
            }
            Record::Frame(_) | Record::CrcError(_) | Record::Lost(_) => {}
        }
        if self.out.len() >= FLUSH_AT {
            self.w.write_all(&self.out).map_err(Failure::stdout)?;
            self.out.clear();
        }
        Ok(())
    }
}

impl<W: Write> Sink for JsonLines<W> {
    // Always inlined, so that a record written as nothing (every line's frame) costs
    // nothing on the hot path.
    #[inline(always)]
    fn record(&mut self, record: Record<'_>) -> Result<(), Failure> {
        match record {
            // Faults are counted in the stats line, not written one by one.
            Record::Frame(_) | Record::CrcError(_) | Record::Lost(_) => Ok(()),
            _ => self.write(record),
        }
    }

    fn input_paused(&mut self) -> Result<(), Failure> {
        if !self.out.is_empty() {
            self.w.write_all(&self.out).map_err(Failure::stdout)?;
            self.out.clear();
            self.w.flush().map_err(Failure::stdout)?;
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------
// The CAN log decoder

/// Decodes CAN log lines, in order, into records.
pub struct LogDecoder {
    postbacks: PostbackAssembler,
    text: TextAssembler<TEXT_CAPACITY>,
    stats: Stats,
    /// The latest log time seen (timestamps drive the assembler's gap bound; lines without
    /// one keep the previous time).
    now: Instant,
    /// Assembler counters at the last report, for reporting what each frame changed.
    mark_discarded: u32,
    mark_crc: u32,
    mark_malformed: u32,
    /// Postback frames lost since the last good postback: each run of up to four of them
    /// is one incomplete message.
    lost_frames: u32,
}

impl Default for LogDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl LogDecoder {
    /// A decoder at the start of a log.
    pub fn new() -> Self {
        LogDecoder {
            postbacks: PostbackAssembler::new(),
            text: TextAssembler::new(),
            stats: Stats::default(),
            now: Instant::from_millis(0),
            mark_discarded: 0,
            mark_crc: 0,
            mark_malformed: 0,
            lost_frames: 0,
        }
    }

    /// The counters so far.
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Reports the postback frames the assembler threw away since the last report: four
    /// for each CRC error, and the rest, less the malformed ones, as lost.
    fn report_discards(&mut self, at: Origin<'_>, sink: &mut impl Sink) -> Result<(), Failure> {
        let s = self.postbacks.stats();
        // CRC errors and malformed frames discard frames too: no discard, nothing to report.
        if s.discarded_frames == self.mark_discarded {
            return Ok(());
        }
        let discarded = s.discarded_frames.wrapping_sub(self.mark_discarded);
        let crc = s.crc_errors.wrapping_sub(self.mark_crc);
        let malformed = s.malformed.wrapping_sub(self.mark_malformed);
        self.mark_discarded = s.discarded_frames;
        self.mark_crc = s.crc_errors;
        self.mark_malformed = s.malformed;
        // Every CRC error discards exactly four frames and every malformed frame at least
        // itself, so over any span the lost frames add up to what the totals give.
        let lost = discarded
            .saturating_sub(crc.saturating_mul(4))
            .saturating_sub(malformed);
        self.stats.crc_errors += u64::from(crc);
        self.lost_frames = self.lost_frames.saturating_add(lost);
        for _ in 0..crc {
            sink.record(Record::CrcError(at))?;
        }
        for _ in 0..lost.div_ceil(4) {
            sink.record(Record::Lost(at))?;
        }
        Ok(())
    }

    /// Counts the frames lost since the last good postback as incomplete messages.
    fn close_loss_run(&mut self) {
        self.stats.incomplete += u64::from(self.lost_frames.div_ceil(4));
        self.lost_frames = 0;
    }

    /// Counts a decoded message and hands it on.
    fn message(&mut self, record: Record<'_>, sink: &mut impl Sink) -> Result<(), Failure> {
        self.stats.messages += 1;
        sink.record(record)
    }

    /// Takes one line (without its newline); `None` is a line too long to keep, which is
    /// malformed.
    pub fn line(&mut self, line: Option<&[u8]>, sink: &mut impl Sink) -> Result<(), Failure> {
        self.stats.lines += 1;
        let Some(line) = line else {
            self.stats.malformed_lines += 1;
            return Ok(());
        };
        let (ts, id, data, len) = match parse_line(line) {
            Line::Blank => return Ok(()),
            Line::Malformed => {
                self.stats.malformed_lines += 1;
                return Ok(());
            }
            Line::Foreign => {
                self.stats.frames += 1;
                self.stats.foreign_frames += 1;
                return Ok(());
            }
            Line::Frame { ts, id, data, len } => (ts, id, data, len),
        };
        self.stats.frames += 1;
        if let Some(ts) = ts {
            self.now = timestamp_millis(ts);
        }
        let at = Origin { ts, id: Some(id) };
        sink.record(Record::Frame(at))?;
        let data = &data[..len];
        match id {
            ids::POSTBACK => {
                if len != 8 {
                    self.stats.malformed_lines += 1;
                }
                let pb = self.postbacks.feed(id, data, self.now);
                self.report_discards(at, sink)?;
                if let Some(pb) = pb {
                    self.close_loss_run();
                    self.message(Record::Postback(at, pb), sink)?;
                }
            }
            ids::CONTROL => match Command::decode(data) {
                Ok(cmd) => self.message(Record::Command(at, cmd), sink)?,
                Err(_) => self.stats.malformed_lines += 1,
            },
            ids::GPS | ids::ALTITUDE | ids::ATTITUDE => match VehicleFrame::decode(id, data) {
                Ok(v) => self.message(Record::Vehicle(at, v), sink)?,
                Err(_) => self.stats.malformed_lines += 1,
            },
            ids::TEXT | ids::TEXT_END => match self.text.feed(id, data) {
                Ok(Some(text)) => {
                    // Not `self.message`: `text` borrows the assembler.
                    self.stats.messages += 1;
                    sink.record(Record::Text(at, text))?;
                }
                Ok(None) => {}
                Err(_) => self.stats.malformed_lines += 1,
            },
            _ => self.stats.foreign_frames += 1,
        }
        Ok(())
    }

    /// Ends the log: partial messages still held are counted as incomplete.
    pub fn finish(&mut self, sink: &mut impl Sink) -> Result<(), Failure> {
        if let Some(late) = self.postbacks.expiry() {
            self.postbacks.expire(late);
        }
        self.report_discards(Origin::default(), sink)?;
        self.close_loss_run();
        if self.text.pending() > 0 {
            self.stats.incomplete += 1;
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------
// The stream decoder

/// Decodes a serial/TCP byte capture into records.
#[derive(Default)]
pub struct StreamDecoder {
    parser: StreamParser,
    undecodable: u64,
    messages: u64,
    /// Parser counters at the last report: CRC errors, and bytes skipped or in invalid
    /// frames.
    mark_crc: u32,
    mark_skipped: u32,
    /// The sum of the parser's fault counters after the last byte: one compare a byte.
    mark_faults: u32,
    /// Since the last frame: whether a CRC error explains the bytes skipped after it (the
    /// parser rescans a bad frame's bytes), and whether a loss was reported already.
    bad_frame: bool,
    lost_reported: bool,
}

impl StreamDecoder {
    /// Takes the next bytes of the stream.
    pub fn bytes(&mut self, bytes: &[u8], sink: &mut impl Sink) -> Result<(), Failure> {
        // Bytes are taken one at a time so that faults land between the right messages.
        for &b in bytes {
            let item = self.parser.push(b);
            // The counters only grow, so their sum changes exactly when one of them does.
            let s = self.parser.stats();
            let faults = s
                .crc_errors
                .wrapping_add(s.skipped_bytes)
                .wrapping_add(s.invalid_frames);
            if faults != self.mark_faults {
                self.mark_faults = faults;
                self.report_faults(sink)?;
            }
            let Some(item) = item else { continue };
            self.bad_frame = false;
            self.lost_reported = false;
            let at = Origin::default();
            match item {
                StreamItem::Control(data) => match Command::decode(&data) {
                    Ok(cmd) => {
                        self.messages += 1;
                        sink.record(Record::Command(at, cmd))?;
                    }
                    Err(_) => self.undecodable += 1,
                },
                StreamItem::Postback(pb) => {
                    self.messages += 1;
                    sink.record(Record::Postback(at, pb))?;
                }
            }
        }
        Ok(())
    }

    /// Reports the faults the last byte revealed. Out of line: most bytes reveal none.
    #[cold]
    #[inline(never)]
    fn report_faults(&mut self, sink: &mut impl Sink) -> Result<(), Failure> {
        let at = Origin::default();
        let s = self.parser.stats();
        for _ in 0..s.crc_errors.wrapping_sub(self.mark_crc) {
            sink.record(Record::CrcError(at))?;
            self.bad_frame = true;
        }
        self.mark_crc = s.crc_errors;
        // Bytes skipped while looking for a header and not explained by a CRC error:
        // frames lost or garbled on the line, one report a run.
        let skipped = s.skipped_bytes.saturating_add(s.invalid_frames);
        if skipped != self.mark_skipped {
            if !self.bad_frame && !self.lost_reported {
                sink.record(Record::Lost(at))?;
                self.lost_reported = true;
            }
            self.mark_skipped = skipped;
        }
        Ok(())
    }

    /// Ends the stream; a partial frame is counted as incomplete.
    pub fn finish(&mut self, sink: &mut impl Sink) -> Result<(), Failure> {
        self.parser.finish();
        if self.parser.stats().truncated > 0 {
            sink.record(Record::Lost(Origin::default()))?;
        }
        Ok(())
    }

    /// The counters so far.
    pub fn stats(&self) -> Stats {
        let s = self.parser.stats();
        Stats {
            lines: 0,
            frames: u64::from(s.control_frames) + u64::from(s.postbacks) + u64::from(s.crc_errors),
            messages: self.messages,
            crc_errors: s.crc_errors.into(),
            incomplete: s.truncated.into(),
            malformed_lines: self.undecodable,
            foreign_frames: 0,
        }
    }
}

// ---------------------------------------------------------------------------------------
// Reading the input

/// Calls `f` with each line of `input` (without the newline), in constant memory: lines
/// that fit in one read are passed in place; a line longer than [`MAX_LINE`] is passed as
/// `None`. `block_done` is called after the lines of each block read are passed, before
/// the next read. Both get `state`, so that both can change it.
pub fn for_each_line<R: BufRead, S>(
    mut input: R,
    state: &mut S,
    mut f: impl FnMut(&mut S, Option<&[u8]>) -> Result<(), Failure>,
    mut block_done: impl FnMut(&mut S) -> Result<(), Failure>,
) -> Result<(), Failure> {
    let mut carry: Vec<u8> = Vec::with_capacity(MAX_LINE);
    let mut overlong = false;
    loop {
        let block = match input.fill_buf() {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(Failure::io("cannot read input", e)),
        };
        if block.is_empty() {
            if overlong {
                f(state, None)?;
            } else if !carry.is_empty() {
                f(state, Some(&carry))?;
            }
            return Ok(());
        }
        let mut consumed = 0;
        let mut rest = block;
        while let Some(nl) = memchr::memchr(b'\n', rest) {
            let line = &rest[..nl];
            if overlong {
                f(state, None)?;
            } else if carry.is_empty() {
                if line.len() > MAX_LINE {
                    f(state, None)?;
                } else {
                    f(state, Some(line))?;
                }
            } else if carry.len() + line.len() > MAX_LINE {
                f(state, None)?;
            } else {
                carry.extend_from_slice(line);
                f(state, Some(&carry))?;
            }
            carry.clear();
            overlong = false;
            consumed += nl + 1;
            rest = &rest[nl + 1..];
        }
        // A partial line at the end of the block.
        if !overlong {
            if carry.len() + rest.len() > MAX_LINE {
                overlong = true;
                carry.clear();
            } else {
                carry.extend_from_slice(rest);
            }
        }
        consumed += rest.len();
        input.consume(consumed);
        block_done(state)?;
    }
}

/// A reader that notes whether its last read returned less than was asked for: on a pipe
/// or a terminal, the writer has nothing more for now (the next read may block), so what
/// was decoded so far should be handed over.
struct NoteShortReads<R> {
    inner: R,
    short: std::rc::Rc<std::cell::Cell<bool>>,
}

impl<R: Read> Read for NoteShortReads<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.short.set(n < buf.len());
        Ok(n)
    }
}

/// An input that can be asked whether a read would block now.
#[derive(Clone, Copy)]
struct Poll {
    #[cfg(unix)]
    fd: std::os::fd::RawFd,
}

impl Poll {
    /// Whether a read would block now: true only for a pipe, terminal or socket with
    /// nothing waiting (a regular file is always ready).
    fn would_block(self) -> bool {
        #[cfg(unix)]
        {
            let mut p = libc::pollfd {
                fd: self.fd,
                events: libc::POLLIN,
                revents: 0,
            };
            // SAFETY: one valid pollfd, timeout 0: poll only reads and writes `p`.
            let ready = unsafe { libc::poll(&mut p, 1, 0) };
            ready == 0
        }
        #[cfg(not(unix))]
        {
            false
        }
    }
}

/// A log or capture to decode: a file, or stdin.
pub struct Input {
    reader: Box<dyn Read>,
    poll: Poll,
}

/// Opens `file`, or stdin when it is absent or `-`.
pub fn open(file: Option<&str>) -> Result<Input, Failure> {
    #[cfg(unix)]
    use std::os::fd::AsRawFd;
    match file {
        None | Some("-") => {
            let stdin = std::io::stdin();
            let poll = Poll {
                #[cfg(unix)]
                fd: stdin.as_raw_fd(),
            };
            Ok(Input {
                reader: Box::new(stdin.lock()),
                poll,
            })
        }
        Some(path) => {
            let f = std::fs::File::open(path)
                .map_err(|e| Failure::io(format!("cannot open {path}"), e))?;
            let poll = Poll {
                #[cfg(unix)]
                fd: f.as_raw_fd(),
            };
            Ok(Input {
                reader: Box::new(f),
                poll,
            })
        }
    }
}

/// Decodes all of `input`, a CAN log or with `stream` a serial/TCP capture, into `sink`,
/// and returns the counters. The sink is told whenever the input pauses: a read returned
/// less than a full block, or a full one but the next would block.
pub fn decode_into(input: Input, stream: bool, sink: &mut impl Sink) -> Result<Stats, Failure> {
    let Input { reader, poll } = input;
    if stream {
        let mut reader = reader;
        let mut dec = StreamDecoder::default();
        let mut block = vec![0u8; READ_BLOCK];
        loop {
            let n = match reader.read(&mut block) {
                Ok(0) => break,
                Ok(n) => n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(Failure::io("cannot read input", e)),
            };
            dec.bytes(&block[..n], sink)?;
            if n < block.len() || poll.would_block() {
                sink.input_paused()?;
            }
        }
        dec.finish(sink)?;
        Ok(dec.stats())
    } else {
        let short = std::rc::Rc::new(std::cell::Cell::new(false));
        let reader = NoteShortReads {
            inner: reader,
            short: short.clone(),
        };
        let reader = std::io::BufReader::with_capacity(READ_BLOCK, reader);
        let mut dec = LogDecoder::new();
        for_each_line(
            reader,
            &mut (&mut dec, &mut *sink),
            |(dec, sink), line| dec.line(line, *sink),
            |(_, sink)| {
                if short.get() || poll.would_block() {
                    sink.input_paused()
                } else {
                    Ok(())
                }
            },
        )?;
        dec.finish(sink)?;
        Ok(dec.stats())
    }
}

/// `gimbalctl decode [--stream] [--stats] [FILE|-]`.
pub fn run(file: Option<&str>, stream: bool, with_stats: bool) -> Result<(), Failure> {
    let input = open(file)?;
    let stdout = std::io::stdout();
    let mut json = JsonLines::new(stdout.lock());
    let stats = decode_into(input, stream, &mut json)?;
    json.finish(with_stats.then_some(&stats))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each record as a word, to check their order.
    #[derive(Default)]
    struct Words(Vec<&'static str>);

    impl Sink for Words {
        fn record(&mut self, record: Record<'_>) -> Result<(), Failure> {
            self.0.push(match record {
                Record::Frame(_) => "frame",
                Record::Postback(..) => "postback",
                Record::Command(..) => "command",
                Record::Vehicle(..) => "vehicle",
                Record::Text(..) => "text",
                Record::CrcError(_) => "crc",
                Record::Lost(_) => "lost",
            });
            Ok(())
        }
    }

    /// A line's frame comes first, then the faults it revealed, then its message. Lost
    /// frames are reported where each is seen, while the stats count the messages they
    /// belonged to.
    #[test]
    fn records_come_in_log_order_with_their_faults() {
        let frames = Postback::default().to_can_frames();
        let line = |f: &[u8; 8]| {
            let hex: String = f.iter().map(|b| format!("{b:02X}")).collect();
            format!("{:08X}#{hex}", ids::POSTBACK)
        };
        let mut bad = frames;
        bad[1][3] ^= 0x10;
        let mut log: Vec<String> = frames.iter().map(line).collect();
        // Its header lost: three orphans.
        log.extend(frames[1..].iter().map(line));
        log.extend(bad.iter().map(line));
        log.extend(frames.iter().map(line));
        // Cut short by the end of the log.
        log.extend(frames[..2].iter().map(line));
        let mut dec = LogDecoder::new();
        let mut words = Words::default();
        for l in &log {
            dec.line(Some(l.as_bytes()), &mut words).unwrap();
        }
        dec.finish(&mut words).unwrap();
        let four = ["frame"; 4];
        let mut want: Vec<&str> = four.to_vec();
        want.push("postback");
        want.extend(["frame", "lost"].repeat(3));
        want.extend(four);
        want.push("crc");
        want.extend(four);
        want.push("postback");
        want.extend(["frame", "frame", "lost"]);
        assert_eq!(words.0, want);
        let s = dec.stats();
        assert_eq!(
            (s.lines, s.frames, s.messages, s.crc_errors, s.incomplete),
            (17, 17, 2, 1, 2)
        );
    }

    /// `would_block` on a pipe: true while empty, false once a byte waits, true again once
    /// it is read; a regular file is always ready.
    #[cfg(unix)]
    #[test]
    fn would_block_on_pipes_not_files() {
        use std::io::Write;
        use std::os::fd::{AsRawFd, FromRawFd};
        let mut fds = [0; 2];
        // SAFETY: a valid array of two descriptors for pipe(2) to fill.
        assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0);
        // SAFETY: both descriptors are new and owned here.
        let (mut r, mut w) = unsafe {
            (
                std::fs::File::from_raw_fd(fds[0]),
                std::fs::File::from_raw_fd(fds[1]),
            )
        };
        let poll = Poll { fd: r.as_raw_fd() };
        assert!(poll.would_block());
        w.write_all(b"x").unwrap();
        assert!(!poll.would_block());
        let mut b = [0u8; 1];
        r.read_exact(&mut b).unwrap();
        assert!(poll.would_block());
        let file = std::fs::File::open(concat!(env!("CARGO_MANIFEST_DIR"), "/Cargo.toml")).unwrap();
        assert!(!Poll {
            fd: file.as_raw_fd()
        }
        .would_block());
    }

    #[test]
    fn long_lines_do_not_grow_memory() {
        let mut input = Vec::new();
        input.extend_from_slice(b"00000F01#0F07000000000000\n");
        input.extend(std::iter::repeat_n(b'x', MAX_LINE * 3));
        input.extend_from_slice(b"\n00000F01#0F07000000000000");
        let reader = std::io::BufReader::with_capacity(64, &input[..]);
        let mut seen = Vec::new();
        for_each_line(
            reader,
            &mut seen,
            |seen, l| {
                seen.push(l.map(|l| l.to_vec()));
                Ok(())
            },
            |_| Ok(()),
        )
        .unwrap();
        assert_eq!(seen.len(), 3);
        assert_eq!(seen[0].as_deref(), Some(&b"00000F01#0F07000000000000"[..]));
        assert_eq!(seen[1], None);
        assert_eq!(seen[2].as_deref(), Some(&b"00000F01#0F07000000000000"[..]));
    }
}
