//! The tracker's configuration and its validation.

use crate::boundary::BoundaryCue;
use crate::colour::Binning;
use crate::correlation::{CorrelationCue, GradientCue};
use crate::edges::EdgeCue;
use crate::error::{Checks, ConfigError};
use crate::filter::{Dynamics, Resampling};
use crate::foreground::BackgroundWeight;
use crate::histogram::Similarity;
use crate::likelihood::{Combination, Likelihood, Shape, Sigma};
use crate::region::Sampling;
use crate::scalar::Real;

/// Where a missed target is looked for beyond the particles' reach: at the
/// places whose colours stand out from their surroundings as the target's
/// do, in the foreground map (see [`crate::foreground`]).
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Redetect {
    /// Only where the particles go.
    Off,
    /// Around the last place, when a tracked target is missed before any
    /// step has found it since it was learnt (nothing is known of its
    /// motion yet) or while it moves more than half its size a frame: it
    /// may have left the particles' reach. A share of the particles
    /// ([`Config::reseed_fraction`], halved) is drawn at the best places
    /// within four half axes of its last estimate, with the velocity that
    /// took it there. On the real sequences it hardly acts (their accuracy
    /// is the same as with `Off`); on a target moving most of its size a
    /// frame it keeps it (docs/accuracy.md).
    #[default]
    Near,
    /// [`Redetect::Near`], and over the whole frame while searching or
    /// lost (over [`LostSearch::Widening`]'s square while lost, with it):
    /// half of the particles re-drawn each step go to the best places, the
    /// other half anywhere.
    Frame,
}

/// Where the particles re-drawn while the target is lost go
/// ([`Config::reseed_fraction`] of them each step), and where
/// [`Redetect::Frame`] looks for it then.
#[derive(Copy, Clone, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LostSearch {
    /// Anywhere in the frame, from the first frame lost: a target that
    /// reappears anywhere can be found, and so can every look-alike.
    #[default]
    Frame,
    /// Within a square about the place the target was last found: its half
    /// side is four times the target's larger half axis (the reach of
    /// [`Redetect::Near`]) plus `growth` half axes for each frame since,
    /// clipped to the frame. A target lost against a busy background (a
    /// small bird in a flock, a car at night) is most often still near
    /// where it was last seen, and is found again there before a far
    /// look-alike draws the particles away; one that reappears far away is
    /// found once the square has grown to it. A target last found at the
    /// frame's edge (its box within a half axis of it) may have left the
    /// view and come back anywhere: it is looked for over the whole frame.
    /// It trades the confidence's ranking of the misses for accuracy
    /// (docs/accuracy.md).
    Widening {
        /// Half axes the square's half side grows by each frame, in `[0, 10]`.
        growth: Real,
    },
}

/// Everything that tunes a [`crate::Tracker`]. Start from [`Config::default`]
/// and change fields; [`Config::validate`] (called by the tracker's
/// constructor) rejects NaN, infinite and out-of-range values with a
/// [`ConfigError`] naming the field.
///
/// ```
/// use pftrack::{Config, Sigma};
/// let mut c = Config::default();
/// c.likelihood.sigma = Sigma::Fixed(Real::NAN);
/// # use pftrack::Real;
/// assert_eq!(c.validate().unwrap_err().field, "likelihood.sigma");
/// ```
#[derive(Copy, Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config {
    /// Colour quantisation of the histograms.
    pub binning: Binning,
    /// Split the ellipse into four quadrants, each with its own colour
    /// histogram (adaptive-bins paper). The colour similarity is then the
    /// median of the four, and an estimate reports a partial occlusion when
    /// one quadrant fails the appearance test while the other three pass.
    /// Each quadrant gets a quarter of the capacity `K`, so the binning must
    /// fit in `K / 4` bins ([`Binning::Rgb4x4x4`] or [`Binning::Adaptive`] at
    /// the default 512).
    pub quadrants: bool,
    /// How histograms are compared with the model.
    pub similarity: Similarity,
    /// Which pixels of each region are read.
    pub sampling: Sampling,
    /// Most pixels read per region and cue; larger regions are read on a
    /// coarser lattice so that the cost per particle stays bounded whatever
    /// the target's size. 0 means no limit.
    pub max_samples: u32,
    /// The edge-orientation cue, or `None` for colour only.
    pub edges: Option<EdgeCue>,
    /// The likelihood-table mode for a target of fixed size (head-tracking
    /// paper), or `None` for per-particle histograms. Needs a tracker with a
    /// table capacity `T > 0`; particles then keep the initial size.
    pub table: Option<TableMode>,
    /// The ellipse-boundary gradient cue (head-tracking paper), or `None`.
    pub boundary: Option<BoundaryCue>,
    /// How colour and edge distances combine (ignored for colour only).
    pub combination: Combination,
    /// From Bhattacharyya distance to weight.
    pub likelihood: Likelihood,
    /// Resampling scheme.
    pub resampling: Resampling,
    /// Process noise of the constant-velocity model.
    pub dynamics: Dynamics,
    /// Model adaptation rate `α` in `[0, 1]`: `q ← (1 − α) q + α p_E[S]`.
    /// 0 keeps the initial model forever.
    pub alpha: Real,
    /// When the model is updated.
    pub model_update: ModelUpdate,
    /// The model is updated only when the mean state's likelihood
    /// `π_E[S] = exp(−d²/(2σ_u²))` exceeds this, in `[0, 1]`, so occluded
    /// frames do not pollute it (first paper), with `σ_u` = `update_sigma`.
    pub update_threshold: Real,
    /// The σ of the model-update gate. It is its own, not the likelihood's:
    /// an adaptive σ rescales every frame so that the best particle looks
    /// good, which would open the gate on a frame where nothing matches
    /// (measured: the model then drifts onto an occluder). With the first
    /// paper's σ of 0.2 this is exactly its rule; the default 0.4 is more
    /// permissive, because the combined colour + edge distance is larger
    /// than colour's alone and a small target's similarity is noisier: with
    /// [`Life::Confidence`], which updates only above `found_above`, the
    /// gate then closes on no frame of the real sequences that the
    /// confidence trusts (a tighter gate kept a 5-pixel target's model from
    /// following it as it grew; docs/accuracy.md), and on its own it keeps
    /// the model unchanged while the fixtures' target is hidden.
    pub update_sigma: Real,
    /// A particle "appears" (sees the target) when its `ρ` exceeds the
    /// background mean by this many background standard deviations (the paper's 2).
    pub appearance_sigmas: Real,
    /// A floor under the appearance threshold, in `[0, 1]`. The background
    /// statistics come from a sparse grid, but particles *search* for the
    /// best-matching background patch, which can beat `μ + kσ` by far when
    /// the background is uniformly unlike the target; the floor keeps such
    /// a patch from counting as the target.
    pub min_appearance: Real,
    /// The kick-off fraction `b` in `(0, 1]`: tracking starts when more than
    /// `b · N` particles appear, and a frame with at most `b · N` counts as a miss.
    pub kickoff: Real,
    /// Consecutive misses after which a tracked target is declared lost (1 to 1000).
    pub lost_after: u16,
    /// While searching or lost, this fraction of particles, in `[0, 1]`, is
    /// re-drawn uniformly over the frame (while lost, over where
    /// [`Config::lost_search`] says) each step, so the search keeps
    /// exploring instead of settling on the best background match (with
    /// [`Redetect::Frame`], half of them at the places found instead). Half
    /// of it is what [`Redetect::Near`] draws near a missed target.
    pub reseed_fraction: Real,
    /// Smallest half axis a particle may have, in pixels (at least 1).
    pub min_half_axis: Real,
    /// What drives the searching / tracking / lost states.
    pub life: Life,
    /// Where a missed target is looked for beyond the particles' reach
    /// (see [`Redetect`]).
    pub redetect: Redetect,
    /// Where a lost target is looked for (see [`LostSearch`]).
    pub lost_search: LostSearch,
    /// The share of the `N` particles, in `(0, 1]`, that are drawn and
    /// observed on a frame after one whose estimate was confidently on the
    /// target (tracking, with a confidence above [`Life::Confidence`]'s
    /// `found_above`); 1 (the default) observes all of them on every frame.
    /// Observing the hypotheses is most of a step's work, so a share trades
    /// accuracy for time where the target is easy: at 0.6 a QVGA frame
    /// costs about a quarter fewer instructions, for 0.006 of AUC on the
    /// real sequences and 0.02 of the confidence's ROC AUC
    /// (docs/performance.md). In a
    /// [`crate::Group`], a target that another comes near observes all of
    /// its hypotheses whatever the share, so that identities hold (below
    /// 0.6 targets that cross can swap).
    pub sure_share: Real,
    /// A frame on which the estimate moves with its surroundings counts as
    /// a miss, for a target that moved against them over its first frames
    /// (the `motion` module, built with the `scene-motion` feature, a
    /// default one): a box left on the background by a panning camera is
    /// reported lost, and its reported confidence halved. On in
    /// [`Config::default`] where built: on the real
    /// sequences it reports many more of the missing frames at the same
    /// accuracy (docs/accuracy.md), for a small share of a QVGA frame's
    /// instructions on a Cortex-M4F (audit/budgets.txt). Asking for it
    /// without the feature is a configuration error.
    pub scene_motion: bool,
    /// Size and shape searched each frame against the surroundings, or
    /// `None` to leave size to the particles' random walk.
    pub size: Option<SizeSearch>,
    /// Position refined each frame against the surroundings, or `None` to
    /// take the filter's mean as it is.
    pub shift: Option<ShiftSearch>,
    /// Adaptation rate of the surroundings' colour histogram (see
    /// [`crate::foreground`]) on model-update frames, in `[0, 1]`.
    pub surroundings_rate: Real,
    /// The colour model's bins weighted by how much more of each colour the
    /// target has than its surroundings (see [`BackgroundWeight`]), or
    /// `None` to leave the model as learnt.
    pub background_weight: Option<BackgroundWeight>,
    /// The grey-level template cue (see [`crate::template`]) in each
    /// particle's similarity, or `None`.
    pub template: Option<TemplateCue>,
    /// A correlation filter on the grey levels around the target (see
    /// [`CorrelationCue`]; built with the `correlation` feature, a default
    /// one), or `None`. [`CorrelationCue::MEASURED`] by default where the
    /// feature is built, `None` where it is not.
    pub correlation: Option<CorrelationCue>,
    /// A correlation filter on gradient channels over a wide window (see
    /// [`GradientCue`]; built with the `gradient` feature), or `None`, the
    /// default.
    pub gradient: Option<GradientCue>,
}

/// What drives the life cycle: when a tracked target counts as missed (and,
/// after `lost_after` misses, lost) and when a searched-for one is found.
#[derive(Copy, Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Life {
    /// The first paper's appearance test: a frame is a miss when at most
    /// `kickoff · N` particles have a colour `ρ` above the background
    /// statistics measured at initialisation, and the target is found when
    /// more do. The estimate's confidence is its similarity with the model.
    Appearance,
    /// The estimate's confidence decides: the probability that the estimate
    /// is on the target, from how much its box stands out from the ring
    /// around it, its grey-level correlation with the template, its colour
    /// similarity with the first model and its size against the first
    /// box's (see [`crate::Estimate::confidence`]). The model adapts only above
    /// `found_above`, so a drifting estimate cannot teach the model its drift.
    Confidence {
        /// A tracking frame whose confidence is below this is a miss, in `[0, 1]`.
        lost_below: Real,
        /// A searched-for or lost target is found when the confidence
        /// exceeds this, in `[0, 1]`.
        found_above: Real,
    },
}

/// The grey-level template cue: each particle's normalised cross-correlation
/// with the template (negative correlations count as 0) is mixed into its
/// similarity as `(1 − weight) · s + weight · ncc`, and the template, the
/// first box's, is blended towards the estimate's on model-update frames.
/// Weight 0 keeps the particles' similarity as it is and only adapts the
/// template that the size and position searches and the confidence read
/// (without this cue they read the first box's).
#[derive(Copy, Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TemplateCue {
    /// Share of the template's score, in `[0, 1]`.
    pub weight: Real,
    /// Adaptation rate of the template on model-update frames, in `[0, 1]`.
    pub rate: Real,
}

/// How the estimate's size and shape are searched each frame. The filter's
/// mean box, and the boxes one step wider, narrower, taller, shorter, wider
/// and shorter, and narrower and taller, are
/// scored by their contrast with the ring around them in the map of
/// `P(target | colour)` (see [`crate::foreground`]) plus `similarity` times
/// their similarity with the models and `template` times their grey-level
/// correlation with the template; the best becomes the estimate, and the
/// particles are rescaled with it. Contrast penalises a box too large (it
/// takes in background), the model similarity one too small (it leaves out
/// colours the model has), the template a box that has grown over something
/// of the target's colours but not its layout (a shadow, a reflection, the
/// body below a face): each candidate is read at its own size, so its
/// layout matches only at the target's. Two pulls towards the first box's
/// shape and area (the scale regularisation of ASMS, Vojíř et al. 2014)
/// keep the box from wandering one 2% step at a time where contrast and
/// similarity are flat, as on a dark target against a dark background. There is no search
/// in table mode, whose size is fixed, nor on a step given a
/// [`crate::ScalePrior`], which sets the size.
#[derive(Copy, Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SizeSearch {
    /// Relative size step of the candidates, in `(0, 0.5]`.
    pub step: Real,
    /// Weight of the candidates' similarity with the models, in `[0, 10]`.
    pub similarity: Real,
    /// Width and height are searched separately (the aspect ratio follows
    /// the target), or only together.
    pub aspect: bool,
    /// Penalty on a candidate's aspect ratio departing from the initial
    /// box's: this times `|ln(aspect / initial aspect)|` is taken off its
    /// score, in `[0, 10]`.
    pub aspect_pull: Real,
    /// Penalty on a candidate's area departing from the initial box's:
    /// this times `|ln(area / initial area)|` is taken off its score, in
    /// `[0, 10]`.
    pub scale_pull: Real,
    /// Weight of the candidates' grey-level correlation with the template
    /// (see [`crate::template`]), in `[0, 10]`.
    pub template: Real,
}

/// How the estimate's position is refined each frame, after its size: the
/// box and the boxes one step left, right, up and down are scored like the
/// size search's candidates (contrast with the ring around them in the map
/// of [`crate::foreground`], plus `similarity` times their similarity with
/// the models), plus `template` times their grey-level correlation with
/// the template, and the best is kept, for up to `rounds` steps
/// (stopping where none of the four beats the box). The particles move
/// with the estimate, so that a filter that lags a moving target catches
/// up.
#[derive(Copy, Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ShiftSearch {
    /// A step, as a share of the box's width (left and right) or height
    /// (up and down), in `(0, 0.5]`.
    pub step: Real,
    /// Most steps taken, 1 to 8.
    pub rounds: u8,
    /// Weight of the candidates' similarity with the models, in `[0, 10]`.
    pub similarity: Real,
    /// Weight of the candidates' grey-level correlation with the template
    /// (see [`crate::template`]), in `[0, 10]`: colour cannot tell
    /// a box from the same box a few pixels off on a target of one colour,
    /// the layout of light and dark can.
    pub template: Real,
}

/// When the target model adapts (it never does with `alpha` = 0). Either
/// way, only on tracking frames where the target is seen.
#[derive(Copy, Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ModelUpdate {
    /// When the estimate is trustworthy: `exp(−d²/(2σ_u²))` above
    /// `update_threshold`, with `σ_u` = `update_sigma` (first paper).
    Confident,
    /// Only when the model has become poor (adaptive-bins paper): `ρ₀` is
    /// learnt as the mean confidence of the first `frames` tracking frames,
    /// and the model is updated when the confidence falls below
    /// `T = factor · ρ₀`: "why update the model when it is still good?"
    WhenDegraded {
        /// The factor `c` of `T = c · ρ₀`, in `[0, 1]`.
        factor: Real,
        /// Frames averaged into `ρ₀` (1 to 1000).
        frames: u16,
    },
}

/// The likelihood-table mode: each frame, the similarity of every position
/// on a grid over the particles' area is computed by one sliding window
/// (see [`crate::Tracker`]'s `T` and the `table` module), and particles look
/// theirs up at the nearest grid point.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TableMode {
    /// Grid spacing in pixels (1 to 16); coarser if the area needs more than
    /// `T` cells.
    pub spacing: u8,
}

impl Default for Config {
    /// The most accurate configuration the build has: [`Config::accurate`]
    /// where the `gradient` feature is built (a default feature), and
    /// [`Config::fast`] where it is not, so that a board built without it
    /// for its RAM or frame rate gets a configuration it can run.
    ///
    /// ```
    /// use pftrack::Config;
    ///
    /// let expected = if cfg!(feature = "gradient") { Config::accurate() } else { Config::fast() };
    /// assert_eq!(Config::default(), expected);
    /// ```
    fn default() -> Self {
        if cfg!(feature = "gradient") { Config::accurate() } else { Config::fast() }
    }
}

impl Config {
    /// The configuration for boards that need the frame rate or the RAM:
    /// colour with the grey-level correlation filter, no gradient filter.
    /// Chosen by the ablation on the real sequences' *tune* split and kept
    /// where the *check* split agrees (docs/accuracy.md): the first paper's
    /// filter (RGB 8x8x8, α = 0.1, π_T = 0.15) with the third paper's
    /// checkerboard and Sobel edge cue (8 bins, threshold 100, lowered for
    /// a target with fewer than 10% of its pixels that strong), a per-region
    /// budget of 500 samples, damped velocities with wide position noise (a
    /// fifth of the target's size, or its recent speed if that is more), σ
    /// from the particles' spread, the size (pulled towards the first box's)
    /// and then the position (with the grey template's layout)
    /// searched against the surroundings, the colour model weighted towards
    /// the target's distinctive colours (strength 0.5 above odds 0.8), the
    /// grey-level filter where the `correlation` feature is built, and the
    /// confidence-driven life cycle (lost below 0.6, found and learning
    /// above 0.8); a lost target is looked for over the whole frame. It is
    /// [`Config::default`] in a build without the `gradient` feature, where
    /// the tracker is about a third smaller (docs/performance.md).
    ///
    /// ```
    /// use pftrack::Config;
    ///
    /// assert_eq!(Config::fast().gradient, None);
    /// assert!(Config::fast().validate().is_ok());
    /// ```
    pub fn fast() -> Self {
        Config {
            binning: Binning::Rgb8x8x8,
            quadrants: false,
            similarity: Similarity::Bhattacharyya,
            sampling: Sampling::Checkerboard,
            max_samples: 500,
            edges: Some(EdgeCue { bins: 8, threshold: 100, flat_bin: false, strong_percent: 10 }),
            table: None,
            boundary: None,
            combination: Combination::Product,
            likelihood: Likelihood {
                sigma: Sigma::Spread { spread: 8.0, min: 0.005, max: 0.5 },
                eps: 0.005,
                shape: Shape::Gaussian,
            },
            resampling: Resampling::Systematic,
            dynamics: Dynamics {
                position_noise: 0.2,
                velocity_noise: 0.1,
                velocity_decay: 0.5,
                speed_noise: 1.0,
                scale_noise: 0.01,
            },
            alpha: 0.1,
            model_update: ModelUpdate::Confident,
            update_threshold: 0.15,
            update_sigma: 0.4,
            appearance_sigmas: 2.0,
            min_appearance: 0.5,
            kickoff: 0.1,
            lost_after: 3,
            reseed_fraction: 0.25,
            min_half_axis: 2.0,
            life: Life::Confidence { lost_below: 0.6, found_above: 0.8 },
            redetect: Redetect::Near,
            lost_search: LostSearch::Frame,
            sure_share: 1.0,
            scene_motion: crate::motion::DEFAULT,
            size: Some(SizeSearch {
                step: 0.02,
                similarity: 1.0,
                aspect: true,
                aspect_pull: 0.03,
                scale_pull: 0.05,
                template: 0.0,
            }),
            shift: Some(ShiftSearch { step: 0.05, rounds: 1, similarity: 3.0, template: 0.15 }),
            surroundings_rate: 0.05,
            background_weight: Some(BackgroundWeight { strength: 0.5, above: 0.8 }),
            template: None,
            correlation: crate::correlation::DEFAULT,
            gradient: None,
        }
    }

    /// The most accurate configuration measured, and the default
    /// (docs/accuracy.md): [`Config::fast`] with the gradient filter
    /// ([`GradientCue::MEASURED`], the `gradient` feature) beside the
    /// grey-level one, and 0.6 of the hypotheses observed after a confident
    /// frame ([`Config::sure_share`]), which pays for part of the filter.
    /// The grey-level filter takes its response's highest value wherever it
    /// lies ([`CorrelationCue::centre_bias`] 0): beside the gradient filter
    /// the bias lost on the check split. A lost target is looked for about
    /// where it was last found, the square widening by 0.05 of its half
    /// axes a frame ([`LostSearch::Widening`]): fewer frames miss the
    /// target. The grey-level template follows the target (rate 0.05 on
    /// model-update frames, [`TemplateCue`] with weight 0) and weighs 0.3
    /// in the size search ([`SizeSearch::template`]): fewer boxes grow over
    /// a reflection or a body below, and fewer frames miss the target. A
    /// frame is a miss below a confidence of 0.7
    /// ([`Life::Confidence`]`{ lost_below: 0.7, found_above: 0.8 }`): more
    /// of the frames off the target are reported, for a few more good ones
    /// reported lost, at the same accuracy. It
    /// takes about half as much RAM again as [`Config::fast`] (the
    /// gradient filter's memory is in every tracker of a build with
    /// the feature) and more instructions a frame (docs/performance.md); a
    /// build without the `gradient` feature refuses it by name, as it
    /// refuses the filter.
    ///
    /// ```
    /// use pftrack::{Config, ConfigError, Error, ParamProblem, Tracker};
    ///
    /// match Tracker::<100>::new(Config::accurate(), 1) {
    ///     Ok(tracker) => assert_eq!(tracker.config().sure_share, 0.6),
    ///     Err(e) => assert_eq!(
    ///         e,
    ///         Error::Config(ConfigError { field: "gradient", problem: ParamProblem::NotBuilt { feature: "gradient" } })
    ///     ),
    /// }
    /// ```
    pub fn accurate() -> Self {
        let correlation = crate::correlation::DEFAULT.map(|c| CorrelationCue { centre_bias: 0.0, ..c });
        Config {
            gradient: Some(GradientCue::MEASURED),
            sure_share: 0.6,
            correlation,
            lost_search: LostSearch::Widening { growth: 0.05 },
            size: Config::fast().size.map(|s| SizeSearch { template: 0.3, ..s }),
            life: Life::Confidence { lost_below: 0.7, found_above: 0.8 },
            template: Some(TemplateCue { weight: 0.0, rate: 0.05 }),
            ..Config::fast()
        }
    }

    /// The names [`Config::named`] knows, for tools that take a
    /// configuration as text.
    pub const NAMES: [&'static str; 3] = ["default", "accurate", "fast"];

    /// The configuration named `name`: `"default"` ([`Config::default`]),
    /// `"accurate"` ([`Config::accurate`]) or `"fast"` ([`Config::fast`]);
    /// `None` for any other name.
    ///
    /// ```
    /// use pftrack::Config;
    ///
    /// assert_eq!(Config::named("fast"), Some(Config::fast()));
    /// assert!(Config::NAMES.iter().all(|n| Config::named(n).is_some()));
    /// assert_eq!(Config::named("quick"), None);
    /// ```
    pub fn named(name: &str) -> Option<Self> {
        match name {
            "default" => Some(Config::default()),
            "accurate" => Some(Config::accurate()),
            "fast" => Some(Config::fast()),
            _ => None,
        }
    }

    /// Whether some technique reads the surroundings' colours (see
    /// [`crate::foreground`]), so that the tracker learns them.
    pub fn uses_surroundings(&self) -> bool {
        self.life != Life::Appearance
            || self.size.is_some()
            || self.shift.is_some()
            || self.background_weight.is_some()
            || self.redetect != Redetect::Off
    }

    /// Whether some technique reads the grey-level template (see
    /// [`crate::template`]), so that the tracker learns it.
    pub fn uses_template(&self) -> bool {
        self.life != Life::Appearance
            || self.template.is_some()
            || self.shift.is_some_and(|s| s.template > 0.0)
            || self.size.is_some_and(|s| s.template > 0.0)
    }

    /// Checks every field against its documented range.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let mut c = Checks::new();
        match self.likelihood.sigma {
            Sigma::Fixed(s) => c.positive("likelihood.sigma", s, 10.0),
            Sigma::Spread { spread, min, max } => {
                c.positive("likelihood.sigma.spread", spread, 100.0);
                c.positive("likelihood.sigma.min", min, 10.0);
                c.positive("likelihood.sigma.max", max, 10.0);
                c.out_of_range_if(min > max, "likelihood.sigma.max");
            }
            Sigma::Adaptive { min, max } => {
                c.positive("likelihood.sigma.min", min, 10.0);
                c.positive("likelihood.sigma.max", max, 10.0);
                c.out_of_range_if(min > max, "likelihood.sigma.max");
            }
        }
        c.share("likelihood.eps", self.likelihood.eps);
        if let Combination::Weighted { colour } = self.combination {
            c.share("combination.colour", colour);
        }
        if let Some(e) = self.edges {
            c.out_of_range_if(!matches!(e.bins, 2 | 4 | 8 | 16), "edges.bins");
            c.out_of_range_if(e.threshold > 1500, "edges.threshold");
            c.out_of_range_if(e.strong_percent > 100, "edges.strong_percent");
        }
        if let Some(t) = self.table {
            c.out_of_range_if(!(1..=16).contains(&t.spacing), "table.spacing");
            // The window's histogram is whole-ellipse, and only the
            // Bhattacharyya sum can be kept up to date pixel by pixel.
            c.out_of_range_if(
                self.quadrants || self.similarity != crate::histogram::Similarity::Bhattacharyya,
                "table",
            );
        }
        crate::boundary::validate(&mut c, self.boundary);
        let d = &self.dynamics;
        c.range("dynamics.position_noise", d.position_noise, 0.0, 10.0);
        c.range("dynamics.velocity_noise", d.velocity_noise, 0.0, 10.0);
        c.share("dynamics.velocity_decay", d.velocity_decay);
        c.range("dynamics.speed_noise", d.speed_noise, 0.0, 10.0);
        c.range("dynamics.scale_noise", d.scale_noise, 0.0, 0.5);
        crate::motion::validate(&mut c, self.scene_motion);
        crate::correlation::validate(&mut c, self.correlation);
        crate::correlation::validate_gradient(&mut c, self.gradient);
        crate::histogram::validate_quadrants(&mut c, self.quadrants);
        crate::bins::validate(&mut c, self.binning);
        c.share("alpha", self.alpha);
        if let ModelUpdate::WhenDegraded { factor, frames } = self.model_update {
            c.share("model_update.factor", factor);
            c.out_of_range_if(frames == 0 || frames > 1000, "model_update.frames");
        }
        c.share("update_threshold", self.update_threshold);
        c.positive("update_sigma", self.update_sigma, 10.0);
        c.range("appearance_sigmas", self.appearance_sigmas, 0.0, 100.0);
        c.share("min_appearance", self.min_appearance);
        c.positive("kickoff", self.kickoff, 1.0);
        c.out_of_range_if(self.lost_after == 0 || self.lost_after > 1000, "lost_after");
        c.share("reseed_fraction", self.reseed_fraction);
        if let LostSearch::Widening { growth } = self.lost_search {
            c.range("lost_search.growth", growth, 0.0, 10.0);
        }
        c.range("min_half_axis", self.min_half_axis, 1.0, (crate::pixel::MAX_DIMENSION / 2) as Real);
        if let Some(t) = self.template {
            c.share("template.weight", t.weight);
            c.share("template.rate", t.rate);
        }
        c.out_of_range_if(!(self.sure_share > 0.0 && self.sure_share <= 1.0), "sure_share");
        if let Life::Confidence { lost_below, found_above } = self.life {
            c.share("life.lost_below", lost_below);
            c.share("life.found_above", found_above);
        }
        if let Some(s) = self.size {
            c.positive("size.step", s.step, 0.5);
            c.range("size.similarity", s.similarity, 0.0, 10.0);
            c.range("size.aspect_pull", s.aspect_pull, 0.0, 10.0);
            c.range("size.scale_pull", s.scale_pull, 0.0, 10.0);
            c.range("size.template", s.template, 0.0, 10.0);
        }
        if let Some(s) = self.shift {
            c.positive("shift.step", s.step, 0.5);
            c.range("shift.rounds", s.rounds as Real, 1.0, 8.0);
            c.range("shift.similarity", s.similarity, 0.0, 10.0);
            c.range("shift.template", s.template, 0.0, 10.0);
        }
        c.share("surroundings_rate", self.surroundings_rate);
        if let Some(b) = self.background_weight {
            c.share("background_weight.strength", b.strength);
            c.range("background_weight.above", b.above, 0.0, 0.95);
        }
        c.result()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::ParamProblem;

    #[test]
    fn default_is_valid() {
        assert_eq!(Config::default().validate(), Ok(()));
    }

    #[test]
    fn of_several_bad_fields_the_first_checked_is_named() {
        // Every check runs; the error must still be the first in the order
        // the checks are written (alpha, then kickoff, then lost_after), as
        // if each check returned early.
        let c = Config { alpha: 1.5, kickoff: 0.0, lost_after: 0, ..Config::default() };
        assert_eq!(c.validate(), Err(ConfigError { field: "alpha", problem: ParamProblem::OutOfRange }));
        let c = Config { kickoff: 0.0, lost_after: 0, ..Config::default() };
        assert_eq!(c.validate(), Err(ConfigError { field: "kickoff", problem: ParamProblem::OutOfRange }));
        // A cue that is not built is refused by name before its own fields
        // are read: their problems are not the one reported.
        let c = Config {
            gradient: Some(crate::GradientCue { rate: Real::NAN, ..crate::GradientCue::MEASURED }),
            alpha: 1.5,
            ..Config::default()
        };
        let first = if cfg!(feature = "gradient") {
            ConfigError { field: "gradient.rate", problem: ParamProblem::NonFinite }
        } else {
            crate::cue::not_built("gradient", "gradient")
        };
        assert_eq!(c.validate(), Err(first));
    }

    #[test]
    fn each_bad_field_is_named() {
        type Case = (fn(&mut Config), &'static str, ParamProblem);
        let cases: [Case; 26] = [
            (|c| c.combination = Combination::Weighted { colour: 1.5 }, "combination.colour", ParamProblem::OutOfRange),
            (
                |c| c.edges = Some(EdgeCue { bins: 7, threshold: 50, flat_bin: true, strong_percent: 10 }),
                "edges.bins",
                ParamProblem::OutOfRange,
            ),
            (
                |c| c.edges = Some(EdgeCue { bins: 8, threshold: 9999, flat_bin: true, strong_percent: 10 }),
                "edges.threshold",
                ParamProblem::OutOfRange,
            ),
            (
                |c| c.edges = Some(EdgeCue { bins: 8, threshold: 100, flat_bin: false, strong_percent: 101 }),
                "edges.strong_percent",
                ParamProblem::OutOfRange,
            ),
            (|c| c.likelihood.sigma = Sigma::Fixed(0.0), "likelihood.sigma", ParamProblem::OutOfRange),
            (|c| c.likelihood.sigma = Sigma::Fixed(-1.0), "likelihood.sigma", ParamProblem::OutOfRange),
            (|c| c.likelihood.sigma = Sigma::Fixed(Real::INFINITY), "likelihood.sigma", ParamProblem::NonFinite),
            (
                |c| c.likelihood.sigma = Sigma::Adaptive { min: 0.5, max: 0.1 },
                "likelihood.sigma.max",
                ParamProblem::OutOfRange,
            ),
            (|c| c.likelihood.eps = Real::NAN, "likelihood.eps", ParamProblem::NonFinite),
            (|c| c.dynamics.position_noise = -0.1, "dynamics.position_noise", ParamProblem::OutOfRange),
            (|c| c.dynamics.scale_noise = 1e9, "dynamics.scale_noise", ParamProblem::OutOfRange),
            (|c| c.dynamics.speed_noise = Real::NAN, "dynamics.speed_noise", ParamProblem::NonFinite),
            (|c| c.alpha = 1.5, "alpha", ParamProblem::OutOfRange),
            (|c| c.kickoff = 0.0, "kickoff", ParamProblem::OutOfRange),
            (|c| c.lost_after = 0, "lost_after", ParamProblem::OutOfRange),
            (|c| c.reseed_fraction = Real::NEG_INFINITY, "reseed_fraction", ParamProblem::NonFinite),
            (
                |c| c.lost_search = LostSearch::Widening { growth: Real::NAN },
                "lost_search.growth",
                ParamProblem::NonFinite,
            ),
            (|c| c.lost_search = LostSearch::Widening { growth: 11.0 }, "lost_search.growth", ParamProblem::OutOfRange),
            (|c| c.min_half_axis = 0.5, "min_half_axis", ParamProblem::OutOfRange),
            (
                |c| c.size = Some(SizeSearch { scale_pull: -0.1, ..Config::default().size.unwrap() }),
                "size.scale_pull",
                ParamProblem::OutOfRange,
            ),
            (
                |c| c.size = Some(SizeSearch { aspect_pull: Real::NAN, ..Config::default().size.unwrap() }),
                "size.aspect_pull",
                ParamProblem::NonFinite,
            ),
            (
                |c| c.shift = Some(ShiftSearch { step: 0.0, ..Config::default().shift.unwrap() }),
                "shift.step",
                ParamProblem::OutOfRange,
            ),
            (
                |c| c.shift = Some(ShiftSearch { rounds: 0, ..Config::default().shift.unwrap() }),
                "shift.rounds",
                ParamProblem::OutOfRange,
            ),
            (
                |c| c.background_weight = Some(BackgroundWeight { strength: 1.5, above: 0.0 }),
                "background_weight.strength",
                ParamProblem::OutOfRange,
            ),
            (
                |c| c.background_weight = Some(BackgroundWeight { strength: 0.5, above: 1.0 }),
                "background_weight.above",
                ParamProblem::OutOfRange,
            ),
            (
                |c| c.background_weight = Some(BackgroundWeight { strength: Real::NAN, above: 0.0 }),
                "background_weight.strength",
                ParamProblem::NonFinite,
            ),
        ];
        for (mutate, field, problem) in cases {
            let mut c = Config::default();
            mutate(&mut c);
            assert_eq!(c.validate(), Err(ConfigError { field, problem }));
        }
    }
}
