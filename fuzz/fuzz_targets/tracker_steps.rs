//! A tracker fed arbitrary frames, an arbitrary box and a few steps. On every
//! input: no panic; every estimate finite and inside the frame; confidence in
//! [0, 1]; weights normalised.
#![no_main]
use libfuzzer_sys::fuzz_target;
use pftrack::{BoundingBox, Config, Frame, PixelFormat, Tracker};

fuzz_target!(|input: (u8, u8, u8, [f32; 4], u64, &[u8])| {
    let (w, h, code, b, seed, pixels) = input;
    let (w, h) = (usize::from(w % 48) + 1, usize::from(h % 48) + 1);
    let Some(format) = PixelFormat::from_code(u16::from(code % 4) + 1) else { return };
    let bpp = format.bytes_per_pixel();
    let frame_len = w * h * bpp;
    if pixels.len() < frame_len || (format == PixelFormat::Yuv422 && w % 2 == 1) {
        return;
    }
    let mut t: Box<Tracker<16>> = Box::new(Tracker::new(Config::default(), seed).expect("defaults are valid"));
    let Ok(first) = Frame::packed(&pixels[..frame_len], w, h, format) else { return };
    if t.init(&first, BoundingBox::new(b[0], b[1], b[2], b[3])).is_err() {
        return;
    }
    // Later frames: further slices of the input, wrapping around.
    for k in 1..=4 {
        let start = (k * 7919) % (pixels.len() - frame_len + 1);
        let Ok(f) = Frame::packed(&pixels[start..start + frame_len], w, h, format) else { return };
        let e = t.step(&f).expect("same frame size");
        let el = e.ellipse;
        assert!(el.cx.is_finite() && el.cy.is_finite() && el.hx.is_finite() && el.hy.is_finite(), "{el:?}");
        assert!((0.0..=w as f32).contains(&el.cx) && (0.0..=h as f32).contains(&el.cy), "{el:?} in {w}x{h}");
        assert!((0.0..=1.0).contains(&e.confidence));
        let sum: f32 = t.weights().iter().sum();
        assert!((sum - 1.0).abs() < 1e-3, "weights sum to {sum}");
    }
});
