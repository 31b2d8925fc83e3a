//! The tracker on the committed fixtures, judged against their exact ground
//! truth. Each threshold says why it is the right one.

use host_tests::fixture::Fixture;
use host_tests::metrics::centre_error;
use host_tests::scene::{Story, catalogue, generate};
use pftrack::{BoundingBox, Config, Estimate, Event, Frame, GradientCue, Redetect, TrackState, Tracker};
use std::path::PathBuf;

/// Seeds every tracking claim is checked under: a claim that holds for one
/// lucky seed only is not a property of the tracker.
const SEEDS: [u64; 3] = [1, 2, 3];

fn load(name: &str) -> Fixture {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../fixtures").join(format!("{name}.pft"));
    Fixture::load(&path).unwrap()
}

fn frames(fx: &Fixture) -> Vec<Frame<'_>> {
    (0..fx.frames.len()).map(|i| fx.frame(i).unwrap()).collect()
}

/// Runs the default tracker; returns the estimates of frames 1.. and the
/// model's bins after each of them.
fn run(fx: &Fixture, seed: u64) -> (Vec<Estimate>, Vec<Vec<u16>>) {
    run_with(fx, Config::default(), seed)
}

/// The named configurations every tracking bar holds for: the default
/// (`Config::accurate`, both correlation filters) and `Config::fast`, the
/// configuration for boards that need the frame rate.
fn each_named(check: impl Fn(&str, Config)) {
    for (label, cfg) in [("default", Config::default()), ("fast", Config::fast())] {
        check(label, cfg);
    }
}

/// [`run`] with a configuration of its own.
fn run_with(fx: &Fixture, cfg: Config, seed: u64) -> (Vec<Estimate>, Vec<Vec<u16>>) {
    let fr = frames(fx);
    let mut t: Box<Tracker<100>> = Box::new(Tracker::new(cfg, seed).unwrap());
    t.init(&fr[0], fx.frames[0].truth).unwrap();
    let mut est = Vec::new();
    let mut models = Vec::new();
    for f in &fr[1..] {
        est.push(t.step(f).unwrap());
        models.push(t.model().unwrap().bins().to_vec());
    }
    (est, models)
}

/// Whether the estimate's centre lies inside the target's true ellipse: the
/// tracker is on the target, not beside it.
fn on_target(e: &Estimate, truth: &BoundingBox) -> bool {
    let (tx, ty) = truth.centre();
    let (ex, ey) = e.bbox().centre();
    let (a, b) = (0.5 * truth.width, 0.5 * truth.height);
    ((ex - tx) / a).powi(2) + ((ey - ty) / b).powi(2) <= 1.0
}

#[test]
fn committed_fixtures_are_what_the_generator_makes() {
    // Reason: the ground truth is exact only if the pixels came from the
    // generator that computed it; regenerating must give the same bytes.
    for spec in catalogue() {
        let fx = load(spec.name);
        assert!(fx == generate(&spec), "{} differs from the generator's output", spec.name);
    }
}

#[test]
fn follows_smooth_scaling_gray_and_occluded_targets() {
    // Reason: with the target fully visible and unlike the background, the
    // estimate's centre must lie inside the true ellipse on at least 90% of
    // frames, and the mean IoU must reach 0.5, the usual "success" overlap.
    // The distractor scene is left out on purpose: its decoy has the same
    // colours, which colour alone cannot always tell apart.
    each_named(|label, cfg| {
        for name in ["smooth_scale", "gray_smooth", "occlusion", "occlusion_i420"] {
            let fx = load(name);
            for seed in SEEDS {
                let (est, _) = run_with(&fx, cfg, seed);
                let visible: Vec<usize> =
                    (1..fx.frames.len()).filter(|&i| fx.frames[i].visible_permille >= 500).collect();
                let inside = visible.iter().filter(|&&i| on_target(&est[i - 1], &fx.frames[i].truth)).count();
                let frac = inside as f64 / visible.len() as f64;
                assert!(frac >= 0.9, "{label} {name} seed {seed}: centre on target in {frac:.2} of visible frames");
                let iou: f64 = visible.iter().map(|&i| est[i - 1].bbox().iou(&fx.frames[i].truth) as f64).sum::<f64>()
                    / visible.len() as f64;
                assert!(iou >= 0.5, "{label} {name} seed {seed}: mean IoU {iou:.2}");
            }
        }
    });
}

#[test]
fn reports_lost_when_the_target_leaves_and_tracking_when_it_returns() {
    each_named(|label, cfg| {
        let fx = load("exit_return");
        let gone = (0..fx.frames.len()).find(|&i| fx.frames[i].visible_permille == 0).unwrap();
        let back = (gone..fx.frames.len()).find(|&i| fx.frames[i].visible_permille >= 500).unwrap();
        let lost_after = cfg.lost_after as usize;
        for seed in SEEDS {
            let (est, _) = run_with(&fx, cfg, seed);
            // Estimates are for frames 1..; frame i is est[i - 1].
            let lost_at = (1..fx.frames.len()).find(|&i| est[i - 1].event == Some(Event::LostTarget)).unwrap();
            // Reason: the target is gone at `gone`; the filter needs `lost_after`
            // consecutive misses, plus one frame of slack for the particles that
            // still overlap the last visible sliver.
            assert!(
                lost_at >= gone - 1 && lost_at <= gone + lost_after,
                "{label} seed {seed}: lost at {lost_at}, gone at {gone}"
            );
            // It stays lost while the target is away: nothing in the background
            // looks like it. (Re-acquiring on a partial return is fine.)
            for i in (lost_at..back).filter(|&i| fx.frames[i].visible_permille == 0) {
                assert_ne!(est[i - 1].state, TrackState::Tracking, "{label} seed {seed}: claims tracking at frame {i}");
            }
            let found = (back - 2..fx.frames.len()).find(|&i| est[i - 1].event == Some(Event::Reacquired)).unwrap();
            // Reason: once half the target is back in view, the particles waiting
            // at the border see it within a few frames.
            assert!(found <= back + 3, "{label} seed {seed}: reacquired at {found}, back at {back}");
            // And it is really on it a few frames later.
            let i = (found + 4).min(fx.frames.len() - 1);
            assert!(on_target(&est[i - 1], &fx.frames[i].truth), "{label} seed {seed}: off target at frame {i}");
        }
    });
}

/// Mean IoU over the frames after the first, of the estimates and of a box
/// that keeps the first frame's size on the true centre (what tracking the
/// position perfectly but not the size would score).
fn mean_ious(fx: &Fixture, est: &[Estimate]) -> (f64, f64) {
    let first = fx.frames[0].truth;
    let n = (fx.frames.len() - 1) as f64;
    let (mut got, mut fixed) = (0.0, 0.0);
    for (i, e) in est.iter().enumerate() {
        let t = fx.frames[i + 1].truth;
        let (cx, cy) = t.centre();
        let kept = BoundingBox::new(cx - 0.5 * first.width, cy - 0.5 * first.height, first.width, first.height);
        got += e.bbox().iou(&t) as f64;
        fixed += kept.iou(&t) as f64;
    }
    (got / n, fixed / n)
}

#[test]
fn estimates_the_size_of_a_shrinking_target() {
    // Reason: exact truth from the generator: the target shrinks to half
    // its width and height. A box that followed the centre perfectly but
    // kept the first size would score a mean IoU below 0.6 (checked here,
    // so the bar cannot be met by position alone); the estimate must reach 0.6.
    each_named(|label, cfg| {
        let fx = load("shrink");
        for seed in SEEDS {
            let (est, _) = run_with(&fx, cfg, seed);
            let (got, fixed) = mean_ious(&fx, &est);
            assert!(fixed < 0.6, "a fixed size already scores {fixed:.2}");
            assert!(got >= 0.6, "{label} seed {seed}: mean IoU {got:.2} (a fixed size: {fixed:.2})");
        }
    });
}

#[test]
fn estimates_the_shape_of_a_turning_target() {
    // Reason: exact truth from the generator: the target turns from tall to
    // wide, its aspect (width / height) from 0.7 to 1.4 at a constant area.
    // Every run's mean IoU must reach 0.6, and over the last quarter of the
    // sequence (true aspect 1.2 to 1.4) the estimate must be wider than
    // tall on average over ten seeds: a box that kept its first shape stays
    // near 0.7 (measured: 0.73 over the same seeds with the aspect search
    // off, `size=0.02:1:scale:0.05`). The mean over seeds, because single
    // runs of `Config::fast` end anywhere between 0.99 and 1.21.
    each_named(|label, cfg| {
        let fx = load("turn");
        let n = fx.frames.len();
        let seeds = 1..=10u64;
        let mut aspects = Vec::new();
        for seed in seeds.clone() {
            let (est, _) = run_with(&fx, cfg, seed);
            let (got, _) = mean_ious(&fx, &est);
            assert!(got >= 0.6, "{label} seed {seed}: mean IoU {got:.2}");
            let late = &est[n * 3 / 4 - 1..];
            aspects
                .push(late.iter().map(|e| (e.bbox().width / e.bbox().height) as f64).sum::<f64>() / late.len() as f64);
        }
        let mean = aspects.iter().sum::<f64>() / aspects.len() as f64;
        assert!(mean > 1.0, "mean aspect {mean:.2} over the last quarter (seeds {seeds:?}: {aspects:.2?})");
    });
}

#[test]
fn finds_a_target_that_comes_back_on_the_other_side() {
    // Reason: the target leaves through the right edge and re-enters from
    // the left, far from where it was lost; the filter must declare it lost
    // while it is away and find it again within 10 frames of half of it
    // being back in view.
    each_named(|label, cfg| {
        let fx = load("cross_over");
        let gone = (0..fx.frames.len()).find(|&i| fx.frames[i].visible_permille == 0).unwrap();
        let back = (gone..fx.frames.len()).find(|&i| fx.frames[i].visible_permille >= 500).unwrap();
        for seed in SEEDS {
            let (est, _) = run_with(&fx, cfg, seed);
            assert!(
                (1..back).any(|i| est[i - 1].event == Some(Event::LostTarget)),
                "{label} seed {seed}: never declared lost while the target was away"
            );
            for i in (gone + cfg.lost_after as usize + 1..back).filter(|&i| fx.frames[i].visible_permille == 0) {
                assert_ne!(est[i - 1].state, TrackState::Tracking, "{label} seed {seed}: claims tracking at frame {i}");
            }
            let found = (back - 2..fx.frames.len())
                .find(|&i| est[i - 1].event == Some(Event::Reacquired))
                .unwrap_or_else(|| panic!("{label} seed {seed}: never found again"));
            assert!(found <= back + 10, "{label} seed {seed}: found at {found}, back at {back}");
            let i = (found + 3).min(fx.frames.len() - 1);
            assert!(on_target(&est[i - 1], &fx.frames[i].truth), "{label} seed {seed}: off target at frame {i}");
        }
    });
}

#[test]
fn model_is_not_updated_while_the_target_is_hidden() {
    // Reason: π_E[S] of a hidden target is far below π_T, so the first
    // paper's gate must keep the model exactly as it was.
    each_named(|label, cfg| {
        let fx = load("occlusion");
        for seed in SEEDS {
            let (est, models) = run_with(&fx, cfg, seed);
            let hidden: Vec<usize> = (1..fx.frames.len()).filter(|&i| fx.frames[i].visible_permille == 0).collect();
            assert!(hidden.len() >= 3, "the scene hides the target for several frames");
            for &i in &hidden {
                assert!(!est[i - 1].model_updated, "{label} seed {seed}: model updated at hidden frame {i}");
                assert_eq!(models[i - 1], models[i - 2], "{label} seed {seed}: model changed at hidden frame {i}");
            }
            // ...while it does adapt on clear frames (the gate is not simply shut).
            assert!(est.iter().take(5).any(|e| e.model_updated), "{label} seed {seed}: never updated on clear frames");
            // After the occluder has passed, the tracker is back on the target.
            let last = fx.frames.len() - 1;
            assert!(on_target(&est[last - 1], &fx.frames[last].truth), "{label} seed {seed}: lost after occlusion");
        }
    });
}

#[test]
fn confidence_is_not_high_while_off_target() {
    // Reason: the confidence is the tracker's probability that its estimate
    // is on the target; a confident (> 0.8) estimate whose centre is off the
    // target would mean the background looks like the target, which these
    // scenes are built to rule out. The lighting-ramp scene is included:
    // there the tracker may lose the target, but it must not be confident
    // while doing so. The crossing scene is left out: its second target
    // is the first's twin in colour and stripes, so there the background
    // does look like the target, and after they cross a lone tracker has
    // only their motion to tell them apart (a group keeps them apart:
    // groups.rs).
    each_named(|label, cfg| {
        for spec in catalogue().into_iter().filter(|s| s.story != Story::Crossing) {
            let fx = load(spec.name);
            let (est, _) = run_with(&fx, cfg, 1);
            for (i, e) in est.iter().enumerate() {
                let f = &fx.frames[i + 1];
                if e.confidence > 0.8 && f.visible_permille > 0 {
                    assert!(
                        centre_error(&e.bbox(), &f.truth) < f.truth.width.max(f.truth.height) as f64,
                        "{label} {}: frame {}: confidence {} off target",
                        spec.name,
                        i + 1,
                        e.confidence
                    );
                }
                assert!((0.0..=1.0).contains(&e.confidence));
            }
        }
    });
}

#[test]
fn searching_acquires_a_target_that_appears() {
    // The model comes from the first frame; the search starts while the target
    // is away, and must not fire until it returns (automatic initialisation).
    each_named(|label, cfg| {
        let fx = load("exit_return");
        let fr = frames(&fx);
        let gone = (0..fx.frames.len()).find(|&i| fx.frames[i].visible_permille == 0).unwrap();
        let back = (gone..fx.frames.len()).find(|&i| fx.frames[i].visible_permille >= 500).unwrap();
        for seed in SEEDS {
            let mut t: Box<Tracker<100>> = Box::new(Tracker::new(cfg, seed).unwrap());
            t.search(&fr[0], fx.frames[0].truth).unwrap();
            assert_eq!(t.state(), TrackState::Searching);
            let mut acquired = None;
            for (i, f) in fr.iter().enumerate().skip(gone) {
                let e = t.step(f).unwrap();
                if e.event == Some(Event::Acquired) {
                    acquired = Some(i);
                    break;
                }
                assert_eq!(e.state, TrackState::Searching, "{label} seed {seed}: frame {i}");
            }
            let at = acquired.unwrap_or_else(|| panic!("{label} seed {seed}: never acquired"));
            // Reason: acquisition needs the target in view (it cannot happen before
            // it returns) and a few frames for the re-drawn particles to find it.
            assert!(at + 2 >= back && at <= back + 4, "{label} seed {seed}: acquired at {at}, back at {back}");
        }
    });
}

#[test]
fn same_seed_same_track_other_seed_other_track() {
    // Reason: determinism is a promise (the firmware reproduces the host's
    // track from the seed); a different seed must change something, or the
    // generator is not actually used.
    let fx = load("smooth_scale");
    let (a, _) = run(&fx, 7);
    let (b, _) = run(&fx, 7);
    let (c, _) = run(&fx, 8);
    assert_eq!(a, b);
    assert_ne!(a, c);
}

#[test]
fn reinitialisation_moves_the_tracker_to_a_new_box() {
    // Reason: init on a new box discards the old hypothesis entirely, so the
    // next estimate is on the new box even if it is far from the old one.
    let fx = load("distractor");
    let fr = frames(&fx);
    let mut t: Box<Tracker<100>> = Box::new(Tracker::new(Config::default(), 1).unwrap());
    t.init(&fr[0], fx.frames[0].truth).unwrap();
    for f in &fr[1..5] {
        t.step(f).unwrap();
    }
    // The decoy at frame 5 (centre (100 - 1.5*5, 58), same size as the target).
    let decoy = BoundingBox::new(100.0 - 7.5 - 11.0, 58.0 - 13.0, 22.0, 26.0);
    let e = t.init(&fr[5], decoy).unwrap();
    assert_eq!(e.event, Some(Event::Initialised));
    let e = t.step(&fr[6]).unwrap();
    let moved = BoundingBox::new(decoy.x - 1.5, decoy.y, decoy.width, decoy.height);
    assert!(centre_error(&e.bbox(), &moved) < 5.0, "{:?}", e.bbox());
}

#[test]
fn misuse_gives_typed_errors() {
    let fx = load("gray_smooth");
    let fr = frames(&fx);
    let mut t: Box<Tracker<50>> = Box::new(Tracker::new(Config::default(), 1).unwrap());
    assert_eq!(t.step(&fr[0]), Err(pftrack::Error::NotInitialised));
    assert_eq!(
        t.init(&fr[0], BoundingBox::new(500.0, 0.0, 10.0, 10.0)),
        Err(pftrack::Error::Region(pftrack::RegionError::OutsideFrame))
    );
    t.init(&fr[0], fx.frames[0].truth).unwrap();
    let small = vec![0u8; 64 * 48];
    let other = Frame::packed(&small, 64, 48, pftrack::PixelFormat::Gray8).unwrap();
    assert_eq!(t.step(&other), Err(pftrack::Error::FrameSizeChanged { expected: (128, 96), got: (64, 48) }));
}

#[test]
fn edge_cue_tells_the_target_from_a_same_coloured_decoy() {
    use pftrack::{Binning, EdgeMap, EdgeParams, Ellipse, Histogram, Model, Sampling};
    let fx = load("distractor");
    let fr = frames(&fx);
    let last = fx.frames.len() - 1;
    // The decoy: same size, centre (100 − 1.5 t, 50) (host-tests/src/scene.rs).
    let decoy = |t: usize| {
        let t = t as f32;
        BoundingBox::new(100.0 - 1.5 * t - 11.0, 50.0 - 13.0, 22.0, 26.0)
    };

    // Why colour alone cannot work here: in frame 0 the two are apart, and
    // their colour histograms are nearly identical while their edge
    // orientations (stripes turned 90°) differ clearly.
    let (t, d) = (Ellipse::from_box(&fx.frames[0].truth), Ellipse::from_box(&decoy(0)));
    let mut h = Histogram::<512>::new();
    h.compute(&fr[0], &t, Binning::Rgb8x8x8, Sampling::Full);
    let colour = Model::from_histogram(&h).unwrap();
    h.compute(&fr[0], &d, Binning::Rgb8x8x8, Sampling::Full);
    let rho_colour = colour.bhattacharyya(&h);
    let mut map = EdgeMap::<16384>::new();
    map.compute(
        &fr[0],
        (0, 0, 128, 96),
        EdgeParams { bins: 8, threshold: 100, sampling: Sampling::Full, step: 1, flat_bin: false },
    );
    let edge_hist = |e: &Ellipse| {
        let mut h = Histogram::<17>::new();
        let (x0, x1) = ((e.cx - e.hx) as usize, (e.cx + e.hx) as usize);
        let (y0, y1) = ((e.cy - e.hy) as usize, (e.cy + e.hy) as usize);
        for y in y0..=y1 {
            for x in x0..=x1 {
                if ((x as f32 + 0.5 - e.cx) / e.hx).powi(2) + ((y as f32 + 0.5 - e.cy) / e.hy).powi(2) < 1.0
                    && let Some(b) = map.bin_at(x, y)
                {
                    h.add(b, 1);
                }
            }
        }
        h
    };
    let rho_edge = Model::from_histogram(&edge_hist(&t)).unwrap().bhattacharyya(&edge_hist(&d));
    // (Measured: colour 0.87, edges 0.64; the edges still share the blobs'
    // outlines, which have every orientation.) For scale, the target against
    // the background is below 0.5 on colour.
    assert!(rho_colour > 0.85, "colour ρ(target, decoy) = {rho_colour}");
    assert!(rho_edge < rho_colour - 0.2, "edge ρ(target, decoy) = {rho_edge}, colour {rho_colour}");

    // So after they cross, colour alone follows the decoy on some seeds
    // (measured: 8 of 16),
    // while both named configurations stay on the target on every seed, on
    // every frame where the target is mostly visible (the crossing
    // included). "Colour alone" is without the correlation filters too:
    // they see the texture as the edges do (without the edges but with the
    // grey-level filter, the decoy was followed on none of the 16 seeds).
    let colour_only = Config { edges: None, correlation: None, ..Config::fast() };
    let mut decoy_followed = 0;
    for seed in 1..=16u64 {
        each_named(|label, cfg| {
            let (with_edges, _) = run_with(&fx, cfg, seed);
            for i in (1..=last).filter(|&i| fx.frames[i].visible_permille >= 500) {
                let on = on_target(&with_edges[i - 1], &fx.frames[i].truth);
                assert!(on, "{label} seed {seed}: off the target at frame {i}");
            }
        });
        let (colour_est, _) = run_with(&fx, colour_only, seed);
        let est = colour_est.last().unwrap();
        if on_target(est, &decoy(last)) {
            decoy_followed += 1;
        }
    }
    assert!(decoy_followed >= 4, "colour alone followed the decoy on {decoy_followed} of 16 seeds");
}

/// Share of frames after the first on which the estimate's centre lies
/// inside the true ellipse, for a tracker with `cfg`.
fn share_on_target(fx: &Fixture, cfg: Config, seed: u64) -> f64 {
    let (est, _) = run_with(fx, cfg, seed);
    let on = est.iter().zip(&fx.frames[1..]).filter(|(e, f)| on_target(e, &f.truth)).count();
    on as f64 / est.len() as f64
}

#[test]
fn follows_a_target_that_moves_most_of_its_width_a_frame() {
    // Reason: exact truth from the generator: the target zigzags at 18 px a
    // frame, 0.8 of its width, turning back at each side. The estimate's
    // centre must lie inside the true ellipse on at least 70% of the frames:
    // the first frames, before the tracker has seen the target move, and
    // the turns may be missed, not the runs between them. With the colour
    // cues alone, a position noise scaled to the target's size alone
    // (`speed_noise` 0) must fall short of the bar on every seed (measured
    // over seeds 1-10: 0.31 to 0.46 against 0.87 to 0.97 for `Config::fast`
    // and 1.0 for the default), so the bar tests the speed-scaled noise.
    // (The correlation filters, which search a window twice the target's
    // size and more, rescue some seeds without it: measured 0.51 on seed 1
    // with the grey-level filter.)
    let fx = load("fast");
    let colour = Config { correlation: None, ..Config::fast() };
    for seed in SEEDS {
        each_named(|label, cfg| {
            let got = share_on_target(&fx, cfg, seed);
            assert!(got >= 0.7, "{label} seed {seed}: on target on {got:.2} of frames");
        });
        let with = share_on_target(&fx, colour, seed);
        assert!(with >= 0.7, "seed {seed}: colour cues alone, on target on {with:.2} of frames");
        // Without re-detection near the target too, which finds a target
        // that the particles no longer reach (it rescues seed 2: 0.64).
        let mut slow = Config { redetect: Redetect::Off, ..colour };
        slow.dynamics.speed_noise = 0.0;
        let without = share_on_target(&fx, slow, seed);
        assert!(without < 0.5, "seed {seed}: without the speed noise, on target on {without:.2} of frames");
    }
}

/// For a tracker with `cfg`: the mean IoU over the frames after the first,
/// and how many of them it reported anything but tracking.
fn held(fx: &Fixture, cfg: Config, seed: u64) -> (f64, usize) {
    let (est, _) = run_with(fx, cfg, seed);
    (mean_ious(fx, &est).0, est.iter().filter(|e| e.state != TrackState::Tracking).count())
}

/// Asserts that a tracker with `cfg`, named `label`, reaches a mean IoU of
/// `bar` on `fx` with `seed` ([`held`]) and reports no frame not tracking.
fn assert_held(fx: &Fixture, (label, cfg): (&str, Config), seed: u64, bar: f64) {
    let (got, not_tracking) = held(fx, cfg, seed);
    assert!(got >= bar, "{label} seed {seed}: mean IoU {got:.2}");
    assert_eq!(not_tracking, 0, "{label} seed {seed}: reported not tracking");
}

#[test]
fn follows_a_target_while_the_view_pans() {
    // Reason: exact truth from the generator: the whole background moves
    // 8 px a frame to the left while the target moves 1.5 px a frame to
    // the right, 9.5 px a frame against its surroundings. The mean IoU must
    // reach 0.6 (measured over seeds 1-16: 0.87 to 0.93 for the default,
    // 0.86 to 0.92 for `Config::fast`), and the tracker
    // must never report the target lost: its surroundings move, but not
    // with the box, so the surroundings-motion test must not take the
    // target for background.
    each_named(|label, cfg| {
        let fx = load("pan");
        for seed in SEEDS {
            assert_held(&fx, (label, cfg), seed, 0.6);
        }
    });
}

#[test]
fn keeps_a_small_target_that_moves_most_of_its_size_a_frame() {
    // Reason: exact truth from the generator: a 12x12 target zigzags at 10
    // px a frame across the frame with a vertical swing of up to 9 px a
    // frame, up to 1.1 of its size a frame, and it moves 13 px in the
    // first frame, before the tracker has seen it move. Over 16 seeds the
    // mean IoU must reach 0.5 and no frame may be reported lost (measured:
    // 0.83 to 0.87 for the default, 0.65 to 0.71 for `Config::fast`, none
    // lost). Without re-detection near the target (`Redetect::Off`)
    // `Config::fast`'s particles lose it at the start and at the turns:
    // every seed falls short of one bar or the other (measured: 0.07 to
    // 0.46, 9 to 31 frames not tracking), so the bar tests the
    // re-detection. (The default's gradient filter, which searches a window
    // several times the target's, holds it without: the same figures.)
    let fx = load("small_fast");
    let off = Config { redetect: Redetect::Off, ..Config::fast() };
    for seed in 1..=16 {
        each_named(|label, cfg| assert_held(&fx, (label, cfg), seed, 0.5));
        let (without, not_tracking) = held(&fx, off, seed);
        assert!(
            without < 0.5 || not_tracking > 0,
            "seed {seed}: without re-detection, mean IoU {without:.2} and always tracking"
        );
    }
}

#[test]
fn follows_a_target_that_turns_half_a_turn() {
    // Reason: exact truth from the generator: an elongated striped target
    // (32x22 px) turns half a turn over 30 frames, its stripes with it;
    // the truth is the turned ellipse's box, from 32x22 through 22x32 and
    // back. The mean IoU must reach 0.6 (measured over seeds 1-16: 0.61 to
    // 0.71 for the default, 0.62 to 0.71 for `Config::fast`), and no frame
    // may be reported lost.
    each_named(|label, cfg| {
        let fx = load("rotate");
        for seed in SEEDS {
            assert_held(&fx, (label, cfg), seed, 0.6);
        }
    });
}

#[test]
fn a_turning_layout_is_learnt_at_once() {
    // Reason: the truth and the bar of the test above, which the default
    // (`Config::accurate`) meets. Its gradient filter holds the stripes'
    // layout; left to learn on its turn while they turn, it pulls the box
    // towards wherever the old layout fits (measured without learning at
    // once: 0.54 to 0.69 over seeds 1-16, eleven seeds under the bar or
    // with frames reported lost), so the bar tests the learning at once:
    // without it, some seed must fall short.
    let fx = load("rotate");
    let accurate = Config::accurate();
    let waiting = Config { gradient: accurate.gradient.map(|g| GradientCue { relearn_below: 0.0, ..g }), ..accurate };
    let short = (1..=16).filter(|&seed| {
        let (without, not_tracking) = held(&fx, waiting, seed);
        without < 0.6 || not_tracking > 0
    });
    assert!(short.count() > 0, "the filter learning on its turn follows the turn on every seed");
}

#[test]
fn stays_on_a_target_among_look_alikes() {
    // Reason: exact truth from the generator: three decoys in the target's
    // colours, in the same proportions, differ from it only in texture;
    // one passes behind it head on, one passes a pixel above its outline
    // and one rides alongside it as close below. Over 16 seeds the
    // estimate's centre must stay inside the target's true ellipse on
    // every frame. The colour histogram alone (no edge cue, no correlation
    // filter) cannot tell them apart: it must leave the target on some
    // seed (measured: on 14 of the 16, for up to 10 frames), so the bar
    // tests the texture cues.
    let fx = load("look_alikes");
    let colour_alone = Config { edges: None, correlation: None, ..Config::fast() };
    let mut lost_by_colour = 0;
    for seed in 1..=16 {
        each_named(|label, cfg| {
            let on = share_on_target(&fx, cfg, seed);
            assert_eq!(on, 1.0, "{label} seed {seed}: on the target on {on:.2} of frames");
        });
        lost_by_colour += usize::from(share_on_target(&fx, colour_alone, seed) < 1.0);
    }
    assert!(lost_by_colour > 0, "the colour histogram alone stays on the target on every seed");
}
