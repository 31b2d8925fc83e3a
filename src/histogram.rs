//! Kernel-weighted colour histograms inside an ellipse, the target model, and
//! the Bhattacharyya similarity between them.
//!
//! The histogram of a region is `p(u) = f · Σ k(r_i) δ[h(x_i) − u]` with the
//! kernel `k(r) = 1 − r²` (zero outside the ellipse), where `r` is the pixel's
//! normalised elliptical radius `sqrt((dx/Hx)² + (dy/Hy)²)`. Weighting by the
//! kernel lets the rim, where background leaks in, count less than the centre.
//!
//! All of it is integer (see [`crate::scalar`]): weights are `0..=256`, bins
//! are `u32` sums, and the Bhattacharyya coefficient is an integer dot product
//! of square roots, turned into a [`Real`] once per comparison.

use crate::frame::{Frame, Gray8, PixelFormat, PixelRead, Rgb565, Rgb888, Yuv422};
use crate::geometry::Ellipse;
use crate::scalar::{KERNEL_ONE, RADIUS2_SHIFT, Real, sqrt_q4};

/// How a colour maps to a histogram bin. A component of the configuration,
/// so other colour spaces slot in beside RGB.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, Default)]
pub enum Binning {
    /// RGB quantised to 8 levels per channel: 512 bins (the first paper's choice).
    #[default]
    Rgb8x8x8,
}

impl Binning {
    /// Number of bins this binning uses; a histogram's capacity `K` must be at
    /// least this.
    pub const fn bins(self) -> usize {
        match self {
            Binning::Rgb8x8x8 => 512,
        }
    }

    /// The bin of an 8-bit RGB colour; always below [`Binning::bins`].
    #[inline(always)]
    pub fn bin(self, rgb: [u8; 3]) -> usize {
        match self {
            Binning::Rgb8x8x8 => ((rgb[0] as usize >> 5) << 6) | ((rgb[1] as usize >> 5) << 3) | (rgb[2] as usize >> 5),
        }
    }
}

/// Which pixels of a region are read.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, Default)]
pub enum Sampling {
    /// Every pixel.
    #[default]
    Full,
    /// Pixels with `x + y` even: half of them, in a pattern that still covers
    /// every row and column (the third paper's checkerboard).
    Checkerboard,
    /// Pixels with both `x` and `y` even: a quarter.
    Quarter,
}

/// The integer form of one ellipse, ready for rasterising.
///
/// `r²` is `dx²·ax + dy²·ay` in units of `2^-24`: `ax = 2^24 / Hx²`. The centre
/// is the pixel that contains the real centre; the half-pixel this moves the
/// kernel by is far below what a histogram can see.
struct Raster {
    cx: i32,
    cy: i32,
    ax: u32,
    ay: u32,
    ry: i32,
}

impl Raster {
    fn new(e: &Ellipse) -> Option<Self> {
        // The tracker keeps centres and axes finite and bounded; a caller passing
        // garbage gets an empty region rather than a panic.
        if !(e.cx.is_finite() && e.cy.is_finite() && e.hx.is_finite() && e.hy.is_finite()) {
            return None;
        }
        let limit = (2 * crate::frame::MAX_DIMENSION) as Real;
        if e.cx.abs() > limit || e.cy.abs() > limit {
            return None;
        }
        // Half axes below half a pixel would make ax exceed 2^26; such a region
        // is its centre pixel anyway. Above MAX_DIMENSION, ax would round to 0.
        let hx = e.hx.clamp(0.5, crate::frame::MAX_DIMENSION as Real);
        let hy = e.hy.clamp(0.5, crate::frame::MAX_DIMENSION as Real);
        let one = (1u32 << RADIUS2_SHIFT) as Real;
        Some(Raster {
            cx: floor(e.cx),
            cy: floor(e.cy),
            ax: (one / (hx * hx)) as u32,
            ay: (one / (hy * hy)) as u32,
            ry: hy as i32,
        })
    }
}

fn floor(v: Real) -> i32 {
    let t = v as i32;
    if (t as Real) > v { t - 1 } else { t }
}

/// Calls `visit(row, x, weight)` for every sampled pixel of `frame` inside
/// ellipse `e`, with its kernel weight in `1..=KERNEL_ONE`. Pixels outside the
/// frame are skipped, so a region partly off-frame is the part that is on it.
///
/// This is the one place that walks an elliptical region; every cue builds on it.
#[inline(always)]
pub(crate) fn for_each_in_ellipse<F: FnMut(&[u8], usize, u32)>(
    frame: &Frame<'_>,
    e: &Ellipse,
    sampling: Sampling,
    mut visit: F,
) {
    let Some(r) = Raster::new(e) else { return };
    let one = 1u32 << RADIUS2_SHIFT;
    let w_shift = RADIUS2_SHIFT - KERNEL_ONE.trailing_zeros();
    let (width, height) = (frame.width() as i32, frame.height() as i32);
    let y_lo = (r.cy - r.ry).max(0);
    let y_hi = (r.cy + r.ry).min(height - 1);
    for y in y_lo..=y_hi {
        if sampling == Sampling::Quarter && y % 2 != 0 {
            continue;
        }
        let dy = y.abs_diff(r.cy);
        let ry2 = match dy.checked_mul(dy).and_then(|d| d.checked_mul(r.ay)) {
            Some(v) if v < one => v,
            _ => continue,
        };
        let rem = one - ry2;
        // Widest |dx| with dx²·ax <= rem; ax >= 1 so the division is safe.
        let dx_max = (rem / r.ax.max(1)).isqrt() as i32;
        let mut x = (r.cx - dx_max).max(0);
        let x_hi = (r.cx + dx_max).min(width - 1);
        let step = match sampling {
            Sampling::Full => 1,
            Sampling::Checkerboard => {
                if (x + y) % 2 != 0 {
                    x += 1;
                }
                2
            }
            Sampling::Quarter => {
                if x % 2 != 0 {
                    x += 1;
                }
                2
            }
        };
        let Some(row) = frame.row(y as usize) else { continue };
        while x <= x_hi {
            let dx = x.abs_diff(r.cx);
            // dx <= dx_max, so dx²·ax <= rem < 2^24: no overflow.
            let r2 = ry2 + dx * dx * r.ax;
            if r2 < one {
                let w = (one - r2) >> w_shift;
                if w > 0 {
                    visit(row, x as usize, w);
                }
            }
            x += step;
        }
    }
}

/// A kernel-weighted histogram with capacity for `K` bins: raw integer
/// counts plus their total (its normalisation is implicit, `p(u) = c(u) / total`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Histogram<const K: usize> {
    counts: [u32; K],
    total: u32,
}

impl<const K: usize> Default for Histogram<K> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const K: usize> Histogram<K> {
    /// An empty histogram.
    pub const fn new() -> Self {
        Histogram {
            counts: [0; K],
            total: 0,
        }
    }

    /// The raw weighted counts.
    pub fn counts(&self) -> &[u32; K] {
        &self.counts
    }

    /// The sum of all counts (the normaliser).
    pub fn total(&self) -> u32 {
        self.total
    }

    /// Adds `weight` to bin `bin`; bins past `K` are ignored.
    pub fn add(&mut self, bin: usize, weight: u32) {
        if let Some(c) = self.counts.get_mut(bin) {
            *c = c.saturating_add(weight);
            self.total = self.total.saturating_add(weight);
        }
    }

    /// Replaces the contents with the colour histogram of ellipse `e` in `frame`.
    ///
    /// Bins that `binning` produces at or past `K` are dropped; the tracker's
    /// configuration check rules that out.
    ///
    /// ```
    /// use pftrack::{Binning, Ellipse, Frame, Histogram, PixelFormat, Sampling};
    /// let pixels = [255u8, 0, 0].repeat(16 * 16); // all red
    /// let frame = Frame::packed(&pixels, 16, 16, PixelFormat::Rgb888)?;
    /// let mut h = Histogram::<512>::new();
    /// h.compute(&frame, &Ellipse { cx: 8.0, cy: 8.0, hx: 5.0, hy: 5.0 }, Binning::Rgb8x8x8, Sampling::Full);
    /// // Every pixel is red, so all of the mass is in red's bin.
    /// let red = Binning::Rgb8x8x8.bin([255, 0, 0]);
    /// assert_eq!(h.counts()[red], h.total());
    /// # Ok::<(), pftrack::FrameError>(())
    /// ```
    pub fn compute(&mut self, frame: &Frame<'_>, e: &Ellipse, binning: Binning, sampling: Sampling) {
        self.counts = [0; K];
        self.total = 0;
        match frame.format() {
            PixelFormat::Rgb565 => self.accumulate::<Rgb565>(frame, e, binning, sampling),
            PixelFormat::Rgb888 => self.accumulate::<Rgb888>(frame, e, binning, sampling),
            PixelFormat::Yuv422 => self.accumulate::<Yuv422>(frame, e, binning, sampling),
            PixelFormat::Gray8 => self.accumulate::<Gray8>(frame, e, binning, sampling),
        }
    }

    fn accumulate<P: PixelRead>(&mut self, frame: &Frame<'_>, e: &Ellipse, binning: Binning, sampling: Sampling) {
        let counts = &mut self.counts;
        let mut total = 0u32;
        for_each_in_ellipse(frame, e, sampling, |row, x, w| {
            if let Some(rgb) = P::rgb(row, x)
                && let Some(c) = counts.get_mut(binning.bin(rgb))
            {
                // Sums stay below 2^32 for any frame within MAX_DIMENSION;
                // wrapping keeps the loop free of a panic path regardless.
                *c = c.wrapping_add(w);
                total = total.wrapping_add(w);
            }
        });
        self.total = total;
    }
}

/// The target model: a normalised histogram `q` and its square roots, kept
/// ready for the Bhattacharyya sum.
///
/// `q(u)` is stored in units of `2^-16` and `sqrt(q(u))` in units of `2^-12`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Model<const K: usize> {
    q: [u16; K],
    sqrt_q: [u16; K],
}

/// Fixed-point scale of a normalised model bin.
const Q_ONE: u64 = 1 << 16;

impl<const K: usize> Model<K> {
    /// The model of a histogram, or `None` if the histogram is empty.
    pub fn from_histogram(h: &Histogram<K>) -> Option<Self> {
        if h.total == 0 {
            return None;
        }
        let mut m = Model {
            q: [0; K],
            sqrt_q: [0; K],
        };
        for (q, &c) in m.q.iter_mut().zip(h.counts.iter()) {
            *q = normalised(c, h.total);
        }
        m.refresh_roots();
        Some(m)
    }

    /// Blends a new observation into the model, `q ← (1 − α) q + α p`
    /// (the adaptive model of the first paper). `alpha` is clamped to `[0, 1]`;
    /// an empty histogram leaves the model unchanged.
    pub fn blend(&mut self, h: &Histogram<K>, alpha: Real) {
        if h.total == 0 || !(alpha > 0.0) {
            return;
        }
        let a = (alpha.min(1.0) * Q_ONE as Real) as u64;
        for (q, &c) in self.q.iter_mut().zip(h.counts.iter()) {
            let p = normalised(c, h.total) as u64;
            let v = ((Q_ONE - a) * *q as u64 + a * p + (Q_ONE >> 1)) >> 16;
            *q = v.min(u16::MAX as u64) as u16;
        }
        self.refresh_roots();
    }

    fn refresh_roots(&mut self) {
        for (s, &q) in self.sqrt_q.iter_mut().zip(self.q.iter()) {
            // sqrt(q · 2^16 · 2^8) = sqrt(q_real) · 2^12
            *s = ((q as u32) << 8).isqrt() as u16;
        }
    }

    /// The normalised bins, in units of `2^-16`.
    pub fn bins(&self) -> &[u16; K] {
        &self.q
    }

    /// The Bhattacharyya coefficient `ρ = Σ sqrt(p(u) q(u))` between the
    /// histogram and this model, in `[0, 1]`: 1 for identical distributions,
    /// 0 for disjoint ones, 0 for an empty histogram.
    ///
    /// With `p(u) = c(u) / C` this is `Σ sqrt(c(u)) sqrt(q(u)) / sqrt(C)`, so the
    /// candidate histogram is never normalised: one integer root per non-empty
    /// bin and one division per comparison. The result is within 0.005 of
    /// the exact value (tested against an f64 implementation).
    pub fn bhattacharyya(&self, h: &Histogram<K>) -> Real {
        if h.total == 0 {
            return 0.0;
        }
        let mut sum = 0u64;
        for (&c, &s) in h.counts.iter().zip(self.sqrt_q.iter()) {
            if c != 0 && s != 0 {
                // sqrt_q4(c) < 2^20 and s <= 2^12: the product fits in u32.
                sum += (sqrt_q4(c) * s as u32) as u64;
            }
        }
        // Σ 16·sqrt(c) · 4096·sqrt(q) / (16·sqrt(C) · 4096)
        let denom = sqrt_q4(h.total) as Real * 4096.0;
        if denom > 0.0 {
            (sum as Real / denom).clamp(0.0, 1.0)
        } else {
            0.0
        }
    }
}

/// `c / total` in units of `2^-16`, saturated to `u16`.
fn normalised(c: u32, total: u32) -> u16 {
    if total == 0 {
        return 0;
    }
    let v = (c as u64 * Q_ONE + (total as u64 >> 1)) / total as u64;
    v.min(u16::MAX as u64) as u16
}

/// The Bhattacharyya distance `d = sqrt(1 − ρ)`.
pub fn bhattacharyya_distance(rho: Real) -> Real {
    crate::scalar::sqrt((1.0 - rho).max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::PixelFormat;

    fn gray_frame(buf: &[u8], w: usize, h: usize) -> Frame<'_> {
        Frame::packed(buf, w, h, PixelFormat::Gray8).unwrap()
    }

    fn count_pixels(frame: &Frame<'_>, e: &Ellipse, s: Sampling) -> (u32, u64) {
        let (mut n, mut mass) = (0u32, 0u64);
        for_each_in_ellipse(frame, e, s, |_, _, w| {
            n += 1;
            mass += w as u64;
        });
        (n, mass)
    }

    #[test]
    fn ellipse_covers_its_area() {
        // Reason: an ellipse with half axes a, b covers π·a·b pixels, up to the
        // rim's discretisation (≈ perimeter/2 pixels, under 5% here); the
        // kernel 1 − r² integrates to π·a·b/2, so the mass is 256 · π·a·b/2.
        let buf = vec![0u8; 200 * 200];
        let f = gray_frame(&buf, 200, 200);
        for (a, b) in [(20.0f32, 20.0f32), (30.0, 12.0), (7.0, 15.0)] {
            let e = Ellipse {
                cx: 100.0,
                cy: 100.0,
                hx: a,
                hy: b,
            };
            let (n, mass) = count_pixels(&f, &e, Sampling::Full);
            let area = core::f64::consts::PI * a as f64 * b as f64;
            assert!((n as f64 - area).abs() / area < 0.05, "{a}x{b}: {n} px vs {area}");
            let want_mass = 256.0 * area / 2.0;
            assert!(
                (mass as f64 - want_mass).abs() / want_mass < 0.05,
                "{a}x{b}: mass {mass} vs {want_mass}"
            );

            // Reason: checkerboard reads every other pixel, quarter one in four.
            let (nc, mc) = count_pixels(&f, &e, Sampling::Checkerboard);
            let (nq, mq) = count_pixels(&f, &e, Sampling::Quarter);
            assert!((nc as f64 / n as f64 - 0.5).abs() < 0.03, "checkerboard {nc} of {n}");
            assert!((nq as f64 / n as f64 - 0.25).abs() < 0.03, "quarter {nq} of {n}");
            assert!((mc as f64 / mass as f64 - 0.5).abs() < 0.03);
            assert!((mq as f64 / mass as f64 - 0.25).abs() < 0.03);
        }
    }

    #[test]
    fn off_frame_part_is_skipped() {
        // Reason: an ellipse centred on the left edge has half of its pixels on
        // the frame (the column x = 0 is the centre column, so a bit more).
        let buf = vec![0u8; 100 * 100];
        let f = gray_frame(&buf, 100, 100);
        let inside = count_pixels(
            &f,
            &Ellipse {
                cx: 50.0,
                cy: 50.0,
                hx: 10.0,
                hy: 10.0,
            },
            Sampling::Full,
        )
        .0;
        let edge = count_pixels(
            &f,
            &Ellipse {
                cx: 0.0,
                cy: 50.0,
                hx: 10.0,
                hy: 10.0,
            },
            Sampling::Full,
        )
        .0;
        let frac = edge as f64 / inside as f64;
        assert!(frac > 0.5 && frac < 0.6, "{edge} of {inside}");
        // Entirely outside: nothing, and no panic.
        assert_eq!(
            count_pixels(
                &f,
                &Ellipse {
                    cx: -50.0,
                    cy: 50.0,
                    hx: 10.0,
                    hy: 10.0
                },
                Sampling::Full
            )
            .0,
            0
        );
        assert_eq!(
            count_pixels(
                &f,
                &Ellipse {
                    cx: Real::NAN,
                    cy: 50.0,
                    hx: 10.0,
                    hy: 10.0
                },
                Sampling::Full
            )
            .0,
            0
        );
        // A degenerate ellipse still reads its centre pixel.
        assert_eq!(
            count_pixels(
                &f,
                &Ellipse {
                    cx: 5.5,
                    cy: 5.5,
                    hx: 0.0,
                    hy: 0.0
                },
                Sampling::Full
            )
            .0,
            1
        );
    }

    #[test]
    fn histogram_mass_is_the_kernel_mass() {
        // Reason: every pixel lands in exactly one bin, so the bins sum to the
        // total, which is the kernel mass of the region.
        let mut buf = vec![0u8; 64 * 64];
        for (i, p) in buf.iter_mut().enumerate() {
            *p = (i * 37 % 251) as u8;
        }
        let f = gray_frame(&buf, 64, 64);
        let e = Ellipse {
            cx: 30.0,
            cy: 33.0,
            hx: 12.0,
            hy: 9.0,
        };
        let mut h = Histogram::<512>::new();
        h.compute(&f, &e, Binning::Rgb8x8x8, Sampling::Full);
        let sum: u64 = h.counts().iter().map(|&c| c as u64).sum();
        assert_eq!(sum, h.total() as u64);
        assert_eq!(sum, count_pixels(&f, &e, Sampling::Full).1);
        // A model made from it sums to 1 within the rounding of 512 bins.
        let m = Model::from_histogram(&h).unwrap();
        let qsum: i64 = m.bins().iter().map(|&q| q as i64).sum();
        assert!((qsum - 65536).abs() <= 256, "{qsum}");
    }

    fn reference_rho(p: &Histogram<512>, q: &Histogram<512>) -> f64 {
        let (tp, tq) = (p.total() as f64, q.total() as f64);
        p.counts()
            .iter()
            .zip(q.counts().iter())
            .map(|(&a, &b)| ((a as f64 / tp) * (b as f64 / tq)).sqrt())
            .sum()
    }

    #[test]
    fn bhattacharyya_identical_disjoint_and_reference() {
        let mut a = Histogram::<512>::new();
        let mut b = Histogram::<512>::new();
        for (bin, w) in [(3usize, 1000u32), (40, 256), (41, 17), (500, 5000)] {
            a.add(bin, w);
        }
        for (bin, w) in [(7usize, 1000u32), (8, 256)] {
            b.add(bin, w);
        }
        let ma = Model::from_histogram(&a).unwrap();
        // Reason: ρ(p, p) = Σ p(u) = 1 exactly; the fixed point costs < 0.005.
        let same = ma.bhattacharyya(&a);
        assert!(same > 0.995 && same <= 1.0, "{same}");
        // Reason: no shared bin, so every product is zero.
        assert_eq!(ma.bhattacharyya(&b), 0.0);
        assert_eq!(ma.bhattacharyya(&Histogram::new()), 0.0);
        assert!(Model::from_histogram(&Histogram::<512>::new()).is_none());

        // Reason: cross-check against a straightforward f64 implementation on
        // pseudo-random histograms of varied sparsity and mass.
        let mut seed = 12345u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 33) as u32
        };
        for trial in 0..50 {
            let mut p = Histogram::<512>::new();
            let mut q = Histogram::<512>::new();
            let used = 4 + trial * 10;
            for _ in 0..used {
                let bin = next() as usize % 512;
                p.add(bin, next() % 2000 + 1);
                if next() % 3 != 0 {
                    q.add(bin, next() % 2000 + 1);
                } else {
                    q.add(next() as usize % 512, next() % 50 + 1);
                }
            }
            let got = Model::from_histogram(&q).unwrap().bhattacharyya(&p) as f64;
            let want = reference_rho(&p, &q);
            assert!((got - want).abs() < 0.005, "trial {trial}: {got} vs {want}");
        }
    }

    #[test]
    fn blend_moves_the_model_by_alpha() {
        // Reason: q' = (1 − α) q + α p bin by bin; with q all in bin 1 and p all
        // in bin 2, α = 0.25 gives 0.75 and 0.25. A bin holding all the mass
        // saturates at 65535/65536, so bin 1 may be one unit short.
        let mut q = Histogram::<512>::new();
        q.add(1, 100);
        let mut p = Histogram::<512>::new();
        p.add(2, 300);
        let mut m = Model::from_histogram(&q).unwrap();
        m.blend(&p, 0.25);
        assert!((49151..=49152).contains(&m.bins()[1]), "{}", m.bins()[1]);
        assert_eq!(m.bins()[2], 16384);
        let before = m.clone();
        m.blend(&p, 0.0);
        assert_eq!(m, before, "alpha 0 leaves the model alone");
        m.blend(&Histogram::new(), 0.5);
        assert_eq!(m, before, "an empty observation leaves the model alone");
    }

    #[test]
    fn rgb_binning_uses_top_three_bits() {
        assert_eq!(Binning::Rgb8x8x8.bin([0, 0, 0]), 0);
        assert_eq!(Binning::Rgb8x8x8.bin([255, 255, 255]), 511);
        assert_eq!(
            Binning::Rgb8x8x8.bin([0b1010_0000, 0b0110_0000, 0b0010_0000]),
            (5 << 6) | (3 << 3) | 1
        );
    }

    #[test]
    fn distance_of_coefficient() {
        assert_eq!(bhattacharyya_distance(1.0), 0.0);
        assert_eq!(bhattacharyya_distance(0.0), 1.0);
        assert!((bhattacharyya_distance(0.75) - 0.5).abs() < 1e-6);
    }
}
