//! OTB-format sequences: a folder with `img/` (frames sorted by name, JPEG or
//! PNG) and `groundtruth.txt` (one `x,y,w,h` per line), or for several
//! targets `groundtruth.1.txt`, `groundtruth.2.txt`, … (one per target).

use crate::source::{FrameSource, ImageFolder, images_in};
use pftrack::BoundingBox;
use std::path::{Path, PathBuf};

/// Parses ground truth: one box per line, values separated by commas, tabs
/// or spaces. Blank lines are skipped. Errors name the line.
pub fn parse_groundtruth(text: &str) -> Result<Vec<BoundingBox>, String> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        let vals: Vec<&str> = line.split([',', '\t', ' ']).filter(|s| !s.is_empty()).collect();
        if vals.len() != 4 {
            return Err(format!("line {}: expected 4 values x,y,w,h, found {}", i + 1, vals.len()));
        }
        let mut v = [0f32; 4];
        for (slot, s) in v.iter_mut().zip(&vals) {
            // OTB marks absent targets with NaN; keep them (they are not scored).
            *slot = s.parse::<f32>().map_err(|_| format!("line {}: `{s}` is not a number", i + 1))?;
        }
        out.push(BoundingBox::new(v[0], v[1], v[2], v[3]));
    }
    if out.is_empty() {
        return Err("no boxes".into());
    }
    Ok(out)
}

/// Parses a track's confidences (`<sequence>.confidence` beside its boxes):
/// one number per line, for each frame after the first (the first box is
/// given, not tracked). Blank lines are skipped. Errors name the line.
pub fn parse_confidences(text: &str) -> Result<Vec<f32>, String> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let v = line.trim().parse::<f32>().map_err(|_| format!("line {}: `{}` is not a number", i + 1, line.trim()))?;
        if v.is_nan() {
            return Err(format!("line {}: NaN is not a confidence", i + 1));
        }
        out.push(v);
    }
    Ok(out)
}

/// The frame files of a sequence (in its `img/`), sorted by name.
pub fn list_images(dir: &Path) -> Result<Vec<PathBuf>, String> {
    images_in(&dir.join("img"))
}

/// An OTB sequence opened for streaming: its ground truth, read whole (a
/// few bytes per frame), and its frames, decoded one at a time.
pub struct Stream {
    /// The folder's name.
    pub name: String,
    /// Ground truth, one box per frame, for each target: one list from
    /// `groundtruth.txt`, or one per `groundtruth.N.txt` in the order of N.
    pub truths: Vec<Vec<BoundingBox>>,
    /// The frames.
    pub frames: ImageFolder,
}

/// The ground-truth files of a sequence folder: `groundtruth.txt`, or
/// `groundtruth.1.txt` to `groundtruth.K.txt` with none missing between.
/// A folder that cannot be listed gives `groundtruth.txt`, so that reading
/// it names the file that is missing.
pub fn groundtruth_files(dir: &Path) -> Result<Vec<PathBuf>, String> {
    let single = dir.join("groundtruth.txt");
    let Ok(rd) = std::fs::read_dir(dir) else { return Ok(vec![single]) };
    let mut numbers: Vec<u32> = rd
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter_map(|n| n.strip_prefix("groundtruth.")?.strip_suffix(".txt")?.parse().ok())
        .collect();
    numbers.sort_unstable();
    if numbers.is_empty() {
        return Ok(vec![single]);
    }
    if single.exists() {
        return Err(format!("{}: both groundtruth.txt and groundtruth.N.txt: one target or several?", dir.display()));
    }
    if let Some((k, n)) = numbers.iter().enumerate().find(|&(k, &n)| n as usize != k + 1) {
        return Err(format!("{}: groundtruth.{n}.txt but no groundtruth.{}.txt", dir.display(), k + 1));
    }
    Ok(numbers.iter().map(|n| dir.join(format!("groundtruth.{n}.txt"))).collect())
}

/// Opens a sequence folder, checking that frames and every target's ground
/// truth agree in number.
pub fn open(dir: &Path) -> Result<Stream, String> {
    let name = dir
        .file_name()
        .and_then(|n| n.to_str())
        .ok_or_else(|| format!("{}: not a sequence folder", dir.display()))?
        .to_string();
    let gt_paths = groundtruth_files(dir)?;
    let mut truths = Vec::new();
    for gt_path in &gt_paths {
        let text = std::fs::read_to_string(gt_path).map_err(|e| format!("{}: {e}", gt_path.display()))?;
        truths.push(parse_groundtruth(&text).map_err(|e| format!("{}: {e}", gt_path.display()))?);
    }
    let files = list_images(dir)?;
    for (truth, gt_path) in truths.iter().zip(&gt_paths) {
        if files.len() != truth.len() {
            let gt = gt_path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
            let boxes = if gt == "groundtruth.txt" { String::new() } else { format!(" ({gt})") };
            return Err(format!(
                "{}: {} frames in img/ but {} ground-truth boxes{boxes}",
                dir.display(),
                files.len(),
                truth.len()
            ));
        }
    }
    Ok(Stream { name, truths, frames: ImageFolder::new(files) })
}

/// A decoded OTB sequence, frames as packed RGB888.
pub struct Sequence {
    /// The folder's name.
    pub name: String,
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Packed RGB888 frames.
    pub frames: Vec<Vec<u8>>,
    /// Ground truth, one box per frame.
    pub truth: Vec<BoundingBox>,
}

/// Loads and decodes a whole sequence into memory (for studies that run it
/// many times), checking that frames and ground truth agree. `progress` is
/// called after each decoded frame. A folder of several targets is refused:
/// what loads whole scores one target a sequence.
pub fn load(dir: &Path, mut progress: impl FnMut(usize, usize)) -> Result<Sequence, String> {
    let Stream { name, truths, mut frames } = open(dir)?;
    let [truth] = <[_; 1]>::try_from(truths)
        .map_err(|t| format!("{}: {} targets; only one target a sequence is scored here", dir.display(), t.len()))?;
    let n = frames.frame_count().unwrap_or(0);
    let (width, height) = frames.size();
    let mut decoded = Vec::with_capacity(n);
    while let Some(f) = frames.next_frame().map_err(|e| format!("{}: {e}", dir.display()))? {
        decoded.push(host_bytes(&f));
        progress(decoded.len(), n);
    }
    Ok(Sequence { name, width, height, frames: decoded, truth })
}

/// A change to the first box a run starts from, as OTB's spatial
/// robustness evaluation (SRE, Wu et al. 2013) makes: the box moves by
/// `dx` of its width and `dy` of its height, and its width and height are
/// multiplied by `scale` about its centre. Both trackers of a comparison
/// start from the same changed box, so one lucky or unlucky start does not
/// decide a sequence.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Perturb {
    /// Shift right, in widths of the box.
    pub dx: f32,
    /// Shift down, in heights of the box.
    pub dy: f32,
    /// Factor on width and height, about the centre.
    pub scale: f32,
}

/// The twelve starts of OTB's spatial robustness evaluation: the box moved
/// by a tenth of its width and/or height in eight directions (left, right,
/// up, down, then the four corners), or scaled by 0.8, 0.9, 1.1 and 1.2.
pub const SRE_STARTS: [Perturb; 12] = {
    const fn p(dx: f32, dy: f32, scale: f32) -> Perturb {
        Perturb { dx, dy, scale }
    }
    [
        p(-0.1, 0.0, 1.0),
        p(0.1, 0.0, 1.0),
        p(0.0, -0.1, 1.0),
        p(0.0, 0.1, 1.0),
        p(-0.1, -0.1, 1.0),
        p(0.1, -0.1, 1.0),
        p(-0.1, 0.1, 1.0),
        p(0.1, 0.1, 1.0),
        p(0.0, 0.0, 0.8),
        p(0.0, 0.0, 0.9),
        p(0.0, 0.0, 1.1),
        p(0.0, 0.0, 1.2),
    ]
};

impl std::fmt::Display for Perturb {
    /// As [`Perturb`] parses it: `DX,DY,SCALE`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{},{},{}", self.dx, self.dy, self.scale)
    }
}

impl Perturb {
    /// The changed box.
    pub fn apply(&self, b: &BoundingBox) -> BoundingBox {
        let (cx, cy) = (b.x + b.width * (0.5 + self.dx), b.y + b.height * (0.5 + self.dy));
        let (w, h) = (b.width * self.scale, b.height * self.scale);
        BoundingBox::new(cx - w / 2.0, cy - h / 2.0, w, h)
    }
}

impl std::str::FromStr for Perturb {
    type Err = String;

    /// `DX,DY,SCALE`, e.g. `0.1,0,1` or `0,0,0.8`.
    fn from_str(s: &str) -> Result<Self, String> {
        let v: Vec<f32> = s
            .split(',')
            .map(|t| t.trim().parse::<f32>())
            .collect::<Result<_, _>>()
            .map_err(|_| format!("`{s}` is not three numbers DX,DY,SCALE"))?;
        let [dx, dy, scale] = v[..] else { return Err(format!("`{s}` is not three numbers DX,DY,SCALE")) };
        if !(dx.is_finite() && dy.is_finite() && scale.is_finite() && scale > 0.0) {
            return Err(format!("`{s}`: shifts must be finite and the scale above 0"));
        }
        Ok(Perturb { dx, dy, scale })
    }
}

/// The packed RGB888 bytes of an RGB888 frame.
fn host_bytes(f: &pftrack::Frame<'_>) -> Vec<u8> {
    (0..f.height()).filter_map(|y| f.row(y)).flatten().copied().collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn separators_and_errors() {
        let g = parse_groundtruth("1,2,3,4\n5\t6\t7\t8\n\n9 10 11 12\n1.5, 2.5, 3, 4\n").unwrap();
        assert_eq!(g.len(), 4);
        assert_eq!(g[1], BoundingBox::new(5.0, 6.0, 7.0, 8.0));
        assert_eq!(g[3].x, 1.5);
        assert!(parse_groundtruth("1,2,3\n").unwrap_err().contains("line 1"));
        assert!(parse_groundtruth("1,2,3,4\n1,2,x,4").unwrap_err().contains("line 2"));
        assert!(parse_groundtruth("").is_err());
    }

    #[test]
    fn one_groundtruth_file_or_numbered_ones_without_a_gap() {
        // Reason: the layouts `open` reads: groundtruth.txt alone (also
        // when missing, so that reading it names the file), or
        // groundtruth.1.txt up to .K.txt in number order (10 after 9, not
        // after 1); both kinds, or a number missing, are refused.
        let dir = std::env::temp_dir().join(format!("pftrack-otb-gt-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let names = |v: Vec<PathBuf>| -> Vec<String> {
            v.iter().map(|p| p.file_name().unwrap().to_string_lossy().into_owned()).collect()
        };
        assert_eq!(names(groundtruth_files(&dir).unwrap()), ["groundtruth.txt"]);
        for n in (1..=10).rev() {
            std::fs::write(dir.join(format!("groundtruth.{n}.txt")), "").unwrap();
        }
        let got = names(groundtruth_files(&dir).unwrap());
        assert_eq!((got.len(), got[8].as_str(), got[9].as_str()), (10, "groundtruth.9.txt", "groundtruth.10.txt"));
        std::fs::remove_file(dir.join("groundtruth.2.txt")).unwrap();
        assert!(groundtruth_files(&dir).unwrap_err().contains("no groundtruth.2.txt"));
        std::fs::write(dir.join("groundtruth.2.txt"), "").unwrap();
        std::fs::write(dir.join("groundtruth.txt"), "").unwrap();
        assert!(groundtruth_files(&dir).unwrap_err().contains("both"));
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn confidences_and_errors() {
        assert_eq!(parse_confidences("0.5\n\n 1\n0.25 \n").unwrap(), vec![0.5, 1.0, 0.25]);
        assert_eq!(parse_confidences("").unwrap(), Vec::<f32>::new());
        assert!(parse_confidences("0.5\nx\n").unwrap_err().contains("line 2"));
        assert!(parse_confidences("NaN\n").unwrap_err().contains("line 1"));
    }

    #[test]
    fn perturbed_start() {
        // A 20x10 box at (100, 50): centre (110, 55).
        let b = BoundingBox::new(100.0, 50.0, 20.0, 10.0);
        // 10% of the width right and of the height up: centre (112, 54).
        let p: Perturb = "0.1,-0.1,1".parse().unwrap();
        assert_eq!(p.apply(&b), BoundingBox::new(102.0, 49.0, 20.0, 10.0));
        // 0.8 of the size about the same centre: 16x8 at (102, 51).
        let p: Perturb = "0,0,0.8".parse().unwrap();
        assert_eq!(p.apply(&b), BoundingBox::new(102.0, 51.0, 16.0, 8.0));
        assert!("0,0".parse::<Perturb>().is_err());
        assert!("0,0,0".parse::<Perturb>().is_err());
        assert!("nan,0,1".parse::<Perturb>().is_err());
        // What `track starts` prints parses back to the same start.
        for p in SRE_STARTS {
            assert_eq!(p.to_string().parse::<Perturb>(), Ok(p));
        }
    }
}
