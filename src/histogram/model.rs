//! The target model and its comparison with a region's histogram.

use crate::scalar::{Real, sqrt_q4};

use super::Histogram;

/// How a histogram is compared with the model.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Similarity {
    /// The Bhattacharyya coefficient `ρ = Σ sqrt(p(u) q(u))` (first paper).
    #[default]
    Bhattacharyya,
    /// Histogram intersection `Σ min(p(u), q(u))` of the normalised
    /// histograms (Swain and Ballard, the head-tracking paper's
    /// `Σ min(I, M) / Σ I` with both normalised to the same mass).
    Intersection,
}

/// The target model: a normalised histogram `q` and its square roots, kept
/// ready for the Bhattacharyya sum.
///
/// `q(u)` is stored in units of `2^-16` and `sqrt(q(u))` in units of `2^-12`.
/// A model of a quadrant layout holds four blocks of `K / 4` bins, each
/// normalised on its own.
///
/// Its non-empty bins are kept as a bitmap of `W` 32-bit words (see
/// [`SUPPORT_WORDS`]): one bit per bin up to `32·W` bins, one per group of
/// bins beyond.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Model<const K: usize, const W: usize = SUPPORT_WORDS> {
    pub(super) q: [u16; K],
    pub(super) sqrt_q: [u16; K],
    /// Where `q` is non-zero, for sums that only need those bins.
    pub(super) support: Support<W>,
    pub(super) segments: u8,
}

/// The words of a [`Model`]'s bitmap of non-empty bins unless said
/// otherwise: 16, one bit per bin of the 512 RGB bins. A model of fewer
/// bins may take fewer words (the tracker's edge model, of
/// [`MAX_EDGE_BINS`](crate::MAX_EDGE_BINS) bins, takes one: 60 bytes of RAM less).
pub const SUPPORT_WORDS: usize = 16;

/// The non-empty bins of a model, as one bit per group of
/// `K.div_ceil(32·W)` bins (one bit per bin for `K <= 32·W`): `4·W` bytes
/// for any `K`.
///
/// A target's colours fill few of the 512 RGB bins (tens, on the real
/// sequences), and the Bhattacharyya sum of every particle needs only
/// those: visiting them through the bitmap is what keeps the sum from
/// costing a pass over all 512 bins per particle.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Support<const W: usize = SUPPORT_WORDS> {
    pub(super) words: [u32; W],
}

impl<const W: usize> Support<W> {
    const GROUPS: usize = W * 32;

    /// Bins per bit for `K` bins (at least 1).
    const fn group_len<const K: usize>() -> usize {
        // A support of no words is refused when built (`of`); the test of
        // `GROUPS` keeps the division defined regardless.
        if K <= Self::GROUPS || Self::GROUPS == 0 { 1 } else { K.div_ceil(Self::GROUPS) }
    }

    const EMPTY: Self = Support { words: [0; W] };

    /// The support of the non-zero values of `v`.
    pub(super) fn of<const K: usize>(v: &[u16; K]) -> Self {
        const { assert!(W > 0, "a model's support takes at least one word") };
        let g = Self::group_len::<K>();
        let mut words = [0u32; W];
        for (i, _) in v.iter().enumerate().filter(|&(_, &x)| x != 0) {
            let group = i / g;
            if let Some(w) = words.get_mut(group / 32) {
                *w |= 1 << (group % 32);
            }
        }
        Support { words }
    }

    /// Calls `f(i)` for every bin `i` in `lo..hi` whose group is in the
    /// support, in increasing order.
    #[inline(always)]
    pub(super) fn for_each<const K: usize>(&self, lo: usize, hi: usize, mut f: impl FnMut(usize)) {
        let g = Self::group_len::<K>();
        // Only the words that hold groups (one for an edge model's 17 bins).
        let used = K.div_ceil(g).div_ceil(32);
        for (i, &word) in self.words.iter().enumerate().take(used) {
            let mut w = word;
            while w != 0 {
                let group = 32 * i + w.trailing_zeros() as usize;
                w &= w - 1;
                if g == 1 {
                    // One bin per bit (K <= 512, known at compile time).
                    if (lo..hi).contains(&group) {
                        f(group);
                    }
                } else {
                    for bin in (group * g).max(lo)..((group + 1) * g).min(hi) {
                        f(bin);
                    }
                }
            }
        }
    }
}

/// Fixed-point scale of a normalised model bin.
pub(super) const Q_ONE: u64 = 1 << 16;

impl<const K: usize> Model<K> {
    /// The model of a histogram, or `None` if the histogram is empty.
    pub fn from_histogram(h: &Histogram<K>) -> Option<Self> {
        Self::from_segments(h, 1)
    }
}

impl<const K: usize, const W: usize> Model<K, W> {
    /// The model of a histogram laid out in `segments` equal blocks (1 or 4),
    /// each normalised on its own; `None` if any block is empty.
    pub(crate) fn from_segments(h: &Histogram<K>, segments: u8) -> Option<Self> {
        // Checked before the model is built, so that it is built in place
        // (an early return from the filling loop costs a 2·K-byte copy on
        // the stack, which raises `init`'s peak stack: audit/budgets.txt).
        if !Self::can_learn(h, segments) {
            return None;
        }
        let mut m = Model { q: [0; K], sqrt_q: [0; K], support: Support::EMPTY, segments: 1 };
        m.learn(h, segments);
        Some(m)
    }

    /// Whether `h` has mass in each of its `segments` blocks (what
    /// [`Model::learn`] needs).
    pub(crate) fn can_learn(h: &Histogram<K>, segments: u8) -> bool {
        let segments = segments.max(1);
        let len = Self::len_of(segments);
        !h.counts.chunks(len).any(|c| segment_total(h, c, segments) == 0)
    }

    /// Replaces the model, in place, with that of `h` laid out in
    /// `segments` blocks; `h` must pass [`Model::can_learn`] (an empty block
    /// gets all-zero bins).
    pub(crate) fn learn(&mut self, h: &Histogram<K>, segments: u8) {
        let segments = segments.max(1);
        let len = Self::len_of(segments);
        self.segments = segments;
        for (q, c) in self.q.chunks_mut(len).zip(h.counts.chunks(len)) {
            let total = segment_total(h, c, segments);
            for (q, &c) in q.iter_mut().zip(c) {
                *q = normalised(c, total);
            }
        }
        self.refresh_roots();
    }

    /// An all-zero model (matches nothing), to be filled by [`Model::learn`].
    pub(crate) const fn zero() -> Self {
        Model { q: [0; K], sqrt_q: [0; K], support: Support::EMPTY, segments: 1 }
    }

    /// Bins per segment (at least 1, so that chunking is well defined).
    pub(super) fn segment_len(&self) -> usize {
        Self::len_of(self.segments)
    }

    pub(super) fn len_of(segments: u8) -> usize {
        // Without the feature a model has one segment, and saying so as a
        // constant lets the compiler drop the per-segment code.
        if !cfg!(feature = "quadrants") {
            return K.max(1);
        }
        (K / segments.max(1) as usize).max(1)
    }

    /// Blends a new observation into the model, `q ← (1 − α) q + α p`
    /// (the adaptive model of the first paper). `alpha` is clamped to `[0, 1]`;
    /// an empty histogram (or an empty segment of one) leaves the model (or
    /// that segment) unchanged.
    #[inline(never)]
    pub fn blend(&mut self, h: &Histogram<K>, alpha: Real) {
        self.blend_bins(h, alpha);
        self.refresh_roots();
    }

    /// [`Model::blend`] short of the roots the similarity sums read, for a
    /// caller that recomputes them at once ([`Model::reweight`]): 512
    /// square roots a model update saved.
    pub(crate) fn blend_bins(&mut self, h: &Histogram<K>, alpha: Real) {
        if h.total == 0 || !(alpha > 0.0) {
            return;
        }
        let a = (alpha.min(1.0) * Q_ONE as Real) as u64;
        let len = self.segment_len();
        for (q, c) in self.q.chunks_mut(len).zip(h.counts.chunks(len)) {
            let total = segment_total(h, c, self.segments);
            if total == 0 {
                continue;
            }
            for (q, &c) in q.iter_mut().zip(c) {
                let p = normalised(c, total) as u64;
                let v = ((Q_ONE - a) * *q as u64 + a * p + (Q_ONE >> 1)) >> 16;
                *q = v.min(u16::MAX as u64) as u16;
            }
        }
    }

    /// Weighs the model's bins by the odds `w`, each odds level `o` by
    /// `table[o]` sixteenths (the surroundings' weights, see
    /// [`crate::foreground::weights`]): the roots become those of the
    /// weighted bins, renormalised per segment, while `q` itself stays
    /// unweighted for blending. A weight is at most 240, so `q · weight` <
    /// 2^24 and a segment's sum (its q add up to about 2^16) fits easily in
    /// a u64.
    pub(crate) fn reweight(&mut self, w: &[u8; K], table: &[u32]) {
        let len = self.segment_len();
        let weight = |i: usize| {
            let o = w.get(i % len).copied().unwrap_or(0) as usize;
            table.get(o).copied().unwrap_or(0) as u64
        };
        for (j, (sq, q)) in self.sqrt_q.chunks_mut(len).zip(self.q.chunks(len)).enumerate() {
            let total: u64 = q.iter().enumerate().map(|(u, &q)| q as u64 * weight(j * len + u)).sum();
            // One division per segment: `v = q · w · 2^16 / total` is
            // `q · w · r / 2^24` with `r = 2^40 / total`, short of the exact
            // quotient by under one unit (`q · w / 2^24 <= total / 2^24 < 1`),
            // and at most 2^40 before the shift.
            let r = (1u64 << 40).checked_div(total);
            for (u, (s, &q)) in sq.iter_mut().zip(q.iter()).enumerate() {
                // A segment whose colours all have no weight keeps its plain roots.
                let v = match r {
                    Some(r) => ((q as u64 * weight(j * len + u) * r) >> 24).min(u16::MAX as u64) as u32,
                    None => q as u32,
                };
                *s = crate::scalar::isqrt(v << 8) as u16;
            }
        }
        self.support = Support::of(&self.sqrt_q);
    }

    pub(super) fn refresh_roots(&mut self) {
        for (s, &q) in self.sqrt_q.iter_mut().zip(self.q.iter()) {
            *s = root(q);
        }
        self.support = Support::of(&self.sqrt_q);
    }

    /// Bin `u` of the whole target's distribution, in units of `2^-16`:
    /// the mean over the segments of their bin `u` (bin `u` itself for a
    /// model of one segment).
    pub(crate) fn whole_bin(&self, u: usize) -> u32 {
        let len = self.segment_len();
        let sum: u32 = (0..self.segments as usize).filter_map(|s| self.q.get(s * len + u)).map(|&q| q as u32).sum();
        sum / self.segments.max(1) as u32
    }

    /// The normalised bins, in units of `2^-16`.
    pub fn bins(&self) -> &[u16; K] {
        &self.q
    }

    /// The model's non-empty bins, for [`Clear::Support`]; `None` for a
    /// model of several segments, whose comparisons need every bin.
    pub(crate) fn support(&self) -> Option<&Support<W>> {
        (self.segments <= 1).then_some(&self.support)
    }

    /// `sqrt(q(u))` per bin, in units of `2^-12`.
    pub(crate) fn sqrt_bins(&self) -> &[u16; K] {
        &self.sqrt_q
    }

    /// The Bhattacharyya coefficient `ρ = Σ sqrt(p(u) q(u))` between the
    /// histogram and this model, in `[0, 1]`: 1 for identical distributions,
    /// 0 for disjoint ones, 0 for an empty histogram.
    ///
    /// With `p(u) = c(u) / C` this is `Σ sqrt(c(u)) sqrt(q(u)) / sqrt(C)`, so the
    /// candidate histogram is never normalised: one integer root per non-empty
    /// bin and one division per comparison. The result is within 0.005 of
    /// the exact value (tested against an f64 implementation).
    pub fn bhattacharyya(&self, h: &Histogram<K>) -> Real {
        bhattacharyya::<K, W>(&h.counts, &self.sqrt_q, h.total, (&self.support, 0))
    }

    /// The histogram intersection `Σ min(p(u), q(u))`, in `[0, 1]`: 1 for
    /// identical distributions, 0 for disjoint ones and for an empty histogram.
    pub fn intersection(&self, h: &Histogram<K>) -> Real {
        intersection(&h.counts, &self.q, h.total)
    }

    /// How `h` compares with this model under `kind`. For a quadrant model,
    /// the comparisons of the four quadrants.
    #[inline(never)]
    pub(crate) fn compare(&self, h: &Histogram<K>, kind: Similarity) -> [Real; 4] {
        let mut out = [0.0; 4];
        let len = self.segment_len();
        let blocks = h.counts.chunks(len).zip(self.q.chunks(len)).zip(self.sqrt_q.chunks(len));
        for (j, (o, ((c, q), sq))) in out.iter_mut().zip(blocks).enumerate() {
            let total = segment_total(h, c, self.segments);
            *o = compare_block::<K, W>(c, (q, sq), total, kind, (&self.support, j * len));
        }
        out
    }
}

/// The mass of one segment's counts `c` (the histogram's total when there is
/// only one segment, saving a sum per comparison on the default path).
pub(super) fn segment_total<const K: usize>(h: &Histogram<K>, c: &[u32], segments: u8) -> u32 {
    if !cfg!(feature = "quadrants") || segments <= 1 { h.total } else { c.iter().fold(0u32, |a, &v| a.wrapping_add(v)) }
}

/// One block's similarity. Out of line, so that the per-particle caller
/// holds one copy of each sum rather than one per quadrant (inlined, the
/// copies cost more code than the call saves).
#[inline(never)]
pub(super) fn compare_block<const K: usize, const W: usize>(
    c: &[u32],
    (q, sq): (&[u16], &[u16]),
    total: u32,
    kind: Similarity,
    support: (&Support<W>, usize),
) -> Real {
    match kind {
        Similarity::Bhattacharyya => bhattacharyya::<K, W>(c, sq, total, support),
        Similarity::Intersection => intersection(c, q, total),
    }
}

/// `Σ sqrt(c(u)/C) sqrt(q(u))` from counts, their total and the model's
/// roots, for the block of bins from `first` (of a `K`-bin model whose
/// non-zero bins are `support`): only the model's non-zero bins are visited.
pub(super) fn bhattacharyya<const K: usize, const W: usize>(
    counts: &[u32],
    sqrt_q: &[u16],
    total: u32,
    (support, first): (&Support<W>, usize),
) -> Real {
    if total == 0 {
        return 0.0;
    }
    let mut sum = 0u64;
    support.for_each::<K>(first, first + counts.len(), |bin| {
        if let (Some(&c), Some(&s)) = (counts.get(bin - first), sqrt_q.get(bin - first))
            && c != 0
        {
            // sqrt_q4(c) < 2^20 and s <= 2^12: the product fits in u32.
            sum += (sqrt_q4(c) * s as u32) as u64;
        }
    });
    rho_of(sum, total)
}

/// `ρ` from the sum `Σ 16·sqrt(c(u)) · 4096·sqrt(q(u))` and the counts'
/// total `C` (not 0), clamped to `[0, 1]`. Inlined: it ends every
/// particle's Bhattacharyya sum, so a call's overhead would be paid once
/// per particle and show in the QVGA audit's instructions per frame.
#[inline(always)]
pub(super) fn rho_of(sum: u64, total: u32) -> Real {
    // Σ 16·sqrt(c) · 4096·sqrt(q) / (16·sqrt(C) · 4096)
    let denom = sqrt_q4(total) as Real * 4096.0;
    // In two 32-bit halves: one instruction each on a Cortex-M4F, where a
    // 64-bit conversion is a library call. The sum is at most about
    // 2^16·sqrt(C) (Cauchy–Schwarz, Σ q = 1), so the high half is 0 short
    // of huge totals, and the value is then the same.
    let sum = (sum >> 32) as u32 as Real * 4_294_967_296.0 + sum as u32 as Real;
    if denom > 0.0 { crate::scalar::clamp(sum / denom, 0.0, 1.0) } else { 0.0 }
}

/// `Σ min(c(u)/C, q(u))`, exactly in integers: `Σ min(c·2^16, q·C) / (C·2^16)`.
pub(super) fn intersection(counts: &[u32], q: &[u16], total: u32) -> Real {
    if total == 0 {
        return 0.0;
    }
    let mut sum = 0u64;
    for (&c, &q) in counts.iter().zip(q.iter()) {
        // Each term is below 2^48; K of them stay far below 2^64.
        sum += (c as u64 * Q_ONE).min(q as u64 * total as u64);
    }
    crate::scalar::clamp(sum as Real / (total as Real * Q_ONE as Real), 0.0, 1.0)
}

/// `c / total` in units of `2^-16`, saturated to `u16`.
pub(super) fn normalised(c: u32, total: u32) -> u16 {
    if total == 0 {
        return 0;
    }
    // Most bins are empty or small: below 2^15, `c·2^16 + total/2` fits in
    // 32 bits, and a 32-bit division is one instruction on a Cortex-M4
    // where the 64-bit one is a library call. The same value either way.
    if c < 1 << 15 {
        let v = ((c << 16) + (total >> 1)) / total;
        return v.min(u16::MAX as u32) as u16;
    }
    let v = (c as u64 * Q_ONE + (total as u64 >> 1)) / total as u64;
    v.min(u16::MAX as u64) as u16
}

/// `sqrt(q)` of a normalised bin, in units of `2^-12`:
/// `sqrt(q · 2^16 · 2^8) = sqrt(q_real) · 2^12`.
pub(super) fn root(q: u16) -> u16 {
    crate::scalar::isqrt((q as u32) << 8) as u16
}

/// A model's normalised bins alone, for a model compared once a frame
/// rather than once a particle (the tracker's first-frame anchor): the
/// roots the Bhattacharyya sum needs are taken as the sum goes, which
/// spares storing them and the support (`2·K + 64` bytes of RAM, 1 KB for
/// 512 bins). [`PlainModel::compare`] gives what [`Model::compare`] gives for the
/// model the bins were copied from, bit for bit.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct PlainModel<const K: usize> {
    pub(super) q: [u16; K],
    pub(super) segments: u8,
}

impl<const K: usize> PlainModel<K> {
    /// All-zero bins (match nothing), to be filled by [`PlainModel::copy_from`].
    pub(crate) const fn zero() -> Self {
        PlainModel { q: [0; K], segments: 1 }
    }

    /// Makes these the bins of `model`, in place (a new value would pass
    /// `2·K` bytes through the stack).
    pub(crate) fn copy_from<const W: usize>(&mut self, model: &Model<K, W>) {
        self.q.copy_from_slice(&model.q);
        self.segments = model.segments;
    }

    /// How `h` compares with these bins under `kind`, per segment (see
    /// [`Model::compare`]).
    pub(crate) fn compare(&self, h: &Histogram<K>, kind: Similarity) -> [Real; 4] {
        let mut out = [0.0; 4];
        let len = Model::<K>::len_of(self.segments);
        for (o, (c, q)) in out.iter_mut().zip(h.counts.chunks(len).zip(self.q.chunks(len))) {
            let total = segment_total(h, c, self.segments);
            *o = match kind {
                Similarity::Intersection => intersection(c, q, total),
                Similarity::Bhattacharyya if total == 0 => 0.0,
                Similarity::Bhattacharyya => {
                    // The bins both have, as `bhattacharyya` visits through
                    // the support (a bin's root is 0 only where it is).
                    let mut sum = 0u64;
                    for (&c, &q) in c.iter().zip(q.iter()) {
                        if c != 0 && q != 0 {
                            sum += (sqrt_q4(c) * root(q) as u32) as u64;
                        }
                    }
                    rho_of(sum, total)
                }
            };
        }
        out
    }
}

/// The Bhattacharyya distance `d = sqrt(1 − ρ)`.
pub fn bhattacharyya_distance(rho: Real) -> Real {
    crate::scalar::sqrt((1.0 - rho).max(0.0))
}
