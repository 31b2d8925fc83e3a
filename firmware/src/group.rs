//! A fixture of several targets: a group of them all, each added from its
//! first box, one trace line per target and frame (`FRAME TARGET TRACE`, as
//! `pftrack-trace` prints it), and the group's instruction counts, stack and
//! RAM. Built with the `group` feature only: a build without it refuses
//! such a fixture, so that the default build and its audited figures are
//! one tracker's.

use crate::host::FixtureStream;
use core::fmt::Write;
#[cfg(feature = "group")]
use pftrack::{BoundingBox, Config, Frame, Group};

/// The most targets the group holds.
#[cfg(feature = "group")]
const TARGETS: usize = 3;

/// The group lives in a static: it is the largest object.
#[cfg(feature = "group")]
type FwGroup = Group<TARGETS, 100>;

/// Tracks the fixture of `stream` with a group; returns whether it ran to
/// the end.
#[cfg(feature = "group")]
pub fn run(
    out: &mut impl Write,
    stream: &mut FixtureStream,
    ticks: &mut [u32],
    (path, seed, kind): (&str, u64, &str),
) -> bool {
    macro_rules! fail {
        ($($t:tt)*) => {{
            let _ = writeln!(out, "error: {}", format_args!($($t)*));
            return false;
        }};
    }
    let h = stream.header;
    let n = h.targets as usize;
    if n > TARGETS {
        fail!("{path} has {n} targets; this build's group holds {TARGETS}");
    }
    let share = match kind {
        "pf" => 1.0,
        "pf-sure" => crate::SURE_SHARE,
        _ => fail!(
            "tracker `{kind}`: a fixture of several targets is tracked by the particle filter's group (pf or pf-sure)"
        ),
    };
    let group = match make_group(seed, share) {
        Ok(Some(g)) => g,
        Ok(None) => fail!("group taken"),
        Err(e) => fail!("{e}"),
    };
    // Only now, as for one tracker (`crate::frame_buffer`).
    let Some(buffer) = crate::frame_buffer() else { fail!("buffer taken") };
    let pixels = match buffer.get_mut(..h.frame_len()) {
        Some(p) => p,
        None => fail!("{path}: frames larger than the buffer"),
    };
    let Some(mut cp) = cortex_m::Peripherals::take() else { fail!("peripherals taken") };
    crate::start_systick(&mut cp);
    let _ = writeln!(out, "board {}", crate::board::NAME);
    let _ = writeln!(
        out,
        "fixture {path} {}x{} {:?} frames {} seed {seed} tracker group of {n}",
        h.width, h.height, h.format, h.frames
    );
    let mut stack_floor = crate::paint_stack();
    let mut init_stack = None;
    let mut measured = 0usize;
    let mut others = [BoundingBox::default(); TARGETS];
    for i in 0..h.frames as usize {
        let first = match stream.next(i as u32, pixels, &mut others) {
            Ok(m) => m.truth,
            Err(e) => fail!("{path}: {e}"),
        };
        let frame = match Frame::new(pixels, h.width, h.height, h.stride, h.format) {
            Ok(f) => f,
            Err(e) => fail!("frame {i}: {e}"),
        };
        let t0 = cortex_m::peripheral::SYST::get_current();
        if i == 0 {
            let boxes = core::iter::once(first).chain(others.iter().copied()).take(n);
            for (k, b) in boxes.enumerate() {
                match add(group, &frame, b) {
                    Ok(est) => {
                        let _ = writeln!(out, "{i} {k} {}", est.trace());
                    }
                    Err(e) => fail!("frame {i}, target {k}: {e}"),
                }
            }
            init_stack = stack_floor.map(crate::peak_stack);
            stack_floor = crate::paint_stack();
            continue;
        }
        let result = step(group, &frame);
        let t1 = cortex_m::peripheral::SYST::get_current();
        match result {
            Ok(all) => {
                for t in all {
                    let _ = writeln!(out, "{i} {} {}", t.id.0, t.estimate.trace());
                }
            }
            Err(e) => fail!("frame {i}: {e}"),
        }
        if let Some(slot) = ticks.get_mut(measured) {
            // SysTick counts down and wraps at 2^24; one step is far shorter.
            *slot = t0.wrapping_sub(t1) & 0x00ff_ffff;
            measured += 1;
        }
    }
    let peak = stack_floor.map(crate::peak_stack);
    crate::report(out, &mut ticks[..measured], (init_stack, peak), core::mem::size_of::<FwGroup>());
    true
}

/// A build without the `group` feature refuses a fixture of several targets.
#[cfg(not(feature = "group"))]
pub fn run(out: &mut impl Write, stream: &mut FixtureStream, _: &mut [u32], (path, _, _): (&str, u64, &str)) -> bool {
    let _ = writeln!(
        out,
        "error: {path} has {} targets; this build ({}) tracks one (the `group` feature tracks several)",
        stream.header.targets,
        crate::board::NAME
    );
    false
}

/// Builds the group into a static (out of line, as `make_tracker`), its
/// targets observing `sure_share` of their hypotheses after a confident frame.
#[cfg(feature = "group")]
#[inline(never)]
fn make_group(seed: u64, sure_share: pftrack::Real) -> Result<Option<&'static mut FwGroup>, pftrack::Error> {
    let g = FwGroup::new(Config { sure_share, ..Config::fast() }, seed)?;
    Ok(cortex_m::singleton!(: FwGroup = g))
}

#[cfg(feature = "group")]
#[inline(never)]
fn add(g: &mut FwGroup, frame: &Frame<'_>, b: BoundingBox) -> Result<pftrack::Estimate, pftrack::Error> {
    g.add(frame, b).map(|a| a.estimate)
}

#[cfg(feature = "group")]
#[inline(never)]
fn step(g: &mut FwGroup, frame: &Frame<'_>) -> Result<pftrack::Tracks<TARGETS>, pftrack::Error> {
    g.step(frame)
}
