//! Whole fixtures in memory, on top of the `pftrack-fixture` codecs (which
//! the firmware and the Linux trace runner share; the format is documented
//! there and in the README).

#[cfg(test)]
use pftrack::FrameError;
use pftrack::{BoundingBox, Frame, PixelFormat};
pub use pftrack_fixture::{FixtureError, HEADER_LEN, Header, MAGIC, RECORD_META_LEN, RecordMeta, VERSION};

/// One frame of a fixture: its pixels and what the scene knows about it.
#[derive(Debug, Clone, PartialEq)]
pub struct FixtureFrame {
    /// The ground-truth box of the target's nominal ellipse.
    pub truth: BoundingBox,
    /// Fraction of the target visible, per mille.
    pub visible_permille: u16,
    /// The truths of the other targets of a fixture with several, in the
    /// order they are added (empty for one target).
    pub others: Vec<RecordMeta>,
    /// `stride * height` bytes of pixels.
    pub pixels: Vec<u8>,
}

impl FixtureFrame {
    /// Every target's truth and visibility, the first target's first.
    pub fn targets(&self) -> impl Iterator<Item = RecordMeta> + '_ {
        let first = RecordMeta { truth: self.truth, visible_permille: self.visible_permille };
        std::iter::once(first).chain(self.others.iter().copied())
    }
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

impl Fixture {
    /// Parses a fixture held in memory.
    pub fn parse(bytes: &[u8]) -> Result<Self, FixtureError> {
        let h = Header::parse(bytes)?;
        let record_len = h.record_len();
        let mut frames = Vec::new();
        let mut at = HEADER_LEN;
        for index in 0..h.frames {
            let rest = bytes.len() - at;
            if rest < record_len {
                return Err(FixtureError::TruncatedFrame { index, expected_len: record_len, actual_len: rest });
            }
            let meta = RecordMeta::parse(&bytes[at..at + RECORD_META_LEN], index)?;
            let others = (1..h.targets as usize)
                .map(|k| RecordMeta::parse(&bytes[at + k * RECORD_META_LEN..], index))
                .collect::<Result<_, _>>()?;
            let pixels = bytes[at + h.meta_len()..at + record_len].to_vec();
            frames.push(FixtureFrame { truth: meta.truth, visible_permille: meta.visible_permille, others, pixels });
            at += record_len;
        }
        if at != bytes.len() {
            return Err(FixtureError::TrailingBytes { extra: bytes.len() - at });
        }
        Ok(Fixture { format: h.format, width: h.width, height: h.height, stride: h.stride, frames })
    }

    /// Serialises the fixture.
    pub fn to_bytes(&self) -> Vec<u8> {
        let h = Header {
            format: self.format,
            width: self.width,
            height: self.height,
            stride: self.stride,
            frames: self.frames.len() as u32,
            targets: self.frames.first().map_or(1, |f| 1 + f.others.len() as u16),
        };
        let mut out = Vec::with_capacity(HEADER_LEN + self.frames.len() * h.record_len());
        out.extend_from_slice(&h.to_bytes());
        for f in &self.frames {
            for m in f.targets() {
                out.extend_from_slice(&m.to_bytes());
            }
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
                    others: Vec::new(),
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
