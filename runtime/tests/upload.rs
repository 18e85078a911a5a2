//! The mapped upload (`GpuScene::from_mapped`): sections copied as stored in
//! bounded chunks, each section's CRC-32 checked as its chunks pass.

mod common;

use glam::DVec3;
use runtime::render::{
    CoefficientStorage, GpuScene, MultiviewMode, RendererDesc, SceneError, StereoRenderer,
};
use runtime::session::OffscreenSwapchain;
use solution::format::{MappedSolution, ScalarType};

/// Offset in `bytes` of the first occurrence of `needle`.
fn find(bytes: &[u8], needle: &[u8]) -> usize {
    bytes
        .windows(needle.len())
        .position(|w| w == needle)
        .expect("section bytes not found in the file")
}

#[test]
fn a_flipped_coefficient_byte_is_refused_while_streaming() {
    let (dir, clean) = common::mapped(&common::glossy_room(6, 4));
    let path = clean.path().to_path_buf();
    // Batch 1 is the L = 4 floor; flip the low mantissa byte of its 10th
    // coefficient: still a finite f32, so only the checksum can tell.
    let section = clean.coefficient_bytes(1);
    let at = find(&std::fs::read(&path).unwrap(), &section[..64]) + 36;
    drop(clean);
    let mut bytes = std::fs::read(&path).unwrap();
    bytes[at] ^= 0x01;
    std::fs::write(&path, &bytes).unwrap();

    let whole = MappedSolution::open(&path).unwrap_err().to_string();
    let file = MappedSolution::open_deferring_checksums(&path)
        .expect("every check but the section checksums passes");
    let gpu = common::gpu();
    let error = match GpuScene::from_mapped(&gpu, &file, None) {
        Err(SceneError::File(e)) => e.to_string(),
        Err(e) => panic!("refused for another reason: {e}"),
        Ok(_) => panic!("a corrupted coefficient section was uploaded"),
    };
    // The same words as the whole-file check: the file, the section and its
    // batch, both CRCs.
    assert_eq!(error, whole);
    for part in ["scene.sol", "coefficients of batch 1", "CRC-32"] {
        assert!(error.contains(part), "{error:?} lacks {part:?}");
    }
    drop(dir);
}

/// A staging buffer of a few KiB splits every section across submits (vertex
/// and index sections mid-element, coefficient sections between vertices): the
/// image must still match the CPU reference, which it can only if every byte
/// reached its place. Tolerances: those of runtime/tests/reference.rs (same
/// room, no MSAA).
#[test]
fn tiny_staging_chunks_give_the_reference_image() {
    let solution = common::glossy_room(12, 6);
    for storage in [CoefficientStorage::F32, CoefficientStorage::F16] {
        let (_dir, file) = common::mapped(&common::stored_as(&solution, storage));
        let gpu = common::gpu();
        // 4000 bytes: a multiple of neither 36 (vertex) nor 4·49·3 = 588 (an
        // L = 6 f32 vertex's coefficients).
        let (scene, stats) = GpuScene::from_mapped_in_chunks(&gpu, &file, None, 4000).unwrap();
        assert!(stats.submits > 10, "{stats:?}");
        let camera = common::room_camera(96, 80);
        let views = camera.stereo_views(0.3, DVec3::ZERO);
        let swapchain = OffscreenSwapchain::new(&gpu, 96, 80, 1).unwrap();
        let desc = RendererDesc {
            width: 96,
            height: 80,
            max_samples: 1,
            multiview: MultiviewMode::Auto,
            ..RendererDesc::default()
        };
        let mut renderer =
            StereoRenderer::from_scene(&gpu, scene, file.header(), desc, &swapchain.desc())
                .unwrap();
        renderer.render(&views, 0).unwrap();
        let eyes = renderer.read_back(&gpu, 0, 2).unwrap();
        for (eye, (view, label)) in eyes.iter().zip(views.iter().zip(["left", "right"])) {
            common::assert_matches_cpu_reference(
                &format!("chunked-{storage:?}-{label}"),
                &solution,
                view,
                eye,
                common::Tolerances {
                    mean: 2e-3,
                    p99: 5e-3,
                    fraction: 0.01,
                },
            );
        }
        common::assert_validation_clean(&gpu);
    }
}

#[test]
fn a_file_mixing_f32_and_f16_batches_is_refused_by_name() {
    let mut solution = common::glossy_room(4, 2);
    solution.batches[1].scalar = ScalarType::F16 {
        scale: solution::format::f16_scale_for(&solution.batches[1].coefficients),
    };
    let (_dir, file) = common::mapped(&solution);
    let gpu = common::gpu();
    match GpuScene::from_mapped(&gpu, &file, None) {
        Err(e @ SceneError::MixedStorage { .. }) => {
            let text = e.to_string();
            assert!(
                text.contains("batch 1") && text.contains("batch 0"),
                "{text}"
            );
        }
        Err(e) => panic!("refused for another reason: {e}"),
        Ok(_) => panic!("a mixed file was uploaded"),
    }
}
