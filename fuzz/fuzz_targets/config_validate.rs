//! Arbitrary values in every numeric configuration field: validation either
//! refuses them, or a tracker can be built and run with them.
#![no_main]
use libfuzzer_sys::fuzz_target;
use pftrack::{BoundingBox, Config, Frame, GradientCue, LostSearch, PixelFormat, Sigma, SizeSearch, Tracker};

fuzz_target!(|v: [f32; 22]| {
    let mut c = Config::default();
    c.likelihood.sigma = if v[0] >= 0.0 { Sigma::Fixed(v[1]) } else { Sigma::Adaptive { min: v[1], max: v[2] } };
    c.likelihood.eps = v[3];
    c.dynamics.position_noise = v[4];
    c.dynamics.velocity_noise = v[5];
    c.dynamics.velocity_decay = v[6];
    c.dynamics.scale_noise = v[7];
    c.alpha = v[8];
    c.update_threshold = v[9];
    c.update_sigma = v[10];
    c.kickoff = v[11];
    c.reseed_fraction = v[12];
    c.min_half_axis = v[13];
    c.dynamics.speed_noise = v[14];
    c.sure_share = v[15];
    // Lost after one miss, so that the steps below reach the lost search.
    c.lost_search = LostSearch::Widening { growth: v[16] };
    c.size = c.size.map(|s| SizeSearch { template: v[17], ..s });
    c.gradient = c.gradient.map(|g| GradientCue { pyramid_pull: v[18], pyramid_learn_above: v[19], grey_pull: v[20], narrow_above: v[21], ..g });
    c.lost_after = 1;
    if c.validate().is_err() {
        assert!(Tracker::<8>::new(c, 1).is_err(), "the constructor validates too");
        return;
    }
    let px = [90u8; 32 * 24];
    let f = Frame::packed(&px, 32, 24, PixelFormat::Gray8).expect("a valid frame");
    let mut t = Tracker::<8>::new(c, 1).expect("validated");
    if t.init(&f, BoundingBox::new(8.0, 6.0, 10.0, 8.0)).is_ok() {
        for _ in 0..3 {
            let e = t.step(&f).expect("same frame size");
            assert!(e.ellipse.cx.is_finite() && (0.0..=1.0).contains(&e.confidence));
        }
    }
});
