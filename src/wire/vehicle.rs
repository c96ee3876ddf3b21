//! Vehicle frames: what the flight controller pushes to the gimbal (section 2.3).
//!
//! | frame | CAN ID | bytes 0..=3 | bytes 4..=7 |
//! |---|---|---|---|
//! | [`Gps`] | `0x0000FF15` | latitude, i32, 1e-7° | longitude, i32, 1e-7° |
//! | [`Altitude`] | `0x0000FF16` | altitude, i32, cm | zero |
//! | [`Attitude`] | `0x0000FF13` | pitch i16, roll i16 (0.01°) | heading i16 (0.01°), zero |
//!
//! All values are little-endian two's complement. An i16 cannot hold 360.00°, so the
//! heading goes on the wire in [-180.00°, 180.00°): [`Attitude::new`] normalises any finite
//! heading into that range.
//!
//! ```
//! use idu_gimbal::wire::vehicle::{Attitude, VehicleFrame};
//! let att = Attitude::new(1.5, -2.0, 270.0)?; // 270° is sent as -90.00°
//! assert_eq!(att.heading_centideg(), -9000);
//! let frame = VehicleFrame::from(att).to_frame();
//! assert_eq!(frame.id, 0x0000_FF13);
//! assert_eq!(frame.data, [0x96, 0x00, 0x38, 0xFF, 0xD8, 0xDC, 0x00, 0x00]);
//! assert_eq!(VehicleFrame::decode(frame.id, &frame.data), Ok(VehicleFrame::Attitude(att)));
//! # Ok::<(), idu_gimbal::wire::RangeError>(())
//! ```

use core::fmt;

use super::{ids, round_f32, round_f64, Frame, RangeError};

mod field {
    use core::ops::Range;
    pub const LAT: Range<usize> = 0..4;
    pub const LON: Range<usize> = 4..8;
    pub const ALT: Range<usize> = 0..4;
    pub const ALT_PAD: Range<usize> = 4..8;
    pub const PITCH: Range<usize> = 0..2;
    pub const ROLL: Range<usize> = 2..4;
    pub const HEADING: Range<usize> = 4..6;
    pub const ATT_PAD: Range<usize> = 6..8;
}

/// Vehicle position: latitude and longitude in units of 1e-7 degree.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Gps {
    lat_e7: i32,
    lon_e7: i32,
}

impl Gps {
    /// CAN ID of the GPS frame.
    pub const ID: u32 = ids::GPS;
    /// Latitude and longitude 0 (a placeholder for storage that is not yet set).
    pub(crate) const ZERO: Gps = Gps {
        lat_e7: 0,
        lon_e7: 0,
    };

    /// A position from degrees: latitude in [-90, 90], longitude in [-180, 180].
    pub fn new(lat_deg: f64, lon_deg: f64) -> Result<Self, RangeError> {
        let lat = RangeError::check("latitude", lat_deg, -90.0, 90.0)?;
        let lon = RangeError::check("longitude", lon_deg, -180.0, 180.0)?;
        // In range, so the scaled values fit an i32 (±1.8e9 < 2^31).
        Ok(Gps {
            lat_e7: round_f64(lat * 1e7) as i32,
            lon_e7: round_f64(lon * 1e7) as i32,
        })
    }

    /// A position from wire units (1e-7 degree), validated as [`Gps::new`] does; a
    /// rejected value is reported in wire units (`latitude_e7`, `longitude_e7`).
    pub fn from_e7(lat_e7: i32, lon_e7: i32) -> Result<Self, RangeError> {
        RangeError::check("latitude_e7", lat_e7, -900_000_000, 900_000_000)?;
        RangeError::check("longitude_e7", lon_e7, -1_800_000_000, 1_800_000_000)?;
        Ok(Gps { lat_e7, lon_e7 })
    }

    /// Latitude in degrees.
    pub fn lat_deg(&self) -> f64 {
        f64::from(self.lat_e7) / 1e7
    }

    /// Longitude in degrees.
    pub fn lon_deg(&self) -> f64 {
        f64::from(self.lon_e7) / 1e7
    }

    /// Latitude in 1e-7 degree.
    pub fn lat_e7(&self) -> i32 {
        self.lat_e7
    }

    /// Longitude in 1e-7 degree.
    pub fn lon_e7(&self) -> i32 {
        self.lon_e7
    }
}

/// Vehicle altitude in centimetres.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Altitude {
    cm: i32,
}

impl Altitude {
    /// CAN ID of the altitude frame.
    pub const ID: u32 = ids::ALTITUDE;
    /// The lowest altitude the wire can carry, in metres (`i32::MIN` cm).
    pub const MIN_M: f64 = i32::MIN as f64 / 100.0;
    /// The highest altitude the wire can carry, in metres (`i32::MAX` cm).
    pub const MAX_M: f64 = i32::MAX as f64 / 100.0;

    /// An altitude from metres, within what an i32 of centimetres holds.
    pub fn new(metres: f64) -> Result<Self, RangeError> {
        let m = RangeError::check("altitude", metres, Self::MIN_M, Self::MAX_M)?;
        let cm = round_f64(m * 100.0);
        // Rounding at the very edge could step past i32; reject rather than saturate.
        if cm < f64::from(i32::MIN) || cm > f64::from(i32::MAX) {
            return Err(RangeError {
                field: "altitude",
                value: metres,
                min: Self::MIN_M,
                max: Self::MAX_M,
            });
        }
        Ok(Altitude { cm: cm as i32 })
    }

    /// An altitude from wire units (every i32 is valid).
    pub const fn from_cm(cm: i32) -> Self {
        Altitude { cm }
    }

    /// Altitude in metres.
    pub fn metres(&self) -> f64 {
        f64::from(self.cm) / 100.0
    }

    /// Altitude in centimetres.
    pub const fn cm(&self) -> i32 {
        self.cm
    }
}

/// Vehicle attitude: pitch, roll and heading in units of 0.01 degree.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Attitude {
    pitch: i16,
    roll: i16,
    heading: i16,
}

impl Attitude {
    /// CAN ID of the attitude frame.
    pub const ID: u32 = ids::ATTITUDE;
    /// Level, heading north (a placeholder for storage that is not yet set).
    pub(crate) const ZERO: Attitude = Attitude {
        pitch: 0,
        roll: 0,
        heading: 0,
    };

    /// An attitude from degrees: pitch in [-90, 90], roll in [-180, 180], heading any finite
    /// value (normalised into [-180, 180) for the wire).
    pub fn new(pitch_deg: f32, roll_deg: f32, heading_deg: f32) -> Result<Self, RangeError> {
        let pitch = RangeError::check("vehicle_pitch", pitch_deg, -90.0, 90.0)?;
        let roll = RangeError::check("vehicle_roll", roll_deg, -180.0, 180.0)?;
        if !heading_deg.is_finite() {
            return Err(RangeError {
                field: "vehicle_heading",
                value: heading_deg.into(),
                min: f64::NEG_INFINITY,
                max: f64::INFINITY,
            });
        }
        // Normalise in wire units so rounding cannot land on +180.00.
        let centi = round_f32(libm::remainderf(heading_deg, 360.0) * 100.0) as i32;
        let heading = wrap_centideg(centi);
        Ok(Attitude {
            pitch: round_f32(pitch * 100.0) as i16,
            roll: round_f32(roll * 100.0) as i16,
            heading: heading as i16,
        })
    }

    /// An attitude from wire units (0.01°), validated as [`Attitude::new`] does except that
    /// the heading must already be in [-18000, 17999]; a rejected value is reported in wire
    /// units (`vehicle_pitch_cdeg`, ...).
    pub fn from_centideg(pitch: i16, roll: i16, heading: i16) -> Result<Self, RangeError> {
        RangeError::check("vehicle_pitch_cdeg", pitch.into(), -9000, 9000)?;
        RangeError::check("vehicle_roll_cdeg", roll.into(), -18000, 18000)?;
        RangeError::check("vehicle_heading_cdeg", heading.into(), -18000, 17999)?;
        Ok(Attitude {
            pitch,
            roll,
            heading,
        })
    }

    /// Pitch in degrees.
    pub fn pitch_deg(&self) -> f32 {
        f32::from(self.pitch) / 100.0
    }

    /// Roll in degrees.
    pub fn roll_deg(&self) -> f32 {
        f32::from(self.roll) / 100.0
    }

    /// Heading in degrees, in [-180, 180).
    pub fn heading_deg(&self) -> f32 {
        f32::from(self.heading) / 100.0
    }

    /// Pitch in 0.01°.
    pub const fn pitch_centideg(&self) -> i16 {
        self.pitch
    }

    /// Roll in 0.01°.
    pub const fn roll_centideg(&self) -> i16 {
        self.roll
    }

    /// Heading in 0.01°, in [-18000, 17999].
    pub const fn heading_centideg(&self) -> i16 {
        self.heading
    }
}

/// `cdeg` (0.01°) wrapped into [-18000, 18000), the attitude's heading range. Total: the
/// remainder comes first, so no `i32` overflows on the way.
pub(crate) const fn wrap_centideg(cdeg: i32) -> i32 {
    let r = cdeg.rem_euclid(36_000);
    if r < 18_000 {
        r
    } else {
        // r in [18000, 35999]: exact.
        r.saturating_sub(36_000)
    }
}

/// Any of the three vehicle frames.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum VehicleFrame {
    /// Position.
    Gps(Gps),
    /// Altitude.
    Altitude(Altitude),
    /// Attitude.
    Attitude(Attitude),
}

impl From<Gps> for VehicleFrame {
    fn from(v: Gps) -> Self {
        VehicleFrame::Gps(v)
    }
}

impl From<Altitude> for VehicleFrame {
    fn from(v: Altitude) -> Self {
        VehicleFrame::Altitude(v)
    }
}

impl From<Attitude> for VehicleFrame {
    fn from(v: Attitude) -> Self {
        VehicleFrame::Attitude(v)
    }
}

fn put(data: &mut [u8; 8], range: core::ops::Range<usize>, bytes: &[u8]) {
    if let Some(dst) = data.get_mut(range) {
        dst.copy_from_slice(bytes);
    }
}

fn get<const N: usize>(data: &[u8; 8], range: core::ops::Range<usize>) -> [u8; N] {
    data.get(range)
        .and_then(|s| s.try_into().ok())
        .unwrap_or([0; N])
}

impl VehicleFrame {
    /// The frame's CAN ID.
    pub const fn id(&self) -> u32 {
        match self {
            VehicleFrame::Gps(_) => ids::GPS,
            VehicleFrame::Altitude(_) => ids::ALTITUDE,
            VehicleFrame::Attitude(_) => ids::ATTITUDE,
        }
    }

    /// The 8 data bytes.
    pub fn encode(&self) -> [u8; 8] {
        let mut d = [0u8; 8];
        match self {
            VehicleFrame::Gps(g) => {
                put(&mut d, field::LAT, &g.lat_e7.to_le_bytes());
                put(&mut d, field::LON, &g.lon_e7.to_le_bytes());
            }
            VehicleFrame::Altitude(a) => put(&mut d, field::ALT, &a.cm.to_le_bytes()),
            VehicleFrame::Attitude(a) => {
                put(&mut d, field::PITCH, &a.pitch.to_le_bytes());
                put(&mut d, field::ROLL, &a.roll.to_le_bytes());
                put(&mut d, field::HEADING, &a.heading.to_le_bytes());
            }
        }
        d
    }

    /// The frame: ID and data.
    pub fn to_frame(&self) -> Frame {
        Frame::new(self.id(), self.encode())
    }

    /// Decodes a frame received with CAN ID `id`.
    pub fn decode(id: u32, data: &[u8]) -> Result<Self, VehicleError> {
        let d: &[u8; 8] = data
            .try_into()
            .map_err(|_| VehicleError::WrongLength { len: data.len() })?;
        let zero = |r: core::ops::Range<usize>| d.get(r).is_some_and(|s| s.iter().all(|&b| b == 0));
        match id {
            ids::GPS => Gps::from_e7(
                i32::from_le_bytes(get(d, field::LAT)),
                i32::from_le_bytes(get(d, field::LON)),
            )
            .map(VehicleFrame::Gps)
            .map_err(VehicleError::Value),
            ids::ALTITUDE if zero(field::ALT_PAD) => Ok(VehicleFrame::Altitude(Altitude::from_cm(
                i32::from_le_bytes(get(d, field::ALT)),
            ))),
            ids::ATTITUDE if zero(field::ATT_PAD) => Attitude::from_centideg(
                i16::from_le_bytes(get(d, field::PITCH)),
                i16::from_le_bytes(get(d, field::ROLL)),
                i16::from_le_bytes(get(d, field::HEADING)),
            )
            .map(VehicleFrame::Attitude)
            .map_err(VehicleError::Value),
            ids::ALTITUDE | ids::ATTITUDE => Err(VehicleError::NonZeroPadding { id }),
            _ => Err(VehicleError::NotVehicle { id }),
        }
    }
}

/// Why bytes did not decode as a vehicle frame.
#[derive(Clone, Copy, PartialEq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum VehicleError {
    /// The CAN ID is not one of the vehicle frames'.
    NotVehicle {
        /// The ID received.
        id: u32,
    },
    /// Vehicle frames carry exactly 8 bytes.
    WrongLength {
        /// The length received.
        len: usize,
    },
    /// Bytes the document leaves unused were not zero.
    NonZeroPadding {
        /// The ID of the frame.
        id: u32,
    },
    /// A value outside its valid range.
    Value(RangeError),
}

impl fmt::Display for VehicleError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            VehicleError::NotVehicle { id } => {
                write!(
                    f,
                    "CAN ID {id:#010X} is not a vehicle frame (0x0000FF13, 0x0000FF15, 0x0000FF16)"
                )
            }
            VehicleError::WrongLength { len } => {
                write!(f, "vehicle frame has {len} bytes, expected 8")
            }
            VehicleError::NonZeroPadding { id } => {
                write!(f, "unused bytes of frame {id:#010X} are not zero")
            }
            VehicleError::Value(e) => e.fmt(f),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for VehicleError {}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn gps_bytes_by_hand() {
        // 47.3977419 N, 8.5455938 E -> 473977419 = 0x1C40_524B, 85455938 = 0x0517_F442.
        let g = Gps::new(47.3977419, 8.5455938).unwrap();
        assert_eq!((g.lat_e7(), g.lon_e7()), (473_977_419, 85_455_938));
        let f = VehicleFrame::from(g).to_frame();
        assert_eq!(f.id, 0x0000_FF15);
        assert_eq!(f.data, [0x4B, 0x52, 0x40, 0x1C, 0x42, 0xF4, 0x17, 0x05]);
        // Southern / western hemisphere: -33.8688197, -151.2092955 two's complement.
        let g = Gps::new(-33.8688197, -151.2092955).unwrap();
        assert_eq!(VehicleFrame::from(g).encode(), {
            let mut d = [0u8; 8];
            d[..4].copy_from_slice(&(-338_688_197i32).to_le_bytes());
            d[4..].copy_from_slice(&(-1_512_092_955i32).to_le_bytes());
            d
        });
    }

    #[test]
    fn altitude_bytes_by_hand() {
        // 123.45 m = 12345 cm = 0x3039.
        let f = VehicleFrame::from(Altitude::new(123.45).unwrap()).to_frame();
        assert_eq!(f.id, 0x0000_FF16);
        assert_eq!(f.data, [0x39, 0x30, 0, 0, 0, 0, 0, 0]);
        // -1 cm.
        assert_eq!(
            VehicleFrame::from(Altitude::new(-0.01).unwrap()).encode(),
            [0xFF, 0xFF, 0xFF, 0xFF, 0, 0, 0, 0]
        );
    }

    #[test]
    fn attitude_accessors_in_wire_units_and_degrees() {
        // -12.34° pitch = -1234 cdeg, 56.78° roll = 5678 cdeg, 90° heading = 9000 cdeg.
        let a = Attitude::new(-12.34, 56.78, 90.0).unwrap();
        assert_eq!(
            (a.pitch_centideg(), a.roll_centideg(), a.heading_centideg()),
            (-1234, 5678, 9000)
        );
        // Wire units straight through, and back to degrees (exact: n / 100 rounds once).
        let a = Attitude::from_centideg(-9000, 18000, -18000).unwrap();
        assert_eq!(
            (a.pitch_centideg(), a.roll_centideg(), a.heading_centideg()),
            (-9000, 18000, -18000)
        );
        assert_eq!(
            (a.pitch_deg(), a.roll_deg(), a.heading_deg()),
            (-90.0, 180.0, -180.0)
        );
    }

    #[test]
    fn attitude_heading_normalisation() {
        let h = |deg: f32| Attitude::new(0.0, 0.0, deg).unwrap().heading_centideg();
        assert_eq!(h(0.0), 0);
        assert_eq!(h(179.99), 17999);
        assert_eq!(h(180.0), -18000);
        assert_eq!(h(-180.0), -18000);
        assert_eq!(h(270.0), -9000);
        assert_eq!(h(359.999), 0); // rounds to 360.00, which is 0
        assert_eq!(h(720.5), 50);
        assert_eq!(h(-450.0), -9000);
        assert!(Attitude::new(0.0, 0.0, f32::NAN).is_err());
        assert!(Attitude::new(0.0, 0.0, f32::INFINITY).is_err());
    }

    #[test]
    fn wrap_centideg_is_total() {
        for (cdeg, wrapped) in [
            (0, 0),
            (17_999, 17_999),
            (18_000, -18_000),
            (-18_000, -18_000),
            (-18_001, 17_999),
            (36_000, 0),
            (-36_000, 0),
            // Far outside any angle the crate makes: no overflow on the way.
            (i32::MAX, 11_647),
            (i32::MIN, -11_648),
        ] {
            assert_eq!(wrap_centideg(cdeg), wrapped, "{cdeg}");
        }
        for cdeg in -100_000..100_000 {
            assert_eq!(
                wrap_centideg(cdeg),
                (cdeg + 18_000).rem_euclid(36_000) - 18_000
            );
        }
    }

    #[test]
    fn bounds_are_exact() {
        assert!(Gps::new(90.0, 180.0).is_ok());
        assert!(Gps::new(-90.0, -180.0).is_ok());
        let e = Gps::new(90.000_000_1, 0.0).unwrap_err();
        assert_eq!((e.field, e.min, e.max), ("latitude", -90.0, 90.0));
        assert_eq!(
            Gps::new(0.0, -180.000_000_1).unwrap_err().field,
            "longitude"
        );
        assert!(Gps::new(f64::NAN, 0.0).unwrap_err().is_not_finite());
        assert!(Altitude::new(Altitude::MAX_M).is_ok());
        assert!(Altitude::new(Altitude::MIN_M).is_ok());
        assert_eq!(
            Altitude::new(Altitude::MAX_M + 0.01).unwrap_err().field,
            "altitude"
        );
        assert!(Altitude::new(f64::INFINITY).is_err());
        assert!(Attitude::new(90.0, 180.0, 0.0).is_ok());
        assert_eq!(
            Attitude::new(90.01, 0.0, 0.0).unwrap_err().field,
            "vehicle_pitch"
        );
        assert_eq!(
            Attitude::new(0.0, -180.01, 0.0).unwrap_err().field,
            "vehicle_roll"
        );
    }

    #[test]
    fn decode_rejections() {
        assert_eq!(
            VehicleFrame::decode(0xF01, &[0; 8]),
            Err(VehicleError::NotVehicle { id: 0xF01 })
        );
        assert_eq!(
            VehicleFrame::decode(ids::GPS, &[0; 7]),
            Err(VehicleError::WrongLength { len: 7 })
        );
        assert_eq!(
            VehicleFrame::decode(ids::ALTITUDE, &[1, 0, 0, 0, 0, 0, 0, 1]),
            Err(VehicleError::NonZeroPadding { id: ids::ALTITUDE })
        );
        assert_eq!(
            VehicleFrame::decode(ids::ATTITUDE, &[0, 0, 0, 0, 0, 0, 9, 0]),
            Err(VehicleError::NonZeroPadding { id: ids::ATTITUDE })
        );
        // Latitude 90.0000001: 900000001 = 0x35A4_E901.
        assert!(matches!(
            VehicleFrame::decode(ids::GPS, &[0x01, 0xE9, 0xA4, 0x35, 0, 0, 0, 0]),
            Err(VehicleError::Value(RangeError { field: "latitude_e7", value, .. })) if value == 900_000_001.0
        ));
        // Pitch 90.01 = 9001 = 0x2329.
        assert!(matches!(
            VehicleFrame::decode(ids::ATTITUDE, &[0x29, 0x23, 0, 0, 0, 0, 0, 0]),
            Err(VehicleError::Value(RangeError { field: "vehicle_pitch_cdeg", value, .. })) if value == 9001.0
        ));
    }

    proptest! {
        #[test]
        fn gps_round_trip(lat in -90.0f64..=90.0, lon in -180.0f64..=180.0) {
            let g = Gps::new(lat, lon).unwrap();
            prop_assert!((g.lat_deg() - lat).abs() <= 0.5e-7 + 1e-12);
            prop_assert!((g.lon_deg() - lon).abs() <= 0.5e-7 + 1e-12);
            let v = VehicleFrame::from(g);
            prop_assert_eq!(VehicleFrame::decode(v.id(), &v.encode()), Ok(v));
        }

        #[test]
        fn altitude_round_trip(cm: i32) {
            let v = VehicleFrame::from(Altitude::from_cm(cm));
            prop_assert_eq!(VehicleFrame::decode(v.id(), &v.encode()), Ok(v));
            let a = Altitude::new(f64::from(cm) / 100.0).unwrap();
            prop_assert_eq!(a.cm(), cm);
        }

        #[test]
        fn attitude_round_trip(p in -90.0f32..=90.0, r in -180.0f32..=180.0, h in -1.0e4f32..1.0e4) {
            let a = Attitude::new(p, r, h).unwrap();
            prop_assert!((-18000..18000).contains(&a.heading_centideg()));
            // Same direction as asked, within rounding.
            let diff = libm::remainderf(a.heading_deg() - h, 360.0).abs();
            prop_assert!(diff <= 0.006 + h.abs() * 1e-6, "diff {}", diff);
            prop_assert!((a.pitch_deg() - p).abs() <= 0.005 + 1e-5);
            let v = VehicleFrame::from(a);
            prop_assert_eq!(VehicleFrame::decode(v.id(), &v.encode()), Ok(v));
        }

        #[test]
        fn rejected_just_outside(eps in 1e-6f64..1.0) {
            prop_assert!(Gps::new(90.0 + eps, 0.0).is_err());
            prop_assert!(Gps::new(-90.0 - eps, 0.0).is_err());
            prop_assert!(Gps::new(0.0, 180.0 + eps).is_err());
            prop_assert!(Gps::new(0.0, -180.0 - eps).is_err());
            let e = eps as f32 + 1e-4;
            prop_assert!(Attitude::new(90.0 + e, 0.0, 0.0).is_err());
            prop_assert!(Attitude::new(-90.0 - e, 0.0, 0.0).is_err());
            prop_assert!(Attitude::new(0.0, 180.0 + e, 0.0).is_err());
        }

        #[test]
        fn decode_never_panics(id: u32, bytes in proptest::collection::vec(any::<u8>(), 0..12)) {
            let _ = VehicleFrame::decode(id, &bytes);
        }
    }
}
