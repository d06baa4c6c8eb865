//! One frame on the GPU: opening a device, tracing and reading back a frame,
//! and the veiling glare applied to it on the CPU (as `mirage render` does).

use super::gpu::{Gpu, Tracer};
use super::pack::{View, pack};
use crate::error::{Error, Result};
use crate::medium::Medium;
use crate::render::Shading;
use crate::scene::Scene;

/// A GPU, or the error every command reports without one.
pub fn open_gpu() -> Result<Gpu> {
    Gpu::new().map_err(|e| match e {
        Error::Gpu { stage, message } => Error::Gpu {
            stage,
            message: format!(
                "{message} (without a GPU, install Mesa's software Vulkan: apt-get install mesa-vulkan-drivers libvulkan1)"
            ),
        },
        other => other,
    })
}

/// Renders one frame of `scene` seen through `medium` on the GPU and reads it
/// back: linear RGB, row-major, top row first. Ctrl-C stops it between two
/// compute passes ([`Tracer::render_interruptible`]) as
/// [`Error::Interrupted`].
pub fn render_frame(
    gpu: &Gpu,
    scene: &Scene,
    medium: &Medium,
    view: &View,
) -> Result<Vec<[f32; 3]>> {
    let buffers = pack(scene, medium, view).map_err(|e| e.in_file(&scene.source))?;
    let tracer = Tracer::new(gpu, &buffers);
    tracer.render_interruptible(gpu)?;
    let mut pixels = tracer.read_back(gpu)?;
    crate::interrupt::check()?;
    apply_glare(scene, view, &mut pixels);
    Ok(pixels)
}

/// Adds the scene's veiling glare to a lit frame of `view` read back from the
/// GPU (`pixels`: linear RGB, row-major), as `mirage render` does: a
/// post-process on the CPU, for headless frames and for the window once its
/// view has settled. `None` when the scene has no glare or the frame is in
/// albedo.
pub fn apply_glare(
    scene: &Scene,
    view: &View,
    pixels: &mut [[f32; 3]],
) -> Option<crate::render::glare::GlareStats> {
    let g = scene.glare.as_ref()?;
    if view.shading != Shading::Lit {
        return None;
    }
    let (w, h) = (view.camera.width, view.camera.height);
    let settings = g.in_pixels(view.camera.pixel_angle());
    Some(crate::render::glare::apply(pixels, w, h, &settings))
}
