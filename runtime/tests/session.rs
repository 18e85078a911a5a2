//! The mock session drives the frame loop along a scripted walk, with the
//! validation layer on.

mod common;

use glam::DVec3;
use runtime::render::{RendererDesc, StereoRenderer};
use runtime::session::{run_frame, HeadPath, MockDesc, MockSession, Session};

#[test]
fn mock_session_walks_a_scripted_path_with_zero_validation_messages() {
    let gpu = common::gpu();
    // The room in file coordinates; the scene was re-centred by `offset` and is
    // in centimetres (units_per_metre = 100), so the walk file (scene
    // coordinates) and the IPD (metres) both need converting.
    let offset = DVec3::new(1000.0, 0.0, -500.0);
    let mut solution = common::glossy_room(6, 4);
    solution.header.units_per_metre = 100.0;
    solution.header.recentre_offset = offset.to_array();
    // Scale the room up 100× to centimetres.
    for batch in &mut solution.batches {
        for v in &mut batch.vertices {
            v.position = v.position.map(|x| x * 100.0);
        }
    }
    solution.header.bounds_min = common::ROOM_MIN.map(|x| x * 100.0);
    solution.header.bounds_max = common::ROOM_MAX.map(|x| x * 100.0);
    let walk = format!(
        "# t x y z yaw pitch\n0 {} 150 {} 0 0\n0.1 {} 150 {} 20 -10\n0.2 {} 120 {} 40 -20\n",
        1000.0, -200.0, 1050.0, -350.0, 1100.0, -450.0
    );
    let path = HeadPath::parse(&walk, "walk.txt").unwrap();
    let frames = 12;
    let (w, h) = (48, 40);
    let mut session = MockSession::new(
        &gpu,
        MockDesc {
            width: w,
            height: h,
            images: 3,
            path: path.clone(),
            ipd_m: 0.064,
            units_per_metre: 100.0,
            up_axis: solution.header.up_axis,
            recentre_offset: offset,
            fov_y_deg: 80.0,
            frame_rate: 60.0,
            frames: Some(frames),
        },
    )
    .unwrap();
    let desc = RendererDesc {
        width: w,
        height: h,
        ..RendererDesc::default()
    };
    let mut renderer = StereoRenderer::new(&gpu, &solution, desc, &session.swapchain()).unwrap();
    let mut images = Vec::new();
    while !session.should_exit() {
        let report = run_frame(&mut session, &mut renderer).unwrap();
        images.push(report.image.unwrap());
        // The head is where the path says at the frame's time, in file
        // coordinates; the eyes are 6.4 cm apart along the head's right vector.
        let head = path.sample(report.timing.predicted_display_time);
        let [l, r] = [report.views[0], report.views[1]];
        let mid = 0.5 * (l.pose.position + r.pose.position);
        assert!((mid - (head.position - offset)).length() < 1e-9);
        assert!(((r.pose.position - l.pose.position).length() - 6.4).abs() < 1e-9);
        let right = l.pose.orientation * DVec3::X;
        assert!((r.pose.position - l.pose.position).normalize().dot(right) > 1.0 - 1e-12);
    }
    assert_eq!(session.frames_done(), frames);
    // Swapchain images are used round-robin.
    assert_eq!(&images[..4], &[0, 1, 2, 0]);
    // The last frame shows the room in both eyes (the head is inside it).
    let last = session.last_image.unwrap();
    let eyes = renderer.read_back(&gpu, last, 2).unwrap();
    for eye in &eyes {
        let lit = eye.radiance.chunks_exact(3).filter(|p| p[0] > 0.1).count();
        assert!(lit > (w * h / 2) as usize, "only {lit} lit pixels");
    }
    common::assert_validation_clean(&gpu);
    // Teardown (renderer, session images, device, instance) is clean too: the
    // layer reports leaked or in-use objects when the device is destroyed.
    let log = gpu.validation_log_handle();
    drop(renderer);
    drop(session);
    drop(gpu);
    assert_eq!(log.count(), 0, "{}", log.messages().join("\n"));
}
