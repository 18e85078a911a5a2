//! End to end: each family at about 1k triangles, written to files and
//! solved by the real `solver` binary (`--preset draft`, a budget of 3 shots,
//! `--strict` so that any import warning — a degenerate, non-planar or
//! mis-wound face — fails the test), then described by `solver info`; and the
//! daylit families solved the same way by their own sun and sky; and a
//! `--glossy` scene solved in the directional mode its config asks for.

use scenegen::{generate, glossy, scene::write_scene, Family};
use std::ffi::OsStr;
use std::path::Path;
use std::process::Command;

mod common;
use common::solver;

fn json(bytes: &[u8]) -> serde_json::Value {
    serde_json::from_slice(bytes)
        .unwrap_or_else(|e| panic!("not JSON ({e}): {}", String::from_utf8_lossy(bytes)))
}

/// `solver info --json OUT`, which must succeed, as JSON.
fn info_json(solver: &Path, out: &Path) -> serde_json::Value {
    let info = Command::new(solver)
        .arg("info")
        .arg("--json")
        .arg(out)
        .output()
        .unwrap();
    assert!(
        info.status.success(),
        "{}",
        String::from_utf8_lossy(&info.stderr)
    );
    json(&info.stdout)
}

/// `solver solve TOML --out OUT --preset draft --max-shots SHOTS --strict
/// --threads 2 EXTRA…`, which must succeed or stop at its shot cap (status 4).
fn solve_strictly(
    solver: &Path,
    family: Family,
    toml: &Path,
    out: &Path,
    shots: u32,
    extra: &[&OsStr],
) {
    let run = Command::new(solver)
        .arg("solve")
        .arg(toml)
        .arg("--out")
        .arg(out)
        .args(["--preset", "draft", "--max-shots", &shots.to_string()])
        .args(["--strict", "--threads", "2"])
        .args(extra)
        .output()
        .unwrap();
    assert!(
        run.status.success() || run.status.code() == Some(4),
        "{}: {}",
        family.name(),
        String::from_utf8_lossy(&run.stderr)
    );
}

#[test]
fn the_solver_accepts_every_family() {
    let solver = solver();
    let dir = tempfile::tempdir().unwrap();
    for family in Family::ALL {
        let scene = generate(family, 1000, 1).unwrap();
        let paths = write_scene(&scene, dir.path(), family.name()).unwrap();
        let out = dir.path().join(format!("{}.sol", family.name()));
        let stats = dir.path().join(format!("{}.json", family.name()));
        solve_strictly(
            &solver,
            family,
            &paths.toml,
            &out,
            3,
            &["--stats-json".as_ref(), stats.as_os_str()],
        );
        let stats = json(&std::fs::read(&stats).unwrap());
        assert_eq!(stats["shots"], 3, "{}: {stats}", family.name());
        // Three shots of the light(s) leave less than all of the power unshot.
        assert!(stats["unshot_fraction"].as_f64().unwrap() < 1.0, "{stats}");

        let header = info_json(&solver, &out);
        assert_eq!(header["units_per_metre"], 1000.0, "{header}");
        // The solution's bounds span the generated geometry: same extent per
        // axis. Bounds are stored in f32 around the re-centred origin (about
        // 8 m here, so a resolution of 1e-3 mm); 0.01 mm is above that.
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &scene.mesh.positions {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        for a in 0..3 {
            let extent = header["bounds_max"][a].as_f64().unwrap()
                - header["bounds_min"][a].as_f64().unwrap();
            assert!(
                (extent - (hi[a] - lo[a])).abs() < 0.01,
                "{} axis {a}: {extent} vs {}",
                family.name(),
                hi[a] - lo[a]
            );
        }
        assert_eq!(header["camera"]["eye"][0], scene.camera.eye[0], "{header}");
    }
}

#[test]
fn the_solver_solves_the_daylit_families_by_their_own_lights() {
    // The daylit scenes as written, lit only by their `[sun]` and `[sky]`,
    // under `--strict` (no degenerate, non-planar or mis-wound face): the
    // lights' shot comes first, so after three shots some of their power is
    // shot on (unshot fraction below 1), and the file records the lights.
    let solver = solver();
    let dir = tempfile::tempdir().unwrap();
    for (family, triangles) in [(Family::Atrium, 5_000), (Family::WindowRoom, 300)] {
        let scene = generate(family, triangles, 1).unwrap();
        let paths = write_scene(&scene, dir.path(), family.name()).unwrap();
        let out = dir.path().join(format!("{}.sol", family.name()));
        let stats = dir.path().join(format!("{}.json", family.name()));
        solve_strictly(
            &solver,
            family,
            &paths.toml,
            &out,
            3,
            &["--stats-json".as_ref(), stats.as_os_str()],
        );
        let stats = json(&std::fs::read(&stats).unwrap());
        assert_eq!(stats["shots"], 3, "{}: {stats}", family.name());
        let unshot = stats["unshot_fraction"].as_f64().unwrap();
        assert!(unshot > 0.0 && unshot < 1.0, "{}: {stats}", family.name());
        let header = info_json(&solver, &out);
        assert!(
            header.get("lighting").is_some(),
            "{}: {header}",
            family.name()
        );
    }
}

#[test]
fn the_solver_solves_a_glossy_generated_scene_directionally() {
    // The Cornell boxes with a glossy floor (`--glossy floor`: Ks 0.5, Ns
    // 100), as written, under `--strict` (so Kd + Ks ≤ 1, or the import
    // would warn) and without `--mode`: the config's `mode = "directional"`
    // must make the floor glossy, stored as SH of an order above 0, while
    // the diffuse rest is order 0.
    let solver = solver();
    let dir = tempfile::tempdir().unwrap();
    let family = Family::CornellBoxes;
    let mut scene = generate(family, 300, 1).unwrap();
    let requests = ["floor".parse().unwrap()];
    glossy::apply(&mut scene, family.name(), &requests).unwrap();
    let paths = write_scene(&scene, dir.path(), "glossy").unwrap();
    let out = dir.path().join("glossy.sol");
    solve_strictly(&solver, family, &paths.toml, &out, 3, &[]);
    let header = info_json(&solver, &out);
    let orders: Vec<u64> = header["batches"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| b["representation"]["order"].as_u64().unwrap())
        .collect();
    assert!(orders.contains(&0), "{orders:?}");
    assert!(orders.iter().any(|&l| l > 0), "no glossy batch: {orders:?}");
}
