//! Special functions used by the samplers, in single precision like Mitsuba's `scalar_rgb`.
//!
//! Polynomial coefficients are Giles's, digit for digit (some exceed f32 precision).
#![allow(clippy::excessive_precision)]

/// Error function (libm's single-precision `erff`, max error < 1 ulp).
#[inline]
pub fn erf(x: f32) -> f32 {
    libm::erff(x)
}

/// Inverse error function, M. Giles, "Approximating the erfinv function" (GPU Computing Gems
/// Jade, 2011), single-precision branch set: relative error below 4e-7 on (-1, 1). This is the
/// approximation Dr.Jit (and so Mitsuba 3) uses, so Beckmann visible-normal samples agree with
/// Mitsuba's to float precision.
#[inline]
pub(crate) fn erfinv(x: f32) -> f32 {
    let mut w = -((1.0 - x) * (1.0 + x)).ln();
    let p = if w < 5.0 {
        w -= 2.5;
        let mut p = 2.810_226_36e-08_f32;
        p = 3.432_739_39e-07 + p * w;
        p = -3.523_387_7e-06 + p * w;
        p = -4.391_506_54e-06 + p * w;
        p = 0.000_218_580_87 + p * w;
        p = -0.001_253_725_03 + p * w;
        p = -0.004_177_681_64 + p * w;
        p = 0.246_640_727 + p * w;
        1.501_409_41 + p * w
    } else {
        w = w.sqrt() - 3.0;
        let mut p = -0.000_200_214_257_f32;
        p = 0.000_100_950_558 + p * w;
        p = 0.001_349_343_22 + p * w;
        p = -0.003_673_428_44 + p * w;
        p = 0.005_739_507_73 + p * w;
        p = -0.007_622_461_3 + p * w;
        p = 0.009_438_870_47 + p * w;
        p = 1.001_674_06 + p * w;
        2.832_976_82 + p * w
    };
    p * x
}

/// `sqrt(max(x, 0))`: square root of a quantity that is non-negative up to rounding.
#[inline]
pub(crate) fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

/// `|a| * sign(b)`, with the sign of `b` taken from its sign bit (so `-0.0` counts as negative).
#[inline]
pub(crate) fn mulsign(a: f32, b: f32) -> f32 {
    if b.is_sign_negative() {
        -a
    } else {
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn erfinv_inverts_erf() {
        for i in 1..200 {
            let x = -0.995 + i as f32 * 0.00995;
            let y = erf(erfinv(x));
            assert!((y - x).abs() < 2e-6, "x={x} erf(erfinv(x))={y}");
        }
    }
}
