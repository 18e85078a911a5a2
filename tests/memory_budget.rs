//! `solver solve --memory-budget`: the child's peak resident set (wait4's
//! ru_maxrss) stays under the budget, a near-mirror's SH order is capped with
//! a warning that says what it costs, and a scene too large for the budget is
//! refused with the estimate and the budget, before its state is allocated.
//!
//! The scene is generated here: the bundled Cornell box (16 quads) with a
//! tessellated sphere of 1,984 triangles in MTL `Ns 1000` (α = √(2/1002) ≈
//! 0.045, `solver/src/scene/mtl.rs`), Ks 0.9: at `--preset medium` its 8 × 8
//! patches per triangle give about 127,000 elements, and the lobe asks for
//! SH order ≈ 60, 3 · 61² f64 per array per vertex: tens of GB unbudgeted.

// Only the binary helper is used here; the others serve the other tests.
#[allow(dead_code)]
mod common;

use bench_support::child::{Ending, Measuring};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// Writes the Cornell box with a mirror sphere into `dir`; returns the OBJ.
/// The sphere: `slices` × `stacks` UV tessellation (triangles at the poles,
/// quads split in two elsewhere: 2 · slices · (stacks − 1) triangles), wound
/// counter-clockwise seen from outside, centred clear of both blocks and the
/// light.
pub fn write_mirror_sphere_scene(dir: &Path, slices: usize, stacks: usize) -> PathBuf {
    let config = Path::new(env!("CARGO_MANIFEST_DIR")).join("config");
    let obj = std::fs::read_to_string(config.join("cornell_box.obj")).unwrap();
    let mut mtl = std::fs::read_to_string(config.join("cornell_box.mtl")).unwrap();
    mtl.push_str("\nnewmtl mirror\nKd 0.05 0.05 0.05\nKs 0.9 0.9 0.9\nNs 1000\n");
    let mut text = obj.replace("mtllib cornell_box.mtl", "mtllib mirror_sphere.mtl");
    let base = obj.lines().filter(|l| l.starts_with("v ")).count();
    let (centre, radius) = ([150.0, 330.0, 380.0], 90.0);
    text.push_str("\no mirror_sphere\nusemtl mirror\n");
    // Rings 1..stacks-1 of `slices` vertices, then the two poles.
    for i in 1..stacks {
        let theta = std::f64::consts::PI * i as f64 / stacks as f64;
        for j in 0..slices {
            let phi = 2.0 * std::f64::consts::PI * j as f64 / slices as f64;
            let d = [
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            ];
            text.push_str(&format!(
                "v {} {} {}\n",
                centre[0] + radius * d[0],
                centre[1] + radius * d[1],
                centre[2] + radius * d[2]
            ));
        }
    }
    let ring = |i: usize, j: usize| base + 1 + (i - 1) * slices + j % slices;
    let top = base + 1 + (stacks - 1) * slices;
    let bottom = top + 1;
    text.push_str(&format!(
        "v {} {} {}\nv {} {} {}\n",
        centre[0],
        centre[1] + radius,
        centre[2],
        centre[0],
        centre[1] - radius,
        centre[2]
    ));
    // φ runs from +x toward +z, so seen from outside (+y at the top) the
    // order (ring j+1, ring j) is counter-clockwise.
    for j in 0..slices {
        text.push_str(&format!("f {} {} {}\n", top, ring(1, j + 1), ring(1, j)));
        text.push_str(&format!(
            "f {} {} {}\n",
            bottom,
            ring(stacks - 1, j),
            ring(stacks - 1, j + 1)
        ));
    }
    for i in 1..stacks - 1 {
        for j in 0..slices {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i, j + 1),
                ring(i + 1, j + 1),
                ring(i + 1, j),
            );
            text.push_str(&format!("f {a} {b} {c}\nf {a} {c} {d}\n"));
        }
    }
    std::fs::write(dir.join("mirror_sphere.mtl"), mtl).unwrap();
    let path = dir.join("mirror_sphere.obj");
    std::fs::write(&path, text).unwrap();
    path
}

/// What a child solve did: its exit status, its stderr and its peak resident
/// set in bytes.
pub struct Measured {
    pub success: bool,
    /// Stopped at its `--max-shots` above the threshold (exit status 4).
    pub capped: bool,
    pub stderr: String,
    pub peak_rss: u64,
}

/// Runs `cmd` and reaps it with wait4(2), whose rusage is the child's own
/// (ru_maxrss): not the test's, nor another child's.
pub fn run_measured(cmd: &mut Command) -> Measured {
    let mut child = Measuring::spawn(cmd.stdout(Stdio::null()).stderr(Stdio::piped())).unwrap();
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut child.take_stderr().unwrap(), &mut stderr).unwrap();
    let reaped = child.wait().expect("wait4 reaps the solve");
    Measured {
        success: reaped.success(),
        capped: reaped.ending() == Ending::Exited(4),
        stderr,
        peak_rss: reaped.peak_rss_bytes,
    }
}

/// The estimated peak and the budget of the closing line `memory: estimated
/// peak N bytes (…) within the budget M bytes (…)`.
pub fn estimate_and_budget(stderr: &str) -> (u64, u64) {
    let line = stderr
        .lines()
        .find(|l| l.contains("memory: estimated peak") && l.contains("within the budget"))
        .unwrap_or_else(|| panic!("no memory line in:\n{stderr}"));
    let numbers: Vec<u64> = line
        .split_whitespace()
        .filter_map(|w| w.parse().ok())
        .collect();
    (numbers[0], numbers[1])
}

fn solve(scene: &Path, out: &Path, extra: &[&str]) -> Command {
    let mut cmd = Command::new(common::binary("solver"));
    cmd.arg("solve")
        .arg(scene)
        .arg("-o")
        .arg(out)
        .args(["--threads", "2"])
        .args(extra);
    cmd
}

/// The mirror sphere at medium under a 512 MiB budget: without one its SH
/// state alone would be tens of GB. The solve caps the sphere's order, warns
/// with the order kept and the Parseval error, and stays under the budget as
/// the kernel measures it. Three shots keep the test short; the budget's
/// decisions (the cap) are made before the first.
#[test]
fn a_capped_mirror_sphere_stays_under_its_budget() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_mirror_sphere_scene(dir.path(), 32, 32);
    let out = dir.path().join("out.sol");
    let budget: u64 = 512 << 20;
    let m = run_measured(&mut solve(
        &scene,
        &out,
        &[
            "--mode",
            "directional",
            "--preset",
            "medium",
            "--max-shots",
            "3",
            "--memory-budget",
            "512MiB",
        ],
    ));
    assert!(m.capped, "{}", m.stderr);
    // The measured peak under the budget, the kernel's own figure.
    assert!(
        m.peak_rss <= budget,
        "peak RSS {} MiB over the budget {} MiB:\n{}",
        m.peak_rss >> 20,
        budget >> 20,
        m.stderr
    );
    let warning = m
        .stderr
        .lines()
        .find(|l| l.contains("material `mirror`") && l.contains("keeps L ="))
        .unwrap_or_else(|| panic!("no cap warning:\n{}", m.stderr));
    assert!(warning.contains("of the lobe's energy"), "{warning}");
    assert!(warning.contains("blurred"), "{warning}");
    let (estimate, named_budget) = estimate_and_budget(&m.stderr);
    assert_eq!(named_budget, budget);
    // The estimate within ±25% of the measured peak (issue 13's bound).
    let ratio = estimate as f64 / m.peak_rss as f64;
    eprintln!(
        "estimate {estimate} B, measured peak {} B, ratio {ratio:.2}",
        m.peak_rss
    );
    assert!(
        (0.75..=1.25).contains(&ratio),
        "estimate {estimate} against measured {} ({ratio:.2})",
        m.peak_rss
    );
    assert!(out.exists());
}

/// A budget too small for even the unrefined mesh at SH order 0: refused
/// before meshing, naming the estimate and the budget, with a peak resident
/// set under that budget (nothing of the solve's state was allocated).
#[test]
fn a_scene_too_large_for_its_budget_is_refused_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_mirror_sphere_scene(dir.path(), 32, 32);
    let out = dir.path().join("out.sol");
    let m = run_measured(&mut solve(
        &scene,
        &out,
        &[
            "--mode",
            "directional",
            "--preset",
            "medium",
            // Patches of 0.002 of the diagonal (2 mm): each of the sphere's small
            // triangles (18 mm) gets ten a side, an unrefined mesh that cannot
            // fit. (Medium's own size keeps each as one patch, and the same
            // scene then fits in 40 MiB at L = 3.)
            "--patch-size",
            "0.002",
            "--memory-budget",
            "40MiB",
        ],
    ));
    assert!(!m.success, "must refuse:\n{}", m.stderr);
    assert!(
        m.stderr.contains("exceeds the memory budget 40.0 MiB"),
        "{}",
        m.stderr
    );
    assert!(
        m.stderr.contains("the estimated peak memory"),
        "{}",
        m.stderr
    );
    assert!(m.stderr.contains("before meshing"), "{}", m.stderr);
    assert!(m.peak_rss <= 40 << 20, "peak RSS {} MiB", m.peak_rss >> 20);
    assert!(!out.exists());
}

/// The figures of docs/benchmarks.md ("Memory: estimate against measured
/// peak"): each scene's estimate against its measured peak. Slow (minutes
/// in a release build); run with `cargo test --release --test memory_budget
/// -- --ignored --nocapture`.
#[test]
#[ignore]
fn estimate_against_measured_peak() {
    let dir = tempfile::tempdir().unwrap();
    let config = Path::new(env!("CARGO_MANIFEST_DIR")).join("config");
    let sphere = write_mirror_sphere_scene(dir.path(), 32, 32);
    let cornell = config.join("cornell_box.obj");
    let glossy = config.join("glossy_cornell_box.toml");
    let cases: Vec<(&str, &Path, Vec<&str>)> = vec![
        (
            "Cornell box, diffuse, medium",
            &cornell,
            vec!["--preset", "medium"],
        ),
        (
            "Cornell box, diffuse, final",
            &cornell,
            vec!["--preset", "final"],
        ),
        (
            "glossy Cornell box, directional, medium",
            &glossy,
            vec!["--mode", "directional", "--preset", "medium"],
        ),
        (
            "mirror sphere (Ns 1000), directional, medium, 2 GiB",
            &sphere,
            vec![
                "--mode",
                "directional",
                "--preset",
                "medium",
                "--memory-budget",
                "2GiB",
            ],
        ),
    ];
    for (name, scene, args) in cases {
        let out = dir.path().join("bench.sol");
        let _ = std::fs::remove_file(&out);
        let start = std::time::Instant::now();
        let m = run_measured(&mut solve(scene, &out, &args));
        assert!(m.success, "{name}: {}", m.stderr);
        let (estimate, budget) = estimate_and_budget(&m.stderr);
        let summary = m
            .stderr
            .lines()
            .find(|l| l.contains(" elements, "))
            .unwrap_or("");
        let warnings: Vec<&str> = m.stderr.lines().filter(|l| l.contains("warning")).collect();
        println!(
            "{name}: estimate {:.1} MiB, measured {:.1} MiB ({:+.0}%), budget {:.1} MiB, {:.0} s\n  {summary}\n  {}",
            estimate as f64 / (1u64 << 20) as f64,
            m.peak_rss as f64 / (1u64 << 20) as f64,
            100.0 * (estimate as f64 / m.peak_rss as f64 - 1.0),
            budget as f64 / (1u64 << 20) as f64,
            start.elapsed().as_secs_f64(),
            warnings.join("\n  ")
        );
    }
}
