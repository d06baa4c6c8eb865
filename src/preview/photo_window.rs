//! The previewer's photo mode window (`mirage preview PHOTO-PROBLEM.json`):
//! the photograph in its own pixel frame, the marks drawn as the overlay
//! draws them (`mirage overlay`) for the current air and camera, and the
//! controls to mark, fit and save. The logic is [`super::photo`]'s; this
//! file wires it to winit, wgpu and egui.
//!
//! - **The photo** fills the central area with its aspect ratio kept
//!   ([`PhotoFrame`]); a photo wider or taller than 4096 pixels is shown
//!   downscaled (the marks stay in the photo's own pixels).
//! - **Marks**: per mark its marked pixel (a ring: yellow for a target,
//!   cyan for a horizon mark), where the current air and camera put it (a
//!   cross, joined to the ring), where straight rays would (a square), and
//!   its name; the apparent horizon across the photo (pink). The panel lists
//!   every mark's residual and the RMS.
//! - **Editing**: a click on the photo away from the marks opens "New mark",
//!   which asks for the target: one of the problem's named points (each
//!   named mark's target), the sea horizon (round earth), or a point typed
//!   in (latitude, longitude, height with a site; else x, y, z in metres). A
//!   click on a mark selects it ("Delete" in the panel); dragging a mark moves
//!   it. Every edit re-validates the problem and recomputes the predictions;
//!   an invalid edit is undone and its error shown.
//! - **Fit** runs `mirage fit`'s fit of the problem as marked on a
//!   background thread (the window stays live) and shows the fitted camera
//!   and air's predictions; **Save** writes the marks back into the file
//!   (only its `marks`, atomically).
//! - **Not drawn**: a GPU render of the air behind the photo. The photo is
//!   the picture here; the render of the same air is `mirage preview` of a
//!   scene, and the marks' predictions come from rays traced on the CPU
//!   exactly as the fit traces them.

use super::display::read_png;
use super::gpu::{Gpu, copy_to_buffer, surface_config};
use super::photo::{NewTarget, PhotoFitJob, PhotoFrame, PhotoSession, typed_point};
use super::script::{Event, Player, Stage};
use crate::error::{Error, Result};
use crate::io::write_atomic;
use egui::{Color32, Pos2, Stroke};
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::window::{Window, WindowId};

/// How the photo window starts.
#[derive(Debug, Default)]
pub struct PhotoWindowSettings {
    /// Window width and height in pixels (default 1600 × 900).
    pub size: (Option<u32>, Option<u32>),
    /// Close after this many frames.
    pub frames: Option<u64>,
    /// Save the last frame here.
    pub screenshot: Option<PathBuf>,
    /// A script to play (closes the window a few frames after its end).
    pub script: Option<Player>,
}

/// The largest side of the photo's texture.
const MAX_TEXTURE: u32 = 4096;
/// Target marks' ring, as in the overlay.
const TARGET: Color32 = Color32::from_rgb(255, 214, 0);
/// Horizon marks' ring.
const HORIZON_MARK: Color32 = Color32::from_rgb(0, 224, 255);
/// The apparent horizon.
const HORIZON_LINE: Color32 = Color32::from_rgb(255, 96, 208);
/// Outlines under the marks.
const DARK: Color32 = Color32::from_rgb(12, 12, 12);
/// The ring's radius (points).
pub const RING: f32 = 8.0;

/// Opens the photo window on `session` showing `photo`.
pub fn run(
    session: PhotoSession,
    photo: image::RgbImage,
    settings: PhotoWindowSettings,
) -> Result<()> {
    let event_loop = EventLoop::new().map_err(|e| {
        Error::gpu(
            "opening a window (is DISPLAY set? `mirage overlay` draws the marks without one)",
            e,
        )
    })?;
    let size = (
        settings.size.0.unwrap_or(1600),
        settings.size.1.unwrap_or(900),
    );
    let photo = if photo.width().max(photo.height()) > MAX_TEXTURE {
        let k = MAX_TEXTURE as f64 / photo.width().max(photo.height()) as f64;
        image::imageops::resize(
            &photo,
            ((photo.width() as f64 * k).round() as u32).max(1),
            ((photo.height() as f64 * k).round() as u32).max(1),
            image::imageops::FilterType::Triangle,
        )
    } else {
        photo
    };
    let save_path = session.path.display().to_string();
    let mut app = PhotoApp {
        session,
        photo: Some(photo),
        texture: None,
        size,
        frames_left: settings.frames,
        screenshot: settings.screenshot,
        script: settings.script,
        egui: egui::Context::default(),
        graphics: None,
        failure: None,
        frame: None,
        widgets: HashMap::new(),
        popup: None,
        selected: None,
        drag: None,
        fit: None,
        message: String::new(),
        save_path,
        frames_drawn: 0,
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| Error::gpu("running the window's event loop", e))?;
    if let Some(f) = &app.frame {
        // For the window test: where the photo was drawn.
        eprintln!(
            "photo frame: origin {:.3} {:.3} scale {:.6}",
            f.origin[0], f.origin[1], f.scale
        );
    }
    match app.failure.take() {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// The new mark's popup.
struct Popup {
    pixel: [f64; 2],
    fields: [String; 3],
}

struct Graphics {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    gpu: Gpu,
    egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
}

struct PhotoApp {
    session: PhotoSession,
    photo: Option<image::RgbImage>,
    texture: Option<egui::TextureHandle>,
    size: (u32, u32),
    frames_left: Option<u64>,
    screenshot: Option<PathBuf>,
    script: Option<Player>,
    egui: egui::Context,
    graphics: Option<Graphics>,
    failure: Option<Error>,
    /// Where the photo was drawn on the last frame.
    frame: Option<PhotoFrame>,
    /// The labelled widgets' rectangles on the last frame (for scripts).
    widgets: HashMap<String, egui::Rect>,
    popup: Option<Popup>,
    selected: Option<usize>,
    /// The mark being dragged and where it is now (photo pixels).
    drag: Option<(usize, [f64; 2])>,
    fit: Option<PhotoFitJob>,
    message: String,
    save_path: String,
    /// Frames drawn so far.
    frames_drawn: u64,
}

impl Stage for PhotoApp {
    fn photo_to_screen(&self, p: [f64; 2]) -> Option<[f64; 2]> {
        self.frame.map(|f| f.to_screen(p))
    }
    fn widget(&self, label: &str) -> Option<[f64; 2]> {
        self.widgets
            .get(label)
            .map(|r| [r.center().x as f64, r.center().y as f64])
    }
    fn fitting(&self) -> bool {
        self.fit.is_some()
    }
}

fn pos(p: [f64; 2]) -> Pos2 {
    Pos2::new(p[0] as f32, p[1] as f32)
}

impl PhotoApp {
    /// A button that scripts can press by its label.
    fn button(&mut self, ui: &mut egui::Ui, label: &str, enabled: bool) -> bool {
        let r = ui.add_enabled(enabled, egui::Button::new(label));
        self.widgets.insert(label.to_string(), r.rect);
        r.clicked()
    }

    /// Shows an edit's outcome.
    fn report_edit(&mut self, what: &str, outcome: Result<()>) {
        self.message = match outcome {
            Ok(()) => format!(
                "{what}: RMS residual {:.3} px",
                self.session.report.rms_pixels
            ),
            Err(e) => format!("{what} undone: {e}"),
        };
        eprintln!("{}", self.message);
    }

    /// Takes the fit's result once it is done.
    fn poll_fit(&mut self) {
        let Some(job) = &self.fit else { return };
        let state = job.state();
        let Some(done) = state.done else { return };
        self.fit = None;
        let before = self.session.report.rms_pixels;
        self.message = match done.map_err(|e| e.to_string()).and_then(|report| {
            self.session
                .take_fit(&report)
                .map_err(|e| e.to_string())
                .map(|()| report)
        }) {
            Ok(report) => {
                let mut s = format!(
                    "fit: RMS residual {before:.4} → {:.4} px in {} iterations;",
                    self.session.report.rms_pixels, state.iterations
                );
                for p in &report.parameters {
                    s.push_str(&format!(" {} = {:.6}", p.name, p.value));
                }
                s
            }
            Err(e) => format!("fit failed: {e}"),
        };
        eprintln!("{}", self.message);
    }

    fn controls(&mut self, ui: &mut egui::Ui) {
        ui.heading(&self.session.problem.name);
        let r = &self.session.report;
        ui.label(format!(
            "{} ({} × {} px, f = {:.1} px)",
            r.image, r.size[0], r.size[1], r.focal_pixels
        ));
        ui.label(format!(
            "RMS residual {:.3} px at the {} numbers",
            r.rms_pixels,
            if self.session.fitted.is_some() {
                "fitted"
            } else {
                "starting"
            }
        ));
        ui.separator();
        ui.label("Click the photo to add a mark; drag a mark to move it; click one to select it.");
        let mut select = None;
        egui::Grid::new("marks").striped(true).show(ui, |ui| {
            for (i, m) in self.session.report.marks.iter().enumerate() {
                if ui
                    .selectable_label(self.selected == Some(i), &m.name)
                    .clicked()
                {
                    select = Some(i);
                }
                ui.label(format!("{:.3} px", m.residual));
                ui.end_row();
            }
        });
        if select.is_some() {
            self.selected = select;
        }
        if let Some(i) = self.selected
            && let Some(m) = self.session.marks.get(i)
        {
            ui.label(format!(
                "selected: {} at ({:.2}, {:.2})",
                m.name.as_deref().unwrap_or("mark"),
                m.pixel[0],
                m.pixel[1]
            ));
            if self.button(ui, "Delete", true) {
                let outcome = self.session.delete_mark(i);
                self.selected = None;
                self.report_edit("mark deleted", outcome);
            }
        }
        ui.separator();
        let fitting = self.fit.is_some();
        ui.horizontal(|ui| {
            if self.button(ui, "Fit", !fitting) {
                self.fit = Some(PhotoFitJob::start(&self.session.problem));
                self.message = "fitting…".into();
            }
            if let Some(job) = &self.fit {
                ui.spinner();
                ui.label(format!("{} iterations", job.state().iterations));
            }
        });
        ui.horizontal(|ui| {
            if self.button(ui, "Save", true) {
                let out = PathBuf::from(self.save_path.trim());
                self.message = match self.session.save(&out) {
                    Ok(()) => format!(
                        "saved {} marks to {}",
                        self.session.marks.len(),
                        out.display()
                    ),
                    Err(e) => format!("not saved: {e}"),
                };
                eprintln!("{}", self.message);
            }
            ui.text_edit_singleline(&mut self.save_path);
        });
        if !self.message.is_empty() {
            ui.label(&self.message);
        }
        if let Some(g) = &self.graphics {
            ui.separator();
            ui.small(g.gpu.describe());
        }
    }

    /// The new mark's popup: its target.
    fn popup(&mut self, ctx: &egui::Context) {
        let Some(mut popup) = self.popup.take() else {
            return;
        };
        let named = self.session.named_targets();
        let geographic = self.session.has_site();
        let round = self.session.problem.trace.earth.radius().is_some();
        let at = self.frame.map(|f| f.to_screen(popup.pixel));
        let mut chosen = None;
        let mut keep = true;
        let mut window = egui::Window::new("New mark")
            .collapsible(false)
            .resizable(false);
        if let Some(at) = at {
            window = window.default_pos(pos([at[0] + 16.0, at[1] + 16.0]));
        }
        window.show(ctx, |ui| {
            ui.label(format!(
                "at pixel ({:.1}, {:.1}); its target:",
                popup.pixel[0], popup.pixel[1]
            ));
            for (k, (name, _)) in named.iter().enumerate() {
                let r = ui.button(name);
                self.widgets.insert(format!("target {name}"), r.rect);
                if r.clicked() {
                    chosen = Some(NewTarget::Named(k));
                }
            }
            if round {
                let r = ui.button("the sea horizon");
                self.widgets.insert("target horizon".into(), r.rect);
                if r.clicked() {
                    chosen = Some(NewTarget::Horizon);
                }
            }
            ui.separator();
            let names = if geographic {
                ["latitude", "longitude", "height"]
            } else {
                ["x", "y", "z"]
            };
            for (name, field) in names.iter().zip(popup.fields.iter_mut()) {
                ui.horizontal(|ui| {
                    ui.label(*name);
                    let r = ui.text_edit_singleline(field);
                    self.widgets.insert(format!("field {name}"), r.rect);
                });
            }
            ui.horizontal(|ui| {
                let typed = typed_point(&popup.fields, geographic);
                let r = ui.add_enabled(typed.is_some(), egui::Button::new("Add typed point"));
                self.widgets.insert("Add typed point".into(), r.rect);
                if r.clicked()
                    && let Some(p) = typed
                {
                    chosen = Some(NewTarget::Point(p));
                }
                let r = ui.button("Cancel");
                self.widgets.insert("Cancel".into(), r.rect);
                if r.clicked() {
                    keep = false;
                }
            });
        });
        if let Some(target) = chosen {
            let outcome = self.session.add_mark(popup.pixel, target).map(|i| {
                self.selected = Some(i);
            });
            self.report_edit(
                &format!(
                    "mark added at ({:.2}, {:.2})",
                    popup.pixel[0], popup.pixel[1]
                ),
                outcome,
            );
            keep = false;
        }
        if keep {
            self.popup = Some(popup);
        }
    }

    /// The photo's area: the picture, the marks, and the pointer on them.
    fn photo_area(&mut self, ui: &mut egui::Ui) {
        let rect = ui.max_rect();
        let response = ui.allocate_rect(rect, egui::Sense::click_and_drag());
        let size = self.session.size();
        let frame = PhotoFrame::fit(
            [rect.min.x as f64, rect.min.y as f64],
            [rect.width() as f64, rect.height() as f64],
            size,
        );
        self.frame = Some(frame);
        let to_pixel = |p: Pos2| frame.to_pixel([p.x as f64, p.y as f64]);
        let inside = |p: [f64; 2]| {
            (-0.5..=size[0] as f64 - 0.5).contains(&p[0])
                && (-0.5..=size[1] as f64 - 0.5).contains(&p[1])
        };
        let grab = RING as f64 * 1.5 / frame.scale;
        if response.drag_started()
            && let Some(origin) = ui.ctx().input(|i| i.pointer.press_origin())
            && let Some(i) = self.session.hit(to_pixel(origin), grab)
        {
            self.drag = Some((i, self.session.marks[i].pixel));
            self.selected = Some(i);
        }
        if let Some((_, at)) = &mut self.drag
            && let Some(p) = response.interact_pointer_pos()
        {
            let q = to_pixel(p);
            *at = [
                q[0].clamp(0.0, size[0] as f64 - 1.0),
                q[1].clamp(0.0, size[1] as f64 - 1.0),
            ];
        }
        if response.drag_stopped()
            && let Some((i, at)) = self.drag.take()
        {
            let outcome = self.session.move_mark(i, at);
            self.report_edit(
                &format!("mark {i} moved to ({:.2}, {:.2})", at[0], at[1]),
                outcome,
            );
        }
        if response.clicked()
            && let Some(p) = response.interact_pointer_pos()
        {
            let q = to_pixel(p);
            if let Some(i) = self.session.hit(q, grab) {
                self.selected = Some(i);
            } else if inside(q) {
                self.popup = Some(Popup {
                    pixel: q,
                    fields: Default::default(),
                });
            }
        }
        self.paint(ui.painter(), frame);
    }

    /// Draws the photo and the marks in `frame`.
    fn paint(&mut self, painter: &egui::Painter, frame: PhotoFrame) {
        if let Some(img) = self.photo.take() {
            let color = egui::ColorImage::from_rgb(
                [img.width() as usize, img.height() as usize],
                img.as_raw(),
            );
            self.texture = Some(painter.ctx().load_texture(
                "photo",
                color,
                egui::TextureOptions::LINEAR,
            ));
        }
        let size = self.session.size();
        let s = |p: [f64; 2]| pos(frame.to_screen(p));
        let corner = |p: [f64; 2]| {
            let q = [
                frame.origin[0] + p[0] * frame.scale,
                frame.origin[1] + p[1] * frame.scale,
            ];
            pos(q)
        };
        let image_rect =
            egui::Rect::from_min_max(corner([0.0, 0.0]), corner([size[0] as f64, size[1] as f64]));
        if let Some(t) = &self.texture {
            painter.image(
                t.id(),
                image_rect,
                egui::Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0)),
                Color32::WHITE,
            );
        }
        let painter = painter.with_clip_rect(image_rect);
        let line: Vec<Pos2> = self
            .session
            .report
            .horizon_line
            .iter()
            .map(|p| s(*p))
            .collect();
        painter.add(egui::Shape::line(line, Stroke::new(2.0, HORIZON_LINE)));
        for (i, m) in self.session.report.marks.iter().enumerate() {
            let dragged = self.drag.filter(|(k, _)| *k == i).map(|(_, at)| at);
            let ring = s(dragged.unwrap_or(m.pixel));
            let color = if m.horizon { HORIZON_MARK } else { TARGET };
            let wide = if self.selected == Some(i) { 3.5 } else { 2.0 };
            if let Some(q) = m.straight {
                let r = egui::Rect::from_center_size(s(q), egui::vec2(9.0, 9.0));
                painter.rect_stroke(r, 0.0, Stroke::new(1.5, color), egui::StrokeKind::Middle);
            }
            if let Some(q) = m.predicted.filter(|_| dragged.is_none()) {
                let c = s(q);
                painter.line_segment([ring, c], Stroke::new(1.0, color));
                let d = 6.0;
                for (a, b) in [
                    (egui::vec2(-d, -d), egui::vec2(d, d)),
                    (egui::vec2(-d, d), egui::vec2(d, -d)),
                ] {
                    painter.line_segment([c + a, c + b], Stroke::new(3.5, DARK));
                    painter.line_segment([c + a, c + b], Stroke::new(1.8, color));
                }
            }
            painter.circle_stroke(ring, RING, Stroke::new(wide + 2.0, DARK));
            painter.circle_stroke(ring, RING, Stroke::new(wide, color));
            painter.text(
                ring + egui::vec2(RING + 4.0, -RING - 2.0),
                egui::Align2::LEFT_BOTTOM,
                &m.name,
                egui::FontId::proportional(13.0),
                Color32::WHITE,
            );
        }
    }

    fn ui(&mut self, ui: &mut egui::Ui) {
        self.widgets.clear();
        egui::Panel::right("controls")
            .default_size(330.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| self.controls(ui));
            });
        egui::CentralPanel::no_frame().show(ui, |ui| self.photo_area(ui));
        let ctx = ui.ctx().clone();
        self.popup(&ctx);
    }

    fn init_graphics(&mut self, event_loop: &ActiveEventLoop) -> Result<Graphics> {
        let attrs = Window::default_attributes()
            .with_title(format!("mirage preview: {}", self.session.path.display()))
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
        let caps = surface.get_capabilities(&gpu.adapter);
        let size = window.inner_size();
        let config = surface_config(&caps, size.width, size.height)?;
        let format = config.format;
        surface.configure(&gpu.device, &config);
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
            egui_state,
            egui_renderer,
        })
    }

    /// The script's events for this frame, as egui's; when the script is
    /// played, the window closes a few frames later.
    fn scripted(&mut self) -> Result<Vec<egui::Event>> {
        // The layout settles in the first frames: the script waits for it.
        if self.frame.is_none() || self.frames_drawn < 3 {
            return Ok(Vec::new());
        }
        let Some(mut player) = self.script.take() else {
            return Ok(Vec::new());
        };
        let events = player.frame(self)?;
        if player.done() {
            self.frames_left = Some(self.frames_left.map_or(3, |n| n.min(3)));
        } else {
            self.script = Some(player);
        }
        let button = |p: [f64; 2], pressed| egui::Event::PointerButton {
            pos: pos(p),
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: egui::Modifiers::NONE,
        };
        Ok(events
            .into_iter()
            .map(|e| match e {
                Event::Move(p) => egui::Event::PointerMoved(pos(p)),
                Event::Press(p) => button(p, true),
                Event::Release(p) => button(p, false),
                Event::Text(t) => egui::Event::Text(t),
            })
            .collect())
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        self.poll_fit();
        let Some(mut g) = self.graphics.take() else {
            return Ok(());
        };
        let mut raw = g.egui_state.take_egui_input(&g.window);
        match self.scripted() {
            Ok(events) => raw.events.extend(events),
            Err(e) => {
                self.graphics = Some(g);
                return Err(e);
            }
        }
        let ctx = self.egui.clone();
        let mut output = ctx.run_ui(raw, |ui| self.ui(ui));
        let platform = std::mem::take(&mut output.platform_output);
        g.egui_state.handle_platform_output(&g.window, platform);
        let ppp = output.pixels_per_point;
        let paint = self
            .egui
            .tessellate(std::mem::take(&mut output.shapes), ppp);
        let mut textures = std::mem::take(&mut output.textures_delta);
        for (id, deltas) in &textures.set {
            for delta in deltas {
                g.egui_renderer
                    .update_texture(&g.gpu.device, &g.gpu.queue, *id, delta);
            }
        }
        let outcome = self.draw(&mut g, &paint, ppp);
        for id in &textures.free {
            g.egui_renderer.free_texture(id);
        }
        textures.clear();
        self.graphics = Some(g);
        outcome?;
        self.frames_drawn += 1;
        if let Some(n) = &mut self.frames_left {
            *n = n.saturating_sub(1);
            if *n == 0 {
                event_loop.exit();
            }
        }
        Ok(())
    }

    /// Draws egui's panels into the surface (and on the last frame into the
    /// screenshot, written as PNG).
    fn draw(&mut self, g: &mut Graphics, paint: &[egui::ClippedPrimitive], ppp: f32) -> Result<()> {
        let frame = match g.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f)
            | wgpu::CurrentSurfaceTexture::Suboptimal(f) => f,
            _ => {
                g.surface.configure(&g.gpu.device, &g.config);
                return Ok(());
            }
        };
        let (fw, fh) = (g.config.width, g.config.height);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [fw, fh],
            pixels_per_point: ppp,
        };
        let last = self.frames_left == Some(1);
        let shot = (last && self.screenshot.is_some()).then(|| {
            g.gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("screenshot"),
                size: wgpu::Extent3d {
                    width: fw,
                    height: fh,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: g.config.format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        });
        let target = frame.texture.create_view(&Default::default());
        let mut encoder = g
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        let mut commands = g.egui_renderer.update_buffers(
            &g.gpu.device,
            &g.gpu.queue,
            &mut encoder,
            paint,
            &screen,
        );
        let shot_view = shot.as_ref().map(|t| t.create_view(&Default::default()));
        for view in std::iter::once(&target).chain(shot_view.as_ref()) {
            let mut pass = encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("photo"),
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
            g.egui_renderer.render(&mut pass, paint, &screen);
        }
        let read = shot
            .as_ref()
            .map(|t| copy_to_buffer(&g.gpu.device, &mut encoder, t, 4));
        commands.push(encoder.finish());
        g.gpu.queue.submit(commands);
        g.gpu.queue.present(frame);
        if let (Some((buffer, row)), Some(path)) = (read, &self.screenshot) {
            let png = read_png(&g.gpu, &buffer, row, fw, fh, g.config.format)?;
            write_atomic(path, &png)?;
        }
        Ok(())
    }
}

impl ApplicationHandler for PhotoApp {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.graphics.is_some() {
            return;
        }
        match self.init_graphics(event_loop) {
            Ok(g) => {
                g.window.request_redraw();
                self.graphics = Some(g);
            }
            Err(e) => {
                self.failure = Some(e);
                event_loop.exit();
            }
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
                    self.failure = Some(e);
                    event_loop.exit();
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
