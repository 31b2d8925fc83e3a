//! From a Bhattacharyya coefficient to a particle weight.
//!
//! `L = exp(−d² / (2σ²)) + ε`, with `d² = 1 − ρ`. The floor `ε` keeps
//! particles that see nothing like the target alive, so a filter that has lost
//! its target can still find it again (third paper). `σ` is either fixed or
//! chosen each frame so that the best particle gets `log L = −1`.

use crate::scalar::{self, Real, exp};

/// How the likelihood's width is chosen.
#[derive(Copy, Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Sigma {
    /// The same `σ` every frame (the first paper uses 0.2).
    Fixed(Real),
    /// Each frame, `σ = sqrt(d_min² / 2)` for the best particle's distance
    /// `d_min`, so that particle gets `log L = −1`; bounded to `[min, max]` so
    /// that a perfect match does not make every other particle weightless and
    /// a terrible frame does not make the weights flat.
    Adaptive {
        /// Lower bound on σ.
        min: Real,
        /// Upper bound on σ.
        max: Real,
    },
    /// Each frame, σ from the spread of the particles' distances: the
    /// average particle gets `exp(−spread)` of the best one's likelihood,
    /// whatever the best one's own distance. Unlike [`Sigma::Adaptive`],
    /// selection does not weaken when every particle is far from a perfect
    /// match (as happens when a cue never scores 1), and does not harden
    /// when one is perfect.
    Spread {
        /// How many e-folds below the best particle the average one lies.
        spread: Real,
        /// Lower bound on σ.
        min: Real,
        /// Upper bound on σ.
        max: Real,
    },
}

/// The form of the likelihood.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Shape {
    /// `exp(−d² / (2σ²))` (first paper).
    #[default]
    Gaussian,
    /// `exp(−d / σ)`: the adaptive-bins paper's `λ · exp(−β d)` with
    /// `β = 1/σ` (the constant `λ` cancels when weights are normalised).
    /// Heavier-tailed: far particles keep more weight.
    Exponential,
}

/// How the colour and edge distances combine into one.
#[derive(Copy, Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Combination {
    /// The product of the two cues' likelihoods with a shared σ:
    /// `exp(−d_c²/2σ²) · exp(−d_e²/2σ²) = exp(−(d_c² + d_e²)/2σ²)`,
    /// i.e. `d² = d_c² + d_e²`.
    Product,
    /// `d² = w · d_c² + (1 − w) · d_e²` with `w` the colour weight in `[0, 1]`.
    Weighted {
        /// Weight of the colour cue.
        colour: Real,
    },
}

impl Combination {
    /// The combined similarity in `[0, 1]` of a colour and an edge
    /// Bhattacharyya coefficient: `1 − d² / d²_max`, so 1 is a perfect match
    /// on both cues. The likelihood's `d²` is `d²_max · (1 − similarity)`.
    pub fn similarity(&self, rho_colour: Real, rho_edge: Real) -> Real {
        match *self {
            Combination::Product => 0.5 * (rho_colour + rho_edge),
            Combination::Weighted { colour } => colour * rho_colour + (1.0 - colour) * rho_edge,
        }
    }

    /// The largest `d²` the combination can produce.
    pub fn d2_max(&self) -> Real {
        match self {
            Combination::Product => 2.0,
            Combination::Weighted { .. } => 1.0,
        }
    }
}

/// The likelihood model.
#[derive(Copy, Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Likelihood {
    /// How σ is chosen.
    pub sigma: Sigma,
    /// The floor ε added to every weight.
    pub eps: Real,
    /// Gaussian or exponential in the distance.
    pub shape: Shape,
}

impl Likelihood {
    /// The σ to use this frame, given the smallest squared distance of any
    /// particle: adaptive σ gives that particle `log L = −1` in either shape.
    /// σ from the spread needs the particles' mean distance too (see
    /// [`Likelihood::sigma_and_offset`]); from the best alone it is its floor.
    pub fn sigma_for(&self, d2_min: Real) -> Real {
        match self.sigma {
            Sigma::Fixed(s) => s,
            // With no spread to measure, the floor.
            Sigma::Spread { .. } => self.sigma_and_offset(d2_min, d2_min).0,
            Sigma::Adaptive { min, max } => {
                let d2 = scalar::max(d2_min, 0.0);
                let s = match self.shape {
                    Shape::Gaussian => crate::scalar::sqrt(0.5 * d2),
                    Shape::Exponential => crate::scalar::sqrt(d2),
                };
                crate::scalar::clamp(s, min, max)
            }
        }
    }

    /// The σ for a frame whose best particle is at squared distance
    /// `d2_min` and whose particles average `d2_mean`, and the offset to
    /// take off every particle's squared distance before
    /// [`Likelihood::weight`]. The offset is 0 except for [`Sigma::Spread`],
    /// which measures distances from the best particle's, less `2σ²`, so
    /// that the best particle gets `log L = −1` in every mode.
    pub fn sigma_and_offset(&self, d2_min: Real, d2_mean: Real) -> (Real, Real) {
        match self.sigma {
            Sigma::Spread { spread, min, max } => {
                let s2 = scalar::max(d2_mean - d2_min, 0.0) / (2.0 * spread);
                let sigma = crate::scalar::clamp(crate::scalar::sqrt(s2), min, max);
                (sigma, d2_min - 2.0 * sigma * sigma)
            }
            _ => (self.sigma_for(d2_min), 0.0),
        }
    }

    /// `exp(−d² / (2σ²)) + ε` (or `exp(−d / σ) + ε`) for a squared distance `d2 = 1 − ρ`.
    pub fn weight(&self, d2: Real, sigma: Real) -> Real {
        match self.shape {
            Shape::Gaussian => gaussian(d2, sigma) + self.eps,
            Shape::Exponential => exp(-crate::scalar::sqrt(scalar::max(d2, 0.0)) / sigma) + self.eps,
        }
    }
}

/// `exp(−d² / (2σ²))`, the likelihood without its floor.
pub fn gaussian(d2: Real, sigma: Real) -> Real {
    exp(-scalar::max(d2, 0.0) / (2.0 * sigma * sigma))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_sigma_puts_the_average_particle_spread_e_folds_below_the_best() {
        // Reason: by hand. Best d² = 0.1, mean d² = 0.5, spread 8:
        // 2σ² = 0.4 / 8 = 0.05, offset = 0.1 − 0.05 = 0.05. The best
        // particle gets exp(−(0.1 − 0.05) / 0.05) = e^−1 (as in every mode),
        // the average one exp(−(0.5 − 0.05) / 0.05) = e^−9, i.e. e^−8 of it.
        let l =
            Likelihood { sigma: Sigma::Spread { spread: 8.0, min: 0.001, max: 1.0 }, eps: 0.0, shape: Shape::Gaussian };
        let (sigma, offset) = l.sigma_and_offset(0.1, 0.5);
        assert!((2.0 * sigma * sigma - 0.05).abs() < 1e-6, "{sigma}");
        assert!((offset - 0.05).abs() < 1e-6, "{offset}");
        let (best, mean) = (l.weight(0.1 - offset, sigma), l.weight(0.5 - offset, sigma));
        assert!((best - (-1.0f32).exp()).abs() < 1e-5, "{best}");
        assert!((mean / best - (-8.0f32).exp()).abs() < 1e-6, "{}", mean / best);
        // Bounded: no spread at all falls back to the floor.
        assert_eq!(l.sigma_and_offset(0.3, 0.3).0, 0.001);
    }

    #[test]
    fn adaptive_sigma_gives_best_particle_log_l_minus_one() {
        // Reason: σ² = d_min²/2 makes d_min²/(2σ²) exactly 1 (paper 3, eq. 24).
        // The exponential shape: σ = d_min makes d_min/σ = 1 as well.
        for shape in [Shape::Gaussian, Shape::Exponential] {
            let l = Likelihood { sigma: Sigma::Adaptive { min: 0.01, max: 1.0 }, eps: 0.0, shape };
            for d2 in [0.01f32, 0.05, 0.2, 0.6] {
                let s = l.sigma_for(d2);
                let w = l.weight(d2, s);
                assert!((w.ln() + 1.0).abs() < 1e-3, "{shape:?} d2={d2}: log L = {}", w.ln());
            }
        }
        let l = Likelihood { sigma: Sigma::Adaptive { min: 0.01, max: 1.0 }, eps: 0.0, shape: Shape::Gaussian };
        // Bounds hold at both ends.
        assert_eq!(l.sigma_for(0.0), 0.01);
        assert_eq!(l.sigma_for(4.0), 1.0);
    }

    #[test]
    fn combinations_by_hand() {
        // Reason: product adds squared distances (0.2 + 0.4 = 0.6 of at most
        // 2, similarity 0.7); weighted 0.25/0.75 gives 0.05 + 0.3 = 0.35.
        let p = Combination::Product;
        let s = p.similarity(0.8, 0.6);
        assert!((p.d2_max() * (1.0 - s) - 0.6).abs() < 1e-6);
        let w = Combination::Weighted { colour: 0.25 };
        let s = w.similarity(0.8, 0.6);
        assert!((w.d2_max() * (1.0 - s) - 0.35).abs() < 1e-6);
        assert_eq!(p.similarity(1.0, 1.0), 1.0);
        assert_eq!(w.similarity(0.0, 0.0), 0.0);
    }

    #[test]
    fn fixed_sigma_and_floor() {
        // Reason: hand values: d² = 0.08, σ = 0.2 gives exp(−1) = 0.3679.
        let l = Likelihood { sigma: Sigma::Fixed(0.2), eps: 0.01, shape: Shape::Gaussian };
        assert_eq!(l.sigma_for(0.5), 0.2);
        assert!((l.weight(0.08, 0.2) - (0.36788 + 0.01)).abs() < 1e-4);
        // A hopeless particle still has the floor.
        assert!((l.weight(1.0, 0.2) - 0.01).abs() < 1e-5);
        assert_eq!(gaussian(0.0, 0.2), 1.0);
        // Exponential by hand: d² = 0.04, d = 0.2, σ = 0.2 gives exp(−1).
        let e = Likelihood { shape: Shape::Exponential, ..l };
        assert!((e.weight(0.04, 0.2) - (0.36788 + 0.01)).abs() < 1e-4);
    }
}
