//! The surroundings-motion test: its switch, its validation and default,
//! and the cue the tracker keeps ([`scene`] where the `scene-motion`
//! feature builds it, a stand-in that does nothing where not).

#[cfg(feature = "scene-motion")]
mod scene;

#[cfg(not(feature = "scene-motion"))]
use crate::cue::Absent;
use crate::cue::not_built;
use crate::error::Checks;

#[cfg(feature = "scene-motion")]
pub(crate) use scene::SceneMotion;

/// The cue in a build without the `scene-motion` feature.
#[cfg(not(feature = "scene-motion"))]
pub(crate) type SceneMotion = Absent<On>;

/// The test's settings: it has none but being on.
#[derive(Copy, Clone, Debug)]
pub(crate) struct On;

/// On wherever it is built: on the real sequences it reports many more of
/// the missing frames at the same accuracy (docs/accuracy.md).
pub(crate) const DEFAULT: bool = cfg!(feature = "scene-motion");

/// The settings as the tracker's cues take them.
pub(crate) fn settings(on: bool) -> Option<On> {
    on.then_some(On)
}

/// Asking for the test in a build without it is an error that names the
/// feature.
#[inline]
pub(crate) fn validate(c: &mut Checks, on: bool) {
    if on && !cfg!(feature = "scene-motion") {
        c.fail(not_built("scene_motion", "scene-motion"));
    }
}
