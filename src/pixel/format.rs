//! The pixel formats a frame may have, and the limits on its size.

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
    /// Bytes per pixel of a row as [`Frame::new`](crate::Frame::new)'s stride counts it: YUV
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
    /// other as [`Frame::new`](crate::Frame::new) lays them out. `None` if it overflows.
    pub const fn frame_bytes(self, stride: usize, height: usize) -> Option<usize> {
        let Some(luma) = stride.checked_mul(height) else { return None };
        let chroma = match self {
            // Two planes of half the stride, half the height.
            PixelFormat::I420 => (stride / 2) * (height / 2) * 2,
            // One plane of the full stride, half the height.
            PixelFormat::Nv12 => stride * (height / 2),
            PixelFormat::Rgb565 | PixelFormat::Rgb888 | PixelFormat::Yuv422 | PixelFormat::Gray8 => 0,
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
