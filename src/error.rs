//! Typed errors. Nothing in the core panics on bad input: every check that
//! input can fail returns one of these.

use crate::scalar::Real;
use core::fmt;

/// Why a buffer could not be viewed as a [`crate::Frame`].
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FrameError {
    /// Width or height is zero.
    ZeroSize,
    /// Width or height exceeds [`crate::pixel::MAX_DIMENSION`].
    TooLarge {
        /// The requested width.
        width: usize,
        /// The requested height.
        height: usize,
    },
    /// The stride is shorter than one row of pixels.
    StrideTooSmall {
        /// The requested stride in bytes.
        stride: usize,
        /// The bytes one row of pixels needs.
        row_bytes: usize,
    },
    /// The buffer is shorter than the dimensions require.
    BufferTooSmall {
        /// Bytes needed (`usize::MAX` if the product overflows).
        needed: usize,
        /// Bytes given.
        got: usize,
    },
    /// YUV 4:2:2 stores pixels in pairs, so the width must be even.
    OddYuvWidth {
        /// The requested width.
        width: usize,
    },
    /// YUV 4:2:0 shares one chroma sample among 2x2 pixels, so the width
    /// and the height must be even.
    OddChromaSize {
        /// The requested width.
        width: usize,
        /// The requested height.
        height: usize,
    },
    /// A chroma plane's stride is shorter than one row of its samples.
    ChromaStrideTooSmall {
        /// Which plane.
        plane: ChromaPlane,
        /// The plane's stride in bytes.
        stride: usize,
        /// The bytes one row of its samples needs.
        row_bytes: usize,
    },
    /// A chroma plane's buffer is shorter than its rows need.
    ChromaTooSmall {
        /// Which plane.
        plane: ChromaPlane,
        /// Bytes needed (`usize::MAX` if the product overflows).
        needed: usize,
        /// Bytes given.
        got: usize,
    },
}

/// A chroma plane of a planar YUV 4:2:0 frame, as [`FrameError`] names it.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ChromaPlane {
    /// The U (Cb) plane of I420.
    U,
    /// The V (Cr) plane of I420.
    V,
    /// The interleaved U, V plane of NV12.
    Uv,
}

/// What is wrong with one configuration field.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ParamProblem {
    /// NaN or infinite.
    NonFinite,
    /// Outside its documented range.
    OutOfRange,
    /// Asks for a technique this build of the crate leaves out: enable the
    /// named Cargo feature.
    NotBuilt {
        /// The Cargo feature that builds it in.
        feature: &'static str,
    },
}

/// A rejected [`crate::Config`] field.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ConfigError {
    /// The field's name, as spelled in [`crate::Config`].
    pub field: &'static str,
    /// What is wrong with it.
    pub problem: ParamProblem,
}

/// Why a box cannot be tracked in a frame.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RegionError {
    /// A coordinate or size is NaN or infinite.
    NonFinite,
    /// Width or height is zero or negative.
    EmptyBox,
    /// Wider or taller than the frame.
    LargerThanFrame,
    /// The box does not overlap the frame at all.
    OutsideFrame,
    /// The box's ellipse contains no pixel of the frame, so it has no colour
    /// histogram to learn.
    NoPixels,
}

/// Every error the tracker can return.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// The frame view is inconsistent.
    Frame(FrameError),
    /// The configuration is invalid.
    Config(ConfigError),
    /// The initial box is unusable.
    Region(RegionError),
    /// [`crate::Tracker::step`] was called before the tracker was
    /// initialised from a box or given a target to search for.
    NotInitialised,
    /// The frame's size differs from the frame the tracker was initialised on.
    /// Re-initialise to change resolution.
    FrameSizeChanged {
        /// The size the tracker was initialised with.
        expected: (usize, usize),
        /// The size of the frame given.
        got: (usize, usize),
    },
    /// [`crate::Group::add`] on a group that holds as many targets as it can.
    GroupFull {
        /// How many targets the group holds.
        capacity: usize,
    },
    /// No target of the group has this identity (never given, or removed).
    UnknownTarget {
        /// The identity asked for ([`crate::TargetId`]'s number).
        id: u16,
    },
}

impl From<FrameError> for Error {
    fn from(e: FrameError) -> Self {
        Error::Frame(e)
    }
}

impl From<ConfigError> for Error {
    fn from(e: ConfigError) -> Self {
        Error::Config(e)
    }
}

impl From<RegionError> for Error {
    fn from(e: RegionError) -> Self {
        Error::Region(e)
    }
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            FrameError::ZeroSize => write!(f, "frame width or height is zero"),
            FrameError::TooLarge { width, height } => {
                write!(f, "frame {width}x{height} exceeds the maximum of {0}x{0}", crate::pixel::MAX_DIMENSION)
            }
            FrameError::StrideTooSmall { stride, row_bytes } => {
                write!(f, "stride {stride} is shorter than a row of {row_bytes} bytes")
            }
            FrameError::BufferTooSmall { needed, got } => {
                write!(f, "frame buffer holds {got} bytes but the dimensions need {needed}")
            }
            FrameError::OddYuvWidth { width } => write!(f, "YUV 4:2:2 needs an even width, got {width}"),
            FrameError::OddChromaSize { width, height } => {
                write!(f, "YUV 4:2:0 needs an even width and height, got {width}x{height}")
            }
            FrameError::ChromaStrideTooSmall { plane, stride, row_bytes } => {
                write!(f, "{plane:?} plane stride {stride} is shorter than a row of {row_bytes} bytes")
            }
            FrameError::ChromaTooSmall { plane, needed, got } => {
                write!(f, "{plane:?} plane holds {got} bytes but the dimensions need {needed}")
            }
        }
    }
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.problem {
            ParamProblem::NonFinite => write!(f, "config field `{}` is NaN or infinite", self.field),
            ParamProblem::OutOfRange => write!(f, "config field `{}` is out of range", self.field),
            ParamProblem::NotBuilt { feature } => {
                write!(f, "config field `{}` needs pftrack's `{feature}` feature", self.field)
            }
        }
    }
}

impl fmt::Display for RegionError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = match self {
            RegionError::NonFinite => "box has a NaN or infinite coordinate",
            RegionError::EmptyBox => "box has zero or negative width or height",
            RegionError::LargerThanFrame => "box is larger than the frame",
            RegionError::OutsideFrame => "box lies entirely outside the frame",
            RegionError::NoPixels => "box's ellipse contains no pixel of the frame",
        };
        f.write_str(s)
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Frame(e) => write!(f, "bad frame: {e}"),
            Error::Config(e) => write!(f, "bad configuration: {e}"),
            Error::Region(e) => write!(f, "bad box: {e}"),
            Error::NotInitialised => write!(f, "tracker not initialised: call init or search first"),
            Error::FrameSizeChanged { expected, got } => write!(
                f,
                "frame is {}x{} but the tracker was initialised on {}x{}",
                got.0, got.1, expected.0, expected.1
            ),
            Error::GroupFull { capacity } => write!(f, "the group already holds {capacity} targets, its capacity"),
            Error::UnknownTarget { id } => write!(f, "the group has no target {id}"),
        }
    }
}

impl core::error::Error for FrameError {}
impl core::error::Error for ConfigError {}
impl core::error::Error for RegionError {}
impl core::error::Error for Error {}

/// A configuration's checks, made in order, of which the first to fail is
/// the one reported. Each check is a call with nothing after it (a failing
/// check records its error unless an earlier one has), not a branch and an
/// early return: a configuration has about eighty, checked once, and the
/// early returns took flash (docs/performance.md).
pub(crate) struct Checks(Result<(), ConfigError>);

impl Checks {
    /// No check made yet.
    pub(crate) const fn new() -> Self {
        Checks(Ok(()))
    }

    /// The first problem recorded, if any.
    pub(crate) fn result(self) -> Result<(), ConfigError> {
        self.0
    }

    /// Records `e` unless an earlier check failed.
    #[inline(never)]
    pub(crate) fn fail(&mut self, e: ConfigError) {
        if self.0.is_ok() {
            self.0 = Err(e);
        }
    }

    /// `v` must be finite and in `[lo, hi]`. The one range check of every
    /// configuration in the crate. Out of line: inlined at each of its
    /// calls, it would take flash for no speed that matters (a
    /// configuration is checked once).
    #[inline(never)]
    pub(crate) fn range(&mut self, field: &'static str, v: Real, lo: Real, hi: Real) {
        if !v.is_finite() {
            self.fail(ConfigError { field, problem: ParamProblem::NonFinite });
        } else if !(v >= lo && v <= hi) {
            self.fail(ConfigError { field, problem: ParamProblem::OutOfRange });
        }
    }

    /// A share: `v` finite and in `[0, 1]`. Most of a configuration's
    /// numbers are, and the call without the bounds takes less flash.
    #[inline(never)]
    pub(crate) fn share(&mut self, field: &'static str, v: Real) {
        self.range(field, v, 0.0, 1.0);
    }

    /// `v` finite and in `(0, hi]`.
    #[inline(never)]
    pub(crate) fn positive(&mut self, field: &'static str, v: Real, hi: Real) {
        self.range(field, v, 0.0, hi);
        self.out_of_range_if(v <= 0.0, field);
    }

    /// `field` is out of its range where `bad`.
    #[inline(never)]
    pub(crate) fn out_of_range_if(&mut self, bad: bool, field: &'static str) {
        if bad {
            self.fail(ConfigError { field, problem: ParamProblem::OutOfRange });
        }
    }
}
