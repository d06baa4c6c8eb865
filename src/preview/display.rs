//! Showing a traced frame: the display pipeline (tone mapping and sRGB
//! encoding of the linear image into the window), and reading a rendered
//! window back as a PNG (the `--screenshot`).

use super::gpu::Gpu;
use super::shader::DISPLAY_SHADER;
use crate::error::{Error, Result};

/// The display pipeline for a surface `format`, its bind group layout (the
/// uniform rectangle and mode, the linear image) and its uniform buffer.
pub fn display_pipeline(
    device: &wgpu::Device,
    format: wgpu::TextureFormat,
) -> (wgpu::RenderPipeline, wgpu::BindGroupLayout, wgpu::Buffer) {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("display.wgsl"),
        source: wgpu::ShaderSource::Wgsl(DISPLAY_SHADER.into()),
    });
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("display bindings"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            },
        ],
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("display layout"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("display"),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        multiview_mask: None,
        cache: None,
    });
    let uniform = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("display uniform"),
        size: 32,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    (pipeline, layout, uniform)
}

/// Maps a read-back buffer of a `w × h` texture in `format` and encodes it as
/// PNG bytes.
pub fn read_png(
    gpu: &Gpu,
    buffer: &wgpu::Buffer,
    row: u32,
    w: u32,
    h: u32,
    format: wgpu::TextureFormat,
) -> Result<Vec<u8>> {
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    gpu.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| Error::gpu("waiting for the screenshot", e))?;
    rx.recv()
        .map_err(|e| Error::gpu("reading back the screenshot", e))?
        .map_err(|e| Error::gpu("reading back the screenshot", e))?;
    let data = buffer
        .get_mapped_range(..)
        .map_err(|e| Error::gpu("reading back the screenshot", e))?;
    let bgra = matches!(
        format,
        wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
    );
    let mut rgb = Vec::with_capacity((3 * w * h) as usize);
    for y in 0..h {
        let line = &data[(y * row) as usize..(y * row + 4 * w) as usize];
        for px in line.chunks_exact(4) {
            if bgra {
                rgb.extend_from_slice(&[px[2], px[1], px[0]]);
            } else {
                rgb.extend_from_slice(&px[..3]);
            }
        }
    }
    let img = image::RgbImage::from_raw(w, h, rgb)
        .ok_or_else(|| Error::encode("the screenshot", "the image buffer has the wrong size"))?;
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, image::ImageFormat::Png)
        .map_err(|e| Error::encode("the screenshot", e))?;
    Ok(bytes.into_inner())
}
