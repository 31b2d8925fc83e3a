//! `track convert`: any input `run` reads, written as YUV4MPEG2.

use crate::shared::create;
use host_tests::source::RawSpec;
use std::path::Path;

/// `track convert`: any input as a Y4M file, one frame at a time.
pub(crate) fn command(input: &str, output: &str, raw: Option<RawSpec>) -> Result<(), String> {
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
