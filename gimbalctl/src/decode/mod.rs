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

use idu_gimbal::wire::control::Command;
use idu_gimbal::wire::postback::Postback;
use idu_gimbal::wire::vehicle::VehicleFrame;

use crate::error::Failure;
use crate::json::Obj;

mod candump;
mod input;
mod json_lines;
mod log;
mod stream;

pub use input::{decode_into, open};
pub use json_lines::{write_command, write_postback, write_vehicle, JsonLines};
pub use log::LogDecoder;
pub use stream::StreamDecoder;

/// The longest line kept; longer lines are malformed (no candump line comes close).
pub const MAX_LINE: usize = 4096;

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
    /// Frames of other devices: other IDs, standard IDs, remote, CAN FD, CAN XL and error
    /// frames.
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

/// `gimbalctl decode [--stream] [--stats] [FILE|-]`.
pub fn run(file: Option<&str>, stream: bool, with_stats: bool) -> Result<(), Failure> {
    let input = open(file)?;
    let stdout = std::io::stdout();
    let mut json = JsonLines::new(stdout.lock());
    let stats = decode_into(input, stream, &mut json)?;
    json.finish(with_stats.then_some(&stats))?;
    // Without the stats line, what could not be decoded is still said.
    let faults = [
        (stats.crc_errors, "CRC error"),
        (stats.incomplete, "incomplete message"),
        (stats.malformed_lines, "malformed line"),
    ];
    if !with_stats && faults.iter().any(|&(n, _)| n != 0) {
        let said: Vec<String> = faults
            .iter()
            .map(|&(n, what)| crate::counts::counted(n, what))
            .collect();
        eprintln!(
            "gimbalctl decode: warning: {} (--stats counts them)",
            said.join(", ")
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use idu_gimbal::wire::ids;

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

    /// A capture that ends inside a frame reports it lost when it is finished; one that
    /// ends on a frame's last byte reports nothing more.
    #[test]
    fn a_capture_ending_mid_frame_reports_it_lost() {
        let bytes = Postback::default().to_stream_bytes();
        for (cut, want) in [
            (bytes.len(), &["postback"][..]),
            (bytes.len() - 1, &["lost"][..]),
            (1, &["lost"][..]),
        ] {
            let mut dec = StreamDecoder::default();
            let mut words = Words::default();
            dec.bytes(&bytes[..cut], &mut words).unwrap();
            dec.finish(&mut words).unwrap();
            assert_eq!(words.0, want, "{cut} bytes");
            assert_eq!(dec.stats().incomplete, u64::from(cut < bytes.len()));
        }
    }
}
