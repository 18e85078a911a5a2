//! Same results before and after a refactor (issue 40): the solver of a base
//! commit and the solver of this tree solve the same scenes with the same
//! flags, and their solution files must agree byte for byte in every section
//! but the header's solve time and the settings JSON's keys that the refactor
//! removed or renamed.
//!
//! No hashes are stored: `scripts/same-results.sh` builds the base commit's
//! solver beside this tree's and runs this test with both. It is ignored in a
//! plain `cargo test`, which has no base solver to compare with.
//!
//! Environment: `SAME_RESULTS_BASE_SOLVER` and `SAME_RESULTS_NEW_SOLVER` (the
//! two binaries), `SAME_RESULTS_SCENES` (a folder holding the scenegen scenes
//! `spheres-room.toml` and `floor-plan.toml` at 10k triangles), and
//! `SAME_RESULTS_IGNORE_KEYS` (comma-separated top-level settings keys that
//! may differ or be missing on either side).

mod common;
#[path = "support/emissive_box_scene.rs"]
mod emissive_box_scene;
// Shared with the tests that check the box against the truth; the camera is theirs.
#[allow(dead_code)]
#[path = "support/textured_cornell_scene.rs"]
mod textured_cornell_scene;

use std::path::{Path, PathBuf};
use std::process::Command;

/// One solve: a name for the report, the scene, and the flags after
/// `solve SCENE -o OUT`.
struct Case {
    name: &'static str,
    scene: PathBuf,
    flags: Vec<&'static str>,
}

fn cases(repo: &Path, generated: &Path, scenegen: &Path) -> Vec<Case> {
    let config = |f: &str| repo.join("config").join(f);
    let case = |name, scene: PathBuf, flags: &[&'static str]| Case {
        name,
        scene,
        flags: flags.to_vec(),
    };
    let textured_dir = generated.join("textured");
    std::fs::create_dir_all(&textured_dir).unwrap();
    let textured = textured_cornell_scene::write_scene(repo, &textured_dir, true);
    let emissive_dir = generated.join("emissive");
    std::fs::create_dir_all(&emissive_dir).unwrap();
    let emissive = emissive_box_scene::write_scene(&emissive_dir, true);
    emissive_box_scene::write_textures(&emissive_dir);
    vec![
        case(
            "cornell draft",
            config("cornell_box.toml"),
            &["--preset", "draft"],
        ),
        case(
            "cornell medium",
            config("cornell_box.toml"),
            &["--preset", "medium"],
        ),
        case(
            "cornell final",
            config("cornell_box.toml"),
            &["--preset", "final"],
        ),
        case(
            "cornell patch shooters",
            config("cornell_box.toml"),
            &["--preset", "medium", "--shooters", "patch"],
        ),
        case(
            "glossy box draft",
            config("glossy_cornell_box.toml"),
            &["--preset", "draft"],
        ),
        case(
            "textured diffuse draft",
            textured.clone(),
            &["--preset", "draft"],
        ),
        case(
            "textured directional draft",
            textured,
            &["--preset", "draft", "--mode", "directional"],
        ),
        case("emissive texture medium", emissive, &["--preset", "medium"]),
        case(
            "spheres room 10k draft",
            scenegen.join("spheres-room.toml"),
            &["--preset", "draft"],
        ),
        case(
            "floor plan 10k draft",
            scenegen.join("floor-plan.toml"),
            &["--preset", "draft"],
        ),
    ]
}

fn solve(solver: &Path, scene: &Path, out: &Path, flags: &[&str]) {
    let mut cmd = Command::new(solver);
    cmd.arg("solve").arg(scene).arg("-o").arg(out).args(flags);
    common::run(
        &mut cmd,
        &format!("{} solve {}", solver.display(), scene.display()),
    );
}

/// Solves the Cornell box at draft to a budget of 3 shots with a checkpoint
/// every 2, then resumes it to the end: the file of a resumed solve.
fn interrupted_and_resumed(solver: &Path, scene: &Path, out: &Path) {
    let draft = ["--preset", "draft"];
    // Stopped at its shot cap, the solve exits with status 4 (status 0 from a
    // base commit older than that status).
    let mut capped = Command::new(solver);
    capped
        .arg("solve")
        .arg(scene)
        .arg("-o")
        .arg(out)
        .args(draft)
        .args(["--max-shots", "3", "--checkpoint-every", "2"]);
    common::run_to_shot_cap(
        &mut capped,
        &format!("{} solve {}", solver.display(), scene.display()),
    );
    solve(solver, scene, out, &[&draft[..], &["--resume"]].concat());
}

fn env_path(name: &str) -> PathBuf {
    PathBuf::from(
        std::env::var_os(name)
            .unwrap_or_else(|| panic!("{name} is not set: run scripts/same-results.sh")),
    )
}

#[test]
#[ignore = "run by scripts/same-results.sh, which builds the base commit's solver"]
fn solutions_match_the_base_commit() {
    let base = env_path("SAME_RESULTS_BASE_SOLVER");
    let new = env_path("SAME_RESULTS_NEW_SOLVER");
    let scenegen = env_path("SAME_RESULTS_SCENES");
    let ignored: Vec<String> = std::env::var("SAME_RESULTS_IGNORE_KEYS")
        .unwrap_or_default()
        .split(',')
        .filter(|k| !k.is_empty())
        .map(str::to_owned)
        .collect();
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    let mut differences = Vec::new();
    let mut compare = |name: &str, old: &Path, new: &Path| {
        let found = same_results::differences(
            &std::fs::read(old).unwrap(),
            &std::fs::read(new).unwrap(),
            &ignored,
        );
        eprintln!(
            "{name}: {}",
            if found.is_empty() {
                "same"
            } else {
                "DIFFERENT"
            }
        );
        differences.extend(found.into_iter().map(|d| format!("{name}: {d}")));
    };
    for (k, case) in cases(repo, dir.path(), &scenegen).iter().enumerate() {
        let (old, fresh) = (
            dir.path().join(format!("{k}.base.sol")),
            dir.path().join(format!("{k}.new.sol")),
        );
        solve(&base, &case.scene, &old, &case.flags);
        solve(&new, &case.scene, &fresh, &case.flags);
        compare(case.name, &old, &fresh);
    }
    let cornell = repo.join("config/cornell_box.toml");
    let (old, fresh) = (
        dir.path().join("resumed.base.sol"),
        dir.path().join("resumed.new.sol"),
    );
    interrupted_and_resumed(&base, &cornell, &old);
    interrupted_and_resumed(&new, &cornell, &fresh);
    compare("cornell draft interrupted and resumed", &old, &fresh);
    assert!(differences.is_empty(), "{}", differences.join("\n"));
}

/// The comparison of two solution files, read as bytes by the layout of
/// docs/solution-format.md, without the `solution` crate: the base commit's
/// reader may differ from this tree's, and the comparison must not depend on
/// either.
mod same_results {
    use serde_json::Value;

    const PREAMBLE: usize = 64;
    /// The header's `stats.seconds`, the one timing field (header offset 176).
    const SECONDS: std::ops::Range<usize> = 176..184;
    /// The header's `settings_section` index (header offset 156).
    const SETTINGS_SECTION: usize = 156;

    fn u32_at(b: &[u8], at: usize) -> usize {
        u32::from_le_bytes(b[at..at + 4].try_into().unwrap()) as usize
    }

    fn u64_at(b: &[u8], at: usize) -> usize {
        u64::from_le_bytes(b[at..at + 8].try_into().unwrap()) as usize
    }

    /// The file's blocks: (header, batch table, section table).
    struct Blocks<'a> {
        header: &'a [u8],
        batches: &'a [u8],
        sections: Vec<&'a [u8]>,
    }

    fn blocks(b: &[u8]) -> Blocks<'_> {
        let header_len = u32_at(b, 32);
        let batches_len = u32_at(b, 36) * u32_at(b, 40);
        let (count, entry) = (u32_at(b, 44), u32_at(b, 48));
        let header = &b[PREAMBLE..PREAMBLE + header_len];
        let batches = &b[PREAMBLE + header_len..PREAMBLE + header_len + batches_len];
        let table = PREAMBLE + header_len + batches_len;
        let sections = (0..count)
            .map(|k| &b[table + k * entry..table + (k + 1) * entry])
            .collect();
        Blocks {
            header,
            batches,
            sections,
        }
    }

    /// The bytes a section table entry points at.
    fn section<'a>(file: &'a [u8], entry: &[u8]) -> &'a [u8] {
        let offset = u64_at(entry, 8);
        &file[offset..offset + u64_at(entry, 16)]
    }

    /// The settings JSON without the ignored top-level keys.
    fn settings(bytes: &[u8], ignored: &[String]) -> Value {
        let mut value: Value = serde_json::from_slice(bytes).unwrap();
        if let Some(map) = value.as_object_mut() {
            for key in ignored {
                map.remove(key);
            }
        }
        value
    }

    /// What differs between `old` and `new`, one line each; empty when they
    /// agree everywhere but the solve time, the checksums and offsets that
    /// the settings section's length moves, and the ignored settings keys.
    pub fn differences(old: &[u8], new: &[u8], ignored: &[String]) -> Vec<String> {
        let mut found = Vec::new();
        // Magic and version (0..12), then the block counts and lengths
        // (24..64). The metadata CRC (12..16) covers the section offsets and
        // the file length (16..24) the settings' length, so neither is compared.
        if old[..12] != new[..12] || old[24..PREAMBLE] != new[24..PREAMBLE] {
            found.push("preamble (version or block layout)".to_owned());
            return found;
        }
        let (a, b) = (blocks(old), blocks(new));
        let header_differs = (0..a.header.len())
            .filter(|i| !SECONDS.contains(i))
            .any(|i| a.header[i] != b.header[i]);
        if header_differs {
            found.push("header (other than stats.seconds)".to_owned());
        }
        if a.batches != b.batches {
            found.push("batch table".to_owned());
        }
        let settings_index = u32_at(a.header, SETTINGS_SECTION);
        for (k, (ea, eb)) in a.sections.iter().zip(&b.sections).enumerate() {
            let (sa, sb) = (section(old, ea), section(new, eb));
            if ea[..4] != eb[..4] {
                found.push(format!("section {k}: kind"));
            } else if k == settings_index {
                let (ja, jb) = (settings(sa, ignored), settings(sb, ignored));
                if ja != jb {
                    found.push(format!("settings JSON: base {ja} / new {jb}"));
                }
            } else if sa != sb {
                let first = sa.iter().zip(sb).position(|(x, y)| x != y);
                found.push(format!(
                    "section {k} (kind {}): {} / {} bytes, first difference at {first:?}",
                    u32_at(ea, 0),
                    sa.len(),
                    sb.len()
                ));
            }
        }
        found
    }
}
