//! Reading a frame's lumas into the ring of rows the Sobel operator
//! slides over, and classifying each cell of the map from them.

use crate::frame::Frame;
use crate::pixel::{self, Loop, Loops, PixelRead, RowReader};

use super::{NIBBLE_NONE, NONE, orientation_with, sector_shift, sobel};

/// The lumas of pixels `xa..xb` of `row` (a row of `frame`) into `dst`:
/// one format dispatch per row, then that format's own loop.
pub(super) fn luma_span(frame: &Frame<'_>, row: &[u8], span: (usize, usize), dst: &mut [u8]) {
    pixel::read(frame.format(), LumaRow { frame, row, at: span, dst, windows: false })
}

/// The lumas of one ring row: [`luma_span`]'s (`windows` false, `at` the
/// span) or [`luma_windows`]' (`at` the first column and the spacing).
pub(super) struct LumaRow<'f, 'r> {
    pub(super) frame: &'r Frame<'f>,
    pub(super) row: &'f [u8],
    pub(super) at: (usize, usize),
    pub(super) dst: &'r mut [u8],
    pub(super) windows: bool,
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
pub(super) fn luma_span_of<P: PixelRead>(row: &[u8], (xa, xb): (usize, usize), dst: &mut [u8]) {
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
pub(super) fn luma_windows(frame: &Frame<'_>, row: &[u8], at: (usize, usize), dst: &mut [u8]) {
    pixel::read(frame.format(), LumaRow { frame, row, at, dst, windows: true })
}

/// [`luma_windows`] in format `P`.
pub(super) fn luma_windows_of<P: PixelRead>(row: &[u8], (x0, dx): (usize, usize), dst: &mut [u8]) {
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
pub(super) fn sparse_cells(
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
pub(super) fn window<const N: usize>(row: &[u8], i: usize) -> Option<&[u8; N]> {
    row.get(i..)?.first_chunk::<N>()
}

/// A cell's value from its Sobel gradient: `weak` below the squared
/// threshold `t2`, else its orientation bin ([`sector_shift`] of the bin
/// count worked out once).
#[derive(Copy, Clone)]
pub(super) struct Classify {
    pub(super) t2: i32,
    pub(super) weak: u8,
    pub(super) shift: u32,
}

impl Classify {
    #[inline(always)]
    fn of(self, gx: i32, gy: i32) -> u8 {
        if gx * gx + gy * gy < self.t2 { self.weak } else { orientation_with(gx, gy, self.shift) as u8 }
    }
}

/// The ring's three luma rows, top to bottom.
pub(super) type Ring<'a> = (&'a [u8], &'a [u8], &'a [u8]);

/// What [`ring_cells`] needs besides the ring and the cells' spacing: the
/// frame width `w`, whether the row is on the frame's border, the number of
/// orientation bins, the squared threshold, the value of weak cells, and
/// whether cells are 4-bit.
pub(super) struct SobelCells {
    pub(super) w: usize,
    pub(super) border: bool,
    pub(super) bins: usize,
    pub(super) t2: i32,
    pub(super) weak: u8,
    pub(super) nibbles: bool,
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
pub(super) fn ring_cells<const XS: usize>(
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
pub(super) fn checker_pairs(out: &mut [u8], (r0, r1, r2): (&[u8], &[u8], &[u8]), i: usize, class: Classify) -> usize {
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
pub(super) fn put(row: &mut [u8], c: usize, v: u8, nibbles: bool) {
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
pub(super) fn cell(bytes: &[u8], c: usize, nibbles: bool) -> u8 {
    if nibbles {
        // NIBBLE_NONE for no bin, as the pair loop reads it: in 4-bit maps
        // every sample lands in an edge bin (see `histogram::take`).
        bytes.get(c >> 1).map_or(NIBBLE_NONE, |b| (b >> ((c & 1) * 4)) & 0x0f)
    } else {
        bytes.get(c).copied().unwrap_or(NONE)
    }
}
