//! Pure codecs: bytes to typed values and back, with no state and no I/O.
//!
//! One module per protocol concept. Constructors validate physical units once, so a value
//! that exists is valid and encoding it cannot fail; decoding returns typed values, with
//! `Unknown(n)` for enum bytes that newer firmware may send.
//!
//! "The document" in these docs is the vendor's CAN protocol document (V-1.1), cited by
//! section; "the protocol notes" are the repository's `docs/protocol-notes.md`, which
//! record how each of its typos and gaps is resolved, and why. Tests take their vectors
//! from both.

use core::fmt;

/// An enum of the codes a field takes, with `Unknown(n)` for the codes the document does
/// not list (newer firmware), and `from_code` / `code` between the two: one mechanism for
/// every such field (smoltcp's `enum_with_unknown!` is the model).
macro_rules! enum_with_unknown {
    (
        $(#[$attr:meta])*
        pub enum $name:ident {
            $( $(#[$variant_attr:meta])* $variant:ident = $code:literal, )+
        }
    ) => {
        $(#[$attr])*
        pub enum $name {
            $( $(#[$variant_attr])* $variant, )+
            /// A code the document does not list (newer firmware).
            Unknown(u8),
        }

        impl $name {
            /// The value of a code; codes the document does not list become `Unknown`.
            pub const fn from_code(code: u8) -> Self {
                match code {
                    $( $code => $name::$variant, )+
                    n => $name::Unknown(n),
                }
            }

            /// The code on the wire.
            pub const fn code(self) -> u8 {
                match self {
                    $( $name::$variant => $code, )+
                    $name::Unknown(n) => n,
                }
            }
        }
    };
}

pub mod control;
pub mod crc;
pub mod ids;
pub mod postback;
pub mod serial;
pub mod text;
pub mod vehicle;

/// A CAN frame as the protocol uses it: a 29-bit extended identifier and 8 data bytes.
///
/// The link works on these so that it needs no CAN crate types; the port converts them
/// to and from its CAN driver's frame type.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Frame {
    /// The raw extended identifier (at most [`ids::EXTENDED_MAX`]).
    pub id: u32,
    /// The 8 data bytes (every frame of the protocol has DLC 8).
    pub data: [u8; 8],
}

impl Frame {
    /// A frame with the given identifier and data.
    pub const fn new(id: u32, data: [u8; 8]) -> Self {
        Frame { id, data }
    }
}

/// A physical value that a constructor rejected: not finite, or outside its valid range.
///
/// `field` names the argument as the protocol document does; `min` and `max` give the
/// valid range in the same physical unit as `value` (degrees, deg/s, zoom ratio,
/// seconds, counts or image coordinates).
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct RangeError {
    /// The rejected argument, e.g. `"pitch"`.
    pub field: &'static str,
    /// The value given (NaN or infinite when it was not finite).
    pub value: f64,
    /// The smallest valid value.
    pub min: f64,
    /// The largest valid value.
    pub max: f64,
}

impl RangeError {
    /// Checks that `value` is within `[min, max]`, one mechanism for every unit: `f32`
    /// (the cheap float path on a Cortex-M4F), `f64` (GPS coordinates, which need it) and
    /// integer wire units (decoding then needs no floating point). A NaN fails both
    /// comparisons and an infinity one of them, so neither passes. The error reports the
    /// value and the range in the caller's unit.
    #[inline]
    pub(crate) fn check<T>(field: &'static str, value: T, min: T, max: T) -> Result<T, Self>
    where
        T: PartialOrd + Copy + Into<f64>,
    {
        if value >= min && value <= max {
            Ok(value)
        } else {
            Err(RangeError {
                field,
                value: value.into(),
                min: min.into(),
                max: max.into(),
            })
        }
    }

    /// The same error in a unit `scale` times larger (wire units to physical ones).
    pub(crate) fn scaled(self, scale: f64) -> Self {
        RangeError {
            value: self.value / scale,
            min: self.min / scale,
            max: self.max / scale,
            ..self
        }
    }

    /// Whether the value was NaN or infinite rather than merely out of range.
    pub fn is_not_finite(&self) -> bool {
        !self.value.is_finite()
    }
}

impl fmt::Display for RangeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.is_not_finite() {
            write!(
                f,
                "{} must be a finite number in [{}, {}], got {}",
                self.field, self.min, self.max, self.value
            )
        } else {
            write!(
                f,
                "{} = {} is out of range [{}, {}]",
                self.field, self.value, self.min, self.max
            )
        }
    }
}

#[cfg(feature = "defmt")]
impl defmt::Format for RangeError {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(
            f,
            "{=str} = {=f64} is not in [{=f64}, {=f64}]",
            self.field,
            self.value,
            self.min,
            self.max
        )
    }
}

#[cfg(feature = "std")]
impl std::error::Error for RangeError {}

/// Rounds a scaled physical value to the nearest wire unit (half away from zero).
///
/// Callers range-check the value first, so the result fits the wire type.
pub(crate) fn round_f32(x: f32) -> f32 {
    libm::roundf(x)
}

/// Double-precision [`round_f32`].
pub(crate) fn round_f64(x: f64) -> f64 {
    libm::round(x)
}
