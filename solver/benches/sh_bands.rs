//! How many SH bands a glossy lobe costs: the order chosen per α and error target,
//! the storage per vertex, the time per basis evaluation, and how each ringing
//! remedy changes the lobe. Prints the figures recorded in `docs/sh-bands.md` and
//! `docs/lab/sh-ringing.md`.
//!
//! Run: `cargo bench -p solver --bench sh_bands`.

use glam::{DVec3, Vec3};
use solution::sh;
use solver::brdf::{self, GlossyLobe, Window};
use std::hint::black_box;
use std::time::Instant;

/// `sh_error_target` of each preset in `config/presets.toml` (read from the file the
/// solver embeds, so these figures follow the presets).
fn preset_targets() -> Vec<(String, f64)> {
    let text = include_str!("../../config/presets.toml");
    let mut section = String::new();
    let mut out = Vec::new();
    for line in text.lines() {
        let line = line.split('#').next().unwrap_or("").trim();
        if let Some(name) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
            section = name.to_string();
        } else if let Some(value) = line.strip_prefix("sh_error_target") {
            if let Some(v) = value
                .trim()
                .strip_prefix('=')
                .and_then(|v| v.trim().parse().ok())
            {
                out.push((section.clone(), v));
            }
        }
    }
    out
}

fn directions(n: usize) -> Vec<DVec3> {
    let mut seed = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| {
            let z = 2.0 * next() - 1.0;
            let phi = 2.0 * std::f64::consts::PI * next();
            let s = (1.0 - z * z).sqrt();
            DVec3::new(s * phi.cos(), s * phi.sin(), z)
        })
        .collect()
}

/// Fastest of 9 runs of the time per call, in nanoseconds. The bench machine is
/// shared (2 cores, other builds running), so the minimum, the run least disturbed
/// by preemption, is the stable estimate of the uncontended cost.
fn time_per_call(calls: usize, mut f: impl FnMut()) -> f64 {
    let calls = (calls / 4).max(50);
    let runs: Vec<f64> = (0..9)
        .map(|_| {
            let start = Instant::now();
            for _ in 0..calls {
                f();
            }
            start.elapsed().as_nanos() as f64 / calls as f64
        })
        .collect();
    runs.into_iter().fold(f64::INFINITY, f64::min)
}

fn ns_eval_basis(order: u32, dirs: &[DVec3]) -> (f64, f64) {
    let n = sh::coefficient_count(order);
    let mut out = vec![0.0; n];
    let mut out32 = vec![0.0f32; n];
    let calls = (2_000_000 / n).clamp(200, 200_000);
    let mut i = 0;
    let t64 = time_per_call(calls, || {
        sh::eval_basis(order, dirs[i % dirs.len()], &mut out);
        black_box(&out);
        i += 1;
    });
    let dirs32: Vec<Vec3> = dirs.iter().map(|d| d.as_vec3()).collect();
    let t32 = time_per_call(calls, || {
        sh::eval_basis_f32(order, dirs32[i % dirs32.len()], &mut out32);
        black_box(&out32);
        i += 1;
    });
    (t64, t32)
}

fn main() {
    let dirs = directions(1024);
    let targets = preset_targets();
    let default_target = targets
        .iter()
        .find(|(s, _)| s == "medium")
        .map(|t| t.1)
        .unwrap_or(1e-3);
    let max_order = 64; // SolverSettings' default max_sh_order
    println!(
        "# sh_bands (default target {default_target:e} = preset `medium`, max order {max_order})"
    );
    println!();
    println!("## Order per glossiness");
    println!("| α | preset | target | L | capped | fit error | coefficients/vertex 3(L+1)² | f32 bytes | f16 bytes | ns eval_basis f64 | ns eval_basis f32 |");
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for alpha in [0.3, 0.15, 0.1, 0.05] {
        for (preset, target) in &targets {
            let choice = brdf::choose_order(alpha, *target, max_order);
            let coefficients = 3 * sh::coefficient_count(choice.order);
            let (t64, t32) = ns_eval_basis(choice.order, &dirs);
            println!(
                "| {alpha} | {preset} | {target:e} | {} | {} | {:.2e} | {coefficients} | {} | {} | {t64:.0} | {t32:.0} |",
                choice.order,
                choice.capped,
                choice.error,
                4 * coefficients,
                2 * coefficients
            );
        }
    }
    println!();
    println!("## eval_basis time by order");
    println!("| L | (L+1)² | ns f64 | ns f32 | ns per coefficient (f64) | ns eval_rgb |");
    println!("| --- | --- | --- | --- | --- | --- |");
    for order in [0u32, 2, 8, 16, 25, 48, 64, 100] {
        let (t64, t32) = ns_eval_basis(order, &dirs);
        let n = sh::coefficient_count(order);
        let coefficients = vec![0.25f32; 3 * n];
        let mut scratch = vec![0.0; n];
        let mut i = 0;
        let rgb = time_per_call((2_000_000 / n).clamp(200, 200_000), || {
            black_box(sh::eval_rgb_with(
                order,
                &coefficients,
                dirs[i % dirs.len()],
                &mut scratch,
            ));
            i += 1;
        });
        println!(
            "| {order} | {n} | {t64:.0} | {t32:.0} | {:.2} | {rgb:.0} |",
            t64 / n as f64
        );
    }
    println!();
    println!("## Ringing remedies at the default target's order");
    println!("min: lowest value of the lobe (peak 1); L2: relative L2 error vs the exact lobe; peak: max |error| (relative to the peak 1); neg: negative mass / lobe mass; clamp L2: L2 error after clamping at 0; offset L2 / energy: Remington 1992, App. G remedy (a), constant added so that min ≥ 0, and its share of the energy.");
    println!();
    println!("| α | L | window | min | L2 | peak | neg | clamp L2 | offset L2 | offset energy |");
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for alpha in [0.3, 0.15, 0.1, 0.05, 0.03, 0.02, 0.01] {
        let order = brdf::choose_order(alpha, default_target, max_order).order;
        for window in Window::ALL {
            let r = brdf::ringing(alpha, order, window);
            println!(
                "| {alpha} | {order} | {} | {:.2e} | {:.2e} | {:.2e} | {:.2e} | {:.2e} | {:.2e} | {:.2e} |",
                window.name(),
                r.min_value,
                r.l2_error,
                r.peak_error,
                r.negative_mass,
                r.clamped_l2_error,
                r.offset_l2_error,
                r.offset_energy_fraction
            );
        }
    }
    println!();
    println!("## Windowed lobes at the order that meets the default target");
    println!("| α | window | L | capped | min | L2 | peak | neg |");
    println!("| --- | --- | --- | --- | --- | --- | --- | --- |");
    for alpha in [0.3, 0.15, 0.1, 0.05] {
        for window in Window::ALL {
            let choice = brdf::choose_order_windowed(alpha, default_target, 100, window);
            let r = brdf::ringing(alpha, choice.order, window);
            println!(
                "| {alpha} | {} | {} | {} | {:.2e} | {:.2e} | {:.2e} | {:.2e} |",
                window.name(),
                choice.order,
                choice.capped,
                r.min_value,
                r.l2_error,
                r.peak_error,
                r.negative_mass
            );
        }
    }
    println!();
    println!("## Solver-side costs per glossy material and per shot");
    println!("| α | L | GlossyLobe::new ms | table samples | table error | ns add_lobe_sh |");
    println!("| --- | --- | --- | --- | --- | --- |");
    for alpha in [0.3, 0.15, 0.1, 0.05] {
        let start = Instant::now();
        let lobe = GlossyLobe::new(alpha, 0.5, default_target, max_order, Window::None)
            .expect("valid alpha");
        let build_ms = start.elapsed().as_secs_f64() * 1e3;
        let n = sh::coefficient_count(lobe.order());
        let mut out = vec![0.0; n];
        let mut scratch = vec![0.0; n];
        let mut i = 0;
        let t = time_per_call((2_000_000 / n).clamp(200, 200_000), || {
            let d = dirs[i % dirs.len()];
            lobe.add_lobe_sh(DVec3::new(d.x, d.y, d.z.abs()), 1.0, &mut out, &mut scratch);
            i += 1;
        });
        black_box(&out);
        println!(
            "| {alpha} | {} | {build_ms:.1} | {} | {:.1e} | {t:.0} |",
            lobe.order(),
            lobe.table.samples(),
            lobe.table.interpolation_error()
        );
    }
}
