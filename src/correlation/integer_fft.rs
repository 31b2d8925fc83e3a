//! A 16-point FFT in integers: the grey-level filter's forward transform.
//!
//! A Cortex-M0+ has no floating point: `microfft`'s butterflies there are
//! library calls (an `f32` multiply is about 70 instructions, an add about
//! 50), and the grey-level filter's four forward transforms a frame took
//! about a sixth of its instructions. In integers a butterfly is a few
//! dozen instructions on every core, and exact: every core computes the
//! same bits, as the crate's one scalar convention asks.
//!
//! Values are `i32`. The factors `e^{−2πik/16}` are kept in units of
//! 2^-15, and a product is rounded to the nearest unit ([`times`], exact
//! for values below 2^30). Nothing is scaled between stages: a transform
//! of values below `2^m` in magnitude gives values below `2^(m+4)` (16
//! terms), so the two passes of a 16 x 16 transform of values below 2^21
//! stay below 2^29.

use num_complex::Complex;

/// A complex value in integers.
pub(super) type Int = Complex<i32>;

/// Points per transform.
pub(super) const N: usize = 16;

/// The unit of the factors: 2^-15 (1 is [`ONE`]).
const SHIFT: u32 = 15;
pub(super) const ONE: i32 = 1 << SHIFT;

/// `(cos, sin)` of `2π k / N` for `k` in `0..N / 2`, in units of 2^-15,
/// rounded, computed at compile time.
const FACTORS: [(i32, i32); N / 2] = factors();

// Evaluated at compile time only (for a `const`): an index out of range
// would stop the build, never the device.
#[allow(clippy::indexing_slicing)]
const fn factors() -> [(i32, i32); N / 2] {
    use core::f64::consts::{FRAC_PI_2, TAU};
    let mut out = [(0, 0); N / 2];
    let mut k = 0;
    while k < N / 2 {
        let a = TAU * k as f64 / N as f64;
        // cos θ = sin(θ + π/2).
        out[k] = (units_f64(super::series::sin(a + FRAC_PI_2)), units_f64(super::series::sin(a)));
        k += 1;
    }
    out
}

/// `v` in units of 2^-15, rounded (halves away from zero), at compile time.
pub(super) const fn units_f64(v: f64) -> i32 {
    if v >= 0.0 { (v * ONE as f64 + 0.5) as i32 } else { -((-v * ONE as f64 + 0.5) as i32) }
}

/// `a · w / 2^15`, rounded to the nearest integer (halves up), exactly,
/// for `|a| < 2^30` and `|w| ≤ 2^15`: in one 64-bit product where the core
/// multiplies 32 by 32 bits into 64 ([`wide`]), in two 32-bit ones where
/// it does not ([`split`]; on the Cortex-M0+ a 64-bit product is a library
/// call of about 40 instructions). The two give the same value. Which
/// core is which: ARMv6-M, the one Cortex-M without the long multiply,
/// is also the one without 32-bit atomic instructions.
#[inline(always)]
pub(super) fn times(a: i32, w: i32) -> i32 {
    if cfg!(target_has_atomic = "32") { wide(a, w) } else { split(a, w) }
}

/// [`times`] in one 64-bit product.
#[inline(always)]
fn wide(a: i32, w: i32) -> i32 {
    ((a as i64 * w as i64 + (1 << (SHIFT - 1))) >> SHIFT) as i32
}

/// [`times`] in 32-bit products: with `a = h · 2^16 + l`, `0 ≤ l < 2^16`,
/// the high part's product is a multiple of 2^15 below 2^30, and the low
/// part's is below 2^31 − 2^15 in magnitude. Out of line: the Cortex-M0+
/// build's code is near its budget, and a call costs a few instructions a
/// product.
#[inline(never)]
fn split(a: i32, w: i32) -> i32 {
    let (high, low) = (a >> 16, a & 0xffff);
    ((high * w) << (16 - SHIFT)) + ((low * w + (1 << (SHIFT - 1))) >> SHIFT)
}

/// The forward transform of `x` in place, `X(k) = Σ x(n) e^{−2πi nk/N}`
/// (unscaled, as `microfft`'s), by radix-2 decimation in time. Inputs
/// below 2^25 in magnitude give outputs below 2^29 (and the factors'
/// rounding), and every product on the way is exact ([`times`]).
pub(super) fn forward(x: &mut [Int; N]) {
    // Into bit-reversed order: the six pairs whose 4-bit indices mirror
    // each other change places (constant indices, within the array).
    x.swap(1, 8);
    x.swap(2, 4);
    x.swap(3, 12);
    x.swap(5, 10);
    x.swap(7, 14);
    x.swap(11, 13);
    // The first two stages, whose factors are 1 and −i: no products.
    for block in x.chunks_exact_mut(4) {
        if let [a, b, c, d] = block {
            let (a0, b0, c0, d0) = (*a + *b, *a - *b, *c + *d, *c - *d);
            let d1 = minus_i(d0);
            (*a, *c) = (a0 + c0, a0 - c0);
            (*b, *d) = (b0 + d1, b0 - d1);
        }
    }
    // The last two, with products where the factor is not 1 or −i.
    stage::<8>(x);
    stage::<16>(x);
}

/// One stage of the transform: butterflies between the halves of each
/// block of `SIZE` values, by the factors `e^{−2πik/SIZE}`.
#[inline(always)]
fn stage<const SIZE: usize>(x: &mut [Int; N]) {
    let stride = N / SIZE;
    for block in x.chunks_exact_mut(SIZE) {
        let (low, high) = block.split_at_mut(SIZE / 2);
        for (k, (a, b)) in low.iter_mut().zip(high.iter_mut()).enumerate() {
            // `b · e^{−iθ}` = `(b.re cos + b.im sin, b.im cos − b.re sin)`.
            let t = match (k * stride, FACTORS.get(k * stride)) {
                (0, _) | (_, None) => *b,
                (4, _) => minus_i(*b),
                (_, Some(&(c, s))) => Int::new(times(b.re, c) + times(b.im, s), times(b.im, c) - times(b.re, s)),
            };
            (*a, *b) = (*a + t, *a - t);
        }
    }
}

/// The inverse transform of `x` in place, unscaled: `x(n) = Σ X(k)
/// e^{2πi nk/N}` (`N` times `microfft`'s inverse), the conjugate of the
/// forward transform of `X`'s conjugate. Bounds as [`forward`]'s.
pub(super) fn inverse(x: &mut [Int; N]) {
    for v in x.iter_mut() {
        v.im = -v.im;
    }
    forward(x);
    for v in x.iter_mut() {
        v.im = -v.im;
    }
}

/// `(cos, sin)` of `2π k / N` in units of 2^-15, for any `k`.
#[inline(always)]
pub(super) fn turn(k: usize) -> (i32, i32) {
    let (c, s) = FACTORS.get(k % (N / 2)).copied().unwrap_or((ONE, 0));
    // Half a turn on: both negated.
    if k % N >= N / 2 { (-c, -s) } else { (c, s) }
}

/// `v · (−i)`.
#[inline(always)]
fn minus_i(v: Int) -> Int {
    Int::new(v.im, -v.re)
}

/// The spectra of two real sequences `a` and `b` from one transform of
/// `a + i b`, doubled (exact in integers): `2 A(k) = Z(k) + Z*(N − k)` and
/// `2 B(k) = −i (Z(k) − Z*(N − k))`, for `k` in `0..=N / 2` (the rest
/// mirror them). Inputs below 2^24 give outputs below 2^29.
pub(super) fn two_real(z: &mut [Int; N], a: &mut [Int], b: &mut [Int]) {
    forward(z);
    let z = &*z;
    for (k, (a, b)) in a.iter_mut().zip(b.iter_mut()).enumerate().take(N / 2 + 1) {
        let (Some(&here), Some(there)) = (z.get(k), z.get((N - k) % N).map(|v| v.conj())) else { continue };
        (*a, *b) = (here + there, minus_i(here - there));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use microfft::Complex32;

    /// A small deterministic generator (the tests need no better).
    fn values(seed: u32, bound: i32) -> impl FnMut() -> i32 {
        let mut s = seed;
        move || {
            s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            ((s >> 8) as i64 * (2 * bound as i64 + 1) / (1 << 24)) as i32 - bound
        }
    }

    #[test]
    fn products_are_exact_and_rounded() {
        // The Cortex-M0+'s way against the definition, the rounded 64-bit
        // product (which `wide` is, as written), over the range the
        // transforms use and its edges.
        let mut next = values(7, (1 << 30) - 1);
        let mut factor = values(11, ONE);
        let edges = [0, 1, -1, (1 << 30) - 1, -(1 << 30) + 1, 0xffff, -0x10000, 12_345_678, -0x3fff_0001];
        for i in 0..20_000 {
            let a = edges.get(i).copied().unwrap_or_else(&mut next);
            let w = [ONE, -ONE, 0, 1].get(i % 7).copied().unwrap_or_else(&mut factor);
            let exact = (a as i64 * w as i64 + (1 << (SHIFT - 1))) >> SHIFT;
            assert_eq!(split(a, w) as i64, exact, "{a} x {w}");
        }
    }

    #[test]
    fn the_factors_are_the_unit_circle_rounded() {
        for (k, &(c, s)) in FACTORS.iter().enumerate() {
            let a = core::f64::consts::TAU * k as f64 / N as f64;
            assert!((c as f64 - a.cos() * ONE as f64).abs() <= 0.5, "cos {k}");
            assert!((s as f64 - a.sin() * ONE as f64).abs() <= 0.5, "sin {k}");
        }
    }

    /// The transform against `microfft`'s in `f32`: the two agree to
    /// within the factors' rounding (a relative 2^-15 a stage) and the
    /// products' (half a unit each), far below what either filter notices.
    #[test]
    fn the_transform_matches_microffts() {
        for (seed, bound) in [(1, 1 << 20), (2, 1000), (3, 3), (4, (1 << 25) - 1)] {
            let mut next = values(seed, bound);
            let mut ints = [Int::new(0, 0); N];
            for v in ints.iter_mut() {
                *v = Int::new(next(), next());
            }
            let mut floats = ints.map(|v| Complex32::new(v.re as f32, v.im as f32));
            forward(&mut ints);
            let floats = microfft::complex::cfft_16(&mut floats);
            let largest = floats.iter().fold(0.0f32, |m, v| m.max(v.re.abs()).max(v.im.abs()));
            for (i, f) in ints.iter().zip(floats.iter()) {
                for (a, b) in [(i.re, f.re), (i.im, f.im)] {
                    assert!((a as f32 - b).abs() <= 4.0 + 4e-4 * largest, "{a} against {b} (bound {bound})");
                }
            }
        }
    }

    /// The largest values the bound allows, laid out to add up at one
    /// output (`e^{2πi nk/N}` at full scale): that output reaches 16 times
    /// the input, and nothing overflows on the way (a debug build, as the
    /// tests are, would panic).
    #[test]
    fn the_largest_inputs_do_not_overflow() {
        let bound = ((1 << 25) - 1) as f64;
        for k in 0..N {
            let mut x = [Int::new(0, 0); N];
            for (n, v) in x.iter_mut().enumerate() {
                let a = core::f64::consts::TAU * (n * k) as f64 / N as f64;
                *v = Int::new((bound * a.cos()) as i32, (bound * a.sin()) as i32);
            }
            forward(&mut x);
            let peak = x.get(k).copied().unwrap_or_default();
            // Within the factors' rounding (2^-15 relative, four stages).
            let within = 16.0 * bound * 4.0 / (1 << 15) as f64;
            assert!(
                (peak.re as f64 - 16.0 * bound).abs() < within && (peak.im.abs() as f64) < within,
                "bin {k}: {peak}"
            );
        }
    }

    /// Two real sequences through one transform against each through its
    /// own: the same spectra (doubled), to within the products' rounding.
    #[test]
    fn two_real_sequences_share_a_transform() {
        let mut next = values(5, (1 << 20) - 1);
        let (mut a, mut b) = ([Int::new(0, 0); N], [Int::new(0, 0); N]);
        let mut z = [Int::new(0, 0); N];
        for ((a, b), z) in a.iter_mut().zip(b.iter_mut()).zip(z.iter_mut()) {
            (a.re, b.re) = (next(), next());
            *z = Int::new(a.re, b.re);
        }
        let (mut two_a, mut two_b) = ([Int::new(0, 0); N / 2 + 1], [Int::new(0, 0); N / 2 + 1]);
        two_real(&mut z, &mut two_a, &mut two_b);
        forward(&mut a);
        forward(&mut b);
        for (alone, shared) in a.iter().zip(two_a.iter()).chain(b.iter().zip(two_b.iter())) {
            let d = 2 * *alone - *shared;
            // Each side's rounding: half a unit a product, ten complex
            // products on the way to an output, twice over.
            assert!(d.re.abs() <= 40 && d.im.abs() <= 40, "{alone} doubled against {shared}");
        }
    }

    /// The inverse against `microfft`'s, which divides by `N`: the same
    /// values times `N`, to within the factors' rounding.
    #[test]
    fn the_inverse_matches_microffts_times_n() {
        let mut next = values(9, (1 << 20) - 1);
        let mut ints = [Int::new(0, 0); N];
        for v in ints.iter_mut() {
            *v = Int::new(next(), next());
        }
        let mut floats = ints.map(|v| Complex32::new(v.re as f32, v.im as f32));
        inverse(&mut ints);
        let floats = microfft::inverse::ifft_16(&mut floats);
        let largest = floats.iter().fold(0.0f32, |m, v| m.max(v.re.abs()).max(v.im.abs())) * N as f32;
        for (i, f) in ints.iter().zip(floats.iter()) {
            for (a, b) in [(i.re, f.re), (i.im, f.im)] {
                assert!((a as f32 - b * N as f32).abs() <= 4.0 + 4e-4 * largest, "{a} against {b} x {N}");
            }
        }
    }

    #[test]
    fn a_turn_is_the_unit_circle_at_any_step() {
        for k in 0..3 * N {
            let a = core::f64::consts::TAU * k as f64 / N as f64;
            let (c, s) = turn(k);
            assert!((c as f64 - a.cos() * ONE as f64).abs() <= 0.5, "cos {k}");
            assert!((s as f64 - a.sin() * ONE as f64).abs() <= 0.5, "sin {k}");
        }
    }
}
