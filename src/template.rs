//! A small grey-level template of the target, compared by normalised
//! cross-correlation: the cue that sees *where* things are inside the box,
//! which a histogram does not.
//!
//! The target box is read on a `G × G` grid of luma samples (see
//! `PER_CELL` for how many pixels make a sample). A candidate box is read
//! the same way, at its own size, so the comparison also penalises a wrong
//! scale or aspect. The score is the Pearson correlation of the two sample vectors,
//! in `[-1, 1]`: insensitive to brightness and contrast changes, high only
//! when the layout of light and dark matches.

use crate::frame::Frame;
use crate::geometry::Ellipse;
use crate::pixel::{self, Loop, Loops, PixelRead, RowReader};
use crate::scalar::{Real, half_steps, index_within, sqrt};

/// Samples per side of the template grid.
pub const GRID: usize = 8;

/// Samples of a template.
const SAMPLES: usize = GRID * GRID;

/// A grey-level template: `GRID × GRID` luma samples with their sums.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Template {
    samples: [u8; SAMPLES],
    /// Sum and sum of squares of `samples`.
    sum: u32,
    sum2: u32,
    /// Whether the template holds a learnt patch.
    valid: bool,
}

impl Default for Template {
    fn default() -> Self {
        Self::new()
    }
}

/// A sampled candidate: the samples and their sums.
struct Patch {
    samples: [u8; SAMPLES],
    sum: u32,
    sum2: u32,
}

impl Template {
    /// An empty template (matches nothing).
    pub const fn new() -> Self {
        Template { samples: [0; SAMPLES], sum: 0, sum2: 0, valid: false }
    }

    /// Learns the template of the box of `e`.
    pub(crate) fn learn(&mut self, frame: &Frame<'_>, e: &Ellipse) {
        let p = sample(frame, e);
        (self.samples, self.sum, self.sum2, self.valid) = (p.samples, p.sum, p.sum2, true);
    }

    /// Blends the box of `e` into the template: `t ← (1 − rate) t + rate · c`.
    pub(crate) fn blend(&mut self, frame: &Frame<'_>, e: &Ellipse, rate: Real) {
        if !self.valid {
            return self.learn(frame, e);
        }
        let p = sample(frame, e);
        let a = (crate::scalar::clamp(rate, 0.0, 1.0) * 256.0) as u32;
        let (mut sum, mut sum2) = (0u32, 0u32);
        for (t, &c) in self.samples.iter_mut().zip(p.samples.iter()) {
            let v = (((256 - a) * *t as u32 + a * c as u32 + 128) >> 8).min(255);
            *t = v as u8;
            sum += v;
            sum2 += v * v;
        }
        (self.sum, self.sum2) = (sum, sum2);
    }

    /// The normalised cross-correlation of the box of `e` with the
    /// template, in `[-1, 1]`; 0 for a flat template or patch (no layout to
    /// compare) or before anything was learnt.
    pub fn correlation(&self, frame: &Frame<'_>, e: &Ellipse) -> Real {
        if !self.valid {
            return 0.0;
        }
        let p = sample(frame, e);
        let dot: u32 = self.samples.iter().zip(p.samples.iter()).map(|(&t, &c)| t as u32 * c as u32).sum();
        let n = SAMPLES as i64;
        let num = n * dot as i64 - self.sum as i64 * p.sum as i64;
        let vt = n * self.sum2 as i64 - (self.sum as i64) * (self.sum as i64);
        let vc = n * p.sum2 as i64 - (p.sum as i64) * (p.sum as i64);
        if vt <= 0 || vc <= 0 {
            return 0.0;
        }
        let den = sqrt(vt as Real) * sqrt(vc as Real);
        crate::scalar::clamp(num as Real / den, -1.0, 1.0)
    }
}

/// Most pixels read per cell and side: a cell of a large box is read on a
/// sub-grid of at most this many by this many pixels. Two: the position
/// search reads five boxes a frame, at 256 reads each (4 × 4 would be 1024,
/// and on the real sequences tracks no better within noise); one pixel a
/// cell makes the correlation a step function of the box's position, which
/// a hill climb cannot climb.
const PER_CELL: i32 = 2;

/// `j + ½` for each point `j` of a cell's side.
const HALF_STEPS: [Real; PER_CELL as usize] = half_steps();

/// Reads the box of `e` on the template grid: each sample is the mean luma
/// of its cell of the box (so the correlation falls off smoothly, over
/// about a cell, as a candidate moves off the target), read on a sub-grid
/// of at most [`PER_CELL`]² pixels. Pixels off the frame repeat its edge.
fn sample(frame: &Frame<'_>, e: &Ellipse) -> Patch {
    let mut p = Patch { samples: [0; SAMPLES], sum: 0, sum2: 0 };
    // The last column and row (a frame is never empty; in `i32`, which
    // compiles smaller here than a saturating subtraction).
    let (xlast, ylast) = (frame.width() as i32 - 1, frame.height() as i32 - 1);
    let (cw, ch) = (2.0 * e.hx / GRID as Real, 2.0 * e.hy / GRID as Real);
    // Sub-grid points per cell and side (pixels at least one apart).
    let (nx, ny) = (cw.max(1.0).min(PER_CELL as Real) as usize, ch.max(1.0).min(PER_CELL as Real) as usize);
    // The columns and rows read, GRID cells of nx (ny) each, worked out
    // once; off the frame they repeat its edge.
    let mut xs = [0usize; GRID * PER_CELL as usize];
    let mut ys = [0usize; GRID * PER_CELL as usize];
    for (coords, n, size, start, last) in [(&mut xs, nx, cw, e.cx - e.hx, xlast), (&mut ys, ny, ch, e.cy - e.hy, ylast)]
    {
        let sub = size / n as Real;
        // Cell by cell, point by point: no division (a library call on a
        // Cortex-M0+, which has no divide instruction).
        let mut slots = coords.iter_mut();
        for cell in 0..GRID {
            let first = start + cell as Real * size;
            // Point `j` of a cell lies `j + ½` sub-steps into it (from a
            // table: no conversion per point).
            for &at in HALF_STEPS.iter().take(n) {
                let v = first + at * sub;
                if let Some(c) = slots.next() {
                    *c = index_within(v, last as usize);
                }
            }
        }
    }
    // At least one read per cell; 1, 2 or 4 with PER_CELL = 2, which
    // `div_small` divides by without a divide instruction.
    let per = (nx * ny) as u32;
    let mut cells = [0u32; GRID];
    for (j, rows) in ys.chunks(ny.max(1)).take(GRID).enumerate() {
        cells.iter_mut().for_each(|c| *c = 0);
        for &y in rows {
            let Some(row) = frame.row(y) else { continue };
            let cols = xs.chunks(nx.max(1));
            // One format dispatch per row, not per pixel.
            pixel::read(frame.format(), CellRow { frame, cells: &mut cells, row, cols });
        }
        for (i, &c) in cells.iter().enumerate() {
            // The mean of the cell's reads, rounded.
            let v = crate::region::div_small(c + per / 2, per);
            if let Some(t) = p.samples.get_mut(j * GRID + i) {
                *t = v as u8;
            }
            p.sum += v;
            p.sum2 += v * v;
        }
    }
    p
}

/// [`add_row`] in any format, a pixel at a time through the frame: the
/// same sums (tested).
fn add_row_any<'c>(frame: &Frame<'_>, cells: &mut [u32; GRID], row: &[u8], cols: impl Iterator<Item = &'c [usize]>) {
    for (c, cols) in cells.iter_mut().zip(cols) {
        *c += cols.iter().map(|&x| frame.luma_in(row, x).map_or(0, |v| v as u32)).sum::<u32>();
    }
}

/// One row of the template's grid: the lumas of `row` (a row of `frame`)
/// at each cell's columns, added to the cell.
struct CellRow<'f, 'r, I> {
    frame: &'r Frame<'f>,
    cells: &'r mut [u32; GRID],
    row: &'f [u8],
    cols: I,
}

impl<'c, I: Iterator<Item = &'c [usize]>> RowReader for CellRow<'_, '_, I> {
    type Output = ();
    // Loops of its own where they save time, not in the lean build.
    const LOOPS: Loops = Loops::camera_luma(Loop::Fast);

    #[inline(always)]
    fn rows_of<P: PixelRead>(self) {
        add_row::<P>(self.cells, self.row, self.cols)
    }

    #[inline(always)]
    fn general(self) {
        add_row_any(self.frame, self.cells, self.row, self.cols)
    }
}

/// Adds the luma of the pixels of `row` at each cell's columns to the cell.
#[inline(always)]
fn add_row<'c, P: PixelRead>(cells: &mut [u32; GRID], row: &[u8], cols: impl Iterator<Item = &'c [usize]>) {
    let Some(px) = P::pixels(row) else { return };
    for (c, cols) in cells.iter_mut().zip(cols) {
        *c += cols.iter().map(|&x| px.get(x).map_or(0, |&p| P::px_luma(p) as u32)).sum::<u32>();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pixel::{Gray8, PixelFormat, Rgb565};

    const W: usize = 120;
    const H: usize = 90;

    fn noise(seed: u32) -> Vec<u8> {
        let mut next = crate::testing::lcg(seed);
        (0..W * H).map(|_| 40 + (next() >> 24) as u8 / 2).collect()
    }

    #[test]
    fn the_per_format_row_sums_equal_the_general_ones() {
        // Reason: a cross-check of two implementations of a row's cell sums:
        // the camera formats' own loop and the pixel-at-a-time read through
        // the frame (what the lean builds take), on random RGB565 and GRAY8
        // rows, with one and two columns a cell, past the row's end too.
        let grey = noise(5);
        let rgb: Vec<u8> = noise(6).into_iter().chain(noise(7)).collect();
        let frames = [
            Frame::packed(&rgb, W, H, PixelFormat::Rgb565).unwrap(),
            Frame::packed(&grey, W, H, PixelFormat::Gray8).unwrap(),
        ];
        let mut next = crate::testing::lcg(8);
        for f in &frames {
            for y in [0, 17, H - 1] {
                let row = f.row(y).unwrap();
                for per in [1usize, 2] {
                    let xs: Vec<usize> = (0..GRID * per).map(|_| (next() >> 16) as usize % (W + 8)).collect();
                    let (mut own, mut any) = ([0u32; GRID], [0u32; GRID]);
                    match f.format() {
                        PixelFormat::Rgb565 => add_row::<Rgb565>(&mut own, row, xs.chunks(per)),
                        _ => add_row::<Gray8>(&mut own, row, xs.chunks(per)),
                    }
                    add_row_any(f, &mut any, row, xs.chunks(per));
                    assert_eq!(own, any, "{:?} row {y}, {per} a cell", f.format());
                    assert!(own.iter().any(|&c| c > 0));
                }
            }
        }
    }

    #[test]
    fn correlation_is_one_on_the_template_and_ignores_gain_and_offset() {
        // Reason: the definition of Pearson's correlation. The same patch
        // correlates 1 with itself; a patch whose grey levels are
        // v / 2 + 10 correlates 1 too (up to rounding: each pixel within
        // ±0.5 of v / 2 + 10, each cell mean within ±0.5 more); a flat patch has no layout
        // to compare and scores 0.
        let px = noise(3);
        let f = Frame::packed(&px, W, H, PixelFormat::Gray8).unwrap();
        let e = Ellipse { cx: 60.0, cy: 45.0, hx: 16.0, hy: 12.0 };
        let mut t = Template::new();
        assert_eq!(t.correlation(&f, &e), 0.0, "nothing learnt yet");
        t.learn(&f, &e);
        assert!((t.correlation(&f, &e) - 1.0).abs() < 1e-5);
        let brighter: Vec<u8> = px.iter().map(|&v| v / 2 + 10).collect();
        let g = Frame::packed(&brighter, W, H, PixelFormat::Gray8).unwrap();
        assert!(t.correlation(&g, &e) > 0.99, "{}", t.correlation(&g, &e));
        let flat = vec![90u8; W * H];
        assert_eq!(t.correlation(&Frame::packed(&flat, W, H, PixelFormat::Gray8).unwrap(), &e), 0.0);
    }

    #[test]
    fn correlation_falls_off_over_about_a_cell() {
        // Reason: the samples are means of a 2 × 2 sub-grid of each 4 px
        // cell; on noise that is constant over 2 × 2 pixel blocks, as a
        // camera's is over its optics' blur, a 1 px shift reads the same
        // block for half the points and keeps most of the correlation, and a
        // shift by two cells of independent noise leaves little (cells of
        // independent noise correlate 0 in expectation; 64 of them, within
        // about ±0.3).
        let fine = noise(5);
        let px: Vec<u8> = (0..W * H).map(|i| fine[(i / W / 2 * 2) * W + i % W / 2 * 2]).collect();
        let f = Frame::packed(&px, W, H, PixelFormat::Gray8).unwrap();
        let e = Ellipse { cx: 60.0, cy: 45.0, hx: 16.0, hy: 16.0 };
        let mut t = Template::new();
        t.learn(&f, &e);
        let at = |dx: f32| t.correlation(&f, &Ellipse { cx: e.cx + dx, ..e });
        assert!(at(1.0) > 0.6, "{}", at(1.0));
        assert!(at(1.0) >= at(2.0) && at(2.0) > at(4.0), "{} {} {}", at(1.0), at(2.0), at(4.0));
        assert!(at(8.0).abs() < 0.35, "{}", at(8.0));
    }

    #[test]
    fn blending_at_rate_zero_keeps_and_at_one_replaces() {
        // Reason: t ← (1 − rate) t + rate · c at the ends of the range.
        let (a, b) = (noise(7), noise(8));
        let (fa, fb) = (
            Frame::packed(&a, W, H, PixelFormat::Gray8).unwrap(),
            Frame::packed(&b, W, H, PixelFormat::Gray8).unwrap(),
        );
        let e = Ellipse { cx: 60.0, cy: 45.0, hx: 16.0, hy: 12.0 };
        let mut t = Template::new();
        t.learn(&fa, &e);
        let first = t.clone();
        t.blend(&fb, &e, 0.0);
        assert_eq!(t, first);
        t.blend(&fb, &e, 1.0);
        let mut want = Template::new();
        want.learn(&fb, &e);
        assert_eq!(t, want);
    }
}
