//! The correlation filter beside colour: its settings, their validation
//! and default, and the cue the tracker keeps ([`filter`] where the
//! `correlation` feature builds it, a stand-in that does nothing where not).

#[cfg(feature = "correlation")]
mod filter;

#[cfg(not(feature = "correlation"))]
use crate::cue::Absent;
use crate::cue::not_built;
use crate::error::{ConfigError, check, positive};
use crate::scalar::Real;

#[cfg(feature = "correlation")]
pub(crate) use filter::CorrelationFilter as Correlation;

/// The cue in a build without the `correlation` feature.
#[cfg(not(feature = "correlation"))]
pub(crate) type Correlation = Absent<CorrelationCue>;

/// The default settings: on wherever the filter is built (the second cue
/// that lifts accuracy on new video, docs/accuracy.md); off, and so valid,
/// where it is not.
pub(crate) const DEFAULT: Option<CorrelationCue> =
    if cfg!(feature = "correlation") { Some(CorrelationCue::MEASURED) } else { None };

/// Checks the settings; asking for the filter in a build without it is an
/// error that names the feature.
// Inlined into `Config::validate`, the one caller, as its other checks are.
#[inline(always)]
pub(crate) fn validate(settings: Option<CorrelationCue>) -> Result<(), ConfigError> {
    let Some(c) = settings else { return Ok(()) };
    if !cfg!(feature = "correlation") {
        return Err(not_built("correlation", "correlation"));
    }
    check("correlation.padding", c.padding, 1.0, 4.0)?;
    positive("correlation.rate", c.rate, 1.0)?;
    check("correlation.learn_above", c.learn_above, 0.0, 1.0)?;
    check("correlation.pull", c.pull, 0.0, 1.0)?;
    check("correlation.scale_step", c.scale_step, 0.0, 0.2)?;
    check("correlation.scale_pull", c.scale_pull, 0.0, 1.0)?;
    check("correlation.min_psr", c.min_psr, 0.0, 20.0)
}

/// A correlation filter (MOSSE) on the grey levels of a window around the
/// target, learnt as a running mean and answered by the peak of its
/// response: each frame, before the size and position searches, the
/// filter's mean state moves `pull` of the way to the peak. A second cue
/// beside colour that sees texture, as Staple pairs a correlation filter
/// with a colour score (Bertinetto et al. 2016). Built with the
/// `correlation` Cargo feature, a default one (its state takes RAM in every
/// tracker built with it, and its working spectrum more stack while it
/// reads a window: audit/budgets.txt), and on in [`Config::default`](crate::Config::default) where
/// built. Turning it off (`None`) saves most on a core without an FPU,
/// where its FFTs run in software and are a large share of each frame's
/// instructions (docs/performance.md); asking for it without the feature
/// is a configuration error.
///
/// ```
/// use pftrack::{Config, ConfigError, CorrelationCue, Error, ParamProblem, Tracker};
///
/// // Off: the colour cues alone.
/// let lean = Config { correlation: None, ..Config::default() };
/// assert!(Tracker::<100>::new(lean, 1).is_ok());
/// let config = Config { correlation: Some(CorrelationCue::MEASURED), ..Config::default() };
/// match Tracker::<100>::new(config, 1) {
///     Ok(tracker) => assert_eq!(tracker.config().correlation, Some(CorrelationCue::MEASURED)),
///     // A build without the `correlation` feature names it.
///     Err(e) => assert_eq!(
///         e,
///         Error::Config(ConfigError {
///             field: "correlation",
///             problem: ParamProblem::NotBuilt { feature: "correlation" }
///         })
///     ),
/// }
/// ```
#[derive(Copy, Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CorrelationCue {
    /// The window's side as a multiple of the box's, in `[1, 4]`: the
    /// surroundings it takes in are what the filter can also lock on, and
    /// how far the target may move in a frame and still be in it.
    pub padding: Real,
    /// Learning rate `η` of the filter's running mean, in `(0, 1]`.
    pub rate: Real,
    /// Frames whose confidence exceeds this, in `[0, 1]`, teach the filter.
    pub learn_above: Real,
    /// The share of the way to the response's peak the estimate moves, in
    /// `[0, 1]`.
    pub pull: Real,
    /// Relative size step of the scale search, in `[0, 0.2]`: the windows
    /// one step larger and smaller are correlated too, and the estimate's
    /// size moves towards the one whose response peaks highest (the scale
    /// search of DSST, Danelljan et al. 2014, with three scales). 0 leaves
    /// the size to the size search.
    pub scale_step: Real,
    /// The share of the way to the best scale the size moves, in `[0, 1]`.
    pub scale_pull: Real,
    /// The response's peak-to-sidelobe ratio below which the filter moves
    /// neither the estimate nor its size, in `[0, 20]`: a window with no
    /// clear match (MOSSE's own test of a failing filter; about 3 on a
    /// texture the filter never saw). On a target with no texture of its
    /// own the window's texture is the background's, and a filter that
    /// followed it would hold the box to the background.
    pub min_psr: Real,
}

impl CorrelationCue {
    /// The settings chosen on the real sequences' tune split
    /// (docs/accuracy.md): a window twice the box, learnt at 0.05 on every
    /// frame whose confidence exceeds 0.7, a move 0.7 of the way to the
    /// peak, and a size that moves 0.3 of the way to the best of three
    /// scales 3% apart, when the response's PSR reaches 3.
    pub const MEASURED: CorrelationCue = CorrelationCue {
        padding: 2.0,
        rate: 0.05,
        learn_above: 0.7,
        pull: 0.7,
        scale_step: 0.03,
        scale_pull: 0.3,
        min_psr: 3.0,
    };
}
