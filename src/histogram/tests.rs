use super::model::*;
use super::walk::*;
use super::*;
use crate::colour::Binning;
use crate::edges::EdgeMap;
use crate::foreground::{BackgroundWeight, weights};
use crate::frame::Frame;
use crate::geometry::Ellipse;
use crate::pixel::{Gray8, PixelFormat, Rgb565, Rgb888};
use crate::region::for_each_in_ellipse;
use crate::region::{Lattice, Sampling, for_each_row};
use crate::scalar::{Real, sqrt_q4};

#[test]
fn normalising_in_32_bits_gives_the_64_bit_value() {
    // Reason: cross-check of two implementations. The 32-bit fast path
    // must give exactly the rounded 64-bit quotient, saturated, for
    // every count below 2^15 (both sides of the switch included) and
    // totals from 1 to the largest u32.
    let wide = |c: u32, t: u32| ((c as u64 * Q_ONE + (t as u64 >> 1)) / t as u64).min(u16::MAX as u64) as u16;
    let mut next = crate::testing::lcg(11);
    let mut totals = vec![1, 2, 3, 255, 256, 40_000, 65_535, 65_536, 1 << 20, u32::MAX - 1, u32::MAX];
    totals.extend((0..2000).map(|_| next() | 1));
    let mut counts = vec![0, 1, 2, 100, 4095, (1 << 15) - 1, 1 << 15, (1 << 15) + 1, 70_000];
    counts.extend((0..50).map(|_| next() >> 17));
    for &t in &totals {
        for &c in &counts {
            assert_eq!(normalised(c, t), wide(c, t), "c {c} total {t}");
        }
    }
}

#[test]
fn histogram_mass_is_the_kernel_mass() {
    // Reason: every sampled pixel lands in exactly one bin, so the bins sum
    // to the total, which is the kernel mass the region walk visits, under
    // every sampling and in every binning.
    let mut buf = vec![0u8; 64 * 64 * 3];
    for (i, p) in buf.iter_mut().enumerate() {
        *p = (i * 37 % 251) as u8;
    }
    let f = Frame::packed(&buf, 64, 64, PixelFormat::Rgb888).unwrap();
    let e = Ellipse { cx: 30.0, cy: 33.0, hx: 12.0, hy: 9.0 };
    for sampling in [Sampling::Full, Sampling::Checkerboard, Sampling::Quarter] {
        for binning in [Binning::Rgb8x8x8, Binning::Hsv8x8x4] {
            let mut h = Histogram::<512>::new();
            h.compute(&f, &e, binning, sampling);
            let sum: u64 = h.counts().iter().map(|&c| c as u64).sum();
            assert_eq!(sum, h.total() as u64);
            let mut mass = 0u64;
            for_each_in_ellipse(&f, &e, Lattice::new(sampling, 0, e.hx, e.hy), |_, _, _, w| mass += w as u64);
            assert_eq!(sum, mass);
            assert!(h.counts()[binning.bins()..].iter().all(|&c| c == 0), "bins past {binning:?}'s range");
            // A model made from it sums to 1 within the rounding of 512 bins.
            let m = Model::from_histogram(&h).unwrap();
            let qsum: i64 = m.bins().iter().map(|&q| q as i64).sum();
            assert!((qsum - 65536).abs() <= 256, "{qsum}");
        }
    }
}

/// The frame size of [`noise_scenes`].
const NOISE: (usize, usize) = (90, 70);

/// Random RGB565 and GRAY8 pixels of a frame of [`NOISE`] size, and a
/// source of ellipses inside it, across its border, off it, tiny and
/// large: the cases the region walks' cross-checks compare.
fn noise_scenes(seed: u32) -> (Vec<u8>, Vec<u8>, impl FnMut() -> Ellipse) {
    let (w, h) = NOISE;
    let mut state = crate::testing::lcg(seed);
    let mut next = move || state() >> 8;
    let rgb: Vec<u8> = (0..w * h * 2).map(|_| next() as u8).collect();
    let grey: Vec<u8> = (0..w * h).map(|_| next() as u8).collect();
    let ellipse = move || Ellipse {
        cx: (next() % 1300) as f32 / 10.0 - 20.0,
        cy: (next() % 1100) as f32 / 10.0 - 20.0,
        hx: (next() % 400) as f32 / 10.0 + 0.2,
        hy: (next() % 400) as f32 / 10.0 + 0.2,
    };
    (rgb, grey, ellipse)
}

/// The frames of [`noise_scenes`]' pixels.
fn noise_frames<'a>(rgb: &'a [u8], grey: &'a [u8]) -> [Frame<'a>; 2] {
    let (w, h) = NOISE;
    [Frame::packed(rgb, w, h, PixelFormat::Rgb565).unwrap(), Frame::packed(grey, w, h, PixelFormat::Gray8).unwrap()]
}

#[test]
fn the_per_format_row_bins_equal_the_general_ones() {
    // Reason: a cross-check of two implementations of a row's bins
    // under the default layout: each format's own loop over packed
    // pixels and the general accessor's (what RGB888 takes on bare
    // metal), on random RGB565, RGB888 and GRAY8 frames, for runs from
    // several columns and steps, including runs past the row's end.
    let (rgb, grey, _) = noise_scenes(21);
    let (w, h) = NOISE;
    let rgb888 = crate::testing::noise_bytes(22, w * h * 3);
    let frames = [
        Frame::packed(&rgb, w, h, PixelFormat::Rgb565).unwrap(),
        Frame::packed(&rgb888, w, h, PixelFormat::Rgb888).unwrap(),
        Frame::packed(&grey, w, h, PixelFormat::Gray8).unwrap(),
    ];
    let layout = Layout::whole(Binning::Rgb8x8x8);
    for f in &frames {
        for y in [0, 7, h - 1] {
            let row = f.row(y).unwrap();
            for (x0, step, n) in [(0, 1, w), (3, 2, 40), (1, 3, 50), (w - 5, 1, 20)] {
                let (mut own, mut any) = (Vec::new(), Vec::new());
                let at = (x0, step, n);
                match f.format() {
                    PixelFormat::Rgb565 => packed_bins::<Rgb565, _>(row, at, |i, b| own.push((i, b))),
                    PixelFormat::Rgb888 => packed_bins::<Rgb888, _>(row, at, |i, b| own.push((i, b))),
                    _ => packed_bins::<Gray8, _>(row, at, |i, b| own.push((i, b))),
                }
                general_bins(f, &layout, y, at, |i, b| any.push((i, b)));
                assert_eq!(own, any, "{:?} row {y} from {x0} by {step}", f.format());
                assert_eq!(own.len(), n.min((w - x0).div_ceil(step)));
            }
        }
    }
}

#[test]
fn the_per_format_loops_equal_the_shared_one() {
    // Reason: a cross-check of two implementations of one histogram:
    // each pixel format's own walk (checkerboard rows, pair rows, the
    // indexed loop) and the shared loop that reads pixels through the
    // general accessor (what RGB888 takes on bare metal) must give
    // identical colour and edge counts and totals, on random frames of
    // the four packed formats, on the lattices a target's size selects,
    // with an edge map and without, for ellipses inside, across the
    // border, off the frame, tiny and large.
    let (rgb, grey, mut ellipse) = noise_scenes(13);
    let (w, h) = NOISE;
    let rgb888 = crate::testing::noise_bytes(17, w * h * 3);
    let frames = [
        Frame::packed(&rgb, w, h, PixelFormat::Rgb565).unwrap(),
        Frame::packed(&rgb, w, h, PixelFormat::Yuv422).unwrap(),
        Frame::packed(&grey, w, h, PixelFormat::Gray8).unwrap(),
        Frame::packed(&rgb888, w, h, PixelFormat::Rgb888).unwrap(),
    ];
    let layout = Layout::whole(Binning::Rgb8x8x8);
    let mut filled = 0;
    for f in &frames {
        for (sampling, step) in [(Sampling::Checkerboard, 1), (Sampling::Checkerboard, 2), (Sampling::Full, 3)] {
            let lattice = Lattice::with_step(sampling, step);
            let mut map = EdgeMap::<4096>::new();
            map.compute_on(f, (0, 0, w, h), 8, 60, false, lattice);
            for _ in 0..100 {
                let e = ellipse();
                for with_map in [true, false] {
                    let (mut h1, mut h2) = (Histogram::<512>::new(), Histogram::<512>::new());
                    let (mut e1, mut e2) = (EdgeHistogram::new(), EdgeHistogram::new());
                    let (m1, m2) = match with_map {
                        true => (Some((&map, &mut e1)), Some((&map, &mut e2))),
                        false => (None, None),
                    };
                    h1.compute_by::<4096>(f, &e, (&layout, lattice), m1, Clear::All, true);
                    h2.compute_by::<4096>(f, &e, (&layout, lattice), m2, Clear::All, false);
                    assert_eq!((h1.total, h1.counts), (h2.total, h2.counts), "{:?} {lattice:?} {e:?}", f.format());
                    assert_eq!((e1.total, e1.counts), (e2.total, e2.counts), "{:?} {lattice:?} {e:?}", f.format());
                    filled += (h1.total > 0) as u32;
                }
            }
        }
    }
    assert!(filled > 1000, "only {filled} regions had pixels");
}

#[test]
fn checkerboard_walk_equals_the_general_walk() {
    // Reason: a cross-check of two implementations of the same walk: the
    // checkerboard's own (row geometry written out) and the general one
    // (any lattice) must give identical colour and edge counts and
    // totals, on random RGB565 and GRAY8 scenes, for ellipses inside,
    // across the border, off the frame, tiny and large; with the map over
    // the whole frame, and over its columns from the 23rd on (as the
    // tracker maps only where its hypotheses are), so that rows start left
    // of the map.
    let (rgb, grey, mut ellipse) = noise_scenes(7);
    let frames = noise_frames(&rgb, &grey);
    let (w, h) = NOISE;
    let lattice = Lattice::CHECKERBOARD;
    let mut checked = 0;
    for (f, left) in frames.iter().flat_map(|f| [(f, 0), (f, 23)]) {
        let mut map = EdgeMap::<4096>::new();
        map.compute_on(f, (left, 0, w, h), 8, 60, false, lattice);
        let rows = map.checker_rows().expect("4-bit cells at full resolution");
        for _ in 0..300 {
            let e = ellipse();
            let (mut c1, mut e1) = ([0u32; 512], [0u32; MAX_EDGE_BINS]);
            let (mut c2, mut e2) = ([0u32; 512], [0u32; MAX_EDGE_BINS]);
            let (t1, t2) = match f.format() {
                PixelFormat::Rgb565 => (
                    checker_walk::<Rgb565, 512>(f, &e, rows, &mut c1, &mut e1).unwrap(),
                    general_walk::<Rgb565, 512, 4096>(f, &e, lattice, Some(&map), &mut c2, &mut e2),
                ),
                _ => (
                    checker_walk::<Gray8, 512>(f, &e, rows, &mut c1, &mut e1).unwrap(),
                    general_walk::<Gray8, 512, 4096>(f, &e, lattice, Some(&map), &mut c2, &mut e2),
                ),
            };
            assert_eq!((t1, c1, e1), (t2, c2, e2), "{e:?}");
            checked += (t1 > 0) as u32;
        }
    }
    assert!(checked > 600, "only {checked} ellipses had pixels");
}

#[test]
fn pair_rows_equal_the_indexed_rows() {
    // Reason: a cross-check of two implementations of one walk: rows of
    // whole cell bytes (`pair_row`, with a lone sample at either end
    // where its cell shares a byte with one outside the row) and the
    // per-sample indexed loop must give identical colour
    // and edge counts and totals, on random RGB565 and GRAY8 scenes, on
    // the lattices a target's size selects (checker and full, steps 1
    // to 3), for ellipses inside, across the border, off the frame, tiny
    // and large.
    let (rgb, grey, mut ellipse) = noise_scenes(11);
    let frames = noise_frames(&rgb, &grey);
    let (w, h) = NOISE;
    let (mut paired, mut rows) = (0u32, 0u32);
    for f in &frames {
        for (sampling, step) in
            [(Sampling::Checkerboard, 2), (Sampling::Checkerboard, 3), (Sampling::Full, 1), (Sampling::Full, 2)]
        {
            let lattice = Lattice::with_step(sampling, step);
            let mut map = EdgeMap::<4096>::new();
            map.compute_on(f, (0, 0, w, h), 8, 60, false, lattice);
            assert!(map.nibbles(), "4-bit cells");
            for _ in 0..200 {
                let e = ellipse();
                let (mut c1, mut e1) = ([0u32; 512], [0u32; MAX_EDGE_BINS]);
                let (mut c2, mut e2) = ([0u32; 512], [0u32; MAX_EDGE_BINS]);
                let (mut c3, mut e3) = ([0u32; 512], [0u32; MAX_EDGE_BINS]);
                let mut t1 = 0u32;
                let t2 = match f.format() {
                    PixelFormat::Rgb565 => {
                        for_each_row(f, &e, lattice, |span| {
                            let cells = map.row_cells(&span);
                            t1 += indexed_row::<Rgb565, 512>(&span, &cells, &mut c1, &mut e1);
                            rows += 1;
                            paired += pair_row::<Rgb565, 512>(&span, &cells, &mut c3, &mut e3) as u32;
                        });
                        general_walk::<Rgb565, 512, 4096>(f, &e, lattice, Some(&map), &mut c2, &mut e2)
                    }
                    _ => {
                        for_each_row(f, &e, lattice, |span| {
                            let cells = map.row_cells(&span);
                            t1 += indexed_row::<Gray8, 512>(&span, &cells, &mut c1, &mut e1);
                            rows += 1;
                            paired += pair_row::<Gray8, 512>(&span, &cells, &mut c3, &mut e3) as u32;
                        });
                        general_walk::<Gray8, 512, 4096>(f, &e, lattice, Some(&map), &mut c2, &mut e2)
                    }
                };
                assert_eq!((t1, c1, e1), (t2, c2, e2), "{lattice:?} {e:?}");
            }
        }
    }
    // Most rows take the pair loop; those at the frame's edge do not.
    assert!(paired * 4 > rows * 3, "{paired} of {rows} rows paired");
}

#[test]
fn checkerboard_histogram_matches_full_on_a_smooth_image() {
    // Reason: on a smooth image neighbouring pixels have nearly the same
    // colour, so half of them estimate the same distribution: the paper
    // measured ρ = 0.9998 for the checkerboard, 0.9993 for a quarter.
    let (w, h) = (120usize, 90usize);
    let mut buf = Vec::with_capacity(w * h * 3);
    for y in 0..h {
        for x in 0..w {
            let fx = x as f32 / w as f32;
            let fy = y as f32 / h as f32;
            buf.extend_from_slice(&[(255.0 * fx) as u8, (255.0 * fy) as u8, (128.0 + 100.0 * (fx - fy)) as u8]);
        }
    }
    let f = Frame::packed(&buf, w, h, PixelFormat::Rgb888).unwrap();
    let e = Ellipse { cx: 60.0, cy: 45.0, hx: 30.0, hy: 25.0 };
    let mut full = Histogram::<512>::new();
    full.compute(&f, &e, Binning::Rgb8x8x8, Sampling::Full);
    let m = Model::from_histogram(&full).unwrap();
    let mut part = Histogram::<512>::new();
    part.compute(&f, &e, Binning::Rgb8x8x8, Sampling::Checkerboard);
    let rho_c = m.bhattacharyya(&part);
    part.compute(&f, &e, Binning::Rgb8x8x8, Sampling::Quarter);
    let rho_q = m.bhattacharyya(&part);
    assert!(rho_c > 0.99, "checkerboard ρ {rho_c}");
    assert!(rho_q > 0.99, "quarter ρ {rho_q}");
}

fn reference_rho(p: &Histogram<512>, q: &Histogram<512>) -> f64 {
    let (tp, tq) = (p.total() as f64, q.total() as f64);
    p.counts().iter().zip(q.counts().iter()).map(|(&a, &b)| ((a as f64 / tp) * (b as f64 / tq)).sqrt()).sum()
}

#[test]
fn bhattacharyya_identical_disjoint_and_reference() {
    let mut a = Histogram::<512>::new();
    let mut b = Histogram::<512>::new();
    for (bin, w) in [(3usize, 1000u32), (40, 256), (41, 17), (500, 5000)] {
        a.add(bin, w);
    }
    for (bin, w) in [(7usize, 1000u32), (8, 256)] {
        b.add(bin, w);
    }
    let ma = Model::from_histogram(&a).unwrap();
    // Reason: ρ(p, p) = Σ p(u) = 1 exactly; the fixed point costs < 0.005.
    let same = ma.bhattacharyya(&a);
    assert!(same > 0.995 && same <= 1.0, "{same}");
    // Reason: no shared bin, so every product is zero.
    assert_eq!(ma.bhattacharyya(&b), 0.0);
    assert_eq!(ma.bhattacharyya(&Histogram::new()), 0.0);
    assert!(Model::from_histogram(&Histogram::<512>::new()).is_none());

    // Reason: cross-check against a straightforward f64 implementation on
    // pseudo-random histograms of varied sparsity and mass.
    let mut seed = 12345u64;
    let mut next = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 33) as u32
    };
    for trial in 0..50 {
        let mut p = Histogram::<512>::new();
        let mut q = Histogram::<512>::new();
        let used = 4 + trial * 10;
        for _ in 0..used {
            let bin = next() as usize % 512;
            p.add(bin, next() % 2000 + 1);
            if next() % 3 != 0 {
                q.add(bin, next() % 2000 + 1);
            } else {
                q.add(next() as usize % 512, next() % 50 + 1);
            }
        }
        let got = Model::from_histogram(&q).unwrap().bhattacharyya(&p) as f64;
        let want = reference_rho(&p, &q);
        assert!((got - want).abs() < 0.005, "trial {trial}: {got} vs {want}");
    }
}

#[test]
fn clearing_the_support_only_gives_the_same_similarities() {
    // Reason: a histogram cleared only on the model's support (holding
    // leftovers of earlier regions elsewhere) must compare with that
    // model exactly as a freshly cleared one does, under both similarity
    // kinds: the sums read no other bin. Regions of a random RGB565
    // scene, one after another in the same histogram.
    let (w, h) = (80usize, 60usize);
    let mut state = crate::testing::lcg(99);
    let mut next = move || state() >> 8;
    let px: Vec<u8> = (0..w * h * 2).map(|_| (next() % 7 * 37) as u8).collect();
    let f = Frame::packed(&px, w, h, PixelFormat::Rgb565).unwrap();
    let layout = Layout::whole(Binning::Rgb8x8x8);
    let lattice = Lattice::CHECKERBOARD;
    let mut target = Histogram::<512>::new();
    target.compute_on(&f, &Ellipse { cx: 40.0, cy: 30.0, hx: 9.0, hy: 7.0 }, Binning::Rgb8x8x8, lattice);
    let model = Model::from_histogram(&target).unwrap();
    let support = model.support().expect("one segment");
    let mut reused = Histogram::<512>::new();
    let mut fresh = Histogram::<512>::new();
    for i in 0..40 {
        let e = Ellipse { cx: (next() % 80) as f32, cy: (next() % 60) as f32, hx: 3.0 + i as f32 * 0.3, hy: 6.0 };
        reused.compute_with::<0>(&f, &e, &layout, lattice, None, Clear::Support(support));
        fresh.compute_with::<0>(&f, &e, &layout, lattice, None, Clear::All);
        for kind in [Similarity::Bhattacharyya, Similarity::Intersection] {
            assert_eq!(model.compare(&reused, kind), model.compare(&fresh, kind), "{e:?} {kind:?}");
        }
    }
    // The leftovers are really there: outside the support, the reused
    // histogram differs from the fresh one.
    assert_ne!(reused.counts(), fresh.counts());
}

#[test]
fn plain_model_compares_as_its_model_does() {
    // Reason: cross-check of two implementations. A `PlainModel` takes
    // each root as its sum goes, where a `Model` reads stored roots
    // through its support; both sum the same integer terms, so every
    // comparison must be equal bit for bit, for models of one and four
    // segments, under both similarity kinds, on random sparse
    // histograms (empty ones and ones disjoint from the model included).
    let mut next = crate::testing::lcg(5);
    let mut random = |fill: u32| {
        let mut h = Histogram::<512>::new();
        for bin in 0..512 {
            if next() % 100 < fill {
                h.add(bin, next() % 5000);
            }
        }
        h
    };
    for segments in [1u8, 4] {
        for round in 0..30 {
            let learnt = random(40);
            let Some(model) = Model::<512>::from_segments(&learnt, segments) else { continue };
            let mut plain = PlainModel::zero();
            plain.copy_from(&model);
            for h in [random(round % 10), random(60), Histogram::new(), learnt.clone()] {
                for kind in [Similarity::Bhattacharyya, Similarity::Intersection] {
                    assert_eq!(plain.compare(&h, kind), model.compare(&h, kind), "{segments} {kind:?}");
                }
            }
        }
    }
}

/// The Bhattacharyya sum over every bin, with no support bitmap, in
/// the same fixed point as [`bhattacharyya`].
fn rho_over_all_bins<const K: usize>(m: &Model<K>, h: &Histogram<K>) -> Real {
    let sum: u64 = h.counts().iter().zip(m.sqrt_bins()).map(|(&c, &s)| (sqrt_q4(c) * s as u32) as u64).sum();
    crate::scalar::clamp(sum as Real / (sqrt_q4(h.total()) as Real * 4096.0), 0.0, 1.0)
}

fn support_matches_all_bins<const K: usize>(next: &mut impl FnMut() -> u32) {
    for trial in 0..40 {
        let (mut p, mut q) = (Histogram::<K>::new(), Histogram::<K>::new());
        for _ in 0..(1 + trial * 7) {
            p.add(next() as usize % K, next() % 3000 + 1);
            q.add(next() as usize % K, next() % 3000 + 1);
        }
        // Shared bins too, at both ends of the range (bitmap word edges).
        for bin in [0, 31, 32, K / 2, K - 1] {
            p.add(bin, next() % 100 + 1);
            if next().is_multiple_of(2) {
                q.add(bin, next() % 100 + 1);
            }
        }
        let m = Model::from_histogram(&q).unwrap();
        assert_eq!(m.bhattacharyya(&p), rho_over_all_bins(&m, &p), "K = {K}, trial {trial}");
    }
}

#[test]
fn support_sum_equals_the_sum_over_all_bins() {
    // Reason: bins where the model is zero add nothing, so visiting only
    // the model's support must give the very same integer sum; checked
    // for one bit per bin (512, 17) and for groups of bins (K > 512).
    let mut seed = 777u64;
    let mut next = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 33) as u32
    };
    support_matches_all_bins::<512>(&mut next);
    support_matches_all_bins::<17>(&mut next);
    support_matches_all_bins::<1030>(&mut next);
    support_matches_all_bins::<2048>(&mut next);
}

#[test]
fn intersection_identical_disjoint_reference_and_below_rho() {
    let mut a = Histogram::<512>::new();
    for (bin, w) in [(3usize, 1000u32), (40, 256), (41, 17), (500, 5000)] {
        a.add(bin, w);
    }
    let m = Model::from_histogram(&a).unwrap();
    // Reason: Σ min(p, p) = Σ p = 1; the model's 2^-16 rounding costs
    // at most a few units.
    let same = m.intersection(&a);
    assert!(same > 0.999 && same <= 1.0, "{same}");
    // Reason: no shared bin, so every minimum is zero.
    let mut b = Histogram::<512>::new();
    b.add(7, 10);
    assert_eq!(m.intersection(&b), 0.0);
    assert_eq!(m.intersection(&Histogram::new()), 0.0);
    // Reason: cross-check with f64 on pseudo-random histograms, and the
    // invariant min(p, q) <= sqrt(p q), so intersection <= ρ.
    let mut seed = 99u64;
    let mut next = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 33) as u32
    };
    for trial in 0..50 {
        let (mut p, mut q) = (Histogram::<512>::new(), Histogram::<512>::new());
        for _ in 0..4 + trial * 10 {
            let bin = next() as usize % 512;
            p.add(bin, next() % 2000 + 1);
            q.add(if next() % 3 == 0 { next() as usize % 512 } else { bin }, next() % 2000 + 1);
        }
        let model = Model::from_histogram(&q).unwrap();
        let got = model.intersection(&p) as f64;
        let (tp, tq) = (p.total() as f64, q.total() as f64);
        let want: f64 =
            p.counts().iter().zip(q.counts().iter()).map(|(&x, &y)| (x as f64 / tp).min(y as f64 / tq)).sum();
        assert!((got - want).abs() < 0.005, "trial {trial}: {got} vs {want}");
        assert!(got <= model.bhattacharyya(&p) as f64 + 0.005, "trial {trial}");
    }
}

#[cfg(feature = "quadrants")]
#[test]
fn quadrant_blocks_are_normalised_and_compared_apart() {
    // Reason: each quadrant block of a 4-segment model sums to 1 on its
    // own, so a quadrant's similarity does not depend on how much mass
    // the others hold: doubling one block's counts leaves all four
    // comparisons unchanged, and emptying a block's match drops only it.
    let mut h = Histogram::<512>::new();
    for q in 0..4 {
        h.add(q * 128 + 5, 100 * (q as u32 + 1));
        h.add(q * 128 + 9, 50);
    }
    let m = Model::<512>::from_segments(&h, 4).unwrap();
    for q in 0..4 {
        let sum: u32 = m.bins()[q * 128..(q + 1) * 128].iter().map(|&v| v as u32).sum();
        assert!((65530..=65536).contains(&sum), "block {q}: {sum}");
    }
    let base = m.compare(&h, Similarity::Bhattacharyya);
    assert!(base.iter().all(|&r| r > 0.995), "{base:?}");
    let mut heavier = h.clone();
    heavier.add(5, 100);
    heavier.add(9, 50);
    assert_eq!(m.compare(&heavier, Similarity::Bhattacharyya)[1..], base[1..]);
    let mut moved = Histogram::<512>::new();
    for q in 0..4 {
        let bin = if q == 2 { q * 128 + 77 } else { q * 128 + 5 };
        moved.add(bin, 100);
    }
    let r = m.compare(&moved, Similarity::Bhattacharyya);
    assert_eq!(r[2], 0.0);
    assert!(r[0] > 0.5 && r[1] > 0.5 && r[3] > 0.5, "{r:?}");
    // An empty block has no model.
    let mut gap = Histogram::<512>::new();
    gap.add(5, 1);
    assert!(Model::<512>::from_segments(&gap, 4).is_none());
}

#[test]
fn blend_moves_the_model_by_alpha() {
    // Reason: q' = (1 − α) q + α p bin by bin; with q all in bin 1 and p all
    // in bin 2, α = 0.25 gives 0.75 and 0.25. A bin holding all the mass
    // saturates at 65535/65536, so bin 1 may be one unit short.
    let mut q = Histogram::<512>::new();
    q.add(1, 100);
    let mut p = Histogram::<512>::new();
    p.add(2, 300);
    let mut m = Model::from_histogram(&q).unwrap();
    m.blend(&p, 0.25);
    assert!((49151..=49152).contains(&m.bins()[1]), "{}", m.bins()[1]);
    assert_eq!(m.bins()[2], 16384);
    let before = m.clone();
    m.blend(&p, 0.0);
    assert_eq!(m, before, "alpha 0 leaves the model alone");
    m.blend(&Histogram::new(), 0.5);
    assert_eq!(m, before, "an empty observation leaves the model alone");
}

#[test]
fn reweighting_scales_each_bin_by_its_odds_as_configured() {
    // Reason, by hand: half the model in bin 1, which the surroundings
    // lack (odds 15 of 15), half in bin 2, which only they have (odds
    // 0). At strength s a bin counts 1 − s + s · odds / 15 times, so the
    // weighted model is (1, 1 − s) renormalised: at s = 0.5, 2/3 and
    // 1/3, whose roots in units of 2^-12 are 3344.0 and 2364.9; at s = 1
    // bin 2 drops out and bin 1 holds everything (root 4096, one unit
    // less where the bin saturates); at s = 0 the plain roots, 2896.3.
    let mut h = Histogram::<512>::new();
    h.add(1, 100);
    h.add(2, 100);
    let mut odds = [8u8; 512];
    (odds[1], odds[2]) = (15, 0);
    let plain = Model::from_histogram(&h).unwrap();
    let near = |got: u16, want: f64| (got as f64 - want).abs() <= 2.0;
    for (s, want1, want2) in [(0.5, 3344.0, 2364.9), (1.0, 4096.0, 0.0), (0.0, 2896.3, 2896.3)] {
        let mut m = plain.clone();
        m.reweight(&odds, &weights(BackgroundWeight { strength: s, above: 0.0 }));
        assert!(near(m.sqrt_q[1], want1) && near(m.sqrt_q[2], want2), "s = {s}: {} {}", m.sqrt_q[1], m.sqrt_q[2]);
        assert_eq!(m.q, plain.q, "the bins blended later stay unweighted");
    }
    // Blending short of the roots, then reweighting, is what blending
    // and reweighting give: the roots `blend` computes are replaced.
    let mut p = Histogram::<512>::new();
    p.add(2, 50);
    p.add(3, 50);
    let (mut a, mut b) = (plain.clone(), plain.clone());
    a.blend(&p, 0.3);
    let half = &weights(BackgroundWeight { strength: 0.5, above: 0.0 });
    a.reweight(&odds, half);
    b.blend_bins(&p, 0.3);
    b.reweight(&odds, half);
    assert_eq!(a, b);
    // Above a threshold: bin 2 at odds 12 of 15. With `above` 0 it
    // counts 0.5 + 0.5 · 12/15 = 0.9 against bin 1's 1, so 1/1.9 and
    // 0.9/1.9 (roots 2971.6 and 2819.1); with `above` 0.8 (12 of 15)
    // it gains nothing, 0.5 against 1: 2/3 and 1/3 again.
    odds[2] = 12;
    for (above, want1, want2) in [(0.0, 2971.6, 2819.1), (0.8, 3344.0, 2364.9)] {
        let mut m = plain.clone();
        m.reweight(&odds, &weights(BackgroundWeight { strength: 0.5, above }));
        assert!(near(m.sqrt_q[1], want1) && near(m.sqrt_q[2], want2), "above {above}: {} {}", m.sqrt_q[1], m.sqrt_q[2]);
    }
}

#[test]
fn distance_of_coefficient() {
    assert_eq!(bhattacharyya_distance(1.0), 0.0);
    assert_eq!(bhattacharyya_distance(0.0), 1.0);
    assert!((bhattacharyya_distance(0.75) - 0.5).abs() < 1e-6);
}
