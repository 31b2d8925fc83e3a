//! The searches around the filter's estimate: size and shape, position,
//! and re-detection of a lost target.

use super::scratch::*;
use crate::config::Config;
use crate::filter::Particle;
use crate::foreground::{ForegroundMap, RING};
use crate::frame::Frame;
use crate::geometry::Ellipse;
use crate::scalar::{Real, ln, unit_from_bits};
use rand_core::Rng;

/// What the size and position searches measure of a candidate box: its
/// contrast with its ring in the foreground map, and, once asked for, its
/// similarity with the models and its grey-level correlation with the
/// template. The winner's parts are handed on, so that the next
/// search and the confidence do not measure the same box again.
#[derive(Copy, Clone)]
pub(super) struct Parts {
    pub(super) contrast: Real,
    pub(super) sim: Option<Real>,
    pub(super) correlation: Option<Real>,
}

impl Parts {
    /// The contrast of the box of `c`; `None` where the map cannot say.
    pub(super) fn of<const K: usize, const E: usize>(sc: &Scratch<K, E>, c: &Ellipse) -> Option<Parts> {
        Some(Parts { contrast: sc.fgmap.contrast(c, RING)?, sim: None, correlation: None })
    }

    /// The score a search ranks the box of `c` by: contrast plus
    /// `similarity` times its similarity and `template` times its
    /// correlation, each measured on first use.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn score<const K: usize, const E: usize>(
        &mut self,
        sc: &mut Scratch<K, E>,
        cfg: &Config,
        frame: &Frame<'_>,
        models: &Models<K>,
        c: &Ellipse,
        similarity: Real,
        template: Real,
    ) -> Real {
        let mut score = self.contrast;
        if template > 0.0 {
            score += template * *self.correlation.get_or_insert_with(|| models.template.correlation(frame, c));
        }
        if similarity > 0.0 {
            score += similarity * *self.sim.get_or_insert_with(|| sc.similarity(cfg, frame, models, c, false).sim);
        }
        score
    }
}

/// The factors on the half axes of `e` whose box scores best (see
/// [`crate::SizeSearch`]), with that box's parts; the foreground map must
/// cover the largest candidate's ring.
pub(super) fn search_size<const K: usize, const E: usize>(
    sc: &mut Scratch<K, E>,
    cfg: &Config,
    frame: &Frame<'_>,
    models: &Models<K>,
    e: &Ellipse,
    search: &crate::config::SizeSearch,
    (ix, iy): (Real, Real),
) -> ((Real, Real), Option<Parts>) {
    let up = 1.0 + search.step;
    let dn = 1.0 / up;
    // The mean first, so that a tie keeps it; then one step along each
    // axis, and the two turns (wider and shorter, narrower and taller) so
    // that the aspect can follow a turning target at twice the rate; or
    // one step in scale only.
    let candidates: &[(Real, Real)] = if search.aspect {
        &[(1.0, 1.0), (up, 1.0), (dn, 1.0), (1.0, up), (1.0, dn), (up, dn), (dn, up)]
    } else {
        &[(1.0, 1.0), (up, up), (dn, dn)]
    };
    let mut best = ((1.0, 1.0), None);
    let mut best_score = Real::NEG_INFINITY;
    for &(fx, fy) in candidates {
        let c = Ellipse { hx: e.hx * fx, hy: e.hy * fy, ..*e };
        let Some(mut parts) = Parts::of(sc, &c) else { continue };
        let mut score = parts.score(sc, cfg, frame, models, &c, search.similarity, search.template);
        if search.aspect_pull > 0.0 {
            score -= search.aspect_pull * ln((c.hx * iy) / (c.hy * ix)).abs();
        }
        if search.scale_pull > 0.0 {
            score -= search.scale_pull * ln((c.hx * c.hy) / (ix * iy)).abs();
        }
        if score > best_score {
            (best, best_score) = (((fx, fy), Some(parts)), score);
        }
    }
    best
}

/// The offset of the best box on a hill climb from `e`, one step left,
/// right, up or down per round, scored like the size search's candidates,
/// with that box's parts; `start` holds what is known of `e`'s.
pub(super) fn search_shift<const K: usize, const E: usize>(
    sc: &mut Scratch<K, E>,
    cfg: &Config,
    frame: &Frame<'_>,
    models: &Models<K>,
    e: &Ellipse,
    search: &crate::config::ShiftSearch,
    start: Option<Parts>,
) -> ((Real, Real), Option<Parts>) {
    let (sx, sy) = (2.0 * search.step * e.hx, 2.0 * search.step * e.hy);
    let (w, h) = (frame.width() as Real, frame.height() as Real);
    let (mut dx, mut dy) = (0.0, 0.0);
    let Some(mut parts) = start.or_else(|| Parts::of(sc, e)) else { return ((0.0, 0.0), None) };
    let mut best = parts.score(sc, cfg, frame, models, e, search.similarity, search.template);
    for _ in 0..search.rounds {
        let mut next = None;
        for (mx, my) in [(sx, 0.0), (-sx, 0.0), (0.0, sy), (0.0, -sy)] {
            // The offset summed first: the winner is then exactly the box
            // the caller moves the estimate to, whose parts these are.
            let c = Ellipse { cx: e.cx + (dx + mx), cy: e.cy + (dy + my), ..*e };
            if !(c.cx >= 0.0 && c.cx <= w && c.cy >= 0.0 && c.cy <= h) {
                continue;
            }
            let Some(mut p) = Parts::of(sc, &c) else { continue };
            let score = p.score(sc, cfg, frame, models, &c, search.similarity, search.template);
            if score > best {
                (best, next) = (score, Some((mx, my, p)));
            }
        }
        let Some((mx, my, p)) = next else { break };
        (dx, dy, parts) = (dx + mx, dy + my, p);
    }
    ((dx, dy), Some(parts))
}

/// Spots re-detection proposes.
pub(super) const SPOTS: usize = 4;

/// The centres of the (at most [`SPOTS`]) target-sized boxes of `frame`
/// that stand out most from their surroundings in the foreground map,
/// best first, at least one box apart, among the centres in `area`
/// (`x0, y0, x1, y1`) that keep the box in the frame.
pub(super) fn redetect<const K: usize>(
    map: &mut ForegroundMap<FG_CELLS>,
    frame: &Frame<'_>,
    models: &Models<K>,
    (hx, hy): (Real, Real),
    area: (Real, Real, Real, Real),
) -> [Option<(Real, Real)>; SPOTS] {
    let (w, h) = (frame.width() as Real, frame.height() as Real);
    let (x0, y0, x1, y1) = (area.0.max(hx), area.1.max(hy), area.2.min(w - hx), area.3.min(h - hy));
    // The map covers the boxes' surroundings too (it clips to the frame).
    let (rx, ry) = (RING * hx, RING * hy);
    let rect = ((x0 - rx) as i32, (y0 - ry) as i32, (x1 + rx) as i32 + 1, (y1 + ry) as i32 + 1);
    map.compute(frame, rect, &models.layout, &models.fg);
    let stride = hx.min(hy).max(map.step() as Real);
    let mut best: [Option<(Real, Real, Real)>; SPOTS] = [None; SPOTS];
    let mut y = y0;
    while y < y1 {
        let mut x = x0;
        while x < x1 {
            if let Some(c) = map.contrast(&Ellipse { cx: x, cy: y, hx, hy }, RING) {
                // Insert into the list if it beats an entry and is not next to a better one.
                let near = |&(bx, by, _): &(Real, Real, Real)| (bx - x).abs() < 2.0 * hx && (by - y).abs() < 2.0 * hy;
                let dominated = best.iter().flatten().any(|b| near(b) && b.2 >= c);
                if !dominated && c > 0.0 {
                    // Weaker neighbours make way; the rest keep their order.
                    let mut kept = [None; SPOTS];
                    for (slot, b) in kept.iter_mut().zip(best.iter().flatten().filter(|b| !near(b))) {
                        *slot = Some(*b);
                    }
                    // The candidate goes before the first spot it matches or
                    // beats; each one it displaces moves down, the last drops.
                    let mut item = Some((x, y, c));
                    for slot in kept.iter_mut() {
                        let Some(i) = item else { break };
                        match slot {
                            Some(b) if b.2 > i.2 => {}
                            _ => item = slot.replace(i),
                        }
                    }
                    best = kept;
                }
            }
            x += stride;
        }
        y += stride;
    }
    best.map(|b| b.map(|(x, y, _)| (x, y)))
}

/// A particle at rest anywhere in `area` (`x0, y0, x1, y1`).
pub(super) fn uniform_particle<R: Rng>(rng: &mut R, area: (Real, Real, Real, Real), hx: Real, hy: Real) -> Particle {
    let (x0, y0, x1, y1) = area;
    let x = x0 + unit_from_bits(rng.next_u32()) * (x1 - x0);
    let y = y0 + unit_from_bits(rng.next_u32()) * (y1 - y0);
    Particle { x, y, hx, hy, ..Default::default() }
}
