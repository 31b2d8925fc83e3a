//! Link-time proof that the tracker's `init` and `step` contain no reachable
//! panic: the panic handler calls a function that exists nowhere, so if any
//! panic path survives optimisation the link fails, naming its caller.
//! Build only (CI does, for thumbv7em and thumbv6m):
//! `cargo build --release --manifest-path firmware/Cargo.toml --target thumbv7em-none-eabihf --bin panic_check`.
//! A deliberate `slice[i]` with an unknown `i` added here makes it fail, as it should.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use pftrack::{BoundingBox, Config, Frame, PixelFormat, Tracker};

#[entry]
fn main() -> ! {
    // cortex-m-rt hands `static mut`s in the entry function over as
    // `&'static mut`. Inputs are read through volatile loads, so the
    // optimiser cannot assume anything about them.
    static mut PIXELS: [u8; 160 * 120 * 2] = [0; 160 * 120 * 2];
    static mut OUT: f32 = 0.0;
    let base = PIXELS.as_ptr();
    // SAFETY: reads within PIXELS.
    let (seed, w, x) = unsafe {
        (
            core::ptr::read_volatile(base as *const u32) as u64,
            core::ptr::read_volatile(base.add(4)) as usize,
            f32::from_bits(core::ptr::read_volatile(base.add(8) as *const u32)),
        )
    };
    let mut t = match Tracker::<100>::new(Config::default(), seed) {
        Ok(t) => t,
        Err(_) => loop {
            cortex_m::asm::wfi();
        },
    };
    let pixels: &[u8] = &PIXELS[..];
    if let Ok(frame) = Frame::new(pixels, 160 - (w & 1) * 2, 120, 320, PixelFormat::Rgb565)
        && t.init(&frame, BoundingBox::new(x, x, 20.0, 20.0)).is_ok()
    {
        loop {
            if let Ok(e) = t.step(&frame) {
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
