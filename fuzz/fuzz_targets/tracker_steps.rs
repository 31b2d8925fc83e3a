//! A tracker fed arbitrary frames, an arbitrary box and a few steps, under
//! one of several configurations (the defaults and each optional technique,
//! or a mean-shift baseline). On every input: no panic; every estimate finite
//! and inside the frame; confidence in [0, 1]; weights normalised.
#![no_main]
use libfuzzer_sys::fuzz_target;
use pftrack::{
    Binning, BoundaryCue, BoundingBox, Config, Frame, GradientCue, LostSearch, MeanShift, MeanShiftConfig, ModelUpdate,
    PixelFormat, Redetect, ScalePrior, Shape, Similarity, TableMode, Tracker,
};
use rand_xoshiro::Xoshiro128PlusPlus;

fn config(pick: u8) -> Config {
    let d = Config::default();
    match pick % 15 {
        0 => d,
        1 => Config { quadrants: true, binning: Binning::Rgb4x4x4, ..d },
        2 => Config { quadrants: true, binning: Binning::Adaptive, ..d },
        3 => Config { similarity: Similarity::Intersection, ..d },
        4 => Config { likelihood: pftrack::Likelihood { shape: Shape::Exponential, ..d.likelihood }, ..d },
        5 => Config { model_update: ModelUpdate::WhenDegraded { factor: 0.9, frames: 2 }, ..d },
        6 => Config { boundary: Some(BoundaryCue { weight: 0.3 }), ..d },
        7 => Config { scene_motion: !d.scene_motion, ..d },
        8 => Config { sure_share: 0.3, ..d },
        // Lost after one miss, so that the few steps reach the lost
        // search: the re-detection's spots within a widening square.
        9 => {
            Config { redetect: Redetect::Frame, lost_search: LostSearch::Widening { growth: 10.0 }, lost_after: 1, ..d }
        }
        // The gradient filter in place of the grey-level one, and beside
        // it with its response blended into the particles' similarities.
        10 => Config { gradient: Some(GradientCue::MEASURED), correlation: None, ..d },
        11 => Config { gradient: Some(GradientCue { blend: 0.3, ..GradientCue::MEASURED }), ..d },
        // Both filters and a share of the hypotheses (the learning window
        // taken from the search's cells).
        12 => Config::accurate(),
        // The gradient filter's scale pyramid learning from every fourth
        // frame and moving the whole way.
        13 => Config {
            gradient: Some(GradientCue { pyramid_pull: 1.0, pyramid_learn_above: 0.0, ..GradientCue::MEASURED }),
            ..Config::accurate()
        },
        _ => Config { table: Some(TableMode { spacing: 1 }), ..d },
    }
}

fuzz_target!(|input: (u8, u8, u8, u8, [f32; 4], u64, &[u8])| {
    let (w, h, code, pick, b, seed, pixels) = input;
    let (w, h) = (usize::from(w % 48) + 1, usize::from(h % 48) + 1);
    let Some(format) = PixelFormat::from_code(u16::from(code % 6) + 1) else { return };
    let Some(frame_len) = format.frame_bytes(w * format.bytes_per_pixel(), h) else { return };
    let odd = (format == PixelFormat::Yuv422 || format.is_planar()) && w % 2 == 1;
    if pixels.len() < frame_len || odd || (format.is_planar() && h % 2 == 1) {
        return;
    }
    let Ok(first) = Frame::packed(&pixels[..frame_len], w, h, format) else { return };
    if pick >= 128 {
        let cfg = if pick & 1 == 0 { MeanShiftConfig::default() } else { MeanShiftConfig::kalman() };
        let mut m: Box<MeanShift> = Box::new(MeanShift::new(cfg).expect("valid"));
        if m.init(&first, BoundingBox::new(b[0], b[1], b[2], b[3])).is_err() {
            return;
        }
        for k in 1..=4 {
            let start = (k * 7919) % (pixels.len() - frame_len + 1);
            let Ok(f) = Frame::packed(&pixels[start..start + frame_len], w, h, format) else { return };
            let e = m.step(&f).expect("same frame size");
            let el = e.ellipse;
            assert!(el.cx.is_finite() && el.cy.is_finite() && el.hx.is_finite() && el.hy.is_finite(), "{el:?}");
            assert!((0.0..=w as f32).contains(&el.cx) && (0.0..=h as f32).contains(&el.cy), "{el:?} in {w}x{h}");
            assert!((0.0..=1.0).contains(&e.confidence));
        }
        return;
    }
    let mut t: Box<Tracker<16, 512, 4096, Xoshiro128PlusPlus, 1024>> =
        Box::new(Tracker::new(config(pick), seed).expect("every picked configuration is valid"));
    if t.init(&first, BoundingBox::new(b[0], b[1], b[2], b[3])).is_err() {
        return;
    }
    // Later frames: further slices of the input, wrapping around.
    for k in 1..=4 {
        let start = (k * 7919) % (pixels.len() - frame_len + 1);
        let Ok(f) = Frame::packed(&pixels[start..start + frame_len], w, h, format) else { return };
        let e = if pick & 64 != 0 {
            let prior = ScalePrior { half_minor: (b[2].abs() % 40.0).max(1.0), tolerance: 1.0 };
            match t.step_with_prior(&f, prior) {
                Ok(e) => e,
                Err(_) => return, // a NaN box makes a NaN prior: rejected, as it should be
            }
        } else {
            t.step(&f).expect("same frame size")
        };
        let el = e.ellipse;
        assert!(el.cx.is_finite() && el.cy.is_finite() && el.hx.is_finite() && el.hy.is_finite(), "{el:?}");
        assert!((0.0..=w as f32).contains(&el.cx) && (0.0..=h as f32).contains(&el.cy), "{el:?} in {w}x{h}");
        assert!((0.0..=1.0).contains(&e.confidence));
        let sum: f32 = t.weights().iter().sum();
        assert!((sum - 1.0).abs() < 1e-3, "weights sum to {sum}");
    }
});
