//! Colour quantisation: how a pixel's colour maps to a histogram bin.

/// How a colour maps to a histogram bin. A component of the configuration;
/// a histogram's capacity `K` must be at least [`Binning::bins`].
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Binning {
    /// RGB with 8 levels per channel: 512 bins (the first paper's choice).
    #[default]
    Rgb8x8x8,
    /// HSV with 8 hues, 8 saturations and 4 values: 256 bins. Coarse in
    /// value, so less sensitive to lighting than RGB (the first paper's
    /// alternative). Greys (zero saturation) share the hue-0 bins.
    Hsv8x8x4,
    /// RGB with 4 levels per channel: 64 bins (small enough for four
    /// quadrant histograms in the default 512-bin capacity).
    Rgb4x4x4,
    /// RGB with `L` levels per channel (`L³` bins), `L` chosen per region
    /// when the tracker learns its target by the Birgé–Rozenholc penalised
    /// likelihood (the adaptive-bins paper), from every `L` from 2 up to
    /// what the region's share of the histogram capacity holds.
    Adaptive,
}

/// The smallest and largest levels per channel [`Binning::Adaptive`] tries.
pub const ADAPTIVE_LEVELS: (u8, u8) = (2, 8);

impl Binning {
    /// Number of bins this binning uses; for [`Binning::Adaptive`], the
    /// fewest it may choose (8).
    pub const fn bins(self) -> usize {
        match self {
            Binning::Rgb8x8x8 => 512,
            Binning::Hsv8x8x4 => 256,
            Binning::Rgb4x4x4 => 64,
            Binning::Adaptive => 8,
        }
    }

    /// The bin of an 8-bit RGB colour; always below [`Binning::bins`].
    /// [`Binning::Adaptive`] bins at its coarsest here (2 levels); the
    /// tracker uses [`levels_bin`] with the levels it chose.
    #[inline(always)]
    pub fn bin(self, rgb: [u8; 3]) -> usize {
        match self {
            Binning::Rgb8x8x8 => ((rgb[0] as usize >> 5) << 6) | ((rgb[1] as usize >> 5) << 3) | (rgb[2] as usize >> 5),
            Binning::Hsv8x8x4 => hsv_bin(rgb),
            Binning::Rgb4x4x4 => ((rgb[0] as usize >> 6) << 4) | ((rgb[1] as usize >> 6) << 2) | (rgb[2] as usize >> 6),
            Binning::Adaptive => levels_bin(rgb, 2),
        }
    }
}

/// The bin of an 8-bit RGB colour with `levels` equal-width levels per
/// channel: `(r·L/256)·L² + (g·L/256)·L + b·L/256`, below `L³`. Integer
/// multiplies and shifts only.
#[inline(always)]
pub fn levels_bin([r, g, b]: [u8; 3], levels: u8) -> usize {
    let l = levels as usize;
    let q = |c: u8| (c as usize * l) >> 8;
    (q(r) * l + q(g)) * l + q(b)
}

/// `min(floor(8 · num / den), 7)` for `den > 0`, exactly, by a three-step
/// binary search on `8 · num >= k · den`: no division, which a Cortex-M0+
/// lacks, and no rounding at bin edges, which a reciprocal table has.
#[inline(always)]
fn eighths(num: u32, den: u32) -> u32 {
    let t = 8 * num;
    let mut k = 0;
    if t >= (k + 4) * den {
        k += 4;
    }
    if t >= (k + 2) * den {
        k += 2;
    }
    if t >= (k + 1) * den {
        k += 1;
    }
    k
}

/// HSV 8x8x4 bin in integers: bin = hue·32 + saturation·4 + value.
#[inline(always)]
fn hsv_bin([r, g, b]: [u8; 3]) -> usize {
    let (r, g, b) = (r as u32, g as u32, b as u32);
    let max = r.max(g).max(b);
    let min = r.min(g).min(b);
    let delta = max - min;
    let v_bin = max >> 6;
    if delta == 0 {
        return v_bin as usize;
    }
    // Saturation s = floor(255·delta/max) in 0..=255; its bin is s / 32.
    let s_bin = eighths(255 * delta, 256 * max);
    // Hue on a scale of 6·delta per turn: red 0, green 2·delta, blue 4·delta.
    let hp = if max == r {
        if g >= b { g - b } else { 6 * delta - (b - g) }
    } else if max == g {
        2 * delta + b - r
    } else {
        4 * delta + r - g
    };
    let h_bin = eighths(hp, 6 * delta);
    ((h_bin << 5) | (s_bin << 2) | v_bin) as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_bins_agree_with_the_fixed_rgb_binnings() {
        // Reason: 8 and 4 equal levels are the top 3 and 2 bits, so
        // `levels_bin` must reproduce Rgb8x8x8 and Rgb4x4x4 on every colour
        // of a grid, and stay below L³ for every L.
        for r in (0..=255).step_by(17) {
            for g in (0..=255).step_by(5) {
                for b in (0..=255).step_by(3) {
                    let c = [r as u8, g as u8, b as u8];
                    assert_eq!(levels_bin(c, 8), Binning::Rgb8x8x8.bin(c));
                    assert_eq!(levels_bin(c, 4), Binning::Rgb4x4x4.bin(c));
                    for l in 2..=8u8 {
                        assert!(levels_bin(c, l) < (l as usize).pow(3));
                    }
                }
            }
        }
        assert_eq!(levels_bin([255, 255, 255], 5), 124);
    }

    #[test]
    fn rgb_binning_uses_top_three_bits() {
        assert_eq!(Binning::Rgb8x8x8.bin([0, 0, 0]), 0);
        assert_eq!(Binning::Rgb8x8x8.bin([255, 255, 255]), 511);
        assert_eq!(Binning::Rgb8x8x8.bin([0b1010_0000, 0b0110_0000, 0b0010_0000]), (5 << 6) | (3 << 3) | 1);
    }

    /// Floating-point HSV, the textbook definition.
    fn reference_hsv(rgb: [u8; 3]) -> (f64, f64, f64) {
        let [r, g, b] = rgb.map(|c| c as f64);
        let max = r.max(g).max(b);
        let min = r.min(g).min(b);
        let d = max - min;
        let h = if d == 0.0 {
            0.0
        } else if max == r {
            (60.0 * (g - b) / d).rem_euclid(360.0)
        } else if max == g {
            60.0 * (b - r) / d + 120.0
        } else {
            60.0 * (r - g) / d + 240.0
        };
        let s = if max == 0.0 { 0.0 } else { d / max };
        (h, s, max)
    }

    #[test]
    fn hsv_bins_match_the_float_definition() {
        // Reason: cross-check with the textbook float HSV over a grid of
        // colours. The integer version is exact, so only colours sitting on a
        // bin edge, where f64 rounding may tip the reference, can differ.
        let mut off_by_edge = 0;
        for r in (0..=255).step_by(15) {
            for g in (0..=255).step_by(15) {
                for b in (0..=255).step_by(15) {
                    let rgb = [r as u8, g as u8, b as u8];
                    let (h, s, v) = reference_hsv(rgb);
                    let want_h = if s == 0.0 { 0 } else { ((h / 45.0).floor() as usize).min(7) };
                    let want_s = if s == 0.0 { 0 } else { ((s * 255.0).floor() as usize >> 5).min(7) };
                    let want = (want_h << 5) | (want_s << 2) | (v as usize >> 6);
                    let got = Binning::Hsv8x8x4.bin(rgb);
                    assert!(got < 256);
                    if got != want {
                        let near_h = (h / 45.0 - (h / 45.0).round()).abs() < 1e-9;
                        let near_s = ((s * 255.0) - (s * 255.0).round()).abs() < 1e-9;
                        assert!(near_h || near_s, "{rgb:?}: got {got}, want {want} (h {h}, s {s})");
                        off_by_edge += 1;
                    }
                }
            }
        }
        assert!(off_by_edge < 20, "{off_by_edge} colours off by an edge");
    }

    #[test]
    fn hsv_hue_is_brightness_invariant() {
        // Reason: scaling a colour scales max and delta alike, so hue and
        // saturation (and hence those bin fields) stay the same.
        let a = Binning::Hsv8x8x4.bin([200, 100, 50]);
        let b = Binning::Hsv8x8x4.bin([120, 60, 30]);
        assert_eq!(a >> 2, b >> 2);
        assert_ne!(a & 3, b & 3, "value differs");
    }
}
