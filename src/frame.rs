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
use crate::pixel::{Gray8, PixelRead, Rgb565, Rgb888, Yuv422, yuv_centred_to_rgb};
pub use crate::pixel::{MAX_DIMENSION, PixelFormat, luma, rgb_to_rgb565, rgb_to_yuv, yuv_to_rgb};

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
        // Every constructor checked that `stride · (height − 1) + width ·
        // bytes per pixel` fits the buffer, so for `y < height` neither sum
        // overflows: plain arithmetic (a checked multiplication is a 64-bit
        // library call on a Cortex-M0+, and this runs for every row read).
        let start = y.wrapping_mul(self.stride);
        let len = self.width * self.format.bytes_per_pixel();
        self.data.get(start..start.wrapping_add(len))
    }

    /// The colour of pixel `(x, y)` as 8-bit RGB, or `None` outside the frame.
    ///
    /// This is the slow, general accessor, for tools, tests and reads of a
    /// few pixels once a target (the gradient filter's grey-video test); the
    /// histogram loops use the same conversion, compiled once per format, on
    /// whole rows.
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
            PixelFormat::I420
            | PixelFormat::Rgb565
            | PixelFormat::Rgb888
            | PixelFormat::Yuv422
            | PixelFormat::Gray8 => (bx, 0),
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pixel::PixelFormat;

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
}
