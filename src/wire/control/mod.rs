//! Control commands to the gimbal and the dual-light camera (section 2.1).
//!
//! Every command is one CAN frame on [`ids::CONTROL`] (`0x00000F01`, extended, DLC 8):
//!
//! | byte | 0 | 1 | 2..=7 |
//! |---|---|---|---|
//! | field | peripheral | CMD | DATA1..DATA6 |
//!
//! The peripheral is `0x0F` (gimbal and its camera) or `0x1F` (dual-light thermal camera).
//! The same CMD byte means different things on the two, so the peripheral is part of the
//! type: a [`Command`] is either a [`GimbalCommand`] or a [`DualLightCommand`]. Multi-byte
//! values are little-endian two's complement; bytes a command does not use are `00`.
//!
//! ```
//! use idu_gimbal::wire::control::{Command, GimbalCommand, Pitch, Rate};
//!
//! // The document's "pitch angle: -45" example.
//! let cmd = Command::from(GimbalCommand::Pitch(Pitch::new(-45.0)?));
//! assert_eq!(cmd.encode(), [0x0F, 0x08, 0x02, 0x3E, 0xFE, 0x00, 0x00, 0x00]);
//! assert_eq!(Command::decode(&cmd.encode()), Ok(cmd));
//!
//! // "Left 5 deg/s": negative yaw rate turns left.
//! let left = Command::from(GimbalCommand::Rate(Rate::new(-5.0, 0.0)?));
//! assert_eq!(left.to_frame().data, [0x0F, 0x04, 0x0C, 0xFE, 0, 0, 0, 0]);
//! assert_eq!(left.to_frame().id, 0x0000_0F01);
//! # Ok::<(), idu_gimbal::wire::RangeError>(())
//! ```
//!
//! # Commands
//!
//! | periph. | CMD | variant | DATA1..DATA6 |
//! |---|---|---|---|
//! | `0F` | `01` | [`GimbalCommand::PointingZoom`] | x `i16`, y `i16`, each [−10000, 10000] ([`ImageOffset`]) |
//! | `0F` | `02` | [`GimbalCommand::NoseFollowing`] | — |
//! | `0F` | `03` | [`GimbalCommand::Recenter`] | — |
//! | `0F` | `04` | [`GimbalCommand::Rate`] | yaw, pitch `i16` in (deg/s)×100, each [−10000, 10000] ([`Rate`]) |
//! | `0F` | `05` | [`GimbalCommand::StartTracking`] | centre x, y `u16` [0, 8191]; width/16 `u8`; height/16 `u8` ([`TrackingBox`]) |
//! | `0F` | `06` | [`GimbalCommand::StopTracking`] | — |
//! | `0F` | `07` | [`GimbalCommand::LookDown`] | — |
//! | `0F` | `08` | [`GimbalCommand::Heading`] | `01`; heading deg×10 `u16` [0, 3600] ([`Heading`]) |
//! | `0F` | `08` | [`GimbalCommand::Pitch`] | `02`; pitch deg×10 `i16` [−1000, 600] ([`Pitch`]) |
//! | `0F` | `08` | [`GimbalCommand::ZoomRatio`] | `03`; ratio×100 `u16` [100, 3500] ([`ZoomRatio`]) |
//! | `0F` | `10` | [`GimbalCommand::Photo`] | mode `01` single, `02` burst, `03` time-lapse, `04` timer, `05` stop; count or seconds [1, 255] ([`Photo`]) |
//! | `0F` | `11` | [`GimbalCommand::Video`] | `01` start, `02` stop recording ([`Video`]) |
//! | `0F` | `12` | [`GimbalCommand::Zoom`] | `01` in, `02` out, `03` stop, `04` 1×, `05` 2× in, `06` 2× out ([`Zoom`]) |
//! | `0F` | `13` | [`GimbalCommand::Focus`] | `01` +, `02` −, `03` stop, `04` auto ([`Focus`]) |
//! | `0F` | `14` | [`GimbalCommand::PointingFocus`] | x, y `u16` [0, 8191] ([`ImagePoint`]); `19` `19` (25, 25) |
//! | `0F` | `F0` | [`GimbalCommand::FastCalibration`] | — |
//! | `1F` | `01` | [`DualLightCommand::PointingZoom`] | as gimbal `01` |
//! | `1F` | `02` | [`DualLightCommand::Palette`] | palette `00`..=`0E` ([`Palette`]) |
//! | `1F` | `04` | [`DualLightCommand::Rate`] | as gimbal `04` |
//! | `1F` | `05` | [`DualLightCommand::StartTracking`] | as gimbal `05` |
//! | `1F` | `07` | [`DualLightCommand::StopTracking`] | — (`07`, not `06`, on this peripheral) |
//! | `1F` | `12` | [`DualLightCommand::ElectronicZoom`] | `01` in, `02` out, `03` stop ([`ElectronicZoom`]) |
//!
//! # Conventions and decisions
//!
//! - Signs follow the document's examples: a negative yaw rate turns left, a positive
//!   pitch rate or angle points up. Image coordinates grow rightwards and downwards.
//! - Constructors take physical units, check them (NaN and infinities are rejected) and
//!   round half away from zero to the nearest wire unit, e.g. `Pitch::new(-45.04)` is
//!   −450 deci-degrees. The range check is on the physical value, before rounding:
//!   `Pitch::new(60.04)` is rejected although it would round to 600, the bound.
//! - The zoom ratio accepts [1, 35]: most models stop at 30, some go to 35 (the protocol notes).
//! - Tracking box DATA5 ("length (X)") is the box width, DATA6 ("width (Y)") its height,
//!   each in image units divided by 16.
//! - Decoding is strict, so that decoding then encoding gives back the same bytes: the
//!   length must be 8, unused bytes must be `00`, every value must be in its documented
//!   range and every sub-code known. A zero burst count or time-lapse/timer delay is
//!   invalid, and pointing focus must carry 25, 25 in DATA5/DATA6. When a frame has
//!   several faults, the first of wrong length, unknown peripheral, unknown CMD, invalid
//!   value, non-zero padding is reported.

use core::fmt;

use super::{ids, Frame, RangeError};

mod data;

pub use data::{
    ElectronicZoom, Focus, Heading, ImageOffset, ImagePoint, Palette, Photo, Pitch, Rate,
    TrackingBox, Video, Zoom, ZoomRatio,
};

/// Byte offsets of the control frame's fields, in one place.
mod field {
    use core::ops::Range;

    /// The peripheral code (`0x0F` or `0x1F`).
    pub const PERIPHERAL: usize = 0;
    /// The command code.
    pub const CMD: usize = 1;
    /// DATA1..DATA6. Named for the layout check below, its only use, which Rust 1.87 (the
    /// crate's minimum) does not count as one.
    #[allow(dead_code)]
    pub const DATA: Range<usize> = 2..8;

    /// DATA1-2: image x (pointing zoom, tracking centre, pointing focus) or yaw rate.
    pub const X: Range<usize> = 2..4;
    /// DATA3-4: image y or pitch rate.
    pub const Y: Range<usize> = 4..6;
    /// DATA5: tracking box width/16, or 25 for pointing focus.
    pub const BOX_WIDTH: usize = 6;
    /// DATA6: tracking box height/16, or 25 for pointing focus.
    pub const BOX_HEIGHT: usize = 7;

    /// DATA1: a sub-code (angle type, photo, video, zoom or focus mode, palette).
    pub const MODE: usize = 2;
    /// DATA2: the photo mode's parameter (burst count, delay or timer seconds).
    pub const PARAM: usize = 3;
    /// DATA2-3: the specify-angle value (heading, pitch or zoom ratio).
    pub const ANGLE: Range<usize> = 3..5;
}

/// Every field lies inside the 8-byte frame, so the accessors below never miss.
const _: () = {
    assert!(field::PERIPHERAL < field::CMD && field::CMD < field::DATA.start);
    assert!(field::DATA.end == Command::LEN);
    assert!(field::X.start >= field::DATA.start && field::X.end - field::X.start == 2);
    assert!(field::Y.end <= field::DATA.end && field::Y.end - field::Y.start == 2);
    assert!(field::ANGLE.end <= field::DATA.end && field::ANGLE.end - field::ANGLE.start == 2);
    assert!(field::BOX_WIDTH < field::DATA.end && field::BOX_HEIGHT < field::DATA.end);
    assert!(field::MODE >= field::DATA.start && field::PARAM < field::DATA.end);
};

// The accessors take their field as a constant: every index is checked at compile time
// (the assertions above, and rustc's own bound check of a constant index), so none can miss
// at run time and none needs a fallback.

/// A two-byte field's bytes (its start and end, `Range`'s fields, as constants).
macro_rules! get_2 {
    ($data:expr, $field:expr) => {
        [$data[$field.start], $data[$field.end - 1]]
    };
}

/// Writes a two-byte field.
macro_rules! put_2 {
    ($buf:expr, $field:expr, $bytes:expr) => {{
        let [lo, hi] = $bytes;
        $buf[$field.start] = lo;
        $buf[$field.end - 1] = hi;
    }};
}

/// Which device a control frame is addressed to (byte 0).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Peripheral {
    /// The gimbal and its camera core, `0x0F`.
    Gimbal,
    /// The dual-light (thermal) camera, `0x1F`.
    DualLight,
}

impl Peripheral {
    /// The byte on the wire.
    pub const fn code(self) -> u8 {
        match self {
            Peripheral::Gimbal => 0x0F,
            Peripheral::DualLight => 0x1F,
        }
    }

    /// The peripheral with this code, if it is one.
    pub const fn from_code(code: u8) -> Option<Self> {
        match code {
            0x0F => Some(Peripheral::Gimbal),
            0x1F => Some(Peripheral::DualLight),
            _ => None,
        }
    }
}

/// Commands to the gimbal and its camera core (peripheral `0x0F`).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
// A word-sized tag: `Command` then keeps the dual-light commands in the bytes after it (a
// niche), so it has no tag of its own and `Command::encode` tests the variant with one load
// and compare instead of two loads (with the sub-code below, a third of an angle command's
// encode; the value grows from 8 to 12 bytes, `Command` from 10).
#[repr(u32)]
pub enum GimbalCommand {
    /// Bring the point to the image centre and zoom in 2× (`0x01`).
    PointingZoom(ImageOffset),
    /// Follow the vehicle's nose (`0x02`).
    NoseFollowing,
    /// One-click back to centre (`0x03`).
    Recenter,
    /// Rotate at these rates; repeat about every 50 ms to keep moving (`0x04`).
    Rate(Rate),
    /// Start tracking the target in the box (`0x05`).
    StartTracking(TrackingBox),
    // The variants are in command-code order but for stop tracking, after the angle
    // commands: the pointing commands then come first and the three angle commands
    // together, so that `is_pointing` and `Command::encode`'s fast path each test the
    // variant with one compare.
    /// One-click down 90° (`0x07`).
    LookDown,
    /// Point at this heading (`0x08`, type 1).
    Heading(Heading),
    /// Point at this pitch (`0x08`, type 2).
    Pitch(Pitch),
    /// Set this optical zoom ratio (`0x08`, type 3).
    ZoomRatio(ZoomRatio),
    /// Stop tracking (`0x06`).
    StopTracking,
    /// Photo command (`0x10`).
    Photo(Photo),
    /// Video command (`0x11`).
    Video(Video),
    /// Optical zoom command (`0x12`).
    Zoom(Zoom),
    /// Focus command (`0x13`).
    Focus(Focus),
    /// Focus on this point (`0x14`).
    PointingFocus(ImagePoint),
    /// Fast calibration (`0xF0`).
    FastCalibration,
}

/// Commands to the dual-light (thermal) camera (peripheral `0x1F`).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DualLightCommand {
    /// Bring the point to the image centre and zoom in (`0x01`).
    PointingZoom(ImageOffset),
    /// Select the thermal palette (`0x02`).
    Palette(Palette),
    /// Rotate at these rates; repeat about every 50 ms to keep moving (`0x04`).
    Rate(Rate),
    /// Start tracking the target in the box (`0x05`).
    StartTracking(TrackingBox),
    /// Stop tracking (`0x07`; `0x06` is not a command on this peripheral).
    StopTracking,
    /// Electronic zoom command (`0x12`).
    ElectronicZoom(ElectronicZoom),
}

/// Specify-angle (`0x08`) types, DATA1.
const ANGLE_HEADING: u8 = 1;
const ANGLE_PITCH: u8 = 2;
const ANGLE_ZOOM: u8 = 3;
/// Pointing focus DATA5 and DATA6.
const POINTING_FOCUS_SIZE: u8 = 25;

fn put_offset(buf: &mut [u8; 8], o: ImageOffset) {
    put_2!(buf, field::X, o.x().to_le_bytes());
    put_2!(buf, field::Y, o.y().to_le_bytes());
}

fn put_rate(buf: &mut [u8; 8], r: Rate) {
    put_2!(buf, field::X, r.yaw_centi().to_le_bytes());
    put_2!(buf, field::Y, r.pitch_centi().to_le_bytes());
}

fn put_point(buf: &mut [u8; 8], p: ImagePoint) {
    put_2!(buf, field::X, p.x().to_le_bytes());
    put_2!(buf, field::Y, p.y().to_le_bytes());
}

fn put_box(buf: &mut [u8; 8], b: TrackingBox) {
    put_point(buf, b.centre());
    buf[field::BOX_WIDTH] = b.width16();
    buf[field::BOX_HEIGHT] = b.height16();
}

/// Reads DATA fields for decoding; every failure carries the whole frame.
struct Reader<'a> {
    data: &'a [u8; 8],
}

impl Reader<'_> {
    fn invalid(&self, field: &'static str) -> DecodeError {
        DecodeError::InvalidValue {
            data: *self.data,
            field,
        }
    }

    fn mode(&self) -> u8 {
        self.data[field::MODE]
    }

    fn sub_code<T>(
        &self,
        from_code: fn(u8) -> Option<T>,
        field: &'static str,
    ) -> Result<T, DecodeError> {
        from_code(self.mode()).ok_or_else(|| self.invalid(field))
    }

    fn offset(&self) -> Result<ImageOffset, DecodeError> {
        let x = i16::from_le_bytes(get_2!(self.data, field::X));
        let y = i16::from_le_bytes(get_2!(self.data, field::Y));
        ImageOffset::new(x.into(), y.into()).map_err(|e| self.invalid(e.field))
    }

    fn rate(&self) -> Result<Rate, DecodeError> {
        let yaw = i16::from_le_bytes(get_2!(self.data, field::X));
        let pitch = i16::from_le_bytes(get_2!(self.data, field::Y));
        Rate::from_centi(yaw, pitch).map_err(|e| self.invalid(e.field))
    }

    fn point(&self) -> Result<ImagePoint, DecodeError> {
        let x = u16::from_le_bytes(get_2!(self.data, field::X));
        let y = u16::from_le_bytes(get_2!(self.data, field::Y));
        ImagePoint::new(x.into(), y.into()).map_err(|e| self.invalid(e.field))
    }

    fn tracking_box(&self) -> Result<TrackingBox, DecodeError> {
        Ok(TrackingBox::from_raw(
            self.point()?,
            self.data[field::BOX_WIDTH],
            self.data[field::BOX_HEIGHT],
        ))
    }

    fn angle_u16(&self) -> u16 {
        u16::from_le_bytes(get_2!(self.data, field::ANGLE))
    }

    fn angle_i16(&self) -> i16 {
        i16::from_le_bytes(get_2!(self.data, field::ANGLE))
    }
}

impl GimbalCommand {
    /// Writes CMD and DATA.
    fn write(&self, buf: &mut [u8; 8]) {
        let cmd = match *self {
            GimbalCommand::PointingZoom(o) => {
                put_offset(buf, o);
                0x01
            }
            GimbalCommand::NoseFollowing => 0x02,
            GimbalCommand::Recenter => 0x03,
            GimbalCommand::Rate(r) => {
                put_rate(buf, r);
                0x04
            }
            GimbalCommand::StartTracking(b) => {
                put_box(buf, b);
                0x05
            }
            GimbalCommand::StopTracking => 0x06,
            GimbalCommand::LookDown => 0x07,
            GimbalCommand::Heading(h) => {
                buf[field::MODE] = ANGLE_HEADING;
                put_2!(buf, field::ANGLE, h.deci().to_le_bytes());
                0x08
            }
            GimbalCommand::Pitch(p) => {
                buf[field::MODE] = ANGLE_PITCH;
                put_2!(buf, field::ANGLE, p.deci().to_le_bytes());
                0x08
            }
            GimbalCommand::ZoomRatio(z) => {
                buf[field::MODE] = ANGLE_ZOOM;
                put_2!(buf, field::ANGLE, z.centi().to_le_bytes());
                0x08
            }
            GimbalCommand::Photo(p) => {
                let (mode, param) = p.codes();
                buf[field::MODE] = mode;
                buf[field::PARAM] = param;
                0x10
            }
            GimbalCommand::Video(v) => {
                buf[field::MODE] = v.code();
                0x11
            }
            GimbalCommand::Zoom(z) => {
                buf[field::MODE] = z.code();
                0x12
            }
            GimbalCommand::Focus(f) => {
                buf[field::MODE] = f.code();
                0x13
            }
            GimbalCommand::PointingFocus(p) => {
                put_point(buf, p);
                buf[field::BOX_WIDTH] = POINTING_FOCUS_SIZE;
                buf[field::BOX_HEIGHT] = POINTING_FOCUS_SIZE;
                0x14
            }
            GimbalCommand::FastCalibration => 0xF0,
        };
        buf[field::CMD] = cmd;
    }

    /// Reads CMD and the DATA it uses (padding is checked by the caller).
    fn read(r: &Reader<'_>) -> Result<Self, DecodeError> {
        Ok(match r.data[field::CMD] {
            0x01 => GimbalCommand::PointingZoom(r.offset()?),
            0x02 => GimbalCommand::NoseFollowing,
            0x03 => GimbalCommand::Recenter,
            0x04 => GimbalCommand::Rate(r.rate()?),
            0x05 => GimbalCommand::StartTracking(r.tracking_box()?),
            0x06 => GimbalCommand::StopTracking,
            0x07 => GimbalCommand::LookDown,
            0x08 => {
                let invalid = |e: RangeError| r.invalid(e.field);
                match r.mode() {
                    ANGLE_HEADING => {
                        GimbalCommand::Heading(Heading::from_deci(r.angle_u16()).map_err(invalid)?)
                    }
                    ANGLE_PITCH => {
                        GimbalCommand::Pitch(Pitch::from_deci(r.angle_i16()).map_err(invalid)?)
                    }
                    ANGLE_ZOOM => GimbalCommand::ZoomRatio(
                        ZoomRatio::from_centi(r.angle_u16()).map_err(invalid)?,
                    ),
                    _ => return Err(r.invalid("angle_type")),
                }
            }
            0x10 => GimbalCommand::Photo(
                Photo::from_codes(r.mode(), r.data[field::PARAM])
                    .map_err(|field| r.invalid(field))?,
            ),
            0x11 => GimbalCommand::Video(r.sub_code(Video::from_code, Video::FIELD)?),
            0x12 => GimbalCommand::Zoom(r.sub_code(Zoom::from_code, Zoom::FIELD)?),
            0x13 => GimbalCommand::Focus(r.sub_code(Focus::from_code, Focus::FIELD)?),
            0x14 => {
                let point = r.point()?;
                if r.data[field::BOX_WIDTH] != POINTING_FOCUS_SIZE
                    || r.data[field::BOX_HEIGHT] != POINTING_FOCUS_SIZE
                {
                    return Err(r.invalid("focus_box"));
                }
                GimbalCommand::PointingFocus(point)
            }
            0xF0 => GimbalCommand::FastCalibration,
            _ => return Err(DecodeError::UnknownCommand { data: *r.data }),
        })
    }

    fn is_pointing(&self) -> bool {
        matches!(
            self,
            GimbalCommand::PointingZoom(_)
                | GimbalCommand::NoseFollowing
                | GimbalCommand::Recenter
                | GimbalCommand::Rate(_)
                | GimbalCommand::StartTracking(_)
                | GimbalCommand::LookDown
                | GimbalCommand::Heading(_)
                | GimbalCommand::Pitch(_)
        )
    }
}

impl DualLightCommand {
    /// Writes CMD and DATA.
    fn write(&self, buf: &mut [u8; 8]) {
        let cmd = match *self {
            DualLightCommand::PointingZoom(o) => {
                put_offset(buf, o);
                0x01
            }
            DualLightCommand::Palette(p) => {
                buf[field::MODE] = p.code();
                0x02
            }
            DualLightCommand::Rate(r) => {
                put_rate(buf, r);
                0x04
            }
            DualLightCommand::StartTracking(b) => {
                put_box(buf, b);
                0x05
            }
            DualLightCommand::StopTracking => 0x07,
            DualLightCommand::ElectronicZoom(z) => {
                buf[field::MODE] = z.code();
                0x12
            }
        };
        buf[field::CMD] = cmd;
    }

    /// Reads CMD and the DATA it uses (padding is checked by the caller).
    fn read(r: &Reader<'_>) -> Result<Self, DecodeError> {
        Ok(match r.data[field::CMD] {
            0x01 => DualLightCommand::PointingZoom(r.offset()?),
            0x02 => DualLightCommand::Palette(r.sub_code(Palette::from_code, "palette")?),
            0x04 => DualLightCommand::Rate(r.rate()?),
            0x05 => DualLightCommand::StartTracking(r.tracking_box()?),
            0x07 => DualLightCommand::StopTracking,
            0x12 => DualLightCommand::ElectronicZoom(
                r.sub_code(ElectronicZoom::from_code, ElectronicZoom::FIELD)?,
            ),
            _ => return Err(DecodeError::UnknownCommand { data: *r.data }),
        })
    }

    fn is_pointing(&self) -> bool {
        matches!(
            self,
            DualLightCommand::PointingZoom(_)
                | DualLightCommand::Rate(_)
                | DualLightCommand::StartTracking(_)
        )
    }
}

/// A control command to either peripheral: one frame on [`Command::ID`].
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Command {
    /// A command to the gimbal and its camera core (`0x0F`).
    Gimbal(GimbalCommand),
    /// A command to the dual-light camera (`0x1F`).
    DualLight(DualLightCommand),
}

impl From<GimbalCommand> for Command {
    fn from(c: GimbalCommand) -> Self {
        Command::Gimbal(c)
    }
}

impl From<DualLightCommand> for Command {
    fn from(c: DualLightCommand) -> Self {
        Command::DualLight(c)
    }
}

impl Command {
    /// The CAN identifier of control frames.
    pub const ID: u32 = ids::CONTROL;
    /// The length of a control frame's data.
    pub const LEN: usize = 8;

    /// The peripheral the command is addressed to.
    pub fn peripheral(&self) -> Peripheral {
        match self {
            Command::Gimbal(_) => Peripheral::Gimbal,
            Command::DualLight(_) => Peripheral::DualLight,
        }
    }

    /// The 8 data bytes of the command's frame.
    #[inline]
    pub fn encode(&self) -> [u8; 8] {
        // The specify-angle commands (what point-at and most applications send, at up to
        // 10 Hz) are one constant with the sub-code and value or'ed in; the rest are
        // written field by field, out of line. The sub-code as a `u32`: as a `u8` the
        // compiler derives it from the variant and then narrows it (two more instructions).
        let (mode, value) = match *self {
            Command::Gimbal(GimbalCommand::Heading(h)) => (u32::from(ANGLE_HEADING), h.deci()),
            Command::Gimbal(GimbalCommand::Pitch(p)) => (u32::from(ANGLE_PITCH), p.deci() as u16),
            Command::Gimbal(GimbalCommand::ZoomRatio(z)) => (u32::from(ANGLE_ZOOM), z.centi()),
            // As a `u64`: returned in two registers, not through memory.
            _ => return self.encode_fields().to_le_bytes(),
        };
        // Little-endian: byte 0 the peripheral, 1 CMD 0x08, 2 the angle type, 3-4 the
        // value (field::MODE and field::ANGLE; a test holds this to `encode_fields`).
        let prefix = u64::from(Peripheral::Gimbal.code()) | 0x08 << 8;
        (prefix | u64::from(mode) << 16 | u64::from(value) << 24).to_le_bytes()
    }

    /// [`Command::encode`], field by field: every command (the bytes as a little-endian
    /// `u64`).
    #[inline(never)]
    fn encode_fields(&self) -> u64 {
        let mut buf = [0u8; Self::LEN];
        buf[field::PERIPHERAL] = self.peripheral().code();
        match self {
            Command::Gimbal(c) => c.write(&mut buf),
            Command::DualLight(c) => c.write(&mut buf),
        }
        u64::from_le_bytes(buf)
    }

    /// Decodes a control frame's data strictly (see the [module docs](self)).
    ///
    /// Any slice is accepted and none panics; only exactly 8 bytes can succeed.
    pub fn decode(data: &[u8]) -> Result<Command, DecodeError> {
        let data: [u8; 8] = data
            .try_into()
            .map_err(|_| DecodeError::WrongLength { len: data.len() })?;
        let r = Reader { data: &data };
        let command = match Peripheral::from_code(data[field::PERIPHERAL]) {
            Some(Peripheral::Gimbal) => Command::Gimbal(GimbalCommand::read(&r)?),
            Some(Peripheral::DualLight) => Command::DualLight(DualLightCommand::read(&r)?),
            None => return Err(DecodeError::UnknownPeripheral { data }),
        };
        // `read` consumed exactly the bytes `encode` writes, reproducing them, and
        // `encode` zeroes the rest: any other difference is in the padding.
        if command.encode() == data {
            Ok(command)
        } else {
            Err(DecodeError::NonZeroPadding { data })
        }
    }

    /// The command as a frame on [`Command::ID`].
    pub fn to_frame(&self) -> Frame {
        Frame::new(Self::ID, self.encode())
    }

    /// Whether the command moves or aims the gimbal.
    ///
    /// True for pointing zoom, nose-following, recenter, rate, start tracking, look down,
    /// heading and pitch (on the dual-light camera: pointing zoom, rate and start
    /// tracking). False for stop tracking, zoom ratio, photo, video, zoom, focus,
    /// pointing focus, fast calibration, palette and electronic zoom. A driver holding
    /// a rate uses it to cancel the hold.
    pub fn is_pointing(&self) -> bool {
        match self {
            Command::Gimbal(c) => c.is_pointing(),
            Command::DualLight(c) => c.is_pointing(),
        }
    }
}

/// Why [`Command::decode`] rejected a frame. All but `WrongLength` carry the frame.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DecodeError {
    /// The data was not exactly 8 bytes long.
    WrongLength {
        /// The length received.
        len: usize,
    },
    /// Byte 0 is neither `0x0F` nor `0x1F`.
    UnknownPeripheral {
        /// The frame.
        data: [u8; 8],
    },
    /// Byte 1 is not a command of the addressed peripheral.
    UnknownCommand {
        /// The frame.
        data: [u8; 8],
    },
    /// A value is outside its documented range, a sub-code is unknown, a photo count or
    /// delay is zero, or pointing focus DATA5/DATA6 is not 25.
    InvalidValue {
        /// The frame.
        data: [u8; 8],
        /// The offending field, e.g. `"pitch"`, `"photo_mode"`, `"angle_type"`.
        field: &'static str,
    },
    /// A byte the command does not use is not zero.
    NonZeroPadding {
        /// The frame.
        data: [u8; 8],
    },
}

impl DecodeError {
    /// The rejected frame, when it was 8 bytes long.
    pub fn data(&self) -> Option<&[u8; 8]> {
        match self {
            DecodeError::WrongLength { .. } => None,
            DecodeError::UnknownPeripheral { data }
            | DecodeError::UnknownCommand { data }
            | DecodeError::InvalidValue { data, .. }
            | DecodeError::NonZeroPadding { data } => Some(data),
        }
    }
}

impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DecodeError::WrongLength { len } => {
                write!(f, "control frame must be 8 bytes, got {len}")
            }
            DecodeError::UnknownPeripheral { data } => {
                write!(f, "control frame {data:02X?}: unknown peripheral")
            }
            DecodeError::UnknownCommand { data } => {
                write!(f, "control frame {data:02X?}: unknown command")
            }
            DecodeError::InvalidValue { data, field } => {
                write!(f, "control frame {data:02X?}: invalid {field}")
            }
            DecodeError::NonZeroPadding { data } => {
                write!(f, "control frame {data:02X?}: unused bytes are not zero")
            }
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for DecodeError {}

#[cfg(test)]
mod tests;
