//! Borrowed views of raw camera frames.
//!
//! A [`Frame`] is a checked window onto a byte buffer as a camera, a DMA
//! engine or a video decoder wrote it: width, height, a row stride in bytes
//! (rows may be padded), and a [`PixelFormat`]. Planar YUV 4:2:0 frames
//! ([`PixelFormat::I420`], [`PixelFormat::Nv12`]) are a luma plane plus
//! chroma planes, each with its own stride, in one buffer or in several.
//! Construction validates every dimension against the buffers once, so the
//! pixel loops afterwards only need cheap, non-panicking slice accesses.

use crate::error::{ChromaPlane, FrameError};

/// The largest accepted width or height, in pixels.
///
/// It keeps every histogram sum below `2^32` (see [`crate::scalar::KERNEL_ONE`])
/// and every coordinate product inside `i32`.
pub const MAX_DIMENSION: usize = 4096;

/// A pixel layout, as camera sensors, their DMA engines and video decoders
/// deliver it.
///
/// Every YUV format is read as full-range BT.601 (the JPEG convention, Y and
/// chroma over 0..=255). Studio-range video (Y over 16..=235) reads slightly
/// less saturated; the tracker compares a frame only with models learnt
/// from the same source, so this shifts nothing it relies on.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PixelFormat {
    /// 16-bit RGB 5:6:5, little-endian: red in bits 15..11, green 10..5, blue 4..0.
    Rgb565,
    /// 24-bit RGB, bytes in the order R, G, B.
    Rgb888,
    /// YUV 4:2:2 packed as Y0 U Y1 V (YUYV): two pixels share one U and V.
    /// The width must be even.
    Yuv422,
    /// 8-bit luminance.
    Gray8,
    /// Planar YUV 4:2:0 (YUV420p): a Y plane, then a U plane, then a V
    /// plane, each chroma sample shared by a 2x2 block of pixels. Width and
    /// height must be even. What video decoders and most Linux cameras give.
    I420,
    /// Semi-planar YUV 4:2:0: a Y plane, then one plane of interleaved U, V
    /// pairs, each pair shared by a 2x2 block of pixels. Width and height
    /// must be even. What many camera ISPs and hardware decoders give.
    Nv12,
}

impl PixelFormat {
    /// Bytes per pixel of a row as [`Frame::new`]'s stride counts it: YUV
    /// 4:2:2 averages 2 per pixel (4 bytes per pair), and the planar formats
    /// count their luma plane's 1.
    pub const fn bytes_per_pixel(self) -> usize {
        match self {
            PixelFormat::Rgb565 | PixelFormat::Yuv422 => 2,
            PixelFormat::Rgb888 => 3,
            PixelFormat::Gray8 | PixelFormat::I420 | PixelFormat::Nv12 => 1,
        }
    }

    /// Whether the format keeps luma and chroma in separate planes.
    pub const fn is_planar(self) -> bool {
        matches!(self, PixelFormat::I420 | PixelFormat::Nv12)
    }

    /// The bytes of one whole frame in one buffer, every row padded to its
    /// plane's stride, with (luma) row stride `stride`: what a fixture
    /// record or one frame of a raw stream holds. The planes follow each
    /// other as [`Frame::new`] lays them out. `None` if it overflows.
    pub const fn frame_bytes(self, stride: usize, height: usize) -> Option<usize> {
        let Some(luma) = stride.checked_mul(height) else { return None };
        let chroma = match self {
            // Two planes of half the stride, half the height.
            PixelFormat::I420 => (stride / 2) * (height / 2) * 2,
            // One plane of the full stride, half the height.
            PixelFormat::Nv12 => stride * (height / 2),
            _ => 0,
        };
        luma.checked_add(chroma)
    }

    /// The format's code in the fixture file format (stable; see the README).
    pub const fn code(self) -> u16 {
        match self {
            PixelFormat::Rgb565 => 1,
            PixelFormat::Rgb888 => 2,
            PixelFormat::Yuv422 => 3,
            PixelFormat::Gray8 => 4,
            PixelFormat::I420 => 5,
            PixelFormat::Nv12 => 6,
        }
    }

    /// The format with the given fixture code, if there is one.
    pub const fn from_code(code: u16) -> Option<Self> {
        match code {
            1 => Some(PixelFormat::Rgb565),
            2 => Some(PixelFormat::Rgb888),
            3 => Some(PixelFormat::Yuv422),
            4 => Some(PixelFormat::Gray8),
            5 => Some(PixelFormat::I420),
            6 => Some(PixelFormat::Nv12),
            _ => None,
        }
    }
}

/// One plane of a planar frame: its bytes and its row stride, as a camera
/// driver or decoder hands them over (V4L2's multi-planar buffers, FFmpeg's
/// `data[i]` and `linesize[i]`).
#[derive(Copy, Clone, Debug)]
pub struct Plane<'a> {
    /// The plane's bytes, from its first row.
    pub data: &'a [u8],
    /// The distance in bytes between the starts of two rows.
    pub stride: usize,
}

impl<'a> Plane<'a> {
    /// A plane of `data` with rows `stride` bytes apart.
    pub const fn new(data: &'a [u8], stride: usize) -> Self {
        Plane { data, stride }
    }

    /// Checks that `rows` rows of `row_bytes` fit (the last row needs no
    /// padding); the errors name `chroma`, or are the luma plane's (or a
    /// packed frame's) with `None`.
    fn check(&self, rows: usize, row_bytes: usize, chroma: Option<ChromaPlane>) -> Result<(), FrameError> {
        let (stride, got) = (self.stride, self.data.len());
        if stride < row_bytes {
            return Err(match chroma {
                None => FrameError::StrideTooSmall { stride, row_bytes },
                Some(plane) => FrameError::ChromaStrideTooSmall { plane, stride, row_bytes },
            });
        }
        let too_small = |needed| match chroma {
            None => FrameError::BufferTooSmall { needed, got },
            Some(plane) => FrameError::ChromaTooSmall { plane, needed, got },
        };
        let needed = stride
            .checked_mul(rows.saturating_sub(1))
            .and_then(|b| b.checked_add(row_bytes))
            .ok_or(too_small(usize::MAX))?;
        if got < needed {
            return Err(too_small(needed));
        }
        Ok(())
    }
}

/// The chroma planes of a planar frame: U and V for I420, the interleaved
/// plane twice for NV12; empty for the packed formats.
type Chroma<'a> = [Plane<'a>; 2];

/// The chroma of a packed frame: none.
const NO_CHROMA: Chroma<'static> = [Plane::new(&[], 0), Plane::new(&[], 0)];

/// A validated, borrowed view of one frame.
///
/// ```
/// use pftrack::{Frame, PixelFormat};
///
/// // A 4x2 GRAY8 image whose rows are padded to 8 bytes.
/// let buf = [0u8; 8 + 4];
/// let frame = Frame::new(&buf, 4, 2, 8, PixelFormat::Gray8)?;
/// assert_eq!((frame.width(), frame.height()), (4, 2));
///
/// // One byte short of the last row: a typed error, not a panic.
/// assert!(Frame::new(&buf[..11], 4, 2, 8, PixelFormat::Gray8).is_err());
/// # Ok::<(), pftrack::FrameError>(())
/// ```
///
/// A planar frame in one buffer, or in one buffer per plane:
///
/// ```
/// use pftrack::{Frame, PixelFormat, Plane};
///
/// // 4x2 I420: 8 bytes of Y, then 2 of U and 2 of V (one per 2x2 block).
/// let buf = [16u8, 16, 16, 16, 16, 16, 16, 16, 128, 128, 128, 128];
/// let whole = Frame::packed(&buf, 4, 2, PixelFormat::I420)?;
/// let (y, uv) = buf.split_at(8);
/// let (u, v) = uv.split_at(2);
/// let split = Frame::i420(Plane::new(y, 4), Plane::new(u, 2), Plane::new(v, 2), 4, 2)?;
/// assert_eq!(whole.rgb(3, 1), split.rgb(3, 1));
/// assert_eq!(whole.rgb(3, 1), Some([16, 16, 16]));
/// # Ok::<(), pftrack::FrameError>(())
/// ```
#[derive(Copy, Clone, Debug)]
pub struct Frame<'a> {
    /// The pixels, or for a planar format the luma plane.
    data: &'a [u8],
    width: usize,
    height: usize,
    stride: usize,
    format: PixelFormat,
    chroma: Chroma<'a>,
}

impl<'a> Frame<'a> {
    /// Checks the dimensions against the buffer and returns a view.
    ///
    /// `stride` is the distance in bytes between the starts of two rows; it
    /// must be at least `width * bytes_per_pixel`. The buffer must hold
    /// `stride * (height - 1) + width * bytes_per_pixel` bytes (the last row
    /// needs no padding); longer buffers are accepted.
    ///
    /// A planar format takes its planes one after the other in `data`, as
    /// [`PixelFormat::frame_bytes`] counts them: the Y plane's `height` rows
    /// `stride` apart, then for I420 the U and the V plane, each `height / 2`
    /// rows `stride / 2` apart, and for NV12 the UV plane, `height / 2` rows
    /// `stride` apart. Planes elsewhere: [`Frame::i420`], [`Frame::nv12`].
    pub fn new(
        data: &'a [u8],
        width: usize,
        height: usize,
        stride: usize,
        format: PixelFormat,
    ) -> Result<Self, FrameError> {
        check_size(width, height, format)?;
        let row_bytes = width * format.bytes_per_pixel();
        if !format.is_planar() {
            Plane::new(data, stride).check(height, row_bytes, None)?;
            return Ok(Frame { data, width, height, stride, format, chroma: NO_CHROMA });
        }
        // The luma plane's rows are all padded: the chroma follows it.
        let luma_len =
            stride.checked_mul(height).ok_or(FrameError::BufferTooSmall { needed: usize::MAX, got: data.len() })?;
        let (y, rest) = (data.get(..luma_len).unwrap_or(data), data.get(luma_len..).unwrap_or(&[]));
        let luma = Plane::new(y, stride);
        if format == PixelFormat::I420 {
            // No overflow: cs · (height / 2) is under stride · height.
            let cs = stride / 2;
            let (u, v) = rest.split_at_checked(cs * (height / 2)).unwrap_or((rest, &[]));
            Self::i420(luma, Plane::new(u, cs), Plane::new(v, cs), width, height)
        } else {
            Self::nv12(luma, Plane::new(rest, stride), width, height)
        }
    }

    /// A planar I420 frame from its three planes, each with its own stride:
    /// `y` holds `height` rows of `width` bytes, `u` and `v` `height / 2`
    /// rows of `width / 2`.
    pub fn i420(y: Plane<'a>, u: Plane<'a>, v: Plane<'a>, width: usize, height: usize) -> Result<Self, FrameError> {
        let format = PixelFormat::I420;
        check_size(width, height, format)?;
        y.check(height, width, None)?;
        u.check(height / 2, width / 2, Some(ChromaPlane::U))?;
        v.check(height / 2, width / 2, Some(ChromaPlane::V))?;
        Ok(Frame { data: y.data, width, height, stride: y.stride, format, chroma: [u, v] })
    }

    /// A semi-planar NV12 frame from its two planes, each with its own
    /// stride: `y` holds `height` rows of `width` bytes, `uv` `height / 2`
    /// rows of `width` bytes (`width / 2` U, V pairs).
    pub fn nv12(y: Plane<'a>, uv: Plane<'a>, width: usize, height: usize) -> Result<Self, FrameError> {
        let format = PixelFormat::Nv12;
        check_size(width, height, format)?;
        y.check(height, width, None)?;
        uv.check(height / 2, width, Some(ChromaPlane::Uv))?;
        Ok(Frame { data: y.data, width, height, stride: y.stride, format, chroma: [uv, uv] })
    }

    /// A tightly packed frame: the stride is `width * bytes_per_pixel`.
    pub fn packed(data: &'a [u8], width: usize, height: usize, format: PixelFormat) -> Result<Self, FrameError> {
        Self::new(data, width, height, width.saturating_mul(format.bytes_per_pixel()), format)
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Row stride in bytes (of the luma plane, for the planar formats).
    pub fn stride(&self) -> usize {
        self.stride
    }

    /// The pixel buffer, or a planar format's luma plane (rows `stride`
    /// bytes apart), for loops that have
    /// checked rows and columns against the frame's size themselves and
    /// slice it with one bounds test per row.
    #[inline(always)]
    pub(crate) fn bytes(&self) -> &'a [u8] {
        self.data
    }

    /// The pixel format.
    pub fn format(&self) -> PixelFormat {
        self.format
    }

    /// The pixel bytes of row `y` (exactly `width * bytes_per_pixel` bytes),
    /// or `None` past the last row. For the planar formats, the row of the
    /// luma plane: a GRAY8 row.
    #[inline]
    pub fn row(&self, y: usize) -> Option<&'a [u8]> {
        // The buffer may be longer than the frame: bound by the height, not
        // only by the bytes (found by fuzzing `frame_new`).
        if y >= self.height {
            return None;
        }
        let start = y.checked_mul(self.stride)?;
        let len = self.width * self.format.bytes_per_pixel();
        self.data.get(start..start.checked_add(len)?)
    }

    /// The colour of pixel `(x, y)` as 8-bit RGB, or `None` outside the frame.
    ///
    /// This is the slow, general accessor for tools and tests; the histogram
    /// loops use the same conversion, compiled once per format, on whole rows.
    pub fn rgb(&self, x: usize, y: usize) -> Option<[u8; 3]> {
        let row = self.row(y)?;
        if x >= self.width {
            return None;
        }
        match self.format {
            PixelFormat::Rgb565 => Rgb565::rgb(row, x),
            PixelFormat::Rgb888 => Rgb888::rgb(row, x),
            PixelFormat::Yuv422 => Yuv422::rgb(row, x),
            PixelFormat::Gray8 => Gray8::rgb(row, x),
            PixelFormat::I420 | PixelFormat::Nv12 => {
                let y_value = *row.get(x)? as i32;
                let [u, v] = self.chroma_at(x / 2, y / 2)?;
                Some(yuv_centred_to_rgb(y_value, u as i32 - 128, v as i32 - 128))
            }
        }
    }

    /// The U and V samples of a planar frame's 2x2 block `(bx, by)`.
    #[inline]
    fn chroma_at(&self, bx: usize, by: usize) -> Option<[u8; 2]> {
        let [u, v] = self.chroma;
        // NV12 keeps both in one plane, U at even bytes and V at odd ones.
        let (at, step) = match self.format {
            PixelFormat::Nv12 => (2 * bx, 1),
            _ => (bx, 0),
        };
        let u_at = by.checked_mul(u.stride)?.checked_add(at)?;
        let v_at = by.checked_mul(v.stride)?.checked_add(at + step)?;
        Some([*u.data.get(u_at)?, *v.data.get(v_at)?])
    }
}

/// The checks of a frame's size that come before its buffers'.
fn check_size(width: usize, height: usize, format: PixelFormat) -> Result<(), FrameError> {
    if width == 0 || height == 0 {
        return Err(FrameError::ZeroSize);
    }
    if width > MAX_DIMENSION || height > MAX_DIMENSION {
        return Err(FrameError::TooLarge { width, height });
    }
    if format == PixelFormat::Yuv422 && !width.is_multiple_of(2) {
        return Err(FrameError::OddYuvWidth { width });
    }
    if format.is_planar() && !(width.is_multiple_of(2) && height.is_multiple_of(2)) {
        return Err(FrameError::OddChromaSize { width, height });
    }
    Ok(())
}

impl Frame<'_> {
    /// The 8-bit luma (BT.601) of pixel `(x, y)`, or `None` outside the
    /// frame: read directly in GRAY8 and YUV, from tables in RGB565.
    pub fn luma(&self, x: usize, y: usize) -> Option<u8> {
        self.luma_in(self.row(y)?, x)
    }

    /// The luma of pixel `x` of `row`, a row of this frame (from [`Frame::row`]).
    #[inline]
    pub(crate) fn luma_in(&self, row: &[u8], x: usize) -> Option<u8> {
        match self.format {
            PixelFormat::Rgb565 => Rgb565::luma(row, x),
            PixelFormat::Rgb888 => Rgb888::luma(row, x),
            PixelFormat::Yuv422 => Yuv422::luma(row, x),
            // A planar frame's rows are its luma plane's.
            PixelFormat::Gray8 | PixelFormat::I420 | PixelFormat::Nv12 => Gray8::luma(row, x),
        }
    }
}

/// Reads one pixel of a row in a given format. Implemented by zero-sized
/// format markers so that the histogram loop is compiled once per format,
/// with no per-pixel format dispatch.
pub(crate) trait PixelRead {
    /// One pixel's bytes, in formats whose pixels are self-contained.
    type Px: Copy;

    /// Whether region walks on the default checkerboard get their own
    /// compiled loop in this format (the camera formats whose pixels are
    /// self-contained: RGB565 and GRAY8); the others share the general walk,
    /// which saves flash.
    const CHECKER_WALK: bool = false;

    /// The row as an array of pixels, pixel `x` at index `x`; `None` for
    /// YUV 4:2:2, whose pixel pairs share their chroma. Loops that walk a
    /// row read through this, with one bounds test per row instead of per
    /// pixel.
    fn pixels(row: &[u8]) -> Option<&[Self::Px]>;

    /// The RGB 8x8x8 bin of a pixel from [`PixelRead::pixels`]: the top
    /// three bits of each channel.
    fn px_8x8x8(p: Self::Px) -> usize;

    /// The 8-bit luma of a pixel from [`PixelRead::pixels`].
    fn px_luma(p: Self::Px) -> u8;

    /// 8-bit RGB of pixel `x` of `row`, or `None` if `x` is past the row.
    fn rgb(row: &[u8], x: usize) -> Option<[u8; 3]>;

    /// 8-bit luma (BT.601) of pixel `x` of `row`: the grey level edges are
    /// taken on. Formats that carry it (GRAY8, YUV) read it directly.
    #[inline(always)]
    fn luma(row: &[u8], x: usize) -> Option<u8> {
        Self::rgb(row, x).map(luma)
    }

    /// The RGB 8x8x8 bin of pixel `x`.
    #[inline(always)]
    fn rgb_8x8x8(row: &[u8], x: usize) -> Option<usize> {
        match Self::pixels(row) {
            Some(px) => px.get(x).map(|&p| Self::px_8x8x8(p)),
            None => Self::rgb(row, x).map(bin_8x8x8),
        }
    }
}

/// The RGB 8x8x8 bin of 8-bit RGB: the top three bits of each channel.
#[inline(always)]
fn bin_8x8x8([r, g, b]: [u8; 3]) -> usize {
    ((r as usize >> 5) << 6) | ((g as usize >> 5) << 3) | (b as usize >> 5)
}

/// BT.601 luma of 8-bit RGB, in 8-bit fixed point (the same weights as
/// [`rgb_to_yuv`]'s Y).
#[inline(always)]
pub fn luma([r, g, b]: [u8; 3]) -> u8 {
    ((77 * r as u32 + 150 * g as u32 + 29 * b as u32 + 128) >> 8) as u8
}

/// `256 ·` [`luma`] of an RGB565 pixel, with the rounding's 128, as the
/// sum of a part from its low byte (`[0]`, which carries the 128) and one
/// from its high byte (`[1]`).
/// The expanded channels are `R8 = f(hi)`, `B8 = f(lo)` and
/// `G8 = 32·(hi & 7) + ((hi & 7) >> 1) + 4·(lo >> 5)` (the bit replication
/// of the 6-bit green splits the same way), so `77·R8 + 150·G8 + 29·B8`
/// does too. 1 KiB of flash saves about 20 instructions per pixel of the
/// edge map on a Cortex-M4.
static RGB565_LUMA: [[u16; 256]; 2] = rgb565_luma_tables();

/// Builds [`RGB565_LUMA`]. Evaluated at compile time only, where an index
/// out of range is a build error, not a panic.
#[allow(clippy::indexing_slicing)]
const fn rgb565_luma_tables() -> [[u16; 256]; 2] {
    let mut t = [[0u16; 256]; 2];
    let mut i = 0;
    while i < 256 {
        let b5 = (i & 0x1f) as u32;
        let b8 = (b5 << 3) | (b5 >> 2);
        let g_lo = 4 * (i as u32 >> 5);
        t[0][i] = (150 * g_lo + 29 * b8 + 128) as u16;
        let r5 = (i >> 3) as u32;
        let r8 = (r5 << 3) | (r5 >> 2);
        let g_hi = 32 * (i as u32 & 7) + ((i as u32 & 7) >> 1);
        t[1][i] = (77 * r8 + 150 * g_hi) as u16;
        i += 1;
    }
    t
}

/// The red and green part of an RGB565 pixel's 8x8x8 bin, by its high byte
/// (`RRRRRGGG`): `(r >> 2) << 6 | (g >> 3) << 3`.
/// A table instead of two shifts and masks: measured on the QVGA audit,
/// 0.24 M fewer instructions per frame (without the masks' constants, the
/// pixel loop has the registers it needs).
static RGB565_HIGH_BIN: [u16; 256] = rgb565_high_bin_table();

/// Builds [`RGB565_HIGH_BIN`]. Evaluated at compile time only, where an
/// index out of range is a build error, not a panic.
#[allow(clippy::indexing_slicing)]
const fn rgb565_high_bin_table() -> [u16; 256] {
    let mut t = [0u16; 256];
    let mut i = 0;
    while i < 256 {
        t[i] = (((i >> 5) << 6) | ((i & 7) << 3)) as u16;
        i += 1;
    }
    t
}

/// Marker for [`PixelFormat::Rgb565`].
pub(crate) struct Rgb565;
/// Marker for [`PixelFormat::Rgb888`].
pub(crate) struct Rgb888;
/// Marker for [`PixelFormat::Yuv422`].
pub(crate) struct Yuv422;
/// Marker for [`PixelFormat::Gray8`].
pub(crate) struct Gray8;

impl PixelRead for Rgb565 {
    type Px = [u8; 2];
    const CHECKER_WALK: bool = true;

    #[inline(always)]
    fn pixels(row: &[u8]) -> Option<&[[u8; 2]]> {
        Some(row.as_chunks::<2>().0)
    }

    /// The top three bits of the expanded channels are the top three of the
    /// packed ones (bit replication only fills low bits): red 15..13, green
    /// 10..8, blue 4..2.
    #[inline(always)]
    fn px_8x8x8([lo, hi]: [u8; 2]) -> usize {
        // Red and green come from the high byte alone: one table load.
        RGB565_HIGH_BIN.get(hi as usize).map_or(0, |&b| b as usize) | ((lo as usize >> 2) & 7)
    }

    /// [`luma`] of the expanded channels, exactly, from two tables: luma is
    /// linear in the channels, and each expanded channel splits into a part
    /// from each byte (see [`RGB565_LUMA`]).
    #[inline(always)]
    fn luma(row: &[u8], x: usize) -> Option<u8> {
        Some(Self::px_luma(*Self::pixels(row)?.get(x)?))
    }

    #[inline(always)]
    fn px_luma([lo, hi]: [u8; 2]) -> u8 {
        let [lo_part, hi_part] = &RGB565_LUMA;
        // A byte indexes a 256-entry table: the compiler drops these checks.
        let sum = lo_part.get(lo as usize).map_or(0, |&v| v as u32) + hi_part.get(hi as usize).map_or(0, |&v| v as u32);
        (sum >> 8) as u8
    }

    #[inline(always)]
    fn rgb(row: &[u8], x: usize) -> Option<[u8; 3]> {
        let v = u16::from_le_bytes(*Self::pixels(row)?.get(x)?);
        // Replicate the top bits into the low ones so that 0x1f maps to 255.
        let r = ((v >> 11) & 0x1f) as u8;
        let g = ((v >> 5) & 0x3f) as u8;
        let b = (v & 0x1f) as u8;
        Some([(r << 3) | (r >> 2), (g << 2) | (g >> 4), (b << 3) | (b >> 2)])
    }
}

impl PixelRead for Rgb888 {
    type Px = [u8; 3];

    #[inline(always)]
    fn pixels(row: &[u8]) -> Option<&[[u8; 3]]> {
        Some(row.as_chunks::<3>().0)
    }

    #[inline(always)]
    fn px_8x8x8(p: [u8; 3]) -> usize {
        bin_8x8x8(p)
    }

    #[inline(always)]
    fn px_luma(p: [u8; 3]) -> u8 {
        luma(p)
    }

    #[inline(always)]
    fn rgb(row: &[u8], x: usize) -> Option<[u8; 3]> {
        Self::pixels(row)?.get(x).copied()
    }
}

impl PixelRead for Yuv422 {
    type Px = ();

    #[inline(always)]
    fn pixels(_: &[u8]) -> Option<&[()]> {
        None
    }

    #[inline(always)]
    fn px_8x8x8(_: ()) -> usize {
        0
    }

    #[inline(always)]
    fn px_luma(_: ()) -> u8 {
        0
    }

    #[inline(always)]
    fn rgb(row: &[u8], x: usize) -> Option<[u8; 3]> {
        let pair = 4 * (x / 2);
        let y = *row.get(2 * x)? as i32;
        let u = *row.get(pair + 1)? as i32 - 128;
        let v = *row.get(pair + 3)? as i32 - 128;
        Some(yuv_centred_to_rgb(y, u, v))
    }

    #[inline(always)]
    fn luma(row: &[u8], x: usize) -> Option<u8> {
        row.get(2 * x).copied()
    }
}

impl PixelRead for Gray8 {
    type Px = u8;
    const CHECKER_WALK: bool = true;

    #[inline(always)]
    fn pixels(row: &[u8]) -> Option<&[u8]> {
        Some(row)
    }

    #[inline(always)]
    fn px_8x8x8(g: u8) -> usize {
        bin_8x8x8([g, g, g])
    }

    #[inline(always)]
    fn px_luma(g: u8) -> u8 {
        g
    }

    #[inline(always)]
    fn rgb(row: &[u8], x: usize) -> Option<[u8; 3]> {
        let g = *row.get(x)?;
        Some([g, g, g])
    }

    #[inline(always)]
    fn luma(row: &[u8], x: usize) -> Option<u8> {
        row.get(x).copied()
    }
}

/// Full-range BT.601 YUV to RGB, the conversion every YUV format is read
/// with (for tools that convert YUV frames the way the tracker sees them).
pub fn yuv_to_rgb([y, u, v]: [u8; 3]) -> [u8; 3] {
    yuv_centred_to_rgb(y as i32, u as i32 - 128, v as i32 - 128)
}

/// Full-range BT.601 YUV to RGB in 8-bit fixed point (coefficients × 256),
/// chroma centred on 0.
#[inline(always)]
fn yuv_centred_to_rgb(y: i32, u: i32, v: i32) -> [u8; 3] {
    let r = y + ((359 * v) >> 8);
    let g = y - ((88 * u + 183 * v) >> 8);
    let b = y + ((454 * u) >> 8);
    [r.max(0).min(255) as u8, g.max(0).min(255) as u8, b.max(0).min(255) as u8]
}

/// Full-range BT.601 RGB to YUV, the inverse of the conversion used to read
/// [`PixelFormat::Yuv422`] frames (for tools that write such frames).
pub fn rgb_to_yuv(rgb: [u8; 3]) -> [u8; 3] {
    let [r, g, b] = [rgb[0] as i32, rgb[1] as i32, rgb[2] as i32];
    let y = (77 * r + 150 * g + 29 * b + 128) >> 8;
    let u = ((-43 * r - 85 * g + 128 * b + 128) >> 8) + 128;
    let v = ((128 * r - 107 * g - 21 * b + 128) >> 8) + 128;
    [y.max(0).min(255) as u8, u.max(0).min(255) as u8, v.max(0).min(255) as u8]
}

/// Packs 8-bit RGB into little-endian RGB565 bytes (for tools that write frames).
pub fn rgb_to_rgb565(rgb: [u8; 3]) -> [u8; 2] {
    let v = ((rgb[0] as u16 >> 3) << 11) | ((rgb[1] as u16 >> 2) << 5) | (rgb[2] as u16 >> 3);
    v.to_le_bytes()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rgb565_bins_equal_the_bins_of_the_expanded_pixel() {
        // Reason: a cross-check of the table-driven RGB 8x8x8 bin against
        // the definition (expand to 8-bit RGB, top three bits of each), for
        // all 65536 pixels.
        for v in 0..=u16::MAX {
            let px = v.to_le_bytes();
            let want = Rgb565::rgb(&px, 0).map(bin_8x8x8);
            assert_eq!(Some(Rgb565::px_8x8x8(px)), want, "pixel {v:#06x}");
        }
    }

    #[test]
    fn rgb565_luma_tables_equal_luma_of_the_expanded_pixel() {
        // Reason: a cross-check of the two-table luma against the definition
        // (expand to 8-bit RGB, then BT.601), for all 65536 pixels.
        for v in 0..=u16::MAX {
            let px = v.to_le_bytes();
            assert_eq!(Rgb565::luma(&px, 0), Rgb565::rgb(&px, 0).map(luma), "pixel {v:#06x}");
        }
    }

    #[test]
    fn rejects_inconsistent_dimensions() {
        let buf = [0u8; 100];
        assert_eq!(Frame::new(&buf, 0, 2, 8, PixelFormat::Gray8).err(), Some(FrameError::ZeroSize));
        assert_eq!(
            Frame::new(&buf, 5, 2, 8, PixelFormat::Rgb565).err(),
            Some(FrameError::StrideTooSmall { stride: 8, row_bytes: 10 })
        );
        assert_eq!(
            Frame::new(&buf, 10, 10, 10, PixelFormat::Gray8).err(),
            None,
            "exactly 100 bytes is enough for 10x10 GRAY8"
        );
        assert_eq!(
            Frame::new(&buf, 10, 11, 10, PixelFormat::Gray8).err(),
            Some(FrameError::BufferTooSmall { needed: 110, got: 100 })
        );
        assert_eq!(Frame::new(&buf, 3, 1, 8, PixelFormat::Yuv422).err(), Some(FrameError::OddYuvWidth { width: 3 }));
        assert!(matches!(Frame::new(&buf, 5000, 1, 5000, PixelFormat::Gray8), Err(FrameError::TooLarge { .. })));
        // A stride so large that stride * (height - 1) overflows.
        assert!(matches!(
            Frame::new(&buf, 1, 3, usize::MAX / 2 + 1, PixelFormat::Gray8),
            Err(FrameError::BufferTooSmall { .. })
        ));
    }

    #[test]
    fn reads_every_format_with_stride() {
        // Reason: each format encodes the same colour (200, 100, 50) by hand;
        // decoding must return it (within each format's quantisation).
        let c565 = rgb_to_rgb565([200, 100, 50]);
        // 2 pixels per row, stride 6 (2 bytes of padding), 2 rows.
        let mut buf = [0xAAu8; 12];
        buf[6 + 2] = c565[0];
        buf[6 + 3] = c565[1];
        let f = Frame::new(&buf, 2, 2, 6, PixelFormat::Rgb565).unwrap_or_else(|e| panic!("{e:?}"));
        let got = f.rgb(1, 1).unwrap_or_default();
        // RGB565 keeps 5/6/5 bits: errors up to 7/3/7.
        assert!(
            (got[0] as i32 - 200).abs() <= 7 && (got[1] as i32 - 100).abs() <= 3 && (got[2] as i32 - 50).abs() <= 7
        );
        assert_eq!(f.rgb(2, 1), None);
        assert_eq!(f.rgb(0, 2), None);
        // Rows past the height are not rows, even when the buffer goes on.
        let long = [0u8; 64];
        let f = Frame::new(&long, 2, 2, 6, PixelFormat::Rgb565).unwrap_or_else(|e| panic!("{e:?}"));
        assert!(f.row(1).is_some() && f.row(2).is_none());

        let buf888 = [1u8, 2, 3, 200, 100, 50];
        let f = Frame::packed(&buf888, 2, 1, PixelFormat::Rgb888).unwrap_or_else(|e| panic!("{e:?}"));
        assert_eq!(f.rgb(1, 0), Some([200, 100, 50]));

        let [y, u, v] = rgb_to_yuv([200, 100, 50]);
        let yuyv = [y, u, y, v];
        let f = Frame::packed(&yuyv, 2, 1, PixelFormat::Yuv422).unwrap_or_else(|e| panic!("{e:?}"));
        for x in 0..2 {
            let got = f.rgb(x, 0).unwrap_or_default();
            for (g, w) in got.iter().zip([200u8, 100, 50]) {
                assert!((*g as i32 - w as i32).abs() <= 3, "{got:?}");
            }
        }

        let f = Frame::packed(&[9u8, 77], 2, 1, PixelFormat::Gray8).unwrap_or_else(|e| panic!("{e:?}"));
        assert_eq!(f.rgb(1, 0), Some([77, 77, 77]));
    }

    /// A 4x4 planar frame's samples: luma 100 everywhere but pixel (3, 3),
    /// and per 2x2 block the chroma pairs below.
    const BLOCK_UV: [[u8; 2]; 4] = [[178, 98], [128, 128], [0, 255], [255, 0]];

    #[test]
    fn planar_formats_decode_by_hand() {
        // Reason: the values by hand from the BT.601 full-range formulas
        // (coefficients x 256, arithmetic shifts round down):
        // Y 100, U 178, V 98 (u = 50, v = -30):
        //   R = 100 + (359·-30 >> 8) = 100 - 43 = 57
        //   G = 100 - ((88·50 + 183·-30) >> 8) = 100 - (-1090 >> 8) = 105
        //   B = 100 + (454·50 >> 8) = 100 + 88 = 188
        // U = V = 128: grey 100.
        // U 0, V 255 (u = -128, v = 127): R = 100 + 178 → 255,
        //   G = 100 - ((-11264 + 23241) >> 8) = 100 - 46 = 54, B = 100 - 227 → 0.
        // U 255, V 0 (u = 127, v = -128): R = 100 - 180 → 0,
        //   G = 100 - ((11176 - 23424) >> 8) = 100 + 48 = 148, B = 100 + 225 → 255.
        let want = [[57, 105, 188], [100, 100, 100], [255, 54, 0], [0, 148, 255]];
        // I420 with padded strides: Y stride 6, U and V stride 3.
        let mut y = [0u8; 6 * 4];
        for r in 0..4 {
            y[r * 6..r * 6 + 4].fill(100);
        }
        y[3 * 6 + 3] = 7;
        let (mut u, mut v, mut uv) = ([9u8; 3 * 2], [9u8; 3 * 2], [9u8; 5 * 2]);
        for (b, [cu, cv]) in BLOCK_UV.iter().enumerate() {
            let (bx, by) = (b % 2, b / 2);
            u[by * 3 + bx] = *cu;
            v[by * 3 + bx] = *cv;
            uv[by * 5 + 2 * bx] = *cu;
            uv[by * 5 + 2 * bx + 1] = *cv;
        }
        let i420 = Frame::i420(Plane::new(&y, 6), Plane::new(&u, 3), Plane::new(&v, 3), 4, 4).unwrap();
        let nv12 = Frame::nv12(Plane::new(&y, 6), Plane::new(&uv, 5), 4, 4).unwrap();
        for f in [i420, nv12] {
            for py in 0..4 {
                for px in 0..4 {
                    let block = (py / 2) * 2 + px / 2;
                    if (px, py) != (3, 3) {
                        assert_eq!(f.rgb(px, py), Some(want[block]), "{:?} ({px}, {py})", f.format());
                    }
                    assert_eq!(f.luma(px, py), Some(if (px, py) == (3, 3) { 7 } else { 100 }));
                }
            }
            assert_eq!(f.rgb(4, 0), None);
            assert_eq!(f.rgb(0, 4), None);
            assert_eq!(f.row(1), Some(&[100u8; 4][..]), "a planar frame's row is its luma row");
        }
        // The same samples in one buffer, as Frame::new lays them out.
        let mut whole = y.to_vec();
        whole.extend_from_slice(&u);
        whole.extend_from_slice(&v);
        let f = Frame::new(&whole, 4, 4, 6, PixelFormat::I420).unwrap();
        assert_eq!(PixelFormat::I420.frame_bytes(6, 4), Some(whole.len()));
        for py in 0..4 {
            for px in 0..4 {
                assert_eq!(f.rgb(px, py), i420.rgb(px, py));
            }
        }
    }

    #[test]
    fn planar_frames_check_every_plane() {
        let buf = [0u8; 64];
        let p = |n: usize, stride: usize| Plane::new(&buf[..n], stride);
        assert_eq!(
            Frame::i420(p(16, 4), p(4, 2), p(4, 2), 3, 4).err(),
            Some(FrameError::OddChromaSize { width: 3, height: 4 })
        );
        assert_eq!(
            Frame::i420(p(16, 4), p(4, 1), p(4, 2), 4, 4).err(),
            Some(FrameError::ChromaStrideTooSmall { plane: ChromaPlane::U, stride: 1, row_bytes: 2 })
        );
        // V needs one padded row and one of 2 bytes: 3 + 2 = 5.
        assert_eq!(
            Frame::i420(p(16, 4), p(4, 2), p(4, 3), 4, 4).err(),
            Some(FrameError::ChromaTooSmall { plane: ChromaPlane::V, needed: 5, got: 4 })
        );
        assert_eq!(
            Frame::nv12(p(15, 4), p(8, 4), 4, 4).err(),
            Some(FrameError::BufferTooSmall { needed: 16, got: 15 })
        );
        assert_eq!(
            Frame::nv12(p(16, 4), p(7, 4), 4, 4).err(),
            Some(FrameError::ChromaTooSmall { plane: ChromaPlane::Uv, needed: 8, got: 7 })
        );
        assert!(Frame::nv12(p(16, 4), p(8, 4), 4, 4).is_ok());
        // One buffer: 4x4 I420 packed is 16 + 4 + 4 = 24 bytes; NV12 16 + 8.
        assert_eq!(PixelFormat::I420.frame_bytes(4, 4), Some(24));
        assert_eq!(PixelFormat::Nv12.frame_bytes(4, 4), Some(24));
        assert!(Frame::packed(&buf[..24], 4, 4, PixelFormat::I420).is_ok());
        assert_eq!(
            Frame::packed(&buf[..23], 4, 4, PixelFormat::I420).err(),
            Some(FrameError::ChromaTooSmall { plane: ChromaPlane::V, needed: 4, got: 3 })
        );
        assert_eq!(
            Frame::packed(&buf[..10], 4, 4, PixelFormat::Nv12).err(),
            Some(FrameError::BufferTooSmall { needed: 16, got: 10 })
        );
        assert_eq!(
            Frame::new(&buf, 4, 4, usize::MAX / 2, PixelFormat::Nv12).err(),
            Some(FrameError::BufferTooSmall { needed: usize::MAX, got: 64 })
        );
        assert_eq!(PixelFormat::I420.frame_bytes(usize::MAX, 2), None);
    }

    #[test]
    fn rgb565_direct_bins_equal_bins_of_the_expanded_colour() {
        // Reason: cross-check the shortcut against the definition on every
        // one of the 65536 RGB565 values.
        for v in 0..=u16::MAX {
            let px = v.to_le_bytes();
            let [r, g, b] = Rgb565::rgb(&px, 0).unwrap();
            let want = ((r as usize >> 5) << 6) | ((g as usize >> 5) << 3) | (b as usize >> 5);
            assert_eq!(Rgb565::rgb_8x8x8(&px, 0), Some(want), "{v:#06x}");
        }
    }

    #[test]
    fn rgb565_extremes_map_to_full_range() {
        let white = rgb_to_rgb565([255, 255, 255]);
        assert_eq!(Rgb565::rgb(&white, 0), Some([255, 255, 255]));
        assert_eq!(Rgb565::rgb(&[0, 0], 0), Some([0, 0, 0]));
    }
}
