//! Whether the estimate moves with its surroundings: for a target that has
//! been seen to move against them, a box that no longer does has slid onto
//! the background.
//!
//! A box that drifts off its target onto a patch of the target's colours
//! (a stone urn beside a walker, the dirt a cyclist rode off) looks right to
//! every colour and template test, but it moves with the scene: as the
//! camera pans, the box and the ring around it shift alike, while a walking
//! target moves against its ring. Each frame, [`SceneMotion`] reads the luma
//! of the box on an 8 × 8 lattice and that of its surroundings on an 8 × 8
//! lattice over twice the box, less the points inside the box (112
//! samples). On the next frame it finds the shift at which each set best
//! matches the new frame (least mean absolute difference): the ring's from
//! its last shift, in steps of 2 then 1 pixel (scenes move smoothly); the
//! box's from the ring's, in unit steps; each then to a fraction of a
//! pixel, by a parabola through the best whole shift's difference and its
//! neighbours'. It keeps running means of the ring's motion and of the
//! box's motion against the ring's.
//!
//! A static target filmed from a moving camera (a building from a drone)
//! also moves with its surroundings, so the test applies only to a target
//! that moved against them over its first [`EARLY`] tracked frames, when
//! the box is still on it: by its net displacement against them, the sum
//! of its motions as vectors, so that the small errors of each frame's
//! match, which point every way and cancel, do not make a still target
//! with little texture count as moving (measured on the real sequences:
//! docs/accuracy.md). Measured offline on the real sequences
//! (`tools/local-motion`, full-resolution matching), the test flags most of
//! the frames of the two sequences where the box is left on the background
//! and few of the frames on the target.

use crate::cue::Cue;
use crate::frame::Frame;
use crate::geometry::Ellipse;
use crate::pixel::{self, Loop, Loops, PixelRead, RowReader};
use crate::scalar::{Real, sqrt};

/// Lattice points per side, for the box and for the window around it.
const GRID: usize = 8;
/// Points of the box's lattice.
const BOX_POINTS: usize = GRID * GRID;
/// Points of the window's lattice outside the box: the window's lattice
/// is twice as coarse, so the box covers its middle half on each axis.
const RING_POINTS: usize = GRID * GRID - (GRID / 2) * (GRID / 2);
/// Tracked frames over which the target shows whether it moves against its
/// surroundings.
pub(crate) const EARLY: u16 = 20;
/// A box moving less than this against its ring, in pixels a frame (running
/// mean), moves with it; a target whose net displacement against its ring
/// over its first frames is at least this much a frame is one that moves.
pub(crate) const STILL: Real = 0.5;
/// A ring moving at least this much, in pixels a frame (running mean),
/// tells a moving camera (or scene); with a still one there is nothing to
/// compare.
pub(crate) const MOVING: Real = 1.0;
/// Weight of each frame in the running means (about the last ten frames).
const RATE: Real = 0.2;

/// The last frame's samples around the estimate and the running means of
/// the motion measured from them.
#[derive(Clone, Debug)]
pub(crate) struct SceneMotion {
    /// Luma of the box's lattice points (0 for those outside the frame:
    /// which they are follows from the box, [`Lattice::rows_in`]).
    inner: [u8; BOX_POINTS],
    /// Luma of the ring's lattice points (the same).
    outer: [u8; RING_POINTS],
    /// The last box given: the samples were read on it if it has lattices
    /// (a box without, such as the NaN box of a new state, is not read).
    /// Not an `Option`, whose tag would take a word of its own (4 bytes in
    /// every tracker): whether it was read follows from the box.
    at: Ellipse,
    /// Running means: the box's motion against the ring's, and the ring's,
    /// in pixels a frame.
    against: Real,
    ring: Real,
    /// The ring's last shift, where its search starts (scenes move
    /// smoothly); 16 bits, as frames are (`MAX_DIMENSION`).
    last: (i16, i16),
    /// Sum of the box's motion against the ring over the first tracked
    /// frames, as a vector in pixels, and how many tracked frames were
    /// measured.
    early: (Real, Real),
    frames: u16,
}

/// Which points of a lattice lay in the frame when read: per lattice row,
/// bit `i` for column `i`.
type Rows = [u8; GRID];

/// A lattice over a box: `GRID` pixel columns and rows, and whether the
/// middle half on each axis is left out (the window's lattice, whose middle
/// is the box).
struct Lattice {
    xs: [i32; GRID],
    ys: [i32; GRID],
    hole: bool,
}

impl Lattice {
    /// The box's lattice of `e` (`window` false: points spaced an eighth of
    /// the box) or its window's (`window` true: an eighth of twice the box,
    /// less the middle half on each axis, which is the box).
    fn of(e: &Ellipse, window: bool) -> Option<Lattice> {
        let k = if window { 2.0 } else { 1.0 };
        let (x0, y0) = (e.cx - k * e.hx, e.cy - k * e.hy);
        let (sx, sy) = (2.0 * k * e.hx / GRID as Real, 2.0 * k * e.hy / GRID as Real);
        // Points lie within a few frame sizes of the frame; a NaN or huge
        // box has no lattice.
        if !(x0.abs() < 1.0e6 && y0.abs() < 1.0e6 && sx.abs() < 1.0e6 && sy.abs() < 1.0e6) {
            return None;
        }
        let mut l = Lattice { xs: [0; GRID], ys: [0; GRID], hole: window };
        for (i, (x, y)) in l.xs.iter_mut().zip(l.ys.iter_mut()).enumerate() {
            *x = crate::region::floor(x0 + (i as Real + 0.5) * sx);
            *y = crate::region::floor(y0 + (i as Real + 0.5) * sy);
        }
        Some(l)
    }

    /// The columns of row `j` that hold points: all, or in the window's
    /// middle rows those left and right of the box.
    #[inline(always)]
    fn cols(&self, j: usize) -> &'static [usize] {
        const ALL: [usize; GRID] = [0, 1, 2, 3, 4, 5, 6, 7];
        const SIDES: [usize; GRID / 2] = [0, 1, 6, 7];
        if self.hole && (GRID / 4..GRID - GRID / 4).contains(&j) { &SIDES } else { &ALL }
    }

    /// Which points lie in a `width × height` frame: those [`sample`]
    /// reads a pixel for (a frame's rows hold `width` pixels each).
    fn rows_in(&self, (width, height): (usize, usize)) -> Rows {
        let mut rows = [0u8; GRID];
        for (j, (r, &y)) in rows.iter_mut().zip(self.ys.iter()).enumerate() {
            if usize::try_from(y).is_ok_and(|y| y < height) {
                for &i in self.cols(j) {
                    if self.xs.get(i).is_some_and(|&x| usize::try_from(x).is_ok_and(|x| x < width)) {
                        *r |= 1 << (i % GRID);
                    }
                }
            }
        }
        rows
    }

    /// Calls `f(row, column, luma)` for each point, row by row (the
    /// window's middle left out), with its pixel shifted by `(dx, dy)`:
    /// `None` outside the frame. Any format, a pixel at a time (the
    /// searches' comparisons go through [`sum_rows`] in the camera formats).
    fn read(&self, frame: &Frame<'_>, (dx, dy): (i32, i32), mut f: impl FnMut(usize, usize, Option<u8>)) {
        for (j, &y) in self.ys.iter().enumerate() {
            let row = usize::try_from(y + dy).ok().and_then(|y| frame.row(y));
            for &i in self.cols(j) {
                let x = self.xs.get(i).and_then(|&x| usize::try_from(x + dx).ok());
                f(j, i, row.zip(x).and_then(|(row, x)| frame.luma_in(row, x)));
            }
        }
    }
}

/// Reads the lattice's pixels into `out` (0 for those outside the frame).
fn sample(frame: &Frame<'_>, lattice: &Lattice, out: &mut [u8]) {
    let mut slots = out.iter_mut();
    lattice.read(frame, (0, 0), |_, _, luma| {
        if let Some(v) = slots.next() {
            *v = luma.unwrap_or(0);
        }
    });
}

/// The mean absolute difference between the stored samples and `frame` at
/// their pixels shifted by `d`, over the points in the frame both times, in
/// 1/16 grey levels; `None` if fewer than half of them are.
fn difference(frame: &Frame<'_>, lattice: &Lattice, stored: &[u8], rows: &Rows, d: (i32, i32)) -> Option<u32> {
    let (sum, n) = pixel::read(frame.format(), Differences { frame, lattice, stored, rows, d });
    if 2 * n as usize >= stored.len() { (sum << 4).checked_div(n) } else { None }
}

/// The sums behind [`difference`]: its arguments, read by the loops below.
struct Differences<'f, 'r> {
    frame: &'r Frame<'f>,
    lattice: &'r Lattice,
    stored: &'r [u8],
    rows: &'r Rows,
    d: (i32, i32),
}

impl RowReader for Differences<'_, '_> {
    type Output = (u32, u32);
    // Loops of its own where they save time, not in the lean build.
    const LOOPS: Loops = Loops::camera_luma(Loop::Fast);

    #[inline(always)]
    fn rows_of<P: PixelRead>(self) -> (u32, u32) {
        sum_rows::<P>(self.frame, self.lattice, self.stored, self.rows, self.d)
    }

    #[inline(always)]
    fn general(self) -> (u32, u32) {
        sum_any(self.frame, self.lattice, self.stored, self.rows, self.d)
    }
}

/// The sum of absolute differences and the count behind [`difference`] in
/// any format, a pixel at a time through the frame: the same as
/// [`sum_rows`]' (tested).
fn sum_any(frame: &Frame<'_>, lattice: &Lattice, stored: &[u8], rows: &Rows, d: (i32, i32)) -> (u32, u32) {
    let (mut sum, mut n) = (0u32, 0u32);
    let mut samples = stored.iter();
    lattice.read(frame, d, |j, i, luma| {
        let stored_in = rows.get(j).is_some_and(|r| r & (1 << (i % GRID)) != 0);
        if let (Some(l), Some(&s)) = (luma, samples.next())
            && stored_in
        {
            sum += (l as i32 - s as i32).unsigned_abs();
            n += 1;
        }
    });
    (sum, n)
}

/// The sum of absolute differences and the count behind [`difference`], in
/// a format whose rows are arrays of pixels: each shifted column is placed
/// once, as is each row, and a point costs a bit test, two reads and a
/// difference.
#[inline(always)]
fn sum_rows<P: PixelRead>(
    frame: &Frame<'_>,
    lattice: &Lattice,
    stored: &[u8],
    rows: &Rows,
    (dx, dy): (i32, i32),
) -> (u32, u32) {
    // The shifted columns, and which of them lie in the frame.
    let (mut xs, mut cols_in) = ([0usize; GRID], 0u8);
    for (i, (o, &x)) in xs.iter_mut().zip(lattice.xs.iter()).enumerate() {
        if let Ok(x) = usize::try_from(x + dx)
            && x < frame.width()
        {
            *o = x;
            cols_in |= 1 << i;
        }
    }
    let (mut sum, mut n) = (0u32, 0u32);
    let mut rest = stored;
    for ((j, &y), &row_in) in lattice.ys.iter().enumerate().zip(rows) {
        let cols = lattice.cols(j);
        let (here, next) = rest.split_at(cols.len().min(rest.len()));
        rest = next;
        // Points read last frame whose shifted column is in this one.
        let live = row_in & cols_in;
        if live == 0 {
            continue;
        }
        let Some(px) = usize::try_from(y + dy).ok().and_then(|y| frame.row(y)).and_then(P::pixels) else {
            continue;
        };
        for (&i, &s) in cols.iter().zip(here) {
            // `i` is below GRID: the remainder keeps the index check away.
            if live & (1 << (i % GRID)) != 0
                && let Some(&p) = xs.get(i % GRID).and_then(|&x| px.get(x))
            {
                sum += (P::px_luma(p) as i32 - s as i32).unsigned_abs();
                n += 1;
            }
        }
    }
    (sum, n)
}

/// The shift at which `stored` best matches `frame`, to a fraction of a
/// pixel: a descent over whole pixels from `start` with steps of the given
/// sizes (at each step, the eight shifts that far around the best so far,
/// or without `diagonals` the four along the axes; steps 2, 1 reach 3
/// pixels from `start` with 17 comparisons instead of 49; a unit step that
/// finds no better neighbour ends it), then, on each axis, the vertex of
/// the parabola through the best shift's difference and its two
/// neighbours'. Returns the whole-pixel shift and the refined one.
///
/// Why the fraction: a box's motion against its ring is the difference of
/// two such shifts, each rounded on its own when whole. A box left on the
/// background of a scene panning 1.5 px a frame reads 1 or 2 px, and its
/// ring the other, from frame to frame: 1 px "against" half the time, a
/// running mean near the [`STILL`] threshold. On the real sequences the
/// fraction lifts the share of missing frames the test reports
/// (docs/accuracy.md).
fn best_shift(
    frame: &Frame<'_>,
    lattice: &Lattice,
    (stored, rows): (&[u8], &Rows),
    start: (i32, i32),
    steps: &[i32],
    diagonals: bool,
) -> Option<((i32, i32), (Real, Real))> {
    const AROUND: [(i32, i32); 8] = [(-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)];
    let diff = |d: (i32, i32)| difference(frame, lattice, stored, rows, d);
    let mut best = diff(start).map(|v| (v, start));
    let mut centre = start;
    // The differences around `centre` in its last unit-step round, in
    // `AROUND`'s order: the parabolas' points, when the descent ends there.
    let mut around = [None; 8];
    for &step in steps {
        for (slot, (ox, oy)) in around.iter_mut().zip(AROUND) {
            if !diagonals && ox != 0 && oy != 0 {
                continue;
            }
            let d = (centre.0 + ox * step, centre.1 + oy * step);
            let v = diff(d);
            *slot = v.filter(|_| step == 1);
            if let Some(v) = v
                && best.is_none_or(|(b, _)| v < b)
            {
                best = Some((v, d));
            }
        }
        let next = best?.1;
        if next == centre && step == 1 {
            // A descent in unit steps ends where no neighbour is better.
            break;
        }
        centre = next;
        around = [None; 8];
    }
    // The descent ends on its last centre: `d` is `centre`. Its left,
    // right, upper and lower neighbours come from the round about it, where
    // there was one (a unit step that found nothing better), or are
    // measured now.
    let (v, d) = best?;
    // `k` is the offset's index in `AROUND` (less code and fewer
    // instructions a frame than a lookup by offset).
    let near = |k: usize, (ox, oy): (i32, i32)| around.get(k).copied().flatten().or_else(|| diff((d.0 + ox, d.1 + oy)));
    let (left, right, up, down) = (near(3, (-1, 0)), near(4, (1, 0)), near(1, (0, -1)), near(6, (0, 1)));
    let fx = d.0 as Real + vertex(left, v, right);
    let fy = d.1 as Real + vertex(up, v, down);
    Some((d, (fx, fy)))
}

/// The offset, in `[-0.5, 0.5]`, of the lowest point of the parabola
/// through `(-1, before)`, `(0, at)` and `(1, after)`; 0 where a neighbour
/// is unmeasured or the three points are not a valley.
fn vertex(before: Option<u32>, at: u32, after: Option<u32>) -> Real {
    let (Some(b), Some(a)) = (before, after) else { return 0.0 };
    let (b, c, a) = (b as Real, at as Real, a as Real);
    let curve = b - 2.0 * c + a;
    if curve > 0.0 { (0.5 * (b - a) / curve).clamp(-0.5, 0.5) } else { 0.0 }
}

impl SceneMotion {
    /// Nothing read, nothing measured.
    pub(crate) const fn new() -> Self {
        SceneMotion {
            inner: [0; BOX_POINTS],
            outer: [0; RING_POINTS],
            at: Ellipse { cx: Real::NAN, cy: Real::NAN, hx: Real::NAN, hy: Real::NAN },
            against: 0.0,
            ring: 0.0,
            last: (0, 0),
            early: (0.0, 0.0),
            frames: 0,
        }
    }

    /// Starts over on the box `e` of `frame` (a new target).
    pub(crate) fn start(&mut self, frame: &Frame<'_>, e: &Ellipse) {
        *self = Self::new();
        self.read_at(frame, e);
    }

    fn read_at(&mut self, frame: &Frame<'_>, e: &Ellipse) {
        self.at = *e;
        if let (Some(inner), Some(outer)) = (Lattice::of(e, false), Lattice::of(e, true)) {
            sample(frame, &inner, &mut self.inner);
            sample(frame, &outer, &mut self.outer);
        }
    }

    /// Measures how the last frame's box and ring moved into `frame`, folds
    /// that into the running means (and, on `tracked` frames among the
    /// first, into the target's own motion), and reads the box `e` for the
    /// next frame. Returns whether the estimate now moves with its
    /// surroundings (see [`SceneMotion::moves_with_surroundings`]).
    pub(crate) fn update(&mut self, frame: &Frame<'_>, e: &Ellipse, tracked: bool) -> bool {
        // The last box's lattices, if it had them (and so was read).
        if let (Some(ring_lattice), Some(box_lattice)) = (Lattice::of(&self.at, true), Lattice::of(&self.at, false)) {
            // The ring's shift from its last one; the box's by unit steps from
            // the ring's, at most three, along the axes only (a diagonal
            // takes two): a box moving further against its ring is not
            // moving with it, whatever the exact figure, and the fraction
            // needs only the axis neighbours. Compared with diagonals, the
            // box's search costs fewer instructions a frame, with the same
            // reports on the real sequences.
            //
            // Which stored points lay in the frame follows from the box: the
            // frame has the size of the one they were read on (the tracker
            // refuses another).
            let size = (frame.width(), frame.height());
            let last = (self.last.0 as i32, self.last.1 as i32);
            let (l, m) = (&ring_lattice, &box_lattice);
            let outer = best_shift(frame, l, (&self.outer, &l.rows_in(size)), last, &[2, 1], true);
            let inner =
                outer.and_then(|(r, _)| best_shift(frame, m, (&self.inner, &m.rows_in(size)), r, &[1, 1, 1], false));
            let clamp = |v: i32| v.clamp(i16::MIN as i32, i16::MAX as i32) as i16;
            self.last = outer.map_or((0, 0), |((x, y), _)| (clamp(x), clamp(y)));
            if let (Some((_, (bx, by))), Some((_, (rx, ry)))) = (inner, outer) {
                let hypot = |x: Real, y: Real| sqrt(x * x + y * y);
                let (against, ring) = (hypot(bx - rx, by - ry), hypot(rx, ry));
                if self.frames == 0 {
                    (self.against, self.ring) = (against, ring);
                } else {
                    self.against += RATE * (against - self.against);
                    self.ring += RATE * (ring - self.ring);
                }
                if tracked {
                    if self.frames < EARLY {
                        self.early = (self.early.0 + (bx - rx), self.early.1 + (by - ry));
                    }
                    self.frames = self.frames.saturating_add(1);
                }
            }
        }
        self.read_at(frame, e);
        self.moves_with_surroundings()
    }

    /// Whether a target that moved against its surroundings over its first
    /// [`EARLY`] tracked frames (a net displacement of at least [`STILL`]
    /// pixels a frame) is now estimated by a box that moves with a moving
    /// ring (running means: less than [`STILL`] against a ring moving at
    /// least [`MOVING`] pixels a frame).
    fn moves_with_surroundings(&self) -> bool {
        let (ex, ey) = self.early;
        let moved = sqrt(ex * ex + ey * ey) >= STILL * EARLY as Real;
        self.frames >= EARLY && moved && self.against < STILL && self.ring >= MOVING
    }
}

impl Cue for SceneMotion {
    type Settings = super::On;

    fn start(&mut self, on: Option<&super::On>, frame: &Frame<'_>, e: &Ellipse, _: &mut [u16]) {
        if on.is_some() {
            SceneMotion::start(self, frame, e);
        }
    }

    fn miss(&mut self, _: &super::On, frame: &Frame<'_>, e: &Ellipse, tracking: bool) -> bool {
        self.update(frame, e, tracking)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pixel::{Gray8, PixelFormat, Rgb565};

    const W: usize = 160;
    const H: usize = 120;

    /// A smooth grey texture (wide matching basins, as real scenes have),
    /// its content moved by `(sx, sy)` pixels (a fraction of a pixel too);
    /// where `target` is given, a differently textured 24x24 square at that
    /// top-left corner, on top.
    fn scene((sx, sy): (f32, f32), target: Option<(i32, i32)>) -> Vec<u8> {
        let tex =
            |x: f32, y: f32| 128.0 + 50.0 * (x / 5.0).sin() + 40.0 * (y / 7.0).cos() + 30.0 * ((x + y) / 9.0).sin();
        let blob = |x: f32, y: f32| 128.0 + 90.0 * (x / 3.0).sin() * (y / 4.0).cos();
        let mut px = vec![0u8; W * H];
        for y in 0..H as i32 {
            for x in 0..W as i32 {
                let mut v = tex(x as f32 - sx, y as f32 - sy);
                if let Some((tx, ty)) = target
                    && (tx..tx + 24).contains(&x)
                    && (ty..ty + 24).contains(&y)
                {
                    v = blob((x - tx) as f32, (y - ty) as f32);
                }
                px[y as usize * W + x as usize] = v.clamp(0.0, 255.0) as u8;
            }
        }
        px
    }

    fn frame(px: &[u8]) -> Frame<'_> {
        Frame::packed(px, W, H, PixelFormat::Gray8).unwrap()
    }

    /// The ellipse of the 24x24 box at top-left `(x, y)`.
    fn boxed((x, y): (i32, i32)) -> Ellipse {
        Ellipse { cx: x as Real + 12.0, cy: y as Real + 12.0, hx: 12.0, hy: 12.0 }
    }

    #[test]
    fn the_points_in_the_frame_are_those_read() {
        // Reason: a cross-check of two ways to say which lattice points lie
        // in the frame: the masks `rows_in` derives from the box and the
        // frame's size, and the points whose pixel the frame's reads return,
        // in every packed format, for boxes inside, across each border,
        // off the frame, tiny and larger than it.
        let px = crate::testing::noise_bytes(5, W * H * 3);
        let mut next = crate::testing::lcg(9);
        let mut checked = (0, 0);
        for format in [PixelFormat::Rgb565, PixelFormat::Rgb888, PixelFormat::Yuv422, PixelFormat::Gray8] {
            let f = Frame::packed(&px[..W * H * format.bytes_per_pixel()], W, H, format).unwrap();
            for _ in 0..200 {
                let mut r = |m: u32| (next() >> 8) % m;
                let e = Ellipse {
                    cx: r(2 * W as u32) as Real - (W / 2) as Real + 0.3,
                    cy: r(2 * H as u32) as Real - (H / 2) as Real + 0.6,
                    hx: r(200) as Real + 0.5,
                    hy: r(150) as Real + 0.5,
                };
                for window in [false, true] {
                    let Some(l) = Lattice::of(&e, window) else { continue };
                    let mut read = [0u8; GRID];
                    l.read(&f, (0, 0), |j, i, luma| {
                        if let (Some(_), Some(r)) = (luma, read.get_mut(j)) {
                            *r |= 1 << i;
                        }
                    });
                    assert_eq!(l.rows_in((W, H)), read, "{format:?} {e:?} {window}");
                    let n: u32 = read.iter().map(|r| r.count_ones()).sum();
                    checked = (checked.0 + (n == 0 || n == 64 || (window && n == 48)) as u32, checked.1 + 1);
                }
            }
        }
        // Some boxes lie partly outside the frame (neither none nor all
        // of their points in it).
        assert!(checked.1 - checked.0 >= 100, "{checked:?}");
    }

    #[test]
    fn the_per_format_sums_equal_the_general_ones() {
        // Reason: a cross-check of two implementations of the matching
        // sums: the camera formats' row loop and the pixel-at-a-time read
        // through the frame (what the other formats, and every format in
        // the lean builds, take), on random RGB565 and GRAY8 frames, for
        // box and window lattices inside, across the borders and off the
        // frame, at shifts up to 4 pixels each way.
        let px = crate::testing::noise_bytes(11, W * H * 2);
        let mut next = crate::testing::lcg(12);
        let mut compared = 0;
        for format in [PixelFormat::Rgb565, PixelFormat::Gray8] {
            let f = Frame::packed(&px[..W * H * format.bytes_per_pixel()], W, H, format).unwrap();
            for _ in 0..100 {
                let mut r = |m: u32| (next() >> 8) % m;
                let e = Ellipse {
                    cx: r(W as u32 + 40) as Real - 20.0 + 0.3,
                    cy: r(H as u32 + 40) as Real - 20.0 + 0.6,
                    hx: r(60) as Real + 2.5,
                    hy: r(45) as Real + 2.5,
                };
                let d = (r(9) as i32 - 4, r(9) as i32 - 4);
                for window in [false, true] {
                    let Some(l) = Lattice::of(&e, window) else { continue };
                    let mut stored = [0u8; BOX_POINTS];
                    let n = if window { RING_POINTS } else { BOX_POINTS };
                    sample(&f, &l, &mut stored[..n]);
                    let rows = l.rows_in((W, H));
                    let own = match format {
                        PixelFormat::Rgb565 => sum_rows::<Rgb565>(&f, &l, &stored[..n], &rows, d),
                        _ => sum_rows::<Gray8>(&f, &l, &stored[..n], &rows, d),
                    };
                    assert_eq!(own, sum_any(&f, &l, &stored[..n], &rows, d), "{format:?} {e:?} {window} {d:?}");
                    compared += (own.1 > 0) as u32;
                }
            }
        }
        assert!(compared >= 200, "{compared}");
    }

    #[test]
    fn a_pan_is_measured_to_a_fraction_of_a_pixel_and_a_box_on_the_scene_moves_with_it() {
        // Reason: ground truth by construction. The second frame is the
        // first with its content moved 3 px right and 2 px up, so the ring's
        // best whole-pixel match is exactly (3, -2), |(3, -2)| = sqrt(13),
        // and a box on the scene moves the same, 0 against its ring. The
        // parabolas through each axis's three differences put the vertex
        // within a tenth of a pixel of the whole shift (the texture's
        // differences are nearly even about it; measured: 0.013 against).
        // The first measurement sets the running means.
        let (a, b) = (scene((0.0, 0.0), None), scene((3.0, -2.0), None));
        let mut m = SceneMotion::new();
        let e = boxed((60, 50));
        m.start(&frame(&a), &e);
        assert!(!m.update(&frame(&b), &e, true));
        assert_eq!(m.last, (3, -2));
        let (against, ring) = (m.against, m.ring);
        assert!(against < 0.1, "{against}");
        assert!((ring - 13.0f32.sqrt()).abs() < 0.1, "{ring}");
    }

    #[test]
    fn a_half_pixel_pan_is_measured_as_half_a_pixel() {
        // Reason: ground truth by construction and a symmetry. Content
        // moved 2.5 px right matches shifts 2 and 3 equally well, so the
        // parabola through the differences at 2, 3 and their outer
        // neighbour has its vertex between them, near 2.5; rounded to whole
        // pixels the pan would read 2 or 3. Vertically the content did not
        // move. Tolerance: a quarter pixel for the texture's rounding to
        // grey levels.
        let (a, b) = (scene((0.0, 0.0), None), scene((2.5, 0.0), None));
        let lattice = Lattice::of(&boxed((60, 50)), true).unwrap();
        let mut stored = [0u8; RING_POINTS];
        sample(&frame(&a), &lattice, &mut stored);
        let rows = lattice.rows_in((W, H));
        let (whole, (fx, fy)) = best_shift(&frame(&b), &lattice, (&stored, &rows), (0, 0), &[2, 1], true).unwrap();
        assert!(whole == (2, 0) || whole == (3, 0), "{whole:?}");
        assert!((fx - 2.5).abs() < 0.25, "{fx}");
        assert!(fy.abs() < 0.25, "{fy}");
    }

    /// Drives a tracker's view: `EARLY` frames of a target over a still
    /// scene (the box on it) that moves `step(k)` px right on its `k`-th
    /// frame; then `panning` frames of the scene panning 2 px a frame right
    /// with the box left on the scene. Returns whether each panning frame
    /// was flagged.
    fn run(step: impl Fn(u16) -> i32, panning: i32) -> Vec<bool> {
        let mut m = SceneMotion::new();
        let mut at = (40, 48);
        let first = scene((0.0, 0.0), Some(at));
        m.start(&frame(&first), &boxed(at));
        for k in 0..EARLY {
            at.0 += step(k);
            let px = scene((0.0, 0.0), Some(at));
            assert!(!m.update(&frame(&px), &boxed(at), true), "flagged while on the target");
        }
        // The target is gone; the box sits on the scene, which pans.
        let stuck = (100, 48);
        (1..=panning)
            .map(|k| {
                let px = scene(((2 * k) as f32, 0.0), None);
                let b = (stuck.0 + 2 * k, stuck.1);
                m.update(&frame(&px), &boxed(b), true)
            })
            .collect()
    }

    #[test]
    fn a_box_left_on_a_panning_scene_is_flagged_for_a_target_seen_to_move() {
        // Reason: by construction and by hand. On the walking target the
        // box moves 2 px a frame against its still ring, so the running
        // mean of that is 2 and so is the first frames' mean (above STILL:
        // a target that moves). On the first panning frame the box has
        // jumped off the target: its last samples are matched against a
        // frame without it, at most 3 px each way from the ring's shift and
        // half a pixel more for the fraction (|(3.5, 3.5)| = 4.95). From
        // then on the box moves with the scene: 0 against a ring moving 2
        // px. So after k panning frames the box's mean is at most about
        // (0.8 * 2 + 0.2 * 4.95) * 0.8^(k - 1), below 0.5 from k = 9
        // (0.44); the ring's is 2 * (1 - 0.8^k), below 1 up to k = 3.
        // Hence not flagged on the first three panning frames, flagged
        // from the ninth on.
        let flags = run(|_| 2, 12);
        assert!(flags.iter().take(3).all(|&f| !f), "{flags:?}");
        assert!(flags.iter().skip(8).all(|&f| f), "{flags:?}");
    }

    #[test]
    fn a_target_never_seen_to_move_is_never_flagged() {
        // Reason: the gate. A target that stood still over its first frames
        // (0 against its ring, below STILL) may be a building filmed from a
        // drone: moving with the scene is what it does.
        assert!(run(|_| 0, 12).iter().all(|&f| !f));
    }

    #[test]
    fn a_target_that_moves_back_and_forth_is_not_one_that_moves() {
        // Reason: by construction and by hand. The target moves 2 px a
        // frame against its still ring, right then left: each frame's
        // motion is 2 px, above STILL, but they cancel, and its net
        // displacement over the first 20 frames is 0, below 20 · STILL =
        // 10 px. So, like a still one, it is never flagged (errors of the
        // shift that point every way, as on a target with little texture,
        // cancel the same way).
        assert!(run(|k| if k % 2 == 0 { 2 } else { -2 }, 12).iter().all(|&f| !f));
    }

    #[test]
    fn boxes_off_the_frame_or_not_numbers_measure_nothing_and_do_not_panic() {
        // Reason: an invariant. Lattice points outside the frame are not
        // read; a NaN box has no lattice; neither panics or measures.
        let a = scene((0.0, 0.0), None);
        let mut m = SceneMotion::new();
        let far = Ellipse { cx: -500.0, cy: 900.0, hx: 12.0, hy: 12.0 };
        m.start(&frame(&a), &far);
        assert!(!m.update(&frame(&a), &far, true));
        let nan = Ellipse { cx: Real::NAN, ..far };
        m.start(&frame(&a), &nan);
        assert!(!m.update(&frame(&a), &nan, true));
        assert_eq!((m.against, m.ring), (0.0, 0.0));
    }
}
