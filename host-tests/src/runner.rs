//! Runs the core tracker over a sequence of frames and times it.

use pftrack::{BoundingBox, Config, Estimate, Frame, MeanShift, MeanShiftConfig, Tracker};
use std::time::Instant;

/// Particle count of the host harness: the papers' 100, or the number in
/// `PFTRACK_PARTICLES` when the harness is built (1 to 1000), to measure
/// what another `Tracker<N>` would do with `track`, e.g.
/// `PFTRACK_PARTICLES=200 cargo run --release -p host-tests --bin track -- ablate ...`.
/// The tests and `soak` build their own `Tracker<100>`: their thresholds
/// are for 100.
pub const PARTICLES: usize = match option_env!("PFTRACK_PARTICLES") {
    Some(n) => parse_count(n),
    None => 100,
};

/// A decimal count from 1 to 1000, at compile time: anything else stops
/// the build with the reason.
const fn parse_count(s: &str) -> usize {
    match usize::from_str_radix(s, 10) {
        Ok(0) => panic!("PFTRACK_PARTICLES is 0"),
        Ok(n) if n > 1000 => panic!("PFTRACK_PARTICLES is over 1000"),
        Ok(n) => n,
        Err(_) => panic!("PFTRACK_PARTICLES is not a decimal number"),
    }
}

/// Edge-map bytes of the harness's tracker: the core's default, as on the
/// firmware, so that the accuracy measured here is what a board gets (4-bit
/// cells: 8192 lattice points, which the real sequences' particles fit at
/// full resolution; see `pftrack::EdgeMap`).
pub const EDGE_CELLS: usize = 4096;

/// Likelihood-table cells of the harness's tracker (table mode): a 128x128
/// grid of candidate positions at the finest spacing.
pub const TABLE_CELLS: usize = 16384;

/// The tracker type the harness uses.
pub type HostTracker = Tracker<PARTICLES, 512, EDGE_CELLS, rand_xoshiro::Xoshiro128PlusPlus, TABLE_CELLS>;

/// The group the host tools track several targets with: up to
/// [`GROUP_TARGETS`] of them, each as [`HostTracker`] follows one.
pub type HostGroup =
    pftrack::Group<GROUP_TARGETS, PARTICLES, 512, EDGE_CELLS, rand_xoshiro::Xoshiro128PlusPlus, TABLE_CELLS>;

/// The most targets `track run` follows at once.
pub const GROUP_TARGETS: usize = 8;

/// Which tracker runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum Method {
    /// The colour particle filter ([`pftrack::Tracker`]), with the given [`Config`].
    #[default]
    Pf,
    /// Mean shift ([`pftrack::MeanShift`], default configuration).
    Meanshift,
    /// Kalman-predicted mean shift ([`pftrack::MeanShiftConfig::kalman`]).
    Kalman,
}

impl Method {
    /// A short label for tables.
    pub fn label(self) -> &'static str {
        match self {
            Method::Pf => "pftrack particle filter",
            Method::Meanshift => "pftrack mean shift",
            Method::Kalman => "pftrack Kalman mean shift",
        }
    }
}

/// What a run produced.
#[derive(Debug, Clone)]
pub struct Run {
    /// One box per frame; the first is the initial box.
    pub boxes: Vec<BoundingBox>,
    /// One estimate per frame after the first.
    pub estimates: Vec<Estimate>,
    /// Wall time of each `step`, in milliseconds (decoding excluded).
    pub step_ms: Vec<f64>,
    /// The appearance threshold the tracker learnt at initialisation.
    pub threshold: f32,
    /// Levels per colour channel of each histogram block, as chosen at
    /// initialisation (meaningful for adaptive binning; `None` for mean shift).
    pub colour_levels: Option<[u8; 4]>,
    /// The edge cue's gradient threshold chosen at initialisation (`None`
    /// without the cue, and for mean shift).
    pub edge_threshold: Option<u16>,
    /// Every 4th particle's centre after each step (for pictures).
    pub particles: Vec<Vec<(f32, f32)>>,
    /// The particle filter's diagnostics after each step (empty for mean shift).
    pub diagnostics: Vec<pftrack::Diagnostics>,
}

/// A tracker of any [`Method`], stepped one frame at a time: what every
/// command drives, whether its frames sit in memory or stream past.
pub enum AnyTracker {
    /// The particle filter.
    Pf(Box<HostTracker>),
    /// Mean shift, plain or Kalman-predicted, with its similarity threshold.
    MeanShift(Box<MeanShift>, f32),
}

impl AnyTracker {
    /// A tracker of `method` (`config` and `seed` apply to the particle
    /// filter), initialised on `first` with `init`; returns it and the
    /// initialisation's estimate.
    pub fn start(
        method: Method,
        config: Config,
        seed: u64,
        first: &Frame<'_>,
        init: BoundingBox,
    ) -> Result<(Self, Estimate), pftrack::Error> {
        let ms = |c: MeanShiftConfig| -> Result<(Self, Estimate), pftrack::Error> {
            let mut t: Box<MeanShift> = Box::new(MeanShift::new(c)?);
            let est = t.init(first, init)?;
            Ok((AnyTracker::MeanShift(t, c.min_similarity), est))
        };
        match method {
            Method::Pf => {
                let mut t = Box::new(HostTracker::new(config, seed)?);
                let est = t.init(first, init)?;
                Ok((AnyTracker::Pf(t), est))
            }
            Method::Meanshift => ms(MeanShiftConfig::default()),
            Method::Kalman => ms(MeanShiftConfig::kalman()),
        }
    }

    /// Tracks one more frame.
    pub fn step(&mut self, frame: &Frame<'_>) -> Result<Estimate, pftrack::Error> {
        match self {
            AnyTracker::Pf(t) => t.step(frame),
            AnyTracker::MeanShift(t, _) => t.step(frame),
        }
    }

    /// The appearance threshold: learnt at initialisation by the particle
    /// filter, configured for mean shift.
    pub fn threshold(&self) -> f32 {
        match self {
            AnyTracker::Pf(t) => t.appearance_threshold().unwrap_or(0.0),
            AnyTracker::MeanShift(_, min) => *min,
        }
    }

    /// Every 4th particle's centre (none for mean shift), for pictures.
    pub fn particles(&self) -> Vec<(f32, f32)> {
        match self {
            AnyTracker::Pf(t) => t.particles().iter().step_by(4).map(|p| (p.x, p.y)).collect(),
            AnyTracker::MeanShift(..) => Vec::new(),
        }
    }

    /// The particle filter's diagnostics of the last step.
    pub fn diagnostics(&self) -> Option<pftrack::Diagnostics> {
        match self {
            AnyTracker::Pf(t) => Some(t.diagnostics()),
            AnyTracker::MeanShift(..) => None,
        }
    }

    /// The edge cue's threshold chosen at initialisation (particle filter
    /// with the cue only).
    pub fn edge_threshold(&self) -> Option<u16> {
        match self {
            AnyTracker::Pf(t) => t.edge_threshold(),
            AnyTracker::MeanShift(..) => None,
        }
    }

    /// The colour levels chosen at initialisation (particle filter only).
    pub fn colour_levels(&self) -> Option<[u8; 4]> {
        match self {
            AnyTracker::Pf(t) => t.colour_levels(),
            AnyTracker::MeanShift(..) => None,
        }
    }
}

impl Run {
    /// An empty run that starts from `init`.
    pub fn new(init: BoundingBox, tracker: &AnyTracker) -> Self {
        Run {
            boxes: vec![init],
            estimates: Vec::new(),
            step_ms: Vec::new(),
            threshold: tracker.threshold(),
            colour_levels: tracker.colour_levels(),
            edge_threshold: tracker.edge_threshold(),
            particles: Vec::new(),
            diagnostics: Vec::new(),
        }
    }

    /// Steps `tracker` on `frame` and records the estimate, the step's time
    /// (collecting particles for pictures is not counted) and the rest.
    pub fn step(&mut self, tracker: &mut AnyTracker, frame: &Frame<'_>) -> Result<Estimate, pftrack::Error> {
        let t0 = Instant::now();
        let est = tracker.step(frame)?;
        self.step_ms.push(ms_since(t0));
        self.boxes.push(est.bbox());
        self.estimates.push(est);
        self.particles.push(tracker.particles());
        self.diagnostics.extend(tracker.diagnostics());
        Ok(est)
    }
}

/// Tracks `frames` with `method`, initialised on the first with `init`
/// (`config` and `seed` apply to the particle filter). `progress` is called
/// after each frame with (done, total).
pub fn track_with<'a>(
    method: Method,
    config: Config,
    seed: u64,
    frames: &[Frame<'a>],
    init: BoundingBox,
    mut progress: impl FnMut(usize, usize),
) -> Result<Run, pftrack::Error> {
    let first = frames.first().ok_or(pftrack::Error::NotInitialised)?;
    let (mut tracker, _) = AnyTracker::start(method, config, seed, first, init)?;
    let mut run = Run::new(init, &tracker);
    for (i, f) in frames.iter().enumerate().skip(1) {
        run.step(&mut tracker, f)?;
        progress(i + 1, frames.len());
    }
    Ok(run)
}

/// Tracks `frames` with the particle filter, initialised on the first with
/// `init`. `progress` is called after each frame with (done, total).
pub fn track<'a>(
    config: Config,
    seed: u64,
    frames: &[Frame<'a>],
    init: BoundingBox,
    progress: impl FnMut(usize, usize),
) -> Result<Run, pftrack::Error> {
    track_with(Method::Pf, config, seed, frames, init, progress)
}

fn ms_since(t0: Instant) -> f64 {
    t0.elapsed().as_secs_f64() * 1e3
}

#[cfg(test)]
mod tests {
    use super::parse_count;

    #[test]
    fn a_particle_count_is_read_as_written() {
        // Reason: decimal digits, by hand.
        assert_eq!((parse_count("1"), parse_count("50"), parse_count("1000")), (1, 50, 1000));
    }

    #[test]
    #[should_panic(expected = "not a decimal number")]
    fn a_count_that_is_not_a_number_is_refused() {
        parse_count("2e2");
    }

    #[test]
    #[should_panic(expected = "over 1000")]
    fn a_count_over_a_thousand_is_refused() {
        parse_count("1001");
    }

    #[test]
    #[should_panic(expected = "is 0")]
    fn no_particles_is_refused() {
        parse_count("0");
    }
}
