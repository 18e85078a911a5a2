//! End-to-end tests of `solver solve`: the binary on small scenes written by the
//! tests themselves (a 1 m room with a ceiling light and a floating blocker), so
//! they need no files outside the crate and each runs in about a second.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn solver() -> Command {
    Command::new(env!("CARGO_BIN_EXE_solver"))
}

/// A closed unit room (normals inward), a 0.2 m square light just under the
/// ceiling and a floating square at half height that shadows the floor.
/// `emission` is the light's radiance, so two values make two different scenes.
fn write_room(dir: &Path, name: &str, emission: f64) -> PathBuf {
    let mtl = format!(
        "newmtl white\nKd 0.6 0.6 0.6\n\
         newmtl red\nKd 0.6 0.1 0.1\n\
         newmtl light\nKd 0.5 0.5 0.5\nKe {emission} {emission} {emission}\n"
    );
    std::fs::write(dir.join(format!("{name}.mtl")), mtl).unwrap();
    // Each quad is counter-clockwise seen from inside the room (design notes).
    let obj = format!(
        "mtllib {name}.mtl\n\
         v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
         v 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
         v 0.4 0.99 0.4\nv 0.6 0.99 0.4\nv 0.6 0.99 0.6\nv 0.4 0.99 0.6\n\
         v 0.3 0.5 0.3\nv 0.3 0.5 0.7\nv 0.7 0.5 0.7\nv 0.7 0.5 0.3\n\
         usemtl white\n\
         f 1 5 6 2\n\
         f 4 3 7 8\n\
         f 1 2 3 4\n\
         f 5 8 7 6\n\
         f 2 6 7 3\n\
         usemtl red\n\
         f 1 4 8 5\n\
         usemtl light\n\
         f 9 10 11 12\n\
         usemtl white\n\
         f 13 14 15 16\n"
    );
    let path = dir.join(format!("{name}.obj"));
    std::fs::write(&path, obj).unwrap();
    path
}

fn run(cmd: &mut Command) -> Output {
    let out = cmd.output().expect("the solver binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !stderr.contains("panicked"),
        "the solver panicked:\n{stderr}"
    );
    out
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn assert_ok(out: &Output) {
    assert!(out.status.success(), "solver failed: {}", stderr(out));
}

/// The exit status `solver solve --help` documents for a solve stopped at its
/// shot cap above its threshold.
const EXIT_SHOT_CAP: i32 = 4;

fn assert_capped(out: &Output) {
    assert_eq!(
        out.status.code(),
        Some(EXIT_SHOT_CAP),
        "not stopped at the shot cap: {}",
        stderr(out)
    );
}

/// The solve flags every test shares: the draft preset, two threads (the
/// machine's cores) and a fixed seed.
fn draft(scene: &Path, out: &Path) -> Command {
    draft_on(scene, out, 2)
}

fn draft_on(scene: &Path, out: &Path, threads: u32) -> Command {
    let mut cmd = solver();
    cmd.arg("solve")
        .arg(scene)
        .arg("-o")
        .arg(out)
        .args(["--preset", "draft", "--seed", "7", "--threads"])
        .arg(threads.to_string());
    cmd
}

fn read(path: &Path) -> solution::format::Solution {
    solution::format::read_solution(path).expect("a valid solution file")
}

/// Radiance and geometry must be identical; the header may differ only in the
/// wall-clock seconds and in the settings text (the runs had different shot
/// budgets and checkpoint intervals).
fn assert_same_result(a: &solution::format::Solution, b: &solution::format::Solution) {
    assert_eq!(a.batches.len(), b.batches.len());
    for (x, y) in a.batches.iter().zip(&b.batches) {
        assert_eq!(x.representation, y.representation);
        assert_eq!(x.vertices, y.vertices, "vertex positions and frames");
        assert_eq!(x.indices, y.indices, "triangles");
        // Bit-exact radiance: the checkpoint carries every f64 exactly.
        let bits = |c: &[f32]| c.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&x.coefficients), bits(&y.coefficients), "radiance");
    }
    let (mut ha, mut hb) = (a.header.clone(), b.header.clone());
    for h in [&mut ha, &mut hb] {
        h.stats.seconds = 0.0;
        h.settings_json.clear();
    }
    assert_eq!(ha, hb, "headers apart from seconds and settings text");
}

#[test]
fn solve_writes_solution_and_stats() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_room(dir.path(), "room", 10.0);
    let out = dir.path().join("room.sol");
    let stats_path = dir.path().join("stats.json");
    let result = run(draft(&scene, &out).arg("--stats-json").arg(&stats_path));
    assert_ok(&result);

    let solution = read(&out);
    assert!(!solution.header.partial, "a finished solve is not partial");
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats_path).unwrap()).unwrap();
    let mut keys: Vec<&str> = stats
        .as_object()
        .unwrap()
        .keys()
        .map(|k| k.as_str())
        .collect();
    keys.sort();
    assert_eq!(
        keys,
        [
            "elements",
            "rays",
            "rays_per_second",
            "seconds",
            "shots",
            "threads",
            "unshot_fraction",
            "vertices"
        ]
    );
    let num = |k: &str| stats[k].as_f64().unwrap();
    // The draft threshold is 2% of emitted power (config/presets.toml) and the run
    // converged (no shot budget hit), so the remaining unshot power is below it.
    assert!(num("unshot_fraction") < 0.02, "{stats}");
    assert_eq!(
        num("unshot_fraction"),
        solution.header.stats.unshot_fraction
    );
    assert_eq!(num("shots") as u64, solution.header.stats.shots);
    assert_eq!(num("rays") as u64, solution.header.stats.rays);
    assert_eq!(num("threads"), 2.0);
    // 8 input polygons make at least 8 elements.
    assert!(num("shots") >= 1.0 && num("rays") > 0.0 && num("elements") >= 8.0);
    assert!(num("vertices") >= 4.0);
    // rays_per_second is rays / seconds, to the precision JSON prints.
    let rate = num("rays") / num("seconds");
    assert!((num("rays_per_second") - rate).abs() <= 1e-9 * rate);
    // Converged: the checkpoint is gone and the summary was printed.
    assert!(!dir.path().join("room.sol.checkpoint").exists());
    assert!(stderr(&result).contains("shots"), "{}", stderr(&result));
}

#[test]
fn resume_after_a_stop_equals_an_uninterrupted_solve() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_room(dir.path(), "room", 10.0);
    let whole = dir.path().join("whole.sol");
    assert_ok(&run(&mut draft(&scene, &whole)));

    // Stop at a shot budget of 3 with checkpoints every 2 shots: the solve is not
    // converged, so the checkpoint is kept for --resume.
    let split = dir.path().join("split.sol");
    let checkpoint = dir.path().join("split.sol.checkpoint");
    let first = run(draft(&scene, &split).args(["--max-shots", "3", "--checkpoint-every", "2"]));
    assert_capped(&first);
    assert!(checkpoint.exists(), "{}", stderr(&first));
    assert!(stderr(&first).contains("--resume"), "{}", stderr(&first));
    assert_eq!(read(&split).header.stats.shots, 3);

    // Starting over without --resume would lose the saved work: refused.
    let refused = run(&mut draft(&scene, &split));
    assert!(!refused.status.success());
    assert!(
        stderr(&refused).contains("--resume"),
        "{}",
        stderr(&refused)
    );

    // Resume with another thread count and checkpoint interval (neither may
    // change the result) to the end.
    let mut resume = draft_on(&scene, &split, 1);
    resume.args(["--resume", "--checkpoint-every", "5"]);
    assert_ok(&run(&mut resume));
    assert!(!checkpoint.exists(), "removed once converged");
    assert_same_result(&read(&whole), &read(&split));
}

/// An honest ending: a solve stopped by `--max-shots` above its threshold exits
/// with its own status, says how far it got against the threshold, marks its file
/// partial and keeps its checkpoint; `--resume` with a larger cap converges.
#[test]
fn shot_cap_ends_partial_with_its_own_exit_code() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_room(dir.path(), "room", 10.0);
    let out = dir.path().join("room.sol");
    let checkpoint = dir.path().join("room.sol.checkpoint");
    // Three shots cannot bring the unshot power under 0.01%: the light alone is
    // one shot, and the six walls, the blocker and their refinements are more.
    let capped = run(draft(&scene, &out).args(["--max-shots", "3", "--threshold", "1e-4"]));
    assert_capped(&capped);
    let message = stderr(&capped);
    assert!(
        message.contains("stopped after 3 shots")
            && message.contains("unshot, above the threshold 0.01%")
            && message.contains("partial"),
        "{message}"
    );
    let partial = read(&out);
    assert!(partial.header.partial, "the file says partial: true");
    assert_eq!(partial.header.stats.shots, 3);
    assert!(partial.header.stats.unshot_fraction >= 1e-4);
    assert!(checkpoint.exists(), "the checkpoint is kept: {message}");

    let resumed =
        run(draft(&scene, &out).args(["--threshold", "1e-4", "--resume", "--max-shots", "100000"]));
    assert_ok(&resumed);
    let done = read(&out);
    assert!(!done.header.partial);
    assert!(done.header.stats.shots > 3);
    assert!(done.header.stats.unshot_fraction < 1e-4);
    assert!(!checkpoint.exists(), "removed once converged");
}

#[test]
fn checkpoint_of_another_scene_or_settings_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_room(dir.path(), "room", 10.0);
    let brighter = write_room(dir.path(), "brighter", 20.0);
    let out = dir.path().join("room.sol");
    assert_capped(&run(draft(&scene, &out).args(["--max-shots", "1"])));

    let other_scene = run(draft(&brighter, &out).arg("--resume"));
    assert!(!other_scene.status.success());
    let message = stderr(&other_scene);
    assert!(
        message.contains("different scene") && message.contains("room.sol.checkpoint"),
        "{message}"
    );

    let other_settings = run(draft(&scene, &out).args(["--resume", "--samples", "9"]));
    assert!(!other_settings.status.success());
    let message = stderr(&other_settings);
    assert!(message.contains("samples"), "{message}");

    // Nothing was lost: the checkpoint is still there.
    assert!(dir.path().join("room.sol.checkpoint").exists());

    // --resume with no checkpoint says which file is missing.
    let nothing = run(draft(&scene, &dir.path().join("none.sol")).arg("--resume"));
    assert!(!nothing.status.success());
    let message = stderr(&nothing);
    assert!(message.contains("none.sol.checkpoint"), "{message}");
}

#[test]
fn bad_input_gives_clear_messages() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.sol");

    let missing = dir.path().join("no-such-scene.obj");
    let result = run(&mut draft(&missing, &out));
    assert!(!result.status.success());
    let message = stderr(&result);
    assert!(message.contains("no-such-scene.obj"), "{message}");

    let scene = write_room(dir.path(), "room", 10.0);
    // A value clap cannot parse: usage error (exit 2) naming the flag and value.
    let result = run(draft(&scene, &out).args(["--samples", "lots"]));
    assert_eq!(result.status.code(), Some(2));
    let message = stderr(&result);
    assert!(
        message.contains("lots") && message.contains("--samples"),
        "{message}"
    );
    let result = run(draft(&scene, &out).args(["--mode", "glossy"]));
    assert_eq!(result.status.code(), Some(2));
    assert!(stderr(&result).contains("glossy"), "{}", stderr(&result));
    // Values out of range: named with their flag and value.
    let result = run(draft(&scene, &out).args(["--threshold", "1.5"]));
    assert_eq!(result.status.code(), Some(1));
    let message = stderr(&result);
    assert!(
        message.contains("--threshold") && message.contains("1.5"),
        "{message}"
    );
    let result = run(draft(&scene, &out).args(["--samples", "0"]));
    assert_eq!(result.status.code(), Some(1));
    assert!(stderr(&result).contains("--samples"), "{}", stderr(&result));
    // Out-of-range flags are refused before the scene is read: with a missing
    // scene the error is the flag's, not the file's.
    let result = run(draft(&missing, &out).args(["--samples", "0"]));
    assert_eq!(result.status.code(), Some(1));
    let message = stderr(&result);
    assert!(
        message.contains("--samples") && !message.contains("no-such-scene.obj"),
        "{message}"
    );
    assert!(!out.exists(), "no solution from failed runs");
}

#[test]
fn preview_has_the_display_files_image_size() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_room(dir.path(), "room", 10.0);
    // Remington 1992, appendix A: comment, eye/lookat, up, fov, near/far, resolution,
    // diameter, ambient, threshold. The eye is inside the room, looking at the
    // far wall, so every pixel sees a lit surface.
    let display = dir.path().join("room.display");
    std::fs::write(
        &display,
        "inside the room, toward +z\n\
         eye 0.5 0.4 0.05 lookat 0.5 0.4 1\n\
         up 0 1 0\n\
         fovx 53 fovy 40\n\
         near 0.01 far 10\n\
         xres 64 yres 48\n\
         diameter 2\n\
         ambient 1\n\
         threshold 20\n",
    )
    .unwrap();
    let out = dir.path().join("room.sol");
    let png = dir.path().join("room.png");
    let result = run(draft(&scene, &out)
        .arg("--display")
        .arg(&display)
        .arg("--preview")
        .arg(&png));
    assert_ok(&result);
    let image = image::open(&png).expect("a decodable PNG").to_rgb8();
    assert_eq!(image.dimensions(), (64, 48));
    // Every pixel looks at a wall, floor or ceiling that receives light (directly
    // or by one bounce), so after exposure almost none may be black; the 10% slack
    // covers pixels on the light's and blocker's silhouettes.
    let black = image.pixels().filter(|p| p.0 == [0, 0, 0]).count();
    assert!(black * 10 < 64 * 48, "{black} black pixels of {}", 64 * 48);
}

#[test]
fn help_explains_every_flag() {
    let result = run(solver().args(["solve", "--help"]));
    assert_ok(&result);
    let help = String::from_utf8_lossy(&result.stdout);
    for flag in [
        "--out",
        "--preset",
        "--samples",
        "--threshold",
        "--max-shots",
        "--seed",
        "--threads",
        "--no-shadows",
        "--method",
        "--mode",
        "--units-per-metre",
        "--strict",
        "--checkpoint-every",
        "--no-ambient",
        "--resume",
        "--display",
        "--preview",
        "--stats-json",
        "--sun",
        "--sky",
    ] {
        assert!(help.contains(flag), "--help does not mention {flag}");
    }
    // The exit codes, the shot cap's among them.
    assert!(
        help.contains("Exit codes") && help.contains("4 stopped at the shot cap"),
        "{help}"
    );
    // The knobs say what they trade.
    assert!(help.contains("faster") && help.contains("slower"), "{help}");
}

/// A real Ctrl-C (SIGINT) mid-solve: exit code 130 with the resume hint, a
/// checkpoint and a partial solution on disk; resuming to a shot budget gives the
/// same file as an uninterrupted solve to that budget.
#[cfg(unix)]
#[test]
fn ctrl_c_saves_a_resumable_checkpoint() {
    use std::time::{Duration, Instant};
    let dir = tempfile::tempdir().unwrap();
    let scene = write_room(dir.path(), "room", 10.0);
    let out = dir.path().join("room.sol");
    let checkpoint = dir.path().join("room.sol.checkpoint");
    // A threshold of 1e-7 needs hundreds of shots, far more than happen between
    // the first checkpoint and the signal, so the solve is still running when the
    // signal arrives.
    let long = ["--threshold", "1e-7"];
    let child = draft(&scene, &out)
        .args(long)
        .args(["--max-shots", "1000000", "--checkpoint-every", "1"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while !checkpoint.exists() {
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "no checkpoint appeared"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let result = child.wait_with_output().unwrap();
    let message = stderr(&result);
    assert_eq!(result.status.code(), Some(130), "{message}");
    assert!(message.contains("--resume"), "{message}");
    let partial = read(&out);
    assert!(partial.header.partial);
    let shots = partial.header.stats.shots;

    // Resume to 3 shots past the interruption, and solve the same budget in one go.
    let budget = (shots + 3).to_string();
    let resumed = run(draft(&scene, &out)
        .args(long)
        .args(["--resume", "--max-shots", &budget]));
    assert_capped(&resumed);
    let whole = dir.path().join("whole.sol");
    assert_capped(&run(draft(&scene, &whole)
        .args(long)
        .args(["--max-shots", &budget])));
    let (a, b) = (read(&out), read(&whole));
    assert_eq!(a.header.stats.shots, shots + 3);
    assert_same_result(&a, &b);
    // The resume took the set-up's searches from the checkpoint.
    let fresh = setup_line(&message);
    let again = setup_line(&stderr(&resumed));
    eprintln!("set-up, fresh: {fresh}\nset-up, resumed: {again}");
    assert!(
        fresh.contains("contact cuts") && fresh.contains("hidden vertices"),
        "{fresh}"
    );
    assert!(
        !again.contains("contact cuts") && !again.contains("hidden vertices"),
        "{again}"
    );
}

/// The set-up's summary line (`solver: set-up 1.2 s (contact cuts …)`).
fn setup_line(stderr: &str) -> String {
    stderr
        .lines()
        .find(|l| l.starts_with("solver: set-up "))
        .unwrap_or_else(|| panic!("no set-up summary in:\n{stderr}"))
        .to_owned()
}

/// A 16 m room whose floor carries an n × n field of 10 cm boxes (five faces
/// each, standing on it) under one ceiling light: a set-up of many
/// receivers and vertices to probe, long enough to be interrupted.
fn write_box_field(dir: &Path, n: usize) -> PathBuf {
    let mut obj = String::from("mtllib field.mtl\nusemtl white\n");
    let mut v = 0;
    let mut quad = |obj: &mut String, corners: [[f64; 3]; 4]| {
        for c in corners {
            obj.push_str(&format!("v {} {} {}\n", c[0], c[1], c[2]));
        }
        obj.push_str(&format!("f {} {} {} {}\n", v + 1, v + 2, v + 3, v + 4));
        v += 4;
    };
    let s = 16.0;
    // Floor, ceiling and walls, counter-clockwise seen from inside.
    quad(
        &mut obj,
        [[0.0, 0.0, 0.0], [0.0, 0.0, s], [s, 0.0, s], [s, 0.0, 0.0]],
    );
    quad(
        &mut obj,
        [[0.0, 3.0, 0.0], [s, 3.0, 0.0], [s, 3.0, s], [0.0, 3.0, s]],
    );
    quad(
        &mut obj,
        [
            [0.0, 0.0, 0.0],
            [s, 0.0, 0.0],
            [s, 3.0, 0.0],
            [0.0, 3.0, 0.0],
        ],
    );
    quad(
        &mut obj,
        [[0.0, 0.0, s], [0.0, 3.0, s], [s, 3.0, s], [s, 0.0, s]],
    );
    quad(
        &mut obj,
        [
            [0.0, 0.0, 0.0],
            [0.0, 3.0, 0.0],
            [0.0, 3.0, s],
            [0.0, 0.0, s],
        ],
    );
    quad(
        &mut obj,
        [[s, 0.0, 0.0], [s, 0.0, s], [s, 3.0, s], [s, 3.0, 0.0]],
    );
    for i in 0..n {
        for j in 0..n {
            let (x0, z0) = (1.0 + i as f64 * 0.15, 1.0 + j as f64 * 0.15);
            let (x1, z1, h) = (x0 + 0.1, z0 + 0.1, 0.1);
            quad(
                &mut obj,
                [[x0, h, z0], [x0, h, z1], [x1, h, z1], [x1, h, z0]],
            );
            quad(
                &mut obj,
                [[x0, 0.0, z0], [x1, 0.0, z0], [x1, h, z0], [x0, h, z0]],
            );
            quad(
                &mut obj,
                [[x0, 0.0, z1], [x0, h, z1], [x1, h, z1], [x1, 0.0, z1]],
            );
            quad(
                &mut obj,
                [[x0, 0.0, z0], [x0, h, z0], [x0, h, z1], [x0, 0.0, z1]],
            );
            quad(
                &mut obj,
                [[x1, 0.0, z0], [x1, 0.0, z1], [x1, h, z1], [x1, h, z0]],
            );
        }
    }
    obj.push_str("usemtl light\n");
    let (a, b, y) = (7.0, 9.0, 2.999);
    quad(&mut obj, [[a, y, a], [b, y, a], [b, y, b], [a, y, b]]);
    std::fs::write(
        dir.join("field.mtl"),
        "newmtl white\nKd 0.6 0.6 0.6\nnewmtl light\nKd 0.5 0.5 0.5\nKe 10 10 10\n",
    )
    .unwrap();
    let path = dir.join("field.obj");
    std::fs::write(&path, obj).unwrap();
    path
}

/// A real Ctrl-C (SIGINT) during the set-up: the set-up finishes, its
/// checkpoint is written and the solve stops (exit 130); `--resume` skips
/// the set-up's searches and reaches the same bits as an uninterrupted solve
/// to the same shot budget. The two set-ups' times are printed.
#[cfg(unix)]
#[test]
fn ctrl_c_during_the_set_up_keeps_the_set_up() {
    use std::io::{BufRead, BufReader};
    let dir = tempfile::tempdir().unwrap();
    let scene = write_box_field(dir.path(), 90);
    let budget = ["--max-shots", "4"];
    let whole = dir.path().join("whole.sol");
    let reference = run(draft(&scene, &whole).args(budget));
    assert_capped(&reference);

    let out = dir.path().join("field.sol");
    let mut child = draft(&scene, &out)
        .args(budget)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut seen = String::new();
    // The memory budget's line is the last before the set-up begins.
    let mut signalled = false;
    for line in BufReader::new(child.stderr.take().unwrap()).lines() {
        let line = line.unwrap();
        seen.push_str(&line);
        seen.push('\n');
        if !signalled && line.contains("memory budget") {
            let kill = Command::new("kill")
                .args(["-INT", &child.id().to_string()])
                .status()
                .unwrap();
            assert!(kill.success());
            signalled = true;
        }
    }
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "{seen}");
    assert!(seen.contains("finishing the set-up"), "{seen}");
    assert!(dir.path().join("field.sol.checkpoint").exists(), "{seen}");

    let resumed = run(draft(&scene, &out).args(budget).arg("--resume"));
    assert_capped(&resumed);
    assert_same_result(&read(&out), &read(&whole));
    let (fresh, again) = (setup_line(&seen), setup_line(&stderr(&resumed)));
    eprintln!("set-up, fresh: {fresh}\nset-up, resumed: {again}");
    assert!(
        !again.contains("contact cuts") && !again.contains("hidden vertices"),
        "{again}"
    );
}
