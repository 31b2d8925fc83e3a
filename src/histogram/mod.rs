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
//! of square roots, turned into a [`Real`](crate::Real) once per comparison.

mod model;
#[cfg(test)]
mod tests;
mod walk;

use crate::colour::{Binning, levels_bin};
use crate::cue::not_built;
use crate::edges::MAX_EDGE_BINS;
use crate::edges::{EdgeMap, NIBBLE_NONE};
use crate::error::Checks;
use crate::frame::Frame;
use crate::geometry::Ellipse;
use crate::pixel::{self, PixelRead};
use crate::region::{Lattice, Sampling};

pub use model::{Model, SUPPORT_WORDS, Similarity, bhattacharyya_distance};
pub(crate) use model::{PlainModel, Support};
use walk::*;
pub(crate) use walk::{for_each_bin, row_bins};

/// Whether the quadrant layout is on: asked for, and built (the
/// `quadrants` feature).
pub(crate) const fn quadrants(on: bool) -> bool {
    cfg!(feature = "quadrants") && on
}

/// Asking for quadrants in a build without them is an error that names the
/// feature.
#[inline]
pub(crate) fn validate_quadrants(c: &mut Checks, on: bool) {
    if on && !cfg!(feature = "quadrants") {
        c.fail(not_built("quadrants", "quadrants"));
    }
}

/// How the bins of a histogram are laid out: the colour binning, whether the
/// ellipse is split into quadrants (each with its own block of bins), and
/// the levels per channel each block uses under [`Binning::Adaptive`].
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(crate) struct Layout {
    pub binning: Binning,
    /// 1 (the whole ellipse) or 4 (quadrants: top-left, top-right,
    /// bottom-left, bottom-right, split at the centre pixel), each owning
    /// `K / segments` consecutive bins.
    pub segments: u8,
    /// Levels per channel of each segment, for [`Binning::Adaptive`].
    pub levels: [u8; 4],
}

impl Layout {
    /// One histogram over the whole ellipse.
    pub(crate) const fn whole(binning: Binning) -> Self {
        Layout { binning, segments: 1, levels: [crate::colour::ADAPTIVE_LEVELS.0; 4] }
    }

    /// The bin of an 8-bit RGB colour in the first segment (the whole
    /// ellipse's, without quadrants).
    #[inline]
    pub(crate) fn bin(&self, rgb: [u8; 3]) -> usize {
        match self.binning {
            Binning::Adaptive => levels_bin(rgb, self.levels[0]),
            other => other.bin(rgb),
        }
    }

    /// Whether this is the layout the per-format loops are compiled for.
    fn is_fast(&self) -> bool {
        self.segments == 1 && self.binning == Binning::Rgb8x8x8
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
        Histogram { counts: [0; K], total: 0 }
    }

    /// The raw weighted counts.
    pub fn counts(&self) -> &[u32; K] {
        &self.counts
    }

    /// The sum of all counts (the normaliser).
    pub fn total(&self) -> u32 {
        self.total
    }

    /// Empties the histogram.
    pub fn clear(&mut self) {
        self.counts = [0; K];
        self.total = 0;
    }

    /// Adds `weight` to bin `bin`; bins past `K` are ignored. Sums wrap past
    /// `u32::MAX`, which kernel weights over any frame the core accepts
    /// cannot reach (see [`crate::scalar::KERNEL_ONE`]).
    #[inline(always)]
    pub fn add(&mut self, bin: usize, weight: u32) {
        if let Some(c) = self.counts.get_mut(bin) {
            *c = c.wrapping_add(weight);
            self.total = self.total.wrapping_add(weight);
        }
    }

    /// Adds `weight` to bin `bin` (if there is one) without touching the
    /// total, for region walks that sum it once at the end.
    #[inline(always)]
    fn add_to_bin(&mut self, bin: usize, weight: u32) {
        if let Some(c) = self.counts.get_mut(bin) {
            *c = c.wrapping_add(weight);
        }
    }

    /// Removes `weight` from bin `bin` (undoing [`Histogram::add`]); bins past
    /// `K` are ignored.
    #[inline(always)]
    pub(crate) fn sub(&mut self, bin: usize, weight: u32) {
        if let Some(c) = self.counts.get_mut(bin) {
            *c = c.wrapping_sub(weight);
            self.total = self.total.wrapping_sub(weight);
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
        self.compute_on(frame, e, binning, Lattice::new(sampling, 0, e.hx, e.hy));
    }

    /// [`Histogram::compute`] on an explicit lattice.
    pub(crate) fn compute_on(&mut self, frame: &Frame<'_>, e: &Ellipse, binning: Binning, lattice: Lattice) {
        self.compute_with::<0>(frame, e, &Layout::whole(binning), lattice, None, Clear::All);
    }

    /// [`Histogram::compute_on`] with `layout`, also filling an edge
    /// histogram from `edges`' map (which must be on `lattice`): both cues
    /// ride on one walk over the region. `clear` says which colour bins
    /// must come out exact.
    #[inline(always)]
    pub(crate) fn compute_with<const E: usize>(
        &mut self,
        frame: &Frame<'_>,
        e: &Ellipse,
        layout: &Layout,
        lattice: Lattice,
        edges: Option<(&EdgeMap<E>, &mut EdgeHistogram)>,
        clear: Clear<'_>,
    ) {
        self.compute_by::<E>(frame, e, (layout, lattice), edges, clear, true);
    }

    /// [`Histogram::compute_with`], through the per-format loops where
    /// there is one if `per_format`, else through the shared loop that
    /// reads pixels through the general accessor: the same counts either
    /// way (tested, which is what the flag is for).
    #[inline(always)]
    fn compute_by<const E: usize>(
        &mut self,
        frame: &Frame<'_>,
        e: &Ellipse,
        (layout, lattice): (&Layout, Lattice),
        edges: Option<(&EdgeMap<E>, &mut EdgeHistogram)>,
        clear: Clear<'_>,
        per_format: bool,
    ) {
        match clear {
            Clear::All => self.clear(),
            Clear::Support(support) => {
                support.for_each::<K>(0, K, |b| {
                    if let Some(c) = self.counts.get_mut(b) {
                        *c = 0;
                    }
                });
                self.total = 0;
            }
        }
        let mut unused = EdgeHistogram::new();
        let (map, edge) = match edges {
            Some((map, hist)) => (Some(map), hist),
            None => (None, &mut unused),
        };
        edge.clear();
        // The default layout gets a loop compiled per pixel format (see
        // `RegionWalk::LOOPS`); the others (HSV, coarser or adaptive RGB,
        // quadrants), slower per pixel anyway, share one loop that reads
        // pixels through the general accessor: a loop per layout and format
        // would cost more flash than a small target can spare.
        let walk = RegionWalk { hist: self, frame, e, layout, lattice, map, edge };
        pixel::read_if(per_format && layout.is_fast(), frame.format(), walk);
        // 4-bit maps drop the weight of cells with no bin into the nibble
        // form's "none" bin, which no orientation uses (see `take`).
        if map.is_some_and(|m| m.nibbles())
            && let Some(c) = edge.counts.get_mut(NIBBLE_NONE as usize)
        {
            *c = 0;
        }
        edge.recount();
    }

    #[inline(always)]
    fn accumulate<P: PixelRead, const E: usize>(
        &mut self,
        frame: &Frame<'_>,
        e: &Ellipse,
        lattice: Lattice,
        map: Option<&EdgeMap<E>>,
        edge: &mut EdgeHistogram,
    ) {
        let (counts, edge) = (&mut self.counts, &mut edge.counts);
        // The default case (the checkerboard, RGB565 or GRAY8 pixels, a
        // 4-bit edge map at full resolution) has a walk of its own whose
        // rows cost a fraction of the general walk's set-up outside the
        // pixel loop (`audit/profile`, docs/performance.md); both visit the
        // same samples with the same weights (tested).
        let checker = match map.and_then(|m| m.checker_rows()) {
            Some(rows) if lattice == Lattice::CHECKERBOARD && P::CHECKER_WALK => {
                checker_walk::<P, K>(frame, e, rows, counts, edge)
            }
            _ => None,
        };
        self.total = checker.unwrap_or_else(|| general_walk::<P, K, E>(frame, e, lattice, map, counts, edge));
    }

    /// Sums the counts into the total (after [`Histogram::add_to_bin`]).
    fn recount(&mut self) {
        self.total = self.counts.iter().fold(0u32, |a, &c| a.wrapping_add(c));
    }
}

/// Which colour bins [`Histogram::compute_with`] starts from zero.
#[derive(Copy, Clone)]
pub(crate) enum Clear<'a> {
    /// All of them: the histogram comes out exact.
    All,
    /// Only a model's non-empty bins, for a histogram that is only compared
    /// with that model (one segment): the Bhattacharyya and intersection
    /// sums read no other bin (an intersection term is 0 where the model
    /// is), so the rest may keep what earlier regions left there. It
    /// spares clearing all `K` bins per particle, a `memclr` that with 512
    /// bins shows in the QVGA audit's instructions per frame.
    Support(&'a Support),
}

/// An edge-orientation histogram: up to 16 orientation bins and a flat one.
pub(crate) type EdgeHistogram = Histogram<MAX_EDGE_BINS>;
