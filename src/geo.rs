//! Exact WGS84 look-at: the bearing, elevation and slant range from the vehicle to a
//! ground location (a region of interest), for pointing the gimbal at it.
//!
//! # Method
//!
//! Both [`Position`]s are converted from geodetic coordinates (latitude, longitude, height)
//! to Earth-centred, Earth-fixed (ECEF) Cartesian coordinates on the WGS84 ellipsoid, and
//! the difference vector is rotated into the local east-north-up (ENU) frame at the
//! vehicle, whose "up" is the ellipsoid normal there. Then
//!
//! - bearing = `atan2(east, north)`, normalised to `[0, 360)` degrees clockwise from true
//!   north;
//! - elevation = `atan2(up, hypot(east, north))`, in `[-90, 90]` degrees, negative below
//!   the vehicle's horizon;
//! - range = `|(east, north, up)|`, the straight-line (slant) distance in metres.
//!
//! This is the closed-form transform, not an approximation: no flat-earth, spherical or
//! small-distance assumption is made, so it is as accurate at 50 km as at 5 m, and the
//! curvature of the earth shows up as it should (a target at the same height 10 km away
//! lies about 0.045° below the horizon). It works across the antimeridian and near the
//! poles: the ECEF coordinates are computed in a frame turned to the vehicle's meridian,
//! from the longitude difference wrapped into `[-180, 180]`.
//!
//! The ellipsoid is WGS84: semi-major axis [`WGS84_A`] = 6 378 137.0 m and flattening
//! [`WGS84_F`] = 1 / 298.257 223 563 (the values GPS receivers use).
//!
//! # Heights
//!
//! [`Position::alt_m`] is taken as the height above the WGS84 ellipsoid. GPS receivers and
//! maps usually give height above mean sea level (the geoid) instead; the two differ by
//! the geoid undulation *N* (between about −106 m and +85 m). When both positions use the
//! same reference, *N* cancels to first order, because it is almost the same at both
//! points. What remains is
//!
//! - the change of *N* between the two points, which moves the target vertically by that
//!   amount: the geoid's slope (the deflection of the vertical) is typically a few arcseconds
//!   and rarely over 1′, so the elevation error is typically under 0.003° and rarely over
//!   0.02°, whatever the range;
//! - a second-order term, at most |*N*| / *a* ≈ 2 × 10⁻⁵ rad (0.001°), from both points
//!   being moved along slightly different normals.
//!
//! Both are below a gimbal's pointing resolution. Mixing references (one height above the
//! ellipsoid, the other above sea level) is an error of *N* metres in height and does not
//! cancel.
//!
//! # Accuracy
//!
//! The only errors are double-precision rounding: ECEF coordinates are good to about
//! 10⁻⁹ m, so the angles are good to about 10⁻⁹ m divided by the range (about 10⁻⁷° at
//! 1 m). The tests compare every result with an independent implementation (`pymap3d`)
//! over ranges from 1 m to 50 km, latitudes within ±85° and across the antimeridian, and
//! require agreement within 0.01° of bearing and elevation and 0.1 m + 10⁻⁵ × range of
//! range; the actual agreement is far closer.
//!
//! Two inputs have no well-defined answer:
//!
//! - a target closer than [`MIN_RANGE_M`] (1 mm) is [`GeoError::SamePosition`];
//! - a target straight above or below the vehicle (horizontal distance under
//!   [`VERTICAL_M`], 1 mm) has no bearing: [`look_at`] returns bearing 0 with elevation
//!   ±90.
//!
//! At a pole "north" is taken along the vehicle's meridian, as the ENU convention does,
//! so the bearing there depends on the vehicle's longitude.
//!
//! # Cost
//!
//! One [`look_at`] is six sines and cosines, two square roots, two arc tangents, two
//! `hypot`s and a few dozen multiply-adds, all in `f64`. The Cortex-M4F's FPU is single
//! precision, so these run in software (`libm`); that is still small next to a 10 Hz
//! control period, and the call allocates nothing and cannot panic.
//!
//! # Example
//!
//! ```
//! use idu_gimbal::geo::{look_at, Position};
//!
//! # fn main() -> Result<(), idu_gimbal::geo::GeoError> {
//! // A drone 120 m above the ellipsoid, looking at a point on the ground (height 20 m)
//! // about 500 m to its north-east.
//! let vehicle = Position::new(47.3977, 8.5456, 120.0)?;
//! let target = Position::new(47.4009, 8.5503, 20.0)?;
//! let look = look_at(&vehicle, &target)?;
//!
//! assert!(look.bearing_deg > 40.0 && look.bearing_deg < 50.0);
//! assert!(look.elevation_deg < -10.0); // below the horizon
//! assert!(look.range_m > 400.0 && look.range_m < 600.0);
//! # Ok(())
//! # }
//! ```

use core::fmt;

use crate::wire::RangeError;

/// WGS84 semi-major axis (equatorial radius), in metres.
pub const WGS84_A: f64 = 6_378_137.0;

/// WGS84 flattening, `1 / 298.257223563`.
pub const WGS84_F: f64 = 1.0 / 298.257_223_563;

/// WGS84 first eccentricity squared, `f (2 − f)`.
const WGS84_E2: f64 = WGS84_F * (2.0 - WGS84_F);

/// Lowest accepted altitude, in metres (below the Dead Sea shore and most mines).
pub const ALT_MIN_M: f64 = -1_000.0;

/// Highest accepted altitude, in metres (100 km, the Kármán line).
pub const ALT_MAX_M: f64 = 100_000.0;

/// Targets closer than this (in metres, 1 mm) coincide with the vehicle:
/// [`look_at`] returns [`GeoError::SamePosition`].
pub const MIN_RANGE_M: f64 = 1e-3;

/// Targets whose horizontal distance from the vehicle is below this (in metres, 1 mm) are
/// straight above or below it: [`look_at`] returns bearing 0.
pub const VERTICAL_M: f64 = 1e-3;

/// A geodetic position on the WGS84 ellipsoid.
///
/// Constructed only by [`Position::new`], so every `Position` is valid.
#[derive(Clone, Copy, PartialEq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Position {
    lat_deg: f64,
    lon_deg: f64,
    alt_m: f64,
}

impl Position {
    /// A position from latitude and longitude in degrees and height in metres.
    ///
    /// - `lat_deg`: geodetic latitude in `[-90, 90]`, positive north;
    /// - `lon_deg`: longitude in `[-180, 180]`, positive east (both ±180 are accepted and
    ///   mean the same meridian);
    /// - `alt_m`: height above the WGS84 ellipsoid in `[ALT_MIN_M, ALT_MAX_M]`
    ///   (−1 000 m to 100 000 m). Height above mean sea level may be used for both
    ///   positions instead; see the [module docs](self) for the residual error.
    ///
    /// # Errors
    ///
    /// [`GeoError::Range`] naming the first argument (`"latitude"`, `"longitude"` or
    /// `"altitude"`) that is not finite or is out of range.
    pub fn new(lat_deg: f64, lon_deg: f64, alt_m: f64) -> Result<Self, GeoError> {
        Ok(Position {
            lat_deg: RangeError::check("latitude", lat_deg, -90.0, 90.0)?,
            lon_deg: RangeError::check("longitude", lon_deg, -180.0, 180.0)?,
            alt_m: RangeError::check("altitude", alt_m, ALT_MIN_M, ALT_MAX_M)?,
        })
    }

    /// Geodetic latitude in degrees, `[-90, 90]`, positive north.
    pub fn lat_deg(&self) -> f64 {
        self.lat_deg
    }

    /// Longitude in degrees, `[-180, 180]`, positive east.
    pub fn lon_deg(&self) -> f64 {
        self.lon_deg
    }

    /// Height above the WGS84 ellipsoid in metres.
    pub fn alt_m(&self) -> f64 {
        self.alt_m
    }
}

/// Where the target is as seen from the vehicle, in the vehicle's local level frame.
#[derive(Clone, Copy, PartialEq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LookAngles {
    /// True bearing in degrees, `[0, 360)`, clockwise from true north. 0 when the target
    /// is straight above or below the vehicle.
    pub bearing_deg: f64,
    /// Elevation in degrees, `[-90, 90]`, above the plane normal to the ellipsoid normal at
    /// the vehicle; negative below the horizon.
    pub elevation_deg: f64,
    /// Straight-line (slant) distance in metres, at least [`MIN_RANGE_M`].
    pub range_m: f64,
}

/// Why a look-at could not be computed.
#[derive(Clone, Copy, PartialEq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GeoError {
    /// A coordinate was not finite or out of range.
    Range(RangeError),
    /// The target is within [`MIN_RANGE_M`] of the vehicle, so it has no direction.
    SamePosition,
}

impl From<RangeError> for GeoError {
    fn from(e: RangeError) -> Self {
        GeoError::Range(e)
    }
}

impl fmt::Display for GeoError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GeoError::Range(e) => e.fmt(f),
            GeoError::SamePosition => write!(
                f,
                "target is within {} m of the vehicle and has no direction",
                MIN_RANGE_M
            ),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for GeoError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            GeoError::Range(e) => Some(e),
            GeoError::SamePosition => None,
        }
    }
}

/// Bearing, elevation and slant range from `vehicle` to `target`.
///
/// See the [module docs](self) for the method and its accuracy.
///
/// # Errors
///
/// [`GeoError::SamePosition`] when the target is closer than [`MIN_RANGE_M`] (1 mm).
pub fn look_at(vehicle: &Position, target: &Position) -> Result<LookAngles, GeoError> {
    // Longitude difference in [-180, 180], so the antimeridian needs no special case and
    // the trigonometry sees small arguments for nearby targets.
    let mut dlon = target.lon_deg - vehicle.lon_deg;
    if dlon > 180.0 {
        dlon -= 360.0;
    } else if dlon < -180.0 {
        dlon += 360.0;
    }

    let (sin_lat0, cos_lat0) = libm::sincos(vehicle.lat_deg.to_radians());
    let (sin_lat1, cos_lat1) = libm::sincos(target.lat_deg.to_radians());
    let (sin_dlon, cos_dlon) = libm::sincos(dlon.to_radians());

    // ECEF coordinates in a frame turned about the polar axis so that the vehicle's
    // meridian is the x-z plane: the vehicle has y = 0 and the target's y is its east
    // offset.
    let (r0, z0) = meridian_xz(vehicle.alt_m, sin_lat0, cos_lat0);
    let (r1, z1) = meridian_xz(target.alt_m, sin_lat1, cos_lat1);
    let dx = r1 * cos_dlon - r0;
    let dz = z1 - z0;

    let east = r1 * sin_dlon;
    let north = cos_lat0 * dz - sin_lat0 * dx;
    let up = cos_lat0 * dx + sin_lat0 * dz;

    let horizontal = libm::hypot(east, north);
    let range_m = libm::hypot(horizontal, up);
    if range_m.is_nan() || range_m < MIN_RANGE_M {
        return Err(GeoError::SamePosition);
    }

    let elevation_deg = libm::atan2(up, horizontal).to_degrees();
    let bearing_deg = if horizontal < VERTICAL_M {
        0.0
    } else {
        normalize_bearing(libm::atan2(east, north).to_degrees())
    };

    Ok(LookAngles {
        bearing_deg,
        elevation_deg,
        range_m,
    })
}

/// Distance from the polar axis and height above the equatorial plane (ECEF `hypot(x, y)`
/// and `z`) of a point at geodetic latitude with the given sine and cosine, `h` metres
/// above the ellipsoid.
fn meridian_xz(h: f64, sin_lat: f64, cos_lat: f64) -> (f64, f64) {
    // Radius of curvature in the prime vertical.
    let n = WGS84_A / libm::sqrt(1.0 - WGS84_E2 * sin_lat * sin_lat);
    ((n + h) * cos_lat, (n * (1.0 - WGS84_E2) + h) * sin_lat)
}

/// Maps an angle from `atan2` (in `[-180, 180]` degrees) into `[0, 360)`.
fn normalize_bearing(deg: f64) -> f64 {
    let mut b = if deg < 0.0 { deg + 360.0 } else { deg };
    // A tiny negative angle rounds to exactly 360 when shifted.
    if b >= 360.0 {
        b -= 360.0;
    }
    // Turn -0.0 into 0.0.
    b + 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pos(lat: f64, lon: f64, alt: f64) -> Position {
        Position::new(lat, lon, alt).unwrap()
    }

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn straight_up_at_equator() {
        let l = look_at(&pos(0.0, 0.0, 0.0), &pos(0.0, 0.0, 1000.0)).unwrap();
        assert_eq!(l.bearing_deg, 0.0);
        assert!(close(l.elevation_deg, 90.0, 1e-12), "{l:?}");
        assert!(close(l.range_m, 1000.0, 1e-9), "{l:?}");
    }

    #[test]
    fn straight_down_at_mid_latitude() {
        let l = look_at(&pos(45.0, 10.0, 500.0), &pos(45.0, 10.0, 100.0)).unwrap();
        assert_eq!(l.bearing_deg, 0.0);
        assert!(close(l.elevation_deg, -90.0, 1e-9), "{l:?}");
        assert!(close(l.range_m, 400.0, 1e-6), "{l:?}");
    }

    #[test]
    fn east_along_equator() {
        // 0.001° of longitude at the equator is a * 0.001° in radians along the arc.
        let l = look_at(&pos(0.0, 0.0, 0.0), &pos(0.0, 0.001, 0.0)).unwrap();
        let arc = WGS84_A * 0.001_f64.to_radians();
        assert!(close(l.bearing_deg, 90.0, 1e-9), "{l:?}");
        // Chord is barely shorter than the arc; the target dips by half the subtended angle.
        assert!(close(l.range_m, arc, 1e-6), "{l:?}");
        assert!(close(l.elevation_deg, -0.0005, 1e-9), "{l:?}");
    }

    #[test]
    fn west_north_south() {
        let v = pos(10.0, 20.0, 0.0);
        // A parallel is not a straight line: a point on it to the west lies a little north
        // of due west, by about half the longitude difference times sin(latitude).
        let w = look_at(&v, &pos(10.0, 19.999, 0.0)).unwrap();
        let tilt = 0.0005 * 10.0_f64.to_radians().sin();
        assert!(close(w.bearing_deg, 270.0 + tilt, 1e-7), "{w:?}");
        let n = look_at(&v, &pos(10.001, 20.0, 0.0)).unwrap();
        assert!(
            n.bearing_deg < 1e-9 || n.bearing_deg > 360.0 - 1e-9,
            "{n:?}"
        );
        let s = look_at(&v, &pos(9.999, 20.0, 0.0)).unwrap();
        assert!(close(s.bearing_deg, 180.0, 1e-9), "{s:?}");
    }

    #[test]
    fn north_along_meridian_at_equator() {
        // The meridian radius of curvature at the equator is a (1 - e²).
        let l = look_at(&pos(0.0, 0.0, 0.0), &pos(0.0001, 0.0, 0.0)).unwrap();
        let arc = WGS84_A * (1.0 - WGS84_E2) * 0.0001_f64.to_radians();
        assert!(close(l.range_m, arc, 1e-4), "{l:?} vs {arc}");
        assert!(l.elevation_deg < 0.0);
    }

    #[test]
    fn across_antimeridian() {
        let l = look_at(&pos(0.0, 179.99, 0.0), &pos(0.0, -179.99, 0.0)).unwrap();
        assert!(close(l.bearing_deg, 90.0, 1e-6), "{l:?}");
        let arc = WGS84_A * 0.02_f64.to_radians();
        assert!(close(l.range_m, arc, 0.01), "{l:?}");
        let back = look_at(&pos(0.0, -179.99, 0.0), &pos(0.0, 179.99, 0.0)).unwrap();
        assert!(close(back.bearing_deg, 270.0, 1e-6), "{back:?}");
    }

    #[test]
    fn both_180_meridians_coincide() {
        assert_eq!(
            look_at(&pos(30.0, 180.0, 0.0), &pos(30.0, -180.0, 0.0)),
            Err(GeoError::SamePosition)
        );
    }

    #[test]
    fn same_position_threshold() {
        let v = pos(30.0, 40.0, 10.0);
        assert_eq!(look_at(&v, &v), Err(GeoError::SamePosition));
        assert_eq!(
            look_at(&v, &pos(30.0, 40.0, 10.0005)),
            Err(GeoError::SamePosition)
        );
        let l = look_at(&v, &pos(30.0, 40.0, 10.002)).unwrap();
        assert!(close(l.elevation_deg, 90.0, 1e-3), "{l:?}");
    }

    #[test]
    fn constructor_rejects_bad_inputs() {
        for (lat, lon, alt, field) in [
            (f64::NAN, 0.0, 0.0, "latitude"),
            (90.000001, 0.0, 0.0, "latitude"),
            (0.0, f64::INFINITY, 0.0, "longitude"),
            (0.0, -180.5, 0.0, "longitude"),
            (0.0, 0.0, -1000.1, "altitude"),
            (0.0, 0.0, 100_000.1, "altitude"),
            (0.0, 0.0, f64::NAN, "altitude"),
        ] {
            match Position::new(lat, lon, alt) {
                Err(GeoError::Range(e)) => assert_eq!(e.field, field),
                other => panic!("{lat} {lon} {alt}: {other:?}"),
            }
        }
        let p = pos(-90.0, 180.0, ALT_MAX_M);
        assert_eq!(
            (p.lat_deg(), p.lon_deg(), p.alt_m()),
            (-90.0, 180.0, ALT_MAX_M)
        );
        assert!(Position::new(90.0, -180.0, ALT_MIN_M).is_ok());
    }

    #[test]
    fn bearing_normalisation() {
        assert_eq!(normalize_bearing(-0.0).to_bits(), 0.0_f64.to_bits());
        assert_eq!(normalize_bearing(-1e-15), 0.0);
        assert_eq!(normalize_bearing(-90.0), 270.0);
        assert_eq!(normalize_bearing(180.0), 180.0);
    }

    #[test]
    fn display() {
        let e = Position::new(91.0, 0.0, 0.0).unwrap_err();
        assert_eq!(e.to_string(), "latitude = 91 is out of range [-90, 90]");
        assert!(GeoError::SamePosition.to_string().contains("0.001 m"));
    }
}
