//! A scale pyramid on the gradient channels: the target's size measured
//! against a learnt view of it at many sizes (DSST's scale pyramid,
//! Danelljan et al. 2014, matched by correlation rather than by a trained
//! filter).
//!
//! Each frame the window about the estimate, [`WINDOW`] times the box, is
//! read on [`CELLS`] x [`CELLS`] cells ([`channels::read`]) at [`SIZES`]
//! sizes [`STEP`] apart, the middle one the box's: a column of the pyramid
//! per size, each channel of it zero-mean and of unit length. The learnt
//! pyramid is the same read of the target's past boxes. Matched at offsets
//! of up to [`REACH`] sizes, the frame's pyramid and the learnt one agree
//! best where the frame's size lines up with the size the target was
//! learnt at: the mean product of their overlapping columns, refined to a
//! fraction of a size by a parabola through the best offset and its
//! neighbours, and the estimate moves part of the way there
//! ([`GradientCue::pyramid_pull`]).
//!
//! Why beside the filters' own scale searches, which compare three sizes
//! each: in place of them it loses, beside them it gains (docs/accuracy.md
//! measures both), so the searches stay and the pyramid follows them. It is
//! part of the gradient filter's cue because it reads the same channels and
//! is asked for by its settings; its state is its own.
//!
//! In integers: the columns are bytes, `i8` in units of `1 / Q` of a
//! channel's length (the largest a unit-length channel of [`CELLS`]²
//! cells, one of five, can hold is 127), and the learnt pyramid is a
//! running mean of them at a fifth, learnt on every fourth sure frame, so
//! that a step of the mean is at least a unit. A frame's pyramid is never
//! stored: each column is matched against the learnt ones as it is read.

use super::GradientCue;
use super::channels::{self, CHANNELS};
use crate::filter::{Particle, scale_estimate};
use crate::frame::Frame;
use crate::geometry::Ellipse;
use crate::scalar::{Real, exp, sqrt};

/// Cells per side of each column's lattice.
pub const CELLS: usize = 5;
/// Sizes in the pyramid (odd: the middle one is the box's).
pub const SIZES: usize = 13;
/// The relative step between neighbouring sizes.
pub const STEP: Real = 1.03;
/// The window's side as a multiple of the box's.
pub const WINDOW: Real = 2.0;
/// The largest offset, in sizes, at which the pyramids are matched.
pub const REACH: usize = 2;
/// A column's values: the channels' cells.
const COLUMN: usize = CHANNELS * CELLS * CELLS;
/// A column value's unit is `1 / Q` of a channel's length: a channel of
/// unit length is a fifth of its column's energy, so a cell of it is at
/// most `1 / √5` long, `Q / √5` is 127.
const Q: Real = 284.0;
/// A multiple of every offset's count of overlapping columns
/// (`SIZES − |k|`, `k` up to `REACH`): their product.
const OVERLAPS: i32 = {
    let (mut p, mut k) = (1, 0);
    while k <= REACH {
        p *= (SIZES - k) as i32;
        k += 1;
    }
    p
};
/// Sure frames between two that the pyramid learns from.
const LEARN_EVERY: u8 = 4;

/// The sizes' factors, smallest first: `STEP^(i − SIZES / 2)`.
const FACTORS: [Real; SIZES] = factors();

// Evaluated at compile time only (for a `const`): an index out of range
// would stop the build, never the device.
#[allow(clippy::indexing_slicing)]
const fn factors() -> [Real; SIZES] {
    let mut out = [1.0; SIZES];
    let mut i = SIZES / 2;
    while i + 1 < SIZES {
        out[i + 1] = out[i] * STEP;
        out[SIZES - 2 - i] = out[SIZES - 1 - i] / STEP;
        i += 1;
    }
    out
}

/// The learnt pyramid: a column per size, smallest first.
#[derive(Clone, Debug)]
pub(crate) struct ScalePyramid {
    learnt: [[i8; COLUMN]; SIZES],
    /// Whether `learnt` holds a target's pyramid.
    learned: bool,
    /// Sure frames seen since the last one learnt.
    waiting: u8,
}

/// Reads column `i` of the pyramid about `e` into `out`: the cells, each
/// channel zero-mean and of unit length, in units of `1 / Q`. False where
/// the read does not fit (never for the sizes here).
fn column(frame: &Frame<'_>, e: &Ellipse, i: usize, out: &mut [i8; COLUMN]) -> bool {
    let f = FACTORS.get(i).copied().unwrap_or(1.0) * 2.0 * WINDOW / CELLS as Real;
    let mut cells = [0u8; COLUMN];
    if !channels::read(frame, (e.cx, e.cy), (e.hx * f, e.hy * f), CELLS, &mut cells) {
        return false;
    }
    const PLANE: usize = CELLS * CELLS;
    for (ch, o) in cells.chunks_exact(PLANE).zip(out.chunks_exact_mut(PLANE)) {
        // In units of 1/PLANE: `PLANE · c − Σ c` is the cell less the mean.
        let sum: i32 = ch.iter().map(|&c| c as i32).sum();
        let deviation = |c: u8| PLANE as i32 * c as i32 - sum;
        let energy: u32 = ch.iter().map(|&c| deviation(c).unsigned_abs().pow(2)).sum();
        // A flat channel has no layout: its column values are 0.
        let gain = if energy > 0 { (Q / sqrt(CHANNELS as Real * energy as Real) * 65_536.0) as i32 } else { 0 };
        for (o, &c) in o.iter_mut().zip(ch) {
            *o = ((deviation(c) * gain + 32_768) >> 16).max(-127).min(127) as i8;
        }
    }
    true
}

/// The sum of products of two columns.
fn dot(a: &[i8; COLUMN], b: &[i8; COLUMN]) -> i32 {
    a.iter().zip(b).map(|(&a, &b)| a as i32 * b as i32).sum()
}

/// `round(t / 5)` for `|t|` up to 5 · 127, by a multiplication (cores
/// without a divider), halves away from zero.
fn fifth(t: i32) -> i8 {
    let m = (t.unsigned_abs() * 13_107 + 32_768) >> 16;
    (if t < 0 { -(m as i32) } else { m as i32 }) as i8
}

impl ScalePyramid {
    /// No pyramid learnt: it moves nothing until it has learnt one.
    pub(crate) const fn new() -> Self {
        ScalePyramid { learnt: [[0; COLUMN]; SIZES], learned: false, waiting: 0 }
    }

    /// Forgets any target and, where the pyramid is on, learns the one
    /// about `e`.
    pub(crate) fn start(&mut self, c: &GradientCue, frame: &Frame<'_>, e: &Ellipse) {
        self.learned = c.pyramid_pull > 0.0 && self.learn(frame, e, true);
        self.waiting = 0;
    }

    /// Reads the pyramid about `e` and takes it (`fresh`) or moves the
    /// learnt one a fifth of the way to it. False where a column could not
    /// be read, which `channels::read` does only for lattices larger than
    /// its own (never these): a fresh pyramid is then not counted as
    /// learnt.
    #[inline(never)]
    fn learn(&mut self, frame: &Frame<'_>, e: &Ellipse, fresh: bool) -> bool {
        let mut col = [0i8; COLUMN];
        for (i, learnt) in self.learnt.iter_mut().enumerate() {
            if !column(frame, e, i, &mut col) {
                return false;
            }
            for (l, &z) in learnt.iter_mut().zip(&col) {
                *l = if fresh { z } else { fifth(4 * *l as i32 + z as i32) };
            }
        }
        true
    }

    /// The frame's size relative to the learnt one's, in sizes: the offset
    /// at which the pyramids agree best, refined by a parabola. `None`
    /// before a pyramid is learnt.
    #[inline(never)]
    fn offset(&self, frame: &Frame<'_>, e: &Ellipse) -> Option<Real> {
        if !self.learned {
            return None;
        }
        // `agree[REACH + k]`: the products of the frame's column at size
        // `j` and the learnt one at `j − k`, summed over the columns that
        // overlap.
        let mut agree = [0i32; 2 * REACH + 1];
        let mut col = [0i8; COLUMN];
        for j in 0..SIZES {
            if !column(frame, e, j, &mut col) {
                return None;
            }
            for (a, k) in agree.iter_mut().zip(-(REACH as i32)..) {
                if let Some(learnt) = self.learnt.get((j as i32 - k) as usize) {
                    *a += dot(learnt, &col);
                }
            }
        }
        // The mean over each offset's overlapping columns (`SIZES − |k|`),
        // times OVERLAPS, in integers; no offset unless another agrees
        // better (a flat window agrees with nothing).
        for (i, a) in agree.iter_mut().enumerate() {
            *a *= OVERLAPS / (SIZES - i.abs_diff(REACH)) as i32;
        }
        let (mut best, mut top) = (REACH, agree.get(REACH).copied().unwrap_or(0));
        for (i, &a) in agree.iter().enumerate() {
            if a > top {
                (best, top) = (i, a);
            }
        }
        let mut k = best as Real - REACH as Real;
        if let (Some(&l), Some(&h)) = (best.checked_sub(1).and_then(|b| agree.get(b)), agree.get(best + 1)) {
            let curve = l - 2 * top + h;
            if curve < 0 {
                k += (l - h) as Real / (2 * curve) as Real;
            }
        }
        Some(k)
    }

    /// Scales the estimate and its particles `pyramid_pull` of the way (in
    /// log size) to the size the pyramids agree on.
    pub(crate) fn place<const N: usize>(
        &self,
        c: &GradientCue,
        frame: &Frame<'_>,
        (ellipse, particles): (&mut Ellipse, &mut [Particle; N]),
    ) {
        if !(c.pyramid_pull > 0.0) {
            return;
        }
        if let Some(k) = self.offset(frame, ellipse) {
            let f = exp(c.pyramid_pull * k * LN_STEP);
            scale_estimate(ellipse, particles, (f, f));
        }
    }

    /// On every fourth frame more confident than
    /// [`GradientCue::pyramid_learn_above`], moves the learnt pyramid a
    /// fifth of the way to the one about `e`.
    pub(crate) fn adapt(&mut self, c: &GradientCue, frame: &Frame<'_>, e: &Ellipse, confidence: Real) {
        if !(self.learned && c.pyramid_pull > 0.0 && confidence > c.pyramid_learn_above) {
            return;
        }
        self.waiting = self.waiting.saturating_add(1);
        if self.waiting < LEARN_EVERY {
            return;
        }
        self.waiting = 0;
        self.learn(frame, e, false);
    }
}

/// `ln STEP`, for the factor of a fractional offset.
const LN_STEP: Real = 0.029_558_802;

// OVERLAPS is a multiple of every overlap, and an offset's mean (a column's
// products are at most about Q², the columns of unit length) times it fits
// 32 bits.
const _: () = assert!(REACH < SIZES / 2);
const _: () = assert!((2.0 * Q * Q) as i64 * OVERLAPS as i64 <= i32::MAX as i64);

// A channel's energy, `Σ (PLANE · c − Σ c)²`, fits the 32 bits it is
// summed in.
const _: () = assert!(CELLS * CELLS * (CELLS * CELLS * 255) * (CELLS * CELLS * 255) <= u32::MAX as usize);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pixel::PixelFormat;

    const W: usize = 320;
    const H: usize = 240;
    const CENTRE: (Real, Real) = (160.0, 120.0);

    /// Random 8x8 blocks of grey 30 to 225 about the centre, the content
    /// scaled by `g` about it: a target `g` times the size it had at 1.
    fn scaled(g: f64) -> Vec<u8> {
        let mut next = crate::testing::lcg(5);
        let levels: Vec<u8> = (0..64 * 64).map(|_| 30 + (next() >> 24) as u8 % 196).collect();
        let mut px = vec![0u8; W * H];
        for y in 0..H {
            for x in 0..W {
                let u = (x as f64 + 0.5 - CENTRE.0 as f64) / g / 8.0 + 32.0;
                let v = (y as f64 + 0.5 - CENTRE.1 as f64) / g / 8.0 + 32.0;
                px[y * W + x] = levels[(v.floor() as usize % 64) * 64 + u.floor() as usize % 64];
            }
        }
        px
    }

    fn frame(px: &[u8]) -> Frame<'_> {
        Frame::packed(px, W, H, PixelFormat::Gray8).unwrap()
    }

    fn target() -> Ellipse {
        Ellipse { cx: CENTRE.0, cy: CENTRE.1, hx: 20.0, hy: 16.0 }
    }

    fn learnt(px: &[u8]) -> ScalePyramid {
        let mut p = ScalePyramid::new();
        p.start(&GradientCue::MEASURED, &frame(px), &target());
        assert!(p.learned);
        p
    }

    #[test]
    fn the_tables_match_the_functions_they_stand_for() {
        // Reason: std's powf and ln are the independent reference.
        for (i, &f) in FACTORS.iter().enumerate() {
            let e = (STEP as f64).powf(i as f64 - (SIZES / 2) as f64);
            assert!((f as f64 - e).abs() < 1e-6, "size {i}: {f} against {e}");
        }
        // LN_STEP is written out (`ln` is not a `const fn`): it must follow STEP.
        assert!((LN_STEP as f64 - (STEP as f64).ln()).abs() < 1e-7);
    }

    #[test]
    fn a_fifth_rounds_as_the_division_does() {
        // Reason: f64 division rounded half away from zero, at every input.
        for t in -5 * 127..=5 * 127 {
            assert_eq!(fifth(t) as f64, (t as f64 / 5.0).round(), "{t}");
        }
    }

    #[test]
    fn a_column_is_zero_mean_and_of_unit_length_in_each_channel() {
        // Reason: the definition (module docs): each channel's values sum to
        // 0 and their squares to Q²/5, up to rounding each value by half a
        // unit.
        let px = scaled(1.0);
        let mut col = [0i8; COLUMN];
        assert!(column(&frame(&px), &target(), SIZES / 2, &mut col));
        for ch in col.chunks_exact(CELLS * CELLS) {
            let sum: i32 = ch.iter().map(|&v| v as i32).sum();
            let energy: i32 = ch.iter().map(|&v| v as i32 * v as i32).sum();
            assert!(sum.abs() <= (CELLS * CELLS / 2) as i32, "sum {sum}");
            let unit = Q * Q / CHANNELS as Real;
            assert!((energy as Real - unit).abs() < 0.05 * unit, "energy {energy} against {unit}");
        }
    }

    #[test]
    fn the_pyramid_measures_a_target_that_grew_or_shrank() {
        // Reason: generated scene with known scale: the texture learnt at 1,
        // then shown 1.03² and 1.03⁻² times as large about the same centre;
        // a target g times larger fills the frame's window at size j as the
        // learnt one filled size j − log(g) / log(STEP), an offset of +2 or
        // −2 sizes (within a third of a size, the lattice's blur).
        let p = learnt(&scaled(1.0));
        for (g, expected) in [(1.0609, 2.0), (1.0 / 1.0609, -2.0), (1.0, 0.0)] {
            let px = scaled(g);
            let k = p.offset(&frame(&px), &target()).unwrap();
            assert!((k - expected).abs() < 0.34, "scale {g}: offset {k} against {expected}");
        }
    }

    #[test]
    fn the_estimate_moves_the_pull_of_the_way_and_a_flat_frame_moves_nothing() {
        // Reason: `place` scales by STEP^(pull · k): with the offset measured
        // near +2 and the measured pull 0.2, about 1.03^0.4 (1.2%) larger;
        // a flat frame has no layout, and every offset agrees equally (0),
        // so the size stays.
        let p = learnt(&scaled(1.0));
        let c = GradientCue::MEASURED;
        let mut particles = [Particle::at(&target()); 4];
        let mut e = target();
        let px = scaled(1.0609);
        p.place(&c, &frame(&px), (&mut e, &mut particles));
        let grown = e.hx / 20.0;
        assert!((grown - 1.03f32.powf(0.4)).abs() < 0.003, "grew by {grown}");
        assert_eq!(particles[0].hx, e.hx);
        let flat = vec![128u8; W * H];
        let mut e = target();
        p.place(&c, &frame(&flat), (&mut e, &mut particles));
        assert_eq!((e.hx, e.hy), (20.0, 16.0));
    }

    #[test]
    fn learning_moves_the_pyramid_a_fifth_of_the_way_on_every_fourth_sure_frame() {
        // Reason: the documented schedule: three sure frames change nothing,
        // the fourth moves each value to round((4 · old + new) / 5); unsure
        // frames do not count.
        let old = scaled(1.0);
        let new = scaled(1.0609);
        let mut p = learnt(&old);
        let before = p.learnt;
        let c = GradientCue::MEASURED;
        for _ in 0..3 {
            p.adapt(&c, &frame(&new), &target(), 0.95);
            p.adapt(&c, &frame(&new), &target(), 0.5);
        }
        assert_eq!(p.learnt, before);
        p.adapt(&c, &frame(&new), &target(), 0.95);
        let mut fresh = ScalePyramid::new();
        fresh.start(&c, &frame(&new), &target());
        for ((l, b), f) in p.learnt.iter().flatten().zip(before.iter().flatten()).zip(fresh.learnt.iter().flatten()) {
            assert_eq!(*l as f64, ((4 * *b as i32 + *f as i32) as f64 / 5.0).round());
        }
    }
}
