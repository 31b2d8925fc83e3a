//! OTB one-pass evaluation (docs/accuracy.md, "The data and the protocol"): success AUC and precision@20.

use pftrack::BoundingBox;

/// IoU thresholds of the success plot: 0, 0.05, …, 1.0.
pub const SUCCESS_THRESHOLDS: usize = 21;

/// Scores of one tracked sequence.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scores {
    /// Mean over the IoU thresholds of the fraction of frames above each.
    pub auc: f64,
    /// Fraction of frames whose centre error is at most 20 px.
    pub precision20: f64,
    /// Mean IoU.
    pub mean_iou: f64,
    /// Frames scored (frames whose ground truth has a target).
    pub frames: usize,
}

/// Whether a ground-truth box marks a present target (OTB marks absent
/// targets with zero or NaN sizes).
pub fn has_target(b: &BoundingBox) -> bool {
    b.width > 0.0 && b.height > 0.0 && b.x.is_finite() && b.y.is_finite()
}

/// Euclidean distance between box centres.
pub fn centre_error(a: &BoundingBox, b: &BoundingBox) -> f64 {
    let (ax, ay) = a.centre();
    let (bx, by) = b.centre();
    ((ax as f64 - bx as f64).powi(2) + (ay as f64 - by as f64).powi(2)).sqrt()
}

/// The fraction of `values` strictly above `t`.
fn fraction_above(values: &[f64], t: f64) -> f64 {
    values.iter().filter(|&&v| v > t).count() as f64 / values.len() as f64
}

/// Scores `predicted` against `truth`, frame by frame; frames without a
/// target in the ground truth are skipped. `None` if no frame can be scored.
pub fn score(predicted: &[BoundingBox], truth: &[BoundingBox]) -> Option<Scores> {
    let pairs: Vec<_> = predicted.iter().zip(truth).filter(|(_, t)| has_target(t)).collect();
    if pairs.is_empty() {
        return None;
    }
    let ious: Vec<f64> = pairs.iter().map(|(p, t)| p.iou(t) as f64).collect();
    let errs: Vec<f64> = pairs.iter().map(|(p, t)| centre_error(p, t)).collect();
    let auc = (0..SUCCESS_THRESHOLDS).map(|i| fraction_above(&ious, i as f64 * 0.05)).sum::<f64>()
        / SUCCESS_THRESHOLDS as f64;
    let precision20 = errs.iter().filter(|&&e| e <= 20.0).count() as f64 / errs.len() as f64;
    let mean_iou = ious.iter().sum::<f64>() / ious.len() as f64;
    Some(Scores { auc, precision20, mean_iou, frames: pairs.len() })
}

/// The success curve: for each IoU threshold 0, 0.05, …, 1 the fraction of
/// scored frames whose IoU is above it (its mean is [`Scores::auc`]).
pub fn success_curve(predicted: &[BoundingBox], truth: &[BoundingBox]) -> Option<Vec<f64>> {
    let ious: Vec<f64> =
        predicted.iter().zip(truth).filter(|(_, t)| has_target(t)).map(|(p, t)| p.iou(t) as f64).collect();
    if ious.is_empty() {
        return None;
    }
    Some((0..SUCCESS_THRESHOLDS).map(|i| fraction_above(&ious, i as f64 * 0.05)).collect())
}

/// Centre-error thresholds of the precision curve: 0, 1, …, 50 px.
pub const PRECISION_THRESHOLDS: usize = 51;

/// The precision curve: for each threshold 0..=50 px the fraction of scored
/// frames whose centre error is at most it (its value at 20 is
/// [`Scores::precision20`]).
pub fn precision_curve(predicted: &[BoundingBox], truth: &[BoundingBox]) -> Option<Vec<f64>> {
    let errs: Vec<f64> =
        predicted.iter().zip(truth).filter(|(_, t)| has_target(t)).map(|(p, t)| centre_error(p, t)).collect();
    if errs.is_empty() {
        return None;
    }
    let n = errs.len() as f64;
    Some((0..PRECISION_THRESHOLDS).map(|t| errs.iter().filter(|&&e| e <= t as f64).count() as f64 / n).collect())
}

/// Where a track's overlap is lost: its success AUC with each box given the
/// truth's size about the tracker's centre, and with each box moved to the
/// truth's centre at the tracker's size. The first minus the track's AUC is
/// what sizing costs it, the second minus it what placing costs; the third
/// splits placing into the frames where the box still overlaps the target
/// and those where it has lost it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Breakdown {
    /// AUC with the truth's width and height at the tracker's centres.
    pub true_size: f64,
    /// AUC with the tracker's width and height at the truth's centres.
    pub true_centre: f64,
    /// The same, but only the boxes that overlap the truth by at least
    /// [`MISS_IOU`] moved (the target held, the box off its centre); the
    /// rest as they are.
    pub held_centre: f64,
}

/// The [`Breakdown`] of `predicted` against `truth` (frames without a
/// target skipped); `None` if no frame can be scored.
pub fn breakdown(predicted: &[BoundingBox], truth: &[BoundingBox]) -> Option<Breakdown> {
    // A box of size (w, h) centred on (cx, cy).
    let at = |(cx, cy): (f32, f32), w: f32, h: f32| BoundingBox::new(cx - w / 2.0, cy - h / 2.0, w, h);
    let sized: Vec<BoundingBox> = predicted.iter().zip(truth).map(|(p, t)| at(p.centre(), t.width, t.height)).collect();
    let placed: Vec<BoundingBox> =
        predicted.iter().zip(truth).map(|(p, t)| at(t.centre(), p.width, p.height)).collect();
    let held: Vec<BoundingBox> = predicted
        .iter()
        .zip(&placed)
        .zip(truth)
        .map(|((p, moved), t)| if p.iou(t) as f64 >= MISS_IOU { *moved } else { *p })
        .collect();
    Some(Breakdown {
        true_size: score(&sized, truth)?.auc,
        true_centre: score(&placed, truth)?.auc,
        held_centre: score(&held, truth)?.auc,
    })
}

/// IoU below which a frame counts as missing the target.
pub const MISS_IOU: f64 = 0.1;

/// IoU from which a frame counts as good.
pub const GOOD_IOU: f64 = 0.3;

/// How well a tracker knows when it is wrong, pooled over the frames of one
/// or more runs: frames whose box misses the target (IoU < [`MISS_IOU`])
/// should be reported as not tracking, good frames (IoU ≥ [`GOOD_IOU`])
/// should not, and the confidence should rank missing frames below the rest.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Awareness {
    /// Missing frames.
    pub missing: usize,
    /// Missing frames reported not tracking (lost or searching).
    pub missing_flagged: usize,
    /// Good frames.
    pub good: usize,
    /// Good frames reported not tracking.
    pub good_flagged: usize,
    /// (confidence, missing) of every scored frame, for the ROC.
    pub samples: Vec<(f32, bool)>,
}

impl Awareness {
    /// Adds one frame: the tracker's box, whether it reported tracking, its
    /// confidence, and the truth (frames without a target are skipped).
    pub fn add(&mut self, predicted: &BoundingBox, tracking: bool, confidence: f32, truth: &BoundingBox) {
        if !has_target(truth) {
            return;
        }
        let iou = predicted.iou(truth) as f64;
        let missing = iou < MISS_IOU;
        if missing {
            self.missing += 1;
            self.missing_flagged += !tracking as usize;
        } else if iou >= GOOD_IOU {
            self.good += 1;
            self.good_flagged += !tracking as usize;
        }
        self.samples.push((confidence, missing));
    }

    /// Pools another set of frames into this one.
    pub fn merge(&mut self, other: &Awareness) {
        self.missing += other.missing;
        self.missing_flagged += other.missing_flagged;
        self.good += other.good;
        self.good_flagged += other.good_flagged;
        self.samples.extend_from_slice(&other.samples);
    }

    /// The share of scored frames that miss the target (`None` without any).
    pub fn missing_share(&self) -> Option<f64> {
        (!self.samples.is_empty()).then(|| self.missing as f64 / self.samples.len() as f64)
    }

    /// The share of missing frames reported not tracking (`None` without any).
    pub fn missing_reported(&self) -> Option<f64> {
        (self.missing > 0).then(|| self.missing_flagged as f64 / self.missing as f64)
    }

    /// The share of good frames reported not tracking (`None` without any).
    pub fn good_reported_lost(&self) -> Option<f64> {
        (self.good > 0).then(|| self.good_flagged as f64 / self.good as f64)
    }

    /// The confidence's ROC AUC for telling missing frames from the others:
    /// the probability that a frame that is not missing has a higher
    /// confidence than a missing one (ties count half), i.e. the
    /// Mann–Whitney U statistic over the product of the class sizes.
    /// `None` unless both classes occur.
    pub fn roc_auc(&self) -> Option<f64> {
        let mut s = self.samples.clone();
        s.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (mut neg, mut pos) = (0u64, 0u64);
        // Sum of the ranks (1-based, ties averaged) of the frames that are not missing.
        let mut rank_sum = 0.0f64;
        let mut i = 0;
        while i < s.len() {
            let mut j = i;
            while j < s.len() && s[j].0 == s[i].0 {
                j += 1;
            }
            let avg_rank = (i + 1 + j) as f64 / 2.0;
            for &(_, missing) in &s[i..j] {
                if missing {
                    neg += 1;
                } else {
                    pos += 1;
                    rank_sum += avg_rank;
                }
            }
            i = j;
        }
        if neg == 0 || pos == 0 {
            return None;
        }
        let u = rank_sum - (pos * (pos + 1)) as f64 / 2.0;
        Some(u / (pos * neg) as f64)
    }
}

/// The IoU at which a box is on a target: the usual threshold of a
/// correct detection.
pub const ON_TARGET_IOU: f32 = 0.5;

/// Identity swaps of several tracks against several truths, target `k`'s
/// track against target `k`'s truth: the (frame, target) pairs where the
/// track claims the target (`Some`: the tracker reports it tracked) on
/// another target's truth (IoU at least [`ON_TARGET_IOU`]) and not on its
/// own. A target reported lost claims nothing. Frames past the shortest
/// list are not counted.
pub fn identity_swaps(tracks: &[Vec<Option<BoundingBox>>], truths: &[Vec<BoundingBox>]) -> usize {
    let frames = tracks.iter().map(Vec::len).chain(truths.iter().map(Vec::len)).min().unwrap_or(0);
    let mut swaps = 0;
    for f in 0..frames {
        for (k, track) in tracks.iter().enumerate() {
            let Some(b) = &track[f] else { continue };
            let on = |t: &BoundingBox| has_target(t) && b.iou(t) >= ON_TARGET_IOU;
            let own = truths.get(k).is_some_and(|t| on(&t[f]));
            let other = truths.iter().enumerate().any(|(j, t)| j != k && on(&t[f]));
            swaps += usize::from(other && !own);
        }
    }
    swaps
}

/// The median of a list (0 for an empty one).
pub fn median(values: &[f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mut v = values.to_vec();
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perfect_track_scores_one() {
        // Reason: IoU 1 exceeds every threshold below 1 but not 1.0 itself
        // (strictly above), so AUC = 20/21; centre error 0 passes P20.
        let t = vec![BoundingBox::new(0.0, 0.0, 10.0, 10.0); 5];
        let s = score(&t, &t).unwrap();
        assert!((s.auc - 20.0 / 21.0).abs() < 1e-12);
        assert_eq!(s.precision20, 1.0);
        assert_eq!(s.mean_iou, 1.0);
    }

    #[test]
    fn hand_computed_mixture() {
        // One perfect frame (IoU 1) and one disjoint 30 px away (IoU 0):
        // AUC = (20/21 + 0) / 2 by the threshold count, with threshold 0
        // excluded for the disjoint frame since 0 is not above 0; P20 = 1/2.
        let truth = vec![BoundingBox::new(0.0, 0.0, 10.0, 10.0); 2];
        let pred = vec![truth[0], BoundingBox::new(30.0, 0.0, 10.0, 10.0)];
        let s = score(&pred, &truth).unwrap();
        assert!((s.auc - 10.0 / 21.0).abs() < 1e-12);
        assert_eq!(s.precision20, 0.5);
        assert!((centre_error(&pred[1], &truth[1]) - 30.0).abs() < 1e-9);
    }

    #[test]
    fn breakdown_by_hand() {
        // Reason: by hand. Frame 1 has the right centre at twice the size
        // (IoU 1/4); frame 2 the right size 30 px off (IoU 0). With the
        // truth's size, frame 1 becomes exact (above 20 of 21 thresholds)
        // and frame 2 stays disjoint (none): (20/21 + 0) / 2. At the
        // truth's centre, frame 2 becomes exact and frame 1 stays at IoU
        // 1/4, above the thresholds 0, 0.05, ..., 0.2 (5 of 21): (5/21 +
        // 20/21) / 2.
        let truth = vec![BoundingBox::new(0.0, 0.0, 10.0, 10.0); 2];
        let pred = vec![BoundingBox::new(-5.0, -5.0, 20.0, 20.0), BoundingBox::new(30.0, 0.0, 10.0, 10.0)];
        let b = breakdown(&pred, &truth).unwrap();
        assert!((b.true_size - 10.0 / 21.0).abs() < 1e-9, "{b:?}");
        assert!((b.true_centre - 12.5 / 21.0).abs() < 1e-9, "{b:?}");
        // Only the boxes that overlap the truth move to its centre: frame 1
        // 2 px off (IoU 2/3, above 0, ..., 0.65: 14 of 21) becomes exact
        // (20 of 21); frame 2, disjoint, stays where it is (none). Where
        // held: (20/21 + 0) / 2; every box moved: (20/21 + 20/21) / 2.
        let pred = vec![BoundingBox::new(2.0, 0.0, 10.0, 10.0), BoundingBox::new(30.0, 0.0, 10.0, 10.0)];
        let b = breakdown(&pred, &truth).unwrap();
        assert!((score(&pred, &truth).unwrap().auc - 7.0 / 21.0).abs() < 1e-9);
        assert!((b.held_centre - 10.0 / 21.0).abs() < 1e-9, "{b:?}");
        assert!((b.true_centre - 20.0 / 21.0).abs() < 1e-9, "{b:?}");
        assert!(breakdown(&pred, &[BoundingBox::new(0.0, 0.0, 0.0, 0.0); 2]).is_none());
    }

    #[test]
    fn absent_targets_are_not_scored() {
        let truth = vec![BoundingBox::new(0.0, 0.0, 10.0, 10.0), BoundingBox::new(0.0, 0.0, 0.0, 0.0)];
        let pred = vec![truth[0], BoundingBox::new(50.0, 50.0, 10.0, 10.0)];
        assert_eq!(score(&pred, &truth).unwrap().frames, 1);
        assert!(score(&pred[1..], &truth[1..]).is_none());
    }

    #[test]
    fn curves_agree_with_the_scores() {
        // Reason: by definition the success curve's mean is the AUC and the
        // precision curve at 20 px is P20; both curves never increase /
        // decrease respectively as the threshold grows.
        let truth: Vec<_> = (0..40).map(|i| BoundingBox::new(i as f32, 10.0, 20.0, 30.0)).collect();
        let pred: Vec<_> =
            (0..40).map(|i| BoundingBox::new(i as f32 + (i % 7) as f32 * 4.0, 12.0, 18.0, 30.0)).collect();
        let s = score(&pred, &truth).unwrap();
        let sc = success_curve(&pred, &truth).unwrap();
        let pc = precision_curve(&pred, &truth).unwrap();
        assert!((sc.iter().sum::<f64>() / sc.len() as f64 - s.auc).abs() < 1e-12);
        assert_eq!(pc[20], s.precision20);
        assert!(sc.windows(2).all(|w| w[1] <= w[0]) && pc.windows(2).all(|w| w[1] >= w[0]));
    }

    #[test]
    fn awareness_by_hand() {
        // Reason: hand-built frames. Truth is a 10x10 box at the origin.
        // Frame A: exact box (IoU 1, good), tracking, confidence 0.9.
        // Frame B: disjoint box (IoU 0, missing), reported lost, confidence 0.2.
        // Frame C: disjoint box (missing), tracking, confidence 0.95.
        // Frame D: half-overlapping box, IoU 50/150 = 1/3 (good), lost, 0.5.
        let t = BoundingBox::new(0.0, 0.0, 10.0, 10.0);
        let far = BoundingBox::new(50.0, 50.0, 10.0, 10.0);
        let half = BoundingBox::new(5.0, 0.0, 10.0, 10.0);
        let mut a = Awareness::default();
        a.add(&t, true, 0.9, &t);
        a.add(&far, false, 0.2, &t);
        a.add(&far, true, 0.95, &t);
        a.add(&half, false, 0.5, &t);
        a.add(&far, true, 0.1, &BoundingBox::default()); // no target: skipped
        assert_eq!((a.missing, a.missing_flagged, a.good, a.good_flagged), (2, 1, 2, 1));
        // Two of the four scored frames miss; the frame without a target is not counted.
        assert_eq!(a.missing_share(), Some(0.5));
        assert_eq!(a.missing_reported(), Some(0.5));
        assert_eq!(a.good_reported_lost(), Some(0.5));
        // Pairs (not missing, missing): (0.9, 0.2) yes, (0.9, 0.95) no,
        // (0.5, 0.2) yes, (0.5, 0.95) no: 2 of 4.
        assert_eq!(a.roc_auc(), Some(0.5));
        // A tie counts half: one good and one missing frame at 0.7.
        let mut b = Awareness::default();
        b.add(&t, true, 0.7, &t);
        b.add(&far, true, 0.7, &t);
        assert_eq!(b.roc_auc(), Some(0.5));
        let mut c = Awareness::default();
        c.add(&t, true, 0.8, &t);
        c.add(&far, true, 0.1, &t);
        assert_eq!(c.roc_auc(), Some(1.0), "perfect separation");
        c.merge(&b);
        assert_eq!(c.samples.len(), 4);
    }

    #[test]
    fn missing_share_by_hand() {
        // Reason: by hand. Truth is a 10x10 box at the origin. A box moved
        // 9 px right overlaps 1x10: IoU 10/190 ≈ 0.053, missing. One moved
        // 8 px: IoU 20/180 ≈ 0.111, not missing (0.1 is the bound). Exact
        // and disjoint boxes: 1 and 0. Missing: 2 of 4 frames.
        let t = BoundingBox::new(0.0, 0.0, 10.0, 10.0);
        let mut a = Awareness::default();
        for x in [9.0, 8.0, 0.0, 50.0] {
            a.add(&BoundingBox::new(x, 0.0, 10.0, 10.0), true, 0.0, &t);
        }
        assert_eq!(a.missing, 2);
        assert_eq!(a.missing_share(), Some(0.5));
        // A constant confidence tells nothing: every pair ties.
        assert_eq!(a.roc_auc(), Some(0.5));
        assert_eq!(Awareness::default().missing_share(), None);
    }

    #[test]
    fn median_of_even_and_odd() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
        assert_eq!(median(&[]), 0.0);
    }

    #[test]
    fn identity_swaps_count_tracks_on_another_target_and_not_their_own() {
        // Reason: hand-built tracks. Two targets 100 px apart for four
        // frames; on frame 2 the tracks are exchanged (two swaps), on
        // frame 3 both tracks sit on target B (one swap: A's track, which
        // is on B's truth and not its own); on frame 4 A's track is on B
        // but reported lost (no claim, no swap).
        let (a, b) = (BoundingBox::new(0.0, 0.0, 10.0, 10.0), BoundingBox::new(100.0, 0.0, 10.0, 10.0));
        let truths = vec![vec![a, a, a, a], vec![b, b, b, b]];
        let tracks = vec![vec![Some(a), Some(b), Some(b), None], vec![Some(b), Some(a), Some(b), Some(b)]];
        assert_eq!(identity_swaps(&tracks, &truths), 3);
        // Right where the truths overlap, being on both is not a swap.
        assert_eq!(identity_swaps(&[vec![Some(a)]], &[vec![a], vec![a]]), 0);
        // A hidden target's empty truth is on nothing.
        assert_eq!(identity_swaps(&[vec![Some(b)], vec![Some(b)]], &[vec![BoundingBox::default()], vec![b]]), 1);
    }
}
