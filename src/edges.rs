//! The edge cue: Sobel gradients on grey levels, quantised orientation, and
//! edge-orientation histograms inside the same kernel-weighted ellipses as
//! colour (the third paper).
//!
//! Gradients are computed once per frame into an [`EdgeMap`], and only over
//! the region the particles cover; each particle's histogram then only looks
//! orientations up. The map lives in a fixed buffer of `E` cells owned by the
//! tracker. When the region has more pixels than that, the map is computed on
//! a coarser grid (every 2nd, 4th, … pixel in each direction) and particles
//! read the nearest grid cell: the same trade the subsampled colour
//! histograms make, with no allocation and a bounded cost.

use crate::frame::{Frame, Gray8, PixelFormat, PixelRead, Rgb565, Rgb888, Yuv422};
use crate::histogram::{Histogram, RowSink};

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
const NONE: u8 = u8::MAX;

/// The orientation bin of gradient `(gx, gy)` among `bins` equal sectors of
/// 0–180°, by sector tests with integer cross products (no `atan`).
/// `bins` must be 2, 4, 8 or 16.
pub fn orientation_bin(gx: i32, gy: i32, bins: usize) -> usize {
    // Orientation is modulo 180°: fold into the upper half plane.
    let (gx, gy) = if gy < 0 || (gy == 0 && gx < 0) { (-gx, -gy) } else { (gx, gy) };
    let stride = 16 / bins.max(2).min(16);
    // Bin = the number of boundaries at or clockwise of the gradient; the
    // boundaries are sorted by angle, so binary search.
    let (mut lo, mut hi) = (0usize, bins);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        let (c, s) = DIRECTIONS.get(mid * stride).copied().unwrap_or((0, 0));
        // cross(boundary, g) >= 0  <=>  g is at or past the boundary.
        if c * gy - s * gx >= 0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// How an [`EdgeMap`] is computed.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EdgeParams {
    /// Orientation bins over 0–180°: 2, 4, 8 or 16.
    pub bins: usize,
    /// Gradient strength below which a pixel is weak.
    pub threshold: u16,
    /// The finest grid spacing worth computing, in pixels.
    pub min_spacing: usize,
    /// Whether weak pixels count in a bin of their own (bin `bins`), so the
    /// histogram also says how much of the region has edges at all.
    pub flat_bin: bool,
}

/// A per-frame map of quantised edge orientations over a region of the
/// frame, in a fixed buffer of `E` cells.
#[derive(Clone, Debug)]
pub struct EdgeMap<const E: usize> {
    cells: [u8; E],
    x0: usize,
    y0: usize,
    cols: usize,
    rows: usize,
    /// Grid spacing is `1 << shift` pixels.
    shift: u32,
}

impl<const E: usize> Default for EdgeMap<E> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const E: usize> EdgeMap<E> {
    /// An empty map (every lookup is weak).
    pub const fn new() -> Self {
        EdgeMap { cells: [NONE; E], x0: 0, y0: 0, cols: 0, rows: 0, shift: 0 }
    }

    /// Grid spacing in pixels: 1 when the region fits the buffer at full resolution.
    pub fn spacing(&self) -> usize {
        1 << self.shift
    }

    /// Computes orientations over the pixel rectangle `[x0, x1) × [y0, y1)`
    /// (clipped to the frame), dropping gradients with
    /// `sqrt(gx² + gy²) < threshold`. The grid spacing is the largest power
    /// of two not above `min_spacing` (a histogram that reads every 4th pixel
    /// needs no finer map), or coarser if the region does not fit `E` cells.
    pub fn compute(&mut self, frame: &Frame<'_>, rect: (usize, usize, usize, usize), params: EdgeParams) {
        match frame.format() {
            PixelFormat::Rgb565 => self.compute_as::<Rgb565>(frame, rect, params),
            PixelFormat::Rgb888 => self.compute_as::<Rgb888>(frame, rect, params),
            PixelFormat::Yuv422 => self.compute_as::<Yuv422>(frame, rect, params),
            PixelFormat::Gray8 => self.compute_as::<Gray8>(frame, rect, params),
        }
    }

    fn compute_as<P: PixelRead>(&mut self, frame: &Frame<'_>, rect: (usize, usize, usize, usize), p: EdgeParams) {
        let EdgeParams { bins, threshold, min_spacing, flat_bin } = p;
        let weak = if flat_bin { bins.min(16) as u8 } else { NONE };
        let (x0, y0, x1, y1) = rect;
        let (w, h) = (frame.width(), frame.height());
        let (x0, y0) = (x0.min(w), y0.min(h));
        let (x1, y1) = (x1.max(x0).min(w), y1.max(y0).min(h));
        // Start at the spacing the histograms need, coarsen until the region fits.
        let mut shift = 0;
        while shift < 12 && (2usize << shift) <= min_spacing {
            shift += 1;
        }
        while shift < 12 && ((x1 - x0) >> shift).max(1) * ((y1 - y0) >> shift).max(1) > E {
            shift += 1;
        }
        let d = 1usize << shift;
        let cols = (x1 - x0).div_ceil(d).min(E);
        let rows = (y1 - y0).div_ceil(d);
        let rows = E.checked_div(cols).map_or(0, |fit| rows.min(fit));
        // Field by field: rebuilding the struct would copy the cell buffer
        // through the stack.
        (self.x0, self.y0, self.cols, self.rows, self.shift) = (x0, y0, cols, rows, shift);
        let t2 = threshold as i32 * threshold as i32;
        let empty: &[u8] = &[];
        for j in 0..rows {
            let y = y0 + j * d;
            let out = self.cells.get_mut(j * cols..(j + 1) * cols).unwrap_or_default();
            // The Sobel window needs rows y-1..=y+1: the border rows are weak.
            if y == 0 || y + 1 >= h {
                out.fill(NONE);
                continue;
            }
            let rows3 = [y - 1, y, y + 1].map(|r| frame.row(r).unwrap_or(empty));
            // Luma of column x in the three rows.
            let column = |x: usize| rows3.map(|r| P::luma(r, x).map_or(0, i32::from));
            // Slide a 3-column window along the row; at spacing 1 each step
            // decodes one new column instead of nine pixels.
            let mut window: Option<(usize, [[i32; 3]; 3])> = None;
            for (i, cell) in out.iter_mut().enumerate() {
                let x = x0 + i * d;
                *cell = if x == 0 || x + 1 >= w {
                    NONE
                } else {
                    let cols3 = match window {
                        Some((px, [_, m, r])) if px + 1 == x => [m, r, column(x + 1)],
                        _ => [column(x - 1), column(x), column(x + 1)],
                    };
                    window = Some((x, cols3));
                    let [[a, dd, g], [b, _, hh], [c, f, k]] = cols3;
                    let (gx, gy) = sobel([a, b, c, dd, 0, f, g, hh, k]);
                    if gx * gx + gy * gy < t2 { weak } else { orientation_bin(gx, gy, bins) as u8 }
                };
            }
        }
    }

    /// The bin of the map cell nearest pixel `(x, y)`: its orientation, or
    /// the flat bin (`bins`) for a weak gradient when there is one; `None` for
    /// a weak gradient without a flat bin, the frame border, or a pixel
    /// outside the mapped region.
    #[inline(always)]
    pub fn bin_at(&self, x: usize, y: usize) -> Option<usize> {
        let i = x.checked_sub(self.x0)? >> self.shift;
        let j = y.checked_sub(self.y0)? >> self.shift;
        if i >= self.cols || j >= self.rows {
            return None;
        }
        match self.cells.get(j * self.cols + i) {
            Some(&v) if v != NONE => Some(v as usize),
            _ => None,
        }
    }
}

/// Feeds a region walk's samples into an edge-orientation histogram (see
/// [`crate::histogram::RowSink`]), looking each map row up once per pixel row.
pub(crate) struct EdgeSink<'a, const E: usize, const B: usize> {
    map: &'a EdgeMap<E>,
    hist: &'a mut Histogram<B>,
    /// The current row's cells: empty when the row is outside the map, or
    /// when the sink is switched off.
    cells: &'a [u8],
    on: bool,
}

impl<'a, const E: usize, const B: usize> EdgeSink<'a, E, B> {
    /// A sink into `hist` (which it clears), reading `map`; `on == false`
    /// makes it take nothing, so one compiled loop serves both cases.
    pub(crate) fn new(map: &'a EdgeMap<E>, hist: &'a mut Histogram<B>, on: bool) -> Self {
        hist.clear();
        EdgeSink { map, hist, cells: &[], on }
    }
}

impl<const E: usize, const B: usize> RowSink for EdgeSink<'_, E, B> {
    #[inline(always)]
    fn row(&mut self, y: usize) {
        let m = self.map;
        let j = y.wrapping_sub(m.y0) >> m.shift;
        self.cells = if self.on && j < m.rows { m.cells.get(j * m.cols..(j + 1) * m.cols).unwrap_or(&[]) } else { &[] };
    }

    #[inline(always)]
    fn pixel(&mut self, x: usize, w: u32) {
        // Left of the map the subtraction wraps to a huge index: no cell.
        if let Some(&v) = self.cells.get(x.wrapping_sub(self.map.x0) >> self.map.shift)
            && v != NONE
        {
            self.hist.add(v as usize, w);
        }
    }
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
    use crate::geometry::Ellipse;
    use crate::region::{Lattice, Sampling, for_each_in_ellipse};

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
            map.compute(&f, (0, 0, 40, 40), EdgeParams { bins: 8, threshold: 50, min_spacing: 1, flat_bin: false });
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

    #[test]
    fn sliding_window_matches_direct_sobel_at_every_spacing() {
        // Reason: cross-check the map (sliding window, one new column per
        // step) against the plain per-pixel definition on a random image.
        let (w, h) = (37usize, 29usize);
        let mut seed = 99u32;
        let px: Vec<u8> = (0..w * h * 3)
            .map(|_| {
                seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (seed >> 24) as u8
            })
            .collect();
        let f = Frame::packed(&px, w, h, PixelFormat::Rgb888).unwrap();
        let l = |x: usize, y: usize| crate::frame::luma(f.rgb(x, y).unwrap()) as i32;
        for spacing in [1usize, 2, 4] {
            let mut map = EdgeMap::<4096>::new();
            let (x0, y0) = (3usize, 2usize);
            map.compute(
                &f,
                (x0, y0, w, h),
                EdgeParams { bins: 8, threshold: 120, min_spacing: spacing, flat_bin: false },
            );
            assert_eq!(map.spacing(), spacing);
            for y in (y0..h).step_by(spacing) {
                for x in (x0..w).step_by(spacing) {
                    let want = if x == 0 || y == 0 || x + 1 >= w || y + 1 >= h {
                        None
                    } else {
                        let win = [
                            l(x - 1, y - 1),
                            l(x, y - 1),
                            l(x + 1, y - 1),
                            l(x - 1, y),
                            l(x, y),
                            l(x + 1, y),
                            l(x - 1, y + 1),
                            l(x, y + 1),
                            l(x + 1, y + 1),
                        ];
                        let (gx, gy) = sobel(win);
                        (gx * gx + gy * gy >= 120 * 120).then(|| orientation_bin(gx, gy, 8))
                    };
                    assert_eq!(map.bin_at(x, y), want, "spacing {spacing} at ({x}, {y})");
                }
            }
        }
    }

    #[test]
    fn weak_gradients_are_dropped_and_the_map_coarsens_to_fit() {
        let flat = vec![100u8; 64 * 64];
        let f = Frame::packed(&flat, 64, 64, PixelFormat::Gray8).unwrap();
        let mut map = EdgeMap::<256>::new();
        // 64x64 = 4096 pixels into 256 cells: spacing 4.
        map.compute(&f, (0, 0, 64, 64), EdgeParams { bins: 8, threshold: 1, min_spacing: 1, flat_bin: false });
        assert_eq!(map.spacing(), 4);
        assert_eq!(map.bin_at(30, 30), None, "a flat frame has no edges");
        assert_eq!(map.bin_at(100, 30), None, "outside the frame");
        // Stripes 2 grey levels apart: a gradient of 8, under a threshold of 10.
        let faint: Vec<u8> = (0..64 * 64).map(|i| if (i % 64) / 4 % 2 == 0 { 100 } else { 102 }).collect();
        let f = Frame::packed(&faint, 64, 64, PixelFormat::Gray8).unwrap();
        map.compute(&f, (0, 0, 64, 64), EdgeParams { bins: 8, threshold: 10, min_spacing: 1, flat_bin: false });
        assert!((0..64).all(|x| map.bin_at(x, 30).is_none()));
        map.compute(&f, (0, 0, 64, 64), EdgeParams { bins: 8, threshold: 5, min_spacing: 3, flat_bin: false });
        assert_eq!(map.spacing(), 4, "budget 256 cells still rules");
        map.compute(&f, (0, 0, 64, 64), EdgeParams { bins: 8, threshold: 5, min_spacing: 1, flat_bin: false });
        assert!((0..64).any(|x| map.bin_at(x, 30).is_some()));
        // With a flat bin, the weak pixels are counted there (bin 8 of 8 + 1).
        // The map's cells are 4 px apart; those of x < 4 sit on the border.
        map.compute(&f, (0, 0, 64, 64), EdgeParams { bins: 8, threshold: 10, min_spacing: 1, flat_bin: true });
        assert!((4..64).all(|x| map.bin_at(x, 30) == Some(8)));
        assert_eq!(map.bin_at(0, 30), None, "the border has no Sobel window");
    }
}
