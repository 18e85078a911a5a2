//! End to end through the file system: the solver's writer, the runtime's mapped
//! reader, and what a hostile file can make the reader allocate.
//!
//! This test binary installs a global allocator that records, per thread, the
//! largest single allocation, so the hostile-header test can show that a file
//! claiming 2^40 vertices makes the reader allocate nothing of that size.

use solution::camera::{Camera, UpAxis};
use solution::format::layout::{self, batch as bf, header as hf, preamble as pf};
use solution::format::{
    check_frame_cost, decode, encode, f16_scale_for, frame_cost, read_solution, write_solution,
    Batch, FormatError, Header, MappedSolution, Problem, Representation, ScalarType, Solution,
    SolveMode, SolveStats, Vertex, DEFAULT_MAX_FRAME_COST, MAX_FRAME_COST_FLAG, MAX_SH_ORDER,
};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::path::PathBuf;

struct Tracking;

thread_local! {
    // `const` initialisation: reading it never allocates, so the allocator may
    // use it.
    static LARGEST: Cell<usize> = const { Cell::new(0) };
}

fn note(size: usize) {
    // `try_with` fails only while the thread is being torn down.
    let _ = LARGEST.try_with(|largest| largest.set(largest.get().max(size)));
}

// SAFETY: every method forwards to `System` with the arguments it received, so
// `Tracking` upholds `GlobalAlloc`'s contract exactly as `System` does; `note`
// does not allocate.
unsafe impl GlobalAlloc for Tracking {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        // SAFETY: forwarded unchanged (see the impl's comment).
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        // SAFETY: forwarded unchanged.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note(new_size);
        // SAFETY: forwarded unchanged.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded unchanged.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Tracking = Tracking;

/// The largest single allocation `f` makes on this thread.
fn largest_allocation<T>(f: impl FnOnce() -> T) -> (T, usize) {
    LARGEST.with(|l| l.set(0));
    let out = f();
    (out, LARGEST.with(|l| l.get()))
}

#[test]
fn the_tracker_sees_allocations() {
    // Without this, the bounds below could pass because nothing was recorded.
    let (v, largest) = largest_allocation(|| vec![7u8; 123_457]);
    assert_eq!(v.len(), 123_457);
    assert!(largest >= 123_457);
}

fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("solution_file");
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(format!("{}-{name}", std::process::id()))
}

/// A floor of `n × n` quads (diffuse, f32) and the same floor lifted by one unit
/// as a glossy L = 3 batch stored in f16.
fn grid_solution(n: u32) -> Solution {
    let mut vertices = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            vertices.push(Vertex {
                position: [i as f32, 0.0, j as f32],
                normal: [0.0, 1.0, 0.0],
                tangent: [1.0, 0.0, 0.0],
            });
        }
    }
    let mut indices = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let v = j * (n + 1) + i;
            indices.extend([v, v + n + 1, v + 1, v + 1, v + n + 1, v + n + 2]);
        }
    }
    let diffuse_coefficients: Vec<f32> = (0..vertices.len() * 3)
        .map(|k| (k % 97) as f32 * 0.37)
        .collect();
    let glossy_coefficients: Vec<f32> = (0..vertices.len() * 16 * 3)
        .map(|k| ((k % 31) as f32 - 15.0) * 11.3)
        .collect();
    let lifted: Vec<Vertex> = vertices
        .iter()
        .map(|v| Vertex {
            position: [v.position[0], 1.0, v.position[2]],
            ..*v
        })
        .collect();
    Solution {
        lighting: None,
        header: Header {
            units_per_metre: 1.0,
            up_axis: UpAxis::PosY,
            recentre_offset: [1e6, 0.0, -1e6],
            camera: Camera {
                eye: [1e6, 2.0, -1e6 - 5.0],
                target: [1e6, 0.0, -1e6],
                up: [0.0, 1.0, 0.0],
                fov_y_deg: 60.0,
                width: 800,
                height: 600,
            },
            bounds_min: [0.0, 0.0, 0.0],
            bounds_max: [n as f32, 1.0, n as f32],
            partial: false,
            mode: SolveMode::Directional,
            stats: SolveStats::default(),
            settings_json: "{}".into(),
        },
        batches: vec![
            Batch {
                representation: Representation::Sh { order: 0 },
                scalar: ScalarType::F32,
                vertices,
                coefficients: diffuse_coefficients,
                indices: indices.clone(),
                texturing: None,
            },
            Batch {
                representation: Representation::Sh { order: 3 },
                scalar: ScalarType::F16 {
                    scale: f16_scale_for(&glossy_coefficients),
                },
                vertices: lifted,
                coefficients: glossy_coefficients,
                indices,
                texturing: None,
            },
        ],
        textures: Vec::new(),
    }
}

#[test]
fn written_file_maps_back_to_the_same_solution() {
    let original = grid_solution(40);
    let path = scratch("grid.sol");
    write_solution(&path, &original).unwrap();
    let mapped = MappedSolution::open(&path).unwrap();
    let back = mapped.to_solution().unwrap();
    assert_eq!(back.header, original.header);
    // The f32 batch is bit-exact.
    assert_eq!(back.batches[0], original.batches[0]);
    let (b, o) = (&back.batches[1], &original.batches[1]);
    assert_eq!((&b.vertices, &b.indices), (&o.vertices, &o.indices));
    let ScalarType::F16 { scale } = o.scalar else {
        unreachable!()
    };
    // f16 with a power-of-two scale: only the rounding to half, 2^-11 relative
    // (normal halves) or 2^-25 × scale absolute (subnormal), as documented.
    for (x, y) in b.coefficients.iter().zip(&o.coefficients) {
        assert!((x - y).abs() <= 2f32.powi(-11) * y.abs() + 2f32.powi(-25) * scale);
    }
    // The bytes the runtime uploads are the documented little-endian layouts.
    let v0 = &mapped.vertex_bytes(1)[..36];
    assert_eq!(&v0[4..8], &1.0f32.to_le_bytes());
    let h = u16::from_le_bytes([
        mapped.coefficient_bytes(1)[0],
        mapped.coefficient_bytes(1)[1],
    ]);
    assert_eq!(half_to_f32(h) * scale, b.coefficients[0]);
    assert_eq!(read_solution(&path).unwrap(), back);
    std::fs::remove_file(&path).unwrap();
}

/// IEEE half to f32 without the `half` crate (the root package does not depend on
/// it), for normal and subnormal halves.
fn half_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exponent = ((h >> 10) & 0x1F) as i32;
    let mantissa = (h & 0x3FF) as f32;
    sign * if exponent == 0 {
        mantissa * 2f32.powi(-24)
    } else {
        (1.0 + mantissa / 1024.0) * 2f32.powi(exponent - 15)
    }
}

fn fix_metadata_crc(bytes: &mut [u8]) {
    let len = u64::from_le_bytes(bytes[pf::METADATA_LENGTH..][..8].try_into().unwrap());
    let crc = layout::metadata_crc(&bytes[..len as usize]);
    bytes[pf::METADATA_CRC..][..4].copy_from_slice(&crc.to_le_bytes());
}

#[test]
fn hostile_counts_allocate_nothing_near_their_size() {
    let bytes = encode(&grid_solution(3)).unwrap();
    let batch0 = layout::PREAMBLE_LEN + layout::HEADER_LEN;
    let batch1 = batch0 + layout::BATCH_ENTRY_LEN;
    let patches: [(usize, u64, &[u8]); 4] = [
        (
            batch0 + bf::VERTEX_COUNT,
            1 << 40,
            &(1u64 << 40).to_le_bytes(),
        ),
        (
            batch1 + bf::INDEX_COUNT,
            (1 << 40) + 2,
            &((1u64 << 40) + 2).to_le_bytes(),
        ),
        // Within the u32 limits, so only the section-length check stops it.
        (
            batch1 + bf::VERTEX_COUNT,
            u32::MAX.into(),
            &u64::from(u32::MAX).to_le_bytes(),
        ),
        (pf::BATCH_COUNT, u32::MAX.into(), &u32::MAX.to_le_bytes()),
    ];
    for (at, claimed, value) in patches {
        let mut bad = bytes.clone();
        bad[at..at + value.len()].copy_from_slice(value);
        fix_metadata_crc(&mut bad);
        let (result, largest) = largest_allocation(|| decode(&bad));
        let err = result.expect_err("hostile count accepted");
        assert!(err.problem().is_some(), "{err}");
        // The reader's allocations are bounded by the file's length (see
        // solution/src/format/read.rs); a reader trusting the count would ask for
        // at least `claimed` bytes.
        assert!(
            largest <= bad.len(),
            "count {claimed}: largest allocation {largest} B exceeds the {} B file",
            bad.len()
        );

        // Through the file system the map is not a heap allocation either.
        let path = scratch("hostile.sol");
        std::fs::write(&path, &bad).unwrap();
        let (result, largest) = largest_allocation(|| MappedSolution::open(&path));
        let err = result.expect_err("hostile count accepted from disk");
        assert_eq!(err.path(), Some(path.as_path()));
        assert!(largest <= bad.len(), "mapped: {largest} B");
        std::fs::remove_file(&path).unwrap();
    }
}

/// Values the contract refuses although every count and checksum is right: an SH
/// order above [`MAX_SH_ORDER`], a header camera that `Camera::validate` refuses,
/// bounds that leave a vertex out. Each is refused with a message naming the
/// value, from memory and from disk, allocating no more than the file's size.
#[test]
fn hostile_values_are_refused_clearly_allocating_nothing_beyond_the_file() {
    let bytes = encode(&grid_solution(3)).unwrap();
    let header = layout::PREAMBLE_LEN;
    let batch1 = header + layout::HEADER_LEN + layout::BATCH_ENTRY_LEN;
    let cases: [(&str, usize, Vec<u8>, &str); 4] = [
        (
            "SH order above the limit",
            batch1 + bf::REPRESENTATION_PARAMETER,
            (MAX_SH_ORDER + 1).to_le_bytes().to_vec(),
            "batch 1: SH order is 65, above the limit of 64",
        ),
        (
            "camera field of view",
            header + hf::CAMERA_FOV_Y_DEG,
            179.5f64.to_le_bytes().to_vec(),
            "header: camera",
        ),
        (
            "camera image size",
            header + hf::CAMERA_WIDTH,
            100_000u32.to_le_bytes().to_vec(),
            "header: camera",
        ),
        (
            // The grid reaches x = 3; these bounds stop at x = 2.
            "bounds that exclude vertices",
            header + hf::BOUNDS_MAX,
            2f32.to_le_bytes().to_vec(),
            "batch 0: vertex 3 position [3.0, 0.0, 0.0] lies outside the header bounds",
        ),
    ];
    for (name, at, value, message) in cases {
        let mut bad = bytes.clone();
        bad[at..at + value.len()].copy_from_slice(&value);
        fix_metadata_crc(&mut bad);
        let (result, largest) = largest_allocation(|| decode(&bad));
        let err = result.expect_err(name).to_string();
        assert!(err.contains(message), "{name}: {err}");
        assert!(
            largest <= bad.len(),
            "{name}: largest allocation {largest} B"
        );

        let path = scratch("hostile-value.sol");
        std::fs::write(&path, &bad).unwrap();
        let (result, largest) = largest_allocation(|| MappedSolution::open(&path));
        let err = result.expect_err(name);
        assert_eq!(err.path(), Some(path.as_path()), "{name}");
        assert!(err.to_string().contains(message), "{name}: {err}");
        assert!(largest <= bad.len(), "{name}: mapped, {largest} B");
        std::fs::remove_file(&path).unwrap();
    }
}

/// The per-frame cost bound is the runtime's to apply (the reader opens the file
/// whatever its cost): below the default it passes; above a limit it is refused
/// naming the file, the cost, the limit and the override flag.
#[test]
fn frame_cost_above_the_limit_is_refused_without_the_override() {
    let path = scratch("frame-cost.sol");
    write_solution(&path, &grid_solution(3)).unwrap();
    let mapped = MappedSolution::open(&path).unwrap();
    // 16 vertices at L = 0 (1 term) and 16 at L = 3 (16 terms).
    let cost = frame_cost(mapped.batches());
    assert_eq!(cost, 16 + 16 * 16);
    check_frame_cost(&path, cost, DEFAULT_MAX_FRAME_COST).unwrap();
    let err = check_frame_cost(&path, cost, cost - 1).unwrap_err();
    let text = err.to_string();
    for part in [
        path.display().to_string(),
        format!("{cost} basis terms per view"),
        format!("limit of {}", cost - 1),
        MAX_FRAME_COST_FLAG.to_string(),
    ] {
        assert!(text.contains(&part), "{part:?} missing from: {text}");
    }
    assert!(matches!(err.problem(), Some(Problem::FrameCost { .. })));
    std::fs::remove_file(&path).unwrap();
}

#[test]
fn a_valid_decode_allocates_at_most_twice_the_file() {
    // f16 coefficients widen to f32: the one place decoded data outgrows the file.
    let solution = grid_solution(20);
    let bytes = encode(&solution).unwrap();
    let (result, largest) = largest_allocation(|| decode(&bytes));
    result.unwrap();
    assert!(
        largest <= 2 * bytes.len(),
        "{largest} B for a {} B file",
        bytes.len()
    );
}

#[test]
fn truncated_file_on_disk_is_refused_with_its_path() {
    let path = scratch("truncated.sol");
    write_solution(&path, &grid_solution(2)).unwrap();
    let full = std::fs::read(&path).unwrap();
    std::fs::write(&path, &full[..full.len() - 1]).unwrap();
    let err = MappedSolution::open(&path).unwrap_err();
    let message = err.to_string();
    assert!(matches!(err, FormatError::File { .. }), "{message}");
    assert!(
        matches!(err.problem(), Some(Problem::LengthMismatch { .. })),
        "{message}"
    );
    assert!(
        message.starts_with(&path.display().to_string()),
        "{message}"
    );
    std::fs::remove_file(&path).unwrap();
}
