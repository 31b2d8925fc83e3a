//! Helpers shared by the unit tests.

/// Memory as the tracker lends it to the cues: a foreground map's sums
/// ([`crate::foreground::ForegroundMap::lend`]), boxed off the test's stack.
#[cfg(feature = "correlation")]
pub(crate) fn lent() -> Box<crate::foreground::ForegroundMap<4096>> {
    Box::new(crate::foreground::ForegroundMap::new())
}

/// A repeatable stream of 32-bit states for test scenes: the linear
/// congruential generator of Numerical Recipes (`s ← 1664525·s + 1013904223`),
/// its new state per call. For pictures and random inputs, not statistics;
/// callers take the state's high bits.
pub(crate) fn lcg(seed: u32) -> impl FnMut() -> u32 {
    let mut s = seed;
    move || {
        s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        s
    }
}

/// `len` bytes of noise: the top byte of each state of [`lcg`] from `seed`.
pub(crate) fn noise_bytes(seed: u32, len: usize) -> Vec<u8> {
    let mut next = lcg(seed);
    (0..len).map(|_| (next() >> 24) as u8).collect()
}
