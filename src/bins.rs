//! Choosing the number of histogram bins from the data: the Birgé–Rozenholc
//! penalised likelihood of the adaptive-bins paper.
//!
//! For `n` samples binned into `K` equal cells with counts `M_j`, the
//! histogram density's log-likelihood is `L(K) = Σ M_j ln(K M_j / n)`, and the
//! chosen `K` maximises `L(K) − (K − 1 + (ln K)^2.5)`. Too many bins overfit
//! (and make the tracker fragile under lighting change), too few cannot tell
//! the target from its surroundings; the penalty trades the two off.
//!
//! Colour histograms here have `L³` cells for `L` levels per channel, cells of
//! equal volume in the RGB cube, so the same criterion applies with `K = L³`.
//! The candidates are `L = 2, 3, …` up to what the capacity holds; the
//! counts are taken one candidate at a time in the caller's histogram, so
//! nothing is allocated.

use crate::colour::{ADAPTIVE_LEVELS, levels_bin};
use crate::cue::not_built;
use crate::error::Checks;
use crate::frame::Frame;
use crate::geometry::Ellipse;
use crate::histogram::Histogram;
use crate::region::{Lattice, floor, for_each_row, quadrant};
use crate::scalar::{Real, ln, sqrt};

/// The Birgé–Rozenholc score `Σ M_j ln(K M_j / n) − (K − 1 + (ln K)^2.5)` of
/// the cell counts `counts` (`K = counts.len()` cells, `n = Σ counts`).
/// Higher is better; an empty histogram scores `-inf`.
///
/// ```
/// use pftrack::bins::birge_rozenholc;
/// // Flat data: every cell holds the same count, so more cells explain it no
/// // better (L(K) = 0) and the penalty picks the fewest.
/// let flat2 = [500u32; 2];
/// let flat8 = [125u32; 8];
/// assert!(birge_rozenholc(&flat2) > birge_rozenholc(&flat8));
/// ```
pub fn birge_rozenholc(counts: &[u32]) -> Real {
    let k = counts.len();
    let n: u64 = counts.iter().map(|&c| c as u64).sum();
    if k == 0 || n == 0 {
        return Real::NEG_INFINITY;
    }
    // Σ M_j ln(K M_j / n) = n ln(K / n) + Σ M_j ln M_j (empty cells add 0).
    let (kf, nf) = (k as Real, n as Real);
    let mut sum = nf * (ln(kf) - ln(nf));
    for &m in counts.iter().filter(|&&m| m > 0) {
        let m = m as Real;
        sum += m * ln(m);
    }
    let lk = ln(kf);
    sum - (kf - 1.0 + lk * lk * sqrt(lk))
}

/// Asking for adaptive bins in a build without them is an error that names
/// the feature.
#[inline]
pub(crate) fn validate(c: &mut Checks, binning: crate::colour::Binning) {
    if binning == crate::colour::Binning::Adaptive && !cfg!(feature = "adaptive-bins") {
        c.fail(not_built("binning", "adaptive-bins"));
    }
}

/// The levels per channel of each segment under `binning`: chosen by
/// [`choose_levels`] for [`crate::colour::Binning::Adaptive`] in a build with the
/// `adaptive-bins` feature, `None` (the layout's own) otherwise.
pub(crate) fn levels<const K: usize>(
    binning: crate::colour::Binning,
    hist: &mut Histogram<K>,
    frame: &Frame<'_>,
    e: &Ellipse,
    lattice: Lattice,
    segments: u8,
) -> Option<[u8; 4]> {
    (cfg!(feature = "adaptive-bins") && binning == crate::colour::Binning::Adaptive)
        .then(|| choose_levels(hist, frame, e, lattice, segments))
}

/// Levels per channel for each of `segments` (1 or 4) blocks of a `K`-bin
/// histogram of ellipse `e`, by [`birge_rozenholc`] on the samples of
/// `lattice` (unweighted: the criterion is about sample counts). `hist` is
/// working memory. Quadrants split at the centre pixel, as in
/// [`crate::histogram`]'s quadrant layout. Out of line: it runs once per
/// initialisation, and inlined it would grow the hot caller's code.
#[inline(never)]
pub(crate) fn choose_levels<const K: usize>(
    hist: &mut Histogram<K>,
    frame: &Frame<'_>,
    e: &Ellipse,
    lattice: Lattice,
    segments: u8,
) -> [u8; 4] {
    let segments = segments.clamp(1, 4) as usize;
    let seg = K / segments;
    let (lo, hi) = ADAPTIVE_LEVELS;
    let mut best = [(Real::NEG_INFINITY, lo); 4];
    let centre = (floor(e.cx), floor(e.cy));
    for levels in lo..=hi {
        let cells = (levels as usize).pow(3);
        if cells > seg {
            break;
        }
        hist.clear();
        for_each_row(frame, e, lattice, |span| {
            let y = span.y;
            for (x, _) in span {
                let q = if segments == 4 { quadrant(x, y, centre) } else { 0 };
                if let Some(rgb) = frame.rgb(x, y) {
                    hist.add(q * seg + levels_bin(rgb, levels), 1);
                }
            }
        });
        for (s, b) in best.iter_mut().enumerate().take(segments) {
            if let Some(c) = hist.counts().get(s * seg..s * seg + cells) {
                let score = birge_rozenholc(c);
                if score > b.0 {
                    *b = (score, levels);
                }
            }
        }
    }
    best.map(|(_, l)| l)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::PixelFormat;
    use crate::region::Sampling;

    /// The levels chosen for a whole-ellipse histogram of a frame filled by `colour(i)` per pixel.
    fn levels_for(colour: impl Fn(usize) -> [u8; 3]) -> u8 {
        let (w, h) = (64usize, 64usize);
        let px: Vec<u8> = (0..w * h).flat_map(&colour).collect();
        let f = Frame::packed(&px, w, h, PixelFormat::Rgb888).unwrap();
        let e = Ellipse { cx: 32.0, cy: 32.0, hx: 30.0, hy: 30.0 };
        let mut hist = Histogram::<512>::new();
        choose_levels(&mut hist, &f, &e, Lattice::new(Sampling::Full, 0, e.hx, e.hy), 1)[0]
    }

    #[test]
    fn flat_data_gets_few_bins_multimodal_data_more() {
        // Reason: colours spread uniformly over the RGB cube make every
        // L-level histogram flat, L(K) ≈ 0, so the penalty picks the fewest
        // levels (2). Four tight colour clusters that fall in one cell of a
        // coarse grid but apart in a fine one gain n·ln(K/4)-ish likelihood
        // from more cells, far above the penalty with ~2800 samples, so more
        // levels win (at least 4, where the clusters separate).
        let mut next = crate::testing::lcg(7);
        let mut uniform = Vec::new();
        for _ in 0..64 * 64 {
            let seed = next();
            uniform.push([(seed >> 24) as u8, (seed >> 16) as u8, (seed >> 8) as u8]);
        }
        let flat = levels_for(|i| uniform[i]);
        assert_eq!(flat, 2, "uniform colours");
        let clusters = [[20u8, 20, 20], [100, 20, 20], [20, 100, 20], [100, 100, 20]];
        let multi = levels_for(|i| clusters[(i * 7 + i / 64) % 4]);
        assert!(multi >= 4, "four clusters got {multi} levels");
    }

    #[test]
    fn score_by_hand() {
        // Reason: hand computation. Counts [3, 1], n = 4, K = 2:
        // L = 3 ln(6/4) + 1 ln(2/4) = 1.21640 − 0.69315 = 0.52325;
        // penalty = 1 + (ln 2)^2.5 = 1 + 0.40000 = 1.40000.
        let s = birge_rozenholc(&[3, 1]);
        let want = 3.0 * (1.5f64).ln() + (0.5f64).ln() - (1.0 + (2f64).ln().powf(2.5));
        assert!((s as f64 - want).abs() < 1e-5, "{s} vs {want}");
        assert_eq!(birge_rozenholc(&[0, 0]), Real::NEG_INFINITY);
        assert_eq!(birge_rozenholc(&[]), Real::NEG_INFINITY);
    }

    #[test]
    fn quadrants_choose_their_own_levels() {
        // Reason: the paper's point: a homogeneous quadrant needs few bins, a
        // textured one more. Left half uniform noise (flat → 2 levels), right
        // half four clusters (→ more), split at the centre pixel.
        let (w, h) = (64usize, 64usize);
        let clusters = [[20u8, 20, 20], [100, 20, 20], [20, 100, 20], [100, 100, 20]];
        let mut next = crate::testing::lcg(3);
        let mut px = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let seed = next();
                let c = if x < 32 {
                    [(seed >> 24) as u8, (seed >> 16) as u8, (seed >> 8) as u8]
                } else {
                    clusters[(x + y) % 4]
                };
                px.extend_from_slice(&c);
            }
        }
        let f = Frame::packed(&px, w, h, PixelFormat::Rgb888).unwrap();
        let e = Ellipse { cx: 32.0, cy: 32.0, hx: 30.0, hy: 30.0 };
        let mut hist = Histogram::<512>::new();
        let l = choose_levels(&mut hist, &f, &e, Lattice::new(Sampling::Full, 0, e.hx, e.hy), 4);
        // Quadrants: top-left, top-right, bottom-left, bottom-right; at most 5
        // levels fit a quarter of 512 bins.
        assert_eq!((l[0], l[2]), (2, 2), "{l:?}");
        assert!(l[1] >= 4 && l[3] >= 4 && l[1] <= 5 && l[3] <= 5, "{l:?}");
    }
}
