//! The channels the gradient filter reads ([`super::gradient`]): a window
//! around the target on a lattice of square cells, each cell the mean grey
//! level of its 2 x 2 lattice points and their gradient magnitudes shared
//! among [`ORIENTATIONS`] unsigned orientations (soft-binned, as HOG's
//! cells are: Dalal and Triggs 2005).
//!
//! Why gradients beside grey: the orientation of edges survives a change
//! of lighting and of colour, and places a target whose colours its
//! surroundings share; the hand-crafted trackers that lead on public
//! benchmarks (ECO-HC, BACF, STRCF) read them.
//!
//! The cells are kept as bytes (the window's cells are the filter's largest
//! memory): grey as the cells' mean luma, each orientation as its mean
//! magnitude in luma levels per two lattice points, rounded and saturated
//! at 255 (an edge that strong in all four points of a cell is rare, and
//! saturating it is HOG's clipping in effect).

use crate::frame::Frame;
use crate::pixel::{self, Loop, Loops, PixelRead, RowReader};
use crate::scalar::{Real, clamp, sqrt_q4};

/// Unsigned gradient orientations: channels 1 to `ORIENTATIONS`.
pub(crate) const ORIENTATIONS: usize = 4;
/// Grey, then the orientations.
pub(crate) const CHANNELS: usize = 1 + ORIENTATIONS;
/// The largest lattice the filter reads, in cells per side.
pub(crate) const MAX_CELLS: usize = 48;
/// Lattice points per cell side.
const POINTS: usize = 2;
/// The largest lattice, in points per side.
const MAX_POINTS: usize = POINTS * MAX_CELLS;

/// Reads the `n` x `n` cells (`n` at most [`MAX_CELLS`]) of side `cell`
/// (pixels, horizontal and vertical) centred on `centre` into `out`,
/// channel by channel, each row by row: channel `k` of cell `(r, c)` at
/// `out[(k · n + r) · n + c]`. Cell `n / 2` (row and column) starts at the
/// centre. Points outside the frame repeat its edge. False, with `out`
/// untouched, where `out` or `n` does not fit.
pub(crate) fn read(frame: &Frame<'_>, centre: (Real, Real), cell: (Real, Real), n: usize, out: &mut [u8]) -> bool {
    let points = POINTS * n;
    if n == 0 || n > MAX_CELLS || out.len() < CHANNELS * n * n {
        return false;
    }
    let (xmax, ymax) = (frame.width().saturating_sub(1) as Real, frame.height().saturating_sub(1) as Real);
    let step = (cell.0 / POINTS as Real, cell.1 / POINTS as Real);
    let at =
        |i: usize, c: Real, step: Real, max: Real| clamp(c + (i as Real + 0.5 - n as Real) * step, 0.0, max) as usize;
    let mut columns = [0usize; MAX_POINTS];
    for (j, x) in columns.iter_mut().enumerate().take(points) {
        *x = at(j, centre.0, step.0, xmax);
    }
    let columns = columns.get(..points).unwrap_or(&[]);
    let row = |i: usize, luma: &mut [u8; MAX_POINTS]| {
        let y = at(i.min(points - 1), centre.1, step.1, ymax);
        if let Some(pixels) = frame.row(y) {
            // One format dispatch per row, not per pixel.
            pixel::read(frame.format(), PointRow { frame, row: pixels, columns, luma });
        }
    };
    // The rows above, at and below the point being read (the lattice's
    // edge rows repeat).
    let (mut here, mut below) = ([0u8; MAX_POINTS], [0u8; MAX_POINTS]);
    row(0, &mut here);
    let mut above = here;
    row(1, &mut below);
    let mut grey = [0u16; MAX_CELLS];
    let mut grad = [[0.0 as Real; MAX_CELLS]; ORIENTATIONS];
    let plane = n * n;
    for i in 0..points {
        for c in 0..points {
            let get = |r: &[u8; MAX_POINTS], c: usize| r.get(c).copied().unwrap_or(0) as i32;
            let l = get(&here, c);
            let gx = get(&here, (c + 1).min(points - 1)) - get(&here, c.saturating_sub(1));
            let gy = get(&below, c) - get(&above, c);
            let cc = c / POINTS;
            if let Some(g) = grey.get_mut(cc) {
                *g += l as u16;
            }
            if let Some((bin, f)) = orientation(gx, gy) {
                let m = sqrt_q4((gx * gx + gy * gy) as u32) as Real / 16.0;
                if let Some(g) = grad.get_mut(bin).and_then(|g| g.get_mut(cc)) {
                    *g += m * (1.0 - f);
                }
                if let Some(g) = grad.get_mut((bin + 1) % ORIENTATIONS).and_then(|g| g.get_mut(cc)) {
                    *g += m * f;
                }
            }
        }
        if i % POINTS == POINTS - 1 {
            // A row of cells is complete.
            let r = i / POINTS;
            let per = (POINTS * POINTS) as u16;
            for (cc, g) in grey.iter_mut().enumerate().take(n) {
                if let Some(o) = out.get_mut(r * n + cc) {
                    *o = ((*g + per / 2) / per) as u8;
                }
                *g = 0;
            }
            for (k, channel) in grad.iter_mut().enumerate() {
                for (cc, g) in channel.iter_mut().enumerate().take(n) {
                    if let Some(o) = out.get_mut((k + 1) * plane + r * n + cc) {
                        *o = (*g / (POINTS * POINTS) as Real + 0.5).min(255.0) as u8;
                    }
                    *g = 0.0;
                }
            }
        }
        above = here;
        here = below;
        if i + 2 < points {
            row(i + 2, &mut below);
        }
    }
    true
}

/// The orientation of the gradient `(gx, gy)`, unsigned (in `[0, π)`), as
/// the lower of the two orientation bins it falls between and its share of
/// the upper one; `None` for no gradient. Bin `b` is centred on
/// `(b + ½) π / ORIENTATIONS`. The angle comes from a rational
/// approximation of the arctangent (within 0.005 rad, a hundred and fiftieth
/// of a bin), so that no trigonometry runs per point.
fn orientation(gx: i32, gy: i32) -> Option<(usize, Real)> {
    if gx == 0 && gy == 0 {
        return None;
    }
    // Fold onto [0, π): an edge and its opposite are one orientation.
    let (gx, gy) = if gy < 0 || (gy == 0 && gx < 0) { (-gx, -gy) } else { (gx, gy) };
    let (ax, ay) = (gx.abs() as Real, gy as Real);
    // The angle from the nearer axis, in eighths of a turn: atan(z) for
    // z in [0, 1] is about z·π/4 + 0.273·z·(1 − z).
    let octant = |z: Real| z + 0.3476 * z * (1.0 - z);
    let first = if ay <= ax { octant(ay / ax) } else { 2.0 - octant(ax / ay) };
    // In units of π / 4, in [0, 4).
    let quarter = if gx >= 0 { first } else { 4.0 - first };
    let b = quarter * (ORIENTATIONS as Real / 4.0) - 0.5;
    if b < 0.0 {
        Some((ORIENTATIONS - 1, b + 1.0))
    } else {
        Some(((b as usize).min(ORIENTATIONS - 1), b - (b as usize) as Real))
    }
}

/// One row of points: the lumas of `row` (a row of `frame`) at `columns`.
struct PointRow<'f, 'r> {
    frame: &'r Frame<'f>,
    row: &'f [u8],
    columns: &'r [usize],
    luma: &'r mut [u8; MAX_POINTS],
}

impl RowReader for PointRow<'_, '_> {
    type Output = ();
    // About a hundred rows a frame: loops of their own in every build.
    const LOOPS: Loops = Loops::camera_luma(Loop::Always);

    fn rows_of<P: PixelRead>(self) {
        let Some(px) = P::pixels(self.row) else { return };
        for (l, &x) in self.luma.iter_mut().zip(self.columns.iter()) {
            *l = px.get(x).map_or(0, |&p| P::px_luma(p));
        }
    }

    #[inline(always)]
    fn general(self) {
        for (l, &x) in self.luma.iter_mut().zip(self.columns.iter()) {
            *l = self.frame.luma_in(self.row, x).unwrap_or(0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pixel::PixelFormat;

    #[test]
    fn orientations_fall_in_the_bins_their_angles_say() {
        // Reason: std's atan2 is the reference; the bins are centred on
        // (b + 1/2)·45°, so an angle's bin and share follow by hand.
        for deg in 0..360 {
            let t = (deg as f64 + 0.3).to_radians();
            let (gx, gy) = ((100.0 * t.cos()).round() as i32, (100.0 * t.sin()).round() as i32);
            let (bin, f) = orientation(gx, gy).unwrap();
            let mut a = (gy as f64).atan2(gx as f64);
            if a < 0.0 {
                a += std::f64::consts::PI;
            }
            if a >= std::f64::consts::PI {
                a -= std::f64::consts::PI;
            }
            let b = a / std::f64::consts::PI * ORIENTATIONS as f64 - 0.5;
            let want = b.rem_euclid(ORIENTATIONS as f64);
            let got = bin as f64 + f as f64;
            let d = (got - want).abs().min(ORIENTATIONS as f64 - (got - want).abs());
            assert!(d < 0.01, "{deg}°: bin {bin} + {f} against {want}");
        }
        assert_eq!(orientation(0, 0), None);
    }

    #[test]
    fn a_vertical_edge_fills_the_horizontal_gradient_bins_only() {
        // Reason: a step from dark to light along x has gradients along x
        // (0°), which lie half in bin 3 (centred on 157.5°, wrapping) and
        // half in bin 0 (22.5°); grey is the mean luma by construction.
        let (w, h) = (64, 32);
        let px: Vec<u8> = (0..w * h).map(|i| if i % w < 32 { 40 } else { 200 }).collect();
        let frame = Frame::packed(&px, w, h, PixelFormat::Gray8).unwrap();
        let n = 8;
        let mut out = vec![0u8; CHANNELS * n * n];
        assert!(read(&frame, (32.0, 16.0), (2.0, 2.0), n, &mut out));
        let at = |k: usize, r: usize, c: usize| out[(k * n + r) * n + c];
        for r in 0..n {
            assert_eq!(at(0, r, 0), 40);
            assert_eq!(at(0, r, n - 1), 200);
            // Points one pixel apart, point j at x = 24 + j: the edge
            // between x = 31 and 32 is seen by points 7 and 8 (gx = 160
            // each), the last of cell 3 and the first of cell 4. Each cell
            // has one such point in each of its two point rows: 2 · 160,
            // half to bin 0 and half to bin 3, over 4 points is 40.
            for c in [3, 4] {
                assert_eq!(at(1, r, c), 40, "bin 0, cell {c}");
                assert_eq!(at(4, r, c), 40, "bin 3, cell {c}");
                assert_eq!(at(2, r, c), 0);
                assert_eq!(at(3, r, c), 0);
            }
            assert_eq!(at(1, r, 2), 0);
            assert_eq!(at(1, r, 5), 0);
        }
        assert!(!read(&frame, (32.0, 16.0), (2.0, 2.0), MAX_CELLS + 1, &mut out));
    }
}
