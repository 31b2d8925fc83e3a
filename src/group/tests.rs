use super::*;
use crate::apart::NEAR;
use crate::frame::PixelFormat;
use crate::testing::noise_bytes;
use crate::tracker::Tracker;

const W: usize = 160;
const H: usize = 96;

/// Body and stripe colours of the squares, by kind.
const KINDS: [[[u8; 3]; 2]; 3] =
    [[[215, 45, 35], [235, 200, 40]], [[30, 60, 220], [240, 240, 240]], [[40, 200, 60], [220, 40, 200]]];

/// A textured RGB888 scene with same-coloured striped squares of side `s`
/// centred at `centres`, the first drawn last (in front).
fn scene(centres: &[(f32, f32)], s: usize, t: usize) -> Vec<u8> {
    let kinds: Vec<_> = centres.iter().map(|&c| (c, 0)).collect();
    scene_of(&kinds, s, t)
}

/// [`scene`] with squares of the given kinds.
fn scene_of(squares: &[((f32, f32), usize)], s: usize, t: usize) -> Vec<u8> {
    let noise = noise_bytes(t as u32 + 1, W * H);
    let mut px = vec![0u8; W * H * 3];
    for (i, p) in px.chunks_exact_mut(3).enumerate() {
        let (x, y) = (i % W, i / W);
        let base = if (x / 8 + y / 8) % 2 == 0 { 70 } else { 110 };
        let n = noise[i] % 9;
        p.copy_from_slice(&[base + n, base + 20 + n, base + 10 + n]);
    }
    for &((cx, cy), kind) in squares.iter().rev() {
        let (x0, y0) = ((cx - s as f32 / 2.0) as isize, (cy - s as f32 / 2.0) as isize);
        for y in y0..y0 + s as isize {
            for x in x0..x0 + s as isize {
                if (0..W as isize).contains(&x) && (0..H as isize).contains(&y) {
                    let stripe = ((y - y0) / 4) % 2 == 1;
                    let c = KINDS[kind][usize::from(stripe)];
                    px[(y as usize * W + x as usize) * 3..][..3].copy_from_slice(&c);
                }
            }
        }
    }
    px
}

fn frame(px: &[u8]) -> Frame<'_> {
    Frame::packed(px, W, H, PixelFormat::Rgb888).unwrap()
}

fn square(c: (f32, f32), s: usize) -> BoundingBox {
    BoundingBox::new(c.0 - s as f32 / 2.0, c.1 - s as f32 / 2.0, s as f32, s as f32)
}

#[test]
fn a_group_of_one_is_a_tracker_with_the_same_seed() {
    // Reason: cross-check of two paths. With no other target there is
    // nothing to keep apart from, and target 0 draws from the group's seed,
    // so the group repeats the lone tracker's computation bit for bit, with
    // all hypotheses or a share of them (no other target comes near), and
    // with the gradient filter, whose working memory is lent from the
    // group's shared scratch rather than the tracker's own.
    let path = |t: usize| (30.0 + 2.5 * t as f32, 48.0 + 6.0 * (t as f32 * 0.3).sin());
    let first = scene(&[path(0)], 16, 0);
    let shared = Config { sure_share: 0.6, ..Config::fast() };
    let mut cases = vec![(1, Config::fast()), (7, Config::fast()), (1, shared), (7, shared)];
    if cfg!(feature = "gradient") {
        let without = Config { gradient: None, ..Config::accurate() };
        cases.extend([(1, Config::accurate()), (7, Config::accurate()), (1, without)]);
    }
    let mut tracks = Vec::new();
    for (seed, cfg) in cases {
        let mut lone: Tracker<60> = Tracker::new(cfg, seed).unwrap();
        let mut group: Group<2, 60> = Group::new(cfg, seed).unwrap();
        lone.init(&frame(&first), square(path(0), 16)).unwrap();
        let id = group.add(&frame(&first), square(path(0), 16)).unwrap().id;
        let mut track = String::new();
        for t in 1..30 {
            let px = scene(&[path(t)], 16, t);
            let a = lone.step(&frame(&px)).unwrap();
            let b = group.step(&frame(&px)).unwrap();
            assert_eq!(b.len(), 1);
            assert_eq!(b[0].id, id);
            assert_eq!(format!("{a:?}"), format!("{:?}", b[0].estimate), "seed {seed}, frame {t}");
            track += &format!("{a:?}");
        }
        tracks.push(track);
    }
    // The gradient filter took part: without it the track is another.
    if cfg!(feature = "gradient") {
        assert_ne!(tracks.get(4), tracks.get(6));
    }
}

#[test]
fn bad_calls_are_errors_and_leave_the_group_as_it_was() {
    // Reason: the contract. A full group, an unknown or removed identity
    // and a frame of another size (to add, step or re-initialise with) are
    // typed errors; identities are not reused after a removal.
    let px = scene(&[(40.0, 40.0), (110.0, 50.0)], 16, 0);
    let f = frame(&px);
    let mut g: Group<2, 30> = Group::new(Config::default(), 1).unwrap();
    let a = g.add(&f, square((40.0, 40.0), 16)).unwrap();
    assert_eq!(a.overlap, None);
    let b = g.add(&f, square((110.0, 50.0), 16)).unwrap();
    assert_ne!(a.id, b.id);
    assert_eq!(g.add(&f, square((80.0, 30.0), 16)).err(), Some(Error::GroupFull { capacity: 2 }));
    assert_eq!(g.len(), 2);
    g.remove(a.id).unwrap();
    assert_eq!(g.remove(a.id), Err(Error::UnknownTarget { id: a.id.0 }));
    assert_eq!(g.state(a.id), Err(Error::UnknownTarget { id: a.id.0 }));
    assert_eq!(g.reinit(a.id, &f, square((40.0, 40.0), 16)).err(), Some(Error::UnknownTarget { id: a.id.0 }));
    // A box half over target b: accepted, with their overlap (8x16 of two
    // 16x16 boxes: IoU 128 / 384).
    let c = g.add(&f, square((118.0, 50.0), 16)).unwrap();
    assert!(c.id != a.id && c.id != b.id);
    let (with, iou) = c.overlap.unwrap();
    assert_eq!(with, b.id);
    assert!((iou - 1.0 / 3.0).abs() < 1e-3, "{iou}");
    let small = vec![0u8; 32 * 24 * 3];
    let other = Frame::packed(&small, 32, 24, PixelFormat::Rgb888).unwrap();
    assert_eq!(g.step(&other).err(), Some(Error::FrameSizeChanged { expected: (W, H), got: (32, 24) }));
    assert_eq!(g.ids().collect::<Vec<_>>(), [c.id, b.id]);
    assert!(matches!(
        g.reinit(c.id, &other, BoundingBox::new(0.0, 0.0, 8.0, 8.0)),
        Err(Error::FrameSizeChanged { .. })
    ));
    g.remove(c.id).unwrap();
    assert!(matches!(g.add(&other, BoundingBox::new(0.0, 0.0, 8.0, 8.0)), Err(Error::FrameSizeChanged { .. })));
    assert_eq!(g.ids().collect::<Vec<_>>(), [b.id]);
}

/// The crossing scene: two same-coloured squares on one line, at
/// different speeds, the faster in front; they overlap around frame 25 and
/// are 68 px apart at frame 40.
fn crossing(t: usize) -> [(f32, f32); 2] {
    let t = t as f32;
    [(24.0 + 2.5 * t, 48.0), (136.0 - 2.0 * t, 48.0)]
}

/// Frames (of the last ten) in which a target's estimate is nearer the
/// other's truth than its own, with `apart` as the group's discount.
fn swaps(seed: u64) -> usize {
    swaps_with(seed, Config::default())
}

fn swaps_with(seed: u64, cfg: Config) -> usize {
    let first = scene(&crossing(0), 16, 0);
    let mut g: Group<2, 60> = Group::new(cfg, seed).unwrap();
    let [a, b] = crossing(0);
    let ids = [g.add(&frame(&first), square(a, 16)).unwrap().id, g.add(&frame(&first), square(b, 16)).unwrap().id];
    let mut swapped = 0;
    for t in 1..=40 {
        let truth = crossing(t);
        let px = scene(&truth, 16, t);
        let out = g.step(&frame(&px)).unwrap();
        if t <= 30 {
            continue;
        }
        for (i, id) in ids.iter().enumerate() {
            let est = out.iter().find(|o| o.id == *id).unwrap().estimate.bbox().centre();
            let d = |p: (f32, f32)| (est.0 - p.0).abs() + (est.1 - p.1).abs();
            if d(truth[1 - i]) < d(truth[i]) {
                swapped += 1;
            }
        }
    }
    swapped
}

#[test]
fn two_same_coloured_targets_cross_without_swapping() {
    // Reason: generated scene with exact truth. After the crossing each
    // target's estimate must be nearer its own square than the other's,
    // for every one of 16 seeds. (Two lone trackers, or a group that does
    // not keep its targets apart, fail on 9 of the 16: both settle on one
    // square, or they swap. A group whose gradient filter may move a box
    // near the other target, `Freedom::Held` aside, fails on 14 of them.)
    let bad: Vec<_> = (1..=16).map(|s| (s, swaps(s))).filter(|&(_, n)| n > 0).collect();
    assert!(bad.is_empty(), "seeds with a swap or a merge (seed, frames): {bad:?}");
}

#[test]
fn targets_near_each_other_observe_all_their_hypotheses() {
    // Reason: the group's rule for `Config::sure_share`: a confidently
    // tracked target observes the share of its hypotheses only while no
    // other target's region comes within `NEAR` of its half axes; near one,
    // it observes all of them, so the crossing (the targets 112 px apart
    // at first, overlapping in the middle) must see both, and, as with all
    // hypotheses, no swap on any of 16 seeds. (Measured: at a share of 0.5
    // one seed of the 16 swaps; without the correlation filter, at 0.6 one
    // seed swaps and at 0.7 none, as docs/several-targets.md says.)
    const N: usize = 60;
    let share = if cfg!(feature = "correlation") { 0.6 } else { 0.7 };
    let cfg = Config { sure_share: share, ..Config::fast() };
    let (mut shared, mut all_near) = (0, 0);
    for seed in 1..=16 {
        assert_eq!(swaps_with(seed, cfg), 0, "seed {seed}: a swap or a merge");
        let first = scene(&crossing(0), 16, 0);
        let mut g: Group<2, N> = Group::new(cfg, seed).unwrap();
        for c in crossing(0) {
            g.add(&frame(&first), square(c, 16)).unwrap();
        }
        for t in 1..=40 {
            let px = scene(&crossing(t), 16, t);
            // The regions as the step sees them: as the last frame left them.
            let held: Vec<_> = g.members.iter().map(|m| m.held().map(|e| core(&e))).collect();
            let mine: Vec<_> = g.members.iter().map(|m| m.track.held()).collect();
            g.step(&frame(&px)).unwrap();
            for (i, m) in g.members.iter().enumerate() {
                let Some(mine) = mine[i] else { continue };
                let window = Ellipse { hx: NEAR * mine.hx, hy: NEAR * mine.hy, ..mine }.to_box();
                let near =
                    held.iter().enumerate().any(|(j, h)| j != i && h.is_some_and(|h| h.covered_by(&window) > 0.0));
                let observed = m.track.weights().iter().filter(|&&w| w > 0.0).count();
                if near {
                    assert_eq!(observed, N, "seed {seed} frame {t}: a target near another observes all");
                    all_near += 1;
                } else if observed == (share * N as Real) as usize {
                    shared += 1;
                }
            }
        }
    }
    assert!(shared > 0 && all_near > 0, "{shared} steps with the share, {all_near} near another");
}

/// Three squares of different kinds, apart: two on gentle paths, and a third that
/// leaves through the right edge at frame 12, is out of the frame for
/// frames 17 to 26, and comes back from frame 27 on.
fn three(t: usize) -> [((f32, f32), usize); 3] {
    let tf = t as f32;
    let c = if t < 17 {
        (110.0 + 4.5 * tf, 76.0)
    } else if t < 27 {
        (300.0, 76.0)
    } else {
        (156.0 - 3.0 * (tf - 27.0), 76.0)
    };
    [((30.0 + 1.5 * tf, 26.0 + 4.0 * (tf * 0.2).sin()), 0), ((90.0 - tf, 48.0), 1), (c, 2)]
}

#[test]
fn a_target_that_leaves_and_returns_is_reacquired_with_its_identity() {
    // Reason: generated scene with exact truth. The third square is wholly
    // out of the frame on frames 17-26 and wholly in from frame 30 (its
    // centre 8 px inside the edge): it must be tracked on its own square
    // again within 10 frames of coming back, while the other two are
    // tracked on theirs on every frame.
    for seed in 1..=4 {
        let squares = three(0);
        let first = scene_of(&squares, 16, 0);
        let mut g: Group<3, 60> = Group::new(Config::default(), seed).unwrap();
        let ids: Vec<_> = squares.iter().map(|&(c, _)| g.add(&frame(&first), square(c, 16)).unwrap().id).collect();
        let mut back = None;
        for t in 1..=45 {
            let truth = three(t);
            let px = scene_of(&truth, 16, t);
            let out = g.step(&frame(&px)).unwrap();
            for (i, id) in ids.iter().enumerate() {
                let est = out.iter().find(|o| o.id == *id).unwrap().estimate;
                let (x, y) = est.bbox().centre();
                let on = (x - truth[i].0.0).abs() < 6.0 && (y - truth[i].0.1).abs() < 6.0;
                if i < 2 {
                    assert!(on && est.state == TrackState::Tracking, "seed {seed} frame {t} target {i}: {est:?}");
                } else if t >= 27 && back.is_none() && on && est.state == TrackState::Tracking {
                    back = Some(t);
                }
            }
        }
        let back = back.unwrap_or(usize::MAX);
        assert!(back <= 30 + 10, "seed {seed}: back on its square at frame {back}");
    }
}

#[test]
fn two_targets_that_start_touching_stay_on_their_own() {
    // Reason: generated scene with exact truth. Two squares of different
    // kinds side by side, touching, move apart: each estimate stays on its
    // own square.
    for seed in 1..=4 {
        let at = |t: usize| [((72.0 - 1.5 * t as f32, 48.0), 0), ((88.0 + 1.5 * t as f32, 48.0), 1)];
        let first = scene_of(&at(0), 16, 0);
        let mut g: Group<2, 60> = Group::new(Config::default(), seed).unwrap();
        let a = g.add(&frame(&first), square(at(0)[0].0, 16)).unwrap();
        let b = g.add(&frame(&first), square(at(0)[1].0, 16)).unwrap();
        // Touching, not overlapping.
        assert_eq!(b.overlap, None);
        for t in 1..=20 {
            let truth = at(t);
            let out = g.step(&frame(&scene_of(&truth, 16, t))).unwrap();
            for (i, id) in [a.id, b.id].iter().enumerate() {
                let (x, y) = out.iter().find(|o| o.id == *id).unwrap().estimate.bbox().centre();
                assert!((x - truth[i].0.0).abs() < 6.0 && (y - truth[i].0.1).abs() < 6.0, "seed {seed} frame {t}");
            }
        }
    }
}
