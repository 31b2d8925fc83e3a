//! One step: predict, observe, estimate, the life cycle, adapt.

use super::confidence::{MOVES_WITH_SCENE, SPEED_RATE, TYPICAL_CONTRAST, on_target};
use super::scratch::*;
use super::search::*;
use super::{ScalePrior, Track, Tracker};
use crate::apart::{Alone, Apart};
use crate::config::{Life, LostSearch, ModelUpdate, Redetect};
use crate::cue::{Freedom, Verdict};
use crate::error::Error;
use crate::estimate::{Diagnostics, Estimate, Event, TrackState};
use crate::filter::{Bounds, Particle, mean_state, normal, resample, scale_estimate, shift_estimate};
use crate::foreground::RING;
use crate::frame::Frame;
use crate::geometry::Ellipse;
use crate::likelihood::gaussian;
use crate::scalar::{Real, clamp, sqrt};
use rand_core::Rng;

impl<const N: usize, const K: usize, const E: usize, R: Rng, const T: usize> Tracker<N, K, E, R, T> {
    /// Tracks one frame: resample, propagate, observe, estimate, then update
    /// the state machine and, when the estimate is trustworthy, the model.
    ///
    /// The frame must have the size the tracker was initialised with; any
    /// pixel format may be used.
    pub fn step(&mut self, frame: &Frame<'_>) -> Result<Estimate, Error> {
        self.track.step_inner(&mut self.scratch, frame, None, Alone)
    }

    /// [`Tracker::step`] with an external size measurement for this frame
    /// (see [`ScalePrior`]). A NaN, infinite or out-of-range prior is an
    /// [`Error::Config`] naming `prior.half_minor` or `prior.tolerance`, and
    /// the tracker is left as it was.
    pub fn step_with_prior(&mut self, frame: &Frame<'_>, prior: ScalePrior) -> Result<Estimate, Error> {
        prior.validate()?;
        self.track.step_inner(&mut self.scratch, frame, Some(prior), Alone)
    }
}

impl<const N: usize, const K: usize, R: Rng, const T: usize> Track<N, K, R, T> {
    /// One step, as its phases: predict where the target may be, observe
    /// each hypothesis, weigh them, estimate (and size) the target, decide
    /// its state, and adapt the models.
    pub(crate) fn step_inner<const E: usize, A: Apart>(
        &mut self,
        scratch: &mut Scratch<K, E>,
        frame: &Frame<'_>,
        prior: Option<ScalePrior>,
        apart: A,
    ) -> Result<Estimate, Error> {
        let target = self.target.as_ref().ok_or(Error::NotInitialised)?;
        let size = (frame.width(), frame.height());
        if size != target.frame {
            return Err(Error::FrameSizeChanged { expected: target.frame, got: size });
        }
        // Identities are at stake where another target is near.
        let near = self.held().is_some_and(|mine| apart.near(&mine));
        let n = self.hypotheses(near);
        self.predict(scratch, frame, prior, n);
        let observed = self.observe(scratch, frame, apart, n);
        if let Some(t) = self.target.as_ref() {
            let half_axes = t.half_axes;
            // The foreground map is dead from the prediction's re-detection
            // until the estimate builds it again: the cues work in its memory.
            let work = scratch.fgmap.lend();
            self.cues.rescore(&self.config, frame, (&self.particles, &mut self.weights), n, half_axes, work);
        }
        let sigma = self.weigh(observed.d2_max, n);
        // An external size measurement, or the table's fixed size, decides
        // the size: no search then.
        let sized = prior.is_some() || (T > 0 && self.config.table.is_some());
        let look = self.estimate(scratch, frame, &observed, (!sized, near), n);
        // Measured on every frame, so that its running means stay current.
        let stuck = self.cues.miss(&self.config, frame, &look.ellipse, self.state == TrackState::Tracking);
        let was_tracking = self.state == TrackState::Tracking;
        let taken = !was_tracking && apart.taken(&look.ellipse);
        let event = self.life_cycle(look.found && !stuck && !taken);
        if matches!(event, Some(Event::Acquired | Event::Reacquired)) {
            // Found again, the target is followed from the box that found
            // it: the hypotheses the search left scattered would otherwise
            // draw the next estimate back to look-alikes. Each keeps its
            // velocity, so that a moving target is not left behind.
            let at = Particle::at(&look.ellipse);
            for p in self.particles.iter_mut() {
                *p = Particle { vx: p.vx, vy: p.vy, ..at };
            }
            self.weights = [1.0 / N as Real; N];
        }
        self.settled |= self.state == TrackState::Tracking && self.misses == 0;
        self.follow(&look.ellipse, was_tracking);
        let model_updated = self.adapt(scratch, frame, &look, event, stuck);
        Ok(Estimate {
            ellipse: look.ellipse,
            confidence: if stuck { look.confidence * MOVES_WITH_SCENE } else { look.confidence },
            state: self.state,
            event,
            appearing: observed.appearing,
            model_updated,
            sigma,
            occluded_quadrant: look.occluded_quadrant,
        })
    }

    /// Resamples `n` hypotheses in proportion to the last step's weights
    /// into the first slots, moves them by the dynamics, and, while the
    /// target is not tracked, re-draws a share of them to keep exploring.
    pub(super) fn predict<const E: usize>(
        &mut self,
        scratch: &mut Scratch<K, E>,
        frame: &Frame<'_>,
        prior: Option<ScalePrior>,
        n: usize,
    ) {
        let Track { config: cfg, rng, particles, weights, target, state, misses, settled, .. } = self;
        let Some(target) = target.as_ref() else { return };
        let (w, h) = (frame.width(), frame.height());
        let bounds = Bounds { width: w as Real, height: h as Real, min_half: cfg.min_half_axis };
        // On the stack: the counts live only while the set is rewritten.
        let mut copies = [0u16; N];
        resample(particles, weights, &mut copies, n, cfg.resampling, rng);
        for p in particles.iter_mut().take(n) {
            cfg.dynamics.propagate(p, &bounds, target.speed, rng);
            if let Some(prior) = &prior {
                prior.apply(p);
            }
            if T > 0 && cfg.table.is_some() {
                // The table holds one window size: the target's.
                (p.hx, p.hy) = target.half_axes;
            }
        }
        let (hx, hy) = target.half_axes;
        // A tracked target missed before any step found it (its motion
        // unknown), or missed while it moves more than half its size a
        // frame, may have left the particles' reach.
        // Its speed over `FAST` times its size `2·sqrt(hx·hy)`, squared.
        let fast = target.speed * target.speed > 4.0 * FAST * FAST * hx * hy;
        let near =
            *state == TrackState::Tracking && cfg.redetect != Redetect::Off && *misses > 0 && (!*settled || fast);
        if *state == TrackState::Tracking && !near {
            return;
        }
        let reseed = (cfg.reseed_fraction * N as Real) as usize;
        let whole = (0.0, 0.0, w as Real, h as Real);
        // A lost target is looked for about where it was last found
        // (`LostSearch::Widening`), unless that was at the frame's edge
        // (within a half axis): it may have left the view there, and may
        // come back anywhere.
        let (fx, fy) = target.found_at;
        let inside = fx > 2.0 * hx && fy > 2.0 * hy && fx + 2.0 * hx < whole.2 && fy + 2.0 * hy < whole.3;
        let widening = match cfg.lost_search {
            LostSearch::Widening { growth } if *state == TrackState::Lost && inside => Some(growth * *misses as Real),
            _ => None,
        };
        // One square serves both searches near the target: about its last
        // estimate after a miss (`Redetect::Near`), or, lost, about where it
        // was last found, widening.
        let ((cx, cy), more) = if near { (target.centre, 0.0) } else { ((fx, fy), widening.unwrap_or(0.0)) };
        let reach = (NEAR_REACH + more) * hx.max(hy);
        let square = (cx - reach, cy - reach, cx + reach, cy + reach);
        let search = match widening {
            Some(_) => (square.0.max(0.0), square.1.max(0.0), square.2.min(whole.2), square.3.min(whole.3)),
            None => whole,
        };
        // Where to look: one call, so that the scan is built once.
        let area = if near { Some(square) } else { (cfg.redetect == Redetect::Frame).then_some(search) };
        let spots = match area {
            Some(area) => redetect(&mut scratch.fgmap, frame, &target.models, (hx, hy), area),
            None => [None; SPOTS],
        };
        let found = spots.iter().flatten().count();
        // While lost, the first of the others go back to where the target
        // was last found: one that went behind something reappears there,
        // and the rest of the search, spread wider, is most often on
        // look-alikes by then.
        let back = if *state == TrackState::Lost { reseed / BACK_SHARE } else { 0 };
        // Spread over the set: copies of one parent tend to sit together.
        let stride = N.checked_div(reseed).unwrap_or(N).max(1);
        for (i, p) in particles.iter_mut().step_by(stride).take(reseed).enumerate() {
            // Every other re-drawn particle goes to one of the spots in turn,
            // the first of the rest back to the place last found.
            let spot = if i % 2 == 0 && found > 0 {
                spots.get(i / 2 % found).copied().flatten()
            } else {
                (i < back).then_some((fx, fy))
            };
            *p = match spot {
                Some((x, y)) => {
                    let s = 0.1 * sqrt(4.0 * hx * hy);
                    let (dx, dy) = (normal(rng), normal(rng));
                    // A target found away from its last place moved there
                    // over the frames it was missed, and goes on moving.
                    let (vx, vy) = if near {
                        let m = *misses as Real;
                        ((x - target.centre.0) / m, (y - target.centre.1) / m)
                    } else {
                        (0.0, 0.0)
                    };
                    // A place near the frame's border may be jittered
                    // across it: centres stay inside, as the dynamics keep
                    // them. Clamped rather than through `keep_inside`: the
                    // velocity is the draw's own, and resetting it took
                    // flash the `Config::fast` build has not got.
                    let (x, y) = (clamp(x + s * dx, 0.0, bounds.width), clamp(y + s * dy, 0.0, bounds.height));
                    Particle { x, y, vx, vy, hx, hy }
                }
                // Near the target, only the places: the rest of the set
                // goes on tracking.
                None if near => continue,
                None => uniform_particle(rng, search, hx, hy),
            };
        }
    }

    /// The similarity with the models of each of the first `n` particles,
    /// left in `weights` (0 for the others).
    pub(super) fn observe<const E: usize, A: Apart>(
        &mut self,
        scratch: &mut Scratch<K, E>,
        frame: &Frame<'_>,
        apart: A,
        n: usize,
    ) -> Observed {
        let size = (frame.width(), frame.height());
        let table = if T > 0 { self.config.table } else { None };
        let Track { config: cfg, particles, target, .. } = self;
        let Some(target) = target.as_ref() else { return Observed::default() };
        // Edges first, once, over the region the particles cover.
        let rect = target.models.edge.is_some().then(|| {
            let (mut x0, mut y0, mut x1, mut y1) = (size.0, size.1, 0, 0);
            for p in particles.iter().take(n) {
                let (a, b, c, d) = cover(&p.ellipse(), size.0, size.1);
                (x0, y0, x1, y1) = (x0.min(a), y0.min(b), x1.max(c), y1.max(d));
            }
            (x0, y0, x1, y1)
        });
        scratch.prepare(cfg, frame, rect, target.half_axes, target.edge_threshold);
        // `T > 0` is known at compile time: without a table, none of its
        // code is built into the tracker (it would take flash for nothing).
        if let Some(mode) = table {
            self.fill_table(scratch, frame, mode);
        }
        let Track { config: cfg, particles, weights, target, table: tab, .. } = self;
        let Some(target) = target.as_ref() else { return Observed::default() };
        // The boundary scores (in 1/16 Sobel units; at most 1443 · 16 <
        // 2^16) wait until the best one, their normaliser, is known.
        let mut scores = [0u16; N];
        let mut out = Observed { appearing: 0, g_best: 0, d2_max: target.models.d2_max(cfg) };
        for w in weights.iter_mut().skip(n) {
            *w = 0.0;
        }
        for ((p, w), g) in particles.iter().zip(weights.iter_mut()).zip(scores.iter_mut()).take(n) {
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
            // A template kept for the searches and the confidence alone
            // (weight 0) costs the particles nothing.
            *w = match cfg.template {
                Some(t) if t.weight > 0.0 => {
                    (1.0 - t.weight) * sim + t.weight * target.models.template.correlation(frame, &e).max(0.0)
                }
                _ => sim,
            };
            if crate::boundary::on(cfg.boundary) {
                *g = crate::boundary::score(frame, &e);
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
        if A::ANY {
            for (w, p) in weights.iter_mut().zip(particles.iter()) {
                *w *= apart.factor(&p.ellipse());
            }
        }
        out
    }

    /// Turns the similarities of the first `n` particles in `weights` into
    /// normalised likelihoods; returns the σ used.
    pub(super) fn weigh(&mut self, d2_max: Real, n: usize) -> Real {
        let cfg = &self.config;
        let n = n.clamp(1, N);
        let (weights, _) = self.weights.split_at_mut(n);
        let best = weights.iter().fold(0.0 as Real, |a, &w| a.max(w));
        let mean = weights.iter().sum::<Real>() / n as Real;
        let (sigma, offset) = cfg.likelihood.sigma_and_offset(d2_max * (1.0 - best), d2_max * (1.0 - mean));
        let mut sum = 0.0;
        for w in weights.iter_mut() {
            *w = cfg.likelihood.weight(d2_max * (1.0 - *w) - offset, sigma);
            sum += *w;
        }
        if sum > 0.0 && sum.is_finite() {
            for w in weights.iter_mut() {
                *w /= sum;
            }
        } else {
            weights.fill(1.0 / n as Real);
        }
        sigma
    }

    /// How many hypotheses this step draws and observes: a share of them
    /// after a frame confidently on the target ([`crate::Config::sure_share`];
    /// the last confidence is recomputed from its signals, which the
    /// tracker keeps), unless another target is `near`; all of them
    /// otherwise.
    fn hypotheses(&self, near: bool) -> usize {
        let cfg = &self.config;
        let Life::Confidence { found_above, .. } = cfg.life else { return N };
        if !(cfg.sure_share < 1.0) || self.state != TrackState::Tracking {
            return N;
        }
        let (d, Some(target)) = (&self.diag, self.target.as_ref()) else { return N };
        // Tracking, the target's size is the last estimate's.
        let sure = on_target(d.contrast, d.correlation, d.anchored, target.size_change(target.half_axes)) > found_above;
        if !sure || near {
            return N;
        }
        ((cfg.sure_share * N as Real) as usize).clamp(2, N)
    }

    /// The weighted mean state, sized against the surroundings (unless
    /// `search` is false: the size is decided elsewhere this frame), and how
    /// it compares with the models; `near` when another target of a group
    /// is near (see [`Freedom::Held`]).
    pub(super) fn estimate<const E: usize>(
        &mut self,
        scratch: &mut Scratch<K, E>,
        frame: &Frame<'_>,
        observed: &Observed,
        (search, near): (bool, bool),
        n: usize,
    ) -> Look {
        let Track { config: cfg, particles, weights, target, state, diag, cues, .. } = self;
        let n = n.min(N);
        let mut ellipse =
            mean_state(particles.get(..n).unwrap_or(particles), weights.get(..n).unwrap_or(weights)).ellipse();
        // The texture cue first, so that the searches and the confidence
        // measure the box where it leaves it.
        let freedom = match (near, search) {
            (true, _) => Freedom::Held,
            (false, true) => Freedom::Full,
            (false, false) => Freedom::Position,
        };
        let psr = cues.place(cfg, frame, (&mut ellipse, particles), freedom, scratch.fgmap.lend());
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
                let g = (crate::boundary::score(frame, &ellipse) as Real / observed.g_best as Real).min(1.0);
                (1.0 - b.weight) * seen.sim + b.weight * g
            }
            _ => seen.sim,
        };
        let occluded_quadrant =
            if crate::histogram::quadrants(cfg.quadrants) { occluded(seen.quads, target.threshold) } else { None };
        let (confidence, found) = match cfg.life {
            Life::Appearance => (similarity, observed.appearing as Real > cfg.kickoff * N as Real),
            Life::Confidence { lost_below, found_above } => {
                let correlation = correlation.unwrap_or_else(|| models.template.correlation(frame, &ellipse));
                let anchored = seen.anchored;
                *diag = Diagnostics { contrast, correlation, anchored, similarity, psr };
                let p = on_target(contrast, correlation, anchored, target.size_change((ellipse.hx, ellipse.hy)));
                (p, if *state == TrackState::Tracking { p >= lost_below } else { p > found_above })
            }
        };
        Look { ellipse, confidence, similarity, found, occluded_quadrant }
    }

    /// Keeps the target's recent speed: the estimate's displacement, over
    /// frames tracked one after another, smoothed so that one jump of the
    /// estimate does not scatter the particles for long.
    pub(super) fn follow(&mut self, e: &Ellipse, was_tracking: bool) {
        let Some(target) = self.target.as_mut() else { return };
        if was_tracking && self.state == TrackState::Tracking {
            let (dx, dy) = (e.cx - target.centre.0, e.cy - target.centre.1);
            target.speed += SPEED_RATE * (sqrt(dx * dx + dy * dy) - target.speed);
        }
        target.centre = (e.cx, e.cy);
        if self.state == TrackState::Tracking && self.misses == 0 {
            target.found_at = target.centre;
        }
    }

    /// Moves the state machine on whether the target was found this frame.
    pub(super) fn life_cycle(&mut self, found: bool) -> Option<Event> {
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
            TrackState::Lost => {
                self.misses = self.misses.saturating_add(1);
                None
            }
            TrackState::Searching => None,
        }
    }

    /// Adapts the models on steady, trustworthy tracking frames; returns
    /// whether they were updated. `stuck` where the surroundings-motion
    /// test flagged the estimate.
    pub(super) fn adapt<const E: usize>(
        &mut self,
        scratch: &mut Scratch<K, E>,
        frame: &Frame<'_>,
        look: &Look,
        event: Option<Event>,
        stuck: bool,
    ) -> bool {
        let Track { config: cfg, target, state, misses, cues, .. } = self;
        let Some(target) = target.as_mut() else { return false };
        // The foreground map is dead once the step has estimated: the cues
        // learn in its memory.
        let verdict = Verdict { confidence: look.confidence, moves_with_scene: stuck };
        cues.adapt(cfg, frame, &look.ellipse, verdict, scratch.fgmap.lend());
        let steady = *state == TrackState::Tracking && event.is_none() && *misses == 0 && cfg.alpha > 0.0;
        let d2_max = target.models.d2_max(cfg);
        let wanted = match cfg.model_update {
            ModelUpdate::Confident => {
                gaussian(d2_max * (1.0 - look.similarity), cfg.update_sigma) > cfg.update_threshold
            }
            ModelUpdate::WhenDegraded { factor, frames } => {
                let (sum, n) = (&mut target.rho0_sum, &mut target.rho0_count);
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
                m.colour.reweight(m.fg.odds(), &crate::foreground::weights(b));
            }
        }
        if *state == TrackState::Tracking {
            target.half_axes = (look.ellipse.hx, look.ellipse.hy);
        }
        updated
    }
}

/// How far from its last estimate, in its larger half axis, a missed
/// target is looked for ([`Redetect::Near`]).
const NEAR_REACH: Real = 4.0;

/// One in this many of the particles re-drawn while the target is lost is
/// drawn about where it was last found.
const BACK_SHARE: usize = 4;

/// A target moving more than this share of its size a frame is fast
/// ([`Redetect::Near`]).
const FAST: Real = 0.5;

/// What observing the particles found.
#[derive(Copy, Clone, Debug, Default)]
pub(super) struct Observed {
    /// Particles that pass the appearance test.
    pub(super) appearing: u16,
    /// The best boundary score (0 without the boundary cue).
    pub(super) g_best: u16,
    /// The largest squared distance the active cues can produce.
    pub(super) d2_max: Real,
}

/// The estimate and what it looks like.
#[derive(Copy, Clone, Debug)]
pub(super) struct Look {
    pub(super) ellipse: Ellipse,
    /// What [`Estimate::confidence`] reports.
    pub(super) confidence: Real,
    /// Similarity of the estimate with the models (and the boundary cue).
    pub(super) similarity: Real,
    /// Whether the life cycle counts the target as seen in this frame.
    pub(super) found: bool,
    pub(super) occluded_quadrant: Option<u8>,
}
