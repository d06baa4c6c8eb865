//! The GPU: adapter and device setup, the tracing compute pipeline and its
//! buffers, and headless frames read back to the CPU.
//!
//! Without a GPU, Mesa's software Vulkan (lavapipe, Debian
//! `mesa-vulkan-drivers libvulkan1`) serves: wgpu picks it as a `Cpu` adapter.

use super::layout::GpuRay;
use super::pack::{SKY_HEIGHT, SKY_WIDTH, SceneBuffers, passes};
use super::shader::{WORKGROUP, trace_shader};
use crate::error::{Error, Result};
use wgpu::util::DeviceExt;

/// A device and its queue.
pub struct Gpu {
    /// The instance (kept for surfaces).
    pub instance: wgpu::Instance,
    /// The adapter.
    pub adapter: wgpu::Adapter,
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
}

/// The window surface's configuration: the first non-sRGB format it offers
/// (egui wants one; the display shader encodes sRGB itself), else its first,
/// at `width` × `height` (at least 1 × 1), vsync, two frames in flight.
pub fn surface_config(
    caps: &wgpu::SurfaceCapabilities,
    width: u32,
    height: u32,
) -> Result<wgpu::SurfaceConfiguration> {
    let format = caps
        .formats
        .iter()
        .copied()
        .find(|f| !f.is_srgb())
        .or_else(|| caps.formats.first().copied())
        .ok_or_else(|| Error::gpu("configuring the surface", "it supports no format"))?;
    Ok(wgpu::SurfaceConfiguration {
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        format,
        width: width.max(1),
        height: height.max(1),
        present_mode: wgpu::PresentMode::AutoVsync,
        desired_maximum_frame_latency: 2,
        alpha_mode: caps.alpha_modes[0],
        view_formats: vec![],
        color_space: wgpu::SurfaceColorSpace::Auto,
    })
}

impl Gpu {
    /// A device on the default adapter (a software one if that is all there
    /// is); `Err` with the reason when there is none.
    pub fn new() -> Result<Gpu> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        Gpu::with_instance(instance, None)
    }

    /// A device on an adapter of `instance` that can present to `surface`.
    pub fn with_instance(
        instance: wgpu::Instance,
        surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Gpu> {
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: surface,
            apply_limit_buckets: false,
        }))
        .map_err(|e| Error::gpu("requesting an adapter", e))?;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("mirage preview"),
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| Error::gpu("opening the device", e))?;
        Ok(Gpu {
            instance,
            adapter,
            device,
            queue,
        })
    }

    /// The adapter's name and kind, e.g. `llvmpipe (LLVM 15.0.6, 256 bits) (Cpu, Vulkan)`.
    pub fn describe(&self) -> String {
        let i = self.adapter.get_info();
        format!("{} ({:?}, {:?})", i.name, i.device_type, i.backend)
    }
}

/// The tracing pipeline with the scene's buffers and the output image.
pub struct Tracer {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    hotspots: wgpu::Buffer,
    objects: wgpu::Buffer,
    nodes: wgpu::Buffer,
    profile: wgpu::Buffer,
    cells: wgpu::Buffer,
    near: wgpu::Buffer,
    stars: wgpu::Buffer,
    air_table: wgpu::Buffer,
    /// The rays of a band's pixels between passes ([`GpuRay`]).
    rays: wgpu::Buffer,
    /// Per band `[first row, rows, 0, 0]`, one at each multiple of
    /// `band_stride` (bound at a dynamic offset).
    bands: wgpu::Buffer,
    band_stride: u32,
    band_count: u32,
    band_rows: u32,
    band_bytes: u64,
    sky: wgpu::Texture,
    output: wgpu::Texture,
    /// Per pixel, the sum of its samples while the window accumulates
    /// ([`super::accumulate`]); 16 bytes when the image's would not fit in
    /// one storage binding ([`Tracer::accumulates`]).
    accum: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    width: u32,
    height: u32,
    /// Passes a frame ([`passes`]).
    passes: u32,
}

/// Records the copy of `texture` (`bytes_per_texel` bytes a texel) into a new
/// read-back buffer; returns it with its row pitch (rows are padded to
/// wgpu's copy alignment).
pub fn copy_to_buffer(
    device: &wgpu::Device,
    encoder: &mut wgpu::CommandEncoder,
    texture: &wgpu::Texture,
    bytes_per_texel: u32,
) -> (wgpu::Buffer, u32) {
    let (w, h) = (texture.width(), texture.height());
    let row = (bytes_per_texel * w).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
        * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("read-back"),
        size: (row * h) as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(h),
            },
        },
        wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
    );
    (buffer, row)
}

fn storage_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    storage_entry_with(binding, true)
}

/// A compute shader's storage buffer the shader writes (the image, the sums).
fn writable_storage_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    storage_entry_with(binding, false)
}

fn storage_entry_with(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn storage_buffer(device: &wgpu::Device, label: &str, bytes: &[u8]) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
    })
}

/// The most bytes of ray states a band takes (a quarter of a GiB; devices
/// may bind less: lavapipe 128 MiB, 1.4 million pixels).
pub const BAND_BYTES: u64 = 1 << 28;

/// The bands of an image `width × height`: rows per band (each band's rays
/// in one storage binding), the band count, and the buffers: the rays of a
/// band, and the bands' `[first row, rows, 0, 0]` at `stride` bytes apart.
fn band_buffers(
    device: &wgpu::Device,
    width: u32,
    height: u32,
    band_bytes: u64,
) -> (u32, u32, wgpu::Buffer, wgpu::Buffer, u32) {
    let limits = device.limits();
    let ray = std::mem::size_of::<GpuRay>() as u64;
    let bytes = band_bytes
        .min(limits.max_storage_buffer_binding_size)
        .min(limits.max_buffer_size);
    let rows = (bytes / (ray * width as u64)).clamp(1, height as u64) as u32;
    let count = height.div_ceil(rows);
    let rays = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("rays"),
        size: width as u64 * rows as u64 * ray,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let stride = limits.min_uniform_buffer_offset_alignment.max(16);
    let mut table = vec![0u32; (count * stride / 4) as usize];
    for b in 0..count {
        let at = (b * stride / 4) as usize;
        table[at] = b * rows;
        table[at + 1] = rows;
    }
    let bands = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("bands"),
        contents: bytemuck::cast_slice(&table),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    (rows, count, rays, bands, stride)
}

/// The accumulation buffer of an image `width × height`: an RGBA f32 sum per
/// pixel, or 16 bytes (nothing accumulates) when that is more than one
/// storage binding may hold.
fn accum_buffer(device: &wgpu::Device, width: u32, height: u32) -> wgpu::Buffer {
    let limits = device.limits();
    let bytes = 16 * width as u64 * height as u64;
    let fits = bytes
        <= limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("accumulated samples"),
        size: if fits { bytes } else { 16 },
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    })
}

fn output_texture(device: &wgpu::Device, width: u32, height: u32) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some("linear image"),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba32Float,
        usage: wgpu::TextureUsages::STORAGE_BINDING
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    })
}

impl Tracer {
    /// Compiles the shader and uploads `scene`.
    pub fn new(gpu: &Gpu, scene: &SceneBuffers) -> Tracer {
        Tracer::with_band_bytes(gpu, scene, BAND_BYTES)
    }

    /// [`Tracer::new`], tracing the image in bands whose rays take at most
    /// `band_bytes` (at least one row a band; the tests cut small frames).
    pub fn with_band_bytes(gpu: &Gpu, scene: &SceneBuffers, band_bytes: u64) -> Tracer {
        let device = &gpu.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("trace.wgsl"),
            source: wgpu::ShaderSource::Wgsl(trace_shader().into()),
        });
        let mut entries = vec![wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        }];
        entries.extend((1..=4).chain(7..=10).map(storage_entry));
        entries.extend([11, 13].map(writable_storage_entry));
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: 12,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: true,
                min_binding_size: wgpu::BufferSize::new(16),
            },
            count: None,
        });
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: 5,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        });
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: 6,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::WriteOnly,
                format: wgpu::TextureFormat::Rgba32Float,
                view_dimension: wgpu::TextureViewDimension::D2,
            },
            count: None,
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("trace bindings"),
            entries: &entries,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("trace layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("trace"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
        let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("params"),
            contents: bytemuck::bytes_of(&scene.params),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let sky = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("sky table"),
            size: wgpu::Extent3d {
                width: SKY_WIDTH,
                height: SKY_HEIGHT,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let (width, height) = (scene.params.size[0].max(1), scene.params.size[1].max(1));
        let output = output_texture(device, width, height);
        let accum = accum_buffer(device, width, height);
        let (band_rows, band_count, rays, bands, band_stride) =
            band_buffers(device, width, height, band_bytes);
        let hotspots = storage_buffer(device, "hot spots", bytemuck::cast_slice(&scene.hotspots));
        let objects = storage_buffer(device, "objects", bytemuck::cast_slice(&scene.objects));
        let nodes = storage_buffer(device, "nodes", bytemuck::cast_slice(&scene.nodes));
        let profile = storage_buffer(device, "profile", bytemuck::cast_slice(&scene.profile));
        let cells = storage_buffer(device, "grid cells", bytemuck::cast_slice(&scene.cells));
        let near = storage_buffer(device, "near lists", bytemuck::cast_slice(&scene.near));
        let stars = storage_buffer(device, "star cells", bytemuck::cast_slice(&scene.stars));
        let air_table = storage_buffer(device, "air table", bytemuck::cast_slice(&scene.air_table));
        let bind_group = Self::bind(
            device,
            &layout,
            [
                &params, &hotspots, &objects, &nodes, &profile, &cells, &near, &stars, &air_table,
                &rays,
            ],
            &bands,
            &accum,
            &sky,
            &output,
        );
        let tracer = Tracer {
            pipeline,
            layout,
            params,
            hotspots,
            objects,
            nodes,
            profile,
            cells,
            near,
            stars,
            air_table,
            rays,
            bands,
            band_stride,
            band_count,
            band_rows,
            band_bytes,
            sky,
            output,
            accum,
            bind_group,
            width,
            height,
            passes: passes(&scene.params),
        };
        tracer.write_sky(gpu, scene);
        tracer
    }

    /// The bind group: `buffers` are the uniform block, then the storage
    /// buffers at bindings 1–4 and 7–11; `bands` one band's row at binding
    /// 12; `accum` the accumulation buffer at 13.
    fn bind(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        buffers: [&wgpu::Buffer; 10],
        bands: &wgpu::Buffer,
        accum: &wgpu::Buffer,
        sky: &wgpu::Texture,
        output: &wgpu::Texture,
    ) -> wgpu::BindGroup {
        let sky_view = sky.create_view(&Default::default());
        let out_view = output.create_view(&Default::default());
        let mut entries: Vec<wgpu::BindGroupEntry<'_>> = buffers
            .iter()
            .zip([0, 1, 2, 3, 4, 7, 8, 9, 10, 11])
            .map(|(b, binding)| wgpu::BindGroupEntry {
                binding,
                resource: b.as_entire_binding(),
            })
            .collect();
        entries.push(wgpu::BindGroupEntry {
            binding: 12,
            resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer: bands,
                offset: 0,
                size: wgpu::BufferSize::new(16),
            }),
        });
        entries.push(wgpu::BindGroupEntry {
            binding: 13,
            resource: accum.as_entire_binding(),
        });
        entries.push(wgpu::BindGroupEntry {
            binding: 5,
            resource: wgpu::BindingResource::TextureView(&sky_view),
        });
        entries.push(wgpu::BindGroupEntry {
            binding: 6,
            resource: wgpu::BindingResource::TextureView(&out_view),
        });
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("trace bind group"),
            layout,
            entries: &entries,
        })
    }

    fn write_sky(&self, gpu: &Gpu, scene: &SceneBuffers) {
        gpu.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &self.sky,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(&scene.sky),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(16 * SKY_WIDTH),
                rows_per_image: Some(SKY_HEIGHT),
            },
            wgpu::Extent3d {
                width: SKY_WIDTH,
                height: SKY_HEIGHT,
                depth_or_array_layers: 1,
            },
        );
    }

    /// Uploads a changed scene: the uniform block always, the storage buffers
    /// (recreated when they grew), and the output image when the size changed.
    pub fn update(&mut self, gpu: &Gpu, scene: &SceneBuffers) {
        let device = &gpu.device;
        let queue = &gpu.queue;
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&scene.params));
        let mut rebind = false;
        let mut put = |buf: &mut wgpu::Buffer, label: &str, bytes: &[u8]| {
            if (bytes.len() as u64) <= buf.size() {
                queue.write_buffer(buf, 0, bytes);
            } else {
                *buf = storage_buffer(device, label, bytes);
                rebind = true;
            }
        };
        put(
            &mut self.hotspots,
            "hot spots",
            bytemuck::cast_slice(&scene.hotspots),
        );
        put(
            &mut self.objects,
            "objects",
            bytemuck::cast_slice(&scene.objects),
        );
        put(&mut self.nodes, "nodes", bytemuck::cast_slice(&scene.nodes));
        put(
            &mut self.profile,
            "profile",
            bytemuck::cast_slice(&scene.profile),
        );
        put(
            &mut self.air_table,
            "air table",
            bytemuck::cast_slice(&scene.air_table),
        );
        let (w, h) = (scene.params.size[0].max(1), scene.params.size[1].max(1));
        self.passes = passes(&scene.params);
        if (w, h) != (self.width, self.height) {
            self.output = output_texture(device, w, h);
            self.accum = accum_buffer(device, w, h);
            (
                self.band_rows,
                self.band_count,
                self.rays,
                self.bands,
                self.band_stride,
            ) = band_buffers(device, w, h, self.band_bytes);
            self.width = w;
            self.height = h;
            rebind = true;
        }
        if rebind {
            self.bind_group = Self::bind(
                device,
                &self.layout,
                [
                    &self.params,
                    &self.hotspots,
                    &self.objects,
                    &self.nodes,
                    &self.profile,
                    &self.cells,
                    &self.near,
                    &self.stars,
                    &self.air_table,
                    &self.rays,
                ],
                &self.bands,
                &self.accum,
                &self.sky,
                &self.output,
            );
        }
    }

    /// Uploads only the uniform block (camera moves, toggles).
    pub fn update_params(&mut self, gpu: &Gpu, scene: &SceneBuffers) {
        gpu.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&scene.params));
        self.passes = passes(&scene.params);
    }

    /// Records the tracing of a frame, band by band (one band unless the
    /// image's rays outgrow one storage binding): the band's rays cleared,
    /// then its passes (see [`super::pack`](mod@super::pack)), one dispatch
    /// each; wgpu puts a barrier between dispatches that write the same
    /// storage buffer.
    pub fn dispatch(&self, encoder: &mut wgpu::CommandEncoder) {
        for b in 0..self.band_count {
            encoder.clear_buffer(&self.rays, 0, None);
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("trace"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.bind_group, &[b * self.band_stride]);
            for _ in 0..self.passes {
                pass.dispatch_workgroups(
                    self.width.div_ceil(WORKGROUP),
                    self.band_rows.div_ceil(WORKGROUP),
                    1,
                );
            }
        }
    }

    /// Whether the accumulation buffer holds the image (else frames cannot
    /// add to the samples of the frames before: [`super::accumulate`]).
    pub fn accumulates(&self) -> bool {
        self.accum.size() >= 16 * self.width as u64 * self.height as u64
    }

    /// Passes a band of a frame takes.
    pub fn passes(&self) -> u32 {
        self.passes
    }

    /// The bands a frame is traced in.
    pub fn bands(&self) -> u32 {
        self.band_count
    }

    /// The linear image (what the display pass and read-back use).
    pub fn output(&self) -> &wgpu::Texture {
        &self.output
    }

    /// Traces one frame and waits for it.
    pub fn render(&self, gpu: &Gpu) {
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        self.dispatch(&mut encoder);
        gpu.queue.submit([encoder.finish()]);
        let _ = gpu.device.poll(wgpu::PollType::wait_indefinitely());
    }

    /// Traces one frame as [`Tracer::render`] does, but one submission per
    /// compute pass, waiting for each: a cancellation point
    /// ([`crate::interrupt`]) between passes, so that Ctrl-C stops a
    /// headless frame within a pass (one pass marches every pixel's ray on by
    /// a bounded number of iterations) rather than at the end of the frame.
    /// The passes are those of [`Tracer::dispatch`], in the same order on the
    /// same buffers: the frame is the same.
    pub fn render_interruptible(&self, gpu: &Gpu) -> Result<()> {
        for b in 0..self.band_count {
            for k in 0..self.passes {
                crate::interrupt::check()?;
                let mut encoder = gpu
                    .device
                    .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
                if k == 0 {
                    encoder.clear_buffer(&self.rays, 0, None);
                }
                {
                    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some("trace"),
                        timestamp_writes: None,
                    });
                    pass.set_pipeline(&self.pipeline);
                    pass.set_bind_group(0, &self.bind_group, &[b * self.band_stride]);
                    pass.dispatch_workgroups(
                        self.width.div_ceil(WORKGROUP),
                        self.band_rows.div_ceil(WORKGROUP),
                        1,
                    );
                }
                gpu.queue.submit([encoder.finish()]);
                gpu.device
                    .poll(wgpu::PollType::wait_indefinitely())
                    .map_err(|e| Error::gpu("waiting for a pass", e))?;
            }
        }
        crate::interrupt::check()
    }

    /// Traces one frame and reads it back: linear RGB, row-major, top row first.
    pub fn render_to_cpu(&self, gpu: &Gpu) -> Result<Vec<[f32; 3]>> {
        self.read(gpu, true)
    }

    /// Reads back the frame last traced, without tracing again.
    pub fn read_back(&self, gpu: &Gpu) -> Result<Vec<[f32; 3]>> {
        self.read(gpu, false)
    }

    /// Replaces the linear image with `pixels` (linear RGB, row-major, top row
    /// first, the image's size): how a frame post-processed on the CPU (the
    /// glare) gets back to the display pass.
    pub fn upload(&self, gpu: &Gpu, pixels: &[[f32; 3]]) {
        let (w, h) = (self.width, self.height);
        assert_eq!(pixels.len(), (w * h) as usize, "upload of the wrong size");
        let rgba: Vec<[f32; 4]> = pixels.iter().map(|p| [p[0], p[1], p[2], 1.0]).collect();
        gpu.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &self.output,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(&rgba),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(16 * w),
                rows_per_image: Some(h),
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
    }

    /// Reads the linear image back, after tracing it first if `trace`.
    fn read(&self, gpu: &Gpu, trace: bool) -> Result<Vec<[f32; 3]>> {
        let (w, h) = (self.width, self.height);
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        if trace {
            self.dispatch(&mut encoder);
        }
        let (staging, row) = copy_to_buffer(&gpu.device, &mut encoder, &self.output, 16);
        gpu.queue.submit([encoder.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        staging.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        gpu.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::gpu("waiting for the frame", e))?;
        rx.recv()
            .map_err(|e| Error::gpu("reading back the frame", e))?
            .map_err(|e| Error::gpu("reading back the frame", e))?;
        let data = staging
            .get_mapped_range(..)
            .map_err(|e| Error::gpu("reading back the frame", e))?;
        let mut out = Vec::with_capacity((w * h) as usize);
        for y in 0..h {
            let line: &[f32] =
                bytemuck::cast_slice(&data[(y * row) as usize..(y * row + 16 * w) as usize]);
            for x in 0..w as usize {
                out.push([line[4 * x], line[4 * x + 1], line[4 * x + 2]]);
            }
        }
        Ok(out)
    }
}
