//! The interface of the cues beside the colour model that keep state of
//! their own (the correlation filter, the surroundings-motion test).
//!
//! Each such cue is one module that holds its settings, their validation,
//! its default, and the form it takes in a build without its Cargo feature
//! ([`Absent`]: no memory, no work, settings refused by validation with an
//! error that names the feature). The tracker keeps one value of each in
//! its list of cues and calls the hooks below at fixed points of a step,
//! with the cue's own settings; it names no feature.

use crate::error::{ConfigError, ParamProblem};
use crate::filter::Particle;
use crate::frame::Frame;
use crate::geometry::Ellipse;
use crate::scalar::Real;
use core::marker::PhantomData;

/// A cue with state of its own. Every hook but [`Cue::start`] is called
/// only while the cue is on (its settings are `Some`).
pub(crate) trait Cue {
    /// The cue's settings, as [`crate::Config`] holds them when it is on.
    type Settings: Copy;

    /// Learns the target afresh from its first box `e` (initialisation,
    /// search, re-initialisation), forgetting any earlier target; `settings`
    /// is `None` when the cue is off. `work` is working memory the tracker
    /// lends for the call (see [`crate::foreground::ForegroundMap::lend`]):
    /// a learning's large temporaries go there rather than on the stack.
    fn start(&mut self, settings: Option<&Self::Settings>, frame: &Frame<'_>, e: &Ellipse, work: &mut [u16]);

    /// Mixes the cue's own score of each of the first `n` particles into
    /// its similarity in `similarities` (before the similarities are
    /// weighed), for a target of half axes `half_axes` (`work` as for
    /// [`Cue::start`]).
    #[allow(unused_variables)]
    fn rescore<const N: usize>(
        &mut self,
        settings: &Self::Settings,
        frame: &Frame<'_>,
        (particles, similarities): (&[Particle; N], &mut [Real; N]),
        n: usize,
        half_axes: (Real, Real),
        work: &mut [u16],
    ) {
    }

    /// Looks at the frame around the filter's mean state before the size
    /// and position searches, and may move the estimate and its particles
    /// with it, as far as `freedom` lets it (`work` as for [`Cue::start`]).
    /// Returns the peak-to-sidelobe ratio of its response, if it has one.
    #[allow(unused_variables)]
    fn place<const N: usize>(
        &mut self,
        settings: &Self::Settings,
        frame: &Frame<'_>,
        estimate: (&mut Ellipse, &mut [Particle; N]),
        freedom: Freedom,
        work: &mut [u16],
    ) -> Option<Real> {
        None
    }

    /// Whether this frame's estimate `e` counts as a miss (called on every
    /// frame, so that running measures stay current; `tracking` while the
    /// target is tracked).
    #[allow(unused_variables)]
    fn miss(&mut self, settings: &Self::Settings, frame: &Frame<'_>, e: &Ellipse, tracking: bool) -> bool {
        false
    }

    /// Adapts to this frame's estimate `e` and what the tracker concluded
    /// of it (`work` as for [`Cue::start`]).
    #[allow(unused_variables)]
    fn adapt(&mut self, settings: &Self::Settings, frame: &Frame<'_>, e: &Ellipse, verdict: Verdict, work: &mut [u16]) {
    }
}

/// What the tracker concluded of a frame's estimate, as the cues adapt to
/// it.
#[derive(Copy, Clone, Debug)]
// Read whole only by the gradient filter (the grey-level one reads the
// confidence).
#[cfg_attr(not(feature = "gradient"), allow(dead_code))]
pub(crate) struct Verdict {
    /// The confidence of its signals ([`crate::on_target`]), as the cues
    /// learn from it: not halved where the surroundings-motion test flags
    /// the estimate, as the reported confidence is.
    pub(crate) confidence: Real,
    /// Whether the surroundings-motion test flagged the estimate: it moves
    /// with the scene around it, as background does.
    pub(crate) moves_with_scene: bool,
}

/// What [`Cue::place`] may change of the estimate.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(crate) enum Freedom {
    /// Its position and its size.
    Full,
    /// Its position: the size is decided elsewhere this frame.
    Position,
    /// Nothing: another target of a group is near, and a layout cue finds
    /// a look-alike neighbour's layout as well as the target's own, so
    /// only the colour hypotheses, which the group keeps apart, place the
    /// target there. The cue still measures its response.
    Held,
}

// Read only by the correlation filters.
#[cfg_attr(not(feature = "correlation"), allow(dead_code))]
impl Freedom {
    /// Whether the cue may move the estimate.
    pub(crate) fn moves(self) -> bool {
        self != Freedom::Held
    }

    /// Whether the cue may size the estimate.
    pub(crate) fn sizes(self) -> bool {
        self == Freedom::Full
    }
}

/// A cue this build leaves out: it takes no memory and does nothing (its
/// settings never pass validation, see [`not_built`]).
// Unused in a build with every such cue.
#[cfg_attr(all(feature = "correlation", feature = "gradient", feature = "scene-motion"), allow(dead_code))]
#[derive(Copy, Clone, Debug)]
pub(crate) struct Absent<S>(PhantomData<S>);

#[cfg_attr(all(feature = "correlation", feature = "gradient", feature = "scene-motion"), allow(dead_code))]
impl<S> Absent<S> {
    /// The stand-in.
    pub(crate) const fn new() -> Self {
        Absent(PhantomData)
    }
}

impl<S: Copy> Cue for Absent<S> {
    type Settings = S;

    fn start(&mut self, _: Option<&S>, _: &Frame<'_>, _: &Ellipse, _: &mut [u16]) {}
}

/// The error for settings that ask for a cue this build leaves out.
pub(crate) const fn not_built(field: &'static str, feature: &'static str) -> ConfigError {
    ConfigError { field, problem: ParamProblem::NotBuilt { feature } }
}
