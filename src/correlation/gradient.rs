//! A correlation filter on gradient channels over a wide window: grey and
//! four gradient orientations ([`super::channels`]) on cells about a
//! thirteenth of the box, learnt jointly over a window 2.5 times the box and
//! read over one [`READ`] cells across (about 3.6 times the box).
//!
//! Learning is CSR-DCF's (Lukežič et al. 2017): each learning frame the
//! channels' joint closed-form filter `H_k = G X_k* / (Σ_j |X_j|² + λ)` is
//! solved in the Fourier domain on [`LEARN`] x [`LEARN`] cells (each channel
//! centred, tapered by a Hann window; grey scaled to unit energy and the
//! orientations together to unit energy), turned back into space, **cut to
//! the box's support** ([`SUPPORT`] x [`SUPPORT`] cells) and kept as a
//! running mean of such cut filters. Cutting is what lets the window be
//! wide: the filter learns the target against its surroundings without
//! answering to them (the boundary effects BACF and CSR-DCF remove). The
//! learning window is taken from the cells this frame's search read where
//! it lies within them (to the nearest cell), so that learning reads no
//! pixels of its own.
//!
//! Reading is in space, where the cut filter is small: the response at a
//! shift is the sum over channels and support cells of the filter times the
//! window's cells (normalised as learnt, over the whole read window),
//! weighted by how far the shift is from the window's centre. It is
//! evaluated where it is needed: at every shift of the 2 x 2-pooled filter
//! over the 2 x 2-pooled cells (a smoothed response on every second shift,
//! at a quarter of the products; its peak-to-sidelobe ratio is the
//! filter's), then at full resolution about the pooled peak, climbing to
//! the best shift; and, where [`GradientCue::blend`] asks, at each
//! particle. No response FFT runs, and only the learning frames transform
//! (every [`GradientCue::learn_every`]-th confident frame). The sums are
//! of integer products (the cells are bytes, the filter is kept in 16 bits
//! a channel), exact on every core and as fast without an FPU as with one.
//!
//! After its own scale search the cue sizes the estimate by its scale
//! pyramid where the `scale-pyramid` feature builds it
//! ([`super::pyramid`], [`GradientCue::pyramid_pull`]).
//!
//! Memory: the read window's cells as bytes ([`READ`]² x 5) and the filter
//! (16 bits a weight and a scale per channel, [`SUPPORT`]² x 5 weights)
//! live in the tracker; a learning frame's spectrum, energy sum and cut
//! filter live in memory the tracker lends (its foreground map's), and a
//! second spectrum in the read window's cells past the learning window's,
//! free while it learns (docs/performance.md).

use super::GradientCue;
use super::channels::{self, CHANNELS, MAX_CELLS};
use super::filter::{peak, round, sub_cell, taper};
#[cfg(feature = "scale-pyramid")]
use super::pyramid::ScalePyramid;
use super::series::sin;
use crate::cue::{Cue, Freedom, Verdict};
use crate::filter::{Particle, scale_estimate, shift_estimate};
use crate::frame::Frame;
use crate::geometry::Ellipse;
use crate::scalar::{Real, sqrt};
use microfft::Complex32;

/// The learning lattice, in cells per side (a power of two, for the FFT).
pub const LEARN: usize = 32;
/// The read lattice, in cells per side.
pub const READ: usize = MAX_CELLS;
/// The filter's side, in cells: the box's support in the learning window.
pub const SUPPORT: usize = 13;
/// The support's half side.
const HALF: usize = SUPPORT / 2;
/// The learning window's side as a multiple of the box's: the box is
/// `LEARN / WINDOW`, about 13 cells, across.
const WINDOW: Real = 2.5;
/// The regulariser `λ` of the joint solve. The channels have unit energy
/// (grey, and the orientations together), so a bin of `Σ |X|²` averages
/// about 2 by Parseval; λ = 0.1 keeps weak frequencies from dominating.
const LAMBDA: Real = 0.1;
/// The pooled read lattice's side: 2 x 2 cells to a pooled cell.
const POOLED: usize = READ / 2;
/// The pooled filter's side (the support and a row and column of zeros).
const POOLED_SUPPORT: usize = SUPPORT.div_ceil(2);
/// How far, relatively, the learning window's cells may differ in size
/// from the read window's for it to be taken from there.
const SAME_CELL: Real = 0.03;
/// How many times the search about the coarse best may move to a
/// better neighbour.
const CLIMB: usize = 4;
/// The σ of the Gaussian peak the filter is trained to answer with, in cells.
const PEAK_SIGMA: f64 = 1.0;
/// The half spectrum's columns: 0 to `LEARN / 2`.
const COLS: usize = LEARN / 2 + 1;

/// Half a spectrum of the learning lattice, column by column: `[v][u]`
/// holds horizontal frequency `v` (0 to `LEARN / 2`) and vertical frequency
/// `u`, so that each column transforms in place.
type Spectrum = [[Complex32; LEARN]; COLS];
/// One channel's filter in space, row by row.
type Cut = [[Real; SUPPORT]; SUPPORT];
/// A number per bin of the half spectrum, laid out as [`Spectrum`].
type Bins = [[Real; LEARN]; COLS];

/// The Hann taper of the learning lattice, computed at compile time.
const TAPER: [Real; LEARN] = taper();

/// The weight of a shift in the read window: the Hann taper of a window
/// twice the learning window's side (`2 · LEARN` cells, 5 times the box) at
/// the shift's cell, `sin²(π (LEARN + s + ½) / (2 · LEARN))` for a shift of
/// `s` cells, indexed by `s + READ / 2`. A response far from the window's
/// centre counts for less: the target moves little between frames, and a
/// look-alike at the window's edge is more likely than the target there
/// (the cosine window Siamese trackers put on their responses).
const SHIFT_WEIGHT: [Real; READ] = shift_weight(1);

/// The weight of a shift after a sure frame ([`GradientCue::narrow_above`]):
/// [`SHIFT_WEIGHT`] squared, a window about 0.7 as wide (at half its height
/// about 11 cells from the centre rather than 15.5). While the
/// estimate is sure, the target is where it was, give or take its motion,
/// and a look-alike a box away is not it; after a frame that is not (or one
/// that moves with the scene around it, as background does), the target
/// may be wherever it went meanwhile, and the wide window lets the filter
/// find it there.
const SURE_SHIFT_WEIGHT: [Real; READ] = shift_weight(2);

/// Whether a frame of `verdict` is sure enough for the next frame's
/// response to be read through [`SURE_SHIFT_WEIGHT`]
/// ([`GradientCue::narrow_above`]).
fn sure(c: &GradientCue, verdict: Verdict) -> bool {
    verdict.confidence > c.narrow_above && !verdict.moves_with_scene
}

/// The Hann taper of [`SHIFT_WEIGHT`] to the power `power`.
// Evaluated at compile time only (for a `const`): an index out of range
// would stop the build, never the device.
#[allow(clippy::indexing_slicing)]
const fn shift_weight(power: u32) -> [Real; READ] {
    let mut out = [0.0; READ];
    let mut i = 0;
    while i < READ {
        let cell = (LEARN + i) as f64 - (READ / 2) as f64;
        let s = sin(core::f64::consts::PI * (cell + 0.5) / (2 * LEARN) as f64);
        let (mut w, mut k) = (1.0, 0);
        while k < power {
            w *= s * s;
            k += 1;
        }
        out[i] = w as Real;
        i += 1;
    }
    out
}

/// The spectrum of the Gaussian peak at lattice point 0 (wrapped) along one
/// axis of the learning lattice (real and even, so real; the 2-D one is
/// `PEAK[u] · PEAK[v]`), computed at compile time.
const PEAK: [Real; LEARN] = peak(PEAK_SIGMA);

/// How a window's cells are normalised: channel `k`'s value `v` counts as
/// `gain[k] · (v − mean[k])` (grey as `ln(1 + luma)`).
#[derive(Copy, Clone, Debug, Default)]
struct Norm {
    gain: [Real; CHANNELS],
    mean: [Real; CHANNELS],
}

/// How the filter's integer sums over a window's cells become its
/// response: `Σ_k f_k · acc_k − m`, where `acc_k` is channel `k`'s sum of
/// weights times cells, `f_k` the channel's gain times its weights' scale,
/// and `m` the channels' means' share (`Σ_k f_k · mean[k] · Σ weights_k`),
/// the same at every shift. In integers up to the last step (one
/// conversion a shift: the Cortex-M0+'s floating point is in software):
/// `factor[k]` is `f_k` in units of `1 / q`, the largest ±2^15, `offset`
/// is `m` in the same units, and the response is
/// `((Σ_k factor[k] · acc_k − offset) >> READING_SHIFT) · unit`.
#[derive(Copy, Clone, Debug, Default)]
struct Reading {
    factor: [i32; CHANNELS],
    offset: i64,
    unit: Real,
}

/// The bits a [`Reading`]'s sum drops before its conversion. The sum less
/// the offset is `Σ_k factor[k] · Σ w (cell − mean[k])`, at most
/// `5 · 2^15 · 169 · 32,767 · 255 < 2^48` in magnitude (the pooled filter's
/// 49 weights sum the full one's 169), so what is left fits an `i32`.
const READING_SHIFT: u32 = 17;

/// The `n` x `n` cells of a buffer of [`CHANNELS`] planes
/// ([`channels::read`]'s layout).
#[derive(Copy, Clone)]
struct Lattice<'a> {
    cells: &'a [u8],
    n: usize,
}

impl<'a> Lattice<'a> {
    /// All `n` x `n` cells of `cells`.
    fn whole(cells: &'a [u8], n: usize) -> Self {
        Lattice { cells, n }
    }

    /// Row `r` of channel `k` (empty outside the buffer).
    fn row(&self, k: usize, r: usize) -> &'a [u8] {
        let start = (k * self.n + r) * self.n;
        self.cells.get(start..start + self.n).unwrap_or(&[])
    }
}

/// What this frame's window showed: where it was, and where its response
/// peaks.
#[derive(Copy, Clone, Debug)]
struct Seen {
    centre: (Real, Real),
    /// Cell side, pixels (horizontal, vertical).
    cell: (Real, Real),
    reading: Reading,
    /// The response's peak, the peak's offset from `centre` in pixels, and
    /// the peak-to-sidelobe ratio over the coarse grid.
    peak: Real,
    at: (Real, Real),
    psr: Real,
}

/// The gradient filter: the running mean of cut filters, and the working
/// memory for one window's cells.
#[derive(Clone, Debug)]
pub(crate) struct GradientFilter {
    /// The running mean of cut filters in integers, each channel scaled so
    /// that its largest weight is ±32,767 (a window's response is then
    /// sums of integer products, exact and alike on every core, and on
    /// cores without an FPU as fast as on those with one): the weights,
    /// `Σ` of each channel's weights (for the means' share of a response),
    /// and each channel's scale back.
    weights: [[[i16; SUPPORT]; SUPPORT]; CHANNELS],
    sums: [i32; CHANNELS],
    scales: [Real; CHANNELS],
    /// Whether the weights hold a learnt filter.
    learned: bool,
    /// Confident frames seen since the last one learnt.
    waiting: u16,
    /// Whether this frame's response, as `place` read it, fell under
    /// [`GradientCue::relearn_below`] (until `adapt` has seen it).
    unlike: bool,
    /// Whether the window first learnt was all grey levels
    /// ([`GradientCue::grey_pull`]).
    grey: bool,
    /// Whether the last frame was sure ([`GradientCue::narrow_above`]): the
    /// response is then weighted by [`SURE_SHIFT_WEIGHT`].
    sure: bool,
    /// Where `cells` holds this frame's read window: its centre and cell
    /// size (cleared once the frame is adapted to).
    window: Option<((Real, Real), (Real, Real))>,
    /// The read window's cells ([`channels::read`]'s layout); the learning
    /// window's while one is learnt.
    cells: [u8; CHANNELS * READ * READ],
    /// The target's scale pyramid on the same channels.
    #[cfg(feature = "scale-pyramid")]
    pyramid: ScalePyramid,
}

/// Cell side for a box of half axes `(hx, hy)`, pixels.
fn cell_size((hx, hy): (Real, Real)) -> (Real, Real) {
    (2.0 * hx * WINDOW / LEARN as Real, 2.0 * hy * WINDOW / LEARN as Real)
}

/// A channel's value at a cell, as a number.
#[inline(always)]
fn value(v: u8) -> Real {
    v as Real
}

/// The sum of products of one row of weights and one row of cells,
/// written out: the firmware is built for size, which keeps loops rolled,
/// and this is the innermost loop of every response (a third of the
/// instructions the rolled loop takes).
#[inline(always)]
fn dot(w: &[i16; SUPPORT], v: &[u8; SUPPORT]) -> i32 {
    let [w0, w1, w2, w3, w4, w5, w6, w7, w8, w9, w10, w11, w12] = *w;
    let [v0, v1, v2, v3, v4, v5, v6, v7, v8, v9, v10, v11, v12] = *v;
    let p = |w: i16, v: u8| w as i32 * v as i32;
    p(w0, v0)
        + p(w1, v1)
        + p(w2, v2)
        + p(w3, v3)
        + p(w4, v4)
        + p(w5, v5)
        + p(w6, v6)
        + p(w7, v7)
        + p(w8, v8)
        + p(w9, v9)
        + p(w10, v10)
        + p(w11, v11)
        + p(w12, v12)
}

// `dot` is written for this support.
const _: () = assert!(SUPPORT == 13);

/// [`dot`] for the pooled filter's rows.
#[inline(always)]
fn pooled_dot(w: &[i32; POOLED_SUPPORT], v: &[u8; POOLED_SUPPORT]) -> i32 {
    let [w0, w1, w2, w3, w4, w5, w6] = *w;
    let [v0, v1, v2, v3, v4, v5, v6] = *v;
    let p = |w: i32, v: u8| w * v as i32;
    p(w0, v0) + p(w1, v1) + p(w2, v2) + p(w3, v3) + p(w4, v4) + p(w5, v5) + p(w6, v6)
}

/// The filter `weights` (rows of `S` weights, a channel each) read as
/// `reading` over the `n` x `n` cells `cells` with its top-left cell at
/// `(top, left)`: each channel's integer sum of products, row by row with
/// `dot`, then `Σ_k factor[k] · acc_k − offset`. `None` where the filter
/// leaves the cells. Shared by the full filter and the pooled one.
#[inline(always)]
fn products<W, const S: usize>(
    weights: &[[[W; S]; S]; CHANNELS],
    (cells, n): (&[u8], usize),
    reading: &Reading,
    (top, left): (usize, usize),
    dot: impl Fn(&[W; S], &[u8; S]) -> i32,
) -> Option<Real> {
    let mut out = -reading.offset;
    for (k, (weights, &factor)) in weights.iter().zip(reading.factor.iter()).enumerate() {
        let plane = cells.get(k * n * n..(k + 1) * n * n)?;
        let mut acc = 0i32;
        for (r, weights) in weights.iter().enumerate() {
            let start = (top + r) * n + left;
            let row: &[u8; S] = plane.get(start..start + S)?.try_into().ok()?;
            acc += dot(weights, row);
        }
        out += factor as i64 * acc as i64;
    }
    Some((out >> READING_SHIFT) as i32 as Real * reading.unit)
}

// `pooled_dot` is written for this support; the pooled lattice and the
// padded filter's origin are whole pooled cells.
const _: () = assert!(POOLED_SUPPORT == 7 && READ.is_multiple_of(2) && (READ / 2 - HALF - 1).is_multiple_of(2));

impl GradientFilter {
    /// An empty filter (it answers nothing until it has learnt a window).
    pub(crate) const fn new() -> Self {
        GradientFilter {
            weights: [[[0; SUPPORT]; SUPPORT]; CHANNELS],
            sums: [0; CHANNELS],
            scales: [0.0; CHANNELS],
            learned: false,
            waiting: 0,
            unlike: false,
            grey: false,
            sure: false,
            window: None,
            cells: [0; CHANNELS * READ * READ],
            #[cfg(feature = "scale-pyramid")]
            pyramid: ScalePyramid::new(),
        }
    }

    /// The weights of the read window's shifts this frame: narrower after
    /// a sure frame.
    fn shift_weights(&self) -> &'static [Real; READ] {
        if self.sure { &SURE_SHIFT_WEIGHT } else { &SHIFT_WEIGHT }
    }

    /// How the filter reads a window's cells normalised by `norm`.
    fn reading(&self, norm: &Norm) -> Reading {
        let (mut factors, mut offset) = ([0.0 as Real; CHANNELS], 0.0 as Real);
        for (k, factor) in factors.iter_mut().enumerate() {
            let at = |v: &[Real; CHANNELS]| v.get(k).copied().unwrap_or(0.0);
            *factor = at(&norm.gain) * at(&self.scales);
            offset += *factor * at(&norm.mean) * self.sums.get(k).copied().unwrap_or(0) as Real;
        }
        let largest = factors.iter().fold(0.0 as Real, |m, f| m.max(f.abs()));
        if !(largest > 0.0) {
            return Reading::default();
        }
        let q = 32_768.0 / largest;
        let mut out =
            Reading { offset: (offset * q) as i64, unit: (1u32 << READING_SHIFT) as Real / q, ..Reading::default() };
        for (f, &v) in out.factor.iter_mut().zip(factors.iter()) {
            *f = round(v * q);
        }
        out
    }

    /// The filter's response to the `n` x `n` cells `cells`, read as
    /// `reading`, with its support's top-left cell at `(top, left)`; `None`
    /// where the support leaves the cells.
    fn response(&self, cells: &[u8], n: usize, reading: &Reading, top: i32, left: i32) -> Option<Real> {
        if top < 0 || left < 0 || top as usize + SUPPORT > n || left as usize + SUPPORT > n {
            return None;
        }
        // At most 169 · 32,767 · 255 in magnitude a channel: within an i32.
        products(&self.weights, (cells, n), reading, (top as usize, left as usize), dot)
    }

    /// The response in the read window at a shift of `(sr, sc)` cells from
    /// its centre.
    fn at_shift(&self, reading: &Reading, sr: i32, sc: i32) -> Option<Real> {
        let origin = (READ / 2 - HALF) as i32;
        let table = self.shift_weights();
        let weight = |s: i32| table.get((s + (READ / 2) as i32) as usize).copied().unwrap_or(0.0);
        Some(self.response(&self.cells, READ, reading, origin + sr, origin + sc)? * weight(sr) * weight(sc))
    }

    /// The coarse search: the response of the 2 x 2-pooled filter to the
    /// read window's 2 x 2-pooled cells at every pooled shift, weighted as
    /// [`Self::at_shift`] weights the shift it stands for. The best pooled
    /// shift (in pooled cells from the centre) and the peak-to-sidelobe
    /// ratio over all of them.
    fn coarse(&self, reading: &Reading, work: &mut [u16]) -> Option<((i32, i32), Real)> {
        // Pooled cell `p` holds the window's cells `2p` and `2p + 1`; the
        // filter is padded with a row and a column of zeros before its
        // first, so that at an even shift its padded top-left cell starts
        // a pooled cell.
        const ORIGIN: usize = (READ / 2 - HALF - 1) / 2;
        let (weights, cells) = pooled_room(work)?;
        for (k, pooled) in cells.chunks_exact_mut(POOLED * POOLED).enumerate() {
            let plane = self.cells.get(k * READ * READ..(k + 1) * READ * READ)?;
            for (r, out) in pooled.chunks_exact_mut(POOLED).enumerate() {
                let (a, b) = (plane.get(2 * r * READ..)?, plane.get((2 * r + 1) * READ..)?);
                for (c, v) in out.iter_mut().enumerate() {
                    let cell = |row: &[u8], i: usize| row.get(i).copied().unwrap_or(0) as u16;
                    let sum = cell(a, 2 * c) + cell(a, 2 * c + 1) + cell(b, 2 * c) + cell(b, 2 * c + 1);
                    *v = ((sum + 2) >> 2) as u8;
                }
            }
        }
        for (pooled, full) in weights.iter_mut().zip(self.weights.iter()) {
            for row in pooled.iter_mut() {
                row.fill(0);
            }
            // Row and column `r` of the filter are `r + 1` of the padded
            // one, in pooled cell `(r + 1) / 2`.
            for (r, row) in full.iter().enumerate() {
                let Some(out) = pooled.get_mut(r.div_ceil(2)) else { continue };
                for (c, &w) in row.iter().enumerate() {
                    if let Some(v) = out.get_mut(c.div_ceil(2)) {
                        *v += w as i32;
                    }
                }
            }
        }
        let span = ORIGIN as i32;
        let table = self.shift_weights();
        let weight = |t: i32| table.get((2 * t + (READ / 2) as i32) as usize).copied().unwrap_or(0.0);
        let (mut best, mut at) = (Real::MIN, (0, 0));
        let (mut s1, mut s2, mut count) = (0.0 as Real, 0.0 as Real, 0u32);
        for tr in -span..=span {
            for tc in -span..=span {
                let corner = ((ORIGIN as i32 + tr) as usize, (ORIGIN as i32 + tc) as usize);
                // At most 49 · 4 · 32,767 · 255 in magnitude a channel:
                // within an i32.
                let v = products(weights, (cells, POOLED), reading, corner, pooled_dot)? * weight(tr) * weight(tc);
                (s1, s2, count) = (s1 + v, s2 + v * v, count + 1);
                if v > best {
                    (best, at) = (v, (tr, tc));
                }
            }
        }
        let mean = s1 / count as Real;
        let sd = sqrt((s2 / count as Real - mean * mean).max(0.0));
        Some((at, if sd > 0.0 { (best - mean) / sd } else { 0.0 }))
    }

    /// Reads the window around `centre` for a box of half axes `half_axes`
    /// and finds its response's peak; `None` before anything is learnt, or
    /// for a window of one grey level.
    fn look(
        &mut self,
        frame: &Frame<'_>,
        centre: (Real, Real),
        half_axes: (Real, Real),
        work: &mut [u16],
    ) -> Option<Seen> {
        if !self.learned {
            return None;
        }
        let cell = cell_size(half_axes);
        self.window = None;
        if !channels::read(frame, centre, cell, READ, &mut self.cells) {
            return None;
        }
        self.window = Some((centre, cell));
        let reading = self.reading(&normalise(Lattice::whole(&self.cells, READ), None)?);
        // The coarse search, on 2 x 2-pooled cells and weights: each pooled
        // shift answers for the four shifts it covers (a smoothed response
        // sampled every second shift, so that a sharp peak between the
        // samples is not missed), at a quarter of the products.
        let (coarse, psr) = self.coarse(&reading, work)?;
        // Then every shift about the coarse best, climbing while the best
        // is on the edge of those evaluated.
        let mut at = (2 * coarse.0, 2 * coarse.1);
        let mut best = self.at_shift(&reading, at.0, at.1)?;
        // The 3 x 3 shifts about `at` (outside the window: the least).
        let mut around = [[Real::MIN; 3]; 3];
        let mut settled = false;
        for _ in 0..CLIMB {
            let (r0, c0) = at;
            let mut moved = (0, 0);
            for (i, row) in around.iter_mut().enumerate() {
                for (j, v) in row.iter_mut().enumerate() {
                    let (dr, dc) = (i as i32 - 1, j as i32 - 1);
                    *v = if (dr, dc) == (0, 0) {
                        best
                    } else {
                        self.at_shift(&reading, r0 + dr, c0 + dc).unwrap_or(Real::MIN)
                    };
                    if *v > best {
                        (best, moved) = (*v, (dr, dc));
                    }
                }
            }
            if moved == (0, 0) {
                settled = true;
                break;
            }
            at = (r0 + moved.0, c0 + moved.1);
        }
        // The sub-cell fit from the best's neighbours (those evaluated
        // last, unless the climb ran out while still moving).
        let (r, c) = at;
        let near = |i: usize, j: usize| {
            let v = if settled {
                around.get(i).and_then(|row| row.get(j)).copied()
            } else {
                self.at_shift(&reading, r + i as i32 - 1, c + j as i32 - 1)
            };
            v.filter(|&v| v > Real::MIN).unwrap_or(best)
        };
        let dr = sub_cell(near(0, 1), best, near(2, 1));
        let dc = sub_cell(near(1, 0), best, near(1, 2));
        Some(Seen {
            centre,
            cell,
            reading,
            peak: best,
            at: ((c as Real + dc) * cell.0, (r as Real + dr) * cell.1),
            psr,
        })
    }

    /// The response at zero shift of the window about `e`'s centre with
    /// cells `scale` times `cell` (the scale search's measure: the filter's
    /// match at one size against another). Each size is normalised over its
    /// own cells: larger cells see larger differences between their points
    /// on smooth content, which would otherwise favour growing.
    /// Its cells are read into `work` (lent memory, as for [`Cue::place`]).
    fn at_scale(
        &self,
        frame: &Frame<'_>,
        (e, cell, scale): (&Ellipse, (Real, Real), Real),
        work: &mut [u16],
    ) -> Option<Real> {
        const N: usize = SCALE_N;
        let (cells, _) = super::carve::<u8, { CHANNELS * N * N }>(work)?;
        cells.fill(0);
        if !channels::read(frame, (e.cx, e.cy), (cell.0 * scale, cell.1 * scale), N, cells) {
            return None;
        }
        let reading = self.reading(&normalise(Lattice::whole(cells, N), None)?);
        self.response(cells, N, &reading, (N / 2 - HALF) as i32, (N / 2 - HALF) as i32)
    }

    /// Moves the estimate `pull` of the way to the response's peak, and
    /// scales it towards the best of three cell sizes, when the response
    /// has a clear peak; the response's PSR, `None` where there is none.
    fn steer<const N: usize>(
        &mut self,
        c: &GradientCue,
        frame: &Frame<'_>,
        (ellipse, particles): (&mut Ellipse, &mut [Particle; N]),
        freedom: Freedom,
        work: &mut [u16],
    ) -> Option<Real> {
        // The window about the estimate, where the search for the peak
        // starts (not the particles' mean, which the blend reads: the
        // estimate is measured the better centre, docs/accuracy.md).
        let seen = self.look(frame, (ellipse.cx, ellipse.cy), (ellipse.hx, ellipse.hy), work)?;
        self.unlike = seen.psr < c.relearn_below;
        if seen.psr >= c.min_psr && freedom.moves() {
            let (x, y) = (seen.centre.0 + seen.at.0, seen.centre.1 + seen.at.1);
            let pull = if self.grey { c.grey_pull } else { c.pull };
            let (dx, dy) = (pull * (x - ellipse.cx), pull * (y - ellipse.cy));
            shift_estimate(ellipse, particles, (dx, dy), frame);
            if c.scale_step > 0.0 && freedom.sizes() {
                let mut best = None;
                for s in [1.0, 1.0 + c.scale_step, 1.0 / (1.0 + c.scale_step)] {
                    if let Some(r) = self.at_scale(frame, (ellipse, seen.cell, s), work)
                        && best.is_none_or(|(b, _)| r > b)
                    {
                        best = Some((r, s));
                    }
                }
                if let Some((_, s)) = best {
                    let f = 1.0 + c.scale_pull * (s - 1.0);
                    scale_estimate(ellipse, particles, (f, f));
                }
            }
        }
        Some(seen.psr)
    }

    /// Learns the window around `e` at `rate` (the first window is learnt
    /// whole, whatever the rate), its temporaries in `work` ([`room`]).
    fn learn(&mut self, frame: &Frame<'_>, e: &Ellipse, rate: Real, work: &mut [u16]) {
        let Some(Room { spectrum, gain, cut }) = room(work) else { return };
        let cell = cell_size((e.hx, e.hy));
        // The learning window's cells at the front of `cells`, whole: moved
        // there from this frame's read window where it lies within it, read
        // afresh where not. The rest of `cells` is then free until the next
        // frame reads (see `held`).
        match self.window.take().and_then(|w| within(w, e, cell)) {
            Some((top, left)) => {
                for k in 0..CHANNELS {
                    for r in 0..LEARN {
                        // Each row moves to an index no later than its own
                        // and no later row's: nothing unread is overwritten.
                        let from = (k * READ + top + r) * READ + left;
                        let row = self.cells.get(from..).and_then(|s| s.first_chunk::<LEARN>()).copied();
                        let to = self.cells.get_mut((k * LEARN + r) * LEARN..).and_then(|s| s.first_chunk_mut());
                        if let (Some(row), Some(to)) = (row, to) {
                            *to = row;
                        }
                    }
                }
            }
            None => {
                let Some(cells) = self.cells.get_mut(..CHANNELS * LEARN * LEARN) else { return };
                if !channels::read(frame, (e.cx, e.cy), cell, LEARN, cells) {
                    return;
                }
            }
        }
        let Some((cells, rest)) = self.cells.split_at_mut_checked(CHANNELS * LEARN * LEARN) else { return };
        let lattice = Lattice::whole(cells, LEARN);
        let Some(norm) = normalise(lattice, Some(&TAPER)) else { return };
        // Each channel is transformed twice (once for the energy sum, once
        // for its own solve) rather than all kept, so that at most two
        // spectra are held at a time: all but the last two, which are
        // still held (the one before the last in the free cells).
        let mut held = held(rest);
        let kept = if held.is_some() { 2 } else { 1 };
        for col in gain.iter_mut() {
            col.fill(LAMBDA);
        }
        for k in 0..CHANNELS {
            let spectrum = slot(k, held.as_deref_mut(), spectrum);
            transform(spectrum, lattice, &norm, k);
            for (gain, col) in gain.iter_mut().zip(spectrum.iter()) {
                for (e, x) in gain.iter_mut().zip(col.iter()) {
                    *e += x.re * x.re + x.im * x.im;
                }
            }
        }
        // The trained peak's spectrum over the energy, once for all
        // channels.
        for (col, &pv) in gain.iter_mut().zip(PEAK.iter()) {
            for (e, &pu) in col.iter_mut().zip(PEAK.iter()) {
                *e = pu * pv / *e;
            }
        }
        let eta = if self.learned { rate } else { 1.0 };
        for row in cut.iter_mut() {
            row.fill(0.0);
        }
        // The channels still held are solved first.
        for k in (0..CHANNELS).rev().take(kept).chain(0..CHANNELS - kept) {
            let spectrum = slot(k, held.as_deref_mut(), spectrum);
            if k + kept < CHANNELS {
                transform(spectrum, lattice, &norm, k);
            }
            solve(spectrum, gain, cut);
            if let (Some(weights), Some(sum), Some(scale)) =
                (self.weights.get_mut(k), self.sums.get_mut(k), self.scales.get_mut(k))
            {
                blend((weights, sum, scale), cut, eta);
            }
        }
        self.learned = true;
        self.waiting = 0;
    }
}

/// The learning's temporaries: one channel's spectrum, the channels'
/// energy sum (then the solve's gain) and one channel's cut filter.
struct Room<'a> {
    spectrum: &'a mut Spectrum,
    gain: &'a mut Bins,
    cut: &'a mut Cut,
}

/// The learning's temporaries laid out in `work` (see [`super::carve`]).
fn room(work: &mut [u16]) -> Option<Room<'_>> {
    let (spectrum, rest) = super::carve::<[Complex32; LEARN], COLS>(work)?;
    let (gain, rest) = super::carve::<[Real; LEARN], COLS>(rest)?;
    let (cut, _) = super::carve::<[Real; SUPPORT], SUPPORT>(rest)?;
    Some(Room { spectrum, gain, cut })
}

/// Where channel `k`'s spectrum lies while it learns: the one before the
/// last in `held` where there is one, every other in `spectrum`.
fn slot<'a>(k: usize, held: Option<&'a mut Spectrum>, spectrum: &'a mut Spectrum) -> &'a mut Spectrum {
    match held {
        Some(h) if k + 2 == CHANNELS => h,
        _ => spectrum,
    }
}

/// A second spectrum for the learning, in the read window's cells past
/// the learning window's (free while it learns), from its first address a
/// spectrum may start at; `None` where it does not fit.
fn held(cells: &mut [u8]) -> Option<&mut Spectrum> {
    let start = cells.as_ptr().align_offset(align_of::<Spectrum>());
    let bytes = cells.get_mut(start..start.checked_add(size_of::<Spectrum>())?)?;
    bytemuck::try_from_bytes_mut(bytes).ok()
}

// The read window's cells hold a spectrum past the learning window's.
const _: () = assert!(CHANNELS * (READ * READ - LEARN * LEARN) >= size_of::<Spectrum>() + align_of::<Spectrum>());

/// The filter pooled 2 x 2, as the coarse search reads it.
type PooledWeights = [[[i32; POOLED_SUPPORT]; POOLED_SUPPORT]; CHANNELS];

/// The coarse search's pooled cells.
type PooledCells = [u8; CHANNELS * POOLED * POOLED];

/// The coarse search's temporaries laid out in `work`: its pooled filter,
/// then its pooled cells. Not through [`super::carve`]: carved that way,
/// the coarse search's inner loop spills a register (about 18,000 more
/// instructions a QVGA frame on the Cortex-M4F, `audit/profile`).
fn pooled_room(work: &mut [u16]) -> Option<(&mut PooledWeights, &mut PooledCells)> {
    const WEIGHTS: usize = size_of::<PooledWeights>() / 4;
    const WORDS: usize = WEIGHTS + size_of::<PooledCells>().div_ceil(4);
    let words: &mut [i32] = bytemuck::try_cast_slice_mut(work.get_mut(..2 * WORDS)?).ok()?;
    let (weights, cells) = words.split_at_mut_checked(WEIGHTS)?;
    let weights: &mut [[[i32; POOLED_SUPPORT]; POOLED_SUPPORT]] = bytemuck::try_cast_slice_mut(weights).ok()?;
    let cells: &mut [u8] = bytemuck::cast_slice_mut(cells);
    Some((weights.try_into().ok()?, cells.get_mut(..size_of::<PooledCells>())?.try_into().ok()?))
}

/// A scale window's cells: a lattice one cell wider than the support, so
/// that cell `n / 2` (which starts at the centre) is the support's middle.
const SCALE_N: usize = SUPPORT + 1;
type ScaleCells = [u8; CHANNELS * SCALE_N * SCALE_N];

/// Bytes of lent memory the learning takes ([`Room`]).
const LEARNING_BYTES: usize = size_of::<Spectrum>() + size_of::<Bins>() + size_of::<Cut>();

/// Bytes of lent memory the filter needs at most: the learning's, the
/// coarse search's or a scale window's (the tracker lends its foreground
/// map's sums, which hold the largest: `tracker::scratch` checks).
pub(crate) const WORK_BYTES: usize = {
    let (coarse, scale) = (size_of::<PooledWeights>() + size_of::<PooledCells>(), size_of::<ScaleCells>());
    let larger = if coarse > scale { coarse } else { scale };
    if LEARNING_BYTES > larger { LEARNING_BYTES } else { larger }
};

/// Where the learning window about `e`, of cells `cell`, lies in the read
/// window `(centre, cell)` this frame read (its top-left cell), if it lies
/// within it to the nearest cell and its cells are the same size to within
/// [`SAME_CELL`]: learning then reads no pixels of its own.
fn within(((cx, cy), read): ((Real, Real), (Real, Real)), e: &Ellipse, cell: (Real, Real)) -> Option<(usize, usize)> {
    let same = |a: Real, b: Real| (a - b).abs() <= SAME_CELL * b;
    if !(same(cell.0, read.0) && same(cell.1, read.1)) {
        return None;
    }
    let at = |d: Real, side: Real| {
        let o = round(d / side) + (READ / 2 - LEARN / 2) as i32;
        (0..=(READ - LEARN) as i32).contains(&o).then_some(o as usize)
    };
    Some((at(e.cy - cy, read.1)?, at(e.cx - cx, read.0)?))
}

/// Whether every pixel on a [`LEARN`] x [`LEARN`] lattice from the learning
/// window's top-left corner, a [`LEARN`]th of its side apart (rounded down
/// to whole pixels, at least one), is a grey level: its red, green and
/// blue agree in their top five bits, as a grey level's do in every format
/// (RGB565 keeps only those of red and blue; GRAY8 and YUV with U = V =
/// 128 give R = G = B). That is a mono camera's frame, or grey video
/// delivered in a colour format; colour video has pixels that differ by
/// more than that. The window rather than the box, so that a grey target
/// in a colour scene is not taken for grey video; points past the frame's
/// edge are left out. Read once a target, when it is learnt.
#[inline(never)]
fn grey_levels(frame: &Frame<'_>, e: &Ellipse) -> bool {
    // The window's corner and the step between samples, in whole pixels
    // (the casts saturate: a corner left of or above the frame is 0).
    let corner = ((e.cx - WINDOW * e.hx) as usize, (e.cy - WINDOW * e.hy) as usize);
    let step = |h: Real| ((2.0 * WINDOW * h / LEARN as Real) as usize).max(1);
    let (sx, sy) = (step(e.hx), step(e.hy));
    let grey = |[r, g, b]: [u8; 3]| r >> 3 == g >> 3 && g >> 3 == b >> 3;
    // Within a few frame sides for any box the tracker accepts; wrapping,
    // so that no box could make it panic (a place past the frame reads
    // nothing).
    let at = |start: usize, k: usize, step: usize| start.wrapping_add(k.wrapping_mul(step));
    (0..LEARN).all(|i| (0..LEARN).all(|j| frame.rgb(at(corner.0, j, sx), at(corner.1, i, sy)).is_none_or(grey)))
}

/// Blends a channel's cut filter `cut` into its weights, sum and scale at
/// `eta`, and quantises them afresh.
fn blend((weights, sum, scale): (&mut [[i16; SUPPORT]; SUPPORT], &mut i32, &mut Real), cut: &Cut, eta: Real) {
    let old = *scale * (1.0 - eta);
    let mixed = |w: i16, h: Real| w as Real * old + h * eta;
    let pairs = || weights.iter().flatten().zip(cut.iter().flatten());
    let largest = pairs().fold(0.0 as Real, |m, (&w, &h)| m.max(mixed(w, h).abs()));
    let to_int = if largest > 0.0 { 32_767.0 / largest } else { 0.0 };
    *sum = 0;
    for (q, &h) in weights.iter_mut().flatten().zip(cut.iter().flatten()) {
        *q = round(mixed(*q, h) * to_int) as i16;
        *sum += *q as i32;
    }
    *scale = if largest > 0.0 { largest / 32_767.0 } else { 0.0 };
}

/// Each channel's mean and gain over the `n` x `n` cells `cells` (tapered
/// by `taper` where given, as the learning window is): grey to unit energy,
/// the orientations together to unit energy. `None` for a window of one
/// grey level.
fn normalise(lattice: Lattice<'_>, taper: Option<&[Real; LEARN]>) -> Option<Norm> {
    let mut norm = Norm::default();
    let mut energy = [0.0 as Real; CHANNELS];
    let n = lattice.n;
    let count = n * n;
    for (k, (mean, e)) in norm.mean.iter_mut().zip(energy.iter_mut()).enumerate() {
        let rows = || (0..n).map(|r| lattice.row(k, r));
        if rows().any(|row| row.len() != n) {
            return None;
        }
        match taper {
            // Untapered, in integers: exact, and the squared sum cancels
            // nothing (`count · Σv² − (Σv)²`, at most 2^43 for the largest
            // window; the sums themselves fit 32 bits, checked below).
            None => {
                let (s1, s2) =
                    rows().flatten().fold((0u32, 0u32), |(a, b), &v| (a + v as u32, b + v as u32 * v as u32));
                let (s1, s2) = (s1 as u64, s2 as u64);
                *mean = s1 as Real / count as Real;
                *e = ((count as u64 * s2 - s1 * s1) as Real) / count as Real;
            }
            Some(t) => {
                // An exact sum (at most 255 · 32², within f32's integers).
                let s1: u32 = rows().flatten().map(|&v| v as u32).sum();
                *mean = s1 as Real / count as Real;
                // A second pass: the sum of squares less the squared sum
                // would cancel away f32's digits.
                *e = 0.0;
                for (row, &tr) in rows().zip(t.iter()) {
                    let mut line = 0.0 as Real;
                    for (&v, &tc) in row.iter().zip(t.iter()) {
                        let d = (value(v) - *mean) * tc;
                        line += d * d;
                    }
                    *e += line * tr * tr;
                }
            }
        }
    }
    let [grey, orientations @ ..] = energy;
    // Per cell: a window of one grey level leaves at most f32's rounding of
    // its mean.
    let floor = 1e-6 * count as Real;
    if !(grey > floor) {
        return None;
    }
    let orientations: Real = orientations.iter().sum();
    let (g0, g1) = (1.0 / sqrt(grey), if orientations > floor { 1.0 / sqrt(orientations) } else { 0.0 });
    for (k, gain) in norm.gain.iter_mut().enumerate() {
        *gain = if k == 0 { g0 } else { g1 };
    }
    Some(norm)
}

/// One channel's filter from its half spectrum `work` (overwritten) into
/// `cut`: the joint closed form `G X* / (Σ_j |X_j|² + λ)` (`gain` holding
/// `G / (Σ_j |X_j|² + λ)`), turned back into space and cut to the support.
#[inline(never)]
fn solve(work: &mut Spectrum, gain: &Bins, cut: &mut Cut) {
    // The support, about the learning window's middle (where the target's
    // centre is at zero shift): rows and columns `LEARN / 2 ± HALF`.
    const FIRST: usize = LEARN / 2 - HALF;
    // Back along the columns, then the rows the support needs, two at a
    // time (rows a and b of a real filter have Hermitian spectra: one
    // inverse FFT of `X_a + i X_b` gives a in the real part and b in the
    // imaginary part).
    for (col, gain) in work.iter_mut().zip(gain.iter()) {
        for (x, &g) in col.iter_mut().zip(gain.iter()) {
            *x = x.conj() * g;
        }
        let _ = microfft::inverse::ifft_32(col);
    }
    let scale = 1.0 / (LEARN * LEARN) as Real;
    for pair in (FIRST..FIRST + SUPPORT).step_by(2) {
        let mut full = [Complex32::new(0.0, 0.0); LEARN];
        for (i, v) in full.iter_mut().enumerate() {
            let bin = i.min(LEARN - i);
            let at = |r: usize| work.get(bin).and_then(|col| col.get(r)).copied().unwrap_or_default();
            let (xa, xb) = (at(pair), at(pair + 1));
            let (xa, xb) = if i > LEARN / 2 { (xa.conj(), xb.conj()) } else { (xa, xb) };
            *v = xa + Complex32::new(-xb.im, xb.re);
        }
        let full = microfft::inverse::ifft_32(&mut full);
        for (half, r) in [pair, pair + 1].into_iter().enumerate() {
            if !(FIRST..FIRST + SUPPORT).contains(&r) {
                continue;
            }
            // The filter pairs its cell `LEARN / 2 − b` with the window's
            // cell at offset `b` from the centre: the weights are the cut
            // filter turned half a turn.
            let Some(out) = cut.get_mut(FIRST + SUPPORT - 1 - r) else { continue };
            for (j, w) in out.iter_mut().enumerate() {
                let Some(x) = full.get(FIRST + SUPPORT - 1 - j) else { continue };
                *w = if half == 0 { x.re } else { x.im } * scale;
            }
        }
    }
}

/// Channel `k` of the learning window, centred, scaled and tapered, into
/// `work` as its half spectrum.
fn transform(work: &mut Spectrum, lattice: Lattice<'_>, norm: &Norm, k: usize) {
    let (gain, mean) = (norm.gain.get(k).copied().unwrap_or(0.0), norm.mean.get(k).copied().unwrap_or(0.0));
    for (r, &tr) in TAPER.iter().enumerate() {
        let g = gain * tr;
        let mut line = [0.0 as Real; LEARN];
        for ((x, &v), &tc) in line.iter_mut().zip(lattice.row(k, r).iter()).zip(TAPER.iter()) {
            *x = (value(v) - mean) * g * tc;
        }
        let spectrum = microfft::real::rfft_32(&mut line);
        // The real FFT packs the last column's real value into the
        // first's imaginary part.
        let (dc, nyquist) = (spectrum[0].re, spectrum[0].im);
        for (col, x) in work.iter_mut().zip(spectrum.iter()) {
            if let Some(slot) = col.get_mut(r) {
                *slot = *x;
            }
        }
        for (col, x) in [(0, dc), (COLS - 1, nyquist)] {
            if let Some(slot) = work.get_mut(col).and_then(|col| col.get_mut(r)) {
                *slot = Complex32::new(x, 0.0);
            }
        }
    }
    for col in work.iter_mut() {
        let _ = microfft::complex::cfft_32(col);
    }
}

impl Cue for GradientFilter {
    type Settings = GradientCue;

    fn start(&mut self, settings: Option<&GradientCue>, frame: &Frame<'_>, e: &Ellipse, work: &mut [u16]) {
        self.learned = false;
        self.waiting = 0;
        self.window = None;
        // The box given is the target: as sure as a frame can be.
        let given = Verdict { confidence: 1.0, moves_with_scene: false };
        self.sure = settings.is_some_and(|c| sure(c, given));
        if let Some(_c) = settings {
            self.grey = grey_levels(frame, e);
            self.learn(frame, e, 1.0, work);
            #[cfg(feature = "scale-pyramid")]
            self.pyramid.start(_c, frame, e);
        }
    }

    /// Where [`GradientCue::blend`] asks: reads the window about the
    /// particles' mean, finds its response's peak, and blends each
    /// particle's response (over the peak, negative as 0, 0 outside the
    /// window) into its similarity.
    fn rescore<const N: usize>(
        &mut self,
        c: &GradientCue,
        frame: &Frame<'_>,
        (particles, similarities): (&[Particle; N], &mut [Real; N]),
        n: usize,
        half_axes: (Real, Real),
        work: &mut [u16],
    ) {
        let n = n.min(N);
        if n == 0 || !(c.blend > 0.0) {
            return;
        }
        let (mut mx, mut my) = (0.0 as Real, 0.0 as Real);
        for p in particles.iter().take(n) {
            (mx, my) = (mx + p.x, my + p.y);
        }
        let centre = (mx / n as Real, my / n as Real);
        let Some(seen) = self.look(frame, centre, half_axes, work) else { return };
        if !(seen.peak > 0.0) {
            return;
        }
        // Particles crowd a few cells: each shift near the centre is
        // evaluated once (NaN: not yet).
        const NEAR: i32 = 8;
        const SIDE: usize = 2 * NEAR as usize + 1;
        let mut near = [Real::NAN; SIDE * SIDE];
        for (p, s) in particles.iter().zip(similarities.iter_mut()).take(n) {
            let sr = round((p.y - centre.1) / seen.cell.1);
            let sc = round((p.x - centre.0) / seen.cell.0);
            let slot = if sr.abs() <= NEAR && sc.abs() <= NEAR {
                near.get_mut(((sr + NEAR) * SIDE as i32 + sc + NEAR) as usize)
            } else {
                None
            };
            let r = match slot {
                Some(v) if !v.is_nan() => *v,
                slot => {
                    let r = self.at_shift(&seen.reading, sr, sc).map_or(0.0, |r| (r / seen.peak).max(0.0));
                    if let Some(v) = slot {
                        *v = r;
                    }
                    r
                }
            };
            *s = (1.0 - c.blend) * *s + c.blend * r;
        }
    }

    /// [`GradientFilter::steer`], then, where the estimate may be sized,
    /// the scale pyramid's sizing, whether or not the response had a peak.
    fn place<const N: usize>(
        &mut self,
        c: &GradientCue,
        frame: &Frame<'_>,
        (ellipse, particles): (&mut Ellipse, &mut [Particle; N]),
        freedom: Freedom,
        work: &mut [u16],
    ) -> Option<Real> {
        let psr = self.steer(c, frame, (&mut *ellipse, &mut *particles), freedom, work);
        #[cfg(feature = "scale-pyramid")]
        if freedom.sizes() {
            self.pyramid.place(c, frame, (ellipse, particles));
        }
        psr
    }

    /// Learns on every `learn_every`-th confident frame at its own rate:
    /// as a running mean over many frames it does not drift with one. A
    /// sure frame whose layout no longer matches is learnt at once
    /// ([`GradientCue::relearn_below`]).
    fn adapt(&mut self, c: &GradientCue, frame: &Frame<'_>, e: &Ellipse, verdict: Verdict, work: &mut [u16]) {
        let confidence = verdict.confidence;
        self.sure = sure(c, verdict);
        if confidence > c.learn_above {
            self.waiting = self.waiting.saturating_add(1);
            let turned = self.unlike && confidence > c.relearn_above;
            if !self.learned || self.waiting >= c.learn_every as u16 || turned {
                self.learn(frame, e, c.rate, work);
            }
        }
        self.unlike = false;
        self.window = None;
        #[cfg(feature = "scale-pyramid")]
        self.pyramid.adapt(c, frame, e, confidence);
    }
}

// The support fits the learning window, which fits the read window.
const _: () = assert!(SUPPORT < LEARN && LEARN <= READ);
// A window's sum of squared cells fits the 32 bits `normalise` sums in.
const _: () = assert!(READ * READ * 255 * 255 <= u32::MAX as usize);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pixel::PixelFormat;

    const W: usize = 320;
    const H: usize = 240;

    /// Random 6x6 blocks of grey 40 to 215 (broadband, like natural
    /// texture), the content moved by `(dx, dy)` pixels.
    fn blocks(dx: i32, dy: i32) -> Vec<u8> {
        let mut next = crate::testing::lcg(11);
        let levels: Vec<u8> = (0..64 * 64).map(|_| 40 + (next() >> 24) as u8 % 176).collect();
        let mut px = vec![0u8; W * H];
        for y in 0..H {
            for x in 0..W {
                let (u, v) = ((x as i32 - dx + 60) as usize / 6, (y as i32 - dy + 60) as usize / 6);
                px[y * W + x] = levels[(v % 64) * 64 + u % 64];
            }
        }
        px
    }

    fn frame(px: &[u8]) -> Frame<'_> {
        Frame::packed(px, W, H, PixelFormat::Gray8).unwrap()
    }

    use crate::testing::lent;

    fn target() -> Ellipse {
        Ellipse { cx: 160.0, cy: 120.0, hx: 16.0, hy: 16.0 }
    }

    #[test]
    fn the_tables_match_the_functions_they_stand_for() {
        // Reason: std's sin, exp and cos and the DFT's definition are the
        // independent reference for the compile-time series.
        for (i, &t) in TAPER.iter().enumerate() {
            let s = (std::f64::consts::PI * (i as f64 + 0.5) / LEARN as f64).sin();
            assert!((t as f64 - s * s).abs() < 1e-6, "taper {i}");
        }
        for (u, &p) in PEAK.iter().enumerate() {
            let e: f64 = (0..LEARN)
                .map(|k| {
                    let d = k.min(LEARN - k) as f64;
                    (-d * d / 2.0).exp() * (std::f64::consts::TAU * (u * k) as f64 / LEARN as f64).cos()
                })
                .sum();
            assert!((p as f64 - e).abs() < 1e-6, "peak spectrum {u}: {p} against {e}");
        }
    }

    #[test]
    fn the_sure_window_is_the_window_squared() {
        // Reason: the definition, against std's sin: the Hann taper of a
        // window 2 · LEARN cells wide at a shift of s cells, squared. By
        // hand, 14 cells off the centre: sin²(π · 46.5 / 64) = 0.5734, and
        // squared 0.3287.
        for (i, (&w, &n)) in SHIFT_WEIGHT.iter().zip(SURE_SHIFT_WEIGHT.iter()).enumerate() {
            let s =
                (std::f64::consts::PI * (LEARN as f64 + i as f64 - (READ / 2) as f64 + 0.5) / (2 * LEARN) as f64).sin();
            assert!((w as f64 - s * s).abs() < 1e-6 && (n as f64 - s.powi(4)).abs() < 1e-6, "shift {i}");
        }
        let at = |t: &[Real; READ], s: usize| t[READ / 2 + s];
        assert!((at(&SHIFT_WEIGHT, 14) - 0.5734).abs() < 1e-4 && (at(&SURE_SHIFT_WEIGHT, 14) - 0.3287).abs() < 1e-4);
    }

    #[test]
    fn the_window_narrows_after_a_sure_frame_that_does_not_move_with_the_scene() {
        // Reason: the rule of `GradientCue::narrow_above`, case by case: the
        // box given is sure unless the window never narrows (1); then each
        // frame decides the next one's window.
        let px = blocks(0, 0);
        let c = GradientCue::MEASURED;
        let mut f = GradientFilter::new();
        f.start(Some(&c), &frame(&px), &target(), lent().lend());
        assert!(f.sure);
        let never = GradientCue { narrow_above: 1.0, ..c };
        f.start(Some(&never), &frame(&px), &target(), lent().lend());
        assert!(!f.sure);
        f.start(Some(&c), &frame(&px), &target(), lent().lend());
        for (confidence, moves_with_scene, sure) in
            [(0.97, false, true), (0.97, true, false), (0.9, false, false), (0.97, false, true)]
        {
            f.adapt(&c, &frame(&px), &target(), Verdict { confidence, moves_with_scene }, lent().lend());
            assert_eq!(f.sure, sure, "confidence {confidence}, moves with the scene {moves_with_scene}");
            assert_eq!(f.shift_weights(), if sure { &SURE_SHIFT_WEIGHT } else { &SHIFT_WEIGHT });
        }
    }

    #[test]
    fn after_a_sure_frame_a_stronger_look_alike_a_box_away_does_not_take_the_peak() {
        // Reason: the windows' weights by hand. The filter learns a
        // textured box on a flat background; the next frame shows the box
        // faint (contrast 0.55) where it was and at full contrast 35 px
        // (14 cells of 2.5 px) to the right. Each copy's response is its
        // own, times its shift's weight (the two axes' tapers multiplied):
        // 0.9988 at the centre and 0.5730 14 cells to the right with the
        // wide window, 0.9976 and 0.3283 with the sure one. The faint copy
        // answers less than the full one, and the weights decide between
        // them: read with the wide window the peak goes to the far copy
        // (it does up to a contrast of 0.66), with the sure one it stays
        // (from a contrast of 0.44; the responses grow with contrast less
        // than in proportion, grey being read as log-luma).
        let texture = blocks(0, 0);
        let paste = |near: Real, far: bool| {
            let mut px = vec![128u8; W * H];
            for y in 104..136 {
                for x in 144..176 {
                    let v = texture[y * W + x] as Real - 128.0;
                    px[y * W + x] = (128.0 + near * v) as u8;
                    if far {
                        px[y * W + x + 35] = texture[y * W + x];
                    }
                }
            }
            px
        };
        let mut f = GradientFilter::new();
        f.learn(&frame(&paste(1.0, false)), &target(), 1.0, lent().lend());
        let two = paste(0.55, true);
        for (sure, x) in [(false, 35.0), (true, 0.0)] {
            f.sure = sure;
            let seen = f.look(&frame(&two), (160.0, 120.0), (16.0, 16.0), lent().lend()).unwrap();
            assert!((seen.at.0 - x).abs() < 2.5 && seen.at.1.abs() < 2.5, "sure {sure}: peak at {:?}", seen.at);
        }
    }

    #[test]
    fn the_peak_is_where_the_texture_moved() {
        // Reason: the scene's truth. The filter learns the texture about
        // the target; a frame whose content moved by (dx, dy) must answer
        // with its peak (dx, dy) from the window's centre, to within a
        // cell's share (cells are 2.5 px here), and with a clear PSR.
        let first = blocks(0, 0);
        let mut f = GradientFilter::new();
        f.learn(&frame(&first), &target(), 1.0, lent().lend());
        assert!(f.learned);
        for (dx, dy) in [(0, 0), (7, -5), (-12, 9), (20, 3)] {
            let moved = blocks(dx, dy);
            let seen = f.look(&frame(&moved), (160.0, 120.0), (16.0, 16.0), lent().lend()).unwrap();
            assert!((seen.at.0 - dx as Real).abs() < 1.5, "({dx}, {dy}): x at {:?}", seen.at);
            assert!((seen.at.1 - dy as Real).abs() < 1.5, "({dx}, {dy}): y at {:?}", seen.at);
            assert!(seen.psr > 5.0, "({dx}, {dy}): psr {}", seen.psr);
        }
        // Read about another centre: the same place in the frame.
        let moved = blocks(7, -5);
        let seen = f.look(&frame(&moved), (150.0, 126.0), (16.0, 16.0), lent().lend()).unwrap();
        assert!((150.0 + seen.at.0 - 167.0).abs() < 1.5 && (126.0 + seen.at.1 - 115.0).abs() < 1.5, "{:?}", seen.at);
    }

    #[test]
    fn learning_from_the_search_window_matches_a_fresh_read() {
        // Reason: a cross-check of two ways to the same cells. With cells
        // of 2.5 px (half axes 16), a box two cells right of and one cell
        // above the read window's centre has its learning window from the
        // read window's cell (row 6, column 9) (23 − 16 − 1, 23 − 16 + 2,
        // by hand). Those cells must be the ones a fresh read of the box's
        // learning window gives, but for the orientations on its border,
        // which a fresh read takes without the neighbours beyond it.
        let px = blocks(0, 0);
        let e = Ellipse { cx: 165.0, cy: 117.5, hx: 16.0, hy: 16.0 };
        assert_eq!(within(((160.0, 120.0), (2.5, 2.5)), &e, (2.5, 2.5)), Some((6, 9)));
        let mut read = vec![0u8; CHANNELS * READ * READ];
        let mut fresh = vec![0u8; CHANNELS * LEARN * LEARN];
        assert!(channels::read(&frame(&px), (160.0, 120.0), (2.5, 2.5), READ, &mut read));
        assert!(channels::read(&frame(&px), (165.0, 117.5), (2.5, 2.5), LEARN, &mut fresh));
        let whole = Lattice::whole(&fresh, LEARN);
        for k in 0..CHANNELS {
            for r in 0..LEARN {
                let inner = k == 0 || (1..LEARN - 1).contains(&r);
                let start = (k * READ + 6 + r) * READ + 9;
                let (a, b) = (&read[start..start + LEARN], whole.row(k, r));
                if inner {
                    assert_eq!(a.get(1..LEARN - 1), b.get(1..LEARN - 1), "channel {k}, row {r}");
                }
                if k == 0 {
                    assert_eq!(a, b, "grey, row {r}");
                }
            }
        }
        // Learnt from there, the filter is the fresh read's to within the
        // border's share: its orientations weigh little under the taper,
        // but the joint solve's weak regulariser passes some of them on.
        let mut fresh = GradientFilter::new();
        fresh.learn(&frame(&px), &e, 1.0, lent().lend());
        let mut reused = GradientFilter::new();
        reused.learn(&frame(&px), &target(), 1.0, lent().lend());
        assert!(reused.look(&frame(&px), (160.0, 120.0), (16.0, 16.0), lent().lend()).is_some());
        assert!(reused.window.is_some());
        reused.learn(&frame(&px), &e, 1.0, lent().lend());
        assert!(reused.window.is_none(), "the window is used once");
        for k in 0..CHANNELS {
            let (a, b) = (&fresh.weights[k], &reused.weights[k]);
            let worst = a
                .iter()
                .flatten()
                .zip(b.iter().flatten())
                .map(|(&x, &y)| (x as Real * fresh.scales[k] - y as Real * reused.scales[k]).abs())
                .fold(0.0, Real::max);
            let largest = 32_767.0 * fresh.scales[k];
            assert!(worst < 0.1 * largest, "channel {k}: {worst} against {largest}");
        }
        // Beyond the read window (more than 7 cells off), or at another
        // cell size, the learning window is read afresh.
        let far = Ellipse { cx: 180.0, ..e };
        assert_eq!(within(((160.0, 120.0), (2.5, 2.5)), &far, (2.5, 2.5)), None);
        assert_eq!(within(((160.0, 120.0), (2.5, 2.5)), &e, (2.6, 2.5)), None);
    }

    /// `px` turned a quarter turn about the target's centre (grey 128
    /// where the turn brings in nothing).
    fn quarter_turn(px: &[u8]) -> Vec<u8> {
        let (cx, cy) = (160, 120);
        let mut out = vec![128u8; W * H];
        for y in 0..H as i32 {
            for x in 0..W as i32 {
                let (u, v) = (cx - (y - cy), cy + (x - cx));
                if (0..W as i32).contains(&u) && (0..H as i32).contains(&v) {
                    out[(y * W as i32 + x) as usize] = px[(v * W as i32 + u) as usize];
                }
            }
        }
        out
    }

    #[test]
    fn a_sure_frame_whose_layout_no_longer_matches_is_learnt_at_once() {
        // Reason: the rule's cases by construction. The filter learns a
        // texture, then waits its turn (`learn_every`) to learn again. The
        // same texture answers with a clear peak (PSR over 5, the test
        // above); turned a quarter turn about the target it is a layout the
        // filter never saw (PSR under `relearn_below`, 4). A frame of the
        // turned texture must teach the filter at once when its confidence
        // exceeds `relearn_above` (0.8), and wait its turn when it does
        // not; the texture as learnt must wait its turn however sure.
        let first = blocks(0, 0);
        let turned = quarter_turn(&first);
        let c = GradientCue::MEASURED;
        for (px, confidence, learns) in [(&first, 0.95, false), (&turned, 0.75, false), (&turned, 0.95, true)] {
            let mut f = GradientFilter::new();
            let mut e = target();
            f.learn(&frame(&first), &e, c.rate, lent().lend());
            let mut ps = [Particle::default(); 4];
            let psr = f.place(&c, &frame(px), (&mut e, &mut ps), Freedom::Position, lent().lend()).unwrap();
            assert_eq!(psr < c.relearn_below, learns || confidence < c.relearn_above, "PSR {psr}");
            let before = f.weights;
            f.adapt(&c, &frame(px), &e, Verdict { confidence, moves_with_scene: false }, lent().lend());
            assert_eq!(f.weights != before, learns, "confidence {confidence}, PSR {psr}");
            assert_eq!(f.waiting, if learns { 0 } else { 1 });
        }
    }

    #[test]
    fn a_held_estimate_is_measured_but_not_moved() {
        // Reason: the rule of `Freedom::Held` by construction. The learnt
        // texture moved 4 px right and 3 px down answers with a clear peak
        // there: free, the filter pulls the box towards it; held (a group's
        // neighbour near), it leaves the box and the particles where they
        // were, and reports the same response.
        let c = GradientCue::MEASURED;
        let mut f = GradientFilter::new();
        f.learn(&frame(&blocks(0, 0)), &target(), c.rate, lent().lend());
        let px = blocks(4, 3);
        let moved = frame(&px);
        let mut psrs = [0.0; 2];
        for (i, freedom) in [Freedom::Position, Freedom::Held].into_iter().enumerate() {
            let (mut e, start) = (target(), target());
            let mut ps = [Particle::default(); 4];
            psrs[i] = f.place(&c, &moved, (&mut e, &mut ps), freedom, lent().lend()).unwrap();
            assert!(psrs[i] >= c.min_psr, "{freedom:?}: PSR {}", psrs[i]);
            if freedom.moves() {
                assert!(e.cx - start.cx > 2.0 && e.cy - start.cy > 1.5, "{e:?}");
            } else {
                assert_eq!((e, ps), (start, [Particle::default(); 4]));
            }
        }
        assert_eq!(psrs[0], psrs[1]);
    }

    #[test]
    fn grey_video_is_told_from_colour_and_trusts_the_filter_further() {
        // Reason: the rule by construction. A frame whose every pixel read
        // over the learning window is a grey level (GRAY8, RGB with R = G =
        // B, RGB565 written from grey levels, whose expanded red and green
        // differ by up to 4) is grey video; a coloured band (blue halved)
        // through the window makes it colour, one outside the window (which
        // spans the centre ± 2.5 half axes, 120 to 200 px here) does not.
        // On grey video the estimate moves `grey_pull` of the way to the
        // response's peak, on colour video `pull` of it (shifts are exact:
        // nothing is clamped this far inside the frame).
        let e = target();
        let rgb = |px: &[u8], tinted: &dyn Fn(usize, usize) -> bool| -> Vec<u8> {
            let pixel = |(i, &v): (usize, &u8)| if tinted(i % W, i / W) { [v, v, v / 2] } else { [v, v, v] };
            px.iter().enumerate().flat_map(pixel).collect()
        };
        fn rgb_frame(px: &[u8]) -> Frame<'_> {
            Frame::packed(px, W, H, PixelFormat::Rgb888).unwrap()
        }
        let texture = blocks(0, 0);
        assert!(grey_levels(&frame(&texture), &e));
        let rgb565: Vec<u8> = texture.iter().flat_map(|&v| crate::pixel::rgb_to_rgb565([v, v, v])).collect();
        assert!(grey_levels(&Frame::packed(&rgb565, W, H, PixelFormat::Rgb565).unwrap(), &e));
        assert!(grey_levels(&rgb_frame(&rgb(&texture, &|_, _| false)), &e));
        assert!(grey_levels(&rgb_frame(&rgb(&texture, &|x, _| x < 100)), &e));
        assert!(!grey_levels(&rgb_frame(&rgb(&texture, &|_, y| (115..=125).contains(&y))), &e));
        let c = GradientCue { pull: 0.5, grey_pull: 1.0, scale_step: 0.0, pyramid_pull: 0.0, ..GradientCue::MEASURED };
        let grey = (texture.clone(), blocks(4, 3), PixelFormat::Gray8, c.grey_pull);
        let colour = (rgb(&texture, &|_, _| true), rgb(&blocks(4, 3), &|_, _| true), PixelFormat::Rgb888, c.pull);
        for (first, moved, format, pull) in [grey, colour] {
            let mut f = GradientFilter::new();
            f.start(Some(&c), &Frame::packed(&first, W, H, format).unwrap(), &e, lent().lend());
            let moved = Frame::packed(&moved, W, H, format).unwrap();
            let seen = f.look(&moved, (e.cx, e.cy), (e.hx, e.hy), lent().lend()).unwrap();
            assert!(seen.at.0 > 2.0 && seen.at.1 > 1.5 && seen.psr >= c.min_psr, "{format:?}: {:?}", seen.at);
            let (mut est, mut ps) = (e, [Particle::default(); 4]);
            f.place(&c, &moved, (&mut est, &mut ps), Freedom::Position, lent().lend());
            let moved_by = (est.cx - e.cx, est.cy - e.cy);
            assert!((moved_by.0 - pull * seen.at.0).abs() < 1e-3, "{format:?}: {moved_by:?}, {:?}", seen.at);
            assert!((moved_by.1 - pull * seen.at.1).abs() < 1e-3, "{format:?}: {moved_by:?}, {:?}", seen.at);
        }
    }

    #[test]
    fn the_learning_takes_its_room_only_from_aligned_memory_that_holds_it() {
        // Reason: the invariant `room` checks instead of trusting: the
        // spectrum, the energy sum and the cut filter are 4-byte values. In
        // memory off a 4-byte boundary, or a word short, there is no room
        // and nothing is learnt; in the tracker's lent memory (aligned,
        // large enough) there is, and the filter learns.
        let mut map = lent();
        let w = map.lend();
        assert!(room(w).is_some());
        assert!(room(&mut w[1..]).is_none(), "off a 4-byte boundary");
        assert!(room(&mut w[..LEARNING_BYTES / 2 - 2]).is_none(), "a word short");
        let px = blocks(0, 0);
        let mut f = GradientFilter::new();
        f.learn(&frame(&px), &target(), 1.0, &mut w[1..]);
        assert!(!f.learned);
        f.learn(&frame(&px), &target(), 1.0, w);
        assert!(f.learned);
    }

    #[test]
    fn the_cells_past_the_learning_window_hold_a_spectrum() {
        // Reason: the learning transforms a channel fewer only where the
        // read window's free cells hold a whole spectrum from an aligned
        // address; `held` finds one in any part of them at least a
        // spectrum and an alignment long, and none in a shorter one.
        let mut f = GradientFilter::new();
        let free = &mut f.cells[CHANNELS * LEARN * LEARN..];
        assert!(held(free).is_some());
        for skip in 0..4 {
            assert!(held(&mut free[skip..]).is_some(), "from byte {skip}");
        }
        let short = size_of::<Spectrum>() - 1;
        assert!(held(&mut free[..short]).is_none());
    }

    #[test]
    fn a_flat_frame_teaches_nothing_and_answers_nothing() {
        // Reason: a window of one grey level has no energy to normalise
        // (the invariant `normalise` guards).
        let flat = vec![90u8; W * H];
        let mut f = GradientFilter::new();
        f.learn(&frame(&flat), &target(), 1.0, lent().lend());
        assert!(!f.learned);
        let first = blocks(0, 0);
        f.learn(&frame(&first), &target(), 1.0, lent().lend());
        assert!(f.look(&frame(&flat), (160.0, 120.0), (16.0, 16.0), lent().lend()).is_none());
    }

    #[test]
    fn particles_on_the_target_score_higher_than_particles_off_it() {
        // Reason: the blend's purpose, on the scene's truth: the texture
        // moved by (9, 4); particles there keep (1 − blend) of their
        // similarity and gain blend times the response over the peak
        // (about 1), particles two boxes away gain little, and particles
        // outside the window gain nothing.
        let first = blocks(0, 0);
        let moved = blocks(9, 4);
        let mut f = GradientFilter::new();
        f.learn(&frame(&first), &target(), 1.0, lent().lend());
        // Six on the target, one two boxes away, one outside the window
        // (the window is centred on their mean, (191.75, 119.25)).
        let places = [(169.0, 124.0); 6].into_iter().chain([(120.0, 90.0), (400.0, 120.0)]);
        let mut ps = [Particle::default(); 8];
        for (p, (x, y)) in ps.iter_mut().zip(places) {
            (p.x, p.y, p.hx, p.hy) = (x, y, 16.0, 16.0);
        }
        let mut sims = [0.5; 8];
        let c = GradientCue { blend: 0.3, ..GradientCue::MEASURED };
        f.rescore(&c, &frame(&moved), (&ps, &mut sims), 8, (16.0, 16.0), lent().lend());
        let kept = 0.5 * (1.0 - c.blend);
        assert!(sims[0] > kept + 0.8 * c.blend, "{sims:?}");
        assert!(sims.iter().take(6).all(|&s| s == sims[0]), "{sims:?}");
        assert!(sims[6] < sims[0] - 0.5 * c.blend, "{sims:?}");
        assert_eq!(sims[7], 0.5 * (1.0 - c.blend), "outside the window: {sims:?}");
    }
}
