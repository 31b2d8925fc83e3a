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

use crate::config::MIN_EDGE_THRESHOLD;
use crate::frame::Frame;
use crate::geometry::Ellipse;
use crate::pixel::{self, Loop, Loops, PixelRead, RowReader};
use crate::region::{Lattice, RowSpan, Sampling, div_small, floor};
use crate::scalar::{Real, isqrt, sqrt};

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

/// The lumas of pixels `xa..xb` of `row` (a row of `frame`) into `dst`:
/// one format dispatch per row, then that format's own loop.
fn luma_span(frame: &Frame<'_>, row: &[u8], span: (usize, usize), dst: &mut [u8]) {
    pixel::read(frame.format(), LumaRow { frame, row, at: span, dst, windows: false })
}

/// The lumas of one ring row: [`luma_span`]'s (`windows` false, `at` the
/// span) or [`luma_windows`]' (`at` the first column and the spacing).
struct LumaRow<'f, 'r> {
    frame: &'r Frame<'f>,
    row: &'f [u8],
    at: (usize, usize),
    dst: &'r mut [u8],
    windows: bool,
}

impl RowReader for LumaRow<'_, '_> {
    type Output = ();
    // Every format: the edge map reads every pixel it covers.
    const LOOPS: Loops = Loops {
        rgb565: Loop::Always,
        rgb888: Loop::Always,
        yuv422: Loop::Always,
        gray8: Loop::Always,
        planar_luma: Loop::Always,
    };

    #[inline(always)]
    fn rows_of<P: PixelRead>(self) {
        if self.windows {
            luma_windows_of::<P>(self.row, self.at, self.dst)
        } else {
            luma_span_of::<P>(self.row, self.at, self.dst)
        }
    }

    fn general(self) {
        let l = |x: usize| self.frame.luma_in(self.row, x).unwrap_or(0);
        let (x0, d) = self.at;
        if self.windows {
            for (i, cell) in self.dst.as_chunks_mut::<3>().0.iter_mut().enumerate() {
                let x = x0 + i * d;
                *cell = [x.checked_sub(1).map_or(0, l), l(x), l(x + 1)];
            }
        } else {
            for (i, v) in self.dst.iter_mut().enumerate().take(d.saturating_sub(x0)) {
                *v = l(x0 + i);
            }
        }
    }
}

/// [`luma_span`] in format `P`.
fn luma_span_of<P: PixelRead>(row: &[u8], (xa, xb): (usize, usize), dst: &mut [u8]) {
    match P::pixels(row).and_then(|px| px.get(xa..xb)) {
        // Zipped slices: no bounds test per pixel.
        Some(px) => {
            // Two pixels per iteration: half the loop's overhead.
            let (pairs, last) = px.as_chunks::<2>();
            for (v, &[p, q]) in dst.as_chunks_mut::<2>().0.iter_mut().zip(pairs) {
                *v = [P::px_luma(p), P::px_luma(q)];
            }
            if let (Some(v), Some(&p)) = (dst.get_mut(2 * pairs.len()), last.first()) {
                *v = P::px_luma(p);
            }
        }
        None => {
            for (i, v) in dst.iter_mut().enumerate().take(xb.saturating_sub(xa)) {
                *v = P::luma(row, xa + i).unwrap_or(0);
            }
        }
    }
}

/// The lumas of columns `x − 1`, `x`, `x + 1` for `x` = `x0`, `x0 + dx`,
/// … of `row` (a row of `frame`), three to a cell, into `dst` (0 where a
/// column is outside the row): one format dispatch per row, then that
/// format's own loop.
fn luma_windows(frame: &Frame<'_>, row: &[u8], at: (usize, usize), dst: &mut [u8]) {
    pixel::read(frame.format(), LumaRow { frame, row, at, dst, windows: true })
}

/// [`luma_windows`] in format `P`.
fn luma_windows_of<P: PixelRead>(row: &[u8], (x0, dx): (usize, usize), dst: &mut [u8]) {
    // Column x − 1 of x = 0 reads as 0 (such a cell is at the frame's
    // border and never classified): through a wrapped index past the
    // slice where there is one (cheaper per frame than a branch per cell
    // here), and by asking for no column where the format computes an
    // offset from it. The row's pixels are sliced once,
    // not per read.
    match P::pixels(row) {
        Some(px) => {
            let l = |x: usize| px.get(x).map_or(0, |&p| P::px_luma(p));
            let mut x = x0;
            for cell in dst.as_chunks_mut::<3>().0 {
                // Written out: a loop here is not unrolled at opt-level "s".
                *cell = [l(x.wrapping_sub(1)), l(x), l(x + 1)];
                x += dx;
            }
        }
        None => {
            let l = |x: usize| P::luma(row, x).unwrap_or(0);
            let mut x = x0;
            for cell in dst.as_chunks_mut::<3>().0 {
                *cell = [x.checked_sub(1).map_or(0, l), l(x), l(x + 1)];
                x += dx;
            }
        }
    }
}

/// Cells `c0..c1` of map row `out`, `dx` pixels apart from pixel `x_first`,
/// from ring rows holding three lumas per cell ([`luma_windows`]), one cell
/// at a time.
#[inline(never)]
fn sparse_cells(
    out: &mut [u8],
    (r0, r1, r2): (&[u8], &[u8], &[u8]),
    (x_first, dx): (usize, usize),
    (c0, c1): (usize, usize),
    cfg: &SobelCells,
) {
    let SobelCells { w, border, bins, t2, weak, nibbles } = *cfg;
    let class = Classify { t2, weak, shift: sector_shift(bins) };
    // Zipped windows: no bounds test per cell.
    let windows = r0.as_chunks::<3>().0.iter().zip(r1.as_chunks::<3>().0).zip(r2.as_chunks::<3>().0);
    let mut x = x_first;
    for (c, ((&[a, b, cc], &[d, _, f]), &[g, h, k])) in (c0..c1).zip(windows) {
        let v = if border || x == 0 || x + 1 >= w {
            NONE
        } else {
            let i = |v: u8| v as i32;
            let (gx, gy) = sobel([i(a), i(b), i(cc), i(d), 0, i(f), i(g), i(h), i(k)]);
            class.of(gx, gy)
        };
        put(out, c, v, nibbles);
        x += dx;
    }
}

/// `N` bytes of `row` from `i`, if they are all there.
#[inline(always)]
fn window<const N: usize>(row: &[u8], i: usize) -> Option<&[u8; N]> {
    row.get(i..)?.first_chunk::<N>()
}

/// A cell's value from its Sobel gradient: `weak` below the squared
/// threshold `t2`, else its orientation bin ([`sector_shift`] of the bin
/// count worked out once).
#[derive(Copy, Clone)]
struct Classify {
    t2: i32,
    weak: u8,
    shift: u32,
}

impl Classify {
    #[inline(always)]
    fn of(self, gx: i32, gy: i32) -> u8 {
        if gx * gx + gy * gy < self.t2 { self.weak } else { orientation_with(gx, gy, self.shift) as u8 }
    }
}

/// The ring's three luma rows, top to bottom.
type Ring<'a> = (&'a [u8], &'a [u8], &'a [u8]);

/// What [`ring_cells`] needs besides the ring and the cells' spacing: the
/// frame width `w`, whether the row is on the frame's border, the number of
/// orientation bins, the squared threshold, the value of weak cells, and
/// whether cells are 4-bit.
struct SobelCells {
    w: usize,
    border: bool,
    bins: usize,
    t2: i32,
    weak: u8,
    nibbles: bool,
}

/// Cells `c0..c1` (`c0` even) of map row `out` from a ring of three luma
/// rows holding pixels from column `xa`, cell `c0` at pixel `x_first`.
/// The Sobel sums are taken per column (`S = top + 2·middle + bottom`,
/// `D = bottom − top`, so `gx = S(x+1) − S(x−1)` and
/// `gy = D(x−1) + 2·D(x) + D(x+1)`, the same integers as [`sobel`]); a
/// pair of cells fills one byte of a 4-bit map. Cells one pixel apart go
/// two at a time from one four-column window per ring row (they share two
/// columns); checkerboard cells of a 4-bit map, two pixels apart, go in
/// runs through [`checker_pairs`], which carries each pair's last column
/// to the next. Cells at the frame's border, a last cell alone, and the
/// checkerboard cells of byte maps go one cell at a time. Out of line and
/// shared by every pixel format; compiled per cell spacing `XS` (1 or 2
/// pixels), so that each copy holds only its own loop (fewer instructions
/// per frame on the QVGA audit than with the spacing at run time). `XS` 0
/// takes the spacing `dx` at run time: one copy, where loops that only
/// save time are left out (`Loop::Fast` in `crate::pixel`), because code
/// space counts for more than this loop's speed (audit/budgets.txt).
#[inline(never)]
fn ring_cells<const XS: usize>(
    out: &mut [u8],
    ((r0, r1, r2), dx): (Ring<'_>, usize),
    xa: usize,
    x_first: usize,
    (c0, c1): (usize, usize),
    cfg: &SobelCells,
) {
    let xs = if XS == 0 { dx } else { XS };
    let SobelCells { w, border, bins, t2, weak, nibbles } = *cfg;
    let class = Classify { t2, weak, shift: sector_shift(bins) };
    let classify = |gx: i32, gy: i32| class.of(gx, gy);
    // One cell, with every test (the frame border, the window's pixels).
    let single = |x: usize| {
        if border || x == 0 || x + 1 >= w {
            return NONE;
        }
        let i = x.wrapping_sub(xa + 1);
        match (window::<3>(r0, i), window::<3>(r1, i), window::<3>(r2, i)) {
            (Some(&[a, b, c]), Some(&[d, _, f]), Some(&[g, h, k])) => {
                let (gx, gy) = sobel([a, b, c, d, 0, f, g, h, k].map(i32::from));
                classify(gx, gy)
            }
            _ => NONE,
        }
    };
    let (mut c, mut x) = (c0, x_first);
    while c < c1 {
        // A run of checkerboard pairs inside the frame (x − 1 >= 0 and
        // x + 3 < w for each) goes to the sliding loop.
        if xs == 2 && nibbles && !border && x >= 1 && x + 4 <= w {
            let run = ((c1 - c) / 2).min((w - x) / 4);
            let bytes = out.get_mut(c >> 1..).and_then(|o| o.get_mut(..run)).unwrap_or_default();
            // Weak cells' value clamped to a nibble once (orientation bins
            // are below 16: at most 16 bins).
            let nibble = Classify { weak: weak.min(NIBBLE_NONE), ..class };
            let done = checker_pairs(bytes, (r0, r1, r2), x.wrapping_sub(xa + 1), nibble);
            c += 2 * done;
            x += 4 * done;
            if c >= c1 {
                break;
            }
        }
        let both = c + 1 < c1;
        let i = x.wrapping_sub(xa + 1);
        // Cells one pixel apart share a window (checkerboard cells that
        // come here go one at a time).
        let inner = xs == 1 && !border && x >= 1 && both && x + 2 < w;
        // (An inner pair has x >= 1 and x > xa, so `i` does not wrap.)
        let windows =
            if inner { (window::<4>(r0, i), window::<4>(r1, i), window::<4>(r2, i)) } else { (None, None, None) };
        let (va, vb) = match windows {
            (Some(&[t0, t1, t2_, t3]), Some(&[m0, m1, m2, m3]), Some(&[b0, b1, b2, b3])) => {
                let s = |t: u8, m: u8, b: u8| t as i32 + 2 * m as i32 + b as i32;
                let d = |t: u8, b: u8| b as i32 - t as i32;
                let (d0, d1, d2, d3) = (d(t0, b0), d(t1, b1), d(t2_, b2), d(t3, b3));
                let va = classify(s(t2_, m2, b2) - s(t0, m0, b0), d0 + 2 * d1 + d2);
                let vb = classify(s(t3, m3, b3) - s(t1, m1, b1), d1 + 2 * d2 + d3);
                (va, vb)
            }
            _ => (single(x), if both { single(x + xs) } else { NONE }),
        };
        if nibbles {
            // A cell past the row's last leaves its nibble 0 (never read
            // with a weight).
            if let Some(byte) = out.get_mut(c >> 1) {
                let high = if both { vb.min(NIBBLE_NONE) << 4 } else { 0 };
                *byte = va.min(NIBBLE_NONE) | high;
            }
        } else {
            if let Some(byte) = out.get_mut(c) {
                *byte = va;
            }
            if both && let Some(byte) = out.get_mut(c + 1) {
                *byte = vb;
            }
        }
        c += 2;
        x += 2 * xs;
    }
}

/// Pairs of cells two pixels apart (the checkerboard) into the 4-bit cell
/// bytes `out` (`class` gives nibbles), the first pair's window starting at
/// column `i` of the ring rows: the same sums as [`ring_cells`]' windows,
/// but each column's sums
/// taken once, the last column's carried to the next pair, with no bounds
/// test per pair. Returns the number of pairs done: all of `out`'s, unless
/// the ring ends first.
#[inline(always)]
fn checker_pairs(out: &mut [u8], (r0, r1, r2): (&[u8], &[u8], &[u8]), i: usize, class: Classify) -> usize {
    let (Some(&t), Some(&m), Some(&b)) = (r0.get(i), r1.get(i), r2.get(i)) else { return 0 };
    fn chunks(r: &[u8], from: usize) -> &[[u8; 4]] {
        r.get(from..).unwrap_or_default().as_chunks::<4>().0
    }
    let (tops, mids, bots) = (chunks(r0, i + 1), chunks(r1, i + 1), chunks(r2, i + 1));
    let s = |t: u8, m: u8, b: u8| t as i32 + 2 * m as i32 + b as i32;
    let d = |t: u8, b: u8| b as i32 - t as i32;
    // Column x − 1 of the first pair.
    let (mut s_prev, mut d_prev) = (s(t, m, b), d(t, b));
    let mut done = 0;
    for (((byte, &[t0, t1, t2, t3]), &[_, m1, _, m3]), &[b0, b1, b2, b3]) in
        out.iter_mut().zip(tops).zip(mids).zip(bots)
    {
        // Columns x, x + 1, x + 2, x + 3: cells at x and x + 2.
        let (d0, s1, d1, d2, s3, d3) = (d(t0, b0), s(t1, m1, b1), d(t1, b1), d(t2, b2), s(t3, m3, b3), d(t3, b3));
        let va = class.of(s1 - s_prev, d_prev + 2 * d0 + d1);
        let vb = class.of(s3 - s1, d1 + 2 * d2 + d3);
        *byte = va | (vb << 4);
        (s_prev, d_prev) = (s3, d3);
        done += 1;
    }
    done
}

/// Writes cell `c` of a map row, in order (an even cell of a 4-bit map
/// clears its byte's odd one).
#[inline(always)]
fn put(row: &mut [u8], c: usize, v: u8, nibbles: bool) {
    if nibbles {
        if let Some(byte) = row.get_mut(c >> 1) {
            let v = v.min(NIBBLE_NONE);
            *byte = if c & 1 == 0 { v } else { (*byte & 0x0f) | (v << 4) };
        }
    } else if let Some(byte) = row.get_mut(c) {
        *byte = v;
    }
}

/// Cell `c` of a map row: its bin, or for none (no bin, or past the row)
/// [`NIBBLE_NONE`] in 4-bit maps and [`NONE`] in byte maps.
#[inline(always)]
fn cell(bytes: &[u8], c: usize, nibbles: bool) -> u8 {
    if nibbles {
        // NIBBLE_NONE for no bin, as the pair loop reads it: in 4-bit maps
        // every sample lands in an edge bin (see `histogram::take`).
        bytes.get(c >> 1).map_or(NIBBLE_NONE, |b| (b >> ((c & 1) * 4)) & 0x0f)
    } else {
        bytes.get(c).copied().unwrap_or(NONE)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::histogram::{Clear, Histogram};
    use crate::pixel::PixelFormat;
    use crate::region::for_each_in_ellipse;

    #[test]
    fn a_target_with_weak_gradients_gets_the_strength_its_share_reaches() {
        // Reason: by hand. Grey level 3·x: every pixel's Sobel gx is
        // 4 · (3(x+1) − 3(x−1)) = 24 and gy is 0, so every sample has
        // strength 24. The 64 bins below a threshold of 100 are 2 wide, so
        // 24 is a bin edge and comes back exactly.
        let (w, h) = (64, 48);
        let ramp: Vec<u8> = (0..w * h).map(|i| (3 * (i % w)) as u8).collect();
        let f = Frame::packed(&ramp, w, h, PixelFormat::Gray8).unwrap();
        let e = Ellipse { cx: 32.0, cy: 24.0, hx: 20.0, hy: 15.0 };
        assert_eq!(soft_threshold(&f, &e, 100, 10), 24, "none reach 100: lowered to what all reach");
        assert_eq!(soft_threshold(&f, &e, 20, 10), 20, "all reach 20: kept");
        assert_eq!(soft_threshold(&f, &e, 100, 0), 100, "0% keeps the threshold fixed");
        // A flat patch has no strength at all: the floor.
        let flat = vec![50u8; w * h];
        let f = Frame::packed(&flat, w, h, PixelFormat::Gray8).unwrap();
        assert_eq!(soft_threshold(&f, &e, 100, 10), MIN_EDGE_THRESHOLD);
        // An ellipse off the frame has no samples: unchanged.
        let off = Ellipse { cx: -100.0, cy: -100.0, hx: 5.0, hy: 5.0 };
        assert_eq!(soft_threshold(&f, &off, 100, 10), 100);
    }

    #[test]
    fn the_share_decides_whether_a_sharp_edge_keeps_the_threshold() {
        // Reason: by hand. A vertical step from 0 to 100 at x = 32 gives
        // strength 4 · 100 = 400 in columns 31 and 32 and 0 elsewhere. In a
        // 41-px-wide ellipse on a 1-px lattice (area 41·21 < 1024 samples)
        // those 2 columns are between 2/41 ≈ 5% of a full row and all of a
        // row 1 or 2 px wide, and over the whole ellipse between 5% and 10%
        // (counted below), so 3% keeps 100, and 20% drops to the floor: the
        // rest of the samples have strength 0.
        let (w, h) = (64, 32);
        let step: Vec<u8> = (0..w * h).map(|i| if i % w >= 32 { 100 } else { 0 }).collect();
        let f = Frame::packed(&step, w, h, PixelFormat::Gray8).unwrap();
        let e = Ellipse { cx: 32.0, cy: 16.0, hx: 20.5, hy: 10.5 };
        let (mut n, mut strong) = (0, 0);
        for_each_in_ellipse(&f, &e, Lattice::with_step(Sampling::Full, 1), |_, x, y, _| {
            if y > 0 && y + 1 < h {
                n += 1;
                strong += (x == 31 || x == 32) as u32;
            }
        });
        assert!(20 * strong > n && 10 * strong < n, "{strong} of {n}: the share is between 5% and 10%");
        assert_eq!(soft_threshold(&f, &e, 100, 3), 100);
        assert_eq!(soft_threshold(&f, &e, 100, 20), MIN_EDGE_THRESHOLD);
    }

    #[test]
    fn sobel_on_a_hand_computed_patch() {
        // Reason: by hand, for the patch
        //   10 20 30
        //   10 20 30
        //   10 20 60
        // gx = (30 + 2·30 + 60) − (10 + 2·10 + 10) = 150 − 40 = 110
        // gy = (10 + 2·20 + 60) − (10 + 2·20 + 30) = 110 − 80 = 30
        assert_eq!(sobel([10, 20, 30, 10, 20, 30, 10, 20, 60]), (110, 30));
        // A flat patch has no gradient.
        assert_eq!(sobel([7; 9]), (0, 0));
    }

    #[test]
    fn orientation_bins_of_known_angles() {
        // Reason: with 8 bins of 22.5°, an edge at angle θ belongs to bin
        // floor((θ mod 180) / 22.5); test the middle of every bin, and the
        // opposite direction (θ + 180°), which is the same orientation.
        for bins in [2usize, 4, 8, 16] {
            let width = 180.0 / bins as f64;
            for k in 0..bins {
                let theta = (k as f64 + 0.5) * width;
                let (gx, gy) = ((1000.0 * theta.to_radians().cos()) as i32, (1000.0 * theta.to_radians().sin()) as i32);
                assert_eq!(orientation_bin(gx, gy, bins), k, "{bins} bins, {theta}°");
                assert_eq!(orientation_bin(-gx, -gy, bins), k, "{bins} bins, {theta}° + 180°");
            }
        }
        // Horizontal gradients (vertical edges) are bin 0 either way.
        assert_eq!(orientation_bin(50, 0, 8), 0);
        assert_eq!(orientation_bin(-50, 0, 8), 0);
        // Vertical gradients are the first bin past 90°.
        assert_eq!(orientation_bin(0, 50, 8), 4);
    }

    #[test]
    fn orientation_bins_match_the_angle_of_random_gradients() {
        // Reason: the bin is floor((atan2(gy, gx) mod 180°) / (180° / bins))
        // by definition; checked against f64 atan2 on random Sobel-sized
        // gradients, skipping those within 0.05° of a boundary (the
        // direction table is rounded to 1/4096). Other counts act as the
        // power of two below them, as documented.
        let mut next = crate::testing::lcg(11);
        let mut checked = 0;
        for _ in 0..20_000 {
            let (gx, gy) = ((next() >> 21) as i32 - 1024, (next() >> 21) as i32 - 1024);
            if gx == 0 && gy == 0 {
                continue;
            }
            let angle = (gy as f64).atan2(gx as f64).to_degrees().rem_euclid(180.0);
            for bins in [2usize, 4, 8, 16] {
                let width = 180.0 / bins as f64;
                let off = angle % width;
                if off < 0.05 || width - off < 0.05 {
                    continue;
                }
                assert_eq!(orientation_bin(gx, gy, bins), (angle / width) as usize, "({gx}, {gy}), {bins} bins");
                checked += 1;
            }
            assert_eq!(orientation_bin(gx, gy, 3), orientation_bin(gx, gy, 2));
            assert_eq!(orientation_bin(gx, gy, 12), orientation_bin(gx, gy, 8));
            assert_eq!(orientation_bin(gx, gy, 0), 0);
            assert_eq!(orientation_bin(gx, gy, 1), 0);
        }
        assert!(checked > 70_000, "{checked}");
    }

    fn stripes(w: usize, h: usize, vertical: bool) -> Vec<u8> {
        (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                let u = if vertical { x } else { y };
                if (u / 4) % 2 == 0 { 30 } else { 220 }
            })
            .collect()
    }

    #[test]
    fn synthetic_edges_land_in_their_orientation_bins() {
        // Reason: vertical stripes have horizontal gradients (bin 0);
        // horizontal stripes have vertical gradients (bin 4 of 8).
        for (vertical, want) in [(true, 0usize), (false, 4)] {
            let px = stripes(40, 40, vertical);
            let f = Frame::packed(&px, 40, 40, PixelFormat::Gray8).unwrap();
            let mut map = EdgeMap::<2048>::new();
            map.compute(
                &f,
                (0, 0, 40, 40),
                EdgeParams { bins: 8, threshold: 50, sampling: Sampling::Full, step: 1, flat_bin: false },
            );
            assert_eq!(map.spacing(), 1);
            let mut h = Histogram::<16>::new();
            let l = Lattice::new(Sampling::Full, 0, 10.0, 10.0);
            for_each_in_ellipse(&f, &Ellipse { cx: 20.0, cy: 20.0, hx: 10.0, hy: 10.0 }, l, |_, x, y, w| {
                if let Some(bin) = map.bin_at(x, y) {
                    h.add(bin, w);
                }
            });
            assert!(h.total() > 0);
            assert_eq!(h.counts()[want], h.total(), "vertical={vertical}: {:?}", &h.counts()[..8]);
        }
    }

    /// [`sobel`] of the 3x3 window of grey levels `l` around `(x, y)`, an
    /// inner pixel: the per-pixel definition the maps are checked against.
    fn sobel_at(l: &impl Fn(usize, usize) -> i32, x: usize, y: usize) -> (i32, i32) {
        let (xs, ys) = ([x - 1, x, x + 1], [y - 1, y, y + 1]);
        sobel(core::array::from_fn(|i| l(xs[i % 3], ys[i / 3])))
    }

    #[test]
    fn wide_maps_match_direct_sobel_across_column_tiles() {
        // Reason: cross-check of the row-ring fill against the per-pixel
        // definition on a frame wide enough for several column tiles, on
        // both lattices of step 1, in RGB565 (the two-table luma).
        let (w, h) = (431usize, 23usize);
        let px = crate::testing::noise_bytes(5, w * h * 2);
        let f = Frame::packed(&px, w, h, PixelFormat::Rgb565).unwrap();
        let l = |x: usize, y: usize| crate::frame::luma(f.rgb(x, y).unwrap()) as i32;
        for sampling in [Sampling::Checkerboard, Sampling::Full] {
            let mut map = EdgeMap::<8192>::new();
            let (x0, y0) = (2usize, 1usize);
            map.compute(&f, (x0, y0, w, h), EdgeParams { bins: 8, threshold: 90, sampling, step: 1, flat_bin: true });
            assert_eq!(map.spacing(), 1);
            let lattice = Lattice::with_step(sampling, 1);
            for y in y0..h {
                for x in x0..w {
                    if !lattice.contains(x, y) {
                        continue;
                    }
                    let want = if x == 0 || y == 0 || x + 1 >= w || y + 1 >= h {
                        None
                    } else {
                        let (gx, gy) = sobel_at(&l, x, y);
                        Some(if gx * gx + gy * gy < 90 * 90 { 8 } else { orientation_bin(gx, gy, 8) })
                    };
                    assert_eq!(map.bin_at(x, y), want, "{sampling:?} at ({x}, {y})");
                }
            }
        }
    }

    #[test]
    fn every_pixel_format_reads_the_map_its_lumas_give() {
        // Reason: cross-check of the per-format luma readers (whole spans
        // for dense cells, three columns a cell for sparse ones) against
        // the frame's own per-pixel luma, the definition, in each camera
        // format, on lattices dense (step 1) and sparse (steps 2 and 3,
        // checkerboard and full).
        let (w, h) = (38usize, 29usize);
        for format in [PixelFormat::Rgb565, PixelFormat::Yuv422, PixelFormat::Gray8, PixelFormat::Rgb888] {
            let px = crate::testing::noise_bytes(7, w * h * format.bytes_per_pixel());
            let f = Frame::packed(&px, w, h, format).unwrap();
            let l = |x: usize, y: usize| f.luma(x, y).unwrap() as i32;
            for (sampling, step) in [
                (Sampling::Full, 1),
                (Sampling::Checkerboard, 1),
                (Sampling::Full, 2),
                (Sampling::Full, 3),
                (Sampling::Checkerboard, 3),
            ] {
                let params = EdgeParams { bins: 8, threshold: 60, sampling, step, flat_bin: false };
                let mut map = EdgeMap::<4096>::new();
                map.compute(&f, (1, 1, w, h), params);
                assert_eq!(map.spacing(), 1);
                let lattice = Lattice::with_step(sampling, step);
                let mut n = 0;
                for y in 1..h - 1 {
                    for x in 1..w - 1 {
                        if lattice.contains(x, y) {
                            let (gx, gy) = sobel_at(&l, x, y);
                            let want = (gx * gx + gy * gy >= 60 * 60).then(|| orientation_bin(gx, gy, 8));
                            assert_eq!(map.bin_at(x, y), want, "{format:?} {sampling:?} step {step} at ({x}, {y})");
                            n += 1;
                        }
                    }
                }
                assert!(n > 10, "{format:?} {sampling:?} step {step}: {n} cells checked");
            }
        }
    }

    #[test]
    fn map_matches_direct_sobel_on_every_lattice() {
        // Reason: cross-check the map (sliding window, shared columns,
        // lattice-indexed cells) against the plain per-pixel definition on a
        // random image, at every sampled pixel of several lattices, and
        // against the region walk's own order of cells.
        let (w, h) = (37usize, 29usize);
        let px = crate::testing::noise_bytes(99, w * h * 3);
        let f = Frame::packed(&px, w, h, PixelFormat::Rgb888).unwrap();
        let l = |x: usize, y: usize| crate::frame::luma(f.rgb(x, y).unwrap()) as i32;
        let direct = |x: usize, y: usize, bins: usize| {
            if x == 0 || y == 0 || x + 1 >= w || y + 1 >= h {
                return None;
            }
            let (gx, gy) = sobel_at(&l, x, y);
            (gx * gx + gy * gy >= 120 * 120).then(|| orientation_bin(gx, gy, bins))
        };
        // 8 bins take 4-bit cells, 16 a byte each.
        for (sampling, step, bins) in [Sampling::Full, Sampling::Checkerboard, Sampling::Quarter]
            .into_iter()
            .flat_map(|s| [1usize, 2, 3].map(|step| (s, step)))
            .flat_map(|(s, step)| [8usize, 16].map(|b| (s, step, b)))
        {
            {
                let mut map = EdgeMap::<4096>::new();
                let (x0, y0) = (3usize, 2usize);
                let params = EdgeParams { bins, threshold: 120, sampling, step, flat_bin: false };
                map.compute(&f, (x0, y0, w, h), params);
                assert_eq!(map.spacing(), 1);
                let lattice = Lattice::with_step(sampling, step);
                let mut n = 0;
                for y in y0..h {
                    for x in x0..w {
                        if lattice.contains(x, y) {
                            assert_eq!(map.bin_at(x, y), direct(x, y, bins), "{sampling:?} step {step} at ({x}, {y})");
                            n += 1;
                        }
                    }
                }
                assert!(n > 20, "{n} lattice pixels");
                // A region walk reads the same cells along each row.
                let e = Ellipse { cx: 20.0, cy: 15.0, hx: 12.0, hy: 9.0 };
                let mut via_walk = Histogram::<17>::new();
                let whole = crate::histogram::Layout::whole(crate::colour::Binning::Rgb8x8x8);
                Histogram::<512>::new().compute_with(&f, &e, &whole, lattice, Some((&map, &mut via_walk)), Clear::All);
                let mut via_lookup = Histogram::<17>::new();
                for_each_in_ellipse(&f, &e, lattice, |_, x, y, w| {
                    if let Some(b) = direct(x, y, bins) {
                        via_lookup.add(b, w);
                    }
                });
                assert!(via_lookup.total() > 0);
                assert_eq!(via_walk, via_lookup, "{sampling:?} step {step}");
                // A map too small for the region is coarsened; the walk then
                // reads the cell `bin_at` names for each sample.
                let mut small = EdgeMap::<16>::new();
                small.compute(&f, (x0, y0, w, h), params);
                assert!(small.spacing() > 1);
                let mut via_walk = Histogram::<17>::new();
                Histogram::<512>::new().compute_with(
                    &f,
                    &e,
                    &whole,
                    lattice,
                    Some((&small, &mut via_walk)),
                    Clear::All,
                );
                let mut via_lookup = Histogram::<17>::new();
                for_each_in_ellipse(&f, &e, lattice, |_, x, y, w| {
                    if let Some(b) = small.bin_at(x, y) {
                        via_lookup.add(b, w);
                    }
                });
                assert!(via_lookup.total() > 0);
                assert_eq!(via_walk, via_lookup, "coarse: {sampling:?} step {step}");
            }
        }
    }

    #[test]
    fn weak_gradients_are_dropped_and_the_map_coarsens_to_fit() {
        let flat = vec![100u8; 64 * 64];
        let f = Frame::packed(&flat, 64, 64, PixelFormat::Gray8).unwrap();
        let mut map = EdgeMap::<256>::new();
        // 64x64 = 4096 pixels into 256 cells: spacing 4.
        map.compute(
            &f,
            (0, 0, 64, 64),
            EdgeParams { bins: 8, threshold: 1, sampling: Sampling::Full, step: 1, flat_bin: false },
        );
        assert_eq!(map.spacing(), 4);
        assert_eq!(map.bin_at(30, 30), None, "a flat frame has no edges");
        assert_eq!(map.bin_at(100, 30), None, "outside the frame");
        // Stripes 2 grey levels apart: a gradient of 8, under a threshold of 10.
        let faint: Vec<u8> = (0..64 * 64).map(|i| if (i % 64) / 4 % 2 == 0 { 100 } else { 102 }).collect();
        let f = Frame::packed(&faint, 64, 64, PixelFormat::Gray8).unwrap();
        map.compute(
            &f,
            (0, 0, 64, 64),
            EdgeParams { bins: 8, threshold: 10, sampling: Sampling::Full, step: 1, flat_bin: false },
        );
        assert!((0..64).all(|x| map.bin_at(x, 30).is_none()));
        // Every 3rd row and column: 22x22 lattice points, 242 bytes of 4-bit
        // cells: they fit. With 16 bins, a byte per cell: every 2nd of them.
        map.compute(
            &f,
            (0, 0, 64, 64),
            EdgeParams { bins: 8, threshold: 5, sampling: Sampling::Full, step: 3, flat_bin: false },
        );
        assert_eq!(map.spacing(), 1);
        map.compute(
            &f,
            (0, 0, 64, 64),
            EdgeParams { bins: 16, threshold: 5, sampling: Sampling::Full, step: 3, flat_bin: false },
        );
        assert_eq!(map.spacing(), 2, "the budget of 256 bytes still rules");
        map.compute(
            &f,
            (0, 0, 64, 64),
            EdgeParams { bins: 8, threshold: 5, sampling: Sampling::Full, step: 1, flat_bin: false },
        );
        assert!((0..64).any(|x| map.bin_at(x, 30).is_some()));
        // With a flat bin, the weak pixels are counted there (bin 8 of 8 + 1).
        // The map's cells are 4 px apart; those of x < 4 sit on the border.
        map.compute(
            &f,
            (0, 0, 64, 64),
            EdgeParams { bins: 8, threshold: 10, sampling: Sampling::Full, step: 1, flat_bin: true },
        );
        assert!((4..64).all(|x| map.bin_at(x, 30) == Some(8)));
        assert_eq!(map.bin_at(0, 30), None, "the border has no Sobel window");
    }
}
