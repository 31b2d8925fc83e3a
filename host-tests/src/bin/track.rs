//! Runs the tracker on OTB sequences or on the project's fixtures, writes the
//! track of each, and prints success AUC, precision@20 and ms/frame.

use clap::{Parser, Subcommand};
use host_tests::fixture::Fixture;
use host_tests::metrics::{Awareness, breakdown, has_target, median, score};
use host_tests::otb;
use host_tests::runner::{AnyTracker, Method, PARTICLES, Run, track_with};
use host_tests::source::{FixtureStream, FrameSource, RawSpec, fixture_truth};
use indicatif::{ProgressBar, ProgressStyle};
use pftrack::{BoundingBox, Config, Estimate, Event, Frame, PixelFormat, TrackState};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(about = "Track sequences with pftrack and score them against ground truth")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(clap::Args, Clone)]
struct Common {
    #[arg(skip)]
    config: Config,
    /// Which tracker runs (`--set`s configure the particle filter).
    #[arg(long, value_enum, default_value_t = Method::Pf)]
    tracker: Method,
    /// Where to write `<sequence>.txt` tracks (one x,y,w,h line per frame).
    #[arg(long, default_value = "out")]
    out_dir: PathBuf,
    /// Seed of the tracker's random generator.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Also print every frame's estimate: state, event, confidence, appearing particles, box and truth.
    #[arg(long)]
    frames: bool,
    /// Also write `<sequence>.gif` (every frame annotated: estimate in white,
    /// ground truth in cyan, particles in magenta, a status bar coloured by
    /// state, as long as the confidence) and `<sequence>.png` (one frame of it).
    #[arg(long)]
    gif: bool,
    /// Also write `success.png` and `precision.png` (OTB-style plots of this
    /// run over all its sequences) into the output folder.
    #[arg(long)]
    plots: bool,
    /// Override a configuration field, e.g. `--set sampling=checkerboard --set eps=0.01`
    /// (repeatable; an unknown key lists the known ones).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Also append every frame's confidence and the signals behind it to
    /// this CSV file: sequence, frame, IoU with the truth, tracking (1 or
    /// 0), confidence, contrast, correlation, anchored similarity,
    /// similarity, the correlation filter's PSR (0 without it; see
    /// `tools/fit-confidence`).
    #[arg(long)]
    dump: Option<PathBuf>,
    /// Start from the first ground-truth box moved by DX of its width and
    /// DY of its height and scaled by SCALE about its centre, e.g.
    /// `--perturb 0.1,0,1` (OTB's spatial robustness evaluation; every
    /// frame is still scored against the truth).
    #[arg(long, value_name = "DX,DY,SCALE", allow_hyphen_values = true)]
    perturb: Option<otb::Perturb>,
}

/// The options of `track run`.
#[derive(clap::Args)]
struct RunArgs {
    /// A folder of JPEG/PNG images (sorted by name), a .y4m file, `-` for
    /// YUV4MPEG2 on standard input (e.g. from `ffmpeg -f yuv4mpegpipe -`),
    /// or with --raw a raw camera dump (a file or `-`).
    input: String,
    /// The target in the first frame: left, top, width, height in pixels.
    #[arg(long = "box", value_name = "X,Y,W,H", allow_hyphen_values = true)]
    bbox: String,
    /// Read INPUT as raw frames back to back: rgb565, rgb888, yuyv, gray8,
    /// i420 or nv12, rows packed, e.g. `--raw rgb565:320x240`.
    #[arg(long, value_name = "FORMAT:WxH")]
    raw: Option<RawSpec>,
    /// Write the JSON lines to this file instead of standard output.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Write `frame,state,confidence,x,y,w,h` rows to this file instead of
    /// JSON lines on standard output.
    #[arg(long, value_name = "FILE")]
    csv: Option<PathBuf>,
    /// Write every frame with the estimate drawn as YUV4MPEG2 video to this
    /// file, or to standard output with `-` (JSON must then go to a file:
    /// --json or --csv), e.g. `--annotate - | ffmpeg -i - out.mp4`.
    #[arg(long, value_name = "FILE.y4m")]
    annotate: Option<String>,
    /// Write an annotated GIF (at most 300 frames, evenly spaced) to this file.
    #[arg(long, value_name = "FILE")]
    gif: Option<PathBuf>,
    /// At the end, print frames, frames per second, losses and peak memory
    /// to standard error.
    #[arg(long)]
    summary: bool,
    /// Ground truth to score the track against: an OTB `groundtruth.txt`
    /// (x,y,w,h per frame) or a .pft fixture; the summary then adds the
    /// success AUC and the mean IoU over the frames with a target.
    #[arg(long, value_name = "FILE")]
    truth: Option<PathBuf>,
    /// Seed of the tracker's random generator.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Which tracker runs (`--set`s configure the particle filter).
    #[arg(long, value_enum, default_value_t = Method::Pf)]
    tracker: Method,
    /// Override a configuration field, e.g. `--set life=confidence:0.8:0.85` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
}

#[derive(Subcommand)]
enum Command {
    /// Tracks your own footage from one box: a video as Y4M (a file or a
    /// pipe from ffmpeg), a folder of images or a raw camera dump; one JSON
    /// line per frame on standard output.
    Run(RunArgs),
    /// Writes any input `run` reads (a fixture, a folder of images, a raw
    /// dump, Y4M) as a YUV4MPEG2 file, e.g. to encode it with ffmpeg.
    Convert {
        /// As for `run`.
        input: String,
        /// The .y4m file to write, or `-` for standard output.
        output: String,
        /// As for `run`.
        #[arg(long, value_name = "FORMAT:WxH")]
        raw: Option<RawSpec>,
    },
    /// OTB sequence folders (img/ + groundtruth.txt); fixture files (.pft) are accepted too.
    Otb {
        /// Sequence folders or .pft fixture files.
        #[arg(required = true)]
        seqs: Vec<PathBuf>,
        #[command(flatten)]
        common: Common,
    },
    /// The project's fixture files (.pft).
    Fixture {
        /// Fixture files.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        #[command(flatten)]
        common: Common,
    },
    /// Scores result sets against ground truth: each result folder holds
    /// `<sequence>.txt` (x,y,w,h per frame, as `otb` writes) and optionally
    /// `<sequence>.ms` (median ms/frame). Prints one table and draws the
    /// success and precision plots of all sets.
    Score {
        /// OTB sequence folders (only groundtruth.txt is read).
        #[arg(long, required = true, num_args = 1..)]
        truth: Vec<PathBuf>,
        /// Result folders, as NAME=FOLDER or FOLDER (named after the
        /// folder); NAME=F1,F2,… scores several runs (e.g. seeds) as one,
        /// averaging each sequence's scores over them.
        #[arg(long, required = true, num_args = 1..)]
        results: Vec<String>,
        /// Where to write success.png and precision.png.
        #[arg(long, default_value = "out")]
        plots: PathBuf,
        /// A tune / check division of the sequences: the table then has a
        /// mean AUC column for each split besides the overall one.
        #[arg(long)]
        split: Option<PathBuf>,
    },
    /// Prints the twelve changed first boxes of `ablate --sre`, one
    /// DX,DY,SCALE per line, as `--perturb` takes them.
    Starts,
    /// Runs each configuration variant of the ablation study over the
    /// sequences for several seeds and prints one markdown table of mean
    /// AUC, P20 and ms/frame.
    Ablate {
        /// Sequence folders or .pft fixture files.
        #[arg(required = true)]
        seqs: Vec<PathBuf>,
        /// Seeds 1..=N are run for every variant.
        #[arg(long, default_value_t = 3)]
        seeds: u64,
        /// Run only the variants whose name contains this.
        #[arg(long)]
        only: Option<String>,
        /// A tune / check division of the sequences (e.g.
        /// `../shared/realseq-split.txt`): the table then has a mean AUC
        /// column for each split besides the overall one.
        #[arg(long)]
        split: Option<PathBuf>,
        /// Also print every sequence's AUC per seed under each variant, and
        /// how many of its missing frames were reported not tracking (per seed).
        #[arg(long)]
        per_sequence: bool,
        /// Run every seed from each of the twelve changed first boxes of
        /// OTB's spatial robustness evaluation (`track starts` lists them)
        /// and average over all of them: a variant then cannot win by one
        /// lucky start.
        #[arg(long, conflicts_with = "perturb")]
        sre: bool,
        #[command(flatten)]
        common: Common,
    },
}

/// The ablation study: each variant changes the defaults (the best
/// combination found) in one respect, except the first, which is the first
/// paper's filter as written. The `--set`s of the command line apply on top.
const VARIANTS: &[(&str, &[&str])] = &[
    ("defaults (best combination)", &[]),
    (
        "paper 1 as written",
        &[
            "sampling=full",
            "max_samples=0",
            "edges=off",
            "sigma=0.2",
            "eps=0",
            "position_noise=0.1",
            "velocity_noise=0.05",
            "velocity_decay=1",
            "speed_noise=0",
            "update_sigma=0.2",
            "life=appearance",
            "size=off",
            "shift=off",
            "background_weight=off",
        ],
    ),
    ("life: the appearance test (paper 1)", &["life=appearance"]),
    ("life: confidence, lost below 0.5, found above 0.6", &["life=confidence:0.5:0.6"]),
    ("life: confidence, lost below 0.7, found above 0.8", &["life=confidence:0.7:0.8"]),
    ("life: confidence, lost below 0.8, found above 0.85", &["life=confidence:0.8:0.85"]),
    ("life: + re-detection while lost", &["redetect=on"]),
    ("life: without the surroundings-motion test", &["scene_motion=off"]),
    ("size: not searched (random walk only)", &["size=off"]),
    ("size: searched by contrast only", &["size=0.02:0:0.03:0.05"]),
    ("size: scale only (aspect kept)", &["size=0.02:1:scale:0.05"]),
    ("size: step 0.05", &["size=0.05:1:0.03:0.05"]),
    ("size: no pull towards the first box", &["size=0.02:1:0:0"]),
    ("size: pull on the area only", &["size=0.02:1:0:0.05"]),
    ("size: pulls 0.03 on aspect and area", &["size=0.02:1:0.03:0.03"]),
    ("position: not refined (filter mean)", &["shift=off"]),
    ("position: refined without the template", &["shift=0.05:1:3:0"]),
    ("position: template weight 0.3", &["shift=0.05:1:3:0.3"]),
    ("position: refined by contrast only", &["shift=0.05:1:0:0"]),
    ("position: up to 3 steps", &["shift=0.05:3:3:0.15"]),
    ("surroundings: adapt at 0.02", &["surroundings_rate=0.02"]),
    ("colour: model not background-weighted", &["background_weight=off"]),
    ("colour: not background-weighted, life 0.5 / 0.6", &["background_weight=off", "life=confidence:0.5:0.6"]),
    ("colour: half background-weighted, every colour", &["background_weight=0.5"]),
    ("colour: fully background-weighted model (CBWH)", &["background_weight=1"]),
    ("cues: + grey template, share 0.3", &["template=0.3:0.05"]),
    ("cues: without the correlation filter (colour alone)", &["correlation=off"]),
    ("likelihood: adaptive σ, floor 0.02", &["adaptive_sigma=0.02:0.5"]),
    ("likelihood: σ from spread, 4 e-folds", &["spread_sigma=4:0.005:0.5"]),
    ("likelihood: fixed σ 0.2, no ε", &["sigma=0.2", "eps=0"]),
    ("sampling: 1000 samples per region", &["max_samples=1000"]),
    ("sampling: all pixels", &["sampling=full"]),
    ("sampling: quarter", &["sampling=quarter"]),
    ("sampling: checkerboard, no budget", &["max_samples=0"]),
    ("cues: colour only", &["edges=off"]),
    ("cues: edges threshold 50", &["edges=8:50"]),
    ("cues: edges threshold fixed, not lowered for a soft target", &["strong_percent=0"]),
    ("cues: edges with a flat bin", &["edges=8:100:flat"]),
    ("cues: weighted 0.5 instead of product", &["combination=weighted:0.5"]),
    ("colour: HSV 8x8x4", &["binning=hsv8x8x4"]),
    ("colour: RGB 4x4x4", &["binning=rgb4x4x4"]),
    ("colour: adaptive bins (Birgé–Rozenholc)", &["binning=adaptive"]),
    ("spatial: quadrants, RGB 4x4x4", &["quadrants=on", "binning=rgb4x4x4"]),
    (
        "dynamics: constant velocity, paper noise",
        &["velocity_decay=1", "velocity_noise=0.05", "position_noise=0.1", "speed_noise=0"],
    ),
    ("dynamics: position noise from the size alone", &["speed_noise=0"]),
    ("dynamics: speed noise 1.5", &["speed_noise=1.5"]),
    ("model: update gate σ 0.2 (paper 1)", &["update_sigma=0.2"]),
    ("model: never updated", &["alpha=0"]),
    ("model: update only when degraded (T = 0.9 ρ₀, 10 frames)", &["model_update=degraded:0.9:10"]),
    ("resampling: multinomial", &["resampling=multinomial"]),
    ("similarity: histogram intersection", &["similarity=intersection"]),
    ("likelihood: exponential exp(-d/σ)", &["shape=exponential"]),
    ("likelihood table, spacing 2 (fixed size)", &["table=2"]),
    ("cues: + ellipse-boundary gradient, share 0.3", &["boundary=0.3"]),
];

/// Variants that swap the particle filter for another tracker.
const OTHER_TRACKERS: &[(&str, Method)] =
    &[("baseline: mean shift (±5% scale)", Method::Meanshift), ("baseline: Kalman mean shift", Method::Kalman)];

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

fn bar(len: usize, what: &str) -> ProgressBar {
    let b = ProgressBar::new(len as u64);
    b.set_style(
        ProgressStyle::with_template("{prefix:>12} {msg:8} [{bar:30}] {pos}/{len}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    b.set_message(what.to_string());
    b
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

struct Row {
    name: String,
    auc: f64,
    p20: f64,
    ms: f64,
    frames: usize,
    lost: usize,
    reacquired: usize,
    aware: Awareness,
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

/// The first ground-truth box, if it has a target to start from, changed by
/// `perturb` if given.
fn start_box(name: &str, truth: &[BoundingBox], perturb: Option<otb::Perturb>) -> Result<BoundingBox, String> {
    let init = *truth.first().ok_or_else(|| format!("{name}: no frames"))?;
    if !has_target(&init) {
        return Err(format!("{name}: the first ground-truth box has no target to start from"));
    }
    Ok(perturb.map_or(init, |p| p.apply(&init)))
}

/// A run's scores against the truth.
fn row_of(name: &str, run: &Run, truth: &[BoundingBox]) -> Result<Row, String> {
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

/// A sequence opened for streaming: its name, its frames, and its truth
/// (read whole from an OTB folder; a fixture's comes with each frame).
struct Opened {
    name: String,
    frames: Box<dyn FrameSource>,
    truth: Vec<BoundingBox>,
}

fn open_sequence(path: &Path) -> Result<Opened, String> {
    if path.is_file() {
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("fixture").to_string();
        let reader = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let frames = FixtureStream::new(Box::new(reader)).map_err(|e| format!("{}: {e}", path.display()))?;
        return Ok(Opened { name, frames: Box::new(frames), truth: fixture_truth(path)? });
    }
    if !path.is_dir() {
        return Err(format!("{}: no such file or folder", path.display()));
    }
    let s = otb::open(path)?;
    Ok(Opened { name: s.name, frames: Box::new(s.frames), truth: s.truth })
}

/// Tracks one sequence as it streams past, one frame in memory at a time,
/// writes its track (and with `--gif` its pictures), and scores it.
fn run_one(path: &Path, common: &Common) -> Result<(Row, Vec<BoundingBox>, Vec<BoundingBox>), String> {
    use host_tests::picture::GifFrames;
    let Opened { name, mut frames, truth } = open_sequence(path)?;
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
    if let Some(path) = &common.dump {
        use std::io::Write;
        let mut f = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        let mut text = String::new();
        for (i, ((e, d), b)) in run.estimates.iter().zip(&run.diagnostics).zip(run.boxes.iter().skip(1)).enumerate() {
            let Some(t) = truth.get(i + 1).filter(|t| has_target(t)) else { continue };
            text += &format!(
                "{},{},{:.4},{},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4}\n",
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
            );
        }
        f.write_all(text.as_bytes()).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    let out = common.out_dir.join(format!("{}.txt", name));
    let text: String =
        run.boxes.iter().map(|b| format!("{:.2},{:.2},{:.2},{:.2}\n", b.x, b.y, b.width, b.height)).collect();
    std::fs::write(&out, text).map_err(|e| format!("{}: {e}", out.display()))?;
    let ms = common.out_dir.join(format!("{}.ms", name));
    std::fs::write(&ms, format!("{:.4}\n", row.ms)).map_err(|e| format!("{}: {e}", ms.display()))?;
    Ok((row, run.boxes, truth))
}

/// One result set's curves and mean scores over its sequences.
struct SetScore {
    name: String,
    success: Vec<f64>,
    precision: Vec<f64>,
    auc: f64,
    p20: f64,
    ms: Option<f64>,
}

/// Scores the boxes of each sequence against its truth, averaging curves
/// and scores over sequences (the tables' convention: mean of per-sequence AUC).
fn score_set(name: &str, runs: &[(Vec<BoundingBox>, Vec<BoundingBox>)], ms: Option<f64>) -> Result<SetScore, String> {
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

fn draw_plots(sets: &[SetScore], dir: &Path, what: &str) -> Result<(), String> {
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

fn score_command(truth: &[PathBuf], results: &[String], plots: &Path, split: Option<&Split>) -> Result<(), String> {
    let truths: Vec<(String, Vec<BoundingBox>)> = truth
        .iter()
        .map(|dir| {
            let name = dir.file_name().and_then(|n| n.to_str()).unwrap_or("").to_string();
            read_boxes(&dir.join("groundtruth.txt")).map(|t| (name, t))
        })
        .collect::<Result<_, _>>()?;
    // Per set: its curves, and each sequence's AUC averaged over the set's runs.
    let mut sets = Vec::new();
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
        let mut per_seq = vec![0.0; truths.len()];
        // Means over sequences of the breakdown's two AUCs.
        let mut breakdowns = (0.0, 0.0);
        for folder in &folders {
            for ((seq, t), acc) in truths.iter().zip(per_seq.iter_mut()) {
                let boxes = read_boxes(&folder.join(format!("{seq}.txt")))?;
                if boxes.len() != t.len() {
                    return Err(format!("{name}: {seq} has {} boxes for {} frames", boxes.len(), t.len()));
                }
                if let Ok(v) = std::fs::read_to_string(folder.join(format!("{seq}.ms")))
                    && let Ok(v) = v.trim().parse::<f64>()
                {
                    ms.push(v);
                }
                *acc += score(&boxes, t).map_or(0.0, |s| s.auc) / folders.len() as f64;
                if let Some(b) = breakdown(&boxes, t) {
                    let n = (folders.len() * truths.len()) as f64;
                    (breakdowns.0, breakdowns.1) = (breakdowns.0 + b.true_size / n, breakdowns.1 + b.true_centre / n);
                }
                runs.push((boxes, t.clone()));
            }
        }
        let ms = (ms.len() == runs.len()).then(|| ms.iter().sum::<f64>() / ms.len() as f64);
        sets.push((score_set(&name, &runs, ms)?, per_seq, breakdowns));
    }
    let seqs: Vec<&str> = truths.iter().map(|(n, _)| n.as_str()).collect();
    println!("{} sequences: {}", seqs.len(), seqs.join(", "));
    println!();
    let mean_of = |per_seq: &[f64], names: &[String]| {
        let v: Vec<f64> =
            seqs.iter().zip(per_seq).filter(|(n, _)| names.iter().any(|m| m == *n)).map(|(_, &a)| a).collect();
        fmt3((!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64))
    };
    match split {
        Some(_) => {
            println!("| tracker | tune AUC | check AUC | mean AUC | mean P20 | ms/frame |");
            println!("|---|---|---|---|---|---|");
        }
        None => {
            println!("| tracker | mean AUC | mean P20 | ms/frame |");
            println!("|---|---|---|---|");
        }
    }
    let mut order: Vec<&(SetScore, Vec<f64>, (f64, f64))> = sets.iter().collect();
    order.sort_by(|a, b| b.0.auc.total_cmp(&a.0.auc));
    for (r, per_seq, _) in order.iter().copied() {
        let ms = r.ms.map(|m| format!("{m:.3}")).unwrap_or_else(|| "-".to_string());
        match split {
            Some(sp) => println!(
                "| {} | {} | {} | {:.3} | {:.3} | {ms} |",
                r.name,
                mean_of(per_seq, &sp.tune),
                mean_of(per_seq, &sp.check),
                r.auc,
                r.p20
            ),
            None => println!("| {} | {:.3} | {:.3} | {ms} |", r.name, r.auc, r.p20),
        }
    }
    println!();
    println!(
        "Where the overlap is lost (mean AUC over sequences, each box given the truth's size about its own centre, or moved to the truth's centre at its own size):"
    );
    println!();
    println!("| tracker | mean AUC | with the truth's size | with the truth's centre |");
    println!("|---|---|---|---|");
    for (r, per_seq, (size, centre)) in order {
        let auc = per_seq.iter().sum::<f64>() / per_seq.len().max(1) as f64;
        println!("| {} | {auc:.3} | {size:.3} ({:+.3}) | {centre:.3} ({:+.3}) |", r.name, size - auc, centre - auc);
    }
    std::fs::create_dir_all(plots).map_err(|e| format!("{}: {e}", plots.display()))?;
    let sets: Vec<SetScore> = sets.into_iter().map(|(s, _, _)| s).collect();
    draw_plots(&sets, plots, &format!("{} sequences", seqs.len()))
}

/// The tune / check division of sequences (`../shared/realseq-split.txt`:
/// lines `tune: A B …` and `check: C D …`, `#` comments).
struct Split {
    tune: Vec<String>,
    check: Vec<String>,
}

impl Split {
    fn load(path: &Path) -> Result<Split, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let (mut tune, mut check) = (None, None);
        for line in text.lines().map(str::trim).filter(|l| !l.is_empty() && !l.starts_with('#')) {
            let (key, names) = line
                .split_once(':')
                .ok_or_else(|| format!("{}: `{line}`: expected `tune:` or `check:`", path.display()))?;
            let names: Vec<String> = names.split_whitespace().map(str::to_string).collect();
            match key.trim() {
                "tune" => tune = Some(names),
                "check" => check = Some(names),
                other => return Err(format!("{}: unknown split `{other}`", path.display())),
            }
        }
        match (tune, check) {
            (Some(tune), Some(check)) => Ok(Split { tune, check }),
            _ => Err(format!("{}: needs both a `tune:` and a `check:` line", path.display())),
        }
    }
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

fn pct(v: Option<f64>) -> String {
    v.map(|v| format!("{:.1}%", 100.0 * v)).unwrap_or_else(|| "-".into())
}

fn fmt3(v: Option<f64>) -> String {
    v.map(|v| format!("{v:.3}")).unwrap_or_else(|| "-".into())
}

/// One line on how well the estimates' states and confidences tell good
/// frames from missing ones.
fn describe(a: &Awareness) -> String {
    let total = a.samples.len().max(1) as f64;
    format!(
        "missing frames (IoU < 0.1): {:.1}%, of which reported not tracking {}; good frames (IoU >= 0.3) reported not tracking {}; confidence ROC AUC (missing vs the rest) {}",
        100.0 * a.missing as f64 / total,
        pct(a.missing_reported()),
        pct(a.good_reported_lost()),
        fmt3(a.roc_auc())
    )
}

/// Options of the ablation study.
struct AblateOpts<'a> {
    seeds: u64,
    only: Option<&'a str>,
    split: Option<Split>,
    per_sequence: bool,
    /// Every seed runs from each of [`otb::SRE_STARTS`].
    sre: bool,
}

/// The changes to the first box every seed runs from: the twelve of
/// [`otb::SRE_STARTS`] with `--sre`, else `--perturb`'s (or none).
fn starts(sre: bool, perturb: Option<otb::Perturb>) -> Vec<Option<otb::Perturb>> {
    if sre { otb::SRE_STARTS.iter().copied().map(Some).collect() } else { vec![perturb] }
}

fn ablate(paths: &[PathBuf], opts: &AblateOpts<'_>, common: &Common) -> Result<(), String> {
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
        let mut config = Config::default();
        for s in sets.iter().map(|s| s.to_string()).chain(common.set.iter().cloned()) {
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

fn main() -> ExitCode {
    let cli = Cli::parse();
    let (paths, mut common, ablation) = match cli.command {
        Command::Convert { input, output, raw } => {
            return match convert_command(&input, &output, raw) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::FAILURE
                }
            };
        }
        Command::Run(args) => {
            return match run_command(&args) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::FAILURE
                }
            };
        }
        Command::Score { truth, results, plots, split } => {
            let split = match split.as_deref().map(Split::load).transpose() {
                Ok(s) => s,
                Err(e) => {
                    eprintln!("error: {e}");
                    return ExitCode::FAILURE;
                }
            };
            return match score_command(&truth, &results, &plots, split.as_ref()) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::FAILURE
                }
            };
        }
        Command::Starts => {
            for p in otb::SRE_STARTS {
                println!("{p}");
            }
            return ExitCode::SUCCESS;
        }
        Command::Otb { seqs, common } => (seqs, common, None),
        Command::Fixture { files, common } => (files, common, None),
        Command::Ablate { seqs, seeds, only, split, per_sequence, sre, common } => {
            (seqs, common, Some((seeds, only, split, per_sequence, sre)))
        }
    };
    for s in &common.set {
        if let Err(e) = host_tests::settings::apply(&mut common.config, s) {
            eprintln!("error: --set {e}");
            return ExitCode::FAILURE;
        }
    }
    if let Err(e) = common.config.validate() {
        eprintln!("error: {e}");
        return ExitCode::FAILURE;
    }
    if let Some((seeds, only, split, per_sequence, sre)) = ablation {
        let split = match split.as_deref().map(Split::load).transpose() {
            Ok(s) => s,
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::FAILURE;
            }
        };
        let opts = AblateOpts { seeds, only: only.as_deref(), split, per_sequence, sre };
        return match ablate(&paths, &opts, &common) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::FAILURE
            }
        };
    }
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
    let mut failed = false;
    for p in &paths {
        match run_one(p, &common) {
            Ok((r, boxes, truth)) => {
                scored.push((boxes, truth));
                println!(
                    "{:<22} {:>6} {:>6.3} {:>6.3} {:>9.3} {:>5} {:>6}",
                    r.name, r.frames, r.auc, r.p20, r.ms, r.lost, r.reacquired
                );
                rows.push(r);
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

/// Where `track run` writes the records.
enum Sink {
    Json(Box<dyn std::io::Write>),
    Csv(Box<dyn std::io::Write>),
}

fn create(path: &Path) -> Result<Box<dyn std::io::Write>, String> {
    let f = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(Box::new(std::io::BufWriter::new(f)))
}

/// The peak resident memory of this process (Linux's VmHWM) as the
/// summaries print it, e.g. `5.2 MB`.
fn peak_memory() -> String {
    let kb = std::fs::read_to_string("/proc/self/status").ok().and_then(|status| {
        let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
        line.split_whitespace().nth(1)?.parse::<u64>().ok()
    });
    kb.map_or_else(|| "unknown".to_string(), |kb| format!("{:.1} MB", (kb * 1024) as f64 / 1e6))
}

/// `track run`: one frame in memory at a time, every record written and
/// flushed as its frame is done, so that an error or an endless stream
/// leaves everything tracked so far on the output.
fn run_command(a: &RunArgs) -> Result<(), String> {
    use host_tests::picture::GifFrames;
    use host_tests::record::{Record, Y4mWriter};
    use std::io::Write;
    let mut config = Config::default();
    for s in &a.set {
        host_tests::settings::apply(&mut config, s).map_err(|e| format!("--set {e}"))?;
    }
    config.validate().map_err(|e| e.to_string())?;
    let v: Vec<f32> = a
        .bbox
        .split(',')
        .map(|t| t.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("--box `{}` is not four numbers X,Y,W,H", a.bbox))?;
    let [x, y, w, h] = v[..] else { return Err(format!("--box `{}` is not four numbers X,Y,W,H", a.bbox)) };
    let init = BoundingBox::new(x, y, w, h);
    let stdout_video = a.annotate.as_deref() == Some("-");
    if stdout_video && a.json.is_none() && a.csv.is_none() {
        return Err("--annotate - writes video to standard output: give --json FILE or --csv FILE for the track".into());
    }
    let mut sinks = Vec::new();
    if let Some(p) = &a.json {
        sinks.push(Sink::Json(create(p)?));
    }
    if let Some(p) = &a.csv {
        let mut out = create(p)?;
        writeln!(out, "{}", Record::CSV_HEADER).map_err(|e| format!("{}: {e}", p.display()))?;
        sinks.push(Sink::Csv(out));
    }
    if sinks.is_empty() {
        sinks.push(Sink::Json(Box::new(std::io::stdout().lock())));
    }
    // A reader that stops reading (`| head`) ends the run quietly, with
    // what it wanted written: `closed` says so.
    let closed = std::cell::Cell::new(false);
    let mut write = |r: &Record| -> Result<(), String> {
        for s in &mut sinks {
            let (out, line) = match s {
                Sink::Json(o) => (o, r.json()),
                Sink::Csv(o) => (o, r.csv()),
            };
            match writeln!(out, "{line}").and_then(|_| out.flush()) {
                Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => closed.set(true),
                other => other.map_err(|e| format!("writing the track: {e}"))?,
            }
        }
        Ok(())
    };

    let mut src = host_tests::source::open(&a.input, a.raw)?;
    let size = src.size();
    let rate = src.rate().unwrap_or((30, 1));
    let mut video = match a.annotate.as_deref() {
        None => None,
        Some("-") => Some(Y4mWriter::new(
            Box::new(std::io::BufWriter::new(std::io::stdout().lock())) as Box<dyn Write>,
            size,
            rate,
        )?),
        Some(p) => Some(Y4mWriter::new(create(Path::new(p))?, size, rate)?),
    };
    let mut gif = a.gif.as_ref().map(|_| GifFrames::new(size.0, None));
    let pb = ProgressBar::new_spinner();
    pb.set_draw_target(indicatif::ProgressDrawTarget::stderr());
    pb.set_style(
        ProgressStyle::with_template("{spinner} {pos} frames, {per_sec} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    let truth = match &a.truth {
        None => None,
        Some(p) if p.extension().is_some_and(|e| e == "pft") => Some(fixture_truth(p)?),
        Some(p) => Some(
            std::fs::read_to_string(p)
                .map_err(|e| e.to_string())
                .and_then(|t| otb::parse_groundtruth(&t))
                .map_err(|e| format!("{}: {e}", p.display()))?,
        ),
    };
    let mut boxes = Vec::new();
    let t0 = std::time::Instant::now();
    let first = src.next_frame()?.ok_or_else(|| format!("{}: no frames", a.input))?;
    let (mut tracker, est0) =
        AnyTracker::start(a.tracker, config, a.seed, &first, init).map_err(|e| format!("frame 1: {e}"))?;
    write(&Record::initial(init))?;
    if truth.is_some() {
        boxes.push(init);
    }
    // Every frame goes to the video, the GIF keeps some: particles and
    // pixels are gathered only for what is drawn.
    let mut draw = |i: usize, f: &Frame<'_>, est: &Estimate, tracker: &AnyTracker| -> Result<(), String> {
        let kept = gif.as_ref().is_some_and(|g| g.wants(i));
        if video.is_none() && !kept {
            return Ok(());
        }
        let parts = tracker.particles();
        if let Some(v) = &mut video {
            v.write(f, Some(est), &parts)?;
        }
        if let Some(g) = gif.as_mut().filter(|_| kept) {
            g.push(i, (f.width(), f.height(), host_tests::scene::to_rgb(f)), Some(est), None, &parts);
        }
        Ok(())
    };
    draw(0, &first, &est0, &tracker)?;
    let (mut frames, mut lost, mut found, mut tracking) = (1usize, 0usize, 0usize, 1usize);
    while !closed.get()
        && let Some(f) = src.next_frame()?
    {
        frames += 1;
        let est = tracker.step(&f).map_err(|e| format!("frame {frames}: {e}"))?;
        write(&Record::of(frames, &est))?;
        if truth.is_some() {
            boxes.push(est.bbox());
        }
        draw(frames - 1, &f, &est, &tracker)?;
        lost += usize::from(est.event == Some(Event::LostTarget));
        found += usize::from(est.event == Some(Event::Reacquired));
        tracking += usize::from(est.state == TrackState::Tracking);
        pb.set_position(frames as u64);
        pb.set_message(host_tests::record::state_name(est.state));
    }
    pb.finish_and_clear();
    drop(video);
    if let (Some(path), Some(g)) = (&a.gif, &gif) {
        g.write(path, None, (66 * g.every() as u32).min(1000))?;
    }
    if let Some(t) = &truth {
        let scored = t.get(..boxes.len()).and_then(|t| score(&boxes, t)).ok_or_else(|| {
            format!("--truth has {} boxes for {} frames, or none with a target", t.len(), boxes.len())
        })?;
        let ious: Vec<f64> = boxes.iter().zip(t).filter(|(_, t)| has_target(t)).map(|(b, t)| b.iou(t) as f64).collect();
        eprintln!(
            "against the truth: success AUC {:.3}, mean IoU {:.3} over {} frames with a target",
            scored.auc,
            ious.iter().sum::<f64>() / ious.len().max(1) as f64,
            ious.len()
        );
    }
    if a.summary {
        let secs = t0.elapsed().as_secs_f64();
        eprintln!(
            "{frames} frames in {secs:.2} s ({:.0} fps), tracking {:.1}% of frames, lost {lost} times, re-acquired {found} times, peak memory {}",
            frames as f64 / secs.max(1e-9),
            100.0 * tracking as f64 / frames as f64,
            peak_memory(),
        );
    }
    Ok(())
}

/// `track convert`: any input as a Y4M file, one frame at a time.
fn convert_command(input: &str, output: &str, raw: Option<RawSpec>) -> Result<(), String> {
    use host_tests::record::Y4mWriter;
    let mut src = host_tests::source::open(input, raw)?;
    let (size, rate) = (src.size(), src.rate().unwrap_or((30, 1)));
    let out: Box<dyn std::io::Write> = match output {
        "-" => Box::new(std::io::BufWriter::new(std::io::stdout().lock())),
        p => create(Path::new(p))?,
    };
    let mut video = Y4mWriter::new(out, size, rate)?;
    while let Some(f) = src.next_frame()? {
        video.write(&f, None, &[])?;
    }
    Ok(())
}
