//! `gimbalctl plot [--stream] [LOG|-] -o FILE.svg`: one picture of a log.
//!
//! Four panels on one time axis:
//!
//! 1. **pitch**: the reported pitch, and each commanded pitch (`pitch`, `look-down`,
//!    `center`) as a cross at its value;
//! 2. **heading**: the reported heading and motor heading, each commanded heading as a
//!    cross, and the vehicle heading when the log has attitude frames;
//! 3. **rates**: the commanded yaw and pitch rates (a step line, from rate commands) against
//!    the rates the postbacks show (the change of heading and pitch between two postbacks
//!    over the time between them);
//! 4. **status**: the control mode (a step line at full lock, heading follow or lock),
//!    tracking (a band), and the faults on the time axis: link gaps (no postback for more
//!    than 1.5 s; a grey span), CRC errors (red lines) and lost frames (orange lines).
//!
//! The log is decoded by `decode`'s decoders, the trace being one more sink of their
//! records, so the plot shows the postbacks, commands and faults `gimbalctl decode` finds.
//!
//! Time is the log's timestamps, in seconds from the first. A log without timestamps (the
//! `cansend` and screen forms, `--stream` captures) is drawn against estimated time: 0.5 s
//! per postback (the gimbal's period); link gaps cannot be seen in such a log.
//!
//! Memory is bounded whatever the log's length: every series is kept in at most
//! [`BUCKETS`] time buckets holding the first, minimum, maximum and last point of the
//! bucket (with their times); when a series needs more, neighbouring buckets merge in pairs and the bucket
//! width doubles. So a spike survives decimation (it is the max or min of its bucket), and a
//! long log costs the same as a short one. Fault markers are bucketed the same way (one
//! marker per bucket, however many faults fell in it), and at most [`MAX_GAPS`] link gaps
//! are kept (beyond that the closest neighbours merge into one span covering both).
//!
//! Only SVG is written: plotters' PNG path needs its bitmap backend and, for any text, a
//! font from the system (`ttf`, through fontconfig) or one compiled in, which a bare
//! machine does not have.

use std::fmt::Write as _;

use plotters::prelude::*;

use crate::decode;
use crate::error::Failure;

mod draw;
mod series;
mod trace;

pub use draw::render;
pub use series::Series;
pub use trace::Trace;

/// Time buckets per series (each holds its first, min, max and last point: at most four
/// times as many points).
pub const BUCKETS: usize = 1024;
/// Link gaps kept.
pub const MAX_GAPS: usize = 256;
/// A link gap: no postback for longer than this (three missed 500 ms periods).
pub const GAP_S: f64 = 1.5;
/// Estimated time per postback in a log without timestamps.
const UNTIMED_PERIOD_S: f64 = 0.5;

/// The picture's size in pixels.
const WIDTH: u32 = 1280;
const HEIGHT: u32 = 1000;

// Series colours: the structure test finds series by them.
/// Reported pitch.
pub const C_PITCH: RGBColor = RGBColor(0x1F, 0x77, 0xB4);
/// Reported heading.
pub const C_HEADING: RGBColor = RGBColor(0x2C, 0xA0, 0x2C);
/// Reported motor heading.
pub const C_MOTOR: RGBColor = RGBColor(0x94, 0x67, 0xBD);
/// Vehicle heading (attitude frames).
pub const C_VEHICLE: RGBColor = RGBColor(0x8C, 0x56, 0x4B);
/// Commanded angles (crosses) and commanded rates (step lines).
pub const C_CMD: RGBColor = RGBColor(0x00, 0x00, 0x00);
/// Commanded pitch rate.
pub const C_CMD_PITCH_RATE: RGBColor = RGBColor(0x17, 0xBE, 0xCF);
/// Commanded yaw rate.
pub const C_CMD_YAW_RATE: RGBColor = RGBColor(0xBC, 0xBD, 0x22);
/// Reported pitch rate.
pub const C_PITCH_RATE: RGBColor = RGBColor(0x1F, 0x77, 0xB5);
/// Reported yaw rate.
pub const C_YAW_RATE: RGBColor = RGBColor(0x2C, 0xA0, 0x2D);
/// Control mode.
pub const C_MODE: RGBColor = RGBColor(0x7F, 0x7F, 0x7F);
/// Tracking band.
pub const C_TRACKING: RGBColor = RGBColor(0xFF, 0xBB, 0x78);
/// Link gap spans.
pub const C_GAP: RGBColor = RGBColor(0xC7, 0xC7, 0xC7);
/// CRC error markers.
pub const C_CRC: RGBColor = RGBColor(0xD6, 0x27, 0x28);
/// Lost frame markers.
pub const C_LOST: RGBColor = RGBColor(0xFF, 0x7F, 0x0E);

/// What `-o` names, checked before any input is read.
fn check_output(path: &str) -> Result<(), Failure> {
    let ext = std::path::Path::new(path)
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("svg") => Ok(()),
        Some("png") => Err(Failure::Usage(format!(
            "-o {path}: PNG is not supported (it needs system fonts to draw text); valid extensions: .svg"
        ))),
        _ => Err(Failure::Usage(format!(
            "-o {path}: unknown picture format; valid extensions: .svg"
        ))),
    }
}

/// `gimbalctl plot [--stream] [LOG|-] -o FILE.svg`.
pub fn run(file: Option<&str>, stream: bool, output: &str) -> Result<(), Failure> {
    check_output(output)?;
    let input = decode::open(file)?;
    let mut trace = Trace::default();
    decode::decode_into(input, stream, &mut trace)?;
    trace.finish();
    if trace.postbacks == 0 && trace.commands == 0 && trace.vehicle_heading.count == 0 {
        return Err(Failure::Runtime(format!(
            "{}: no postback, command or attitude frame: nothing to plot",
            file.unwrap_or("stdin")
        )));
    }
    let name = match file {
        None | Some("-") => "stdin",
        Some(path) => path,
    };
    let svg = render(&trace, &format!("gimbalctl plot: {name}"))?;
    std::fs::write(output, svg.as_bytes())
        .map_err(|e| Failure::Runtime(format!("cannot write {output}: {e}")))?;
    let mut summary = String::new();
    let _ = writeln!(
        summary,
        "{output}: {:.1} s{}, {} postbacks, {} commands, {} attitude frames, {} link gaps, {} CRC errors, {} lost frames",
        trace.end,
        if trace.timed { "" } else { " (estimated)" },
        trace.postbacks,
        trace.commands,
        trace.vehicle_heading.count,
        trace.gaps.len(),
        trace.crc.count,
        trace.lost.count,
    );
    if trace.bad_timestamps > 0 {
        let _ = writeln!(
            summary,
            "{output}: {} lines with a timestamp that is not a finite time, drawn at the time before them",
            trace.bad_timestamps
        );
    }
    crate::print(&summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_and_other_extensions_are_refused() {
        assert!(check_output("a.svg").is_ok());
        assert!(check_output("A.SVG").is_ok());
        let refused = |path: &str| match check_output(path) {
            Err(Failure::Usage(m)) => m,
            other => panic!("{path}: {other:?}"),
        };
        // PNG says why it is not drawn; anything else is unknown.
        for png in ["a.png", "dir/B.PNG"] {
            assert_eq!(
                refused(png),
                format!(
                    "-o {png}: PNG is not supported (it needs system fonts to draw text); \
                     valid extensions: .svg"
                )
            );
        }
        for other in ["a.pdf", "a", "svg", "a.svg.gz"] {
            assert_eq!(
                refused(other),
                format!("-o {other}: unknown picture format; valid extensions: .svg")
            );
        }
    }
}
