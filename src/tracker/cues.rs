//! The tracker's cues with state of their own, listed once: a cue is added
//! by its module (see [`crate::cue`]) and one line in [`cues!`]'s list.

use crate::config::Config;
use crate::cue::{Cue, Freedom, Verdict};
use crate::filter::Particle;
use crate::frame::Frame;
use crate::geometry::Ellipse;
use crate::scalar::Real;

/// Declares [`Cues`]: one field per cue, with the [`Config`] field its
/// settings come from, and the hooks that call each cue in list order.
macro_rules! cues {
    ($($name:ident: $ty:ty = $settings:expr;)*) => {
        /// One value of each cue.
        #[derive(Clone, Debug)]
        pub(super) struct Cues {
            $($name: $ty,)*
        }

        impl Cues {
            /// Every cue, empty.
            pub(super) const fn new() -> Self {
                Cues { $($name: <$ty>::new(),)* }
            }

            /// [`Cue::start`] of every cue.
            pub(super) fn start(&mut self, cfg: &Config, frame: &Frame<'_>, e: &Ellipse, work: &mut [u16]) {
                $(Cue::start(&mut self.$name, ($settings)(cfg).as_ref(), frame, e, work);)*
            }

            /// [`Cue::rescore`] of every cue that is on.
            pub(super) fn rescore<const N: usize>(
                &mut self,
                cfg: &Config,
                frame: &Frame<'_>,
                (particles, similarities): (&[Particle; N], &mut [Real; N]),
                n: usize,
                half_axes: (Real, Real),
                work: &mut [u16],
            ) {
                $(if let Some(s) = ($settings)(cfg) {
                    Cue::rescore(&mut self.$name, &s, frame, (particles, &mut *similarities), n, half_axes, work);
                })*
            }

            /// [`Cue::place`] of every cue that is on; the last response's
            /// peak-to-sidelobe ratio, or 0.
            pub(super) fn place<const N: usize>(
                &mut self,
                cfg: &Config,
                frame: &Frame<'_>,
                (ellipse, particles): (&mut Ellipse, &mut [Particle; N]),
                freedom: Freedom,
                work: &mut [u16],
            ) -> Real {
                let mut psr = 0.0;
                $(if let Some(s) = ($settings)(cfg)
                    && let Some(p) = Cue::place(&mut self.$name, &s, frame, (&mut *ellipse, &mut *particles), freedom, work)
                {
                    psr = p;
                })*
                psr
            }

            /// Whether some cue that is on counts the estimate `e` as a miss
            /// ([`Cue::miss`], every such cue asked).
            pub(super) fn miss(&mut self, cfg: &Config, frame: &Frame<'_>, e: &Ellipse, tracking: bool) -> bool {
                let mut miss = false;
                $(if let Some(s) = ($settings)(cfg) {
                    miss |= Cue::miss(&mut self.$name, &s, frame, e, tracking);
                })*
                miss
            }

            /// [`Cue::adapt`] of every cue that is on.
            pub(super) fn adapt(&mut self, cfg: &Config, frame: &Frame<'_>, e: &Ellipse, verdict: Verdict, work: &mut [u16]) {
                $(if let Some(s) = ($settings)(cfg) {
                    Cue::adapt(&mut self.$name, &s, frame, e, verdict, work);
                })*
            }
        }
    };
}

cues! {
    correlation: crate::correlation::Correlation = |c: &Config| c.correlation;
    gradient: crate::correlation::Gradient = |c: &Config| c.gradient;
    motion: crate::motion::SceneMotion = |c: &Config| crate::motion::settings(c.scene_motion);
}
