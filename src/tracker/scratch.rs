//! The tracker's memory: the learnt target and its models, and the working
//! memory for observing regions.

use crate::config::{Config, Life};
use crate::edges::EdgeMap;
use crate::edges::{EDGE_SUPPORT_WORDS, MAX_EDGE_BINS};
use crate::foreground::{Foreground, ForegroundMap};
use crate::frame::Frame;
use crate::geometry::Ellipse;
use crate::histogram::{Clear, Histogram, Layout, Model, PlainModel};
use crate::region::Lattice;
use crate::scalar::Real;

/// The learnt appearance of the target.
#[derive(Clone, Debug)]
pub(super) struct Models<const K: usize> {
    /// How colour histograms are binned (chosen at initialisation for
    /// adaptive binning).
    pub(super) layout: Layout,
    pub(super) colour: Model<K>,
    /// `None` when the edge cue is off, or the target has no edge above the
    /// threshold (a flat target: its edge histogram says nothing).
    pub(super) edge: Option<Model<MAX_EDGE_BINS, EDGE_SUPPORT_WORDS>>,
    /// Which colours are the target's rather than its surroundings'.
    pub(super) fg: Foreground<K>,
    /// The grey-level template.
    pub(super) template: crate::template::Template,
    /// The colour model's bins as first learnt, which never adapt (learnt
    /// for [`Life::Confidence`] only; compared once a frame, so without the
    /// roots and support a model keeps for its per-particle sums).
    pub(super) anchor: PlainModel<K>,
}

impl<const K: usize> Models<K> {
    /// The largest squared distance the active cues can produce.
    pub(super) fn d2_max(&self, cfg: &Config) -> Real {
        if self.edge.is_some() { cfg.combination.d2_max() } else { 1.0 }
    }
}

/// What the tracker learnt when it was initialised.
#[derive(Clone, Debug)]
pub(super) struct Target<const K: usize> {
    pub(super) models: Models<K>,
    /// Frame size the tracker was initialised on.
    pub(super) frame: (usize, usize),
    /// The appearance threshold on the colour ρ.
    pub(super) threshold: Real,
    /// The edge cue's gradient threshold for this target
    /// ([`crate::EdgeCue::strong_percent`]).
    pub(super) edge_threshold: u16,
    /// Half axes to give particles re-drawn while searching.
    pub(super) half_axes: (Real, Real),
    /// The initial box's half axes, which the size search is pulled towards.
    pub(super) initial_axes: (Real, Real),
    /// For [`ModelUpdate::WhenDegraded`]: the sum of the confidences that
    /// make up `ρ₀`.
    pub(super) rho0_sum: Real,
    /// How many there are (a field of its own, not a pair with the sum:
    /// beside `edge_threshold` it takes no padding).
    pub(super) rho0_count: u16,
    /// The last estimate's centre.
    pub(super) centre: (Real, Real),
    /// The centre of the last estimate that found the target, where a lost
    /// one is looked for ([`crate::LostSearch::Widening`]).
    pub(super) found_at: (Real, Real),
    /// The target's recent speed, pixels a frame: the estimate's
    /// displacement between tracking frames, smoothed (for
    /// [`crate::Dynamics::speed_noise`]).
    pub(super) speed: Real,
}

impl<const K: usize> Target<K> {
    /// How far half axes are from the first box's: the confidence's size
    /// signal.
    pub(super) fn size_change(&self, half_axes: (Real, Real)) -> Real {
        super::confidence::size_change(self.initial_axes, half_axes)
    }
}

/// How one region compares with the models.
#[derive(Copy, Clone, Debug)]
pub(super) struct Seen {
    /// Colour similarity (the median of the quadrants' with quadrants).
    pub(super) rho: Real,
    /// Combined similarity of colour and edges.
    pub(super) sim: Real,
    /// The quadrants' colour similarities (zeros without quadrants).
    pub(super) quads: [Real; 4],
    /// Colour similarity with the first model (`rho` without one, or for a
    /// histogram that is not exact).
    pub(super) anchored: Real,
}

/// Working memory for observing regions: the histograms of the last region
/// observed, this frame's sampling lattice and its edge map.
#[derive(Clone, Debug)]
pub(crate) struct Scratch<const K: usize, const E: usize> {
    pub(super) colour: Histogram<K>,
    pub(super) edge: Histogram<MAX_EDGE_BINS>,
    pub(super) map: EdgeMap<E>,
    /// The lattice every region of this frame is read on (the edge map's).
    pub(super) lattice: Lattice,
    /// `P(target | colour)` around the estimate (for the size search and
    /// the confidence), or over the whole frame (for re-detection).
    pub(super) fgmap: ForegroundMap<FG_CELLS>,
}

/// Running sums of the foreground map (a 64 x 64 lattice).
pub(super) const FG_CELLS: usize = 4096;

// The map's sums are lent to the cues as working memory where the map is
// dead (`ForegroundMap::lend`): the correlation filters' spectra, the
// gradient filter's coarse search and its learning lie in them.
#[cfg(feature = "correlation")]
const _: () = assert!(crate::correlation::CORRELATION_WORK_BYTES <= 2 * FG_CELLS);
#[cfg(feature = "gradient")]
const _: () = assert!(crate::correlation::GRADIENT_WORK_BYTES <= 2 * FG_CELLS);

impl<const K: usize, const E: usize> Scratch<K, E> {
    /// Empty working memory.
    pub(crate) fn new() -> Self {
        Scratch {
            colour: Histogram::new(),
            edge: Histogram::new(),
            map: EdgeMap::new(),
            lattice: Lattice::FULL,
            fgmap: ForegroundMap::new(),
        }
    }

    /// Histograms of ellipse `e`, left in `self` (for a model update), with
    /// the colour bins `clear` says exact.
    pub(super) fn observe(&mut self, frame: &Frame<'_>, e: &Ellipse, layout: &Layout, edges: bool, clear: Clear<'_>) {
        // One walk over the region feeds both cues.
        let Scratch { colour, edge, map, lattice, .. } = self;
        let edges = if edges {
            Some((&*map, edge))
        } else {
            edge.clear();
            None
        };
        colour.compute_with(frame, e, layout, *lattice, edges, clear);
    }

    /// How ellipse `e` compares with `models`; all similarities in `[0, 1]`.
    /// With `keep`, the histograms left in `self` are exact (for a model
    /// update); without, only what the comparison read is.
    pub(super) fn similarity(
        &mut self,
        cfg: &Config,
        frame: &Frame<'_>,
        models: &Models<K>,
        e: &Ellipse,
        keep: bool,
    ) -> Seen {
        let clear = match models.colour.support() {
            Some(support) if !keep => Clear::Support(support),
            _ => Clear::All,
        };
        self.observe(frame, e, &models.layout, models.edge.is_some(), clear);
        let per = models.colour.compare(&self.colour, cfg.similarity);
        let (rho, quads) =
            if crate::histogram::quadrants(cfg.quadrants) { (median4(per), per) } else { (per[0], [0.0; 4]) };
        let sim = match &models.edge {
            Some(m) => {
                let [edge, ..] = m.compare(&self.edge, cfg.similarity);
                cfg.combination.similarity(rho, edge)
            }
            None => rho,
        };
        // Only exact histograms can be compared with a second model.
        let anchored = if keep && cfg.life != Life::Appearance {
            let per = models.anchor.compare(&self.colour, cfg.similarity);
            if crate::histogram::quadrants(cfg.quadrants) { median4(per) } else { per[0] }
        } else {
            rho
        };
        Seen { rho, sim, quads, anchored }
    }

    /// Chooses the lattice of regions with half axes `half_axes` (the
    /// target's: one lattice for every region of a frame, so that their
    /// samples share the edge map's cells) and computes the edge map over
    /// the pixel rectangle `[x0, x1) × [y0, y1)` if there is one.
    pub(super) fn prepare(
        &mut self,
        cfg: &Config,
        frame: &Frame<'_>,
        rect: Option<(usize, usize, usize, usize)>,
        half_axes: (Real, Real),
        edge_threshold: u16,
    ) {
        self.lattice = Lattice::new(cfg.sampling, cfg.max_samples, half_axes.0, half_axes.1);
        if let (Some(e), Some(rect)) = (cfg.edges, rect) {
            self.map.compute_on(frame, rect, e.bins as usize, edge_threshold, e.flat_bin, self.lattice);
        }
    }
}

/// The median of four values: the mean of the middle two.
pub(super) fn median4(v: [Real; 4]) -> Real {
    let [a, b, c, d] = v;
    let (lo1, hi1) = if a <= b { (a, b) } else { (b, a) };
    let (lo2, hi2) = if c <= d { (c, d) } else { (d, c) };
    // The middle two are the larger of the lows and the smaller of the highs.
    0.5 * (lo1.max(lo2) + hi1.min(hi2))
}

/// The quadrant that fails the appearance test while the other three pass.
pub(super) fn occluded(quads: [Real; 4], threshold: Real) -> Option<u8> {
    let mut bad = quads.iter().enumerate().filter(|&(_, &q)| !(q > threshold));
    match (bad.next(), bad.next()) {
        (Some((i, _)), None) => Some(i as u8),
        _ => None,
    }
}

/// The pixel rectangle covering ellipse `e` with a one-pixel margin (for the
/// Sobel window), clipped to a `w × h` frame.
pub(super) fn cover(e: &Ellipse, w: usize, h: usize) -> (usize, usize, usize, usize) {
    let clip = |v: Real, hi: usize| -> usize { crate::scalar::clamp(v, 0.0, hi as Real) as usize };
    (clip(e.cx - e.hx - 1.0, w), clip(e.cy - e.hy - 1.0, h), clip(e.cx + e.hx + 2.0, w), clip(e.cy + e.hy + 2.0, h))
}
