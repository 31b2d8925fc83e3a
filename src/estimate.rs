//! What a tracker reports: the estimate of each step, its state and
//! events, and the signals behind its confidence. Shared by the particle
//! filter and the mean-shift baselines.

use crate::geometry::{BoundingBox, Ellipse};
use crate::scalar::Real;

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
    /// surroundings, its correlation with the grey-level template, its
    /// colour similarity with the first model and its size against the
    /// first box's (see [`crate::on_target`]),
    /// halved on a frame where the box moves with its surroundings
    /// ([`crate::Config::scene_motion`]); with
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
    /// With [`crate::Config::quadrants`]: the quadrant (0 top-left, 1 top-right,
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

/// The signals behind the last step's confidence (see [`crate::on_target`]), for
/// diagnostics and for studying failures; all zero under
/// [`crate::Life::Appearance`].
#[derive(Copy, Clone, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Diagnostics {
    /// Contrast of the estimate's box with the ring around it in the
    /// foreground map, in `[-1, 1]`.
    pub contrast: Real,
    /// Grey-level correlation of the estimate with the template (the first
    /// box's, or as [`crate::TemplateCue`] adapts it), in `[-1, 1]`.
    pub correlation: Real,
    /// Colour similarity of the estimate with the first model, in `[0, 1]`.
    /// (The confidence's fourth signal, the size change, comes from the
    /// estimate's box: [`crate::size_change`].)
    pub anchored: Real,
    /// Similarity of the estimate with the adapted models, in `[0, 1]`.
    pub similarity: Real,
    /// Peak-to-sidelobe ratio of the correlation filter's response this step
    /// (MOSSE's measure of how sure the filter is: about 3 on a texture it
    /// never saw); 0 without the filter (`Config::correlation`).
    pub psr: Real,
}
