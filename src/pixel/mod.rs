//! Pixels: the formats a camera or a decoder delivers, their conversions,
//! and the one place where a frame's format picks the loop that reads its
//! rows.
//!
//! A [`crate::Frame`] checks a buffer against its [`PixelFormat`]; every
//! part of the tracker that reads rows (histograms, the edge map, the
//! template, the correlation filter, the surroundings-motion test) goes
//! through one dispatch (`pixel::read`), which compiles each reader once per format it
//! specialises and once for the rest.

mod convert;
mod dispatch;
mod format;
mod read;

pub(crate) use convert::yuv_centred_to_rgb;
pub use convert::{luma, rgb_to_rgb565, rgb_to_yuv, yuv_to_rgb};
pub(crate) use dispatch::{Loop, Loops, RowReader, read, read_if};
pub use format::{MAX_DIMENSION, PixelFormat};
pub(crate) use read::{Gray8, PixelRead, Rgb565, Rgb888, Yuv422};
