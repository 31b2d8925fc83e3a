//! Example: a pan-tilt camera head that follows the tracked target.
//!
//! The tracker runs on a recorded fixture, read from the host over
//! semihosting as in the main firmware; each estimate goes to
//! `pftrack::follower::PanTilt`, which drives two servo PWM channels and a
//! lock LED through embedded-hal 1.0 traits. QEMU's mps2-an386 board has no
//! timers, so there the channels and the LED are small recorders that print
//! what a timer and a GPIO pin would be told. The STM32F405 build drives a
//! real timer through the chip's HAL (`board.rs`): TIM2's channels 1 and 2
//! as 50 Hz PWM, and the duties printed are read back from its compare
//! registers; the LED is a GPIO pin. On your board, pass your HAL's PWM
//! channels (`SetDutyCycle`) and LED pin (`OutputPin`) the same way.
//!
//! `cargo qemu-pantilt [FIXTURE [SEED]]` (default fixtures/smooth_scale.pft),
//! `cargo qemu-f405-pantilt [FIXTURE [SEED]]` on the STM32F405.
//! Exits 0 when the pan servo turned towards the target on at least 90% of
//! the frames where the target was off-centre (the camera does not move in
//! the recording, so this checks the controller's direction, not a closed
//! loop), 1 otherwise.
#![no_std]
#![no_main]

#[cfg(feature = "rp2040")]
compile_error!("the pan-tilt example has no RP2040 servos: build the RP2040 firmware with --bin pftrack-firmware");

// Shared with the main firmware, which uses the rest of it.
#[allow(dead_code)]
#[path = "../board.rs"]
mod board;
#[path = "../host.rs"]
mod host;
#[path = "../tracker_slot.rs"]
mod tracker_slot;

use board::{DutyReadback, FRAME_BYTES, LevelReadback};
use core::fmt::Write;
use cortex_m_rt::entry;
use cortex_m_semihosting::debug::{self, EXIT_FAILURE, EXIT_SUCCESS};
use cortex_m_semihosting::hio;
use pftrack::follower::{FollowerConfig, PanTilt};
use pftrack::{Config, Frame, TrackState};
use tracker_slot::{FwTracker, keep};

#[entry]
fn main() -> ! {
    let ok = run();
    debug::exit(if ok { EXIT_SUCCESS } else { EXIT_FAILURE });
    loop {
        cortex_m::asm::wfi();
    }
}

fn run() -> bool {
    let Ok(mut out) = hio::hstdout() else { return false };
    macro_rules! fail {
        ($($t:tt)*) => {{
            let _ = writeln!(out, "error: {}", format_args!($($t)*));
            return false;
        }};
    }
    let mut args_buf = [0u8; 256];
    let (path, seed) = match host::args(&mut args_buf, "fixtures/smooth_scale.pft") {
        Ok(host::Args { extra: Some(w), .. }) => fail!("unexpected `{w}`: the arguments are FIXTURE [SEED]"),
        Ok(a) => (a.path, a.seed),
        Err(e) => fail!("{e}"),
    };
    let mut stream = match host::FixtureStream::open(path) {
        Ok(s) => s,
        Err(e) => fail!("{path}: {e}"),
    };
    let h = stream.header;
    if h.frame_len() > FRAME_BYTES {
        fail!("frames of {} bytes do not fit {FRAME_BYTES}", h.frame_len());
    }
    let Some(pixels) = cortex_m::singleton!(: [u8; FRAME_BYTES] = [0; FRAME_BYTES]) else { fail!("buffer taken") };
    let tracker = match make_tracker(seed) {
        Ok(Some(t)) => t,
        Ok(None) => fail!("tracker taken"),
        Err(e) => fail!("{e}"),
    };
    let Some((pan, tilt, led)) = board::head() else { fail!("peripherals taken") };
    let mut head = match PanTilt::new(pan, tilt, led, FollowerConfig::default()) {
        Ok(head) => head,
        Err(_) => fail!("follower configuration"),
    };

    let _ = writeln!(out, "board {}", board::NAME);
    let _ = writeln!(out, "fixture {path} {}x{} frames {} seed {seed}", h.width, h.height, h.frames);
    let _ = writeln!(out, "frame state     target-x  pan   tilt  pan-duty tilt-duty led");
    // Each tracked frame with the target off-centre should turn the head
    // towards it: count how often the pan moved the target's way.
    let dead_zone = FollowerConfig::default().dead_zone;
    let (mut agree, mut moves) = (0u32, 0u32);
    for i in 0..h.frames {
        let buf = &mut pixels[..h.frame_len()];
        let meta = match stream.next(i, buf, &mut []) {
            Ok(m) => m,
            Err(e) => fail!("{path}: {e}"),
        };
        let frame = match Frame::new(buf, h.width, h.height, h.stride, h.format) {
            Ok(f) => f,
            Err(e) => fail!("frame {i}: {e}"),
        };
        let est = match if i == 0 { tracker.init(&frame, meta.truth) } else { tracker.step(&frame) } {
            Ok(e) => e,
            Err(e) => fail!("frame {i}: {e}"),
        };
        let before = head.position().0;
        if head.update(&est, h.width, h.height).is_err() {
            fail!("frame {i}: servo write failed");
        }
        let offset = (est.ellipse.cx - 0.5 * h.width as f32) / (0.5 * h.width as f32);
        let turn = head.position().0 - before;
        if est.state == TrackState::Tracking && offset.abs() > dead_zone && turn != 0.0 {
            moves += 1;
            agree += ((turn > 0.0) == (offset > 0.0)) as u32;
        }
        let (pan, tilt) = head.position();
        let (p, t, l) = head.peripherals();
        if i % 5 == 0 || i + 1 == h.frames {
            let _ = writeln!(
                out,
                "{i:>5} {:<9} {:>8.1} {pan:>5.2} {tilt:>5.2} {:>8} {:>9} {}",
                match est.state {
                    TrackState::Tracking => "tracking",
                    TrackState::Searching => "searching",
                    TrackState::Lost => "lost",
                },
                est.ellipse.cx,
                p.duty(),
                t.duty(),
                if l.is_on() { "on" } else { "off" }
            );
        }
    }
    // The derivative term may briefly oppose the offset when the target
    // swings back; the proportional term must win on at least 90% of moves.
    let followed = moves > 0 && agree * 10 >= moves * 9;
    let _ = writeln!(
        out,
        "pan turned towards the target on {agree} of {moves} off-centre frames: {}",
        if followed { "followed" } else { "did NOT follow" }
    );
    followed
}

/// Builds the tracker into its static; out of line, so that the stack the
/// construction takes is gone before the loop.
#[inline(never)]
fn make_tracker(seed: u64) -> Result<Option<&'static mut FwTracker>, pftrack::Error> {
    keep(|| FwTracker::new(Config::default(), seed))
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    if let Ok(mut err) = hio::hstderr() {
        let _ = writeln!(err, "panic: {info}");
    }
    debug::exit(EXIT_FAILURE);
    loop {
        cortex_m::asm::wfi();
    }
}
