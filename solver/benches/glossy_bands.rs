//! What each SH band costs and buys on a glossy floor (issue 4, "Speed and
//! accuracy"): for α in {0.3, 0.15, 0.1, 0.05} and the draft and medium error
//! targets, the order L chosen, coefficients per vertex, solve seconds, file
//! size, and the error of the highlight against a reference solved with
//! L = 64 (or the order where the fit reaches rounding, whichever is lower).
//! Prints the table recorded in `docs/sh-bands.md` and writes the plot
//! `docs/glossy-bands.svg` (hand-written SVG, no dependency).
//!
//! Scene: `config/glossy_floor.toml` (3 m × 4 m room, glossy floor Kd 0.2,
//! Ks 0.6, a 0.4 m light under the ceiling) with the floor's α replaced, the
//! floor cut into 16 × 16 patches and the rest into 2 × 2 (the light 1), a
//! fixed mesh (adaptive off, so every run has the same vertices), 4 rays per
//! receiver, and the same shots for every run (threshold 0.02, at most 120).
//!
//! Highlight error: the radiance of every floor vertex toward the scene's
//! camera eye (0, 0.6, 1.8), red channel, from the SH the solver stored,
//! against the reference's at the same vertex; `max` and `RMS` of the
//! difference over the floor's vertices, relative to the reference's
//! brightest floor vertex (the highlight's peak).
//!
//! Run: `cargo bench -p solver --bench glossy_bands` (about 2–4 minutes on the
//! 2-core bench machine in release).

use bench_support::svg::{frame, polyline, Axis, TAB10};
use glam::DVec3;
use solution::format::SolveMode;
use solution::sh;
use solver::brdf;
use solver::scene::{load_scene, Scene};
use solver::settings::{Preset, SolverSettings};
use solver::solve::Solver;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

const ALPHAS: [f64; 4] = [0.3, 0.15, 0.1, 0.05];
const REFERENCE_ORDER: u32 = 64;

struct Run {
    order: u32,
    seconds: f64,
    shots: u64,
    file_bytes: usize,
    /// Floor vertices' radiance toward the eye (red).
    toward_eye: Vec<f64>,
}

fn scene(alpha: f64) -> (Scene, SolverSettings, DVec3) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../config/glossy_floor.toml");
    let loaded = load_scene(&path, &Default::default()).expect("bundled scene loads");
    let mut settings = SolverSettings::preset(Preset::Medium);
    settings.apply(&loaded.settings);
    settings.mode = SolveMode::Directional;
    settings.adaptive = false;
    settings.samples = 4;
    settings.threshold = 0.02;
    settings.max_shots = 120;
    let mut scene = loaded.scene;
    let floor = scene
        .materials
        .iter()
        .position(|m| m.name == "glossy_floor")
        .expect("the floor material");
    scene.materials[floor].alpha = alpha;
    for p in &mut scene.polygons {
        if p.material == floor {
            p.patches = 16;
        }
    }
    scene.fill_default_patches(2);
    let eye = scene
        .camera
        .map_or(DVec3::new(0.0, 0.6, 1.8), |c| DVec3::from_array(c.eye));
    (scene, settings, eye)
}

fn solve(alpha: f64, target: f64) -> Run {
    let (scene, mut settings, eye) = scene(alpha);
    settings.sh_error_target = target;
    settings.max_sh_order = REFERENCE_ORDER;
    let start = Instant::now();
    let mut solver = Solver::new(&scene, &settings).expect("solver builds");
    while solver.step().is_some() {}
    let seconds = start.elapsed().as_secs_f64();
    let solution = solver.to_solution(false);
    let file_bytes = solution::format::encode(&solution)
        .expect("solution encodes")
        .len();
    let mesh = solver.mesh();
    let orders = solver.directional().expect("directional").surface_orders();
    let order = orders.iter().copied().max().unwrap_or(0);
    let mut toward_eye = Vec::new();
    let mut basis = vec![0.0; sh::coefficient_count(order)];
    for (v, mv) in mesh.vertices.iter().enumerate() {
        let surface = &mesh.surfaces[mv.surface as usize];
        if orders[mv.surface as usize] == 0 {
            continue;
        }
        let (o, c) = solver.vertex_sh(v as u32).expect("vertex");
        let to_eye = (eye - (mv.position + solver.offset())).normalize();
        sh::eval_basis(
            o,
            sh::to_local(to_eye, surface.normal, surface.tangent),
            &mut basis,
        );
        toward_eye.push(c.chunks_exact(3).zip(&basis).map(|(c, y)| c[0] * y).sum());
    }
    Run {
        order,
        seconds,
        shots: solver.progress().shots,
        file_bytes,
        toward_eye,
    }
}

/// (max, RMS) of the difference to the reference, relative to its peak.
fn highlight_error(run: &Run, reference: &Run) -> (f64, f64) {
    let peak = reference.toward_eye.iter().copied().fold(0.0, f64::max);
    let n = run.toward_eye.len().max(1) as f64;
    let (mut max, mut sq) = (0.0f64, 0.0);
    for (a, b) in run.toward_eye.iter().zip(&reference.toward_eye) {
        let d = (a - b).abs() / peak;
        max = max.max(d);
        sq += d * d;
    }
    (max, (sq / n).sqrt())
}

struct Row {
    alpha: f64,
    target: &'static str,
    run: Run,
    max: f64,
    rms: f64,
}

fn main() {
    let targets = [("draft 1e-2", 1e-2), ("medium 1e-3", 1e-3)];
    let mut rows = Vec::new();
    let mut references = Vec::new();
    for alpha in ALPHAS {
        // The reference: L = 64 unwindowed, or lower where the fit is already
        // at rounding (the target then selects the first order reaching it).
        let fit = brdf::LegendreFit::new(alpha, REFERENCE_ORDER);
        let floor_error = fit.error(REFERENCE_ORDER, brdf::Window::None).max(1e-13);
        let reference = solve(alpha, floor_error * (1.0 + 1e-9));
        for (name, target) in targets {
            let run = solve(alpha, target);
            let (max, rms) = highlight_error(&run, &reference);
            rows.push(Row {
                alpha,
                target: name,
                run,
                max,
                rms,
            });
        }
        references.push(reference);
    }
    let mut table = String::new();
    let _ = writeln!(
        table,
        "| α | target | L | coeff./vertex (RGB) | solve s | shots | file KiB | highlight max err | highlight RMS err |"
    );
    let _ = writeln!(
        table,
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"
    );
    for (alpha, reference) in ALPHAS.iter().zip(&references) {
        for r in rows.iter().filter(|r| r.alpha == *alpha) {
            let _ = writeln!(
                table,
                "| {} | {} | {} | {} | {:.2} | {} | {:.0} | {:.2e} | {:.2e} |",
                r.alpha,
                r.target,
                r.run.order,
                3 * sh::coefficient_count(r.run.order),
                r.run.seconds,
                r.run.shots,
                r.run.file_bytes as f64 / 1024.0,
                r.max,
                r.rms
            );
        }
        let _ = writeln!(
            table,
            "| {} | reference | {} | {} | {:.2} | {} | {:.0} | — | — |",
            alpha,
            reference.order,
            3 * sh::coefficient_count(reference.order),
            reference.seconds,
            reference.shots,
            reference.file_bytes as f64 / 1024.0
        );
    }
    println!("{table}");
    let svg = plot(&rows, &references);
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/glossy-bands.svg");
    let tmp = out.with_extension("svg.tmp");
    if std::fs::write(&tmp, svg)
        .and_then(|_| std::fs::rename(&tmp, &out))
        .is_ok()
    {
        println!("wrote {}", out.display());
    } else {
        eprintln!("could not write {}", out.display());
    }
}

/// Two panels: highlight error (max and RMS, log scale) against L, and solve
/// seconds against L (file size as labels), one marker per run.
fn plot(rows: &[Row], references: &[Run]) -> String {
    let (w, h) = (900.0, 380.0);
    let (pw, ph) = (360.0, 260.0);
    let panels = [(70.0, 50.0), (520.0, 50.0)];
    // The order L from 0 to 70 across a panel, in that panel's pixels.
    let x_of = |l: f64, x0: f64| Axis::linear(0.0, 70.0, x0, x0 + pw).at(l);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
    // Error panel: log10 from 1e-6 to 1.
    let (x0, y0) = panels[0];
    let y_err = |e: f64| Axis::log(-6.0, 0.0, y0 + ph, y0).at(e.max(1e-6));
    let _ = writeln!(
        s,
        r#"<text x="{}" y="30" text-anchor="middle">Highlight error vs reference, L = 64 or fit at rounding (rel. to peak)</text>"#,
        x0 + pw / 2.0
    );
    frame(&mut s, x0, y0, pw, ph, "black");
    for k in 0..=6 {
        let y = y0 + ph * k as f64 / 6.0;
        let _ = writeln!(
            s,
            r##"<line x1="{x0}" y1="{y}" x2="{}" y2="{y}" stroke="#ddd"/><text x="{}" y="{}" text-anchor="end">1e-{k}</text>"##,
            x0 + pw,
            x0 - 6.0,
            y + 4.0
        );
    }
    // Second panel: seconds, linear.
    let (x1, y1) = panels[1];
    let max_s = rows
        .iter()
        .map(|r| r.run.seconds)
        .chain(references.iter().map(|r| r.seconds))
        .fold(0.0, f64::max)
        .max(1e-3);
    let y_sec = |t: f64| Axis::linear(0.0, max_s, y1 + ph, y1).at(t);
    let _ = writeln!(
        s,
        r#"<text x="{}" y="30" text-anchor="middle">Solve seconds vs L (labels: file KiB)</text>"#,
        x1 + pw / 2.0
    );
    frame(&mut s, x1, y1, pw, ph, "black");
    for k in 0..=4 {
        let t = max_s * k as f64 / 4.0;
        let y = y_sec(t);
        let _ = writeln!(
            s,
            r##"<line x1="{x1}" y1="{y}" x2="{}" y2="{y}" stroke="#ddd"/><text x="{}" y="{}" text-anchor="end">{t:.1}</text>"##,
            x1 + pw,
            x1 - 6.0,
            y + 4.0
        );
    }
    for (x, _) in panels {
        for l in (0..=70).step_by(10) {
            let xx = x_of(l as f64, x);
            let _ = writeln!(
                s,
                r#"<text x="{xx}" y="{}" text-anchor="middle">{l}</text>"#,
                y0 + ph + 16.0
            );
        }
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{}" text-anchor="middle">SH order L</text>"#,
            x + pw / 2.0,
            y0 + ph + 34.0
        );
    }
    for (i, (alpha, reference)) in ALPHAS.iter().zip(references).enumerate() {
        let c = TAB10[i % TAB10.len()];
        let mine: Vec<&Row> = rows.iter().filter(|r| r.alpha == *alpha).collect();
        // Max error: filled circles joined; RMS: open squares.
        let stroke = format!(r#"stroke="{c}""#);
        polyline(
            &mut s,
            mine.iter()
                .map(|r| (x_of(r.run.order as f64, x0), y_err(r.max))),
            &stroke,
        );
        for r in &mine {
            let x = x_of(r.run.order as f64, x0);
            let _ = writeln!(
                s,
                r#"<circle cx="{x:.1}" cy="{:.1}" r="4" fill="{c}"/><rect x="{:.1}" y="{:.1}" width="7" height="7" fill="none" stroke="{c}"/>"#,
                y_err(r.max),
                x - 3.5,
                y_err(r.rms) - 3.5
            );
        }
        let mut all: Vec<(u32, f64, usize)> = mine
            .iter()
            .map(|r| (r.run.order, r.run.seconds, r.run.file_bytes))
            .collect();
        all.push((reference.order, reference.seconds, reference.file_bytes));
        all.sort_by_key(|a| a.0);
        polyline(
            &mut s,
            all.iter().map(|a| (x_of(a.0 as f64, x1), y_sec(a.1))),
            &stroke,
        );
        for a in &all {
            let (x, y) = (x_of(a.0 as f64, x1), y_sec(a.1));
            let _ = writeln!(
                s,
                r#"<circle cx="{x:.1}" cy="{y:.1}" r="4" fill="{c}"/><text x="{:.1}" y="{:.1}" font-size="9">{:.0}</text>"#,
                x + 5.0,
                y - 5.0,
                a.2 as f64 / 1024.0
            );
        }
        let ly = y0 + ph + 50.0;
        let lx = 70.0 + 150.0 * i as f64;
        let _ = writeln!(
            s,
            r#"<circle cx="{lx}" cy="{ly}" r="4" fill="{c}"/><text x="{}" y="{}">α = {alpha}</text>"#,
            lx + 8.0,
            ly + 4.0
        );
    }
    let _ = writeln!(
        s,
        r#"<text x="670" y="{}">● max error  □ RMS error</text>"#,
        y0 + ph + 54.0
    );
    s.push_str("</svg>\n");
    s
}
