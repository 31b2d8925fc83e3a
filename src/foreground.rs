//! The target against its surroundings: which colours say "target", and a
//! per-frame map of them for scoring boxes.
//!
//! A colour histogram compared with a model by the Bhattacharyya coefficient
//! does not know the background: a box that slides onto a patch of the
//! target's colours, or grows to take in more of them, scores as well as
//! the target. Discriminative colour trackers (Possegger et al., "In
//! defense of color-based model-free tracking", 2015; the colour score of
//! Staple, Bertinetto et al. 2016; the background ratio of ASMS, Vojíř et
//! al. 2014) learn instead, per colour bin `u`, how likely a pixel of that
//! colour belongs to the target rather than to the region around it:
//!
//! `P(target | u) = q(u) / (q(u) + b(u))`
//!
//! with `q` the target's normalised histogram and `b` that of a ring around
//! the target box ([`Foreground`]). Each frame, [`ForegroundMap`] reads that
//! probability for the pixels of a rectangle (on a lattice, 4 bits each)
//! and keeps their running sums (an integral image), so that the sum over
//! any box is four reads. The score of a box is its *contrast*: the mean
//! probability inside minus the mean in a ring around it. A box that fits
//! the target maximises it: a larger box takes in background (its inside
//! mean falls), a smaller one leaves target in its ring (its ring mean
//! rises). That is what lets the tracker estimate size and shape.

use crate::frame::Frame;
use crate::geometry::Ellipse;
use crate::histogram::{Histogram, Layout, Model};
use crate::scalar::Real;

/// Probability levels of a map cell: `P(target | colour)` in sixteenths,
/// 0..=15. Coarse per pixel, but scores are means over tens to thousands of
/// cells; and 15 · 4096 cells fits a `u16` running sum.
pub const LEVELS: u32 = 15;

/// How the colour model's bins are weighted against the surroundings (the
/// background-weighted histograms of CBWH, Ning et al. 2012, generalised):
/// bin `u` counts `1 − strength + strength · max(0, p(u) − above) / (1 −
/// above)` times in the similarity, with `p(u)` = `P(target | u)` learnt
/// against the ring around the target (see [`crate::foreground`]), and
/// the model is renormalised. `{ strength: 1, above: 0 }` is CBWH: a colour
/// the surroundings share is dropped even where it is the target's own.
/// `above` > 0 weighs only the target's distinctive colours up: at
/// `{ strength: 0.5, above: 0.8 }` a colour at least four times as common
/// in the target as around it counts up to twice as much as the rest (the
/// default). Refreshed with the model.
#[derive(Copy, Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BackgroundWeight {
    /// In `[0, 1]`: 0 leaves the model as learnt.
    pub strength: Real,
    /// The odds `P(target | u)` above which a colour gains weight, in `[0, 0.95]`.
    pub above: Real,
}

/// The weight of each odds level `o` in `0..=LEVELS` under `b`, in
/// sixteenths: `LEVELS · (1 − s) + s · max(0, o − above) · LEVELS /
/// (LEVELS − above)`, at most 16 · 15 = 240 (for [`Model::reweight`]).
#[inline]
pub(crate) fn weights(b: BackgroundWeight) -> [u32; LEVELS as usize + 1] {
    let levels = LEVELS as Real;
    // `Config::validate` holds both in range; clamped again so that no
    // caller can overflow the table or divide by `levels − above` = 0.
    let s = crate::scalar::clamp(b.strength, 0.0, 1.0);
    let above = crate::scalar::clamp(b.above, 0.0, 0.95) * levels;
    let mut table = [0u32; LEVELS as usize + 1];
    for (o, t) in table.iter_mut().enumerate() {
        let gain = crate::scalar::max(o as Real - above, 0.0) * levels / (levels - above);
        *t = (16.0 * ((1.0 - s) * levels + s * gain) + 0.5) as u32;
    }
    table
}

/// Per-bin `P(target | colour)` in `0..=LEVELS`, learnt from the target model
/// and the histogram of a ring around the target.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Foreground<const K: usize> {
    /// The surroundings' normalised histogram, in units of `2^-16`.
    around: [u16; K],
    /// `P(target | bin)` in `0..=LEVELS`.
    odds: [u8; K],
    /// Whether anything was learnt.
    learnt: bool,
}

/// How far the ring a box's contrast is taken against extends: to this
/// many times the box's width and height (1.25 box areas of ring).
pub const RING: Real = 1.5;

/// Added to both histograms' bins (units of `2^-16`) so that a colour seen
/// in neither is even odds and one seen a little in one of them is not
/// certain.
const PRIOR: u32 = 64;

impl<const K: usize> Foreground<K> {
    /// Even odds everywhere (nothing learnt).
    pub(crate) const fn new() -> Self {
        Foreground { around: [0; K], odds: [(LEVELS as u8).div_ceil(2); K], learnt: false }
    }

    /// Whether surroundings have been learnt (the tracker learns them only
    /// for the techniques that use them).
    pub fn is_learnt(&self) -> bool {
        self.learnt
    }

    /// `P(target | bin)` of every bin, in `0..=LEVELS`.
    pub fn odds(&self) -> &[u8; K] {
        &self.odds
    }

    /// Learns the surroundings of box `e` in `frame` (replacing them when
    /// `rate` is 1, blending `b ← (1 − rate) b + rate · b_new` otherwise,
    /// with the rate in 1/256ths) and refreshes the odds against `model`.
    /// `scratch` is working memory for the new histogram (on the stack it
    /// would cost 4·K bytes there).
    pub(crate) fn learn(
        &mut self,
        frame: &Frame<'_>,
        e: &Ellipse,
        (layout, model): (&Layout, &Model<K>),
        rate: Real,
        scratch: &mut Histogram<K>,
    ) {
        ring_histogram(frame, e, layout, scratch);
        let total = scratch.total();
        if total > 0 {
            // The first surroundings replace the even odds outright.
            let rate = if self.learnt { rate } else { 1.0 };
            self.learnt = true;
            let a = (crate::scalar::clamp(rate, 0.0, 1.0) * 256.0) as u32;
            for (b, &c) in self.around.iter_mut().zip(scratch.counts().iter()) {
                // c <= total, at most a few thousand samples: c · 2^16 fits a u32.
                let new = (c << 16).checked_div(total).unwrap_or(0).min(65535);
                *b = (((256 - a) * *b as u32 + a * new + 128) >> 8).min(65535) as u16;
            }
        }
        self.refresh(model);
    }

    /// Recomputes the odds from the target model's bins and the surroundings.
    pub(crate) fn refresh(&mut self, model: &Model<K>) {
        for (u, (o, &b)) in self.odds.iter_mut().zip(self.around.iter()).enumerate() {
            let (q, b) = (model.whole_bin(u) + PRIOR, b as u32 + PRIOR);
            *o = (LEVELS * q + (q + b) / 2).checked_div(q + b).unwrap_or(LEVELS / 2) as u8;
        }
    }
}

/// Replaces `hist` with the flat-weighted colour histogram of the ring
/// between box `e` and the box twice its width and height around it (three
/// target areas), clipped to the frame, on a lattice of at most about 500
/// samples.
fn ring_histogram<const K: usize>(frame: &Frame<'_>, e: &Ellipse, layout: &Layout, hist: &mut Histogram<K>) {
    hist.clear();
    let (w, h) = (frame.width() as i32, frame.height() as i32);
    let inner = pixel_box(e.cx - e.hx, e.cy - e.hy, e.cx + e.hx, e.cy + e.hy, w, h);
    let outer = pixel_box(e.cx - 2.0 * e.hx, e.cy - 2.0 * e.hy, e.cx + 2.0 * e.hx, e.cy + 2.0 * e.hy, w, h);
    let area = ((outer.2 - outer.0) as u32).saturating_mul((outer.3 - outer.1) as u32);
    let step = lattice_step(area, 500);
    let cols = crate::region::div_small((outer.2 - outer.0 + step - 1) as u32, step as u32) as usize;
    let mut y = outer.1;
    while y < outer.3 {
        let inside_row = y >= inner.1 && y < inner.3;
        crate::histogram::row_bins(frame, layout, y as usize, (outer.0 as usize, step as usize, cols), |i, bin| {
            let x = outer.0 + i as i32 * step;
            if !(inside_row && x >= inner.0 && x < inner.2) {
                hist.add(bin, 1);
            }
        });
        y += step;
    }
}

/// The pixel rectangle `[x0, x1) × [y0, y1)` covering a real box, clipped to
/// a `w × h` frame.
fn pixel_box(x0: Real, y0: Real, x1: Real, y1: Real, w: i32, h: i32) -> (i32, i32, i32, i32) {
    let c = |v: Real, hi: i32| crate::scalar::clamp(v, 0.0, hi as Real) as i32;
    (c(x0, w), c(y0, h), c(x1 + 0.999, w), c(y1 + 0.999, h))
}

/// The smallest lattice step that samples an area of `area` pixels with at
/// most about `budget` samples.
fn lattice_step(area: u32, budget: u32) -> i32 {
    let mut step = 1u32;
    while area.checked_div(step * step).is_some_and(|n| n > budget) {
        step += 1;
    }
    step as i32
}

/// A value on a 4-byte boundary.
#[derive(Clone, Debug)]
#[repr(C, align(4))]
struct Aligned<T>(T);

/// `P(target | colour)` over a rectangle of one frame, on a lattice, with
/// running sums: the sum over any box is four reads. Holds at most `F`
/// running sums, i.e. `(columns + 1) · (rows + 1) <= F`; larger rectangles
/// are read on a coarser lattice.
#[derive(Clone, Debug)]
pub struct ForegroundMap<const F: usize> {
    /// `sums[j · (cols + 1) + i]`: the sum of the cells left of column `i`
    /// and above row `j` (4-byte aligned: lent as working memory, see
    /// [`ForegroundMap::lend`]).
    sums: Aligned<[u16; F]>,
    /// Pixel of cell (0, 0).
    x0: i32,
    /// See `x0`.
    y0: i32,
    /// Pixels between cells.
    step: i32,
    cols: i32,
    rows: i32,
}

impl<const F: usize> Default for ForegroundMap<F> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const F: usize> ForegroundMap<F> {
    /// An empty map (every box sums to nothing).
    pub const fn new() -> Self {
        const {
            assert!(F <= 4097, "running sums of 4-bit cells fit a u16 up to 4096 cells");
        }
        ForegroundMap { sums: Aligned([0; F]), x0: 0, y0: 0, step: 1, cols: 0, rows: 0 }
    }

    /// Fills the map over the pixel rectangle `[x0, x1) × [y0, y1)` (clipped
    /// to the frame) with the odds of each cell's colour.
    pub(crate) fn compute<const K: usize>(
        &mut self,
        frame: &Frame<'_>,
        rect: (i32, i32, i32, i32),
        layout: &Layout,
        fg: &Foreground<K>,
    ) {
        let (w, h) = (frame.width() as i32, frame.height() as i32);
        // `max` and `min` rather than `clamp`, which asserts its bounds are
        // in order: a panic path.
        let (x0, y0) = (rect.0.max(0).min(w), rect.1.max(0).min(h));
        let (x1, y1) = (rect.2.max(x0).min(w), rect.3.max(y0).min(h));
        // Cells along a side of length `n` at lattice step `s`.
        let along = |n: i32, s: i32| (n + s - 1).checked_div(s).unwrap_or(0);
        let cells = |s: i32| (along(x1 - x0, s) + 1) as usize * (along(y1 - y0, s) + 1) as usize;
        let mut step = 1;
        while cells(step) > F && step < w.max(h) {
            step += 1;
        }
        let (cols, rows) = (along(x1 - x0, step), along(y1 - y0, step));
        (self.x0, self.y0, self.step) = (x0, y0, step);
        if cells(step) > F {
            (self.cols, self.rows) = (0, 0);
            return;
        }
        (self.cols, self.rows) = (cols, rows);
        let stride = (cols + 1) as usize;
        for s in self.sums.0.iter_mut().take(stride) {
            *s = 0;
        }
        let odds = &fg.odds;
        for j in 0..rows {
            let base = (j as usize + 1) * stride;
            if let Some(s) = self.sums.0.get_mut(base) {
                *s = 0;
            }
            // Row j's running sums: the row above's plus this row's so far.
            let Some((above, here)) = self.sums.0.split_at_mut_checked(base) else { break };
            let above = above.get(base - stride + 1..).unwrap_or(&[]);
            let here = here.get_mut(1..).unwrap_or(&mut []);
            let mut run = 0u16;
            let span = (x0 as usize, step as usize, cols as usize);
            crate::histogram::row_bins(frame, layout, (y0 + j * step) as usize, span, |i, bin| {
                run = run.wrapping_add(odds.get(bin).copied().unwrap_or(0) as u16);
                if let (Some(s), Some(&a)) = (here.get_mut(i), above.get(i)) {
                    *s = a.wrapping_add(run);
                }
            });
        }
    }

    /// Fills the map over the box of `e` grown `reach` times in width and
    /// height (with a pixel's margin).
    pub(crate) fn compute_around<const K: usize>(
        &mut self,
        frame: &Frame<'_>,
        e: &Ellipse,
        reach: Real,
        layout: &Layout,
        fg: &Foreground<K>,
    ) {
        let f = crate::region::floor;
        let (ax, ay) = (reach * e.hx, reach * e.hy);
        let rect = (f(e.cx - ax) - 1, f(e.cy - ay) - 1, f(e.cx + ax) + 2, f(e.cy + ay) + 2);
        self.compute(frame, rect, layout, fg);
    }

    /// The map's running sums as working memory, 4-byte aligned. The map
    /// is built afresh wherever it is read (the prediction's re-detection,
    /// the estimate), so between those and after the estimate its sums
    /// hold nothing anyone reads. The map is left empty.
    pub(crate) fn lend(&mut self) -> &mut [u16] {
        (self.cols, self.rows) = (0, 0);
        &mut self.sums.0
    }

    /// Pixels between the map's cells.
    pub(crate) fn step(&self) -> i32 {
        self.step
    }

    /// The sum and count of the cells whose pixels lie in `[x0, x1) × [y0, y1)`.
    pub(crate) fn sum(&self, x0: Real, y0: Real, x1: Real, y1: Real) -> (u32, u32) {
        let s = self.step as Real;
        // The first cell at or after coordinate `v` along an axis whose cell
        // 0 is at `origin` and which has `n` cells (ceil, clipped to [0, n]):
        // cells i with v0 <= origin + i·step < v1 are those from index(v0)
        // to index(v1).
        let index = |v: Real, origin: i32, n: i32| -> i32 {
            let c = crate::scalar::clamp((v - origin as Real) / s, 0.0, n as Real);
            let f = c as i32;
            if (f as Real) < c { f + 1 } else { f }
        };
        let (i0, i1) = (index(x0, self.x0, self.cols), index(x1, self.x0, self.cols));
        let (j0, j1) = (index(y0, self.y0, self.rows), index(y1, self.y0, self.rows));
        if i1 <= i0 || j1 <= j0 {
            return (0, 0);
        }
        let stride = (self.cols + 1) as usize;
        let at = |i: i32, j: i32| self.sums.0.get(j as usize * stride + i as usize).copied().unwrap_or(0);
        let total = at(i1, j1).wrapping_sub(at(i0, j1)).wrapping_sub(at(i1, j0)).wrapping_add(at(i0, j0));
        (total as u32, ((i1 - i0) * (j1 - j0)) as u32)
    }

    /// The contrast of the box of ellipse `e`: its mean odds minus the mean
    /// odds of the ring out to `ring` times its width and height, in
    /// `[-1, 1]`; `None` if the map covers no cell of the box or the ring.
    pub(crate) fn contrast(&self, e: &Ellipse, ring: Real) -> Option<Real> {
        let (ax, ay) = (e.hx * ring, e.hy * ring);
        let (si, ni) = self.sum(e.cx - e.hx, e.cy - e.hy, e.cx + e.hx, e.cy + e.hy);
        let (so, no) = self.sum(e.cx - ax, e.cy - ay, e.cx + ax, e.cy + ay);
        if ni == 0 || no <= ni {
            return None;
        }
        let inside = si as Real / ni as Real;
        let around = (so - si) as Real / (no - ni) as Real;
        Some((inside - around) / LEVELS as Real)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colour::Binning;
    use crate::frame::PixelFormat;
    use crate::region::Lattice;

    const W: usize = 120;
    const H: usize = 90;
    const RED: [u8; 3] = [220, 30, 30];
    const GREY: [u8; 3] = [100, 100, 100];

    /// A grey frame with a red 30x20 box at (40, 30).
    fn scene() -> Vec<u8> {
        let mut px = [GREY; W * H].concat();
        for y in 30..50 {
            for x in 40..70 {
                px[(y * W + x) * 3..][..3].copy_from_slice(&RED);
            }
        }
        px
    }

    fn learnt(f: &Frame<'_>, e: &Ellipse) -> Foreground<512> {
        let mut hist = Histogram::<512>::new();
        hist.compute_on(f, e, Binning::Rgb8x8x8, Lattice::FULL);
        let model = Model::from_histogram(&hist).unwrap();
        let mut fg = Foreground::<512>::new();
        fg.learn(f, e, (&Layout::whole(Binning::Rgb8x8x8), &model), 0.25, &mut hist);
        fg
    }

    #[test]
    fn odds_of_target_surrounding_and_unseen_colours() {
        // Reason: by hand. The ellipse inscribed in the red box sees only
        // red, so q(red) = 1 (65536 units) and q(grey) = 0; the ring around
        // the box is all grey, so b(grey) = 1 and b(red) = 0. With the prior
        // of 64 units: P(red) = 15 · 65600 / 65664 = 14.99 -> 15,
        // P(grey) = 15 · 64 / 65664 -> 0, and a colour seen in neither is
        // 15 · 64 / 128 = 7.5 -> 8 (even odds, rounded half up). The first
        // surroundings replace the even odds whatever the rate.
        let px = scene();
        let f = Frame::packed(&px, W, H, PixelFormat::Rgb888).unwrap();
        let e = Ellipse { cx: 55.0, cy: 40.0, hx: 15.0, hy: 10.0 };
        let fg = learnt(&f, &e);
        assert!(fg.is_learnt());
        let bin = |c| Binning::Rgb8x8x8.bin(c);
        assert_eq!(fg.odds()[bin(RED)], 15);
        assert_eq!(fg.odds()[bin(GREY)], 0);
        assert_eq!(fg.odds()[bin([0, 255, 0])], 8);
        assert!(!Foreground::<512>::new().is_learnt());
    }

    #[test]
    fn box_sums_match_a_direct_count() {
        // Reason: cross-check of the running sums against summing the cells
        // one by one, for random boxes (partly off the map included), on a
        // random frame and a map coarse enough to need a lattice step > 1.
        let mut next = crate::testing::lcg(11);
        let px: Vec<u8> = (0..W * H * 3).map(|_| (next() >> 24) as u8).collect();
        let f = Frame::packed(&px, W, H, PixelFormat::Rgb888).unwrap();
        let e = Ellipse { cx: 60.0, cy: 45.0, hx: 10.0, hy: 8.0 };
        let fg = learnt(&f, &e);
        let layout = Layout::whole(Binning::Rgb8x8x8);
        let mut map = ForegroundMap::<1024>::new();
        map.compute(&f, (7, 5, 113, 88), &layout, &fg);
        assert!(map.step() >= 2, "the rectangle needs more than 1024 sums at step 1");
        let cell = |x: i32, y: i32| fg.odds()[layout.bin(f.rgb(x as usize, y as usize).unwrap())] as u32;
        for _ in 0..300 {
            let mut r = || (next() >> 16) as f32 / 65536.0;
            let (x0, y0) = (r() * 140.0 - 10.0, r() * 110.0 - 10.0);
            let (x1, y1) = (x0 + r() * 60.0, y0 + r() * 50.0);
            let (mut want, mut n) = (0u32, 0u32);
            for j in 0..map.rows {
                for i in 0..map.cols {
                    let (x, y) = (map.x0 + i * map.step, map.y0 + j * map.step);
                    if (x as f32) >= x0 && (x as f32) < x1 && (y as f32) >= y0 && (y as f32) < y1 {
                        want += cell(x, y);
                        n += 1;
                    }
                }
            }
            assert_eq!(map.sum(x0, y0, x1, y1), if n == 0 { (0, 0) } else { (want, n) }, "box {x0},{y0} {x1},{y1}");
        }
    }

    #[test]
    fn the_true_box_has_the_best_contrast() {
        // Reason: the geometry of contrast. Inside the true box every cell is
        // red (odds 15) and the ring around it is all grey (odds 0): contrast
        // 1, the most there is. A larger box takes in grey, a smaller one
        // leaves red in its ring, a shifted one both: each scores less.
        let px = scene();
        let f = Frame::packed(&px, W, H, PixelFormat::Rgb888).unwrap();
        let e = Ellipse { cx: 55.0, cy: 40.0, hx: 15.0, hy: 10.0 };
        let fg = learnt(&f, &e);
        let mut map = ForegroundMap::<4096>::new();
        map.compute_around(&f, &e, 2.0 * RING, &Layout::whole(Binning::Rgb8x8x8), &fg);
        let at = |dx: f32, fx: f32, fy: f32| {
            map.contrast(&Ellipse { cx: e.cx + dx, hx: e.hx * fx, hy: e.hy * fy, ..e }, RING).unwrap()
        };
        assert_eq!(at(0.0, 1.0, 1.0), 1.0);
        for (dx, fx, fy) in [(0.0, 1.2, 1.0), (0.0, 0.8, 1.0), (0.0, 1.0, 1.2), (0.0, 1.0, 0.8), (3.0, 1.0, 1.0)] {
            assert!(at(dx, fx, fy) < 0.95, "shift {dx}, scale {fx} x {fy}: {}", at(dx, fx, fy));
        }
    }
}
