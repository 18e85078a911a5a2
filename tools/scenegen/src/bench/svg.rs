//! Log–log plots as hand-written SVG (no plotting dependency): one line per
//! series through its finished runs, hollow markers for runs stopped at the
//! limit (their value is a lower bound).

use bench_support::svg::{decades, escape, polyline, Page, TAB10};
use std::fmt::Write as _;

#[derive(Clone, Debug)]
pub struct Point {
    pub x: f64,
    pub y: f64,
    /// False for a lower bound (a run stopped at the limit).
    pub finished: bool,
}

#[derive(Clone, Debug)]
pub struct Series {
    pub name: String,
    pub points: Vec<Point>,
}

const PAGE: Page = Page {
    width: 760.0,
    height: 480.0,
    left: 70.0,
    right: 220.0,
    top: 40.0,
    bottom: 55.0,
    title_size: 14,
    x_tick_gap: 16.0,
    y_label_x: 16.0,
    frame_stroke: "black",
};
/// The scale plots' nine colours, as first drawn: tab10 without its olive.
const COLOURS: [&str; 9] = [
    TAB10[0], TAB10[1], TAB10[2], TAB10[3], TAB10[4], TAB10[5], TAB10[6], TAB10[7], TAB10[9],
];

pub fn plot(title: &str, x_label: &str, y_label: &str, series: &[Series]) -> String {
    let all = || series.iter().flat_map(|s| s.points.iter());
    let (x_axis, y_axis) = PAGE.axes(
        decades(all().map(|p| p.x)).unwrap_or((0, 1)),
        decades(all().map(|p| p.y)).unwrap_or((0, 1)),
    );
    let sx = |x: f64| x_axis.at(x);
    let sy = |y: f64| y_axis.at(y);
    let mut s = String::new();
    PAGE.open(&mut s, title);
    PAGE.decade_grid(&mut s, (x_axis, y_axis), x_label, y_label);
    for (i, series) in series.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        let mut finished: Vec<&Point> = series
            .points
            .iter()
            .filter(|p| p.finished && p.x > 0.0 && p.y > 0.0)
            .collect();
        finished.sort_by(|a, b| a.x.total_cmp(&b.x));
        if finished.len() >= 2 {
            polyline(
                &mut s,
                finished.iter().map(|p| (sx(p.x), sy(p.y))),
                &format!(r#"stroke="{colour}" stroke-width="1.5""#),
            );
        }
        for p in series.points.iter().filter(|p| p.x > 0.0 && p.y > 0.0) {
            let fill = if p.finished { colour } else { "white" };
            let _ = writeln!(
                s,
                r#"<circle cx="{:.1}" cy="{:.1}" r="4" fill="{fill}" stroke="{colour}"><title>{} {:.3e}, {:.3e}</title></circle>"#,
                sx(p.x),
                sy(p.y),
                escape(&series.name),
                p.x,
                p.y
            );
        }
        let ly = PAGE.top + 10.0 + 18.0 * i as f64;
        let lx = PAGE.width - PAGE.right + 14.0;
        let _ = writeln!(
            s,
            r#"<circle cx="{lx:.1}" cy="{ly:.1}" r="4" fill="{colour}"/><text x="{:.1}" y="{:.1}">{}</text>"#,
            lx + 10.0,
            ly + 4.0,
            escape(&series.name)
        );
    }
    let _ = writeln!(
        s,
        r#"<text x="{:.1}" y="{:.1}" font-size="11">hollow: stopped at the limit</text>"#,
        PAGE.width - PAGE.right + 8.0,
        PAGE.top + 10.0 + 18.0 * series.len() as f64 + 6.0
    );
    s.push_str("</svg>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_land_on_their_decades() {
        // A point at x = 1e4 on axes spanning 1e3..1e5 sits at the middle of
        // the plot's width (log scale).
        let series = [Series {
            name: "a<b".into(),
            points: vec![
                Point {
                    x: 1e3,
                    y: 1.0,
                    finished: true,
                },
                Point {
                    x: 1e4,
                    y: 10.0,
                    finished: true,
                },
                Point {
                    x: 1e5,
                    y: 100.0,
                    finished: false,
                },
            ],
        }];
        let svg = plot("t", "x", "y", &series);
        let middle = PAGE.left + PAGE.plot_width() / 2.0;
        assert!(svg.contains(&format!(r#"cx="{middle:.1}""#)), "{svg}");
        assert!(svg.contains("a&lt;b") && svg.contains(r#"fill="white" stroke"#));
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    }
}
