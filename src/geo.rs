//! Exact WGS84 look-at: the bearing, elevation and slant range from the vehicle to a
//! ground location (a region of interest), for pointing the gimbal at it; and its
//! inverse, where a line of sight meets the ground.
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
//! # The inverse: where a line of sight meets the ground
//!
//! [`LineOfSight::ground_hit`] goes the other way: from a bearing and a (negative) elevation seen from
//! a vehicle `height` metres above flat ground, where the line of sight meets that ground,
//! as latitude and longitude offsets from the vehicle. It is what a camera's field of view
//! status needs for its image centre, many times a second on a microcontroller, so it is
//! `f32` (the Cortex-M4F's FPU) rather than the `f64` of [`look_at`]:
//!
//! - the ground is the sphere, at the vehicle, that osculates the WGS84 ellipsoid in the
//!   line of sight's azimuth (radius `1 / (cos²β / M + sin²β / N)` with `M` and `N` the
//!   meridian and prime-vertical radii of curvature), so the earth's curvature lowers a
//!   far ground point as it should;
//! - the slant range is the line's nearer intersection with that sphere, in the form that
//!   does not cancel (`H (2R + H) / (…)`), so 100 m over a 6 378 km radius keeps its
//!   digits in `f32`;
//! - the offsets are the sphere's direct problem, solved exactly and written so that
//!   `f32` does not cancel, then scaled from that sphere's radius to the ellipsoid's own
//!   radii north and east.
//!
//! Offsets rather than a position, because an `f32` latitude is good to about a metre but
//! an offset is good to 10⁻⁷ of itself: the caller adds them to its own exact coordinates
//! (MAVLink's 10⁻⁷ degree integers, say). The tests feed every result back through the
//! exact [`look_at`]: the ground point lies within 5 mm of the line of sight out to 2 km,
//! 5 cm out to 10 km, 30 cm out to 30 km and 1 m beyond (grazing lines from 3 km up), and
//! its range agrees to 5 mm, 15 cm, 1.2 m and 4 m. Higher up, where a grazing line reaches
//! the ground hundreds of kilometres away, the one sphere departs from the ellipsoid
//! along the way: over every input accepted (up to 100 km high), within 3 parts in 10⁴
//! of the range off the line of sight and 1.5 parts in 10³ along it (the worst seen: 91 m
//! and 560 m at 1,045 km). A flat-ground model is rarely better than that anyway. A line of
//! sight that passes over a pole meets the ground past it, half a turn of longitude
//! round.
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

/// Latitudes beyond this (degrees) have no [`LineOfSight::ground_hit`]: the east offset's `1 / cos φ`
/// and second-order `tan φ` grow without bound towards a pole.
pub const GROUND_HIT_LAT_MAX_DEG: f32 = 85.0;

/// Heights above the ground [`LineOfSight::ground_hit`] takes, metres: up to [`ALT_MAX_M`].
pub const GROUND_HIT_HEIGHT_MAX_M: f32 = 100_000.0;

/// Where a line of sight meets the ground, from the vehicle: see
/// [`LineOfSight::ground_hit`].
#[derive(Clone, Copy, PartialEq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GroundHit {
    /// The ground point's latitude minus the vehicle's, degrees (north positive).
    pub dlat_deg: f32,
    /// The ground point's longitude minus the vehicle's, degrees (east positive; not
    /// wrapped: the caller wraps the sum).
    pub dlon_deg: f32,
    /// The straight-line distance from the vehicle to the ground point, metres.
    pub range_m: f32,
}

/// A line of sight from a vehicle down to flat ground: what [`LineOfSight::ground_hit`]
/// takes.
#[derive(Clone, Copy, PartialEq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LineOfSight {
    /// The vehicle's geodetic latitude, degrees, within ±[`GROUND_HIT_LAT_MAX_DEG`].
    pub lat_deg: f32,
    /// The ground's height above the WGS84 ellipsoid, metres, in
    /// `[ALT_MIN_M, ALT_MAX_M]` (height above sea level serves: the geoid's −106 m to
    /// +85 m scale the offsets by 1.7 × 10⁻⁵ at most).
    pub ground_alt_m: f32,
    /// The vehicle's height above that ground, metres, in
    /// `[0, GROUND_HIT_HEIGHT_MAX_M]`.
    pub height_m: f32,
    /// The line's bearing, degrees clockwise from true north, within ±360.
    pub bearing_deg: f32,
    /// The line's elevation, degrees, within ±90: negative below the horizon.
    pub elevation_deg: f32,
}

impl LineOfSight {
    /// Where the line meets the ground; `Ok(None)` when it does not (at or above the
    /// horizon). See the [module docs](self) for the method and its accuracy.
    ///
    /// ```
    /// use idu_gimbal::geo::LineOfSight;
    ///
    /// // 100 m over ground at sea level, looking 45° down towards the east: the ground
    /// // 100 m east.
    /// let sight = LineOfSight {
    ///     lat_deg: 47.0,
    ///     ground_alt_m: 0.0,
    ///     height_m: 100.0,
    ///     bearing_deg: 90.0,
    ///     elevation_deg: -45.0,
    /// };
    /// let hit = sight.ground_hit().unwrap().unwrap();
    /// assert!(hit.dlat_deg.abs() < 1e-6);
    /// // The prime-vertical radius of curvature at 47°: a / √(1 − e² sin² 47°).
    /// let east_m = hit.dlon_deg.to_radians() * 6_389_587.0 * 47.0f32.to_radians().cos();
    /// assert!((east_m - 100.0).abs() < 0.01, "{east_m}");
    /// assert!((hit.range_m - 141.42).abs() < 0.01);
    /// // Level: the horizon is never reached.
    /// let level = LineOfSight { elevation_deg: 0.0, ..sight };
    /// assert_eq!(level.ground_hit(), Ok(None));
    /// ```
    ///
    /// # Errors
    ///
    /// A [`RangeError`] naming the first field out of its range above, or not finite:
    /// `"latitude"`, `"ground altitude"`, `"height"`, `"bearing"` or `"elevation"`.
    pub fn ground_hit(&self) -> Result<Option<GroundHit>, RangeError> {
        let lat = GROUND_HIT_LAT_MAX_DEG;
        let lat_deg = RangeError::check("latitude", self.lat_deg, -lat, lat)?;
        let (lo, hi) = (ALT_MIN_M as f32, ALT_MAX_M as f32);
        let g = RangeError::check("ground altitude", self.ground_alt_m, lo, hi)?;
        let h = RangeError::check("height", self.height_m, 0.0, GROUND_HIT_HEIGHT_MAX_M)?;
        let bearing_deg = RangeError::check("bearing", self.bearing_deg, -360.0, 360.0)?;
        let elevation_deg = RangeError::check("elevation", self.elevation_deg, -90.0, 90.0)?;

        const A: f32 = WGS84_A as f32;
        const E2: f32 = WGS84_E2 as f32;
        let (sin_lat, cos_lat) = crate::math::sin_cos(lat_deg.to_radians());
        let (sin_b, cos_b) = crate::math::sin_cos(bearing_deg.to_radians());
        let (sin_e, cos_e) = crate::math::sin_cos(elevation_deg.to_radians());

        // Radii of curvature of the ground (the ellipsoid raised by g): prime vertical
        // N, meridian M, and in the azimuth (Euler's theorem).
        let w = 1.0 - E2 * sin_lat * sin_lat;
        let n0 = A / libm::sqrtf(w);
        let m = n0 * (1.0 - E2) / w + g;
        let n = n0 + g;
        let r = 1.0 / (cos_b * cos_b / m + sin_b * sin_b / n);

        // |t d − c| = r with the sphere's centre c straight below at r + h: with
        // s = −sin e, t² − 2 t (r + h) s + h (2r + h) = 0, whose nearer root is written
        // as the product of the roots over the farther one so that nothing cancels.
        let down = -sin_e;
        let c = h * (2.0 * r + h);
        let b = (r + h) * down;
        let disc = b * b - c;
        if down <= 0.0 || disc < 0.0 {
            return Ok(None);
        }
        let range_m = c / (b + libm::sqrtf(disc));

        // The arc from the point below the vehicle to the hit, as an angle at the centre.
        let sigma = libm::atan2f(range_m * cos_e, r + h - range_m * down);
        // The sphere's direct problem, exactly: the hit's unit vector p in the frame of the
        // vehicle's meridian (x out at the equator, y east, z north). The latitude change
        // is tan Δφ = (p_z cos φ − |p_xy| sin φ) / (…), whose numerator is
        // sin σ cos β − sin φ (|p_xy| − p_x), the difference written so that it does not
        // cancel: p_y² / (|p_xy| + p_x) this side of the pole, |p_xy| + |p_x| past it
        // (p_x ≤ 0, where that quotient would be 0 / 0 on the meridian).
        let (sin_s, cos_s) = crate::math::sin_cos(sigma);
        let px = cos_s * cos_lat - sin_s * cos_b * sin_lat;
        let py = sin_s * sin_b;
        let pz = cos_s * sin_lat + sin_s * cos_b * cos_lat;
        let pxy = libm::sqrtf(px * px + py * py);
        let sum = pxy + libm::fabsf(px);
        let pxy_less_px = if px > 0.0 { py * py / sum } else { sum };
        let dphi = libm::atan2f(
            sin_s * cos_b - sin_lat * pxy_less_px,
            pxy * cos_lat + pz * sin_lat,
        );
        let dlambda = libm::atan2f(py, px);
        // Angles on the sphere of radius r, as distances, over the ellipsoid's own radii.
        let (dlat, dlon) = (dphi * r / m, dlambda * r / n);
        Ok(Some(GroundHit {
            dlat_deg: dlat.to_degrees(),
            dlon_deg: dlon.to_degrees(),
            range_m,
        }))
    }
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

    /// A range error is its `GeoError`'s source (what an error chain reports beneath it);
    /// the same position has none.
    #[cfg(feature = "std")]
    #[test]
    fn error_source() {
        use std::error::Error as _;
        let e = Position::new(91.0, 0.0, 0.0).unwrap_err();
        let source = e.source().and_then(|s| s.downcast_ref::<RangeError>());
        assert_eq!(
            source.map(|r| (r.field, r.value, r.min, r.max)),
            Some(("latitude", 91.0, -90.0, 90.0))
        );
        assert!(GeoError::SamePosition.source().is_none());
    }

    /// A hit fed back through the exact `f64` [`look_at`] from a vehicle at `lon`: how far
    /// it lies off the line of sight (metres, the bearing's error weighed by the horizontal
    /// reach: it is undefined straight down), its range error, and its exact range.
    fn round_trip(sight: &LineOfSight, lon: f64) -> (f64, f64, f64) {
        let hit = sight.ground_hit().unwrap().unwrap();
        let (dlat, dlon) = (f64::from(hit.dlat_deg), f64::from(hit.dlon_deg));
        assert!(dlat.is_finite() && dlon.is_finite(), "{sight:?}: {hit:?}");
        let mut tlon = lon + dlon;
        if tlon > 180.0 {
            tlon -= 360.0;
        } else if tlon < -180.0 {
            tlon += 360.0;
        }
        let (lat, ground) = (f64::from(sight.lat_deg), f64::from(sight.ground_alt_m));
        let target = pos(lat + dlat, tlon, ground);
        let vehicle = pos(lat, lon, ground + f64::from(sight.height_m));
        let look = look_at(&vehicle, &target).unwrap();
        let mut db = (look.bearing_deg - f64::from(sight.bearing_deg)).abs();
        if db > 180.0 {
            db = 360.0 - db;
        }
        let reach = look.range_m * look.elevation_deg.to_radians().cos();
        let de = look.elevation_deg - f64::from(sight.elevation_deg);
        let miss_m = (db.to_radians() * reach).hypot(de.to_radians() * look.range_m);
        let range_err = (f64::from(hit.range_m) - look.range_m).abs();
        (miss_m, range_err, look.range_m)
    }

    /// xorshift64*: deterministic, so a failure reproduces; uniform in `[lo, hi)`.
    fn uniform(seed: &mut u64, lo: f64, hi: f64) -> f64 {
        *seed ^= *seed >> 12;
        *seed ^= *seed << 25;
        *seed ^= *seed >> 27;
        let u = (seed.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * u
    }

    /// Every hit, fed back through the exact `f64` [`look_at`] from the vehicle, gives the
    /// bearing and elevation it came from, and its range. Vehicles at latitudes within
    /// ±85°, 2 m to 3 km up (the ground at 0 to 2 km above the ellipsoid), looking
    /// anywhere from straight down to within a few degrees of the horizon.
    #[test]
    fn ground_hit_inverts_look_at() {
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        // The worst miss (metres off the line of sight, and range error) in each band of
        // range: within 2 km, 10 km, 30 km, and beyond.
        const BANDS: [f64; 3] = [2_000.0, 10_000.0, 30_000.0];
        let mut worst = [(0.0f64, 0.0f64); 4];
        for _ in 0..20_000 {
            let sight = LineOfSight {
                lat_deg: uniform(&mut seed, -85.0, 85.0) as f32,
                ground_alt_m: uniform(&mut seed, 0.0, 2_000.0) as f32,
                height_m: uniform(&mut seed, 2.0, 3_000.0) as f32,
                bearing_deg: uniform(&mut seed, 0.0, 360.0) as f32,
                elevation_deg: uniform(&mut seed, -90.0, -3.0) as f32,
            };
            let lon = uniform(&mut seed, -180.0, 180.0);
            let (miss_m, range_err, range_m) = round_trip(&sight, lon);
            let band = BANDS.iter().take_while(|&&b| range_m > b).count();
            let w = &mut worst[band];
            *w = (w.0.max(miss_m), w.1.max(range_err));
        }
        std::println!("worst (miss m, range error m) by band: {worst:?}");
        // What the method gives (module docs): about twice the worst seen (1.2 mm and
        // 2.5 mm; 19 mm and 72 mm; 0.13 m and 0.62 m; 0.48 m and 2.1 m), the `f32`
        // rounding and the sphere's departure from the ellipsoid together.
        let limits = [(0.005, 0.005), (0.05, 0.15), (0.3, 1.2), (1.0, 4.0)];
        for (band, (w, l)) in worst.iter().zip(limits).enumerate() {
            assert!(w.0 <= l.0 && w.1 <= l.1, "band {band}: {w:?} over {l:?}");
        }
    }

    /// The whole accepted domain: up to 100 km up, any elevation that reaches the ground
    /// (grazing lines included, out to 1,100 km), every latitude within ±85°. Every hit is
    /// finite, and its errors grow with the range: the osculating sphere departs from
    /// the ellipsoid, along the range more than across it.
    #[test]
    fn ground_hit_holds_over_its_whole_domain() {
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        // The worst miss and range error, each over the range.
        let (mut miss, mut along) = (0.0f64, 0.0f64);
        let mut hits = 0;
        for _ in 0..20_000 {
            let ground = uniform(&mut seed, 0.0, 2_000.0);
            let sight = LineOfSight {
                lat_deg: uniform(&mut seed, -85.0, 85.0) as f32,
                // The vehicle within [`look_at`]'s altitudes too.
                ground_alt_m: ground as f32,
                height_m: uniform(&mut seed, 0.0, ALT_MAX_M - ground) as f32,
                bearing_deg: uniform(&mut seed, -360.0, 360.0) as f32,
                elevation_deg: uniform(&mut seed, -90.0, 0.0) as f32,
            };
            if sight.ground_hit().unwrap().is_none() {
                continue;
            }
            hits += 1;
            let (miss_m, range_err, range_m) = round_trip(&sight, 0.0);
            miss = miss.max(miss_m / range_m.max(1.0));
            along = along.max(range_err / range_m.max(1.0));
        }
        std::println!("{hits} hits; worst over the range: miss {miss:e}, range error {along:e}");
        assert!(hits > 15_000, "{hits}");
        // About twice the worst seen (1.5 and 7.1 parts in 10⁴; the module docs).
        assert!(miss < 3e-4 && along < 1.5e-3, "{miss:e} {along:e}");
    }

    /// A line of sight over a pole, from 100 km up: the hit is past it, on the far side's
    /// meridian (a half-turn of longitude away) and on the line of sight.
    #[test]
    fn ground_hit_past_a_pole() {
        for (lat_deg, bearing_deg) in [(85.0, 0.0), (85.0, 1e-4), (-85.0, 180.0), (84.0, -1e-4)] {
            let sight = LineOfSight {
                lat_deg,
                ground_alt_m: 0.0,
                height_m: 100_000.0,
                bearing_deg,
                elevation_deg: -11.0,
            };
            let hit = sight.ground_hit().unwrap().unwrap();
            // Past the pole: the latitude turns back, the longitude is half a turn round.
            assert!(hit.dlon_deg.abs() > 179.9, "{sight:?}: {hit:?}");
            let (miss_m, range_err, range_m) = round_trip(&sight, 10.0);
            assert!(
                miss_m < 1e-4 * range_m && range_err < 1e-4 * range_m,
                "{sight:?}: {hit:?} {miss_m} {range_err} of {range_m}"
            );
        }
    }

    #[test]
    fn ground_hit_misses_and_ranges() {
        let sight = |lat_deg, height_m, elevation_deg| LineOfSight {
            lat_deg,
            ground_alt_m: 0.0,
            height_m,
            bearing_deg: 0.0,
            elevation_deg,
        };
        assert_eq!(sight(0.0, 100.0, 0.0).ground_hit(), Ok(None));
        assert_eq!(sight(0.0, 100.0, 10.0).ground_hit(), Ok(None));
        // From 100 m the horizon dips by acos(R / (R + h)) ≈ 0.32°: just above it misses.
        assert_eq!(sight(0.0, 100.0, -0.3).ground_hit(), Ok(None));
        let far = sight(0.0, 100.0, -0.4).ground_hit().unwrap().unwrap();
        assert!(far.range_m > 10_000.0 && far.range_m < 40_000.0, "{far:?}");
        // Straight down from the ground itself: here.
        let here = sight(10.0, 0.0, -90.0).ground_hit().unwrap().unwrap();
        assert_eq!(
            (here.dlat_deg, here.dlon_deg, here.range_m),
            (0.0, 0.0, 0.0)
        );
        let ok = sight(0.0, 10.0, -10.0);
        for (bad, field) in [
            (
                LineOfSight {
                    lat_deg: 85.1,
                    ..ok
                },
                "latitude",
            ),
            (
                LineOfSight {
                    lat_deg: f32::NAN,
                    ..ok
                },
                "latitude",
            ),
            (
                LineOfSight {
                    ground_alt_m: -1_000.5,
                    ..ok
                },
                "ground altitude",
            ),
            (
                LineOfSight {
                    height_m: -0.1,
                    ..ok
                },
                "height",
            ),
            (
                LineOfSight {
                    height_m: 100_001.0,
                    ..ok
                },
                "height",
            ),
            (
                LineOfSight {
                    bearing_deg: 361.0,
                    ..ok
                },
                "bearing",
            ),
            (
                LineOfSight {
                    elevation_deg: -90.5,
                    ..ok
                },
                "elevation",
            ),
            (
                LineOfSight {
                    elevation_deg: f32::INFINITY,
                    ..ok
                },
                "elevation",
            ),
        ] {
            assert_eq!(bad.ground_hit().unwrap_err().field, field, "{bad:?}");
        }
    }
}
