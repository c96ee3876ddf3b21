//! The COMMAND ARGS shared by `encode` and `send`, what they turn into, and the way back
//! (a decoded [`Command`] to its COMMAND name and ARGS) for `decode`.
//!
//! Every value goes through the library's constructors, which check it in physical units
//! and round to the nearest wire unit; a rejected value is a usage error (exit 2) whose
//! message names the argument and its valid range.

use clap::{Subcommand, ValueEnum};
use idu_gimbal::geo::{self, GeoError, Position};
use idu_gimbal::wire::control::{
    Command, DualLightCommand, ElectronicZoom, Focus, GimbalCommand, Heading, ImageOffset,
    ImagePoint, Palette, Photo, Pitch, Rate, TrackingBox, Video, Zoom, ZoomRatio,
};
use idu_gimbal::wire::vehicle::{Altitude, Attitude, Gps, VehicleFrame};
use idu_gimbal::wire::{text, Frame, RangeError};

use crate::error::Failure;
use crate::json;

/// A control or vehicle command as typed on the command line.
#[derive(Subcommand, Debug, Clone)]
#[command(rename_all = "kebab-case")]
pub enum Spec {
    /// Pointing zoom: bring the image point X Y (offsets from the centre, each -10000..=10000) to the centre and zoom in (0F 01)
    PointZoom(XyArgs),
    /// Follow the vehicle's nose (0F 02)
    Follow,
    /// Back to centre (0F 03)
    Center,
    /// Rate control: YAW and PITCH in deg/s, each -100..=100 (repeat about every 50 ms to keep moving) (0F 04)
    Rate(RateArgs),
    /// Start tracking the box centred on X Y (0..=8191) of W x H image units (0..=4080, sent as /16) (0F 05)
    Track(BoxArgs),
    /// Stop tracking (0F 06)
    TrackStop,
    /// One-click down 90 degrees (0F 07)
    LookDown,
    /// Point at heading DEG, 0..=360 (north-referenced while attitude is pushed, else nose-relative) (0F 08 01)
    Heading {
        #[arg(allow_negative_numbers = true)]
        deg: f64,
    },
    /// Point at pitch DEG, -100..=60, positive up (0F 08 02)
    Pitch {
        #[arg(allow_negative_numbers = true)]
        deg: f64,
    },
    /// Set the optical zoom ratio, 1..=35 (0F 08 03)
    ZoomTo {
        #[arg(allow_negative_numbers = true)]
        ratio: f64,
    },
    /// Photo: single, burst N, timelapse S, timer S or stop (N, S 1..=255) (0F 10)
    #[command(subcommand)]
    Photo(PhotoSpec),
    /// Video recording: start or stop (0F 11)
    Record { action: RecordAction },
    /// Optical zoom: in, out, stop, reset (1x), double, half (0F 12)
    Zoom { action: ZoomAction },
    /// Focus: plus, minus, stop, auto (0F 13)
    Focus { action: FocusAction },
    /// Focus on the image point X Y, each 0..=8191 (0F 14)
    FocusAt(XyArgs),
    /// Fast calibration (0F F0)
    Calibrate,
    /// Dual-light camera pointing zoom, X Y each -10000..=10000 (1F 01)
    IrPointZoom(XyArgs),
    /// Dual-light camera rate control, YAW PITCH in deg/s, each -100..=100 (1F 04)
    IrRate(RateArgs),
    /// Dual-light camera tracking: centre X Y (0..=8191), box W H (0..=4080) (1F 05)
    IrTrack(BoxArgs),
    /// Dual-light camera: stop tracking (1F 07)
    IrTrackStop,
    /// Dual-light camera electronic zoom: in, out, stop (1F 12)
    IrZoom { action: IrZoomAction },
    /// Thermal palette: 0..=14 or black-hot, white-hot, iron-red, rainbow, lava, rainbow-enhanced, molten-metal, bluish-red, amber, amber-inverted, ice-blue, high-contrast, grayscale-inverted, hot-red, cold-blue (1F 02)
    Palette {
        #[arg(allow_hyphen_values = true, value_parser = parse_palette)]
        palette: Palette,
    },
    /// Vehicle GPS position: LAT -90..=90, LON -180..=180 degrees (0000FF15)
    Gps {
        #[arg(allow_negative_numbers = true)]
        lat: f64,
        #[arg(allow_negative_numbers = true)]
        lon: f64,
    },
    /// Vehicle altitude in METRES (0000FF16)
    Altitude {
        #[arg(allow_negative_numbers = true)]
        metres: f64,
    },
    /// Vehicle attitude: PITCH -90..=90, ROLL -180..=180, HEADING (any, sent in [-180, 180)) degrees (0000FF13)
    Attitude {
        #[arg(allow_negative_numbers = true)]
        pitch: f64,
        #[arg(allow_negative_numbers = true)]
        roll: f64,
        #[arg(allow_negative_numbers = true)]
        heading: f64,
    },
    /// ASCII text to the gimbal, 8 bytes a frame (02008201 ... 02008202)
    Text {
        #[arg(allow_hyphen_values = true)]
        text: String,
    },
    /// Aim at a target: heading (north-referenced bearing) then pitch (elevation) frames. Positions are degrees and metres (WGS84)
    LookAt {
        #[arg(allow_negative_numbers = true)]
        veh_lat: f64,
        #[arg(allow_negative_numbers = true)]
        veh_lon: f64,
        #[arg(allow_negative_numbers = true)]
        veh_alt: f64,
        #[arg(allow_negative_numbers = true)]
        tgt_lat: f64,
        #[arg(allow_negative_numbers = true)]
        tgt_lon: f64,
        #[arg(allow_negative_numbers = true)]
        tgt_alt: f64,
    },
}

/// `photo MODE [N|S]`.
#[derive(Subcommand, Debug, Clone, Copy)]
pub enum PhotoSpec {
    /// Take one picture
    Single,
    /// Take N pictures in a row, 1..=255
    Burst {
        #[arg(allow_negative_numbers = true)]
        n: i64,
    },
    /// Time-lapse with a delay of S seconds, 1..=255
    Timelapse {
        #[arg(allow_negative_numbers = true)]
        s: i64,
    },
    /// Take a picture after S seconds, 1..=255
    Timer {
        #[arg(allow_negative_numbers = true)]
        s: i64,
    },
    /// Stop photographing
    Stop,
}

/// `record start|stop`.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum RecordAction {
    Start,
    Stop,
}

/// `zoom in|out|stop|reset|double|half`.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum ZoomAction {
    In,
    Out,
    Stop,
    Reset,
    Double,
    Half,
}

/// `focus plus|minus|stop|auto`.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum FocusAction {
    Plus,
    Minus,
    Stop,
    Auto,
}

/// `ir-zoom in|out|stop`.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum IrZoomAction {
    In,
    Out,
    Stop,
}

/// A palette by code (0..=14) or name.
fn parse_palette(s: &str) -> Result<Palette, String> {
    if let Some(p) = Palette::from_name(s) {
        return Ok(p);
    }
    let names: Vec<&str> = Palette::ALL.iter().map(|p| p.name()).collect();
    match s.parse::<i64>() {
        Ok(n) => u8::try_from(n)
            .ok()
            .and_then(Palette::from_code)
            .ok_or_else(|| format!("palette = {n} is out of range [0, 14]")),
        Err(_) => Err(format!(
            "unknown palette; valid: 0..=14 or {}",
            names.join(", ")
        )),
    }
}

/// What a [`Spec`] becomes on the wire.
#[derive(Debug, Clone)]
pub enum Message {
    /// Control commands (one, or two for `look-at`), each one frame on 0x00000F01.
    Control(Vec<Command>),
    /// A vehicle frame.
    Vehicle(VehicleFrame),
    /// The frames of a text.
    Text(Vec<Frame>),
}

impl Message {
    /// The CAN frames, in order.
    pub fn frames(&self) -> Vec<Frame> {
        match self {
            Message::Control(cmds) => cmds.iter().map(Command::to_frame).collect(),
            Message::Vehicle(v) => vec![v.to_frame()],
            Message::Text(frames) => frames.clone(),
        }
    }
}

/// A number for an error message: plain, or in exponent form when it is very large or
/// very small (`1e300` rather than 301 digits).
fn num(v: f64) -> String {
    let a = v.abs();
    if v.is_finite() && v != 0.0 && !(1e-6..1e15).contains(&a) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// A rejected value: names the argument and its valid range.
fn range_message(e: &RangeError) -> String {
    if e.value.is_finite() {
        format!(
            "{} = {} is out of range [{}, {}]",
            e.field,
            num(e.value),
            num(e.min),
            num(e.max)
        )
    } else {
        format!(
            "{} must be a finite number in [{}, {}], got {}",
            e.field,
            num(e.min),
            num(e.max),
            e.value
        )
    }
}

fn range(cmd: &str, e: RangeError) -> Failure {
    Failure::Usage(format!("{cmd}: {}", range_message(&e)))
}

/// A float argument as the library's single-precision constructors take it. A finite value
/// too large for `f32` is out of range anyway; the error then reports the value as typed.
fn f32_arg<T>(value: f64, make: impl Fn(f32) -> Result<T, RangeError>) -> Result<T, RangeError> {
    let narrowed = if value.is_finite() {
        value.clamp(f64::from(f32::MIN), f64::from(f32::MAX)) as f32
    } else {
        value as f32
    };
    make(narrowed).map_err(|e| RangeError {
        value: if e.value.is_finite() { value } else { e.value },
        ..e
    })
}

/// An integer argument as the library's `i32` constructors take it (values beyond `i32`
/// are out of range; the error then reports the value as typed).
fn i32_arg<T>(value: i64, make: impl Fn(i32) -> Result<T, RangeError>) -> Result<T, RangeError> {
    let narrowed = value.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32;
    make(narrowed).map_err(|e| RangeError {
        value: value as f64,
        ..e
    })
}

/// A count or seconds argument for the photo constructors (`u32`).
fn u32_arg<T>(value: i64, make: impl Fn(u32) -> Result<T, RangeError>) -> Result<T, RangeError> {
    let narrowed = value.clamp(0, i64::from(u32::MAX)) as u32;
    make(narrowed).map_err(|e| RangeError {
        value: value as f64,
        ..e
    })
}

/// X Y as typed: an image offset or point, checked by the command's constructor.
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct XyArgs {
    #[arg(allow_negative_numbers = true)]
    x: i64,
    #[arg(allow_negative_numbers = true)]
    y: i64,
}

impl XyArgs {
    fn offset(self) -> Result<ImageOffset, RangeError> {
        // Check each axis on its own so the error names the right one.
        i32_arg(self.x, |x| ImageOffset::new(x, 0))?;
        i32_arg(self.y, |y| ImageOffset::new(0, y))?;
        ImageOffset::new(self.x as i32, self.y as i32)
    }

    fn point(self) -> Result<ImagePoint, RangeError> {
        i32_arg(self.x, |x| ImagePoint::new(x, 0))?;
        i32_arg(self.y, |y| ImagePoint::new(0, y))?;
        ImagePoint::new(self.x as i32, self.y as i32)
    }
}

/// YAW PITCH in deg/s as typed.
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct RateArgs {
    #[arg(allow_negative_numbers = true)]
    yaw: f64,
    #[arg(allow_negative_numbers = true)]
    pitch: f64,
}

impl RateArgs {
    fn rate(self) -> Result<Rate, RangeError> {
        f32_arg(self.yaw, |y| Rate::new(y, 0.0))?;
        f32_arg(self.pitch, |p| Rate::new(0.0, p))?;
        Rate::new(self.yaw as f32, self.pitch as f32)
    }
}

/// X Y W H as typed: a tracking box's centre (an image point) and size.
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct BoxArgs {
    #[command(flatten)]
    centre: XyArgs,
    #[arg(allow_negative_numbers = true)]
    w: f64,
    #[arg(allow_negative_numbers = true)]
    h: f64,
}

impl BoxArgs {
    fn tracking_box(self) -> Result<TrackingBox, RangeError> {
        let centre = self.centre.point()?;
        f32_arg(self.w, |w| TrackingBox::new(centre, w, 0.0))?;
        f32_arg(self.h, |h| TrackingBox::new(centre, 0.0, h))?;
        TrackingBox::new(centre, self.w as f32, self.h as f32)
    }
}

/// The pitch range a look-at target must be within, degrees.
const LOOK_AT_PITCH: (f64, f64) = (-100.0, 60.0);

fn position(who: &str, lat: f64, lon: f64, alt: f64) -> Result<Position, Failure> {
    Position::new(lat, lon, alt).map_err(|e| match e {
        GeoError::Range(r) => Failure::Usage(format!("look-at: {who} {}", range_message(&r))),
        other => Failure::Usage(format!("look-at: {other}")),
    })
}

/// The heading and pitch commands that aim at `target` from `vehicle`.
fn look_at(veh: (f64, f64, f64), tgt: (f64, f64, f64)) -> Result<Vec<Command>, Failure> {
    let vehicle = position("vehicle", veh.0, veh.1, veh.2)?;
    let target = position("target", tgt.0, tgt.1, tgt.2)?;
    let look =
        geo::look_at(&vehicle, &target).map_err(|e| Failure::Usage(format!("look-at: {e}")))?;
    let (min, max) = LOOK_AT_PITCH;
    if !(min..=max).contains(&look.elevation_deg) {
        return Err(Failure::Usage(format!(
            "look-at: the target is at elevation {:.2} deg, outside the gimbal's pitch range [{min}, {max}]",
            look.elevation_deg
        )));
    }
    // The bearing is in [0, 360) and the elevation in the pitch range: both constructors
    // accept them (single-precision rounding of a bearing just under 360 gives 360, which
    // is still valid).
    let heading = Heading::new(look.bearing_deg as f32).map_err(|e| range("look-at", e))?;
    let pitch = Pitch::new(look.elevation_deg as f32).map_err(|e| range("look-at", e))?;
    Ok(vec![
        GimbalCommand::Heading(heading).into(),
        GimbalCommand::Pitch(pitch).into(),
    ])
}

impl Spec {
    /// The COMMAND name as typed.
    pub fn name(&self) -> &'static str {
        match self {
            Spec::PointZoom(_) => "point-zoom",
            Spec::Follow => "follow",
            Spec::Center => "center",
            Spec::Rate(_) => "rate",
            Spec::Track(_) => "track",
            Spec::TrackStop => "track-stop",
            Spec::LookDown => "look-down",
            Spec::Heading { .. } => "heading",
            Spec::Pitch { .. } => "pitch",
            Spec::ZoomTo { .. } => "zoom-to",
            Spec::Photo(_) => "photo",
            Spec::Record { .. } => "record",
            Spec::Zoom { .. } => "zoom",
            Spec::Focus { .. } => "focus",
            Spec::FocusAt(_) => "focus-at",
            Spec::Calibrate => "calibrate",
            Spec::IrPointZoom(_) => "ir-point-zoom",
            Spec::IrRate(_) => "ir-rate",
            Spec::IrTrack(_) => "ir-track",
            Spec::IrTrackStop => "ir-track-stop",
            Spec::IrZoom { .. } => "ir-zoom",
            Spec::Palette { .. } => "palette",
            Spec::Gps { .. } => "gps",
            Spec::Altitude { .. } => "altitude",
            Spec::Attitude { .. } => "attitude",
            Spec::Text { .. } => "text",
            Spec::LookAt { .. } => "look-at",
        }
    }

    /// Checks the values and builds the message.
    pub fn build(&self) -> Result<Message, Failure> {
        use DualLightCommand as D;
        use GimbalCommand as G;
        let name = self.name();
        let r = |e| range(name, e);
        let g = |c: G| Ok(Message::Control(vec![c.into()]));
        let d = |c: D| Ok(Message::Control(vec![c.into()]));
        match *self {
            Spec::PointZoom(a) => g(G::PointingZoom(a.offset().map_err(r)?)),
            Spec::Follow => g(G::NoseFollowing),
            Spec::Center => g(G::Recenter),
            Spec::Rate(a) => g(G::Rate(a.rate().map_err(r)?)),
            Spec::Track(a) => g(G::StartTracking(a.tracking_box().map_err(r)?)),
            Spec::TrackStop => g(G::StopTracking),
            Spec::LookDown => g(G::LookDown),
            Spec::Heading { deg } => g(G::Heading(f32_arg(deg, Heading::new).map_err(r)?)),
            Spec::Pitch { deg } => g(G::Pitch(f32_arg(deg, Pitch::new).map_err(r)?)),
            Spec::ZoomTo { ratio } => g(G::ZoomRatio(f32_arg(ratio, ZoomRatio::new).map_err(r)?)),
            Spec::Photo(p) => g(G::Photo(match p {
                PhotoSpec::Single => Photo::Single,
                PhotoSpec::Burst { n } => u32_arg(n, Photo::burst).map_err(r)?,
                PhotoSpec::Timelapse { s } => u32_arg(s, Photo::time_lapse).map_err(r)?,
                PhotoSpec::Timer { s } => u32_arg(s, Photo::timer).map_err(r)?,
                PhotoSpec::Stop => Photo::Stop,
            })),
            Spec::Record { action } => g(G::Video(match action {
                RecordAction::Start => Video::Start,
                RecordAction::Stop => Video::Stop,
            })),
            Spec::Zoom { action } => g(G::Zoom(match action {
                ZoomAction::In => Zoom::In,
                ZoomAction::Out => Zoom::Out,
                ZoomAction::Stop => Zoom::Stop,
                ZoomAction::Reset => Zoom::Reset,
                ZoomAction::Double => Zoom::Double,
                ZoomAction::Half => Zoom::Half,
            })),
            Spec::Focus { action } => g(G::Focus(match action {
                FocusAction::Plus => Focus::Plus,
                FocusAction::Minus => Focus::Minus,
                FocusAction::Stop => Focus::Stop,
                FocusAction::Auto => Focus::Auto,
            })),
            Spec::FocusAt(a) => g(G::PointingFocus(a.point().map_err(r)?)),
            Spec::Calibrate => g(G::FastCalibration),
            Spec::IrPointZoom(a) => d(D::PointingZoom(a.offset().map_err(r)?)),
            Spec::IrRate(a) => d(D::Rate(a.rate().map_err(r)?)),
            Spec::IrTrack(a) => d(D::StartTracking(a.tracking_box().map_err(r)?)),
            Spec::IrTrackStop => d(D::StopTracking),
            Spec::IrZoom { action } => d(D::ElectronicZoom(match action {
                IrZoomAction::In => ElectronicZoom::In,
                IrZoomAction::Out => ElectronicZoom::Out,
                IrZoomAction::Stop => ElectronicZoom::Stop,
            })),
            Spec::Palette { palette } => d(D::Palette(palette)),
            Spec::Gps { lat, lon } => Ok(Message::Vehicle(Gps::new(lat, lon).map_err(r)?.into())),
            Spec::Altitude { metres } => {
                Ok(Message::Vehicle(Altitude::new(metres).map_err(r)?.into()))
            }
            Spec::Attitude {
                pitch,
                roll,
                heading,
            } => {
                f32_arg(pitch, |p| Attitude::new(p, 0.0, 0.0)).map_err(r)?;
                f32_arg(roll, |ro| Attitude::new(0.0, ro, 0.0)).map_err(r)?;
                // Any heading: whole turns taken off as typed (in f64), before the f32 the
                // library takes would round a large one to another angle. Not finite: the
                // library's error, below (the value as typed: NaN or infinite alike).
                let heading = if heading.is_finite() {
                    heading.rem_euclid(360.0)
                } else {
                    heading
                };
                let att = Attitude::new(pitch as f32, roll as f32, heading as f32).map_err(r)?;
                Ok(Message::Vehicle(att.into()))
            }
            Spec::Text { ref text } => {
                let frames = text::chunks(text.as_bytes())
                    .map_err(|e| Failure::Usage(format!("text: {e}")))?;
                Ok(Message::Text(frames.collect()))
            }
            Spec::LookAt {
                veh_lat,
                veh_lon,
                veh_alt,
                tgt_lat,
                tgt_lon,
                tgt_alt,
            } => Ok(Message::Control(look_at(
                (veh_lat, veh_lon, veh_alt),
                (tgt_lat, tgt_lon, tgt_alt),
            )?)),
        }
    }
}

/// One decoded argument.
#[derive(Clone, Copy, Debug)]
enum Arg {
    Int(i64),
    /// `value / 10^decimals`.
    Fixed(i64, u32),
    Str(&'static str),
}

/// Up to four decoded arguments, without allocating.
struct Args {
    items: [Arg; 4],
    len: usize,
}

impl Args {
    fn new() -> Self {
        Args {
            items: [Arg::Int(0); 4],
            len: 0,
        }
    }

    fn push(&mut self, a: Arg) -> &mut Self {
        if let Some(slot) = self.items.get_mut(self.len) {
            *slot = a;
            self.len += 1;
        }
        self
    }

    fn int(&mut self, v: impl Into<i64>) -> &mut Self {
        self.push(Arg::Int(v.into()))
    }

    fn fixed(&mut self, v: impl Into<i64>, decimals: u32) -> &mut Self {
        self.push(Arg::Fixed(v.into(), decimals))
    }

    fn str(&mut self, s: &'static str) -> &mut Self {
        self.push(Arg::Str(s))
    }

    fn offset(&mut self, o: ImageOffset) -> &mut Self {
        self.int(o.x()).int(o.y())
    }

    fn rate(&mut self, r: Rate) -> &mut Self {
        self.fixed(r.yaw_centi(), 2).fixed(r.pitch_centi(), 2)
    }

    fn tracking_box(&mut self, b: TrackingBox) -> &mut Self {
        self.int(b.centre().x())
            .int(b.centre().y())
            .int(b.width())
            .int(b.height())
    }
}

/// The peripheral's name, the encode COMMAND name and its ARGS for a decoded command.
fn describe(cmd: &Command) -> (&'static str, &'static str, Args) {
    use DualLightCommand as D;
    use GimbalCommand as G;
    let mut a = Args::new();
    let (peripheral, name) = match *cmd {
        Command::Gimbal(c) => {
            let name = match c {
                G::PointingZoom(o) => {
                    a.offset(o);
                    "point-zoom"
                }
                G::NoseFollowing => "follow",
                G::Recenter => "center",
                G::Rate(r) => {
                    a.rate(r);
                    "rate"
                }
                G::StartTracking(b) => {
                    a.tracking_box(b);
                    "track"
                }
                G::StopTracking => "track-stop",
                G::LookDown => "look-down",
                G::Heading(h) => {
                    a.fixed(h.deci(), 1);
                    "heading"
                }
                G::Pitch(p) => {
                    a.fixed(p.deci(), 1);
                    "pitch"
                }
                G::ZoomRatio(z) => {
                    a.fixed(z.centi(), 2);
                    "zoom-to"
                }
                G::Photo(p) => {
                    match p {
                        Photo::Single => a.str("single"),
                        Photo::Burst(n) => a.str("burst").int(n.get()),
                        Photo::TimeLapse(s) => a.str("timelapse").int(s.get()),
                        Photo::Timer(s) => a.str("timer").int(s.get()),
                        Photo::Stop => a.str("stop"),
                    };
                    "photo"
                }
                G::Video(v) => {
                    a.str(match v {
                        Video::Start => "start",
                        Video::Stop => "stop",
                    });
                    "record"
                }
                G::Zoom(z) => {
                    a.str(match z {
                        Zoom::In => "in",
                        Zoom::Out => "out",
                        Zoom::Stop => "stop",
                        Zoom::Reset => "reset",
                        Zoom::Double => "double",
                        Zoom::Half => "half",
                    });
                    "zoom"
                }
                G::Focus(f) => {
                    a.str(match f {
                        Focus::Plus => "plus",
                        Focus::Minus => "minus",
                        Focus::Stop => "stop",
                        Focus::Auto => "auto",
                    });
                    "focus"
                }
                G::PointingFocus(p) => {
                    a.int(p.x()).int(p.y());
                    "focus-at"
                }
                G::FastCalibration => "calibrate",
            };
            ("gimbal", name)
        }
        Command::DualLight(c) => {
            let name = match c {
                D::PointingZoom(o) => {
                    a.offset(o);
                    "ir-point-zoom"
                }
                D::Palette(p) => {
                    a.str(p.name());
                    "palette"
                }
                D::Rate(r) => {
                    a.rate(r);
                    "ir-rate"
                }
                D::StartTracking(b) => {
                    a.tracking_box(b);
                    "ir-track"
                }
                D::StopTracking => "ir-track-stop",
                D::ElectronicZoom(z) => {
                    a.str(match z {
                        ElectronicZoom::In => "in",
                        ElectronicZoom::Out => "out",
                        ElectronicZoom::Stop => "stop",
                    });
                    "ir-zoom"
                }
            };
            ("dual_light", name)
        }
    };
    (peripheral, name, a)
}

/// Writes `"peripheral":...,"command":...,"args":[...]` for a decoded command: the encode
/// COMMAND name and its ARGS in physical units, so that `encode X | decode` gives back X.
pub fn write_command_fields(obj: &mut json::Obj<'_>, cmd: &Command) {
    let (peripheral, name, args) = describe(cmd);
    obj.str("peripheral", peripheral).str("command", name);
    let out = obj.raw("args");
    out.push(b'[');
    for (i, a) in args.items.iter().take(args.len).enumerate() {
        if i > 0 {
            out.push(b',');
        }
        match *a {
            Arg::Int(v) => json::push_i64(out, v),
            Arg::Fixed(v, d) => json::push_fixed(out, v, d),
            Arg::Str(s) => json::push_str(out, s),
        }
    }
    out.push(b']');
}

/// The command as `COMMAND ARGS...` text, as `encode` takes it (for readable output).
pub fn command_line(cmd: &Command) -> String {
    let (_, name, args) = describe(cmd);
    let mut line = String::from(name);
    for a in args.items.iter().take(args.len) {
        line.push(' ');
        let mut buf = Vec::new();
        match *a {
            Arg::Int(v) => json::push_i64(&mut buf, v),
            Arg::Fixed(v, d) => json::push_fixed(&mut buf, v, d),
            Arg::Str(s) => buf.extend_from_slice(s.as_bytes()),
        }
        line.push_str(&String::from_utf8_lossy(&buf));
    }
    line
}
