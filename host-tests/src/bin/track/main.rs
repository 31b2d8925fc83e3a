//! Runs the tracker on OTB sequences or on the project's fixtures, writes the
//! track of each, and prints success AUC, precision@20 and ms/frame. One
//! module per subcommand: `run`, `convert`, `evaluate` (`otb` and
//! `fixture`), `score`, `starts` and `ablate` (its variants in `variants`),
//! with what several of them use in `shared`.

mod ablate;
mod convert;
mod evaluate;
mod run;
mod score;
mod shared;
mod starts;
mod variants;

use ablate::AblateOpts;
use clap::{Parser, Subcommand};
use host_tests::otb;
use host_tests::runner::Method;
use host_tests::source::RawSpec;
use pftrack::Config;
use shared::Split;
use std::path::PathBuf;
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
    /// similarity, the correlation filter's PSR (0 without it), the size
    /// change from the first box (see `tools/fit-confidence`).
    #[arg(long)]
    dump: Option<PathBuf>,
    /// Start from the first ground-truth box moved by DX of its width and
    /// DY of its height and scaled by SCALE about its centre, e.g.
    /// `--perturb 0.1,0,1` (OTB's spatial robustness evaluation; every
    /// frame is still scored against the truth).
    #[arg(long, value_name = "DX,DY,SCALE", allow_hyphen_values = true)]
    perturb: Option<otb::Perturb>,
}

#[derive(Subcommand)]
enum Command {
    /// Tracks your own footage from one box: a video as Y4M (a file or a
    /// pipe from ffmpeg), a folder of images or a raw camera dump; one JSON
    /// line per frame on standard output.
    Run(run::RunArgs),
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
    ///
    /// A folder with groundtruth.1.txt, groundtruth.2.txt, … instead (one
    /// x,y,w,h line per frame each, zero or NaN sizes where a target is
    /// absent), like a fixture of several targets, is tracked as one group
    /// of all its targets, each added from its first box in file order:
    /// one row per target (SEQ#1, SEQ#2, …), its outputs in SEQ.1.txt,
    /// SEQ.1.ms, SEQ.1.confidence, …, and each sequence's identity swaps
    /// (tracks claimed on another target's truth and not their own) below
    /// the table. A group's ms/frame is the whole group's.
    Otb {
        /// Sequence folders or .pft fixture files.
        #[arg(required = true)]
        seqs: Vec<PathBuf>,
        /// Track each target of a sequence of several alone, not as a group:
        /// target N by its own tracker with seed + N - 1, as the group seeds
        /// it, so that the two runs differ only by the group.
        #[arg(long)]
        alone: bool,
        #[command(flatten)]
        common: Common,
    },
    /// The project's fixture files (.pft); those of several targets as `otb` tracks them.
    Fixture {
        /// Fixture files.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// As for `otb`.
        #[arg(long)]
        alone: bool,
        #[command(flatten)]
        common: Common,
    },
    /// Scores result sets against ground truth: each result folder holds
    /// `<sequence>.txt` (x,y,w,h per frame, as `otb` writes) and optionally
    /// `<sequence>.ms` (median ms/frame). Prints one table and draws the
    /// success and precision plots of all sets.
    Score {
        /// OTB sequence folders (only the ground truth is read; a folder
        /// of several targets is scored as `<sequence>.1.txt`, … of each
        /// result folder).
        #[arg(long, required = true, num_args = 1..)]
        truth: Vec<PathBuf>,
        /// Result folders, as NAME=FOLDER or FOLDER (named after the
        /// folder); NAME=F1,F2,… scores several runs (e.g. seeds) as one,
        /// averaging each sequence's scores over them, and reports how far
        /// apart its runs are and, for a set of as many runs as the first,
        /// its difference with the first paired run by run (F1 with F1…).
        #[arg(long, required = true, num_args = 1..)]
        results: Vec<String>,
        /// Where to write success.png and precision.png.
        #[arg(long, default_value = "out")]
        plots: PathBuf,
        /// A tune / check division of the sequences: the table then has a
        /// mean AUC column for each split besides the overall one.
        #[arg(long)]
        split: Option<PathBuf>,
        /// Also a table of each sequence's AUC per set (the mean over its
        /// runs) and, for a set of several runs, how far apart its runs
        /// are on that sequence (the highest run's AUC less the lowest's).
        #[arg(long)]
        per_sequence: bool,
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

/// `error: …` on standard error for a failed command.
fn report(result: Result<(), String>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let mut alone = false;
    let (paths, mut common, ablation) = match cli.command {
        Command::Convert { input, output, raw } => return report(convert::command(&input, &output, raw)),
        Command::Run(args) => return report(run::command(&args)),
        Command::Score { truth, results, plots, split, per_sequence } => {
            let split = match split.as_deref().map(Split::load).transpose() {
                Ok(s) => s,
                Err(e) => return report(Err(e)),
            };
            return report(score::command(&truth, &results, &plots, split.as_ref(), per_sequence));
        }
        Command::Starts => {
            starts::command();
            return ExitCode::SUCCESS;
        }
        Command::Otb { seqs, alone: a, common } => {
            alone = a;
            (seqs, common, None)
        }
        Command::Fixture { files, alone: a, common } => {
            alone = a;
            (files, common, None)
        }
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
            Err(e) => return report(Err(e)),
        };
        let opts = AblateOpts { seeds, only: only.as_deref(), split, per_sequence, sre };
        return report(ablate::command(&paths, &opts, &common));
    }
    evaluate::command(&paths, &common, alone)
}
