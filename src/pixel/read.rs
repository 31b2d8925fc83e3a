//! Reading one pixel of a row, compiled per format.

use super::convert::{bin_8x8x8, luma, yuv_centred_to_rgb};
#[cfg(doc)]
use super::format::PixelFormat;

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

/// `256 ·` [`luma`] of an RGB565 pixel, with the rounding's 128, as the
/// sum of a part from its low byte (`[0]`, which carries the 128) and one
/// from its high byte (`[1]`).
/// The expanded channels are `R8 = f(hi)`, `B8 = f(lo)` and
/// `G8 = 32·(hi & 7) + ((hi & 7) >> 1) + 4·(lo >> 5)` (the bit replication
/// of the 6-bit green splits the same way), so `77·R8 + 150·G8 + 29·B8`
/// does too. The tables' 1 KiB of flash spares the channels' expansion
/// and three multiplies for every pixel of the edge map.
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
/// A table instead of two shifts and masks: fewer instructions per QVGA
/// frame, because without the masks' constants the pixel loop has the
/// registers it needs (docs/performance.md).
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pixel::rgb_to_rgb565;

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
