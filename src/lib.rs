//! A `no_std`, allocation-free colour particle-filter object tracker for
//! small ARM devices.
//!
//! ```
//! use pftrack::{BoundingBox, Config, Frame, PixelFormat, TrackState, Tracker};
//!
//! // A grey 64x48 RGB888 frame with a red 12x10 target at (20, 15).
//! let mut pixels = [120u8; 64 * 48 * 3];
//! for y in 15..25 {
//!     for x in 20..32 {
//!         pixels[(y * 64 + x) * 3..][..3].copy_from_slice(&[220, 30, 30]);
//!     }
//! }
//! let frame = Frame::packed(&pixels, 64, 48, PixelFormat::Rgb888)?;
//! let mut tracker: Tracker<50> = Tracker::new(Config::default(), 7)?;
//! tracker.init(&frame, BoundingBox::new(20.0, 15.0, 12.0, 10.0))?;
//! let estimate = tracker.step(&frame)?;
//! assert_eq!(estimate.state, TrackState::Tracking);
//! // The target stands out from its surroundings and matches what was learnt.
//! assert!(estimate.confidence > 0.9);
//! # Ok::<(), pftrack::Error>(())
//! ```
//!
//! The method is the adaptive colour particle filter of Nummiaro, Koller-Meier
//! and Van Gool: the target is an upright ellipse whose kernel-weighted colour
//! and edge-orientation histograms are compared with a model by the
//! Bhattacharyya coefficient; a set of `N` hypotheses moves with damped
//! constant-velocity dynamics, is weighted and resampled; the estimate's size
//! and shape are searched against the target's surroundings
//! ([`foreground`]); a confidence (the probability that the estimate is on
//! the target, [`on_target`]) drives explicit searching / tracking / lost
//! states and gates the model's adaptation.
//!
//! # Shape
//! - [`Frame`]: a checked view of a raw camera buffer (RGB565, RGB888,
//!   YUV 4:2:2, GRAY8, with stride).
//! - [`Histogram`], [`Model`]: integer kernel-weighted histograms and the
//!   target model with its Bhattacharyya coefficient.
//! - [`Tracker`]: the filter and its life cycle, configured by [`Config`].
//! - [`Group`]: several targets at once, each with its identity, sharing
//!   one working memory and kept apart.
//! - [`MeanShift`]: the single-hypothesis baselines (mean shift, Kalman mean
//!   shift) on the same frames, histograms and estimates.
//!
//! # Further reading
//! The repository's `docs/` folder: `method.md` (how it works),
//! `accuracy.md` (results on real video, the ablation table, the OpenCV
//! comparison), `performance.md` (the size and speed audits),
//! `on-the-metal.md` (QEMU, real boards, ARMv6 Linux), `robustness.md`
//! (errors, fuzzing, soak) and `fixtures.md` (the test scenes).
//!
//! # Numbers
//! One convention, in [`scalar`]: integers per pixel, `f32` per particle,
//! using only operations that are bit-identical on x86_64 and ARM, so a seeded
//! run gives the same track on the host and on a microcontroller.
//!
//! # Panics
//! None on any input. Constructors validate and return [`Error`]; the
//! per-pixel and per-particle paths use checked slice access and saturating or
//! wrapping arithmetic where a bound is not evident. The only `assert!`s are
//! compile-time checks on the const generic capacities.
//!
#![cfg_attr(not(test), no_std)]

pub(crate) mod apart;
pub mod bins;
pub mod boundary;
pub mod colour;
pub mod config;
pub(crate) mod correlation;
pub(crate) mod cue;
pub mod edges;
pub mod error;
pub mod estimate;
pub mod filter;
#[cfg(feature = "follower")]
pub mod follower;
pub mod foreground;
pub mod frame;
pub mod geometry;
pub mod group;
pub mod histogram;
pub mod likelihood;
pub mod meanshift;
pub(crate) mod motion;
pub mod pixel;
pub mod region;
pub mod scalar;
pub(crate) mod table;
pub mod template;
#[cfg(test)]
mod testing;
pub mod tracker;

pub use boundary::BoundaryCue;
pub use colour::Binning;
pub use config::{Config, Life, LostSearch, ModelUpdate, Redetect, ShiftSearch, SizeSearch, TableMode, TemplateCue};
pub use correlation::{CorrelationCue, GradientCue};
pub use edges::{EDGE_SUPPORT_WORDS, EdgeCue, EdgeMap, EdgeParams, MAX_EDGE_BINS};
pub use error::{ChromaPlane, ConfigError, Error, FrameError, ParamProblem, RegionError};
pub use estimate::{Diagnostics, Estimate, Event, Trace, TrackState};
pub use filter::{Dynamics, Particle, Resampling};
pub use foreground::BackgroundWeight;
pub use frame::{Frame, Plane};
pub use geometry::{BoundingBox, Ellipse};
pub use group::{Added, Group, TargetId, Tracked, Tracks};
pub use histogram::{Histogram, Model, SUPPORT_WORDS, Similarity};
pub use likelihood::{Combination, Likelihood, Shape, Sigma};
pub use meanshift::{MeanShift, MeanShiftConfig, Prediction};
pub use pixel::PixelFormat;
pub use region::Sampling;
pub use scalar::Real;
pub use tracker::{ScalePrior, Tracker, on_target, size_change};
