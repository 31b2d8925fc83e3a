//! Prints the bit-exact trace of a fixture, one line per frame, exactly as the
//! firmware prints it (same tracker type, configuration and seed), so that a
//! host run and an emulated Cortex-M run can be compared with `diff`.
//!
//! Usage: trace FIXTURE [SEED]

use host_tests::fixture::Fixture;
use pftrack::{Config, Tracker};
use std::path::Path;
use std::process::ExitCode;

/// The firmware's tracker type (firmware/src/main.rs): the defaults.
type FwTracker = Tracker<100>;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(path), seed) = (args.first(), args.get(1)) else {
        eprintln!("usage: trace FIXTURE [SEED]");
        return ExitCode::FAILURE;
    };
    let seed: u64 = match seed.map(|s| s.parse()) {
        None => 1,
        Some(Ok(s)) => s,
        Some(Err(_)) => {
            eprintln!("error: seed is not a number");
            return ExitCode::FAILURE;
        }
    };
    match run(Path::new(path), seed) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(path: &Path, seed: u64) -> Result<(), String> {
    let fx = Fixture::load(path)?;
    let mut tracker = Box::new(FwTracker::new(Config::default(), seed).map_err(|e| e.to_string())?);
    for (i, f) in fx.frames.iter().enumerate() {
        let frame = fx.frame(i).ok_or_else(|| format!("frame {i}: bad dimensions"))?;
        let est = if i == 0 { tracker.init(&frame, f.truth) } else { tracker.step(&frame) };
        let est = est.map_err(|e| format!("frame {i}: {e}"))?;
        println!("{i} {}", est.trace());
    }
    Ok(())
}
