//! A deterministic scene generator: synthetic video with exact ground truth.
//!
//! Every scene is a static textured background (a camera on a tripod), a
//! non-rigid striped target whose outline wobbles frame to frame, and
//! whatever the scene is about: smooth or abrupt motion, scale change,
//! occlusion, an illumination ramp, a same-coloured distractor, or the target
//! leaving the frame and coming back. The ground truth is the box of the
//! target's nominal ellipse, and the visibility is counted pixel by pixel.
//!
//! The same spec always produces the same bytes (seeded xoshiro, no clocks),
//! which a test checks against the committed fixtures.

use crate::fixture::{Fixture, FixtureFrame, RecordMeta};
use pftrack::frame::{rgb_to_rgb565, rgb_to_yuv};
use pftrack::{BoundingBox, PixelFormat};
use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use std::f64::consts::PI;

/// What a scene exercises.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Story {
    /// Smooth curved motion while the target grows by 40%.
    SmoothScale,
    /// Three sudden jumps, under a lighting ramp down to 60%.
    AbruptIllumination,
    /// An opaque bar slides over the target: partial, full, partial occlusion.
    Occlusion,
    /// A decoy with the same colours (stripes turned 90°) crosses the target's
    /// path head on, passing behind it.
    Distractor,
    /// The target leaves through the right edge, stays away, and comes back.
    ExitReturn,
    /// Smooth motion in GRAY8: only brightness to go on.
    GraySmooth,
    /// The target shrinks to half its width and height while it drifts.
    Shrink,
    /// The target turns from tall to wide: its aspect ratio (width over
    /// height) doubles, from 0.7 to 1.4, at a constant area.
    Turn,
    /// The target leaves through the right edge and comes back in through
    /// the left one, on the other side of the frame.
    CrossOver,
    /// The target zigzags across the frame at most of its own width a
    /// frame, turning back at each side: faster than a filter whose noise
    /// scales with the target's size alone can follow.
    Fast,
    /// The speed audit's scene: a round target of 1/8 of the frame width
    /// (40x40 px in QVGA) on a smooth path, at any resolution.
    Audit,
    /// Two targets of the same colours and stripes cross on one line, the
    /// faster one in front.
    Crossing,
    /// Three targets of different colours, apart; the third leaves through
    /// the right edge, stays away and comes back.
    ThreeTargets,
    /// Two targets of different colours start side by side, touching, and
    /// move apart.
    Touching,
    /// The audit's scene with this many targets (2 or 3) of its size, of
    /// different colours, on paths of their own.
    AuditTargets(u8),
    /// The camera pans: the whole background moves 8 px a frame to the
    /// left while the target moves the other way across the frame.
    Pan,
    /// A 12x12 target zigzags at 10 px a frame, most of its width, across
    /// the textured background.
    SmallFast,
    /// The target turns half a turn over the scene, its stripes and its
    /// elongated outline with it (the truth is the turned ellipse's box).
    Rotate,
    /// Three decoys in the target's colours, in the same proportions, that
    /// differ from it only in texture (stripes the other way, a
    /// checkerboard, rings), pass close to it.
    LookAlikes,
}

/// A scene to generate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneSpec {
    /// File stem of the fixture.
    pub name: &'static str,
    /// What happens in it.
    pub story: Story,
    /// Pixel format of the frames.
    pub format: PixelFormat,
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Number of frames.
    pub frames: usize,
    /// Seed of the background texture and sensor noise.
    pub seed: u64,
}

/// The committed fixture set: together they cover every item the generator
/// promises, in every pixel format.
pub fn catalogue() -> Vec<SceneSpec> {
    let s = |name, story, format, frames, seed| SceneSpec { name, story, format, width: 128, height: 96, frames, seed };
    vec![
        s("smooth_scale", Story::SmoothScale, PixelFormat::Rgb565, 36, 1),
        s("abrupt_illumination", Story::AbruptIllumination, PixelFormat::Yuv422, 30, 2),
        s("occlusion", Story::Occlusion, PixelFormat::Rgb565, 44, 3),
        s("distractor", Story::Distractor, PixelFormat::Rgb888, 44, 4),
        s("exit_return", Story::ExitReturn, PixelFormat::Rgb565, 48, 5),
        s("gray_smooth", Story::GraySmooth, PixelFormat::Gray8, 30, 6),
        s("shrink", Story::Shrink, PixelFormat::Rgb565, 40, 8),
        s("turn", Story::Turn, PixelFormat::Yuv422, 40, 9),
        s("cross_over", Story::CrossOver, PixelFormat::Rgb565, 50, 10),
        s("occlusion_i420", Story::Occlusion, PixelFormat::I420, 44, 11),
        s("fast", Story::Fast, PixelFormat::Rgb565, 40, 12),
        s("pan", Story::Pan, PixelFormat::Rgb565, 40, 16),
        s("small_fast", Story::SmallFast, PixelFormat::Yuv422, 40, 17),
        s("rotate", Story::Rotate, PixelFormat::Rgb888, 30, 18),
        s("look_alikes", Story::LookAlikes, PixelFormat::Rgb565, 44, 19),
        // Several targets each: apart, so that the tools that take one
        // target a fixture read `fixtures/*.pft` as before.
        s("groups/crossing", Story::Crossing, PixelFormat::Rgb565, 48, 13),
        s("groups/three_targets", Story::ThreeTargets, PixelFormat::Rgb888, 56, 14),
        s("groups/touching", Story::Touching, PixelFormat::Yuv422, 30, 15),
    ]
}

/// The audits' scenes (generated on demand, not committed): QVGA RGB565
/// with a 40x40 target, alone and with one or two more (the group audit),
/// and the same scene in QQVGA GRAY8 (the speed audit), QQVGA RGB565 and
/// QVGA GRAY8 (the largest frames of each format the STM32F405 build holds).
pub fn audit_catalogue() -> Vec<SceneSpec> {
    let audit = |name, format, width, height| SceneSpec {
        name,
        story: Story::Audit,
        format,
        width,
        height,
        frames: 20,
        seed: 7,
    };
    vec![
        audit("audit_qqvga_rgb565", PixelFormat::Rgb565, 160, 120),
        audit("audit_qvga_gray8", PixelFormat::Gray8, 320, 240),
        SceneSpec {
            name: "audit_qvga_rgb565",
            story: Story::Audit,
            format: PixelFormat::Rgb565,
            width: 320,
            height: 240,
            frames: 20,
            seed: 7,
        },
        SceneSpec {
            name: "audit_qvga_rgb565_2",
            story: Story::AuditTargets(2),
            ..audit("", PixelFormat::Rgb565, 320, 240)
        },
        SceneSpec {
            name: "audit_qvga_rgb565_3",
            story: Story::AuditTargets(3),
            ..audit("", PixelFormat::Rgb565, 320, 240)
        },
        SceneSpec {
            name: "audit_qqvga_gray8",
            story: Story::Audit,
            format: PixelFormat::Gray8,
            width: 160,
            height: 120,
            frames: 20,
            seed: 7,
        },
    ]
}

/// The throughput benchmark's scene (`tools/run-throughput`, generated on
/// demand): the audit story at 640x360 in I420, as a video decoder hands
/// frames over, 300 frames (ten seconds at 30 fps).
pub fn throughput_scene() -> SceneSpec {
    SceneSpec {
        name: "throughput_360p_i420",
        story: Story::Audit,
        format: PixelFormat::I420,
        width: 640,
        height: 360,
        frames: 300,
        seed: 7,
    }
}

/// Colours of the target and the distractor.
const BODY: [f64; 3] = [215.0, 45.0, 35.0];
const STRIPE: [f64; 3] = [235.0, 200.0, 40.0];
const OCCLUDER: [f64; 3] = [70.0, 85.0, 115.0];

/// Colours of the other targets of a scene with several, by kind: body
/// and stripe (kind 0 is the target's own, [`BODY`] and [`STRIPE`]).
const KINDS: [[[f64; 3]; 2]; 3] =
    [[BODY, STRIPE], [[35.0, 60.0, 215.0], [235.0, 235.0, 235.0]], [[240.0, 140.0, 30.0], [110.0, 30.0, 150.0]]];

/// Another target of a scene with several.
#[derive(Debug, Clone, Copy)]
struct Blob {
    cx: f64,
    cy: f64,
    a: f64,
    b: f64,
    /// Its colours, in [`KINDS`].
    kind: usize,
}

/// The texture of a target or decoy in the target's colours.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Pattern {
    /// Five bands across, horizontal (the target's own) or vertical.
    Stripes { horizontal: bool },
    /// Bands both ways, alternating like a checkerboard.
    Checker,
    /// Concentric rings, as wide as the stripes.
    Rings,
}

/// A decoy: a blob of the target's size and colours.
#[derive(Debug, Clone, Copy)]
struct Decoy {
    cx: f64,
    cy: f64,
    pattern: Pattern,
    /// Offset of its outline's wobble from the target's, in frames.
    phase: usize,
}

/// Where everything is in frame `t`.
#[derive(Debug, Clone, Copy)]
struct Layout {
    /// Target centre and nominal half axes.
    cx: f64,
    cy: f64,
    a: f64,
    b: f64,
    /// Optional opaque occluder rectangle: x0, y0, x1, y1 (exclusive).
    occluder: Option<[f64; 4]>,
    /// Decoys in the target's colours and size.
    decoys: [Option<Decoy>; 3],
    /// The target's turn from its upright pose, radians.
    angle: f64,
    /// How far the view has panned right: the background is drawn from
    /// this many pixels further along.
    pan: usize,
    /// Global illumination gain.
    gain: f64,
    /// The other targets of a scene with several, drawn behind the first
    /// in this order.
    others: [Option<Blob>; 2],
}

fn layout(story: Story, t: usize, n: usize, (w, h): (usize, usize)) -> Layout {
    let tf = t as f64;
    let base = Layout {
        cx: 64.0,
        cy: 48.0,
        a: 11.0,
        b: 13.0,
        occluder: None,
        decoys: [None; 3],
        angle: 0.0,
        pan: 0,
        gain: 1.0,
        others: [None; 2],
    };
    match story {
        Story::SmoothScale | Story::GraySmooth => {
            let s = 1.0 + 0.4 * tf / (n as f64 - 1.0).max(1.0);
            Layout {
                cx: 64.0 + 30.0 * (2.0 * PI * tf / 36.0).sin(),
                cy: 48.0 + 14.0 * (2.0 * PI * tf / 24.0 + 0.5).sin(),
                a: 10.0 * if story == Story::SmoothScale { s } else { 1.2 },
                b: 13.0 * if story == Story::SmoothScale { s } else { 1.2 },
                ..base
            }
        }
        Story::AbruptIllumination => {
            // Piecewise-constant position with a slow drift, and three jumps.
            let jumps = [(8usize, 12.0, -6.0), (16, -14.0, 8.0), (23, 10.0, 5.0)];
            let (mut cx, mut cy) = (52.0 + 0.5 * tf, 46.0);
            for (at, dx, dy) in jumps {
                if t >= at {
                    cx += dx;
                    cy += dy;
                }
            }
            Layout { cx, cy, gain: 1.0 - 0.4 * tf / (n as f64 - 1.0).max(1.0), ..base }
        }
        Story::Occlusion => {
            let left = 75.0 - tf;
            Layout { cx: 40.0 + 1.2 * tf, cy: 50.0, occluder: Some([left, 20.0, left + 34.0, 80.0]), ..base }
        }
        Story::Distractor => {
            let decoy =
                Decoy { cx: 100.0 - 1.5 * tf, cy: 58.0, pattern: Pattern::Stripes { horizontal: false }, phase: 5 };
            Layout { cx: 30.0 + 1.5 * tf, cy: 40.0, decoys: [Some(decoy), None, None], ..base }
        }
        Story::Pan => {
            // In frame coordinates the target moves right 1.5 px a frame
            // while everything behind it moves left 8: 9.5 px a frame
            // against the background.
            Layout { cx: 30.0 + 1.5 * tf, cy: 48.0 + 10.0 * (tf / 6.0).sin(), pan: 8 * t, ..base }
        }
        Story::SmallFast => {
            // A triangle wave between x = 10 and 118 at 10 px a frame, and a
            // vertical swing of ±24 px.
            let cx = zigzag(tf, 10.0, 118.0, 10.0);
            Layout { cx, cy: 48.0 + 24.0 * (2.0 * PI * tf / 17.0).sin(), a: 6.0, b: 6.0, ..base }
        }
        Story::Rotate => {
            // Half a turn over the scene, while drifting slowly.
            let angle = PI * tf / (n as f64 - 1.0).max(1.0);
            Layout { cx: 52.0 + 0.8 * tf, cy: 48.0 + 6.0 * (tf / 8.0).sin(), a: 16.0, b: 11.0, angle, ..base }
        }
        Story::LookAlikes => {
            // The target crosses the middle. A decoy with its stripes the
            // other way comes the other way along the same line and passes
            // behind it; a checkerboard passes above, its outline a pixel
            // from the target's; rings ride alongside below, as close.
            let decoy = |cx, cy, pattern, phase| Some(Decoy { cx, cy, pattern, phase });
            let cy = 48.0 + 3.0 * (tf / 5.0).sin();
            Layout {
                cx: 24.0 + 1.4 * tf,
                cy,
                decoys: [
                    decoy(110.0 - 1.6 * tf, 48.0, Pattern::Stripes { horizontal: false }, 5),
                    decoy(100.0 - 1.2 * tf, cy - 27.0, Pattern::Checker, 9),
                    decoy(14.0 + 1.3 * tf, cy + 27.0, Pattern::Rings, 13),
                ],
                ..base
            }
        }
        Story::Fast => {
            // A triangle wave between x = 22 and 106 at 18 px a frame (the
            // target is 22 px wide), and a vertical swing of ±20 px.
            let cx = zigzag(tf, 22.0, 106.0, 18.0);
            Layout { cx, cy: 48.0 + 20.0 * (2.0 * PI * tf / 14.0).sin(), ..base }
        }
        Story::Crossing => {
            // The first at 2 px a frame, the second at 1.5, meeting at
            // frame 27; 22 px wide, both, and 68 px apart at the end.
            let other = Blob { cx: 110.0 - 1.5 * tf, cy: 48.0, a: 11.0, b: 13.0, kind: 0 };
            Layout { cx: 14.0 + 2.0 * tf, others: [Some(other), None], ..base }
        }
        Story::ThreeTargets => {
            // The third leaves through the right edge by frame 16, is out
            // of the frame for frames 16 to 27, and is wholly back from
            // frame 34.
            let x3 = if t < 16 {
                82.0 + 3.5 * tf
            } else if t < 28 {
                200.0
            } else {
                139.0 - 3.0 * (tf - 28.0)
            };
            let second = Blob { cx: 104.0 - 0.4 * tf, cy: 24.0, a: 10.0, b: 10.0, kind: 1 };
            let third = Blob { cx: x3, cy: 74.0, a: 10.0, b: 12.0, kind: 2 };
            Layout {
                cx: 24.0 + 0.9 * tf,
                cy: 44.0 + 5.0 * (tf * 0.25).sin(),
                others: [Some(second), Some(third)],
                ..base
            }
        }
        Story::Touching => {
            // Side by side with their outlines touching (22 px wide, 22 px
            // apart), moving apart at 1.5 px a frame each.
            let other = Blob { cx: 75.0 + 1.5 * tf, cy: 50.0, a: 11.0, b: 13.0, kind: 1 };
            Layout { cx: 53.0 - 1.5 * tf, cy: 50.0, others: [Some(other), None], ..base }
        }
        Story::AuditTargets(count) => {
            let one = layout(Story::Audit, t, n, (w, h));
            let (w, h) = (w as f64, h as f64);
            let r = w / 16.0;
            let second = Blob {
                cx: 0.25 * w + 0.1 * w * (2.0 * PI * tf / 36.0).cos(),
                cy: 0.25 * h + 0.1 * h * (2.0 * PI * tf / 28.0).sin(),
                a: r,
                b: r,
                kind: 1,
            };
            let third = Blob {
                cx: 0.75 * w + 0.1 * w * (2.0 * PI * tf / 32.0).sin(),
                cy: 0.78 * h - 0.1 * h * (2.0 * PI * tf / 40.0).cos(),
                a: r,
                b: r,
                kind: 2,
            };
            Layout { others: [Some(second), (count >= 3).then_some(third)], ..one }
        }
        Story::Audit => {
            let (w, h) = (w as f64, h as f64);
            Layout {
                cx: 0.5 * w + 0.25 * w * (2.0 * PI * tf / 40.0).sin(),
                cy: 0.5 * h + 0.2 * h * (2.0 * PI * tf / 30.0).sin(),
                a: w / 16.0,
                b: w / 16.0,
                ..base
            }
        }
        Story::Shrink => {
            // Linear in time from full to half size, drifting right and up.
            let s = 1.0 - 0.5 * tf / (n as f64 - 1.0).max(1.0);
            Layout { cx: 50.0 + 0.8 * tf, cy: 52.0 - 0.3 * tf, a: 20.0 * s, b: 24.0 * s, ..base }
        }
        Story::Turn => {
            // Aspect a/b from 0.7 to 1.4 geometrically, area a·b constant.
            let r = 0.7 * 2f64.powf(tf / (n as f64 - 1.0).max(1.0));
            let area = 16.0 * 16.0;
            Layout { cx: 60.0 + 10.0 * (tf / 10.0).sin(), cy: 48.0, a: (area * r).sqrt(), b: (area / r).sqrt(), ..base }
        }
        Story::CrossOver => {
            let cx = if t < 16 {
                70.0 + 4.5 * tf
            } else if t < 26 {
                // Out of sight: well past the right edge.
                200.0
            } else {
                // In from the left edge, moving right.
                -12.0 + 3.0 * (tf - 26.0)
            };
            Layout { cx, cy: 44.0 + 6.0 * (tf * 0.3).sin(), ..base }
        }
        Story::ExitReturn => {
            let cx = if t < 16 {
                70.0 + 4.5 * tf
            } else if t < 30 {
                // Out of sight: well past the right edge.
                200.0
            } else {
                139.0 - 4.0 * (tf - 30.0)
            };
            Layout { cx, cy: 48.0 + 6.0 * (tf * 0.3).sin(), ..base }
        }
    }
}

/// Where a triangle wave between `lo` and `hi` at `speed` a frame is at
/// frame `tf`, starting at `lo`.
fn zigzag(tf: f64, lo: f64, hi: f64, speed: f64) -> f64 {
    let phase = (speed * tf) % (2.0 * (hi - lo));
    if phase < hi - lo { lo + phase } else { hi - (phase - (hi - lo)) }
}

/// Which of a blob's five bands across (half axis `b`) the offset `u` from
/// its centre falls in: the bands move and scale with the blob.
fn band(u: f64, b: f64) -> i64 {
    ((u + b) / (2.0 * b / 5.0)).floor() as i64
}

/// Whether `(dx, dy)` from a blob's centre is inside its wobbling outline.
fn in_blob(dx: f64, dy: f64, a: f64, b: f64, t: usize) -> bool {
    let r2 = (dx / a).powi(2) + (dy / b).powi(2);
    if r2 > 1.3 {
        return false;
    }
    // Non-rigid: the outline's radius wobbles by ±8% with a moving 3-lobe pattern.
    let theta = dy.atan2(dx);
    let k = 1.0 + 0.08 * (3.0 * theta + 0.7 * t as f64).sin();
    r2 <= k * k
}

/// The colour at `(dx, dy)` from the centre of a blob in the target's
/// colours, textured with `pattern`.
fn blob_colour(dx: f64, dy: f64, b: f64, pattern: Pattern) -> [f64; 3] {
    let stripe = match pattern {
        Pattern::Stripes { horizontal } => return kind_colour(dx, dy, b, horizontal, 0),
        Pattern::Checker => band(dx, b) + band(dy, b),
        // Rings as wide as the stripes, the middle one of the body colour.
        Pattern::Rings => ((dx * dx + dy * dy).sqrt() / (2.0 * b / 5.0) + 0.5).floor() as i64,
    };
    if stripe.rem_euclid(2) == 1 { STRIPE } else { BODY }
}

/// `(dx, dy)` in the frame of a blob turned by `angle`.
fn unturn(dx: f64, dy: f64, angle: f64) -> (f64, f64) {
    let (s, c) = angle.sin_cos();
    (dx * c + dy * s, dy * c - dx * s)
}

/// Half width and half height of the box around an ellipse of half axes
/// `(a, b)` turned by `angle`.
fn turned_box(a: f64, b: f64, angle: f64) -> (f64, f64) {
    let (s, c) = angle.sin_cos();
    ((a * a * c * c + b * b * s * s).sqrt(), (a * a * s * s + b * b * c * c).sqrt())
}

/// [`blob_colour`] in the colours of [`KINDS`]`[kind]`.
fn kind_colour(dx: f64, dy: f64, b: f64, horizontal: bool, kind: usize) -> [f64; 3] {
    let band = band(if horizontal { dy } else { dx }, b);
    let [body, stripe] = KINDS[kind];
    if band.rem_euclid(2) == 1 { stripe } else { body }
}

/// Per mille of the nominal ellipse `(cx, cy, a, b)`, turned by `angle`,
/// that is in a `w × h` frame and not `hidden`.
fn visibility(
    (cx, cy, a, b): (f64, f64, f64, f64),
    angle: f64,
    (w, h): (usize, usize),
    hidden: impl Fn(f64, f64) -> bool,
) -> u16 {
    let (mut total, mut seen) = (0u32, 0u32);
    let (hw, hh) = turned_box(a, b, angle);
    let (x0, x1) = ((cx - hw).floor() as i64, (cx + hw).ceil() as i64);
    let (y0, y1) = ((cy - hh).floor() as i64, (cy + hh).ceil() as i64);
    for y in y0..=y1 {
        for x in x0..=x1 {
            let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
            let (u, v) = unturn(px - cx, py - cy, angle);
            if (u / a).powi(2) + (v / b).powi(2) <= 1.0 {
                total += 1;
                let on = x >= 0 && y >= 0 && (x as usize) < w && (y as usize) < h;
                if on && !hidden(px, py) {
                    seen += 1;
                }
            }
        }
    }
    if total == 0 { 0 } else { (seen as u64 * 1000 / total as u64) as u16 }
}

/// A textured background: smooth colour patches from bilinear value noise,
/// plus a fine checker texture; greens, blues and greys, away from the target's hues.
fn background(w: usize, h: usize, rng: &mut Xoshiro256PlusPlus) -> Vec<[f64; 3]> {
    let cell = 16usize;
    let (gw, gh) = (w / cell + 2, h / cell + 2);
    let palette =
        [[60.0, 120.0, 70.0], [90.0, 140.0, 150.0], [120.0, 120.0, 110.0], [40.0, 80.0, 120.0], [150.0, 160.0, 140.0]];
    let grid: Vec<[f64; 3]> = (0..gw * gh).map(|_| palette[(rng.next_u32() % palette.len() as u32) as usize]).collect();
    let mut out = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let (fx, fy) = (x as f64 / cell as f64, y as f64 / cell as f64);
            let (ix, iy) = (fx.floor() as usize, fy.floor() as usize);
            let (tx, ty) = (fx - ix as f64, fy - iy as f64);
            let g = |i: usize, j: usize| grid[j * gw + i];
            let mut c = [0.0; 3];
            for (k, ck) in c.iter_mut().enumerate() {
                let top = g(ix, iy)[k] * (1.0 - tx) + g(ix + 1, iy)[k] * tx;
                let bot = g(ix, iy + 1)[k] * (1.0 - tx) + g(ix + 1, iy + 1)[k] * tx;
                *ck = top * (1.0 - ty) + bot * ty;
            }
            let texture = if (x / 3 + y / 3) % 2 == 0 { 12.0 } else { -12.0 };
            out.push([c[0] + texture, c[1] + texture, c[2] + texture]);
        }
    }
    out
}

/// Renders a scene.
pub fn generate(spec: &SceneSpec) -> Fixture {
    let (w, h) = (spec.width, spec.height);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(spec.seed);
    // A panning view draws its background from a strip as wide as the
    // frame plus the whole pan.
    let bw = w + layout(spec.story, spec.frames.saturating_sub(1), spec.frames, (w, h)).pan;
    let bg = background(bw, h, &mut rng);
    let bpp = spec.format.bytes_per_pixel();
    let stride = w * bpp;
    let mut frames = Vec::with_capacity(spec.frames);
    let mut rgb = vec![[0u8; 3]; w * h];
    for t in 0..spec.frames {
        let l = layout(spec.story, t, spec.frames, (w, h));
        let occluded =
            |x: f64, y: f64| l.occluder.is_some_and(|[x0, y0, x1, y1]| x >= x0 && x < x1 && y >= y0 && y < y1);
        for y in 0..h {
            for x in 0..w {
                // Pixel centres, in the continuous coordinates of the ground truth.
                let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                let mut c = bg[y * bw + x + l.pan];
                for o in l.others.iter().flatten() {
                    let (dx, dy) = (px - o.cx, py - o.cy);
                    if in_blob(dx, dy, o.a, o.b, t + 3) {
                        c = kind_colour(dx, dy, o.b, true, o.kind);
                    }
                }
                for d in l.decoys.iter().flatten() {
                    let (dx, dy) = (px - d.cx, py - d.cy);
                    if in_blob(dx, dy, l.a, l.b, t + d.phase) {
                        c = blob_colour(dx, dy, l.b, d.pattern);
                    }
                }
                let (dx, dy) = unturn(px - l.cx, py - l.cy, l.angle);
                if in_blob(dx, dy, l.a, l.b, t) {
                    c = blob_colour(dx, dy, l.b, Pattern::Stripes { horizontal: true });
                }
                if occluded(px, py) {
                    c = OCCLUDER;
                    if (x + y) % 4 == 0 {
                        c = [c[0] + 20.0, c[1] + 20.0, c[2] + 20.0];
                    }
                }
                let mut out = [0u8; 3];
                for (o, v) in out.iter_mut().zip(c) {
                    // Sensor noise of ±3 levels after the lighting gain.
                    let noise = (rng.next_u32() % 7) as f64 - 3.0;
                    *o = (v * l.gain + noise).round().clamp(0.0, 255.0) as u8;
                }
                rgb[y * w + x] = out;
            }
        }
        // Visibility: nominal-ellipse pixels (on or off frame) that are on the
        // frame and not under the occluder, nor under a target drawn in front.
        let visible_permille = visibility((l.cx, l.cy, l.a, l.b), l.angle, (w, h), occluded);
        let (hw, hh) = turned_box(l.a, l.b, l.angle);
        let others = l
            .others
            .iter()
            .enumerate()
            .filter_map(|(i, o)| o.map(|o| (i, o)))
            .map(|(i, o)| {
                let in_front = |px: f64, py: f64| {
                    let (u, v) = unturn(px - l.cx, py - l.cy, l.angle);
                    in_blob(u, v, l.a, l.b, t)
                        || l.others.iter().skip(i + 1).flatten().any(|f| in_blob(px - f.cx, py - f.cy, f.a, f.b, t + 3))
                };
                RecordMeta {
                    truth: BoundingBox::new(
                        (o.cx - o.a) as f32,
                        (o.cy - o.b) as f32,
                        (2.0 * o.a) as f32,
                        (2.0 * o.b) as f32,
                    ),
                    visible_permille: visibility((o.cx, o.cy, o.a, o.b), 0.0, (w, h), |x, y| {
                        occluded(x, y) || in_front(x, y)
                    }),
                }
            })
            .collect();
        frames.push(FixtureFrame {
            truth: BoundingBox::new((l.cx - hw) as f32, (l.cy - hh) as f32, (2.0 * hw) as f32, (2.0 * hh) as f32),
            visible_permille,
            others,
            pixels: encode(&rgb, w, h, spec.format),
        });
    }
    Fixture { format: spec.format, width: w, height: h, stride, frames }
}

/// Packs RGB pixels into a camera format, tightly (stride = width * bpp).
pub fn encode(rgb: &[[u8; 3]], w: usize, h: usize, format: PixelFormat) -> Vec<u8> {
    let mut out = Vec::with_capacity(w * h * format.bytes_per_pixel());
    match format {
        PixelFormat::Rgb888 => rgb.iter().for_each(|p| out.extend_from_slice(p)),
        PixelFormat::Rgb565 => rgb.iter().for_each(|p| out.extend_from_slice(&rgb_to_rgb565(*p))),
        PixelFormat::Gray8 => rgb.iter().for_each(|p| out.push(rgb_to_yuv(*p)[0])),
        PixelFormat::Yuv422 => {
            for row in rgb.chunks(w).take(h) {
                for pair in row.chunks(2) {
                    let a = rgb_to_yuv(pair[0]);
                    let b = rgb_to_yuv(*pair.get(1).unwrap_or(&pair[0]));
                    let u = (a[1] as u16 + b[1] as u16).div_ceil(2) as u8;
                    let v = (a[2] as u16 + b[2] as u16).div_ceil(2) as u8;
                    out.extend_from_slice(&[a[0], u, b[0], v]);
                }
            }
        }
        PixelFormat::I420 | PixelFormat::Nv12 => {
            let yuv: Vec<[u8; 3]> = rgb.iter().map(|&p| rgb_to_yuv(p)).collect();
            out.extend(yuv.iter().map(|p| p[0]));
            // Each chroma sample is the rounded mean of its 2x2 block's.
            let block = |bx: usize, by: usize, c: usize| {
                let at = |x: usize, y: usize| yuv.get(y.min(h - 1) * w + x.min(w - 1)).map_or(0, |p| p[c] as u16);
                ((at(2 * bx, 2 * by)
                    + at(2 * bx + 1, 2 * by)
                    + at(2 * bx, 2 * by + 1)
                    + at(2 * bx + 1, 2 * by + 1)
                    + 2)
                    / 4) as u8
            };
            let (cw, ch) = (w / 2, h / 2);
            if format == PixelFormat::I420 {
                for c in [1, 2] {
                    out.extend((0..ch).flat_map(|by| (0..cw).map(move |bx| (bx, by))).map(|(bx, by)| block(bx, by, c)));
                }
            } else {
                let pairs = (0..ch).flat_map(|by| (0..cw).map(move |bx| (bx, by)));
                out.extend(pairs.flat_map(|(bx, by)| [block(bx, by, 1), block(bx, by, 2)]));
            }
        }
    }
    out
}

/// Converts a frame of any format back to RGB888 (for pictures).
pub fn to_rgb(frame: &pftrack::Frame<'_>) -> Vec<u8> {
    let mut out = Vec::with_capacity(frame.width() * frame.height() * 3);
    for y in 0..frame.height() {
        for x in 0..frame.width() {
            out.extend_from_slice(&frame.rgb(x, y).unwrap_or([0, 0, 0]));
        }
    }
    out
}
