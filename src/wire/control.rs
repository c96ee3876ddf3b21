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
use core::num::NonZeroU8;

use super::{ids, round_f32, Frame, RangeError};

/// Byte offsets of the control frame's fields, in one place.
mod field {
    use core::ops::Range;

    /// The peripheral code (`0x0F` or `0x1F`).
    pub const PERIPHERAL: usize = 0;
    /// The command code.
    pub const CMD: usize = 1;
    /// DATA1..DATA6.
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

/// [`RangeError::check`] of a value in wire units; the error speaks the physical unit
/// (all three divided by `scale`), as the float constructors' errors do.
fn check_int(
    field: &'static str,
    value: i32,
    min: i32,
    max: i32,
    scale: f64,
) -> Result<(), RangeError> {
    RangeError::check(field, value, min, max)
        .map(drop)
        .map_err(|e| e.scaled(scale))
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

/// Angular rates for rate control (CMD `0x04`), stored in (deg/s)×100.
///
/// Positive yaw turns right, negative left; positive pitch turns up. The gimbal moves only
/// while rate commands keep coming (the document recommends one every 50 ms) and stops
/// when they stop.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Rate {
    yaw: i16,
    pitch: i16,
}

impl Rate {
    /// The largest rate magnitude, deg/s.
    pub const MAX_DPS: f32 = 100.0;
    /// The largest rate magnitude on the wire, (deg/s)×100.
    pub const MAX_CENTI: i16 = 10_000;
    /// No motion.
    pub const ZERO: Rate = Rate { yaw: 0, pitch: 0 };

    /// Rates in deg/s, each in [−100, 100], rounded to the nearest 0.01 deg/s.
    pub fn new(yaw_dps: f32, pitch_dps: f32) -> Result<Self, RangeError> {
        let yaw = RangeError::check("yaw_rate", yaw_dps, -Self::MAX_DPS, Self::MAX_DPS)?;
        let pitch = RangeError::check("pitch_rate", pitch_dps, -Self::MAX_DPS, Self::MAX_DPS)?;
        Ok(Rate {
            yaw: round_f32(yaw * 100.0) as i16,
            pitch: round_f32(pitch * 100.0) as i16,
        })
    }

    /// Rates in wire units, (deg/s)×100, each in [−10000, 10000].
    pub fn from_centi(yaw: i16, pitch: i16) -> Result<Self, RangeError> {
        let (min, max) = ((-Self::MAX_CENTI).into(), Self::MAX_CENTI.into());
        check_int("yaw_rate", yaw.into(), min, max, 100.0)?;
        check_int("pitch_rate", pitch.into(), min, max, 100.0)?;
        Ok(Rate { yaw, pitch })
    }

    /// Yaw (heading) rate, deg/s.
    pub fn yaw_dps(self) -> f32 {
        f32::from(self.yaw) / 100.0
    }

    /// Pitch rate, deg/s.
    pub fn pitch_dps(self) -> f32 {
        f32::from(self.pitch) / 100.0
    }

    /// Yaw (heading) rate, (deg/s)×100.
    pub const fn yaw_centi(self) -> i16 {
        self.yaw
    }

    /// Pitch rate, (deg/s)×100.
    pub const fn pitch_centi(self) -> i16 {
        self.pitch
    }

    /// Whether both rates are zero (a command that holds the gimbal still).
    pub const fn is_zero(self) -> bool {
        self.yaw == 0 && self.pitch == 0
    }
}

/// A heading angle to point at (CMD `0x08`, type 1), stored in deci-degrees.
///
/// Relative to north while the flight controller pushes its attitude, relative to the
/// vehicle's nose otherwise. 360° is accepted and sent as 3600, as documented.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Heading(u16);

impl Heading {
    /// The largest heading, degrees.
    pub const MAX_DEG: f32 = 360.0;
    /// The largest heading on the wire, deci-degrees.
    pub const MAX_DECI: u16 = 3600;
    /// North (or the nose), 0°.
    pub const NORTH: Heading = Heading(0);

    /// The heading of any angle in 0.01°, wrapped into [0°, 360°) and rounded to the
    /// command's 0.1° (359.96° rounds to 360.0°, which is north). Total: every angle has
    /// one.
    pub const fn from_centideg_wrapped(cdeg: i32) -> Heading {
        // rem_euclid: [0, 35999] (+ 5 is exact); rounded to tenths: [0, 3600], the
        // command's range.
        Heading((cdeg.rem_euclid(36_000).saturating_add(5) / 10) as u16)
    }

    /// A heading in degrees in [0, 360], rounded to the nearest 0.1°.
    pub fn new(degrees: f32) -> Result<Self, RangeError> {
        let d = RangeError::check("heading", degrees, 0.0, Self::MAX_DEG)?;
        Ok(Heading(round_f32(d * 10.0) as u16))
    }

    /// A heading in wire units, deci-degrees in [0, 3600].
    pub fn from_deci(deci: u16) -> Result<Self, RangeError> {
        check_int("heading", deci.into(), 0, Self::MAX_DECI.into(), 10.0)?;
        Ok(Heading(deci))
    }

    /// The heading, degrees.
    pub fn degrees(self) -> f32 {
        f32::from(self.0) / 10.0
    }

    /// The heading, deci-degrees.
    pub const fn deci(self) -> u16 {
        self.0
    }
}

/// A pitch angle to point at (CMD `0x08`, type 2), stored in deci-degrees; positive is up.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Pitch(i16);

impl Pitch {
    /// The lowest pitch, degrees.
    pub const MIN_DEG: f32 = -100.0;
    /// The highest pitch, degrees.
    pub const MAX_DEG: f32 = 60.0;
    /// The lowest pitch on the wire, deci-degrees.
    pub const MIN_DECI: i16 = -1000;
    /// The highest pitch on the wire, deci-degrees.
    pub const MAX_DECI: i16 = 600;
    /// Level, 0°.
    pub const LEVEL: Pitch = Pitch(0);

    /// A pitch in degrees in [−100, 60], rounded to the nearest 0.1°.
    pub fn new(degrees: f32) -> Result<Self, RangeError> {
        let d = RangeError::check("pitch", degrees, Self::MIN_DEG, Self::MAX_DEG)?;
        Ok(Pitch(round_f32(d * 10.0) as i16))
    }

    /// A pitch in wire units, deci-degrees in [−1000, 600].
    pub fn from_deci(deci: i16) -> Result<Self, RangeError> {
        check_int(
            "pitch",
            deci.into(),
            Self::MIN_DECI.into(),
            Self::MAX_DECI.into(),
            10.0,
        )?;
        Ok(Pitch(deci))
    }

    /// The pitch, degrees.
    pub fn degrees(self) -> f32 {
        f32::from(self.0) / 10.0
    }

    /// The pitch, deci-degrees.
    pub const fn deci(self) -> i16 {
        self.0
    }
}

/// An optical zoom ratio to set (CMD `0x08`, type 3), stored ×100.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ZoomRatio(u16);

impl ZoomRatio {
    /// The smallest ratio (no zoom).
    pub const MIN: f32 = 1.0;
    /// The largest ratio (30 on most models, 35 on some).
    pub const MAX: f32 = 35.0;
    /// The smallest ratio on the wire, ×100.
    pub const MIN_CENTI: u16 = 100;
    /// The largest ratio on the wire, ×100.
    pub const MAX_CENTI: u16 = 3500;

    /// A ratio in [1, 35], rounded to the nearest 0.01.
    pub fn new(ratio: f32) -> Result<Self, RangeError> {
        let r = RangeError::check("zoom_ratio", ratio, Self::MIN, Self::MAX)?;
        Ok(ZoomRatio(round_f32(r * 100.0) as u16))
    }

    /// A ratio in wire units, ×100 in [100, 3500].
    pub fn from_centi(centi: u16) -> Result<Self, RangeError> {
        check_int(
            "zoom_ratio",
            centi.into(),
            Self::MIN_CENTI.into(),
            Self::MAX_CENTI.into(),
            100.0,
        )?;
        Ok(ZoomRatio(centi))
    }

    /// The ratio.
    pub fn ratio(self) -> f32 {
        f32::from(self.0) / 100.0
    }

    /// The ratio ×100.
    pub const fn centi(self) -> u16 {
        self.0
    }
}

/// A point as an offset from the image centre, for pointing zoom (CMD `0x01`).
///
/// Each axis is in [−10000, 10000]: top-left is (−10000, −10000), bottom-right
/// (10000, 10000).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ImageOffset {
    x: i16,
    y: i16,
}

impl ImageOffset {
    /// The largest offset magnitude on either axis.
    pub const MAX: i16 = 10_000;
    /// The image centre.
    pub const CENTRE: ImageOffset = ImageOffset { x: 0, y: 0 };

    /// An offset with each axis in [−10000, 10000].
    pub fn new(x: i32, y: i32) -> Result<Self, RangeError> {
        let (min, max) = ((-Self::MAX).into(), Self::MAX.into());
        check_int("x", x, min, max, 1.0)?;
        check_int("y", y, min, max, 1.0)?;
        Ok(ImageOffset {
            x: x as i16,
            y: y as i16,
        })
    }

    /// Horizontal offset, positive to the right.
    pub const fn x(self) -> i16 {
        self.x
    }

    /// Vertical offset, positive downwards.
    pub const fn y(self) -> i16 {
        self.y
    }
}

/// A point in image coordinates, for tracking and pointing focus (CMD `0x05`, `0x14`).
///
/// Each axis is in [0, 8191]: top-left is (0, 0), bottom-right (8191, 8191).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ImagePoint {
    x: u16,
    y: u16,
}

impl ImagePoint {
    /// The largest coordinate on either axis.
    pub const MAX: u16 = 8191;

    /// A point with each axis in [0, 8191].
    pub fn new(x: i32, y: i32) -> Result<Self, RangeError> {
        let max = i32::from(Self::MAX);
        check_int("x", x, 0, max, 1.0)?;
        check_int("y", y, 0, max, 1.0)?;
        Ok(ImagePoint {
            x: x as u16,
            y: y as u16,
        })
    }

    /// Horizontal coordinate, from the left edge.
    pub const fn x(self) -> u16 {
        self.x
    }

    /// Vertical coordinate, from the top edge.
    pub const fn y(self) -> u16 {
        self.y
    }
}

/// A target box to start tracking (CMD `0x05`): its centre and its size in image units,
/// sent divided by 16.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TrackingBox {
    centre: ImagePoint,
    width16: u8,
    height16: u8,
}

impl TrackingBox {
    /// The largest box side, image units (255 × 16).
    pub const MAX_SIDE: f32 = 4080.0;

    /// A box of `width` × `height` image units, each in [0, 4080], each rounded to the
    /// nearest multiple of 16.
    pub fn new(centre: ImagePoint, width: f32, height: f32) -> Result<Self, RangeError> {
        let w = RangeError::check("width", width, 0.0, Self::MAX_SIDE)?;
        let h = RangeError::check("height", height, 0.0, Self::MAX_SIDE)?;
        Ok(TrackingBox {
            centre,
            width16: round_f32(w / 16.0) as u8,
            height16: round_f32(h / 16.0) as u8,
        })
    }

    /// A box from its wire sizes (DATA5 = width/16, DATA6 = height/16).
    pub const fn from_raw(centre: ImagePoint, width16: u8, height16: u8) -> Self {
        TrackingBox {
            centre,
            width16,
            height16,
        }
    }

    /// The box centre.
    pub const fn centre(self) -> ImagePoint {
        self.centre
    }

    /// The box width, image units (a multiple of 16).
    pub const fn width(self) -> u16 {
        // At most 255 × 16 = 4080: exact.
        (self.width16 as u16).saturating_mul(16)
    }

    /// The box height, image units (a multiple of 16).
    pub const fn height(self) -> u16 {
        // At most 255 × 16 = 4080: exact.
        (self.height16 as u16).saturating_mul(16)
    }

    /// The box width as sent, image units / 16.
    pub const fn width16(self) -> u8 {
        self.width16
    }

    /// The box height as sent, image units / 16.
    pub const fn height16(self) -> u8 {
        self.height16
    }
}

/// Camera photo commands (CMD `0x10`).
///
/// The parameters are [`NonZeroU8`] so that a zero count or delay, which the camera has
/// no meaning for and [`Command::decode`] rejects, cannot be built. The constructors
/// [`Photo::burst`], [`Photo::time_lapse`] and [`Photo::timer`] take plain integers.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Photo {
    /// Take one picture (mode 1).
    Single,
    /// Continuous shooting of this many pictures (mode 2).
    Burst(NonZeroU8),
    /// Time-lapse photography with this delay in seconds (mode 3).
    TimeLapse(NonZeroU8),
    /// Timed photography after this many seconds (mode 4).
    Timer(NonZeroU8),
    /// Stop photographing (mode 5).
    Stop,
}

impl Photo {
    fn parameter(field: &'static str, value: u32) -> Result<NonZeroU8, RangeError> {
        let value = RangeError::check(field, value, 1, 255)?;
        // 1..=255 after the check: neither the cast nor the zero test can fail.
        NonZeroU8::new(value as u8).ok_or(RangeError {
            field,
            value: 0.0,
            min: 1.0,
            max: 255.0,
        })
    }

    /// Continuous shooting of `count` pictures, in [1, 255].
    pub fn burst(count: u32) -> Result<Self, RangeError> {
        Self::parameter("count", count).map(Photo::Burst)
    }

    /// Time-lapse photography with a delay of `seconds`, in [1, 255].
    pub fn time_lapse(seconds: u32) -> Result<Self, RangeError> {
        Self::parameter("seconds", seconds).map(Photo::TimeLapse)
    }

    /// Timed photography after `seconds`, in [1, 255].
    pub fn timer(seconds: u32) -> Result<Self, RangeError> {
        Self::parameter("seconds", seconds).map(Photo::Timer)
    }

    /// DATA1 and DATA2.
    fn codes(self) -> (u8, u8) {
        match self {
            Photo::Single => (1, 0),
            Photo::Burst(n) => (2, n.get()),
            Photo::TimeLapse(s) => (3, s.get()),
            Photo::Timer(s) => (4, s.get()),
            Photo::Stop => (5, 0),
        }
    }

    fn from_codes(mode: u8, param: u8) -> Result<Self, &'static str> {
        let nonzero = |field| NonZeroU8::new(param).ok_or(field);
        match mode {
            1 => Ok(Photo::Single),
            2 => nonzero("count").map(Photo::Burst),
            3 => nonzero("seconds").map(Photo::TimeLapse),
            4 => nonzero("seconds").map(Photo::Timer),
            5 => Ok(Photo::Stop),
            _ => Err("photo_mode"),
        }
    }
}

/// Generates a field-less enum of sub-codes (DATA1) with its code table.
macro_rules! sub_code_enum {
    (
        $(#[$meta:meta])*
        $name:ident, $field:literal {
            $($(#[$vmeta:meta])* $variant:ident = $code:literal,)+
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        pub enum $name {
            $($(#[$vmeta])* $variant,)+
        }

        impl $name {
            /// The field name [`DecodeError::InvalidValue`] reports for a bad code.
            const FIELD: &'static str = $field;

            const fn code(self) -> u8 {
                match self {
                    $($name::$variant => $code,)+
                }
            }

            const fn from_code(code: u8) -> Option<Self> {
                match code {
                    $($code => Some($name::$variant),)+
                    _ => None,
                }
            }
        }
    };
}

sub_code_enum! {
    /// Camera video commands (CMD `0x11`).
    Video, "video_mode" {
        /// Start recording (1).
        Start = 1,
        /// Stop recording (2).
        Stop = 2,
    }
}

sub_code_enum! {
    /// Camera optical zoom commands (CMD `0x12` to the gimbal).
    Zoom, "zoom_mode" {
        /// Zoom in continuously until [`Zoom::Stop`] (1).
        In = 1,
        /// Zoom out continuously until [`Zoom::Stop`] (2).
        Out = 2,
        /// Stop zooming (3).
        Stop = 3,
        /// Back to 1× (4).
        Reset = 4,
        /// Zoom in by a factor of 2 (5).
        Double = 5,
        /// Zoom out by a factor of 2 (6).
        Half = 6,
    }
}

sub_code_enum! {
    /// Camera focus commands (CMD `0x13`).
    Focus, "focus_mode" {
        /// Focus + (1).
        Plus = 1,
        /// Focus − (2).
        Minus = 2,
        /// Stop focusing (3).
        Stop = 3,
        /// Auto-focus (4).
        Auto = 4,
    }
}

sub_code_enum! {
    /// Dual-light camera electronic zoom commands (CMD `0x12` to the dual-light camera).
    ElectronicZoom, "electronic_zoom_mode" {
        /// Zoom in continuously until [`ElectronicZoom::Stop`] (1).
        In = 1,
        /// Zoom out continuously until [`ElectronicZoom::Stop`] (2).
        Out = 2,
        /// Stop zooming (3).
        Stop = 3,
    }
}

/// Thermal image palettes of the dual-light camera (CMD `0x02`, DATA1 `0x00`..=`0x0E`).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Palette {
    /// Black hot, `0x00`.
    BlackHot,
    /// White hot, `0x01`.
    WhiteHot,
    /// Iron red, `0x02`.
    IronRed,
    /// Rainbow, `0x03`.
    Rainbow,
    /// Lava, `0x04`.
    Lava,
    /// Rainbow enhancement, `0x05`.
    RainbowEnhanced,
    /// Molten metal, `0x06`.
    MoltenMetal,
    /// Bluish red, `0x07`.
    BluishRed,
    /// Amber, `0x08`.
    Amber,
    /// Amber inversion, `0x09`.
    AmberInverted,
    /// Ice blue, `0x0A`.
    IceBlue,
    /// High contrast, `0x0B`.
    HighContrast,
    /// Grayscale inversion, `0x0C`.
    GrayscaleInverted,
    /// High-temperature red, `0x0D`.
    HotRed,
    /// Low-temperature blue, `0x0E`.
    ColdBlue,
}

impl Palette {
    /// Every palette, in code order (`ALL[n].code() == n`).
    pub const ALL: [Palette; 15] = [
        Palette::BlackHot,
        Palette::WhiteHot,
        Palette::IronRed,
        Palette::Rainbow,
        Palette::Lava,
        Palette::RainbowEnhanced,
        Palette::MoltenMetal,
        Palette::BluishRed,
        Palette::Amber,
        Palette::AmberInverted,
        Palette::IceBlue,
        Palette::HighContrast,
        Palette::GrayscaleInverted,
        Palette::HotRed,
        Palette::ColdBlue,
    ];

    /// The byte on the wire (DATA1).
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// The palette with this code, if it is one (`0x00`..=`0x0E`).
    pub fn from_code(code: u8) -> Option<Self> {
        Self::ALL.get(usize::from(code)).copied()
    }

    /// The palette's kebab-case name, e.g. `"ice-blue"`.
    pub const fn name(self) -> &'static str {
        match self {
            Palette::BlackHot => "black-hot",
            Palette::WhiteHot => "white-hot",
            Palette::IronRed => "iron-red",
            Palette::Rainbow => "rainbow",
            Palette::Lava => "lava",
            Palette::RainbowEnhanced => "rainbow-enhanced",
            Palette::MoltenMetal => "molten-metal",
            Palette::BluishRed => "bluish-red",
            Palette::Amber => "amber",
            Palette::AmberInverted => "amber-inverted",
            Palette::IceBlue => "ice-blue",
            Palette::HighContrast => "high-contrast",
            Palette::GrayscaleInverted => "grayscale-inverted",
            Palette::HotRed => "hot-red",
            Palette::ColdBlue => "cold-blue",
        }
    }

    /// The palette with this [name](Palette::name) (exact, case-sensitive match).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }
}

impl fmt::Display for Palette {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
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
    put_2!(buf, field::X, o.x.to_le_bytes());
    put_2!(buf, field::Y, o.y.to_le_bytes());
}

fn put_rate(buf: &mut [u8; 8], r: Rate) {
    put_2!(buf, field::X, r.yaw.to_le_bytes());
    put_2!(buf, field::Y, r.pitch.to_le_bytes());
}

fn put_point(buf: &mut [u8; 8], p: ImagePoint) {
    put_2!(buf, field::X, p.x.to_le_bytes());
    put_2!(buf, field::Y, p.y.to_le_bytes());
}

fn put_box(buf: &mut [u8; 8], b: TrackingBox) {
    put_point(buf, b.centre);
    buf[field::BOX_WIDTH] = b.width16;
    buf[field::BOX_HEIGHT] = b.height16;
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
                put_2!(buf, field::ANGLE, h.0.to_le_bytes());
                0x08
            }
            GimbalCommand::Pitch(p) => {
                buf[field::MODE] = ANGLE_PITCH;
                put_2!(buf, field::ANGLE, p.0.to_le_bytes());
                0x08
            }
            GimbalCommand::ZoomRatio(z) => {
                buf[field::MODE] = ANGLE_ZOOM;
                put_2!(buf, field::ANGLE, z.0.to_le_bytes());
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
            Command::Gimbal(GimbalCommand::Heading(h)) => (u32::from(ANGLE_HEADING), h.0),
            Command::Gimbal(GimbalCommand::Pitch(p)) => (u32::from(ANGLE_PITCH), p.0 as u16),
            Command::Gimbal(GimbalCommand::ZoomRatio(z)) => (u32::from(ANGLE_ZOOM), z.0),
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
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn g(c: GimbalCommand) -> Command {
        Command::Gimbal(c)
    }

    fn d(c: DualLightCommand) -> Command {
        Command::DualLight(c)
    }

    fn nz(n: u8) -> NonZeroU8 {
        NonZeroU8::new(n).unwrap()
    }

    /// Encodes to exactly `bytes`, and `bytes` decodes to exactly the command.
    #[track_caller]
    fn assert_vector(cmd: Command, bytes: [u8; 8]) {
        assert_eq!(cmd.encode(), bytes, "encode {cmd:?}");
        assert_eq!(Command::decode(&bytes), Ok(cmd), "decode {bytes:02X?}");
        let frame = cmd.to_frame();
        assert_eq!((frame.id, frame.data), (0x0000_0F01, bytes));
    }

    #[test]
    fn command_keeps_no_tag_of_its_own() {
        // `GimbalCommand`'s word-sized tag leaves room for the dual-light commands beside
        // it; if `Command` grew a tag again, `encode`'s angle path would load it too.
        assert_eq!(
            core::mem::size_of::<Command>(),
            core::mem::size_of::<GimbalCommand>()
        );
    }

    #[test]
    fn notes_vectors() {
        // the protocol notes / section 2.2.1 of the document, byte for byte.
        assert_vector(
            g(GimbalCommand::Rate(Rate::new(-5.0, 0.0).unwrap())),
            [0x0F, 0x04, 0x0C, 0xFE, 0x00, 0x00, 0x00, 0x00],
        );
        assert_vector(
            g(GimbalCommand::Rate(Rate::new(0.0, 5.0).unwrap())),
            [0x0F, 0x04, 0x00, 0x00, 0xF4, 0x01, 0x00, 0x00],
        );
        assert_vector(
            g(GimbalCommand::Heading(Heading::new(45.0).unwrap())),
            [0x0F, 0x08, 0x01, 0xC2, 0x01, 0x00, 0x00, 0x00],
        );
        assert_vector(
            g(GimbalCommand::Pitch(Pitch::new(-45.0).unwrap())),
            [0x0F, 0x08, 0x02, 0x3E, 0xFE, 0x00, 0x00, 0x00],
        );
        assert_vector(
            g(GimbalCommand::ZoomRatio(ZoomRatio::new(10.0).unwrap())),
            [0x0F, 0x08, 0x03, 0xE8, 0x03, 0x00, 0x00, 0x00],
        );
        assert_vector(
            g(GimbalCommand::Photo(Photo::Single)),
            [0x0F, 0x10, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00],
        );
        assert_vector(
            g(GimbalCommand::Video(Video::Start)),
            [0x0F, 0x11, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00],
        );
        assert_vector(
            g(GimbalCommand::NoseFollowing),
            [0x0F, 0x02, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00],
        );
        // The look-down frame inside the protocol notes' TCP reference vector.
        assert_vector(
            g(GimbalCommand::LookDown),
            [0x0F, 0x07, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00],
        );
    }

    #[test]
    fn gimbal_vectors() {
        use GimbalCommand as G;
        // (-1234, 10000): -1234 = 0xFB2E, 10000 = 0x2710.
        let offset = ImageOffset::new(-1234, 10000).unwrap();
        assert_vector(
            g(G::PointingZoom(offset)),
            [0x0F, 0x01, 0x2E, 0xFB, 0x10, 0x27, 0, 0],
        );
        let corner = ImageOffset::new(-10000, -10000).unwrap();
        assert_vector(
            g(G::PointingZoom(corner)),
            [0x0F, 0x01, 0xF0, 0xD8, 0xF0, 0xD8, 0, 0],
        );
        assert_vector(g(G::Recenter), [0x0F, 0x03, 0, 0, 0, 0, 0, 0]);
        // 100 deg/s right = 10000 = 0x2710; -100 deg/s down = -10000 = 0xD8F0.
        assert_vector(
            g(G::Rate(Rate::new(100.0, -100.0).unwrap())),
            [0x0F, 0x04, 0x10, 0x27, 0xF0, 0xD8, 0, 0],
        );
        // Centre (4096, 8191) = 0x1000, 0x1FFF; 160 x 48 units = 10, 3 sixteenths.
        let bx = TrackingBox::new(ImagePoint::new(4096, 8191).unwrap(), 160.0, 48.0).unwrap();
        assert_vector(
            g(G::StartTracking(bx)),
            [0x0F, 0x05, 0x00, 0x10, 0xFF, 0x1F, 0x0A, 0x03],
        );
        let max = TrackingBox::new(ImagePoint::new(0, 0).unwrap(), 4080.0, 0.0).unwrap();
        assert_vector(
            g(G::StartTracking(max)),
            [0x0F, 0x05, 0, 0, 0, 0, 0xFF, 0x00],
        );
        assert_vector(g(G::StopTracking), [0x0F, 0x06, 0, 0, 0, 0, 0, 0]);
        // 360 deg = 3600 = 0x0E10; 0 deg.
        assert_vector(
            g(G::Heading(Heading::new(360.0).unwrap())),
            [0x0F, 0x08, 0x01, 0x10, 0x0E, 0, 0, 0],
        );
        assert_vector(
            g(G::Heading(Heading::new(0.0).unwrap())),
            [0x0F, 0x08, 0x01, 0x00, 0x00, 0, 0, 0],
        );
        // -100 deg = -1000 = 0xFC18; 60 deg = 600 = 0x0258.
        assert_vector(
            g(G::Pitch(Pitch::new(-100.0).unwrap())),
            [0x0F, 0x08, 0x02, 0x18, 0xFC, 0, 0, 0],
        );
        assert_vector(
            g(G::Pitch(Pitch::new(60.0).unwrap())),
            [0x0F, 0x08, 0x02, 0x58, 0x02, 0, 0, 0],
        );
        // 1x = 100 = 0x0064; 35x = 3500 = 0x0DAC.
        assert_vector(
            g(G::ZoomRatio(ZoomRatio::new(1.0).unwrap())),
            [0x0F, 0x08, 0x03, 0x64, 0x00, 0, 0, 0],
        );
        assert_vector(
            g(G::ZoomRatio(ZoomRatio::new(35.0).unwrap())),
            [0x0F, 0x08, 0x03, 0xAC, 0x0D, 0, 0, 0],
        );
        assert_vector(
            g(G::Photo(Photo::burst(3).unwrap())),
            [0x0F, 0x10, 0x02, 0x03, 0, 0, 0, 0],
        );
        assert_vector(
            g(G::Photo(Photo::time_lapse(255).unwrap())),
            [0x0F, 0x10, 0x03, 0xFF, 0, 0, 0, 0],
        );
        assert_vector(
            g(G::Photo(Photo::timer(10).unwrap())),
            [0x0F, 0x10, 0x04, 0x0A, 0, 0, 0, 0],
        );
        assert_vector(g(G::Photo(Photo::Stop)), [0x0F, 0x10, 0x05, 0, 0, 0, 0, 0]);
        assert_vector(g(G::Video(Video::Stop)), [0x0F, 0x11, 0x02, 0, 0, 0, 0, 0]);
        for (zoom, code) in [
            (Zoom::In, 1),
            (Zoom::Out, 2),
            (Zoom::Stop, 3),
            (Zoom::Reset, 4),
            (Zoom::Double, 5),
            (Zoom::Half, 6),
        ] {
            assert_vector(g(G::Zoom(zoom)), [0x0F, 0x12, code, 0, 0, 0, 0, 0]);
        }
        for (focus, code) in [
            (Focus::Plus, 1),
            (Focus::Minus, 2),
            (Focus::Stop, 3),
            (Focus::Auto, 4),
        ] {
            assert_vector(g(G::Focus(focus)), [0x0F, 0x13, code, 0, 0, 0, 0, 0]);
        }
        // (300, 8000) = 0x012C, 0x1F40; DATA5 = DATA6 = 25 = 0x19.
        assert_vector(
            g(G::PointingFocus(ImagePoint::new(300, 8000).unwrap())),
            [0x0F, 0x14, 0x2C, 0x01, 0x40, 0x1F, 0x19, 0x19],
        );
        assert_vector(g(G::FastCalibration), [0x0F, 0xF0, 0, 0, 0, 0, 0, 0]);
    }

    #[test]
    fn dual_light_vectors() {
        use DualLightCommand as D;
        let offset = ImageOffset::new(10000, -1).unwrap();
        assert_vector(
            d(D::PointingZoom(offset)),
            [0x1F, 0x01, 0x10, 0x27, 0xFF, 0xFF, 0, 0],
        );
        assert_vector(
            d(D::Palette(Palette::IceBlue)),
            [0x1F, 0x02, 0x0A, 0, 0, 0, 0, 0],
        );
        assert_vector(
            d(D::Palette(Palette::BlackHot)),
            [0x1F, 0x02, 0x00, 0, 0, 0, 0, 0],
        );
        assert_vector(
            d(D::Palette(Palette::ColdBlue)),
            [0x1F, 0x02, 0x0E, 0, 0, 0, 0, 0],
        );
        // Left 5 deg/s and up 5 deg/s, as on the gimbal.
        assert_vector(
            d(D::Rate(Rate::new(-5.0, 5.0).unwrap())),
            [0x1F, 0x04, 0x0C, 0xFE, 0xF4, 0x01, 0, 0],
        );
        let bx = TrackingBox::new(ImagePoint::new(1, 2).unwrap(), 16.0, 4080.0).unwrap();
        assert_vector(
            d(D::StartTracking(bx)),
            [0x1F, 0x05, 0x01, 0x00, 0x02, 0x00, 0x01, 0xFF],
        );
        assert_vector(d(D::StopTracking), [0x1F, 0x07, 0, 0, 0, 0, 0, 0]);
        for (ez, code) in [
            (ElectronicZoom::In, 1),
            (ElectronicZoom::Out, 2),
            (ElectronicZoom::Stop, 3),
        ] {
            assert_vector(d(D::ElectronicZoom(ez)), [0x1F, 0x12, code, 0, 0, 0, 0, 0]);
        }
    }

    #[test]
    fn palettes() {
        let names = [
            "black-hot",
            "white-hot",
            "iron-red",
            "rainbow",
            "lava",
            "rainbow-enhanced",
            "molten-metal",
            "bluish-red",
            "amber",
            "amber-inverted",
            "ice-blue",
            "high-contrast",
            "grayscale-inverted",
            "hot-red",
            "cold-blue",
        ];
        for (i, (p, name)) in Palette::ALL.into_iter().zip(names).enumerate() {
            assert_eq!(usize::from(p.code()), i);
            assert_eq!(Palette::from_code(i as u8), Some(p));
            assert_eq!(p.name(), name);
            assert_eq!(Palette::from_name(name), Some(p));
            assert_eq!(std::format!("{p}"), name);
        }
        assert_eq!(Palette::IceBlue.code(), 0x0A);
        assert_eq!(Palette::HotRed.code(), 0x0D);
        assert_eq!(Palette::from_code(0x0F), None);
        assert_eq!(Palette::from_name("Ice-Blue"), None);
        assert_eq!(Palette::from_name(""), None);
    }

    #[test]
    fn peripheral_codes() {
        assert_eq!(Peripheral::Gimbal.code(), 0x0F);
        assert_eq!(Peripheral::DualLight.code(), 0x1F);
        for code in 0..=u8::MAX {
            let p = Peripheral::from_code(code);
            assert_eq!(p.is_some(), code == 0x0F || code == 0x1F);
            if let Some(p) = p {
                assert_eq!(p.code(), code);
            }
        }
        assert_eq!(g(GimbalCommand::Recenter).peripheral(), Peripheral::Gimbal);
        assert_eq!(
            d(DualLightCommand::StopTracking).peripheral(),
            Peripheral::DualLight
        );
        assert_eq!(Command::ID, ids::CONTROL);
    }

    #[test]
    fn is_pointing() {
        use DualLightCommand as D;
        use GimbalCommand as G;
        let o = ImageOffset::CENTRE;
        let p = ImagePoint::new(0, 0).unwrap();
        let bx = TrackingBox::from_raw(p, 1, 1);
        let pointing = [
            g(G::PointingZoom(o)),
            g(G::NoseFollowing),
            g(G::Recenter),
            g(G::Rate(Rate::ZERO)),
            g(G::StartTracking(bx)),
            g(G::LookDown),
            g(G::Heading(Heading::from_deci(0).unwrap())),
            g(G::Pitch(Pitch::from_deci(0).unwrap())),
            d(D::PointingZoom(o)),
            d(D::Rate(Rate::ZERO)),
            d(D::StartTracking(bx)),
        ];
        let other = [
            g(G::StopTracking),
            g(G::ZoomRatio(ZoomRatio::from_centi(100).unwrap())),
            g(G::Photo(Photo::Single)),
            g(G::Video(Video::Start)),
            g(G::Zoom(Zoom::In)),
            g(G::Focus(Focus::Auto)),
            g(G::PointingFocus(p)),
            g(G::FastCalibration),
            d(D::Palette(Palette::Lava)),
            d(D::StopTracking),
            d(D::ElectronicZoom(ElectronicZoom::In)),
        ];
        for c in pointing {
            assert!(c.is_pointing(), "{c:?}");
        }
        for c in other {
            assert!(!c.is_pointing(), "{c:?}");
        }
    }

    #[test]
    fn rejections() {
        let err = |b: &[u8]| Command::decode(b).unwrap_err();
        let unknown_peripheral = [0x2F, 0x02, 0, 0, 0, 0, 0, 0];
        assert_eq!(
            err(&unknown_peripheral),
            DecodeError::UnknownPeripheral {
                data: unknown_peripheral
            }
        );
        for bytes in [
            [0x0F, 0x09, 0, 0, 0, 0, 0, 0],
            [0x0F, 0x00, 0, 0, 0, 0, 0, 0],
            [0x0F, 0xFF, 0, 0, 0, 0, 0, 0],
            // Stop tracking is 0x07 on the dual-light camera; 0x06 is nothing there.
            [0x1F, 0x06, 0, 0, 0, 0, 0, 0],
            [0x1F, 0x03, 0, 0, 0, 0, 0, 0],
            [0x1F, 0x10, 0x01, 0, 0, 0, 0, 0],
            [0x1F, 0xF0, 0, 0, 0, 0, 0, 0],
        ] {
            assert_eq!(err(&bytes), DecodeError::UnknownCommand { data: bytes });
        }
        for bytes in [
            [0x0F, 0x02, 0x01, 0, 0, 0, 0, 0],
            [0x0F, 0x07, 0, 0, 0, 0, 0, 0x01],
            [0x1F, 0x07, 0, 0, 0, 0, 0x80, 0],
            [0x0F, 0x04, 0x0C, 0xFE, 0, 0, 0x01, 0],
            [0x0F, 0x08, 0x01, 0xC2, 0x01, 0x01, 0, 0],
            [0x0F, 0x10, 0x01, 0x03, 0, 0, 0, 0],
            [0x0F, 0x10, 0x02, 0x03, 0x01, 0, 0, 0],
            [0x0F, 0x11, 0x01, 0, 0, 0, 0, 0xFF],
            [0x1F, 0x02, 0x0A, 0x01, 0, 0, 0, 0],
            [0x1F, 0x12, 0x01, 0, 0, 0x01, 0, 0],
            [0x0F, 0x01, 0, 0, 0, 0, 0x01, 0],
        ] {
            assert_eq!(err(&bytes), DecodeError::NonZeroPadding { data: bytes });
        }
        let invalid = |bytes: [u8; 8], field: &'static str| {
            assert_eq!(
                err(&bytes),
                DecodeError::InvalidValue { data: bytes, field },
                "{bytes:02X?}"
            );
        };
        // Heading 3601, pitch 601 and -1001, zoom 99 and 3501, angle types 0, 4, 7.
        invalid([0x0F, 0x08, 0x01, 0x11, 0x0E, 0, 0, 0], "heading");
        invalid([0x0F, 0x08, 0x01, 0xFF, 0xFF, 0, 0, 0], "heading");
        invalid([0x0F, 0x08, 0x02, 0x59, 0x02, 0, 0, 0], "pitch");
        invalid([0x0F, 0x08, 0x02, 0x17, 0xFC, 0, 0, 0], "pitch");
        invalid([0x0F, 0x08, 0x03, 0x63, 0x00, 0, 0, 0], "zoom_ratio");
        invalid([0x0F, 0x08, 0x03, 0xAD, 0x0D, 0, 0, 0], "zoom_ratio");
        invalid([0x0F, 0x08, 0x00, 0, 0, 0, 0, 0], "angle_type");
        invalid([0x0F, 0x08, 0x04, 0x64, 0, 0, 0, 0], "angle_type");
        invalid([0x0F, 0x08, 0x07, 0, 0, 0, 0, 0], "angle_type");
        // Rates 10001 and -10001.
        invalid([0x0F, 0x04, 0x11, 0x27, 0, 0, 0, 0], "yaw_rate");
        invalid([0x1F, 0x04, 0, 0, 0xEF, 0xD8, 0, 0], "pitch_rate");
        // Offsets 10001, -10001 and i16::MIN.
        invalid([0x0F, 0x01, 0x11, 0x27, 0, 0, 0, 0], "x");
        invalid([0x1F, 0x01, 0, 0, 0xEF, 0xD8, 0, 0], "y");
        invalid([0x0F, 0x01, 0x00, 0x80, 0, 0, 0, 0], "x");
        // Image points 8192.
        invalid([0x0F, 0x05, 0x00, 0x20, 0, 0, 1, 1], "x");
        invalid([0x1F, 0x05, 0, 0, 0x00, 0x20, 1, 1], "y");
        invalid([0x0F, 0x14, 0x00, 0x20, 0, 0, 25, 25], "x");
        // Pointing focus must carry 25, 25.
        invalid([0x0F, 0x14, 0, 0, 0, 0, 0, 0], "focus_box");
        invalid([0x0F, 0x14, 0, 0, 0, 0, 25, 24], "focus_box");
        invalid([0x0F, 0x14, 0, 0, 0, 0, 26, 25], "focus_box");
        // Photo: unknown modes and zero parameters.
        invalid([0x0F, 0x10, 0x09, 0, 0, 0, 0, 0], "photo_mode");
        invalid([0x0F, 0x10, 0x00, 0, 0, 0, 0, 0], "photo_mode");
        invalid([0x0F, 0x10, 0x06, 0x01, 0, 0, 0, 0], "photo_mode");
        invalid([0x0F, 0x10, 0x02, 0x00, 0, 0, 0, 0], "count");
        invalid([0x0F, 0x10, 0x03, 0x00, 0, 0, 0, 0], "seconds");
        invalid([0x0F, 0x10, 0x04, 0x00, 0, 0, 0, 0], "seconds");
        // Sub-codes one past the end, and zero.
        invalid([0x0F, 0x11, 0x03, 0, 0, 0, 0, 0], "video_mode");
        invalid([0x0F, 0x11, 0x00, 0, 0, 0, 0, 0], "video_mode");
        invalid([0x0F, 0x12, 0x07, 0, 0, 0, 0, 0], "zoom_mode");
        invalid([0x0F, 0x12, 0x00, 0, 0, 0, 0, 0], "zoom_mode");
        invalid([0x0F, 0x13, 0x05, 0, 0, 0, 0, 0], "focus_mode");
        invalid([0x1F, 0x12, 0x04, 0, 0, 0, 0, 0], "electronic_zoom_mode");
        invalid([0x1F, 0x02, 0x0F, 0, 0, 0, 0, 0], "palette");
        // An invalid value is reported before non-zero padding.
        invalid([0x0F, 0x08, 0x07, 0, 0, 0, 0, 0xFF], "angle_type");

        let ok = [0x0F, 0x07, 0, 0, 0, 0, 0, 0];
        assert_eq!(err(&ok[..7]), DecodeError::WrongLength { len: 7 });
        assert_eq!(
            err(&[0x0F, 0x07, 0, 0, 0, 0, 0, 0, 0]),
            DecodeError::WrongLength { len: 9 }
        );
        assert_eq!(err(&[]), DecodeError::WrongLength { len: 0 });
        assert!(Command::decode(&ok).is_ok());
    }

    #[test]
    fn decode_error_display_and_data() {
        let e = DecodeError::InvalidValue {
            data: [0x0F, 0x10, 0x09, 0, 0, 0, 0, 0],
            field: "photo_mode",
        };
        assert_eq!(
            std::format!("{e}"),
            "control frame [0F, 10, 09, 00, 00, 00, 00, 00]: invalid photo_mode"
        );
        assert_eq!(e.data(), Some(&[0x0F, 0x10, 0x09, 0, 0, 0, 0, 0]));
        let e = DecodeError::WrongLength { len: 7 };
        assert_eq!(std::format!("{e}"), "control frame must be 8 bytes, got 7");
        assert_eq!(e.data(), None);
    }

    #[test]
    fn rounding_to_nearest() {
        // Binary-exact halves round away from zero.
        assert_eq!(Pitch::new(-0.25).unwrap().deci(), -3);
        assert_eq!(Pitch::new(0.25).unwrap().deci(), 3);
        assert_eq!(Heading::new(0.25).unwrap().deci(), 3);
        assert_eq!(ZoomRatio::new(1.125).unwrap().centi(), 113);
        let r = Rate::new(0.125, -0.125).unwrap();
        assert_eq!((r.yaw_centi(), r.pitch_centi()), (13, -13));
        // Values well clear of a half in f32.
        assert_eq!(Pitch::new(-45.04).unwrap().deci(), -450);
        assert_eq!(Pitch::new(-45.06).unwrap().deci(), -451);
        assert_eq!(Heading::new(45.04).unwrap().deci(), 450);
        assert_eq!(Heading::new(45.06).unwrap().deci(), 451);
        assert_eq!(Heading::new(359.96).unwrap().deci(), 3600);
        // The range check is on the physical value, before rounding.
        assert_rejects(Pitch::new(60.04), "pitch");
        assert_eq!(Pitch::new(59.96).unwrap().deci(), 600);
        assert_eq!(ZoomRatio::new(10.004).unwrap().centi(), 1000);
        assert_eq!(ZoomRatio::new(10.006).unwrap().centi(), 1001);
        let r = Rate::new(-5.0, 12.345_6).unwrap();
        assert_eq!((r.yaw_centi(), r.pitch_centi()), (-500, 1235));
        // Tracking box sides: nearest multiple of 16, halves up.
        let c = ImagePoint::new(0, 0).unwrap();
        let bx = TrackingBox::new(c, 8.0, 23.9).unwrap();
        assert_eq!((bx.width16(), bx.height16()), (1, 1));
        let bx = TrackingBox::new(c, 7.9, 24.0).unwrap();
        assert_eq!((bx.width16(), bx.height16()), (0, 2));
        assert_eq!((bx.width(), bx.height()), (0, 32));
        let bx = TrackingBox::new(c, 4079.9, 4072.0).unwrap();
        assert_eq!((bx.width16(), bx.height16()), (255, 255));
        assert_eq!((bx.width(), bx.height()), (4080, 4080));
    }

    #[test]
    fn accessors() {
        let r = Rate::new(-5.0, 0.5).unwrap();
        assert_eq!((r.yaw_dps(), r.pitch_dps()), (-5.0, 0.5));
        assert!(!r.is_zero());
        assert!(Rate::ZERO.is_zero());
        assert_eq!(Rate::new(0.004, -0.004).unwrap(), Rate::ZERO);
        assert_eq!(Rate::from_centi(-500, 50).unwrap(), r);
        assert_eq!(Heading::from_deci(450).unwrap().degrees(), 45.0);
        assert_eq!(Pitch::from_deci(-450).unwrap().degrees(), -45.0);
        assert_eq!(ZoomRatio::from_centi(1000).unwrap().ratio(), 10.0);
        let o = ImageOffset::new(-3, 4).unwrap();
        assert_eq!((o.x(), o.y()), (-3, 4));
        let p = ImagePoint::new(8191, 7).unwrap();
        assert_eq!((p.x(), p.y()), (8191, 7));
        let bx = TrackingBox::from_raw(p, 2, 3);
        assert_eq!(bx.centre(), p);
        assert_eq!((bx.width(), bx.height()), (32, 48));
        assert_eq!(Photo::burst(3).unwrap(), Photo::Burst(nz(3)));
        assert_eq!(Photo::time_lapse(1).unwrap(), Photo::TimeLapse(nz(1)));
        assert_eq!(Photo::timer(255).unwrap(), Photo::Timer(nz(255)));
        assert_eq!(
            Command::from(GimbalCommand::LookDown),
            Command::Gimbal(GimbalCommand::LookDown)
        );
        assert_eq!(
            Command::from(DualLightCommand::StopTracking),
            Command::DualLight(DualLightCommand::StopTracking)
        );
    }

    #[track_caller]
    fn assert_rejects<T: fmt::Debug>(r: Result<T, RangeError>, field: &str) {
        match r {
            Err(e) => assert_eq!(e.field, field),
            Ok(v) => panic!("{field}: accepted {v:?}"),
        }
    }

    #[test]
    fn constructors_bounds() {
        let bad = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY];
        // Each f32 constructor: (accepts?, inclusive bounds, just-outside values).
        for v in bad.into_iter().chain([60.06, -100.06, 60.01, -100.01]) {
            assert_rejects(Pitch::new(v), "pitch");
        }
        assert_eq!(Pitch::new(60.0).unwrap().deci(), 600);
        assert_eq!(Pitch::new(-100.0).unwrap().deci(), -1000);
        for v in bad.into_iter().chain([360.01, -0.01, 360.06]) {
            assert_rejects(Heading::new(v), "heading");
        }
        assert_eq!(Heading::new(360.0).unwrap().deci(), 3600);
        assert_eq!(Heading::new(-0.0).unwrap().deci(), 0);
        for v in bad.into_iter().chain([0.99, 35.01, 0.0, -1.0]) {
            assert_rejects(ZoomRatio::new(v), "zoom_ratio");
        }
        assert_eq!(ZoomRatio::new(1.0).unwrap().centi(), 100);
        assert_eq!(ZoomRatio::new(35.0).unwrap().centi(), 3500);
        for v in bad.into_iter().chain([100.01, -100.01]) {
            assert_rejects(Rate::new(v, 0.0), "yaw_rate");
            assert_rejects(Rate::new(0.0, v), "pitch_rate");
        }
        let r = Rate::new(100.0, -100.0).unwrap();
        assert_eq!((r.yaw_centi(), r.pitch_centi()), (10000, -10000));
        let r = Rate::new(-100.0, 100.0).unwrap();
        assert_eq!((r.yaw_centi(), r.pitch_centi()), (-10000, 10000));
        let c = ImagePoint::new(0, 0).unwrap();
        for v in bad.into_iter().chain([4080.01, -0.01, 4088.0]) {
            assert_rejects(TrackingBox::new(c, v, 0.0), "width");
            assert_rejects(TrackingBox::new(c, 0.0, v), "height");
        }
        assert!(TrackingBox::new(c, 4080.0, 4080.0).is_ok());
        assert!(TrackingBox::new(c, 0.0, 0.0).is_ok());

        // Wire-unit constructors.
        for v in [10001, -10001, i16::MIN, i16::MAX] {
            assert_rejects(Rate::from_centi(v, 0), "yaw_rate");
            assert_rejects(Rate::from_centi(0, v), "pitch_rate");
        }
        assert!(Rate::from_centi(10000, -10000).is_ok());
        assert_rejects(Heading::from_deci(3601), "heading");
        assert!(Heading::from_deci(3600).is_ok());
        assert_rejects(Pitch::from_deci(601), "pitch");
        assert_rejects(Pitch::from_deci(-1001), "pitch");
        assert!(Pitch::from_deci(600).is_ok() && Pitch::from_deci(-1000).is_ok());
        assert_rejects(ZoomRatio::from_centi(99), "zoom_ratio");
        assert_rejects(ZoomRatio::from_centi(3501), "zoom_ratio");
        assert!(ZoomRatio::from_centi(100).is_ok() && ZoomRatio::from_centi(3500).is_ok());

        // Integer constructors.
        for v in [10001, -10001, i32::MIN, i32::MAX] {
            assert_rejects(ImageOffset::new(v, 0), "x");
            assert_rejects(ImageOffset::new(0, v), "y");
        }
        assert!(ImageOffset::new(10000, -10000).is_ok());
        assert!(ImageOffset::new(-10000, 10000).is_ok());
        for v in [-1, 8192, i32::MIN, i32::MAX] {
            assert_rejects(ImagePoint::new(v, 0), "x");
            assert_rejects(ImagePoint::new(0, v), "y");
        }
        assert!(ImagePoint::new(8191, 0).is_ok() && ImagePoint::new(0, 8191).is_ok());
        for v in [0, 256, u32::MAX] {
            assert_rejects(Photo::burst(v), "count");
            assert_rejects(Photo::time_lapse(v), "seconds");
            assert_rejects(Photo::timer(v), "seconds");
        }
        for v in [1, 255] {
            assert!(Photo::burst(v).is_ok());
            assert!(Photo::time_lapse(v).is_ok());
            assert!(Photo::timer(v).is_ok());
        }
    }

    #[test]
    fn range_errors_are_in_physical_units() {
        let e = Pitch::from_deci(601).unwrap_err();
        assert_eq!((e.field, e.min, e.max), ("pitch", -100.0, 60.0));
        assert!((e.value - 60.1).abs() < 1e-9);
        let e = Rate::from_centi(0, -10001).unwrap_err();
        assert_eq!(
            (e.field, e.value, e.min, e.max),
            ("pitch_rate", -100.01, -100.0, 100.0)
        );
        let e = Photo::burst(0).unwrap_err();
        assert_eq!((e.field, e.value, e.min, e.max), ("count", 0.0, 1.0, 255.0));
        let e = Pitch::new(f32::NAN).unwrap_err();
        assert!(e.is_not_finite());
    }

    fn arb_rate() -> impl Strategy<Value = Rate> {
        (-10000i16..=10000, -10000i16..=10000).prop_map(|(y, p)| Rate::from_centi(y, p).unwrap())
    }

    fn arb_offset() -> impl Strategy<Value = ImageOffset> {
        (-10000i32..=10000, -10000i32..=10000).prop_map(|(x, y)| ImageOffset::new(x, y).unwrap())
    }

    fn arb_point() -> impl Strategy<Value = ImagePoint> {
        (0i32..=8191, 0i32..=8191).prop_map(|(x, y)| ImagePoint::new(x, y).unwrap())
    }

    fn arb_box() -> impl Strategy<Value = TrackingBox> {
        (arb_point(), any::<u8>(), any::<u8>()).prop_map(|(c, w, h)| TrackingBox::from_raw(c, w, h))
    }

    fn arb_photo() -> impl Strategy<Value = Photo> {
        prop_oneof![
            Just(Photo::Single),
            Just(Photo::Stop),
            (1u32..=255).prop_map(|n| Photo::burst(n).unwrap()),
            (1u32..=255).prop_map(|n| Photo::time_lapse(n).unwrap()),
            (1u32..=255).prop_map(|n| Photo::timer(n).unwrap()),
        ]
    }

    fn arb_gimbal() -> impl Strategy<Value = GimbalCommand> {
        use GimbalCommand as G;
        prop_oneof![
            arb_offset().prop_map(G::PointingZoom),
            Just(G::NoseFollowing),
            Just(G::Recenter),
            arb_rate().prop_map(G::Rate),
            arb_box().prop_map(G::StartTracking),
            Just(G::StopTracking),
            Just(G::LookDown),
            (0u16..=3600).prop_map(|v| G::Heading(Heading::from_deci(v).unwrap())),
            (-1000i16..=600).prop_map(|v| G::Pitch(Pitch::from_deci(v).unwrap())),
            (100u16..=3500).prop_map(|v| G::ZoomRatio(ZoomRatio::from_centi(v).unwrap())),
            arb_photo().prop_map(G::Photo),
            prop::sample::select(&[Video::Start, Video::Stop][..]).prop_map(G::Video),
            prop::sample::select(
                &[
                    Zoom::In,
                    Zoom::Out,
                    Zoom::Stop,
                    Zoom::Reset,
                    Zoom::Double,
                    Zoom::Half
                ][..]
            )
            .prop_map(G::Zoom),
            prop::sample::select(&[Focus::Plus, Focus::Minus, Focus::Stop, Focus::Auto][..])
                .prop_map(G::Focus),
            arb_point().prop_map(G::PointingFocus),
            Just(G::FastCalibration),
        ]
    }

    fn arb_dual_light() -> impl Strategy<Value = DualLightCommand> {
        use DualLightCommand as D;
        prop_oneof![
            arb_offset().prop_map(D::PointingZoom),
            prop::sample::select(&Palette::ALL[..]).prop_map(D::Palette),
            arb_rate().prop_map(D::Rate),
            arb_box().prop_map(D::StartTracking),
            Just(D::StopTracking),
            prop::sample::select(
                &[
                    ElectronicZoom::In,
                    ElectronicZoom::Out,
                    ElectronicZoom::Stop
                ][..]
            )
            .prop_map(D::ElectronicZoom),
        ]
    }

    fn arb_command() -> impl Strategy<Value = Command> {
        prop_oneof![
            arb_gimbal().prop_map(Command::Gimbal),
            arb_dual_light().prop_map(Command::DualLight),
        ]
    }

    /// Frames biased towards valid ones: known peripherals and commands, small sub-codes,
    /// zero bytes, and the bytes of real commands with one byte changed.
    fn arb_frame() -> impl Strategy<Value = [u8; 8]> {
        let byte = prop_oneof![3 => Just(0u8), 2 => 0u8..8, 1 => Just(25u8), 2 => any::<u8>()];
        let cmd = prop_oneof![
            prop::sample::select(
                &[
                    0x01u8, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08, 0x10, 0x11, 0x12, 0x13, 0x14,
                    0xF0
                ][..]
            ),
            any::<u8>(),
        ];
        let peripheral = prop_oneof![4 => Just(0x0Fu8), 4 => Just(0x1F), 1 => any::<u8>()];
        let built = (
            peripheral,
            cmd,
            [
                byte.clone(),
                byte.clone(),
                byte.clone(),
                byte.clone(),
                byte.clone(),
                byte,
            ],
        )
            .prop_map(|(p, c, [d1, d2, d3, d4, d5, d6])| [p, c, d1, d2, d3, d4, d5, d6]);
        let mutated = (arb_command(), 0usize..8, any::<u8>()).prop_map(|(c, i, b)| {
            let mut bytes = c.encode();
            bytes[i] = b;
            bytes
        });
        prop_oneof![built, mutated]
    }

    proptest! {
        /// `encode`'s constant-and-or path for the angle commands writes what the field
        /// writer does, for every command.
        #[test]
        fn encode_equals_the_field_writer(cmd in arb_command()) {
            prop_assert_eq!(cmd.encode(), cmd.encode_fields().to_le_bytes());
        }

        #[test]
        fn encode_decode_round_trip(cmd in arb_command()) {
            let bytes = cmd.encode();
            prop_assert_eq!(bytes[0], cmd.peripheral().code());
            prop_assert_eq!(Command::decode(&bytes), Ok(cmd));
            prop_assert_eq!(cmd.to_frame(), Frame::new(0x0F01, bytes));
        }

        #[test]
        fn decode_encode_round_trip(bytes in arb_frame()) {
            if let Ok(cmd) = Command::decode(&bytes) {
                prop_assert_eq!(cmd.encode(), bytes);
            }
        }

        #[test]
        fn decode_any_bytes_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..16)) {
            match Command::decode(&bytes) {
                Err(DecodeError::WrongLength { len }) => {
                    prop_assert_eq!(len, bytes.len());
                    prop_assert_ne!(len, 8);
                }
                Err(e) => {
                    prop_assert_eq!(bytes.len(), 8);
                    prop_assert_eq!(e.data().map(|d| &d[..]), Some(&bytes[..]));
                }
                Ok(cmd) => prop_assert_eq!(&cmd.encode()[..], &bytes[..]),
            }
        }

        #[test]
        fn pitch_accepts_exactly_its_range(v in any::<f32>()) {
            let r = Pitch::new(v);
            prop_assert_eq!(r.is_ok(), (-100.0..=60.0).contains(&v));
            if let Ok(p) = r {
                prop_assert_eq!(p.deci(), libm::roundf(v * 10.0) as i16);
            }
        }

        #[test]
        fn heading_accepts_exactly_its_range(v in any::<f32>()) {
            let r = Heading::new(v);
            prop_assert_eq!(r.is_ok(), (0.0..=360.0).contains(&v));
            if let Ok(h) = r {
                prop_assert_eq!(h.deci(), libm::roundf(v * 10.0) as u16);
            }
        }

        #[test]
        fn zoom_ratio_accepts_exactly_its_range(v in any::<f32>()) {
            let r = ZoomRatio::new(v);
            prop_assert_eq!(r.is_ok(), (1.0..=35.0).contains(&v));
            if let Ok(z) = r {
                prop_assert_eq!(z.centi(), libm::roundf(v * 100.0) as u16);
            }
        }

        #[test]
        fn rate_accepts_exactly_its_range(y in any::<f32>(), p in -100.0f32..=100.0) {
            let r = Rate::new(y, p);
            prop_assert_eq!(r.is_ok(), (-100.0..=100.0).contains(&y));
            if let Ok(r) = r {
                prop_assert_eq!(r.yaw_centi(), libm::roundf(y * 100.0) as i16);
                prop_assert_eq!(r.pitch_centi(), libm::roundf(p * 100.0) as i16);
            }
        }

        #[test]
        fn tracking_box_accepts_exactly_its_range(w in any::<f32>(), h in 0.0f32..=4080.0) {
            let c = ImagePoint::new(1, 1).unwrap();
            let r = TrackingBox::new(c, w, h);
            prop_assert_eq!(r.is_ok(), (0.0..=4080.0).contains(&w));
            if let Ok(b) = r {
                prop_assert!((f32::from(b.width()) - w).abs() <= 8.0);
                prop_assert!((f32::from(b.height()) - h).abs() <= 8.0);
            }
        }

        #[test]
        fn integer_constructors_accept_exactly_their_range(x in any::<i32>(), n in any::<u32>()) {
            prop_assert_eq!(ImageOffset::new(x, 0).is_ok(), (-10000..=10000).contains(&x));
            prop_assert_eq!(ImagePoint::new(0, x).is_ok(), (0..=8191).contains(&x));
            prop_assert_eq!(Photo::burst(n).is_ok(), (1..=255).contains(&n));
            prop_assert_eq!(Photo::timer(n).is_ok(), (1..=255).contains(&n));
        }

        #[test]
        fn physical_accessors_round_trip(h in 0u16..=3600, p in -1000i16..=600, z in 100u16..=3500, y in -10000i16..=10000) {
            let h = Heading::from_deci(h).unwrap();
            prop_assert_eq!(Heading::new(h.degrees()), Ok(h));
            let p = Pitch::from_deci(p).unwrap();
            prop_assert_eq!(Pitch::new(p.degrees()), Ok(p));
            let z = ZoomRatio::from_centi(z).unwrap();
            prop_assert_eq!(ZoomRatio::new(z.ratio()), Ok(z));
            let r = Rate::from_centi(y, -y).unwrap();
            prop_assert_eq!(Rate::new(r.yaw_dps(), r.pitch_dps()), Ok(r));
        }
    }
}
