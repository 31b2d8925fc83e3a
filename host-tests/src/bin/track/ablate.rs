//! `track ablate`: each configuration variant run over the sequences for
//! several seeds (and with `--sre` from several first boxes), one markdown
//! table of mean scores.

use crate::Common;
use crate::evaluate::{Row, row_of, start_box};
use crate::shared::{Split, bar, fmt3, pct};
use crate::variants::{OTHER_TRACKERS, VARIANTS};
use host_tests::fixture::Fixture;
use host_tests::metrics::Awareness;
use host_tests::otb;
use host_tests::runner::{Method, PARTICLES, Run, track_with};
use indicatif::ProgressBar;
use pftrack::{BoundingBox, Config, Frame, PixelFormat};
use std::path::{Path, PathBuf};

/// A loaded sequence, in whatever format it came.
struct Loaded {
    name: String,
    width: usize,
    height: usize,
    stride: usize,
    format: PixelFormat,
    frames: Vec<Vec<u8>>,
    truth: Vec<BoundingBox>,
}

fn load(path: &Path) -> Result<Loaded, String> {
    if path.is_file() {
        let fx = Fixture::load(path)?;
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("fixture").to_string();
        // Frames where the target is entirely hidden or gone are not scored.
        let truth =
            fx.frames.iter().map(|f| if f.visible_permille == 0 { BoundingBox::default() } else { f.truth }).collect();
        let frames = fx.frames.into_iter().map(|f| f.pixels).collect();
        return Ok(Loaded {
            name,
            width: fx.width,
            height: fx.height,
            stride: fx.stride,
            format: fx.format,
            frames,
            truth,
        });
    }
    if !path.is_dir() {
        return Err(format!("{}: no such file or folder", path.display()));
    }
    let pb = bar(0, "decode");
    pb.set_prefix(path.file_name().and_then(|n| n.to_str()).unwrap_or("").to_string());
    let seq = otb::load(path, |i, n| {
        pb.set_length(n as u64);
        pb.set_position(i as u64);
    });
    pb.finish_and_clear();
    let seq = seq?;
    Ok(Loaded {
        name: seq.name,
        width: seq.width,
        height: seq.height,
        stride: seq.width * 3,
        format: PixelFormat::Rgb888,
        frames: seq.frames,
        truth: seq.truth,
    })
}

/// Tracks one loaded sequence and scores it, with a progress bar unless `quiet`.
fn evaluate(
    seq: &Loaded,
    method: Method,
    config: Config,
    (seed, start): (u64, Option<otb::Perturb>),
    quiet: bool,
) -> Result<(Row, Run), String> {
    let frames: Vec<Frame<'_>> = seq
        .frames
        .iter()
        .enumerate()
        .map(|(i, px)| {
            Frame::new(px, seq.width, seq.height, seq.stride, seq.format)
                .map_err(|e| format!("{}: frame {}: {e}", seq.name, i + 1))
        })
        .collect::<Result<_, _>>()?;
    let init = start_box(&seq.name, &seq.truth, start)?;
    let pb = if quiet { ProgressBar::hidden() } else { bar(frames.len(), "track") };
    pb.set_prefix(seq.name.clone());
    let run = track_with(method, config, seed, &frames, init, |i, _| pb.set_position(i as u64))
        .map_err(|e| format!("{}: {e}", seq.name))?;
    pb.finish_and_clear();
    Ok((row_of(&seq.name, &run, &seq.truth)?, run))
}

/// What one (variant, seed, sequence) run gave.
struct Cell {
    auc: f64,
    p20: f64,
    ms: f64,
    aware: Awareness,
}

/// One run of an ablation: a seed, a sequence (its index), and a change to
/// its first box.
#[derive(Copy, Clone)]
struct Job {
    seed: u64,
    seq: usize,
    start: Option<otb::Perturb>,
}

/// Runs `jobs` on every core, each with a fresh tracker.
fn run_jobs(
    seqs: &[Loaded],
    jobs: &[Job],
    method: Method,
    config: Config,
    pb: &ProgressBar,
) -> Result<Vec<Cell>, String> {
    use std::sync::Mutex;
    use std::sync::atomic::{AtomicUsize, Ordering};
    let next = AtomicUsize::new(0);
    let out: Mutex<Vec<Option<Result<Cell, String>>>> = Mutex::new((0..jobs.len()).map(|_| None).collect());
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).min(jobs.len().max(1));
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&Job { seed, seq: k, start }) = jobs.get(i) else { break };
                    let Some(seq) = seqs.get(k) else { break };
                    let cell = evaluate(seq, method, config, (seed, start), true).map(|(row, _)| Cell {
                        auc: row.auc,
                        p20: row.p20,
                        ms: row.ms,
                        aware: row.aware,
                    });
                    if let Ok(mut o) = out.lock()
                        && let Some(slot) = o.get_mut(i)
                    {
                        *slot = Some(cell);
                    }
                    pb.inc(1);
                }
            });
        }
    });
    let out = out.into_inner().map_err(|_| "a worker thread panicked".to_string())?;
    out.into_iter().map(|c| c.unwrap_or_else(|| Err("a run did not finish".into()))).collect()
}

/// Mean of `f` over the cells whose sequence is in `names` (all if `None`).
fn mean_over(
    cells: &[(usize, &Cell)],
    seqs: &[Loaded],
    names: Option<&[String]>,
    f: impl Fn(&Cell) -> f64,
) -> Option<f64> {
    let v: Vec<f64> = cells
        .iter()
        .filter(|(k, _)| names.is_none_or(|n| seqs.get(*k).is_some_and(|s| n.contains(&s.name))))
        .map(|(_, c)| f(c))
        .collect();
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

/// Options of the ablation study.
pub(crate) struct AblateOpts<'a> {
    pub(crate) seeds: u64,
    pub(crate) only: Option<&'a str>,
    pub(crate) split: Option<Split>,
    pub(crate) per_sequence: bool,
    /// Every seed runs from each of [`otb::SRE_STARTS`].
    pub(crate) sre: bool,
}

/// The changes to the first box every seed runs from: the twelve of
/// [`otb::SRE_STARTS`] with `--sre`, else `--perturb`'s (or none).
fn starts(sre: bool, perturb: Option<otb::Perturb>) -> Vec<Option<otb::Perturb>> {
    if sre { otb::SRE_STARTS.iter().copied().map(Some).collect() } else { vec![perturb] }
}

/// `track ablate`: the table of every variant (with `--only`, of those
/// whose name contains it).
pub(crate) fn command(paths: &[PathBuf], opts: &AblateOpts<'_>, common: &Common) -> Result<(), String> {
    let seqs: Vec<Loaded> = paths.iter().map(|p| load(p)).collect::<Result<_, _>>()?;
    let seeds = opts.seeds;
    println!(
        "ablation over {} sequences, seeds 1..={seeds}{} (mean over runs and sequences), {PARTICLES} particles; extra settings: {}",
        seqs.len(),
        if opts.sre { ", each from the 12 first boxes of `track starts`" } else { "" },
        if common.set.is_empty() { "none".to_string() } else { common.set.join(" ") }
    );
    if let Some(sp) = &opts.split {
        for (what, names) in [("tune", &sp.tune), ("check", &sp.check)] {
            let have: Vec<&str> = seqs.iter().filter(|s| names.contains(&s.name)).map(|s| s.name.as_str()).collect();
            println!("{what}: {} of {} sequences ({})", have.len(), names.len(), have.join(" "));
        }
    }
    println!();
    println!(
        "miss%: missing frames (IoU < 0.1) reported not tracking; good%: good frames (IoU >= 0.3) reported not tracking; ROC: the confidence's ROC AUC, missing frames against the rest (frames pooled per run, a seed or with --sre a seed and a start, then averaged)"
    );
    println!();
    let split_cols = opts.split.is_some();
    if split_cols {
        println!("| variant | settings | tune AUC | check AUC | all AUC | all P20 | miss% | good% | ROC | ms/frame |");
        println!("|---|---|---|---|---|---|---|---|---|---|");
    } else {
        println!("| variant | settings | mean AUC | mean P20 | miss% | good% | ROC | ms/frame |");
        println!("|---|---|---|---|---|---|---|---|");
    }
    let variants = VARIANTS
        .iter()
        .map(|&(name, sets)| (name, sets, Method::Pf))
        .chain(OTHER_TRACKERS.iter().map(|&(name, m)| (name, &[][..], m)));
    for (name, sets, method) in variants.filter(|(n, _, _)| opts.only.is_none_or(|o| n.contains(o))) {
        // The command line's settings first, so that `--set config=fast`
        // is the base every variant changes.
        let mut config = Config::default();
        for s in common.set.iter().cloned().chain(sets.iter().map(|s| s.to_string())) {
            host_tests::settings::apply(&mut config, &s)?;
        }
        config.validate().map_err(|e| format!("variant `{name}`: {e}"))?;
        // The mean-shift trackers draw no random numbers: one seed says all.
        let seeds_here = if method == Method::Pf { seeds } else { 1 };
        let starts = starts(opts.sre, common.perturb);
        let runs: Vec<(u64, Option<otb::Perturb>)> =
            (1..=seeds_here).flat_map(|s| starts.iter().map(move |&p| (s, p))).collect();
        let jobs: Vec<Job> =
            runs.iter().flat_map(|&(seed, start)| (0..seqs.len()).map(move |seq| Job { seed, seq, start })).collect();
        let pb = bar(jobs.len(), "ablate");
        pb.set_prefix(name.chars().take(12).collect::<String>());
        let cells = run_jobs(&seqs, &jobs, method, config, &pb)?;
        pb.finish_and_clear();
        let indexed: Vec<(usize, &Cell)> = jobs.iter().map(|j| j.seq).zip(cells.iter()).collect();
        // Awareness: frames pooled over sequences per run (seed and start),
        // the rates averaged over runs.
        let (mut miss, mut good, mut roc) = (Vec::new(), Vec::new(), Vec::new());
        for &(seed, start) in &runs {
            let mut pooled = Awareness::default();
            for (_, c) in jobs.iter().zip(&cells).filter(|(j, _)| j.seed == seed && j.start == start) {
                pooled.merge(&c.aware);
            }
            miss.extend(pooled.missing_reported());
            good.extend(pooled.good_reported_lost());
            roc.extend(pooled.roc_auc());
        }
        let avg = |v: &[f64]| (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
        let shown = match method {
            Method::Pf if sets.is_empty() => "(defaults)".to_string(),
            Method::Pf => sets.join(" "),
            m => format!(
                "--tracker {}",
                clap::ValueEnum::to_possible_value(&m).map(|v| v.get_name().to_string()).unwrap_or_default()
            ),
        };
        let all_auc = fmt3(mean_over(&indexed, &seqs, None, |c| c.auc));
        let all_p20 = fmt3(mean_over(&indexed, &seqs, None, |c| c.p20));
        let ms = fmt3(mean_over(&indexed, &seqs, None, |c| c.ms));
        let aware = format!("{} | {} | {}", pct(avg(&miss)), pct(avg(&good)), fmt3(avg(&roc)));
        match &opts.split {
            Some(sp) => println!(
                "| {name} | `{shown}` | {} | {} | {all_auc} | {all_p20} | {aware} | {ms} |",
                fmt3(mean_over(&indexed, &seqs, Some(&sp.tune), |c| c.auc)),
                fmt3(mean_over(&indexed, &seqs, Some(&sp.check), |c| c.auc)),
            ),
            None => println!("| {name} | `{shown}` | {all_auc} | {all_p20} | {aware} | {ms} |"),
        }
        if opts.per_sequence {
            for (k, seq) in seqs.iter().enumerate() {
                // Per seed (over its starts with --sre): the mean AUC, and
                // where the pooled miss% comes from, reported of missing.
                let mine = |seed: u64| {
                    jobs.iter().zip(&cells).filter(move |(j, _)| j.seq == k && j.seed == seed).map(|(_, c)| c)
                };
                let per: Vec<String> = (1..=seeds_here)
                    .map(|s| {
                        let (sum, n) = mine(s).fold((0.0, 0), |(a, n), c| (a + c.auc, n + 1));
                        format!("{:.3}", sum / n.max(1) as f64)
                    })
                    .collect();
                let flagged: Vec<String> = (1..=seeds_here)
                    .map(|s| {
                        let (f, m) =
                            mine(s).fold((0, 0), |(f, m), c| (f + c.aware.missing_flagged, m + c.aware.missing));
                        format!("{f}/{m}")
                    })
                    .collect();
                let group = match &opts.split {
                    Some(sp) if sp.tune.contains(&seq.name) => " (tune)",
                    Some(sp) if sp.check.contains(&seq.name) => " (check)",
                    _ => "",
                };
                println!(
                    "|   {}{group} | seeds {} | {} | missing frames reported {} |",
                    seq.name,
                    per.join(" / "),
                    fmt3(mean_over(&indexed, &seqs, Some(std::slice::from_ref(&seq.name)), |c| c.auc)),
                    flagged.join(" / "),
                );
            }
        }
    }
    Ok(())
}
