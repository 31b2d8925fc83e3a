//! The static the firmware's particle-filter tracker lives in, shared by
//! the firmware and the pan-tilt example.

use pftrack::{Error, Tracker};

/// The tracker lives in a static, not on the stack: it is the largest object.
pub type FwTracker = Tracker<100>;

/// The one static every kind of particle-filter tracker is built into (a
/// run builds one): a static per kind would take a tracker's RAM once for
/// every kind the build has. The constructor's whole result is moved into
/// it and the tracker used where it lies: a tracker taken out of its
/// `Result` first, or passed through `cortex_m::singleton!`, is one or two
/// more copies of it on the stack, more than the STM32F405 has room for.
/// Inlined into each `make_*` with its constructor, so that each
/// configuration is known at compile time and its validation folds away.
#[inline(always)]
pub fn keep(made: impl FnOnce() -> Result<FwTracker, Error>) -> Result<Option<&'static mut FwTracker>, Error> {
    static mut TRACKER: core::mem::MaybeUninit<Result<FwTracker, Error>> = core::mem::MaybeUninit::uninit();
    static mut TAKEN: bool = false;
    // SAFETY: `TAKEN` is read and set with interrupts off, so `TRACKER` is
    // written, and handed out, once.
    let first =
        cortex_m::interrupt::free(|_| unsafe { !core::mem::replace(&mut *core::ptr::addr_of_mut!(TAKEN), true) });
    if !first {
        return Ok(None);
    }
    // SAFETY: only this call, the first, reaches here (above).
    match unsafe { (*core::ptr::addr_of_mut!(TRACKER)).write(made()) } {
        Ok(t) => Ok(Some(t)),
        Err(e) => Err(*e),
    }
}
