//! The benchmark's rows, their growth (log–log slopes) and the CSV and
//! markdown that record them.

use std::fmt::Write as _;

/// How a run ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Status {
    /// Reached the preset's threshold.
    Converged,
    /// Stopped at the preset's shot budget above the threshold.
    ShotBudget,
    /// Stopped at the wall-clock limit (seconds); the figures are the progress reached.
    OverLimit(f64),
    /// Ended with an error (the reason, e.g. an exit code or signal).
    Failed(String),
}

impl Status {
    pub fn label(&self) -> String {
        match self {
            Status::Converged => "converged".to_owned(),
            Status::ShotBudget => "shot budget".to_owned(),
            Status::OverLimit(limit) => format!("> limit ({limit:.0} s)"),
            Status::Failed(why) => format!("failed: {why}"),
        }
    }

    /// Whether the run finished (its cost is that of the whole solve).
    pub fn finished(&self) -> bool {
        matches!(self, Status::Converged | Status::ShotBudget)
    }
}

/// One family × size × preset.
#[derive(Clone, Debug)]
pub struct Row {
    pub family: String,
    pub target: usize,
    pub triangles: usize,
    pub preset: String,
    pub status: Status,
    pub wall_seconds: f64,
    pub cpu_seconds: f64,
    pub peak_rss_bytes: u64,
    /// From the solver's --stats-json (absent when it wrote none).
    pub elements: Option<u64>,
    pub vertices: Option<u64>,
    pub shots: Option<u64>,
    pub rays: Option<u64>,
    pub unshot_fraction: Option<f64>,
    pub solution_bytes: Option<u64>,
    /// The largest checkpoint seen during the run (0: none was written).
    pub checkpoint_bytes: u64,
}

const MIB: f64 = 1024.0 * 1024.0;

fn opt<T: std::fmt::Display>(v: &Option<T>) -> String {
    v.as_ref().map_or_else(String::new, |x| x.to_string())
}

pub fn csv(rows: &[Row]) -> String {
    let mut s = String::from(
        "family,target_triangles,triangles,preset,status,wall_s,cpu_s,peak_rss_bytes,elements,vertices,shots,rays,unshot_fraction,solution_bytes,checkpoint_bytes\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{},\"{}\",{:.3},{:.3},{},{},{},{},{},{},{},{}",
            r.family,
            r.target,
            r.triangles,
            r.preset,
            r.status.label().replace('"', "'"),
            r.wall_seconds,
            r.cpu_seconds,
            r.peak_rss_bytes,
            opt(&r.elements),
            opt(&r.vertices),
            opt(&r.shots),
            opt(&r.rays),
            r.unshot_fraction
                .map_or_else(String::new, |u| format!("{u:.6}")),
            opt(&r.solution_bytes),
            r.checkpoint_bytes
        );
    }
    s
}

/// Reads back the rows [`csv`] wrote (to merge several benchmark runs into
/// one report). Errors name the line.
pub fn parse_csv(text: &str) -> Result<Vec<Row>, String> {
    let mut rows = Vec::new();
    for (i, line) in text.lines().enumerate().skip(1) {
        if line.trim().is_empty() {
            continue;
        }
        rows.push(parse_row(line).map_err(|e| format!("line {}: {e}: {line}", i + 1))?);
    }
    Ok(rows)
}

fn parse_row(line: &str) -> Result<Row, String> {
    // The status is the one quoted field (it may hold commas); split around it.
    let (head, rest) = line.split_once(",\"").ok_or("no quoted status")?;
    let (status, tail) = rest.split_once("\",").ok_or("unterminated status")?;
    let head: Vec<&str> = head.split(',').collect();
    let tail: Vec<&str> = tail.split(',').collect();
    if head.len() != 4 || tail.len() != 10 {
        return Err(format!(
            "{} + 1 + {} fields, not 4 + 1 + 10",
            head.len(),
            tail.len()
        ));
    }
    fn num<T: std::str::FromStr>(field: &str, name: &str) -> Result<T, String> {
        field
            .parse()
            .map_err(|_| format!("{name} `{field}` is not a number"))
    }
    fn maybe<T: std::str::FromStr>(field: &str, name: &str) -> Result<Option<T>, String> {
        if field.is_empty() {
            Ok(None)
        } else {
            num(field, name).map(Some)
        }
    }
    let status = if status == "converged" {
        Status::Converged
    } else if status == "shot budget" {
        Status::ShotBudget
    } else if let Some(limit) = status
        .strip_prefix("> limit (")
        .and_then(|r| r.strip_suffix(" s)"))
    {
        Status::OverLimit(num(limit, "limit")?)
    } else {
        Status::Failed(status.strip_prefix("failed: ").unwrap_or(status).to_owned())
    };
    Ok(Row {
        family: head[0].to_owned(),
        target: num(head[1], "target_triangles")?,
        triangles: num(head[2], "triangles")?,
        preset: head[3].to_owned(),
        status,
        wall_seconds: num(tail[0], "wall_s")?,
        cpu_seconds: num(tail[1], "cpu_s")?,
        peak_rss_bytes: num(tail[2], "peak_rss_bytes")?,
        elements: maybe(tail[3], "elements")?,
        vertices: maybe(tail[4], "vertices")?,
        shots: maybe(tail[5], "shots")?,
        rays: maybe(tail[6], "rays")?,
        unshot_fraction: maybe(tail[7], "unshot_fraction")?,
        solution_bytes: maybe(tail[8], "solution_bytes")?,
        checkpoint_bytes: num(tail[9], "checkpoint_bytes")?,
    })
}

/// The least-squares slope of ln y against ln x, or None with fewer than two
/// distinct x. On log–log axes a slope of 1 is linear growth.
pub fn log_log_slope(points: &[(f64, f64)]) -> Option<f64> {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    let n = logs.len() as f64;
    let mx = logs.iter().map(|p| p.0).sum::<f64>() / n;
    let my = logs.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = logs.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = logs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (logs.len() >= 2 && sxx > 1e-12).then(|| sxy / sxx)
}

/// The smallest count the growth slopes use: 10k nominal, less the ±20% the
/// generator allows.
pub const SLOPE_FROM_TRIANGLES: usize = 8_000;

/// One family × preset's growth from 10k triangles up, over finished runs.
#[derive(Clone, Debug)]
pub struct Growth {
    pub family: String,
    pub preset: String,
    pub points: usize,
    pub cpu_slope: Option<f64>,
    pub rss_slope: Option<f64>,
}

pub fn growth(rows: &[Row]) -> Vec<Growth> {
    let mut keys: Vec<(String, String)> = Vec::new();
    for r in rows {
        let key = (r.family.clone(), r.preset.clone());
        if !keys.contains(&key) {
            keys.push(key);
        }
    }
    keys.into_iter()
        .map(|(family, preset)| {
            let used: Vec<&Row> = rows
                .iter()
                .filter(|r| r.family == family && r.preset == preset)
                .filter(|r| r.status.finished() && r.triangles >= SLOPE_FROM_TRIANGLES)
                .collect();
            let points = |f: &dyn Fn(&Row) -> f64| -> Vec<(f64, f64)> {
                used.iter().map(|r| (r.triangles as f64, f(r))).collect()
            };
            Growth {
                points: used.len(),
                cpu_slope: log_log_slope(&points(&|r| r.cpu_seconds)),
                rss_slope: log_log_slope(&points(&|r| r.peak_rss_bytes as f64)),
                family,
                preset,
            }
        })
        .collect()
}

pub fn markdown(rows: &[Row]) -> String {
    let mut s = String::from(
        "| family | triangles | preset | status | wall s | CPU s | peak RSS MiB | elements | vertices | shots | rays | unshot % | solution MiB | checkpoint MiB |\n\
         | --- | ---: | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {:.1} | {:.1} | {:.0} | {} | {} | {} | {} | {} | {} | {} |",
            r.family,
            r.triangles,
            r.preset,
            r.status.label(),
            r.wall_seconds,
            r.cpu_seconds,
            r.peak_rss_bytes as f64 / MIB,
            opt(&r.elements),
            opt(&r.vertices),
            opt(&r.shots),
            opt(&r.rays),
            r.unshot_fraction
                .map_or_else(String::new, |u| format!("{:.2}", 100.0 * u)),
            r.solution_bytes
                .map_or_else(String::new, |b| format!("{:.2}", b as f64 / MIB)),
            if r.checkpoint_bytes > 0 {
                format!("{:.2}", r.checkpoint_bytes as f64 / MIB)
            } else {
                "none written".to_owned()
            }
        );
    }
    s.push_str(
        "\nGrowth from 10k triangles up (least-squares slope of ln y on ln triangles, finished runs only):\n\n\
         | family | preset | runs used | CPU s slope | peak RSS slope |\n| --- | --- | ---: | ---: | ---: |\n",
    );
    for g in growth(rows) {
        let slope = |v: Option<f64>| v.map_or_else(|| "n/a".to_owned(), |x| format!("{x:.2}"));
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} |",
            g.family,
            g.preset,
            g.points,
            slope(g.cpu_slope),
            slope(g.rss_slope)
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slope_of_a_power_law_is_its_exponent() {
        // y = 3 x^1.5 exactly: least squares on the logs recovers 1.5 to
        // rounding (1e-12).
        let points: Vec<(f64, f64)> = [1e4, 1e5, 1e6]
            .iter()
            .map(|&x: &f64| (x, 3.0 * x.powf(1.5)))
            .collect();
        assert!((log_log_slope(&points).unwrap() - 1.5).abs() < 1e-12);
        // Noisy points around y = x: the slope of (1, 1), (10, 20), (100, 100)
        // by hand is ln(100)/ln(100) = 1 (the middle point is symmetric in x
        // and shifts the intercept only).
        let s = log_log_slope(&[(1.0, 1.0), (10.0, 20.0), (100.0, 100.0)]).unwrap();
        assert!((s - 1.0).abs() < 1e-12, "{s}");
        assert_eq!(log_log_slope(&[(5.0, 1.0)]), None);
        assert_eq!(log_log_slope(&[(5.0, 1.0), (5.0, 2.0)]), None);
    }

    #[test]
    fn growth_uses_only_finished_runs_from_10k() {
        let row = |triangles: usize, cpu: f64, status: Status| Row {
            family: "f".into(),
            target: triangles,
            triangles,
            preset: "draft".into(),
            status,
            wall_seconds: cpu,
            cpu_seconds: cpu,
            peak_rss_bytes: triangles as u64,
            elements: None,
            vertices: None,
            shots: None,
            rays: None,
            unshot_fraction: None,
            solution_bytes: None,
            checkpoint_bytes: 0,
        };
        let rows = [
            row(1_000, 1e6, Status::Converged),
            row(10_000, 10.0, Status::Converged),
            row(100_000, 1000.0, Status::ShotBudget),
            row(1_000_000, 120.0, Status::OverLimit(120.0)),
        ];
        let g = &growth(&rows)[0];
        assert_eq!(g.points, 2);
        assert!((g.cpu_slope.unwrap() - 2.0).abs() < 1e-12);
        assert!((g.rss_slope.unwrap() - 1.0).abs() < 1e-12);
        assert!(markdown(&rows).contains("> limit (120 s)"));
        assert_eq!(csv(&rows).lines().count(), 5);
        // The CSV reads back to the same rows (the markdown of both agrees).
        let back = parse_csv(&csv(&rows)).unwrap();
        assert_eq!(markdown(&back), markdown(&rows));
        let failed = [row(10, 1.0, Status::Failed("Exited(1): a, b".into()))];
        assert_eq!(
            parse_csv(&csv(&failed)).unwrap()[0].status,
            failed[0].status
        );
        assert!(parse_csv("header\nf,1,2\n")
            .unwrap_err()
            .starts_with("line 2"));
    }
}
