//! The likelihood-table mode of the head-tracking paper, for a target of
//! fixed size: once per frame, the similarity of every candidate position
//! on a grid over the search area is computed by sliding one window across
//! it, updating the histograms incrementally (the pixels that leave the
//! ellipse are removed, those that enter are added) instead of rebuilding
//! them; particles then look their similarity up in the table.
//!
//! Sliding needs every pixel to weigh the same wherever the window is, so
//! the window's histograms are unweighted (the paper's interior masks), not
//! kernel-weighted like a particle's. The Bhattacharyya sum is kept
//! incrementally too: `S = Σ sqrt(c(u)) sqrt(q(u))` changes only in the bins
//! a moving pixel touches.
//!
//! Whether it pays depends on the ratio of grid positions to particles: each
//! position costs the pixels on two arcs of the outline (about `4·Hy` at
//! spacing 1) plus one similarity, where a particle costs its whole region.
//! The ablation (`track ablate`) and README give the measured figures.

use crate::colour::{Binning, levels_bin};
use crate::edges::EdgeMap;
use crate::edges::{EDGE_SUPPORT_WORDS, MAX_EDGE_BINS};
use crate::frame::Frame;
use crate::histogram::{Histogram, Model};
use crate::likelihood::Combination;
use crate::region::{Extents, Lattice};
use crate::scalar::{Real, sqrt_q4};

/// Where a window's pixels go: the colour bin of a pixel, and its edge bin.
pub(crate) struct Bins<'a, const E: usize> {
    pub frame: &'a Frame<'a>,
    pub binning: Binning,
    /// Levels per channel for adaptive binning.
    pub levels: u8,
    pub map: Option<&'a EdgeMap<E>>,
    pub lattice: Lattice,
}

impl<const E: usize> Bins<'_, E> {
    fn colour(&self, x: usize, y: usize) -> Option<usize> {
        let rgb = self.frame.rgb(x, y)?;
        Some(match self.binning {
            Binning::Adaptive => levels_bin(rgb, self.levels),
            b => b.bin(rgb),
        })
    }
}

/// A window's histograms with the running Bhattacharyya sum of its colour
/// histogram against the model.
pub(crate) struct Window<'m, const K: usize> {
    pub colour: Histogram<K>,
    pub edge: Histogram<MAX_EDGE_BINS>,
    model: &'m Model<K>,
    /// `Σ sqrt_q4(c(u)) · sqrt(q(u))` in the units of [`Model::bhattacharyya`].
    sum: u64,
}

impl<'m, const K: usize> Window<'m, K> {
    pub(crate) fn new(model: &'m Model<K>) -> Self {
        Window { colour: Histogram::new(), edge: Histogram::new(), model, sum: 0 }
    }

    fn clear(&mut self) {
        self.colour.clear();
        self.edge.clear();
        self.sum = 0;
    }

    /// Adds (`add`) or removes one pixel.
    fn pixel<const E: usize>(&mut self, bins: &Bins<'_, E>, x: usize, y: usize, add: bool) {
        if let Some(b) = bins.colour(x, y)
            && let (Some(&c), Some(&s)) = (self.colour.counts().get(b), self.model.sqrt_bins().get(b))
        {
            let before = sqrt_q4(c) as u64 * s as u64;
            if add {
                self.colour.add(b, 1);
            } else {
                self.colour.sub(b, 1);
            }
            let after = sqrt_q4(c.wrapping_add(if add { 1 } else { u32::MAX })) as u64 * s as u64;
            self.sum = self.sum.wrapping_add(after).wrapping_sub(before);
        }
        if let Some(e) = bins.map.and_then(|m| m.bin_at(x, y)) {
            if add {
                self.edge.add(e, 1);
            } else {
                self.edge.sub(e, 1);
            }
        }
    }

    /// Adds or removes the lattice pixels of row `y` with `x` in `[lo, hi]`,
    /// clipped to the frame.
    fn span<const E: usize>(&mut self, bins: &Bins<'_, E>, y: i32, lo: i32, hi: i32, add: bool) {
        let f = bins.frame;
        if y < 0 || y as usize >= f.height() {
            return;
        }
        let (lo, hi) = (lo.max(0), hi.min(f.width() as i32 - 1));
        let mut x = lo;
        while x <= hi {
            if bins.lattice.contains(x as usize, y as usize) {
                self.pixel(bins, x as usize, y as usize, add);
            }
            x += 1;
        }
    }

    /// Rebuilds the window centred on pixel `(cx, cy)`.
    pub(crate) fn place<const E: usize>(&mut self, bins: &Bins<'_, E>, ext: &Extents, cx: i32, cy: i32) {
        self.clear();
        for dy in -ext.ry()..=ext.ry() {
            if let Some(d) = ext.half_width(dy) {
                self.span(bins, cy + dy, cx - d, cx + d, true);
            }
        }
    }

    /// Moves the window from centre column `cx` to `cx + step` on row `cy`:
    /// per row, the pixels left behind go, the ones reached come in.
    pub(crate) fn slide<const E: usize>(&mut self, bins: &Bins<'_, E>, ext: &Extents, cx: i32, cy: i32, step: i32) {
        for dy in -ext.ry()..=ext.ry() {
            let Some(d) = ext.half_width(dy) else { continue };
            let (old_lo, old_hi, new_lo, new_hi) = (cx - d, cx + d, cx + step - d, cx + step + d);
            self.span(bins, cy + dy, old_lo, old_hi.min(new_lo - 1), false);
            self.span(bins, cy + dy, new_lo.max(old_hi + 1), new_hi, true);
        }
    }

    /// The colour ρ of the window, exactly [`Model::bhattacharyya`] of its histogram.
    pub(crate) fn rho(&self) -> Real {
        let denom = sqrt_q4(self.colour.total()) as Real * 4096.0;
        if denom > 0.0 { crate::scalar::clamp(self.sum as Real / denom, 0.0, 1.0) } else { 0.0 }
    }
}

/// One frame's table: per grid cell, the colour ρ and the combined
/// similarity, in units of `2^-16`, over a grid of `T` cells at most.
#[derive(Clone, Debug)]
pub(crate) struct Table<const T: usize> {
    cells: [(u16, u16); T],
    x0: i32,
    y0: i32,
    cols: usize,
    rows: usize,
    spacing: i32,
}

fn q16(v: Real) -> u16 {
    (crate::scalar::clamp(v, 0.0, 1.0) * 65535.0 + 0.5) as u16
}

impl<const T: usize> Table<T> {
    pub(crate) const fn new() -> Self {
        Table { cells: [(0, 0); T], x0: 0, y0: 0, cols: 0, rows: 0, spacing: 1 }
    }

    /// Fills the table over the centre pixels `[x0, x1] × [y0, y1]`, at
    /// `spacing` pixels or coarser if the grid would not fit `T` cells.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn fill<const K: usize, const E: usize>(
        &mut self,
        bins: &Bins<'_, E>,
        ext: &Extents,
        model: &Model<K>,
        edge_model: Option<&Model<MAX_EDGE_BINS, EDGE_SUPPORT_WORDS>>,
        combination: Combination,
        area: (i32, i32, i32, i32),
        spacing: i32,
    ) {
        let (x0, y0, x1, y1) = area;
        let (w, h) = ((x1 - x0).max(0) as usize + 1, (y1 - y0).max(0) as usize + 1);
        let mut s = spacing.max(1) as usize;
        while s < 4096 && w.div_ceil(s) * h.div_ceil(s) > T {
            s *= 2;
        }
        (self.x0, self.y0, self.spacing) = (x0, y0, s as i32);
        (self.cols, self.rows) = (w.div_ceil(s), h.div_ceil(s));
        let mut win = Window::new(model);
        for j in 0..self.rows {
            let cy = y0 + (j * s) as i32;
            for i in 0..self.cols {
                let cx = x0 + (i * s) as i32;
                if i == 0 {
                    win.place(bins, ext, cx, cy);
                } else {
                    win.slide(bins, ext, cx - s as i32, cy, s as i32);
                }
                let rho = win.rho();
                let sim = match edge_model {
                    Some(m) => combination.similarity(rho, m.bhattacharyya(&win.edge)),
                    None => rho,
                };
                if let Some(c) = self.cells.get_mut(j * self.cols + i) {
                    *c = (q16(rho), q16(sim));
                }
            }
        }
    }

    /// (colour ρ, combined similarity) of the grid cell nearest `(x, y)`,
    /// clamped onto the grid.
    pub(crate) fn lookup(&self, x: Real, y: Real) -> (Real, Real) {
        let s = self.spacing.max(1) as Real;
        let idx = |v: Real, o: i32, n: usize| -> usize {
            let t = (v - o as Real) / s + 0.5;
            crate::scalar::clamp(t, 0.0, n.saturating_sub(1) as Real) as usize
        };
        let (i, j) = (idx(x, self.x0, self.cols), idx(y, self.y0, self.rows));
        match self.cells.get(j * self.cols + i) {
            Some(&(r, c)) => (r as Real / 65535.0, c as Real / 65535.0),
            None => (0.0, 0.0),
        }
    }

    /// Grid spacing of the last fill, in pixels.
    pub(crate) fn spacing(&self) -> i32 {
        self.spacing
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::PixelFormat;
    use crate::geometry::Ellipse;
    use crate::region::{Sampling, for_each_in_ellipse};

    fn noise(w: usize, h: usize) -> Vec<u8> {
        let mut next = crate::testing::lcg(17);
        (0..w * h * 3)
            .map(|i| {
                let seed = next();
                // Smooth-ish colour with noise, so that many bins are in play.
                ((i % 97) as u32 * 2 + (seed >> 28)) as u8
            })
            .collect()
    }

    #[test]
    fn sliding_histogram_equals_the_direct_one_at_every_position() {
        // Reason: a cross-check between two implementations: at every
        // position of a raster scan (several steps, both samplings, windows
        // partly off the frame), the slid histogram must equal, bin for bin,
        // the unweighted histogram of the pixels the region walk visits, and
        // its running ρ must equal the model's ρ of that histogram exactly.
        let (w, h) = (60usize, 44usize);
        let px = noise(w, h);
        let f = Frame::packed(&px, w, h, PixelFormat::Rgb888).unwrap();
        let mut model_hist = Histogram::<512>::new();
        model_hist.compute(&f, &Ellipse { cx: 30.0, cy: 22.0, hx: 9.0, hy: 6.0 }, Binning::Rgb8x8x8, Sampling::Full);
        let model = Model::from_histogram(&model_hist).unwrap();
        for (hx, hy) in [(9.0f32, 6.0f32), (4.5, 11.0)] {
            for sampling in [Sampling::Full, Sampling::Checkerboard, Sampling::Quarter] {
                for step in [1i32, 2, 3, 7] {
                    let lattice = Lattice::new(sampling, 0, hx, hy);
                    let bins = Bins::<16> { frame: &f, binning: Binning::Rgb8x8x8, levels: 8, map: None, lattice };
                    let ext = Extents::new(&Ellipse { cx: 0.0, cy: 0.0, hx, hy }).unwrap();
                    let mut win = Window::new(&model);
                    for cy in [-3i32, 0, 10, 22, 40, 47] {
                        let mut cx = -4;
                        win.place(&bins, &ext, cx, cy);
                        while cx < 64 {
                            let e = Ellipse { cx: cx as f32 + 0.5, cy: cy as f32 + 0.5, hx, hy };
                            let mut direct = Histogram::<512>::new();
                            for_each_in_ellipse(&f, &e, lattice, |_, x, y, _| {
                                direct.add(Binning::Rgb8x8x8.bin(f.rgb(x, y).unwrap()), 1)
                            });
                            assert_eq!(win.colour, direct, "{hx}x{hy} {sampling:?} step {step} at ({cx},{cy})");
                            assert_eq!(win.rho(), model.bhattacharyya(&direct), "ρ at ({cx},{cy})");
                            win.slide(&bins, &ext, cx, cy, step);
                            cx += step;
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn lookup_finds_the_nearest_cell() {
        // Reason: by construction: cell (i, j) holds the window centred on
        // pixel (x0 + i·s, y0 + j·s); a particle at (x, y) in continuous
        // coordinates sits in pixel floor(x), nearest cell round((x − x0)/s).
        let mut t = Table::<64> { cells: [(0, 0); 64], x0: 10, y0: 20, cols: 8, rows: 8, spacing: 2 };
        for (k, c) in t.cells.iter_mut().enumerate() {
            *c = (k as u16, k as u16 * 2);
        }
        let (r, _) = t.lookup(14.2, 26.9);
        // (14.2 − 10)/2 + 0.5 = 2.6 → 2; (26.9 − 20)/2 + 0.5 = 3.95 → 3.
        assert_eq!((r * 65535.0).round() as usize, 3 * 8 + 2);
        // Off the grid: clamped to the border cells.
        let (r, _) = t.lookup(-100.0, 1000.0);
        assert_eq!((r * 65535.0).round() as usize, 7 * 8);
    }
}
