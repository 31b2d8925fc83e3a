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

use crate::colour::{Binning, levels_bin};
use crate::config::MAX_EDGE_BINS;
use crate::edges::{EdgeMap, NIBBLE_NONE, RowCells};
use crate::frame::Frame;
use crate::geometry::Ellipse;
use crate::pixel::{self, Loop, Loops, PixelRead, RowReader};
use crate::region::{
    Kernel, Lattice, PairKernel, Raster, RowSpan, Sampling, floor, for_each_row, quadrant, shrink, widen,
};
use crate::scalar::{KERNEL_ONE, RADIUS2_SHIFT};
use crate::scalar::{Real, sqrt_q4};

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
        if per_format && layout.is_fast() {
            pixel::read(frame.format(), walk)
        } else {
            walk.general()
        }
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
        // rows cost a fraction of the general walk's set-up (measured: 454
        // instructions per row outside the pixel loop on a Cortex-M4, for
        // rows of 16 samples); both visit the same samples with the same
        // weights (tested).
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

/// One region's colour and edge walk: [`Histogram::compute_with`]'s
/// arguments, read by a loop per format or the general one.
struct RegionWalk<'h, 'f, 'r, const K: usize, const E: usize> {
    hist: &'h mut Histogram<K>,
    frame: &'r Frame<'f>,
    e: &'r Ellipse,
    layout: &'r Layout,
    lattice: Lattice,
    map: Option<&'r EdgeMap<E>>,
    edge: &'r mut EdgeHistogram,
}

impl<const K: usize, const E: usize> RowReader for RegionWalk<'_, '_, '_, K, E> {
    type Output = ();
    // RGB888 reaches a microcontroller from no camera (they give RGB565,
    // YUV 4:2:2 or GRAY8); the planar formats' pixels span planes.
    const LOOPS: Loops = Loops {
        rgb565: Loop::Always,
        rgb888: Loop::Host,
        yuv422: Loop::Always,
        gray8: Loop::Always,
        planar_luma: Loop::General,
    };

    #[inline(always)]
    fn rows_of<P: PixelRead>(self) {
        self.hist.accumulate::<P, E>(self.frame, self.e, self.lattice, self.map, self.edge)
    }

    #[inline(always)]
    fn general(self) {
        let RegionWalk { hist, frame, e, layout, lattice, map, edge } = self;
        let (counts, mut total) = (&mut hist.counts, 0u32);
        let quads = cfg!(feature = "quadrants") && layout.segments == 4;
        let seg = K / layout.segments.max(1) as usize;
        let centre = (floor(e.cx), floor(e.cy));
        let (binning, levels) = (layout.binning, layout.levels);
        for_each_row(frame, e, lattice, |span| {
            let y = span.y;
            let cells = row_cells(map, &span);
            for (i, (x, w)) in span.enumerate() {
                edge.add_to_bin(cells.get(i) as usize, w);
                let q = if quads { quadrant(x, y, centre) } else { 0 };
                if let Some(rgb) = frame.rgb(x, y) {
                    let b = match binning {
                        Binning::Adaptive => levels_bin(rgb, levels.get(q).copied().unwrap_or(2)),
                        other => other.bin(rgb),
                    };
                    if let Some(c) = counts.get_mut(q * seg + b) {
                        *c = c.wrapping_add(w);
                        total = total.wrapping_add(w);
                    }
                }
            }
        });
        hist.total = total;
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
    /// spares clearing all `K` bins per particle (measured on the QVGA
    /// audit: 0.1 M instructions per frame in `memclr` for 512 bins).
    Support(&'a Support),
}

/// An edge-orientation histogram: up to 16 orientation bins and a flat one.
pub(crate) type EdgeHistogram = Histogram<MAX_EDGE_BINS>;

/// The edge cells of `span`'s samples in `map`, or none.
#[inline(always)]
fn row_cells<'m, const E: usize>(map: Option<&'m EdgeMap<E>>, span: &RowSpan<'_>) -> RowCells<'m> {
    map.map_or(RowCells::EMPTY, |m| m.row_cells(span))
}

/// One sample: its colour bin `bin` and edge cell `cell` take weight `w`.
/// Returns the colour mass added. A cell with no bin is `NONE`, past the
/// histogram, or in 4-bit maps [`NIBBLE_NONE`], a bin no orientation uses
/// (4-bit maps have at most 8 orientations and the flat bin), emptied after
/// the walk: no branch per sample, and in a 4-bit map every sample lands in
/// an edge bin.
#[inline(always)]
fn take<const K: usize>(bin: usize, cell: u8, w: u32, counts: &mut [u32; K], edge: &mut [u32; MAX_EDGE_BINS]) -> u32 {
    // Weak cells (NONE) are past the histogram: no bin.
    if let Some(c) = edge.get_mut(cell as usize) {
        *c = c.wrapping_add(w);
    }
    match counts.get_mut(bin) {
        // Sums stay below 2^32 for any frame within MAX_DIMENSION;
        // wrapping keeps the loop free of a panic path regardless.
        Some(c) => {
            *c = c.wrapping_add(w);
            w
        }
        None => 0,
    }
}

/// The colour and edge walk of ellipse `e` on any lattice: rows from
/// [`for_each_row`], cells from [`EdgeMap::row_cells`]. Returns the colour
/// mass.
#[inline(always)]
fn general_walk<P: PixelRead, const K: usize, const E: usize>(
    frame: &Frame<'_>,
    e: &Ellipse,
    lattice: Lattice,
    map: Option<&EdgeMap<E>>,
    counts: &mut [u32; K],
    edge: &mut [u32; MAX_EDGE_BINS],
) -> u32 {
    let mut total = 0u32;
    // With a 4-bit map, every sample on its row adds its weight to one edge
    // value and (with all 512 bins of the fast layout) to one colour bin:
    // the colour mass is the sum over the edge values, and the rows need
    // not keep it (`edge` starts empty). Rows of whole cell bytes are read
    // two samples at a time in the camera formats (RGB565, GRAY8), a loop
    // that saves time only; both ways count the same samples with the same
    // weights (tested).
    let by_edges = Loop::Fast.compiled() && P::CHECKER_WALK && K >= 512 && map.is_some_and(|m| m.nibbles());
    for_each_row(frame, e, lattice, |span| {
        // The default checkerboard takes `checker_walk`; what comes here
        // (coarser lattices, regions past the map) takes the pair loop on
        // rows of whole cell bytes, or one indexed loop.
        let cells = row_cells(map, &span);
        if !(by_edges && pair_row::<P, K>(&span, &cells, counts, edge)) {
            total = total.wrapping_add(indexed_row::<P, K>(&span, &cells, counts, edge));
        }
    });
    if by_edges { edge.iter().take(NIBBLE_NONE as usize + 1).fold(0u32, |a, &c| a.wrapping_add(c)) } else { total }
}

/// A row of [`general_walk`] on a 4-bit map at the lattice's resolution,
/// whose consecutive samples read consecutive cells: through
/// [`stride_pairs`], two samples per cell byte. Returns whether it took the
/// row (else nothing is counted).
#[inline(always)]
fn pair_row<P: PixelRead, const K: usize>(
    span: &RowSpan<'_>,
    cells: &RowCells<'_>,
    counts: &mut [u32; K],
    edge: &mut [u32; MAX_EDGE_BINS],
) -> bool {
    if cells.shift != 0 || !cells.nibbles || span.n == 0 {
        return false;
    }
    let (base, n) = (cells.base, span.n);
    // The bytes from the first sample's cell to the last's; the samples'
    // pixels, the last on the row.
    let bytes = (base.wrapping_add(n - 1) >> 1).wrapping_sub(base >> 1).wrapping_add(1);
    let Some(bytes) = cells.bytes.get(base >> 1..).and_then(|b| b.get(..bytes)) else { return false };
    match P::pixels(span.row).and_then(|px| px.get(span.x..)) {
        Some(px) if (n - 1).checked_mul(span.dx).is_some_and(|end| end < px.len()) => {
            stride_pairs::<P, K>(counts, edge, (px, bytes), (span.dx, n, base & 1 == 1), span.kernel);
            true
        }
        _ => false,
    }
}

/// [`pair_loop`] for `n` samples `dx` pixels apart, the first at `px[0]`
/// reading `bytes[0]`'s high nibble if `odd` (an odd cell), else its low
/// one: a lone first sample, pairs that share a byte, a lone last one. Out
/// of line, so that the loop has the registers to itself.
#[inline(never)]
fn stride_pairs<P: PixelRead, const K: usize>(
    counts: &mut [u32; K],
    edge: &mut [u32; MAX_EDGE_BINS],
    (px, mut bytes): (&[P::Px], &[u8]),
    (dx, mut n, odd): (usize, usize, bool),
    mut kernel: Kernel,
) {
    let mut x = 0usize;
    if odd {
        let w = kernel.next_weight();
        if let (Some(&p), Some((&b, rest))) = (px.first(), bytes.split_first()) {
            take(P::px_8x8x8(p), b >> 4, w, counts, edge);
            bytes = rest;
        }
        (x, n) = (dx, n.saturating_sub(1));
    }
    // Pairs' weights only: the samples lie inside the ellipse, so no
    // weight past them is read (those could overflow for thin ellipses).
    let mut kernel = PairKernel::new(kernel);
    let (pairs, rest) = bytes.split_at((n / 2).min(bytes.len()));
    for &b in pairs {
        let (Some(&p0), Some(&p1)) = (px.get(x), px.get(x.wrapping_add(dx))) else { return };
        x = x.wrapping_add(2 * dx);
        let (w0, w1) = kernel.next_pair_or_zero();
        take(P::px_8x8x8(p0), b & 0x0f, w0, counts, edge);
        take(P::px_8x8x8(p1), b >> 4, w1, counts, edge);
    }
    if n % 2 == 1
        && let (Some(&p), Some(&b)) = (px.get(x), rest.first())
    {
        take(P::px_8x8x8(p), b & 0x0f, kernel.next_pair_or_zero().0, counts, edge);
    }
}

/// [`general_walk`] for the default checkerboard (pixels with `x + y` even)
/// and a map from [`EdgeMap::checker_rows`], with the row geometry of
/// [`for_each_row`] written out for that lattice: rows one apart, samples
/// two apart, the map row and column by subtraction. Rows `cy − d` and
/// `cy + d` have the same width, the same parity and so the same samples
/// and weights: their geometry is worked out once for both. Returns the
/// colour mass: with a 4-bit map every sample adds its weight to one edge
/// value and to one colour bin (the checkerboard path reads RGB 8x8x8, all
/// of whose bins exist), so it is the sum over the edge values, and the
/// pixel loops need not keep it. `edge` must start empty. `None`, before
/// any work, if the ellipse has rows outside the map. Out of line, so that
/// its registers are its own (inlined into the tracker's observation, its
/// row set-up kept most of its state on the stack).
#[inline(never)]
fn checker_walk<P: PixelRead, const K: usize>(
    frame: &Frame<'_>,
    e: &Ellipse,
    (bytes, j0, k0, cols, rows, stride): (&[u8], usize, usize, usize, usize, usize),
    counts: &mut [u32; K],
    edge: &mut [u32; MAX_EDGE_BINS],
) -> Option<u32> {
    let Some(r) = Raster::new(e) else { return Some(0) };
    let one = 1u32 << RADIUS2_SHIFT;
    let min_gap = 1u32 << (RADIUS2_SHIFT - KERNEL_ONE.trailing_zeros());
    let (width, height) = (frame.width() as i32, frame.height() as i32);
    let (y_lo, y_hi) = ((r.cy - r.ry).max(0), (r.cy + r.ry).min(height - 1));
    if y_lo > y_hi {
        return Some(0);
    }
    // Every pixel row y_lo..=y_hi must have its map row (lattice row j = y).
    if (y_lo as usize) < j0 || y_hi as usize + 1 - j0 > rows {
        return None;
    }
    // Where the centre row starts in the frame's bytes and in the map
    // (lattice row j = y). Wrapping: exact for the rows in y_lo..=y_hi, the
    // only ones read (`cy` may be off the frame).
    let (fstride, data) = (frame.stride(), frame.bytes());
    let cy = r.cy as usize;
    let (px_centre, cells_centre) = (cy.wrapping_mul(fstride), cy.wrapping_sub(j0).wrapping_mul(stride));
    // The half width of row d = 0; further rows only narrow it (`shrink`).
    let mut dx_max = r.rx;
    widen(&mut dx_max, one - min_gap, r.ax);
    let px_bytes = core::mem::size_of::<P::Px>();
    // Rows on the fast path wait in a batch, run by one call: the pixel
    // loop's registers are set up once per batch, not per row.
    let mut batch = heapless::Vec::<RowPair, ROW_BATCH>::new();
    // Where rows cy − d and cy + d start, moved one row per d.
    let (mut px_up, mut cells_up) = (px_centre, cells_centre);
    let (mut px_down, mut cells_down) = (px_centre, cells_centre);
    // Row cy − d is in y_lo..=y_hi for d in cy − y_hi..=cy − y_lo, row
    // cy + d for d in y_lo − cy..=y_hi − cy: one unsigned comparison each.
    let span = (y_hi - y_lo) as u32;
    let (up_from, down_from) = (r.cy - y_hi, y_lo - r.cy);
    for d in 0..=r.ry as u32 {
        // d <= ry <= Hy, so d²·ay <= Hy²·2^24 / Hy² = 2^24: no overflow.
        // Rows past the kernel (r² > one − min_gap) end the walk: r² grows
        // with d.
        let ry2 = d.wrapping_mul(d).wrapping_mul(r.ay);
        let Some(rem) = (one - min_gap).checked_sub(ry2) else { break };
        shrink(&mut dx_max, rem, r.ax);
        let half = dx_max as i32;
        let (x_lo, x_hi) = ((r.cx - half).max(0), (r.cx + half).min(width - 1));
        let (y_up, y_down) = (r.cy - d as i32, r.cy + d as i32);
        // The first pixel with x + y even (the same for both rows: they are
        // 2d apart).
        let first = x_lo + ((x_lo ^ y_up) & 1);
        let up = (d as i32).wrapping_sub(up_from) as u32 <= span;
        let down = d > 0 && (d as i32).wrapping_sub(down_from) as u32 <= span;
        if first <= x_hi {
            let n = ((x_hi - first) >> 1) as usize + 1;
            // Lattice column of the first sample: (first - (y & 1)) / 2.
            let base = ((first >> 1) as usize).wrapping_sub(k0);
            // Whole cell bytes: from the byte of the first sample to that of
            // the last, one sample before the first (an odd cell) and one
            // after the last (an even cell) may come along. They are outside
            // the ellipse, so their clamped weight is 0 and they change no
            // count; this needs their pixels on the row.
            let (m0, m1) = (base >> 1, (base + n - 1) >> 1);
            let x0 = first - 2 * (base & 1) as i32;
            let pairs = m1.wrapping_sub(m0).wrapping_add(1);
            // The padded samples' pixels must be on the row, and their
            // cells in the map.
            if base < cols && x0 >= 0 && x0 as usize + 4 * pairs <= width as usize && m0 + pairs <= stride {
                let lo = x0 as usize * px_bytes;
                // A row outside the region gets offsets past any slice.
                let row = |on: bool, px: usize, cells: usize| match on {
                    true => (px.wrapping_add(lo), cells.wrapping_add(m0)),
                    false => (usize::MAX, usize::MAX),
                };
                let pair = RowPair {
                    rows: [row(up, px_up, cells_up), row(down, px_down, cells_down)],
                    pairs,
                    kernel: Kernel::start(one - ry2, r.ax, x0 - r.cx, 2),
                };
                if batch.is_full() {
                    fast_rows::<P, K>(&batch, (data, bytes), counts, edge);
                    batch.clear();
                }
                // Not full: the pair is pushed.
                let _ = batch.push(pair);
            } else {
                let plan = RowPlan { first: first as usize, n, start: (one - ry2, r.ax, first - r.cx), base };
                // The map row's offset from y, not the carried ones: carried
                // into this cold branch, they cost the common rows spills
                // (measured: 5 k instructions per QVGA frame).
                for (y, on) in [(y_up, up), (y_down, down)] {
                    let start = (y as usize).wrapping_sub(j0).wrapping_mul(stride);
                    if on && let Some(row) = frame.row(y as usize) {
                        let cells = bytes.get(start..start.wrapping_add(stride)).unwrap_or(&[]);
                        edge_row::<P, K>(row, y as usize, &plan, cells, counts, edge);
                    }
                }
            }
        }
        (px_up, cells_up) = (px_up.wrapping_sub(fstride), cells_up.wrapping_sub(stride));
        (px_down, cells_down) = (px_down.wrapping_add(fstride), cells_down.wrapping_add(stride));
    }
    fast_rows::<P, K>(&batch, (data, bytes), counts, edge);
    Some(edge.iter().take(NIBBLE_NONE as usize + 1).fold(0u32, |a, &c| a.wrapping_add(c)))
}

/// What [`edge_row`] needs of a row of [`checker_walk`].
struct RowPlan {
    /// The first exact sample and the number of them.
    first: usize,
    n: usize,
    /// [`Kernel::start`]'s arguments for the first exact sample.
    start: (u32, u32, i32),
    /// The first exact sample's map column.
    base: usize,
}

/// How many pairs of rows [`checker_walk`] hands [`fast_rows`] at a time.
const ROW_BATCH: usize = 8;

/// Rows `cy − d` and `cy + d` of [`checker_walk`] when their padded
/// samples' pixels and cells are all there.
#[derive(Copy, Clone)]
struct RowPair {
    /// Where each row's padded samples' pixels start in the frame's bytes
    /// and their cells in the map's (`usize::MAX` for a row outside the
    /// region).
    rows: [(usize, usize); 2],
    /// Number of pairs of samples (four-pixel chunks and cell bytes).
    pairs: usize,
    /// The weights from the first padded sample.
    kernel: Kernel,
}

/// The rows of a batch from [`checker_walk`]; a row whose pixels or cells
/// are not all in the frame or the map (none is: checked when it was
/// planned) is skipped. Out of line, so that the pair loop has the
/// registers to itself (inlined into the walk, it kept half of its state
/// on the stack).
#[inline(never)]
fn fast_rows<P: PixelRead, const K: usize>(
    batch: &[RowPair],
    (data, bytes): (&[u8], &[u8]),
    counts: &mut [u32; K],
    edge: &mut [u32; MAX_EDGE_BINS],
) {
    let chunk = 4 * core::mem::size_of::<P::Px>();
    for pair in batch {
        for &(px, cells) in &pair.rows {
            let Some(px) = data.get(px..) else { continue };
            let Some(px) = px.get(..pair.pairs.wrapping_mul(chunk)) else { continue };
            let Some(cells) = bytes.get(cells..) else { continue };
            let Some(cells) = cells.get(..pair.pairs) else { continue };
            if let Some(px) = P::pixels(px) {
                pair_loop::<P, K>(counts, edge, px.as_chunks::<4>().0, cells, pair.kernel);
            }
        }
    }
}

/// A row of [`checker_walk`] at the frame's or the map's edge (its padded
/// cell bytes or pixels are not all there): the exact samples only. Cold and
/// out of line, to keep the common rows' registers free.
#[cold]
#[inline(never)]
fn edge_row<P: PixelRead, const K: usize>(
    row: &[u8],
    y: usize,
    plan: &RowPlan,
    cells: &[u8],
    counts: &mut [u32; K],
    edge: &mut [u32; MAX_EDGE_BINS],
) {
    // Few rows come here (those at the frame's or the map's edge): the
    // indexed loop, with a bounds test per sample, costs the least flash.
    let (rem, ax, u) = plan.start;
    let span = RowSpan { y, row, x: plan.first, n: plan.n, dx: 2, kernel: Kernel::start(rem, ax, u, 2) };
    let cells = RowCells { bytes: cells, base: plan.base, shift: 0, nibbles: true };
    indexed_row::<P, K>(&span, &cells, counts, edge);
}

/// Two samples per cell byte and per four-pixel chunk, weights clamped to 0
/// (see [`checker_walk`], which also sums the colour mass). Out of line, so
/// that the loop has the registers to itself (inlined, it kept half of its
/// state on the stack); the histograms come first among the arguments, so
/// that they arrive in registers and stay there (measured: one instruction
/// per pair less than reloading them from the stack).
#[inline(never)]
fn pair_loop<P: PixelRead, const K: usize>(
    counts: &mut [u32; K],
    edge: &mut [u32; MAX_EDGE_BINS],
    quads: &[[P::Px; 4]],
    bytes: &[u8],
    kernel: Kernel,
) {
    let mut kernel = PairKernel::new(kernel);
    for (q, &b) in quads.iter().zip(bytes) {
        let [p0, _, p1, _] = *q;
        let (w0, w1) = kernel.next_pair_or_zero();
        take(P::px_8x8x8(p0), b & 0x0f, w0, counts, edge);
        take(P::px_8x8x8(p1), b >> 4, w1, counts, edge);
    }
}

/// The per-pixel loop of any row: sample `i` reads `cells.get(i)` and its
/// pixel through a bounds-tested read. Returns the row's colour mass.
#[inline(always)]
fn indexed_row<P: PixelRead, const K: usize>(
    span: &RowSpan<'_>,
    cells: &RowCells<'_>,
    counts: &mut [u32; K],
    edge: &mut [u32; MAX_EDGE_BINS],
) -> u32 {
    let (row, mut x, dx, mut kernel) = (span.row, span.x, span.dx, span.kernel);
    let mut total = 0u32;
    for i in 0..span.n {
        let w = kernel.next_weight();
        if let Some(bin) = P::rgb_8x8x8(row, x) {
            total = total.wrapping_add(take(bin, cells.get(i), w, counts, edge));
        }
        x += dx;
    }
    total
}

/// Calls `visit(i, bin)` for the pixels `(x0 + i·step, y)`, `i < n`, that
/// lie in the frame, with their colour bin under `layout` (its first
/// segment's). For the default layout each pixel format has its own loop
/// (RGB565 bins come straight from the packed bits); the others share the
/// general accessor.
pub(crate) fn row_bins<F: FnMut(usize, usize)>(
    frame: &Frame<'_>,
    layout: &Layout,
    y: usize,
    (x0, step, n): (usize, usize, usize),
    visit: F,
) {
    let Some(row) = frame.row(y) else { return };
    let step = step.max(1);
    if !layout.is_fast() {
        return general_bins(frame, layout, y, (x0, step, n), visit);
    }
    pixel::read(frame.format(), RowBins { frame, layout, row, y, at: (x0, step, n), visit })
}

/// [`row_bins`]' arguments, read by a loop per format or the general one.
struct RowBins<'f, 'r, F> {
    frame: &'r Frame<'f>,
    layout: &'r Layout,
    row: &'f [u8],
    y: usize,
    at: (usize, usize, usize),
    visit: F,
}

impl<F: FnMut(usize, usize)> RowReader for RowBins<'_, '_, F> {
    type Output = ();
    // The formats whose pixels are self-contained (YUV 4:2:2's pairs share
    // their chroma), RGB888 as in the region walk.
    const LOOPS: Loops = Loops {
        rgb565: Loop::Always,
        rgb888: Loop::Host,
        yuv422: Loop::General,
        gray8: Loop::Always,
        planar_luma: Loop::General,
    };

    #[inline(always)]
    fn rows_of<P: PixelRead>(self) {
        packed_bins::<P, F>(self.row, self.at, self.visit)
    }

    #[inline(always)]
    fn general(self) {
        general_bins(self.frame, self.layout, self.y, self.at, self.visit)
    }
}

#[inline(always)]
fn packed_bins<P: PixelRead, F: FnMut(usize, usize)>(row: &[u8], (x0, step, n): (usize, usize, usize), mut visit: F) {
    let Some(px) = P::pixels(row) else { return };
    for (i, &p) in px.iter().skip(x0).step_by(step).take(n).enumerate() {
        visit(i, P::px_8x8x8(p));
    }
}

fn general_bins<F: FnMut(usize, usize)>(
    frame: &Frame<'_>,
    layout: &Layout,
    y: usize,
    (x0, step, n): (usize, usize, usize),
    mut visit: F,
) {
    for i in 0..n {
        match frame.rgb(x0 + i * step, y) {
            Some(rgb) => visit(i, layout.bin(rgb)),
            None => return,
        }
    }
}

/// Calls `visit(x, y, bin)` for every sample of ellipse `e` on `lattice`:
/// the region walk of [`Histogram::compute_on`], for algorithms that need
/// each pixel's bin and place (mean shift).
pub(crate) fn for_each_bin<F: FnMut(usize, usize, usize)>(
    frame: &Frame<'_>,
    e: &Ellipse,
    binning: Binning,
    lattice: Lattice,
    visit: F,
) {
    // Chosen once per region, not per pixel: RGB565 camera frames with the
    // default binning read bins straight from the packed bits.
    let walk = BinWalk { frame, e, binning, lattice, visit };
    if binning == Binning::Rgb8x8x8 { pixel::read(frame.format(), walk) } else { walk.general() }
}

/// [`for_each_bin`]'s arguments, read by a loop per format or the general one.
struct BinWalk<'f, 'r, F> {
    frame: &'r Frame<'f>,
    e: &'r Ellipse,
    binning: Binning,
    lattice: Lattice,
    visit: F,
}

impl<F: FnMut(usize, usize, usize)> RowReader for BinWalk<'_, '_, F> {
    type Output = ();
    // Mean shift's walk on RGB565 camera frames; the rest read through the
    // general accessor.
    const LOOPS: Loops = Loops {
        rgb565: Loop::Always,
        rgb888: Loop::General,
        yuv422: Loop::General,
        gray8: Loop::General,
        planar_luma: Loop::General,
    };

    /// Bins of the default binning straight from the pixels.
    #[inline(always)]
    fn rows_of<P: PixelRead>(self) {
        let BinWalk { frame, e, lattice, mut visit, .. } = self;
        for_each_row(frame, e, lattice, |span| {
            let (y, row) = (span.y, span.row);
            for (x, _) in span {
                if let Some(bin) = P::rgb_8x8x8(row, x) {
                    visit(x, y, bin);
                }
            }
        });
    }

    #[inline(always)]
    fn general(self) {
        let BinWalk { frame, e, binning, lattice, mut visit } = self;
        for_each_row(frame, e, lattice, |span| {
            let y = span.y;
            for (x, _) in span {
                if let Some(rgb) = frame.rgb(x, y) {
                    visit(x, y, binning.bin(rgb));
                }
            }
        });
    }
}

/// How a histogram is compared with the model.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Similarity {
    /// The Bhattacharyya coefficient `ρ = Σ sqrt(p(u) q(u))` (first paper).
    #[default]
    Bhattacharyya,
    /// Histogram intersection `Σ min(p(u), q(u))` of the normalised
    /// histograms (Swain and Ballard, the head-tracking paper's
    /// `Σ min(I, M) / Σ I` with both normalised to the same mass).
    Intersection,
}

/// The target model: a normalised histogram `q` and its square roots, kept
/// ready for the Bhattacharyya sum.
///
/// `q(u)` is stored in units of `2^-16` and `sqrt(q(u))` in units of `2^-12`.
/// A model of a quadrant layout holds four blocks of `K / 4` bins, each
/// normalised on its own.
///
/// Its non-empty bins are kept as a bitmap of `W` 32-bit words (see
/// [`SUPPORT_WORDS`]): one bit per bin up to `32·W` bins, one per group of
/// bins beyond.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Model<const K: usize, const W: usize = SUPPORT_WORDS> {
    q: [u16; K],
    sqrt_q: [u16; K],
    /// Where `q` is non-zero, for sums that only need those bins.
    support: Support<W>,
    segments: u8,
}

/// The words of a [`Model`]'s bitmap of non-empty bins unless said
/// otherwise: 16, one bit per bin of the 512 RGB bins. A model of fewer
/// bins may take fewer words (the tracker's edge model, of
/// [`MAX_EDGE_BINS`] bins, takes one: 60 bytes of RAM less).
pub const SUPPORT_WORDS: usize = 16;

/// The non-empty bins of a model, as one bit per group of
/// `K.div_ceil(32·W)` bins (one bit per bin for `K <= 32·W`): `4·W` bytes
/// for any `K`.
///
/// A target's colours fill few of the 512 RGB bins (tens, on the real
/// sequences), and the Bhattacharyya sum of every particle needs only
/// those: visiting them through the bitmap is what keeps the sum from
/// costing a pass over all 512 bins per particle.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Support<const W: usize = SUPPORT_WORDS> {
    words: [u32; W],
}

impl<const W: usize> Support<W> {
    const GROUPS: usize = W * 32;

    /// Bins per bit for `K` bins (at least 1).
    const fn group_len<const K: usize>() -> usize {
        // A support of no words is refused when built (`of`); the test of
        // `GROUPS` keeps the division defined regardless.
        if K <= Self::GROUPS || Self::GROUPS == 0 { 1 } else { K.div_ceil(Self::GROUPS) }
    }

    const EMPTY: Self = Support { words: [0; W] };

    /// The support of the non-zero values of `v`.
    fn of<const K: usize>(v: &[u16; K]) -> Self {
        const { assert!(W > 0, "a model's support takes at least one word") };
        let g = Self::group_len::<K>();
        let mut words = [0u32; W];
        for (i, _) in v.iter().enumerate().filter(|&(_, &x)| x != 0) {
            let group = i / g;
            if let Some(w) = words.get_mut(group / 32) {
                *w |= 1 << (group % 32);
            }
        }
        Support { words }
    }

    /// Calls `f(i)` for every bin `i` in `lo..hi` whose group is in the
    /// support, in increasing order.
    #[inline(always)]
    fn for_each<const K: usize>(&self, lo: usize, hi: usize, mut f: impl FnMut(usize)) {
        let g = Self::group_len::<K>();
        // Only the words that hold groups (one for an edge model's 17 bins).
        let used = K.div_ceil(g).div_ceil(32);
        for (i, &word) in self.words.iter().enumerate().take(used) {
            let mut w = word;
            while w != 0 {
                let group = 32 * i + w.trailing_zeros() as usize;
                w &= w - 1;
                if g == 1 {
                    // One bin per bit (K <= 512, known at compile time).
                    if (lo..hi).contains(&group) {
                        f(group);
                    }
                } else {
                    for bin in (group * g).max(lo)..((group + 1) * g).min(hi) {
                        f(bin);
                    }
                }
            }
        }
    }
}

/// Fixed-point scale of a normalised model bin.
const Q_ONE: u64 = 1 << 16;

impl<const K: usize> Model<K> {
    /// The model of a histogram, or `None` if the histogram is empty.
    pub fn from_histogram(h: &Histogram<K>) -> Option<Self> {
        Self::from_segments(h, 1)
    }
}

impl<const K: usize, const W: usize> Model<K, W> {
    /// The model of a histogram laid out in `segments` equal blocks (1 or 4),
    /// each normalised on its own; `None` if any block is empty.
    pub(crate) fn from_segments(h: &Histogram<K>, segments: u8) -> Option<Self> {
        // Checked before the model is built, so that it is built in place
        // (an early return from the filling loop costs a 2·K-byte copy on
        // the stack: measured, +2 KB of peak stack in `init`).
        if !Self::can_learn(h, segments) {
            return None;
        }
        let mut m = Model { q: [0; K], sqrt_q: [0; K], support: Support::EMPTY, segments: 1 };
        m.learn(h, segments);
        Some(m)
    }

    /// Whether `h` has mass in each of its `segments` blocks (what
    /// [`Model::learn`] needs).
    pub(crate) fn can_learn(h: &Histogram<K>, segments: u8) -> bool {
        let segments = segments.max(1);
        let len = Self::len_of(segments);
        !h.counts.chunks(len).any(|c| segment_total(h, c, segments) == 0)
    }

    /// Replaces the model, in place, with that of `h` laid out in
    /// `segments` blocks; `h` must pass [`Model::can_learn`] (an empty block
    /// gets all-zero bins).
    pub(crate) fn learn(&mut self, h: &Histogram<K>, segments: u8) {
        let segments = segments.max(1);
        let len = Self::len_of(segments);
        self.segments = segments;
        for (q, c) in self.q.chunks_mut(len).zip(h.counts.chunks(len)) {
            let total = segment_total(h, c, segments);
            for (q, &c) in q.iter_mut().zip(c) {
                *q = normalised(c, total);
            }
        }
        self.refresh_roots();
    }

    /// An all-zero model (matches nothing), to be filled by [`Model::learn`].
    pub(crate) const fn zero() -> Self {
        Model { q: [0; K], sqrt_q: [0; K], support: Support::EMPTY, segments: 1 }
    }

    /// Bins per segment (at least 1, so that chunking is well defined).
    fn segment_len(&self) -> usize {
        Self::len_of(self.segments)
    }

    fn len_of(segments: u8) -> usize {
        // Without the feature a model has one segment, and saying so as a
        // constant lets the compiler drop the per-segment code.
        if !cfg!(feature = "quadrants") {
            return K.max(1);
        }
        (K / segments.max(1) as usize).max(1)
    }

    /// Blends a new observation into the model, `q ← (1 − α) q + α p`
    /// (the adaptive model of the first paper). `alpha` is clamped to `[0, 1]`;
    /// an empty histogram (or an empty segment of one) leaves the model (or
    /// that segment) unchanged.
    #[inline(never)]
    pub fn blend(&mut self, h: &Histogram<K>, alpha: Real) {
        self.blend_bins(h, alpha);
        self.refresh_roots();
    }

    /// [`Model::blend`] short of the roots the similarity sums read, for a
    /// caller that recomputes them at once ([`Model::reweight`]): 512
    /// square roots a model update saved.
    pub(crate) fn blend_bins(&mut self, h: &Histogram<K>, alpha: Real) {
        if h.total == 0 || !(alpha > 0.0) {
            return;
        }
        let a = (alpha.min(1.0) * Q_ONE as Real) as u64;
        let len = self.segment_len();
        for (q, c) in self.q.chunks_mut(len).zip(h.counts.chunks(len)) {
            let total = segment_total(h, c, self.segments);
            if total == 0 {
                continue;
            }
            for (q, &c) in q.iter_mut().zip(c) {
                let p = normalised(c, total) as u64;
                let v = ((Q_ONE - a) * *q as u64 + a * p + (Q_ONE >> 1)) >> 16;
                *q = v.min(u16::MAX as u64) as u16;
            }
        }
    }

    /// Weighs the model's bins by the odds `w` (`P(target | colour)` in
    /// `0..=LEVELS` of [`crate::foreground`]) as `b` says (see
    /// [`crate::BackgroundWeight`]): the roots become those of the weighted
    /// bins, renormalised per segment, while `q` itself stays unweighted for
    /// blending.
    pub(crate) fn reweight(&mut self, w: &[u8; K], b: crate::BackgroundWeight) {
        use crate::foreground::LEVELS;
        let levels = LEVELS as Real;
        // `Config::validate` holds both in range; clamped again so that no
        // caller can overflow the table or divide by `levels − above` = 0.
        let s = crate::scalar::clamp(b.strength, 0.0, 1.0);
        let above = crate::scalar::clamp(b.above, 0.0, 0.95) * levels;
        // Sixteenths of `LEVELS · (1 − s) + s · max(0, o − above) · LEVELS /
        // (LEVELS − above)` for each odds level `o`: at most 16 · 15 = 240,
        // so `q · weight` < 2^24 and a segment's sum (its q add up to about
        // 2^16) fits easily in a u64.
        let mut table = [0u32; LEVELS as usize + 1];
        for (o, t) in table.iter_mut().enumerate() {
            let gain = crate::scalar::max(o as Real - above, 0.0) * levels / (levels - above);
            *t = (16.0 * ((1.0 - s) * levels + s * gain) + 0.5) as u32;
        }
        let len = self.segment_len();
        let weight = |i: usize| {
            let o = w.get(i % len).copied().unwrap_or(0) as usize;
            table.get(o).copied().unwrap_or(0) as u64
        };
        for (j, (sq, q)) in self.sqrt_q.chunks_mut(len).zip(self.q.chunks(len)).enumerate() {
            let total: u64 = q.iter().enumerate().map(|(u, &q)| q as u64 * weight(j * len + u)).sum();
            // One division per segment: `v = q · w · 2^16 / total` is
            // `q · w · r / 2^24` with `r = 2^40 / total`, short of the exact
            // quotient by under one unit (`q · w / 2^24 <= total / 2^24 < 1`),
            // and at most 2^40 before the shift.
            let r = (1u64 << 40).checked_div(total);
            for (u, (s, &q)) in sq.iter_mut().zip(q.iter()).enumerate() {
                // A segment whose colours all have no weight keeps its plain roots.
                let v = match r {
                    Some(r) => ((q as u64 * weight(j * len + u) * r) >> 24).min(u16::MAX as u64) as u32,
                    None => q as u32,
                };
                *s = crate::scalar::isqrt(v << 8) as u16;
            }
        }
        self.support = Support::of(&self.sqrt_q);
    }

    fn refresh_roots(&mut self) {
        for (s, &q) in self.sqrt_q.iter_mut().zip(self.q.iter()) {
            *s = root(q);
        }
        self.support = Support::of(&self.sqrt_q);
    }

    /// Bin `u` of the whole target's distribution, in units of `2^-16`:
    /// the mean over the segments of their bin `u` (bin `u` itself for a
    /// model of one segment).
    pub(crate) fn whole_bin(&self, u: usize) -> u32 {
        let len = self.segment_len();
        let sum: u32 = (0..self.segments as usize).filter_map(|s| self.q.get(s * len + u)).map(|&q| q as u32).sum();
        sum / self.segments.max(1) as u32
    }

    /// The normalised bins, in units of `2^-16`.
    pub fn bins(&self) -> &[u16; K] {
        &self.q
    }

    /// The model's non-empty bins, for [`Clear::Support`]; `None` for a
    /// model of several segments, whose comparisons need every bin.
    pub(crate) fn support(&self) -> Option<&Support<W>> {
        (self.segments <= 1).then_some(&self.support)
    }

    /// `sqrt(q(u))` per bin, in units of `2^-12`.
    pub(crate) fn sqrt_bins(&self) -> &[u16; K] {
        &self.sqrt_q
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
        bhattacharyya::<K, W>(&h.counts, &self.sqrt_q, h.total, (&self.support, 0))
    }

    /// The histogram intersection `Σ min(p(u), q(u))`, in `[0, 1]`: 1 for
    /// identical distributions, 0 for disjoint ones and for an empty histogram.
    pub fn intersection(&self, h: &Histogram<K>) -> Real {
        intersection(&h.counts, &self.q, h.total)
    }

    /// How `h` compares with this model under `kind`. For a quadrant model,
    /// the comparisons of the four quadrants.
    #[inline(never)]
    pub(crate) fn compare(&self, h: &Histogram<K>, kind: Similarity) -> [Real; 4] {
        let mut out = [0.0; 4];
        let len = self.segment_len();
        let blocks = h.counts.chunks(len).zip(self.q.chunks(len)).zip(self.sqrt_q.chunks(len));
        for (j, (o, ((c, q), sq))) in out.iter_mut().zip(blocks).enumerate() {
            let total = segment_total(h, c, self.segments);
            *o = compare_block::<K, W>(c, (q, sq), total, kind, (&self.support, j * len));
        }
        out
    }
}

/// The mass of one segment's counts `c` (the histogram's total when there is
/// only one segment, saving a sum per comparison on the default path).
fn segment_total<const K: usize>(h: &Histogram<K>, c: &[u32], segments: u8) -> u32 {
    if !cfg!(feature = "quadrants") || segments <= 1 { h.total } else { c.iter().fold(0u32, |a, &v| a.wrapping_add(v)) }
}

/// One block's similarity. Out of line, so that the per-particle caller
/// holds one copy of each sum rather than one per quadrant (measured: +3 KB
/// of Cortex-M4 code when inlined).
#[inline(never)]
fn compare_block<const K: usize, const W: usize>(
    c: &[u32],
    (q, sq): (&[u16], &[u16]),
    total: u32,
    kind: Similarity,
    support: (&Support<W>, usize),
) -> Real {
    match kind {
        Similarity::Bhattacharyya => bhattacharyya::<K, W>(c, sq, total, support),
        Similarity::Intersection => intersection(c, q, total),
    }
}

/// `Σ sqrt(c(u)/C) sqrt(q(u))` from counts, their total and the model's
/// roots, for the block of bins from `first` (of a `K`-bin model whose
/// non-zero bins are `support`): only the model's non-zero bins are visited.
fn bhattacharyya<const K: usize, const W: usize>(
    counts: &[u32],
    sqrt_q: &[u16],
    total: u32,
    (support, first): (&Support<W>, usize),
) -> Real {
    if total == 0 {
        return 0.0;
    }
    let mut sum = 0u64;
    support.for_each::<K>(first, first + counts.len(), |bin| {
        if let (Some(&c), Some(&s)) = (counts.get(bin - first), sqrt_q.get(bin - first))
            && c != 0
        {
            // sqrt_q4(c) < 2^20 and s <= 2^12: the product fits in u32.
            sum += (sqrt_q4(c) * s as u32) as u64;
        }
    });
    rho_of(sum, total)
}

/// `ρ` from the sum `Σ 16·sqrt(c(u)) · 4096·sqrt(q(u))` and the counts'
/// total `C` (not 0), clamped to `[0, 1]`. Inlined: it ends every
/// particle's Bhattacharyya sum (measured: 14 k instructions a frame on the
/// QVGA audit as a call).
#[inline(always)]
fn rho_of(sum: u64, total: u32) -> Real {
    // Σ 16·sqrt(c) · 4096·sqrt(q) / (16·sqrt(C) · 4096)
    let denom = sqrt_q4(total) as Real * 4096.0;
    // In two 32-bit halves: one instruction each on a Cortex-M4F, where a
    // 64-bit conversion is a library call. The sum is at most about
    // 2^16·sqrt(C) (Cauchy–Schwarz, Σ q = 1), so the high half is 0 short
    // of huge totals, and the value is then the same.
    let sum = (sum >> 32) as u32 as Real * 4_294_967_296.0 + sum as u32 as Real;
    if denom > 0.0 { crate::scalar::clamp(sum / denom, 0.0, 1.0) } else { 0.0 }
}

/// `Σ min(c(u)/C, q(u))`, exactly in integers: `Σ min(c·2^16, q·C) / (C·2^16)`.
fn intersection(counts: &[u32], q: &[u16], total: u32) -> Real {
    if total == 0 {
        return 0.0;
    }
    let mut sum = 0u64;
    for (&c, &q) in counts.iter().zip(q.iter()) {
        // Each term is below 2^48; K of them stay far below 2^64.
        sum += (c as u64 * Q_ONE).min(q as u64 * total as u64);
    }
    crate::scalar::clamp(sum as Real / (total as Real * Q_ONE as Real), 0.0, 1.0)
}

/// `c / total` in units of `2^-16`, saturated to `u16`.
fn normalised(c: u32, total: u32) -> u16 {
    if total == 0 {
        return 0;
    }
    // Most bins are empty or small: below 2^15, `c·2^16 + total/2` fits in
    // 32 bits, and a 32-bit division is one instruction on a Cortex-M4
    // where the 64-bit one is a library call. The same value either way.
    if c < 1 << 15 {
        let v = ((c << 16) + (total >> 1)) / total;
        return v.min(u16::MAX as u32) as u16;
    }
    let v = (c as u64 * Q_ONE + (total as u64 >> 1)) / total as u64;
    v.min(u16::MAX as u64) as u16
}

/// `sqrt(q)` of a normalised bin, in units of `2^-12`:
/// `sqrt(q · 2^16 · 2^8) = sqrt(q_real) · 2^12`.
fn root(q: u16) -> u16 {
    crate::scalar::isqrt((q as u32) << 8) as u16
}

/// A model's normalised bins alone, for a model compared once a frame
/// rather than once a particle (the tracker's first-frame anchor): the
/// roots the Bhattacharyya sum needs are taken as the sum goes, which
/// spares storing them and the support (`2·K + 64` bytes of RAM, 1 KB for
/// 512 bins). [`PlainModel::compare`] gives what [`Model::compare`] gives for the
/// model the bins were copied from, bit for bit.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct PlainModel<const K: usize> {
    q: [u16; K],
    segments: u8,
}

impl<const K: usize> PlainModel<K> {
    /// All-zero bins (match nothing), to be filled by [`PlainModel::copy_from`].
    pub(crate) const fn zero() -> Self {
        PlainModel { q: [0; K], segments: 1 }
    }

    /// Makes these the bins of `model`, in place (a new value would pass
    /// `2·K` bytes through the stack).
    pub(crate) fn copy_from<const W: usize>(&mut self, model: &Model<K, W>) {
        self.q.copy_from_slice(&model.q);
        self.segments = model.segments;
    }

    /// How `h` compares with these bins under `kind`, per segment (see
    /// [`Model::compare`]).
    pub(crate) fn compare(&self, h: &Histogram<K>, kind: Similarity) -> [Real; 4] {
        let mut out = [0.0; 4];
        let len = Model::<K>::len_of(self.segments);
        for (o, (c, q)) in out.iter_mut().zip(h.counts.chunks(len).zip(self.q.chunks(len))) {
            let total = segment_total(h, c, self.segments);
            *o = match kind {
                Similarity::Intersection => intersection(c, q, total),
                Similarity::Bhattacharyya if total == 0 => 0.0,
                Similarity::Bhattacharyya => {
                    // The bins both have, as `bhattacharyya` visits through
                    // the support (a bin's root is 0 only where it is).
                    let mut sum = 0u64;
                    for (&c, &q) in c.iter().zip(q.iter()) {
                        if c != 0 && q != 0 {
                            sum += (sqrt_q4(c) * root(q) as u32) as u64;
                        }
                    }
                    rho_of(sum, total)
                }
            };
        }
        out
    }
}

/// The Bhattacharyya distance `d = sqrt(1 − ρ)`.
pub fn bhattacharyya_distance(rho: Real) -> Real {
    crate::scalar::sqrt((1.0 - rho).max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pixel::{Gray8, PixelFormat, Rgb565, Rgb888};
    use crate::region::for_each_in_ellipse;

    #[test]
    fn normalising_in_32_bits_gives_the_64_bit_value() {
        // Reason: cross-check of two implementations. The 32-bit fast path
        // must give exactly the rounded 64-bit quotient, saturated, for
        // every count below 2^15 (both sides of the switch included) and
        // totals from 1 to the largest u32.
        let wide = |c: u32, t: u32| ((c as u64 * Q_ONE + (t as u64 >> 1)) / t as u64).min(u16::MAX as u64) as u16;
        let mut next = crate::testing::lcg(11);
        let mut totals = vec![1, 2, 3, 255, 256, 40_000, 65_535, 65_536, 1 << 20, u32::MAX - 1, u32::MAX];
        totals.extend((0..2000).map(|_| next() | 1));
        let mut counts = vec![0, 1, 2, 100, 4095, (1 << 15) - 1, 1 << 15, (1 << 15) + 1, 70_000];
        counts.extend((0..50).map(|_| next() >> 17));
        for &t in &totals {
            for &c in &counts {
                assert_eq!(normalised(c, t), wide(c, t), "c {c} total {t}");
            }
        }
    }

    #[test]
    fn histogram_mass_is_the_kernel_mass() {
        // Reason: every sampled pixel lands in exactly one bin, so the bins sum
        // to the total, which is the kernel mass the region walk visits, under
        // every sampling and in every binning.
        let mut buf = vec![0u8; 64 * 64 * 3];
        for (i, p) in buf.iter_mut().enumerate() {
            *p = (i * 37 % 251) as u8;
        }
        let f = Frame::packed(&buf, 64, 64, PixelFormat::Rgb888).unwrap();
        let e = Ellipse { cx: 30.0, cy: 33.0, hx: 12.0, hy: 9.0 };
        for sampling in [Sampling::Full, Sampling::Checkerboard, Sampling::Quarter] {
            for binning in [Binning::Rgb8x8x8, Binning::Hsv8x8x4] {
                let mut h = Histogram::<512>::new();
                h.compute(&f, &e, binning, sampling);
                let sum: u64 = h.counts().iter().map(|&c| c as u64).sum();
                assert_eq!(sum, h.total() as u64);
                let mut mass = 0u64;
                for_each_in_ellipse(&f, &e, Lattice::new(sampling, 0, e.hx, e.hy), |_, _, _, w| mass += w as u64);
                assert_eq!(sum, mass);
                assert!(h.counts()[binning.bins()..].iter().all(|&c| c == 0), "bins past {binning:?}'s range");
                // A model made from it sums to 1 within the rounding of 512 bins.
                let m = Model::from_histogram(&h).unwrap();
                let qsum: i64 = m.bins().iter().map(|&q| q as i64).sum();
                assert!((qsum - 65536).abs() <= 256, "{qsum}");
            }
        }
    }

    /// The frame size of [`noise_scenes`].
    const NOISE: (usize, usize) = (90, 70);

    /// Random RGB565 and GRAY8 pixels of a frame of [`NOISE`] size, and a
    /// source of ellipses inside it, across its border, off it, tiny and
    /// large: the cases the region walks' cross-checks compare.
    fn noise_scenes(seed: u32) -> (Vec<u8>, Vec<u8>, impl FnMut() -> Ellipse) {
        let (w, h) = NOISE;
        let mut state = crate::testing::lcg(seed);
        let mut next = move || state() >> 8;
        let rgb: Vec<u8> = (0..w * h * 2).map(|_| next() as u8).collect();
        let grey: Vec<u8> = (0..w * h).map(|_| next() as u8).collect();
        let ellipse = move || Ellipse {
            cx: (next() % 1300) as f32 / 10.0 - 20.0,
            cy: (next() % 1100) as f32 / 10.0 - 20.0,
            hx: (next() % 400) as f32 / 10.0 + 0.2,
            hy: (next() % 400) as f32 / 10.0 + 0.2,
        };
        (rgb, grey, ellipse)
    }

    /// The frames of [`noise_scenes`]' pixels.
    fn noise_frames<'a>(rgb: &'a [u8], grey: &'a [u8]) -> [Frame<'a>; 2] {
        let (w, h) = NOISE;
        [Frame::packed(rgb, w, h, PixelFormat::Rgb565).unwrap(), Frame::packed(grey, w, h, PixelFormat::Gray8).unwrap()]
    }

    #[test]
    fn the_per_format_row_bins_equal_the_general_ones() {
        // Reason: a cross-check of two implementations of a row's bins
        // under the default layout: each format's own loop over packed
        // pixels and the general accessor's (what RGB888 takes on bare
        // metal), on random RGB565, RGB888 and GRAY8 frames, for runs from
        // several columns and steps, including runs past the row's end.
        let (rgb, grey, _) = noise_scenes(21);
        let (w, h) = NOISE;
        let rgb888 = crate::testing::noise_bytes(22, w * h * 3);
        let frames = [
            Frame::packed(&rgb, w, h, PixelFormat::Rgb565).unwrap(),
            Frame::packed(&rgb888, w, h, PixelFormat::Rgb888).unwrap(),
            Frame::packed(&grey, w, h, PixelFormat::Gray8).unwrap(),
        ];
        let layout = Layout::whole(Binning::Rgb8x8x8);
        for f in &frames {
            for y in [0, 7, h - 1] {
                let row = f.row(y).unwrap();
                for (x0, step, n) in [(0, 1, w), (3, 2, 40), (1, 3, 50), (w - 5, 1, 20)] {
                    let (mut own, mut any) = (Vec::new(), Vec::new());
                    let at = (x0, step, n);
                    match f.format() {
                        PixelFormat::Rgb565 => packed_bins::<Rgb565, _>(row, at, |i, b| own.push((i, b))),
                        PixelFormat::Rgb888 => packed_bins::<Rgb888, _>(row, at, |i, b| own.push((i, b))),
                        _ => packed_bins::<Gray8, _>(row, at, |i, b| own.push((i, b))),
                    }
                    general_bins(f, &layout, y, at, |i, b| any.push((i, b)));
                    assert_eq!(own, any, "{:?} row {y} from {x0} by {step}", f.format());
                    assert_eq!(own.len(), n.min((w - x0).div_ceil(step)));
                }
            }
        }
    }

    #[test]
    fn the_per_format_loops_equal_the_shared_one() {
        // Reason: a cross-check of two implementations of one histogram:
        // each pixel format's own walk (checkerboard rows, pair rows, the
        // indexed loop) and the shared loop that reads pixels through the
        // general accessor (what RGB888 takes on bare metal) must give
        // identical colour and edge counts and totals, on random frames of
        // the four packed formats, on the lattices a target's size selects,
        // with an edge map and without, for ellipses inside, across the
        // border, off the frame, tiny and large.
        let (rgb, grey, mut ellipse) = noise_scenes(13);
        let (w, h) = NOISE;
        let rgb888 = crate::testing::noise_bytes(17, w * h * 3);
        let frames = [
            Frame::packed(&rgb, w, h, PixelFormat::Rgb565).unwrap(),
            Frame::packed(&rgb, w, h, PixelFormat::Yuv422).unwrap(),
            Frame::packed(&grey, w, h, PixelFormat::Gray8).unwrap(),
            Frame::packed(&rgb888, w, h, PixelFormat::Rgb888).unwrap(),
        ];
        let layout = Layout::whole(Binning::Rgb8x8x8);
        let mut filled = 0;
        for f in &frames {
            for (sampling, step) in [(Sampling::Checkerboard, 1), (Sampling::Checkerboard, 2), (Sampling::Full, 3)] {
                let lattice = Lattice::with_step(sampling, step);
                let mut map = EdgeMap::<4096>::new();
                map.compute_on(f, (0, 0, w, h), 8, 60, false, lattice);
                for _ in 0..100 {
                    let e = ellipse();
                    for with_map in [true, false] {
                        let (mut h1, mut h2) = (Histogram::<512>::new(), Histogram::<512>::new());
                        let (mut e1, mut e2) = (EdgeHistogram::new(), EdgeHistogram::new());
                        let (m1, m2) = match with_map {
                            true => (Some((&map, &mut e1)), Some((&map, &mut e2))),
                            false => (None, None),
                        };
                        h1.compute_by::<4096>(f, &e, (&layout, lattice), m1, Clear::All, true);
                        h2.compute_by::<4096>(f, &e, (&layout, lattice), m2, Clear::All, false);
                        assert_eq!((h1.total, h1.counts), (h2.total, h2.counts), "{:?} {lattice:?} {e:?}", f.format());
                        assert_eq!((e1.total, e1.counts), (e2.total, e2.counts), "{:?} {lattice:?} {e:?}", f.format());
                        filled += (h1.total > 0) as u32;
                    }
                }
            }
        }
        assert!(filled > 1000, "only {filled} regions had pixels");
    }

    #[test]
    fn checkerboard_walk_equals_the_general_walk() {
        // Reason: a cross-check of two implementations of the same walk: the
        // checkerboard's own (row geometry written out) and the general one
        // (any lattice) must give identical colour and edge counts and
        // totals, on random RGB565 and GRAY8 scenes, for ellipses inside,
        // across the border, off the frame, tiny and large.
        let (rgb, grey, mut ellipse) = noise_scenes(7);
        let frames = noise_frames(&rgb, &grey);
        let (w, h) = NOISE;
        let lattice = Lattice::CHECKERBOARD;
        let mut checked = 0;
        for f in &frames {
            let mut map = EdgeMap::<4096>::new();
            map.compute_on(f, (0, 0, w, h), 8, 60, false, lattice);
            let rows = map.checker_rows().expect("4-bit cells at full resolution");
            for _ in 0..300 {
                let e = ellipse();
                let (mut c1, mut e1) = ([0u32; 512], [0u32; MAX_EDGE_BINS]);
                let (mut c2, mut e2) = ([0u32; 512], [0u32; MAX_EDGE_BINS]);
                let (t1, t2) = match f.format() {
                    PixelFormat::Rgb565 => (
                        checker_walk::<Rgb565, 512>(f, &e, rows, &mut c1, &mut e1).unwrap(),
                        general_walk::<Rgb565, 512, 4096>(f, &e, lattice, Some(&map), &mut c2, &mut e2),
                    ),
                    _ => (
                        checker_walk::<Gray8, 512>(f, &e, rows, &mut c1, &mut e1).unwrap(),
                        general_walk::<Gray8, 512, 4096>(f, &e, lattice, Some(&map), &mut c2, &mut e2),
                    ),
                };
                assert_eq!((t1, c1, e1), (t2, c2, e2), "{e:?}");
                checked += (t1 > 0) as u32;
            }
        }
        assert!(checked > 300, "only {checked} ellipses had pixels");
    }

    #[test]
    fn pair_rows_equal_the_indexed_rows() {
        // Reason: a cross-check of two implementations of one walk: rows of
        // whole cell bytes (`pair_row`, with a lone sample at either end
        // where its cell shares a byte with one outside the row) and the
        // per-sample indexed loop must give identical colour
        // and edge counts and totals, on random RGB565 and GRAY8 scenes, on
        // the lattices a target's size selects (checker and full, steps 1
        // to 3), for ellipses inside, across the border, off the frame, tiny
        // and large.
        let (rgb, grey, mut ellipse) = noise_scenes(11);
        let frames = noise_frames(&rgb, &grey);
        let (w, h) = NOISE;
        let (mut paired, mut rows) = (0u32, 0u32);
        for f in &frames {
            for (sampling, step) in
                [(Sampling::Checkerboard, 2), (Sampling::Checkerboard, 3), (Sampling::Full, 1), (Sampling::Full, 2)]
            {
                let lattice = Lattice::with_step(sampling, step);
                let mut map = EdgeMap::<4096>::new();
                map.compute_on(f, (0, 0, w, h), 8, 60, false, lattice);
                assert!(map.nibbles(), "4-bit cells");
                for _ in 0..200 {
                    let e = ellipse();
                    let (mut c1, mut e1) = ([0u32; 512], [0u32; MAX_EDGE_BINS]);
                    let (mut c2, mut e2) = ([0u32; 512], [0u32; MAX_EDGE_BINS]);
                    let (mut c3, mut e3) = ([0u32; 512], [0u32; MAX_EDGE_BINS]);
                    let mut t1 = 0u32;
                    let t2 = match f.format() {
                        PixelFormat::Rgb565 => {
                            for_each_row(f, &e, lattice, |span| {
                                let cells = map.row_cells(&span);
                                t1 += indexed_row::<Rgb565, 512>(&span, &cells, &mut c1, &mut e1);
                                rows += 1;
                                paired += pair_row::<Rgb565, 512>(&span, &cells, &mut c3, &mut e3) as u32;
                            });
                            general_walk::<Rgb565, 512, 4096>(f, &e, lattice, Some(&map), &mut c2, &mut e2)
                        }
                        _ => {
                            for_each_row(f, &e, lattice, |span| {
                                let cells = map.row_cells(&span);
                                t1 += indexed_row::<Gray8, 512>(&span, &cells, &mut c1, &mut e1);
                                rows += 1;
                                paired += pair_row::<Gray8, 512>(&span, &cells, &mut c3, &mut e3) as u32;
                            });
                            general_walk::<Gray8, 512, 4096>(f, &e, lattice, Some(&map), &mut c2, &mut e2)
                        }
                    };
                    assert_eq!((t1, c1, e1), (t2, c2, e2), "{lattice:?} {e:?}");
                }
            }
        }
        // Most rows take the pair loop; those at the frame's edge do not.
        assert!(paired * 4 > rows * 3, "{paired} of {rows} rows paired");
    }

    #[test]
    fn checkerboard_histogram_matches_full_on_a_smooth_image() {
        // Reason: on a smooth image neighbouring pixels have nearly the same
        // colour, so half of them estimate the same distribution: the paper
        // measured ρ = 0.9998 for the checkerboard, 0.9993 for a quarter.
        let (w, h) = (120usize, 90usize);
        let mut buf = Vec::with_capacity(w * h * 3);
        for y in 0..h {
            for x in 0..w {
                let fx = x as f32 / w as f32;
                let fy = y as f32 / h as f32;
                buf.extend_from_slice(&[(255.0 * fx) as u8, (255.0 * fy) as u8, (128.0 + 100.0 * (fx - fy)) as u8]);
            }
        }
        let f = Frame::packed(&buf, w, h, PixelFormat::Rgb888).unwrap();
        let e = Ellipse { cx: 60.0, cy: 45.0, hx: 30.0, hy: 25.0 };
        let mut full = Histogram::<512>::new();
        full.compute(&f, &e, Binning::Rgb8x8x8, Sampling::Full);
        let m = Model::from_histogram(&full).unwrap();
        let mut part = Histogram::<512>::new();
        part.compute(&f, &e, Binning::Rgb8x8x8, Sampling::Checkerboard);
        let rho_c = m.bhattacharyya(&part);
        part.compute(&f, &e, Binning::Rgb8x8x8, Sampling::Quarter);
        let rho_q = m.bhattacharyya(&part);
        assert!(rho_c > 0.99, "checkerboard ρ {rho_c}");
        assert!(rho_q > 0.99, "quarter ρ {rho_q}");
    }

    fn reference_rho(p: &Histogram<512>, q: &Histogram<512>) -> f64 {
        let (tp, tq) = (p.total() as f64, q.total() as f64);
        p.counts().iter().zip(q.counts().iter()).map(|(&a, &b)| ((a as f64 / tp) * (b as f64 / tq)).sqrt()).sum()
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
    fn clearing_the_support_only_gives_the_same_similarities() {
        // Reason: a histogram cleared only on the model's support (holding
        // leftovers of earlier regions elsewhere) must compare with that
        // model exactly as a freshly cleared one does, under both similarity
        // kinds: the sums read no other bin. Regions of a random RGB565
        // scene, one after another in the same histogram.
        let (w, h) = (80usize, 60usize);
        let mut state = crate::testing::lcg(99);
        let mut next = move || state() >> 8;
        let px: Vec<u8> = (0..w * h * 2).map(|_| (next() % 7 * 37) as u8).collect();
        let f = Frame::packed(&px, w, h, PixelFormat::Rgb565).unwrap();
        let layout = Layout::whole(Binning::Rgb8x8x8);
        let lattice = Lattice::CHECKERBOARD;
        let mut target = Histogram::<512>::new();
        target.compute_on(&f, &Ellipse { cx: 40.0, cy: 30.0, hx: 9.0, hy: 7.0 }, Binning::Rgb8x8x8, lattice);
        let model = Model::from_histogram(&target).unwrap();
        let support = model.support().expect("one segment");
        let mut reused = Histogram::<512>::new();
        let mut fresh = Histogram::<512>::new();
        for i in 0..40 {
            let e = Ellipse { cx: (next() % 80) as f32, cy: (next() % 60) as f32, hx: 3.0 + i as f32 * 0.3, hy: 6.0 };
            reused.compute_with::<0>(&f, &e, &layout, lattice, None, Clear::Support(support));
            fresh.compute_with::<0>(&f, &e, &layout, lattice, None, Clear::All);
            for kind in [Similarity::Bhattacharyya, Similarity::Intersection] {
                assert_eq!(model.compare(&reused, kind), model.compare(&fresh, kind), "{e:?} {kind:?}");
            }
        }
        // The leftovers are really there: outside the support, the reused
        // histogram differs from the fresh one.
        assert_ne!(reused.counts(), fresh.counts());
    }

    #[test]
    fn plain_model_compares_as_its_model_does() {
        // Reason: cross-check of two implementations. A `PlainModel` takes
        // each root as its sum goes, where a `Model` reads stored roots
        // through its support; both sum the same integer terms, so every
        // comparison must be equal bit for bit, for models of one and four
        // segments, under both similarity kinds, on random sparse
        // histograms (empty ones and ones disjoint from the model included).
        let mut next = crate::testing::lcg(5);
        let mut random = |fill: u32| {
            let mut h = Histogram::<512>::new();
            for bin in 0..512 {
                if next() % 100 < fill {
                    h.add(bin, next() % 5000);
                }
            }
            h
        };
        for segments in [1u8, 4] {
            for round in 0..30 {
                let learnt = random(40);
                let Some(model) = Model::<512>::from_segments(&learnt, segments) else { continue };
                let mut plain = PlainModel::zero();
                plain.copy_from(&model);
                for h in [random(round % 10), random(60), Histogram::new(), learnt.clone()] {
                    for kind in [Similarity::Bhattacharyya, Similarity::Intersection] {
                        assert_eq!(plain.compare(&h, kind), model.compare(&h, kind), "{segments} {kind:?}");
                    }
                }
            }
        }
    }

    /// The Bhattacharyya sum over every bin, with no support bitmap, in
    /// the same fixed point as [`bhattacharyya`].
    fn rho_over_all_bins<const K: usize>(m: &Model<K>, h: &Histogram<K>) -> Real {
        let sum: u64 = h.counts().iter().zip(m.sqrt_bins()).map(|(&c, &s)| (sqrt_q4(c) * s as u32) as u64).sum();
        crate::scalar::clamp(sum as Real / (sqrt_q4(h.total()) as Real * 4096.0), 0.0, 1.0)
    }

    fn support_matches_all_bins<const K: usize>(next: &mut impl FnMut() -> u32) {
        for trial in 0..40 {
            let (mut p, mut q) = (Histogram::<K>::new(), Histogram::<K>::new());
            for _ in 0..(1 + trial * 7) {
                p.add(next() as usize % K, next() % 3000 + 1);
                q.add(next() as usize % K, next() % 3000 + 1);
            }
            // Shared bins too, at both ends of the range (bitmap word edges).
            for bin in [0, 31, 32, K / 2, K - 1] {
                p.add(bin, next() % 100 + 1);
                if next().is_multiple_of(2) {
                    q.add(bin, next() % 100 + 1);
                }
            }
            let m = Model::from_histogram(&q).unwrap();
            assert_eq!(m.bhattacharyya(&p), rho_over_all_bins(&m, &p), "K = {K}, trial {trial}");
        }
    }

    #[test]
    fn support_sum_equals_the_sum_over_all_bins() {
        // Reason: bins where the model is zero add nothing, so visiting only
        // the model's support must give the very same integer sum; checked
        // for one bit per bin (512, 17) and for groups of bins (K > 512).
        let mut seed = 777u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 33) as u32
        };
        support_matches_all_bins::<512>(&mut next);
        support_matches_all_bins::<17>(&mut next);
        support_matches_all_bins::<1030>(&mut next);
        support_matches_all_bins::<2048>(&mut next);
    }

    #[test]
    fn intersection_identical_disjoint_reference_and_below_rho() {
        let mut a = Histogram::<512>::new();
        for (bin, w) in [(3usize, 1000u32), (40, 256), (41, 17), (500, 5000)] {
            a.add(bin, w);
        }
        let m = Model::from_histogram(&a).unwrap();
        // Reason: Σ min(p, p) = Σ p = 1; the model's 2^-16 rounding costs
        // at most a few units.
        let same = m.intersection(&a);
        assert!(same > 0.999 && same <= 1.0, "{same}");
        // Reason: no shared bin, so every minimum is zero.
        let mut b = Histogram::<512>::new();
        b.add(7, 10);
        assert_eq!(m.intersection(&b), 0.0);
        assert_eq!(m.intersection(&Histogram::new()), 0.0);
        // Reason: cross-check with f64 on pseudo-random histograms, and the
        // invariant min(p, q) <= sqrt(p q), so intersection <= ρ.
        let mut seed = 99u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 33) as u32
        };
        for trial in 0..50 {
            let (mut p, mut q) = (Histogram::<512>::new(), Histogram::<512>::new());
            for _ in 0..4 + trial * 10 {
                let bin = next() as usize % 512;
                p.add(bin, next() % 2000 + 1);
                q.add(if next() % 3 == 0 { next() as usize % 512 } else { bin }, next() % 2000 + 1);
            }
            let model = Model::from_histogram(&q).unwrap();
            let got = model.intersection(&p) as f64;
            let (tp, tq) = (p.total() as f64, q.total() as f64);
            let want: f64 =
                p.counts().iter().zip(q.counts().iter()).map(|(&x, &y)| (x as f64 / tp).min(y as f64 / tq)).sum();
            assert!((got - want).abs() < 0.005, "trial {trial}: {got} vs {want}");
            assert!(got <= model.bhattacharyya(&p) as f64 + 0.005, "trial {trial}");
        }
    }

    #[cfg(feature = "quadrants")]
    #[test]
    fn quadrant_blocks_are_normalised_and_compared_apart() {
        // Reason: each quadrant block of a 4-segment model sums to 1 on its
        // own, so a quadrant's similarity does not depend on how much mass
        // the others hold: doubling one block's counts leaves all four
        // comparisons unchanged, and emptying a block's match drops only it.
        let mut h = Histogram::<512>::new();
        for q in 0..4 {
            h.add(q * 128 + 5, 100 * (q as u32 + 1));
            h.add(q * 128 + 9, 50);
        }
        let m = Model::<512>::from_segments(&h, 4).unwrap();
        for q in 0..4 {
            let sum: u32 = m.bins()[q * 128..(q + 1) * 128].iter().map(|&v| v as u32).sum();
            assert!((65530..=65536).contains(&sum), "block {q}: {sum}");
        }
        let base = m.compare(&h, Similarity::Bhattacharyya);
        assert!(base.iter().all(|&r| r > 0.995), "{base:?}");
        let mut heavier = h.clone();
        heavier.add(5, 100);
        heavier.add(9, 50);
        assert_eq!(m.compare(&heavier, Similarity::Bhattacharyya)[1..], base[1..]);
        let mut moved = Histogram::<512>::new();
        for q in 0..4 {
            let bin = if q == 2 { q * 128 + 77 } else { q * 128 + 5 };
            moved.add(bin, 100);
        }
        let r = m.compare(&moved, Similarity::Bhattacharyya);
        assert_eq!(r[2], 0.0);
        assert!(r[0] > 0.5 && r[1] > 0.5 && r[3] > 0.5, "{r:?}");
        // An empty block has no model.
        let mut gap = Histogram::<512>::new();
        gap.add(5, 1);
        assert!(Model::<512>::from_segments(&gap, 4).is_none());
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
    fn reweighting_scales_each_bin_by_its_odds_as_configured() {
        // Reason, by hand: half the model in bin 1, which the surroundings
        // lack (odds 15 of 15), half in bin 2, which only they have (odds
        // 0). At strength s a bin counts 1 − s + s · odds / 15 times, so the
        // weighted model is (1, 1 − s) renormalised: at s = 0.5, 2/3 and
        // 1/3, whose roots in units of 2^-12 are 3344.0 and 2364.9; at s = 1
        // bin 2 drops out and bin 1 holds everything (root 4096, one unit
        // less where the bin saturates); at s = 0 the plain roots, 2896.3.
        let mut h = Histogram::<512>::new();
        h.add(1, 100);
        h.add(2, 100);
        let mut odds = [8u8; 512];
        (odds[1], odds[2]) = (15, 0);
        let plain = Model::from_histogram(&h).unwrap();
        let near = |got: u16, want: f64| (got as f64 - want).abs() <= 2.0;
        for (s, want1, want2) in [(0.5, 3344.0, 2364.9), (1.0, 4096.0, 0.0), (0.0, 2896.3, 2896.3)] {
            let mut m = plain.clone();
            m.reweight(&odds, crate::BackgroundWeight { strength: s, above: 0.0 });
            assert!(near(m.sqrt_q[1], want1) && near(m.sqrt_q[2], want2), "s = {s}: {} {}", m.sqrt_q[1], m.sqrt_q[2]);
            assert_eq!(m.q, plain.q, "the bins blended later stay unweighted");
        }
        // Blending short of the roots, then reweighting, is what blending
        // and reweighting give: the roots `blend` computes are replaced.
        let mut p = Histogram::<512>::new();
        p.add(2, 50);
        p.add(3, 50);
        let (mut a, mut b) = (plain.clone(), plain.clone());
        a.blend(&p, 0.3);
        let half = crate::BackgroundWeight { strength: 0.5, above: 0.0 };
        a.reweight(&odds, half);
        b.blend_bins(&p, 0.3);
        b.reweight(&odds, half);
        assert_eq!(a, b);
        // Above a threshold: bin 2 at odds 12 of 15. With `above` 0 it
        // counts 0.5 + 0.5 · 12/15 = 0.9 against bin 1's 1, so 1/1.9 and
        // 0.9/1.9 (roots 2971.6 and 2819.1); with `above` 0.8 (12 of 15)
        // it gains nothing, 0.5 against 1: 2/3 and 1/3 again.
        odds[2] = 12;
        for (above, want1, want2) in [(0.0, 2971.6, 2819.1), (0.8, 3344.0, 2364.9)] {
            let mut m = plain.clone();
            m.reweight(&odds, crate::BackgroundWeight { strength: 0.5, above });
            assert!(
                near(m.sqrt_q[1], want1) && near(m.sqrt_q[2], want2),
                "above {above}: {} {}",
                m.sqrt_q[1],
                m.sqrt_q[2]
            );
        }
    }

    #[test]
    fn distance_of_coefficient() {
        assert_eq!(bhattacharyya_distance(1.0), 0.0);
        assert_eq!(bhattacharyya_distance(0.0), 1.0);
        assert!((bhattacharyya_distance(0.75) - 0.5).abs() < 1e-6);
    }
}
