//! What a command carries in DATA1..DATA6: angles, rates, zoom ratios, image points and
//! boxes, photo modes, sub-codes and palettes, each checked in physical units when built
//! (the conventions are the parent module's).

use core::fmt;
use core::num::NonZeroU8;

use crate::wire::{round_f32, RangeError};

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
/// no meaning for and [`Command::decode`](super::Command::decode) rejects, cannot be built. The constructors
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
    pub(super) fn codes(self) -> (u8, u8) {
        match self {
            Photo::Single => (1, 0),
            Photo::Burst(n) => (2, n.get()),
            Photo::TimeLapse(s) => (3, s.get()),
            Photo::Timer(s) => (4, s.get()),
            Photo::Stop => (5, 0),
        }
    }

    pub(super) fn from_codes(mode: u8, param: u8) -> Result<Self, &'static str> {
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
            /// The field name [`DecodeError::InvalidValue`](super::DecodeError::InvalidValue) reports for a bad code.
            pub(super) const FIELD: &'static str = $field;

            pub(super) const fn code(self) -> u8 {
                match self {
                    $($name::$variant => $code,)+
                }
            }

            pub(super) const fn from_code(code: u8) -> Option<Self> {
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
