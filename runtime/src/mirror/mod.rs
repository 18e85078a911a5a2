//! `runtime mirror`: a desktop window showing both eyes of a solution side by
//! side (or one eye, or a red–cyan anaglyph), driven by radview's controls
//! (Remington 1992, app. C) when no XR session runs.
//!
//! * [`controls`]: input events → camera and display state (pure, unit-tested).
//! * [`present`]: the window's surface, swapchain and composite pass.
//! * [`font`]: the 5×7 bitmap font of the help and frame-time overlay.
//! * [`script`]: `--script`, synthetic input per frame for tests.
//! * [`watch`]: `--watch`, reloading the file each time the solver rewrites it.
//! * [`stats`]: frame-time figures.
//!
//! Each frame: acquire a window image (never waiting, unless `--vsync`), apply
//! the frame's input, render both eyes with the stereo renderer into the
//! mirror's own images, copy them into the window image with the overlay, and
//! present. `--frames N` stops after N presented frames and prints the median
//! and p99 frame time (the interval between successive presented frames).

pub mod controls;
pub mod font;
mod frame;
pub mod present;
pub mod script;
pub mod stats;
pub mod watch;

use crate::cli::{open_solution, parse_size, report_truncation_mapped, RenderOptions};
use crate::gpu::{Gpu, GpuDesc};
use crate::render::{Inspect, StereoRenderer};
use anyhow::{Context, Result};
use controls::{Controls, Display, Input, Key, SceneFrame, Wireframe};
use frame::Step;
use glam::DVec3;
use present::Presenter;
use solution::camera::Camera;
use solution::format::MappedSolution;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, KeyEvent, MouseButton, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{Key as WinitKey, NamedKey};
use winit::window::{Window, WindowId};

/// The exit status of `runtime mirror` when no window can be opened (no
/// display, or a display without Vulkan presentation): `scripts/main-job.sh`
/// then writes screenshots instead.
pub const NO_DISPLAY_EXIT_CODE: i32 = 3;

/// No window could be opened.
#[derive(Debug, thiserror::Error)]
#[error("cannot open a window: {0}")]
pub struct NoDisplay(pub String);

/// The time step of held walking keys under `--script` (a headset's 90 Hz), so
/// scripted runs move the same on every machine.
pub const SCRIPT_DT: f64 = 1.0 / 90.0;

#[derive(clap::Args, Debug, Clone)]
pub struct MirrorArgs {
    /// The solution file.
    pub solution: PathBuf,
    /// Stop after N presented frames and print the median and p99 frame time.
    #[arg(long, value_name = "N")]
    pub frames: Option<u64>,
    /// Reload the file each time it is rewritten (e.g. by a running `solver
    /// solve`), keeping the view; a file that fails to load is reported and
    /// the previous solution stays.
    #[arg(long)]
    pub watch: bool,
    /// Initial eye position, scene coordinates (default: the header's camera).
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true)]
    pub eye: Option<Vec<f64>>,
    /// Initial reference point (looked at), scene coordinates.
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true)]
    pub target: Option<Vec<f64>>,
    /// Up direction of the camera (default: the header's camera).
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true)]
    pub up: Option<Vec<f64>>,
    /// Vertical field of view, degrees (default: the header's camera).
    #[arg(long, value_name = "DEG")]
    pub fov_y: Option<f64>,
    /// Window size, WIDTHxHEIGHT (side by side, each eye gets half the width).
    #[arg(long, value_name = "WxH", value_parser = parse_size, default_value = "1024x512")]
    pub size: (u32, u32),
    /// Interpupillary distance in metres (scaled by the header's units_per_metre).
    #[arg(long, value_name = "METRES", default_value_t = 0.064)]
    pub ipd: f64,
    /// How the eyes are shown (keys 1-4 switch).
    #[arg(long, value_enum, default_value_t = Display::SideBySide)]
    pub display: Display,
    /// Wait for the display's refresh (FIFO); without it the window presents
    /// with MAILBOX or IMMEDIATE and never makes a frame wait.
    #[arg(long)]
    pub vsync: bool,
    /// Start with the wireframe over the shading (key m cycles; Remington 1992, app. D, -w).
    #[arg(long)]
    pub wireframe: bool,
    /// Start with vertex normals drawn (key n; Remington 1992, app. D, -n).
    #[arg(long)]
    pub normals: bool,
    /// F12 writes PREFIX-NNN-left/-right .png and .exr.
    #[arg(long, value_name = "PREFIX", default_value = "mirror")]
    pub screenshot_prefix: PathBuf,
    /// Synthetic input per frame (see `runtime/src/mirror/script.rs`).
    #[arg(long, value_name = "FILE", hide = true)]
    pub script: Option<PathBuf>,
    /// Write the window's last image (as shown) to this PNG at exit.
    #[arg(long, value_name = "PNG", hide = true)]
    pub dump_last_frame: Option<PathBuf>,
    /// With --watch: exit after this many reloads.
    #[arg(long, value_name = "N", hide = true)]
    pub quit_after_reloads: Option<u64>,
    #[command(flatten)]
    pub render: RenderOptions,
}

fn vec3(v: &Option<Vec<f64>>, default: [f64; 3]) -> [f64; 3] {
    match v {
        Some(v) if v.len() == 3 => [v[0], v[1], v[2]],
        _ => default,
    }
}

fn scene_frame(file: &MappedSolution) -> SceneFrame {
    let h = file.header();
    let lo = DVec3::from(h.bounds_min.map(f64::from));
    let hi = DVec3::from(h.bounds_max.map(f64::from));
    let diagonal = (hi - lo).length();
    SceneFrame {
        up_axis: h.up_axis,
        units_per_metre: h.units_per_metre,
        diagonal: if diagonal > 0.0 && diagonal.is_finite() {
            diagonal
        } else {
            1.0
        },
    }
}

/// Runs `runtime mirror`.
pub fn run(args: &MirrorArgs) -> Result<()> {
    args.render.check()?;
    if !(args.ipd.is_finite() && args.ipd >= 0.0) {
        anyhow::bail!(
            "--ipd {} must be a finite, non-negative distance in metres",
            args.ipd
        );
    }
    if args.frames == Some(0) {
        anyhow::bail!("--frames must be at least 1");
    }
    // The file's version is noted before it is read, so a rewrite while it is
    // being read is seen as a new version by --watch.
    let watch = args.watch.then(|| watch::Watch::new(&args.solution));
    // Mapped, not read: the upload streams it as stored. It stays mapped
    // while it is drawn, for the renderer made on the first frame and for the
    // edge lists of the wireframe (which read its index sections only).
    let solution = open_solution(&args.solution, args.render.max_frame_cost)?;
    report_truncation_mapped(&solution, args.render.max_order);
    let header = solution.header();
    let camera = Camera {
        eye: vec3(&args.eye, header.camera.eye),
        target: vec3(&args.target, header.camera.target),
        up: vec3(&args.up, header.camera.up),
        fov_y_deg: args.fov_y.unwrap_or(header.camera.fov_y_deg),
        width: args.size.0,
        height: args.size.1,
    };
    camera.validate().context("invalid camera")?;
    let script = match &args.script {
        Some(path) => Some(script::Script::load(path)?),
        None => None,
    };
    let mut controls = Controls::new(camera, scene_frame(&solution));
    controls.view.display = args.display;
    controls.view.wireframe = if args.wireframe {
        Wireframe::Overlay
    } else {
        Wireframe::Off
    };
    controls.view.normals = args.normals;
    controls.view.exposure_stops = args.render.exposure;

    // winit reports a missing display when the event loop is made (and may
    // panic when a windowing library it loads at run time is missing).
    let event_loop = std::panic::catch_unwind(EventLoop::new)
        .map_err(|_| NoDisplay("the windowing system failed to start (see above)".into()))?
        .map_err(|e| NoDisplay(e.to_string()))?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let mut app = App {
        args: args.clone(),
        solution,
        controls,
        script,
        watch,
        state: None,
        error: None,
        validation: None,
    };
    let ran = event_loop.run_app(&mut app);
    // Tear the window and the GPU down before counting validation messages:
    // destruction is where leaks are reported.
    let state = app.state.take();
    let summary = state.as_ref().map(|s| s.summary(&app.controls));
    drop(state);
    if let Some(e) = app.error.take() {
        return Err(e);
    }
    ran.context("the window's event loop failed")?;
    if let Some(summary) = summary {
        print!("{summary}");
    }
    if let Some(log) = &app.validation {
        anyhow::ensure!(
            log.count() == 0,
            "{} Vulkan validation messages (printed above)",
            log.count()
        );
    }
    Ok(())
}

struct App {
    args: MirrorArgs,
    solution: MappedSolution,
    controls: Controls,
    script: Option<script::Script>,
    watch: Option<watch::Watch>,
    state: Option<Running>,
    error: Option<anyhow::Error>,
    validation: Option<Arc<crate::gpu::ValidationLog>>,
}

/// The window and everything drawn into it. Fields drop in order: the
/// renderer and presenter (which free command buffers of the GPU's pool)
/// before the GPU, and the window last.
struct Running {
    renderer: Option<StereoRenderer>,
    presenter: Presenter,
    gpu: Gpu,
    window: Arc<Window>,
    watch: Option<watch::Watch>,
    /// Window events since the last frame.
    pending: Vec<Input>,
    cursor: Option<(f64, f64)>,
    /// Frames drawn (the script's frame counter) and presented.
    frame: u64,
    presented: u64,
    times: stats::FrameTimes,
    /// Per presented frame: the stereo render (submit and wait), and the
    /// window's own work (slot wait, acquire, composite submit, present).
    render_ms: stats::FrameTimes,
    window_ms: stats::FrameTimes,
    last_present: Option<Instant>,
    last_update: Instant,
    hud: String,
    title_at: Instant,
    screenshots: u32,
    reloads: u64,
    exiting: bool,
    renderer_inspect: Inspect,
}

impl Running {
    fn summary(&self, controls: &Controls) -> String {
        let (n, median, p99) = self.times.summary();
        let (_, render, _) = self.render_ms.summary();
        let (_, window, _) = self.window_ms.summary();
        let c = controls.camera(1, 1);
        let size = self.presenter.extent().unwrap_or((0, 0));
        format!(
            "frames: {} presented, median {:.3} ms, p99 {:.3} ms per frame ({} intervals; {}x{} window, \
             {:?} present mode, {})\nframe parts (medians): stereo render {:.3} ms (submit to \
             fence; the queue runs the previous frame's copy or composite first), window CPU side \
             (slot wait, acquire, copy or composite submit, present) {:.3} ms\n\
             camera: eye {:?} {:?} {:?} target {:?} {:?} {:?}\n",
            self.presented,
            median,
            p99,
            n,
            size.0,
            size.1,
            self.presenter.present_mode(),
            self.gpu.info.describe(),
            render,
            window,
            c.eye[0],
            c.eye[1],
            c.eye[2],
            c.target[0],
            c.target[1],
            c.target[2],
        )
    }
}

fn translate_key(event: &KeyEvent) -> Option<Key> {
    match &event.logical_key {
        WinitKey::Named(named) => Some(match named {
            NamedKey::ArrowLeft => Key::Left,
            NamedKey::ArrowRight => Key::Right,
            NamedKey::ArrowUp => Key::Up,
            NamedKey::ArrowDown => Key::Down,
            NamedKey::Tab => Key::Tab,
            NamedKey::Shift => Key::Shift,
            NamedKey::F1 => Key::F1,
            NamedKey::F2 => Key::F2,
            NamedKey::F3 => Key::F3,
            NamedKey::F12 => Key::F12,
            NamedKey::Escape => Key::Escape,
            _ => return None,
        }),
        WinitKey::Character(text) => {
            let mut chars = text.chars();
            match (chars.next(), chars.next()) {
                (Some(c), None) if c.is_ascii_graphic() => Some(Key::Char(c.to_ascii_lowercase())),
                _ => None,
            }
        }
        _ => None,
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.state.is_some() || self.error.is_some() {
            return;
        }
        match self.start(event_loop) {
            Ok(state) => self.state = Some(state),
            Err(e) => {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, _: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let scripted = self.script.is_some();
        let Some(state) = self.state.as_mut() else {
            return;
        };
        match event {
            // The next frame is the last (and is dumped if asked).
            WindowEvent::CloseRequested => state.exiting = true,
            WindowEvent::Resized(_) => state.presenter.resized(),
            // A scripted run ignores the real keyboard and mouse, so a stray
            // event cannot change what a test sees.
            _ if scripted => {}
            WindowEvent::KeyboardInput { event, .. } => {
                if let Some(key) = translate_key(&event) {
                    state.pending.push(match event.state {
                        ElementState::Pressed => Input::KeyDown {
                            key,
                            repeat: event.repeat,
                        },
                        ElementState::Released => Input::KeyUp(key),
                    });
                }
            }
            WindowEvent::MouseInput {
                state: pressed,
                button: MouseButton::Left,
                ..
            } => state.pending.push(match pressed {
                ElementState::Pressed => Input::ButtonDown,
                ElementState::Released => Input::ButtonUp,
            }),
            WindowEvent::CursorMoved { position, .. } => {
                if let Some((x, y)) = state.cursor {
                    state.pending.push(Input::PointerMoved {
                        dx: position.x - x,
                        dy: position.y - y,
                    });
                }
                state.cursor = Some((position.x, position.y));
            }
            WindowEvent::CursorLeft { .. } => state.cursor = None,
            WindowEvent::Focused(false) => state.pending.push(Input::FocusLost),
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if self.state.is_none() || self.error.is_some() {
            return;
        }
        match self.frame() {
            Ok(Step::Presented) => event_loop.set_control_flow(ControlFlow::Poll),
            // Nothing to present into (minimised, or every window image is
            // with the display): look again shortly instead of spinning.
            Ok(Step::Skipped) => event_loop.set_control_flow(ControlFlow::wait_duration(
                std::time::Duration::from_millis(2),
            )),
            Ok(Step::Done) => event_loop.exit(),
            Err(e) => {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }
}

impl App {
    fn start(&mut self, event_loop: &ActiveEventLoop) -> Result<Running> {
        let (w, h) = self.args.size;
        let title = format!("runtime mirror: {}", self.args.solution.display());
        let attributes = Window::default_attributes()
            .with_title(title)
            .with_inner_size(winit::dpi::PhysicalSize::new(w, h));
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .map_err(|e| NoDisplay(e.to_string()))?,
        );
        let extensions =
            present::required_extensions(&window).map_err(|e| NoDisplay(format!("{e:#}")))?;
        let gpu = Gpu::with_extensions(
            &GpuDesc {
                validation: self.args.render.validation,
            },
            &extensions,
        )
        .context("cannot start Vulkan for the window")?;
        self.validation = Some(gpu.validation_log_handle());
        let presenter = Presenter::new(&gpu, window.clone(), self.args.vsync)
            .map_err(|e| NoDisplay(format!("{e:#}")))?;
        let now = Instant::now();
        Ok(Running {
            renderer: None,
            presenter,
            gpu,
            window,
            watch: self.watch.take(),
            pending: Vec::new(),
            cursor: None,
            frame: 0,
            presented: 0,
            times: stats::FrameTimes::default(),
            render_ms: stats::FrameTimes::default(),
            window_ms: stats::FrameTimes::default(),
            last_present: None,
            last_update: now,
            hud: String::new(),
            title_at: now,
            screenshots: 0,
            reloads: 0,
            exiting: false,
            renderer_inspect: Inspect::default(),
        })
    }
}
