//! The CAN log decoder: one line at a time, in any of the three text forms, into records;
//! postbacks through the library's assembler, texts through its text assembler.

use idu_gimbal::link::postback::PostbackAssembler;
use idu_gimbal::link::text::TextAssembler;
use idu_gimbal::wire::control::Command;
use idu_gimbal::wire::ids;
use idu_gimbal::wire::vehicle::VehicleFrame;
use idu_gimbal::Instant;

use super::candump::{parse_line, timestamp_millis, Line};
use super::{Origin, Record, Sink, Stats};
use crate::error::Failure;

/// The longest text message reassembled.
const TEXT_CAPACITY: usize = 4096;

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
