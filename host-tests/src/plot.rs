//! Success and precision plots as the OTB toolkit draws them: one curve per
//! result set, the legend giving each set's score. PNG, drawn with
//! embedded-graphics (its built-in bitmap fonts need no system font).

use embedded_graphics::Pixel;
use embedded_graphics::mono_font::MonoTextStyle;
use embedded_graphics::mono_font::ascii::{FONT_6X10, FONT_7X13_BOLD};
use embedded_graphics::pixelcolor::Rgb888;
use embedded_graphics::prelude::*;
use embedded_graphics::primitives::{Line, PrimitiveStyle, Rectangle};
use embedded_graphics::text::{Alignment, Text};
use std::convert::Infallible;
use std::path::Path;

/// One result set's curve.
#[derive(Debug, Clone)]
pub struct Curve {
    /// Legend label (the score is appended).
    pub name: String,
    /// The y value at each x of the plot's `xs`.
    pub ys: Vec<f64>,
    /// The score shown in the legend, e.g. AUC or P20.
    pub score: f64,
}

/// An RGB image that embedded-graphics can draw on.
struct Canvas {
    img: image::RgbImage,
}

impl OriginDimensions for Canvas {
    fn size(&self) -> Size {
        Size::new(self.img.width(), self.img.height())
    }
}

impl DrawTarget for Canvas {
    type Color = Rgb888;
    type Error = Infallible;

    fn draw_iter<I: IntoIterator<Item = Pixel<Rgb888>>>(&mut self, pixels: I) -> Result<(), Infallible> {
        for Pixel(p, c) in pixels {
            if let (Ok(x), Ok(y)) = (u32::try_from(p.x), u32::try_from(p.y))
                && x < self.img.width()
                && y < self.img.height()
            {
                self.img.put_pixel(x, y, image::Rgb([c.r(), c.g(), c.b()]));
            }
        }
        Ok(())
    }
}

/// Distinct colours for up to 12 curves (then they repeat): `compare/run`
/// draws 11.
const PALETTE: [Rgb888; 12] = [
    Rgb888::new(220, 20, 20),
    Rgb888::new(20, 90, 220),
    Rgb888::new(20, 160, 60),
    Rgb888::new(230, 140, 0),
    Rgb888::new(140, 40, 180),
    Rgb888::new(0, 170, 180),
    Rgb888::new(120, 80, 30),
    Rgb888::new(230, 60, 160),
    Rgb888::new(100, 100, 100),
    Rgb888::new(160, 160, 0),
    Rgb888::new(0, 0, 0),
    Rgb888::new(110, 190, 255),
];

/// Draws `curves` over `xs` (y in [0, 1]) into a PNG at `path`. Curves are
/// listed in the legend by descending score, as OTB does.
pub fn line_plot(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    xs: &[f64],
    curves: &[Curve],
    score_name: &str,
) -> Result<(), String> {
    // Wide enough for the longest legend line (6 px a character, after the
    // plot area and the legend's line sample).
    let legend = curves.iter().map(|c| format!("{} [{score_name} {:.3}]", c.name, c.score).chars().count()).max();
    let (w, h) = ((480 + 46 + 6 * legend.unwrap_or(0) as u32 + 10).max(760), 520u32);
    let mut c = Canvas { img: image::RgbImage::from_pixel(w, h, image::Rgb([255, 255, 255])) };
    // Plot area.
    let (left, top, right, bottom) = (60i32, 40i32, 480i32, 460i32);
    let (x0, x1) = (xs.first().copied().unwrap_or(0.0), xs.last().copied().unwrap_or(1.0));
    let px = |x: f64| left + ((x - x0) / (x1 - x0).max(1e-12) * (right - left) as f64).round() as i32;
    let py = |y: f64| bottom - (y.clamp(0.0, 1.0) * (bottom - top) as f64).round() as i32;
    let black = Rgb888::BLACK;
    let grid = PrimitiveStyle::with_stroke(Rgb888::new(225, 225, 225), 1);
    let axis = PrimitiveStyle::with_stroke(black, 1);
    let small = MonoTextStyle::new(&FONT_6X10, black);
    let bold = MonoTextStyle::new(&FONT_7X13_BOLD, black);
    // Grid and ticks: y every 0.1, x at 11 even steps.
    for i in 0..=10 {
        let y = i as f64 / 10.0;
        Line::new(Point::new(left, py(y)), Point::new(right, py(y))).into_styled(grid).draw(&mut c).ok();
        Text::with_alignment(&format!("{y:.1}"), Point::new(left - 6, py(y) + 3), small, Alignment::Right)
            .draw(&mut c)
            .ok();
        let x = x0 + (x1 - x0) * i as f64 / 10.0;
        Line::new(Point::new(px(x), top), Point::new(px(x), bottom)).into_styled(grid).draw(&mut c).ok();
        let label = if x1 - x0 > 10.0 { format!("{x:.0}") } else { format!("{x:.1}") };
        Text::with_alignment(&label, Point::new(px(x), bottom + 14), small, Alignment::Center).draw(&mut c).ok();
    }
    Rectangle::with_corners(Point::new(left, top), Point::new(right, bottom)).into_styled(axis).draw(&mut c).ok();
    Text::with_alignment(title, Point::new((left + right) / 2, top - 14), bold, Alignment::Center).draw(&mut c).ok();
    Text::with_alignment(x_label, Point::new((left + right) / 2, bottom + 32), small, Alignment::Center)
        .draw(&mut c)
        .ok();
    Text::new(y_label, Point::new(4, top - 14), small).draw(&mut c).ok();

    let mut order: Vec<usize> = (0..curves.len()).collect();
    order.sort_by(|&a, &b| curves[b].score.total_cmp(&curves[a].score));
    for (rank, &i) in order.iter().enumerate() {
        let curve = &curves[i];
        let colour = PALETTE[i % PALETTE.len()];
        let style = PrimitiveStyle::with_stroke(colour, 2);
        let points: Vec<Point> = xs.iter().zip(&curve.ys).map(|(&x, &y)| Point::new(px(x), py(y))).collect();
        for seg in points.windows(2) {
            Line::new(seg[0], seg[1]).into_styled(style).draw(&mut c).ok();
        }
        let ly = top + 10 + 18 * rank as i32;
        Line::new(Point::new(right + 14, ly - 3), Point::new(right + 40, ly - 3)).into_styled(style).draw(&mut c).ok();
        let text = format!("{} [{score_name} {:.3}]", curve.name, curve.score);
        Text::new(&text, Point::new(right + 46, ly), small).draw(&mut c).ok();
    }
    c.img.save(path).map_err(|e| format!("{}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plot_is_written_and_its_curve_is_where_the_data_says() {
        // Reason: geometry of the plot area: y = 1 maps to the top edge
        // (row 40) and y = 0 to the bottom (row 460), x to columns 60..480;
        // a constant curve at y = 0.5 must colour row 250 mid-plot in its
        // palette colour, and nothing of that colour elsewhere in that column
        // inside the plot.
        let dir = std::env::temp_dir().join(format!("pftrack-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("p.png");
        let xs: Vec<f64> = (0..=10).map(|i| i as f64 / 10.0).collect();
        let curves = [Curve { name: "half".into(), ys: vec![0.5; 11], score: 0.5 }];
        line_plot(&path, "t", "x", "y", &xs, &curves, "AUC").unwrap();
        let img = image::open(&path).unwrap().to_rgb8();
        assert_eq!((img.width(), img.height()), (760, 520));
        let red = image::Rgb([220, 20, 20]);
        assert_eq!(*img.get_pixel(270, 250), red);
        let hits = (41..460).filter(|&y| *img.get_pixel(270, y) == red).count();
        assert!((1..=3).contains(&hits), "line 2 px thick: {hits}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
