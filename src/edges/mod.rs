//! The edge cue: Sobel gradients on grey levels, quantised orientation, and
//! edge-orientation histograms inside the same kernel-weighted ellipses as
//! colour (the third paper).
//!
//! Gradients are computed once per frame into an [`EdgeMap`], only over the
//! region the particles cover and only at the pixels their histograms
//! sample (the frame's sampling lattice); each particle's histogram then
//! reads its samples' cells one after another. The map lives in a fixed
//! buffer of `E` bytes owned by the tracker, two 4-bit cells per byte. When
//! the region has more sampled pixels than that, the map keeps every 2nd,
//! 4th, … lattice row and column and a sample reads the cell at or before
//! it: bounded memory and cost, but a coarser edge cue.

mod cells;
#[cfg(test)]
mod tests;

use crate::frame::Frame;
use crate::geometry::Ellipse;
use crate::pixel::Loop;
use crate::region::{Lattice, RowSpan, Sampling, div_small, floor};
use crate::scalar::{Real, isqrt, sqrt};

use cells::*;

/// Parameters of the edge-orientation cue.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EdgeCue {
    /// Orientation bins over 0–180°: 2, 4, 8 or 16.
    pub bins: u8,
    /// Gradients with `sqrt(gx² + gy²)` below this are dropped (Sobel on 8-bit
    /// grey levels, so strengths range up to about 1440). The largest
    /// threshold a target gets: see `strong_percent`.
    pub threshold: u16,
    /// The share of the first box's pixels, in percent, that should count as
    /// edges. Where fewer reach `threshold`, that target's threshold is
    /// lowered to the strength this share does reach (never below
    /// [`MIN_EDGE_THRESHOLD`]; [`crate::Tracker::edge_threshold`] says what
    /// was chosen). Magnification and blur spread an edge over more pixels
    /// and weaken each one's gradient; a fixed threshold would then drop
    /// them all and leave the cue blind. 0 keeps `threshold` fixed.
    pub strong_percent: u8,
    /// Count the dropped weak pixels in one more bin, so that the histogram
    /// also measures how much of the region has edges. Without it, a flat
    /// patch with a few stray edges can match a textured target perfectly
    /// (measured on the exit-and-return scene: the filter "saw" its target in
    /// an empty background).
    pub flat_bin: bool,
}

/// The lowest threshold [`EdgeCue::strong_percent`] lowers to: a gradient
/// of 10 is a step of about 2.5 grey levels, above the noise of a flat
/// patch in a JPEG or a sensor's frame.
pub const MIN_EDGE_THRESHOLD: u16 = 10;

/// Capacity of an edge histogram: 16 orientation bins, the most an
/// [`EdgeCue`] may ask for, plus the flat bin.
pub const MAX_EDGE_BINS: usize = 17;

/// The words of the edge model's bitmap of non-empty bins
/// ([`crate::Model`]'s `W`): one bit per bin of its [`MAX_EDGE_BINS`].
pub const EDGE_SUPPORT_WORDS: usize = MAX_EDGE_BINS.div_ceil(32);

/// Directions at `k · 11.25°` for `k = 0..16`, as `(cos, sin) · 4096`: the
/// orientation bin boundaries for 2, 4, 8 or 16 bins over 0–180°.
const DIRECTIONS: [(i32, i32); 16] = [
    (4096, 0),
    (4017, 799),
    (3784, 1567),
    (3406, 2276),
    (2896, 2896),
    (2276, 3406),
    (1567, 3784),
    (799, 4017),
    (0, 4096),
    (-799, 4017),
    (-1567, 3784),
    (-2276, 3406),
    (-2896, 2896),
    (-3406, 2276),
    (-3784, 1567),
    (-4017, 799),
];

/// Map cell value of a pixel that counts in no bin: weak (unless weak
/// pixels have a bin of their own), on the frame border where the 3x3 Sobel
/// window does not fit, or not computed.
pub(crate) const NONE: u8 = u8::MAX;

/// The orientation bin of gradient `(gx, gy)` among `bins` equal sectors of
/// 0–180°, by sector tests with integer cross products (no `atan`).
/// `bins` must be 2, 4, 8 or 16 (another count acts as the power of two
/// below it, and 0 as 1).
#[inline]
pub fn orientation_bin(gx: i32, gy: i32, bins: usize) -> usize {
    orientation_with(gx, gy, sector_shift(bins))
}

/// `log2` of the [`DIRECTIONS`] per sector for `bins` sectors.
fn sector_shift(bins: usize) -> u32 {
    4 - bins.clamp(1, 16).ilog2()
}

/// [`orientation_bin`] with [`sector_shift`] worked out by the caller, once
/// per map. Out of line: only strong cells come here, and each inlined copy
/// cost flash.
#[inline(never)]
fn orientation_with(gx: i32, gy: i32, shift: u32) -> usize {
    // Orientation is modulo 180°: fold into the upper half plane.
    let (gx, gy) = if gy < 0 || (gy == 0 && gx < 0) { (-gx, -gy) } else { (gx, gy) };
    // Bin = the number of boundaries at or clockwise of the gradient; the
    // boundaries are sorted by angle, so binary search: halve a range of
    // directions, from all 16, down to one sector (`1 << shift` of them).
    let (mut lo, mut half) = (0usize, 8usize);
    while half >= 1 << shift {
        // lo + half < 16; the mask spares a bounds test.
        let (c, s) = DIRECTIONS.get((lo + half) & 15).copied().unwrap_or((0, 0));
        // cross(boundary, g) >= 0  <=>  g is at or past the boundary.
        if c * gy - s * gx >= 0 {
            lo += half;
        }
        half >>= 1;
    }
    lo >> shift
}

/// How an [`EdgeMap`] is computed.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EdgeParams {
    /// Orientation bins over 0–180°: 2, 4, 8 or 16.
    pub bins: usize,
    /// Gradient strength below which a pixel is weak.
    pub threshold: u16,
    /// The sampling of the histograms that will read the map: the map has
    /// a cell for each of their pixels, and no other.
    pub sampling: Sampling,
    /// Rows and columns between the histograms' samples (at least the
    /// sampling's own: 1, or 2 for [`Sampling::Quarter`]).
    pub step: usize,
    /// Whether weak pixels count in a bin of their own (bin `bins`), so the
    /// histogram also says how much of the region has edges at all.
    pub flat_bin: bool,
}

/// The value of a 4-bit cell with no bin (see [`EdgeMap`]).
pub(crate) const NIBBLE_NONE: u8 = 15;

/// A per-frame map of quantised edge orientations over a region of the
/// frame, in a fixed buffer of `E` bytes: one cell per pixel of the
/// sampling lattice (see [`EdgeParams`]), so that a histogram reads its
/// samples' cells one after another. Cells take 4 bits (two per byte, so
/// `2·E` of them) when every value fits, that is with at most 8
/// orientation bins; 16 bins take a byte per cell.
#[derive(Clone, Debug)]
pub struct EdgeMap<const E: usize> {
    bytes: [u8; E],
    lattice: Lattice,
    /// First lattice row and column (`y = j·step`; `x = phase(y) + k·x_step`).
    j0: usize,
    k0: usize,
    cols: usize,
    rows: usize,
    /// One cell per `2^shift` lattice rows and columns.
    shift: u32,
    /// Two 4-bit cells per byte, low nibble first ([`NIBBLE_NONE`] for no
    /// bin); else one byte per cell ([`NONE`] for no bin).
    nibbles: bool,
    /// Bytes per map row (rows start on a byte).
    stride: usize,
}

impl<const E: usize> Default for EdgeMap<E> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const E: usize> EdgeMap<E> {
    /// An empty map (every lookup is weak).
    pub const fn new() -> Self {
        EdgeMap {
            bytes: [NONE; E],
            lattice: Lattice::FULL,
            j0: 0,
            k0: 0,
            cols: 0,
            rows: 0,
            shift: 0,
            nibbles: false,
            stride: 0,
        }
    }

    /// Lattice points per cell side: 1 when every sampled pixel has its own
    /// cell, 2, 4, … when the region did not fit.
    pub fn spacing(&self) -> usize {
        1 << self.shift
    }

    /// Computes orientations at the sampled pixels (see [`EdgeParams`]) of
    /// the pixel rectangle `[x0, x1) × [y0, y1)` (clipped to the frame),
    /// dropping gradients with `sqrt(gx² + gy²) < threshold`. If the region
    /// has more sampled pixels than the map has cells, the map keeps every
    /// 2nd (4th, …) lattice row and column, and a pixel reads the cell at or
    /// before it.
    pub fn compute(&mut self, frame: &Frame<'_>, rect: (usize, usize, usize, usize), params: EdgeParams) {
        let lattice = Lattice::with_step(params.sampling, params.step);
        self.compute_on(frame, rect, params.bins, params.threshold, params.flat_bin, lattice);
    }

    /// [`EdgeMap::compute`] on an explicit lattice.
    pub(crate) fn compute_on(
        &mut self,
        frame: &Frame<'_>,
        rect: (usize, usize, usize, usize),
        bins: usize,
        threshold: u16,
        flat_bin: bool,
        lattice: Lattice,
    ) {
        let bins = bins.min(16);
        let weak = if flat_bin { bins as u8 } else { NONE };
        let nibbles = bins + (flat_bin as usize) < NIBBLE_NONE as usize;
        let (x0, y0, x1, y1) = rect;
        let (w, h) = (frame.width(), frame.height());
        let (x0, y0) = (x0.min(w), y0.min(h));
        let (x1, y1) = (x1.max(x0).min(w), y1.max(y0).min(h));
        let (s, xs) = (lattice.step(), lattice.x_step());
        // Lattice rows j with y0 <= j·s < y1; columns k of any row's phase
        // (0 or s) with x0 <= phase + k·xs < x1, a superset for the other phase.
        let j0 = y0.div_ceil(s);
        let rows_l = y1.div_ceil(s).saturating_sub(j0);
        let k0 = x0.saturating_sub(lattice.phase(s)) / xs;
        let cols_l = x1.div_ceil(xs).saturating_sub(k0);
        let size = |shift: u32| {
            let cols = cols_l.div_ceil(1 << shift);
            let stride = if nibbles { cols.div_ceil(2) } else { cols };
            (cols, stride, rows_l.div_ceil(1 << shift))
        };
        let mut shift = 0;
        while shift < 16 && {
            let (_, stride, rows) = size(shift);
            stride.saturating_mul(rows) > E
        } {
            shift += 1;
        }
        let (cols, stride, rows) = size(shift);
        let (cols, stride) = if stride > E { (0, 0) } else { (cols, stride) };
        let rows = E.checked_div(stride).map_or(0, |fit| rows.min(fit));
        // Field by field: rebuilding the struct would copy the buffer
        // through the stack.
        (self.lattice, self.j0, self.k0, self.cols, self.rows, self.shift) = (lattice, j0, k0, cols, rows, shift);
        (self.nibbles, self.stride) = (nibbles, stride);
        self.fill(frame, bins, threshold, weak);
    }

    /// Fills the map's cells, column tile by column tile. The lumas of the
    /// three rows a Sobel window needs are read into a ring of rows, one
    /// format dispatch per ring row (then that format's own loop), and the
    /// cells are classified from the ring by loops shared by every format:
    /// a classifying loop per format would repeat the same code in flash
    /// once per format. Cells at most two pixels apart read whole spans of
    /// their rows, and rows one pixel apart (a lattice of step 1 at full
    /// resolution) share their lumas with the next map row: each pixel's
    /// luma is computed once, rather than six lumas read for every cell,
    /// which costs more instructions per cell. Sparser cells read only the
    /// three columns of each cell's window.
    fn fill(&mut self, frame: &Frame<'_>, bins: usize, threshold: u16, weak: u8) {
        /// Lumas per ring row.
        const SPAN: usize = 192;
        let (w, h) = (frame.width(), frame.height());
        let (s, xs) = (self.lattice.step(), self.lattice.x_step());
        let (cols, stride, nibbles, k0, j0, shift) =
            (self.cols, self.stride, self.nibbles, self.k0, self.j0, self.shift);
        // At least 1 (the shift is below 16), said so that the division
        // below needs no check.
        let dx = (xs << shift).max(1);
        let sparse = dx > 2;
        let t2 = threshold as i32 * threshold as i32;
        // Dense cells c0..c1 of a tile need pixels from x(c0) - 1 to
        // x(c1 - 1) + 1, where x(c) = phase + k0·xs + c·dx with phase 0 or
        // 1 (dense lattices have a step of 1, or no checkerboard), and
        // `ring_cells` reads five-column windows from the first of each
        // pair of cells. Sparse cells take three ring columns each. Either
        // way an even number per tile, so that pairs (and cell bytes) never
        // straddle two tiles.
        let per_tile = if sparse { SPAN / 3 } else { ((SPAN - 6) / dx + 1) & !1 };
        let mut ring = [[0u8; SPAN]; 3];
        let mut c0 = 0;
        while c0 < cols {
            let c1 = (c0 + per_tile).min(cols);
            // Dense: ring column i holds pixel xa + i.
            let xa = (k0 * xs + c0 * dx).saturating_sub(1);
            let xb = (k0 * xs + (c1 - 1) * dx + 3).min(w);
            // Which pixel row (and, sparse, which first cell's column) each
            // ring row holds (none yet).
            let mut held = [(usize::MAX, 0); 3];
            for j in 0..self.rows {
                let y = (j0 + (j << shift)) * s;
                let Some(out) = self.bytes.get_mut(j * stride..(j + 1) * stride) else { break };
                let x_first = self.lattice.phase(y) + k0 * xs + c0 * dx;
                let border = y == 0 || y + 1 >= h;
                if !border {
                    // Rows y-1, y, y+1 live in ring rows (y-1)%3, y%3, (y+1)%3.
                    let key = if sparse { x_first } else { 0 };
                    for r in [y - 1, y, y + 1] {
                        if let Some(slot) = held.get_mut(r % 3)
                            && *slot != (r, key)
                            && let Some(dst) = ring.get_mut(r % 3)
                        {
                            let row = frame.row(r).unwrap_or(&[]);
                            if sparse {
                                luma_windows(
                                    frame,
                                    row,
                                    (x_first, dx),
                                    dst.get_mut(..3 * (c1 - c0)).unwrap_or_default(),
                                );
                            } else {
                                luma_span(frame, row, (xa, xb), dst);
                            }
                            *slot = (r, key);
                        }
                    }
                }
                let row_of = |i: usize| ring.get(i).map_or(&[][..], |r| &r[..]);
                let window = (row_of((y + 2) % 3), row_of(y % 3), row_of((y + 1) % 3));
                let sobel_cfg = SobelCells { w, border, bins, t2, weak, nibbles };
                // Compiled per spacing (the window's columns are then
                // fixed), except in the lean builds.
                match (sparse, Loop::Fast.compiled(), dx) {
                    (true, ..) => sparse_cells(out, window, (x_first, dx), (c0, c1), &sobel_cfg),
                    (_, false, _) => ring_cells::<0>(out, (window, dx), xa, x_first, (c0, c1), &sobel_cfg),
                    (_, _, 1) => ring_cells::<1>(out, (window, dx), xa, x_first, (c0, c1), &sobel_cfg),
                    _ => ring_cells::<2>(out, (window, dx), xa, x_first, (c0, c1), &sobel_cfg),
                }
            }
            c0 = c1;
        }
    }

    /// The bytes of the map row of the `j`-th lattice row, or none.
    #[inline(always)]
    fn lattice_row(&self, j: usize) -> &[u8] {
        let r = j.wrapping_sub(self.j0) >> self.shift;
        if r < self.rows { self.bytes.get(r * self.stride..(r + 1) * self.stride).unwrap_or(&[]) } else { &[] }
    }

    /// The bin of the map cell of pixel `(x, y)` (the lattice point at or
    /// before it): its orientation, or the flat bin (`bins`) for a weak
    /// gradient when there is one; `None` for a weak gradient without a flat
    /// bin, the frame border, or a pixel outside the mapped region.
    pub fn bin_at(&self, x: usize, y: usize) -> Option<usize> {
        let l = &self.lattice;
        let j = y / l.step();
        let k = x.checked_sub(l.phase(j * l.step()))? / l.x_step();
        let c = k.checked_sub(self.k0)? >> self.shift;
        if c >= self.cols {
            return None;
        }
        match cell(self.lattice_row(j), c, self.nibbles) {
            NONE => None,
            NIBBLE_NONE if self.nibbles => None,
            v => Some(v as usize),
        }
    }

    /// Whether cells take 4 bits.
    pub(crate) fn nibbles(&self) -> bool {
        self.nibbles
    }

    /// The map as rows of 4-bit cells at full resolution of the default
    /// checkerboard (cell `k - k0` of row `y - j0` is pixel
    /// `(2k + (y & 1), y)`), if it is that: `(bytes, j0, k0, cols, rows, stride)`.
    #[allow(clippy::type_complexity)]
    pub(crate) fn checker_rows(&self) -> Option<(&[u8], usize, usize, usize, usize, usize)> {
        (self.nibbles && self.shift == 0 && self.lattice == Lattice::CHECKERBOARD).then_some((
            &self.bytes[..],
            self.j0,
            self.k0,
            self.cols,
            self.rows,
            self.stride,
        ))
    }
}

/// The cells a row of samples reads, from [`EdgeMap::row_cells`].
pub(crate) struct RowCells<'a> {
    /// The map row.
    pub bytes: &'a [u8],
    /// The first sample's lattice column, relative to the map's first.
    pub base: usize,
    /// Lattice columns per cell, as a power of two.
    pub shift: u32,
    /// Whether cells take 4 bits.
    pub nibbles: bool,
}

impl RowCells<'_> {
    /// No map: every sample reads [`NONE`].
    pub(crate) const EMPTY: RowCells<'static> = RowCells { bytes: &[], base: 0, shift: 0, nibbles: false };

    /// The cell of sample `i`, which reads cell `(base + i) >> shift`
    /// (wrapping: cells left of the map are huge indices, past the row):
    /// its bin, or none as [`cell`] says it.
    #[inline(always)]
    pub(crate) fn get(&self, i: usize) -> u8 {
        cell(self.bytes, self.base.wrapping_add(i) >> self.shift, self.nibbles)
    }
}

impl<const E: usize> EdgeMap<E> {
    /// The cells the samples of `span` read, in order. `span` must be a row
    /// of a region walk on the map's lattice.
    #[inline(always)]
    pub(crate) fn row_cells(&self, span: &RowSpan<'_>) -> RowCells<'_> {
        let l = &self.lattice;
        let bytes = self.lattice_row(div_small(span.y as u32, l.step() as u32) as usize);
        let k = div_small(span.x.wrapping_sub(l.phase(span.y)) as u32, l.x_step() as u32) as usize;
        RowCells { bytes, base: k.wrapping_sub(self.k0), shift: self.shift, nibbles: self.nibbles }
    }
}

/// The edge threshold for the target in ellipse `e` of `frame` (see
/// [`crate::EdgeCue::strong_percent`]): `threshold` if at least `percent`%
/// of the ellipse's samples reach it, else the strength that `percent`%
/// of them do reach, to a resolution of `threshold / 64` and never below
/// [`MIN_EDGE_THRESHOLD`]. Samples are the ellipse's pixels on a square
/// lattice spaced so that its bounding box holds at most about 1024,
/// where the 3x3 window fits in the frame; with none, or `percent` 0,
/// `threshold`.
// Once per target, so out of line and small rather than fast: with the
// pixel reads inlined it would take much more code for no gain per frame.
#[inline(never)]
pub(crate) fn soft_threshold(frame: &Frame<'_>, e: &Ellipse, threshold: u16, percent: u8) -> u16 {
    const SAMPLES: usize = 1024;
    const BINS: usize = 64;
    if percent == 0 || threshold <= MIN_EDGE_THRESHOLD {
        return threshold;
    }
    // Counts of strengths in [b·width, (b+1)·width) below the threshold, and
    // of those at or above it.
    let width = (threshold as u32).div_ceil(BINS as u32).max(1);
    let (mut counts, mut strong, mut n) = ([0u16; BINS], 0u32, 0u32);
    let area = 4.0 * e.hx * e.hy;
    // At least 1: `step_by` would panic on 0.
    let step =
        if area > SAMPLES as Real { (sqrt(area / SAMPLES as Real) as usize).saturating_add(1) } else { 1 }.max(1);
    // The ellipse's pixels on a square lattice, where the 3x3 window fits.
    let (w, h) = (frame.width() as i32, frame.height() as i32);
    let (x0, x1) = (floor(e.cx - e.hx).max(1), floor(e.cx + e.hx).min(w - 2));
    let (y0, y1) = (floor(e.cy - e.hy).max(1), floor(e.cy + e.hy).min(h - 2));
    let (ax, ay) = (1.0 / (e.hx * e.hx), 1.0 / (e.hy * e.hy));
    for y in (y0..=y1).step_by(step) {
        for x in (x0..=x1).step_by(step) {
            let (dx, dy) = (x as Real - e.cx, y as Real - e.cy);
            if !(dx * dx * ax + dy * dy * ay <= 1.0) {
                continue;
            }
            let mut p = [0i32; 9];
            for (i, v) in (0i32..).zip(p.iter_mut()) {
                *v = luma_at(frame, x + i % 3 - 1, y + i / 3 - 1);
            }
            let (gx, gy) = sobel(p);
            // At most 1443 for 8-bit levels: the square fits in u32.
            let m = isqrt((gx * gx + gy * gy).unsigned_abs());
            n += 1;
            if m >= threshold as u32 {
                strong += 1;
            } else if let Some(c) = counts.get_mut((m / width) as usize) {
                *c = c.saturating_add(1);
            }
        }
    }
    let wanted = percent as u32 * n;
    if n == 0 || strong * 100 >= wanted {
        return threshold;
    }
    let mut reach = strong;
    for (b, &c) in counts.iter().enumerate().rev() {
        reach += c as u32;
        if reach * 100 >= wanted {
            return ((b as u32 * width) as u16).max(MIN_EDGE_THRESHOLD);
        }
    }
    MIN_EDGE_THRESHOLD
}

/// The luma of pixel `(x, y)` (0 off the frame), out of line: one copy of
/// every format's read rather than nine.
#[inline(never)]
fn luma_at(frame: &Frame<'_>, x: i32, y: i32) -> i32 {
    frame.luma(x as usize, y as usize).unwrap_or(0) as i32
}

/// Sobel gradients of a 3x3 window given row by row (the centre is unused).
/// `gx` is positive where brightness grows to the right, `gy` downwards.
pub fn sobel(p: [i32; 9]) -> (i32, i32) {
    let [a, b, c, d, _, f, g, h, k] = p;
    let gx = (c + 2 * f + k) - (a + 2 * d + g);
    let gy = (g + 2 * h + k) - (a + 2 * b + c);
    (gx, gy)
}
