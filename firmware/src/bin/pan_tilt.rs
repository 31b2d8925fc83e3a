//! Example: a pan-tilt camera head that follows the tracked target.
//!
//! The tracker runs on a recorded fixture, read from the host over
//! semihosting as in the main firmware; each estimate goes to
//! `pftrack::follower::PanTilt`, which drives two servo PWM channels and a
//! lock LED through embedded-hal 1.0 traits. QEMU's board has no servos, so
//! the channels and the LED here are small recorders that print what a
//! timer and a GPIO pin would be told; on a board, pass your HAL's PWM
//! channels (`SetDutyCycle`) and LED pin (`OutputPin`) instead and nothing
//! else changes.
//!
//! `cargo qemu-pantilt [FIXTURE [SEED]]` (default fixtures/smooth_scale.pft).
//! Exits 0 when the pan servo turned towards the target on at least 90% of
//! the frames where the target was off-centre (the camera does not move in
//! the recording, so this checks the controller's direction, not a closed
//! loop), 1 otherwise.
#![no_std]
#![no_main]

#[path = "../host.rs"]
mod host;

use core::convert::Infallible;
use core::fmt::Write;
use cortex_m_rt::entry;
use cortex_m_semihosting::debug::{self, EXIT_FAILURE, EXIT_SUCCESS};
use cortex_m_semihosting::hio;
use embedded_hal::digital::{ErrorType as PinErrorType, OutputPin};
use embedded_hal::pwm::{ErrorType as PwmErrorType, SetDutyCycle};
use pftrack::follower::{FollowerConfig, PanTilt};
use pftrack::{Config, Frame, TrackState, Tracker};

/// Largest frame held: QQVGA RGB565 would do for the committed fixtures.
const FRAME_BYTES: usize = 320 * 240 * 2;

/// A PWM channel that remembers its duty: what a 50 Hz servo timer counting
/// at 1 MHz would be given (20,000 ticks per period).
struct Servo {
    duty: u16,
}

impl PwmErrorType for Servo {
    type Error = Infallible;
}

impl SetDutyCycle for Servo {
    fn max_duty_cycle(&self) -> u16 {
        20_000
    }

    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), Infallible> {
        self.duty = duty;
        Ok(())
    }
}

/// A GPIO pin that remembers its level.
struct Led {
    on: bool,
}

impl PinErrorType for Led {
    type Error = Infallible;
}

impl OutputPin for Led {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.on = false;
        Ok(())
    }

    fn set_high(&mut self) -> Result<(), Infallible> {
        self.on = true;
        Ok(())
    }
}

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
    let Some(tracker) = make_tracker(seed) else { fail!("tracker") };
    let mut head =
        match PanTilt::new(Servo { duty: 0 }, Servo { duty: 0 }, Led { on: false }, FollowerConfig::default()) {
            Ok(head) => head,
            Err(_) => fail!("follower configuration"),
        };

    let _ = writeln!(out, "fixture {path} {}x{} frames {} seed {seed}", h.width, h.height, h.frames);
    let _ = writeln!(out, "frame state     target-x  pan   tilt  pan-duty tilt-duty led");
    // Each tracked frame with the target off-centre should turn the head
    // towards it: count how often the pan moved the target's way.
    let dead_zone = FollowerConfig::default().dead_zone;
    let (mut agree, mut moves) = (0u32, 0u32);
    for i in 0..h.frames {
        let buf = &mut pixels[..h.frame_len()];
        let meta = match stream.next(i, buf) {
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
                p.duty,
                t.duty,
                if l.on { "on" } else { "off" }
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

#[inline(never)]
fn make_tracker(seed: u64) -> Option<&'static mut Tracker<100>> {
    let t = Tracker::<100>::new(Config::default(), seed).ok()?;
    cortex_m::singleton!(: Tracker<100> = t)
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
