//! The previewer window: winit + wgpu + egui. Every frame traces the view on
//! the GPU ([`super::gpu::Tracer`]), shows it tone-mapped in the central
//! area, and draws the controls beside it.
//!
//! - **Camera**: drag (left, or right in hot-spot mode) turns the view: in place
//!   (fly) or around the point looked at (orbit); W/A/S/D/Q/E move (Shift:
//!   ×10); the wheel zooms the field of view down to 0.01°. Turning follows the
//!   pointer at any zoom (the angle per pixel is the pixel's angle).
//! - **Editing** ([`super::editing`]): a slider per medium parameter, named by
//!   its path; in hot-spot mode, dragging a hot spot on the ground moves it,
//!   dragging its rim resizes it, double-clicking the ground adds one. The
//!   problem's pairs are drawn (through: circle, target: cross) with their
//!   current endpoint distances; "Fit" runs the fit from the current medium
//!   in the background; "Save" writes the input with the edited medium,
//!   atomically. A medium of real air is drawn as the file has it and is not
//!   editable (the editor edits logistic parameters): its panel says so, and
//!   its sliders, hot-spot drags, fit and save are off.
//!
//! - **Accumulation** ([`super::accumulate`]): while anything changes each
//!   frame traces "samples per frame" afresh; once the view is still, each
//!   frame adds the next samples of the renderer's sequence to the picture,
//!   up to "accumulate up to" (`--spp`, default 16), and then no frame is
//!   traced until something changes. The panel says how many samples the
//!   picture holds. N accumulated samples make the headless frame at
//!   `--spp N`.
//! - **Glare**: once the still view holds all its samples, the scene's veiling
//!   glare is added on the CPU to the frame traced last, as on headless frames;
//!   moving, editing or unticking "glare" traces afresh.
//!
//! Overlays (hot-spot rims, pair markers) are placed with straight rays: they
//! mark where things are, the traced image shows where they appear.

use super::accumulate::Accumulation;
use super::camera::{CameraState, MAX_FOV, MIN_FOV};
use super::display::{display_pipeline, read_png};
use super::editing::{self, Drag, FitJob};
use super::gpu::{Gpu, Tracer, copy_to_buffer, surface_config};
use super::input::Input;
use super::pack::{SceneBuffers, View, pack};
use crate::error::{Error, FieldError, Result};
use crate::io::write_atomic;
use crate::medium::{LogisticMedium, Medium, Param};
use crate::render::Shading;
use crate::render::accel::Aabb;
use crate::render::air::Air;
use crate::render::camera::Camera;
use glam::{DVec2, DVec3};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::window::{Window, WindowId};

/// How the window starts: `mirage preview`'s flags, checked.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WindowSettings {
    /// Window width in pixels (default 1600).
    pub width: Option<u32>,
    /// Window height in pixels (default 900).
    pub height: Option<u32>,
    /// Show the albedo of what each ray hits.
    pub albedo: bool,
    /// Straight rays.
    pub straight: bool,
    /// The most samples per pixel accumulated while the view is still (≥ 1).
    pub accumulate: u32,
    /// Close after this many frames.
    pub frames: Option<u64>,
    /// Save the last frame (picture and panels) here.
    pub screenshot: Option<PathBuf>,
}

/// Opens the previewer window on `input`; closes after `settings.frames`
/// frames if given, saving the last one (picture and panels) to
/// `settings.screenshot`.
pub fn run(input: Input, settings: WindowSettings) -> Result<()> {
    let WindowSettings {
        width,
        height,
        albedo,
        straight,
        accumulate,
        frames,
        screenshot,
    } = settings;
    let event_loop = EventLoop::new().map_err(|e| {
        Error::gpu(
            "opening a window (is DISPLAY set? mirage preview --headless renders without one)",
            e,
        )
    })?;
    let size = (width.unwrap_or(1600), height.unwrap_or(900));
    let mut app = App::new(input, size, albedo, straight, frames, screenshot);
    app.accumulation = Accumulation::new(accumulate);
    event_loop
        .run_app(&mut app)
        .map_err(|e| Error::gpu("running the window's event loop", e))?;
    match app.failure.take() {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// The per-parameter slider state.
struct Slider {
    param: Param,
    range: (f64, f64),
}

/// The GPU side of the window, created once the window exists.
struct Graphics {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    gpu: Gpu,
    tracer: Tracer,
    buffers: SceneBuffers,
    display: wgpu::RenderPipeline,
    display_layout: wgpu::BindGroupLayout,
    display_uniform: wgpu::Buffer,
    egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
}

struct App {
    input: Input,
    size: (u32, u32),
    medium: LogisticMedium,
    /// A medium of another kind than the logistic one (real air), shown as
    /// the file has it and not editable: the editor's sliders, hot-spot
    /// drags, fit and save edit logistic parameters.
    fixed: Option<Medium>,
    /// Why the edited medium was not applied.
    medium_error: Option<FieldError>,
    medium_dirty: bool,
    sliders: Vec<Slider>,
    camera: CameraState,
    shading: Shading,
    straight: bool,
    /// Samples a frame traces.
    spp: u32,
    /// The samples in the picture, and the most it accumulates.
    accumulation: Accumulation,
    render_scale: u32,
    exposure: f32,
    glare: bool,
    /// The linear image holds the glare of the view traced last.
    glared: bool,
    /// What the linear image was last traced with (the uniform block's bytes).
    traced: Vec<u8>,
    glare_message: String,
    edit_hot_spots: bool,
    drag: Option<Drag>,
    distances: Vec<f64>,
    fit: Option<FitJob>,
    fit_message: String,
    save_path: String,
    save_message: String,
    frames_left: Option<u64>,
    screenshot: Option<PathBuf>,
    frame_ms: f64,
    frame_count: u64,
    egui: egui::Context,
    graphics: Option<Graphics>,
    failure: Option<Error>,
}

impl App {
    fn new(
        input: Input,
        size: (u32, u32),
        albedo: bool,
        straight: bool,
        frames: Option<u64>,
        screenshot: Option<PathBuf>,
    ) -> App {
        // Real air is shown read-only; the editor edits the logistic kind.
        let fixed = match &input.scene.medium {
            Medium::Logistic(_) => None,
            other => Some(other.clone()),
        };
        let medium = input
            .scene
            .medium
            .as_logistic()
            .cloned()
            .unwrap_or_else(LogisticMedium::vacuum);
        let bounds = |p: Param| {
            input
                .problem
                .as_ref()
                .and_then(|pr| pr.free.iter().position(|&f| f == p).map(|k| pr.bounds[k]))
        };
        let sliders = medium
            .params()
            .into_iter()
            .filter(|_| fixed.is_none())
            .map(|(param, v)| Slider {
                param,
                range: editing::slider_range(param, v, bounds(param)),
            })
            .collect();
        let distances = input
            .problem
            .as_ref()
            .filter(|_| fixed.is_none())
            .map(|p| editing::pair_distances(p, &medium))
            .unwrap_or_default();
        let save_path = editing::edited_path(&input.path).display().to_string();
        let exposure = input.scene.exposure as f32;
        App {
            camera: CameraState::from_settings(&input.scene.camera),
            input,
            size,
            medium,
            fixed,
            medium_error: None,
            medium_dirty: false,
            sliders,
            shading: if albedo {
                Shading::Albedo
            } else {
                Shading::Lit
            },
            straight,
            spp: 1,
            accumulation: Accumulation::new(super::accumulate::DEFAULT_TARGET),
            render_scale: 1,
            exposure,
            glare: true,
            glared: false,
            traced: Vec::new(),
            glare_message: String::new(),
            edit_hot_spots: false,
            drag: None,
            distances,
            fit: None,
            fit_message: String::new(),
            save_path,
            save_message: String::new(),
            frames_left: frames,
            screenshot,
            frame_ms: 0.0,
            frame_count: 0,
            egui: egui::Context::default(),
            graphics: None,
            failure: None,
        }
    }

    fn view(&self, width: u32, height: u32) -> View {
        View {
            camera: self.camera.camera(width, height),
            shading: self.shading,
            straight: self.straight,
            samples_per_pixel: self.spp,
            hit_fraction: crate::render::RenderOptions::default().hit_fraction,
        }
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, e: Error) {
        self.failure = Some(e);
        event_loop.exit();
    }

    fn init_graphics(&mut self, event_loop: &ActiveEventLoop) -> Result<Graphics> {
        let attrs = Window::default_attributes()
            .with_title(format!("mirage preview: {}", self.input.path.display()))
            .with_inner_size(winit::dpi::PhysicalSize::new(self.size.0, self.size.1));
        let window = Arc::new(
            event_loop
                .create_window(attrs)
                .map_err(|e| Error::gpu("creating the window", e))?,
        );
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let surface = instance
            .create_surface(Arc::clone(&window))
            .map_err(|e| Error::gpu("creating the window's surface", e))?;
        let gpu = Gpu::with_instance(instance, Some(&surface))?;
        // A software adapter (lavapipe) starts at half resolution.
        if gpu.adapter.get_info().device_type == wgpu::DeviceType::Cpu {
            self.render_scale = 2;
        }
        let caps = surface.get_capabilities(&gpu.adapter);
        let size = window.inner_size();
        let config = surface_config(&caps, size.width, size.height)?;
        let format = config.format;
        surface.configure(&gpu.device, &config);
        let view = self.view(64, 36);
        let buffers = pack(&self.input.scene, &self.shown_medium(), &view)
            .map_err(|e| e.in_file(&self.input.path))?;
        let tracer = Tracer::new(&gpu, &buffers);
        let (display, display_layout, display_uniform) = display_pipeline(&gpu.device, format);
        let egui_state = egui_winit::State::new(
            self.egui.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(gpu.device.limits().max_texture_dimension_2d as usize),
        );
        let egui_renderer =
            egui_wgpu::Renderer::new(&gpu.device, format, egui_wgpu::RendererOptions::default());
        Ok(Graphics {
            window,
            surface,
            config,
            gpu,
            tracer,
            buffers,
            display,
            display_layout,
            display_uniform,
            egui_state,
            egui_renderer,
        })
    }

    /// The controls; returns the central area's rectangle (points) and the
    /// response of the view to the pointer.
    fn ui(&mut self, ui: &mut egui::Ui) -> (egui::Rect, egui::Response) {
        egui::Panel::right("controls")
            .default_size(330.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| self.controls(ui));
            });
        let inner = egui::CentralPanel::no_frame().show(ui, |ui| {
            let rect = ui.max_rect();
            let response = ui.allocate_rect(rect, egui::Sense::click_and_drag());
            (rect, response)
        });
        inner.inner
    }

    fn controls(&mut self, ui: &mut egui::Ui) {
        ui.heading(&self.input.scene.name);
        if let Some(g) = &self.graphics {
            ui.label(format!(
                "{} — {:.1} ms/frame",
                g.gpu.describe(),
                self.frame_ms
            ));
        }
        ui.separator();
        ui.label("View");
        ui.horizontal(|ui| {
            ui.radio_value(&mut self.camera.orbit, false, "fly");
            ui.radio_value(&mut self.camera.orbit, true, "orbit");
        });
        ui.add(
            egui::Slider::new(&mut self.camera.fov, MIN_FOV..=MAX_FOV)
                .logarithmic(true)
                .text("field of view (°)"),
        );
        if ui.checkbox(&mut self.straight, "straight rays").changed() {
            self.medium_dirty = true;
        }
        ui.horizontal(|ui| {
            ui.radio_value(&mut self.shading, Shading::Lit, "lit");
            ui.radio_value(&mut self.shading, Shading::Albedo, "albedo");
        });
        ui.add(
            egui::Slider::new(&mut self.exposure, 0.1..=8.0)
                .logarithmic(true)
                .text("exposure"),
        );
        if self.input.scene.glare.is_some() {
            ui.checkbox(&mut self.glare, "glare (once the view is still)");
            if self.glare && !self.glare_message.is_empty() {
                ui.label(&self.glare_message);
            }
        }
        ui.add(egui::Slider::new(&mut self.spp, 1..=16).text("samples per frame"));
        let mut target = self.accumulation.target();
        if ui
            .add(
                egui::Slider::new(&mut target, 1..=1024)
                    .logarithmic(true)
                    .text("accumulate up to"),
            )
            .changed()
        {
            self.accumulation.set_target(target);
        }
        ui.label(format!(
            "{} of {} samples per pixel in the picture{}",
            self.accumulation.samples(),
            self.accumulation.target(),
            if self.accumulation.complete() {
                ""
            } else {
                " (adding while the view is still)"
            }
        ));
        ui.horizontal(|ui| {
            ui.label("resolution");
            for s in [1, 2, 4] {
                ui.radio_value(&mut self.render_scale, s, format!("1/{s}"));
            }
        });
        let p = self.camera.position;
        ui.label(format!(
            "eye ({:.1}, {:.2}, {:.1}) m, heading {:.2}°, elevation {:.3}°",
            p.x,
            p.y,
            p.z,
            self.camera.yaw.to_degrees(),
            self.camera.pitch.to_degrees()
        ));
        ui.separator();
        ui.label("Medium");
        if let Some(m) = &self.fixed {
            ui.label(format!(
                "{}: shown as the file has it, read-only (the sliders, hot-spot drags, fit and save edit the logistic model; edit the file, or fit with `mirage fit`)",
                m.kind_name()
            ));
        }
        for s in &self.sliders {
            let Some(mut v) = self.medium.get(s.param) else {
                continue;
            };
            let (lo, hi) = s.range;
            let r = ui.add(egui::Slider::new(&mut v, lo..=hi).text(s.param.to_string()));
            if r.changed() && self.medium.set(s.param, v).is_ok() {
                self.medium_dirty = true;
            }
        }
        if let Some(e) = &self.medium_error {
            ui.colored_label(egui::Color32::LIGHT_RED, format!("{e} (not applied)"));
        }
        let editable = self.fixed.is_none();
        ui.add_enabled(
            editable,
            egui::Checkbox::new(
                &mut self.edit_hot_spots,
                "drag hot spots on the ground (double-click: add one)",
            ),
        );
        ui.separator();
        if let Some(problem) = &self.input.problem {
            ui.label(format!("Pairs ({} free parameters)", problem.free.len()));
            for (i, d) in self.distances.iter().enumerate() {
                ui.label(format!("pair {i}: endpoint {d:.4} m from its target"));
            }
            let running = self
                .fit
                .as_ref()
                .is_some_and(|f| f.progress().done.is_none());
            if ui
                .add_enabled(
                    editable && !running && !problem.free.is_empty(),
                    egui::Button::new("Fit from here"),
                )
                .clicked()
            {
                self.fit = Some(FitJob::start(problem, &self.medium));
            }
            if !self.fit_message.is_empty() {
                ui.label(&self.fit_message);
            }
            ui.separator();
        }
        ui.horizontal(|ui| {
            ui.label("save to");
            ui.text_edit_singleline(&mut self.save_path);
        });
        if ui
            .add_enabled(editable, egui::Button::new("Save"))
            .clicked()
        {
            let out = PathBuf::from(&self.save_path);
            self.save_message = match editing::save(&self.input.path, &self.medium, &out) {
                Ok(()) => format!("saved {}", out.display()),
                Err(e) => e.to_string(),
            };
        }
        if !self.save_message.is_empty() {
            ui.label(&self.save_message);
        }
    }

    /// Pointer and keys over the view.
    fn interact(&mut self, ui: &egui::Ui, rect: egui::Rect, response: &egui::Response) {
        let ppp = ui.ctx().pixels_per_point() as f64;
        let (w, h) = (
            (rect.width() as f64 * ppp).max(1.0),
            (rect.height() as f64 * ppp).max(1.0),
        );
        let cam = self.camera.camera(w as u32, h as u32);
        let ground_at = |pos: egui::Pos2| {
            let px = (pos.x - rect.min.x) as f64 * ppp;
            let py = (pos.y - rect.min.y) as f64 * ppp;
            editing::ground_point(&cam, px, py).map(|g| DVec2::new(g.x, g.z))
        };
        let turn_button = if self.edit_hot_spots {
            egui::PointerButton::Secondary
        } else {
            egui::PointerButton::Primary
        };
        if response.dragged_by(turn_button) || response.dragged_by(egui::PointerButton::Secondary) {
            let d = response.drag_delta();
            self.camera.turn(d.x as f64 * ppp, d.y as f64 * ppp, h);
        }
        if self.edit_hot_spots && self.fixed.is_none() {
            if response.drag_started_by(egui::PointerButton::Primary) {
                self.drag = response
                    .interact_pointer_pos()
                    .and_then(ground_at)
                    .and_then(|g| editing::pick(&self.medium, g));
            }
            if response.dragged_by(egui::PointerButton::Primary)
                && let (Some(drag), Some(g)) = (
                    self.drag,
                    response.interact_pointer_pos().and_then(ground_at),
                )
            {
                editing::apply_drag(&mut self.medium, drag, g);
                self.medium_dirty = true;
            }
            if response.drag_stopped() {
                self.drag = None;
            }
            if response.double_clicked()
                && let Some(g) = response.interact_pointer_pos().and_then(ground_at)
            {
                let spot = editing::new_hot_spot(&self.medium, g);
                self.medium.hotspots.push(spot);
                self.rebuild_sliders();
                self.medium_dirty = true;
            }
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y) as f64;
            if scroll != 0.0 {
                self.camera.zoom(scroll / 50.0);
            }
        }
        let (fw, rt, up, fast) = ui.input(|i| {
            let k = |key| i.key_down(key) as i32 as f64;
            (
                k(egui::Key::W) - k(egui::Key::S),
                k(egui::Key::D) - k(egui::Key::A),
                k(egui::Key::E) - k(egui::Key::Q),
                i.modifiers.shift,
            )
        });
        if ui.ctx().memory(|m| m.focused().is_none()) && (fw != 0.0 || rt != 0.0 || up != 0.0) {
            let speed = if fast { 10.0 } else { 1.0 };
            self.camera.fly(fw * speed, rt * speed, up * 0.1 * speed);
        }
        self.draw_overlays(ui, rect, &cam, ppp);
    }

    fn rebuild_sliders(&mut self) {
        let old: Vec<(Param, (f64, f64))> =
            self.sliders.iter().map(|s| (s.param, s.range)).collect();
        self.sliders = self
            .medium
            .params()
            .into_iter()
            .map(|(param, v)| Slider {
                param,
                range: old
                    .iter()
                    .find(|(p, _)| *p == param)
                    .map(|(_, r)| *r)
                    .unwrap_or_else(|| editing::slider_range(param, v, None)),
            })
            .collect();
    }

    fn draw_overlays(&self, ui: &egui::Ui, rect: egui::Rect, cam: &Camera, ppp: f64) {
        let painter = ui.painter_at(rect);
        let to_screen = |p: DVec3| {
            cam.project(p).map(|(x, y)| {
                egui::pos2(rect.min.x + (x / ppp) as f32, rect.min.y + (y / ppp) as f32)
            })
        };
        let rim = egui::Stroke::new(1.5, egui::Color32::from_rgb(255, 140, 40));
        for h in &self.medium.hotspots {
            let mut line: Vec<egui::Pos2> = Vec::new();
            for k in 0..=96 {
                let t = std::f64::consts::TAU * k as f64 / 96.0;
                let p = DVec3::new(h.x + h.radius * t.cos(), 0.0, h.z + h.radius * t.sin());
                match to_screen(p) {
                    Some(s) => line.push(s),
                    None => {
                        if line.len() > 1 {
                            painter.line(std::mem::take(&mut line), rim);
                        }
                        line.clear();
                    }
                }
            }
            if line.len() > 1 {
                painter.line(line, rim);
            }
        }
        if let Some(problem) = &self.input.problem {
            let through = egui::Stroke::new(1.5, egui::Color32::from_rgb(80, 220, 255));
            let target = egui::Stroke::new(1.5, egui::Color32::from_rgb(255, 60, 200));
            for (i, pair) in problem.pairs.iter().enumerate() {
                if let Some(s) = to_screen(DVec3::from_array(pair.through)) {
                    painter.circle_stroke(s, 5.0, through);
                }
                if let Some(s) = to_screen(DVec3::from_array(pair.target)) {
                    let d = 5.0;
                    painter.line_segment([s + egui::vec2(-d, -d), s + egui::vec2(d, d)], target);
                    painter.line_segment([s + egui::vec2(-d, d), s + egui::vec2(d, -d)], target);
                    let text = match self.distances.get(i) {
                        Some(d) => format!("{i}: {d:.3} m"),
                        None => format!("{i}"),
                    };
                    painter.text(
                        s + egui::vec2(7.0, -7.0),
                        egui::Align2::LEFT_BOTTOM,
                        text,
                        egui::FontId::proportional(12.0),
                        egui::Color32::WHITE,
                    );
                }
            }
        }
    }

    /// The medium drawn: the read-only one, else the edited logistic one.
    fn shown_medium(&self) -> Medium {
        match &self.fixed {
            Some(m) => m.clone(),
            None => Medium::Logistic(self.medium.clone()),
        }
    }

    /// Applies an edited medium: validated, re-analysed, uploaded, and the
    /// pairs re-traced.
    fn apply_medium(&mut self) {
        self.medium_dirty = false;
        if let Err(e) = self.medium.validate() {
            self.medium_error = Some(e.within("medium"));
            return;
        }
        self.medium_error = None;
        if let Some(p) = &self.input.problem
            && self.fixed.is_none()
        {
            self.distances = editing::pair_distances(p, &self.medium);
        }
        let medium = self.shown_medium();
        if let Some(g) = &mut self.graphics {
            let scene = &self.input.scene;
            let air = Air::new(
                &medium,
                self.straight,
                scene.step,
                scene.ground.is_some(),
                Aabb::of_objects(&scene.objects),
                scene.earth,
            );
            g.buffers.set_air(&medium, &air);
            g.tracer.update(&g.gpu, &g.buffers);
        }
    }

    fn poll_fit(&mut self) {
        let Some(job) = &self.fit else { return };
        let p = job.progress();
        match p.done {
            None => {
                self.fit_message = format!(
                    "fitting: {} iterations ({}), best objective {:.3e}",
                    p.iterations, p.run, p.best_objective
                );
            }
            Some(Ok(m)) => {
                self.fit_message = format!("fit done after {} iterations", p.iterations);
                self.medium = m;
                self.rebuild_sliders();
                self.medium_dirty = true;
                self.fit = None;
            }
            Some(Err(e)) => {
                self.fit_message = format!("fit failed: {e}");
                self.fit = None;
            }
        }
    }

    /// Whether this frame traces the view, and which samples: while
    /// anything changes, `spp` samples afresh; once the view is the one
    /// traced last, the next samples added to the picture's
    /// ([`super::accumulate`]) until it holds its target; then nothing is
    /// traced until something changes, and (once) the image traced last is
    /// read back, given the scene's glare on the CPU
    /// ([`super::frame::apply_glare`], as headless frames get it) and
    /// uploaded in its place. Sets the samples in `g.buffers`' uniform block.
    fn glare_or_trace(
        &mut self,
        g: &mut Graphics,
        view: &View,
        medium_changed: bool,
    ) -> Result<bool> {
        // The view as `set_view` left it (no accumulation fields set): what
        // "still" compares.
        let params = bytemuck::bytes_of(&g.buffers.params);
        let still = !medium_changed && self.traced == params;
        self.traced = params.to_vec();
        if !g.tracer.accumulates() {
            // An image too large for the accumulation buffer: a frame holds
            // what it traces.
            self.accumulation.set_target(self.spp);
        }
        if let Some(samples) = self.accumulation.next(still, self.spp) {
            g.buffers.set_samples(samples, g.tracer.accumulates());
            self.glared = false;
            if samples.first > 0 && self.accumulation.complete() {
                // For the window test and the curious: accumulation ran.
                eprintln!(
                    "accumulated: {} samples per pixel in a {}×{} frame",
                    samples.total(),
                    view.camera.width,
                    view.camera.height
                );
            }
            return Ok(true);
        }
        let want = self.glare && self.shading == Shading::Lit && self.input.scene.glare.is_some();
        if want && !self.glared {
            let mut pixels = g.tracer.read_back(&g.gpu)?;
            if let Some(stats) = super::frame::apply_glare(&self.input.scene, view, &mut pixels) {
                g.tracer.upload(&g.gpu, &pixels);
                self.glare_message = format!(
                    "glare: {} source pixels, {:.0} ms",
                    stats.sources,
                    stats.seconds * 1000.0
                );
                // For the window test and the curious: the glare path ran.
                eprintln!(
                    "glare: {} source pixels in a {}×{} frame, {:.3} s",
                    stats.sources, view.camera.width, view.camera.height, stats.seconds
                );
            }
            self.glared = true;
        }
        if !want && self.glared {
            // Glare unticked on a still view: the picture without it again.
            self.accumulation = Accumulation::new(self.accumulation.target());
            return self.glare_or_trace(g, view, true);
        }
        Ok(false)
    }

    /// Draws one frame: the controls, the edits they made, the traced view
    /// (or its glare, once still) and the panels over it; saves the
    /// screenshot on the last frame.
    fn redraw(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let start = Instant::now();
        self.poll_fit();
        let Some(mut g) = self.graphics.take() else {
            return Ok(());
        };
        let (mut output, view_rect) = self.run_ui(&mut g);
        let medium_changed = self.medium_dirty;
        if self.medium_dirty {
            g = self.apply_medium_with(g);
        }
        let ppp = output.pixels_per_point;
        let place = Placement::of(view_rect, ppp, &g.config, self.render_scale);
        let view = self.view(place.trace_width, place.trace_height);
        let trace = self.upload_view(&mut g, &view, medium_changed)?;
        // egui's texture changes are applied now, whether or not this frame
        // is presented (an unapplied delta is a bug egui checks for).
        let mut textures = std::mem::take(&mut output.textures_delta);
        g.update_egui_textures(&textures);
        let Some(frame) = self.acquire_frame(&g) else {
            g.free_egui_textures(&mut textures);
            self.graphics = Some(g);
            return Ok(());
        };
        let plan = FramePlan {
            trace,
            place,
            display_group: self.display_bind_group(&g, &place),
            paint: self.egui.tessellate(output.shapes, ppp),
            screen: egui_wgpu::ScreenDescriptor {
                size_in_pixels: [g.config.width, g.config.height],
                pixels_per_point: ppp,
            },
            shot: self.screenshot_texture(&g),
        };
        let shot = g.encode_and_submit(&frame, &plan);
        g.gpu.queue.present(frame);
        g.free_egui_textures(&mut textures);
        if let (Some((buffer, row)), Some(path)) = (shot, &self.screenshot) {
            let (fw, fh) = (g.config.width, g.config.height);
            let png = read_png(&g.gpu, &buffer, row, fw, fh, g.config.format)?;
            write_atomic(path, &png)?;
        }
        self.count_frame(event_loop, start);
        self.graphics = Some(g);
        Ok(())
    }

    /// Runs the controls and the view's interaction for this frame and hands
    /// egui's platform output (cursor, clipboard) to the window; returns
    /// egui's output and the central area's rectangle (points).
    fn run_ui(&mut self, g: &mut Graphics) -> (egui::FullOutput, egui::Rect) {
        let raw = g.egui_state.take_egui_input(&g.window);
        let ctx = self.egui.clone();
        let mut view_rect = egui::Rect::NOTHING;
        let mut output = ctx.run_ui(raw, |ui| {
            let (rect, response) = self.ui(ui);
            self.interact(ui, rect, &response);
            view_rect = rect;
        });
        let platform = std::mem::take(&mut output.platform_output);
        g.egui_state.handle_platform_output(&g.window, platform);
        (output, view_rect)
    }

    /// [`Self::apply_medium`] while the frame holds the graphics: they are
    /// lent back to `self` for it.
    fn apply_medium_with(&mut self, g: Graphics) -> Graphics {
        self.graphics = Some(g);
        self.apply_medium();
        self.graphics.take().expect("just put back")
    }

    /// Uploads the frame's view (camera, shading, size) and decides whether
    /// this frame traces ([`Self::glare_or_trace`]).
    fn upload_view(&mut self, g: &mut Graphics, view: &View, medium_changed: bool) -> Result<bool> {
        g.buffers.set_view(view);
        let trace = self.glare_or_trace(g, view, medium_changed)?;
        g.tracer.update(&g.gpu, &g.buffers);
        Ok(trace)
    }

    /// The surface's next texture; `None` when it is lost or outdated: the
    /// surface is then reconfigured for the next frame, which traces (this
    /// one's trace is never dispatched).
    fn acquire_frame(&mut self, g: &Graphics) -> Option<wgpu::SurfaceTexture> {
        match g.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f)
            | wgpu::CurrentSurfaceTexture::Suboptimal(f) => Some(f),
            _ => {
                self.traced.clear();
                g.surface.configure(&g.gpu.device, &g.config);
                None
            }
        }
    }

    /// Writes the display pass's uniform (where the image goes, its size,
    /// the tone mapping) and binds it with the linear image.
    fn display_bind_group(&self, g: &Graphics, place: &Placement) -> wgpu::BindGroup {
        let uniform: [f32; 8] = [
            place.x as f32,
            place.y as f32,
            place.width as f32,
            place.height as f32,
            place.trace_width as f32,
            place.trace_height as f32,
            if self.shading == Shading::Albedo {
                1.0
            } else {
                0.0
            },
            self.exposure,
        ];
        g.gpu
            .queue
            .write_buffer(&g.display_uniform, 0, bytemuck::cast_slice(&uniform));
        let linear_view = g.tracer.output().create_view(&Default::default());
        g.gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("display"),
            layout: &g.display_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: g.display_uniform.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&linear_view),
                },
            ],
        })
    }

    /// On the last frame with a screenshot asked for, a texture the frame is
    /// drawn into a second time, to be read back.
    fn screenshot_texture(&self, g: &Graphics) -> Option<wgpu::Texture> {
        let last = self.frames_left == Some(1);
        (last && self.screenshot.is_some()).then(|| {
            g.gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("screenshot"),
                size: wgpu::Extent3d {
                    width: g.config.width,
                    height: g.config.height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: g.config.format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        })
    }

    /// Counts the frame and its time; closes the window after the last one.
    fn count_frame(&mut self, event_loop: &ActiveEventLoop, start: Instant) {
        self.frame_count += 1;
        self.frame_ms = start.elapsed().as_secs_f64() * 1000.0;
        if let Some(n) = &mut self.frames_left {
            *n = n.saturating_sub(1);
            if *n == 0 {
                event_loop.exit();
            }
        }
    }
}

/// Where the traced image goes in the window (framebuffer pixels) and the
/// size it is traced at.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Placement {
    x: u32,
    y: u32,
    width: u32,
    height: u32,
    trace_width: u32,
    trace_height: u32,
}

impl Placement {
    /// The central area `rect` (points, `ppp` pixels each) clamped to the
    /// surface, traced at 1/`render_scale` of its resolution.
    fn of(
        rect: egui::Rect,
        ppp: f32,
        config: &wgpu::SurfaceConfiguration,
        render_scale: u32,
    ) -> Placement {
        let (fw, fh) = (config.width, config.height);
        let x = ((rect.min.x * ppp).max(0.0) as u32).min(fw - 1);
        let y = ((rect.min.y * ppp).max(0.0) as u32).min(fh - 1);
        let width = ((rect.width() * ppp) as u32).clamp(1, fw - x);
        let height = ((rect.height() * ppp) as u32).clamp(1, fh - y);
        Placement {
            x,
            y,
            width,
            height,
            trace_width: (width / render_scale).max(1),
            trace_height: (height / render_scale).max(1),
        }
    }
}

/// What one frame draws, once the view is uploaded.
struct FramePlan {
    /// Whether the view is traced afresh (else the image traced last is
    /// shown, with its glare).
    trace: bool,
    /// Where the image goes.
    place: Placement,
    /// The display pass's uniform and the linear image.
    display_group: wgpu::BindGroup,
    /// egui's panels, tessellated.
    paint: Vec<egui::ClippedPrimitive>,
    /// The surface as egui sees it.
    screen: egui_wgpu::ScreenDescriptor,
    /// The screenshot's texture, on the last frame when one is asked for.
    shot: Option<wgpu::Texture>,
}

impl Graphics {
    /// Applies egui's new and changed textures.
    fn update_egui_textures(&mut self, textures: &egui::TexturesDelta) {
        for (id, deltas) in &textures.set {
            for delta in deltas {
                self.egui_renderer
                    .update_texture(&self.gpu.device, &self.gpu.queue, *id, delta);
            }
        }
    }

    /// Frees the textures egui is done with, once the frame no longer uses
    /// them.
    fn free_egui_textures(&mut self, textures: &mut egui::TexturesDelta) {
        for id in &textures.free {
            self.egui_renderer.free_texture(id);
        }
        textures.clear();
    }

    /// Records and submits the frame: the trace (if the plan says so), then
    /// the display pass and egui's panels into `frame` (and again into the
    /// screenshot's texture); returns the screenshot's read-back buffer and
    /// row pitch.
    fn encode_and_submit(
        &mut self,
        frame: &wgpu::SurfaceTexture,
        plan: &FramePlan,
    ) -> Option<(wgpu::Buffer, u32)> {
        let (fw, fh) = (self.config.width, self.config.height);
        let place = &plan.place;
        let target = frame.texture.create_view(&Default::default());
        let mut encoder = self
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        if plan.trace {
            self.tracer.dispatch(&mut encoder);
        }
        let mut commands = self.egui_renderer.update_buffers(
            &self.gpu.device,
            &self.gpu.queue,
            &mut encoder,
            &plan.paint,
            &plan.screen,
        );
        let shot_view = plan
            .shot
            .as_ref()
            .map(|t| t.create_view(&Default::default()));
        for view in std::iter::once(&target).chain(shot_view.as_ref()) {
            let mut pass = encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("frame"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                })
                .forget_lifetime();
            pass.set_viewport(
                place.x as f32,
                place.y as f32,
                place.width as f32,
                place.height as f32,
                0.0,
                1.0,
            );
            pass.set_pipeline(&self.display);
            pass.set_bind_group(0, &plan.display_group, &[]);
            pass.draw(0..3, 0..1);
            pass.set_viewport(0.0, 0.0, fw as f32, fh as f32, 0.0, 1.0);
            self.egui_renderer
                .render(&mut pass, &plan.paint, &plan.screen);
        }
        let shot = plan
            .shot
            .as_ref()
            .map(|t| copy_to_buffer(&self.gpu.device, &mut encoder, t, 4));
        commands.push(encoder.finish());
        self.gpu.queue.submit(commands);
        shot
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.graphics.is_some() {
            return;
        }
        match self.init_graphics(event_loop) {
            Ok(g) => {
                g.window.request_redraw();
                self.graphics = Some(g);
            }
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        if let Some(g) = &mut self.graphics {
            let _ = g.egui_state.on_window_event(&g.window, &event);
        }
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                if let Some(g) = &mut self.graphics
                    && size.width > 0
                    && size.height > 0
                {
                    g.config.width = size.width;
                    g.config.height = size.height;
                    g.surface.configure(&g.gpu.device, &g.config);
                }
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw(event_loop) {
                    self.fail(event_loop, e);
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(g) = &self.graphics {
            g.window.request_redraw();
        }
    }
}
