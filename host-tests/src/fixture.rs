//! The recorded-frame fixture format (`.pft`).
//!
//! A fixture is a header followed by fixed-size frame records, all
//! little-endian, so that firmware can stream it record by record with a
//! single read size and no parsing beyond the header:
//!
//! ```text
//! header, 32 bytes
//!   0   [u8; 8]  magic "PFTRKFX1"
//!   8   u16      version = 1
//!   10  u16      pixel format: 1 RGB565 (LE), 2 RGB888, 3 YUV422 (YUYV), 4 GRAY8
//!   12  u16      width, pixels
//!   14  u16      height, pixels
//!   16  u32      stride, bytes per row (>= width * bytes per pixel)
//!   20  u32      frame count
//!   24  u32      reserved, 0
//!   28  u32      reserved, 0
//! frame record, 20 + stride * height bytes, repeated `frame count` times
//!   0   f32 x4   ground-truth box x, y, w, h (top-left origin, pixels)
//!   16  u16      visible fraction of the target, per mille (0 = absent or fully hidden)
//!   18  u16      reserved, 0
//!   20  [u8]     stride * height bytes of pixels
//! ```
//!
//! Reading validates everything and reports a [`FixtureError`]; nothing panics
//! on a truncated or inconsistent file.

use pftrack::{BoundingBox, Frame, FrameError, PixelFormat};
use std::fmt;

/// The magic bytes at the start of every fixture.
pub const MAGIC: &[u8; 8] = b"PFTRKFX1";
/// The only version this code reads and writes.
pub const VERSION: u16 = 1;
/// Size of the header in bytes.
pub const HEADER_LEN: usize = 32;
/// Size of a frame record's metadata, before its pixels.
pub const RECORD_META_LEN: usize = 20;

/// Why a fixture could not be read.
#[derive(Debug, Clone, PartialEq)]
pub enum FixtureError {
    /// Shorter than the header.
    TruncatedHeader { len: usize },
    /// The magic bytes are wrong: not a fixture.
    BadMagic,
    /// A version this code does not read.
    UnsupportedVersion(u16),
    /// An unknown pixel format code.
    UnknownFormat(u16),
    /// The header's dimensions are inconsistent.
    BadDimensions(FrameError),
    /// The file ends inside frame `index`.
    TruncatedFrame { index: u32, expected_len: usize, actual_len: usize },
    /// Bytes after the last frame.
    TrailingBytes { extra: usize },
    /// A ground-truth value is NaN or infinite.
    BadGroundTruth { index: u32 },
    /// A visibility above 1000 per mille.
    BadVisibility { index: u32, value: u16 },
}

impl fmt::Display for FixtureError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FixtureError::TruncatedHeader { len } => {
                write!(f, "file is {len} bytes, shorter than the {HEADER_LEN}-byte fixture header")
            }
            FixtureError::BadMagic => write!(f, "not a pftrack fixture (bad magic bytes)"),
            FixtureError::UnsupportedVersion(v) => write!(f, "fixture version {v} is not supported (want {VERSION})"),
            FixtureError::UnknownFormat(c) => write!(f, "unknown pixel format code {c}"),
            FixtureError::BadDimensions(e) => write!(f, "inconsistent header dimensions: {e}"),
            FixtureError::TruncatedFrame { index, expected_len, actual_len } => {
                write!(f, "file ends inside frame {index}: its record needs {expected_len} bytes, {actual_len} remain")
            }
            FixtureError::TrailingBytes { extra } => write!(f, "{extra} unexpected bytes after the last frame"),
            FixtureError::BadGroundTruth { index } => write!(f, "frame {index} has a NaN or infinite ground-truth box"),
            FixtureError::BadVisibility { index, value } => {
                write!(f, "frame {index} has visibility {value} per mille (max 1000)")
            }
        }
    }
}

impl std::error::Error for FixtureError {}

/// One frame of a fixture: its pixels and what the scene knows about it.
#[derive(Debug, Clone, PartialEq)]
pub struct FixtureFrame {
    /// The ground-truth box of the target's nominal ellipse.
    pub truth: BoundingBox,
    /// Fraction of the target visible, per mille.
    pub visible_permille: u16,
    /// `stride * height` bytes of pixels.
    pub pixels: Vec<u8>,
}

/// A whole fixture in memory.
#[derive(Debug, Clone, PartialEq)]
pub struct Fixture {
    /// Pixel format of every frame.
    pub format: PixelFormat,
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Row stride in bytes.
    pub stride: usize,
    /// The frames in order.
    pub frames: Vec<FixtureFrame>,
}

fn u16_at(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b[at], b[at + 1]])
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

fn f32_at(b: &[u8], at: usize) -> f32 {
    f32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

impl Fixture {
    /// Parses a fixture held in memory.
    pub fn parse(bytes: &[u8]) -> Result<Self, FixtureError> {
        if bytes.len() < HEADER_LEN {
            return Err(FixtureError::TruncatedHeader { len: bytes.len() });
        }
        if &bytes[..8] != MAGIC {
            return Err(FixtureError::BadMagic);
        }
        let version = u16_at(bytes, 8);
        if version != VERSION {
            return Err(FixtureError::UnsupportedVersion(version));
        }
        let code = u16_at(bytes, 10);
        let format = PixelFormat::from_code(code).ok_or(FixtureError::UnknownFormat(code))?;
        let width = u16_at(bytes, 12) as usize;
        let height = u16_at(bytes, 14) as usize;
        let stride = u32_at(bytes, 16) as usize;
        let count = u32_at(bytes, 20);
        // Let the core judge the dimensions, exactly as it will when tracking:
        // with an empty buffer, consistent dimensions fail only on its length.
        match Frame::new(&[], width, height, stride, format) {
            Ok(_) | Err(FrameError::BufferTooSmall { .. }) => {}
            Err(e) => return Err(FixtureError::BadDimensions(e)),
        }
        // width, height <= MAX_DIMENSION and stride < 2^32: no overflow on 64-bit.
        let frame_len = stride * height;
        let record_len = RECORD_META_LEN + frame_len;
        let mut frames = Vec::new();
        let mut at = HEADER_LEN;
        for index in 0..count {
            let rest = bytes.len() - at;
            if rest < record_len {
                return Err(FixtureError::TruncatedFrame { index, expected_len: record_len, actual_len: rest });
            }
            let truth = BoundingBox::new(
                f32_at(bytes, at),
                f32_at(bytes, at + 4),
                f32_at(bytes, at + 8),
                f32_at(bytes, at + 12),
            );
            if ![truth.x, truth.y, truth.width, truth.height].iter().all(|v| v.is_finite()) {
                return Err(FixtureError::BadGroundTruth { index });
            }
            let visible_permille = u16_at(bytes, at + 16);
            if visible_permille > 1000 {
                return Err(FixtureError::BadVisibility { index, value: visible_permille });
            }
            let pixels = bytes[at + RECORD_META_LEN..at + record_len].to_vec();
            frames.push(FixtureFrame { truth, visible_permille, pixels });
            at += record_len;
        }
        if at != bytes.len() {
            return Err(FixtureError::TrailingBytes { extra: bytes.len() - at });
        }
        Ok(Fixture { format, width, height, stride, frames })
    }

    /// Serialises the fixture.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out =
            Vec::with_capacity(HEADER_LEN + self.frames.len() * (RECORD_META_LEN + self.stride * self.height));
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&VERSION.to_le_bytes());
        out.extend_from_slice(&self.format.code().to_le_bytes());
        out.extend_from_slice(&(self.width as u16).to_le_bytes());
        out.extend_from_slice(&(self.height as u16).to_le_bytes());
        out.extend_from_slice(&(self.stride as u32).to_le_bytes());
        out.extend_from_slice(&(self.frames.len() as u32).to_le_bytes());
        out.extend_from_slice(&[0u8; 8]);
        for f in &self.frames {
            for v in [f.truth.x, f.truth.y, f.truth.width, f.truth.height] {
                out.extend_from_slice(&v.to_le_bytes());
            }
            out.extend_from_slice(&f.visible_permille.to_le_bytes());
            out.extend_from_slice(&0u16.to_le_bytes());
            out.extend_from_slice(&f.pixels);
        }
        out
    }

    /// Reads and parses a fixture file.
    pub fn load(path: &std::path::Path) -> Result<Self, String> {
        let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
        Fixture::parse(&bytes).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// A core frame view of frame `i`.
    pub fn frame(&self, i: usize) -> Option<Frame<'_>> {
        let f = self.frames.get(i)?;
        Frame::new(&f.pixels, self.width, self.height, self.stride, self.format).ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tiny() -> Fixture {
        Fixture {
            format: PixelFormat::Rgb565,
            width: 3,
            height: 2,
            stride: 8,
            frames: (0..3)
                .map(|i| FixtureFrame {
                    truth: BoundingBox::new(i as f32, 0.5, 2.0, 1.0),
                    visible_permille: 1000 - i as u16,
                    pixels: (0..16).map(|b| (b * 7 + i) as u8).collect(),
                })
                .collect(),
        }
    }

    #[test]
    fn round_trip() {
        let f = tiny();
        let bytes = f.to_bytes();
        // Reason: header + 3 records of 20 + 8*2 bytes, by the format above.
        assert_eq!(bytes.len(), 32 + 3 * 36);
        assert_eq!(Fixture::parse(&bytes), Ok(f));
    }

    #[test]
    fn every_truncation_is_an_error() {
        // Reason: every strict prefix of a valid file is missing something.
        let bytes = tiny().to_bytes();
        for len in 0..bytes.len() {
            let r = Fixture::parse(&bytes[..len]);
            assert!(r.is_err(), "prefix of {len} bytes parsed");
            if len < HEADER_LEN {
                assert_eq!(r, Err(FixtureError::TruncatedHeader { len }));
            } else {
                assert!(matches!(r, Err(FixtureError::TruncatedFrame { .. })), "{len}: {r:?}");
            }
        }
    }

    #[test]
    fn inconsistent_headers_are_errors() {
        let good = tiny().to_bytes();
        let mut b = good.clone();
        b[0] = b'X';
        assert_eq!(Fixture::parse(&b), Err(FixtureError::BadMagic));
        let mut b = good.clone();
        b[8] = 9;
        assert_eq!(Fixture::parse(&b), Err(FixtureError::UnsupportedVersion(9)));
        let mut b = good.clone();
        b[10] = 77;
        assert_eq!(Fixture::parse(&b), Err(FixtureError::UnknownFormat(77)));
        let mut b = good.clone();
        b[16] = 2; // stride 2 < 3 px * 2 bytes
        assert!(matches!(Fixture::parse(&b), Err(FixtureError::BadDimensions(FrameError::StrideTooSmall { .. }))));
        let mut b = good.clone();
        b[12] = 0; // width 0
        assert_eq!(Fixture::parse(&b), Err(FixtureError::BadDimensions(FrameError::ZeroSize)));
        let mut b = good.clone();
        b.push(0);
        assert_eq!(Fixture::parse(&b), Err(FixtureError::TrailingBytes { extra: 1 }));
        let mut b = good.clone();
        b[HEADER_LEN..HEADER_LEN + 4].copy_from_slice(&f32::NAN.to_le_bytes());
        assert_eq!(Fixture::parse(&b), Err(FixtureError::BadGroundTruth { index: 0 }));
        let mut b = good;
        b[HEADER_LEN + 16..HEADER_LEN + 18].copy_from_slice(&1001u16.to_le_bytes());
        assert_eq!(Fixture::parse(&b), Err(FixtureError::BadVisibility { index: 0, value: 1001 }));
    }
}
