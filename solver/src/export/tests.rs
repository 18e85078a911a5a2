//! The exporter on small synthetic solutions, read back with the `gltf` crate
//! (its validation and its accessor reader, independent of the bytes written
//! here).

use super::*;
use glam::{DMat3, DVec3};
use solution::camera::{Camera, UpAxis};
use solution::format::{write_solution, Header, MappedSolution, Solution, SolveMode, SolveStats};
use solution::format::{Batch, ScalarType, Vertex};
use solution::raster::{shade_vertices, tone_map};
use solution::sh;

fn vertex(position: [f32; 3], normal: [f32; 3], tangent: [f32; 3]) -> Vertex {
    Vertex {
        position,
        normal,
        tangent,
    }
}

/// A header in millimetres with +z up, far from the origin (the offset), so
/// the unit scale, the up-axis rotation and the offset all show.
fn header(up_axis: UpAxis) -> Header {
    Header {
        units_per_metre: 1000.0,
        up_axis,
        recentre_offset: [12_345.5, -2_000.25, 700.0],
        camera: Camera {
            eye: [12_345.5, -4_000.0, 1_200.0],
            target: [12_345.5, -2_000.25, 700.0],
            up: [0.0, 0.0, 1.0],
            fov_y_deg: 40.0,
            width: 640,
            height: 480,
        },
        bounds_min: [-500.0, -500.0, -500.0],
        bounds_max: [500.0, 500.0, 500.0],
        partial: false,
        mode: SolveMode::Directional,
        stats: SolveStats::default(),
        settings_json: "{}".into(),
    }
}

/// Three drawn batches (diffuse f32; SH order 1 in f16 holding only the
/// cos θ term; a global cube with k = 1) and one empty batch.
fn solution(up_axis: UpAxis) -> Solution {
    let z = [0.0, 0.0, 1.0];
    let x = [1.0, 0.0, 0.0];
    let floor = [
        vertex([-400.0, -300.0, -200.0], z, x),
        vertex([400.0, -300.0, -200.0], z, x),
        vertex([400.0, 300.0, -200.0], z, x),
        vertex([-400.0, 300.0, -200.0], z, x),
    ];
    let diffuse = Batch {
        representation: Representation::Sh { order: 0 },
        scalar: ScalarType::F32,
        vertices: floor.to_vec(),
        // c₀₀ per channel; radiance = c₀₀·Y₀₀. One negative value (clamped).
        coefficients: vec![
            1.0, 2.0, 3.0, 0.5, 0.25, 0.125, 10.0, 0.0, -1.0, 3.5, 3.5, 3.5,
        ],
        indices: vec![0, 1, 2, 0, 2, 3],
        texturing: None,
    };
    let mut sh1 = vec![0.0f32; 3 * 4 * 3];
    for v in 0..3 {
        // Coefficient k = 2 (l = 1, m = 0: √(3/4π)·cos θ), all channels.
        for c in 0..3 {
            sh1[(v * 4 + 2) * 3 + c] = 0.5 * (v + 1) as f32 + c as f32;
        }
    }
    let glossy = Batch {
        representation: Representation::Sh { order: 1 },
        scalar: ScalarType::F16 { scale: 0.5 },
        vertices: floor[..3].to_vec(),
        coefficients: sh1,
        indices: vec![0, 1, 2],
        texturing: None,
    };
    let cube = Batch {
        representation: Representation::Cube { directions: 6 },
        scalar: ScalarType::F32,
        vertices: floor[1..].to_vec(),
        coefficients: (0..3 * 6 * 3).map(|k| 0.1 * k as f32).collect(),
        indices: vec![0, 1, 2],
        texturing: None,
    };
    let empty = Batch {
        representation: Representation::Sh { order: 0 },
        scalar: ScalarType::F32,
        vertices: Vec::new(),
        coefficients: Vec::new(),
        indices: Vec::new(),
        texturing: None,
    };
    Solution {
        lighting: None,
        header: header(up_axis),
        batches: vec![diffuse, empty, glossy, cube],
        textures: Vec::new(),
    }
}

/// Writes `solution`, maps it and exports it as the command does.
fn export(solution: &Solution, options: ExportOptions, bin_uri: Option<&str>) -> Exported {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.sol");
    write_solution(&path, solution).unwrap();
    let file = MappedSolution::open(&path).unwrap();
    let mut exporter =
        Exporter::new(file.header(), file.batches(), file.textures(), options).unwrap();
    for (i, info) in file.batches().iter().enumerate() {
        let bytes = BatchBytes {
            vertices: file.vertex_bytes(i),
            coefficients: file.coefficient_bytes(i),
            indices: file.index_bytes(i),
            textured_vertices: file.textured_vertex_bytes(i),
        };
        exporter.add_batch(i, info, bytes, |_| {}).unwrap();
    }
    exporter.finish(bin_uri).unwrap()
}

fn glb(exported: &Exported) -> Vec<u8> {
    let mut out = Vec::new();
    write_glb(&mut out, &exported.json, &exported.bin).unwrap();
    assert_eq!(
        out.len() as u64,
        glb_length(exported.json.len() as u64, exported.bin.len() as u64)
    );
    out
}

/// One primitive's attributes as the `gltf` crate reads them.
struct Read {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    colors: Vec<[f32; 3]>,
    radiance: Vec<[f32; 3]>,
    indices: Vec<u32>,
}

fn read_vec3(accessor: &gltf::Accessor, blob: &[u8]) -> Vec<[f32; 3]> {
    assert_eq!(accessor.data_type(), gltf::accessor::DataType::F32);
    assert_eq!(accessor.dimensions(), gltf::accessor::Dimensions::Vec3);
    gltf::accessor::Iter::<[f32; 3]>::new(accessor.clone(), |_| Some(blob))
        .unwrap()
        .collect()
}

fn read_back(bytes: &[u8]) -> (gltf::Gltf, Vec<Read>) {
    // `from_slice` validates the document (references, counts, required fields).
    let file = gltf::Gltf::from_slice(bytes).expect("a valid glTF");
    let blob = file.blob.clone().unwrap_or_default();
    let mut out = Vec::new();
    for mesh in file.meshes() {
        for primitive in mesh.primitives() {
            let reader = primitive.reader(|_| Some(&blob));
            let radiance = primitive
                .attributes()
                .find(|(s, _)| *s == gltf::Semantic::Extras(RADIANCE_ATTRIBUTE[1..].into()))
                .map(|(_, a)| read_vec3(&a, &blob))
                .expect("_RADIANCE");
            let colors = match reader.read_colors(0).expect("COLOR_0") {
                gltf::mesh::util::ReadColors::RgbF32(it) => it.collect(),
                other => panic!("COLOR_0 is not RGB f32: {other:?}"),
            };
            out.push(Read {
                positions: reader.read_positions().unwrap().collect(),
                normals: reader.read_normals().unwrap().collect(),
                colors,
                radiance,
                indices: reader.read_indices().unwrap().into_u32().collect(),
            });
        }
    }
    (file, out)
}

/// The exact metres value (f64) of a stored position.
fn metres(header: &Header, p: [f32; 3], rotate: impl Fn(DVec3) -> DVec3) -> DVec3 {
    rotate(
        (DVec3::from(p.map(f64::from)) + DVec3::from(header.recentre_offset))
            / header.units_per_metre,
    )
}

#[test]
fn the_frame_is_a_proper_rotation_taking_up_to_plus_y() {
    for up in [UpAxis::PosY, UpAxis::NegY, UpAxis::PosZ, UpAxis::NegZ] {
        let frame = GltfFrame::new([0.0; 3], 1.0, up);
        let m = DMat3::from_cols(
            frame.rotate(DVec3::X),
            frame.rotate(DVec3::Y),
            frame.rotate(DVec3::Z),
        );
        assert_eq!(m.determinant(), 1.0, "{up:?}");
        assert_eq!(frame.rotate(DVec3::from(up.vector())), DVec3::Y, "{up:?}");
        let d = [0.25f32, -0.5, 0.75];
        let rotated = frame
            .rotate(DVec3::from(d.map(f64::from)))
            .as_vec3()
            .to_array();
        assert_eq!(frame.direction(d), rotated);
    }
}

#[test]
fn round_trip_through_the_gltf_crate() {
    let solution = solution(UpAxis::PosZ);
    let options = ExportOptions {
        exposure_stops: 1.5,
        curve: ToneCurve::Reinhard,
        glossy_eye: None,
    };
    let exported = export(&solution, options, None);
    let (file, read) = read_back(&glb(&exported));
    let frame = GltfFrame::new(solution.header.recentre_offset, 1000.0, UpAxis::PosZ);
    let drawn: Vec<&Batch> = solution
        .batches
        .iter()
        .filter(|b| !b.indices.is_empty())
        .collect();
    assert_eq!(read.len(), drawn.len(), "the empty batch is skipped");
    assert_eq!(exported.vertices, 10);
    assert_eq!(exported.triangles, 4);
    let eye_file =
        DVec3::from(solution.header.camera.eye) - DVec3::from(solution.header.recentre_offset);
    let exposure = 1.5f32.exp2();
    for (batch, r) in drawn.iter().zip(&read) {
        assert_eq!(r.positions.len(), batch.vertices.len());
        assert_eq!(r.indices, batch.indices);
        // The renderer's vertex stage on the batch as the format's reader
        // widens it: the same f32 values, bit for bit.
        let decoded =
            solution::format::decode(&solution::format::encode(&solution).unwrap()).unwrap();
        let same = decoded
            .batches
            .iter()
            .find(|b| b.vertices == batch.vertices && b.representation == batch.representation)
            .unwrap();
        let expected = shade_vertices(same, u32::MAX, eye_file, true).unwrap();
        assert_eq!(r.radiance, expected);
        for (color, rgb) in r.colors.iter().zip(&expected) {
            // Exact: the same f32 operations on the same f32 inputs.
            assert_eq!(
                *color,
                rgb.map(|x| tone_map(x * exposure, ToneCurve::Reinhard))
            );
        }
        for ((p, n), v) in r.positions.iter().zip(&r.normals).zip(&batch.vertices) {
            let exact = metres(&solution.header, v.position, |d| frame.rotate(d));
            for axis in 0..3 {
                // One rounding to f32: half an ulp, 2⁻²⁴ relative.
                let error = (f64::from(p[axis]) - exact[axis]).abs();
                assert!(
                    error <= exact[axis].abs() * 2f64.powi(-24),
                    "{p:?} vs {exact}"
                );
            }
            // +z up became +y up: the floor's normal points up in glTF.
            assert_eq!(*n, [0.0, 1.0, 0.0]);
        }
    }
    // Independent of the renderer: diffuse radiance is c₀₀·Y₀₀ (clamped at 0),
    // and the order-1 batch's is c₁₀·√(3/4π)·cos θ toward the eye.
    let c = &solution.batches[0].coefficients;
    for (v, rgb) in read[0].radiance.iter().enumerate() {
        for ch in 0..3 {
            let expected = (f64::from(c[v * 3 + ch]) * sh::Y00).max(0.0) as f32;
            assert_eq!(rgb[ch], expected);
        }
    }
    let y10 = (3.0 / (4.0 * std::f64::consts::PI)).sqrt();
    for (v, rgb) in read[1].radiance.iter().enumerate() {
        let p = DVec3::from(solution.batches[2].vertices[v].position.map(f64::from));
        let cos = (eye_file - p).normalize().z;
        for (ch, value) in rgb.iter().enumerate() {
            let coefficient = 0.5 * (v + 1) as f64 + ch as f64;
            let expected = (coefficient * y10 * cos).max(0.0);
            // The coefficients are exact in f16 (multiples of 0.25 below 2048);
            // the f64 evaluation is then rounded to f32 once: 2⁻²⁴ relative,
            // with the SH recurrences' own error far below it.
            assert!(
                (f64::from(*value) - expected).abs() <= 1e-6 * expected.max(1e-30),
                "{value} vs {expected}"
            );
        }
    }
    // The unlit material and the custom attribute's name.
    let material = file.materials().next().unwrap();
    assert!(material.extension_value("KHR_materials_unlit").is_some());
    assert_eq!(
        material.pbr_metallic_roughness().base_color_factor(),
        [1.0; 4]
    );
    assert!(file.extensions_used().any(|e| e == "KHR_materials_unlit"));
    // The tone settings travel with the file, spelled as the flags spell them.
    let extras: serde_json::Value = serde_json::from_slice(&exported.json).unwrap();
    assert_eq!(extras["asset"]["extras"]["tone_curve"], "reinhard");
    assert_eq!(extras["asset"]["extras"]["exposure_stops"], 1.5);
}

#[test]
fn the_header_camera_becomes_a_gltf_perspective_camera() {
    for up in [UpAxis::PosZ, UpAxis::NegY] {
        let mut solution = solution(up);
        if up == UpAxis::NegY {
            solution.header.camera.up = [0.0, -1.0, 0.0];
        }
        let exported = export(&solution, ExportOptions::default(), None);
        let (file, _) = read_back(&glb(&exported));
        let node = file
            .nodes()
            .find(|n| n.camera().is_some())
            .expect("a camera node");
        let gltf_camera = node.camera().unwrap();
        let gltf::camera::Projection::Perspective(p) = gltf_camera.projection() else {
            panic!("not perspective");
        };
        let camera = &solution.header.camera;
        assert!((f64::from(p.yfov()) - camera.fov_y_deg.to_radians()).abs() < 1e-6);
        assert_eq!(p.aspect_ratio(), Some(640.0 / 480.0));
        assert!(p.znear() > 0.0);
        let (translation, rotation, scale) = node.transform().decomposed();
        assert_eq!(scale, [1.0; 3]);
        let frame = GltfFrame::new(solution.header.recentre_offset, 1000.0, up);
        let eye = frame.scene_point(DVec3::from(camera.eye));
        // f32 in the file: 2⁻²⁴ relative of coordinates of a few metres.
        assert!((DVec3::from(translation.map(f64::from)) - eye).length() < 1e-6);
        let q = glam::Quat::from_array(rotation).as_dquat();
        let (_, cam_up, forward) = camera.basis();
        // The node looks down its −z with +y up (glTF 2.0 §3.10.1).
        assert!((q * DVec3::NEG_Z - frame.rotate(forward)).length() < 1e-6);
        assert!((q * DVec3::Y - frame.rotate(cam_up)).length() < 1e-6);
        // In glTF's frame the camera stands upright: its up hint is the
        // header's up axis, so after the rotation its right vector is level
        // (no roll) and its up points to +y's side.
        assert!((q * DVec3::X).y.abs() < 1e-6, "{up:?}");
        assert!((q * DVec3::Y).y > 0.0, "{up:?}");
    }
}

#[test]
fn gltf_and_bin_hold_the_same_buffer_with_its_uri() {
    let solution = solution(UpAxis::PosY);
    let uri = file_name_uri("my scene#1.bin");
    assert_eq!(uri, "my%20scene%231.bin");
    let exported = export(&solution, ExportOptions::default(), Some(&uri));
    let document = gltf::Gltf::from_slice(&exported.json).expect("a valid .gltf");
    let buffer = document.buffers().next().unwrap();
    assert!(matches!(buffer.source(), gltf::buffer::Source::Uri(u) if u == uri));
    assert_eq!(buffer.length(), exported.bin.len());
    let binary = export(&solution, ExportOptions::default(), None);
    assert_eq!(binary.bin, exported.bin);
}

#[test]
fn sizes_beyond_the_u32_limit_are_refused_before_allocating() {
    let header = header(UpAxis::PosY);
    let info = |vertex_count: u32, index_count: u32| BatchInfo {
        representation: Representation::Sh { order: 0 },
        scalar: ScalarType::F32,
        vertex_count,
        index_count,
        frame_convention: 1,
        basis_convention: 1,
        texture: None,
    };
    // 90 million vertices × 48 bytes is 4.3 GB: refused, nothing allocated
    // (the planned buffer would be that size).
    let err = Exporter::new(
        &header,
        &[info(90_000_000, 3)],
        &[],
        ExportOptions::default(),
    )
    .err()
    .expect("refused");
    let message = err.to_string();
    assert!(message.contains("4294967295"), "{message}");
    // Two batches each under the limit, together over it.
    let half = info(45_000_000, 3);
    assert!(Exporter::new(&header, &[half, half], &[], ExportOptions::default()).is_err());
    // Just under: 80 million vertices (3.84 GB) pass the check.
    assert!(glb_length(JSON_BYTES_FIXED, 80_000_000 * VERTEX_BYTES) < MAX_GLTF_BYTES);
}

#[test]
fn wrong_section_lengths_and_missing_batches_are_refused() {
    let solution = solution(UpAxis::PosY);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.sol");
    write_solution(&path, &solution).unwrap();
    let file = MappedSolution::open(&path).unwrap();
    let mut exporter =
        Exporter::new(file.header(), file.batches(), &[], ExportOptions::default()).unwrap();
    let short = BatchBytes {
        vertices: &file.vertex_bytes(0)[..36],
        coefficients: file.coefficient_bytes(0),
        indices: file.index_bytes(0),
        textured_vertices: &[],
    };
    let err = exporter
        .add_batch(0, &file.batches()[0], short, |_| {})
        .unwrap_err();
    assert!(
        err.to_string().contains("vertices section is 36 bytes"),
        "{err}"
    );
    let err = exporter.finish(None).unwrap_err();
    assert!(
        err.to_string().contains("batch 0: planned but never added"),
        "{err}"
    );
    let bad = ExportOptions {
        exposure_stops: f32::NAN,
        ..Default::default()
    };
    assert!(Exporter::new(file.header(), file.batches(), &[], bad).is_err());
}

#[test]
fn glb_container_lengths_and_padding() {
    let mut out = Vec::new();
    write_glb(&mut out, b"{}", &[1, 2, 3, 4, 5]).unwrap();
    // 12 header + 8 + 4 (JSON padded) + 8 + 8 (BIN padded).
    assert_eq!(out.len(), 40);
    assert_eq!(&out[0..4], b"glTF");
    assert_eq!(u32::from_le_bytes(out[8..12].try_into().unwrap()), 40);
    assert_eq!(&out[16..24], b"JSON{}  ");
    assert_eq!(&out[28..32], b"BIN\0");
    assert_eq!(&out[32..40], &[1, 2, 3, 4, 5, 0, 0, 0]);
    assert_eq!(glb_length(2, 0), 24);
}

/// A textured batch (format 2): TEXCOORD_0 = (u, 1 − v), `_RADIANCE` = E/π,
/// COLOR_0 its tone map, the PNG as stored in a material of its own with the
/// batch's factor; a textured batch with an untextured term is reported.
#[test]
fn textured_batches_carry_their_png_uvs_and_e_over_pi() {
    use solution::format::{Texture, TexturedVertex, Texturing};
    let mut solution = solution(UpAxis::PosY);
    solution.batches.truncate(1);
    let texturing = Texturing {
        texture: 0,
        factor: [0.5, 1.0, 0.25],
        emission: None,
        vertices: (0..4)
            .map(|k| TexturedVertex {
                uv: [0.25 * k as f32, 0.125 + 0.25 * k as f32],
                irradiance_over_pi: [0.5 * k as f32, 1.0, 2.0],
            })
            .collect(),
    };
    let mut glossy = solution.batches[0].clone();
    glossy.texturing = Some(texturing.clone());
    solution.batches[0].coefficients.fill(0.0);
    solution.batches[0].texturing = Some(texturing.clone());
    solution.batches.push(glossy);
    let rgba: Vec<u8> = (0..2 * 2 * 4).map(|k| (k * 16) as u8).collect();
    solution.textures = vec![Texture {
        width: 2,
        height: 2,
        rgba: rgba.clone(),
    }];
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("t.sol");
    write_solution(&path, &solution).unwrap();
    let file = MappedSolution::open(&path).unwrap();
    let options = ExportOptions {
        exposure_stops: -1.0,
        ..Default::default()
    };
    let mut exporter =
        Exporter::new(file.header(), file.batches(), file.textures(), options).unwrap();
    let mut dropped = Vec::new();
    for (i, info) in file.batches().iter().enumerate() {
        let bytes = BatchBytes {
            vertices: file.vertex_bytes(i),
            coefficients: file.coefficient_bytes(i),
            indices: file.index_bytes(i),
            textured_vertices: file.textured_vertex_bytes(i),
        };
        dropped.push(exporter.add_batch(i, info, bytes, |_| {}).unwrap());
    }
    // The second batch keeps non-zero coefficients: its untextured term.
    assert_eq!(dropped, [false, true]);
    exporter.add_texture(0, file.texture_bytes(0)).unwrap();
    let exported = exporter.finish(None).unwrap();
    let bytes = glb(&exported);
    let (document, read) = read_back(&bytes);
    let blob = document.blob.clone().unwrap();
    for (primitive, r) in document.meshes().flat_map(|m| m.primitives()).zip(&read) {
        let reader = primitive.reader(|_| Some(&blob));
        let uv: Vec<[f32; 2]> = reader
            .read_tex_coords(0)
            .expect("TEXCOORD_0")
            .into_f32()
            .collect();
        for (k, t) in texturing.vertices.iter().enumerate() {
            assert_eq!(uv[k], [t.uv[0], 1.0 - t.uv[1]]);
            assert_eq!(r.radiance[k], t.irradiance_over_pi);
            let y = t
                .irradiance_over_pi
                .map(|x| tone_map(x * 0.5, ToneCurve::Clamp));
            assert_eq!(r.colors[k], y);
        }
        let material = primitive.material();
        assert!(material.extension_value("KHR_materials_unlit").is_some());
        let pbr = material.pbr_metallic_roughness();
        assert_eq!(pbr.base_color_factor(), [0.5, 1.0, 0.25, 1.0]);
        let info = pbr.base_color_texture().expect("a base colour texture");
        assert_eq!(info.tex_coord(), 0);
        let gltf::image::Source::View { view, mime_type } = info.texture().source().source() else {
            panic!("the image is not in the buffer");
        };
        assert_eq!(mime_type, "image/png");
        let png = &blob[view.offset()..view.offset() + view.length()];
        assert_eq!(png, file.texture_bytes(0));
        let decoded = solution::format::decode_png(png, 2, 2).unwrap();
        assert_eq!(decoded.rgba, rgba);
    }
}

/// A batch with both textures (format 3's emission slot): its material keeps
/// the base-colour texture and factor, and adds the emission texture with
/// Ke × 2^exposure as `emissiveFactor` × `KHR_materials_emissive_strength`
/// (glTF caps the factor at 1), so a viewer shows Kd ρ y + Ke ρ_e 2^E.
#[test]
fn a_batch_with_an_emission_slot_exports_an_emissive_texture() {
    use solution::format::{Texture, TextureSlot, TexturedVertex, Texturing};
    let mut solution = solution(UpAxis::PosY);
    solution.batches.truncate(1);
    solution.batches[0].coefficients.fill(0.0);
    solution.batches[0].texturing = Some(Texturing {
        texture: 0,
        factor: [0.5, 1.0, 0.25],
        emission: Some(TextureSlot {
            texture: 1,
            factor: [3.0, 0.5, 1.5],
        }),
        vertices: vec![
            TexturedVertex {
                uv: [0.5, 0.5],
                irradiance_over_pi: [1.0; 3],
            };
            4
        ],
    });
    let texture = |b: u8| Texture {
        width: 1,
        height: 1,
        rgba: vec![b, b, b, 255],
    };
    solution.textures = vec![texture(200), texture(90)];
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("two.sol");
    write_solution(&path, &solution).unwrap();
    let file = MappedSolution::open(&path).unwrap();
    assert_eq!(file.version(), (3, 0));
    let options = ExportOptions {
        exposure_stops: -1.0,
        ..Default::default()
    };
    let mut exporter =
        Exporter::new(file.header(), file.batches(), file.textures(), options).unwrap();
    let bytes = BatchBytes {
        vertices: file.vertex_bytes(0),
        coefficients: file.coefficient_bytes(0),
        indices: file.index_bytes(0),
        textured_vertices: file.textured_vertex_bytes(0),
    };
    // No untextured term: the emission is in the second slot, not the SH.
    assert!(!exporter
        .add_batch(0, &file.batches()[0], bytes, |_| {})
        .unwrap());
    for k in 0..2 {
        exporter.add_texture(k, file.texture_bytes(k)).unwrap();
    }
    let exported = exporter.finish(None).unwrap();
    let (document, _) = read_back(&glb(&exported));
    let material = document
        .meshes()
        .next()
        .unwrap()
        .primitives()
        .next()
        .unwrap()
        .material();
    assert!(material.extension_value("KHR_materials_unlit").is_some());
    let pbr = material.pbr_metallic_roughness();
    assert_eq!(pbr.base_color_factor(), [0.5, 1.0, 0.25, 1.0]);
    assert_eq!(pbr.base_color_texture().unwrap().texture().index(), 0);
    assert_eq!(material.emissive_texture().unwrap().texture().index(), 1);
    // Ke × 2⁻¹ = (1.5, 0.25, 0.75): factor (1, 1/6, 1/2), strength 1.5; their
    // product is Ke × 2^E to f32 rounding.
    let strength = material.emissive_strength().unwrap();
    assert_eq!(strength, 1.5);
    for (f, ke) in material
        .emissive_factor()
        .into_iter()
        .zip([3.0f32, 0.5, 1.5])
    {
        assert!((f * strength - ke * 0.5).abs() <= 1e-6, "{f} × {strength}");
    }
}
