//! One frame of the mirror window, step by step: reload a watched file, begin
//! the frame, apply the input, size the eyes and the renderer, draw the eyes
//! (and a screenshot), then the overlay, presentation, dump and statistics.

use super::controls::{self, Command, Controls, Display, ViewOptions, Wireframe};
use super::present::{self, Layout, Overlay};
use super::{font, scene_frame, script, stats, App, MirrorArgs, Running, SCRIPT_DT};
use crate::cli::{open_solution, write_exr, write_png};
use crate::gpu::Gpu;
use crate::render::{Edges, Inspect, RendererDesc, StereoRenderer};
use anyhow::{Context, Result};
use glam::DVec3;
use solution::camera::{Camera, EyeView};
use solution::format::MappedSolution;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What a pass of the frame loop did.
pub(super) enum Step {
    Presented,
    Skipped,
    /// The window should close.
    Done,
}

impl App {
    /// One frame.
    pub(super) fn frame(&mut self) -> Result<Step> {
        let Some(state) = self.state.as_mut() else {
            return Ok(Step::Done);
        };
        let dumping = self.args.dump_last_frame.is_some();
        // --watch: a new version of the file replaces the renderer's scene.
        state.poll_watch(&self.args, &mut self.controls, &mut self.solution);

        let window_start = Instant::now();
        let begun = state.presenter.begin_frame()?;
        let begin_ms = window_start.elapsed().as_secs_f64() * 1e3;
        let Some(frame) = begun else {
            // No window image free right now (or no window area): try again,
            // unless the window is closing.
            return Ok(if state.exiting {
                Step::Done
            } else {
                Step::Skipped
            });
        };
        let screenshot = state.apply_input(self.script.as_mut(), &mut self.controls);
        // Exiting (Esc, closing the window) presents this frame first, so the
        // swapchain image acquired above is given back and can be dumped.
        let last = state.exiting || self.args.frames.is_some_and(|n| state.presented + 1 >= n);

        // Eye images and renderer at the window's per-eye size.
        let (win_w, win_h) = state.presenter.extent().context("no swapchain")?;
        let view = self.controls.view;
        let (eye_w, eye_h) = match view.display {
            Display::SideBySide => ((win_w / 2).max(1), win_h),
            _ => (win_w, win_h),
        };
        state.prepare_renderer(&self.args, &self.solution, &view, (eye_w, eye_h))?;
        let renderer = state.renderer.as_mut().context("no renderer")?;

        // The eyes: both for a screenshot (always a pair) and for the stereo
        // layouts; one otherwise.
        let header = self.solution.header();
        let camera = self.controls.camera(eye_w, eye_h);
        camera.validate().context("the view has become invalid")?;
        let offset = DVec3::from(header.recentre_offset);
        let stereo = camera.stereo_views(self.args.ipd * header.units_per_metre, offset);
        let (views, layout) = eye_views(stereo, view.display, screenshot);
        let render_start = Instant::now();
        renderer.render(&views, frame.slot)?;
        state
            .render_ms
            .push(render_start.elapsed().as_secs_f64() * 1e3);
        if screenshot {
            state.screenshots += 1;
            let base = format!(
                "{}-{:03}",
                self.args.screenshot_prefix.display(),
                state.screenshots
            );
            write_screenshot(renderer, &state.gpu, frame.slot, &base, &camera)?;
        }

        let overlay = overlay(&view, &state.hud, (win_w, win_h));
        let dump = last && dumping;
        let finish_start = Instant::now();
        let image = state
            .presenter
            .finish_frame(&state.gpu, frame, layout, &overlay, dump)?;
        // A dump waits for the GPU and copies: not a normal frame's work.
        if !dump {
            let finish_ms = finish_start.elapsed().as_secs_f64() * 1e3;
            state.window_ms.push(begin_ms + finish_ms);
        }
        if let (Some(image), Some(path)) = (image, &self.args.dump_last_frame) {
            write_png(path, image.width, image.height, &image.rgba)?;
            println!("wrote {}", path.display());
        }
        if state.presented == 0 {
            state.report_first_frame(&view, (win_w, win_h));
        }
        state.count_presented(&self.args.solution, &self.controls, (eye_w, eye_h), header);
        Ok(if last { Step::Done } else { Step::Presented })
    }
}

impl Running {
    /// `--watch`: when the watched file has a new version, the renderer takes
    /// the new scene (keeping its pipelines); a file it cannot draw is refused
    /// like one that fails to read, and the previous solution stays.
    fn poll_watch(
        &mut self,
        args: &MirrorArgs,
        controls: &mut Controls,
        solution: &mut MappedSolution,
    ) {
        let Some(watch) = self.watch.as_mut() else {
            return;
        };
        let now = Instant::now();
        let Some(stamp) = watch.poll(now) else {
            return;
        };
        let loaded = open_solution(&args.solution, args.render.max_frame_cost).and_then(|file| {
            if let Some(renderer) = self.renderer.as_mut() {
                renderer.set_mapped(&self.gpu, &file)?;
            }
            Ok(file)
        });
        match loaded {
            Ok(file) => {
                watch.loaded(stamp);
                controls.set_scene(scene_frame(&file));
                *solution = file;
                self.reloads += 1;
                let h = solution.header();
                let (v, t) = solution.batches().iter().fold((0, 0), |(v, t), b| {
                    (
                        v + u64::from(b.vertex_count),
                        t + u64::from(b.triangle_count()),
                    )
                });
                eprintln!(
                    "reloaded: shots={} partial={} vertices={v} triangles={t}",
                    h.stats.shots, h.partial
                );
                if args.quit_after_reloads.is_some_and(|n| self.reloads >= n) {
                    // The next presented frame is the last.
                    self.exiting = true;
                }
            }
            Err(e) => {
                if watch.failed(stamp, now) {
                    eprintln!(
                        "reload of {} failed, keeping the previous solution: {e:#}",
                        watch.path().display()
                    );
                }
            }
        }
    }

    /// Applies this frame's input (the script's, or the window's) to the
    /// controls and moves them on by the frame's time step; true when a
    /// screenshot was asked for.
    fn apply_input(
        &mut self,
        script: Option<&mut script::Script>,
        controls: &mut Controls,
    ) -> bool {
        let scripted = script.is_some();
        let events = match script {
            Some(script) => script.take(self.frame),
            None => std::mem::take(&mut self.pending)
                .into_iter()
                .map(script::Event::Input)
                .collect(),
        };
        let mut screenshot = false;
        for event in events {
            let input = match event {
                script::Event::Input(input) => input,
                script::Event::Resize(w, h) => {
                    // Takes effect when the window system says so (Resized).
                    let _ = self
                        .window
                        .request_inner_size(winit::dpi::PhysicalSize::new(w, h));
                    continue;
                }
            };
            match controls.apply(input) {
                Some(Command::Exit) => self.exiting = true,
                Some(Command::Screenshot) => screenshot = true,
                None => {}
            }
        }
        let now = Instant::now();
        let dt = if scripted {
            SCRIPT_DT
        } else {
            now.duration_since(self.last_update).as_secs_f64().min(0.1)
        };
        self.last_update = now;
        controls.update(dt);
        screenshot
    }

    /// The eye images at `eye` size (the renderer pointed at new ones), the
    /// renderer made on the first frame, and its tone and inspection set from
    /// the view.
    fn prepare_renderer(
        &mut self,
        args: &MirrorArgs,
        solution: &MappedSolution,
        view: &ViewOptions,
        (eye_w, eye_h): (u32, u32),
    ) -> Result<()> {
        if let Some(retired) = self.presenter.ensure_eye_size(&self.gpu, eye_w, eye_h)? {
            if let Some(renderer) = self.renderer.as_mut() {
                renderer.resize(&self.gpu, &self.presenter.eye_targets())?;
            }
            drop(retired);
        }
        // The file's automatic exposure plus the view's EV offset (`[`, `]`,
        // starting at `--exposure`).
        let tone = crate::render::file_tone(
            solution.lighting(),
            view.exposure_stops,
            args.render.tonemap,
        );
        if self.renderer.is_none() {
            let desc = RendererDesc {
                width: eye_w,
                height: eye_h,
                max_samples: args.render.samples,
                multiview: args.render.multiview,
                max_order: args.render.max_order,
                tone,
                culling: args.render.culling(),
            };
            self.renderer = Some(StereoRenderer::from_mapped(
                &self.gpu,
                solution,
                desc,
                &self.presenter.eye_targets(),
            )?);
            self.renderer_inspect = Inspect::default();
        }
        let renderer = self.renderer.as_mut().context("no renderer")?;
        renderer.set_tone(tone);
        let inspect = Inspect {
            edges: match view.wireframe {
                Wireframe::Off => Edges::Off,
                Wireframe::Overlay => Edges::Overlay,
                Wireframe::Only => Edges::Only,
            },
            normals: view.normals,
        };
        if inspect != self.renderer_inspect {
            renderer.set_inspect(&self.gpu, solution, inspect)?;
            self.renderer_inspect = inspect;
        }
        Ok(())
    }

    /// The first presented frame's line on stderr: window, display, present
    /// mode, format and how the eyes reach the window.
    fn report_first_frame(&self, view: &ViewOptions, (win_w, win_h): (u32, u32)) {
        eprintln!(
            "mirror: first frame presented ({win_w}x{win_h} window, {:?}, {:?} present mode, \
             {:?}, {})",
            view.display,
            self.presenter.present_mode(),
            self.presenter.surface_format(),
            if self.presenter.copies_eyes() {
                "eye images copied"
            } else {
                "composite shader"
            }
        );
    }

    /// Counts a presented frame, its interval, and (once per statistics
    /// window, or when there is none yet) the HUD line and the window title.
    fn count_presented(
        &mut self,
        path: &Path,
        controls: &Controls,
        (eye_w, eye_h): (u32, u32),
        header: &solution::format::Header,
    ) {
        self.frame += 1;
        self.presented += 1;
        let now = Instant::now();
        if let Some(prev) = self.last_present {
            self.times
                .push(now.duration_since(prev).as_secs_f64() * 1e3);
        }
        self.last_present = Some(now);
        if now.duration_since(self.title_at) >= stats::FrameTimes::WINDOW || self.hud.is_empty() {
            self.title_at = now;
            self.hud = hud_line(&self.times, controls, eye_w, eye_h, header);
            self.window.set_title(&format!(
                "runtime mirror: {} - {}",
                file_name(path),
                self.hud
            ));
        }
    }
}

/// The views drawn and how the window shows them: both eyes for the stereo
/// layouts and for a screenshot (always a pair), one otherwise.
fn eye_views(stereo: [EyeView; 2], display: Display, screenshot: bool) -> (Vec<EyeView>, Layout) {
    match display {
        Display::SideBySide => (stereo.to_vec(), Layout::SideBySide),
        Display::Anaglyph => (stereo.to_vec(), Layout::Anaglyph),
        Display::Left if !screenshot => (vec![stereo[0]], Layout::Single { layer: 0 }),
        Display::Right if !screenshot => (vec![stereo[1]], Layout::Single { layer: 0 }),
        Display::Left => (stereo.to_vec(), Layout::Single { layer: 0 }),
        Display::Right => (stereo.to_vec(), Layout::Single { layer: 1 }),
    }
}

/// Reads both eyes of the frame just drawn into `slot` back and writes them
/// as `{base}-left|right.png` and `.exr`, then prints the camera.
fn write_screenshot(
    renderer: &StereoRenderer,
    gpu: &Gpu,
    slot: usize,
    base: &str,
    camera: &Camera,
) -> Result<()> {
    let eyes = renderer.read_back(gpu, slot, 2)?;
    for (eye, side) in eyes.iter().zip(["left", "right"]) {
        let png = PathBuf::from(format!("{base}-{side}.png"));
        let exr = PathBuf::from(format!("{base}-{side}.exr"));
        write_png(&png, eye.width, eye.height, &eye.srgb)?;
        write_exr(&exr, eye.width, eye.height, &eye.radiance)?;
        println!("wrote {} and {}", png.display(), exr.display());
    }
    let c = camera;
    println!(
        "screenshot camera: eye {:?} {:?} {:?} target {:?} {:?} {:?}",
        c.eye[0], c.eye[1], c.eye[2], c.target[0], c.target[1], c.target[2]
    );
    Ok(())
}

/// The overlay: the frame time, then the help, in a text block that fits the
/// window (twice the font's size in a window of at least 800 × 400).
fn overlay(view: &ViewOptions, hud: &str, (win_w, win_h): (u32, u32)) -> Overlay {
    let mut lines = Vec::new();
    if view.hud {
        lines.push(hud.to_string());
    }
    if view.help {
        if view.hud {
            lines.push(String::new());
        }
        lines.extend(Controls::help_lines().iter().map(|s| s.to_string()));
    }
    let scale = if win_w >= 800 && win_h >= 400 { 2 } else { 1 };
    let margin = 4 * scale as i32;
    let max_cols = (win_w.saturating_sub(2 * margin as u32) / (font::CELL_W * scale))
        .min(present::MAX_TEXT_COLS);
    let max_rows = (win_h.saturating_sub(2 * margin as u32) / (font::CELL_H * scale))
        .min(present::MAX_TEXT_ROWS);
    Overlay {
        grid: font::TextGrid::new(&lines, max_cols, max_rows),
        origin: (margin, margin),
        scale,
    }
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string())
}

fn hud_line(
    times: &stats::FrameTimes,
    controls: &Controls,
    eye_w: u32,
    eye_h: u32,
    header: &solution::format::Header,
) -> String {
    let time = match times.recent_mean_ms() {
        Some(ms) => format!("{ms:.1} ms {:.0} fps", 1e3 / ms.max(1e-3)),
        None => "-- ms".into(),
    };
    let mode = match controls.mode {
        controls::Mode::Orbit => "orbit",
        controls::Mode::Walk => "walk",
    };
    let partial = if header.partial {
        format!("  partial, {} shots", header.stats.shots)
    } else {
        String::new()
    };
    format!("{time}  {eye_w}x{eye_h}/eye  {mode}{partial}  F1 help")
}
