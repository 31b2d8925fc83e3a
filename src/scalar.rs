//! The crate's one numeric convention, chosen here and nowhere else.
//!
//! * **Per-pixel work is integer.** Kernel weights are `u32` in `0..=`[`KERNEL_ONE`],
//!   histogram bins are `u32` sums of those weights, and the Bhattacharyya sum is
//!   an integer dot product of square roots (see [`crate::histogram`]). Nothing in a
//!   pixel loop touches floating point, so a Cortex-M0+ without an FPU pays no
//!   soft-float cost there.
//! * **Per-particle and per-frame quantities are [`Real`] (`f32`).** Positions,
//!   half axes, velocities, weights, sigma and confidence are `f32`. Only the
//!   basic IEEE-754 operations (`+ - * /`, comparisons, conversions) are used on
//!   them, plus [`sqrt`] and [`exp`] defined below from those same operations.
//!   IEEE-754 makes each basic operation correctly rounded, and Rust never fuses
//!   a multiply and an add on its own, so the same inputs give the same bits on
//!   x86_64 (SSE), Cortex-M4F (VFP) and a soft-float Cortex-M0+. That is what
//!   makes a seeded run reproducible across targets.
//!
//! No function here calls a platform `libm`: their results differ between
//! platforms in the last bit, which would break reproducibility.

/// The real-number type of the filter state, weights and estimates.
pub type Real = f32;

/// The largest kernel weight, at the centre of an ellipse (`k(0) = 1`).
///
/// 256 levels are far finer than the histogram quantisation, and keep a
/// histogram's total mass below `2^32` for any frame this crate accepts
/// (at most [`crate::pixel::MAX_DIMENSION`]² pixels).
pub const KERNEL_ONE: u32 = 256;

/// Fixed-point scale of the kernel's squared radius (`r² = 1` is `1 << 24`).
pub const RADIUS2_SHIFT: u32 = 24;

/// The square root of `x`, correctly rounded for the cases the tracker uses.
///
/// Computed from an integer bit-level first guess and three Newton steps, using
/// only basic IEEE operations, so it is bit-identical on every target. Returns
/// 0 for zero, negative and NaN input (the callers only take roots of
/// quantities that are non-negative by construction).
///
/// The maximum relative error against `f64::sqrt` is below `2e-7` over
/// `[1e-30, 1e30]` (tested).
pub fn sqrt(x: Real) -> Real {
    // `!(x > 0.0)` also catches NaN.
    if !(x > 0.0) || !x.is_finite() {
        return if x == Real::INFINITY { x } else { 0.0 };
    }
    // Halving the exponent gives a guess within a factor of ~1.06.
    let mut y = Real::from_bits((x.to_bits() >> 1) + 0x1fc0_0000);
    // Each Newton step roughly doubles the number of correct bits:
    // 4 -> 8 -> 16 -> 32 (past the 24 an f32 holds).
    y = 0.5 * (y + x / y);
    y = 0.5 * (y + x / y);
    0.5 * (y + x / y)
}

/// `e^x`, from basic operations only.
///
/// Cody–Waite range reduction `x = k·ln2 + r` with `|r| <= ln2/2`, a
/// degree-6 Taylor polynomial for `e^r` (truncation error below `2e-8`
/// there), and `2^k` built from the exponent bits. Its relative error is
/// below `1e-6` over `[-80, 80]` (tested against f64). Results below the
/// smallest normal `f32` are flushed to 0; NaN gives 0.
pub fn exp(x: Real) -> Real {
    if !(x > -87.0) {
        return 0.0; // also NaN
    }
    let x = x.min(88.0);
    let t = x * core::f32::consts::LOG2_E;
    // Round to nearest; `as` truncates toward zero.
    let k = (if t >= 0.0 { t + 0.5 } else { t - 0.5 }) as i32;
    // ln 2 split into a part exact in f32 and a correction.
    const LN2_HI: Real = 0.693_145_75;
    const LN2_LO: Real = 1.428_606_8e-6;
    let r = (x - k as Real * LN2_HI) - k as Real * LN2_LO;
    let p = 1.0 + r * (1.0 + r * (0.5 + r * (1.0 / 6.0 + r * (1.0 / 24.0 + r * (1.0 / 120.0 + r * (1.0 / 720.0))))));
    // k is in [-126, 127] here, so 2^k is a normal f32.
    let two_k = Real::from_bits(((k + 127).max(1).min(254) as u32) << 23);
    p * two_k
}

/// The natural logarithm of `x`, from basic operations only.
///
/// `x = m · 2^k` with `m` in `[√½, √2)` from the exponent bits, then
/// `ln m = 2 atanh(s)` with `s = (m − 1)/(m + 1)`, `|s| < 0.172`, by five
/// terms of its odd series (truncation below `1e-9`). Relative error below
/// `1e-6` over `[1e-30, 1e30]` (tested against f64). Zero gives
/// `-inf`; negative and NaN input give NaN, as `f32::ln` does.
pub fn ln(x: Real) -> Real {
    if x.is_nan() || x < 0.0 {
        return Real::NAN;
    }
    if x == 0.0 {
        return Real::NEG_INFINITY;
    }
    if x == Real::INFINITY {
        return x;
    }
    // Subnormals: scale into the normal range first.
    let (x, extra) = if x < Real::MIN_POSITIVE { (x * 16_777_216.0, -24i32) } else { (x, 0) };
    let bits = x.to_bits();
    let mut k = ((bits >> 23) & 0xff) as i32 - 127 + extra;
    let mut m = Real::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
    if m > core::f32::consts::SQRT_2 {
        m *= 0.5;
        k += 1;
    }
    let s = (m - 1.0) / (m + 1.0);
    let s2 = s * s;
    let series = s * (2.0 + s2 * (2.0 / 3.0 + s2 * (2.0 / 5.0 + s2 * (2.0 / 7.0 + s2 * (2.0 / 9.0)))));
    const LN2_HI: Real = 0.693_145_75;
    const LN2_LO: Real = 1.428_606_8e-6;
    (k as Real * LN2_HI + series) + k as Real * LN2_LO
}

/// `v` limited to `[lo, hi]`, with NaN mapped to `lo`.
///
/// Unlike `f32::clamp`, it cannot panic (that one asserts `lo <= hi` and
/// formats both in its message, which also drags float formatting into
/// firmware). If `lo > hi`, the result is `hi`.
#[inline(always)]
pub fn clamp(v: Real, lo: Real, hi: Real) -> Real {
    min(max(v, lo), hi)
}

/// The whole part of `v` as an index in `0..=last`: what lies below 0 (and
/// NaN) gives 0, as the conversion saturates, and what lies past `last`
/// gives `last`. The same index as clamping `v` to `[0, last]` first
/// (`last` is a whole number), without the two comparisons, which are
/// library calls on a Cortex-M0+.
#[inline(always)]
pub(crate) fn index_within(v: Real, last: usize) -> usize {
    (v as usize).min(last)
}

/// `i + ½` for each `i` below `N`: the places of `N` samples spread
/// evenly over a side, in steps (a table, so that no sample converts its
/// index).
// Evaluated at compile time only (for a `const`): an index out of range
// would stop the build, never the device.
#[allow(clippy::indexing_slicing)]
pub(crate) const fn half_steps<const N: usize>() -> [Real; N] {
    let mut out = [0.5; N];
    let mut i = 1;
    while i < N {
        out[i] = out[i - 1] + 1.0;
        i += 1;
    }
    out
}

/// The larger of `a` and `b`, or the one that is not NaN: `f32::max`'s
/// answer, by comparisons. `f32::max` is a library call (`fmaxf`) on a
/// Cortex-M4F, and the tracker takes thousands per frame: as calls,
/// `fmaxf` and `fminf` are a visible share of the QVGA audit's
/// instructions (`audit/profile`, docs/performance.md).
#[inline(always)]
pub fn max(a: Real, b: Real) -> Real {
    if a > b || b.is_nan() { a } else { b }
}

/// The smaller of `a` and `b`, or the one that is not NaN (see [`max`]).
#[inline(always)]
pub fn min(a: Real, b: Real) -> Real {
    if a < b || b.is_nan() { a } else { b }
}

/// A uniform sample in `[0, 1)` with 24 bits of resolution, from one `u32`.
pub fn unit_from_bits(bits: u32) -> Real {
    // 24 bits is what an f32 mantissa holds exactly.
    (bits >> 8) as Real * (1.0 / 16_777_216.0)
}

/// A standard-normal sample from one `u64` of randomness.
///
/// It is the Irwin–Hall sum of four 16-bit uniforms, centred and scaled to unit
/// variance: integer work plus one multiply, identical on every target, with no
/// `ln`/`cos` as Box–Muller would need. Its tails stop at ±3.46σ, which is
/// harmless for particle diffusion (and avoids rare huge jumps).
pub fn normal_from_bits(bits: u64) -> Real {
    let sum = (bits & 0xffff) + ((bits >> 16) & 0xffff) + ((bits >> 32) & 0xffff) + (bits >> 48);
    // Mean of the sum is 4 * 65535 / 2; its standard deviation is
    // sqrt(4 * (65536^2 - 1) / 12) = 37837.23.
    // The sum is below 2^18: in i32, the conversion is one instruction
    // (from i64 it is a library call on a Cortex-M4F).
    (sum as i32 - 131_070) as Real * (1.0 / 37_837.23)
}

/// `16 · sqrt(x)`, rounded down, in integers: the square root used by the
/// Bhattacharyya sum.
///
/// The four extra fractional bits keep small histogram bins (a single pixel
/// near the ellipse rim) from being rounded to nothing.
#[inline]
pub fn sqrt_q4(x: u32) -> u32 {
    if x < (1 << 24) { isqrt(x << 8) } else { isqrt(x) << 4 }
}

/// `⌊sqrt(x)⌋`, exactly: a first guess from a table on the top bits of
/// `x`, one integer Newton step and a correction, by whichever of
/// [`isqrt_by_division`] and [`isqrt_by_reciprocal`] suits the core.
///
/// `core`'s `u32::isqrt` is costly per call on the Cortex-M4F (two
/// divisions and a long normalisation), and the Bhattacharyya sum takes
/// one root per non-empty bin of every particle. The Newton step
/// `y + (x − y²)/(2y)` divides: one instruction on a core with a divider
/// (Cortex-M3 and up), a library call on one without (Cortex-M0+, ARM11),
/// where the divisions alone would be a large share of the ARM1136's
/// instructions per frame. Both are exact, so the choice changes no
/// result: tested against `u32::isqrt` on every `x < 2^26`, around every
/// square up to `2^32`, and (ignored by default) on every `u32`.
#[inline(always)]
pub fn isqrt(x: u32) -> u32 {
    if HARDWARE_DIVIDE { isqrt_by_division(x) } else { isqrt_by_reciprocal(x) }
}

/// Whether the target divides in hardware: every host, and the hard-float
/// bare-metal Cortex-M targets (ARMv7E-M: Cortex-M4F and M7). The other ARM
/// targets this crate is built for (Cortex-M0+, and the ARM11s of ARMv6
/// Linux, hard-float for the Raspberry Pi Zero) have no divider; an ARM
/// target wrongly counted among them still computes the same results, a
/// little slower. Hard float alone does not tell: the ARM1176 has a VFP and
/// no integer divider. (Which ARM features a build has is unstable in
/// `cfg`, so the test is on the target's OS and ABI.)
pub(crate) const HARDWARE_DIVIDE: bool =
    !cfg!(target_arch = "arm") || cfg!(all(target_os = "none", target_abi = "eabihf"));

/// [`isqrt`] with one division: the table's guess (within 0.4% of the
/// root), one integer Newton step `⌊(y + ⌊x / y⌋) / 2⌋`, which is
/// `>= ⌊sqrt(x)⌋` from any `y >= 1` and lands at most a couple of units
/// above it, and stepping down while `y² > x`.
#[inline]
pub fn isqrt_by_division(x: u32) -> u32 {
    let top_bit = 31u32.saturating_sub(x.leading_zeros());
    let k = top_bit.saturating_sub(6) & !1;
    let t = (x >> k) as u8;
    // The guess, rounded up (the table's entries are at least 11, so it is
    // never 0; `max` says so to the compiler, which drops the
    // division-by-zero check).
    let guess = ROOT_GUESS.get(t as usize).copied().unwrap_or(u8::MAX) as u32;
    let y = (guess << (k / 2)).div_ceil(16).max(1);
    let mut y = (y + x / y) / 2;
    while (y as u64) * (y as u64) > x as u64 {
        y -= 1;
    }
    y
}

/// [`isqrt`] with no division: the Newton step's division by `2y` is a
/// multiplication by a tabled reciprocal. Why it is exact: whatever the
/// step lands on, stepping down while `y² > x` and up while `(y + 1)² <= x`
/// ends on the root; from the table's guess the step lands within a couple
/// of units of it.
#[inline]
pub fn isqrt_by_reciprocal(x: u32) -> u32 {
    // x >> k in 64..256 (or x itself below 64), k even, so that
    // sqrt(x) = sqrt(x >> k) · 2^h, h = k / 2, up to the bits shifted out.
    let top_bit = 31u32.saturating_sub(x.leading_zeros());
    let k = top_bit.saturating_sub(6) & !1;
    let h = k / 2;
    let t = (x >> k) as u8 as usize;
    // g = 16·sqrt(t + 1/2) (at least 11), r = 2^16 / g.
    let g = ROOT_GUESS.get(t).copied().unwrap_or(u8::MAX) as u32;
    let r = ROOT_RECIPROCAL.get(t).copied().unwrap_or(1) as i32;
    // y ≈ g · 2^h / 16, at most 65,280 (g <= 255, h <= 12): y² fits in
    // 32 bits, and so does x − y² as a signed number (within 1% of x;
    // negative when y is above the root).
    let y = ((g << h) + 8) >> 4;
    let d = x.wrapping_sub(y * y) as i32;
    // (x − y²) / (2y) with 1 / (2y) = 8 / (g · 2^h) = r · 2^-13 · 2^-h:
    // d is shifted first, so that the product fits in 32 bits (|d >> h|
    // < 2^(h+2) and r < 2^13); the bits lost move the step by under one.
    let step = ((d >> h) * r) >> 13;
    let mut y = (y as i32 + step).max(0) as u32;
    while y > 0xffff || y * y > x {
        y -= 1;
    }
    while y < 0xffff && (y + 1) * (y + 1) <= x {
        y += 1;
    }
    y
}

/// `16 · sqrt(t + 1/2)`, rounded, for `t` in `0..256` (the last capped at
/// 255): [`isqrt`]'s first guesses.
static ROOT_GUESS: [u8; 256] = root_guesses();

/// `2^16 / g`, rounded, for each guess `g` of [`ROOT_GUESS`]: [`isqrt`]'s
/// Newton step divides by multiplying.
static ROOT_RECIPROCAL: [u16; 256] = root_reciprocals();

// Indices below 256 in a 256-entry array; `get` is not available in const fns.
#[allow(clippy::indexing_slicing)]
const fn root_guesses() -> [u8; 256] {
    let mut g = [0u8; 256];
    let mut t = 0;
    while t < 256 {
        // round(16·sqrt(t + 1/2)) = round(sqrt(256·t + 128)), by integer search.
        let target = 256 * t as u32 + 128;
        let mut r = 0u32;
        while (r + 1) * (r + 1) <= target {
            r += 1;
        }
        // r = ⌊sqrt(target)⌋; round up when target is past (r + 1/2)².
        if target > r * r + r {
            r += 1;
        }
        g[t] = if r > 255 { 255 } else { r as u8 };
        t += 1;
    }
    g
}

// As above; the guesses are at least 11, so the division is by no zero.
#[allow(clippy::indexing_slicing)]
const fn root_reciprocals() -> [u16; 256] {
    let g = root_guesses();
    let mut r = [0u16; 256];
    let mut t = 0;
    while t < 256 {
        let v = g[t] as u32;
        r[t] = ((65_536 + v / 2) / v) as u16;
        t += 1;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sqrt_matches_f64_reference() {
        // Reason: the reference is the correctly rounded f64 root.
        let mut x = 1e-30f32;
        while x < 1e30 {
            for m in [1.0f32, 1.37, 2.0, 3.3, 7.9] {
                let v = x * m;
                let got = sqrt(v) as f64;
                let want = (v as f64).sqrt();
                assert!(((got - want) / want).abs() < 2e-7, "sqrt({v}) = {got}, want {want}");
            }
            x *= 10.0;
        }
        assert_eq!(sqrt(0.0), 0.0);
        assert_eq!(sqrt(-1.0), 0.0);
        assert_eq!(sqrt(Real::NAN), 0.0);
        assert_eq!(sqrt(4.0), 2.0);
    }

    #[test]
    fn exp_matches_f64_reference() {
        // Reason: the reference is f64's correctly rounded exp.
        let mut x = -80.0f32;
        while x <= 80.0 {
            let got = exp(x) as f64;
            let want = (x as f64).exp();
            assert!(((got - want) / want).abs() < 1e-6, "exp({x}) = {got}, want {want}");
            x += 0.0173;
        }
        assert_eq!(exp(0.0), 1.0);
        assert_eq!(exp(-1000.0), 0.0);
        assert_eq!(exp(Real::NAN), 0.0);
    }

    #[test]
    fn ln_matches_f64_reference() {
        // Reason: the reference is f64's correctly rounded ln; near x = 1,
        // where ln x → 0, the error is judged absolutely.
        let mut x = 1e-30f32;
        while x < 1e30 {
            let got = ln(x) as f64;
            let want = (x as f64).ln();
            assert!((got - want).abs() <= 1e-6 * want.abs().max(1.0), "ln({x}) = {got}, want {want}");
            x *= 1.0137;
        }
        for x in [
            0.5f32,
            0.999,
            1.0,
            1.001,
            core::f32::consts::SQRT_2 * 0.9999,
            core::f32::consts::SQRT_2 * 1.0001,
            2.0,
            3.0,
            1e-40,
        ] {
            let (got, want) = (ln(x) as f64, (x as f64).ln());
            assert!((got - want).abs() <= 1e-6 * want.abs().max(1.0), "ln({x}) = {got}, want {want}");
        }
        assert_eq!(ln(1.0), 0.0);
        assert_eq!(ln(0.0), Real::NEG_INFINITY);
        assert!(ln(-1.0).is_nan() && ln(Real::NAN).is_nan());
    }

    #[test]
    fn max_and_min_agree_with_f32() {
        // Reason: `f32::max`/`min` are the reference (NaN gives the other
        // argument); every pair from a set with NaN, infinities, zeros and
        // ordinary values.
        let v = [Real::NAN, Real::INFINITY, -Real::INFINITY, 0.0, 1.0, -1.0, 2.5, -7.25, Real::MAX, Real::MIN];
        for &a in &v {
            for &b in &v {
                let same = |x: Real, y: Real| x == y || (x.is_nan() && y.is_nan());
                assert!(same(max(a, b), a.max(b)), "max({a}, {b})");
                assert!(same(min(a, b), a.min(b)), "min({a}, {b})");
            }
        }
        assert_eq!(clamp(Real::NAN, 0.0, 1.0), 0.0);
        assert_eq!(clamp(5.0, 0.0, 1.0), 1.0);
        assert_eq!(clamp(5.0, 2.0, 1.0), 1.0);
    }

    #[test]
    fn isqrt_is_the_exact_root() {
        // Reason: `u32::isqrt` from core is the reference. Every x below
        // 2^26 (2^22 in unoptimised builds, to keep them fast), then for
        // every root r the values where the answer changes: r² − 1, r², r² + 1.
        let limit = if cfg!(debug_assertions) { 1u32 << 22 } else { 1 << 26 };
        for f in [isqrt_by_division, isqrt_by_reciprocal] {
            for x in 0..limit {
                assert_eq!(f(x), x.isqrt(), "x = {x}");
            }
            for r in 0..=u16::MAX as u32 {
                let sq = r * r;
                for x in [sq.wrapping_sub(1), sq, sq + 1, sq + r, sq + 2 * r] {
                    assert_eq!(f(x), x.isqrt(), "x = {x}");
                }
            }
            assert_eq!(f(u32::MAX), 65_535);
        }
    }

    #[test]
    #[ignore = "every u32: about a minute; run with --ignored after changing isqrt"]
    fn isqrt_is_the_exact_root_everywhere() {
        for x in 0..=u32::MAX {
            assert_eq!(isqrt_by_division(x), x.isqrt(), "x = {x}");
            assert_eq!(isqrt_by_reciprocal(x), x.isqrt(), "x = {x}");
        }
    }

    #[test]
    fn sqrt_q4_matches_f64() {
        // Reason: 16*sqrt(x) rounded down, compared with the f64 value; the
        // large-x branch drops up to 4 fractional bits, i.e. < 16 units of 2^-4,
        // which is below 1e-3 relative for x >= 2^24.
        for x in [0u32, 1, 2, 3, 255, 256, 1000, 65_535, (1 << 24) - 1, 1 << 24, 1 << 30, u32::MAX] {
            let got = sqrt_q4(x) as f64;
            let want = 16.0 * (x as f64).sqrt();
            assert!(got <= want + 1e-9, "x={x}");
            if x < (1 << 24) {
                assert!(want - got < 1.0, "x={x}: {got} vs {want}");
            } else {
                assert!((want - got) / want < 1e-3, "x={x}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn normal_has_unit_variance_and_zero_mean() {
        // Reason: an Irwin-Hall(4) sum rescaled this way has mean 0 and variance 1
        // exactly; 200k samples put the estimates within a few 1e-3.
        let mut state = 0x1234_5678_9abc_def0u64;
        let (mut s1, mut s2) = (0.0f64, 0.0f64);
        let n = 200_000;
        for _ in 0..n {
            // splitmix64, as an independent source of bits
            state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^= z >> 31;
            let v = normal_from_bits(z) as f64;
            s1 += v;
            s2 += v * v;
        }
        let mean = s1 / n as f64;
        let var = s2 / n as f64 - mean * mean;
        assert!(mean.abs() < 0.01, "mean {mean}");
        assert!((var - 1.0).abs() < 0.02, "var {var}");
    }

    #[test]
    fn unit_is_in_half_open_interval() {
        assert_eq!(unit_from_bits(0), 0.0);
        assert!(unit_from_bits(u32::MAX) < 1.0);
    }
}
