//! Soak test: runs one tracker over a long generated video in which the
//! target keeps leaving and coming back, and checks that nothing drifts:
//! step time stays flat, memory stays constant, and the state machine never
//! sticks (every departure is reported lost, every return re-acquired).
//!
//!   cargo run --release -p host-tests --bin soak -- [--frames 100000] [--seed 1]
//!
//! Exits non-zero, saying why, if a check fails.

use clap::Parser;
use host_tests::metrics::median;
use pftrack::{BoundingBox, Config, Event, Frame, PixelFormat, TrackState, Tracker};
use std::process::ExitCode;
use std::time::Instant;

#[derive(Parser)]
#[command(about = "Long-run check: flat step time, constant memory, no stuck state")]
struct Args {
    /// Frames to run.
    #[arg(long, default_value_t = 100_000)]
    frames: usize,
    /// Tracker seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

const W: usize = 128;
const H: usize = 96;
/// One cycle: the target crosses the frame in view for `VISIBLE` frames, then
/// is away for `AWAY` frames.
const VISIBLE: usize = 120;
const AWAY: usize = 40;
/// A departure must be reported within this many frames, and a return
/// re-acquired within this many frames of the target being fully in view.
const LOST_WITHIN: usize = 10;
const FOUND_WITHIN: usize = 10;

/// The scene: a textured static background and a striped 20x24 target on a
/// horizontal path; RGB565. Rendering is a copy plus a sprite blit, so the
/// soak measures the tracker, not the renderer.
struct Scene {
    background: Vec<u8>,
    sprite: Vec<Option<[u8; 2]>>,
}

impl Scene {
    fn new() -> Self {
        let mut background = Vec::with_capacity(W * H * 2);
        for y in 0..H {
            for x in 0..W {
                let t = if (x / 3 + y / 3) % 2 == 0 { 20 } else { 0 };
                let c = [60 + t + (x / 16) as u8 * 8, 110 + t, 90 + t + (y / 16) as u8 * 10];
                background.extend_from_slice(&pftrack::frame::rgb_to_rgb565(c));
            }
        }
        let sprite = (0..24 * 20)
            .map(|i| {
                let (x, y) = ((i % 20) as f32 - 9.5, (i / 20) as f32 - 11.5);
                let inside = (x / 10.0).powi(2) + (y / 12.0).powi(2) <= 1.0;
                let c = if (i / 20 / 4) % 2 == 0 { [215, 45, 35] } else { [235, 200, 40] };
                inside.then(|| pftrack::frame::rgb_to_rgb565(c))
            })
            .collect();
        Scene { background, sprite }
    }

    /// The target's top-left corner in frame `t`, or `None` while it is away.
    fn position(t: usize) -> Option<(i32, i32)> {
        let phase = t % (VISIBLE + AWAY);
        (phase < VISIBLE).then(|| {
            // Enters from the left edge, leaves through the right one.
            let x = -20 + ((W as i32 + 20) * phase as i32) / VISIBLE as i32;
            let y = 30 + ((t / (VISIBLE + AWAY)) % 3) as i32 * 12;
            (x, y)
        })
    }

    fn render(&self, t: usize, out: &mut [u8]) {
        out.copy_from_slice(&self.background);
        if let Some((x0, y0)) = Self::position(t) {
            for (i, px) in self.sprite.iter().enumerate() {
                let (x, y) = (x0 + (i % 20) as i32, y0 + (i / 20) as i32);
                if let Some(c) = px
                    && (0..W as i32).contains(&x)
                    && (0..H as i32).contains(&y)
                {
                    let at = (y as usize * W + x as usize) * 2;
                    out[at..at + 2].copy_from_slice(c);
                }
            }
        }
    }

    /// Whether the whole target is in view in frame `t`.
    fn fully_visible(t: usize) -> bool {
        Self::position(t).is_some_and(|(x, _)| x >= 0 && x + 20 <= W as i32)
    }
}

fn frame(px: &[u8]) -> Result<Frame<'_>, pftrack::FrameError> {
    Frame::packed(px, W, H, PixelFormat::Rgb565)
}

/// Resident memory of this process in pages, from /proc (Linux).
fn resident_pages() -> Option<u64> {
    std::fs::read_to_string("/proc/self/statm").ok()?.split_whitespace().nth(1)?.parse().ok()
}

fn main() -> ExitCode {
    let args = Args::parse();
    let scene = Scene::new();
    let mut px = vec![0u8; W * H * 2];
    let mut tracker: Box<Tracker<100>> = match Tracker::new(Config::default(), args.seed) {
        Ok(t) => Box::new(t),
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    // Initialise where the target is first fully in view.
    let t0 = (0..VISIBLE).find(|&t| Scene::fully_visible(t)).unwrap_or(0);
    scene.render(t0, &mut px);
    let Some((x, y)) = Scene::position(t0) else { return ExitCode::FAILURE };
    let init = BoundingBox::new(x as f32, y as f32, 20.0, 24.0);
    match frame(&px).map_err(pftrack::Error::from).and_then(|f| tracker.init(&f, init)) {
        Ok(_) => {}
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    }

    let window = 2000.min(args.frames / 4).max(1);
    let (mut first_ms, mut last_ms) = (Vec::with_capacity(window), Vec::with_capacity(window));
    // Memory is sampled after a warm-up window, once the harness's own
    // buffers (timings, progress bar) have been allocated.
    let mut rss_start = None;
    let (mut lost, mut found, mut failures) = (0usize, 0usize, Vec::new());
    let mut away_since: Option<usize> = None;
    let mut back_since: Option<usize> = None;
    let pb = indicatif::ProgressBar::new(args.frames as u64);
    for t in t0 + 1..t0 + 1 + args.frames {
        scene.render(t, &mut px);
        let Ok(f) = frame(&px) else { return ExitCode::FAILURE };
        let start = Instant::now();
        let est = match tracker.step(&f) {
            Ok(e) => e,
            Err(e) => {
                eprintln!("error at frame {t}: {e}");
                return ExitCode::FAILURE;
            }
        };
        let ms = start.elapsed().as_secs_f64() * 1e3;
        let n = t - t0;
        if n <= window {
            first_ms.push(ms);
        } else if n > args.frames - window {
            last_ms.push(ms);
        }
        match est.event {
            Some(Event::LostTarget) => lost += 1,
            Some(Event::Reacquired) => found += 1,
            _ => {}
        }
        // The state machine must follow the scene.
        let present = Scene::position(t).is_some();
        if present {
            away_since = None;
        } else if away_since.is_none() {
            away_since = Some(t);
        }
        if Scene::fully_visible(t) {
            back_since.get_or_insert(t);
        } else {
            back_since = None;
        }
        if let Some(s) = away_since
            && t - s == LOST_WITHIN
            && est.state == TrackState::Tracking
        {
            failures.push(format!("frame {t}: still tracking {LOST_WITHIN} frames after the target left"));
        }
        if let Some(s) = back_since
            && t - s == FOUND_WITHIN
            && est.state != TrackState::Tracking
        {
            failures.push(format!("frame {t}: not tracking {FOUND_WITHIN} frames after the target came back"));
        }
        if n % 1000 == 0 {
            pb.set_position(n as u64);
        }
        if n == window {
            rss_start = resident_pages();
        }
    }
    pb.finish_and_clear();
    let rss_end = resident_pages();
    let cycles = args.frames / (VISIBLE + AWAY);
    let (m0, m1) = (median(&first_ms), median(&last_ms));
    println!("soak: {} frames of {W}x{H} RGB565, seed {}, {cycles} leave-and-return cycles", args.frames, args.seed);
    println!("  step time, median: first {window} frames {m0:.4} ms, last {window} frames {m1:.4} ms");
    println!("  lost {lost} times, re-acquired {found} times");
    println!(
        "  tracker size {} bytes (static); resident pages after warm-up {rss_start:?}, at the end {rss_end:?}",
        std::mem::size_of::<Tracker<100>>()
    );
    if m1 > 1.5 * m0 + 0.05 {
        failures.push(format!("step time grew from {m0:.4} to {m1:.4} ms"));
    }
    if let (Some(a), Some(b)) = (rss_start, rss_end)
        && b > a + 16
    {
        failures.push(format!("resident memory grew from {a} to {b} pages"));
    }
    if cycles > 1 && (lost + 1 < cycles || found + 1 < cycles) {
        failures.push(format!("{cycles} cycles but lost {lost} and re-acquired {found} times"));
    }
    if failures.is_empty() {
        println!("ok");
        ExitCode::SUCCESS
    } else {
        for f in failures.iter().take(20) {
            eprintln!("FAIL: {f}");
        }
        eprintln!("{} failures", failures.len());
        ExitCode::FAILURE
    }
}
