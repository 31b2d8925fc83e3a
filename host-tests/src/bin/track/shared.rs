//! What several subcommands use: progress bars, output files, the peak
//! memory, the tune / check split, and number formats.

use indicatif::{ProgressBar, ProgressStyle};
use std::path::Path;

/// A progress bar of `len` steps, labelled `what`.
pub(crate) fn bar(len: usize, what: &str) -> ProgressBar {
    let b = ProgressBar::new(len as u64);
    b.set_style(
        ProgressStyle::with_template("{prefix:>12} {msg:8} [{bar:30}] {pos}/{len}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    b.set_message(what.to_string());
    b
}

/// A buffered writer to a new file at `path`; the error names the file.
pub(crate) fn create(path: &Path) -> Result<Box<dyn std::io::Write>, String> {
    let f = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(Box::new(std::io::BufWriter::new(f)))
}

/// The peak resident memory of this process (Linux's VmHWM) as the
/// summaries print it, e.g. `5.2 MB`.
pub(crate) fn peak_memory() -> String {
    let kb = std::fs::read_to_string("/proc/self/status").ok().and_then(|status| {
        let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
        line.split_whitespace().nth(1)?.parse::<u64>().ok()
    });
    kb.map_or_else(|| "unknown".to_string(), |kb| format!("{:.1} MB", (kb * 1024) as f64 / 1e6))
}

/// The tune / check division of sequences (`../shared/realseq-split.txt`:
/// lines `tune: A B …` and `check: C D …`, `#` comments).
pub(crate) struct Split {
    pub(crate) tune: Vec<String>,
    pub(crate) check: Vec<String>,
}

impl Split {
    pub(crate) fn load(path: &Path) -> Result<Split, String> {
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

    /// Which split lists the sequence folder `name`: `tune`, `check`, or
    /// `-` for neither.
    pub(crate) fn part_of(&self, name: &str) -> &'static str {
        if self.tune.iter().any(|n| n == name) {
            "tune"
        } else if self.check.iter().any(|n| n == name) {
            "check"
        } else {
            "-"
        }
    }
}

/// A fraction as a percentage with one decimal, `-` for none.
pub(crate) fn pct(v: Option<f64>) -> String {
    v.map(|v| format!("{:.1}%", 100.0 * v)).unwrap_or_else(|| "-".into())
}

/// A number with three decimals, `-` for none.
pub(crate) fn fmt3(v: Option<f64>) -> String {
    v.map(|v| format!("{v:.3}")).unwrap_or_else(|| "-".into())
}
