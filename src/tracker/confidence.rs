//! The confidence: the probability that an estimate is on its target.

use crate::scalar::{Real, exp, ln};

/// The median contrast of estimates on their target (IoU ≥ 0.3) on the
/// real sequences' tune split (`track otb --dump`), for boxes whose
/// contrast cannot be measured.
pub(super) const TYPICAL_CONTRAST: Real = 0.39;

/// What the confidence of a box that moves with its surroundings is
/// multiplied by (`Config::scene_motion`): the test is right on most of the
/// frames it flags, and a flagged box then ranks below every box the life
/// cycle keeps (halved, the surest is under either configuration's lost line).
/// Only the reported confidence: the cues still learn from the signals'.
pub(super) const MOVES_WITH_SCENE: Real = 0.5;

/// How much of each frame's displacement enters the target's recent speed:
/// about the last three frames count.
pub(super) const SPEED_RATE: Real = 0.3;

/// The probability that an estimate is on its target, from three signals
/// that a drifting estimate cannot keep high together: its box's
/// `contrast` with the ring around it in the foreground map (in `[-1, 1]`),
/// its grey-level `correlation` with the template (negative counts as
/// 0), and its colour similarity with the first model, `anchored`; and
/// from how far its size has gone from the first box's, `size_change`
/// ([`size_change`]): a box that has grown over its
/// surroundings or shrunk onto a part of the target is more often off it.
///
/// A logistic model, `1 / (1 + exp(−z))` with `z = 8.31·contrast +
/// 3.06·correlation + 3.31·anchored − 2.33·size_change − 2.37`, whose
/// coefficients are a logistic regression of "IoU with the truth ≥ 0.1"
/// on the real sequences' tune split (`tools/fit-confidence`;
/// docs/accuracy.md). Together the four separate missing frames from the
/// others better there than any one of them alone (the ROC AUCs are in
/// docs/accuracy.md).
///
/// ```
/// // A box that stands out, with the target's layout and colours, at its
/// // first size: z = 8.31·0.4 + 3.06·0.8 + 3.31·0.9 − 2.37 = 6.38.
/// let p = pftrack::on_target(0.4, 0.8, 0.9, 0.0);
/// assert!((p - 1.0 / (1.0 + (-6.38f32).exp())).abs() < 1e-3);
/// // The same box grown to four times the first area is less sure.
/// assert!(pftrack::on_target(0.4, 0.8, 0.9, 4f32.ln()) < p);
/// ```
pub fn on_target(contrast: Real, correlation: Real, anchored: Real, size_change: Real) -> Real {
    let z = 8.31 * contrast + 3.06 * correlation.max(0.0) + 3.31 * anchored - 2.33 * size_change - 2.37;
    1.0 / (1.0 + exp(-z))
}

/// The confidence's size signal (see [`on_target`]): how far a box of
/// `size` is from the `first` box's, `|ln(area / first area)|`, for sizes
/// given as widths and heights or as half axes (only the ratio counts).
/// 0 at the first area whatever the shape, ln 2 at twice or half of it;
/// sizes are positive, as a tracker's are (a zero area gives infinity or
/// NaN).
///
/// ```
/// let twice = pftrack::size_change((10.0, 20.0), (20.0, 20.0));
/// assert!((twice - 2f32.ln()).abs() < 1e-6);
/// assert_eq!(pftrack::size_change((10.0, 20.0), (10.0, 10.0)), twice);
/// assert_eq!(pftrack::size_change((10.0, 20.0), (20.0, 10.0)), 0.0);
/// ```
pub fn size_change(first: (Real, Real), size: (Real, Real)) -> Real {
    ln((size.0 * size.1) / (first.0 * first.1)).abs()
}
