//! An external size measurement for one frame.

use crate::error::ConfigError;
use crate::filter::Particle;
use crate::scalar::Real;

/// An external measurement of the target's size for one frame: the
/// head-tracking paper's depth-derived minor axis (from a depth sensor, a
/// range finder, or a known distance). Particles whose shorter half axis
/// lies outside `half_minor ± tolerance` are rescaled, keeping their aspect
/// ratio, to the nearest end of that range before they are weighed.
#[derive(Copy, Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ScalePrior {
    /// The expected shorter half axis, in pixels (1 to 2048).
    pub half_minor: Real,
    /// How far from it a particle may be, in pixels (0 to 2048; the paper
    /// searched ±1 px).
    pub tolerance: Real,
}

impl ScalePrior {
    pub(super) fn validate(&self) -> Result<(), ConfigError> {
        let limit = (crate::pixel::MAX_DIMENSION / 2) as Real;
        let mut c = crate::error::Checks::new();
        c.range("prior.half_minor", self.half_minor, 1.0, limit);
        c.range("prior.tolerance", self.tolerance, 0.0, limit);
        c.result()
    }

    /// Rescales `p` so that its shorter half axis is within the prior.
    pub(super) fn apply(&self, p: &mut Particle) {
        let minor = p.hx.min(p.hy);
        let want = crate::scalar::clamp(minor, self.half_minor - self.tolerance, self.half_minor + self.tolerance);
        if minor > 0.0 && want != minor {
            let f = want / minor;
            p.hx *= f;
            p.hy *= f;
        }
    }
}
