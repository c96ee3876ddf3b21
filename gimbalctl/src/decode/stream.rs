//! The stream decoder: a serial or TCP byte capture into records, through the library's
//! stream parser.

use idu_gimbal::wire::control::Command;
use idu_gimbal::wire::serial::{StreamItem, StreamParser};

use super::{Origin, Record, Sink, Stats};
use crate::error::Failure;

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
    /// Runs of bytes that held no frame and no CRC error explains, each reported lost.
    lost_runs: u64,
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
                self.lost_runs += 1;
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
            // A frame lost or garbled on the line (a run of bytes that held none, the
            // `Lost` records `plot` counts), and a partial frame at the end.
            incomplete: u64::from(s.truncated) + self.lost_runs,
            malformed_lines: self.undecodable,
            foreign_frames: 0,
        }
    }
}
