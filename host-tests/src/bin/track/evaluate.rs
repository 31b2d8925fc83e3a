//! `track otb` and `track fixture`: sequences tracked one frame at a time
//! and scored against their ground truth (a sequence's scores are also what
//! `ablate` reports).

use crate::Common;
use crate::score::{draw_plots, score_set};
use crate::shared::{bar, fmt3, pct, peak_memory};
use host_tests::metrics::{Awareness, has_target, identity_swaps, median, score};
use host_tests::otb;
use host_tests::runner::{AnyTracker, GROUP_TARGETS, HostGroup, Method, PARTICLES, Run};
use host_tests::source::{FixtureStream, FrameSource, fixture_truths};
use pftrack::{BoundingBox, Estimate, Event, Frame, TrackState};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// One sequence's scores against its truth.
pub(crate) struct Row {
    pub(crate) name: String,
    pub(crate) auc: f64,
    pub(crate) p20: f64,
    pub(crate) ms: f64,
    pub(crate) frames: usize,
    pub(crate) lost: usize,
    pub(crate) reacquired: usize,
    pub(crate) aware: Awareness,
}

/// The first ground-truth box, if it has a target to start from, changed by
/// `perturb` if given.
pub(crate) fn start_box(
    name: &str,
    truth: &[BoundingBox],
    perturb: Option<otb::Perturb>,
) -> Result<BoundingBox, String> {
    let init = *truth.first().ok_or_else(|| format!("{name}: no frames"))?;
    if !has_target(&init) {
        return Err(format!("{name}: the first ground-truth box has no target to start from"));
    }
    Ok(perturb.map_or(init, |p| p.apply(&init)))
}

/// A run's scores against the truth.
pub(crate) fn row_of(name: &str, run: &Run, truth: &[BoundingBox]) -> Result<Row, String> {
    let s = score(&run.boxes, truth).ok_or_else(|| format!("{name}: no frame with a target to score"))?;
    let count = |ev: Event| run.estimates.iter().filter(|e| e.event == Some(ev)).count();
    let mut aware = Awareness::default();
    for ((e, b), t) in run.estimates.iter().zip(run.boxes.iter().skip(1)).zip(truth.iter().skip(1)) {
        aware.add(b, e.state == TrackState::Tracking, e.confidence, t);
    }
    Ok(Row {
        name: name.to_string(),
        auc: s.auc,
        p20: s.precision20,
        ms: median(&run.step_ms),
        frames: run.boxes.len(),
        lost: count(Event::LostTarget),
        reacquired: count(Event::Reacquired),
        aware,
    })
}

fn print_frames(truth: &[BoundingBox], run: &Run) {
    println!("appearance threshold: {:.3}", run.threshold);
    if let Some(t) = run.edge_threshold {
        println!("edge threshold: {t}");
    }
    if let Some(l) = run.colour_levels {
        println!("colour levels per channel: {l:?} (the first for the whole ellipse; with quadrants, TL TR BL BR)");
    }
    print_table(truth, run);
}

/// Every frame's estimate beside the truth.
fn print_table(truth: &[BoundingBox], run: &Run) {
    println!("{:>5} {:>9} {:>11} {:>5} {:>4} {:>27} {:>27}", "frame", "state", "event", "conf", "app", "box", "truth");
    for (i, e) in run.estimates.iter().enumerate() {
        let b = e.bbox();
        let t = truth.get(i + 1).copied().unwrap_or_default();
        println!(
            "{:>5} {:>9} {:>11} {:>5.3} {:>4} {:>6.1},{:>6.1},{:>6.1},{:>6.1} {:>6.1},{:>6.1},{:>6.1},{:>6.1}",
            i + 2,
            format!("{:?}", e.state),
            e.event.map(|v| format!("{v:?}")).unwrap_or_default(),
            e.confidence,
            e.appearing,
            b.x,
            b.y,
            b.width,
            b.height,
            t.x,
            t.y,
            t.width,
            t.height
        );
    }
}

/// A sequence opened for streaming: its name, its frames, and each
/// target's truth (read whole, before the frames stream past).
struct Opened {
    name: String,
    frames: Box<dyn FrameSource>,
    truths: Vec<Vec<BoundingBox>>,
}

fn open_sequence(path: &Path) -> Result<Opened, String> {
    if path.is_file() {
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("fixture").to_string();
        let reader = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let frames = FixtureStream::new(Box::new(reader)).map_err(|e| format!("{}: {e}", path.display()))?;
        return Ok(Opened { name, frames: Box::new(frames), truths: fixture_truths(path)? });
    }
    if !path.is_dir() {
        return Err(format!("{}: no such file or folder", path.display()));
    }
    let s = otb::open(path)?;
    Ok(Opened { name: s.name, frames: Box::new(s.frames), truths: s.truths })
}

/// A target's scores, its track and its truth.
type Scored = (Row, Vec<BoundingBox>, Vec<BoundingBox>);

/// How often the tracks of a sequence of several targets were on another
/// target's truth instead of their own.
struct Swaps {
    name: String,
    /// Claims on another's truth, as [`identity_swaps`] counts them.
    count: usize,
    /// Frames with at least one of them.
    frames: usize,
    /// Frames of the sequence.
    of: usize,
}

/// Tracks one sequence as it streams past, one frame in memory at a time,
/// writes its tracks (and with `--gif` its pictures), and scores them: one
/// target, or every target of a sequence of several (as one group, or
/// each alone with `alone`).
fn run_one(path: &Path, common: &Common, alone: bool) -> Result<(Vec<Scored>, Option<Swaps>), String> {
    let Opened { name, frames, mut truths } = open_sequence(path)?;
    if truths.len() > 1 {
        return run_several(name, frames, &truths, common, alone).map(|(s, w)| (s, Some(w)));
    }
    let truth = truths.pop().ok_or_else(|| format!("{name}: no ground truth"))?;
    Ok((vec![run_single(name, frames, truth, common)?], None))
}

/// Tracks the one target of a sequence.
fn run_single(
    name: String,
    mut frames: Box<dyn FrameSource>,
    truth: Vec<BoundingBox>,
    common: &Common,
) -> Result<Scored, String> {
    use host_tests::picture::GifFrames;
    let n = frames.frame_count().unwrap_or(0);
    let pb = bar(n, "track");
    pb.set_prefix(name.clone());
    let mut gif = common.gif.then(|| GifFrames::new(frames.size().0, Some(n)));
    let mut picture = |i: usize, f: &Frame<'_>, est: Option<&Estimate>, parts: &[(f32, f32)]| {
        if let Some(g) = gif.as_mut().filter(|g| g.wants(i)) {
            let px = (f.width(), f.height(), host_tests::scene::to_rgb(f));
            g.push(i, px, est, truth.get(i).filter(|t| has_target(t)), parts);
        }
    };
    let first = frames.next_frame().map_err(|e| format!("{name}: {e}"))?.ok_or_else(|| format!("{name}: no frames"))?;
    let init = start_box(&name, &truth, common.perturb)?;
    let (mut tracker, _) = AnyTracker::start(common.tracker, common.config, common.seed, &first, init)
        .map_err(|e| format!("{name}: {e}"))?;
    picture(0, &first, None, &[]);
    let mut run = Run::new(init, &tracker);
    let mut i = 1;
    while let Some(f) = frames.next_frame().map_err(|e| format!("{name}: {e}"))? {
        let est = run.step(&mut tracker, &f).map_err(|e| format!("{name}: frame {}: {e}", i + 1))?;
        picture(i, &f, Some(&est), run.particles.last().map_or(&[], Vec::as_slice));
        i += 1;
        pb.set_position(i as u64);
    }
    pb.finish_and_clear();
    let row = row_of(&name, &run, &truth)?;
    if common.frames {
        print_frames(&truth, &run);
    }
    if let Some(g) = &gif {
        let (animation, still) = (format!("{name}.gif"), format!("{name}.png"));
        g.write(&common.out_dir.join(animation), Some(&common.out_dir.join(still)), 66)?;
    }
    write_outputs(&name, &name, &run, &row, &truth, common)?;
    Ok((row, run.boxes, truth))
}

/// Writes a target's outputs as `<file>.txt`, `<file>.ms` and
/// `<file>.confidence`, and with `--dump` appends its frames named `name`.
fn write_outputs(
    name: &str,
    file: &str,
    run: &Run,
    row: &Row,
    truth: &[BoundingBox],
    common: &Common,
) -> Result<(), String> {
    if let Some(path) = &common.dump {
        use std::io::Write;
        let mut f = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        let mut text = String::new();
        // The confidence's size signal, from the boxes written (the
        // tracker reads its ellipse's half axes: the same ratio).
        let first = run.boxes.first().map_or((1.0, 1.0), |b| (b.width, b.height));
        for (i, ((e, d), b)) in run.estimates.iter().zip(&run.diagnostics).zip(run.boxes.iter().skip(1)).enumerate() {
            let Some(t) = truth.get(i + 1).filter(|t| has_target(t)) else { continue };
            text += &format!(
                "{},{},{:.4},{},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4}\n",
                name,
                i + 2,
                b.iou(t),
                (e.state == TrackState::Tracking) as u8,
                e.confidence,
                d.contrast,
                d.correlation,
                d.anchored,
                d.similarity,
                d.psr,
                pftrack::size_change(first, (b.width, b.height)),
            );
        }
        f.write_all(text.as_bytes()).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    let out = common.out_dir.join(format!("{}.txt", file));
    let text: String =
        run.boxes.iter().map(|b| format!("{:.2},{:.2},{:.2},{:.2}\n", b.x, b.y, b.width, b.height)).collect();
    std::fs::write(&out, text).map_err(|e| format!("{}: {e}", out.display()))?;
    let ms = common.out_dir.join(format!("{}.ms", file));
    std::fs::write(&ms, format!("{:.4}\n", row.ms)).map_err(|e| format!("{}: {e}", ms.display()))?;
    // The confidence of each update, so `track score` ranks missing frames
    // by it as it does any other tracker's.
    let conf = common.out_dir.join(format!("{}.confidence", file));
    // Every digit an f32 needs: rounded values would tie and move the ROC.
    let text: String = run.estimates.iter().map(|e| format!("{}\n", e.confidence)).collect();
    std::fs::write(&conf, text).map_err(|e| format!("{}: {e}", conf.display()))
}

/// Tracks every target of a sequence of several: all in one [`HostGroup`],
/// each added from its first box in order, or with `alone` each by its own
/// tracker seeded as the group seeds it (target `k` with seed + k), so that
/// the two differ only by the group. Target `k` (from 0) is scored as
/// `<name>#<k+1>` and written to `<name>.<k+1>.txt`, as its truth is
/// numbered in an OTB folder. The group's rows give the whole group's time
/// a frame.
fn run_several(
    name: String,
    mut frames: Box<dyn FrameSource>,
    truths: &[Vec<BoundingBox>],
    common: &Common,
    alone: bool,
) -> Result<(Vec<Scored>, Swaps), String> {
    use host_tests::picture::{GifFrames, annotate_targets};
    if truths.len() > GROUP_TARGETS {
        return Err(format!("{name}: {} targets, at most {GROUP_TARGETS} at once", truths.len()));
    }
    if !alone && common.tracker != Method::Pf {
        return Err(format!("{name}: a group of several targets needs the particle filter (--tracker pf), or --alone"));
    }
    if !alone && common.dump.is_some() {
        return Err(format!("{name}: --dump needs each target alone (--alone): a group gives no diagnostics"));
    }
    let n = frames.frame_count().unwrap_or(0);
    let pb = bar(n, "track");
    pb.set_prefix(name.clone());
    let mut gif = common.gif.then(|| GifFrames::new(frames.size().0, Some(n)));
    let mut picture = |i: usize, f: &Frame<'_>, targets: &[(u16, Estimate)]| {
        if let Some(g) = gif.as_mut().filter(|g| g.wants(i)) {
            let px = (f.width(), f.height(), host_tests::scene::to_rgb(f));
            g.push_drawn(i, px, |c| annotate_targets(c, targets));
        }
    };
    let first = frames.next_frame().map_err(|e| format!("{name}: {e}"))?.ok_or_else(|| format!("{name}: no frames"))?;
    let label = |k: usize| format!("{name}#{}", k + 1);
    let inits = truths
        .iter()
        .enumerate()
        .map(|(k, t)| start_box(&label(k), t, common.perturb))
        .collect::<Result<Vec<_>, _>>()?;
    let mut runs = Vec::new();
    let mut targets = Vec::new();
    let mut group = None;
    let mut trackers = Vec::new();
    if alone {
        for (k, init) in inits.iter().enumerate() {
            let (t, est) =
                AnyTracker::start(common.tracker, common.config, common.seed.wrapping_add(k as u64), &first, *init)
                    .map_err(|e| format!("{}: {e}", label(k)))?;
            runs.push(Run::new(*init, &t));
            targets.push((k as u16, est));
            trackers.push(t);
        }
    } else {
        let mut g = Box::new(HostGroup::new(common.config, common.seed).map_err(|e| format!("{name}: {e}"))?);
        for (k, init) in inits.iter().enumerate() {
            let added = g.add(&first, *init).map_err(|e| format!("{}: {e}", label(k)))?;
            runs.push(group_run(*init));
            targets.push((added.id.0, added.estimate));
        }
        group = Some(g);
    }
    picture(0, &first, &targets);
    let mut i = 1;
    while let Some(f) = frames.next_frame().map_err(|e| format!("{name}: {e}"))? {
        let at = |e: pftrack::Error| format!("{name}: frame {}: {e}", i + 1);
        targets.clear();
        if let Some(g) = group.as_mut() {
            let t0 = std::time::Instant::now();
            let out = g.step(&f).map_err(at)?;
            let ms = t0.elapsed().as_secs_f64() * 1e3;
            for t in &out {
                let run = runs.get_mut(t.id.0 as usize).ok_or_else(|| format!("{name}: unknown target {}", t.id.0))?;
                run.step_ms.push(ms);
                run.boxes.push(t.estimate.bbox());
                run.estimates.push(t.estimate);
                targets.push((t.id.0, t.estimate));
            }
        } else {
            for (k, (run, t)) in runs.iter_mut().zip(&mut trackers).enumerate() {
                targets.push((k as u16, run.step(t, &f).map_err(at)?));
                // Pictures of several targets draw no particles: none kept.
                run.particles.clear();
            }
        }
        picture(i, &f, &targets);
        i += 1;
        pb.set_position(i as u64);
    }
    pb.finish_and_clear();
    if let Some(g) = &gif {
        let (animation, still) = (format!("{name}.gif"), format!("{name}.png"));
        g.write(&common.out_dir.join(animation), Some(&common.out_dir.join(still)), 66)?;
    }
    // A target claims its box on the first frame (given) and on every frame
    // it is reported tracking.
    let tracks: Vec<Vec<Option<BoundingBox>>> = runs
        .iter()
        .map(|r| {
            let tracking = std::iter::once(true).chain(r.estimates.iter().map(|e| e.state == TrackState::Tracking));
            r.boxes.iter().zip(tracking).map(|(b, on)| on.then_some(*b)).collect()
        })
        .collect();
    let swaps = swaps_of(name.clone(), &tracks, truths);
    let mut scored = Vec::new();
    for (k, (run, truth)) in runs.into_iter().zip(truths).enumerate() {
        let row = row_of(&label(k), &run, truth)?;
        if common.frames {
            println!("{}", label(k));
            if alone {
                print_frames(truth, &run);
            } else {
                print_table(truth, &run);
            }
        }
        write_outputs(&label(k), &format!("{name}.{}", k + 1), &run, &row, truth, common)?;
        scored.push((row, run.boxes, truth.clone()));
    }
    Ok((scored, swaps))
}

/// An empty run of a group's target from `init`: the group reports
/// estimates, not a member's thresholds, particles or diagnostics.
fn group_run(init: BoundingBox) -> Run {
    Run {
        boxes: vec![init],
        estimates: Vec::new(),
        step_ms: Vec::new(),
        threshold: 0.0,
        colour_levels: None,
        edge_threshold: None,
        particles: Vec::new(),
        diagnostics: Vec::new(),
    }
}

/// The identity swaps of a sequence's tracks against its targets' truths,
/// and on how many frames they happen.
fn swaps_of(name: String, tracks: &[Vec<Option<BoundingBox>>], truths: &[Vec<BoundingBox>]) -> Swaps {
    let of = truths.iter().map(Vec::len).min().unwrap_or(0);
    let frames = (0..of)
        .filter(|&f| {
            let one = |t: &[Option<BoundingBox>]| t.get(f).copied().into_iter().collect::<Vec<_>>();
            let tr: Vec<_> = tracks.iter().map(|t| one(t)).collect();
            let th: Vec<Vec<BoundingBox>> = truths.iter().map(|t| t.get(f).copied().into_iter().collect()).collect();
            identity_swaps(&tr, &th) > 0
        })
        .count();
    Swaps { name, count: identity_swaps(tracks, truths), frames, of }
}

/// One line on how well the estimates' states and confidences tell good
/// frames from missing ones.
fn describe(a: &Awareness) -> String {
    format!(
        "missing frames (IoU < 0.1): {}, of which reported not tracking {}; good frames (IoU >= 0.3) reported not tracking {}; confidence ROC AUC (missing vs the rest) {}",
        pct(a.missing_share()),
        pct(a.missing_reported()),
        pct(a.good_reported_lost()),
        fmt3(a.roc_auc())
    )
}

/// `track otb` and `track fixture`: every sequence tracked as it streams
/// past, its track written, and one table of scores printed.
pub(crate) fn command(paths: &[PathBuf], common: &Common, alone: bool) -> ExitCode {
    if let Err(e) = std::fs::create_dir_all(&common.out_dir) {
        eprintln!("error: {}: {e}", common.out_dir.display());
        return ExitCode::FAILURE;
    }
    let settings = if common.set.is_empty() { "default config".to_string() } else { common.set.join(" ") };
    match common.tracker {
        Method::Pf => println!("pftrack, {PARTICLES} particles, seed {}, {settings}", common.seed),
        m => println!("{} (default configuration)", m.label()),
    }
    println!(
        "{:<22} {:>6} {:>6} {:>6} {:>9} {:>5} {:>6}",
        "sequence", "frames", "AUC", "P20", "ms/frame", "lost", "found"
    );
    let mut rows = Vec::new();
    let mut scored = Vec::new();
    let mut swaps = Vec::new();
    let mut failed = false;
    for p in paths {
        match run_one(p, common, alone) {
            Ok((targets, swapped)) => {
                for (r, boxes, truth) in targets {
                    scored.push((boxes, truth));
                    println!(
                        "{:<22} {:>6} {:>6.3} {:>6.3} {:>9.3} {:>5} {:>6}",
                        r.name, r.frames, r.auc, r.p20, r.ms, r.lost, r.reacquired
                    );
                    rows.push(r);
                }
                swaps.extend(swapped);
            }
            Err(e) => {
                eprintln!("error: {e}");
                failed = true;
            }
        }
    }
    if rows.len() > 1 {
        let n = rows.len() as f64;
        println!(
            "{:<22} {:>6} {:>6.3} {:>6.3} {:>9.3}",
            "mean",
            rows.iter().map(|r| r.frames).sum::<usize>(),
            rows.iter().map(|r| r.auc).sum::<f64>() / n,
            rows.iter().map(|r| r.p20).sum::<f64>() / n,
            rows.iter().map(|r| r.ms).sum::<f64>() / n,
        );
    }
    for s in &swaps {
        println!(
            "{}: {} identity swaps, on {} of {} frames ({})",
            s.name,
            s.count,
            s.frames,
            s.of,
            pct((s.of > 0).then(|| s.frames as f64 / s.of as f64))
        );
    }
    if !rows.is_empty() {
        let mut pooled = Awareness::default();
        rows.iter().for_each(|r| pooled.merge(&r.aware));
        println!("{}", describe(&pooled));
    }
    println!("tracks written to {}; peak memory {}", common.out_dir.display(), peak_memory());
    if common.plots && !scored.is_empty() {
        let ms = (!rows.is_empty()).then(|| rows.iter().map(|r| r.ms).sum::<f64>() / rows.len() as f64);
        let drawn = score_set(common.tracker.label(), &scored, ms)
            .and_then(|set| draw_plots(&[set], &common.out_dir, &format!("{} sequences", scored.len())));
        if let Err(e) = drawn {
            eprintln!("error: {e}");
            failed = true;
        }
    }
    if failed { ExitCode::FAILURE } else { ExitCode::SUCCESS }
}
