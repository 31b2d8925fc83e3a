//! Link-time proof that the tracker's `init` and `step` contain no reachable
//! panic: the panic handler calls a function that exists nowhere, so if any
//! panic path survives optimisation the link fails, naming its caller.
//! Build only (CI does, for thumbv7em and thumbv6m):
//! `cargo build --release --manifest-path firmware/Cargo.toml --target thumbv7em-none-eabihf --bin panic_check`.
//! A deliberate `slice[i]` with an unknown `i` added here makes it fail, as it should.
//! The configuration is picked by an input the optimiser cannot see, among
//! the defaults and every optional technique (quadrants, adaptive bins,
//! intersection, exponential likelihood, the degraded-model rule, boundary
//! cue, likelihood table, scale prior, surroundings-motion test, correlation
//! filter), and the mean-shift baselines and a group of targets (added,
//! stepped, re-initialised and removed) run too;
//! CI links it with and without `--features all-options`, with `gradient`
//! (the core's default features, where the default is `Config::accurate`),
//! and without the default `correlation` feature, so the proof covers every
//! build's code.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
// The board builds' device crates provide the interrupt vectors their
// cortex-m-rt expects.
use pftrack::{
    Binning, BoundaryCue, BoundingBox, Config, Frame, Group, MeanShift, MeanShiftConfig, ModelUpdate, PixelFormat,
    ScalePrior, Shape, Similarity, TableMode, Tracker,
};
use rand_xoshiro::Xoshiro128PlusPlus;
#[cfg(feature = "rp2040")]
use rp2040_hal as _;
#[cfg(feature = "stm32f405")]
use stm32f4xx_hal as _;

/// One of the configurations, by `pick`.
fn config(pick: u8) -> Config {
    let d = Config::default();
    match pick % 10 {
        0 => d,
        1 => Config { quadrants: true, binning: Binning::Rgb4x4x4, ..d },
        2 => Config { quadrants: true, binning: Binning::Adaptive, ..d },
        3 => Config { similarity: Similarity::Intersection, ..d },
        4 => Config { likelihood: pftrack::Likelihood { shape: Shape::Exponential, ..d.likelihood }, ..d },
        5 => Config { model_update: ModelUpdate::WhenDegraded { factor: 0.9, frames: 5 }, ..d },
        6 => Config { boundary: Some(BoundaryCue { weight: 0.3 }), ..d },
        7 => Config { scene_motion: !d.scene_motion, ..d },
        8 => Config { correlation: Some(pftrack::CorrelationCue::MEASURED), ..d },
        _ => Config { table: Some(TableMode { spacing: 2 }), ..d },
    }
}

#[entry]
fn main() -> ! {
    // cortex-m-rt hands `static mut`s in the entry function over as
    // `&'static mut`. Inputs are read through volatile loads, so the
    // optimiser cannot assume anything about them.
    static mut PIXELS: [u8; 160 * 120 * 2] = [0; 160 * 120 * 2];
    static mut OUT: f32 = 0.0;
    let base = PIXELS.as_ptr();
    // SAFETY: reads within PIXELS.
    let (seed, w, x, pick) = unsafe {
        (
            core::ptr::read_volatile(base as *const u32) as u64,
            core::ptr::read_volatile(base.add(4)) as usize,
            f32::from_bits(core::ptr::read_volatile(base.add(8) as *const u32)),
            core::ptr::read_volatile(base.add(12)),
        )
    };
    let pixels: &[u8] = &PIXELS[..];
    if pick >= 128 {
        // The baselines.
        let cfg = if pick & 1 == 0 { MeanShiftConfig::default() } else { MeanShiftConfig::kalman() };
        if let (Ok(mut m), Ok(frame)) =
            (MeanShift::<512>::new(cfg), Frame::new(pixels, 160 - (w & 1) * 2, 120, 320, PixelFormat::Rgb565))
            && m.init(&frame, BoundingBox::new(x, x, 20.0, 20.0)).is_ok()
        {
            loop {
                if let Ok(e) = m.step(&frame) {
                    // SAFETY: OUT is this function's own static.
                    unsafe { core::ptr::write_volatile(&raw mut *OUT, e.confidence) };
                }
            }
        }
    }
    if pick & 32 != 0 {
        // A group of three, its targets added, stepped, re-initialised and
        // removed as inputs say.
        if let (Ok(mut g), Ok(frame)) = (
            Group::<3, 100, 512, 4096, Xoshiro128PlusPlus, 256>::new(config(pick), seed),
            Frame::new(pixels, 160 - (w & 1) * 2, 120, 320, PixelFormat::Rgb565),
        ) {
            let ids = [
                g.add(&frame, BoundingBox::new(x, x, 20.0, 20.0)),
                g.add(&frame, BoundingBox::new(x, 2.0 * x, 9.0, 9.0)),
            ];
            loop {
                if let Ok(all) = g.step(&frame) {
                    for t in &all {
                        // SAFETY: OUT is this function's own static.
                        unsafe { core::ptr::write_volatile(&raw mut *OUT, t.estimate.confidence) };
                    }
                }
                if let Ok(a) = &ids[w % 2] {
                    let _ = if w & 4 != 0 {
                        g.remove(a.id)
                    } else {
                        g.reinit(a.id, &frame, BoundingBox::new(x, x, 5.0, 5.0)).map(|_| ())
                    };
                }
            }
        }
    }
    let mut t = match Tracker::<100, 512, 4096, Xoshiro128PlusPlus, 256>::new(config(pick), seed) {
        Ok(t) => t,
        Err(_) => loop {
            cortex_m::asm::wfi();
        },
    };
    if let Ok(frame) = Frame::new(pixels, 160 - (w & 1) * 2, 120, 320, PixelFormat::Rgb565)
        && t.init(&frame, BoundingBox::new(x, x, 20.0, 20.0)).is_ok()
    {
        loop {
            let r = if pick & 64 != 0 {
                t.step_with_prior(&frame, ScalePrior { half_minor: x, tolerance: 1.0 })
            } else {
                t.step(&frame)
            };
            if let Ok(e) = r {
                // SAFETY: OUT is this function's own static.
                unsafe { core::ptr::write_volatile(&raw mut *OUT, e.confidence) };
            }
        }
    }
    loop {
        cortex_m::asm::wfi();
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    unsafe extern "C" {
        /// Deliberately undefined: referencing it fails the link.
        fn pftrack_a_panic_path_is_reachable() -> !;
    }
    unsafe { pftrack_a_panic_path_is_reachable() }
}
