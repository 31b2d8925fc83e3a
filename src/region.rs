//! Walking the pixels of an elliptical region, with kernel weights and
//! subsampling. This is the one place that rasterises an ellipse; the colour
//! and edge cues both build on it, so they always see the same pixels with the
//! same weights.
//!
//! The kernel is `k(r) = 1 − r²` with `r² = (dx/Hx)² + (dy/Hy)²`, in integers:
//! `r²` in units of `2^-24` and the weight in `0..=`[`KERNEL_ONE`]. Because a
//! histogram is normalised by its own total, any subset of the pixels gives a
//! correctly normalised estimate of the same distribution, which is what makes
//! subsampling legitimate.

use crate::frame::Frame;
use crate::geometry::Ellipse;
use crate::pixel::MAX_DIMENSION;
use crate::scalar::{HARDWARE_DIVIDE, KERNEL_ONE, RADIUS2_SHIFT, Real};

/// Which pixels of a region are read.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Sampling {
    /// Every pixel.
    Full,
    /// Pixels with `x + y` even: half of them, in a pattern that still covers
    /// every row and column (the third paper's checkerboard).
    #[default]
    Checkerboard,
    /// Pixels with both `x` and `y` even: a quarter.
    Quarter,
}

/// The sampling lattice of one region: every `step`-th row and column,
/// optionally thinned to a checkerboard of `step`-sized cells.
///
/// The lattice is anchored to the frame (not to the region), so overlapping
/// particles read the same pixels and their histograms differ only by what
/// they cover.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(crate) struct Lattice {
    step: u32,
    checker: bool,
}

impl Lattice {
    /// Every pixel.
    pub(crate) const FULL: Lattice = Lattice { step: 1, checker: false };

    /// The default checkerboard: pixels with `x + y` even.
    pub(crate) const CHECKERBOARD: Lattice = Lattice { step: 1, checker: true };

    /// The lattice for `sampling`, coarsened if needed so that an ellipse with
    /// half axes `hx`, `hy` yields at most about `max_samples` samples
    /// (`0` means no limit).
    pub(crate) fn new(sampling: Sampling, max_samples: u32, hx: Real, hy: Real) -> Self {
        let mut l = Self::with_step(sampling, 1);
        if max_samples == 0 {
            return l;
        }
        // Expected samples: area · density, density = 1/step² (halved by the checker).
        let area = core::f32::consts::PI * hx.max(0.5) * hy.max(0.5);
        let density = if l.checker { 0.5 } else { 1.0 };
        let want = area * density / max_samples as Real;
        if want > (l.step * l.step) as Real {
            // Smallest step with area·density/step² <= max_samples.
            let s = crate::scalar::sqrt(want);
            let mut s_int = s as u32;
            if (s_int as Real) < s {
                s_int += 1;
            }
            l.step = s_int.max(l.step).min(MAX_DIMENSION as u32);
        }
        l
    }

    /// The lattice of `sampling` with at least `step` rows and columns
    /// between samples (`Quarter` is at least 2; at most `MAX_DIMENSION`).
    pub(crate) fn with_step(sampling: Sampling, step: usize) -> Self {
        let (base, checker) = match sampling {
            Sampling::Full => (1u32, false),
            Sampling::Checkerboard => (1, true),
            Sampling::Quarter => (2, false),
        };
        Lattice { step: (step.min(MAX_DIMENSION) as u32).max(base), checker }
    }

    /// Rows and columns between samples.
    pub(crate) fn step(&self) -> usize {
        // At least 1 by construction; said here so divisions need no check.
        self.step.max(1) as usize
    }

    /// Pixels between consecutive samples of a row.
    pub(crate) fn x_step(&self) -> usize {
        let s = self.step() as u32;
        // At least 1, said so that divisions need no check.
        (if self.checker { 2 * s } else { s }).max(1) as usize
    }

    /// The first sampled column of row `y` (on a checkerboard, odd cell rows
    /// start one cell in).
    pub(crate) fn phase(&self, y: usize) -> usize {
        let s = self.step.max(1) as usize;
        if self.checker && div_small(y as u32, s as u32) % 2 == 1 { s } else { 0 }
    }

    /// Whether pixel `(x, y)` is on the lattice: the same pixels
    /// [`for_each_row`] visits (rows at multiples of the step; on a
    /// checkerboard, odd cell rows shifted by one cell).
    pub(crate) fn contains(&self, x: usize, y: usize) -> bool {
        let phase = self.phase(y);
        y.is_multiple_of(self.step.max(1) as usize) && x >= phase && (x - phase).is_multiple_of(self.x_step())
    }
}

/// The quadrant of pixel `(x, y)` in an ellipse centred on pixel `centre`:
/// 0 top-left, 1 top-right, 2 bottom-left, 3 bottom-right (the centre row
/// and column count as bottom and right). The one definition of the
/// quadrant layout, shared by the histograms and the bin-count choice.
#[inline(always)]
pub(crate) fn quadrant(x: usize, y: usize, centre: (i32, i32)) -> usize {
    (x as i32 >= centre.0) as usize + 2 * (y as i32 >= centre.1) as usize
}

/// The rows of an ellipse as the region walk sees them: for each row offset
/// `dy` from the centre pixel, the half width `d` of the pixels it visits
/// (`|dx| <= d`), the pixels whose kernel weight is non-zero. The same for
/// every position of an ellipse of given half axes, which is what lets a
/// window slide.
pub(crate) struct Extents {
    ax: u32,
    ay: u32,
    ry: i32,
}

impl Extents {
    /// The extents of ellipses with the half axes of `e` (its centre is not used).
    pub(crate) fn new(e: &Ellipse) -> Option<Self> {
        let r = Raster::new(&Ellipse { cx: 0.0, cy: 0.0, ..*e })?;
        Some(Extents { ax: r.ax, ay: r.ay, ry: r.ry })
    }

    /// Largest row offset.
    pub(crate) fn ry(&self) -> i32 {
        self.ry
    }

    /// The half width of row `dy`, or `None` if that row has no pixel.
    pub(crate) fn half_width(&self, dy: i32) -> Option<i32> {
        let one = 1u64 << RADIUS2_SHIFT;
        // A pixel counts when its weight (one − r²) >> 16 is non-zero.
        let min_gap = 1u64 << (RADIUS2_SHIFT - KERNEL_ONE.trailing_zeros());
        let dy = dy.unsigned_abs() as u64;
        let ry2 = dy * dy * self.ay as u64;
        let room = one.checked_sub(ry2)?.checked_sub(min_gap)?;
        // Largest d with d²·ax <= room.
        let ax = self.ax.max(1) as u64;
        let mut d = (room / ax).isqrt();
        while d > 0 && d * d * ax > room {
            d -= 1;
        }
        while (d + 1) * (d + 1) * ax <= room {
            d += 1;
        }
        Some(d as i32)
    }
}

/// The integer form of one ellipse, ready for rasterising.
///
/// `r²` is `dx²·ax + dy²·ay` in units of `2^-24`: `ax = 2^24 / Hx²`. The centre
/// is the pixel that contains the real centre; the half-pixel this moves the
/// kernel by is far below what a histogram can see.
pub(crate) struct Raster {
    /// The centre pixel.
    pub cx: i32,
    pub cy: i32,
    /// `2^24 / Hx²` and `2^24 / Hy²`.
    pub ax: u32,
    pub ay: u32,
    /// Largest row offset.
    pub ry: i32,
    /// `⌊Hx⌋`: where [`widen`] can start the centre row's half width (a
    /// step or so from it).
    pub rx: u32,
}

impl Raster {
    pub(crate) fn new(e: &Ellipse) -> Option<Self> {
        // The tracker keeps centres and axes finite and bounded; a caller passing
        // garbage gets an empty region rather than a panic.
        if !(e.cx.is_finite() && e.cy.is_finite() && e.hx.is_finite() && e.hy.is_finite()) {
            return None;
        }
        let limit = (2 * MAX_DIMENSION) as Real;
        if e.cx.abs() > limit || e.cy.abs() > limit {
            return None;
        }
        // Half axes below half a pixel would make ax exceed 2^26; such a region
        // is its centre pixel anyway. Above MAX_DIMENSION, ax would round to 0.
        let hx = crate::scalar::clamp(e.hx, 0.5, MAX_DIMENSION as Real);
        let hy = crate::scalar::clamp(e.hy, 0.5, MAX_DIMENSION as Real);
        let one = (1u32 << RADIUS2_SHIFT) as Real;
        Some(Raster {
            cx: floor(e.cx),
            cy: floor(e.cy),
            ax: (one / (hx * hx)) as u32,
            ay: (one / (hy * hy)) as u32,
            ry: hy as i32,
            rx: hx as u32,
        })
    }
}

/// `⌊v⌋` for values the tracker keeps in range (the pixel containing `v`).
pub(crate) fn floor(v: Real) -> i32 {
    let t = v as i32;
    if (t as Real) > v { t - 1 } else { t }
}

/// The smallest `v >= from` with `v ≡ phase (mod modulus)`, for `from >= 0`.
#[inline(always)]
fn align_up(from: i32, modulus: usize, phase: usize) -> i32 {
    align_up_on::<HARDWARE_DIVIDE>(from, modulus, phase)
}

/// [`align_up`] for a core with (`HW`) or without a divider.
#[inline(always)]
fn align_up_on<const HW: bool>(from: i32, modulus: usize, phase: usize) -> i32 {
    let m = (modulus as u32).max(1);
    // Moduli 1 and 2 (every pixel, checkerboard, quarter) are the common
    // case: no division for them, which a Cortex-M0+ or an ARM11 does in
    // software (a library call, many times a shift's cost). Otherwise at most
    // one, none for a power of two: the phase is below the modulus (a
    // lattice's phase is 0 or its step, its column step being twice that),
    // and `p + m − f % m` is below `2m`, so a subtraction reduces both.
    match m {
        1 => from,
        2 => from + ((phase as i32 - from) & 1),
        _ => {
            let f = from.max(0) as u32;
            let p = if (phase as u32) < m { phase as u32 } else { phase as u32 % m };
            // The default checkerboard, thinned to step 2, has a column step of 4.
            let v = p + m - if !HW && m.is_power_of_two() { f & (m - 1) } else { f % m };
            from + (if v >= m { v - m } else { v }) as i32
        }
    }
}

/// The kernel weights along one row of samples, by finite differences: the
/// weight numerator `t = one − r²` is a quadratic in the sample index, so
/// each sample costs two additions instead of a multiply and a range test.
/// Arithmetic wraps: every `t` that is read lies in `2^16..=2^24`, so the
/// wrapped values are the exact ones (only the differences past the last
/// sample, never read, may overflow).
#[derive(Copy, Clone, Debug)]
pub(crate) struct Kernel {
    t: i32,
    d: i32,
    dd: i32,
}

impl Kernel {
    /// The weights of a row whose first sample is `u` pixels right of the
    /// centre column, samples `dx` apart, for `rem = one − ry2` (the row's
    /// share of the unit): `t(u) = rem − ax·u²` and its first and second
    /// differences.
    #[inline(always)]
    pub(crate) fn start(rem: u32, ax: u32, u: i32, dx: i32) -> Self {
        let ax = ax as i32;
        Kernel {
            t: (rem as i32).wrapping_sub(ax.wrapping_mul(u).wrapping_mul(u)),
            d: ax.wrapping_mul(dx).wrapping_mul(u.wrapping_mul(2).wrapping_add(dx)).wrapping_neg(),
            dd: ax.wrapping_mul(dx).wrapping_mul(dx).wrapping_mul(-2),
        }
    }

    /// The weight of the current sample (at least 1), then moves to the next.
    #[inline(always)]
    pub(crate) fn next_weight(&mut self) -> u32 {
        let w = (self.t >> (RADIUS2_SHIFT - KERNEL_ONE.trailing_zeros())) as u32;
        self.t = self.t.wrapping_add(self.d);
        self.d = self.d.wrapping_add(self.dd);
        w
    }
}

/// [`Kernel`] two samples at a time: the weight numerators `a` and `b`
/// of a pair, with the differences `e = b − a` and `f` (the step from `b`
/// to the next pair's `a`) moved by the second difference: four additions
/// a pair with `dd` the only constant, so that a loop over pairs keeps one
/// value fewer in registers than with `d` and `dd` (and `2·dd`).
#[derive(Copy, Clone, Debug)]
pub(crate) struct PairKernel {
    a: i32,
    e: i32,
    f: i32,
    dd: i32,
}

impl PairKernel {
    /// The pairs of `k`'s samples from its current one.
    #[inline(always)]
    pub(crate) fn new(k: Kernel) -> Self {
        PairKernel { a: k.t, e: k.d, f: k.d.wrapping_add(k.dd), dd: k.dd }
    }

    /// The two weights of the current pair clamped to 0 below (for samples
    /// just past the row's ends, which get none), then moves to the next
    /// pair.
    #[inline(always)]
    pub(crate) fn next_pair_or_zero(&mut self) -> (u32, u32) {
        let shift = RADIUS2_SHIFT - KERNEL_ONE.trailing_zeros();
        let b = self.a.wrapping_add(self.e);
        let w = ((self.a.max(0) >> shift) as u32, (b.max(0) >> shift) as u32);
        self.a = b.wrapping_add(self.f);
        self.e = self.f.wrapping_add(self.dd);
        self.f = self.e.wrapping_add(self.dd);
        w
    }
}

/// The sampled pixels of one row of an ellipse: `n` samples from pixel `x`,
/// `dx` pixels apart, every one with a kernel weight of at least 1. Also an
/// iterator over `(x, weight)` for the callers that are not per-pixel hot.
pub(crate) struct RowSpan<'a> {
    /// Row index.
    pub y: usize,
    /// The row's pixel bytes.
    pub row: &'a [u8],
    /// The first sampled pixel.
    pub x: usize,
    /// Number of samples.
    pub n: usize,
    /// Pixels between samples.
    pub dx: usize,
    /// Weights of the samples, from the first.
    pub kernel: Kernel,
}

impl Iterator for RowSpan<'_> {
    type Item = (usize, u32);

    #[inline(always)]
    fn next(&mut self) -> Option<(usize, u32)> {
        if self.n == 0 {
            return None;
        }
        let x = self.x;
        self.n -= 1;
        self.x += self.dx;
        Some((x, self.kernel.next_weight()))
    }
}

/// Calls `visit` with each row of pixels of `frame` on `lattice` inside
/// ellipse `e` whose kernel weight is at least 1 (`k(r) = 1 − r²` in
/// `1..=KERNEL_ONE`). Pixels outside the frame are skipped, so a region
/// partly off-frame is the part that is on it. Row by row, so that callers
/// can hoist per-row work out of the per-pixel loop.
#[inline(always)]
pub(crate) fn for_each_row<F: FnMut(RowSpan<'_>)>(frame: &Frame<'_>, e: &Ellipse, lattice: Lattice, mut visit: F) {
    let Some(r) = Raster::new(e) else { return };
    let one = 1u32 << RADIUS2_SHIFT;
    // A pixel counts when its weight (one − r²) >> 16 is non-zero: r² may
    // be at most `one − min_gap`.
    let min_gap = 1u32 << (RADIUS2_SHIFT - KERNEL_ONE.trailing_zeros());
    let (width, height) = (frame.width() as i32, frame.height() as i32);
    let s = lattice.step as i32;
    let dx = lattice.x_step() as i32;
    let y_lo = align_up((r.cy - r.ry).max(0), s as usize, 0);
    let y_hi = (r.cy + r.ry).min(height - 1);
    let mut y = y_lo;
    // The widest |dx| of the previous row: a row's width differs little from
    // its neighbour's, so walking from it is cheaper than a square root.
    let mut dx_max: u32 = 0;
    while y <= y_hi {
        // `|dy| <= ry = ⌊Hy⌋` on every row walked, so `dy²·ay <= Hy²·2^24 /
        // Hy² = 2^24`: the product fits 32 bits, and plain multiplications
        // (a checked one is a 64-bit library call on a Cortex-M0+, twice a
        // row of every region) give it exactly.
        let dy = y.abs_diff(r.cy);
        let ry2 = dy.wrapping_mul(dy).wrapping_mul(r.ay);
        if let Some(rem) = one.checked_sub(min_gap).and_then(|m| m.checked_sub(ry2))
            && let Some(row) = frame.row(y as usize)
        {
            widen(&mut dx_max, rem, r.ax);
            let half = dx_max as i32;
            let x_lo = (r.cx - half).max(0);
            let x_hi = (r.cx + half).min(width - 1);
            let first = align_up(x_lo, dx as usize, lattice.phase(y as usize));
            if first <= x_hi {
                let n = div_small((x_hi - first) as u32, dx as u32) as usize + 1;
                let kernel = Kernel::start(one - ry2, r.ax, first - r.cx, dx);
                visit(RowSpan { y: y as usize, row, x: first as usize, n, dx: dx as usize, kernel });
            }
        }
        y += s;
    }
}

/// Moves `dx_max` to the widest `|dx|` with `dx²·ax <= rem` (the same as
/// `isqrt(rem / ax)`), walking from the previous row's width: a row's width
/// differs little from its neighbour's, so this is cheaper than a square
/// root. In 32 bits: `ax <= 2^26` (half axes >= 0.5), the walk starts from
/// a width whose `dx²·ax` fitted an earlier row's `rem` (< 2^24), or from
/// [`Raster::rx`] (`⌊Hx⌋²·ax <= Hx²·2^24 / Hx² = 2^24`), and each
/// step up tests `(d + 1)²·ax <= 4·d²·ax <= 2^26` for `d >= 1`, so no
/// product reaches 2^32.
#[inline(always)]
pub(crate) fn widen(dx_max: &mut u32, rem: u32, ax: u32) {
    let fits = |d: u32| d.wrapping_mul(d).wrapping_mul(ax) <= rem;
    while !fits(*dx_max) && *dx_max > 0 {
        *dx_max -= 1;
    }
    while fits(*dx_max + 1) {
        *dx_max += 1;
    }
}

/// [`widen`] for a `rem` no larger than the one `dx_max` was widened for
/// (rows further from the centre): the width can only narrow.
#[inline(always)]
pub(crate) fn shrink(dx_max: &mut u32, rem: u32, ax: u32) {
    while *dx_max > 0 && dx_max.wrapping_mul(*dx_max).wrapping_mul(ax) > rem {
        *dx_max -= 1;
    }
}

/// `a / b` for `b >= 1`, with no division for the common steps 1 and 2,
/// and on cores without a divider (a Cortex-M0+ or an ARM11 divides in
/// software) none for the other powers of two either: the default
/// checkerboard thinned to step 2 has a column step of 4 (on the ARM1136
/// the shifts here and in [`align_up`] save a visible share of a QVGA
/// frame's instructions, docs/performance.md; on a Cortex-M4F the division
/// is one instruction, fewer than the test and shift).
#[inline(always)]
pub(crate) fn div_small(a: u32, b: u32) -> u32 {
    div_small_on::<HARDWARE_DIVIDE>(a, b)
}

/// [`div_small`] for a core with (`HW`) or without a divider.
#[inline(always)]
fn div_small_on<const HW: bool>(a: u32, b: u32) -> u32 {
    match b {
        0 | 1 => a,
        2 => a >> 1,
        _ if !HW && b.is_power_of_two() => a >> b.trailing_zeros(),
        _ => a / b,
    }
}

/// Calls `visit(row, x, y, weight)` for every pixel of `frame` on `lattice`
/// inside ellipse `e` (see [`for_each_row`]): the per-pixel form, for tests.
#[cfg(test)]
pub(crate) fn for_each_in_ellipse<F: FnMut(&[u8], usize, usize, u32)>(
    frame: &Frame<'_>,
    e: &Ellipse,
    lattice: Lattice,
    mut visit: F,
) {
    for_each_row(frame, e, lattice, |span| {
        let (y, row) = (span.y, span.row);
        for (x, w) in span {
            visit(row, x, y, w);
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn div_small_divides() {
        // Reason: the definition, on every divisor its callers can pass.
        // Both forms, with a divider and without.
        for b in 1..70u32 {
            for a in 0..5000u32 {
                assert_eq!(div_small_on::<true>(a, b), a / b, "{a} / {b}");
                assert_eq!(div_small_on::<false>(a, b), a / b, "{a} / {b}");
            }
        }
    }

    #[test]
    fn align_up_is_the_next_value_of_the_phase() {
        // Reason: the definition, checked directly: the smallest v >= from
        // with v ≡ phase (mod m), for phases below and above the modulus,
        // in both forms (with a divider and without).
        for m in 1..12usize {
            for phase in 0..3 * m {
                for from in 0..200i32 {
                    for v in [align_up_on::<true>(from, m, phase), align_up_on::<false>(from, m, phase)] {
                        assert!(v >= from && v - from < m as i32, "from {from} m {m} phase {phase}: {v}");
                        assert_eq!(v as usize % m, phase % m, "from {from} m {m} phase {phase}: {v}");
                    }
                }
            }
        }
    }
    use crate::frame::PixelFormat;

    fn count(frame: &Frame<'_>, e: &Ellipse, l: Lattice) -> (u32, u64) {
        let (mut n, mut mass) = (0u32, 0u64);
        for_each_in_ellipse(frame, e, l, |_, _, _, w| {
            n += 1;
            mass += w as u64;
        });
        (n, mass)
    }

    fn lattice(s: Sampling) -> Lattice {
        Lattice::new(s, 0, 1.0, 1.0)
    }

    #[test]
    fn kernels_follow_the_closed_form() {
        // Reason: the weight of the sample u pixels right of the centre is
        // max(0, rem − ax·u²) >> 16, by definition; both finite-difference
        // forms must give exactly that, sample by sample, including the
        // clamped samples past the row's ends.
        let mut next = crate::testing::lcg(7);
        let shift = RADIUS2_SHIFT - KERNEL_ONE.trailing_zeros();
        for _ in 0..500 {
            let mut draw = |n: u32| (next() >> 8) % n;
            let ax = 1 + draw(1 << 20);
            let rem = (1 << 16) + draw((1 << 24) - (1 << 16));
            let half = (rem as f64 / ax as f64).sqrt() as i32;
            let (u0, dx) = (-half - 2 - draw(3) as i32, 1 + draw(2) as i32);
            let want = |i: i32| {
                let u = (u0 + i * dx) as i64;
                ((rem as i64 - ax as i64 * u * u).max(0) >> shift) as u32
            };
            let n = 2 * (half + 3) / dx + 2;
            let mut single = Kernel::start(rem, ax, u0, dx);
            let mut pairs = PairKernel::new(Kernel::start(rem, ax, u0, dx));
            for i in 0..n {
                let w = want(i);
                // next_weight is only read where the weight is >= 1.
                if w >= 1 {
                    assert_eq!(single.next_weight(), w, "single, sample {i}");
                } else {
                    single.next_weight();
                }
                if i % 2 == 0 {
                    assert_eq!(pairs.next_pair_or_zero(), (w, want(i + 1)), "pair from sample {i}");
                }
            }
        }
    }

    #[test]
    fn ellipse_covers_its_area() {
        // Reason: an ellipse with half axes a, b covers π·a·b pixels, up to the
        // rim's discretisation (≈ perimeter/2 pixels, under 5% here); the
        // kernel 1 − r² integrates to π·a·b/2, so the mass is 256 · π·a·b/2.
        let buf = vec![0u8; 200 * 200];
        let f = Frame::packed(&buf, 200, 200, PixelFormat::Gray8).unwrap();
        for (a, b) in [(20.0f32, 20.0f32), (30.0, 12.0), (7.0, 15.0)] {
            let e = Ellipse { cx: 100.0, cy: 100.0, hx: a, hy: b };
            let (n, mass) = count(&f, &e, lattice(Sampling::Full));
            let area = core::f64::consts::PI * a as f64 * b as f64;
            assert!((n as f64 - area).abs() / area < 0.05, "{a}x{b}: {n} px vs {area}");
            let want_mass = 256.0 * area / 2.0;
            assert!((mass as f64 - want_mass).abs() / want_mass < 0.05, "{a}x{b}: mass {mass} vs {want_mass}");

            // Reason: checkerboard reads every other pixel, quarter one in four,
            // and both spread evenly, so the kernel mass scales the same way.
            let (nc, mc) = count(&f, &e, lattice(Sampling::Checkerboard));
            let (nq, mq) = count(&f, &e, lattice(Sampling::Quarter));
            assert!((nc as f64 / n as f64 - 0.5).abs() < 0.03, "checkerboard {nc} of {n}");
            assert!((nq as f64 / n as f64 - 0.25).abs() < 0.03, "quarter {nq} of {n}");
            assert!((mc as f64 / mass as f64 - 0.5).abs() < 0.03);
            assert!((mq as f64 / mass as f64 - 0.25).abs() < 0.03);
        }
    }

    #[test]
    fn checkerboard_reads_exactly_the_even_pixels() {
        // Reason: the definition, pixel by pixel.
        let buf = vec![0u8; 50 * 50];
        let f = Frame::packed(&buf, 50, 50, PixelFormat::Gray8).unwrap();
        let e = Ellipse { cx: 25.0, cy: 25.0, hx: 9.0, hy: 6.0 };
        let mut full = Vec::new();
        for_each_in_ellipse(&f, &e, lattice(Sampling::Full), |_, x, y, _| full.push((x, y)));
        let mut checker = Vec::new();
        for_each_in_ellipse(&f, &e, lattice(Sampling::Checkerboard), |_, x, y, _| checker.push((x, y)));
        let want: Vec<_> = full.iter().copied().filter(|(x, y)| (x + y) % 2 == 0).collect();
        assert_eq!(checker, want);
        let mut quarter = Vec::new();
        for_each_in_ellipse(&f, &e, lattice(Sampling::Quarter), |_, x, y, _| quarter.push((x, y)));
        let want: Vec<_> = full.iter().copied().filter(|(x, y)| x % 2 == 0 && y % 2 == 0).collect();
        assert_eq!(quarter, want);
    }

    #[test]
    fn budget_caps_the_sample_count() {
        // Reason: a 60x50 ellipse has ~9400 pixels; a budget of 500 must bring
        // the count down to about 500 (the step is a whole number, so a bit
        // under), while a small region keeps its base lattice untouched.
        let buf = vec![0u8; 200 * 200];
        let f = Frame::packed(&buf, 200, 200, PixelFormat::Gray8).unwrap();
        let e = Ellipse { cx: 100.0, cy: 100.0, hx: 60.0, hy: 50.0 };
        for s in [Sampling::Full, Sampling::Checkerboard, Sampling::Quarter] {
            let l = Lattice::new(s, 500, e.hx, e.hy);
            let (n, _) = count(&f, &e, l);
            assert!((200..=560).contains(&n), "{s:?}: {n} samples, step {}", l.step);
        }
        let small = Lattice::new(Sampling::Checkerboard, 500, 5.0, 5.0);
        assert_eq!(small, lattice(Sampling::Checkerboard));
    }

    #[test]
    fn off_frame_part_is_skipped() {
        // Reason: an ellipse centred on the left edge has half of its pixels on
        // the frame (the column x = 0 is the centre column, so a bit more).
        let buf = vec![0u8; 100 * 100];
        let f = Frame::packed(&buf, 100, 100, PixelFormat::Gray8).unwrap();
        let full = lattice(Sampling::Full);
        let inside = count(&f, &Ellipse { cx: 50.0, cy: 50.0, hx: 10.0, hy: 10.0 }, full).0;
        let edge = count(&f, &Ellipse { cx: 0.0, cy: 50.0, hx: 10.0, hy: 10.0 }, full).0;
        let frac = edge as f64 / inside as f64;
        assert!(frac > 0.5 && frac < 0.6, "{edge} of {inside}");
        // Entirely outside: nothing, and no panic.
        assert_eq!(count(&f, &Ellipse { cx: -50.0, cy: 50.0, hx: 10.0, hy: 10.0 }, full).0, 0);
        assert_eq!(count(&f, &Ellipse { cx: Real::NAN, cy: 50.0, hx: 10.0, hy: 10.0 }, full).0, 0);
        // A degenerate ellipse still reads its centre pixel.
        assert_eq!(count(&f, &Ellipse { cx: 5.5, cy: 5.5, hx: 0.0, hy: 0.0 }, full).0, 1);
    }
}
