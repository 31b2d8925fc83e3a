//! The correlation filters beside colour: their settings, their validation
//! and defaults, and the cues the tracker keeps: [`filter`] on grey levels
//! where the `correlation` feature builds it, [`gradient`] on gradient
//! channels over a wide window where the `gradient` feature does, and
//! stand-ins that do nothing where not.

#[cfg(feature = "gradient")]
mod channels;
#[cfg(feature = "correlation")]
mod filter;
#[cfg(feature = "gradient")]
mod gradient;
#[cfg(feature = "correlation")]
mod integer_fft;
#[cfg(feature = "scale-pyramid")]
mod pyramid;
#[cfg(feature = "correlation")]
mod series;

#[cfg(not(all(feature = "correlation", feature = "gradient")))]
use crate::cue::Absent;
use crate::cue::not_built;
use crate::error::Checks;
use crate::scalar::Real;

#[cfg(feature = "correlation")]
pub(crate) use filter::{CorrelationFilter as Correlation, WORK_BYTES as CORRELATION_WORK_BYTES};

#[cfg(feature = "gradient")]
pub(crate) use gradient::{GradientFilter as Gradient, WORK_BYTES as GRADIENT_WORK_BYTES};

/// The first `[T; N]` laid out in `work` (memory the tracker lends the
/// cues, see [`crate::foreground::ForegroundMap::lend`]) and the rest of
/// `work` after it; `None` if `work` is too short, or not aligned for `T`.
/// The filters' large temporaries live there rather than on the stack.
#[cfg(feature = "correlation")]
fn carve<T: bytemuck::Pod, const N: usize>(work: &mut [u16]) -> Option<(&mut [T; N], &mut [u16])> {
    let size = core::mem::size_of::<[T; N]>();
    let (front, rest) = work.split_at_mut_checked(size.div_ceil(2))?;
    let bytes: &mut [u8] = bytemuck::cast_slice_mut(front);
    Some((bytemuck::try_from_bytes_mut(bytes.get_mut(..size)?).ok()?, rest))
}

/// The cue in a build without the `gradient` feature.
#[cfg(not(feature = "gradient"))]
pub(crate) type Gradient = Absent<GradientCue>;

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
pub(crate) fn validate(c: &mut Checks, settings: Option<CorrelationCue>) {
    let Some(s) = settings else { return };
    if !cfg!(feature = "correlation") {
        c.fail(not_built("correlation", "correlation"));
    }
    c.range("correlation.padding", s.padding, 1.0, 4.0);
    c.positive("correlation.rate", s.rate, 1.0);
    c.share("correlation.learn_above", s.learn_above);
    c.share("correlation.pull", s.pull);
    c.range("correlation.scale_step", s.scale_step, 0.0, 0.2);
    c.share("correlation.scale_pull", s.scale_pull);
    c.range("correlation.min_psr", s.min_psr, 0.0, 20.0);
    c.share("correlation.centre_bias", s.centre_bias);
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
    /// How much the response is weighed towards no shift before its peak
    /// is taken, in `[0, 1]`: each value is multiplied by `1 − centre_bias
    /// · sin²(π d / 16)` along each axis, `d` its shift in the window's 16
    /// lattice points (the cosine window Siamese trackers put on their
    /// score maps). A far peak must then stand clearly above a near one to
    /// move the estimate: a striped target's shift by one stripe, or a
    /// patch of background that matches about as well, no longer wins on a
    /// hair's difference. 0 takes the highest value wherever it lies.
    pub centre_bias: Real,
}

impl CorrelationCue {
    /// The settings chosen on the real sequences' tune split
    /// (docs/accuracy.md): a window twice the box, learnt at 0.05 on every
    /// frame whose confidence exceeds 0.7, a move 0.7 of the way to the
    /// peak, and a size that moves 0.3 of the way to the best of three
    /// scales 3% apart, when the response's PSR reaches 3; the response
    /// weighed towards no shift by 0.7.
    pub const MEASURED: CorrelationCue = CorrelationCue {
        padding: 2.0,
        rate: 0.05,
        learn_above: 0.7,
        pull: 0.7,
        scale_step: 0.03,
        scale_pull: 0.3,
        min_psr: 3.0,
        centre_bias: 0.7,
    };
}

/// Checks the gradient filter's settings; asking for it in a build without
/// it is an error that names the feature.
// Inlined into `Config::validate`, the one caller, as its other checks are.
#[inline(always)]
pub(crate) fn validate_gradient(c: &mut Checks, settings: Option<GradientCue>) {
    let Some(g) = settings else { return };
    if !cfg!(feature = "gradient") {
        c.fail(not_built("gradient", "gradient"));
    }
    c.positive("gradient.rate", g.rate, 1.0);
    c.share("gradient.learn_above", g.learn_above);
    c.out_of_range_if(g.learn_every == 0, "gradient.learn_every");
    c.share("gradient.pull", g.pull);
    c.share("gradient.grey_pull", g.grey_pull);
    c.range("gradient.scale_step", g.scale_step, 0.0, 0.2);
    c.share("gradient.scale_pull", g.scale_pull);
    c.range("gradient.min_psr", g.min_psr, 0.0, 20.0);
    c.share("gradient.blend", g.blend);
    c.range("gradient.relearn_below", g.relearn_below, 0.0, 20.0);
    c.share("gradient.relearn_above", g.relearn_above);
    c.share("gradient.pyramid_pull", g.pyramid_pull);
    if g.pyramid_pull > 0.0 && !cfg!(feature = "scale-pyramid") {
        c.fail(not_built("gradient.pyramid_pull", "scale-pyramid"));
    }
    c.share("gradient.pyramid_learn_above", g.pyramid_learn_above);
    c.share("gradient.narrow_above", g.narrow_above);
}

/// A correlation filter on gradient channels over a wide window (the
/// `gradient` feature): grey and four gradient orientations on cells about
/// a thirteenth of the box, learnt jointly over a window 2.5 times the box
/// with the filter cut to the box's support (CSR-DCF's learning, Lukežič et
/// al. 2017), read in space over a window about 3.6 times the box. Each
/// frame, when its response's peak is clear, the estimate moves `pull` of
/// the way to the peak and its size towards the best of three scales, as
/// the grey-level filter's do ([`CorrelationCue`]); its response at each
/// particle may also join the particle's similarity (`blend`). It is the
/// cue that places a target by the layout of its edges where its colours
/// are its surroundings' too.
///
/// Memory and time: about 12 KB of RAM in every tracker built with the
/// feature (the read window's cells and the filter), more stack on the
/// frames it learns, and about a third more instructions a frame than
/// [`Config::fast`](crate::Config::fast), which leaves it off
/// (docs/performance.md). Beside the grey-level filter it is
/// [`Config::accurate`](crate::Config::accurate), the most accurate
/// configuration measured and [`Config::default`](crate::Config::default)
/// where the feature is built. It may also replace the grey-level filter
/// (`correlation: None`).
///
/// ```
/// use pftrack::{Config, ConfigError, Error, GradientCue, ParamProblem, Tracker};
///
/// let config = Config { gradient: Some(GradientCue::MEASURED), correlation: None, ..Config::default() };
/// match Tracker::<100>::new(config, 1) {
///     Ok(tracker) => assert_eq!(tracker.config().gradient, Some(GradientCue::MEASURED)),
///     // A build without the `gradient` feature names it.
///     Err(e) => assert_eq!(
///         e,
///         Error::Config(ConfigError { field: "gradient", problem: ParamProblem::NotBuilt { feature: "gradient" } })
///     ),
/// }
/// ```
#[derive(Copy, Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GradientCue {
    /// Learning rate `η` of the filter's running mean on each frame it
    /// learns, in `(0, 1]`.
    pub rate: Real,
    /// Frames whose confidence exceeds this, in `[0, 1]`, teach the filter.
    pub learn_above: Real,
    /// The filter learns on every `learn_every`-th such frame (at least 1):
    /// learning transforms the window, reading does not.
    pub learn_every: u8,
    /// The share of the way to the response's peak the estimate moves, in
    /// `[0, 1]`.
    pub pull: Real,
    /// The same share on grey-level video, in `[0, 1]`: where every pixel
    /// sampled over the window the filter first learns is a grey level
    /// (red, green and blue equal in their top five bits: a mono camera's
    /// GRAY8, or grey video in RGB565, RGB888 or YUV), the colour cues see
    /// only brightness, and the filter's layout is trusted further.
    pub grey_pull: Real,
    /// Relative size step of the scale search, in `[0, 0.2]` (0: none).
    pub scale_step: Real,
    /// The share of the way to the best scale the size moves, in `[0, 1]`.
    pub scale_pull: Real,
    /// The peak-to-sidelobe ratio below which the filter moves neither the
    /// estimate nor its size, in `[0, 20]`.
    pub min_psr: Real,
    /// The response's share of each particle's similarity, in `[0, 1]`.
    pub blend: Real,
    /// A frame more confident than `relearn_above` whose response's
    /// peak-to-sidelobe ratio falls under this, in `[0, 20]` (0: never),
    /// teaches the filter at once rather than at its turn: the colours say
    /// the target is held while its layout no longer matches the filter's
    /// (it turns or changes shape), and a filter left to its turn pulls
    /// the estimate towards wherever the old layout fits best.
    pub relearn_below: Real,
    /// The confidence, in `[0, 1]`, a frame must exceed for a low
    /// peak-to-sidelobe ratio to teach the filter at once
    /// ([`GradientCue::relearn_below`]).
    pub relearn_above: Real,
    /// The share of the way, in log size, the estimate's size moves each
    /// frame to the size at which the target's scale pyramid matches the
    /// frame's, in `[0, 1]` (0: no pyramid). The pyramid is the gradient
    /// channels on a 5 x 5-cell lattice over a window twice the box, at
    /// thirteen sizes 3% apart, matched at offsets of up to two sizes
    /// (DSST's scale pyramid, matched by correlation; the `scale-pyramid`
    /// feature): 1,625 bytes of RAM in every tracker built with it.
    pub pyramid_pull: Real,
    /// Every fourth frame whose confidence exceeds this, in `[0, 1]`,
    /// teaches the pyramid (a running mean at a fifth).
    pub pyramid_learn_above: Real,
    /// After a frame whose confidence exceeds this, in `[0, 1]`, and whose
    /// estimate the surroundings-motion test did not flag, the next frame's
    /// response is weighted by a narrower window (the Hann weights squared:
    /// 1.1 boxes from the estimate a response counts 0.33 of itself instead
    /// of 0.57); 1 never narrows it. A sure target is about where it was,
    /// and a look-alike a box away is not it; after a frame that is not
    /// sure, the target may be wherever it went meanwhile, and the wide
    /// window lets the filter find it there.
    pub narrow_above: Real,
}

impl GradientCue {
    /// The settings measured on the real sequences (docs/accuracy.md):
    /// learnt at 0.2 on every fourth frame whose confidence exceeds 0.7
    /// (a running mean as slow as 0.05 on every frame), a move 0.7 of the
    /// way to the peak (0.85 on grey-level video) and a size 0.3 of the way
    /// to the best of three scales 3% apart when the PSR reaches 3, no share
    /// of the particles' similarities (a 0.3 share loses 0.04 on the check
    /// split), and a
    /// frame more confident than 0.8 (the life cycle's default
    /// `found_above`) whose PSR is under 4 learnt at once (a turning target
    /// followed; the real sequences unchanged within their seeds' noise);
    /// where the `scale-pyramid` feature is built, the scale pyramid moving
    /// the size a fifth of the way each frame and learning from frames more
    /// confident than 0.9 (off, 0, where it is not); and the window
    /// narrowed after a frame more confident than 0.95 (fewer frames on
    /// look-alikes, the real sequences' accuracy unchanged within their
    /// seeds' noise or a little better).
    pub const MEASURED: GradientCue = GradientCue {
        rate: 0.2,
        learn_above: 0.7,
        learn_every: 4,
        pull: 0.7,
        grey_pull: 0.85,
        scale_step: 0.03,
        scale_pull: 0.3,
        min_psr: 3.0,
        blend: 0.0,
        relearn_below: 4.0,
        relearn_above: 0.8,
        pyramid_pull: if cfg!(feature = "scale-pyramid") { 0.2 } else { 0.0 },
        pyramid_learn_above: 0.9,
        narrow_above: 0.95,
    };
}
