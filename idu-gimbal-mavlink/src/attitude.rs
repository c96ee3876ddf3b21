//! Gimbal attitude as MAVLink quaternions, built and read from the gimbal's axis
//! rotations: yaw about the down axis, then pitch about the rotated right axis.
//!
//! The IDU gimbal pitches from +60° to −100°: past −90° it looks backwards, upside down.
//! 3-2-1 Euler angles cannot hold that (their pitch is confined to ±90°, and a pitch of
//! −100° reads back as −80° with yaw and roll turned by 180°). The gimbal has no roll axis,
//! so its attitude is exactly `q = q_yaw(ψ) ⊗ q_pitch(θ)`, and that product is inverted
//! directly: for `q = (w, x, y, z)`,
//!
//! - `w = cos(ψ/2)·cos(θ/2)`, `x = −sin(ψ/2)·sin(θ/2)`, `y = cos(ψ/2)·sin(θ/2)`,
//!   `z = sin(ψ/2)·cos(θ/2)`;
//! - so `ψ/2 = atan2(z, w)` (for `cos(θ/2) > 0`, which holds for every |θ| < 180°), and
//!   with `c = cos(ψ/2)`, `s = sin(ψ/2)`: `cos(θ/2) = w·c + z·s`, `sin(θ/2) = y·c − x·s`.
//!
//! That is exact over the whole range, −90° and −100° included, with no singularity, and
//! needs two arc tangents and no sine or cosine (cos(ψ/2) and sin(ψ/2) are `w` and `z` over
//! their length). A quaternion with a roll component (which the gimbal cannot follow) is
//! read as a roll-free attitude in this parametrisation, and [`YawPitch::roll_of`] says how
//! much roll it had.
//!
//! Angles are in radians, MAVLink's unit, as `f32` (MAVLink's quaternions are `f32`).
//! Positive pitch is up, positive yaw is to the right (clockwise seen from above), as in
//! MAVLink's NED/FRD frames and on the gimbal's wire.

use core::f32::consts::PI;

/// A gimbal attitude as its two axis angles, radians.
#[derive(Clone, Copy, PartialEq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct YawPitch {
    /// Yaw, in (−π, π].
    pub yaw_rad: f32,
    /// Pitch, in (−π, π); the gimbal reaches [−100°, 60°].
    pub pitch_rad: f32,
}

/// Wraps an angle into (−π, π].
pub fn wrap_pi(a: f32) -> f32 {
    let r = libm::remainderf(a, 2.0 * PI);
    if r <= -PI {
        r + 2.0 * PI
    } else {
        r
    }
}

pub use idu_gimbal::math::sin_cos;

/// `asin` in `f32` arithmetic only (`libm::asinf` uses `f64` from |v| = 0.5, see
/// [`sin_cos`]), for |v| ≤ 1. Below 0.5, a vehicle's pitch up to 30° and the common case,
/// musl's rational approximation `v + v·R(v²)` (its `asinf.c` coefficients, accurate to
/// f32); above, the angle whose sine is `v` and cosine √(1 − v²).
pub fn asin(v: f32) -> f32 {
    if libm::fabsf(v) < 0.5 {
        let z = v * v;
        let p = z * (1.666_658_7e-1 + z * (-4.274_342_2e-2 + z * -8.656_363e-3));
        let q = 1.0 + z * -7.066_296_3e-1;
        v + v * (p / q)
    } else {
        libm::atan2f(v, libm::sqrtf((1.0 - v) * (1.0 + v)))
    }
}

impl YawPitch {
    /// The quaternion `q_yaw(ψ) ⊗ q_pitch(θ)`, as MAVLink orders it: `[w, x, y, z]`.
    pub fn to_quaternion(self) -> [f32; 4] {
        let (sy, cy) = sin_cos(self.yaw_rad / 2.0);
        let (sp, cp) = sin_cos(self.pitch_rad / 2.0);
        [cy * cp, -sy * sp, cy * sp, sy * cp]
    }

    /// Reads yaw and pitch back from a quaternion `[w, x, y, z]` (see the module docs).
    /// `None` when it is not finite, far from unit length (|q| outside [0.9, 1.1]: not a
    /// rotation, whatever rounding the sender did), or pitched by 180° (no yaw then).
    pub fn from_quaternion(q: [f32; 4]) -> Option<YawPitch> {
        let [w, x, y, z] = q;
        let norm = libm::sqrtf(w * w + x * x + y * y + z * z);
        if !norm.is_finite() || !(0.9..=1.1).contains(&norm) {
            return None;
        }
        // cos(ψ/2) and sin(ψ/2) are w and z over their length: no trigonometry needed.
        let r = libm::sqrtf(w * w + z * z);
        if r < 1e-6 {
            return None;
        }
        let (c, s) = (w / r, z / r);
        let half_pitch = libm::atan2f(y * c - x * s, w * c + z * s);
        Some(
            YawPitch {
                yaw_rad: 2.0 * libm::atan2f(z, w),
                pitch_rad: 2.0 * half_pitch,
            }
            .normalised(),
        )
    }

    fn normalised(self) -> YawPitch {
        YawPitch {
            yaw_rad: wrap_pi(self.yaw_rad),
            ..self
        }
    }

    /// How much roll `q` has, which the gimbal cannot follow: `2(w·x + y·z)`, exactly 0 for
    /// every `q_yaw ⊗ q_pitch` (expand the product), and `sin(roll)·cos(pitch)` for an
    /// attitude with roll. Looking straight down a roll is a yaw, and this reads 0.
    pub fn roll_of(q: [f32; 4]) -> f32 {
        let [w, x, y, z] = q;
        let norm2 = w * w + x * x + y * y + z * z;
        2.0 * (w * x + y * z) / norm2
    }
}

/// The NaN quaternion MAVLink uses for "no attitude given" (with angular velocities instead).
pub fn is_nan_quaternion(q: [f32; 4]) -> bool {
    q.iter().all(|v| v.is_nan())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn asin_matches_f64() {
        let mut worst = 0f64;
        for i in -1000..=1000 {
            let v = i as f32 / 1000.0;
            worst = worst.max((f64::from(asin(v)) - f64::from(v).asin()).abs());
        }
        assert!(worst < 3e-7, "worst error {worst:e}");
    }

    #[test]
    fn wrap_pi_gives_the_half_open_turn() {
        // −π is π's other name: (−π, π] holds π (2π in f32 is PI doubled, exact, and so is
        // −PI + 2·PI).
        assert_eq!(wrap_pi(-PI), PI);
        assert_eq!(wrap_pi(PI), PI);
        assert_eq!(wrap_pi(-0.5), -0.5);
        assert_eq!(wrap_pi(3.0), 3.0);
    }

    #[test]
    fn a_quaternion_pitched_half_a_turn_has_no_yaw() {
        // w = z = 0: turned 180° about a horizontal axis, no heading to read.
        assert_eq!(YawPitch::from_quaternion([0.0, 1.0, 0.0, 0.0]), None);
        assert_eq!(YawPitch::from_quaternion([0.0, 0.6, 0.8, 0.0]), None);
    }

    #[test]
    fn roll_is_read_from_a_quaternion_of_any_length_the_bridge_takes() {
        // 10° of roll, q = (cos 5°, sin 5°, 0, 0): 2·w·x = sin 10°, at length 1 and 1.05.
        let (s, c) = 5f32.to_radians().sin_cos();
        for k in [1.0f32, 1.05, 0.95] {
            let roll = YawPitch::roll_of([k * c, k * s, 0.0, 0.0]);
            // f32 products and one division: a few ulps of 0.17.
            assert!(
                (roll - 10f32.to_radians().sin()).abs() < 1e-6,
                "{k}: {roll}"
            );
        }
    }

    use proptest::prelude::*;

    fn deg(d: f32) -> f32 {
        d.to_radians()
    }

    /// Rotates vector `v` by unit quaternion `q` (q v q*), as an independent check.
    fn rotate(q: [f32; 4], v: [f32; 3]) -> [f32; 3] {
        let [w, x, y, z] = q;
        let (w, x, y, z) = (w as f64, x as f64, y as f64, z as f64);
        let m = [
            [
                1.0 - 2.0 * (y * y + z * z),
                2.0 * (x * y - w * z),
                2.0 * (x * z + w * y),
            ],
            [
                2.0 * (x * y + w * z),
                1.0 - 2.0 * (x * x + z * z),
                2.0 * (y * z - w * x),
            ],
            [
                2.0 * (x * z - w * y),
                2.0 * (y * z + w * x),
                1.0 - 2.0 * (x * x + y * y),
            ],
        ];
        let v = [v[0] as f64, v[1] as f64, v[2] as f64];
        core::array::from_fn(|i| (m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2]) as f32)
    }

    #[test]
    fn axis_rotations_point_the_camera_where_expected() {
        // NED: the camera's forward axis is body x. Yaw 90° points it east.
        let east = rotate(
            YawPitch {
                yaw_rad: deg(90.0),
                pitch_rad: 0.0,
            }
            .to_quaternion(),
            [1.0, 0.0, 0.0],
        );
        assert!((east[0]).abs() < 1e-6 && (east[1] - 1.0).abs() < 1e-6 && east[2].abs() < 1e-6);
        // Pitch −90° points it down (+z in NED).
        let down = rotate(
            YawPitch {
                yaw_rad: deg(30.0),
                pitch_rad: deg(-90.0),
            }
            .to_quaternion(),
            [1.0, 0.0, 0.0],
        );
        assert!((down[2] - 1.0).abs() < 1e-6, "{down:?}");
        // Pitch −100° at yaw 0 looks down and 10° backwards (−x), upside down: the camera's
        // up axis (−z body) points north-ish and down.
        let q = YawPitch {
            yaw_rad: 0.0,
            pitch_rad: deg(-100.0),
        }
        .to_quaternion();
        let fwd = rotate(q, [1.0, 0.0, 0.0]);
        assert!(
            (fwd[0] - deg(-100.0).cos()).abs() < 1e-6 && (fwd[2] + deg(-100.0).sin()).abs() < 1e-6
        );
    }

    #[test]
    fn the_whole_pitch_range_reads_back_including_minus_90_and_minus_100() {
        for pitch in [-100.0, -95.0, -90.0, -89.9, -45.0, 0.0, 30.0, 60.0] {
            for yaw in [-179.0, -90.0, 0.0, 45.0, 90.0, 180.0] {
                let a = YawPitch {
                    yaw_rad: deg(yaw),
                    pitch_rad: deg(pitch),
                };
                let q = a.to_quaternion();
                let b = YawPitch::from_quaternion(q).unwrap();
                // f32 trigonometry: a few 1e-7 rad each way (checked below at 1e-5 rad, 0.0006°).
                assert!(
                    (b.pitch_rad - a.pitch_rad).abs() < 1e-5,
                    "pitch {pitch} yaw {yaw}: {b:?}"
                );
                assert!(
                    wrap_pi(b.yaw_rad - a.yaw_rad).abs() < 1e-5,
                    "pitch {pitch} yaw {yaw}: {b:?}"
                );
                assert!(YawPitch::roll_of(q).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn three_two_one_euler_would_misread_minus_100() {
        // The classic 3-2-1 extraction: pitch = asin(2(wy − xz)) cannot exceed 90°.
        let [w, x, y, z] = YawPitch {
            yaw_rad: 0.0,
            pitch_rad: deg(-100.0),
        }
        .to_quaternion();
        let euler_pitch = (2.0 * (w * y - x * z)).clamp(-1.0, 1.0).asin().to_degrees();
        assert!((euler_pitch + 80.0).abs() < 1e-3, "{euler_pitch}");
        // This module reads it right.
        let b = YawPitch::from_quaternion([w, x, y, z]).unwrap();
        assert!((b.pitch_rad.to_degrees() + 100.0).abs() < 1e-3);
    }

    #[test]
    fn nan_and_non_unit_quaternions_are_refused() {
        assert_eq!(YawPitch::from_quaternion([f32::NAN; 4]), None);
        assert!(is_nan_quaternion([f32::NAN; 4]));
        assert!(!is_nan_quaternion([1.0, 0.0, 0.0, 0.0]));
        assert_eq!(YawPitch::from_quaternion([0.0; 4]), None);
        assert_eq!(YawPitch::from_quaternion([2.0, 0.0, 0.0, 0.0]), None);
        // The negated quaternion is the same rotation.
        let q = YawPitch {
            yaw_rad: deg(120.0),
            pitch_rad: deg(-30.0),
        }
        .to_quaternion();
        let b = YawPitch::from_quaternion(q.map(|v| -v)).unwrap();
        assert!(
            (wrap_pi(b.yaw_rad - deg(120.0))).abs() < 1e-5
                && (b.pitch_rad - deg(-30.0)).abs() < 1e-5
        );
    }

    #[test]
    fn roll_is_measured_not_followed() {
        // Yaw 10°, pitch −20°, then roll 15° about the camera axis.
        let base = YawPitch {
            yaw_rad: deg(10.0),
            pitch_rad: deg(-20.0),
        }
        .to_quaternion();
        let (s, c) = (deg(15.0) / 2.0).sin_cos();
        let roll = [c, s, 0.0, 0.0];
        let [a1, b1, c1, d1] = base;
        let [a2, b2, c2, d2] = roll;
        let q = [
            a1 * a2 - b1 * b2 - c1 * c2 - d1 * d2,
            a1 * b2 + b1 * a2 + c1 * d2 - d1 * c2,
            a1 * c2 - b1 * d2 + c1 * a2 + d1 * b2,
            a1 * d2 + b1 * c2 - c1 * b2 + d1 * a2,
        ];
        assert!(YawPitch::from_quaternion(q).is_some());
        // sin(15°)·cos(−20°) = 0.2432, to f32 rounding.
        let expected = deg(15.0).sin() * deg(-20.0).cos();
        assert!(
            (YawPitch::roll_of(q) - expected).abs() < 1e-5,
            "{}",
            YawPitch::roll_of(q)
        );
    }

    proptest! {
        #[test]
        fn round_trip_over_the_gimbals_range(yaw in -179.99f32..180.0, pitch in -100.0f32..=60.0) {
            let a = YawPitch { yaw_rad: deg(yaw), pitch_rad: deg(pitch) };
            let b = YawPitch::from_quaternion(a.to_quaternion()).unwrap();
            prop_assert!((b.pitch_rad - a.pitch_rad).abs() < 1e-5);
            prop_assert!(wrap_pi(b.yaw_rad - a.yaw_rad).abs() < 1e-5);
        }

        /// Any rotation (a direction drawn in the cube, made unit) reads back as angles in
        /// their ranges; only one pitched by 180° exactly has no yaw.
        #[test]
        fn any_unit_quaternion_reads_without_panic(v in proptest::array::uniform4(-1.0f32..1.0)) {
            let n = libm::sqrtf(v.iter().map(|x| x * x).sum());
            prop_assume!(n > 1e-3);
            let q = v.map(|x| x / n);
            match YawPitch::from_quaternion(q) {
                Some(a) => {
                    prop_assert!(a.yaw_rad > -PI - 1e-6 && a.yaw_rad <= PI + 1e-6);
                    prop_assert!(a.pitch_rad.abs() <= PI + 1e-6);
                }
                None => prop_assert!(q[0].abs() < 1e-3 && q[3].abs() < 1e-3, "{:?}", q),
            }
        }
    }
}
