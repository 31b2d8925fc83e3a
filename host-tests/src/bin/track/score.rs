//! `track score`: result sets scored against ground truth, as one table and
//! the success and precision plots (which `otb` and `fixture` draw too).

use crate::shared::{Split, fmt3, pct};
use host_tests::metrics::{Awareness, breakdown, score};
use host_tests::otb;
use pftrack::BoundingBox;
use std::path::{Path, PathBuf};

/// One result set's curves and mean scores over its sequences.
pub(crate) struct SetScore {
    name: String,
    success: Vec<f64>,
    precision: Vec<f64>,
    auc: f64,
    p20: f64,
    ms: Option<f64>,
}

/// Scores the boxes of each sequence against its truth, averaging curves
/// and scores over sequences (the tables' convention: mean of per-sequence AUC).
pub(crate) fn score_set(
    name: &str,
    runs: &[(Vec<BoundingBox>, Vec<BoundingBox>)],
    ms: Option<f64>,
) -> Result<SetScore, String> {
    use host_tests::metrics::{PRECISION_THRESHOLDS, SUCCESS_THRESHOLDS, precision_curve, success_curve};
    let mut success = vec![0.0; SUCCESS_THRESHOLDS];
    let mut precision = vec![0.0; PRECISION_THRESHOLDS];
    let mut n = 0.0;
    for (boxes, truth) in runs {
        let (Some(s), Some(p)) = (success_curve(boxes, truth), precision_curve(boxes, truth)) else { continue };
        success.iter_mut().zip(&s).for_each(|(a, b)| *a += b);
        precision.iter_mut().zip(&p).for_each(|(a, b)| *a += b);
        n += 1.0;
    }
    if n == 0.0 {
        return Err(format!("{name}: no sequence could be scored"));
    }
    success.iter_mut().chain(precision.iter_mut()).for_each(|v| *v /= n);
    let auc = success.iter().sum::<f64>() / success.len() as f64;
    let p20 = precision.get(20).copied().unwrap_or(0.0);
    Ok(SetScore { name: name.to_string(), success, precision, auc, p20, ms })
}

pub(crate) fn draw_plots(sets: &[SetScore], dir: &Path, what: &str) -> Result<(), String> {
    use host_tests::plot::{Curve, line_plot};
    let xs_s: Vec<f64> = (0..host_tests::metrics::SUCCESS_THRESHOLDS).map(|i| i as f64 * 0.05).collect();
    let xs_p: Vec<f64> = (0..host_tests::metrics::PRECISION_THRESHOLDS).map(|i| i as f64).collect();
    let s: Vec<Curve> =
        sets.iter().map(|r| Curve { name: r.name.clone(), ys: r.success.clone(), score: r.auc }).collect();
    let p: Vec<Curve> =
        sets.iter().map(|r| Curve { name: r.name.clone(), ys: r.precision.clone(), score: r.p20 }).collect();
    line_plot(
        &dir.join("success.png"),
        &format!("Success plots of OPE - {what}"),
        "Overlap threshold",
        "Success rate",
        &xs_s,
        &s,
        "AUC",
    )?;
    line_plot(
        &dir.join("precision.png"),
        &format!("Precision plots of OPE - {what}"),
        "Location error threshold (px)",
        "Precision",
        &xs_p,
        &p,
        "P20",
    )?;
    println!("plots written to {} and {}", dir.join("success.png").display(), dir.join("precision.png").display());
    Ok(())
}

/// Reads a track file (x,y,w,h per line; commas, tabs or spaces).
fn read_boxes(path: &Path) -> Result<Vec<BoundingBox>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    otb::parse_groundtruth(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// Reads a track's confidences, one per frame after the first, if the
/// tracker wrote them (`None` for a tracker without a confidence).
fn read_confidences(path: &Path, frames: usize) -> Result<Option<Vec<f32>>, String> {
    let Ok(text) = std::fs::read_to_string(path) else { return Ok(None) };
    let c = otb::parse_confidences(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    if c.len() + 1 != frames {
        return Err(format!(
            "{}: {} confidences for {frames} frames (one per frame after the first)",
            path.display(),
            c.len()
        ));
    }
    Ok(Some(c))
}

/// The mean of some numbers (`None` for none).
fn mean(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

pub(crate) fn command(
    truth: &[PathBuf],
    results: &[String],
    plots: &Path,
    split: Option<&Split>,
    per_sequence: bool,
) -> Result<(), String> {
    // Each target's truth with the name of its result files: the folder's
    // name, or `<name>.<N>` for its groundtruth.N.txt, as `track otb`
    // writes them; split lists name folders.
    let mut truths: Vec<(String, Vec<BoundingBox>)> = Vec::new();
    let mut folder_of = Vec::new();
    for dir in truth {
        let name = dir.file_name().and_then(|n| n.to_str()).unwrap_or("").to_string();
        let files = otb::groundtruth_files(dir)?;
        let several = files.len() > 1;
        for (k, f) in files.iter().enumerate() {
            truths.push((if several { format!("{name}.{}", k + 1) } else { name.clone() }, read_boxes(f)?));
            folder_of.push(name.clone());
        }
    }
    // Per set: its curves, and each sequence's AUC averaged over the set's runs.
    let mut sets = Vec::new();
    let mut per_runs = Vec::new();
    for spec in results {
        let (name, folders) = match spec.split_once('=') {
            Some((n, f)) => (n.to_string(), f.split(',').map(PathBuf::from).collect::<Vec<_>>()),
            None => {
                let f = PathBuf::from(spec);
                (f.file_name().and_then(|n| n.to_str()).unwrap_or(spec).to_string(), vec![f])
            }
        };
        let mut runs = Vec::new();
        let mut ms = Vec::new();
        // Each run's AUC per sequence.
        let mut per_run = Vec::new();
        // Means over sequences of the breakdown's three AUCs.
        let mut breakdowns = (0.0, 0.0, 0.0);
        // Per folder (a run, e.g. a seed): its frames pooled over sequences,
        // as `track otb` pools them, and whether every track has confidences.
        let mut aware = Vec::new();
        for folder in &folders {
            let (mut pooled, mut confident) = (Awareness::default(), true);
            let mut run_seq = Vec::with_capacity(truths.len());
            for (seq, t) in &truths {
                let boxes = read_boxes(&folder.join(format!("{seq}.txt")))?;
                if boxes.len() != t.len() {
                    return Err(format!("{name}: {seq} has {} boxes for {} frames", boxes.len(), t.len()));
                }
                if let Ok(v) = std::fs::read_to_string(folder.join(format!("{seq}.ms")))
                    && let Ok(v) = v.trim().parse::<f64>()
                {
                    ms.push(v);
                }
                let conf = read_confidences(&folder.join(format!("{seq}.confidence")), boxes.len())?;
                confident &= conf.is_some();
                let conf = conf.unwrap_or_else(|| vec![0.0; boxes.len().saturating_sub(1)]);
                // The first box is given, not tracked: scored from the second
                // frame, as `track otb` does. A track file has no tracking
                // state, so the shares reported not tracking are not printed.
                for ((b, t), &c) in boxes.iter().zip(t).skip(1).zip(&conf) {
                    pooled.add(b, true, c, t);
                }
                run_seq.push(score(&boxes, t).map_or(0.0, |s| s.auc));
                if let Some(b) = breakdown(&boxes, t) {
                    let n = (folders.len() * truths.len()) as f64;
                    breakdowns.0 += b.true_size / n;
                    breakdowns.1 += b.true_centre / n;
                    breakdowns.2 += b.held_centre / n;
                }
                runs.push((boxes, t.clone()));
            }
            aware.push((pooled, confident));
            per_run.push(run_seq);
        }
        // Each sequence's AUC averaged over the runs.
        let mut per_seq = vec![0.0; truths.len()];
        for run in &per_run {
            per_seq.iter_mut().zip(run).for_each(|(acc, auc)| *acc += auc / folders.len() as f64);
        }
        let ms = (ms.len() == runs.len()).then(|| ms.iter().sum::<f64>() / ms.len() as f64);
        let missing: Vec<f64> = aware.iter().filter_map(|(a, _)| a.missing_share()).collect();
        let roc: Vec<f64> = aware.iter().filter(|(_, c)| *c).filter_map(|(a, _)| a.roc_auc()).collect();
        // A ROC only when every run has confidences: a mean over some seeds would not compare.
        let roc = if aware.iter().all(|(_, c)| *c) { mean(&roc) } else { None };
        sets.push((score_set(&name, &runs, ms)?, per_seq, breakdowns, (mean(&missing), roc)));
        per_runs.push(per_run);
    }
    let seqs: Vec<&str> = truths.iter().map(|(n, _)| n.as_str()).collect();
    println!("{} sequences: {}", seqs.len(), seqs.join(", "));
    println!();
    let mean_of = |per_seq: &[f64], names: &[String]| fmt3(mean_within(per_seq, &folder_of, Some(names)));
    match split {
        Some(_) => {
            println!(
                "| tracker | tune AUC | check AUC | mean AUC | mean P20 | IoU < 0.1 | confidence ROC AUC | ms/frame |"
            );
            println!("|---|---|---|---|---|---|---|---|");
        }
        None => {
            println!("| tracker | mean AUC | mean P20 | IoU < 0.1 | confidence ROC AUC | ms/frame |");
            println!("|---|---|---|---|---|---|");
        }
    }
    type Row = (SetScore, Vec<f64>, (f64, f64, f64), (Option<f64>, Option<f64>));
    let mut order: Vec<&Row> = sets.iter().collect();
    order.sort_by(|a, b| b.0.auc.total_cmp(&a.0.auc));
    for (r, per_seq, _, (missing, roc)) in order.iter().copied() {
        let ms = r.ms.map(|m| format!("{m:.3}")).unwrap_or_else(|| "-".to_string());
        let (missing, roc) = (pct(*missing), fmt3(*roc));
        match split {
            Some(sp) => println!(
                "| {} | {} | {} | {:.3} | {:.3} | {missing} | {roc} | {ms} |",
                r.name,
                mean_of(per_seq, &sp.tune),
                mean_of(per_seq, &sp.check),
                r.auc,
                r.p20
            ),
            None => println!("| {} | {:.3} | {:.3} | {missing} | {roc} | {ms} |", r.name, r.auc, r.p20),
        }
    }
    println!();
    println!(
        "IoU < 0.1: the share of frames after the first that miss the target; confidence ROC AUC: how well the tracker's own confidence (written beside its boxes as <sequence>.confidence) ranks those frames below the rest, `-` without one (frames pooled over a run's sequences, averaged over runs)"
    );
    println!();
    println!(
        "Where the overlap is lost (mean AUC over sequences, each box given the truth's size about its own centre, or moved to the truth's centre at its own size; the last column moves only the boxes that still overlap the truth by at least 0.1, the target held):"
    );
    println!();
    println!("| tracker | mean AUC | with the truth's size | with the truth's centre | the same where held |");
    println!("|---|---|---|---|---|");
    for (r, per_seq, (size, centre, held), _) in order {
        let auc = per_seq.iter().sum::<f64>() / per_seq.len().max(1) as f64;
        println!(
            "| {} | {auc:.3} | {size:.3} ({:+.3}) | {centre:.3} ({:+.3}) | {held:.3} ({:+.3}) |",
            r.name,
            size - auc,
            centre - auc,
            held - auc
        );
    }
    let names: Vec<&str> = sets.iter().map(|(s, ..)| s.name.as_str()).collect();
    between_runs(&names, &per_runs, &folder_of, split);
    if per_sequence {
        by_sequence(&names, &per_runs, &seqs, &folder_of, split);
    }
    std::fs::create_dir_all(plots).map_err(|e| format!("{}: {e}", plots.display()))?;
    let sets: Vec<SetScore> = sets.into_iter().map(|(s, _, _, _)| s).collect();
    draw_plots(&sets, plots, &format!("{} sequences", seqs.len()))
}

/// Each sequence's AUC per set, in the order the sets were given: the mean
/// over the set's runs and, for a set of several runs, the spread between
/// them on that sequence (highest less lowest), in brackets: the figure a
/// seed-spread goal is stated in.
fn by_sequence(names: &[&str], per_runs: &[Vec<Vec<f64>>], seqs: &[&str], folder_of: &[String], split: Option<&Split>) {
    println!();
    println!(
        "Per sequence: AUC, the mean over a set's runs, and for a set of several runs the highest run's AUC less the lowest's in brackets:"
    );
    println!();
    let split_head = if split.is_some() { "split | " } else { "" };
    println!("| sequence | {split_head}{} |", names.join(" | "));
    println!("|{}", "---|".repeat(names.len() + 1 + split.is_some() as usize));
    for (i, seq) in seqs.iter().enumerate() {
        let cells: Vec<String> = per_runs
            .iter()
            .map(|runs| {
                let v: Vec<f64> = runs.iter().filter_map(|r| r.get(i).copied()).collect();
                let m = mean(&v).unwrap_or(0.0);
                let (lo, hi) = v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| (l.min(x), h.max(x)));
                if v.len() > 1 { format!("{m:.3} ({:.3})", hi - lo) } else { format!("{m:.3}") }
            })
            .collect();
        let folder = folder_of.get(i).map(String::as_str).unwrap_or("");
        let part = split.map_or(String::new(), |sp| format!("{} | ", sp.part_of(folder)));
        println!("| {seq} | {part}{} |", cells.join(" | "));
    }
}

/// The mean of per-sequence `values` over the sequences whose folder (as
/// `folder_of` names them) is in `only` (all without one); `None` for none.
fn mean_within(values: &[f64], folder_of: &[String], only: Option<&[String]>) -> Option<f64> {
    let v: Vec<f64> = folder_of
        .iter()
        .zip(values)
        .filter(|(n, _)| only.is_none_or(|o| o.iter().any(|m| m == *n)))
        .map(|(_, &a)| a)
        .collect();
    mean(&v)
}

/// The mean and the sample standard deviation of some numbers (at least two).
fn spread(v: &[f64]) -> Option<(f64, f64)> {
    let m = mean(v)?;
    let n = v.len();
    (n > 1).then(|| (m, (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1) as f64).sqrt()))
}

/// How far apart runs are: per set, the standard deviation of a run's
/// mean AUC over the sequences (a run is a result folder, e.g. a seed);
/// per set after the first with as many runs, the mean of its runs'
/// differences with the first set's, run by run in the order given, and
/// that mean's standard error. Paired, the seeds' shared luck (a sequence
/// every configuration finds hard on some seed) cancels. Printed for the
/// sets of two runs or more.
fn between_runs(names: &[&str], per_runs: &[Vec<Vec<f64>>], folder_of: &[String], split: Option<&Split>) {
    if per_runs.iter().all(|runs| runs.len() < 2) {
        return;
    }
    let means = |runs: &[Vec<f64>], only: Option<&[String]>| {
        runs.iter().map(|r| mean_within(r, folder_of, only).unwrap_or(0.0)).collect::<Vec<_>>()
    };
    let first = names.first().copied().unwrap_or("");
    let reference = per_runs.first().map(Vec::as_slice).unwrap_or(&[]);
    let paired = |runs: &[Vec<f64>], only: Option<&[String]>| {
        if runs.len() != reference.len() {
            return "-".to_string();
        }
        let d: Vec<f64> = means(runs, only).iter().zip(means(reference, only)).map(|(a, b)| a - b).collect();
        match spread(&d) {
            Some((m, sd)) => format!("{m:+.4} ± {:.4}", sd / (d.len() as f64).sqrt()),
            None => "-".to_string(),
        }
    };
    println!();
    println!(
        "Between runs (a run is one result folder, e.g. one seed): the standard deviation of a run's mean AUC over the sequences, and each set's difference with the first, {first}, paired run by run in the order given, ± its standard error:"
    );
    println!();
    let check = split.map(|s| s.check.as_slice());
    match check {
        Some(_) => {
            println!("| tracker | runs | sd between runs | difference | on check |");
            println!("|---|---|---|---|---|");
        }
        None => {
            println!("| tracker | runs | sd between runs | difference |");
            println!("|---|---|---|---|");
        }
    }
    for (i, (name, runs)) in names.iter().zip(per_runs).enumerate().filter(|(_, (_, runs))| runs.len() > 1) {
        let sd = spread(&means(runs, None)).map_or("-".to_string(), |(_, sd)| format!("{sd:.4}"));
        let (all, on_check) = if i == 0 {
            ("-".to_string(), "-".to_string())
        } else {
            (paired(runs, None), check.map_or(String::new(), |c| paired(runs, Some(c))))
        };
        match check {
            Some(_) => println!("| {name} | {} | {sd} | {all} | {on_check} |", runs.len()),
            None => println!("| {name} | {} | {sd} | {all} |", runs.len()),
        }
    }
}
