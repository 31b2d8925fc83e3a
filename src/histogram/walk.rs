//! The walks over a region's pixels that fill a histogram: a loop per
//! pixel format where it pays, the general one otherwise.

use crate::colour::{Binning, levels_bin};
use crate::edges::MAX_EDGE_BINS;
use crate::edges::{EdgeMap, NIBBLE_NONE, RowCells};
use crate::frame::Frame;
use crate::geometry::Ellipse;
use crate::pixel::{self, Loop, Loops, PixelRead, RowReader};
use crate::region::{Kernel, Lattice, PairKernel, Raster, RowSpan, floor, for_each_row, quadrant, shrink, widen};
use crate::scalar::{KERNEL_ONE, RADIUS2_SHIFT};

use super::{EdgeHistogram, Histogram, Layout};

/// One region's colour and edge walk: [`Histogram::compute_with`]'s
/// arguments, read by a loop per format or the general one.
pub(super) struct RegionWalk<'h, 'f, 'r, const K: usize, const E: usize> {
    pub(super) hist: &'h mut Histogram<K>,
    pub(super) frame: &'r Frame<'f>,
    pub(super) e: &'r Ellipse,
    pub(super) layout: &'r Layout,
    pub(super) lattice: Lattice,
    pub(super) map: Option<&'r EdgeMap<E>>,
    pub(super) edge: &'r mut EdgeHistogram,
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

/// The edge cells of `span`'s samples in `map`, or none.
#[inline(always)]
pub(super) fn row_cells<'m, const E: usize>(map: Option<&'m EdgeMap<E>>, span: &RowSpan<'_>) -> RowCells<'m> {
    map.map_or(RowCells::EMPTY, |m| m.row_cells(span))
}

/// One sample: its colour bin `bin` and edge cell `cell` take weight `w`.
/// Returns the colour mass added. A cell with no bin is `NONE`, past the
/// histogram, or in 4-bit maps [`NIBBLE_NONE`], a bin no orientation uses
/// (4-bit maps have at most 8 orientations and the flat bin), emptied after
/// the walk: no branch per sample, and in a 4-bit map every sample lands in
/// an edge bin.
#[inline(always)]
pub(super) fn take<const K: usize>(
    bin: usize,
    cell: u8,
    w: u32,
    counts: &mut [u32; K],
    edge: &mut [u32; MAX_EDGE_BINS],
) -> u32 {
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
pub(super) fn general_walk<P: PixelRead, const K: usize, const E: usize>(
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
pub(super) fn pair_row<P: PixelRead, const K: usize>(
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
pub(super) fn stride_pairs<P: PixelRead, const K: usize>(
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
pub(super) fn checker_walk<P: PixelRead, const K: usize>(
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
            // Wrapping, as `base` is: a row starting left of the map gives
            // a `base` past `cols`, refused below.
            let (m0, m1) = (base >> 1, base.wrapping_add(n - 1) >> 1);
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
                // into this cold branch, they cost the common rows spills.
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
pub(super) struct RowPlan {
    /// The first exact sample and the number of them.
    pub(super) first: usize,
    pub(super) n: usize,
    /// [`Kernel::start`]'s arguments for the first exact sample.
    pub(super) start: (u32, u32, i32),
    /// The first exact sample's map column.
    pub(super) base: usize,
}

/// How many pairs of rows [`checker_walk`] hands [`fast_rows`] at a time.
pub(super) const ROW_BATCH: usize = 8;

/// Rows `cy − d` and `cy + d` of [`checker_walk`] when their padded
/// samples' pixels and cells are all there.
#[derive(Copy, Clone)]
pub(super) struct RowPair {
    /// Where each row's padded samples' pixels start in the frame's bytes
    /// and their cells in the map's (`usize::MAX` for a row outside the
    /// region).
    pub(super) rows: [(usize, usize); 2],
    /// Number of pairs of samples (four-pixel chunks and cell bytes).
    pub(super) pairs: usize,
    /// The weights from the first padded sample.
    pub(super) kernel: Kernel,
}

/// The rows of a batch from [`checker_walk`]; a row whose pixels or cells
/// are not all in the frame or the map (none is: checked when it was
/// planned) is skipped. Out of line, so that the pair loop has the
/// registers to itself (inlined into the walk, it kept half of its state
/// on the stack).
#[inline(never)]
pub(super) fn fast_rows<P: PixelRead, const K: usize>(
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
pub(super) fn edge_row<P: PixelRead, const K: usize>(
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
/// that they arrive in registers and stay there rather than being
/// reloaded from the stack for every pair.
#[inline(never)]
pub(super) fn pair_loop<P: PixelRead, const K: usize>(
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
pub(super) fn indexed_row<P: PixelRead, const K: usize>(
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
    pixel::read_if(layout.is_fast(), frame.format(), RowBins { frame, layout, row, y, at: (x0, step, n), visit })
}

/// [`row_bins`]' arguments, read by a loop per format or the general one.
pub(super) struct RowBins<'f, 'r, F> {
    pub(super) frame: &'r Frame<'f>,
    pub(super) layout: &'r Layout,
    pub(super) row: &'f [u8],
    pub(super) y: usize,
    pub(super) at: (usize, usize, usize),
    pub(super) visit: F,
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
pub(super) fn packed_bins<P: PixelRead, F: FnMut(usize, usize)>(
    row: &[u8],
    (x0, step, n): (usize, usize, usize),
    mut visit: F,
) {
    let Some(px) = P::pixels(row) else { return };
    for (i, &p) in px.iter().skip(x0).step_by(step).take(n).enumerate() {
        visit(i, P::px_8x8x8(p));
    }
}

pub(super) fn general_bins<F: FnMut(usize, usize)>(
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
    // RGB565 camera frames with the default binning read bins straight
    // from the packed bits: a format dispatch per row, not per pixel.
    let (packed, format, mut visit) = (binning == Binning::Rgb8x8x8, frame.format(), visit);
    for_each_row(frame, e, lattice, |span| {
        pixel::read_if(packed, format, SpanBins { frame, span, binning, visit: &mut visit })
    });
}

/// One row of [`for_each_bin`], read by a loop per format or the general one.
pub(super) struct SpanBins<'f, 'r, F> {
    pub(super) frame: &'r Frame<'f>,
    pub(super) span: RowSpan<'f>,
    pub(super) binning: Binning,
    pub(super) visit: &'r mut F,
}

impl<F: FnMut(usize, usize, usize)> RowReader for SpanBins<'_, '_, F> {
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
        let SpanBins { span, visit, .. } = self;
        let (y, row) = (span.y, span.row);
        for (x, _) in span {
            if let Some(bin) = P::rgb_8x8x8(row, x) {
                visit(x, y, bin);
            }
        }
    }

    #[inline(always)]
    fn general(self) {
        let SpanBins { frame, span, binning, visit } = self;
        let y = span.y;
        for (x, _) in span {
            if let Some(rgb) = frame.rgb(x, y) {
                visit(x, y, binning.bin(rgb));
            }
        }
    }
}
