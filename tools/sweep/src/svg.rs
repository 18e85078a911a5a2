//! A log–log scatter plot of error against seconds as hand-written SVG, with the
//! Pareto front drawn as a line through ringed points. No plotting dependency:
//! the plot is a few dozen elements.

use bench_support::svg::{decades, escape, polyline, Page, TAB10};
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

const PAGE: Page = Page {
    width: 760.0,
    height: 480.0,
    left: 70.0,
    right: 190.0,
    top: 40.0,
    bottom: 55.0,
    title_size: 15,
    x_tick_gap: 18.0,
    y_label_x: 18.0,
    frame_stroke: "#444",
};

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
    PAGE.open(&mut svg, title);
    if shown.is_empty() {
        let _ = writeln!(
            svg,
            r#"<text x="{}" y="80">no drawable points</text></svg>"#,
            PAGE.left
        );
        return svg;
    }
    // `shown` is not empty and holds only positive finite values.
    let x_decades = decades(shown.iter().map(|p| p.x)).unwrap_or((0, 1));
    let y_decades = decades(shown.iter().map(|p| p.y)).unwrap_or((0, 1));
    let (x_axis, y_axis) = PAGE.axes(x_decades, y_decades);
    let sx = |x: f64| x_axis.at(x);
    let sy = |y: f64| y_axis.at(y);
    PAGE.decade_grid(&mut svg, (x_axis, y_axis), x_label, y_label);
    // Groups in order of first appearance, one colour each.
    let mut groups: Vec<&str> = Vec::new();
    for p in &shown {
        if !groups.contains(&p.group.as_str()) {
            groups.push(&p.group);
        }
    }
    let colour = |g: &str| {
        let k = groups.iter().position(|&x| x == g).unwrap_or(0);
        TAB10[k % TAB10.len()]
    };
    // The front: a staircase would suggest points that do not exist, so it is a
    // plain polyline through the front's points.
    let front_points: Vec<&PlotPoint> = front
        .iter()
        .filter_map(|&i| points.get(i))
        .filter(|p| drawable(p))
        .collect();
    if front_points.len() > 1 {
        polyline(
            &mut svg,
            front_points.iter().map(|p| (sx(p.x), sy(p.y))),
            r##"stroke="#000" stroke-width="1.5" stroke-dasharray="5,3""##,
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
    let lx = PAGE.left + PAGE.plot_width() + 15.0;
    for (k, g) in groups.iter().enumerate() {
        let y = PAGE.top + 10.0 + 18.0 * k as f64;
        let _ = writeln!(
            svg,
            r#"<circle cx="{lx}" cy="{y}" r="4" fill="{}"/><text x="{}" y="{}">{}</text>"#,
            colour(g),
            lx + 10.0,
            y + 4.0,
            escape(g)
        );
    }
    let y = PAGE.top + 10.0 + 18.0 * groups.len() as f64 + 6.0;
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
        assert!(svg.contains(&format!(r#"cx="{:.1}""#, PAGE.left)));
        assert!(svg.contains(&format!(r#"cx="{:.1}""#, PAGE.width - PAGE.right)));
    }
}
