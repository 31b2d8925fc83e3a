//! pftrack from C: the tracker behind a C interface, in storage the caller
//! gives, with every error a code.
//!
//! The header `pftrack.h` beside this crate is generated from this file by
//! cbindgen (`c/cbindgen.toml`); CI fails when the committed header differs
//! from a fresh one. `docs/c.md` shows a camera loop.
//!
//! - Nothing allocates: a tracker lives in a `pftrack_tracker` the caller
//!   declares (a `static` on small stacks), whose size and alignment the
//!   header states. [`pftrack_create`] checks the size the caller's header
//!   gave against this library's, so a header that does not match its
//!   library is an error, not a corrupted tracker.
//! - Every function returns [`PFTRACK_OK`] or a negative code naming the
//!   condition, as the Rust [`pftrack::Error`] does; [`pftrack_error_name`]
//!   names a code and [`pftrack_last_error`] gives the last error's whole
//!   message (which field, which box).
//! - No input makes it panic (the core proves it has no reachable panic,
//!   and this layer only converts), and nothing is written outside the
//!   storage and the outputs it is given.
#![cfg_attr(target_os = "none", no_std)]
// The C names are the interface (`pftrack_tracker`, `pftrack_frame`).
#![allow(non_camel_case_types)]

use core::ffi::c_char;
use core::fmt::Write;
use core::mem::{align_of, size_of};
use pftrack::{
    BoundingBox, Config, CorrelationCue, Error, Event, Frame, Life, PixelFormat, Redetect, TrackState, Tracker,
};

/// Particles of every tracker made through this interface.
pub const PFTRACK_PARTICLES: u32 = 100;

/// Success.
pub const PFTRACK_OK: i32 = 0;
/// A pointer argument was null.
pub const PFTRACK_ERR_NULL: i32 = -1;
/// The storage size the caller gave is not this library's: the header and
/// the library do not match.
pub const PFTRACK_ERR_STORAGE: i32 = -2;
/// The storage does not hold a tracker made by [`pftrack_create`].
pub const PFTRACK_ERR_NOT_CREATED: i32 = -3;
/// The frame's pixel format code is not one of `PFTRACK_FORMAT_*`.
pub const PFTRACK_ERR_FORMAT: i32 = -4;
/// The frame does not fit its buffer (sizes, stride, planes).
pub const PFTRACK_ERR_FRAME: i32 = -5;
/// A configuration value is NaN, out of range, or asks for a technique this
/// build leaves out.
pub const PFTRACK_ERR_CONFIG: i32 = -6;
/// The box is empty, not finite, or outside the frame.
pub const PFTRACK_ERR_BOX: i32 = -7;
/// [`pftrack_step`] before [`pftrack_init`] or [`pftrack_search`].
pub const PFTRACK_ERR_NOT_INITIALISED: i32 = -8;
/// The frame's size differs from the one the tracker was initialised on.
pub const PFTRACK_ERR_FRAME_SIZE_CHANGED: i32 = -9;

/// 16-bit RGB 5:6:5, little-endian.
pub const PFTRACK_FORMAT_RGB565: u32 = 1;
/// 24-bit RGB, bytes R, G, B.
pub const PFTRACK_FORMAT_RGB888: u32 = 2;
/// YUV 4:2:2 packed as Y0 U Y1 V (YUYV).
pub const PFTRACK_FORMAT_YUV422: u32 = 3;
/// 8-bit luminance.
pub const PFTRACK_FORMAT_GRAY8: u32 = 4;
/// Planar YUV 4:2:0: Y plane, then U, then V, in one buffer.
pub const PFTRACK_FORMAT_I420: u32 = 5;
/// Semi-planar YUV 4:2:0: Y plane, then interleaved U, V, in one buffer.
pub const PFTRACK_FORMAT_NV12: u32 = 6;

/// `pftrack_config.base`: the other fields apply over the default
/// configuration (both correlation filters, a lost target looked for where
/// it was lost: the most accurate).
pub const PFTRACK_BASE_DEFAULT: u8 = 0;
/// `pftrack_config.base`: the other fields apply over the configuration for
/// boards that need the frame rate (the grey-level correlation filter
/// alone, a lost target looked for over the frame).
pub const PFTRACK_BASE_FAST: u8 = 1;

/// `pftrack_config.redetect`: a missed target is looked for only where the
/// particles go.
pub const PFTRACK_REDETECT_OFF: u8 = 0;
/// `pftrack_config.redetect`: also at the places near its last one whose
/// colours stand out as its own, after a miss while its motion is unknown
/// (no step has found it since it was learnt) or while it moves more than
/// half its size a frame.
pub const PFTRACK_REDETECT_NEAR: u8 = 1;
/// `pftrack_config.redetect`: near, and over the whole frame while lost.
pub const PFTRACK_REDETECT_FRAME: u8 = 2;

/// The tracker searches for its target.
pub const PFTRACK_STATE_SEARCHING: u32 = 0;
/// The tracker follows its target.
pub const PFTRACK_STATE_TRACKING: u32 = 1;
/// The target is lost; the tracker searches for it again.
pub const PFTRACK_STATE_LOST: u32 = 2;

/// Nothing happened this step.
pub const PFTRACK_EVENT_NONE: u32 = 0;
/// The tracker was initialised on a box.
pub const PFTRACK_EVENT_INITIALISED: u32 = 1;
/// A searched-for target was found.
pub const PFTRACK_EVENT_ACQUIRED: u32 = 2;
/// The tracked target was lost.
pub const PFTRACK_EVENT_LOST_TARGET: u32 = 3;
/// A lost target was found again.
pub const PFTRACK_EVENT_REACQUIRED: u32 = 4;

/// 64-bit words of a [`pftrack_tracker`] on a 64-bit target.
#[cfg(target_pointer_width = "64")]
pub const PFTRACK_TRACKER_WORDS: usize = 4789;
/// 64-bit words of a [`pftrack_tracker`] on a 32-bit target.
#[cfg(not(target_pointer_width = "64"))]
pub const PFTRACK_TRACKER_WORDS: usize = 4781;
/// Bytes of a [`pftrack_tracker`].
pub const PFTRACK_TRACKER_BYTES: usize = PFTRACK_TRACKER_WORDS * 8;
/// Alignment of a [`pftrack_tracker`], in bytes.
pub const PFTRACK_TRACKER_ALIGN: usize = 8;

/// Storage for one tracker. Declare one per target (a `static` where the
/// stack is small), pass its address and `sizeof` to [`pftrack_create`],
/// then its address to every other call. Its bytes are the library's.
#[repr(C)]
pub struct pftrack_tracker {
    /// The library's bytes: not to be read or written by the caller.
    pub opaque: [u64; PFTRACK_TRACKER_WORDS],
}

/// A box: left, top, width, height in pixels.
#[repr(C)]
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct pftrack_box {
    /// Left edge.
    pub x: f32,
    /// Top edge.
    pub y: f32,
    /// Width.
    pub w: f32,
    /// Height.
    pub h: f32,
}

/// One frame as a camera or decoder wrote it: `len` bytes at `data`, rows
/// `stride` bytes apart, in format `format` (`PFTRACK_FORMAT_*`); the
/// planar formats' chroma planes follow the luma plane in the same buffer.
#[repr(C)]
#[derive(Copy, Clone, Debug)]
pub struct pftrack_frame {
    /// The first byte of the first row.
    pub data: *const u8,
    /// Bytes readable at `data`.
    pub len: usize,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Bytes from one row's start to the next's.
    pub stride: u32,
    /// One of `PFTRACK_FORMAT_*`.
    pub format: u32,
}

/// What a step found.
#[repr(C)]
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct pftrack_estimate {
    /// The estimated box.
    pub bbox: pftrack_box,
    /// The probability that the estimate is on the target, in `[0, 1]`:
    /// what a controller should threshold.
    pub confidence: f32,
    /// One of `PFTRACK_STATE_*`.
    pub state: u32,
    /// One of `PFTRACK_EVENT_*`.
    pub event: u32,
}

/// The settings a C caller sets; the rest are those of the configuration
/// `base` names. Fill it with [`pftrack_config_default`] or
/// [`pftrack_config_fast`], then change fields.
#[repr(C)]
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct pftrack_config {
    /// The configuration the other fields apply over: `PFTRACK_BASE_DEFAULT`
    /// or `PFTRACK_BASE_FAST`.
    pub base: u8,
    /// A tracking frame whose confidence is below this is a miss, in `[0, 1]`.
    pub lost_below: f32,
    /// A searched-for or lost target is found above this, in `[0, 1]`.
    pub found_above: f32,
    /// Model adaptation rate, in `[0, 1]`.
    pub alpha: f32,
    /// Consecutive misses after which a tracked target is lost (1 to 1000).
    pub lost_after: u16,
    /// 1: the grey-level correlation filter beside colour; 0: without it.
    pub correlation: u8,
    /// 1: a box that moves with its surroundings counts as a miss; 0: off.
    pub scene_motion: u8,
    /// Where a missed target is looked for beyond the particles' reach:
    /// `PFTRACK_REDETECT_OFF`, `PFTRACK_REDETECT_NEAR` (the default) or
    /// `PFTRACK_REDETECT_FRAME`.
    pub redetect: u8,
    /// The share of the hypotheses observed on a frame after one confidently
    /// on the target, in `(0, 1]`; 1 observes all of them (fewer is faster,
    /// and a little less accurate).
    pub sure_share: f32,
}

/// Distinguishes storage made by [`pftrack_create`] from any other bytes.
const MAGIC: u64 = 0x7066_7472_6163_6b31;

/// What the storage holds; `magic` first, where [`slot`] reads it.
#[repr(C)]
struct Slot {
    // Read through the storage's first word, not by name.
    #[allow(dead_code)]
    magic: u64,
    /// The constructor's outcome, as it returned it.
    made: Result<Tracker<100>, Error>,
    /// The last call's error.
    error: Option<Error>,
}

// The header states the storage's exact size: a tracker whose size changes
// changes the header, which CI compares with a fresh one.
const _: () = assert!(size_of::<Slot>().next_multiple_of(8) == PFTRACK_TRACKER_BYTES, "PFTRACK_TRACKER_BYTES");
const _: () = assert!(align_of::<Slot>() <= PFTRACK_TRACKER_ALIGN);
const _: () = assert!(align_of::<pftrack_tracker>() == PFTRACK_TRACKER_ALIGN);
const _: () = assert!(size_of::<pftrack_tracker>() == PFTRACK_TRACKER_BYTES);
const _: () = assert!(PFTRACK_PARTICLES == 100);

/// The tracker in `t`, if `t` holds one made by [`pftrack_create`].
///
/// # Safety
/// `t` is null or points to a `pftrack_tracker`, writable and not used
/// elsewhere during the call.
unsafe fn slot<'a>(t: *mut pftrack_tracker) -> Result<&'a mut Slot, i32> {
    if t.is_null() {
        return Err(PFTRACK_ERR_NULL);
    }
    let words = t.cast::<u64>();
    // SAFETY: `t` is a valid `pftrack_tracker` (the caller's promise); its
    // first word is a `u64`, and every bit pattern is one.
    if unsafe { words.read() } != MAGIC {
        return Err(PFTRACK_ERR_NOT_CREATED);
    }
    // SAFETY: the magic word is written only by `pftrack_create`, together
    // with a whole `Slot` (which fits and is aligned: the asserts above).
    Ok(unsafe { &mut *t.cast::<Slot>() })
}

/// The frame `f` describes.
///
/// # Safety
/// `f.data` is null with `f.len` 0, or readable for `f.len` bytes.
unsafe fn frame<'a>(f: &pftrack_frame) -> Result<Frame<'a>, (i32, Option<Error>)> {
    let format = u16::try_from(f.format).ok().and_then(PixelFormat::from_code).ok_or((PFTRACK_ERR_FORMAT, None))?;
    let data: &[u8] = if f.data.is_null() || f.len == 0 {
        &[]
    } else {
        // SAFETY: readable for `len` bytes (the caller's promise).
        unsafe { core::slice::from_raw_parts(f.data, f.len) }
    };
    Frame::new(data, f.width as usize, f.height as usize, f.stride as usize, format)
        .map_err(|e| (PFTRACK_ERR_FRAME, Some(Error::Frame(e))))
}

/// The code of a Rust error.
fn code_of(e: &Error) -> i32 {
    match e {
        Error::Frame(_) => PFTRACK_ERR_FRAME,
        Error::Config(_) => PFTRACK_ERR_CONFIG,
        Error::Region(_) => PFTRACK_ERR_BOX,
        Error::NotInitialised => PFTRACK_ERR_NOT_INITIALISED,
        Error::FrameSizeChanged { .. } => PFTRACK_ERR_FRAME_SIZE_CHANGED,
        // A group's errors: this API wraps one tracker, whose calls never
        // return them. Were one to arrive, it is a misuse of the call.
        Error::GroupFull { .. } | Error::UnknownTarget { .. } => PFTRACK_ERR_CONFIG,
    }
}

/// Records the outcome of `r` in `slot` and returns its code.
fn finish<T>(slot: &mut Slot, r: Result<T, (i32, Option<Error>)>) -> Result<T, i32> {
    match r {
        Ok(v) => {
            slot.error = None;
            Ok(v)
        }
        Err((code, e)) => {
            slot.error = e;
            Err(code)
        }
    }
}

fn estimate_of(e: &pftrack::Estimate) -> pftrack_estimate {
    let b = e.bbox();
    pftrack_estimate {
        bbox: pftrack_box { x: b.x, y: b.y, w: b.width, h: b.height },
        confidence: e.confidence,
        state: match e.state {
            TrackState::Searching => PFTRACK_STATE_SEARCHING,
            TrackState::Tracking => PFTRACK_STATE_TRACKING,
            TrackState::Lost => PFTRACK_STATE_LOST,
        },
        event: match e.event {
            None => PFTRACK_EVENT_NONE,
            Some(Event::Initialised) => PFTRACK_EVENT_INITIALISED,
            Some(Event::Acquired) => PFTRACK_EVENT_ACQUIRED,
            Some(Event::LostTarget) => PFTRACK_EVENT_LOST_TARGET,
            Some(Event::Reacquired) => PFTRACK_EVENT_REACQUIRED,
        },
    }
}

/// The configuration error naming `field`, out of its range.
fn out_of_range(field: &'static str) -> Error {
    Error::Config(pftrack::ConfigError { field, problem: pftrack::ParamProblem::OutOfRange })
}

/// The Rust configuration for `c`, or the error naming a flag that is
/// neither 0 nor 1, or a choice that is none of its constants.
fn config_of(c: &pftrack_config) -> Result<Config, Error> {
    let flag = |field: &'static str, v: u8| match v {
        0 => Ok(false),
        1 => Ok(true),
        _ => Err(out_of_range(field)),
    };
    let defaults = base_of(c.base).ok_or_else(|| out_of_range("base"))?;
    Ok(Config {
        life: Life::Confidence { lost_below: c.lost_below, found_above: c.found_above },
        alpha: c.alpha,
        lost_after: c.lost_after,
        correlation: flag("correlation", c.correlation)?
            .then_some(defaults.correlation.unwrap_or(CorrelationCue::MEASURED)),
        scene_motion: flag("scene_motion", c.scene_motion)?,
        redetect: match c.redetect {
            PFTRACK_REDETECT_OFF => Redetect::Off,
            PFTRACK_REDETECT_NEAR => Redetect::Near,
            PFTRACK_REDETECT_FRAME => Redetect::Frame,
            _ => return Err(out_of_range("redetect")),
        },
        sure_share: c.sure_share,
        ..defaults
    })
}

/// The configuration `base` names, if it names one.
fn base_of(base: u8) -> Option<Config> {
    match base {
        PFTRACK_BASE_DEFAULT => Some(Config::default()),
        PFTRACK_BASE_FAST => Some(Config::fast()),
        _ => None,
    }
}

/// Fills `out` with the default settings (`Config::default()`).
///
/// # Safety
/// `out` is null or points to a writable `pftrack_config`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn pftrack_config_default(out: *mut pftrack_config) -> i32 {
    // SAFETY: the caller's promise, passed on.
    unsafe { fill(out, PFTRACK_BASE_DEFAULT) }
}

/// Fills `out` with the settings for boards that need the frame rate
/// (`Config::fast()`).
///
/// # Safety
/// `out` is null or points to a writable `pftrack_config`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn pftrack_config_fast(out: *mut pftrack_config) -> i32 {
    // SAFETY: the caller's promise, passed on.
    unsafe { fill(out, PFTRACK_BASE_FAST) }
}

/// Fills `out` with the settings of the configuration `base` names.
///
/// # Safety
/// `out` is null or points to a writable `pftrack_config`.
unsafe fn fill(out: *mut pftrack_config, base: u8) -> i32 {
    if out.is_null() {
        return PFTRACK_ERR_NULL;
    }
    let Some(d) = base_of(base) else { return PFTRACK_ERR_CONFIG };
    let (lost_below, found_above) = match d.life {
        Life::Confidence { lost_below, found_above } => (lost_below, found_above),
        Life::Appearance => (0.6, 0.8),
    };
    let c = pftrack_config {
        base,
        lost_below,
        found_above,
        alpha: d.alpha,
        lost_after: d.lost_after,
        correlation: d.correlation.is_some() as u8,
        scene_motion: d.scene_motion as u8,
        redetect: match d.redetect {
            Redetect::Off => PFTRACK_REDETECT_OFF,
            Redetect::Near => PFTRACK_REDETECT_NEAR,
            Redetect::Frame => PFTRACK_REDETECT_FRAME,
        },
        sure_share: d.sure_share,
    };
    // SAFETY: writable (the caller's promise).
    unsafe { out.write(c) };
    PFTRACK_OK
}

/// Makes a tracker in `t` with settings `config` and random seed `seed`
/// (the same seed and frames give the same track, bit for bit, on every
/// target). `size` is `sizeof(pftrack_tracker)` as the caller's header
/// says it. Any earlier tracker in `t` is forgotten.
///
/// # Safety
/// `t` is null or points to a writable `pftrack_tracker` not used elsewhere
/// during the call; `config` is null or points to a `pftrack_config`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn pftrack_create(
    t: *mut pftrack_tracker,
    size: usize,
    config: *const pftrack_config,
    seed: u64,
) -> i32 {
    if t.is_null() || config.is_null() {
        return PFTRACK_ERR_NULL;
    }
    if size != size_of::<pftrack_tracker>() {
        return PFTRACK_ERR_STORAGE;
    }
    // SAFETY: readable (the caller's promise).
    let c = unsafe { config.read() };
    let slot = t.cast::<Slot>();
    // SAFETY: `t` is writable, large and aligned enough for a `Slot` (the
    // asserts above); its old contents need no drop (a `Slot` owns nothing
    // outside itself). Each field is written in place, the tracker straight
    // from its constructor: built into a local and then moved, it would take
    // a second tracker's room on the stack.
    let error = unsafe {
        (&raw mut (*slot).magic).write(MAGIC);
        let made = &raw mut (*slot).made;
        match config_of(&c) {
            Ok(cfg) => made.write(Tracker::<100>::new(cfg, seed)),
            Err(e) => made.write(Err(e)),
        }
        let error = (*made).as_ref().err().copied();
        (&raw mut (*slot).error).write(error);
        error
    };
    error.map_or(PFTRACK_OK, |e| code_of(&e))
}

/// Runs `f` on the tracker in `t` and the frame `frame`.
///
/// # Safety
/// As for [`slot`] and [`frame`] (through `frame`, which is null or points to
/// a `pftrack_frame`).
unsafe fn with_frame<T>(
    t: *mut pftrack_tracker,
    f: *const pftrack_frame,
    run: impl FnOnce(&mut Tracker<100>, &Frame<'_>) -> Result<T, Error>,
) -> Result<T, i32> {
    // SAFETY: forwarded from the caller.
    let slot = unsafe { slot(t) }?;
    if f.is_null() {
        return Err(PFTRACK_ERR_NULL);
    }
    // SAFETY: readable (the caller's promise).
    let f = unsafe { f.read() };
    // SAFETY: forwarded from the caller.
    let r = unsafe { frame(&f) }.and_then(|frame| match slot.made.as_mut() {
        Ok(tracker) => run(tracker, &frame).map_err(|e| (code_of(&e), Some(e))),
        Err(e) => Err((PFTRACK_ERR_CONFIG, Some(*e))),
    });
    finish(slot, r)
}

fn box_of(b: pftrack_box) -> BoundingBox {
    BoundingBox::new(b.x, b.y, b.w, b.h)
}

/// The code of `r`, its estimate written to `out` (if not null) on success.
///
/// # Safety
/// `out` is null or writable.
unsafe fn report(r: Result<pftrack::Estimate, i32>, out: *mut pftrack_estimate) -> i32 {
    match r {
        Ok(e) => {
            if !out.is_null() {
                // SAFETY: writable (the caller's promise).
                unsafe { out.write(estimate_of(&e)) };
            }
            PFTRACK_OK
        }
        Err(code) => code,
    }
}

/// Learns the target in `bbox` of `frame` and tracks it from there; call it
/// again at any time to re-initialise. Writes the first estimate to `out`
/// (if not null).
///
/// # Safety
/// `t` as for [`pftrack_create`]; `frame` null or pointing to a
/// `pftrack_frame` whose `data` is readable for `len` bytes; `out` null or
/// writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn pftrack_init(
    t: *mut pftrack_tracker,
    frame: *const pftrack_frame,
    bbox: pftrack_box,
    out: *mut pftrack_estimate,
) -> i32 {
    // SAFETY: forwarded from the caller.
    let r = unsafe { with_frame(t, frame, |tr, f| tr.init(f, box_of(bbox))) };
    // SAFETY: forwarded from the caller.
    unsafe { report(r, out) }
}

/// Learns the target in `bbox` of `frame`, then searches for it in the
/// frames that follow.
///
/// # Safety
/// As for [`pftrack_init`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn pftrack_search(
    t: *mut pftrack_tracker,
    frame: *const pftrack_frame,
    bbox: pftrack_box,
) -> i32 {
    // SAFETY: forwarded from the caller.
    match unsafe { with_frame(t, frame, |tr, f| tr.search(f, box_of(bbox))) } {
        Ok(()) => PFTRACK_OK,
        Err(code) => code,
    }
}

/// Tracks one frame and writes the estimate to `out` (if not null).
///
/// # Safety
/// As for [`pftrack_init`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn pftrack_step(
    t: *mut pftrack_tracker,
    frame: *const pftrack_frame,
    out: *mut pftrack_estimate,
) -> i32 {
    // SAFETY: forwarded from the caller.
    let r = unsafe { with_frame(t, frame, |tr, f| tr.step(f)) };
    // SAFETY: forwarded from the caller.
    unsafe { report(r, out) }
}

/// The name of a code, as a static NUL-terminated string.
#[unsafe(no_mangle)]
pub extern "C" fn pftrack_error_name(code: i32) -> *const c_char {
    let s: &'static [u8] = match code {
        PFTRACK_OK => b"ok\0",
        PFTRACK_ERR_NULL => b"a pointer argument is null\0",
        PFTRACK_ERR_STORAGE => b"the storage size differs from the library's: pftrack.h does not match the library\0",
        PFTRACK_ERR_NOT_CREATED => b"the storage holds no tracker: call pftrack_create first\0",
        PFTRACK_ERR_FORMAT => b"unknown pixel format code\0",
        PFTRACK_ERR_FRAME => b"bad frame\0",
        PFTRACK_ERR_CONFIG => b"bad configuration\0",
        PFTRACK_ERR_BOX => b"bad box\0",
        PFTRACK_ERR_NOT_INITIALISED => b"tracker not initialised: call pftrack_init or pftrack_search first\0",
        PFTRACK_ERR_FRAME_SIZE_CHANGED => b"the frame size differs from the one the tracker was initialised on\0",
        _ => b"unknown code\0",
    };
    s.as_ptr().cast()
}

/// Writes the message of the last error of the tracker in `t` (which field,
/// which box, which size), NUL-terminated and cut to `len` bytes, into
/// `buf`; returns the message's length without the NUL (0 if the last call
/// succeeded or `t` holds no tracker).
///
/// # Safety
/// `t` as for [`pftrack_create`]; `buf` null or writable for `len` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn pftrack_last_error(t: *mut pftrack_tracker, buf: *mut c_char, len: usize) -> usize {
    // SAFETY: forwarded from the caller.
    let Ok(slot) = (unsafe { slot(t) }) else { return 0 };
    let Some(e) = slot.error else { return 0 };
    let mut text = Text { bytes: [0; 192], len: 0 };
    // A message longer than the buffer is cut; `Text` never fails.
    let _ = write!(text, "{e}");
    if !buf.is_null() && len > 0 {
        let n = text.len.min(len - 1);
        // SAFETY: `buf` is writable for `len` > `n` bytes (the caller's
        // promise); `text.bytes` holds at least `n` bytes.
        unsafe {
            core::ptr::copy_nonoverlapping(text.bytes.as_ptr(), buf.cast::<u8>(), n);
            buf.add(n).write(0);
        }
    }
    text.len
}

/// A message written into a fixed buffer, cut at its end.
struct Text {
    bytes: [u8; 192],
    len: usize,
}

impl Write for Text {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        for &b in s.as_bytes() {
            if let Some(slot) = self.bytes.get_mut(self.len) {
                *slot = b;
                self.len += 1;
            }
        }
        Ok(())
    }
}

#[cfg(all(target_os = "none", not(feature = "panic-check")))]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    // Unreachable: the core has no reachable panic, and this layer none
    // (the `panic-check` build proves it at link time).
    loop {}
}

#[cfg(all(target_os = "none", feature = "panic-check"))]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    unsafe extern "C" {
        /// Defined nowhere: a reachable panic fails the link, naming it.
        fn pftrack_c_has_a_reachable_panic() -> !;
    }
    // SAFETY: never called in a program that links.
    unsafe { pftrack_c_has_a_reachable_panic() }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 64x48 GRAY8 frame, grey with a bright 12x10 square at (20, 15).
    fn pixels() -> Vec<u8> {
        let mut px = vec![60u8; 64 * 48];
        for y in 15..25 {
            for x in 20..32 {
                px[y * 64 + x] = 220;
            }
        }
        px
    }

    fn frame_of(px: &[u8], width: u32, height: u32, format: u32) -> pftrack_frame {
        pftrack_frame { data: px.as_ptr(), len: px.len(), width, height, stride: width, format }
    }

    fn storage() -> Box<pftrack_tracker> {
        Box::new(pftrack_tracker { opaque: [0; PFTRACK_TRACKER_WORDS] })
    }

    fn defaults() -> pftrack_config {
        let mut c = pftrack_config {
            base: 9,
            lost_below: 0.0,
            found_above: 0.0,
            alpha: 0.0,
            lost_after: 0,
            correlation: 0,
            scene_motion: 0,
            redetect: 0,
            sure_share: 0.0,
        };
        // SAFETY: a writable config.
        assert_eq!(unsafe { pftrack_config_default(&mut c) }, PFTRACK_OK);
        c
    }

    fn last_error(t: &mut pftrack_tracker) -> String {
        let mut buf = [0 as c_char; 64];
        // SAFETY: a created tracker and a writable buffer of its length.
        let n = unsafe { pftrack_last_error(t, buf.as_mut_ptr(), buf.len()) };
        let text: Vec<u8> = buf.iter().take_while(|&&b| b != 0).map(|&b| b as u8).collect();
        assert!(n >= text.len(), "the length is the whole message's");
        String::from_utf8(text).unwrap_or_default()
    }

    #[test]
    fn defaults_are_the_rust_defaults() {
        // Reason: a C caller who changes nothing gets `Config::default()`,
        // or `Config::fast()` from `pftrack_config_fast`; a base that is
        // neither is an error naming the field.
        let mut c = defaults();
        assert_eq!(config_of(&c), Ok(Config::default()));
        // SAFETY: a writable config.
        assert_eq!(unsafe { pftrack_config_fast(&mut c) }, PFTRACK_OK);
        assert_eq!(config_of(&c), Ok(Config::fast()));
        assert_ne!(Config::fast(), Config::default());
        c.base = 2;
        assert_eq!(config_of(&c), Err(out_of_range("base")));
    }

    #[test]
    fn tracks_as_the_rust_tracker_does() {
        // Reason: a cross-check of the two interfaces on the same frames
        // and seed (c/compare does it on every fixture, from C).
        let px = pixels();
        let mut t = storage();
        let c = defaults();
        // SAFETY: valid storage, config, frame and outputs throughout.
        unsafe {
            assert_eq!(pftrack_create(&mut *t, size_of::<pftrack_tracker>(), &c, 7), PFTRACK_OK);
            let f = frame_of(&px, 64, 48, PFTRACK_FORMAT_GRAY8);
            let mut est = pftrack_estimate::default();
            assert_eq!(pftrack_init(&mut *t, &f, pftrack_box { x: 20.0, y: 15.0, w: 12.0, h: 10.0 }, &mut est), 0);
            assert_eq!(est.event, PFTRACK_EVENT_INITIALISED);
            let mut rust = Tracker::<100>::new(Config::default(), 7).unwrap_or_else(|e| panic!("{e}"));
            let frame = Frame::packed(&px, 64, 48, PixelFormat::Gray8).unwrap_or_else(|e| panic!("{e}"));
            let _ = rust.init(&frame, BoundingBox::new(20.0, 15.0, 12.0, 10.0));
            for _ in 0..5 {
                assert_eq!(pftrack_step(&mut *t, &f, &mut est), PFTRACK_OK);
                let want = rust.step(&frame).map(|e| estimate_of(&e)).unwrap_or_default();
                assert_eq!(est, want);
            }
            assert_eq!(est.state, PFTRACK_STATE_TRACKING);
        }
    }

    #[test]
    fn bad_input_gives_its_code_and_message() {
        // Reason: every condition of the Rust `Error`, and the ones only C
        // can make (null pointers, storage of another size, storage never
        // created, an unknown format code), comes back as its own code.
        let px = pixels();
        let f = frame_of(&px, 64, 48, PFTRACK_FORMAT_GRAY8);
        let b = pftrack_box { x: 20.0, y: 15.0, w: 12.0, h: 10.0 };
        let c = defaults();
        let mut t = storage();
        let size = size_of::<pftrack_tracker>();
        // SAFETY: every pointer is null or valid, as the functions allow.
        unsafe {
            assert_eq!(pftrack_config_default(core::ptr::null_mut()), PFTRACK_ERR_NULL);
            assert_eq!(pftrack_create(core::ptr::null_mut(), size, &c, 1), PFTRACK_ERR_NULL);
            assert_eq!(pftrack_create(&mut *t, size, core::ptr::null(), 1), PFTRACK_ERR_NULL);
            assert_eq!(pftrack_create(&mut *t, size - 8, &c, 1), PFTRACK_ERR_STORAGE);
            // Zeroed storage holds no tracker.
            assert_eq!(pftrack_step(&mut *t, &f, core::ptr::null_mut()), PFTRACK_ERR_NOT_CREATED);
            assert_eq!(last_error(&mut t), "");

            let bad_flag = pftrack_config { correlation: 2, ..c };
            assert_eq!(pftrack_create(&mut *t, size, &bad_flag, 1), PFTRACK_ERR_CONFIG);
            assert!(last_error(&mut t).contains("correlation"), "{}", last_error(&mut t));
            // A tracker that failed its configuration refuses frames.
            assert_eq!(pftrack_init(&mut *t, &f, b, core::ptr::null_mut()), PFTRACK_ERR_CONFIG);
            let nan = pftrack_config { lost_below: f32::NAN, ..c };
            assert_eq!(pftrack_create(&mut *t, size, &nan, 1), PFTRACK_ERR_CONFIG);
            let unknown_choice = pftrack_config { redetect: 3, ..c };
            assert_eq!(pftrack_create(&mut *t, size, &unknown_choice, 1), PFTRACK_ERR_CONFIG);
            assert!(last_error(&mut t).contains("redetect"), "{}", last_error(&mut t));
            let none = pftrack_config { sure_share: 0.0, ..c };
            assert_eq!(pftrack_create(&mut *t, size, &none, 1), PFTRACK_ERR_CONFIG);
            assert!(last_error(&mut t).contains("sure_share"), "{}", last_error(&mut t));

            assert_eq!(pftrack_create(&mut *t, size, &c, 1), PFTRACK_OK);
            assert_eq!(pftrack_step(&mut *t, &f, core::ptr::null_mut()), PFTRACK_ERR_NOT_INITIALISED);
            assert_eq!(pftrack_step(&mut *t, core::ptr::null(), core::ptr::null_mut()), PFTRACK_ERR_NULL);
            let unknown = frame_of(&px, 64, 48, 99);
            assert_eq!(pftrack_init(&mut *t, &unknown, b, core::ptr::null_mut()), PFTRACK_ERR_FORMAT);
            let short = frame_of(&px[..100], 64, 48, PFTRACK_FORMAT_GRAY8);
            assert_eq!(pftrack_init(&mut *t, &short, b, core::ptr::null_mut()), PFTRACK_ERR_FRAME);
            let empty = pftrack_frame { data: core::ptr::null(), len: 0, ..f };
            assert_eq!(pftrack_init(&mut *t, &empty, b, core::ptr::null_mut()), PFTRACK_ERR_FRAME);
            let outside = pftrack_box { x: 70.0, y: 40.0, w: 12.0, h: 10.0 };
            assert_eq!(pftrack_init(&mut *t, &f, outside, core::ptr::null_mut()), PFTRACK_ERR_BOX);
            assert!(last_error(&mut t).starts_with("bad box"), "{}", last_error(&mut t));

            assert_eq!(pftrack_init(&mut *t, &f, b, core::ptr::null_mut()), PFTRACK_OK);
            assert_eq!(last_error(&mut t), "", "a success clears the last error");
            let smaller = frame_of(&px[..32 * 48], 32, 48, PFTRACK_FORMAT_GRAY8);
            assert_eq!(pftrack_step(&mut *t, &smaller, core::ptr::null_mut()), PFTRACK_ERR_FRAME_SIZE_CHANGED);
            assert!(last_error(&mut t).contains("32x48"), "{}", last_error(&mut t));
            // The message is cut to the buffer, NUL included.
            let mut tiny = [1 as c_char; 4];
            let n = pftrack_last_error(&mut *t, tiny.as_mut_ptr(), tiny.len());
            assert!(n > 3 && tiny[3] == 0);
        }
        for code in -9..=0 {
            // SAFETY: the names are static NUL-terminated strings.
            let name = unsafe { core::ffi::CStr::from_ptr(pftrack_error_name(code)) };
            assert!(!name.to_bytes().is_empty() && name.to_bytes() != b"unknown code", "code {code}");
        }
    }
}
