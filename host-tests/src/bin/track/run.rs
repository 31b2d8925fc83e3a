//! `track run`: your own footage tracked from one box, one record per frame.

use crate::shared::{create, peak_memory};
use host_tests::metrics::{has_target, score};
use host_tests::otb;
use host_tests::picture::annotate_targets;
use host_tests::runner::{AnyTracker, HostGroup, Method};
use host_tests::source::{RawSpec, fixture_truth};
use indicatif::{ProgressBar, ProgressStyle};
use pftrack::{BoundingBox, Config, Estimate, Event, Frame, TrackState};
use std::path::{Path, PathBuf};

/// The options of `track run`.
#[derive(clap::Args)]
pub(crate) struct RunArgs {
    /// A folder of JPEG/PNG images (sorted by name), a .y4m file, `-` for
    /// YUV4MPEG2 on standard input (e.g. from `ffmpeg -f yuv4mpegpipe -`),
    /// or with --raw a raw camera dump (a file or `-`).
    input: String,
    /// The target in the first frame: left, top, width, height in pixels.
    /// Repeat it to track several targets at once (the particle filter
    /// only): each record then carries the target's identity, 0 for the
    /// first box, 1 for the second and so on.
    #[arg(long = "box", value_name = "X,Y,W,H", allow_hyphen_values = true, required = true)]
    bbox: Vec<String>,
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

/// A `--box` value: `X,Y,W,H`.
fn parse_box(text: &str) -> Result<BoundingBox, String> {
    let v: Vec<f32> = text
        .split(',')
        .map(|t| t.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("--box `{text}` is not four numbers X,Y,W,H"))?;
    let [x, y, w, h] = v[..] else { return Err(format!("--box `{text}` is not four numbers X,Y,W,H")) };
    Ok(BoundingBox::new(x, y, w, h))
}

/// Where `track run` writes the records.
enum Sink {
    Json(Box<dyn std::io::Write>),
    Csv(Box<dyn std::io::Write>),
}

/// `track run`: one frame in memory at a time, every record written and
/// flushed as its frame is done, so that an error or an endless stream
/// leaves everything tracked so far on the output.
pub(crate) fn command(a: &RunArgs) -> Result<(), String> {
    use host_tests::picture::GifFrames;
    use host_tests::record::{Record, Y4mWriter};
    use std::io::Write;
    let mut config = Config::default();
    for s in &a.set {
        host_tests::settings::apply(&mut config, s).map_err(|e| format!("--set {e}"))?;
    }
    config.validate().map_err(|e| e.to_string())?;
    let boxes = a.bbox.iter().map(|b| parse_box(b)).collect::<Result<Vec<_>, _>>()?;
    let several = boxes.len() > 1;
    if several && a.tracker != Method::Pf {
        return Err("several --box need the particle filter (--tracker pf)".into());
    }
    if several && a.truth.is_some() {
        return Err("--truth scores one target: give one --box".into());
    }
    if boxes.len() > host_tests::runner::GROUP_TARGETS {
        return Err(format!("at most {} --box at once", host_tests::runner::GROUP_TARGETS));
    }
    let Some(&init) = boxes.first() else { return Err("give the target's box: --box X,Y,W,H".into()) };
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
        let header = if several { Record::CSV_HEADER_TARGETS } else { Record::CSV_HEADER };
        writeln!(out, "{header}").map_err(|e| format!("{}: {e}", p.display()))?;
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
    if several {
        let t0 = std::time::Instant::now();
        let first = src.next_frame()?.ok_or_else(|| format!("{}: no frames", a.input))?;
        let mut group = Box::new(HostGroup::new(config, a.seed).map_err(|e| e.to_string())?);
        let mut targets = Vec::new();
        for b in &boxes {
            let added = group.add(&first, *b).map_err(|e| format!("frame 1, --box {b:?}: {e}"))?;
            if let Some((with, iou)) = added.overlap {
                eprintln!("target {} overlaps target {} (IoU {iou:.2})", added.id.0, with.0);
            }
            write(&Record::initial(*b).of_target(added.id.0))?;
            targets.push((added.id.0, added.estimate));
        }
        let mut draw = |i: usize, f: &Frame<'_>, targets: &[(u16, Estimate)]| -> Result<(), String> {
            let kept = gif.as_ref().is_some_and(|g| g.wants(i));
            if let Some(v) = &mut video {
                v.write_drawn(f, |c| annotate_targets(c, targets))?;
            }
            if let Some(g) = gif.as_mut().filter(|_| kept) {
                let rgb = (f.width(), f.height(), host_tests::scene::to_rgb(f));
                g.push_drawn(i, rgb, |c| annotate_targets(c, targets));
            }
            Ok(())
        };
        draw(0, &first, &targets)?;
        let mut frames = 1usize;
        while !closed.get()
            && let Some(f) = src.next_frame()?
        {
            frames += 1;
            let out = group.step(&f).map_err(|e| format!("frame {frames}: {e}"))?;
            targets.clear();
            for t in &out {
                write(&Record::of(frames, &t.estimate).of_target(t.id.0))?;
                targets.push((t.id.0, t.estimate));
            }
            draw(frames - 1, &f, &targets)?;
            pb.set_position(frames as u64);
        }
        pb.finish_and_clear();
        drop(video);
        if let (Some(path), Some(g)) = (&a.gif, &gif) {
            g.write(path, None, (66 * g.every() as u32).min(1000))?;
        }
        if a.summary {
            let secs = t0.elapsed().as_secs_f64();
            eprintln!(
                "{frames} frames of {} targets in {secs:.2} s ({:.0} fps), peak memory {}",
                boxes.len(),
                frames as f64 / secs.max(1e-9),
                peak_memory()
            );
        }
        return Ok(());
    }
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
