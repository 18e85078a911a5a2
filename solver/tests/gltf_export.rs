//! `solver export` (issue 15, "Export round trip"): the Cornell box solved at
//! the draft preset, exported as `.glb` and as `.gltf` + `.bin`, read back with
//! the `gltf` crate (its validation and its accessor reader), and compared with
//! the solution file; then read again by the project's own glTF importer and
//! solved, as a consistency check of the geometry, units and up axis.

use glam::DVec3;
use solution::format::{read_solution, Solution};
use solution::raster::{shade_vertices, tone_map, ToneCurve};
use solution::sh;
use std::path::{Path, PathBuf};
use std::process::Command;

fn solver(args: &[&std::ffi::OsStr]) {
    solver_allowing(args, &[0]);
}

/// Runs the solver, which must exit with one of `codes`: a solve stopped by its
/// `--max-shots` above the threshold exits with 4.
fn solver_allowing(args: &[&std::ffi::OsStr], codes: &[i32]) {
    let output = Command::new(env!("CARGO_BIN_EXE_solver"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        output.status.code().is_some_and(|c| codes.contains(&c)),
        "solver {args:?}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
}

/// The attributes of every primitive, in order, as the `gltf` crate reads them.
#[derive(Debug, PartialEq)]
struct Primitive {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    colors: Vec<[f32; 3]>,
    radiance: Vec<[f32; 3]>,
    indices: Vec<u32>,
}

fn read_primitives(document: &gltf::Gltf, bin: &[u8]) -> Vec<Primitive> {
    let radiance = gltf::Semantic::Extras("RADIANCE".into());
    let mut out = Vec::new();
    for mesh in document.meshes() {
        for primitive in mesh.primitives() {
            let reader = primitive.reader(|_| Some(bin));
            let accessor = primitive.get(&radiance).expect("_RADIANCE");
            let colors = match reader.read_colors(0).expect("COLOR_0") {
                gltf::mesh::util::ReadColors::RgbF32(it) => it.collect(),
                other => panic!("COLOR_0 is not RGB f32: {other:?}"),
            };
            out.push(Primitive {
                positions: reader.read_positions().unwrap().collect(),
                normals: reader.read_normals().unwrap().collect(),
                colors,
                radiance: gltf::accessor::Iter::<[f32; 3]>::new(accessor, |_| Some(bin))
                    .unwrap()
                    .collect(),
                indices: reader.read_indices().unwrap().into_u32().collect(),
            });
        }
    }
    out
}

/// Area of the exported triangles, m² (f64 from the f32 positions).
fn area(primitives: &[Primitive]) -> f64 {
    let mut total = 0.0;
    for p in primitives {
        for t in p.indices.chunks_exact(3) {
            let [a, b, c] =
                [0, 1, 2].map(|k| DVec3::from(p.positions[t[k] as usize].map(f64::from)));
            total += 0.5 * (b - a).cross(c - a).length();
        }
    }
    total
}

fn check_against_solution(solution: &Solution, primitives: &[Primitive]) {
    let header = &solution.header;
    assert_eq!(
        header.units_per_metre, 1000.0,
        "the Cornell box is in millimetres"
    );
    let drawn: Vec<_> = solution
        .batches
        .iter()
        .filter(|b| !b.indices.is_empty())
        .collect();
    assert_eq!(primitives.len(), drawn.len());
    let offset = DVec3::from(header.recentre_offset);
    let eye = DVec3::from(header.camera.eye) - offset;
    for (batch, p) in drawn.iter().zip(primitives) {
        assert_eq!(p.positions.len(), batch.vertices.len());
        assert_eq!(p.indices, batch.indices);
        // The renderer's vertex stage on the solution as read: bit for bit.
        let expected = shade_vertices(batch, u32::MAX, eye, true).unwrap();
        assert_eq!(p.radiance, expected);
        for (v, vertex) in batch.vertices.iter().enumerate() {
            // Diffuse: radiance = c₀₀·Y₀₀, independently of the renderer.
            let c = &batch.coefficients[v * 3..v * 3 + 3];
            assert_eq!(
                p.radiance[v],
                [0, 1, 2].map(|k| (f64::from(c[k]) * sh::Y00).max(0.0) as f32)
            );
            // COLOR_0 is the default tone map, clamp at exposure 0 (2⁰ = 1 is
            // exact): the same f32 operations, so equal to the bit.
            assert_eq!(
                p.colors[v],
                p.radiance[v].map(|x| tone_map(x, ToneCurve::Clamp))
            );
            // Metres, +y up already: one rounding to f32 of the exact value.
            let exact = (DVec3::from(vertex.position.map(f64::from)) + offset) / 1000.0;
            for axis in 0..3 {
                let error = (f64::from(p.positions[v][axis]) - exact[axis]).abs();
                assert!(
                    error <= exact[axis].abs() * 2f64.powi(-24),
                    "{:?} vs {exact}",
                    p.positions[v]
                );
            }
            assert_eq!(p.normals[v], vertex.normal);
        }
    }
}

#[test]
fn export_round_trip_of_the_solved_cornell_box() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let dir = tempfile::tempdir().unwrap();
    let sol = dir.path().join("box.sol");
    let (glb, gltf_path) = (dir.path().join("box.glb"), dir.path().join("box.gltf"));
    let os = |p: &Path| p.as_os_str().to_owned();
    let toml = root.join("config/cornell_box.toml");
    solver(&[
        "solve".as_ref(),
        &os(&toml),
        "--preset".as_ref(),
        "draft".as_ref(),
        "-o".as_ref(),
        &os(&sol),
    ]);
    for out in [&glb, &gltf_path] {
        solver(&["export".as_ref(), &os(&sol), "-o".as_ref(), &os(out)]);
    }
    let solution = read_solution(&sol).unwrap();

    let glb_bytes = std::fs::read(&glb).unwrap();
    let from_glb = gltf::Gltf::from_slice(&glb_bytes).expect("a valid .glb");
    let blob = from_glb.blob.clone().expect("a BIN chunk");
    let glb_primitives = read_primitives(&from_glb, &blob);
    check_against_solution(&solution, &glb_primitives);
    let vertices: usize = glb_primitives.iter().map(|p| p.positions.len()).sum();
    let solved: usize = solution.batches.iter().map(|b| b.vertices.len()).sum();
    assert_eq!(vertices, solved);

    // The .gltf names its .bin, and holds the same values.
    let from_gltf =
        gltf::Gltf::from_slice(&std::fs::read(&gltf_path).unwrap()).expect("a valid .gltf");
    let buffer = from_gltf.buffers().next().unwrap();
    let gltf::buffer::Source::Uri(uri) = buffer.source() else {
        panic!("the .gltf's buffer has no uri");
    };
    assert_eq!(uri, "box.bin");
    let bin = std::fs::read(dir.path().join(uri)).unwrap();
    assert_eq!(bin, blob);
    assert_eq!(read_primitives(&from_gltf, &bin), glb_primitives);

    // The camera: the header's eye in metres, looking along +z as the Cornell
    // camera does.
    let node = from_glb.nodes().find(|n| n.camera().is_some()).unwrap();
    let (translation, rotation, _) = node.transform().decomposed();
    let eye = DVec3::from(solution.header.camera.eye) / 1000.0;
    assert!((DVec3::from(translation.map(f64::from)) - eye).length() < 1e-6);
    let forward = glam::Quat::from_array(rotation).as_dquat() * DVec3::NEG_Z;
    assert!((forward - DVec3::Z).length() < 1e-6, "{forward}");

    reimport(&glb, &glb_primitives, dir.path());
    refusals(&sol, dir.path());
}

/// Bad input: a clear error naming the file, and no output written.
fn refusals(sol: &Path, dir: &Path) {
    let run = |input: &Path, out: &Path| {
        let output = Command::new(env!("CARGO_BIN_EXE_solver"))
            .arg("export")
            .arg(input)
            .arg("-o")
            .arg(out)
            .output()
            .unwrap();
        assert!(!output.status.success());
        assert!(!out.exists(), "{} written", out.display());
        String::from_utf8_lossy(&output.stderr).into_owned()
    };
    let message = run(sol, &dir.join("box.obj"));
    assert!(
        message.contains("box.obj") && message.contains(".glb"),
        "{message}"
    );
    // One flipped bit in the last section (the indices): its checksum.
    let mut bytes = std::fs::read(sol).unwrap();
    let at = bytes.len() - 100;
    bytes[at] ^= 1;
    let bad = dir.join("bad.sol");
    std::fs::write(&bad, bytes).unwrap();
    let message = run(&bad, &dir.join("bad.glb"));
    assert!(
        message.contains("bad.sol") && message.contains("CRC-32"),
        "{message}"
    );
}

/// The project's own importer reads the export back (a consistency check,
/// not a physics one: the export carries radiance, not materials). The file
/// has no emitter, so `load_scene` gets as far as the emitter check; a TOML
/// config then makes its one material emit radiance 1 (and reflect nothing)
/// and `solver solve` solves it. A one-sided Lambertian emitter of radiance L
/// and area A emits π·L·A per channel, so the emitted power (summed over the
/// three channels) is 3π·A with A the exported triangles' area in m²: it
/// checks that the importer sees the exported geometry at its size in metres.
fn reimport(glb: &Path, primitives: &[Primitive], dir: &Path) {
    let options = solver::scene::ImportOptions::default();
    match solver::scene::load_scene(glb, &options) {
        Err(solver::scene::SceneError::NoEmitter(_)) => {}
        Err(e) => panic!("the importer refuses the export: {e}"),
        Ok(_) => panic!("an export has no emitter"),
    }
    let config = dir.join("reimport.toml");
    std::fs::write(
        &config,
        "geometry = [\"box.glb\"]\nunits_per_metre = 1\nup = \"y\"\n\
         [materials.\"solution radiance (unlit)\"]\nkd = 0.0\nemission = 1.0\n",
    )
    .unwrap();
    let out = dir.join("reimport.sol");
    solver_allowing(
        &[
            "solve".as_ref(),
            config.as_os_str(),
            "--preset".as_ref(),
            "draft".as_ref(),
            "--max-shots".as_ref(),
            "1".as_ref(),
            "-o".as_ref(),
            out.as_os_str(),
        ],
        &[0, 4],
    );
    let header = read_solution(&out).unwrap().header;
    let expected = 3.0 * std::f64::consts::PI * area(primitives);
    let relative = (header.stats.emitted_power / expected - 1.0).abs();
    eprintln!(
        "re-imported emitted power {} W, 3π·A = {expected} W, relative difference {relative:.2e}",
        header.stats.emitted_power
    );
    // Areas summed in f64 over f32 corners, in a different order and after
    // welding: a few f32 ulps of relative difference at most.
    assert!(relative < 1e-6, "{relative:e}");
}

/// A textured solution (format 2) through `solver export`: the texture
/// section's PNG lands in the `.glb` as it is, with the UVs flipped to glTF's
/// convention; a textured batch with an untextured term is warned about.
#[test]
fn textured_solution_through_the_cli() {
    use solution::camera::{Camera, UpAxis};
    use solution::format::{
        write_solution, Batch, Header, MappedSolution, Representation, ScalarType, SolveMode,
        SolveStats, Texture, TexturedVertex, Texturing, Vertex,
    };
    let vertex = |x: f32, z: f32| Vertex {
        position: [x, 0.0, z],
        normal: [0.0, 1.0, 0.0],
        tangent: [1.0, 0.0, 0.0],
    };
    let texturing = Texturing {
        texture: 0,
        factor: [1.0, 0.5, 0.25],
        emission: None,
        vertices: (0..4)
            .map(|k| TexturedVertex {
                uv: [(k % 2) as f32, (k / 2) as f32 * 0.75],
                irradiance_over_pi: [0.25, 0.5, k as f32],
            })
            .collect(),
    };
    let mut solution = Solution {
        lighting: None,
        header: Header {
            units_per_metre: 1.0,
            up_axis: UpAxis::PosY,
            recentre_offset: [0.0; 3],
            camera: Camera {
                eye: [0.0, 2.0, 2.0],
                target: [0.0; 3],
                ..Camera::default()
            },
            bounds_min: [-1.0, 0.0, -1.0],
            bounds_max: [1.0, 0.0, 1.0],
            partial: false,
            mode: SolveMode::Diffuse,
            stats: SolveStats::default(),
            settings_json: "{}".into(),
        },
        batches: vec![Batch {
            representation: Representation::Sh { order: 0 },
            scalar: ScalarType::F32,
            vertices: vec![
                vertex(-1.0, 1.0),
                vertex(1.0, 1.0),
                vertex(-1.0, -1.0),
                vertex(1.0, -1.0),
            ],
            coefficients: vec![0.0; 12],
            indices: vec![0, 1, 3, 0, 3, 2],
            texturing: Some(texturing.clone()),
        }],
        textures: vec![Texture {
            width: 4,
            height: 2,
            rgba: (0..32).map(|k| (k * 8) as u8).collect(),
        }],
    };
    let dir = tempfile::tempdir().unwrap();
    for (name, coefficient) in [("plain", 0.0), ("lobe", 0.5)] {
        solution.batches[0].coefficients[0] = coefficient;
        let sol = dir.path().join(format!("{name}.sol"));
        write_solution(&sol, &solution).unwrap();
        let glb = dir.path().join(format!("{name}.glb"));
        let output = Command::new(env!("CARGO_BIN_EXE_solver"))
            .arg("export")
            .arg(&sol)
            .arg("-o")
            .arg(&glb)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(output.status.success(), "{stderr}");
        assert_eq!(
            stderr.contains("untextured term"),
            coefficient != 0.0,
            "{stderr}"
        );
        let bytes = std::fs::read(&glb).unwrap();
        let document = gltf::Gltf::from_slice(&bytes).expect("a valid .glb");
        let blob = document.blob.clone().unwrap();
        let primitive = document
            .meshes()
            .next()
            .unwrap()
            .primitives()
            .next()
            .unwrap();
        let reader = primitive.reader(|_| Some(&blob));
        let uv: Vec<[f32; 2]> = reader.read_tex_coords(0).unwrap().into_f32().collect();
        let expected: Vec<[f32; 2]> = texturing
            .vertices
            .iter()
            .map(|t| [t.uv[0], 1.0 - t.uv[1]])
            .collect();
        assert_eq!(uv, expected);
        let texture = primitive
            .material()
            .pbr_metallic_roughness()
            .base_color_texture()
            .unwrap();
        let gltf::image::Source::View { view, .. } = texture.texture().source().source() else {
            panic!("the image is not in the buffer");
        };
        let stored = MappedSolution::open(&sol).unwrap();
        assert_eq!(
            &blob[view.offset()..view.offset() + view.length()],
            stored.texture_bytes(0)
        );
    }
}
