//! Where `track` reads frames from: a folder of images, a YUV4MPEG2 stream
//! (a `.y4m` file or standard input, as `ffmpeg -f yuv4mpegpipe` writes
//! it), a raw camera dump, or a fixture. Every source hands out one frame at
//! a time from a buffer it reuses, so memory does not grow with the length
//! of the input, and every error names the frame it happened in.

use pftrack::frame::yuv_to_rgb;
use pftrack::{BoundingBox, Frame, PixelFormat};
use pftrack_fixture::{HEADER_LEN, Header, RECORD_META_LEN, RecordMeta};
use std::cell::Cell;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};
use std::rc::Rc;

/// A source of frames, read one at a time.
pub trait FrameSource {
    /// Width and height of every frame.
    fn size(&self) -> (usize, usize);

    /// The next frame, `Ok(None)` at the end of the input. Errors read
    /// "frame N: what is wrong" (frames counted from 1).
    fn next_frame(&mut self) -> Result<Option<Frame<'_>>, String>;

    /// How many frames there are, when the source knows before reading them.
    fn frame_count(&self) -> Option<usize> {
        None
    }

    /// Frames per second as numerator and denominator, when the input says.
    fn rate(&self) -> Option<(usize, usize)> {
        None
    }
}

/// A raw stream's layout: `FORMAT:WxH`, e.g. `rgb565:320x240`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RawSpec {
    /// Pixel format of every frame.
    pub format: PixelFormat,
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
}

/// The raw formats by the names `--raw` takes.
pub const RAW_FORMATS: [(&str, PixelFormat); 6] = [
    ("rgb565", PixelFormat::Rgb565),
    ("rgb888", PixelFormat::Rgb888),
    ("yuyv", PixelFormat::Yuv422),
    ("gray8", PixelFormat::Gray8),
    ("i420", PixelFormat::I420),
    ("nv12", PixelFormat::Nv12),
];

impl std::str::FromStr for RawSpec {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let names = || RAW_FORMATS.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ");
        let (name, size) = s.split_once(':').ok_or_else(|| format!("`{s}` is not FORMAT:WxH"))?;
        let format = RAW_FORMATS
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(name))
            .map(|&(_, f)| f)
            .ok_or_else(|| format!("unknown raw format `{name}` (known: {})", names()))?;
        let (w, h) = size.split_once(['x', 'X']).ok_or_else(|| format!("`{size}` is not WxH"))?;
        let dim = |v: &str| v.trim().parse::<usize>().map_err(|_| format!("`{v}` is not a whole number of pixels"));
        let spec = RawSpec { format, width: dim(w)?, height: dim(h)? };
        // The core judges the size, exactly as when tracking.
        match Frame::new(&[], spec.width, spec.height, spec.width * format.bytes_per_pixel(), format) {
            Ok(_) | Err(pftrack::FrameError::BufferTooSmall { .. }) => Ok(spec),
            Err(e) => Err(format!("{s}: {e}")),
        }
    }
}

/// Opens `input` as a frame source: `-` is a YUV4MPEG2 stream on standard
/// input (or, with `raw`, a raw one), a folder holds images (or an OTB
/// sequence's `img/`), and a file is a `.y4m` stream, a `.pft` fixture or,
/// with `raw`, a raw dump.
pub fn open(input: &str, raw: Option<RawSpec>) -> Result<Box<dyn FrameSource>, String> {
    let path = Path::new(input);
    let reader = || -> Result<Box<dyn Read>, String> {
        if input == "-" {
            Ok(Box::new(std::io::stdin().lock()))
        } else {
            std::fs::File::open(path).map(|f| Box::new(f) as Box<dyn Read>).map_err(|e| format!("{input}: {e}"))
        }
    };
    if let Some(spec) = raw {
        return Ok(Box::new(Raw::new(reader()?, spec)));
    }
    if input == "-" {
        return Ok(Box::new(Y4m::new(reader()?).map_err(|e| format!("standard input: {e}"))?));
    }
    if path.is_dir() {
        let files = images_in(path)
            .or_else(|_| images_in(&path.join("img")))
            .map_err(|_| format!("{input}: no JPEG or PNG images in the folder or its img/"))?;
        return Ok(Box::new(ImageFolder::new(files)));
    }
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("y4m") => Ok(Box::new(Y4m::new(reader()?).map_err(|e| format!("{input}: {e}"))?)),
        Some("pft") => Ok(Box::new(FixtureStream::new(reader()?).map_err(|e| format!("{input}: {e}"))?)),
        _ if !path.exists() => Err(format!("{input}: no such file or folder")),
        _ => Err(format!(
            "{input}: not a folder of images, a .y4m file, a .pft fixture or `-`; for a raw camera dump give --raw FORMAT:WxH"
        )),
    }
}

/// Reads until `buf` is full or the input ends; returns the bytes read.
fn fill(r: &mut impl Read, buf: &mut [u8]) -> Result<usize, String> {
    let mut got = 0;
    while got < buf.len() {
        match r.read(buf.get_mut(got..).unwrap_or_default()) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e.to_string()),
        }
    }
    Ok(got)
}

/// A raw stream of back-to-back frames, each [`PixelFormat::frame_bytes`]
/// long with rows packed (stride = width × bytes per pixel).
pub struct Raw {
    reader: BufReader<Box<dyn Read>>,
    spec: RawSpec,
    buf: Vec<u8>,
    read: usize,
}

impl Raw {
    /// A raw stream of frames laid out as `spec` says.
    pub fn new(reader: Box<dyn Read>, spec: RawSpec) -> Self {
        let stride = spec.width * spec.format.bytes_per_pixel();
        let len = spec.format.frame_bytes(stride, spec.height).unwrap_or(0);
        Raw { reader: BufReader::with_capacity(1 << 16, reader), spec, buf: vec![0; len], read: 0 }
    }
}

impl FrameSource for Raw {
    fn size(&self) -> (usize, usize) {
        (self.spec.width, self.spec.height)
    }

    fn next_frame(&mut self) -> Result<Option<Frame<'_>>, String> {
        let n = self.read + 1;
        let got = fill(&mut self.reader, &mut self.buf).map_err(|e| format!("frame {n}: {e}"))?;
        if got == 0 {
            return Ok(None);
        }
        if got < self.buf.len() {
            return Err(format!(
                "frame {n}: the raw stream ends {got} bytes into the frame, which needs {} ({} frames of {}x{} {:?} and {got} bytes over)",
                self.buf.len(),
                self.read,
                self.spec.width,
                self.spec.height,
                self.spec.format
            ));
        }
        self.read = n;
        Frame::packed(&self.buf, self.spec.width, self.spec.height, self.spec.format)
            .map(Some)
            .map_err(|e| format!("frame {n}: {e}"))
    }
}

/// Counts the bytes read through it and keeps the first line (the Y4M
/// header), so that a frame cut short and a colour space the decoder does
/// not know can be told and named.
struct Tap<R> {
    inner: R,
    count: Rc<Cell<u64>>,
    head: Rc<std::cell::RefCell<Vec<u8>>>,
}

impl<R: Read> Read for Tap<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.count.set(self.count.get() + n as u64);
        let mut head = self.head.borrow_mut();
        let room = 256usize.saturating_sub(head.len());
        head.extend(buf.get(..n).unwrap_or_default().iter().take(room));
        Ok(n)
    }
}

/// How a Y4M colour space reaches the core.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Y4mLayout {
    /// 8-bit 4:2:0 with an even size: the planes as they are (I420).
    I420,
    /// 8-bit 4:2:2 with an even width: re-laid out as YUYV, the same samples.
    Yuyv,
    /// 8-bit luma only: GRAY8.
    Mono,
    /// Anything else of 8 bits (4:4:4, odd sizes): converted to RGB888 with
    /// the core's own YUV conversion.
    Rgb,
}

/// A YUV4MPEG2 stream (the `y4m` crate decodes it).
pub struct Y4m {
    decoder: y4m::Decoder<Tap<BufReader<Box<dyn Read>>>>,
    count: Rc<Cell<u64>>,
    layout: Y4mLayout,
    /// Chroma subsampling of the stream (1 or 2 per axis).
    sub: (usize, usize),
    buf: Vec<u8>,
    read: usize,
}

impl Y4m {
    /// Reads the stream's header.
    pub fn new(reader: Box<dyn Read>) -> Result<Self, String> {
        let count = Rc::new(Cell::new(0));
        let head = Rc::new(std::cell::RefCell::new(Vec::new()));
        let tap = Tap { inner: BufReader::with_capacity(1 << 16, reader), count: count.clone(), head: head.clone() };
        let decoder = y4m::decode(tap).map_err(|e| match e {
            y4m::Error::UnknownColorspace => {
                let head = head.borrow();
                let line = head.split(|&b| b == b'\n').next().unwrap_or_default();
                let name = String::from_utf8_lossy(line)
                    .split(' ')
                    .find_map(|t| t.strip_prefix('C').map(str::to_string))
                    .unwrap_or_default();
                format!("Y4M colour space `{name}` is not supported ({SUPPORTED})")
            }
            y4m::Error::EOF => "empty or cut short inside the Y4M header".to_string(),
            other => format!("not a YUV4MPEG2 stream ({other})"),
        })?;
        use y4m::Colorspace as C;
        let (w, h) = (decoder.get_width(), decoder.get_height());
        let (even_w, even_h) = (w % 2 == 0, h % 2 == 0);
        let (layout, sub) = match decoder.get_colorspace() {
            C::C420 | C::C420jpeg | C::C420paldv | C::C420mpeg2 if even_w && even_h => (Y4mLayout::I420, (2, 2)),
            C::C420 | C::C420jpeg | C::C420paldv | C::C420mpeg2 => (Y4mLayout::Rgb, (2, 2)),
            C::C422 if even_w => (Y4mLayout::Yuyv, (2, 1)),
            C::C422 => (Y4mLayout::Rgb, (2, 1)),
            C::C444 => (Y4mLayout::Rgb, (1, 1)),
            C::Cmono => (Y4mLayout::Mono, (1, 1)),
            other => {
                let name = format!("{other:?}");
                let name = name.strip_prefix('C').unwrap_or(&name).to_string();
                return Err(format!("Y4M colour space `{name}` is not supported ({SUPPORTED})"));
            }
        };
        let probe = match layout {
            Y4mLayout::I420 => PixelFormat::I420,
            Y4mLayout::Yuyv => PixelFormat::Yuv422,
            Y4mLayout::Mono => PixelFormat::Gray8,
            Y4mLayout::Rgb => PixelFormat::Rgb888,
        };
        if let Err(e) = Frame::new(&[], w, h, w * probe.bytes_per_pixel(), probe)
            && !matches!(e, pftrack::FrameError::BufferTooSmall { .. })
        {
            return Err(format!("Y4M frames of {w}x{h}: {e}"));
        }
        Ok(Y4m { decoder, count, layout, sub, buf: Vec::new(), read: 0 })
    }
}

/// The Y4M colour spaces [`Y4m`] reads.
const SUPPORTED: &str = "8-bit 420, 420jpeg, 420paldv, 420mpeg2, 422, 444 and mono are";

impl FrameSource for Y4m {
    fn size(&self) -> (usize, usize) {
        (self.decoder.get_width(), self.decoder.get_height())
    }

    fn rate(&self) -> Option<(usize, usize)> {
        let r = self.decoder.get_framerate();
        (r.num > 0 && r.den > 0).then_some((r.num, r.den))
    }

    fn next_frame(&mut self) -> Result<Option<Frame<'_>>, String> {
        let n = self.read + 1;
        let (w, h) = self.size();
        let before = self.count.get();
        let f = match self.decoder.read_frame() {
            Ok(f) => f,
            // The decoder says EOF for a clean end and for a frame cut
            // short alike: the byte count tells them apart.
            Err(y4m::Error::EOF) if self.count.get() == before => return Ok(None),
            Err(y4m::Error::EOF) => {
                return Err(format!(
                    "frame {n}: the Y4M stream ends {} bytes into the frame (truncated)",
                    self.count.get() - before
                ));
            }
            Err(e) => return Err(format!("frame {n}: bad Y4M frame ({e})")),
        };
        self.read = n;
        let (y, u, v) = (f.get_y_plane(), f.get_u_plane(), f.get_v_plane());
        // The decoder's planes live as long as its frame: copied out (a
        // memcpy: 0.35 MB for a 640x360 frame).
        self.buf.clear();
        let format = match self.layout {
            Y4mLayout::I420 => {
                self.buf.extend_from_slice(y);
                self.buf.extend_from_slice(u);
                self.buf.extend_from_slice(v);
                PixelFormat::I420
            }
            Y4mLayout::Mono => {
                self.buf.extend_from_slice(y);
                PixelFormat::Gray8
            }
            Y4mLayout::Yuyv => {
                for (row, (ur, vr)) in y.chunks_exact(w).zip(u.chunks_exact(w / 2).zip(v.chunks_exact(w / 2))) {
                    for ((pair, &cu), &cv) in row.chunks_exact(2).zip(ur).zip(vr) {
                        self.buf.extend_from_slice(&[pair[0], cu, pair[1], cv]);
                    }
                }
                PixelFormat::Yuv422
            }
            Y4mLayout::Rgb => {
                let (sx, sy) = self.sub;
                let cw = w.div_ceil(sx);
                for yy in 0..h {
                    for xx in 0..w {
                        let c = (yy / sy) * cw + xx / sx;
                        let at = |p: &[u8], i: usize| p.get(i).copied().unwrap_or(128);
                        let yuv = [at(y, yy * w + xx), at(u, c), at(v, c)];
                        self.buf.extend_from_slice(&yuv_to_rgb(yuv));
                    }
                }
                PixelFormat::Rgb888
            }
        };
        Frame::packed(&self.buf, w, h, format).map(Some).map_err(|e| format!("frame {n}: {e}"))
    }
}

/// The JPEG and PNG files directly in `dir`, sorted by name.
pub fn images_in(dir: &Path) -> Result<Vec<PathBuf>, String> {
    let rd = std::fs::read_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut files: Vec<PathBuf> = rd
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.extension()
                .and_then(|e| e.to_str())
                .map(|e| e.to_ascii_lowercase())
                .is_some_and(|e| matches!(e.as_str(), "jpg" | "jpeg" | "png"))
        })
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(format!("{}: no JPEG or PNG frames", dir.display()));
    }
    Ok(files)
}

/// A folder of JPEG or PNG images, sorted by name, decoded to RGB888 one
/// at a time.
pub struct ImageFolder {
    files: Vec<PathBuf>,
    size: (usize, usize),
    buf: Vec<u8>,
    read: usize,
}

impl ImageFolder {
    /// The images `files`, in that order.
    pub fn new(files: Vec<PathBuf>) -> Self {
        // The size comes from the first image's header (decoded in full when
        // its turn comes); 0x0 if it cannot be read, which that turn reports.
        let size = files
            .first()
            .and_then(|f| image::image_dimensions(f).ok())
            .map_or((0, 0), |(w, h)| (w as usize, h as usize));
        ImageFolder { files, size, buf: Vec::new(), read: 0 }
    }
}

impl FrameSource for ImageFolder {
    fn size(&self) -> (usize, usize) {
        self.size
    }

    fn frame_count(&self) -> Option<usize> {
        Some(self.files.len())
    }

    fn next_frame(&mut self) -> Result<Option<Frame<'_>>, String> {
        let n = self.read + 1;
        let Some(path) = self.files.get(self.read) else { return Ok(None) };
        let img = image::open(path).map_err(|e| format!("frame {n} ({}): {e}", path.display()))?.to_rgb8();
        let (w, h) = (img.width() as usize, img.height() as usize);
        if (w, h) != self.size {
            let (fw, fh) = self.size;
            return Err(format!("frame {n} ({}): {w}x{h}, but the first frame is {fw}x{fh}", path.display()));
        }
        self.buf = img.into_raw();
        self.read = n;
        Frame::packed(&self.buf, w, h, PixelFormat::Rgb888).map(Some).map_err(|e| format!("frame {n}: {e}"))
    }
}

/// A `.pft` fixture read record by record, as the firmware streams it.
pub struct FixtureStream {
    reader: BufReader<Box<dyn Read>>,
    header: Header,
    buf: Vec<u8>,
    read: usize,
}

impl FixtureStream {
    /// Reads and checks the fixture's header.
    pub fn new(reader: Box<dyn Read>) -> Result<Self, String> {
        let mut reader = BufReader::new(reader);
        let header = read_header(&mut reader)?;
        Ok(FixtureStream { reader, header, buf: vec![0; header.record_len()], read: 0 })
    }
}

impl FrameSource for FixtureStream {
    fn size(&self) -> (usize, usize) {
        (self.header.width, self.header.height)
    }

    fn frame_count(&self) -> Option<usize> {
        Some(self.header.frames as usize)
    }

    fn next_frame(&mut self) -> Result<Option<Frame<'_>>, String> {
        let n = self.read + 1;
        if self.read >= self.header.frames as usize {
            return Ok(None);
        }
        let got = fill(&mut self.reader, &mut self.buf).map_err(|e| format!("frame {n}: {e}"))?;
        if got < self.buf.len() {
            return Err(format!("frame {n}: the fixture ends {got} bytes into its {}-byte record", self.buf.len()));
        }
        let (meta, pixels) = self.buf.split_at(self.header.meta_len());
        for m in meta.chunks(RECORD_META_LEN) {
            RecordMeta::parse(m, self.read as u32).map_err(|e| e.to_string())?;
        }
        self.read = n;
        let h = self.header;
        Frame::new(pixels, h.width, h.height, h.stride, h.format).map(Some).map_err(|e| format!("frame {n}: {e}"))
    }
}

/// Reads and checks a fixture's header from the start of `r`.
fn read_header(r: &mut impl Read) -> Result<Header, String> {
    let mut head = [0u8; HEADER_LEN];
    let got = fill(r, &mut head)?;
    Header::parse(head.get(..got).unwrap_or_default()).map_err(|e| e.to_string())
}

/// The ground truth of every frame of the fixture at `path` (its first
/// target's, for a fixture of several), read by skipping from record to
/// record over the pixels. Frames where the target is entirely hidden or
/// gone get an empty box: they are not scored.
pub fn fixture_truth(path: &Path) -> Result<Vec<BoundingBox>, String> {
    Ok(fixture_truths(path)?.into_iter().next().unwrap_or_default())
}

/// Every target's ground truth in the fixture at `path`, target by target
/// in the order they are added, as [`fixture_truth`] reads the first's.
pub fn fixture_truths(path: &Path) -> Result<Vec<Vec<BoundingBox>>, String> {
    use std::io::{Seek, SeekFrom};
    let err = |e: String| format!("{}: {e}", path.display());
    let mut file = BufReader::new(std::fs::File::open(path).map_err(|e| err(e.to_string()))?);
    let header = read_header(&mut file).map_err(err)?;
    let targets = header.targets.max(1) as usize;
    let mut truths = vec![Vec::with_capacity(header.frames as usize); targets];
    let mut meta = [0u8; RECORD_META_LEN];
    for i in 0..header.frames {
        for truth in &mut truths {
            let got = fill(&mut file, &mut meta).map_err(err)?;
            let m = RecordMeta::parse(meta.get(..got).unwrap_or_default(), i).map_err(|e| err(e.to_string()))?;
            truth.push(if m.visible_permille == 0 { BoundingBox::default() } else { m.truth });
        }
        // Over the pixels.
        let skip = header.record_len() - targets * RECORD_META_LEN;
        file.seek(SeekFrom::Current(skip as i64)).map_err(|e| err(e.to_string()))?;
    }
    Ok(truths)
}
