//! Writes the committed fixture set (`fixtures/*.pft`, and the scenes of
//! several targets in `fixtures/groups/`) from the scene
//! generator, or checks that the committed files are what it generates.

use clap::Parser;
use host_tests::scene::{audit_catalogue, catalogue, generate, throughput_scene};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(about = "Generate the synthetic fixtures with exact ground truth")]
struct Args {
    /// Output folder.
    #[arg(long, default_value = "fixtures")]
    out_dir: PathBuf,
    /// Compare with the files in --out-dir instead of writing them.
    #[arg(long)]
    check: bool,
    /// Write the speed audit's scenes instead of the committed set.
    #[arg(long)]
    audit: bool,
    /// Write the throughput benchmark's scene instead of the committed set.
    #[arg(long)]
    throughput: bool,
}

fn main() -> ExitCode {
    let args = Args::parse();
    if !args.check
        && let Err(e) = std::fs::create_dir_all(&args.out_dir)
    {
        eprintln!("error: {}: {e}", args.out_dir.display());
        return ExitCode::FAILURE;
    }
    let mut ok = true;
    let specs = match (args.audit, args.throughput) {
        (true, _) => audit_catalogue(),
        (_, true) => vec![throughput_scene()],
        _ => catalogue(),
    };
    for spec in specs {
        let bytes = generate(&spec).to_bytes();
        let path = args.out_dir.join(format!("{}.pft", spec.name));
        if args.check {
            match std::fs::read(&path) {
                Ok(old) if old == bytes => println!("{}: matches", path.display()),
                Ok(_) => {
                    eprintln!("error: {}: differs from the generator's output", path.display());
                    ok = false;
                }
                Err(e) => {
                    eprintln!("error: {}: {e}", path.display());
                    ok = false;
                }
            }
        } else if let Err(e) =
            path.parent().map_or(Ok(()), std::fs::create_dir_all).and_then(|_| std::fs::write(&path, &bytes))
        {
            eprintln!("error: {}: {e}", path.display());
            ok = false;
        } else {
            println!(
                "{}: {} frames {:?} {}x{}, {} bytes",
                path.display(),
                spec.frames,
                spec.format,
                spec.width,
                spec.height,
                bytes.len()
            );
        }
    }
    if ok { ExitCode::SUCCESS } else { ExitCode::FAILURE }
}
