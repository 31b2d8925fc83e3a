//! Several targets at once: a fixed-capacity group of trackers that share
//! one working memory and keep apart.

use crate::apart::{Others, core};
use crate::config::Config;
use crate::error::Error;
use crate::estimate::{Estimate, TrackState};
use crate::frame::Frame;
use crate::geometry::{BoundingBox, Ellipse};
use crate::scalar::Real;
use crate::tracker::{Scratch, Track};
use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro128PlusPlus;

/// A target's identity in a [`Group`]: given by [`Group::add`], never reused
/// by the same group (until 65,536 targets have been added).
#[derive(Copy, Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TargetId(pub u16);

/// One target's estimate from [`Group::step`].
#[derive(Copy, Clone, Debug)]
pub struct Tracked {
    /// Whose estimate it is.
    pub id: TargetId,
    /// The estimate, as [`crate::Tracker::step`] gives it.
    pub estimate: Estimate,
}

/// Every target's estimate from one [`Group::step`], in the order of
/// [`Group::ids`] (a `heapless::Vec`, iterable as a slice).
pub type Tracks<const M: usize> = heapless::Vec<Tracked, M>;

/// What [`Group::add`] reports of a new target.
#[derive(Copy, Clone, Debug)]
pub struct Added {
    /// The new target's identity.
    pub id: TargetId,
    /// Its estimate on the frame it was learnt from.
    pub estimate: Estimate,
    /// The target already tracked whose box overlaps the new one most, and
    /// their intersection over union; `None` when no tracked box overlaps.
    pub overlap: Option<(TargetId, Real)>,
}

/// One member: a target's identity and state.
#[derive(Clone, Debug)]
struct Member<const N: usize, const K: usize, R, const T: usize> {
    /// The target's identity; `None` while the place is free.
    id: Option<TargetId>,
    track: Track<N, K, R, T>,
    /// The estimate's smoothed displacement, pixels a frame, over frames
    /// tracked one after another.
    velocity: (Real, Real),
}

impl<const N: usize, const K: usize, R: Rng, const T: usize> Member<N, K, R, T> {
    /// The region the target will hold on the next frame: where it is,
    /// moved by its velocity. Predicted rather than last, so that two
    /// targets that meet are each pushed along their own way, not back the
    /// way they came.
    fn held(&self) -> Option<Ellipse> {
        self.id?;
        let e = self.track.held()?;
        Some(Ellipse { cx: e.cx + self.velocity.0, cy: e.cy + self.velocity.1, ..e })
    }
}

/// How fast a member's velocity follows its estimate's displacement: half
/// way each frame, so that one jump of the estimate does not swing the
/// region it holds far off.
const VELOCITY_RATE: Real = 0.5;

/// Up to `M` targets, each followed by its own particle filter of `N`
/// particles (colour histograms of up to `K` bins, an edge map of `E` bytes,
/// randomness from `R`), stepped together on each frame.
///
/// - Every target has its own state, events and confidence: a lost one
///   searches while the others track.
/// - The targets share one working memory (histograms, edge map,
///   foreground map), so a group of three takes much less RAM than three
///   [`crate::Tracker`]s; `core::mem::size_of` gives it.
/// - Targets keep apart: a hypothesis of one target weighs less where
///   another tracked target's box covers it, so two similar targets that
///   cross come out with their identities rather than both on one. The
///   regions are those of the last frame's estimates, so the result does
///   not depend on the order the targets are stepped in.
/// - Target `i` (the `i`-th added, from 0) draws from `R` seeded with
///   `seed + i`: a group of one gives the same estimates, bit for bit, as a
///   [`crate::Tracker`] with the same seed.
///
/// ```
/// use pftrack::{BoundingBox, Config, Frame, Group, PixelFormat, TrackState};
///
/// // A grey 96x48 scene: a red square moving right, a blue one moving left.
/// let scene = |t: usize| {
///     let mut px = vec![90u8; 96 * 48 * 3];
///     for (left, colour) in [(8 + 2 * t, [220, 30, 30]), (72 - 2 * t, [30, 30, 220])] {
///         for y in 18..30 {
///             for x in left..left + 12 {
///                 px[(y * 96 + x) * 3..][..3].copy_from_slice(&colour);
///             }
///         }
///     }
///     px
/// };
/// let mut group: Group<2, 50> = Group::new(Config::default(), 42)?;
/// let first = scene(0);
/// let frame = Frame::packed(&first, 96, 48, PixelFormat::Rgb888)?;
/// let red = group.add(&frame, BoundingBox::new(8.0, 18.0, 12.0, 12.0))?.id;
/// let blue = group.add(&frame, BoundingBox::new(72.0, 18.0, 12.0, 12.0))?.id;
/// for t in 1..=8 {
///     let px = scene(t);
///     for tracked in group.step(&Frame::packed(&px, 96, 48, PixelFormat::Rgb888)?)? {
///         let (cx, _) = tracked.estimate.bbox().centre();
///         let truth = if tracked.id == red { 14.0 + 2.0 * t as f32 } else { 78.0 - 2.0 * t as f32 };
///         assert_eq!(tracked.estimate.state, TrackState::Tracking);
///         assert!((cx - truth).abs() < 3.0);
///     }
/// }
/// group.remove(blue)?;
/// assert_eq!(group.len(), 1);
/// # Ok::<(), pftrack::Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct Group<
    const M: usize,
    const N: usize,
    const K: usize = 512,
    const E: usize = 4096,
    R = Xoshiro128PlusPlus,
    const T: usize = 0,
> {
    config: Config,
    seed: u64,
    /// Identity of the next target added.
    next: u16,
    /// Every place, free or not: built once, reused in place.
    members: [Member<N, K, R, T>; M],
    scratch: Scratch<K, E>,
}

impl<const M: usize, const N: usize, const K: usize, const E: usize, R, const T: usize> Group<M, N, K, E, R, T>
where
    R: Rng + SeedableRng,
{
    /// An empty group whose targets all use `config`; target `i` draws
    /// from `R` seeded with `seed + i`. The configuration is checked here,
    /// as [`crate::Tracker::new`] checks it.
    pub fn new(config: Config, seed: u64) -> Result<Self, Error> {
        const { assert!(M >= 1, "a group holds at least one target") }
        // Checked once, with the capacities every member will have.
        Track::<N, K, R, T>::new(config, R::seed_from_u64(seed))?;
        let members = core::array::from_fn(|_| Member {
            id: None,
            track: Track::blank(config, R::seed_from_u64(seed)),
            velocity: (0.0, 0.0),
        });
        Ok(Group { config, seed, next: 0, members, scratch: Scratch::new() })
    }

    /// The configuration every target uses.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// How many targets the group holds.
    pub fn len(&self) -> usize {
        self.active().count()
    }

    /// Whether the group holds no target.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The targets' identities, in the order [`Group::step`] reports them.
    pub fn ids(&self) -> impl Iterator<Item = TargetId> + '_ {
        self.active().filter_map(|m| m.id)
    }

    /// The state of target `id`.
    pub fn state(&self, id: TargetId) -> Result<TrackState, Error> {
        Ok(self.member(id)?.track.state())
    }

    /// Learns a new target from `bbox` in `frame` and starts tracking it
    /// there. A box that overlaps a target already tracked is accepted;
    /// [`Added::overlap`] says by how much. All targets of a group share
    /// the frame size of the first: a frame of another size is
    /// [`Error::FrameSizeChanged`]. On any error the group is unchanged.
    pub fn add(&mut self, frame: &Frame<'_>, bbox: BoundingBox) -> Result<Added, Error> {
        let size = (frame.width(), frame.height());
        if let Some(expected) = self.frame_size()
            && expected != size
        {
            return Err(Error::FrameSizeChanged { expected, got: size });
        }
        let overlap = self
            .active()
            .filter_map(|m| Some((m.id?, m.track.held()?.to_box().iou(&bbox))))
            .filter(|&(_, iou)| iou > 0.0)
            .fold(None, |best: Option<(TargetId, Real)>, o| match best {
                Some(b) if b.1 >= o.1 => Some(b),
                _ => Some(o),
            });
        let id = TargetId(self.next);
        let Group { members, scratch, seed, .. } = self;
        let member = members.iter_mut().find(|m| m.id.is_none()).ok_or(Error::GroupFull { capacity: M })?;
        // In place; the place stays free unless the box is learnt.
        member.track.reset(R::seed_from_u64(seed.wrapping_add(id.0 as u64)));
        let estimate = member.track.init(scratch, frame, bbox)?;
        member.id = Some(id);
        member.velocity = (0.0, 0.0);
        self.next = self.next.wrapping_add(1);
        Ok(Added { id, estimate, overlap })
    }

    /// Re-initialises target `id` on `bbox` in `frame`, keeping its
    /// identity (as [`crate::Tracker::init`] does for one target).
    /// A frame of another size than the other targets' is
    /// [`Error::FrameSizeChanged`].
    pub fn reinit(&mut self, id: TargetId, frame: &Frame<'_>, bbox: BoundingBox) -> Result<Estimate, Error> {
        self.member(id)?;
        let size = (frame.width(), frame.height());
        if let Some(expected) = self.active().filter(|m| m.id != Some(id)).find_map(|m| m.track.frame_size())
            && expected != size
        {
            return Err(Error::FrameSizeChanged { expected, got: size });
        }
        let Group { members, scratch, .. } = self;
        let member = members.iter_mut().find(|m| m.id == Some(id)).ok_or(Error::UnknownTarget { id: id.0 })?;
        let estimate = member.track.init(scratch, frame, bbox)?;
        // A new box: the old motion says nothing of where it goes next.
        member.velocity = (0.0, 0.0);
        Ok(estimate)
    }

    /// Stops following target `id`; its place is free for another.
    pub fn remove(&mut self, id: TargetId) -> Result<(), Error> {
        let member = self.members.iter_mut().find(|m| m.id == Some(id)).ok_or(Error::UnknownTarget { id: id.0 })?;
        member.id = None;
        Ok(())
    }

    /// Tracks every target on one frame; returns each target's estimate
    /// with its identity, in the order of [`Group::ids`].
    ///
    /// A tracked target's hypotheses are weighed down where another tracked
    /// target's box covers them; a target that is lost or searching is
    /// weighed down on every tracked target's box, so that it does not
    /// re-acquire onto another. The frame must have the group's frame size.
    pub fn step(&mut self, frame: &Frame<'_>) -> Result<Tracks<M>, Error> {
        let size = (frame.width(), frame.height());
        if let Some(expected) = self.frame_size()
            && expected != size
        {
            return Err(Error::FrameSizeChanged { expected, got: size });
        }
        // The regions held (their cores), as the last frame left them: every target's
        // step sees the same ones whatever the order.
        let mut held: [Option<(TargetId, BoundingBox)>; M] = [None; M];
        for (h, m) in held.iter_mut().zip(self.members.iter()) {
            *h = m.id.zip(m.held().map(|e| core(&e)));
        }
        let mut out = Tracks::new();
        let Group { members, scratch, .. } = self;
        for m in members.iter_mut() {
            let Some(me) = m.id else { continue };
            let mut others = [BoundingBox::default(); M];
            let mut n = 0;
            for (id, e) in held.iter().flatten() {
                if *id != me
                    && let Some(o) = others.get_mut(n)
                {
                    *o = *e;
                    n += 1;
                }
            }
            let before = m.track.held();
            let own = held.iter().flatten().find(|(id, _)| *id == me).map(|(_, e)| *e);
            let apart = Others { own, held: others.get(..n).unwrap_or(&[]) };
            let estimate = m.track.step_inner(scratch, frame, None, apart)?;
            m.velocity = match (before, m.track.held()) {
                (Some(b), Some(a)) => {
                    let (vx, vy) = m.velocity;
                    (vx + VELOCITY_RATE * (a.cx - b.cx - vx), vy + VELOCITY_RATE * (a.cy - b.cy - vy))
                }
                _ => (0.0, 0.0),
            };
            // At most M members, and `out` holds M.
            let _ = out.push(Tracked { id: me, estimate });
        }
        Ok(out)
    }

    fn member(&self, id: TargetId) -> Result<&Member<N, K, R, T>, Error> {
        self.members.iter().find(|m| m.id == Some(id)).ok_or(Error::UnknownTarget { id: id.0 })
    }

    /// The places that hold a target.
    fn active(&self) -> impl Iterator<Item = &Member<N, K, R, T>> {
        self.members.iter().filter(|m| m.id.is_some())
    }

    /// The frame size of the targets held, if any.
    fn frame_size(&self) -> Option<(usize, usize)> {
        self.active().find_map(|m| m.track.frame_size())
    }
}

#[cfg(test)]
mod tests;
