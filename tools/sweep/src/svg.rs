//! A log–log scatter plot of error against seconds as hand-written SVG, with the
//! Pareto front drawn as a line through ringed points. No plotting dependency:
//! the plot is a few dozen elements.

use std::fmt::Write;

/// One plotted point.
#[derive(Clone, Debug)]
pub struct PlotPoint {
    pub x: f64,
    pub y: f64,
    /// The legend group (one colour per group).
    pub group: String,
    /// Shown on hover (SVG `<title>`).
    pub label: String,
}

const WIDTH: f64 = 760.0;
const HEIGHT: f64 = 480.0;
const LEFT: f64 = 70.0;
const RIGHT: f64 = 190.0;
const TOP: f64 = 40.0;
const BOTTOM: f64 = 55.0;
const COLOURS: [&str; 10] = [
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
    "#bcbd22", "#17becf",
];

/// Powers of ten covering `[lo, hi]` (both > 0), widened to whole decades.
fn decades(lo: f64, hi: f64) -> (i32, i32) {
    let a = lo.log10().floor() as i32;
    let mut b = hi.log10().ceil() as i32;
    if b <= a {
        b = a + 1;
    }
    (a, b)
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// Renders the plot. `front` indexes `points` (in increasing x). Points with a
/// non-positive or non-finite coordinate cannot be drawn on log axes and are
/// left out (the tables still list them).
pub fn plot(
    title: &str,
    x_label: &str,
    y_label: &str,
    points: &[PlotPoint],
    front: &[usize],
) -> String {
    let drawable = |p: &PlotPoint| p.x > 0.0 && p.y > 0.0 && p.x.is_finite() && p.y.is_finite();
    let shown: Vec<&PlotPoint> = points.iter().filter(|p| drawable(p)).collect();
    let mut svg = String::new();
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{HEIGHT}" viewBox="0 0 {WIDTH} {HEIGHT}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(svg, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        svg,
        r#"<text x="{}" y="22" text-anchor="middle" font-size="15">{}</text>"#,
        (LEFT + WIDTH - RIGHT) / 2.0,
        escape(title)
    );
    if shown.is_empty() {
        let _ = writeln!(
            svg,
            r#"<text x="{LEFT}" y="80">no drawable points</text></svg>"#
        );
        return svg;
    }
    let (xa, xb) = decades(
        shown.iter().map(|p| p.x).fold(f64::INFINITY, f64::min),
        shown.iter().map(|p| p.x).fold(0.0, f64::max),
    );
    let (ya, yb) = decades(
        shown.iter().map(|p| p.y).fold(f64::INFINITY, f64::min),
        shown.iter().map(|p| p.y).fold(0.0, f64::max),
    );
    let plot_w = WIDTH - LEFT - RIGHT;
    let plot_h = HEIGHT - TOP - BOTTOM;
    let sx = |x: f64| LEFT + (x.log10() - xa as f64) / (xb - xa) as f64 * plot_w;
    let sy = |y: f64| TOP + plot_h - (y.log10() - ya as f64) / (yb - ya) as f64 * plot_h;
    // Grid and decade labels.
    for d in xa..=xb {
        let x = sx(10f64.powi(d));
        let _ = writeln!(
            svg,
            r##"<line x1="{x:.1}" y1="{TOP}" x2="{x:.1}" y2="{:.1}" stroke="#ddd"/><text x="{x:.1}" y="{:.1}" text-anchor="middle">1e{d}</text>"##,
            TOP + plot_h,
            TOP + plot_h + 18.0
        );
    }
    for d in ya..=yb {
        let y = sy(10f64.powi(d));
        let _ = writeln!(
            svg,
            r##"<line x1="{LEFT}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#ddd"/><text x="{:.1}" y="{:.1}" text-anchor="end">1e{d}</text>"##,
            LEFT + plot_w,
            LEFT - 6.0,
            y + 4.0
        );
    }
    let _ = writeln!(
        svg,
        r##"<rect x="{LEFT}" y="{TOP}" width="{plot_w}" height="{plot_h}" fill="none" stroke="#444"/>"##
    );
    let _ = writeln!(
        svg,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
        LEFT + plot_w / 2.0,
        HEIGHT - 12.0,
        escape(x_label)
    );
    let _ = writeln!(
        svg,
        r#"<text x="18" y="{:.1}" text-anchor="middle" transform="rotate(-90 18 {:.1})">{}</text>"#,
        TOP + plot_h / 2.0,
        TOP + plot_h / 2.0,
        escape(y_label)
    );
    // Groups in order of first appearance, one colour each.
    let mut groups: Vec<&str> = Vec::new();
    for p in &shown {
        if !groups.contains(&p.group.as_str()) {
            groups.push(&p.group);
        }
    }
    let colour = |g: &str| {
        let k = groups.iter().position(|&x| x == g).unwrap_or(0);
        COLOURS[k % COLOURS.len()]
    };
    // The front: a staircase would suggest points that do not exist, so it is a
    // plain polyline through the front's points.
    let front_points: Vec<&PlotPoint> = front
        .iter()
        .filter_map(|&i| points.get(i))
        .filter(|p| drawable(p))
        .collect();
    if front_points.len() > 1 {
        let path: Vec<String> = front_points
            .iter()
            .map(|p| format!("{:.1},{:.1}", sx(p.x), sy(p.y)))
            .collect();
        let _ = writeln!(
            svg,
            r##"<polyline points="{}" fill="none" stroke="#000" stroke-width="1.5" stroke-dasharray="5,3"/>"##,
            path.join(" ")
        );
    }
    for p in &shown {
        let _ = writeln!(
            svg,
            r#"<circle cx="{:.1}" cy="{:.1}" r="4" fill="{}" fill-opacity="0.85"><title>{}</title></circle>"#,
            sx(p.x),
            sy(p.y),
            colour(&p.group),
            escape(&p.label)
        );
    }
    for p in &front_points {
        let _ = writeln!(
            svg,
            r##"<circle cx="{:.1}" cy="{:.1}" r="7" fill="none" stroke="#000" stroke-width="1.5"/>"##,
            sx(p.x),
            sy(p.y)
        );
    }
    // Legend.
    let lx = LEFT + plot_w + 15.0;
    for (k, g) in groups.iter().enumerate() {
        let y = TOP + 10.0 + 18.0 * k as f64;
        let _ = writeln!(
            svg,
            r#"<circle cx="{lx}" cy="{y}" r="4" fill="{}"/><text x="{}" y="{}">{}</text>"#,
            colour(g),
            lx + 10.0,
            y + 4.0,
            escape(g)
        );
    }
    let y = TOP + 10.0 + 18.0 * groups.len() as f64 + 6.0;
    let _ = writeln!(
        svg,
        r##"<circle cx="{lx}" cy="{y}" r="7" fill="none" stroke="#000" stroke-width="1.5"/><text x="{}" y="{}">Pareto front</text>"##,
        lx + 10.0,
        y + 4.0
    );
    svg.push_str("</svg>\n");
    svg
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_map_into_the_plot_area_and_front_is_ringed() {
        let points: Vec<PlotPoint> = [(1.0, 0.1), (10.0, 0.01), (5.0, 0.5), (0.0, 1.0)]
            .iter()
            .map(|&(x, y)| PlotPoint {
                x,
                y,
                group: "g".into(),
                label: "p<1>".into(),
            })
            .collect();
        let svg = plot("t", "x", "y", &points, &[0, 1]);
        // Three drawable points (x = 0 cannot be on a log axis) plus one legend
        // dot; two front rings plus the legend's ring.
        assert_eq!(svg.matches(r#"r="4""#).count(), 4);
        assert_eq!(svg.matches(r#"r="7""#).count(), 3);
        assert!(svg.contains("p&lt;1&gt;"));
        assert!(svg.contains("<polyline"));
        // x from 1e0 to 1e1 spans the plot width: the point at x = 1 sits on the
        // left edge, x = 10 on the right edge.
        assert!(svg.contains(&format!(r#"cx="{LEFT:.1}""#)));
        assert!(svg.contains(&format!(r#"cx="{:.1}""#, WIDTH - RIGHT)));
    }
}
