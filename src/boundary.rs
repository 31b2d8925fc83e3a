//! The ellipse-boundary gradient cue of the head-tracking paper: how strongly
//! the image brightness changes across the ellipse's outline.
//!
//! A head (or any blob-shaped target) has an edge all round; an ellipse that
//! sits on it sees large intensity gradients along its outline, one that is
//! too small, too large or off-centre sees fewer. The score is the mean of
//! `|n · ∇I|` at [`OUTLINE_POINTS`] points of the outline, with `n` the unit
//! normal and `∇I` the Sobel gradient of luma (Birchfield's head tracker, as
//! the paper uses it). The tracker normalises it by the best particle's
//! score in each frame, the paper's normalised score, and mixes it with the
//! colour similarity (see [`BoundaryCue`]).

use crate::cue::not_built;
use crate::edges::sobel;
use crate::error::Checks;
use crate::frame::Frame;
use crate::geometry::Ellipse;
use crate::pixel::luma;
use crate::region::floor;
use crate::scalar::{Real, sqrt};

/// The ellipse-boundary gradient cue: each particle's mean normal gradient
/// along its outline (`boundary::outline_gradient`, built with the `boundary` feature) divided by the
/// best particle's in the frame, mixed with the histogram similarity `s` as
/// `(1 − weight) · s + weight · g`: the head-tracking paper's sum of
/// normalised scores, weighted.
#[derive(Copy, Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BoundaryCue {
    /// Share of the boundary score, in `[0, 1]` (the paper's plain sum is 0.5).
    pub weight: Real,
}

/// Checks the settings; asking for the cue in a build without it is an
/// error that names the feature.
#[inline]
pub(crate) fn validate(c: &mut Checks, settings: Option<BoundaryCue>) {
    let Some(b) = settings else { return };
    if !cfg!(feature = "boundary") {
        c.fail(not_built("boundary", "boundary"));
    }
    c.share("boundary.weight", b.weight);
}

/// Whether the cue is on: asked for in `settings`, and built (the
/// `boundary` feature).
pub(crate) const fn on(settings: Option<BoundaryCue>) -> bool {
    cfg!(feature = "boundary") && settings.is_some()
}

/// The boundary score of `e`, in 1/16 Sobel units (0 in a build without
/// the cue).
pub(crate) fn score(frame: &Frame<'_>, e: &Ellipse) -> u16 {
    if cfg!(feature = "boundary") { (outline_gradient(frame, e) * 16.0).min(u16::MAX as Real) as u16 } else { 0 }
}

/// Points sampled on each outline.
pub const OUTLINE_POINTS: usize = 16;

/// `(cos θ, sin θ)` at `θ = 2πk / 16`: a table, so that no trigonometry runs
/// on the target and every target gets the same bits.
const UNIT: [(Real, Real); OUTLINE_POINTS] = [
    (1.0, 0.0),
    (0.923_879_5, 0.382_683_43),
    (0.707_106_77, 0.707_106_77),
    (0.382_683_43, 0.923_879_5),
    (0.0, 1.0),
    (-0.382_683_43, 0.923_879_5),
    (-0.707_106_77, 0.707_106_77),
    (-0.923_879_5, 0.382_683_43),
    (-1.0, 0.0),
    (-0.923_879_5, -0.382_683_43),
    (-0.707_106_77, -0.707_106_77),
    (-0.382_683_43, -0.923_879_5),
    (0.0, -1.0),
    (0.382_683_43, -0.923_879_5),
    (0.707_106_77, -0.707_106_77),
    (0.923_879_5, -0.382_683_43),
];

/// The mean normal gradient along the outline of `e`, in Sobel units of
/// 8-bit luma (0 to about 1020). Outline points whose 3x3 window leaves the
/// frame are skipped; 0 if none is inside.
pub fn outline_gradient(frame: &Frame<'_>, e: &Ellipse) -> Real {
    if !(e.cx.is_finite() && e.cy.is_finite() && e.hx > 0.0 && e.hy > 0.0 && e.hx.is_finite() && e.hy.is_finite()) {
        return 0.0;
    }
    let (w, h) = (frame.width() as i32, frame.height() as i32);
    let limit = (2 * crate::pixel::MAX_DIMENSION) as Real;
    let (mut sum, mut n) = (0.0 as Real, 0u32);
    for &(c, s) in UNIT.iter() {
        let (px, py) = (e.cx + e.hx * c, e.cy + e.hy * s);
        if !(px.abs() < limit && py.abs() < limit) {
            continue;
        }
        let (x, y) = (floor(px), floor(py));
        if x < 1 || y < 1 || x >= w - 1 || y >= h - 1 {
            continue;
        }
        let mut win = [0i32; 9];
        for (i, v) in win.iter_mut().enumerate() {
            let (dx, dy) = ((i % 3) as i32 - 1, (i / 3) as i32 - 1);
            *v = frame.rgb((x + dx) as usize, (y + dy) as usize).map(luma).unwrap_or(0) as i32;
        }
        let (gx, gy) = sobel(win);
        // The outward normal of (hx cos θ, hy sin θ) is along (cos θ / hx, sin θ / hy).
        let (nx, ny) = (c * e.hy, s * e.hx);
        let norm = sqrt(nx * nx + ny * ny);
        if norm > 0.0 {
            sum += (gx as Real * nx + gy as Real * ny).abs() / norm;
            n += 1;
        }
    }
    if n == 0 { 0.0 } else { sum / n as Real }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::PixelFormat;

    /// A dark disc of radius 15 at (50, 40) on a bright background.
    fn disc() -> Vec<u8> {
        let (w, h) = (100usize, 80usize);
        let mut px = vec![200u8; w * h];
        for y in 0..h {
            for x in 0..w {
                let (dx, dy) = (x as f32 + 0.5 - 50.0, y as f32 + 0.5 - 40.0);
                if dx * dx + dy * dy < 15.0 * 15.0 {
                    px[y * w + x] = 40;
                }
            }
        }
        px
    }

    #[test]
    fn the_outline_on_the_edge_scores_highest() {
        // Reason: ground truth from the generated disc: only an outline on
        // its rim crosses the 160-level step, so the true circle must beat
        // smaller, larger and shifted ones; and on the rim a Sobel step of
        // 160 gives |∇I| near 4·160 = 640 where the window straddles it.
        let px = disc();
        let f = Frame::packed(&px, 100, 80, PixelFormat::Gray8).unwrap();
        let at = |cx: f32, cy: f32, r: f32| outline_gradient(&f, &Ellipse { cx, cy, hx: r, hy: r });
        let truth = at(50.0, 40.0, 15.0);
        assert!(truth > 300.0, "{truth}");
        for (cx, cy, r) in [(50.0, 40.0, 10.0), (50.0, 40.0, 21.0), (56.0, 40.0, 15.0), (50.0, 33.0, 15.0)] {
            let other = at(cx, cy, r);
            assert!(other < 0.7 * truth, "({cx},{cy},{r}): {other} vs {truth}");
        }
        // Flat image: no gradient anywhere.
        let flat = vec![90u8; 100 * 80];
        let g = Frame::packed(&flat, 100, 80, PixelFormat::Gray8).unwrap();
        assert_eq!(outline_gradient(&g, &Ellipse { cx: 50.0, cy: 40.0, hx: 15.0, hy: 15.0 }), 0.0);
        // Entirely off-frame or degenerate: 0, not a panic.
        assert_eq!(at(-500.0, -500.0, 5.0), 0.0);
        assert_eq!(at(f32::NAN, 40.0, 5.0), 0.0);
        assert_eq!(at(50.0, 40.0, 0.0), 0.0);
    }

    #[test]
    fn unit_table_is_the_unit_circle() {
        // Reason: cos² + sin² = 1 and the angles are 22.5° apart (f64 reference).
        for (k, &(c, s)) in UNIT.iter().enumerate() {
            let a = 2.0 * core::f64::consts::PI * k as f64 / 16.0;
            assert!((c as f64 - a.cos()).abs() < 1e-7 && (s as f64 - a.sin()).abs() < 1e-7, "{k}");
        }
    }
}
