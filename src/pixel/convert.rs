//! Conversions between colour spaces, as the tracker reads pixels and as
//! tools that write frames need them.

/// The RGB 8x8x8 bin of 8-bit RGB: the top three bits of each channel.
#[inline(always)]
pub(crate) fn bin_8x8x8([r, g, b]: [u8; 3]) -> usize {
    ((r as usize >> 5) << 6) | ((g as usize >> 5) << 3) | (b as usize >> 5)
}

/// BT.601 luma of 8-bit RGB, in 8-bit fixed point (the same weights as
/// [`rgb_to_yuv`]'s Y).
#[inline(always)]
pub fn luma([r, g, b]: [u8; 3]) -> u8 {
    ((77 * r as u32 + 150 * g as u32 + 29 * b as u32 + 128) >> 8) as u8
}

/// Full-range BT.601 YUV to RGB, the conversion every YUV format is read
/// with (for tools that convert YUV frames the way the tracker sees them).
pub fn yuv_to_rgb([y, u, v]: [u8; 3]) -> [u8; 3] {
    yuv_centred_to_rgb(y as i32, u as i32 - 128, v as i32 - 128)
}

/// Full-range BT.601 YUV to RGB in 8-bit fixed point (coefficients × 256),
/// chroma centred on 0.
#[inline(always)]
pub(crate) fn yuv_centred_to_rgb(y: i32, u: i32, v: i32) -> [u8; 3] {
    let r = y + ((359 * v) >> 8);
    let g = y - ((88 * u + 183 * v) >> 8);
    let b = y + ((454 * u) >> 8);
    [r.max(0).min(255) as u8, g.max(0).min(255) as u8, b.max(0).min(255) as u8]
}

/// Full-range BT.601 RGB to YUV, the inverse of the conversion used to read
/// [`crate::PixelFormat::Yuv422`] frames (for tools that write such frames).
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
