//! The channels the gradient filter reads ([`super::gradient`]): a window
//! around the target on a lattice of square cells, each cell the log of the
//! mean luma of its 2 x 2 lattice points ("grey"), and the gradient of grey
//! across the cells (central differences) shared among [`ORIENTATIONS`]
//! unsigned orientations (soft-binned, as HOG's cells are: Dalal and
//! Triggs 2005).
//!
//! Why gradients beside grey: the orientation of edges survives a change
//! of lighting and of colour, and places a target whose colours its
//! surroundings share; the hand-crafted trackers that lead on public
//! benchmarks (ECO-HC, BACF, STRCF) read them. Why from the cells' grey
//! rather than from every point: a quarter of the gradients to compute (the
//! cells' reading is most of the filter's time), as accurate on the
//! recorded sequences (docs/accuracy.md), and gradients of log-luma, so
//! that an edge's strength is its contrast whatever the light.
//!
//! The cells are kept as bytes (the window's cells are the filter's largest
//! memory): grey as `ln(1 + luma)` scaled to a byte, each orientation as its
//! share of the gradient's length in grey levels, rounded and saturated at
//! 255. Every step is in integers and tables, so that a core without an FPU
//! reads a window as fast as one with it.

use super::series::ln_1p;
use crate::frame::Frame;
use crate::pixel::{self, Loop, Loops, PixelRead, RowReader};
use crate::scalar::{Real, index_within};

/// Unsigned gradient orientations: channels 1 to `ORIENTATIONS`.
pub(crate) const ORIENTATIONS: usize = 4;
/// Grey, then the orientations.
pub(crate) const CHANNELS: usize = 1 + ORIENTATIONS;
/// The largest lattice the filter reads, in cells per side.
pub(crate) const MAX_CELLS: usize = 46;
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
    let (xmax, ymax) = (frame.width().saturating_sub(1), frame.height().saturating_sub(1));
    // Point `i` lies `i + ½ − n` steps from the centre: that many half
    // steps, an odd whole number, times half a step (both exact, so the
    // product rounds as `(i + ½ − n) · step` would).
    let half = (0.5 * cell.0 / POINTS as Real, 0.5 * cell.1 / POINTS as Real);
    let at = |i: usize, c: Real, half: Real, last: usize| {
        index_within(c + (2 * i as i32 + 1 - 2 * n as i32) as Real * half, last)
    };
    let mut columns = [0usize; MAX_POINTS];
    for (j, x) in columns.iter_mut().enumerate().take(points) {
        *x = at(j, centre.0, half.0, xmax);
    }
    let columns = columns.get(..points).unwrap_or(&[]);
    // Grey first: each cell the mean of its 2 x 2 points' lumas, as
    // `LOG_GREY`; each row of points adds its pairs' lumas to its cells.
    let mut grey = [0u16; MAX_CELLS];
    let plane = n * n;
    let per = (POINTS * POINTS) as u16;
    for i in 0..points {
        let y = at(i, centre.1, half.1, ymax);
        if let Some(pixels) = frame.row(y) {
            // One format dispatch per row, not per pixel.
            pixel::read(frame.format(), PointRow { frame, row: pixels, columns, grey: &mut grey });
        }
        if i % POINTS == POINTS - 1 {
            let r = i / POINTS;
            let row = out.get_mut(r * n..(r + 1) * n).unwrap_or(&mut []);
            for (o, g) in row.iter_mut().zip(grey.iter_mut()) {
                // The mean of four lumas is a byte.
                *o = LOG_GREY.get(((*g + per / 2) / per) as u8 as usize).copied().unwrap_or(0);
                *g = 0;
            }
        }
    }
    // Then the orientations, from the grey cells' central differences
    // (edge cells repeat): gradients of log-luma, so that an edge's
    // strength is its contrast, whatever the light. Row by row, each
    // plane's row taken once.
    // (Split and sliced by checked calls: chunks of a size known only at
    // run time would bring a division's panic path.)
    let (grey, rest) = out.split_at_mut(plane);
    let Some((p0, rest)) = rest.split_at_mut_checked(plane) else { return true };
    let Some((p1, rest)) = rest.split_at_mut_checked(plane) else { return true };
    let Some((p2, rest)) = rest.split_at_mut_checked(plane) else { return true };
    let Some(p3) = rest.get_mut(..plane) else { return true };
    let row = |r: usize| grey.get(r * n..(r + 1) * n).unwrap_or(&[]);
    for r in 0..n {
        let at = r * n..(r + 1) * n;
        let (Some(o0), Some(o1), Some(o2), Some(o3)) =
            (p0.get_mut(at.clone()), p1.get_mut(at.clone()), p2.get_mut(at.clone()), p3.get_mut(at))
        else {
            continue;
        };
        let (up, mid, down) = (row(r.saturating_sub(1)), row(r), row((r + 1).min(n - 1)));
        // The cells left of and at the current one (the first repeats).
        let first = mid.first().copied().unwrap_or(0);
        let (mut left, mut centre) = (first, first);
        for (c, (((((o0, o1), o2), o3), &u), &d)) in
            o0.iter_mut().zip(o1.iter_mut()).zip(o2.iter_mut()).zip(o3.iter_mut()).zip(up).zip(down).enumerate()
        {
            // The last repeats.
            let right = mid.get(c + 1).copied().unwrap_or(centre);
            let (gx, gy) = (right as i32 - left as i32, d as i32 - u as i32);
            (left, centre) = (centre, right);
            // The length shared between the two bins the orientation falls
            // between (a byte each, bin `k` in byte `k`); the other bins
            // get none.
            let shares = match orientation(gx, gy) {
                Some((bin, f, m)) => {
                    let share = |part: u32| ((m * part + 32_768) >> 16).min(255);
                    (share(256 - f) << (8 * bin)) | (share(f) << (8 * ((bin + 1) % ORIENTATIONS)))
                }
                None => 0,
            };
            [*o0, *o1, *o2, *o3] = shares.to_le_bytes();
        }
    }
    true
}

/// The grey channel's value for a cell's mean luma `l`: `ln(1 + l)` scaled
/// to a byte (`255 · ln(1 + l) / ln 256`), so that a shadow scales the
/// lumas rather than shifting the values (MOSSE's log-luma), computed at
/// compile time.
const LOG_GREY: [u8; 256] = log_grey();

// Evaluated at compile time only (for a `const`): an index out of range
// would stop the build, never the device.
#[allow(clippy::indexing_slicing)]
const fn log_grey() -> [u8; 256] {
    let mut out = [0u8; 256];
    let mut l = 0;
    while l < 256 {
        let v = ln_1p(l) / ln_1p(255) * 255.0 + 0.5;
        out[l] = v as u8;
        l += 1;
    }
    out
}

/// The arctangent of `z / 256` for `z` in `0..=256`, in 256ths of an
/// eighth of a turn (`atan(z / 256) / (π / 4) · 256`, rounded), and
/// `sqrt(1 + (z / 256)²) · 256`, rounded: a gradient's direction and length
/// from the ratio of its smaller component to its larger, with no
/// trigonometry or root per point. Computed at compile time.
const ATAN: [u16; 257] = atan_table();
const LENGTH: [u16; 257] = length_table();

// Evaluated at compile time only (for a `const`): an index out of range
// would stop the build, never the device.
#[allow(clippy::indexing_slicing)]
const fn atan_table() -> [u16; 257] {
    let mut out = [0u16; 257];
    let mut z = 0;
    while z <= 256 {
        let x = z as f64 / 256.0;
        // atan(x) = π/4 + atan((x − 1) / (x + 1)): an argument within
        // ±1/3 for x in [1/2, 1], where the series converges fast.
        let (t, base) = if x > 0.5 { ((x - 1.0) / (x + 1.0), core::f64::consts::FRAC_PI_4) } else { (x, 0.0) };
        let (mut power, mut sum, mut k) = (t, 0.0, 0);
        while k < 40 {
            let term = power / (2 * k + 1) as f64;
            sum += if k % 2 == 0 { term } else { -term };
            power *= t * t;
            k += 1;
        }
        out[z] = ((base + sum) / core::f64::consts::FRAC_PI_4 * 256.0 + 0.5) as u16;
        z += 1;
    }
    out
}

// Evaluated at compile time only (for a `const`): an index out of range
// would stop the build, never the device.
#[allow(clippy::indexing_slicing)]
const fn length_table() -> [u16; 257] {
    let mut out = [0u16; 257];
    let mut z = 0;
    while z <= 256 {
        let x = 1.0 + (z as f64 / 256.0) * (z as f64 / 256.0);
        // Newton's root from 1 (x is in [1, 2]).
        let (mut y, mut k) = (1.0, 0);
        while k < 30 {
            y = 0.5 * (y + x / y);
            k += 1;
        }
        out[z] = (y * 256.0 + 0.5) as u16;
        z += 1;
    }
    out
}

/// `65,536 / d` for `d` in `1..=255` (0 for 0): the ratio of a gradient's
/// components with a multiplication, on cores without a divider too.
const RECIPROCAL: [u32; 256] = reciprocal_table();

// Evaluated at compile time only (for a `const`): an index out of range
// would stop the build, never the device.
#[allow(clippy::indexing_slicing)]
const fn reciprocal_table() -> [u32; 256] {
    let mut out = [0u32; 256];
    let mut d = 1;
    while d < 256 {
        out[d] = (65_536 + d as u32 / 2) / d as u32;
        d += 1;
    }
    out
}

/// The gradient `(gx, gy)` (each within ±255) as its unsigned orientation
/// (in `[0, π)`): the lower of the two orientation bins it falls between,
/// its share of the upper one in 256ths, and its length in 256ths of a
/// luma level; `None` for no gradient. Bin `b` is centred on
/// `(b + ½) π / ORIENTATIONS`. Integers and tables only: the angle is
/// within about a 500th of a bin of the true one, the length within 0.5%.
fn orientation(gx: i32, gy: i32) -> Option<(usize, u32, u32)> {
    // Fold onto [0, π): an edge and its opposite are one orientation.
    let (gx, gy) = if gy < 0 || (gy == 0 && gx < 0) { (-gx, -gy) } else { (gx, gy) };
    let (ax, ay) = (gx.unsigned_abs().min(255), gy.unsigned_abs().min(255));
    let (big, small) = (ax.max(ay), ax.min(ay));
    if big == 0 {
        return None;
    }
    let recip = RECIPROCAL.get(big as usize).copied().unwrap_or(0);
    let z = ((small * recip + 128) >> 8).min(256) as usize;
    let (angle, length) = (ATAN.get(z).copied().unwrap_or(0) as u32, LENGTH.get(z).copied().unwrap_or(256) as u32);
    // From the x axis, in 256ths of an eighth of a turn (π is 1024).
    let first = if ay <= ax { angle } else { 512 - angle };
    let turn = if gx >= 0 { first } else { 1024 - first };
    // Bins are a quarter of π wide (256) for four orientations, centred
    // half a bin in.
    let width = 1024 / ORIENTATIONS as u32;
    let b = (turn + 1024 - width / 2) % 1024;
    Some((((b / width) as usize).min(ORIENTATIONS - 1), (b % width) * 256 / width, big * length))
}

/// One row of points: the lumas of `row` (a row of `frame`) at `columns`,
/// each pair of points added to its cell's sum in `grey`.
struct PointRow<'f, 'r> {
    frame: &'r Frame<'f>,
    row: &'f [u8],
    columns: &'r [usize],
    grey: &'r mut [u16; MAX_CELLS],
}

impl RowReader for PointRow<'_, '_> {
    type Output = ();
    // About a hundred rows a frame: loops of their own in every build.
    const LOOPS: Loops = Loops::camera_luma(Loop::Always);

    fn rows_of<P: PixelRead>(self) {
        if let Some(px) = P::pixels(self.row) {
            add_points::<P>(px, self.columns, self.grey);
        }
    }

    #[inline(always)]
    fn general(self) {
        let luma = |x: usize| self.frame.luma_in(self.row, x).unwrap_or(0) as u16;
        for (g, pair) in self.grey.iter_mut().zip(self.columns.chunks_exact(POINTS)) {
            if let [a, b] = *pair {
                *g += luma(a) + luma(b);
            }
        }
    }
}

/// Adds the lumas of the pixels `px` at `columns`, each pair of points to
/// its cell's sum in `grey`. Out of line: inside [`read`] the loop's
/// pointers spill to the stack.
#[inline(never)]
fn add_points<P: PixelRead>(px: &[P::Px], columns: &[usize], grey: &mut [u16; MAX_CELLS]) {
    let luma = |x: usize| px.get(x).map_or(0, |&p| P::px_luma(p)) as u16;
    for (g, pair) in grey.iter_mut().zip(columns.chunks_exact(POINTS)) {
        if let [a, b] = *pair {
            *g += luma(a) + luma(b);
        }
    }
}

// `PointRow` adds its points in pairs.
const _: () = assert!(POINTS == 2);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pixel::PixelFormat;

    #[test]
    fn orientations_and_lengths_are_what_trigonometry_says() {
        // Reason: std's atan2 and hypot are the reference; the bins are
        // centred on (b + 1/2)·45°, so an angle's bin and share follow by
        // hand.
        for deg in 0..360 {
            let t = (deg as f64 + 0.3).to_radians();
            let (gx, gy) = ((100.0 * t.cos()).round() as i32, (100.0 * t.sin()).round() as i32);
            let (bin, f, m) = orientation(gx, gy).unwrap();
            let a = (gy as f64).atan2(gx as f64).rem_euclid(std::f64::consts::PI);
            let want = (a / std::f64::consts::PI * ORIENTATIONS as f64 - 0.5).rem_euclid(ORIENTATIONS as f64);
            let got = bin as f64 + f as f64 / 256.0;
            let d = (got - want).abs().min(ORIENTATIONS as f64 - (got - want).abs());
            assert!(d < 0.01, "{deg}°: bin {bin} + {f}/256 against {want}");
            let length = (gx as f64).hypot(gy as f64);
            assert!(
                (m as f64 / 256.0 - length).abs() < 0.005 * length + 0.01,
                "{deg}°: length {m}/256 against {length}"
            );
        }
        assert_eq!(orientation(0, 0), None);
        assert_eq!(orientation(255, -255).map(|(_, _, m)| m), Some(255 * 362), "the longest, in range");
    }

    #[test]
    fn the_tables_match_the_functions_they_stand_for() {
        // Reason: std's atan, sqrt and ln are the independent reference
        // for the compile-time series.
        for z in 0..=256usize {
            let x = z as f64 / 256.0;
            assert!((ATAN[z] as f64 - x.atan() / std::f64::consts::FRAC_PI_4 * 256.0).abs() <= 0.5 + 1e-9, "atan {z}");
            assert!((LENGTH[z] as f64 - (1.0 + x * x).sqrt() * 256.0).abs() <= 0.5 + 1e-9, "length {z}");
        }
        for (l, &g) in LOG_GREY.iter().enumerate() {
            let want = (l as f64).ln_1p() / 256f64.ln() * 255.0;
            assert!((g as f64 - want).abs() <= 0.5 + 1e-4, "grey {l}: {g} against {want}");
        }
        for d in 1..256u32 {
            assert!((RECIPROCAL[d as usize] as f64 - 65_536.0 / d as f64).abs() <= 0.5, "1/{d}");
        }
    }

    #[test]
    fn the_orientations_are_each_cells_from_its_clamped_neighbours() {
        // Reason: a cross-check with the definition written cell by cell:
        // each cell's orientation shares come from `orientation` of the
        // central differences of its grey neighbours, an edge cell's
        // missing neighbour being itself, the length's share of the lower
        // bin `256 - f` and of the next `f` 256ths (rounded, at most 255).
        // On a noisy frame (every orientation and length), for lattices of
        // 1, 2 and 13 cells and the largest.
        let (w, h) = (97, 83);
        let mut state = 12_345u32;
        let px: Vec<u8> = (0..w * h)
            .map(|_| {
                state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (state >> 24) as u8
            })
            .collect();
        let frame = Frame::packed(&px, w, h, PixelFormat::Gray8).unwrap();
        for n in [1, 2, 13, MAX_CELLS] {
            let mut out = vec![0u8; CHANNELS * n * n];
            assert!(read(&frame, (48.3, 41.7), (1.6, 1.4), n, &mut out));
            let g = |r: usize, c: usize| out[r.min(n - 1) * n + c.min(n - 1)] as i32;
            for r in 0..n {
                for c in 0..n {
                    let gx = g(r, c + 1) - g(r, c.saturating_sub(1));
                    let gy = g(r + 1, c) - g(r.saturating_sub(1), c);
                    let mut want = [0u8; ORIENTATIONS];
                    if let Some((bin, f, m)) = orientation(gx, gy) {
                        let share = |part: u32| ((m * part + 32_768) >> 16).min(255) as u8;
                        want[bin] = share(256 - f);
                        want[(bin + 1) % ORIENTATIONS] = share(f);
                    }
                    let got: Vec<u8> = (0..ORIENTATIONS).map(|k| out[((k + 1) * n + r) * n + c]).collect();
                    assert_eq!(got, want, "{n} cells, cell ({r}, {c})");
                }
            }
        }
    }

    #[test]
    fn a_vertical_edge_fills_the_horizontal_gradient_bins_only() {
        // Reason: a step from dark to light along x has gradients along x
        // (0°), which lie half in bin 3 (centred on 157.5°, wrapping) and
        // half in bin 0 (22.5°); grey is the log of the cells' mean luma,
        // and the gradients are its central differences, by construction.
        let (w, h) = (64, 32);
        let px: Vec<u8> = (0..w * h).map(|i| if i % w < 32 { 40 } else { 200 }).collect();
        let frame = Frame::packed(&px, w, h, PixelFormat::Gray8).unwrap();
        let n = 8;
        let mut out = vec![0u8; CHANNELS * n * n];
        assert!(read(&frame, (32.0, 16.0), (2.0, 2.0), n, &mut out));
        let at = |k: usize, r: usize, c: usize| out[(k * n + r) * n + c];
        for r in 0..n {
            assert_eq!(at(0, r, 0), LOG_GREY[40]);
            assert_eq!(at(0, r, n - 1), LOG_GREY[200]);
            // Points one pixel apart, point j at x = 24 + j, cell c its
            // points 2c and 2c + 1: cells 0 to 3 are dark, 4 to 7 light.
            // Cells 3 and 4 have one dark and one light neighbour, a log
            // grey difference d = 244 − 171 = 73; at 0° half of it goes
            // to bin 0 and half to bin 3, rounded: 37.
            let d = (LOG_GREY[200] - LOG_GREY[40]) as u32;
            assert_eq!(d, 73);
            for c in [3, 4] {
                assert_eq!(at(1, r, c), 37, "bin 0, cell {c}");
                assert_eq!(at(4, r, c), 37, "bin 3, cell {c}");
                assert_eq!(at(2, r, c), 0);
                assert_eq!(at(3, r, c), 0);
            }
            assert_eq!(at(1, r, 2), 0);
            assert_eq!(at(1, r, 5), 0);
        }
        assert!(!read(&frame, (32.0, 16.0), (2.0, 2.0), MAX_CELLS + 1, &mut out));
    }
}
