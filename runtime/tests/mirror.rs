//! `runtime mirror` in a real window under Xvfb (a virtual X server started by
//! each test on a display number it picks itself): scripted keys and mouse
//! move the camera as specified, the window shows what the offscreen renderer
//! (`runtime screenshot`) draws for the same camera, the overlays and
//! inspection modes draw what they should, `--watch` reloads rewritten files,
//! and every run is validation-clean (RUNTIME_VALIDATION=1).
//!
//! Xvfb missing is a failure naming the Debian package, never a skip.

mod common;

use glam::DVec3;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::mpsc;
use std::time::Duration;

/// A private X server (Xvfb), killed on drop.
struct Xvfb {
    child: Child,
    display: String,
    /// Xvfb's standard output, kept open: the server writes its display number
    /// again at every server reset, and a closed pipe would kill it by SIGPIPE.
    _displayfd: BufReader<std::process::ChildStdout>,
}

impl Xvfb {
    fn start() -> Xvfb {
        // -displayfd 1: the server picks a free display number itself and
        // writes it to its standard output once it accepts connections.
        // -noreset: several `runtime mirror` runs share one server; without it the
        // server resets when the last client leaves and a quick next run can find
        // it gone.
        let mut child = match Command::new("Xvfb")
            .args([
                "-displayfd",
                "1",
                "-screen",
                "0",
                "1280x720x24",
                "-nolisten",
                "tcp",
                "-noreset",
            ])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
        {
            Ok(c) => c,
            Err(e) => panic!(
                "cannot start Xvfb ({e}): install the Debian package `xvfb` \
                 (scripts/install-deps.sh test does)"
            ),
        };
        let mut line = String::new();
        let stdout = child.stdout.take().expect("piped stdout");
        let mut displayfd = BufReader::new(stdout);
        displayfd
            .read_line(&mut line)
            .expect("Xvfb's display number");
        let number: u32 = line
            .trim()
            .parse()
            .unwrap_or_else(|_| panic!("Xvfb did not report a display number: {line:?}"));
        Xvfb {
            child,
            display: format!(":{number}"),
            _displayfd: displayfd,
        }
    }

    fn mirror(&self, solution: &Path) -> Command {
        common::use_lavapipe_unless_chosen();
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_runtime"));
        cmd.env("DISPLAY", &self.display)
            .env_remove("WAYLAND_DISPLAY")
            .env("RUNTIME_VALIDATION", "1")
            .arg("mirror")
            .arg(solution);
        cmd
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn write_solution(dir: &Path, name: &str, solution: &solution::format::Solution) -> PathBuf {
    let path = dir.join(name);
    solution::format::write_solution(&path, solution).unwrap();
    path
}

/// Runs a command that must succeed without validation messages.
fn run_clean(mut cmd: Command) -> (String, String) {
    let out: Output = cmd.output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(
        out.status.success(),
        "{cmd:?} failed ({}):\n{stderr}\n{stdout}",
        out.status
    );
    assert!(
        !stderr.contains("vulkan validation"),
        "validation messages:\n{stderr}"
    );
    (stdout, stderr)
}

fn rgb(path: &Path) -> image::RgbImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8()
}

/// The largest per-channel difference between `window` pixels (x0.., y) and
/// `reference`, with `pick` choosing the reference's channel per window channel.
fn max_difference(
    window: &image::RgbImage,
    x0: u32,
    reference: &[&image::RgbImage; 3],
) -> (u8, u32) {
    let (w, h) = reference[0].dimensions();
    let mut worst = 0u8;
    let mut differing = 0;
    for y in 0..h {
        for x in 0..w {
            let got = window.get_pixel(x0 + x, y).0;
            for c in 0..3 {
                let want = reference[c].get_pixel(x, y).0[c];
                let d = got[c].abs_diff(want);
                worst = worst.max(d);
                differing += u32::from(d > 0);
            }
        }
    }
    (worst, differing)
}

/// The offscreen stereo pair of the header's camera at `size` per eye.
fn screenshot(dir: &Path, solution: &Path, size: &str) -> (image::RgbImage, image::RgbImage) {
    common::use_lavapipe_unless_chosen();
    let prefix = dir.join("offscreen");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_runtime"));
    cmd.arg("screenshot")
        .arg(solution)
        .args(["--size", size, "--validation", "--out"])
        .arg(&prefix);
    run_clean(cmd);
    (
        rgb(&dir.join("offscreen-left.png")),
        rgb(&dir.join("offscreen-right.png")),
    )
}

/// `(eye, target)` from a line `... eye X Y Z target X Y Z`.
fn parse_camera(line: &str) -> (DVec3, DVec3) {
    let words: Vec<&str> = line.split_whitespace().collect();
    let at = |name: &str| {
        let i = words.iter().position(|w| *w == name).unwrap() + 1;
        DVec3::new(
            words[i].parse().unwrap(),
            words[i + 1].parse().unwrap(),
            words[i + 2].parse().unwrap(),
        )
    };
    (at("eye"), at("target"))
}

/// The 8-bit sRGB value of a linear value, as the sRGB swapchain stores it.
fn srgb8(linear: f32) -> u8 {
    (runtime::render::tonemap::srgb_encode(linear) * 255.0).round() as u8
}

#[test]
fn keys_move_the_camera_as_specified_and_the_window_matches_the_offscreen_renderer() {
    let x = Xvfb::start();
    let dir = tempfile::tempdir().unwrap();
    let solution = common::diffuse_room(4);
    let file = write_solution(dir.path(), "room.sol", &solution);
    // Frame by frame (Remington 1992, app. C.1 keys): azimuth 10 presses + a 100 px drag
    // (0.2°/px: 20°), elevation 10 presses, zoom in twice, move along the line
    // of sight 3 steps, screenshot; reset, walk forward for 9 frames, screenshot;
    // reset, and the last frame (20) is dumped.
    let mut script = String::from("0 key F3\n");
    script += &"1 key Right\n".repeat(10);
    script += "1 drag 100 0\n";
    script += &"2 key Up\n".repeat(10);
    script += "3 key z\n3 key z\n";
    script += &"4 key a\n".repeat(3);
    script += "5 key F12\n6 key r\n6 key Tab\n7 press w\n16 release w\n17 key F12\n";
    script += "18 key Tab\n18 key r\n19 key F12\n";
    std::fs::write(dir.path().join("keys.txt"), script).unwrap();
    let dump = dir.path().join("window.png");
    let mut cmd = x.mirror(&file);
    cmd.args(["--size", "192x96", "--frames", "21", "--script"])
        .arg(dir.path().join("keys.txt"))
        .arg("--dump-last-frame")
        .arg(&dump)
        .arg("--screenshot-prefix")
        .arg(dir.path().join("shot"));
    let (stdout, _) = run_clean(cmd);

    // The spec, computed here with plain trigonometry (not the controls module).
    let camera = solution.header.camera;
    let (e0, t0) = (DVec3::from(camera.eye), DVec3::from(camera.target));
    let up = DVec3::Y;
    let d0 = e0 - t0;
    let dist0 = d0.length();
    // Azimuth right 30°: a right-handed turn about +up moves the eye toward the
    // camera's right (right = forward × up = up × d̂).
    let d = glam::DQuat::from_axis_angle(up, 30f64.to_radians()) * d0;
    let horizontal = (d - up * d.dot(up)).normalize();
    let elevation = (d0.dot(up) / dist0).asin() + 10f64.to_radians();
    let d = (horizontal * elevation.cos() + up * elevation.sin()) * dist0 / 1.1f64.powi(2);
    let diagonal = (DVec3::from(common::ROOM_MAX.map(f64::from))
        - DVec3::from(common::ROOM_MIN.map(f64::from)))
    .length();
    let shift = -d.normalize() * (3.0 * 0.02 * diagonal);
    let want_a = (t0 + d + shift, t0 + shift);
    // Walking: 9 frames of 1/90 s at 1.4 m/s (units_per_metre 1), level.
    let forward = (t0 - e0 - up * (t0 - e0).dot(up)).normalize();
    let walk = forward * (9.0 / 90.0 * 1.4);
    let want_b = (e0 + walk, t0 + walk);

    let shots: Vec<(DVec3, DVec3)> = stdout
        .lines()
        .filter(|l| l.starts_with("screenshot camera:"))
        .map(parse_camera)
        .collect();
    assert_eq!(shots.len(), 3, "{stdout}");
    assert_eq!(shots[2], (e0, t0), "F12 after r: the initial camera");
    // f64 trigonometry on values of order 5: 1e-9 is far above rounding.
    for (got, want, what) in [(shots[0], want_a, "keys"), (shots[1], want_b, "walk")] {
        assert!(
            (got.0 - want.0).length() < 1e-9 && (got.1 - want.1).length() < 1e-9,
            "{what}: eye/target {got:?}, expected {want:?}"
        );
    }
    // r restores the initial camera exactly.
    let last = stdout.lines().find(|l| l.starts_with("camera:")).unwrap();
    assert_eq!(parse_camera(last), (e0, t0), "{stdout}");
    for n in ["001", "002", "003"] {
        for side in ["left", "right"] {
            let png = dir.path().join(format!("shot-{n}-{side}.png"));
            assert_eq!(rgb(&png).dimensions(), (96, 96));
            assert!(dir.path().join(format!("shot-{n}-{side}.exr")).exists());
        }
    }
    let summary = stdout
        .lines()
        .find(|l| l.starts_with("frames: 21 presented"))
        .unwrap_or_else(|| panic!("no frame summary in {stdout}"));
    assert!(
        summary.contains("median") && summary.contains("p99"),
        "{summary}"
    );

    // The window's last image against the offscreen renderer's pair for the
    // same (initial) camera: the eye images are the same renderer's output
    // (same views, size, samples); the window adds an sRGB decode (sampling)
    // and re-encode (the sRGB swapchain), which may round a value by one step.
    let window = rgb(&dump);
    assert_eq!(window.dimensions(), (192, 96));
    let (left, right) = screenshot(dir.path(), &file, "96x96");
    let (worst_l, _) = max_difference(&window, 0, &[&left, &left, &left]);
    let (worst_r, _) = max_difference(&window, 96, &[&right, &right, &right]);
    assert!(
        worst_l <= 1 && worst_r <= 1,
        "window differs from the screenshot by {worst_l} (left) / {worst_r} (right)"
    );
    // F12 of the initial view writes what `runtime screenshot` writes (the
    // same renderer, views and size; the window's eye images may be BGRA).
    for (side, reference) in [("left", &left), ("right", &right)] {
        let shot = rgb(&dir.path().join(format!("shot-003-{side}.png")));
        let (worst, _) = max_difference(&shot, 0, &[reference, reference, reference]);
        assert!(
            worst <= 1,
            "F12 {side} differs from the screenshot by {worst}"
        );
    }
    // And the two eyes differ (a stereo pair, not one image twice).
    let (_, differing) = max_difference(&window, 0, &[&right, &right, &right]);
    assert!(differing > 100, "left and right eyes look the same");
}

#[test]
fn resizing_and_switching_layouts_keep_the_image_right() {
    let x = Xvfb::start();
    let dir = tempfile::tempdir().unwrap();
    let file = write_solution(dir.path(), "room.sol", &common::diffuse_room(4));
    // Window resizes (new swapchain) and layout switches (new eye-image size,
    // the renderer resized in place), ending side by side at 100x60.
    let script = "0 key F3\n2 resize 150 90\n5 key 2\n7 key 4\n9 key 3\n\
                  11 resize 100 60\n13 key 1\n";
    std::fs::write(dir.path().join("s.txt"), script).unwrap();
    let dump = dir.path().join("window.png");
    let mut cmd = x.mirror(&file);
    cmd.args(["--size", "128x64", "--frames", "24", "--script"])
        .arg(dir.path().join("s.txt"))
        .arg("--dump-last-frame")
        .arg(&dump);
    let (stdout, _) = run_clean(cmd);
    assert!(stdout.contains("frames: 24 presented"), "{stdout}");
    let window = rgb(&dump);
    assert_eq!(window.dimensions(), (100, 60), "the window did not resize");
    let (left, right) = screenshot(dir.path(), &file, "50x60");
    let (worst_l, _) = max_difference(&window, 0, &[&left, &left, &left]);
    let (worst_r, _) = max_difference(&window, 50, &[&right, &right, &right]);
    assert!(
        worst_l <= 1 && worst_r <= 1,
        "after resizing, the window differs from the screenshot by {worst_l} / {worst_r}"
    );
}

#[test]
fn anaglyph_takes_red_from_the_left_eye_and_cyan_from_the_right() {
    let x = Xvfb::start();
    let dir = tempfile::tempdir().unwrap();
    let file = write_solution(dir.path(), "room.sol", &common::diffuse_room(4));
    std::fs::write(dir.path().join("s.txt"), "0 key F3\n0 key 4\n").unwrap();
    let dump = dir.path().join("window.png");
    let mut cmd = x.mirror(&file);
    cmd.args(["--size", "80x80", "--frames", "2", "--script"])
        .arg(dir.path().join("s.txt"))
        .arg("--dump-last-frame")
        .arg(&dump);
    run_clean(cmd);
    let window = rgb(&dump);
    let (left, right) = screenshot(dir.path(), &file, "80x80");
    // Channel selection only; the sRGB round trip may move a value one step.
    let (worst, _) = max_difference(&window, 0, &[&left, &right, &right]);
    assert!(worst <= 1, "anaglyph differs by {worst}");
}

#[test]
fn help_overlay_draws_the_key_list_with_the_bitmap_font() {
    let x = Xvfb::start();
    let dir = tempfile::tempdir().unwrap();
    let file = write_solution(dir.path(), "room.sol", &common::diffuse_room(2));
    std::fs::write(dir.path().join("s.txt"), "0 key F3\n0 key F1\n").unwrap();
    // Both ways of drawing it: blended over copied eye images (the default on
    // an sRGB window) and inside the full-screen composite.
    for composite in [false, true] {
        let dump = dir.path().join(format!("window-{composite}.png"));
        let (w, h) = (320u32, 200u32);
        let mut cmd = x.mirror(&file);
        cmd.args(["--size", &format!("{w}x{h}"), "--frames", "2", "--script"])
            .arg(dir.path().join("s.txt"))
            .arg("--dump-last-frame")
            .arg(&dump);
        if composite {
            cmd.env("RUNTIME_MIRROR_COMPOSITE", "1");
        }
        run_clean(cmd);
        check_help_text(&rgb(&dump), w, h);
    }
}

fn check_help_text(window: &image::RgbImage, w: u32, h: u32) {
    use runtime::mirror::controls::Controls;
    use runtime::mirror::font::{TextGrid, CELL_H, CELL_W};
    // The layout the window uses below 800 px: scale 1, a 4 px margin, the
    // grid cut to what fits.
    let lines: Vec<String> = Controls::help_lines()
        .iter()
        .map(|s| s.to_string())
        .collect();
    let grid = TextGrid::new(&lines, (w - 8) / CELL_W, (h - 8) / CELL_H);
    assert!(grid.cols >= 40 && grid.rows == lines.len() as u32);
    let (gw, gh, lit) = grid.rasterize(1);
    // composite.frag's text colour, linear (1.0, 0.95, 0.6), through the sRGB
    // swapchain (±1 for the hardware's encoding).
    let text = [srgb8(1.0), srgb8(0.95), srgb8(0.6)];
    let is_text = |p: [u8; 3]| (0..3).all(|c| p[c].abs_diff(text[c]) <= 1);
    let mut lit_count = 0;
    for y in 0..gh {
        for x in 0..gw {
            let p = window.get_pixel(4 + x, 4 + y).0;
            let on = lit[(y * gw + x) as usize];
            lit_count += usize::from(on);
            assert_eq!(is_text(p), on, "pixel ({x}, {y}) of the text block: {p:?}");
        }
    }
    assert!(lit_count > 1000, "only {lit_count} text pixels");
}

#[test]
fn wireframe_alone_and_normals_draw_lines_on_black() {
    let x = Xvfb::start();
    let dir = tempfile::tempdir().unwrap();
    let file = write_solution(dir.path(), "room.sol", &common::diffuse_room(3));
    // m twice: wireframe alone (prorad -w); n: vertex normals (-n).
    std::fs::write(
        dir.path().join("s.txt"),
        "0 key F3\n0 key m\n0 key m\n0 key n\n0 key 2\n",
    )
    .unwrap();
    let dump = dir.path().join("window.png");
    let mut cmd = x.mirror(&file);
    cmd.args([
        "--size",
        "128x96",
        "--frames",
        "2",
        "--samples",
        "1",
        "--script",
    ])
    .arg(dir.path().join("s.txt"))
    .arg("--dump-last-frame")
    .arg(&dump);
    run_clean(cmd);
    let window = rgb(&dump);
    let (mut black, mut edge, mut normal, mut other) = (0, 0, 0, 0);
    // Without MSAA a line pixel has exactly the line's colour (render/inspect.rs:
    // EDGE_COLOR (0.1, 0.9, 0.3), NORMAL_COLOR (1.0, 0.75, 0.1) as display
    // values, sRGB-encoded by the attachments).
    let enc = |c: [f32; 3]| c.map(|v| (runtime::render::tonemap::srgb_encode(v) * 255.0).round());
    let near = |p: [u8; 3], c: [f32; 3]| {
        let e = enc(c);
        (0..3).all(|i| (f32::from(p[i]) - e[i]).abs() <= 2.0)
    };
    for p in window.pixels() {
        let p = p.0;
        if p == [0, 0, 0] {
            black += 1;
        } else if near(p, runtime::render::inspect::EDGE_COLOR) {
            edge += 1;
        } else if near(p, runtime::render::inspect::NORMAL_COLOR) {
            normal += 1;
        } else {
            other += 1;
        }
    }
    eprintln!("wireframe: {black} black, {edge} edge, {normal} normal pixels");
    assert!(edge > 100 && normal > 20, "edges {edge}, normals {normal}");
    assert!(black > edge + normal, "no shading: mostly black ({black})");
    assert_eq!(other, 0, "only line colours and black");
}

/// Reads stderr lines of a child into a channel.
fn lines_of(stream: impl Read + Send + 'static) -> mpsc::Receiver<String> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stream).lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    rx
}

/// Waits for a line containing `needle`, returning the lines seen; a stuck
/// mirror fails the test instead of hanging it (not a timing assertion).
fn wait_for(rx: &mpsc::Receiver<String>, needle: &str, seen: &mut Vec<String>) {
    loop {
        match rx.recv_timeout(Duration::from_secs(120)) {
            Ok(line) => {
                let found = line.contains(needle);
                seen.push(line);
                if found {
                    return;
                }
            }
            Err(e) => panic!(
                "no line with {needle:?} ({e}); stderr so far:\n{}",
                seen.join("\n")
            ),
        }
    }
}

#[test]
fn watch_reloads_each_rewrite_and_keeps_the_old_solution_when_a_file_is_bad() {
    let x = Xvfb::start();
    let dir = tempfile::tempdir().unwrap();
    let version = |shots: u64, n: usize| {
        let mut s = common::diffuse_room(n);
        s.header.partial = true;
        s.header.stats.shots = shots;
        s
    };
    let file = write_solution(dir.path(), "room.sol", &version(1, 2));
    let mut child = x
        .mirror(&file)
        // Wireframe on: a reload rebuilds the edge lists too.
        .args([
            "--size",
            "64x32",
            "--watch",
            "--wireframe",
            "--quit-after-reloads",
            "3",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let rx = lines_of(child.stderr.take().unwrap());
    let mut seen = Vec::new();
    wait_for(&rx, "first frame presented", &mut seen);
    // Three rewrites the way the solver writes (temporary file + rename), with
    // more elements each time; between them, a file that fails validation.
    for (k, n) in [(2u64, 3usize), (3, 4), (4, 5)] {
        write_solution(dir.path(), "room.sol", &version(k, n));
        wait_for(&rx, &format!("reloaded: shots={k} partial=true"), &mut seen);
        if k == 2 {
            let bad = dir.path().join("bad.tmp");
            std::fs::write(&bad, b"not a solution file").unwrap();
            std::fs::rename(&bad, &file).unwrap();
            wait_for(&rx, "keeping the previous solution", &mut seen);
        }
    }
    let status = child.wait().unwrap();
    let rest: Vec<String> = rx.iter().collect();
    seen.extend(rest);
    let stderr = seen.join("\n");
    assert!(status.success(), "mirror failed: {stderr}");
    assert!(!stderr.contains("vulkan validation"), "{stderr}");
    // Vertices of the n × n room: 4 faces of (n + 1)² each.
    assert!(
        stderr.contains("reloaded: shots=4 partial=true vertices=144"),
        "{stderr}"
    );
    assert_eq!(stderr.matches("reloaded:").count(), 3, "{stderr}");
}

#[test]
fn without_a_display_the_mirror_says_so_with_its_own_status() {
    let dir = tempfile::tempdir().unwrap();
    let file = write_solution(dir.path(), "room.sol", &common::diffuse_room(1));
    common::use_lavapipe_unless_chosen();
    let out = Command::new(env!("CARGO_BIN_EXE_runtime"))
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .arg("mirror")
        .arg(&file)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(runtime::mirror::NO_DISPLAY_EXIT_CODE),
        "{stderr}"
    );
    assert!(stderr.contains("cannot open a window"), "{stderr}");
}

#[test]
fn a_file_above_the_frame_cost_bound_is_refused_before_the_window() {
    // The glossy room at N = 4, L = 8 costs 2100 basis terms per view
    // (25 floor vertices × 81 terms plus 75 wall vertices × 1 term,
    // solution::format::frame_cost; as in tests/cli.rs). The bound is checked
    // when the file is opened, before any window: with no display, 2099 is
    // refused with the format's one-line message and 2100 gets as far as the
    // missing display.
    let dir = tempfile::tempdir().unwrap();
    let file = write_solution(dir.path(), "glossy.sol", &common::glossy_room(4, 8));
    common::use_lavapipe_unless_chosen();
    let mirror = |bound: &str| {
        Command::new(env!("CARGO_BIN_EXE_runtime"))
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .arg("mirror")
            .arg(&file)
            .args(["--max-frame-cost", bound])
            .output()
            .unwrap()
    };
    let out = mirror("2099");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    for part in ["glossy.sol", "2100", "2099", "--max-frame-cost"] {
        assert!(stderr.contains(part), "{stderr:?} lacks {part:?}");
    }
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    let out = mirror("2100");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(runtime::mirror::NO_DISPLAY_EXIT_CODE),
        "at the bound the file is not refused: {stderr}"
    );
}
