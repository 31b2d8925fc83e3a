//! Property tests of the core's invariants, on random inputs (proptest).
//! Each property says why it must hold.

use pftrack::{Binning, BoundingBox, Config, Ellipse, Frame, Histogram, Model, PixelFormat, Sampling, Tracker};
use proptest::prelude::*;

fn frame_bytes() -> impl Strategy<Value = (usize, usize, Vec<u8>)> {
    (4usize..48, 4usize..48)
        .prop_flat_map(|(w, h)| (Just(w), Just(h), proptest::collection::vec(any::<u8>(), w * h * 3)))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    /// Every sampled pixel adds its weight to exactly one bin, so the bins
    /// sum to the total, under every sampling and binning, anywhere on or
    /// off the frame.
    #[test]
    fn histogram_mass_is_conserved(
        (w, h, px) in frame_bytes(),
        cx in -20.0f32..70.0, cy in -20.0f32..70.0, hx in 0.0f32..40.0, hy in 0.0f32..40.0,
        s in 0usize..3, b in 0usize..2,
    ) {
        let f = Frame::packed(&px, w, h, PixelFormat::Rgb888).unwrap();
        let sampling = [Sampling::Full, Sampling::Checkerboard, Sampling::Quarter][s];
        let binning = [Binning::Rgb8x8x8, Binning::Hsv8x8x4][b];
        let mut hist = Histogram::<512>::new();
        hist.compute(&f, &Ellipse { cx, cy, hx, hy }, binning, sampling);
        let sum: u64 = hist.counts().iter().map(|&c| c as u64).sum();
        prop_assert_eq!(sum, hist.total() as u64);
        // And a subset never outweighs the whole: sampling only removes pixels.
        let mut full = Histogram::<512>::new();
        full.compute(&f, &Ellipse { cx, cy, hx, hy }, binning, Sampling::Full);
        prop_assert!(hist.total() <= full.total());
    }

    /// ρ is a cosine of square-root vectors: in [0, 1], and the same both
    /// ways up to the fixed-point rounding of the model side (0.01).
    #[test]
    fn bhattacharyya_in_unit_interval_and_symmetric(
        a in proptest::collection::vec((0usize..512, 1u32..5000), 1..60),
        b in proptest::collection::vec((0usize..512, 1u32..5000), 1..60),
    ) {
        let mut p = Histogram::<512>::new();
        let mut q = Histogram::<512>::new();
        for (bin, w) in a { p.add(bin, w); }
        for (bin, w) in b { q.add(bin, w); }
        let pq = Model::from_histogram(&q).unwrap().bhattacharyya(&p);
        let qp = Model::from_histogram(&p).unwrap().bhattacharyya(&q);
        prop_assert!((0.0..=1.0).contains(&pq) && (0.0..=1.0).contains(&qp));
        prop_assert!((pq - qp).abs() < 0.01, "{} vs {}", pq, qp);
    }

    /// Whatever the frames, the estimate is finite, its centre inside the
    /// frame (particles are kept there, and the estimate is their weighted
    /// mean: inside their hull), confidence in [0, 1], weights normalised.
    #[test]
    fn estimates_stay_sane_on_arbitrary_frames(
        (w, h, px) in frame_bytes(),
        frames in proptest::collection::vec(any::<u8>(), 1..4),
        bx in 0.0f32..1.0, by in 0.0f32..1.0, bw in 0.05f32..1.0, bh in 0.05f32..1.0,
        seed in any::<u64>(),
    ) {
        let f0 = Frame::packed(&px, w, h, PixelFormat::Rgb888).unwrap();
        let (fw, fh) = (w as f32, h as f32);
        let bbox = BoundingBox::new(bx * fw * 0.9, by * fh * 0.9, (bw * fw).max(1.0), (bh * fh).max(1.0));
        let mut t: Box<Tracker<30>> = Box::new(Tracker::new(Config::default(), seed).unwrap());
        if t.init(&f0, bbox).is_err() {
            return Ok(()); // a box the core refuses (e.g. larger than the frame) is covered elsewhere
        }
        for fill in frames {
            // A frame of one grey level, or the original with a shifted palette.
            let shifted: Vec<u8> = px.iter().map(|p| p.wrapping_add(fill)).collect();
            let f = Frame::packed(&shifted, w, h, PixelFormat::Rgb888).unwrap();
            let e = t.step(&f).unwrap();
            let el = e.ellipse;
            prop_assert!(el.cx.is_finite() && el.cy.is_finite() && el.hx.is_finite() && el.hy.is_finite());
            prop_assert!(el.cx >= 0.0 && el.cx <= fw && el.cy >= 0.0 && el.cy <= fh, "{:?}", el);
            prop_assert!((0.0..=1.0).contains(&e.confidence));
            let (lo_x, hi_x) = t.particles().iter().fold((f32::MAX, f32::MIN), |(a, b), p| (a.min(p.x), b.max(p.x)));
            prop_assert!(el.cx >= lo_x - 1e-3 && el.cx <= hi_x + 1e-3, "mean outside the particles' hull");
            let sum: f32 = t.weights().iter().sum();
            prop_assert!((sum - 1.0).abs() < 1e-4, "weights sum to {}", sum);
        }
    }
}
