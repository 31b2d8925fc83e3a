//! pftrack on a Cortex-M4F: reads a recorded fixture (`.pft`) from the host
//! over semihosting, frame by frame, tracks it with the same core and seed
//! as the host harness, and prints one bit-exact trace line per frame plus
//! instruction counts, peak stack and a verdict. Exits 0 on success.
//!
//! Run it with `cargo qemu fixtures/occlusion.pft 1` (QEMU's MPS2 AN386
//! board; see the README), or built for the STM32F405 with
//! `cargo qemu-f405 fixtures/occlusion.pft 1` (QEMU's netduinoplus2). A third
//! word picks the tracker: `pf` (the particle filter, default), `meanshift`
//! or `kalman` (the baselines).
#![no_std]
#![no_main]

// Shared with the pan-tilt example, which uses the rest of it.
#[allow(dead_code)]
mod board;
mod group;
mod host;
mod tracker_slot;

use core::fmt::Write;
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m_rt::entry;
use cortex_m_semihosting::debug::{self, EXIT_FAILURE, EXIT_SUCCESS};
use cortex_m_semihosting::hio;
#[cfg(feature = "defmt")]
use defmt_semihosting as _;
use pftrack::{BoundingBox, Config, Estimate, Frame, MeanShift, MeanShiftConfig};

use board::FRAME_BYTES;
use tracker_slot::{FwTracker, keep};
/// Most frames whose instruction counts are kept for the median.
const MAX_FRAMES: usize = 512;
/// The value the unused stack is painted with.
const PAINT: u32 = 0x5afe_c0de;

/// The tracker this run uses, in its static.
enum Any {
    Pf(&'static mut FwTracker),
    MeanShift(&'static mut MeanShift),
}

// Each tracker's calls stay out of line: inlined into one dispatching
// function, their stack frames would merge and every run would pay for the
// larger (measured: +2 KB of peak stack for the particle filter).
impl Any {
    #[inline(never)]
    fn init(&mut self, frame: &Frame<'_>, bbox: BoundingBox) -> Result<Estimate, pftrack::Error> {
        match self {
            Any::Pf(t) => pf_init(t, frame, bbox),
            Any::MeanShift(t) => ms_init(t, frame, bbox),
        }
    }

    fn step(&mut self, frame: &Frame<'_>) -> Result<Estimate, pftrack::Error> {
        match self {
            Any::Pf(t) => pf_step(t, frame),
            Any::MeanShift(t) => ms_step(t, frame),
        }
    }

    fn ram(&self) -> usize {
        match self {
            Any::Pf(_) => core::mem::size_of::<FwTracker>(),
            Any::MeanShift(_) => core::mem::size_of::<MeanShift>(),
        }
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
    board::init();
    // With defmt, stdout carries the binary defmt stream; text goes to stderr.
    let out = if cfg!(feature = "defmt") { hio::hstderr() } else { hio::hstdout() };
    let Ok(mut out) = out else { return false };
    macro_rules! fail {
        ($($t:tt)*) => {{
            let _ = writeln!(out, "error: {}", format_args!($($t)*));
            return false;
        }};
    }

    let mut args_buf = [0u8; 256];
    let (path, seed, kind) = match host::args(&mut args_buf, "fixtures/occlusion.pft") {
        Ok(a) => (a.path, a.seed, a.extra.unwrap_or("pf")),
        Err(e) => fail!("{e}"),
    };
    let mut stream = match host::FixtureStream::open(path) {
        Ok(s) => s,
        Err(e) => fail!("{path}: {e}"),
    };
    let h = stream.header;
    let (format, width, height, stride, count) = (h.format, h.width, h.height, h.stride, h.frames);
    let frame_len = h.frame_len();
    if frame_len > FRAME_BYTES {
        fail!(
            "{width}x{height} {format:?} frames need {frame_len} bytes; this build ({}) holds {FRAME_BYTES}",
            board::NAME
        );
    }

    let Some(ticks) = cortex_m::singleton!(: [u32; MAX_FRAMES] = [0; MAX_FRAMES]) else { fail!("buffer taken") };
    if h.targets > 1 {
        return group::run(&mut out, &mut stream, ticks, (path, seed, kind));
    }
    let made = match kind {
        "pf" => make_tracker(seed).map(|t| t.map(Any::Pf)),
        #[cfg(feature = "all-options")]
        "pf-still" => make_still_tracker(seed).map(|t| t.map(Any::Pf)),
        #[cfg(feature = "all-options")]
        "pf-sure" => make_sure_tracker(seed).map(|t| t.map(Any::Pf)),
        #[cfg(feature = "gradient")]
        "pf-gradient" => make_gradient_tracker(seed).map(|t| t.map(Any::Pf)),
        #[cfg(feature = "gradient")]
        "pf-accurate" => make_accurate_tracker(seed).map(|t| t.map(Any::Pf)),
        "meanshift" => make_meanshift(MeanShiftConfig::default()).map(|t| t.map(Any::MeanShift)),
        "kalman" => make_meanshift(MeanShiftConfig::kalman()).map(|t| t.map(Any::MeanShift)),
        _ => fail!("tracker `{kind}` is not pf, meanshift or kalman"),
    };
    let mut tracker = match made {
        Ok(Some(t)) => t,
        Ok(None) => fail!("tracker taken"),
        Err(e) => fail!("{e}"),
    };
    // Only now: the tracker's construction may have run into it.
    let Some(pixels) = frame_buffer() else { fail!("buffer taken") };

    let Some(mut cp) = cortex_m::Peripherals::take() else { fail!("peripherals taken") };
    start_systick(&mut cp);

    let _ = writeln!(out, "board {}", board::NAME);
    let _ = writeln!(out, "fixture {path} {width}x{height} {format:?} frames {count} seed {seed} tracker {kind}");
    let mut stack_floor = paint_stack();
    let mut init_stack = None;
    let mut measured = 0usize;
    for i in 0..count as usize {
        let buf = &mut pixels[..frame_len];
        let meta = match stream.next(i as u32, buf, &mut []) {
            Ok(m) => m,
            Err(e) => fail!("{path}: {e}"),
        };
        let frame = match Frame::new(buf, width, height, stride, format) {
            Ok(f) => f,
            Err(e) => fail!("frame {i}: {e}"),
        };
        let t0 = cortex_m::peripheral::SYST::get_current();
        let result = if i == 0 { tracker.init(&frame, meta.truth) } else { tracker.step(&frame) };
        let t1 = cortex_m::peripheral::SYST::get_current();
        // SysTick counts down and wraps at 2^24; one step is far shorter.
        let elapsed = t0.wrapping_sub(t1) & 0x00ff_ffff;
        match result {
            Ok(est) => {
                #[cfg(feature = "defmt")]
                defmt::info!("frame {=usize}: {}", i, est);
                #[cfg(not(feature = "defmt"))]
                let _ = writeln!(out, "{i} {}", est.trace());
            }
            Err(e) => fail!("frame {i}: {e}"),
        }
        if i == 0 {
            // Initialisation and tracking are measured apart: an
            // application can initialise where more stack is free.
            init_stack = stack_floor.map(peak_stack);
            stack_floor = paint_stack();
        }
        if i > 0
            && let Some(slot) = ticks.get_mut(measured)
        {
            *slot = elapsed;
            measured += 1;
        }
    }
    let peak = stack_floor.map(peak_stack);
    report(&mut out, &mut ticks[..measured], (init_stack, peak), tracker.ram());
    true
}

/// Prints the instruction counts of `steps` (SysTick ticks; sorted here),
/// the peak stack of initialisation and tracking, and the RAM of the
/// tracker, then the verdict.
fn report(out: &mut impl Write, steps: &mut [u32], (init_stack, peak): (Option<usize>, Option<usize>), ram: usize) {
    if let Some(per_tick) = board::INSTRUCTIONS_PER_TICK {
        // Every step in order, so that an outlier frame can be found.
        let _ = write!(out, "instructions per step, in order:");
        for t in steps.iter() {
            let _ = write!(out, " {}", t * per_tick);
        }
        let _ = writeln!(out);
        steps.sort_unstable();
        if let (Some(min), Some(max)) = (steps.first(), steps.last()) {
            let med = steps[steps.len() / 2];
            let _ = writeln!(
                out,
                "instructions per step: min {} median {} max {} ({} steps, {} instructions per SysTick tick)",
                min * per_tick,
                med * per_tick,
                max * per_tick,
                steps.len(),
                per_tick
            );
        }
    }
    if let (Some(i), Some(p)) = (init_stack, peak) {
        let _ = writeln!(out, "peak stack: init {i} bytes, step {p} bytes");
    }
    let _ = writeln!(out, "tracker RAM: {ram} bytes");
    let _ = writeln!(out, "ok");
}

/// Starts SysTick counting core cycles down from its largest reload, to
/// count each step's instructions.
fn start_systick(cp: &mut cortex_m::Peripherals) {
    cp.SYST.set_clock_source(SystClkSource::Core);
    cp.SYST.set_reload(0x00ff_ffff);
    cp.SYST.clear_current();
    cp.SYST.enable_counter();
}

/// The buffer frames are read into, the largest static, in `.uninit`: after
/// every other static, just below the stack. A tracker is built (`make_*`)
/// through a temporary the size of the tracker on the stack, before the
/// buffer is first taken; where the statics nearly fill the RAM (the
/// STM32F405's 128 KiB with the gradient filter built in) that temporary
/// runs into this buffer, which holds nothing yet, and not into a static
/// in use.
#[unsafe(link_section = ".uninit.pftrack_frame")]
static mut FRAME: core::mem::MaybeUninit<[u8; FRAME_BYTES]> = core::mem::MaybeUninit::uninit();

/// The frame buffer, zeroed, the first time; `None` after.
pub(crate) fn frame_buffer() -> Option<&'static mut [u8; FRAME_BYTES]> {
    static mut TAKEN: bool = false;
    cortex_m::interrupt::free(|_| {
        // SAFETY: `TAKEN` and `FRAME` are touched only here, with interrupts
        // off, and `FRAME` is handed out once, zeroed first.
        unsafe {
            if TAKEN {
                return None;
            }
            TAKEN = true;
            let p = core::ptr::addr_of_mut!(FRAME).cast::<u8>();
            core::ptr::write_bytes(p, 0, FRAME_BYTES);
            Some(&mut *p.cast::<[u8; FRAME_BYTES]>())
        }
    })
}

/// Builds the tracker into a static. Kept out of line: constructing it needs
/// a temporary the size of the tracker, and that stack frame must be gone
/// before the tracking loop whose stack is measured.
#[inline(never)]
fn make_tracker(seed: u64) -> Result<Option<&'static mut FwTracker>, pftrack::Error> {
    // The configuration for boards that need the frame rate: with the
    // correlation filter where the build has it (the default), the colour
    // cues alone where it does not.
    keep(|| FwTracker::new(Config::fast(), seed))
}

/// [`make_tracker`] with the surroundings-motion test off, in the build with
/// the core's optional techniques, so that `audit/run` can report what the
/// test costs: a function of its own, so that each configuration is known
/// at compile time and the default build's validation folds away as before.
#[cfg(feature = "all-options")]
#[inline(never)]
fn make_still_tracker(seed: u64) -> Result<Option<&'static mut FwTracker>, pftrack::Error> {
    keep(|| FwTracker::new(Config { scene_motion: false, ..Config::fast() }, seed))
}

/// [`make_tracker`] observing [`SURE_SHARE`] of the hypotheses after a
/// confident frame (`Config::sure_share`), in the build with the core's
/// optional techniques, so that `audit/run` can report what the share saves.
#[cfg(feature = "all-options")]
#[inline(never)]
fn make_sure_tracker(seed: u64) -> Result<Option<&'static mut FwTracker>, pftrack::Error> {
    keep(|| FwTracker::new(Config { sure_share: SURE_SHARE, ..Config::fast() }, seed))
}

/// [`make_tracker`] with the gradient filter in place of the grey-level
/// one, in the build with the `gradient` feature, so that `audit/run` can
/// report what it costs.
#[cfg(feature = "gradient")]
#[inline(never)]
fn make_gradient_tracker(seed: u64) -> Result<Option<&'static mut FwTracker>, pftrack::Error> {
    let config = Config { gradient: Some(pftrack::GradientCue::MEASURED), correlation: None, ..Config::fast() };
    keep(|| FwTracker::new(config, seed))
}

/// [`make_tracker`] with `Config::accurate` (the gradient filter beside
/// the grey-level one), in the build with the `gradient` feature.
#[cfg(feature = "gradient")]
#[inline(never)]
fn make_accurate_tracker(seed: u64) -> Result<Option<&'static mut FwTracker>, pftrack::Error> {
    keep(|| FwTracker::new(Config::accurate(), seed))
}

/// The share of hypotheses the audit's `pf-sure` trackers and groups observe
/// after a confident frame: the least at which the group fixtures' targets
/// keep their identities over 16 seeds (docs/several-targets.md).
#[cfg(any(feature = "all-options", feature = "group"))]
pub(crate) const SURE_SHARE: pftrack::Real = 0.6;

#[inline(never)]
fn pf_init(t: &mut FwTracker, frame: &Frame<'_>, bbox: BoundingBox) -> Result<Estimate, pftrack::Error> {
    t.init(frame, bbox)
}

#[inline(never)]
fn pf_step(t: &mut FwTracker, frame: &Frame<'_>) -> Result<Estimate, pftrack::Error> {
    t.step(frame)
}

#[inline(never)]
fn ms_init(t: &mut MeanShift, frame: &Frame<'_>, bbox: BoundingBox) -> Result<Estimate, pftrack::Error> {
    t.init(frame, bbox)
}

#[inline(never)]
fn ms_step(t: &mut MeanShift, frame: &Frame<'_>) -> Result<Estimate, pftrack::Error> {
    t.step(frame)
}

/// Builds a mean-shift tracker into a static (see `make_tracker`).
#[inline(never)]
fn make_meanshift(config: MeanShiftConfig) -> Result<Option<&'static mut MeanShift>, pftrack::Error> {
    let t = MeanShift::new(config)?;
    Ok(cortex_m::singleton!(: MeanShift = t))
}

unsafe extern "C" {
    /// End of .bss: the stack may grow down to here (cortex-m-rt's link.x).
    static mut __sheap: u32;
    /// The initial stack pointer (top of RAM).
    static _stack_start: u32;
}

/// Paints the free stack below the current stack pointer, so that the
/// deepest point the stack reaches can be read back afterwards: a
/// measurement, not an estimate. Returns the lowest painted address.
fn paint_stack() -> Option<usize> {
    let floor = core::ptr::addr_of_mut!(__sheap) as usize;
    let sp = cortex_m::register::msp::read() as usize;
    // Leave what the current frame is using alone.
    let top = sp.checked_sub(64)? & !3;
    let mut p = floor;
    while p < top {
        // SAFETY: [__sheap, sp − 64) is unused RAM between .bss and the live stack.
        unsafe { core::ptr::write_volatile(p as *mut u32, PAINT) };
        p += 4;
    }
    Some(floor)
}

/// Bytes of stack used at the deepest point since `paint_stack`.
fn peak_stack(floor: usize) -> usize {
    let top = core::ptr::addr_of!(_stack_start) as usize;
    let mut p = floor;
    // SAFETY: reads words of RAM between .bss and the stack top.
    while p < top && unsafe { core::ptr::read_volatile(p as *const u32) } == PAINT {
        p += 4;
    }
    top - p
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
