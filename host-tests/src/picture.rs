//! Pictures of what the tracker did: each frame with the estimated ellipse (white),
//! the ground-truth box (cyan), a sample of the particles (magenta), and a status bar whose
//! colour is the state (green tracking, red lost, grey searching) and whose
//! length is the confidence. Written as an animated GIF.

use pftrack::{BoundingBox, Ellipse, Estimate, TrackState};
use std::path::Path;

/// An RGB image being drawn on.
pub struct Canvas {
    width: usize,
    height: usize,
    rgb: Vec<u8>,
}

const ESTIMATE: [u8; 3] = [255, 255, 255];
const TRUTH: [u8; 3] = [0, 220, 255];
const PARTICLE: [u8; 3] = [255, 60, 200];

impl Canvas {
    /// A canvas of packed RGB888 pixels.
    pub fn new(width: usize, height: usize, rgb: Vec<u8>) -> Self {
        Canvas { width, height, rgb }
    }

    fn put(&mut self, x: i64, y: i64, c: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as usize) < self.width && (y as usize) < self.height {
            let at = (y as usize * self.width + x as usize) * 3;
            self.rgb[at..at + 3].copy_from_slice(&c);
        }
    }

    /// A rectangle outline.
    pub fn rect(&mut self, b: &BoundingBox, c: [u8; 3]) {
        let (x0, y0) = (b.x.round() as i64, b.y.round() as i64);
        let (x1, y1) = ((b.x + b.width).round() as i64 - 1, (b.y + b.height).round() as i64 - 1);
        for x in x0..=x1 {
            self.put(x, y0, c);
            self.put(x, y1, c);
        }
        for y in y0..=y1 {
            self.put(x0, y, c);
            self.put(x1, y, c);
        }
    }

    /// An ellipse outline.
    pub fn ellipse(&mut self, e: &Ellipse, c: [u8; 3]) {
        let steps = ((e.hx + e.hy) * 4.0).clamp(16.0, 2000.0) as usize;
        for i in 0..steps {
            let t = i as f32 / steps as f32 * std::f32::consts::TAU;
            self.put((e.cx + e.hx * t.cos()).round() as i64, (e.cy + e.hy * t.sin()).round() as i64, c);
        }
    }

    /// A 3x3 dot.
    pub fn dot(&mut self, x: f32, y: f32, c: [u8; 3]) {
        let (x, y) = (x.round() as i64, y.round() as i64);
        for dy in -1..=1 {
            for dx in -1..=1 {
                self.put(x + dx, y + dy, c);
            }
        }
    }

    /// The status bar along the top edge.
    pub fn status(&mut self, state: TrackState, confidence: f32) {
        let c = match state {
            TrackState::Tracking => [40, 220, 60],
            TrackState::Lost => [230, 40, 40],
            TrackState::Searching => [150, 150, 150],
        };
        let len = (confidence.clamp(0.0, 1.0) * self.width as f32).round() as i64;
        for y in 0..4 {
            for x in 0..self.width as i64 {
                self.put(x, y, if x < len { c } else { [0, 0, 0] });
            }
        }
    }

    /// The picture scaled up by an integer factor (nearest neighbour).
    pub fn scaled(&self, k: usize) -> Canvas {
        let (w, h) = (self.width * k, self.height * k);
        let mut rgb = Vec::with_capacity(w * h * 3);
        for y in 0..h {
            for x in 0..w {
                let at = ((y / k) * self.width + x / k) * 3;
                rgb.extend_from_slice(&self.rgb[at..at + 3]);
            }
        }
        Canvas { width: w, height: h, rgb }
    }

    /// The pixels, packed RGB888.
    pub fn pixels(&self) -> &[u8] {
        &self.rgb
    }
}

/// The colours targets are drawn in, by identity (repeating).
const TARGET_COLOURS: [[u8; 3]; 6] =
    [[255, 255, 255], [255, 220, 0], [0, 230, 255], [255, 80, 200], [120, 255, 80], [255, 140, 40]];

/// A 3x5 pixel font for the digits 0-9, a row of three bits each, top first.
const DIGITS: [[u8; 5]; 10] = [
    [7, 5, 5, 5, 7],
    [2, 6, 2, 2, 7],
    [7, 1, 7, 4, 7],
    [7, 1, 7, 1, 7],
    [5, 5, 7, 1, 1],
    [7, 4, 7, 1, 7],
    [7, 4, 7, 5, 7],
    [7, 1, 1, 1, 1],
    [7, 5, 7, 5, 7],
    [7, 5, 7, 1, 7],
];

impl Canvas {
    /// Writes the number `n` in 3x5 digits, each pixel doubled, with its top
    /// left at `(x, y)`.
    pub fn number(&mut self, x: i64, y: i64, n: u32, c: [u8; 3]) {
        for (k, ch) in n.to_string().bytes().enumerate() {
            let rows = DIGITS[(ch - b'0') as usize];
            for (dy, bits) in rows.iter().enumerate() {
                for dx in 0..3 {
                    if bits >> (2 - dx) & 1 == 1 {
                        let (px, py) = (x + 8 * k as i64 + 2 * dx as i64, y + 2 * dy as i64);
                        for (ox, oy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                            self.put(px + ox, py + oy, c);
                        }
                    }
                }
            }
        }
    }
}

/// Draws several targets' estimates: each in its identity's colour, with
/// its identity written above its box; a target not tracked is drawn dimmed.
pub fn annotate_targets(canvas: &mut Canvas, targets: &[(u16, Estimate)]) {
    for (id, e) in targets {
        let mut c = TARGET_COLOURS[*id as usize % TARGET_COLOURS.len()];
        if e.state != TrackState::Tracking {
            c = c.map(|v| v / 3);
        }
        canvas.ellipse(&e.ellipse, c);
        let b = e.bbox();
        canvas.number(b.x.round() as i64, b.y.round() as i64 - 12, *id as u32, c);
    }
}

/// Draws one frame's overlay.
pub fn annotate(canvas: &mut Canvas, est: Option<&Estimate>, truth: Option<&BoundingBox>, particles: &[(f32, f32)]) {
    for &(x, y) in particles {
        canvas.dot(x, y, PARTICLE);
    }
    if let Some(t) = truth {
        canvas.rect(t, TRUTH);
    }
    if let Some(e) = est {
        canvas.ellipse(&e.ellipse, ESTIMATE);
        canvas.status(e.state, e.confidence);
    }
}

/// The frames of an annotated GIF, at most [`GifFrames::MAX`] however long
/// the input: every `every`-th frame, evenly spaced when the length is known;
/// otherwise, when the list overflows, every other frame is dropped and
/// `every` doubles. Small frames are enlarged so the overlay stays legible.
pub struct GifFrames {
    canvases: Vec<Canvas>,
    every: usize,
    scale: usize,
}

impl GifFrames {
    /// The most frames a GIF keeps.
    pub const MAX: usize = 300;

    /// For frames `width` pixels wide, `len` of them if known.
    pub fn new(width: usize, len: Option<usize>) -> Self {
        let every = len.map_or(1, |n| n.div_ceil(Self::MAX).max(1));
        GifFrames { canvases: Vec::new(), every, scale: (480 / width.max(1)).clamp(1, 4) }
    }

    /// Whether frame `i` (from 0) goes into the GIF: callers skip drawing
    /// what would be dropped.
    pub fn wants(&self, i: usize) -> bool {
        i.is_multiple_of(self.every)
    }

    /// Frames between two kept ones.
    pub fn every(&self) -> usize {
        self.every
    }

    /// Adds frame `i` (from 0), `rgb` its pixels, with its overlay, if it is
    /// one to keep.
    pub fn push(
        &mut self,
        i: usize,
        (width, height, rgb): (usize, usize, Vec<u8>),
        est: Option<&Estimate>,
        truth: Option<&BoundingBox>,
        particles: &[(f32, f32)],
    ) {
        self.push_drawn(i, (width, height, rgb), |c| annotate(c, est, truth, particles));
    }

    /// Adds frame `i` (from 0), `rgb` its pixels, with what `draw` draws on
    /// it, if it is one to keep.
    pub fn push_drawn(
        &mut self,
        i: usize,
        (width, height, rgb): (usize, usize, Vec<u8>),
        draw: impl FnOnce(&mut Canvas),
    ) {
        if !self.wants(i) {
            return;
        }
        let mut c = Canvas::new(width, height, rgb);
        draw(&mut c);
        self.canvases.push(c.scaled(self.scale));
        if self.canvases.len() > Self::MAX {
            let mut n = 0;
            self.canvases.retain(|_| {
                n += 1;
                n % 2 == 1
            });
            self.every *= 2;
        }
    }

    /// Writes the GIF, frames `delay_ms` apart, and with `still` its middle
    /// frame as a PNG.
    pub fn write(&self, gif: &Path, still: Option<&Path>, delay_ms: u32) -> Result<(), String> {
        write_gif(gif, &self.canvases, delay_ms)?;
        match (still, self.canvases.get(self.canvases.len() / 2)) {
            (Some(path), Some(mid)) => write_png(path, mid),
            _ => Ok(()),
        }
    }
}

/// Writes frames as an animated GIF, `delay_ms` apart.
pub fn write_gif(path: &Path, frames: &[Canvas], delay_ms: u32) -> Result<(), String> {
    use image::codecs::gif::{GifEncoder, Repeat};
    use image::{Delay, Frame, RgbaImage};
    let file = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut enc = GifEncoder::new_with_speed(std::io::BufWriter::new(file), 10);
    enc.set_repeat(Repeat::Infinite).map_err(|e| e.to_string())?;
    for c in frames {
        let rgba: Vec<u8> = c.rgb.chunks(3).flat_map(|p| [p[0], p[1], p[2], 255]).collect();
        let img = RgbaImage::from_raw(c.width as u32, c.height as u32, rgba).ok_or("bad canvas size")?;
        enc.encode_frame(Frame::from_parts(img, 0, 0, Delay::from_numer_denom_ms(delay_ms, 1)))
            .map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(())
}

/// Writes one canvas as a PNG.
pub fn write_png(path: &Path, c: &Canvas) -> Result<(), String> {
    image::RgbImage::from_raw(c.width as u32, c.height as u32, c.rgb.clone())
        .ok_or("bad canvas size")?
        .save(path)
        .map_err(|e| format!("{}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drawing_puts_pixels_where_asked_and_nowhere_else() {
        // Reason: a 1-px rectangle outline of a 4x3 box at (2, 1) covers
        // exactly its 10 border pixels (2·4 + 2·1).
        let mut c = Canvas::new(10, 8, vec![0; 10 * 8 * 3]);
        c.rect(&BoundingBox::new(2.0, 1.0, 4.0, 3.0), [255, 0, 0]);
        let lit = c.pixels().chunks(3).filter(|p| p[0] == 255).count();
        assert_eq!(lit, 10);
        // Off-canvas drawing is clipped, not a panic.
        c.dot(-5.0, 100.0, [0, 255, 0]);
        c.ellipse(&Ellipse { cx: -50.0, cy: -50.0, hx: 3.0, hy: 3.0 }, [0, 0, 255]);
        assert_eq!(c.pixels().chunks(3).filter(|p| p[1] == 255 || p[2] == 255).count(), 0);
        // Scaling by 2 quadruples the lit pixels.
        assert_eq!(c.scaled(2).pixels().chunks(3).filter(|p| p[0] == 255).count(), 40);
    }
}
