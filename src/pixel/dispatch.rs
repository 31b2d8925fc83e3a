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
/// every field, or takes a kind of reader that does ([`Loops::camera_luma`]),
/// so a new pixel format does not compile until every reader has said what
/// it does with it.
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

impl Loops {
    /// A reader of luma with loops of its own, worth `worth`, for the
    /// formats whose pixels a row holds whole and cameras deliver (RGB565,
    /// GRAY8 and the planar formats' luma plane); RGB888 and YUV 4:2:2 read
    /// a pixel at a time.
    pub(crate) const fn camera_luma(worth: Loop) -> Loops {
        Loops { rgb565: worth, rgb888: Loop::General, yuv422: Loop::General, gray8: worth, planar_luma: worth }
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::Frame;

    /// Every format, in code order. `position` matches exhaustively, so a
    /// new format does not compile here until it is listed.
    const ALL: [PixelFormat; 6] = [
        PixelFormat::Rgb565,
        PixelFormat::Rgb888,
        PixelFormat::Yuv422,
        PixelFormat::Gray8,
        PixelFormat::I420,
        PixelFormat::Nv12,
    ];

    fn position(f: PixelFormat) -> usize {
        match f {
            PixelFormat::Rgb565 => 0,
            PixelFormat::Rgb888 => 1,
            PixelFormat::Yuv422 => 2,
            PixelFormat::Gray8 => 3,
            PixelFormat::I420 => 4,
            PixelFormat::Nv12 => 5,
        }
    }

    /// Reads row `y` of a frame as lumas (`colour` false) or colours, by
    /// whichever loop the dispatch picks, and says which it was.
    struct Probe<'f, 'r, const COLOUR: bool> {
        frame: &'r Frame<'f>,
        y: usize,
    }

    impl<const COLOUR: bool> RowReader for Probe<'_, '_, COLOUR> {
        type Output = (bool, Vec<[u8; 3]>);
        // Every loop there is; a reader of colour cannot read the planar
        // formats' chroma through a row of their luma plane.
        const LOOPS: Loops = Loops {
            rgb565: Loop::Always,
            rgb888: Loop::Always,
            yuv422: Loop::Always,
            gray8: Loop::Always,
            planar_luma: if COLOUR { Loop::General } else { Loop::Always },
        };

        fn rows_of<P: PixelRead>(self) -> Self::Output {
            let row = self.frame.row(self.y).unwrap_or(&[]);
            let read = |x| if COLOUR { P::rgb(row, x) } else { P::luma(row, x).map(|l| [l; 3]) };
            (true, (0..self.frame.width()).filter_map(read).collect())
        }

        fn general(self) -> Self::Output {
            let (f, y) = (self.frame, self.y);
            let read = |x| if COLOUR { f.rgb(x, y) } else { f.luma(x, y).map(|l| [l; 3]) };
            (false, (0..f.width()).filter_map(read).collect())
        }
    }

    #[test]
    fn every_format_reaches_a_loop_that_reads_what_the_frame_holds() {
        // Reason: the frame's own accessors (`Frame::rgb`, `Frame::luma`)
        // define each format's pixels; whatever loop the one dispatch picks
        // for a format must read the same values, for readers of luma and
        // of colour alike. A format given no loop would take the general
        // one (checked: only the planar formats' colour does).
        for (i, &format) in ALL.iter().enumerate() {
            assert_eq!(position(format), i);
            let (w, h) = (6, 4);
            let bytes: Vec<u8> = (0..format.frame_bytes(w * format.bytes_per_pixel(), h).unwrap_or(0))
                .map(|i| (i * 37 % 251) as u8)
                .collect();
            let frame = Frame::packed(&bytes, w, h, format).unwrap();
            for y in 0..h {
                let (own, lumas) = read(format, Probe::<false> { frame: &frame, y });
                assert!(own, "{format:?}: lumas through a loop of their own");
                let want: Vec<[u8; 3]> = (0..w).map(|x| [frame.luma(x, y).unwrap(); 3]).collect();
                assert_eq!(lumas, want, "{format:?} row {y}: lumas");
                let (own, rgb) = read(format, Probe::<true> { frame: &frame, y });
                assert_eq!(own, !format.is_planar(), "{format:?}: colours through a loop of their own");
                let want: Vec<[u8; 3]> = (0..w).map(|x| frame.rgb(x, y).unwrap()).collect();
                assert_eq!(rgb, want, "{format:?} row {y}: colours");
                // Not specialising takes the general loop.
                assert!(!read_if(false, format, Probe::<true> { frame: &frame, y }).0);
            }
        }
    }
}
