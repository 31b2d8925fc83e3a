//! Prints the bit-exact trace of a fixture, one line per frame, exactly as
//! the firmware prints it (same tracker type, configuration and seed), so
//! that runs on different machines can be compared with `diff`. It depends
//! on nothing but the core and the fixture codecs, so it also builds for an
//! ARMv6 Linux device (see the README).
//!
//! Usage: pftrack-trace FIXTURE [SEED [pf|pf-sure|colour|meanshift|kalman|pf-gradient|pf-accurate|pf-accurate-no-pyramid]]
//! (`pf`: `Config::fast`, as the firmware's default build runs it;
//! `pf-accurate`: `Config::accurate`, the core's default)
//!
//! A fixture of several targets is tracked by a group of them all (the
//! particle filter; mean shift follows one target), one line per target
//! and frame: `FRAME TARGET TRACE`.

use pftrack::{Config, Frame, Group, MeanShift, MeanShiftConfig, Tracker};
use pftrack_fixture::{HEADER_LEN, Header, RECORD_META_LEN, RecordMeta};
use std::io::{Read, Write};
use std::process::ExitCode;

/// The firmware's tracker type (firmware/src/main.rs).
type FwTracker = Tracker<100>;

/// The firmware's group type, for fixtures of several targets.
type FwGroup = Group<3, 100>;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(path) = args.first() else {
        eprintln!(
            "usage: pftrack-trace FIXTURE [SEED [pf|pf-sure|colour|meanshift|kalman|pf-gradient|pf-accurate|pf-accurate-no-pyramid]]"
        );
        return ExitCode::FAILURE;
    };
    let seed = match args.get(1).map(|s| s.parse::<u64>()) {
        None => 1,
        Some(Ok(s)) => s,
        Some(Err(_)) => {
            eprintln!("error: seed is not a number");
            return ExitCode::FAILURE;
        }
    };
    let kind = args.get(2).map(String::as_str).unwrap_or("pf");
    match run(path, seed, kind) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {path}: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Streams the fixture record by record, as the firmware does.
fn run(path: &str, seed: u64, kind: &str) -> Result<(), String> {
    let mut file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let mut head = [0u8; HEADER_LEN];
    file.read_exact(&mut head).map_err(|_| "shorter than a fixture header".to_string())?;
    let h = Header::parse(&head).map_err(|e| e.to_string())?;
    let ms_config = match kind {
        "pf" | "pf-sure" | "colour" => None,
        "pf-gradient" | "pf-accurate" | "pf-accurate-no-pyramid" => None,
        "meanshift" => Some(MeanShiftConfig::default()),
        "kalman" => Some(MeanShiftConfig::kalman()),
        _ => {
            return Err(format!(
                "tracker `{kind}` is not pf, pf-sure, colour, meanshift, kalman, pf-gradient, pf-accurate or pf-accurate-no-pyramid"
            ));
        }
    };
    // `colour`: the particle filter without the correlation filter, as the
    // firmware built without its `correlation` feature runs it; `pf-sure`:
    // a share of the hypotheses after a confident frame, as the firmware's
    // `pf-sure` tracker and group observe.
    let config = match kind {
        "colour" => Config { correlation: None, ..Config::fast() },
        "pf-sure" => Config { sure_share: 0.6, ..Config::fast() },
        // As the firmware's `pf-gradient` tracker (its `gradient` feature).
        "pf-gradient" => Config { gradient: Some(pftrack::GradientCue::MEASURED), correlation: None, ..Config::fast() },
        // As the firmware's `pf-accurate` tracker.
        "pf-accurate" => Config::accurate(),
        // As the firmware's `pf-accurate` tracker in a build without the
        // core's `scale-pyramid` feature (its `gradient` feature alone).
        "pf-accurate-no-pyramid" => {
            let accurate = Config::accurate();
            let gradient = accurate.gradient.map(|g| pftrack::GradientCue { pyramid_pull: 0.0, ..g });
            Config { gradient, ..accurate }
        }
        _ => Config::fast(),
    };
    if h.targets > 1 {
        if ms_config.is_some() {
            return Err(format!("mean shift follows one target; this fixture has {}", h.targets));
        }
        return run_group(file, &h, config, seed);
    }
    let mut tracker = Box::new(FwTracker::new(config, seed).map_err(|e| e.to_string())?);
    let mut ms: Option<Box<MeanShift>> = match ms_config {
        Some(c) => Some(Box::new(MeanShift::new(c).map_err(|e| e.to_string())?)),
        None => None,
    };
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    let mut meta = [0u8; RECORD_META_LEN];
    let mut pixels = vec![0u8; h.frame_len()];
    for i in 0..h.frames {
        if file.read_exact(&mut meta).and_then(|_| file.read_exact(&mut pixels)).is_err() {
            return Err(format!("file ends inside frame {i}"));
        }
        let m = RecordMeta::parse(&meta, i).map_err(|e| e.to_string())?;
        let frame = Frame::new(&pixels, h.width, h.height, h.stride, h.format).map_err(|e| e.to_string())?;
        let est = match (ms.as_mut(), i) {
            (None, 0) => tracker.init(&frame, m.truth),
            (None, _) => tracker.step(&frame),
            (Some(t), 0) => t.init(&frame, m.truth),
            (Some(t), _) => t.step(&frame),
        };
        let est = est.map_err(|e| format!("frame {i}: {e}"))?;
        // A closed pipe is an error to report, not a panic (as println! would).
        writeln!(out, "{i} {}", est.trace()).map_err(|e| format!("standard output: {e}"))?;
    }
    Ok(())
}

/// [`run`] for a fixture of several targets: a group of them all, each
/// added from its first box in the fixture's order.
fn run_group(mut file: std::fs::File, h: &Header, config: Config, seed: u64) -> Result<(), String> {
    let mut group = Box::new(FwGroup::new(config, seed).map_err(|e| e.to_string())?);
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    let mut meta = vec![0u8; h.meta_len()];
    let mut pixels = vec![0u8; h.frame_len()];
    for i in 0..h.frames {
        if file.read_exact(&mut meta).and_then(|_| file.read_exact(&mut pixels)).is_err() {
            return Err(format!("file ends inside frame {i}"));
        }
        let truths = meta
            .chunks(RECORD_META_LEN)
            .map(|m| RecordMeta::parse(m, i))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| e.to_string())?;
        let frame = Frame::new(&pixels, h.width, h.height, h.stride, h.format).map_err(|e| e.to_string())?;
        let mut lines = Vec::new();
        if i == 0 {
            for m in &truths {
                let added = group.add(&frame, m.truth).map_err(|e| format!("frame 0: {e}"))?;
                lines.push((added.id.0, added.estimate));
            }
        } else {
            for t in group.step(&frame).map_err(|e| format!("frame {i}: {e}"))? {
                lines.push((t.id.0, t.estimate));
            }
        }
        for (id, est) in lines {
            writeln!(out, "{i} {id} {}", est.trace()).map_err(|e| format!("standard output: {e}"))?;
        }
    }
    Ok(())
}
