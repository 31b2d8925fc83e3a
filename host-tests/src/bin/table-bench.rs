//! When does the likelihood table beat per-particle histograms? Runs the
//! same sequences with per-particle histograms and with the table (both at
//! a fixed target size), for several particle counts, and prints the median
//! ms per frame of each. Per-particle cost grows with N; the table's with
//! the area the particles cover.
//!
//! Usage: table-bench SEQ... (OTB folders or .pft fixtures)

use host_tests::otb;
use pftrack::{Config, Frame, PixelFormat, TableMode, Tracker};
use rand_xoshiro::Xoshiro128PlusPlus;
use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

struct Seq {
    name: String,
    w: usize,
    h: usize,
    stride: usize,
    format: PixelFormat,
    frames: Vec<Vec<u8>>,
    init: pftrack::BoundingBox,
}

fn load(p: &Path) -> Result<Seq, String> {
    if p.is_file() {
        let fx = host_tests::fixture::Fixture::load(p)?;
        let init = fx.frames.first().map(|f| f.truth).ok_or("empty fixture")?;
        return Ok(Seq {
            name: p.file_stem().and_then(|s| s.to_str()).unwrap_or("").into(),
            w: fx.width,
            h: fx.height,
            stride: fx.stride,
            format: fx.format,
            frames: fx.frames.into_iter().map(|f| f.pixels).collect(),
            init,
        });
    }
    let s = otb::load(p, |_, _| {})?;
    let init = *s.truth.first().ok_or("no ground truth")?;
    Ok(Seq {
        name: s.name,
        w: s.width,
        h: s.height,
        stride: s.width * 3,
        format: PixelFormat::Rgb888,
        frames: s.frames,
        init,
    })
}

/// A [`run`] for one particle count.
type Runner = fn(&Seq, bool) -> Result<f64, String>;

/// Median ms per step of a tracker with `N` particles.
fn run<const N: usize>(seq: &Seq, table: bool) -> Result<f64, String> {
    let config = Config {
        table: table.then_some(TableMode { spacing: 1 }),
        dynamics: pftrack::Dynamics { scale_noise: 0.0, ..Config::default().dynamics },
        ..Config::default()
    };
    let mut t: Box<Tracker<N, 512, 16384, Xoshiro128PlusPlus, 16384>> =
        Box::new(Tracker::new(config, 1).map_err(|e| e.to_string())?);
    fn frame<'a>(seq: &Seq, px: &'a [u8]) -> Result<Frame<'a>, String> {
        Frame::new(px, seq.w, seq.h, seq.stride, seq.format).map_err(|e| e.to_string())
    }
    let first = seq.frames.first().ok_or("no frames")?;
    t.init(&frame(seq, first)?, seq.init).map_err(|e| e.to_string())?;
    let mut ms = Vec::new();
    for px in seq.frames.iter().skip(1) {
        let f = frame(seq, px)?;
        let t0 = Instant::now();
        t.step(&f).map_err(|e| e.to_string())?;
        ms.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    Ok(host_tests::metrics::median(&ms))
}

fn main() -> ExitCode {
    let paths: Vec<String> = std::env::args().skip(1).collect();
    if paths.is_empty() {
        eprintln!("usage: table-bench SEQ...");
        return ExitCode::FAILURE;
    }
    println!("median ms/frame, fixed target size, spacing 1 (table) vs per-particle histograms");
    println!("| sequence | N | per-particle | table |");
    println!("|---|---|---|---|");
    for p in &paths {
        let seq = match load(Path::new(p)) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("error: {p}: {e}");
                return ExitCode::FAILURE;
            }
        };
        let rows: [(usize, Runner); 5] =
            [(25, run::<25>), (100, run::<100>), (400, run::<400>), (1600, run::<1600>), (6400, run::<6400>)];
        for (n, f) in rows {
            match (f(&seq, false), f(&seq, true)) {
                (Ok(a), Ok(b)) => println!("| {} | {n} | {a:.3} | {b:.3} |", seq.name),
                (Err(e), _) | (_, Err(e)) => {
                    eprintln!("error: {}: {e}", seq.name);
                    return ExitCode::FAILURE;
                }
            }
        }
    }
    ExitCode::SUCCESS
}
