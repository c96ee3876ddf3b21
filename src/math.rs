//! Trigonometry in `f32` arithmetic only, for the Cortex-M4F's single-precision FPU:
//! what the geometry ([`crate::geo::LineOfSight`]) and the MAVLink bridge's attitudes
//! use where `libm`'s `f32` functions would pull in `f64` kernels.

/// π/2 in two parts (Cody and Waite): the high part has 8 significant bits, so `k ×` it is
/// exact for |k| < 2¹⁶; the low part carries the rest, to 2.6·10⁻¹².
const PI_2_HI: f32 = 1.570_312_5;
const PI_2_LO: f32 = 4.838_268e-4;

/// The largest |x|, radians, that [`sin_cos`] takes: out to it the reduction by π/2 keeps
/// the result within a few ulps (further out, the low part's rounding, times the number
/// of quarter turns, grows past them: 10⁻⁶ at 10⁵ rad). A gimbal's angles are within 2π.
pub const DOMAIN: f32 = 6_000.0;

/// Sine and cosine in `f32` arithmetic only.
///
/// `libm::sincosf` computes in `f64` (musl's kernels), which a Cortex-M4F does in software:
/// with it the MAVLink bridge carried about 6 KiB of `f64` routines and a Payne–Hanek table for
/// angles it never sees. Here the angle is reduced by multiples of π/2 (to within 10⁻⁷
/// for |x| ≤ 6000 rad, the f32 rounding of the reduced angle itself, far beyond the
/// half-angles of a gimbal's ±325°) and each quadrant
/// evaluates Taylor polynomials to x⁹ and x¹⁰ on [−π/4, π/4], whose truncation error is
/// below 2·10⁻⁹, under f32 rounding (6·10⁻⁸): the result is within a few ulps of the true
/// value (the tests compare with `f64` on a dense grid). Beyond ±[`DOMAIN`], and for NaN
/// and infinities, both are NaN.
pub fn sin_cos(x: f32) -> (f32, f32) {
    // Beyond the domain, NaN, as for NaN itself (then every step below is NaN; the
    // quadrant's cast of a NaN is 0). On the bits, |x| orders as an integer: one compare
    // for NaN and the infinities too.
    let x = if x.to_bits() << 1 <= DOMAIN.to_bits() << 1 {
        x
    } else {
        f32::NAN
    };
    // The nearest quarter turn, halves away from 0, by the FPU's truncating conversion
    // (`libm::roundf` works on the bits: 40 bytes more). Where the sum rounds up to the
    // next integer, r passes π/4 by the sum's ulp times π/2 at most (4·10⁻⁴ at the
    // domain's end), where the polynomials' truncation is still below 2·10⁻⁹.
    let q = (x * core::f32::consts::FRAC_2_PI + libm::copysignf(0.5, x)) as i32;
    let k = q as f32;
    let r = (x - k * PI_2_HI) - k * PI_2_LO;
    let r2 = r * r;
    let sin =
        r + r * r2 * (-1.0 / 6.0 + r2 * (1.0 / 120.0 + r2 * (-1.0 / 5040.0 + r2 / 362_880.0)));
    let cos = 1.0
        + r2 * (-0.5
            + r2 * (1.0 / 24.0 + r2 * (-1.0 / 720.0 + r2 * (1.0 / 40_320.0 - r2 / 3_628_800.0))));
    // The quadrant: k mod 4 (|k| < 3,820 within the domain).
    match q & 3 {
        0 => (sin, cos),
        1 => (cos, -sin),
        2 => (-sin, -cos),
        _ => (-cos, sin),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sin_cos_is_within_a_few_ulps_of_f64() {
        // Every 1/1000 rad over ±4π, and the gimbal's half-angles' range many times over.
        let mut worst = 0f64;
        for i in -12_566..=12_566 {
            let x = i as f32 / 1000.0;
            let (s, c) = sin_cos(x);
            let (s64, c64) = (f64::from(x).sin(), f64::from(x).cos());
            worst = worst
                .max((f64::from(s) - s64).abs())
                .max((f64::from(c) - c64).abs());
        }
        // f32's ulp at 1 is 1.2e-7: a few ulps.
        assert!(worst < 3e-7, "worst error {worst:e}");
        for x in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            let (s, c) = sin_cos(x);
            assert!(s.is_nan() && c.is_nan());
        }
        // Exact at the quadrant points that matter: 0 and ±π/2 (motor at 0 or ±180°).
        assert_eq!(sin_cos(0.0), (0.0, 1.0));
        let (s, c) = sin_cos(core::f32::consts::FRAC_PI_2);
        assert!((s - 1.0).abs() <= 1e-7 && c.abs() <= 1e-7);
    }

    /// Out to the domain's end, within a few ulps of the `f64` sine and cosine of the `f32`
    /// angle given (not of the real number it rounds); beyond it, NaN rather than a value
    /// that is no sine.
    #[test]
    fn sin_cos_over_its_domain_and_nan_beyond() {
        let mut worst = 0f64;
        // About 200,000 angles spread over the domain, and its ends.
        for i in (-100_000..=100_000).chain([-100_001, 100_001]) {
            let x = i as f32 * DOMAIN / 100_001.0;
            let (s, c) = sin_cos(x);
            let (s64, c64) = (f64::from(x).sin(), f64::from(x).cos());
            worst = worst
                .max((f64::from(s) - s64).abs())
                .max((f64::from(c) - c64).abs());
        }
        std::println!("worst error {worst:e}");
        assert!(worst < 3e-7, "worst error {worst:e}");
        for x in [DOMAIN.next_up(), -DOMAIN.next_up(), 1e10, -1e20, f32::MAX] {
            let (s, c) = sin_cos(x);
            assert!(s.is_nan() && c.is_nan(), "{x}: {s} {c}");
        }
        assert!(!sin_cos(DOMAIN).0.is_nan() && !sin_cos(-DOMAIN).1.is_nan());
    }
}
