//! The pieces of a hand-written SVG plot. No plotting dependency: a plot is a
//! few dozen elements, and each tool keeps its own marks and legend while the
//! mapping from values to pixels, the log-log page and its decade grid are
//! written once here.

use std::fmt::Write;

/// Ten distinguishable colours (matplotlib's "tab10"), in their usual order.
pub const TAB10: [&str; 10] = [
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
    "#bcbd22", "#17becf",
];

/// Escapes the three characters that would break an SVG text node or attribute.
pub fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// One axis: values from `lo` to `hi` (their base-10 logarithms on a log axis)
/// go linearly to pixels from `from` to `to`. `to` may be below `from`: an SVG
/// y axis grows downwards, so a y axis maps `lo` to the bottom edge.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Axis {
    pub lo: f64,
    pub hi: f64,
    pub from: f64,
    pub to: f64,
    pub log: bool,
}

impl Axis {
    /// A linear axis.
    pub fn linear(lo: f64, hi: f64, from: f64, to: f64) -> Axis {
        Axis {
            lo,
            hi,
            from,
            to,
            log: false,
        }
    }

    /// A logarithmic axis from `10^lo_exp` to `10^hi_exp`.
    pub fn log(lo_exp: f64, hi_exp: f64, from: f64, to: f64) -> Axis {
        Axis {
            lo: lo_exp,
            hi: hi_exp,
            from,
            to,
            log: true,
        }
    }

    /// The pixel of `value`.
    pub fn at(&self, value: f64) -> f64 {
        let v = if self.log { value.log10() } else { value };
        self.from + (v - self.lo) / (self.hi - self.lo) * (self.to - self.from)
    }
}

/// Whole decades covering the positive finite `values`: (a, b) with
/// `10^a ≤ min` and `max ≤ 10^b`, at least one decade wide. `None` when no
/// value is positive and finite (nothing can be drawn on a log axis).
pub fn decades(values: impl Iterator<Item = f64>) -> Option<(i32, i32)> {
    let (lo, hi) = values
        .filter(|v| *v > 0.0 && v.is_finite())
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !lo.is_finite() {
        return None;
    }
    let a = lo.log10().floor() as i32;
    let b = (hi.log10().ceil() as i32).max(a + 1);
    Some((a, b))
}

/// Writes `<polyline>` through `points` (pixels, to 0.1), unfilled, with the
/// stroke attributes `stroke` (e.g. `stroke="#000" stroke-width="1.5"`).
pub fn polyline(svg: &mut String, points: impl Iterator<Item = (f64, f64)>, stroke: &str) {
    let path: Vec<String> = points.map(|(x, y)| format!("{x:.1},{y:.1}")).collect();
    let _ = writeln!(
        svg,
        r#"<polyline points="{}" fill="none" {stroke}/>"#,
        path.join(" ")
    );
}

/// Writes an unfilled rectangle: a plot's frame.
pub fn frame(svg: &mut String, x: f64, y: f64, width: f64, height: f64, stroke: &str) {
    let _ = writeln!(
        svg,
        r#"<rect x="{x}" y="{y}" width="{width}" height="{height}" fill="none" stroke="{stroke}"/>"#
    );
}

/// A log-log page: its size, its margins around the plot area (the right one
/// holds the legend) and the few typographic choices that differ between the
/// tools' plots.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Page {
    pub width: f64,
    pub height: f64,
    pub left: f64,
    pub right: f64,
    pub top: f64,
    pub bottom: f64,
    /// The title's font size.
    pub title_size: u32,
    /// How far below the plot area the x decade labels' baseline is.
    pub x_tick_gap: f64,
    /// The x of the (rotated) y-axis label.
    pub y_label_x: f64,
    /// The plot area's frame colour.
    pub frame_stroke: &'static str,
}

impl Page {
    /// The plot area's width.
    pub fn plot_width(&self) -> f64 {
        self.width - self.left - self.right
    }

    /// The plot area's height.
    pub fn plot_height(&self) -> f64 {
        self.height - self.top - self.bottom
    }

    /// Opens the SVG: the root element, a white background and the title,
    /// centred over the plot area.
    pub fn open(&self, svg: &mut String, title: &str) {
        let (w, h) = (self.width, self.height);
        let _ = writeln!(
            svg,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="12">"#
        );
        let _ = writeln!(svg, r#"<rect width="100%" height="100%" fill="white"/>"#);
        let _ = writeln!(
            svg,
            r#"<text x="{}" y="22" text-anchor="middle" font-size="{}">{}</text>"#,
            self.left + self.plot_width() / 2.0,
            self.title_size,
            escape(title)
        );
    }

    /// The log axes spanning the decades `x` and `y` over the plot area.
    pub fn axes(&self, x: (i32, i32), y: (i32, i32)) -> (Axis, Axis) {
        let bottom = self.top + self.plot_height();
        (
            Axis::log(
                x.0 as f64,
                x.1 as f64,
                self.left,
                self.left + self.plot_width(),
            ),
            Axis::log(y.0 as f64, y.1 as f64, bottom, self.top),
        )
    }

    /// Draws a grid line and a `1eN` label at every decade of the axes made by
    /// [`Page::axes`] from `x` and `y`, the plot area's frame and the two
    /// axis labels.
    pub fn decade_grid(
        &self,
        svg: &mut String,
        (x, y): (Axis, Axis),
        x_label: &str,
        y_label: &str,
    ) {
        let (plot_w, plot_h) = (self.plot_width(), self.plot_height());
        let (left, top) = (self.left, self.top);
        for d in x.lo as i32..=x.hi as i32 {
            let px = x.at(10f64.powi(d));
            let _ = writeln!(
                svg,
                r##"<line x1="{px:.1}" y1="{top}" x2="{px:.1}" y2="{:.1}" stroke="#ddd"/><text x="{px:.1}" y="{:.1}" text-anchor="middle">1e{d}</text>"##,
                top + plot_h,
                top + plot_h + self.x_tick_gap
            );
        }
        for d in y.lo as i32..=y.hi as i32 {
            let py = y.at(10f64.powi(d));
            let _ = writeln!(
                svg,
                r##"<line x1="{left}" y1="{py:.1}" x2="{:.1}" y2="{py:.1}" stroke="#ddd"/><text x="{:.1}" y="{:.1}" text-anchor="end">1e{d}</text>"##,
                left + plot_w,
                left - 6.0,
                py + 4.0
            );
        }
        frame(svg, left, top, plot_w, plot_h, self.frame_stroke);
        let _ = writeln!(
            svg,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
            left + plot_w / 2.0,
            self.height - 12.0,
            escape(x_label)
        );
        let lx = self.y_label_x;
        let _ = writeln!(
            svg,
            r#"<text x="{lx}" y="{:.1}" text-anchor="middle" transform="rotate(-90 {lx} {:.1})">{}</text>"#,
            top + plot_h / 2.0,
            top + plot_h / 2.0,
            escape(y_label)
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // A 500 × 400 plot area from (100, 50) to (600, 450).
    const PAGE: Page = Page {
        width: 800.0,
        height: 500.0,
        left: 100.0,
        right: 200.0,
        top: 50.0,
        bottom: 50.0,
        title_size: 12,
        x_tick_gap: 20.0,
        y_label_x: 20.0,
        frame_stroke: "grey",
    };

    #[test]
    fn log_axes_put_each_decade_at_its_share_of_the_plot_area() {
        // x spans 1e1..1e4 over pixels 100..600 (three decades of 500/3 px);
        // y spans 1e-3..1e-1 over 450 (bottom) up to 50 (top).
        let (x, y) = PAGE.axes((1, 4), (-3, -1));
        assert!((x.at(10.0) - 100.0).abs() < 1e-9);
        assert!((x.at(1e4) - 600.0).abs() < 1e-9);
        // 10^2.5 is 1.5 decades in: half the width.
        assert!((x.at(10f64.powf(2.5)) - 350.0).abs() < 1e-9);
        // 10^2 is one decade in: a third of the width.
        assert!((x.at(100.0) - (100.0 + 500.0 / 3.0)).abs() < 1e-9);
        assert!((y.at(1e-3) - 450.0).abs() < 1e-9);
        assert!((y.at(1e-1) - 50.0).abs() < 1e-9);
        // 1e-2 is one decade of two: half-way up, 450 − 400/2.
        assert!((y.at(1e-2) - 250.0).abs() < 1e-9);
    }

    #[test]
    fn a_linear_axis_maps_its_ends_and_interpolates_between() {
        let a = Axis::linear(0.0, 70.0, 520.0, 880.0);
        assert_eq!(a.at(0.0), 520.0);
        assert_eq!(a.at(70.0), 880.0);
        // 35 is half of 0..70: half of 360 px past 520.
        assert!((a.at(35.0) - 700.0).abs() < 1e-9);
        // A reversed (y) axis: 0 at the bottom (310), the top (50) at 2.
        let y = Axis::linear(0.0, 2.0, 310.0, 50.0);
        assert!((y.at(0.5) - 245.0).abs() < 1e-9);
    }

    #[test]
    fn decades_cover_the_positive_values_and_are_at_least_one_wide() {
        let v = [0.0, -1.0, f64::NAN, 0.02, 300.0];
        assert_eq!(decades(v.into_iter()), Some((-2, 3)));
        // One value on a power of ten still gets a whole decade.
        assert_eq!(decades([100.0].into_iter()), Some((2, 3)));
        assert_eq!(decades([0.0, f64::INFINITY].into_iter()), None);
    }

    #[test]
    fn the_grid_has_a_labelled_line_per_decade_and_text_is_escaped() {
        let mut svg = String::new();
        PAGE.open(&mut svg, "a<b & c");
        let axes = PAGE.axes((0, 2), (-1, 0));
        PAGE.decade_grid(&mut svg, axes, "x", "y");
        // Three x decades (1e0..1e2) and two y decades (1e-1..1e0).
        assert_eq!(svg.matches("<line").count(), 5);
        assert!(svg.contains(">1e2</text>") && svg.contains(">1e-1</text>"));
        // The middle x decade, 1e1, is at the middle of the plot area.
        assert!(svg.contains(r#"<line x1="350.0""#), "{svg}");
        assert!(svg.contains("a&lt;b &amp; c"));
        let mut line = String::new();
        polyline(
            &mut line,
            [(1.04, 2.0), (3.0, 4.96)].into_iter(),
            "stroke=\"red\"",
        );
        assert_eq!(
            line,
            "<polyline points=\"1.0,2.0 3.0,5.0\" fill=\"none\" stroke=\"red\"/>\n"
        );
    }
}
