//! The tracker: a particle filter over colour histograms with an adaptive
//! model and explicit searching / tracking / lost states.

use crate::config::{Config, EDGE_SUPPORT_WORDS, Life, MAX_EDGE_BINS, ModelUpdate, TableMode};
#[cfg(feature = "correlation")]
use crate::correlation::CorrelationFilter;
use crate::edges::EdgeMap;
use crate::error::{ConfigError, Error, ParamProblem, RegionError};
use crate::filter::{Bounds, Particle, mean_state, resample};
use crate::foreground::{Foreground, ForegroundMap, RING};
use crate::frame::Frame;
use crate::geometry::{BoundingBox, Ellipse};
use crate::histogram::{Clear, Histogram, Layout, Model, PlainModel};
use crate::likelihood::gaussian;
#[cfg(feature = "scene-motion")]
use crate::motion::SceneMotion;
use crate::region::{Extents, Lattice};
use crate::scalar::{Real, exp, ln, normal_from_bits, sqrt, unit_from_bits};
use crate::table::{Bins, Table};
use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro128PlusPlus;

/// What the tracker believes about its target.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TrackState {
    /// Looking for a target it has a model of but has not found yet.
    Searching,
    /// Following the target.
    Tracking,
    /// Had the target and lost it; searching for it again.
    Lost,
}

/// A state change that happened in this step.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Event {
    /// The tracker was (re-)initialised from a box.
    Initialised,
    /// A searched-for target appeared for the first time.
    Acquired,
    /// The target was declared lost.
    LostTarget,
    /// A lost target was found again.
    Reacquired,
}

/// The result of one step.
#[derive(Copy, Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Estimate {
    /// The mean state's ellipse.
    pub ellipse: Ellipse,
    /// How sure the tracker is of the estimate, in `[0, 1]`. With
    /// [`crate::Life::Confidence`] (the default), the probability that the
    /// estimate is on its target, from how much it stands out from its
    /// surroundings, its correlation with the first template and its
    /// colour similarity with the first model (see [`on_target`]); with
    /// [`crate::Life::Appearance`], the similarity between the model and the
    /// estimate (the Bhattacharyya coefficient, combined over colour and
    /// edges, see [`crate::Combination::similarity`]).
    pub confidence: Real,
    /// The state after this step.
    pub state: TrackState,
    /// The transition that happened in this step, if any.
    pub event: Option<Event>,
    /// How many particles satisfied the appearance condition: colour `ρ`
    /// above the background's `μ + kσ` (and the floor).
    pub appearing: u16,
    /// Whether the target model was updated in this step.
    pub model_updated: bool,
    /// The likelihood width σ used in this step.
    pub sigma: Real,
    /// With [`Config::quadrants`]: the quadrant (0 top-left, 1 top-right,
    /// 2 bottom-left, 3 bottom-right) that fails the appearance test while
    /// the other three pass, i.e. a partial occlusion there. `None` otherwise.
    pub occluded_quadrant: Option<u8>,
}

impl Estimate {
    /// The estimate a tracker reports when it is initialised on ellipse `e`.
    pub(crate) fn initialised(e: Ellipse, appearing: u16, sigma: Real) -> Self {
        Estimate {
            ellipse: e,
            confidence: 1.0,
            state: TrackState::Tracking,
            event: Some(Event::Initialised),
            appearing,
            model_updated: false,
            sigma,
            occluded_quadrant: None,
        }
    }

    /// The estimate as a box (the ellipse's bounding box).
    pub fn bbox(&self) -> BoundingBox {
        self.ellipse.to_box()
    }

    /// A bit-exact, one-line text form of the estimate, for comparing runs
    /// across targets: two estimates are identical exactly when their trace
    /// lines are. The host harness and the firmware both print it.
    ///
    /// ```
    /// # use pftrack::{Ellipse, Estimate, TrackState};
    /// let e = Estimate {
    ///     ellipse: Ellipse { cx: 10.5, cy: 20.0, hx: 4.0, hy: 6.25 },
    ///     confidence: 0.5,
    ///     state: TrackState::Tracking,
    ///     event: None,
    ///     appearing: 42,
    ///     model_updated: true,
    ///     sigma: 0.25,
    ///     occluded_quadrant: None,
    /// };
    /// // By hand: 10.5 is 0x41280000 in IEEE-754; the box's top is
    /// // 20 − 6.25 = 13.75, shown rounded to 13.8.
    /// assert_eq!(
    ///     format!("{}", e.trace()),
    ///     "tracking - 41280000 41a00000 40800000 40c80000 3f000000 3e800000 42 u | 6.5,13.8 8.0x12.5 c=500"
    /// );
    /// ```
    pub fn trace(&self) -> Trace<'_> {
        Trace(self)
    }
}

/// See [`Estimate::trace`]: state, event, the ellipse's centre and half axes,
/// the confidence and σ as IEEE-754 bit patterns, the appearing count, `u`
/// if the model was updated (`-` if not), then a rounded human-readable box
/// (x,y w×h) and the confidence in thousandths. No float formatting is used,
/// which keeps it small and identical on every target.
pub struct Trace<'a>(&'a Estimate);

impl core::fmt::Display for Trace<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let e = self.0;
        let state = match e.state {
            TrackState::Searching => "searching",
            TrackState::Tracking => "tracking",
            TrackState::Lost => "lost",
        };
        let event = match e.event {
            None => "-",
            Some(Event::Initialised) => "initialised",
            Some(Event::Acquired) => "acquired",
            Some(Event::LostTarget) => "lost-target",
            Some(Event::Reacquired) => "reacquired",
        };
        let el = &e.ellipse;
        write!(f, "{state} {event}")?;
        for v in [el.cx, el.cy, el.hx, el.hy, e.confidence, e.sigma] {
            write!(f, " {:08x}", v.to_bits())?;
        }
        write!(f, " {} {}", e.appearing, if e.model_updated { "u" } else { "-" })?;
        // Tenths of a pixel, rounded, in integers.
        let tenths = |v: Real| -> i32 {
            let t = v * 10.0;
            (if t >= 0.0 { t + 0.5 } else { t - 0.5 }) as i32
        };
        let d = |f: &mut core::fmt::Formatter<'_>, v: Real| {
            let t = tenths(v);
            let sign = if t < 0 { "-" } else { "" };
            write!(f, "{sign}{}.{}", t.unsigned_abs() / 10, t.unsigned_abs() % 10)
        };
        let b = e.bbox();
        f.write_str(" | ")?;
        d(f, b.x)?;
        f.write_str(",")?;
        d(f, b.y)?;
        f.write_str(" ")?;
        d(f, b.width)?;
        f.write_str("x")?;
        d(f, b.height)?;
        write!(f, " c={}", (e.confidence * 1000.0 + 0.5) as u32)
    }
}

/// The learnt appearance of the target.
#[derive(Clone, Debug)]
struct Models<const K: usize> {
    /// How colour histograms are binned (chosen at initialisation for
    /// adaptive binning).
    layout: Layout,
    colour: Model<K>,
    /// `None` when the edge cue is off, or the target has no edge above the
    /// threshold (a flat target: its edge histogram says nothing).
    edge: Option<Model<MAX_EDGE_BINS, EDGE_SUPPORT_WORDS>>,
    /// Which colours are the target's rather than its surroundings'.
    fg: Foreground<K>,
    /// The grey-level template.
    template: crate::template::Template,
    /// The colour model's bins as first learnt, which never adapt (learnt
    /// for [`Life::Confidence`] only; compared once a frame, so without the
    /// roots and support a model keeps for its per-particle sums).
    anchor: PlainModel<K>,
}

impl<const K: usize> Models<K> {
    /// The largest squared distance the active cues can produce.
    fn d2_max(&self, cfg: &Config) -> Real {
        if self.edge.is_some() { cfg.combination.d2_max() } else { 1.0 }
    }
}

/// What the tracker learnt when it was initialised.
#[derive(Clone, Debug)]
struct Target<const K: usize> {
    models: Models<K>,
    /// Frame size the tracker was initialised on.
    frame: (usize, usize),
    /// The appearance threshold on the colour ρ.
    threshold: Real,
    /// The edge cue's gradient threshold for this target
    /// ([`crate::EdgeCue::strong_percent`]).
    edge_threshold: u16,
    /// Half axes to give particles re-drawn while searching.
    half_axes: (Real, Real),
    /// The initial box's half axes, which the size search is pulled towards.
    initial_axes: (Real, Real),
    /// For [`ModelUpdate::WhenDegraded`]: the sum and count of the
    /// confidences that make up `ρ₀`.
    rho0: (Real, u16),
    /// The last estimate's centre.
    centre: (Real, Real),
    /// The target's recent speed, pixels a frame: the estimate's
    /// displacement between tracking frames, smoothed (for
    /// [`crate::Dynamics::speed_noise`]).
    speed: Real,
}

/// An external measurement of the target's size for one frame: the
/// head-tracking paper's depth-derived minor axis (from a depth sensor, a
/// range finder, or a known distance). Particles whose shorter half axis
/// lies outside `half_minor ± tolerance` are rescaled, keeping their aspect
/// ratio, to the nearest end of that range before they are weighed.
#[derive(Copy, Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ScalePrior {
    /// The expected shorter half axis, in pixels (1 to 2048).
    pub half_minor: Real,
    /// How far from it a particle may be, in pixels (0 to 2048; the paper
    /// searched ±1 px).
    pub tolerance: Real,
}

impl ScalePrior {
    fn validate(&self) -> Result<(), ConfigError> {
        let limit = (crate::pixel::MAX_DIMENSION / 2) as Real;
        crate::config::check("prior.half_minor", self.half_minor, 1.0, limit)?;
        crate::config::check("prior.tolerance", self.tolerance, 0.0, limit)
    }

    /// Rescales `p` so that its shorter half axis is within the prior.
    fn apply(&self, p: &mut Particle) {
        let minor = p.hx.min(p.hy);
        let want = crate::scalar::clamp(minor, self.half_minor - self.tolerance, self.half_minor + self.tolerance);
        if minor > 0.0 && want != minor {
            let f = want / minor;
            p.hx *= f;
            p.hy *= f;
        }
    }
}

/// How one region compares with the models.
#[derive(Copy, Clone, Debug)]
struct Seen {
    /// Colour similarity (the median of the quadrants' with quadrants).
    rho: Real,
    /// Combined similarity of colour and edges.
    sim: Real,
    /// The quadrants' colour similarities (zeros without quadrants).
    quads: [Real; 4],
    /// Colour similarity with the first model (`rho` without one, or for a
    /// histogram that is not exact).
    anchored: Real,
}

/// Working memory for observing regions: the histograms of the last region
/// observed, this frame's sampling lattice and its edge map.
#[derive(Clone, Debug)]
struct Scratch<const K: usize, const E: usize> {
    colour: Histogram<K>,
    edge: Histogram<MAX_EDGE_BINS>,
    map: EdgeMap<E>,
    /// The lattice every region of this frame is read on (the edge map's).
    lattice: Lattice,
    /// `P(target | colour)` around the estimate (for the size search and
    /// the confidence), or over the whole frame (for re-detection).
    fgmap: ForegroundMap<FG_CELLS>,
}

/// Running sums of the foreground map (a 64 x 64 lattice).
const FG_CELLS: usize = 4096;

impl<const K: usize, const E: usize> Scratch<K, E> {
    /// Histograms of ellipse `e`, left in `self` (for a model update), with
    /// the colour bins `clear` says exact.
    fn observe(&mut self, frame: &Frame<'_>, e: &Ellipse, layout: &Layout, edges: bool, clear: Clear<'_>) {
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
    fn similarity(&mut self, cfg: &Config, frame: &Frame<'_>, models: &Models<K>, e: &Ellipse, keep: bool) -> Seen {
        let clear = match models.colour.support() {
            Some(support) if !keep => Clear::Support(support),
            _ => Clear::All,
        };
        self.observe(frame, e, &models.layout, models.edge.is_some(), clear);
        let per = models.colour.compare(&self.colour, cfg.similarity);
        let (rho, quads) =
            if cfg!(feature = "quadrants") && cfg.quadrants { (median4(per), per) } else { (per[0], [0.0; 4]) };
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
            if cfg!(feature = "quadrants") && cfg.quadrants { median4(per) } else { per[0] }
        } else {
            rho
        };
        Seen { rho, sim, quads, anchored }
    }

    /// Chooses the lattice of regions with half axes `half_axes` (the
    /// target's: one lattice for every region of a frame, so that their
    /// samples share the edge map's cells) and computes the edge map over
    /// the pixel rectangle `[x0, x1) × [y0, y1)` if there is one.
    fn prepare(
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

/// The boundary score of `e`, in 1/16 Sobel units (0 when the cue is not built).
fn boundary_q(frame: &Frame<'_>, e: &Ellipse) -> u16 {
    #[cfg(feature = "boundary")]
    return (crate::boundary::outline_gradient(frame, e) * 16.0).min(u16::MAX as Real) as u16;
    #[cfg(not(feature = "boundary"))]
    {
        let _ = (frame, e);
        0
    }
}

/// The median of four values: the mean of the middle two.
fn median4(v: [Real; 4]) -> Real {
    let [a, b, c, d] = v;
    let (lo1, hi1) = if a <= b { (a, b) } else { (b, a) };
    let (lo2, hi2) = if c <= d { (c, d) } else { (d, c) };
    // The middle two are the larger of the lows and the smaller of the highs.
    0.5 * (lo1.max(lo2) + hi1.min(hi2))
}

/// The quadrant that fails the appearance test while the other three pass.
fn occluded(quads: [Real; 4], threshold: Real) -> Option<u8> {
    let mut bad = quads.iter().enumerate().filter(|&(_, &q)| !(q > threshold));
    match (bad.next(), bad.next()) {
        (Some((i, _)), None) => Some(i as u8),
        _ => None,
    }
}

/// The pixel rectangle covering ellipse `e` with a one-pixel margin (for the
/// Sobel window), clipped to a `w × h` frame.
fn cover(e: &Ellipse, w: usize, h: usize) -> (usize, usize, usize, usize) {
    let clip = |v: Real, hi: usize| -> usize { crate::scalar::clamp(v, 0.0, hi as Real) as usize };
    (clip(e.cx - e.hx - 1.0, w), clip(e.cy - e.hy - 1.0, h), clip(e.cx + e.hx + 2.0, w), clip(e.cy + e.hy + 2.0, h))
}

/// A colour particle-filter tracker with `N` particles, colour histograms of
/// up to `K` bins and an edge map of `E` bytes, drawing randomness from `R`.
///
/// Everything is stored inline and nothing allocates; `core::mem::size_of`
/// gives the RAM it needs. Place it in a `static` (e.g. with `static_cell`)
/// on small stacks. `E` bounds the per-frame edge map (4-bit cells, one per
/// sampled pixel of the area the particles cover: 8192 at the default):
/// when the area has more, edges are kept on a coarser grid, at a cost in
/// accuracy (see [`EdgeMap`]). It is unused when the edge cue is off.
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
    config: Config,
    rng: R,
    particles: [Particle; N],
    /// Normalised weights of `particles` after a step.
    weights: [Real; N],
    scratch: Scratch<K, E>,
    target: Option<Target<K>>,
    /// The likelihood table (table mode only; zero-sized when `T` is 0).
    table: Table<T>,
    state: TrackState,
    misses: u16,
    /// The signals behind the last confidence.
    diag: Diagnostics,
    /// The estimate's motion against its surroundings.
    #[cfg(feature = "scene-motion")]
    motion: SceneMotion,
    /// The correlation filter on the grey levels around the target.
    #[cfg(feature = "correlation")]
    correlation: CorrelationFilter,
}

/// The signals behind the last step's confidence (see [`on_target`]), for
/// diagnostics and for studying failures; all zero under
/// [`Life::Appearance`].
#[derive(Copy, Clone, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Diagnostics {
    /// Contrast of the estimate's box with the ring around it in the
    /// foreground map, in `[-1, 1]`.
    pub contrast: Real,
    /// Grey-level correlation of the estimate with the first template, in `[-1, 1]`.
    pub correlation: Real,
    /// Colour similarity of the estimate with the first model, in `[0, 1]`.
    pub anchored: Real,
    /// Similarity of the estimate with the adapted models, in `[0, 1]`.
    pub similarity: Real,
    /// Peak-to-sidelobe ratio of the correlation filter's response this step
    /// (MOSSE's measure of how sure the filter is: about 3 on a texture it
    /// never saw); 0 without the filter (`Config::correlation`).
    pub psr: Real,
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
        Ok(Tracker {
            config,
            rng,
            particles: [Particle::default(); N],
            weights: [1.0 / N as Real; N],
            scratch: Scratch {
                colour: Histogram::new(),
                edge: Histogram::new(),
                map: EdgeMap::new(),
                lattice: Lattice::FULL,
                fgmap: ForegroundMap::new(),
            },
            table: Table::new(),
            target: None,
            state: TrackState::Searching,
            misses: 0,
            diag: Diagnostics::default(),
            #[cfg(feature = "scene-motion")]
            motion: SceneMotion::new(),
            #[cfg(feature = "correlation")]
            correlation: CorrelationFilter::new(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// The signals behind the last step's confidence.
    pub fn diagnostics(&self) -> Diagnostics {
        self.diag
    }

    /// The current state.
    pub fn state(&self) -> TrackState {
        self.state
    }

    /// The particles after the last step (for drawing and diagnostics).
    pub fn particles(&self) -> &[Particle; N] {
        &self.particles
    }

    /// The particles' normalised weights after the last step.
    pub fn weights(&self) -> &[Real; N] {
        &self.weights
    }

    /// The colour model, once initialised.
    pub fn model(&self) -> Option<&Model<K>> {
        self.target.as_ref().map(|t| &t.models.colour)
    }

    /// The edge-orientation model, once initialised with the edge cue on and
    /// a target that has edges.
    pub fn edge_model(&self) -> Option<&Model<MAX_EDGE_BINS, EDGE_SUPPORT_WORDS>> {
        self.target.as_ref().and_then(|t| t.models.edge.as_ref())
    }

    /// Levels per colour channel of each histogram block (one per quadrant,
    /// or the first for the whole ellipse), as chosen at initialisation for
    /// [`crate::Binning::Adaptive`]; `None` before initialisation and with
    /// a fixed binning (whose levels are not chosen).
    pub fn colour_levels(&self) -> Option<[u8; 4]> {
        let adaptive = self.config.binning == crate::Binning::Adaptive;
        self.target.as_ref().filter(|_| adaptive).map(|t| t.models.layout.levels)
    }

    /// The appearance threshold learnt from the background, once initialised.
    pub fn appearance_threshold(&self) -> Option<Real> {
        self.target.as_ref().map(|t| t.threshold)
    }

    /// The edge cue's gradient threshold chosen for the target, once
    /// initialised with the cue on: [`crate::EdgeCue::threshold`], or lower
    /// for a target with fewer strong gradients than
    /// [`crate::EdgeCue::strong_percent`] asks.
    pub fn edge_threshold(&self) -> Option<u16> {
        self.config.edges.and(self.target.as_ref().map(|t| t.edge_threshold))
    }

    /// Learns the target from `bbox` in `frame` and starts tracking it there.
    ///
    /// Calling it again at any time re-initialises the tracker on a new box
    /// (and may change resolution). The background statistics for the
    /// appearance test are measured on the same frame, away from the box.
    pub fn init(&mut self, frame: &Frame<'_>, bbox: BoundingBox) -> Result<Estimate, Error> {
        self.learn(frame, &bbox)?;
        let e = Ellipse::from_box(&bbox);
        self.particles = [Particle::at(&e); N];
        self.weights = [1.0 / N as Real; N];
        self.state = TrackState::Tracking;
        self.misses = 0;
        #[cfg(feature = "scene-motion")]
        self.motion.start(frame, &e);
        self.start_correlation(frame, &e);
        Ok(Estimate::initialised(e, N as u16, self.config.likelihood.sigma_for(0.0)))
    }

    /// Learns the target from `bbox` in a reference `frame`, then searches
    /// for it in the frames that follow (automatic initialisation, first paper):
    /// particles are spread over the frame, and tracking starts once more
    /// than `b · N` of them see the target.
    pub fn search(&mut self, frame: &Frame<'_>, bbox: BoundingBox) -> Result<(), Error> {
        self.learn(frame, &bbox)?;
        let (w, h) = (frame.width(), frame.height());
        let (hx, hy) = self.target.as_ref().map_or((1.0, 1.0), |t| t.half_axes);
        for p in self.particles.iter_mut() {
            *p = uniform_particle(&mut self.rng, w, h, hx, hy);
        }
        self.weights = [1.0 / N as Real; N];
        self.state = TrackState::Searching;
        self.misses = 0;
        #[cfg(feature = "scene-motion")]
        self.motion.start(frame, &Ellipse::from_box(&bbox));
        self.start_correlation(frame, &Ellipse::from_box(&bbox));
        Ok(())
    }

    /// The correlation filter learns the first box afresh (and forgets any
    /// earlier target).
    #[cfg_attr(not(feature = "correlation"), allow(unused_variables, clippy::unused_self))]
    fn start_correlation(&mut self, frame: &Frame<'_>, e: &Ellipse) {
        #[cfg(feature = "correlation")]
        {
            self.correlation.reset();
            if let Some(c) = self.config.correlation {
                self.correlation.learn(frame, e, c.padding, c.rate);
            }
        }
    }

    /// The models of `bbox` and the background statistics of `frame`.
    /// Learns the target of `bbox` into `self.target`; on an error the
    /// tracker is unchanged. The target is built in place: returned by value,
    /// its models (2 KB at the default K) were copied through the stack
    /// (measured: 11.6 KB of peak stack in `init` on a Cortex-M4). With the
    /// correlation filter it stays out of line, so that its locals are gone
    /// before the filter's working spectrum joins the stack (inlined, they
    /// shared `init`'s frame: 4,424 B of peak stack against 3,952 B).
    #[cfg_attr(feature = "correlation", inline(never))]
    fn learn(&mut self, frame: &Frame<'_>, bbox: &BoundingBox) -> Result<(), Error> {
        bbox.validate(frame.width(), frame.height())?;
        let Tracker { config: cfg, scratch: sc, target: slot, .. } = self;
        let cfg = &*cfg;
        let (fw, fh) = (frame.width(), frame.height());
        let e = Ellipse::from_box(bbox);
        let segments = if cfg!(feature = "quadrants") && cfg.quadrants { 4 } else { 1 };
        #[cfg_attr(not(feature = "adaptive-bins"), allow(unused_mut))]
        let mut layout = Layout { segments, ..Layout::whole(cfg.binning) };
        let edge_threshold =
            cfg.edges.map_or(0, |c| crate::edges::soft_threshold(frame, &e, c.threshold, c.strong_percent));
        sc.prepare(cfg, frame, Some(cover(&e, fw, fh)), (e.hx, e.hy), edge_threshold);
        #[cfg(feature = "adaptive-bins")]
        if cfg.binning == crate::colour::Binning::Adaptive {
            layout.levels = crate::bins::choose_levels(&mut sc.colour, frame, &e, sc.lattice, segments);
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
            rho0: (0.0, 0),
            centre: (e.cx, e.cy),
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
                m.colour.reweight(m.fg.odds(), b);
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

    /// Tracks one frame: resample, propagate, observe, estimate, then update
    /// the state machine and, when the estimate is trustworthy, the model.
    ///
    /// The frame must have the size the tracker was initialised with; any
    /// pixel format may be used.
    pub fn step(&mut self, frame: &Frame<'_>) -> Result<Estimate, Error> {
        self.step_inner(frame, None)
    }

    /// [`Tracker::step`] with an external size measurement for this frame
    /// (see [`ScalePrior`]). A NaN, infinite or out-of-range prior is an
    /// [`Error::Config`] naming `prior.half_minor` or `prior.tolerance`, and
    /// the tracker is left as it was.
    pub fn step_with_prior(&mut self, frame: &Frame<'_>, prior: ScalePrior) -> Result<Estimate, Error> {
        prior.validate()?;
        self.step_inner(frame, Some(prior))
    }

    /// One step, as its phases: predict where the target may be, observe
    /// each hypothesis, weigh them, estimate (and size) the target, decide
    /// its state, and adapt the models.
    fn step_inner(&mut self, frame: &Frame<'_>, prior: Option<ScalePrior>) -> Result<Estimate, Error> {
        let target = self.target.as_ref().ok_or(Error::NotInitialised)?;
        let size = (frame.width(), frame.height());
        if size != target.frame {
            return Err(Error::FrameSizeChanged { expected: target.frame, got: size });
        }
        self.predict(frame, prior);
        let observed = self.observe(frame);
        let sigma = self.weigh(observed.d2_max);
        // An external size measurement, or the table's fixed size, decides
        // the size: no search then.
        let sized = prior.is_some() || (T > 0 && self.config.table.is_some());
        let look = self.estimate(frame, &observed, !sized);
        // Measured on every frame, so that its running means stay current.
        #[cfg(feature = "scene-motion")]
        let stuck =
            self.config.scene_motion && self.motion.update(frame, &look.ellipse, self.state == TrackState::Tracking);
        #[cfg(not(feature = "scene-motion"))]
        let stuck = false;
        let was_tracking = self.state == TrackState::Tracking;
        let event = self.life_cycle(look.found && !stuck);
        self.follow(&look.ellipse, was_tracking);
        let model_updated = self.adapt(frame, &look, event);
        Ok(Estimate {
            ellipse: look.ellipse,
            confidence: look.confidence,
            state: self.state,
            event,
            appearing: observed.appearing,
            model_updated,
            sigma,
            occluded_quadrant: look.occluded_quadrant,
        })
    }

    /// Resamples in proportion to the last step's weights, moves every
    /// particle by the dynamics, and, while the target is not tracked,
    /// re-draws a share of them to keep exploring.
    fn predict(&mut self, frame: &Frame<'_>, prior: Option<ScalePrior>) {
        let Tracker { config: cfg, rng, particles, weights, scratch, target, state, .. } = self;
        let Some(target) = target.as_ref() else { return };
        let (w, h) = (frame.width(), frame.height());
        let bounds = Bounds { width: w as Real, height: h as Real, min_half: cfg.min_half_axis };
        // On the stack: the counts live only while the set is rewritten.
        let mut copies = [0u16; N];
        resample(particles, weights, &mut copies, cfg.resampling, rng);
        for p in particles.iter_mut() {
            cfg.dynamics.propagate(p, &bounds, target.speed, rng);
            if let Some(prior) = &prior {
                prior.apply(p);
            }
            if T > 0 && cfg.table.is_some() {
                // The table holds one window size: the target's.
                (p.hx, p.hy) = target.half_axes;
            }
        }
        if *state == TrackState::Tracking {
            return;
        }
        let reseed = (cfg.reseed_fraction * N as Real) as usize;
        let (hx, hy) = target.half_axes;
        let spots =
            if cfg.redetect { redetect(&mut scratch.fgmap, frame, &target.models, (hx, hy)) } else { [None; SPOTS] };
        let found = spots.iter().flatten().count();
        // Spread over the set: copies of one parent tend to sit together.
        let stride = N.checked_div(reseed).unwrap_or(N).max(1);
        for (i, p) in particles.iter_mut().step_by(stride).take(reseed).enumerate() {
            // Every other re-drawn particle goes to one of the spots in turn.
            let spot = if i % 2 == 0 && found > 0 { spots.get(i / 2 % found).copied().flatten() } else { None };
            *p = match spot {
                Some((x, y)) => {
                    let s = 0.1 * sqrt(4.0 * hx * hy);
                    let (dx, dy) = (normal_from_bits(rng.next_u64()), normal_from_bits(rng.next_u64()));
                    Particle { x: x + s * dx, y: y + s * dy, hx, hy, ..Default::default() }
                }
                None => uniform_particle(rng, w, h, hx, hy),
            };
        }
    }

    /// Each particle's similarity with the models, left in `weights`.
    fn observe(&mut self, frame: &Frame<'_>) -> Observed {
        let size = (frame.width(), frame.height());
        let table = if T > 0 { self.config.table } else { None };
        let Tracker { config: cfg, particles, scratch, target, .. } = self;
        let Some(target) = target.as_ref() else { return Observed::default() };
        // Edges first, once, over the region the particles cover.
        let rect = target.models.edge.is_some().then(|| {
            let (mut x0, mut y0, mut x1, mut y1) = (size.0, size.1, 0, 0);
            for p in particles.iter() {
                let (a, b, c, d) = cover(&p.ellipse(), size.0, size.1);
                (x0, y0, x1, y1) = (x0.min(a), y0.min(b), x1.max(c), y1.max(d));
            }
            (x0, y0, x1, y1)
        });
        scratch.prepare(cfg, frame, rect, target.half_axes, target.edge_threshold);
        // `T > 0` is known at compile time: without a table, none of its
        // code is built into the tracker (measured: 3.5 KB of Cortex-M4 code).
        if let Some(mode) = table {
            self.fill_table(frame, mode);
        }
        let Tracker { config: cfg, particles, weights, scratch, target, table: tab, .. } = self;
        let Some(target) = target.as_ref() else { return Observed::default() };
        // The boundary scores (in 1/16 Sobel units; at most 1443 · 16 <
        // 2^16) wait until the best one, their normaliser, is known.
        let mut scores = [0u16; N];
        let mut out = Observed { appearing: 0, g_best: 0, d2_max: target.models.d2_max(cfg) };
        for ((p, w), g) in particles.iter().zip(weights.iter_mut()).zip(scores.iter_mut()) {
            let e = p.ellipse();
            let (rho, sim) = if table.is_some() {
                tab.lookup(p.x, p.y)
            } else {
                let Seen { rho, sim, .. } = scratch.similarity(cfg, frame, &target.models, &e, false);
                (rho, sim)
            };
            if rho > target.threshold {
                out.appearing += 1;
            }
            *w = match cfg.template {
                Some(t) => (1.0 - t.weight) * sim + t.weight * target.models.template.correlation(frame, &e).max(0.0),
                None => sim,
            };
            if cfg!(feature = "boundary") && cfg.boundary.is_some() {
                *g = boundary_q(frame, &e);
                out.g_best = out.g_best.max(*g);
            }
        }
        if let Some(b) = cfg.boundary
            && out.g_best > 0
        {
            for (w, &g) in weights.iter_mut().zip(scores.iter()) {
                *w = (1.0 - b.weight) * *w + b.weight * (g as Real / out.g_best as Real);
            }
        }
        out
    }

    /// Turns the similarities in `weights` into normalised likelihoods;
    /// returns the σ used.
    fn weigh(&mut self, d2_max: Real) -> Real {
        let cfg = &self.config;
        let best = self.weights.iter().fold(0.0 as Real, |a, &w| a.max(w));
        let mean = self.weights.iter().sum::<Real>() / N as Real;
        let (sigma, offset) = cfg.likelihood.sigma_and_offset(d2_max * (1.0 - best), d2_max * (1.0 - mean));
        let mut sum = 0.0;
        for w in self.weights.iter_mut() {
            *w = cfg.likelihood.weight(d2_max * (1.0 - *w) - offset, sigma);
            sum += *w;
        }
        if sum > 0.0 && sum.is_finite() {
            for w in self.weights.iter_mut() {
                *w /= sum;
            }
        } else {
            self.weights = [1.0 / N as Real; N];
        }
        sigma
    }

    /// The weighted mean state, sized against the surroundings, and how it
    /// compares with the models.
    fn estimate(&mut self, frame: &Frame<'_>, observed: &Observed, search: bool) -> Look {
        let Tracker {
            config: cfg,
            particles,
            weights,
            scratch,
            target,
            state,
            diag,
            #[cfg(feature = "correlation")]
            correlation,
            ..
        } = self;
        let mut ellipse = mean_state(particles, weights).ellipse();
        #[cfg_attr(not(feature = "correlation"), allow(unused_mut))]
        let mut psr = 0.0;
        // The texture cue first, so that the searches and the confidence
        // measure the box where it leaves it.
        #[cfg(feature = "correlation")]
        if let Some(c) = cfg.correlation
            && let Some(response) = correlation.respond(frame, &ellipse, c.padding)
        {
            psr = response.psr;
            // A response with no clear peak says nothing of where the
            // target went, nor of its size.
            let sure = psr >= c.min_psr;
            if sure {
                let (dx, dy) = (c.pull * response.shift.0, c.pull * response.shift.1);
                shift_estimate(&mut ellipse, particles, (dx, dy), frame);
            }
            // The scale: windows one step larger and smaller about the new
            // centre, against the first response, whose peak is already the
            // best match at the present size wherever it lay in the window.
            // Not where the size is decided outside (`search` false).
            if sure && c.scale_step > 0.0 && search {
                let mut best = (response.peak, 1.0);
                for s in [1.0 + c.scale_step, 1.0 / (1.0 + c.scale_step)] {
                    let scaled = Ellipse { hx: ellipse.hx * s, hy: ellipse.hy * s, ..ellipse };
                    if let Some(r) = correlation.respond(frame, &scaled, c.padding)
                        && r.peak > best.0
                    {
                        best = (r.peak, s);
                    }
                }
                let f = 1.0 + c.scale_pull * (best.1 - 1.0);
                scale_estimate(&mut ellipse, particles, (f, f));
            }
        }
        let Some(target) = target.as_ref() else {
            return Look { ellipse, confidence: 0.0, similarity: 0.0, found: false, occluded_quadrant: None };
        };
        let models = &target.models;
        let (contrast, correlation) = if cfg.uses_surroundings() {
            // One map serves the size search and the confidence: it covers
            // the largest candidate's ring.
            let size = cfg.size.filter(|_| search);
            let shift = cfg.shift.filter(|_| search);
            let grow = 1.0 + size.map_or(0.0, |s| s.step);
            // A shifted candidate's ring reaches `2 · step` half axes further
            // per round.
            let reach = RING * grow + shift.map_or(0.0, |s| 2.0 * s.step * s.rounds as Real);
            scratch.fgmap.compute_around(frame, &ellipse, reach, &models.layout, &models.fg);
            // The parts of the estimate's box as far as measured.
            let mut parts = None;
            if let Some(search) = size {
                let (fx, fy);
                ((fx, fy), parts) = search_size(scratch, cfg, frame, models, &ellipse, &search, target.initial_axes);
                scale_estimate(&mut ellipse, particles, (fx, fy));
            }
            if let Some(shift) = shift {
                let (dx, dy);
                ((dx, dy), parts) = search_shift(scratch, cfg, frame, models, &ellipse, &shift, parts);
                shift_estimate(&mut ellipse, particles, (dx, dy), frame);
            }
            // A box with no surroundings in the frame (it fills the frame)
            // has no contrast to measure; it counts as a typical target's.
            let contrast = match parts {
                Some(p) => p.contrast,
                None => scratch.fgmap.contrast(&ellipse, RING).unwrap_or(TYPICAL_CONTRAST),
            };
            (contrast, parts.and_then(|p| p.correlation))
        } else {
            (0.0, None)
        };
        let seen = scratch.similarity(cfg, frame, models, &ellipse, true);
        let similarity = match cfg.boundary {
            Some(b) if observed.g_best > 0 => {
                let g = (boundary_q(frame, &ellipse) as Real / observed.g_best as Real).min(1.0);
                (1.0 - b.weight) * seen.sim + b.weight * g
            }
            _ => seen.sim,
        };
        let occluded_quadrant =
            if cfg!(feature = "quadrants") && cfg.quadrants { occluded(seen.quads, target.threshold) } else { None };
        let (confidence, found) = match cfg.life {
            Life::Appearance => (similarity, observed.appearing as Real > cfg.kickoff * N as Real),
            Life::Confidence { lost_below, found_above } => {
                let correlation = correlation.unwrap_or_else(|| models.template.correlation(frame, &ellipse));
                let anchored = seen.anchored;
                *diag = Diagnostics { contrast, correlation, anchored, similarity, psr };
                let p = on_target(contrast, correlation, anchored);
                (p, if *state == TrackState::Tracking { p >= lost_below } else { p > found_above })
            }
        };
        Look { ellipse, confidence, similarity, found, occluded_quadrant }
    }

    /// Keeps the target's recent speed: the estimate's displacement, over
    /// frames tracked one after another, smoothed so that one jump of the
    /// estimate does not scatter the particles for long.
    fn follow(&mut self, e: &Ellipse, was_tracking: bool) {
        let Some(target) = self.target.as_mut() else { return };
        if was_tracking && self.state == TrackState::Tracking {
            let (dx, dy) = (e.cx - target.centre.0, e.cy - target.centre.1);
            target.speed += SPEED_RATE * (sqrt(dx * dx + dy * dy) - target.speed);
        }
        target.centre = (e.cx, e.cy);
    }

    /// Moves the state machine on whether the target was found this frame.
    fn life_cycle(&mut self, found: bool) -> Option<Event> {
        match self.state {
            TrackState::Tracking if found => {
                self.misses = 0;
                None
            }
            TrackState::Tracking => {
                self.misses = self.misses.saturating_add(1);
                (self.misses >= self.config.lost_after).then(|| {
                    self.state = TrackState::Lost;
                    Event::LostTarget
                })
            }
            TrackState::Searching | TrackState::Lost if found => {
                let event = if self.state == TrackState::Searching { Event::Acquired } else { Event::Reacquired };
                self.state = TrackState::Tracking;
                self.misses = 0;
                Some(event)
            }
            TrackState::Searching | TrackState::Lost => None,
        }
    }

    /// Adapts the models on steady, trustworthy tracking frames; returns
    /// whether they were updated.
    fn adapt(&mut self, frame: &Frame<'_>, look: &Look, event: Option<Event>) -> bool {
        let Tracker {
            config: cfg,
            scratch,
            target,
            state,
            misses,
            #[cfg(feature = "correlation")]
            correlation,
            ..
        } = self;
        let Some(target) = target.as_mut() else { return false };
        // The filter learns on every confident frame, at its own slow rate:
        // as a running mean over many frames it does not drift with one.
        #[cfg(feature = "correlation")]
        if let Some(c) = cfg.correlation
            && look.confidence > c.learn_above
        {
            correlation.learn(frame, &look.ellipse, c.padding, c.rate);
        }
        let steady = *state == TrackState::Tracking && event.is_none() && *misses == 0 && cfg.alpha > 0.0;
        let d2_max = target.models.d2_max(cfg);
        let wanted = match cfg.model_update {
            ModelUpdate::Confident => {
                gaussian(d2_max * (1.0 - look.similarity), cfg.update_sigma) > cfg.update_threshold
            }
            ModelUpdate::WhenDegraded { factor, frames } => {
                let (sum, n) = &mut target.rho0;
                if *n < frames {
                    // Still learning ρ₀ on the first tracking frames, where
                    // the estimate is assumed good (as the paper does).
                    if steady {
                        *sum += look.similarity;
                        *n += 1;
                    }
                    false
                } else {
                    look.similarity < factor * (*sum / *n as Real)
                }
            }
        };
        // With the confidence driving the life cycle, only a confident
        // estimate may teach the models.
        let trusted = match cfg.life {
            Life::Appearance => true,
            Life::Confidence { found_above, .. } => look.confidence > found_above,
        };
        let updated = steady && wanted && trusted;
        if updated {
            // The scratch still holds the estimate's histograms.
            let m = &mut target.models;
            // Weighted, the roots are recomputed below, against the
            // surroundings blended in meanwhile.
            if cfg.background_weight.is_some() {
                m.colour.blend_bins(&scratch.colour, cfg.alpha);
            } else {
                m.colour.blend(&scratch.colour, cfg.alpha);
            }
            if let Some(edge) = m.edge.as_mut() {
                edge.blend(&scratch.edge, cfg.alpha);
            }
            if let Some(t) = cfg.template {
                m.template.blend(frame, &look.ellipse, t.rate);
            }
            if cfg.uses_surroundings() {
                // The estimate's histogram is blended in: its memory is free.
                m.fg.learn(frame, &look.ellipse, (&m.layout, &m.colour), cfg.surroundings_rate, &mut scratch.colour);
            }
            if let Some(b) = cfg.background_weight {
                m.colour.reweight(m.fg.odds(), b);
            }
        }
        if *state == TrackState::Tracking {
            target.half_axes = (look.ellipse.hx, look.ellipse.hy);
        }
        updated
    }
}

/// What observing the particles found.
#[derive(Copy, Clone, Debug, Default)]
struct Observed {
    /// Particles that pass the appearance test.
    appearing: u16,
    /// The best boundary score (0 without the boundary cue).
    g_best: u16,
    /// The largest squared distance the active cues can produce.
    d2_max: Real,
}

/// The estimate and what it looks like.
#[derive(Copy, Clone, Debug)]
struct Look {
    ellipse: Ellipse,
    /// What [`Estimate::confidence`] reports.
    confidence: Real,
    /// Similarity of the estimate with the models (and the boundary cue).
    similarity: Real,
    /// Whether the life cycle counts the target as seen in this frame.
    found: bool,
    occluded_quadrant: Option<u8>,
}

/// The median contrast of estimates on their target (IoU ≥ 0.3) on the
/// real sequences' tune split (`track otb --dump`), for boxes whose
/// contrast cannot be measured.
const TYPICAL_CONTRAST: Real = 0.39;

/// How much of each frame's displacement enters the target's recent speed:
/// about the last three frames count.
const SPEED_RATE: Real = 0.3;

/// The probability that an estimate is on its target, from three signals
/// that a drifting estimate cannot keep high together: its box's
/// `contrast` with the ring around it in the foreground map (in `[-1, 1]`),
/// its grey-level `correlation` with the first template (negative counts as
/// 0), and its colour similarity with the first model, `anchored`.
///
/// A logistic model, `1 / (1 + exp(−z))` with `z = 9.2·contrast +
/// 2.4·correlation + 4.8·anchored − 4.2`, whose coefficients are a logistic
/// regression of "IoU with the truth ≥ 0.1" on the real sequences' tune
/// split (`tools/fit-confidence`; docs/accuracy.md). Each signal alone
/// separates missing frames from the others with a ROC AUC of 0.75 to 0.87
/// there; together, 0.90.
pub fn on_target(contrast: Real, correlation: Real, anchored: Real) -> Real {
    let z = 9.2 * contrast + 2.4 * correlation.max(0.0) + 4.8 * anchored - 4.2;
    1.0 / (1.0 + exp(-z))
}

impl<const N: usize, const K: usize, const E: usize, R: Rng, const T: usize> Tracker<N, K, E, R, T> {
    /// Fills the likelihood table over the particles' centres.
    fn fill_table(&mut self, frame: &Frame<'_>, mode: TableMode) {
        let Some(target) = self.target.as_ref() else { return };
        let cfg = &self.config;
        let (hx, hy) = target.half_axes;
        let Some(ext) = Extents::new(&Ellipse { cx: 0.0, cy: 0.0, hx, hy }) else { return };
        let map = if target.models.edge.is_some() { Some(&self.scratch.map) } else { None };
        let bins = Bins {
            frame,
            binning: cfg.binning,
            levels: target.models.layout.levels[0],
            map,
            lattice: self.scratch.lattice,
        };
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

    /// Grid spacing of the last likelihood table, in pixels (table mode).
    pub fn table_spacing(&self) -> Option<usize> {
        self.config.table.map(|_| self.table.spacing() as usize)
    }
}

/// What the size and position searches measure of a candidate box: its
/// contrast with its ring in the foreground map, and, once asked for, its
/// similarity with the models and its grey-level correlation with the
/// first template. The winner's parts are handed on, so that the next
/// search and the confidence do not measure the same box again.
#[derive(Copy, Clone)]
struct Parts {
    contrast: Real,
    sim: Option<Real>,
    correlation: Option<Real>,
}

impl Parts {
    /// The contrast of the box of `c`; `None` where the map cannot say.
    fn of<const K: usize, const E: usize>(sc: &Scratch<K, E>, c: &Ellipse) -> Option<Parts> {
        Some(Parts { contrast: sc.fgmap.contrast(c, RING)?, sim: None, correlation: None })
    }

    /// The score a search ranks the box of `c` by: contrast plus
    /// `similarity` times its similarity and `template` times its
    /// correlation, each measured on first use.
    #[allow(clippy::too_many_arguments)]
    fn score<const K: usize, const E: usize>(
        &mut self,
        sc: &mut Scratch<K, E>,
        cfg: &Config,
        frame: &Frame<'_>,
        models: &Models<K>,
        c: &Ellipse,
        similarity: Real,
        template: Real,
    ) -> Real {
        let mut score = self.contrast;
        if template > 0.0 {
            score += template * *self.correlation.get_or_insert_with(|| models.template.correlation(frame, c));
        }
        if similarity > 0.0 {
            score += similarity * *self.sim.get_or_insert_with(|| sc.similarity(cfg, frame, models, c, false).sim);
        }
        score
    }
}

/// The factors on the half axes of `e` whose box scores best (see
/// [`crate::SizeSearch`]), with that box's parts; the foreground map must
/// cover the largest candidate's ring.
fn search_size<const K: usize, const E: usize>(
    sc: &mut Scratch<K, E>,
    cfg: &Config,
    frame: &Frame<'_>,
    models: &Models<K>,
    e: &Ellipse,
    search: &crate::config::SizeSearch,
    (ix, iy): (Real, Real),
) -> ((Real, Real), Option<Parts>) {
    let up = 1.0 + search.step;
    let dn = 1.0 / up;
    // The mean first, so that a tie keeps it; then one step along each
    // axis, and the two turns (wider and shorter, narrower and taller) so
    // that the aspect can follow a turning target at twice the rate; or
    // one step in scale only.
    let candidates: &[(Real, Real)] = if search.aspect {
        &[(1.0, 1.0), (up, 1.0), (dn, 1.0), (1.0, up), (1.0, dn), (up, dn), (dn, up)]
    } else {
        &[(1.0, 1.0), (up, up), (dn, dn)]
    };
    let mut best = ((1.0, 1.0), None);
    let mut best_score = Real::NEG_INFINITY;
    for &(fx, fy) in candidates {
        let c = Ellipse { hx: e.hx * fx, hy: e.hy * fy, ..*e };
        let Some(mut parts) = Parts::of(sc, &c) else { continue };
        let mut score = parts.score(sc, cfg, frame, models, &c, search.similarity, 0.0);
        if search.aspect_pull > 0.0 {
            score -= search.aspect_pull * ln((c.hx * iy) / (c.hy * ix)).abs();
        }
        if search.scale_pull > 0.0 {
            score -= search.scale_pull * ln((c.hx * c.hy) / (ix * iy)).abs();
        }
        if score > best_score {
            (best, best_score) = (((fx, fy), Some(parts)), score);
        }
    }
    best
}

/// The offset of the best box on a hill climb from `e`, one step left,
/// right, up or down per round, scored like the size search's candidates,
/// with that box's parts; `start` holds what is known of `e`'s.
fn search_shift<const K: usize, const E: usize>(
    sc: &mut Scratch<K, E>,
    cfg: &Config,
    frame: &Frame<'_>,
    models: &Models<K>,
    e: &Ellipse,
    search: &crate::config::ShiftSearch,
    start: Option<Parts>,
) -> ((Real, Real), Option<Parts>) {
    let (sx, sy) = (2.0 * search.step * e.hx, 2.0 * search.step * e.hy);
    let (w, h) = (frame.width() as Real, frame.height() as Real);
    let (mut dx, mut dy) = (0.0, 0.0);
    let Some(mut parts) = start.or_else(|| Parts::of(sc, e)) else { return ((0.0, 0.0), None) };
    let mut best = parts.score(sc, cfg, frame, models, e, search.similarity, search.template);
    for _ in 0..search.rounds {
        let mut next = None;
        for (mx, my) in [(sx, 0.0), (-sx, 0.0), (0.0, sy), (0.0, -sy)] {
            // The offset summed first: the winner is then exactly the box
            // the caller moves the estimate to, whose parts these are.
            let c = Ellipse { cx: e.cx + (dx + mx), cy: e.cy + (dy + my), ..*e };
            if !(c.cx >= 0.0 && c.cx <= w && c.cy >= 0.0 && c.cy <= h) {
                continue;
            }
            let Some(mut p) = Parts::of(sc, &c) else { continue };
            let score = p.score(sc, cfg, frame, models, &c, search.similarity, search.template);
            if score > best {
                (best, next) = (score, Some((mx, my, p)));
            }
        }
        let Some((mx, my, p)) = next else { break };
        (dx, dy, parts) = (dx + mx, dy + my, p);
    }
    ((dx, dy), Some(parts))
}

/// Spots re-detection proposes.
const SPOTS: usize = 4;

/// The centres of the (at most [`SPOTS`]) target-sized boxes of `frame`
/// that stand out most from their surroundings in the foreground map,
/// best first, at least one box apart.
fn redetect<const K: usize>(
    map: &mut ForegroundMap<FG_CELLS>,
    frame: &Frame<'_>,
    models: &Models<K>,
    (hx, hy): (Real, Real),
) -> [Option<(Real, Real)>; SPOTS] {
    let (w, h) = (frame.width() as i32, frame.height() as i32);
    map.compute(frame, (0, 0, w, h), &models.layout, &models.fg);
    let stride = hx.min(hy).max(map.step() as Real);
    let mut best: [Option<(Real, Real, Real)>; SPOTS] = [None; SPOTS];
    let mut y = hy;
    while y < h as Real - hy {
        let mut x = hx;
        while x < w as Real - hx {
            if let Some(c) = map.contrast(&Ellipse { cx: x, cy: y, hx, hy }, RING) {
                // Insert into the list if it beats an entry and is not next to a better one.
                let near = |&(bx, by, _): &(Real, Real, Real)| (bx - x).abs() < 2.0 * hx && (by - y).abs() < 2.0 * hy;
                let dominated = best.iter().flatten().any(|b| near(b) && b.2 >= c);
                if !dominated && c > 0.0 {
                    // Weaker neighbours make way; the rest keep their order.
                    let mut kept = [None; SPOTS];
                    for (slot, b) in kept.iter_mut().zip(best.iter().flatten().filter(|b| !near(b))) {
                        *slot = Some(*b);
                    }
                    // The candidate goes before the first spot it matches or
                    // beats; each one it displaces moves down, the last drops.
                    let mut item = Some((x, y, c));
                    for slot in kept.iter_mut() {
                        let Some(i) = item else { break };
                        match slot {
                            Some(b) if b.2 > i.2 => {}
                            _ => item = slot.replace(i),
                        }
                    }
                    best = kept;
                }
            }
            x += stride;
        }
        y += stride;
    }
    best.map(|b| b.map(|(x, y, _)| (x, y)))
}

/// Moves the estimate and every particle by `(dx, dy)`. Centres stay in the
/// frame, as the dynamics keep them; the estimate, in the frame, stays
/// inside the particles' hull.
fn shift_estimate<const N: usize>(
    ellipse: &mut Ellipse,
    particles: &mut [Particle; N],
    (dx, dy): (Real, Real),
    frame: &Frame<'_>,
) {
    let (w, h) = (frame.width() as Real, frame.height() as Real);
    // Clamped as the particles are, so that the estimate stays their mean's
    // image: inside the frame and inside their hull (clamping is monotone).
    ellipse.cx = crate::scalar::clamp(ellipse.cx + dx, 0.0, w);
    ellipse.cy = crate::scalar::clamp(ellipse.cy + dy, 0.0, h);
    for p in particles.iter_mut() {
        p.x = crate::scalar::clamp(p.x + dx, 0.0, w);
        p.y = crate::scalar::clamp(p.y + dy, 0.0, h);
    }
}

/// Scales the estimate's half axes and every particle's by `(fx, fy)`, so
/// that the filter goes on from the size found.
fn scale_estimate<const N: usize>(ellipse: &mut Ellipse, particles: &mut [Particle; N], (fx, fy): (Real, Real)) {
    ellipse.hx *= fx;
    ellipse.hy *= fy;
    for p in particles.iter_mut() {
        p.hx *= fx;
        p.hy *= fy;
    }
}

/// A particle at rest anywhere in a `width × height` frame.
fn uniform_particle<R: Rng>(rng: &mut R, width: usize, height: usize, hx: Real, hy: Real) -> Particle {
    let x = unit_from_bits(rng.next_u32()) * width as Real;
    let y = unit_from_bits(rng.next_u32()) * height as Real;
    Particle { x, y, hx, hy, ..Default::default() }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colour::Binning;
    use crate::config::{CorrelationCue, EdgeCue};
    use crate::frame::PixelFormat;
    use crate::histogram::Similarity;

    const W: usize = 120;
    const H: usize = 90;

    /// A grey RGB888 frame with a 32x32 target at (44, 29) whose quadrants
    /// are red, green, blue and yellow; `cover` paints a white rectangle
    /// (x, y, w, h) over it.
    fn scene(cover: Option<(usize, usize, usize, usize)>, shade: u8) -> Vec<u8> {
        let mut px = vec![100u8; W * H * 3];
        let colours = [[220, 30, 30], [30, 200, 30], [30, 30, 220], [220, 220, 30]];
        for y in 29..61 {
            for x in 44..76 {
                let q = (x >= 60) as usize + 2 * (y >= 45) as usize;
                let c = colours[q].map(|v: u8| v.saturating_sub(shade));
                px[(y * W + x) * 3..][..3].copy_from_slice(&c);
            }
        }
        if let Some((cx, cy, cw, ch)) = cover {
            for y in cy..cy + ch {
                for x in cx..cx + cw {
                    px[(y * W + x) * 3..][..3].copy_from_slice(&[255, 255, 255]);
                }
            }
        }
        px
    }

    fn frame(px: &[u8]) -> Frame<'_> {
        Frame::packed(px, W, H, PixelFormat::Rgb888).unwrap()
    }

    const BOX: BoundingBox = BoundingBox::new(44.0, 29.0, 32.0, 32.0);

    #[test]
    fn the_shift_search_climbs_onto_the_target() {
        // Reason: generated scene with known geometry. On the map of the
        // learnt odds, a box the target's size has the most contrast where it
        // covers the target exactly: each step towards it takes in target
        // and gives its ring background. From 4 px right of and 3 px above
        // the target, steps of 1.6 px (5% of the 32 px box) climb to within
        // a step of it, left and down; a box already on it stays.
        let px = scene(None, 0);
        let f = frame(&px);
        let mut t: Tracker<60> = Tracker::new(Config::default(), 1).unwrap();
        t.init(&f, BOX).unwrap();
        let Tracker { config: cfg, scratch, target, .. } = &mut t;
        let models = &target.as_ref().unwrap().models;
        let shift = crate::config::ShiftSearch { step: 0.05, rounds: 4, similarity: 3.0, template: 0.0 };
        let on = Ellipse { cx: 60.0, cy: 45.0, hx: 16.0, hy: 16.0 };
        let off = Ellipse { cx: 64.0, cy: 42.0, ..on };
        scratch.fgmap.compute_around(&f, &on, 2.0, &models.layout, &models.fg);
        let (dx, dy) = search_shift(scratch, cfg, &f, models, &off, &shift, None).0;
        assert!(dx < 0.0 && (4.0 + dx).abs() <= 1.6, "dx {dx}");
        assert!(dy > 0.0 && (dy - 3.0).abs() <= 1.6, "dy {dy}");
        assert_eq!(search_shift(scratch, cfg, &f, models, &on, &shift, None).0, (0.0, 0.0));
    }

    #[test]
    fn a_soft_target_keeps_its_edge_cue() {
        // Reason: generated scene. The target is a checker of 4-px squares
        // of grey 100 and 110 on a flat 100 background: its steps of 10 grey
        // levels give Sobel strengths of at most 4·10·√2 ≈ 57, so no pixel
        // reaches the default threshold of 100. With the threshold fixed the
        // edge histogram is empty and the cue has no model; lowered to what
        // 10% of the pixels reach, it is below 57 and the cue learns one.
        let mut px = vec![100u8; W * H * 3];
        for y in 29..61 {
            for x in 44..76 {
                if (x / 4 + y / 4) % 2 == 1 {
                    px[(y * W + x) * 3..][..3].fill(110);
                }
            }
        }
        let f = frame(&px);
        let fixed = EdgeCue { strong_percent: 0, ..Config::default().edges.unwrap() };
        let mut t: Tracker<20> = Tracker::new(Config { edges: Some(fixed), ..Config::default() }, 1).unwrap();
        t.init(&f, BOX).unwrap();
        assert_eq!(t.edge_threshold(), Some(100));
        assert!(t.edge_model().is_none(), "no gradient reaches 100");
        let mut t: Tracker<20> = Tracker::new(Config::default(), 1).unwrap();
        t.init(&f, BOX).unwrap();
        let th = t.edge_threshold().unwrap();
        assert!((crate::config::MIN_EDGE_THRESHOLD..=57).contains(&th), "threshold {th}");
        assert!(t.edge_model().is_some(), "the lowered threshold keeps the texture's edges");
        let mut t: Tracker<20> = Tracker::new(Config { edges: None, ..Config::default() }, 1).unwrap();
        t.init(&f, BOX).unwrap();
        assert_eq!(t.edge_threshold(), None, "no cue, no threshold");
    }

    #[test]
    fn the_template_term_places_a_box_that_colour_cannot() {
        // Reason: generated scene with known geometry. Every pixel is grey
        // 64 or 95, in 8x8 blocks drawn at random: both levels fall in RGB
        // 8x8x8 bin 2, so every box has the same colour histogram (contrast
        // and similarity are flat, and without the template no step beats
        // the box it starts from), while the blocks' layout of light and
        // dark is unique. The template's correlation falls off over a block
        // (8 px) as a box slides off the learnt spot, so from 4 px right of
        // and 3 px above it, steps of 1.6 px climb back to within a step.
        let mut next = crate::testing::lcg(7);
        let levels: Vec<u8> = (0..(W / 8 + 1) * (H / 8 + 1)).map(|_| if next() >> 31 == 1 { 95 } else { 64 }).collect();
        let mut px = vec![0u8; W * H * 3];
        for y in 0..H {
            for x in 0..W {
                px[(y * W + x) * 3..][..3].fill(levels[(y / 8) * (W / 8 + 1) + x / 8]);
            }
        }
        let f = frame(&px);
        let cfg = Config { edges: None, ..Config::default() };
        let mut t: Tracker<60> = Tracker::new(cfg, 1).unwrap();
        t.init(&f, BOX).unwrap();
        let Tracker { config: cfg, scratch, target, .. } = &mut t;
        let models = &target.as_ref().unwrap().models;
        let on = Ellipse { cx: 60.0, cy: 45.0, hx: 16.0, hy: 16.0 };
        let off = Ellipse { cx: 64.0, cy: 42.0, ..on };
        scratch.fgmap.compute_around(&f, &on, 2.0, &models.layout, &models.fg);
        let shift = crate::config::ShiftSearch { rounds: 4, ..cfg.shift.unwrap() };
        let colour_only = crate::config::ShiftSearch { template: 0.0, ..shift };
        assert_eq!(search_shift(scratch, cfg, &f, models, &off, &colour_only, None).0, (0.0, 0.0));
        let (dx, dy) = search_shift(scratch, cfg, &f, models, &off, &shift, None).0;
        assert!(dx < 0.0 && (4.0 + dx).abs() <= 1.6, "dx {dx}");
        assert!(dy > 0.0 && (dy - 3.0).abs() <= 1.6, "dy {dy}");
    }

    #[test]
    fn median_of_four_and_the_occluded_quadrant_by_hand() {
        // Reason: hand values. The median of 4 is the mean of the middle two.
        assert_eq!(median4([0.9, 0.1, 0.8, 0.7]), 0.75);
        assert_eq!(median4([0.2, 0.2, 0.2, 0.2]), 0.2);
        assert_eq!(median4([1.0, 0.0, 0.5, 0.5]), 0.5);
        // Exactly one quadrant at or below the threshold is an occlusion.
        assert_eq!(occluded([0.9, 0.3, 0.8, 0.85], 0.5), Some(1));
        assert_eq!(occluded([0.9, 0.3, 0.2, 0.85], 0.5), None, "two bad: not partial");
        assert_eq!(occluded([0.9, 0.9, 0.8, 0.85], 0.5), None);
        assert_eq!(occluded([0.9, 0.9, 0.8, 0.5], 0.5), Some(3), "at the threshold fails the strict test");
    }

    #[cfg(feature = "quadrants")]
    #[test]
    fn a_covered_quadrant_is_reported_as_a_partial_occlusion() {
        // Reason: generated scene with known geometry: a white patch covers
        // the target's top-left (red) quadrant exactly, so that quadrant's
        // histogram shares nothing with its model while the other three still
        // match perfectly. The median similarity stays high, the estimate
        // stays on the target, and the estimate names quadrant 0. Before and
        // after the occlusion, nothing is reported.
        // The size search is off: it rightly shrinks the box away from a
        // covered quadrant (no longer the target's colours), which moves the
        // split between the quadrants this test is about.
        let cfg = Config { quadrants: true, binning: Binning::Rgb4x4x4, edges: None, size: None, ..Config::default() };
        let mut t: Tracker<60> = Tracker::new(cfg, 3).unwrap();
        let clear = scene(None, 0);
        t.init(&frame(&clear), BOX).unwrap();
        for _ in 0..3 {
            let e = t.step(&frame(&clear)).unwrap();
            assert_eq!(e.occluded_quadrant, None);
        }
        let covered = scene(Some((44, 29, 16, 16)), 0);
        let mut flagged = 0;
        for _ in 0..5 {
            let e = t.step(&frame(&covered)).unwrap();
            assert_eq!(e.state, TrackState::Tracking);
            let (cx, cy) = e.bbox().centre();
            assert!((cx - 60.0).abs() < 4.0 && (cy - 45.0).abs() < 4.0, "({cx}, {cy})");
            if e.occluded_quadrant == Some(0) {
                flagged += 1;
            }

            assert!(matches!(e.occluded_quadrant, None | Some(0)), "{:?}", e.occluded_quadrant);
        }
        // A majority: as frames pass, the estimate drifts up to ~2.5 px
        // towards the visible part (measured), which moves the quadrant
        // split so that the covered quadrant takes in some of the target.
        assert!(flagged >= 3, "flagged on {flagged} of 5 frames");
        for _ in 0..3 {
            t.step(&frame(&clear)).unwrap();
        }
        assert_eq!(t.step(&frame(&clear)).unwrap().occluded_quadrant, None);
    }

    #[test]
    fn the_correlation_filter_needs_its_feature_and_sane_settings() {
        // Reason: a build without the `correlation` feature has no filter,
        // and a setting outside its documented range is named, not clamped.
        let on = Config { correlation: Some(CorrelationCue::MEASURED), ..Config::default() };
        if !cfg!(feature = "correlation") {
            let err = Tracker::<10>::new(on, 1).unwrap_err();
            let want = ConfigError { field: "correlation", problem: ParamProblem::NotBuilt { feature: "correlation" } };
            assert_eq!(err, Error::Config(want));
            return;
        }
        assert!(Tracker::<10>::new(on, 1).is_ok());
        let m = CorrelationCue::MEASURED;
        for (cue, field, problem) in [
            (CorrelationCue { padding: 0.5, ..m }, "correlation.padding", ParamProblem::OutOfRange),
            (CorrelationCue { padding: Real::NAN, ..m }, "correlation.padding", ParamProblem::NonFinite),
            (CorrelationCue { rate: 0.0, ..m }, "correlation.rate", ParamProblem::OutOfRange),
            (CorrelationCue { learn_above: 1.5, ..m }, "correlation.learn_above", ParamProblem::OutOfRange),
            (CorrelationCue { pull: Real::INFINITY, ..m }, "correlation.pull", ParamProblem::NonFinite),
            (CorrelationCue { scale_step: 0.5, ..m }, "correlation.scale_step", ParamProblem::OutOfRange),
            (CorrelationCue { scale_pull: Real::NAN, ..m }, "correlation.scale_pull", ParamProblem::NonFinite),
            (CorrelationCue { min_psr: -1.0, ..m }, "correlation.min_psr", ParamProblem::OutOfRange),
        ] {
            let err = Tracker::<10>::new(Config { correlation: Some(cue), ..Config::default() }, 1).unwrap_err();
            assert_eq!(err, Error::Config(ConfigError { field, problem }));
        }
    }

    #[cfg(feature = "correlation")]
    #[test]
    fn the_correlation_filter_follows_a_texture_colour_cannot_place() {
        // Reason: generated scene with known motion. Every pixel is grey 64
        // or 95 in 8x8 blocks drawn at random, both in one RGB 8x8x8 bin,
        // so every box has the same colour histogram; the whole texture
        // pans 2 px right and 1 px down a frame, so the content first boxed
        // is centred at (60 + 2t, 45 + t) in frame t. The filter sees the
        // layout of light and dark and places the box within 2 px (half of
        // its window's 4-px cells, after the sub-cell fit).
        let mut next = crate::testing::lcg(11);
        let (bw, bh) = (W / 8 + 4, H / 8 + 4);
        let levels: Vec<u8> = (0..bw * bh).map(|_| if next() >> 31 == 1 { 95 } else { 64 }).collect();
        let scene = |t: usize| {
            let mut px = vec![0u8; W * H * 3];
            for y in 0..H {
                for x in 0..W {
                    let (u, v) = (x + 24 - 2 * t, y + 24 - t);
                    px[(y * W + x) * 3..][..3].fill(levels[(v / 8) * bw + u / 8]);
                }
            }
            px
        };
        let cfg = Config { edges: None, correlation: Some(CorrelationCue::MEASURED), ..Config::default() };
        let mut t: Tracker<60> = Tracker::new(cfg, 1).unwrap();
        t.init(&frame(&scene(0)), BOX).unwrap();
        for k in 1..=10 {
            let e = t.step(&frame(&scene(k))).unwrap();
            let (cx, cy) = e.bbox().centre();
            let (x, y) = (60.0 + 2.0 * k as Real, 45.0 + k as Real);
            assert!((cx - x).abs() <= 2.0 && (cy - y).abs() <= 2.0, "frame {k}: ({cx}, {cy}) against ({x}, {y})");
        }
        // Gated at a PSR no response reaches, the filter moves nothing: the
        // track is the colour cues' alone, bit for bit (the filter still
        // learns and reports its PSR, which the estimate does not read),
        // and colour alone cannot follow the texture.
        let gated = Config { correlation: Some(CorrelationCue { min_psr: 20.0, ..CorrelationCue::MEASURED }), ..cfg };
        let colour = Config { correlation: None, ..cfg };
        let (mut a, mut b): (Tracker<60>, Tracker<60>) =
            (Tracker::new(gated, 1).unwrap(), Tracker::new(colour, 1).unwrap());
        a.init(&frame(&scene(0)), BOX).unwrap();
        b.init(&frame(&scene(0)), BOX).unwrap();
        let mut off = 0;
        for k in 1..=10 {
            let (ea, eb) = (a.step(&frame(&scene(k))).unwrap(), b.step(&frame(&scene(k))).unwrap());
            assert_eq!(ea.ellipse, eb.ellipse, "frame {k}");
            assert!(a.diagnostics().psr < 20.0);
            let (cx, cy) = ea.bbox().centre();
            if (cx - 60.0 - 2.0 * k as Real).abs() > 2.0 || (cy - 45.0 - k as Real).abs() > 2.0 {
                off += 1;
            }
        }
        assert!(off > 0, "colour alone followed the texture on every frame");
    }

    #[test]
    fn quadrants_need_room_and_the_feature() {
        // Reason: four quadrant blocks of 512 bins do not fit a 512-bin
        // capacity; the error names the field rather than truncating bins.
        let cfg = Config { quadrants: true, ..Config::default() };
        let err = Tracker::<10>::new(cfg, 1).unwrap_err();
        assert!(matches!(err, Error::Config(ConfigError { field: "quadrants", .. })), "{err:?}");
        if !cfg!(feature = "quadrants") {
            let cfg = Config { quadrants: true, binning: Binning::Rgb4x4x4, ..Config::default() };
            let err = Tracker::<10>::new(cfg, 1).unwrap_err();
            assert_eq!(
                err,
                Error::Config(ConfigError {
                    field: "quadrants",
                    problem: ParamProblem::NotBuilt { feature: "quadrants" }
                })
            );
        }
    }

    #[test]
    fn the_surroundings_motion_test_needs_its_feature() {
        // Reason: a build without the `scene-motion` feature has no such
        // test; asking for it is an error naming the field and the feature.
        let cfg = Config { scene_motion: true, ..Config::default() };
        let got = Tracker::<10>::new(cfg, 1).err();
        if cfg!(feature = "scene-motion") {
            assert_eq!(got, None);
        } else {
            let want =
                ConfigError { field: "scene_motion", problem: ParamProblem::NotBuilt { feature: "scene-motion" } };
            assert_eq!(got, Some(Error::Config(want)));
        }
    }

    #[test]
    fn intersection_tracks_like_bhattacharyya_on_a_clean_scene() {
        // Reason: on an unoccluded, unmoving target both similarities are
        // maximal at the truth (identical histograms give 1 under both), so
        // either keeps the estimate there.
        for similarity in [Similarity::Bhattacharyya, Similarity::Intersection] {
            let cfg = Config { similarity, ..Config::default() };
            let mut t: Tracker<60> = Tracker::new(cfg, 5).unwrap();
            let clear = scene(None, 0);
            t.init(&frame(&clear), BOX).unwrap();
            for _ in 0..5 {
                let e = t.step(&frame(&clear)).unwrap();
                let (cx, cy) = e.bbox().centre();
                assert!((cx - 60.0).abs() < 3.0 && (cy - 45.0).abs() < 3.0, "{similarity:?}: ({cx}, {cy})");
                assert!(e.confidence > 0.8, "{similarity:?}: {}", e.confidence);
            }
        }
    }

    #[test]
    fn scale_prior_bounds_every_particle_and_bad_priors_are_errors() {
        // Reason: the prior's definition: after a step with it, every
        // particle's shorter half axis is within half_minor ± tolerance
        // (the target's true half axis is 16; the prior says 10 ± 1).
        let mut t: Tracker<60> = Tracker::new(Config::default(), 9).unwrap();
        let clear = scene(None, 0);
        t.init(&frame(&clear), BOX).unwrap();
        let prior = ScalePrior { half_minor: 10.0, tolerance: 1.0 };
        for _ in 0..3 {
            t.step_with_prior(&frame(&clear), prior).unwrap();
            for p in t.particles() {
                let minor = p.hx.min(p.hy);
                assert!((9.0 - 1e-3..=11.0 + 1e-3).contains(&minor), "{p:?}");
            }
        }
        let before = *t.particles();
        for (bad, field) in [
            (ScalePrior { half_minor: Real::NAN, tolerance: 1.0 }, "prior.half_minor"),
            (ScalePrior { half_minor: 0.5, tolerance: 1.0 }, "prior.half_minor"),
            (ScalePrior { half_minor: 10.0, tolerance: -1.0 }, "prior.tolerance"),
            (ScalePrior { half_minor: 10.0, tolerance: Real::INFINITY }, "prior.tolerance"),
        ] {
            match t.step_with_prior(&frame(&clear), bad) {
                Err(Error::Config(ConfigError { field: f, .. })) => assert_eq!(f, field),
                other => panic!("{bad:?}: {other:?}"),
            }
        }
        assert_eq!(t.particles(), &before, "a rejected prior leaves the tracker as it was");
    }

    #[test]
    fn table_mode_follows_a_moving_target_and_needs_capacity() {
        // Reason: ground truth of the generated scene: the target moves 2 px
        // right per frame; the table covers the particles' centres, so the
        // best cell is the truth within the grid spacing, and the estimate
        // follows. Size stays fixed in table mode.
        let cfg = Config { table: Some(TableMode { spacing: 1 }), ..Config::default() };
        assert!(matches!(
            Tracker::<60>::new(cfg, 1),
            Err(Error::Config(ConfigError { field: "table", problem: ParamProblem::OutOfRange }))
        ));
        let mut t: Tracker<60, 512, 4096, Xoshiro128PlusPlus, 4096> = Tracker::new(cfg, 4).unwrap();
        let shifted = |dx: usize| {
            let base = scene(None, 0);
            let mut px = vec![100u8; W * H * 3];
            for y in 0..H {
                for x in dx..W {
                    px[(y * W + x) * 3..][..3].copy_from_slice(&base[(y * W + x - dx) * 3..][..3]);
                }
            }
            px
        };
        t.init(&frame(&shifted(0)), BOX).unwrap();
        for k in 1..=10 {
            let e = t.step(&frame(&shifted(2 * k))).unwrap();
            let (cx, cy) = e.bbox().centre();
            assert!((cx - (60.0 + 2.0 * k as f32)).abs() < 3.0 && (cy - 45.0).abs() < 3.0, "frame {k}: ({cx}, {cy})");
            assert_eq!((e.ellipse.hx, e.ellipse.hy), (16.0, 16.0));
        }
        assert_eq!(t.table_spacing(), Some(1));
        // A table that cannot use the Bhattacharyya sum incrementally is refused.
        let bad = Config { similarity: Similarity::Intersection, ..cfg };
        assert!(Tracker::<60, 512, 4096, Xoshiro128PlusPlus, 4096>::new(bad, 1).is_err());
    }

    #[test]
    fn redetection_finds_the_target_where_its_colours_stand_out() {
        // Reason: ground truth of the generated scene. The tracker learns
        // the four-coloured target and its grey surroundings; in a frame
        // where the target has jumped to the far corner, the place whose
        // colours stand out most from their ring is the target's new box,
        // within the map's lattice step and the scan's stride (16 px at
        // this size).
        let cfg = Config { redetect: true, ..Config::default() };
        let mut t: Tracker<20> = Tracker::new(cfg, 1).unwrap();
        t.init(&frame(&scene(None, 0)), BOX).unwrap();
        let mut moved = vec![100u8; W * H * 3];
        let base = scene(None, 0);
        for y in 29..61 {
            for x in 44..76 {
                let (nx, ny) = (x + 40, y + 26);
                if nx < W && ny < H {
                    moved[(ny * W + nx) * 3..][..3].copy_from_slice(&base[(y * W + x) * 3..][..3]);
                }
            }
        }
        let target = t.target.as_ref().unwrap();
        let spots = redetect(&mut t.scratch.fgmap, &frame(&moved), &target.models, target.half_axes);
        let (x, y) = spots[0].expect("a spot");
        // The target's centre is now (100, 71), 4 px from the frame's bottom.
        assert!((x - 100.0).abs() <= 16.0 && (y - 71.0).abs() <= 16.0, "({x}, {y})");
    }

    #[test]
    fn update_when_degraded_waits_for_the_model_to_go_bad() {
        // Reason: the rule's definition. On an unchanging scene the
        // confidence stays at its learnt ρ₀, above 0.9·ρ₀, so the model is
        // never updated; the first paper's rule updates on such confident
        // frames. When the target darkens its colours move to other bins,
        // confidence falls below 0.9·ρ₀ (measured: 0.88 at a 20-level
        // shade) and the model adapts.
        let degraded =
            Config { model_update: ModelUpdate::WhenDegraded { factor: 0.9, frames: 3 }, ..Config::default() };
        let mut t: Tracker<60> = Tracker::new(degraded, 2).unwrap();
        let clear = scene(None, 0);
        t.init(&frame(&clear), BOX).unwrap();
        for _ in 0..8 {
            assert!(!t.step(&frame(&clear)).unwrap().model_updated);
        }
        // Darken by 2 levels a frame up to 20, where the target is still
        // seen: colours cross bin edges a few at a time.
        let mut updated = 0;
        for k in 1..=10u8 {
            let e = t.step(&frame(&scene(None, 2 * k))).unwrap();
            updated += e.model_updated as u32;
            assert_eq!(e.state, TrackState::Tracking, "darkened by {}", 2 * k);
        }
        assert!(updated > 0, "never adapted to the darker target");

        let mut c: Tracker<60> = Tracker::new(Config::default(), 2).unwrap();
        c.init(&frame(&clear), BOX).unwrap();
        let updated = (0..8).filter(|_| c.step(&frame(&clear)).unwrap().model_updated).count();
        assert!(updated >= 6, "the confident rule updates on confident frames: {updated} of 8");
    }
}
