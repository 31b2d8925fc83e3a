//! The particle set: state, constant-velocity dynamics, resampling and the
//! mean-state estimate.

use crate::frame::Frame;
use crate::geometry::Ellipse;
use crate::scalar::{Real, clamp, max, min, normal_from_bits, sqrt, unit_from_bits};
use rand_core::Rng;

/// One hypothesis `s = {x, y, vx, vy, Hx, Hy}`: the centre of an upright
/// ellipse, its velocity in pixels per frame, and its half axes.
///
/// The papers' state also carries a scale rate `ȧ` (the half axes grow by
/// `1 + ȧ` a frame, `ȧ` a random walk). It is left out: any noise on it
/// lets the box's size random-walk, since a colour histogram barely
/// penalises a wrong size (docs/method.md), and without noise it holds 0
/// in every particle. The size follows the target through the scale
/// searches after the estimate instead.
#[derive(Copy, Clone, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Particle {
    /// Centre, x.
    pub x: Real,
    /// Centre, y.
    pub y: Real,
    /// Velocity along x, pixels per frame.
    pub vx: Real,
    /// Velocity along y, pixels per frame.
    pub vy: Real,
    /// Half axis along x.
    pub hx: Real,
    /// Half axis along y.
    pub hy: Real,
}

impl Particle {
    /// A particle at rest on an ellipse.
    pub fn at(e: &Ellipse) -> Self {
        Particle { x: e.cx, y: e.cy, hx: e.hx, hy: e.hy, ..Default::default() }
    }

    /// The particle's ellipse.
    pub fn ellipse(&self) -> Ellipse {
        Ellipse { cx: self.x, cy: self.y, hx: self.hx, hy: self.hy }
    }
}

/// The noise of the constant-velocity model, per frame.
///
/// Position and velocity noise scale with the particle's size
/// `s = sqrt(2Hx · 2Hy)`, so that one configuration serves a 10 px target in
/// QQVGA and a 200 px one in VGA.
#[derive(Copy, Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Dynamics {
    /// Standard deviation of the position noise, as a fraction of `s` (or
    /// more for a fast target: see `speed_noise`).
    pub position_noise: Real,
    /// Standard deviation of the velocity noise, as a fraction of `s`.
    pub velocity_noise: Real,
    /// How much of its velocity a particle keeps each frame, in `[0, 1]`:
    /// `v ← decay · v + noise`. 1 is the papers' constant-velocity model; less
    /// lets a velocity that resampling once favoured fade instead of carrying
    /// the particle off when the target stops or turns.
    pub velocity_decay: Real,
    /// The position noise's standard deviation is at least this times the
    /// target's recent speed in pixels a frame (the estimate's smoothed
    /// displacement), when that is more than `position_noise · s`. A fast
    /// target's next position is as uncertain as its last move is large;
    /// a noise scaled to its size alone leaves a target that moves more
    /// than a fifth of its size a frame behind the particles. 0 scales the
    /// noise with the size alone.
    pub speed_noise: Real,
    /// Standard deviation of the multiplicative noise on each half axis.
    pub scale_noise: Real,
}

/// Where particles may be: the state constraints of the model.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) struct Bounds {
    /// Frame width and height: centres stay inside the frame.
    pub width: Real,
    /// See `width`.
    pub height: Real,
    /// Smallest half axis.
    pub min_half: Real,
}

impl Dynamics {
    /// Moves a particle one frame: `s_t = A s_{t−1} + w_{t−1}`.
    ///
    /// The state is then kept physical: the centre stays inside the frame
    /// (a particle that hits the border loses that velocity component, so the
    /// filter waits at the border where a target that left will come back),
    /// and half axes stay within `[min_half, frame size / 2]`.
    /// `speed` is the target's recent speed in pixels a frame (see
    /// `speed_noise`).
    pub(crate) fn propagate<R: Rng>(&self, p: &mut Particle, b: &Bounds, speed: Real, rng: &mut R) {
        let s = sqrt(4.0 * p.hx * p.hy);
        let mut n = || normal(rng);
        let spread = max(self.position_noise * s, self.speed_noise * speed);
        p.x += p.vx + spread * n();
        p.y += p.vy + spread * n();
        p.vx = self.velocity_decay * p.vx + self.velocity_noise * s * n();
        p.vy = self.velocity_decay * p.vy + self.velocity_noise * s * n();
        // The papers' scale rate `ȧ` takes its noise's draw here. The state
        // leaves `ȧ` out (see [`Particle`]) but its draw keeps its place in
        // the generator's sequence, so that a seed gives the tracks of the
        // seven-component filter this one equals (its `ȧ` held at 0).
        let _ = n();
        p.hx *= 1.0 + self.scale_noise * n();
        p.hy *= 1.0 + self.scale_noise * n();
        keep_inside(&mut p.x, &mut p.vx, b.width);
        keep_inside(&mut p.y, &mut p.vy, b.height);
        p.hx = clamp(p.hx, b.min_half, max(0.5 * b.width, b.min_half));
        p.hy = clamp(p.hy, b.min_half, max(0.5 * b.height, b.min_half));
    }
}

/// A standard-normal draw from `rng` ([`normal_from_bits`]). Out of line:
/// inlined, each of the many draw sites would carry the generator's code.
#[inline(never)]
pub(crate) fn normal<R: Rng>(rng: &mut R) -> Real {
    normal_from_bits(rng.next_u64())
}

fn keep_inside(pos: &mut Real, vel: &mut Real, size: Real) {
    // `!(a >= b)` rather than `a < b` so that NaN also resets.
    if !(*pos >= 0.0) {
        *pos = 0.0;
        *vel = 0.0;
    } else if *pos > size {
        *pos = size;
        *vel = 0.0;
    }
}

/// How particles are drawn in proportion to their weights.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Resampling {
    /// N independent draws: cumulative sum, then a binary search for each
    /// (the first paper, Fig. 2). O(N log N).
    Multinomial,
    /// One random offset and N evenly spaced pointers into the cumulative sum
    /// (the third paper). O(N), and lower variance.
    #[default]
    Systematic,
}

/// Resamples `particles` in place in proportion to `weights`.
///
/// The draws only count how many copies of each particle survive (into
/// `copies`); the set is then rewritten in place, each extra copy going into
/// the slot of a particle that drew none. That needs `2·N` bytes of counts
/// instead of a second particle array (`28·N` bytes), which is what lets a
/// 100-particle tracker fit small RAMs. The order of the set changes, which
/// nothing depends on.
///
/// `weights` must be non-negative; they need not be normalised. They are
/// overwritten with their cumulative sum. A particle of zero weight is never
/// drawn while another has weight; if all weights are zero (or not finite),
/// the set is left as it is.
pub(crate) fn resample<R: Rng, const N: usize>(
    particles: &mut [Particle; N],
    weights: &mut [Real; N],
    copies: &mut [u16; N],
    n: usize,
    method: Resampling,
    rng: &mut R,
) {
    let n = n.clamp(1, N);
    let mut acc = 0.0;
    for w in weights.iter_mut() {
        acc += max(*w, 0.0);
        *w = acc;
    }
    if !(acc > 0.0) || !acc.is_finite() {
        return;
    }
    *copies = [0; N];
    let mut draw = |j: usize| {
        if let Some(c) = copies.get_mut(j) {
            *c = c.saturating_add(1);
        }
    };
    match method {
        Resampling::Multinomial => {
            for _ in 0..n {
                let u = unit_from_bits(rng.next_u32()) * acc;
                // First index whose cumulative weight exceeds u; a zero-weight
                // particle has the same cumulative sum as its predecessor and
                // is never it.
                draw(weights.partition_point(|&c| c <= u).min(N - 1));
            }
        }
        Resampling::Systematic => {
            let step = acc / n as Real;
            let u0 = unit_from_bits(rng.next_u32()) * step;
            let mut j = 0usize;
            for i in 0..n {
                let u = u0 + i as Real * step;
                while j + 1 < N && weights.get(j).is_some_and(|&c| c <= u) {
                    j += 1;
                }
                draw(j);
            }
        }
    }
    // Every draw fills one slot, so the slots of particles drawn 0 times are
    // exactly as many as the extra copies of the others.
    let mut free = 0usize;
    for j in 0..N {
        while copies.get(j).is_some_and(|&c| c > 1) {
            while copies.get(free).is_some_and(|&c| c != 0) {
                free += 1;
            }
            let (Some(&p), true) = (particles.get(j), free < N) else { return };
            if let Some(slot) = particles.get_mut(free) {
                *slot = p;
            }
            if let Some(c) = copies.get_mut(free) {
                *c = 1;
            }
            if let Some(c) = copies.get_mut(j) {
                *c -= 1;
            }
        }
    }
    // Fewer draws than slots: the `n` drawn move to the front, in order
    // (with all `N` drawn every slot is taken and nothing moves).
    if n < N {
        let mut k = 0usize;
        for j in 0..N {
            if copies.get(j).is_some_and(|&c| c != 0) {
                if let Some(&p) = particles.get(j)
                    && let Some(slot) = particles.get_mut(k)
                {
                    *slot = p;
                }
                k += 1;
            }
        }
    }
}

/// The weighted mean state `E[S] = Σ π_i s_i` for normalised weights.
///
/// Each component is kept within the particles' range: in exact arithmetic a
/// weighted mean always is, but rounding in the sum can push it a hair
/// outside (found by the property tests: a centre at 22.000002 in a frame 22
/// pixels high).
pub(crate) fn mean_state(particles: &[Particle], weights: &[Real]) -> Particle {
    let mut m = Particle { hx: 0.0, hy: 0.0, ..Default::default() };
    let mut lo = Particle { x: Real::MAX, y: Real::MAX, hx: Real::MAX, hy: Real::MAX, ..Default::default() };
    let mut hi = Particle { x: Real::MIN, y: Real::MIN, hx: Real::MIN, hy: Real::MIN, ..Default::default() };
    for (p, &w) in particles.iter().zip(weights.iter()) {
        m.x += w * p.x;
        m.y += w * p.y;
        m.vx += w * p.vx;
        m.vy += w * p.vy;
        m.hx += w * p.hx;
        m.hy += w * p.hy;
        (lo.x, hi.x) = (min(lo.x, p.x), max(hi.x, p.x));
        (lo.y, hi.y) = (min(lo.y, p.y), max(hi.y, p.y));
        (lo.hx, hi.hx) = (min(lo.hx, p.hx), max(hi.hx, p.hx));
        (lo.hy, hi.hy) = (min(lo.hy, p.hy), max(hi.hy, p.hy));
    }
    m.x = clamp(m.x, lo.x, hi.x);
    m.y = clamp(m.y, lo.y, hi.y);
    m.hx = clamp(m.hx, lo.hx, hi.hx);
    m.hy = clamp(m.hy, lo.hy, hi.hy);
    m
}

/// Moves the estimate and every particle by `(dx, dy)`. Centres stay in the
/// frame, as the dynamics keep them; the estimate, in the frame, stays
/// inside the particles' hull.
pub(crate) fn shift_estimate<const N: usize>(
    ellipse: &mut Ellipse,
    particles: &mut [Particle; N],
    (dx, dy): (Real, Real),
    frame: &Frame<'_>,
) {
    let (w, h) = (frame.width() as Real, frame.height() as Real);
    // Clamped as the particles are, so that the estimate stays their mean's
    // image: inside the frame and inside their hull (clamping is monotone).
    ellipse.cx = crate::scalar::clamp(ellipse.cx + dx, 0.0, w);
    ellipse.cy = crate::scalar::clamp(ellipse.cy + dy, 0.0, h);
    for p in particles.iter_mut() {
        p.x = crate::scalar::clamp(p.x + dx, 0.0, w);
        p.y = crate::scalar::clamp(p.y + dy, 0.0, h);
    }
}

/// Scales the estimate's half axes and every particle's by `(fx, fy)`, so
/// that the filter goes on from the size found.
pub(crate) fn scale_estimate<const N: usize>(
    ellipse: &mut Ellipse,
    particles: &mut [Particle; N],
    (fx, fy): (Real, Real),
) {
    ellipse.hx *= fx;
    ellipse.hy *= fy;
    for p in particles.iter_mut() {
        p.hx *= fx;
        p.hy *= fy;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::SeedableRng;
    use rand_xoshiro::Xoshiro128PlusPlus;

    fn bounds() -> Bounds {
        Bounds { width: 1000.0, height: 1000.0, min_half: 1.0 }
    }

    /// Constant velocity with no noise at all.
    fn still() -> Dynamics {
        Dynamics { position_noise: 0.0, velocity_noise: 0.0, velocity_decay: 1.0, speed_noise: 0.0, scale_noise: 0.0 }
    }

    #[test]
    fn noiseless_dynamics_are_constant_velocity() {
        // Reason: with zero noise, s_t = A s_{t-1}: the centre advances by the
        // velocity each frame and the size stays.
        let d = still();
        let mut p = Particle { x: 100.0, y: 200.0, vx: 3.0, vy: -2.0, hx: 10.0, hy: 20.0 };
        let mut rng = Xoshiro128PlusPlus::seed_from_u64(1);
        for _ in 0..10 {
            d.propagate(&mut p, &bounds(), 0.0, &mut rng);
        }
        assert_eq!((p.x, p.y), (130.0, 180.0));
        assert_eq!((p.vx, p.vy), (3.0, -2.0));
        assert_eq!((p.hx, p.hy), (10.0, 20.0));
    }

    #[test]
    fn a_step_draws_seven_normals_as_the_papers_state_does() {
        // Reason: the invariant that keeps a seed's tracks those of the
        // seven-component filter (see `propagate`): one step takes seven
        // draws from the generator, the scale rate's included, so that the
        // generator's next value is the eighth of its stream.
        let d = Dynamics { position_noise: 0.1, velocity_noise: 0.05, scale_noise: 0.01, ..still() };
        let mut rng = Xoshiro128PlusPlus::seed_from_u64(5);
        let mut p = Particle { x: 50.0, y: 50.0, hx: 10.0, hy: 10.0, ..Default::default() };
        d.propagate(&mut p, &bounds(), 0.0, &mut rng);
        let mut stream = Xoshiro128PlusPlus::seed_from_u64(5);
        let draws: Vec<u64> = (0..8).map(|_| rand_core::Rng::next_u64(&mut stream)).collect();
        assert_eq!(rand_core::Rng::next_u64(&mut rng), draws[7]);
        // The half axes took the sixth and seventh draws (the fifth is the
        // scale rate's).
        let grow = |bits: u64| 1.0 + 0.01 * normal_from_bits(bits);
        assert_eq!((p.hx, p.hy), (10.0 * grow(draws[5]), 10.0 * grow(draws[6])));
    }

    /// The sample standard deviation of one step's x displacement of a
    /// 20x20 particle (s = 20) at rest, for a target of recent `speed`.
    fn spread_at(d: &Dynamics, speed: Real) -> f64 {
        let mut rng = Xoshiro128PlusPlus::seed_from_u64(3);
        let n = 20_000;
        let (mut s1, mut s2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let mut p = Particle { x: 500.0, y: 500.0, hx: 10.0, hy: 10.0, ..Default::default() };
            d.propagate(&mut p, &bounds(), speed, &mut rng);
            let dx = (p.x - 500.0) as f64;
            s1 += dx;
            s2 += dx * dx;
        }
        let mean = s1 / n as f64;
        (s2 / n as f64 - mean * mean).sqrt()
    }

    #[test]
    fn a_fast_target_spreads_the_particles_as_far_as_it_moves() {
        // Reason, by hand: position noise 0.1 of s = 20 is 2 px. A target
        // moving 10 px a frame with speed noise 1 asks for 10 px, the larger,
        // so that is the spread; one moving 1 px a frame asks for 1 px, and
        // the size's 2 px stay; speed noise 0 keeps 2 px at any speed.
        let d = Dynamics { position_noise: 0.1, speed_noise: 1.0, ..still() };
        assert!((spread_at(&d, 10.0) - 10.0).abs() < 0.25);
        assert!((spread_at(&d, 1.0) - 2.0).abs() < 0.05);
        let size_only = Dynamics { speed_noise: 0.0, ..d };
        assert!((spread_at(&size_only, 10.0) - 2.0).abs() < 0.05);
    }

    #[test]
    fn position_noise_has_the_configured_spread() {
        // Reason: for a 20x20 particle s = 20, so position noise 0.1 gives a
        // one-step standard deviation of 2 px around the predicted centre.
        let d = Dynamics { position_noise: 0.1, ..still() };
        let mut rng = Xoshiro128PlusPlus::seed_from_u64(7);
        let n = 20_000;
        let (mut s1, mut s2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let mut p = Particle { x: 500.0, y: 500.0, vx: 1.0, hx: 10.0, hy: 10.0, ..Default::default() };
            d.propagate(&mut p, &bounds(), 0.0, &mut rng);
            let dx = (p.x - 501.0) as f64;
            s1 += dx;
            s2 += dx * dx;
        }
        let mean = s1 / n as f64;
        let sd = (s2 / n as f64 - mean * mean).sqrt();
        assert!(mean.abs() < 0.05, "{mean}");
        assert!((sd - 2.0).abs() < 0.05, "{sd}");
    }

    #[test]
    fn centre_stays_in_frame_and_stops_at_the_border() {
        let d = still();
        let mut p = Particle { x: 5.0, y: 5.0, vx: -10.0, vy: 0.0, hx: 4.0, hy: 4.0 };
        let mut rng = Xoshiro128PlusPlus::seed_from_u64(1);
        d.propagate(&mut p, &bounds(), 0.0, &mut rng);
        assert_eq!((p.x, p.vx), (0.0, 0.0));
    }

    fn line_particles<const N: usize>() -> [Particle; N] {
        core::array::from_fn(|i| Particle { x: i as Real, ..Default::default() })
    }

    /// How many particles of the set came from each original (by `x`).
    fn origins<const N: usize>(set: &[Particle; N]) -> [usize; N] {
        let mut n = [0usize; N];
        for p in set {
            n[p.x as usize] += 1;
        }
        n
    }

    #[test]
    fn resampling_keeps_n_and_favours_weight() {
        // Reason: with weights 0, 0, 0.75, 0.25 and many draws, particle 2
        // must take about 3/4 of the draws, 3 a quarter, and 0 and 1 none.
        for method in [Resampling::Multinomial, Resampling::Systematic] {
            const N: usize = 4;
            let mut rng = Xoshiro128PlusPlus::seed_from_u64(3);
            let mut counts = [0usize; N];
            for _ in 0..2000 {
                let mut set = line_particles::<N>();
                let mut w = [0.0, 0.0, 0.75, 0.25];
                let mut copies = [0u16; N];
                resample(&mut set, &mut w, &mut copies, N, method, &mut rng);
                for (c, n) in counts.iter_mut().zip(origins(&set)) {
                    *c += n;
                }
            }
            assert_eq!(counts.iter().sum::<usize>(), 8000, "N is kept");
            assert_eq!((counts[0], counts[1]), (0, 0), "{method:?}: zero weight drawn");
            let f2 = counts[2] as f64 / 8000.0;
            assert!((f2 - 0.75).abs() < 0.02, "{method:?}: {f2}");
        }
    }

    #[test]
    fn systematic_resampling_is_exact_for_multiples_of_one_over_n() {
        // Reason: systematic pointers are evenly spaced by 1/N, so a weight of
        // exactly k/N yields exactly k copies whatever the random offset.
        const N: usize = 10;
        let mut rng = Xoshiro128PlusPlus::seed_from_u64(9);
        for _ in 0..100 {
            let mut set = line_particles::<N>();
            let mut w = [0.3, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.2];
            let mut copies = [0u16; N];
            resample(&mut set, &mut w, &mut copies, N, Resampling::Systematic, &mut rng);
            assert_eq!(origins(&set), [3, 0, 0, 5, 0, 0, 0, 0, 0, 2]);
        }
    }

    #[test]
    fn in_place_rewrite_matches_the_draws_for_any_pattern() {
        // Reason: cross-check of the in-place rewrite: for random weights
        // (many zeros, a few heavy), the set afterwards must hold exactly the
        // drawn number of copies of each original, whatever the pattern of
        // sources and free slots.
        const N: usize = 16;
        let mut rng = Xoshiro128PlusPlus::seed_from_u64(5);
        let mut pick = Xoshiro128PlusPlus::seed_from_u64(6);
        for _ in 0..500 {
            let mut w: [Real; N] = core::array::from_fn(|_| {
                let r = pick.next_u32();
                if r % 3 == 0 { 0.0 } else { (r >> 20) as Real }
            });
            w[(pick.next_u32() % N as u32) as usize] += 1.0;
            let mut set = line_particles::<N>();
            let mut copies = [0u16; N];
            resample(&mut set, &mut w, &mut copies, N, Resampling::Multinomial, &mut rng);
            // `copies` ends as 1 for every slot; recount the draws from the set
            // and check they are consistent with the weights' support.
            let n = origins(&set);
            assert_eq!(n.iter().sum::<usize>(), N);
            for (j, &k) in n.iter().enumerate() {
                let weight = w[j] - if j > 0 { w[j - 1] } else { 0.0 };
                assert!(k == 0 || weight > 0.0, "particle {j} drawn {k} times with zero weight");
            }
        }
    }

    #[test]
    fn fewer_draws_fill_the_first_slots() {
        // Reason: drawing n < N, the first n slots must hold exactly the
        // draws. Systematic pointers are 1/n apart, so weights that are
        // multiples of 1/n give exactly those copies whatever the offset:
        // with n = 5 and weights 0.6, 0.4 on particles 2 and 7, three copies
        // of 2 then two of 7, in the order of the originals.
        const N: usize = 10;
        let mut rng = Xoshiro128PlusPlus::seed_from_u64(4);
        for _ in 0..100 {
            let mut set = line_particles::<N>();
            let mut w = [0.0, 0.0, 0.6, 0.0, 0.0, 0.0, 0.0, 0.4, 0.0, 0.0];
            let mut copies = [0u16; N];
            resample(&mut set, &mut w, &mut copies, 5, Resampling::Systematic, &mut rng);
            let xs: [Real; 5] = core::array::from_fn(|i| set[i].x);
            assert_eq!(xs, [2.0, 2.0, 2.0, 7.0, 7.0]);
        }
        // Multinomial draws land on weighted particles only, n of them.
        let mut set = line_particles::<N>();
        let mut w = [0.0, 0.0, 0.6, 0.0, 0.0, 0.0, 0.0, 0.4, 0.0, 0.0];
        let mut copies = [0u16; N];
        resample(&mut set, &mut w, &mut copies, 6, Resampling::Multinomial, &mut rng);
        assert!(set[..6].iter().all(|p| p.x == 2.0 || p.x == 7.0), "{set:?}");
    }

    #[test]
    fn all_zero_weights_keep_the_set() {
        const N: usize = 5;
        let mut set = line_particles::<N>();
        let mut w = [0.0; N];
        let mut copies = [0u16; N];
        let mut rng = Xoshiro128PlusPlus::seed_from_u64(1);
        resample(&mut set, &mut w, &mut copies, N, Resampling::Multinomial, &mut rng);
        assert_eq!(set, line_particles::<N>());
        let mut w = [Real::NAN; N];
        resample(&mut set, &mut w, &mut copies, N, Resampling::Systematic, &mut rng);
        assert_eq!(set, line_particles::<N>());
    }

    #[test]
    fn mean_state_is_the_weighted_average() {
        let src = line_particles::<4>();
        let m = mean_state(&src, &[0.0, 0.5, 0.5, 0.0]);
        assert_eq!(m.x, 1.5);
    }
}
