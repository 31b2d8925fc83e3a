//! The series the correlation filters' tables are computed with, at
//! compile time (`core` has no `f64` functions there): `sin`, `exp` and
//! `ln(1 + l)`, each checked against `std`'s by the tables' tests.

/// `sin(a)` for `a ≥ 0`, at compile time only: folded onto `[0, π/2]`,
/// where eleven terms of the Taylor series are accurate to about 1e-12.
pub(super) const fn sin(a: f64) -> f64 {
    use core::f64::consts::{FRAC_PI_2, PI, TAU};
    let mut a = a;
    while a >= TAU {
        a -= TAU;
    }
    let sign = if a > PI { -1.0 } else { 1.0 };
    if a > PI {
        a -= PI;
    }
    let x = if a > FRAC_PI_2 { PI - a } else { a };
    let (mut term, mut sum, mut k) = (x, x, 1);
    while k < 11 {
        term = -term * x * x / ((2 * k) as f64 * (2 * k + 1) as f64);
        sum += term;
        k += 1;
    }
    sign * sum
}

/// `exp(x)` for `0 ≤ x ≤ 64`, at compile time only: `exp(x / 64)` by
/// its series (twelve terms for an argument at most 1), squared six times.
pub(super) const fn exp(x: f64) -> f64 {
    let y = x / 64.0;
    let (mut term, mut sum, mut k) = (1.0, 1.0, 1);
    while k < 12 {
        term = term * y / k as f64;
        sum += term;
        k += 1;
    }
    let mut i = 0;
    while i < 6 {
        sum *= sum;
        i += 1;
    }
    sum
}

/// `ln(1 + l)`, at compile time only.
pub(super) const fn ln_1p(l: usize) -> f64 {
    // ln(x) = k ln 2 + ln(m), x = m 2^k with m in [1, 2); then
    // ln(m) = 2 atanh(t), t = (m − 1) / (m + 1) ≤ 1/3, whose series
    // converges by a factor of 9 a term.
    let (mut m, mut k) = ((l + 1) as f64, 0);
    while m >= 2.0 {
        m /= 2.0;
        k += 1;
    }
    let t = (m - 1.0) / (m + 1.0);
    let (mut power, mut sum, mut n) = (t, 0.0, 0);
    while n < 20 {
        sum += power / (2 * n + 1) as f64;
        power *= t * t;
        n += 1;
    }
    k as f64 * core::f64::consts::LN_2 + 2.0 * sum
}
