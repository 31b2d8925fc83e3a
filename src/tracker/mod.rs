//! The tracker: a particle filter over colour histograms with an adaptive
//! model and explicit searching / tracking / lost states.

mod confidence;
mod cues;
mod prior;
mod scratch;
mod search;
mod step;
#[cfg(test)]
mod tests;

use crate::config::{Config, Life, TableMode};
use crate::edges::{EDGE_SUPPORT_WORDS, MAX_EDGE_BINS};
use crate::error::{ConfigError, Error, ParamProblem, RegionError};
use crate::estimate::{Diagnostics, Estimate, TrackState};
use crate::filter::Particle;
use crate::foreground::Foreground;
use crate::frame::Frame;
use crate::geometry::{BoundingBox, Ellipse};
use crate::histogram::{Clear, Layout, Model, PlainModel};
use crate::region::Extents;
use crate::scalar::{Real, sqrt};
use crate::table::{Bins, Table};
pub use confidence::{on_target, size_change};
use cues::Cues;
pub use prior::ScalePrior;
use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro128PlusPlus;
pub(crate) use scratch::Scratch;
use scratch::*;
use search::*;

/// A colour particle-filter tracker with `N` particles, colour histograms of
/// up to `K` bins and an edge map of `E` bytes, drawing randomness from `R`.
///
/// Everything is stored inline and nothing allocates; `core::mem::size_of`
/// gives the RAM it needs. Place it in a `static` (e.g. with `static_cell`)
/// on small stacks. `E` bounds the per-frame edge map (4-bit cells, one per
/// sampled pixel of the area the particles cover: 8192 at the default):
/// when the area has more, edges are kept on a coarser grid, at a cost in
/// accuracy (see [`crate::EdgeMap`]). It is unused when the edge cue is off.
///
/// ```
/// use pftrack::{BoundingBox, Config, Frame, PixelFormat, TrackState, Tracker};
///
/// // A 64x48 grey scene with a red 12x12 square that moves right 2 px a frame.
/// let scene = |left: usize| {
///     let mut px = vec![90u8; 64 * 48 * 3];
///     for y in 18..30 {
///         for x in left..left + 12 {
///             px[(y * 64 + x) * 3..][..3].copy_from_slice(&[220, 30, 30]);
///         }
///     }
///     px
/// };
/// let mut tracker: Tracker<50> = Tracker::new(Config::default(), 42)?;
/// let first = scene(10);
/// tracker.init(&Frame::packed(&first, 64, 48, PixelFormat::Rgb888)?, BoundingBox::new(10.0, 18.0, 12.0, 12.0))?;
/// for t in 1..=10 {
///     let px = scene(10 + 2 * t);
///     let est = tracker.step(&Frame::packed(&px, 64, 48, PixelFormat::Rgb888)?)?;
///     assert_eq!(est.state, TrackState::Tracking);
///     let (cx, _) = est.bbox().centre();
///     assert!((cx - (16.0 + 2.0 * t as f32)).abs() < 3.0);
/// }
/// # Ok::<(), pftrack::Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct Tracker<
    const N: usize,
    const K: usize = 512,
    const E: usize = 4096,
    R = Xoshiro128PlusPlus,
    const T: usize = 0,
> {
    track: Track<N, K, R, T>,
    scratch: Scratch<K, E>,
}

/// One target's state: what a [`Tracker`] keeps apart from its working
/// memory, so that the members of a [`crate::Group`] share one.
#[derive(Clone, Debug)]
pub(crate) struct Track<const N: usize, const K: usize, R, const T: usize> {
    config: Config,
    rng: R,
    particles: [Particle; N],
    /// Normalised weights of `particles` after a step (0 past the
    /// hypotheses it observed, [`Config::sure_share`]).
    weights: [Real; N],
    target: Option<Target<K>>,
    /// The likelihood table (table mode only). With `T` 0 its cells take no
    /// room, but its header (origin, grid and spacing) does.
    table: Table<T>,
    state: TrackState,
    /// Frames since the target was last found (none while searching).
    misses: u16,
    /// Whether a step has found the target since it was learnt: until one
    /// has, nothing is known of its motion, and a step that misses it
    /// looks for it around its last place further than the particles reach.
    settled: bool,
    /// The signals behind the last confidence.
    diag: Diagnostics,
    /// The cues with state of their own.
    cues: Cues,
}

impl<const N: usize, const K: usize, const E: usize, const T: usize> Tracker<N, K, E, Xoshiro128PlusPlus, T> {
    /// A tracker with the default generator, xoshiro128++ seeded from `seed`:
    /// the same seed and frames give the same estimates, bit for bit, on every target.
    pub fn new(config: Config, seed: u64) -> Result<Self, Error> {
        Self::with_rng(config, Xoshiro128PlusPlus::seed_from_u64(seed))
    }
}

impl<const N: usize, const K: usize, const E: usize, R: Rng, const T: usize> Tracker<N, K, E, R, T> {
    /// A tracker drawing its randomness from `rng`.
    pub fn with_rng(config: Config, rng: R) -> Result<Self, Error> {
        Ok(Tracker { track: Track::new(config, rng)?, scratch: Scratch::new() })
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.track.config
    }

    /// The signals behind the last step's confidence.
    pub fn diagnostics(&self) -> Diagnostics {
        self.track.diag
    }

    /// The current state.
    pub fn state(&self) -> TrackState {
        self.track.state
    }

    /// The particles after the last step (for drawing and diagnostics).
    pub fn particles(&self) -> &[Particle; N] {
        &self.track.particles
    }

    /// The particles' normalised weights after the last step.
    pub fn weights(&self) -> &[Real; N] {
        &self.track.weights
    }

    /// The colour model, once initialised.
    pub fn model(&self) -> Option<&Model<K>> {
        self.track.target.as_ref().map(|t| &t.models.colour)
    }

    /// The edge-orientation model, once initialised with the edge cue on and
    /// a target that has edges.
    pub fn edge_model(&self) -> Option<&Model<MAX_EDGE_BINS, EDGE_SUPPORT_WORDS>> {
        self.track.target.as_ref().and_then(|t| t.models.edge.as_ref())
    }

    /// Levels per colour channel of each histogram block (one per quadrant,
    /// or the first for the whole ellipse), as chosen at initialisation for
    /// [`crate::colour::Binning::Adaptive`]; `None` before initialisation and with
    /// a fixed binning (whose levels are not chosen).
    pub fn colour_levels(&self) -> Option<[u8; 4]> {
        let adaptive = self.track.config.binning == crate::colour::Binning::Adaptive;
        self.track.target.as_ref().filter(|_| adaptive).map(|t| t.models.layout.levels)
    }

    /// The appearance threshold learnt from the background, once initialised.
    pub fn appearance_threshold(&self) -> Option<Real> {
        self.track.target.as_ref().map(|t| t.threshold)
    }

    /// The edge cue's gradient threshold chosen for the target, once
    /// initialised with the cue on: [`crate::EdgeCue::threshold`], or lower
    /// for a target with fewer strong gradients than
    /// [`crate::EdgeCue::strong_percent`] asks.
    pub fn edge_threshold(&self) -> Option<u16> {
        self.track.config.edges.and(self.track.target.as_ref().map(|t| t.edge_threshold))
    }

    /// Learns the target from `bbox` in `frame` and starts tracking it there.
    ///
    /// Calling it again at any time re-initialises the tracker on a new box
    /// (and may change resolution). The background statistics for the
    /// appearance test are measured on the same frame, away from the box.
    pub fn init(&mut self, frame: &Frame<'_>, bbox: BoundingBox) -> Result<Estimate, Error> {
        self.track.init(&mut self.scratch, frame, bbox)
    }

    /// Learns the target from `bbox` in a reference `frame`, then searches
    /// for it in the frames that follow (automatic initialisation, first paper):
    /// particles are spread over the frame, and tracking starts once more
    /// than `b · N` of them see the target.
    pub fn search(&mut self, frame: &Frame<'_>, bbox: BoundingBox) -> Result<(), Error> {
        self.track.search(&mut self.scratch, frame, bbox)
    }

    /// Grid spacing of the last likelihood table, in pixels (table mode).
    pub fn table_spacing(&self) -> Option<usize> {
        self.track.config.table.map(|_| self.track.table.spacing() as usize)
    }
}

impl<const N: usize, const K: usize, R: Rng, const T: usize> Track<N, K, R, T> {
    /// The state.
    pub(crate) fn state(&self) -> TrackState {
        self.state
    }

    /// The weights after the last step.
    #[cfg(test)]
    pub(crate) fn weights(&self) -> &[Real; N] {
        &self.weights
    }

    /// The frame size the target was learnt on, once it has been.
    pub(crate) fn frame_size(&self) -> Option<(usize, usize)> {
        self.target.as_ref().map(|t| t.frame)
    }

    /// The region the target holds while it is tracked: the last
    /// estimate's centre and size. A target lost or searching holds none.
    pub(crate) fn held(&self) -> Option<Ellipse> {
        let t = self.target.as_ref().filter(|_| self.state == TrackState::Tracking)?;
        let ((cx, cy), (hx, hy)) = (t.centre, t.half_axes);
        Some(Ellipse { cx, cy, hx, hy })
    }

    /// A target's state, before any box: validates `config` against the
    /// capacities.
    pub(crate) fn new(config: Config, rng: R) -> Result<Self, Error> {
        const {
            assert!(N >= 2, "a particle filter needs at least 2 particles");
            assert!(N <= u16::MAX as usize, "at most 65535 particles");
        }
        config.validate()?;
        if config.binning.bins() > K {
            return Err(ConfigError { field: "binning", problem: ParamProblem::OutOfRange }.into());
        }
        if config.quadrants && 4 * config.binning.bins() > K {
            return Err(ConfigError { field: "quadrants", problem: ParamProblem::OutOfRange }.into());
        }
        if config.table.is_some() && T == 0 {
            return Err(ConfigError { field: "table", problem: ParamProblem::OutOfRange }.into());
        }
        Ok(Self::blank(config, rng))
    }

    /// A target's state with a `config` that [`Track::new`] has accepted.
    pub(crate) fn blank(config: Config, rng: R) -> Self {
        Track {
            config,
            rng,
            particles: [Particle::default(); N],
            weights: [1.0 / N as Real; N],
            table: Table::new(),
            target: None,
            state: TrackState::Searching,
            misses: 0,
            settled: false,
            diag: Diagnostics::default(),
            cues: Cues::new(),
        }
    }

    /// Forgets the target, in place (a group's member is reused without a
    /// copy of the whole state passing through the stack), and draws from
    /// `rng` from here on.
    pub(crate) fn reset(&mut self, rng: R) {
        self.rng = rng;
        self.target = None;
        self.state = TrackState::Searching;
        self.misses = 0;
        self.settled = false;
        self.diag = Diagnostics::default();
        self.cues = Cues::new();
    }

    /// Learns the target from `bbox` in `frame` and starts tracking it there.
    ///
    /// Calling it again at any time re-initialises the tracker on a new box
    /// (and may change resolution). The background statistics for the
    /// appearance test are measured on the same frame, away from the box.
    pub(crate) fn init<const E: usize>(
        &mut self,
        scratch: &mut Scratch<K, E>,
        frame: &Frame<'_>,
        bbox: BoundingBox,
    ) -> Result<Estimate, Error> {
        self.learn(scratch, frame, &bbox)?;
        let e = Ellipse::from_box(&bbox);
        self.particles = [Particle::at(&e); N];
        self.weights = [1.0 / N as Real; N];
        self.state = TrackState::Tracking;
        self.misses = 0;
        self.settled = false;
        // No confidence yet: the first step observes every hypothesis.
        self.diag = Diagnostics::default();
        self.cues.start(&self.config, frame, &e, scratch.fgmap.lend());
        Ok(Estimate::initialised(e, N as u16, self.config.likelihood.sigma_for(0.0)))
    }

    /// Learns the target from `bbox` in a reference `frame`, then searches
    /// for it in the frames that follow (automatic initialisation, first paper):
    /// particles are spread over the frame, and tracking starts once more
    /// than `b · N` of them see the target.
    pub(crate) fn search<const E: usize>(
        &mut self,
        scratch: &mut Scratch<K, E>,
        frame: &Frame<'_>,
        bbox: BoundingBox,
    ) -> Result<(), Error> {
        self.learn(scratch, frame, &bbox)?;
        let (w, h) = (frame.width(), frame.height());
        let (hx, hy) = self.target.as_ref().map_or((1.0, 1.0), |t| t.half_axes);
        for p in self.particles.iter_mut() {
            *p = uniform_particle(&mut self.rng, (0.0, 0.0, w as Real, h as Real), hx, hy);
        }
        self.weights = [1.0 / N as Real; N];
        self.state = TrackState::Searching;
        self.misses = 0;
        self.settled = false;
        self.cues.start(&self.config, frame, &Ellipse::from_box(&bbox), scratch.fgmap.lend());
        Ok(())
    }

    /// The models of `bbox` and the background statistics of `frame`.
    /// Learns the target of `bbox` into `self.target`; on an error the
    /// tracker is unchanged. The target is built in place: returned by value,
    /// its models (2 KB at the default K) would be copied through the
    /// stack, taking `init`'s peak stack far past its budget
    /// (audit/budgets.txt). Out of line, so that its locals are gone before
    /// a cue's working memory (the correlation filter's spectrum) joins the
    /// stack.
    #[inline(never)]
    fn learn<const E: usize>(
        &mut self,
        sc: &mut Scratch<K, E>,
        frame: &Frame<'_>,
        bbox: &BoundingBox,
    ) -> Result<(), Error> {
        bbox.validate(frame.width(), frame.height())?;
        let Track { config: cfg, target: slot, .. } = self;
        let cfg = &*cfg;
        let (fw, fh) = (frame.width(), frame.height());
        let e = Ellipse::from_box(bbox);
        let segments = if crate::histogram::quadrants(cfg.quadrants) { 4 } else { 1 };
        let mut layout = Layout { segments, ..Layout::whole(cfg.binning) };
        let edge_threshold =
            cfg.edges.map_or(0, |c| crate::edges::soft_threshold(frame, &e, c.threshold, c.strong_percent));
        sc.prepare(cfg, frame, Some(cover(&e, fw, fh)), (e.hx, e.hy), edge_threshold);
        if let Some(levels) = crate::bins::levels(cfg.binning, &mut sc.colour, frame, &e, sc.lattice, segments) {
            layout.levels = levels;
        }
        sc.observe(frame, &e, &layout, cfg.edges.is_some(), Clear::All);
        if !Model::<K>::can_learn(&sc.colour, segments) {
            return Err(RegionError::NoPixels.into());
        }
        // Nothing fails from here on.
        let edge = if cfg.edges.is_some() { Model::from_segments(&sc.edge, 1) } else { None };
        let target = slot.insert(Target {
            models: Models {
                layout,
                colour: Model::zero(),
                edge,
                fg: Foreground::new(),
                template: crate::template::Template::new(),
                anchor: PlainModel::zero(),
            },
            frame: (fw, fh),
            threshold: 0.0,
            edge_threshold,
            half_axes: (e.hx.max(cfg.min_half_axis), e.hy.max(cfg.min_half_axis)),
            initial_axes: (e.hx.max(cfg.min_half_axis), e.hy.max(cfg.min_half_axis)),
            rho0_sum: 0.0,
            rho0_count: 0,
            centre: (e.cx, e.cy),
            found_at: (e.cx, e.cy),
            speed: 0.0,
        });
        let m = &mut target.models;
        m.colour.learn(&sc.colour, segments);
        let aware = cfg.life != Life::Appearance;
        if aware {
            // In place: a clone would pass 4·K bytes through the stack.
            m.anchor.copy_from(&m.colour);
        }
        if cfg.uses_template() {
            m.template.learn(frame, &e);
        }
        if cfg.uses_surroundings() {
            m.fg.learn(frame, &e, (&m.layout, &m.colour), 1.0, &mut sc.colour);
            if let Some(b) = cfg.background_weight {
                m.colour.reweight(m.fg.odds(), &crate::foreground::weights(b));
            }
        }
        let models = &target.models;

        // Background similarity on a grid of target-sized regions that do not
        // touch the target: at most 8x8 of them, spaced at least one target
        // size apart.
        sc.prepare(cfg, frame, Some((0, 0, fw, fh)), (e.hx, e.hy), edge_threshold);
        let (fw, fh) = (fw as Real, fh as Real);
        let step_x = bbox.width.max(fw / 8.0);
        let step_y = bbox.height.max(fh / 8.0);
        let (mut n, mut s1, mut s2) = (0u32, 0.0 as Real, 0.0 as Real);
        let mut y = 0.0;
        while y + bbox.height <= fh {
            let mut x = 0.0;
            while x + bbox.width <= fw {
                let cand = BoundingBox::new(x, y, bbox.width, bbox.height);
                if cand.iou(bbox) == 0.0 {
                    // The appearance condition is the first paper's: on colour.
                    // Edges are sparse, so in a plain background a few stray
                    // ones can match the target's orientations well (measured
                    // on the exit-and-return scene), which would make an empty
                    // scene "contain" the target.
                    let sim = sc.similarity(cfg, frame, models, &Ellipse::from_box(&cand), false).rho;
                    n += 1;
                    s1 += sim;
                    s2 += sim * sim;
                }
                x += step_x;
            }
            y += step_y;
        }
        // With no room for background samples (a target filling the frame)
        // only the floor applies.
        target.threshold = if n >= 2 {
            let mean = s1 / n as Real;
            let var = (s2 / n as Real - mean * mean).max(0.0);
            (mean + cfg.appearance_sigmas * sqrt(var)).max(cfg.min_appearance).min(1.0)
        } else {
            cfg.min_appearance
        };
        Ok(())
    }
}

impl<const N: usize, const K: usize, R: Rng, const T: usize> Track<N, K, R, T> {
    /// Fills the likelihood table over the particles' centres.
    fn fill_table<const E: usize>(&mut self, scratch: &Scratch<K, E>, frame: &Frame<'_>, mode: TableMode) {
        let Some(target) = self.target.as_ref() else { return };
        let cfg = &self.config;
        let (hx, hy) = target.half_axes;
        let Some(ext) = Extents::new(&Ellipse { cx: 0.0, cy: 0.0, hx, hy }) else { return };
        let map = if target.models.edge.is_some() { Some(&scratch.map) } else { None };
        let bins =
            Bins { frame, binning: cfg.binning, levels: target.models.layout.levels[0], map, lattice: scratch.lattice };
        let (mut x0, mut y0, mut x1, mut y1) = (i32::MAX, i32::MAX, i32::MIN, i32::MIN);
        for p in self.particles.iter() {
            let (x, y) = (crate::region::floor(p.x), crate::region::floor(p.y));
            (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
        }
        if x0 > x1 {
            return;
        }
        let area = (x0, y0, x1, y1);
        let spacing = mode.spacing as i32;
        let edge = target.models.edge.as_ref();
        self.table.fill(&bins, &ext, &target.models.colour, edge, cfg.combination, area, spacing);
    }
}
