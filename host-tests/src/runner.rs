//! Runs the core tracker over a sequence of frames and times it.

use pftrack::{BoundingBox, Config, Estimate, Frame, MeanShift, MeanShiftConfig, Tracker};
use std::time::Instant;

/// Particle count of the host harness (the papers' 100).
pub const PARTICLES: usize = 100;

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
    /// Every 4th particle's centre after each step (for pictures).
    pub particles: Vec<Vec<(f32, f32)>>,
    /// The particle filter's diagnostics after each step (empty for mean shift).
    pub diagnostics: Vec<pftrack::Diagnostics>,
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
    progress: impl FnMut(usize, usize),
) -> Result<Run, pftrack::Error> {
    match method {
        Method::Pf => track(config, seed, frames, init, progress),
        Method::Meanshift => track_meanshift(MeanShiftConfig::default(), frames, init, progress),
        Method::Kalman => track_meanshift(MeanShiftConfig::kalman(), frames, init, progress),
    }
}

/// Tracks `frames` with mean shift configured by `config`.
pub fn track_meanshift<'a>(
    config: MeanShiftConfig,
    frames: &[Frame<'a>],
    init: BoundingBox,
    progress: impl FnMut(usize, usize),
) -> Result<Run, pftrack::Error> {
    let mut tracker: Box<MeanShift> = Box::new(MeanShift::new(config)?);
    let first = frames.first().ok_or(pftrack::Error::NotInitialised)?;
    tracker.init(first, init)?;
    run_steps(frames, init, config.min_similarity, progress, |f| {
        let t0 = Instant::now();
        let est = tracker.step(f)?;
        Ok((est, ms_since(t0), Vec::new()))
    })
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
    let mut tracker = Box::new(HostTracker::new(config, seed)?);
    let first = frames.first().ok_or(pftrack::Error::NotInitialised)?;
    tracker.init(first, init)?;
    let threshold = tracker.appearance_threshold().unwrap_or(0.0);
    let levels = tracker.colour_levels();
    let mut diagnostics = Vec::new();
    let mut run = run_steps(frames, init, threshold, progress, |f| {
        let t0 = Instant::now();
        let est = tracker.step(f)?;
        let ms = ms_since(t0);
        diagnostics.push(tracker.diagnostics());
        Ok((est, ms, tracker.particles().iter().step_by(4).map(|p| (p.x, p.y)).collect()))
    })?;
    run.colour_levels = levels;
    run.diagnostics = diagnostics;
    Ok(run)
}

fn ms_since(t0: Instant) -> f64 {
    t0.elapsed().as_secs_f64() * 1e3
}

/// The loop over frames 2.. shared by every tracker: `step` returns the
/// estimate, the milliseconds its `step` call took (timed by the caller, so
/// that collecting particles for pictures is not counted), and the particle
/// centres to draw.
fn run_steps<'a>(
    frames: &[Frame<'a>],
    init: BoundingBox,
    threshold: f32,
    mut progress: impl FnMut(usize, usize),
    mut step: impl FnMut(&Frame<'a>) -> Result<(Estimate, f64, Vec<(f32, f32)>), pftrack::Error>,
) -> Result<Run, pftrack::Error> {
    let mut run = Run {
        boxes: vec![init],
        estimates: Vec::new(),
        step_ms: Vec::new(),
        threshold,
        colour_levels: None,
        particles: Vec::new(),
        diagnostics: Vec::new(),
    };
    for (i, f) in frames.iter().enumerate().skip(1) {
        let (est, ms, particles) = step(f)?;
        run.step_ms.push(ms);
        run.boxes.push(est.bbox());
        run.estimates.push(est);
        run.particles.push(particles);
        progress(i + 1, frames.len());
    }
    Ok(run)
}
