//! The documents' other methods against the solver's own, on the Cornell box
//! (design notes, "The other methods in the documents"): what each costs and
//! how far it lands from a reference.
//!
//! **Form factors.** Vertex form factors F(v←s) from two sources (the light's
//! central patch and a back-wall patch) to every vertex of a 4 × 4-patch
//! mesh, by `analytic` and `wallace` with 16 and 64 rays and by `hemicube` at
//! R = 32 … 512, timed per shot on one thread (as `Solver::vertex_form_factors`
//! runs). Reference: `analytic` with 1024 rays. Error: Σ_v |F − F_ref| / Σ_v F_ref
//! (relative L1 over the vertices) and the largest |F − F_ref|.
//!
//! **Solvers.** Progressive refinement (analytic, wallace, hemicube factors) and
//! Gauss–Seidel on the full matrix, at several patch grids, wall seconds on
//! every core. The error compares the area-weighted mean radiance of each of the
//! box's 15 non-emitting surfaces (5 room surfaces, 10 block faces) with a
//! reference: RMS over the surfaces of the relative difference (channels
//! summed), and the difference of the mean over all surfaces. Reference: a fine
//! progressive solve (analytic, 8 × 8 patches, 32 rays, threshold 2e-4, no
//! adaptive meshing, so that its mesh is the patch grid and its surface means are
//! unbiased by refinement), cached in `target/bench-cache/`. That reference is
//! itself a radiosity solution, so these two columns measure agreement with
//! it, not accuracy; beside them each solver's MARE and HDR-FLIP against the
//! committed 64 × 64 path-traced truth of the standard camera
//! (`tests/fixtures/cornell_truth_64.exr`, `common/truth.rs`; bias plus the
//! truth's 0.5% noise), the solution rasterized at 512² and box-filtered.
//!
//! Run: `cargo bench -p solver --bench methods`. The figures in
//! docs/benchmarks.md, "Methods", come from it.

#[path = "common/truth.rs"]
mod truth;

use glam::DVec3;
use solver::scene::{load_scene, Scene};
use solver::settings::{FormFactorMethod, Preset, SolverSettings};
use solver::solve::gauss_seidel::{solve_gauss_seidel, GaussSeidelLimits};
use solver::solve::Solver;
use std::path::{Path, PathBuf};
use std::time::Instant;

fn cornell(patches: u32) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../config/cornell_box.obj");
    let mut scene = load_scene(&path, &Default::default())
        .expect("config/cornell_box.obj loads")
        .scene;
    scene.fill_default_patches(patches);
    scene
}

/// The scenes give every polygon its patch count.
fn settings() -> SolverSettings {
    let mut s = SolverSettings::preset(Preset::Draft);
    s.adaptive = false;
    s.ambient = false;
    s.threshold = 1e-3;
    s.max_shots = 1_000_000;
    s
}

fn is_emitter(scene: &Scene, solver: &Solver, surface: usize) -> bool {
    scene.materials[solver.mesh().surfaces[surface].material]
        .emission
        .max_element()
        > 0.0
}

fn form_factors(scene: &Scene) {
    println!("## Form factors: vertex factors from one source patch, 4 x 4 patches");
    let base = settings();
    let probe = Solver::new(scene, &base).expect("the box solves");
    let mesh = probe.mesh();
    // The light's patch nearest its centre, and the back wall's central patch
    // (the wall facing -z).
    let light_centre = {
        let ps: Vec<usize> = (0..mesh.patches.len())
            .filter(|&p| is_emitter(scene, &probe, mesh.patches[p].surface as usize))
            .collect();
        let c = ps
            .iter()
            .map(|&p| mesh.patches[p].corners[0])
            .sum::<DVec3>()
            / ps.len() as f64;
        *ps.iter()
            .min_by(|&&a, &&b| {
                let d = |p: usize| {
                    let poly = mesh.patches[p].polygon();
                    (poly.iter().copied().sum::<DVec3>() / poly.len() as f64 - c).length()
                };
                d(a).total_cmp(&d(b))
            })
            .expect("the box has a light")
    };
    let wall = (0..mesh.patches.len())
        .filter(|&p| {
            let s = &mesh.surfaces[mesh.patches[p].surface as usize];
            s.normal.z < -0.99 && !is_emitter(scene, &probe, mesh.patches[p].surface as usize)
        })
        .nth(5)
        .expect("the box has a back wall");
    println!(
        "{} vertices; sources: light patch {light_centre}, back-wall patch {wall}",
        mesh.vertices.len()
    );
    println!("| method | source | ms per shot | relative L1 error | max abs error |");
    println!("|---|---|---|---|---|");
    for (name, source) in [("light", light_centre as u32), ("wall", wall as u32)] {
        let with = |method: FormFactorMethod, samples: u32, resolution: u32| {
            let mut s = base.clone();
            s.form_factors = method;
            s.samples = samples;
            s.hemicube_resolution = resolution;
            let solver = Solver::new(scene, &s).expect("the box solves");
            // Warm-up, then the best of three.
            let mut factors = solver.vertex_form_factors(source);
            let mut best = f64::INFINITY;
            for _ in 0..3 {
                let t = Instant::now();
                factors = solver.vertex_form_factors(source);
                best = best.min(t.elapsed().as_secs_f64());
            }
            (factors, best)
        };
        let (reference, _) = with(FormFactorMethod::Analytic, 1024, 2);
        let total: f64 = reference.iter().sum();
        let mut rows: Vec<(String, FormFactorMethod, u32, u32)> = Vec::new();
        for samples in [16, 64] {
            rows.push((
                format!("analytic, {samples} rays"),
                FormFactorMethod::Analytic,
                samples,
                2,
            ));
            rows.push((
                format!("wallace, {samples} rays"),
                FormFactorMethod::Wallace,
                samples,
                2,
            ));
        }
        for r in [32, 64, 128, 256, 512] {
            rows.push((
                format!("hemicube, R = {r}"),
                FormFactorMethod::Hemicube,
                1,
                r,
            ));
        }
        for (label, method, samples, r) in rows {
            let (f, seconds) = with(method, samples, r);
            let l1: f64 = f.iter().zip(&reference).map(|(a, b)| (a - b).abs()).sum();
            let max = f
                .iter()
                .zip(&reference)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            println!(
                "| {label} | {name} | {:.2} | {:.4} | {:.2e} |",
                1e3 * seconds,
                l1 / total,
                max
            );
        }
    }
}

/// Area-weighted mean radiance (channels summed) of every non-emitting surface,
/// and of all of them together as the last entry.
fn surface_means(scene: &Scene, solver: &Solver, patch_radiance: Option<&[DVec3]>) -> Vec<f64> {
    let mesh = solver.mesh();
    let count = mesh.surfaces.len() + 1;
    let (mut sum, mut area) = (vec![0.0; count], vec![0.0; count]);
    for (p, patch) in mesh.patches.iter().enumerate() {
        let k = patch.surface as usize;
        if is_emitter(scene, solver, k) {
            continue;
        }
        let integral = match patch_radiance {
            Some(l) => l[p].element_sum() * patch.area,
            None => solver
                .patch_weights(p as u32)
                .iter()
                .map(|&(v, w)| solver.vertex_radiance()[v as usize].element_sum() * w)
                .sum(),
        };
        for slot in [k, count - 1] {
            sum[slot] += integral;
            area[slot] += patch.area;
        }
    }
    sum.iter()
        .zip(&area)
        .map(|(s, &a)| if a > 0.0 { s / a } else { f64::NAN })
        .collect()
}

/// (RMS relative surface error, relative error of the overall mean).
fn compare(means: &[f64], reference: &[f64]) -> (f64, f64) {
    let n = means.len() - 1;
    let mut sq = 0.0;
    let mut count = 0;
    for k in 0..n {
        if means[k].is_finite() && reference[k].is_finite() && reference[k] > 0.0 {
            sq += ((means[k] - reference[k]) / reference[k]).powi(2);
            count += 1;
        }
    }
    (
        (sq / count.max(1) as f64).sqrt(),
        (means[n] - reference[n]) / reference[n],
    )
}

fn reference_means() -> Vec<f64> {
    let cache = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../target/bench-cache/methods-reference.json");
    if let Some(v) = std::fs::read_to_string(&cache)
        .ok()
        .and_then(|s| serde_json::from_str::<Vec<f64>>(&s).ok())
    {
        return v;
    }
    let scene = cornell(8);
    let mut s = settings();
    s.samples = 32;
    s.threshold = 2e-4;
    s.seed = 99;
    let t = Instant::now();
    let mut solver = Solver::new(&scene, &s).expect("the box solves");
    while solver.step().is_some() {}
    let means = surface_means(&scene, &solver, None);
    println!(
        "(reference: {} shots in {:.1} s, cached in {})",
        solver.progress().shots,
        t.elapsed().as_secs_f64(),
        cache.display()
    );
    if let Some(dir) = cache.parent() {
        let _ = std::fs::create_dir_all(dir);
    }
    let _ = std::fs::write(&cache, serde_json::to_string(&means).unwrap_or_default());
    means
}

fn solvers() {
    println!();
    println!("## Solvers: Cornell box, surface means against the reference");
    let reference = reference_means();
    let truth = truth::CornellTruth::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join(".."));
    println!("{}", truth.describe());
    println!(
        "| solver | patches | n | seconds | iterations | RMS surface error | mean error | \
         MARE vs truth | HDR-FLIP vs truth |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for (patches, method, samples, r) in [
        (3, FormFactorMethod::Analytic, 16, 2),
        (6, FormFactorMethod::Analytic, 16, 2),
        (6, FormFactorMethod::Wallace, 16, 2),
        (6, FormFactorMethod::Hemicube, 1, 64),
        (6, FormFactorMethod::Hemicube, 1, 256),
    ] {
        let scene = cornell(patches);
        let mut s = settings();
        s.form_factors = method;
        s.samples = samples;
        s.hemicube_resolution = r;
        let t = Instant::now();
        let mut solver = Solver::new(&scene, &s).expect("the box solves");
        while solver.step().is_some() {}
        let seconds = t.elapsed().as_secs_f64();
        let (rms, mean) = compare(&surface_means(&scene, &solver, None), &reference);
        let against_truth = truth.error(&solver.to_solution(false));
        let label = match method {
            FormFactorMethod::Hemicube => format!("progressive, hemicube R = {r}"),
            FormFactorMethod::Wallace => format!("progressive, wallace {samples} rays"),
            FormFactorMethod::Analytic => format!("progressive, analytic {samples} rays"),
        };
        println!(
            "| {label} | {patches} | {} | {seconds:.2} | {} shots | {rms:.4} | {mean:+.4} | {:.2}% | {:.3} |",
            solver.mesh().patches.len(),
            solver.progress().shots,
            100.0 * against_truth.mare,
            against_truth.flip
        );
    }
    for (patches, r) in [(3, 64), (6, 64), (6, 128), (8, 128), (12, 128)] {
        let scene = cornell(patches);
        let mut s = settings();
        s.hemicube_resolution = r;
        let limits = GaussSeidelLimits {
            tolerance: 1e-6,
            ..Default::default()
        };
        let t = Instant::now();
        let result = solve_gauss_seidel(&scene, &s, &limits).expect("the box solves");
        let seconds = t.elapsed().as_secs_f64();
        let solver = Solver::new(&scene, &s).expect("the box solves");
        let means = surface_means(&scene, &solver, Some(&result.patch_radiance));
        let (rms, mean) = compare(&means, &reference);
        let against_truth = truth.error(&result.solution);
        println!(
            "| gauss-seidel, R = {r} | {patches} | {} | {seconds:.2} (factors {:.2}) | {} sweeps | {rms:.4} | {mean:+.4} | {:.2}% | {:.3} |",
            result.patch_radiance.len(),
            result.form_factor_seconds,
            result.sweeps,
            100.0 * against_truth.mare,
            against_truth.flip
        );
    }
}

fn main() {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!("methods bench: {threads} threads");
    form_factors(&cornell(4));
    solvers();
}
