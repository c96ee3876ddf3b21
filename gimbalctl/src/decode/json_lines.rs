//! Records as JSON lines: one object a message, appended to a reused buffer that goes to
//! the output in large writes.

use std::io::Write;

use idu_gimbal::wire::control::Command;
use idu_gimbal::wire::postback::Postback;
use idu_gimbal::wire::vehicle::VehicleFrame;

use super::{Record, Sink, Stats};
use crate::error::Failure;
use crate::json::Obj;
use crate::spec;

/// Output is handed to stdout when this much has accumulated.
const FLUSH_AT: usize = 1 << 16;

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
