//! The four panels drawn from a [`Trace`], as SVG.

use plotters::prelude::*;

use super::{
    Series, Trace, C_CMD, C_CMD_PITCH_RATE, C_CMD_YAW_RATE, C_CRC, C_GAP, C_HEADING, C_LOST,
    C_MODE, C_MOTOR, C_PITCH, C_PITCH_RATE, C_TRACKING, C_VEHICLE, C_YAW_RATE, GAP_S, HEIGHT,
    WIDTH,
};
use crate::error::Failure;

/// A y range around the series' values, with a margin, and `fallback` when all are empty.
fn y_range(series: &[&Series], fallback: (f64, f64)) -> std::ops::Range<f64> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for s in series {
        if let Some((a, b)) = s.range() {
            lo = lo.min(a);
            hi = hi.max(b);
        }
    }
    if !lo.is_finite() {
        (lo, hi) = fallback;
    }
    let pad = ((hi - lo) * 0.08).max(1.0);
    (lo - pad)..(hi + pad)
}

fn draw_err(e: impl std::fmt::Display) -> Failure {
    Failure::Runtime(format!("cannot draw the plot: {e}"))
}

type Chart<'a, 'b> = ChartContext<
    'a,
    SVGBackend<'b>,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

fn line<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    s: &Series,
    color: RGBColor,
    label: &str,
) -> Result<(), Failure> {
    if s.is_empty() {
        return Ok(());
    }
    chart
        .draw_series(LineSeries::new(s.points(), color.stroke_width(2)))
        .map_err(draw_err)?
        .label(label)
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
    Ok(())
}

fn crosses<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    s: &Series,
    color: RGBColor,
    label: &str,
) -> Result<(), Failure> {
    if s.is_empty() {
        return Ok(());
    }
    chart
        .draw_series(
            s.points()
                .into_iter()
                .map(|p| Cross::new(p, 5, color.stroke_width(2))),
        )
        .map_err(draw_err)?
        .label(label)
        .legend(move |(x, y)| Cross::new((x + 10, y), 5, color.stroke_width(2)));
    Ok(())
}

fn legend<'a, 'b: 'a>(chart: &mut Chart<'a, 'b>) -> Result<(), Failure> {
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(draw_err)
}

fn build<'a, 'b: 'a>(
    area: &'a DrawingArea<SVGBackend<'b>, plotters::coord::Shift>,
    x: std::ops::Range<f64>,
    y: std::ops::Range<f64>,
    caption: &str,
) -> Result<Chart<'a, 'b>, Failure> {
    ChartBuilder::on(area)
        .caption(caption, ("sans-serif", 15))
        .margin(6)
        .margin_right(16)
        .x_label_area_size(32)
        .y_label_area_size(100)
        .build_cartesian_2d(x, y)
        .map_err(draw_err)
}

/// Draws the picture as SVG text.
pub fn render(trace: &Trace, title: &str) -> Result<String, Failure> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        let root = root.titled(title, ("sans-serif", 20)).map_err(draw_err)?;
        let h = root.dim_in_pixel().1 as i32;
        let (a, rest) = root.split_vertically(h * 28 / 100);
        let (b, rest) = rest.split_vertically(h * 28 / 100);
        let (c, d) = rest.split_vertically(h * 22 / 100);
        let x_end = if trace.end > 0.0 { trace.end } else { 1.0 };
        let x = 0.0..x_end;
        let x_desc = if trace.timed {
            "time (s from the first timestamp)"
        } else {
            "time (s, estimated: no timestamps in the log, 0.5 s per postback)"
        };
        // 1. Pitch.
        let mut chart = build(
            &a,
            x.clone(),
            y_range(&[&trace.pitch, &trace.cmd_pitch], (-90.0, 30.0)),
            "pitch (deg)",
        )?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc("deg")
            .draw()
            .map_err(draw_err)?;
        line(&mut chart, &trace.pitch, C_PITCH, "pitch (reported)")?;
        crosses(&mut chart, &trace.cmd_pitch, C_CMD, "pitch (commanded)")?;
        legend(&mut chart)?;

        // 2. Heading.
        let mut chart = build(
            &b,
            x.clone(),
            y_range(
                &[
                    &trace.heading,
                    &trace.motor,
                    &trace.cmd_heading,
                    &trace.vehicle_heading,
                ],
                (0.0, 360.0),
            ),
            "heading (deg)",
        )?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc("deg")
            .draw()
            .map_err(draw_err)?;
        line(&mut chart, &trace.heading, C_HEADING, "heading (reported)")?;
        line(
            &mut chart,
            &trace.motor,
            C_MOTOR,
            "motor heading (reported)",
        )?;
        line(
            &mut chart,
            &trace.vehicle_heading,
            C_VEHICLE,
            "vehicle heading (attitude)",
        )?;
        crosses(&mut chart, &trace.cmd_heading, C_CMD, "heading (commanded)")?;
        legend(&mut chart)?;

        // 3. Rates.
        let mut chart = build(
            &c,
            x.clone(),
            y_range(
                &[
                    &trace.cmd_yaw_rate,
                    &trace.cmd_pitch_rate,
                    &trace.yaw_rate,
                    &trace.pitch_rate,
                ],
                (-10.0, 10.0),
            ),
            "rates (deg/s)",
        )?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc("deg/s")
            .draw()
            .map_err(draw_err)?;
        line(
            &mut chart,
            &trace.yaw_rate,
            C_YAW_RATE,
            "yaw rate (from postbacks)",
        )?;
        line(
            &mut chart,
            &trace.pitch_rate,
            C_PITCH_RATE,
            "pitch rate (from postbacks)",
        )?;
        line(
            &mut chart,
            &trace.cmd_yaw_rate,
            C_CMD_YAW_RATE,
            "yaw rate (commanded)",
        )?;
        line(
            &mut chart,
            &trace.cmd_pitch_rate,
            C_CMD_PITCH_RATE,
            "pitch rate (commanded)",
        )?;
        legend(&mut chart)?;

        // 4. Status: mode, tracking, faults.
        let mut chart = build(&d, x.clone(), -0.5..3.5, "mode, tracking, faults")?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_labels(4)
            .y_label_formatter(&|v| match v.round() as i64 {
                0 => "tracking".into(),
                1 => "full_lock".into(),
                2 => "heading_follow".into(),
                3 => "lock".into(),
                _ => String::new(),
            })
            .disable_y_mesh()
            .draw()
            .map_err(draw_err)?;
        chart
            .draw_series(trace.gaps.iter().map(|&(from, to)| {
                Rectangle::new([(from, -0.5), (to, 3.5)], C_GAP.mix(0.6).filled())
            }))
            .map_err(draw_err)?
            .label(format!("link gap > {GAP_S} s"))
            .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 20, y + 5)], C_GAP.filled()));
        // Tracking: a band over the spans where it is on.
        let spans = tracking_spans(&trace.tracking, trace.end);
        chart
            .draw_series(
                spans.iter().map(|&(from, to)| {
                    Rectangle::new([(from, -0.3), (to, 0.3)], C_TRACKING.filled())
                }),
            )
            .map_err(draw_err)?
            .label("tracking")
            .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 20, y + 5)], C_TRACKING.filled()));
        // Mode: a step line.
        let mode = trace.mode.points();
        let mut steps = Vec::with_capacity(mode.len() * 2);
        for (i, &(t, v)) in mode.iter().enumerate() {
            if i > 0 {
                steps.push((t, mode[i - 1].1));
            }
            steps.push((t, v));
        }
        if let Some(&(_, v)) = mode.last() {
            steps.push((trace.end, v));
        }
        if !steps.is_empty() {
            chart
                .draw_series(LineSeries::new(steps, C_MODE.stroke_width(3)))
                .map_err(draw_err)?
                .label("control mode")
                .legend(|(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], C_MODE.stroke_width(3))
                });
        }
        for (s, color, label) in [
            (&trace.crc, C_CRC, "CRC error"),
            (&trace.lost, C_LOST, "lost frames"),
        ] {
            if s.is_empty() {
                continue;
            }
            chart
                .draw_series(
                    s.times().into_iter().map(|t| {
                        PathElement::new(vec![(t, -0.5), (t, 3.5)], color.stroke_width(2))
                    }),
                )
                .map_err(draw_err)?
                .label(label)
                .legend(move |(x, y)| {
                    PathElement::new(
                        vec![(x + 10, y - 6), (x + 10, y + 6)],
                        color.stroke_width(2),
                    )
                });
        }
        legend(&mut chart)?;
        root.present().map_err(draw_err)?;
    }
    Ok(svg)
}

/// The spans where tracking was on, from the tracking series (1 on, 0 off; decimated, a
/// span may start or end up to one bucket early or late).
fn tracking_spans(s: &Series, end: f64) -> Vec<(f64, f64)> {
    let mut spans = Vec::new();
    let mut start = None;
    for (t, v) in s.points() {
        match (start, v > 0.5) {
            (None, true) => start = Some(t),
            (Some(from), false) => {
                spans.push((from, t));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(from) = start {
        spans.push((from, end));
    }
    spans
}
