//! The choice between a loop compiled for one pixel format and the
//! general loop, made in one match for every reader of rows.
//!
//! A loop that reads rows can be compiled once per pixel format, with the
//! format's conversion inlined and one bounds test per row, or once for
//! all formats, reading each pixel through the frame's accessors. The
//! first is faster and the second smaller; both read the same values
//! (each reader's tests cross-check the two). A reader says in its
//! [`Loops`] which formats earn a loop of their own, [`Loop::compiled`]
//! says which builds compile which kind of loop, and [`read`] dispatches.

use super::format::PixelFormat;
use super::read::{Gray8, PixelRead, Rgb565, Rgb888, Yuv422};

/// Whether this build is for a bare-metal core.
const BARE_METAL: bool = cfg!(target_os = "none");

/// Whether this build is for a bare-metal core without a floating-point
/// unit (`thumbv6m-none-eabi`, the Cortex-M0+): there software floating
/// point takes most of a frame, so a loop specialised for speed saves a
/// small share of it, while code space is tight.
const LEAN: bool = cfg!(all(target_arch = "arm", target_os = "none", target_abi = "eabi"));

/// What a specialised loop is worth, which decides the builds that compile
/// it. Also used for specialisations other than a format's (a loop per
/// lattice spacing, rows read two samples at a time).
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(crate) enum Loop {
    /// Compiled in every build.
    Always,
    /// It saves time, and nothing else: left out of the lean build, where
    /// the general loop's code is worth more than the time.
    Fast,
    /// For a format no camera delivers to a microcontroller (RGB888 comes
    /// from decoded video): compiled on hosts, left out on bare metal.
    Host,
    /// Never: the general loop serves.
    General,
}

impl Loop {
    /// Whether a loop of this worth is compiled in this build: the one rule.
    #[inline(always)]
    pub(crate) const fn compiled(self) -> bool {
        match self {
            Loop::Always => true,
            Loop::Fast => !LEAN,
            Loop::Host => !BARE_METAL,
            Loop::General => false,
        }
    }
}

/// The formats a reader gives a loop of its own. Each reader spells out
/// every field, so a new pixel format does not compile until every reader
/// has said what it does with it.
#[derive(Copy, Clone, Debug)]
pub(crate) struct Loops {
    /// [`PixelFormat::Rgb565`].
    pub rgb565: Loop,
    /// [`PixelFormat::Rgb888`].
    pub rgb888: Loop,
    /// [`PixelFormat::Yuv422`].
    pub yuv422: Loop,
    /// [`PixelFormat::Gray8`].
    pub gray8: Loop,
    /// The planar formats ([`PixelFormat::I420`], [`PixelFormat::Nv12`])
    /// through the GRAY8 loop: their rows are their luma plane's, so this
    /// is for readers of luma only. A reader of colour needs the chroma
    /// planes and says [`Loop::General`].
    pub planar_luma: Loop,
}

/// A loop over a frame's rows, compiled once per format its [`Loops`]
/// names and once in general.
pub(crate) trait RowReader: Sized {
    /// What the loop returns.
    type Output;
    /// The formats with a loop of their own.
    const LOOPS: Loops;
    /// The loop compiled for rows of format `P`.
    fn rows_of<P: PixelRead>(self) -> Self::Output;
    /// The loop for any format, a pixel at a time through the frame's
    /// accessors.
    fn general(self) -> Self::Output;
}

/// Runs `reader` on rows of `format`: its loop for that format where it has
/// one in this build, its general loop otherwise.
#[inline(always)]
pub(crate) fn read<R: RowReader>(format: PixelFormat, reader: R) -> R::Output {
    read_if(true, format, reader)
}

/// [`read`] where `specialise` holds, the general loop where it does not:
/// for a reader whose loops per format serve only some of its settings.
#[inline(always)]
pub(crate) fn read_if<R: RowReader>(specialise: bool, format: PixelFormat, reader: R) -> R::Output {
    let loops = const { R::LOOPS };
    match format {
        PixelFormat::Rgb565 if loops.rgb565.compiled() && specialise => reader.rows_of::<Rgb565>(),
        PixelFormat::Rgb888 if loops.rgb888.compiled() && specialise => reader.rows_of::<Rgb888>(),
        PixelFormat::Yuv422 if loops.yuv422.compiled() && specialise => reader.rows_of::<Yuv422>(),
        // One arm for GRAY8 and the planar formats' luma plane, so that
        // the loop they share is compiled once.
        PixelFormat::Gray8 | PixelFormat::I420 | PixelFormat::Nv12
            if specialise
                && match format {
                    PixelFormat::Gray8 => loops.gray8.compiled(),
                    _ => loops.planar_luma.compiled(),
                } =>
        {
            reader.rows_of::<Gray8>()
        }
        PixelFormat::Rgb565
        | PixelFormat::Rgb888
        | PixelFormat::Yuv422
        | PixelFormat::Gray8
        | PixelFormat::I420
        | PixelFormat::Nv12 => reader.general(),
    }
}
