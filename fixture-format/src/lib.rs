//! The recorded-frame fixture format (`.pft`), `no_std`, for every reader:
//! the host harness, the firmware (which streams it over semihosting) and
//! the Linux trace runner.
//!
//! A fixture is a header followed by fixed-size frame records, all
//! little-endian, so a reader streams it record by record with a single read
//! size and no parsing beyond the header:
//!
//! ```text
//! header, 32 bytes
//!   0   [u8; 8]  magic "PFTRKFX1"
//!   8   u16      version: 1 for one target, 2 for several
//!   10  u16      pixel format: 1 RGB565 (LE), 2 RGB888, 3 YUV422 (YUYV), 4 GRAY8,
//!                5 I420 (planar YUV 4:2:0), 6 NV12 (Y plane, interleaved UV)
//!   12  u16      width, pixels
//!   14  u16      height, pixels
//!   16  u32      stride, bytes per row (>= width * bytes per pixel)
//!   20  u32      frame count
//!   24  u16      version 2: the number of targets T (2 to 16); version 1: 0
//!   26  u16      reserved, 0
//!   28  u32      reserved, 0
//! frame record, 20 * T + frame bytes, repeated `frame count` times (T is 1
//! in version 1); frame bytes are stride * height, and for I420 plus
//! 2 * (stride / 2) * (height / 2) (the U, then the V plane), for NV12 plus
//! stride * (height / 2) (the UV plane)
//!   T times, one per target in the order they are to be added:
//!     0   f32 x4   ground-truth box x, y, w, h (top-left origin, pixels)
//!     16  u16      visible fraction of the target, per mille (0 = absent or fully hidden)
//!     18  u16      reserved, 0
//!   20 * T  [u8]   the frame bytes
//! ```
//!
//! Everything is validated and reported as a [`FixtureError`]; nothing
//! panics on a truncated or inconsistent file.
#![cfg_attr(not(test), no_std)]

use core::fmt;
use pftrack::{BoundingBox, Frame, FrameError, PixelFormat};

/// The magic bytes at the start of every fixture.
pub const MAGIC: &[u8; 8] = b"PFTRKFX1";
/// The version of a fixture with one target.
pub const VERSION: u16 = 1;
/// The version of a fixture with several targets.
pub const VERSION_TARGETS: u16 = 2;
/// The most targets a fixture holds.
pub const MAX_TARGETS: u16 = 16;
/// Size of the header in bytes.
pub const HEADER_LEN: usize = 32;
/// Size of a frame record's metadata, before its pixels.
pub const RECORD_META_LEN: usize = 20;

/// Why a fixture could not be read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FixtureError {
    /// Shorter than the header.
    TruncatedHeader {
        /// Bytes available.
        len: usize,
    },
    /// The magic bytes are wrong: not a fixture.
    BadMagic,
    /// A version this code does not read.
    UnsupportedVersion(u16),
    /// An unknown pixel format code.
    UnknownFormat(u16),
    /// A fixture of several targets (version 2) whose target count is not
    /// 2 to [`MAX_TARGETS`].
    BadTargets(u16),
    /// The header's dimensions are inconsistent.
    BadDimensions(FrameError),
    /// The file ends inside frame `index`.
    TruncatedFrame {
        /// The frame, from 0.
        index: u32,
        /// Bytes its record needs.
        expected_len: usize,
        /// Bytes that remain.
        actual_len: usize,
    },
    /// Bytes after the last frame.
    TrailingBytes {
        /// How many.
        extra: usize,
    },
    /// A ground-truth value is NaN or infinite.
    BadGroundTruth {
        /// The frame, from 0.
        index: u32,
    },
    /// A visibility above 1000 per mille.
    BadVisibility {
        /// The frame, from 0.
        index: u32,
        /// The value found.
        value: u16,
    },
}

impl fmt::Display for FixtureError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FixtureError::TruncatedHeader { len } => {
                write!(f, "file is {len} bytes, shorter than the {HEADER_LEN}-byte fixture header")
            }
            FixtureError::BadMagic => write!(f, "not a pftrack fixture (bad magic bytes)"),
            FixtureError::UnsupportedVersion(v) => {
                write!(f, "fixture version {v} is not supported (want {VERSION} or {VERSION_TARGETS})")
            }
            FixtureError::BadTargets(n) => {
                write!(f, "a fixture of several targets says it has {n} (want 2 to {MAX_TARGETS})")
            }
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

impl core::error::Error for FixtureError {}

fn u16_at(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b.get(at).copied().unwrap_or(0), b.get(at + 1).copied().unwrap_or(0)])
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from(u16_at(b, at)) | (u32::from(u16_at(b, at + 2)) << 16)
}

fn f32_at(b: &[u8], at: usize) -> f32 {
    f32::from_bits(u32_at(b, at))
}

/// A fixture's header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Header {
    /// Pixel format of every frame.
    pub format: PixelFormat,
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Row stride in bytes.
    pub stride: usize,
    /// Number of frame records that follow.
    pub frames: u32,
    /// Number of targets, each with its truth in every record (1 to
    /// [`MAX_TARGETS`]).
    pub targets: u16,
}

impl Header {
    /// Parses and checks a header: the first [`HEADER_LEN`] bytes of a file.
    /// The dimensions are judged by the core, exactly as when tracking.
    pub fn parse(bytes: &[u8]) -> Result<Self, FixtureError> {
        if bytes.len() < HEADER_LEN {
            return Err(FixtureError::TruncatedHeader { len: bytes.len() });
        }
        if bytes.get(..8) != Some(MAGIC.as_slice()) {
            return Err(FixtureError::BadMagic);
        }
        let targets = match u16_at(bytes, 8) {
            VERSION => 1,
            VERSION_TARGETS => match u16_at(bytes, 24) {
                n @ 2..=MAX_TARGETS => n,
                n => return Err(FixtureError::BadTargets(n)),
            },
            v => return Err(FixtureError::UnsupportedVersion(v)),
        };
        let code = u16_at(bytes, 10);
        let format = PixelFormat::from_code(code).ok_or(FixtureError::UnknownFormat(code))?;
        let h = Header {
            format,
            width: u16_at(bytes, 12) as usize,
            height: u16_at(bytes, 14) as usize,
            stride: u32_at(bytes, 16) as usize,
            frames: u32_at(bytes, 20),
            targets,
        };
        // With an empty buffer, consistent dimensions fail only on its length.
        match Frame::new(&[], h.width, h.height, h.stride, h.format) {
            Ok(_) | Err(FrameError::BufferTooSmall { .. }) => Ok(h),
            Err(e) => Err(FixtureError::BadDimensions(e)),
        }
    }

    /// The header's bytes.
    pub fn to_bytes(&self) -> [u8; HEADER_LEN] {
        let mut b = [0u8; HEADER_LEN];
        let (version, targets) = if self.targets > 1 { (VERSION_TARGETS, self.targets) } else { (VERSION, 0) };
        let fields: [(usize, &[u8]); 8] = [
            (0, MAGIC),
            (8, &version.to_le_bytes()),
            (10, &self.format.code().to_le_bytes()),
            (12, &(self.width as u16).to_le_bytes()),
            (14, &(self.height as u16).to_le_bytes()),
            (16, &(self.stride as u32).to_le_bytes()),
            (20, &self.frames.to_le_bytes()),
            (24, &targets.to_le_bytes()),
        ];
        for (at, v) in fields {
            if let Some(dst) = b.get_mut(at..at + v.len()) {
                dst.copy_from_slice(v);
            }
        }
        b
    }

    /// Bytes of one frame's pixels: every row padded to the stride, and for
    /// the planar formats the chroma planes after the luma plane, as
    /// [`PixelFormat::frame_bytes`] lays them out.
    pub fn frame_len(&self) -> usize {
        self.format.frame_bytes(self.stride, self.height).unwrap_or(usize::MAX)
    }

    /// Bytes of one frame record's metadata: one [`RECORD_META_LEN`] per
    /// target.
    pub fn meta_len(&self) -> usize {
        RECORD_META_LEN * self.targets.max(1) as usize
    }

    /// Bytes of one frame record, metadata included.
    pub fn record_len(&self) -> usize {
        self.meta_len().saturating_add(self.frame_len())
    }
}

/// A frame record's metadata.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RecordMeta {
    /// The ground-truth box of the target's nominal ellipse.
    pub truth: BoundingBox,
    /// Fraction of the target visible, per mille.
    pub visible_permille: u16,
}

impl RecordMeta {
    /// Parses and checks the first [`RECORD_META_LEN`] bytes of record `index`.
    pub fn parse(bytes: &[u8], index: u32) -> Result<Self, FixtureError> {
        if bytes.len() < RECORD_META_LEN {
            return Err(FixtureError::TruncatedFrame { index, expected_len: RECORD_META_LEN, actual_len: bytes.len() });
        }
        let truth = BoundingBox::new(f32_at(bytes, 0), f32_at(bytes, 4), f32_at(bytes, 8), f32_at(bytes, 12));
        if ![truth.x, truth.y, truth.width, truth.height].iter().all(|v| v.is_finite()) {
            return Err(FixtureError::BadGroundTruth { index });
        }
        let visible_permille = u16_at(bytes, 16);
        if visible_permille > 1000 {
            return Err(FixtureError::BadVisibility { index, value: visible_permille });
        }
        Ok(RecordMeta { truth, visible_permille })
    }

    /// The metadata's bytes.
    pub fn to_bytes(&self) -> [u8; RECORD_META_LEN] {
        let mut b = [0u8; RECORD_META_LEN];
        let t = self.truth;
        for (i, v) in [t.x, t.y, t.width, t.height].into_iter().enumerate() {
            if let Some(dst) = b.get_mut(4 * i..4 * i + 4) {
                dst.copy_from_slice(&v.to_le_bytes());
            }
        }
        if let Some(dst) = b.get_mut(16..18) {
            dst.copy_from_slice(&self.visible_permille.to_le_bytes());
        }
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_round_trip_and_errors() {
        let h = Header { format: PixelFormat::Rgb565, width: 3, height: 2, stride: 8, frames: 5, targets: 1 };
        let b = h.to_bytes();
        assert_eq!(Header::parse(&b), Ok(h));
        // Reason: 20 bytes of metadata + 8 * 2 bytes of pixels.
        assert_eq!(h.record_len(), 36);
        assert_eq!(Header::parse(&b[..31]), Err(FixtureError::TruncatedHeader { len: 31 }));
        let mut bad = b;
        bad[0] = b'X';
        assert_eq!(Header::parse(&bad), Err(FixtureError::BadMagic));
        let mut bad = b;
        bad[8] = 9;
        assert_eq!(Header::parse(&bad), Err(FixtureError::UnsupportedVersion(9)));
        let mut bad = b;
        bad[10] = 77;
        assert_eq!(Header::parse(&bad), Err(FixtureError::UnknownFormat(77)));
        let mut bad = b;
        bad[16] = 2; // stride 2 < 3 px * 2 bytes
        assert!(matches!(Header::parse(&bad), Err(FixtureError::BadDimensions(FrameError::StrideTooSmall { .. }))));
    }

    #[test]
    fn several_targets_are_version_2_with_a_truth_each() {
        // Reason: the layout above. Three targets: version 2, the count at
        // byte 24, and records of 3 * 20 bytes of metadata before the
        // 8 * 2 bytes of pixels. One target writes version 1, as ever.
        let h = Header { format: PixelFormat::Rgb565, width: 3, height: 2, stride: 8, frames: 5, targets: 3 };
        let b = h.to_bytes();
        assert_eq!((b[8], b[24]), (2, 3));
        assert_eq!(Header::parse(&b), Ok(h));
        assert_eq!((h.meta_len(), h.record_len()), (60, 76));
        let one = Header { targets: 1, ..h }.to_bytes();
        assert_eq!((one[8], one[24]), (1, 0));
        for n in [0u16, 1, 17] {
            let mut bad = b;
            bad[24..26].copy_from_slice(&n.to_le_bytes());
            assert_eq!(Header::parse(&bad), Err(FixtureError::BadTargets(n)));
        }
    }

    #[test]
    fn meta_round_trip_and_errors() {
        let m = RecordMeta { truth: BoundingBox::new(1.5, 2.0, 3.0, 4.0), visible_permille: 750 };
        assert_eq!(RecordMeta::parse(&m.to_bytes(), 0), Ok(m));
        let mut bad = m.to_bytes();
        bad[..4].copy_from_slice(&f32::NAN.to_le_bytes());
        assert_eq!(RecordMeta::parse(&bad, 3), Err(FixtureError::BadGroundTruth { index: 3 }));
        let mut bad = m.to_bytes();
        bad[16..18].copy_from_slice(&1001u16.to_le_bytes());
        assert_eq!(RecordMeta::parse(&bad, 0), Err(FixtureError::BadVisibility { index: 0, value: 1001 }));
        assert!(matches!(RecordMeta::parse(&bad[..10], 2), Err(FixtureError::TruncatedFrame { index: 2, .. })));
    }
}
