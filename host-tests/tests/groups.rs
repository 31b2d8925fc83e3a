//! The scenes of several targets (`fixtures/groups/`, generated with exact
//! truth): a group of all a scene's targets, added from their first boxes,
//! keeps each on its own target.

use host_tests::fixture::Fixture;
use host_tests::metrics::identity_swaps;
use host_tests::runner::HostGroup;
use pftrack::{BoundingBox, Config, Estimate, TrackState};
use std::path::Path;

fn load(name: &str) -> Fixture {
    Fixture::load(Path::new(&format!("{}/../fixtures/groups/{name}.pft", env!("CARGO_MANIFEST_DIR")))).unwrap()
}

/// Every target's estimate on every frame (the first being the
/// initialisation's), and every target's truth, target by target.
fn run(fx: &Fixture, seed: u64) -> (Vec<Vec<Estimate>>, Vec<Vec<BoundingBox>>) {
    // A `HostGroup` is built by value before it is boxed, and with eight
    // trackers' working memory it comes close to a test thread's 2 MiB
    // stack: run it on a thread with room to spare.
    std::thread::scope(|s| {
        std::thread::Builder::new().stack_size(16 << 20).spawn_scoped(s, || run_here(fx, seed)).unwrap().join().unwrap()
    })
}

fn run_here(fx: &Fixture, seed: u64) -> (Vec<Vec<Estimate>>, Vec<Vec<BoundingBox>>) {
    let mut g = Box::new(HostGroup::new(Config::default(), seed).unwrap());
    let first = fx.frame(0).unwrap();
    let n = fx.frames[0].targets().count();
    let mut ests = vec![Vec::new(); n];
    for (k, m) in fx.frames[0].targets().enumerate() {
        let added = g.add(&first, m.truth).unwrap();
        assert_eq!(added.id.0 as usize, k);
        ests[k].push(added.estimate);
    }
    for i in 1..fx.frames.len() {
        for t in g.step(&fx.frame(i).unwrap()).unwrap() {
            ests[t.id.0 as usize].push(t.estimate);
        }
    }
    let truths = (0..n)
        .map(|k| {
            fx.frames
                .iter()
                .map(|f| {
                    let m = f.targets().nth(k).unwrap();
                    if m.visible_permille == 0 { BoundingBox::default() } else { m.truth }
                })
                .collect()
        })
        .collect();
    (ests, truths)
}

/// Whether an estimate is on a target: its centre inside the target's box.
fn on(e: &Estimate, truth: &BoundingBox) -> bool {
    let (x, y) = e.bbox().centre();
    x >= truth.x && x <= truth.x + truth.width && y >= truth.y && y <= truth.y + truth.height
}

/// The boxes the tracks claim: a target reported lost claims none.
fn boxes(ests: &[Vec<Estimate>]) -> Vec<Vec<Option<BoundingBox>>> {
    ests.iter().map(|e| e.iter().map(|e| (e.state == TrackState::Tracking).then(|| e.bbox())).collect()).collect()
}

#[test]
fn two_same_coloured_targets_cross_without_an_identity_swap() {
    // Reason: the scene's truth. Same colours, same stripes, different
    // speeds, the faster in front: over 16 seeds no frame has a target's
    // box on the other's truth and not on its own, and after the crossing
    // (the last 12 frames, 40 px or more apart) each is on its own.
    let fx = load("crossing");
    for seed in 1..=16 {
        let (ests, truths) = run(&fx, seed);
        assert_eq!(identity_swaps(&boxes(&ests), &truths), 0, "seed {seed}");
        for (k, e) in ests.iter().enumerate() {
            for f in fx.frames.len() - 12..fx.frames.len() {
                assert!(on(&e[f], &truths[k][f]), "seed {seed} target {k} frame {f}");
            }
        }
    }
}

#[test]
fn a_target_that_leaves_comes_back_with_its_identity_while_the_others_track() {
    // Reason: the scene's truth. The third target is out of the frame on
    // frames 16-27 and wholly back from frame 34: it is tracked on its own
    // box again within 10 frames of that, and never claimed on another's;
    // the first two are tracked, their estimates' centres in their own
    // boxes, on every frame.
    let fx = load("three_targets");
    for seed in 1..=16 {
        let (ests, truths) = run(&fx, seed);
        assert_eq!(identity_swaps(&boxes(&ests), &truths), 0, "seed {seed}");
        for k in 0..2 {
            for (f, e) in ests[k].iter().enumerate() {
                assert!(
                    on(e, &truths[k][f]) && e.state == TrackState::Tracking,
                    "seed {seed} target {k} frame {f}: {e:?}"
                );
            }
        }
        let back =
            (34..fx.frames.len()).find(|&f| ests[2][f].state == TrackState::Tracking && on(&ests[2][f], &truths[2][f]));
        assert!(back.is_some_and(|f| f <= 34 + 10), "seed {seed}: back at {back:?}");
    }
}

#[test]
fn two_targets_that_start_touching_each_keep_their_own() {
    // Reason: the scene's truth. Side by side with touching outlines,
    // moving apart: each estimate's centre in its own box on every frame,
    // 16 seeds.
    let fx = load("touching");
    for seed in 1..=16 {
        let (ests, truths) = run(&fx, seed);
        for (k, e) in ests.iter().enumerate() {
            for (f, e) in e.iter().enumerate() {
                assert!(on(e, &truths[k][f]), "seed {seed} target {k} frame {f}: {e:?}");
            }
        }
    }
}
