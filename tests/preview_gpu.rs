//! The GPU previewer against the CPU renderer, and its command line.
//!
//! These tests need a GPU adapter; Mesa's software Vulkan (lavapipe, Debian
//! `mesa-vulkan-drivers libvulkan1`) is one. Without an adapter they print a
//! loud SKIPPED line and pass, unless `MIRAGE_REQUIRE_GPU=1` (set by `.ci/run`
//! after installing lavapipe), where they fail.
#![cfg(feature = "preview")]

use mirage::preview::gpu::Gpu;
use mirage::preview::pack::View;
use mirage::preview::render_frame;
use mirage::render::output::ToneMap;
use mirage::render::{RenderOptions, Renderer, Shading};
use mirage::scene::Scene;
use std::path::Path;
use std::process::Command;

/// Writes to the process's stderr directly, past the test harness's capture,
/// so that a skip is seen in a plain `cargo test`.
fn loud(message: &str) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr(), "\n{message}\n");
}

fn require_gpu() -> bool {
    std::env::var("MIRAGE_REQUIRE_GPU").is_ok_and(|v| v == "1")
}

/// The GPU, or `None` after a loud message (a failure when one is required).
fn gpu(test: &str) -> Option<Gpu> {
    match Gpu::new() {
        Ok(g) => Some(g),
        Err(e) => {
            if require_gpu() {
                panic!("{test}: MIRAGE_REQUIRE_GPU=1 but {e}");
            }
            loud(&format!(
                "*** SKIPPED {test}: {e}; install mesa-vulkan-drivers libvulkan1 for software Vulkan, or set MIRAGE_REQUIRE_GPU=1 to fail instead ***"
            ));
            None
        }
    }
}

fn scene(name: &str) -> Scene {
    Scene::load(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("problems/scenes")
            .join(name),
    )
    .unwrap()
}

/// Mean |difference| over channels, and the share of pixels whose largest
/// channel difference exceeds 0.05, of two images in display values (the
/// PNG's tone mapping, in [0, 1]).
fn compare(a: &[[f32; 3]], b: &[[f32; 3]], tone: ToneMap) -> (f64, f64) {
    assert_eq!(a.len(), b.len());
    let mut sum = 0.0;
    let mut bad = 0usize;
    for (p, q) in a.iter().zip(b) {
        let mut worst = 0.0f64;
        for c in 0..3 {
            let d = (tone.apply(p[c]) as f64 - tone.apply(q[c]) as f64).abs() / 255.0;
            sum += d;
            worst = worst.max(d);
        }
        if worst > 0.05 {
            bad += 1;
        }
    }
    (sum / (3 * a.len()) as f64, bad as f64 / a.len() as f64)
}

fn parity(test: &str, file: &str, width: u32, height: u32) {
    parity_of(test, file, scene(file), width, height);
}

/// `file`'s scene with its medium replaced by `medium` (JSON).
fn with_medium(file: &str, medium: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("problems/scenes")
        .join(file);
    let mut value: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    value["medium"] = serde_json::from_str(medium).unwrap();
    Scene::parse(&value.to_string(), &path).unwrap()
}

/// With `MIRAGE_PARITY_DUMP=DIR`, writes the CPU and GPU images of a parity
/// test and their difference (×8) as PNGs into DIR, to see where they differ.
fn dump(
    test: &str,
    shading: Shading,
    width: u32,
    height: u32,
    cpu: &[[f32; 3]],
    gpu: &[[f32; 3]],
    tone: ToneMap,
) {
    let Ok(dir) = std::env::var("MIRAGE_PARITY_DUMP") else {
        return;
    };
    let png = |name: &str, f: &dyn Fn(usize, usize) -> u8| {
        let img = image::RgbImage::from_fn(width, height, |x, y| {
            let i = (y * width + x) as usize;
            image::Rgb([f(i, 0), f(i, 1), f(i, 2)])
        });
        let path = Path::new(&dir).join(format!("{test}-{shading:?}-{name}.png"));
        img.save(&path).unwrap();
    };
    png("cpu", &|i, c| tone.apply(cpu[i][c]));
    png("gpu", &|i, c| tone.apply(gpu[i][c]));
    png("diff", &|i, c| {
        let d = (tone.apply(cpu[i][c]) as i32 - tone.apply(gpu[i][c]) as i32).unsigned_abs();
        (d * 8).min(255) as u8
    });
}

fn parity_of(test: &str, file: &str, scene: Scene, width: u32, height: u32) {
    let Some(gpu) = gpu(test) else { return };
    eprintln!("{test}: adapter {}", gpu.describe());
    for shading in [Shading::Albedo, Shading::Lit] {
        let options = RenderOptions {
            shading,
            width: Some(width),
            height: Some(height),
            ..RenderOptions::default()
        };
        let cpu = Renderer::new(&scene, &options).render();
        let view = View::of_scene(&scene, &options, width, height);
        let gpu_pixels = render_frame(&gpu, &scene, &scene.medium, &view).unwrap();
        let tone = match shading {
            Shading::Lit => ToneMap::Filmic { exposure: 1.0 },
            Shading::Albedo => ToneMap::Clamp,
        };
        let (mean, share) = compare(&cpu.pixels, &gpu_pixels, tone);
        dump(test, shading, width, height, &cpu.pixels, &gpu_pixels, tone);
        eprintln!(
            "{test}: {file} {shading:?} {width}×{height}: mean |GPU − CPU| = {:.3}/255, pixels off by > 0.05: {:.3} %",
            mean * 255.0,
            share * 100.0
        );
        assert!(
            mean < 1.0 / 255.0,
            "{file} {shading:?}: mean difference {:.3}/255",
            mean * 255.0
        );
        assert!(
            share < 0.01,
            "{file} {shading:?}: {:.3} % of pixels differ by more than 0.05",
            share * 100.0
        );
    }
}

#[test]
fn gpu_matches_cpu_on_the_stratified_sea() {
    parity(
        "gpu_matches_cpu_on_the_stratified_sea",
        "sea.json",
        320,
        180,
    );
}

#[test]
fn gpu_matches_cpu_on_the_hot_road() {
    parity("gpu_matches_cpu_on_the_hot_road", "road.json", 320, 180);
}

#[test]
fn gpu_matches_cpu_on_the_hot_road_in_real_air() {
    let scene = with_medium(
        "road.json",
        r#"{"air": {"temperature": {"base": 30.0, "lapse": -0.0065}, "humidity": 0.3},
            "hotspots": [{"x": 0.0, "z": 160.0, "radius": 110.0, "edge": 0.5, "delta": 30.0, "scale_height": 0.35}]}"#,
    );
    parity_of(
        "gpu_matches_cpu_on_the_hot_road_in_real_air",
        "road.json (real air)",
        scene,
        320,
        180,
    );
}

#[test]
fn gpu_matches_cpu_on_stratified_real_air() {
    // Ciddor, a warm surface layer and an inversion aloft, over the sea scene.
    let scene = with_medium("sea.json", STRATIFIED_AIR);
    parity_of(
        "gpu_matches_cpu_on_stratified_real_air",
        "sea.json (real air)",
        scene,
        160,
        90,
    );
}

/// The stratified real air of `gpu_matches_cpu_on_stratified_real_air`.
const STRATIFIED_AIR: &str = r#"{"air": {"temperature": {"base": 10.0, "lapse": -0.0065,
      "exponential": {"delta": 3.15, "scale_height": 0.05},
      "inversion": {"delta": 4.0, "height": 12.0, "thickness": 1.5}},
    "humidity": 0.6, "refractivity": "ciddor"}}"#;

#[test]
fn gpu_matches_cpu_in_a_weak_duct_of_real_air() {
    // Gladstone–Dale air at constant pressure with a 4 K inversion: a duct
    // of δ 3.9e-6 whose trapped rays run up to 25 km before they meet the
    // sea (the GPU once gave them up half-way, on lavapipe).
    let scene = with_medium(
        "sea.json",
        r#"{"air": {"temperature": {"base": 10.0,
              "inversion": {"delta": 4.0, "height": 12.0, "thickness": 1.5}},
            "hydrostatic": false, "refractivity": {"gladstone_dale": 0.079386}}}"#,
    );
    parity_of(
        "gpu_matches_cpu_in_a_weak_duct_of_real_air",
        "sea.json (weak duct)",
        scene,
        160,
        90,
    );
}

#[test]
fn gpu_matches_cpu_on_the_stratified_sea_at_a_5_m_step() {
    // A quarter of the scene's own step: four times the RK4 steps a ray.
    let mut scene = scene("sea.json");
    scene.step = 5.0;
    parity_of(
        "gpu_matches_cpu_on_the_stratified_sea_at_a_5_m_step",
        "sea.json (5 m step)",
        scene,
        160,
        90,
    );
}

#[test]
fn gpu_matches_cpu_on_stratified_real_air_at_a_5_m_step() {
    // The smallest frame of these tests: lavapipe takes a minute for a
    // 160×90 frame of this air at 5 m steps (rays up to 30 km).
    let mut scene = with_medium("sea.json", STRATIFIED_AIR);
    scene.step = 5.0;
    parity_of(
        "gpu_matches_cpu_on_stratified_real_air_at_a_5_m_step",
        "sea.json (real air, 5 m step)",
        scene,
        96,
        54,
    );
}

#[test]
fn gpu_frames_do_not_depend_on_their_passes_and_bands() {
    // The frame traced in passes of 7 march iterations equals the one in
    // passes of the default's: a ray resumed in a later pass takes bit for
    // bit the steps of one traced at once, and no pass runs into llvmpipe's
    // limit of 65535 loop iterations (which would end some rays early). So
    // does the frame traced in bands of 10 rows.
    let test = "gpu_frames_do_not_depend_on_their_passes_and_bands";
    let Some(gpu) = gpu(test) else { return };
    let scene = with_medium("sea.json", STRATIFIED_AIR);
    let options = RenderOptions {
        samples_per_pixel: Some(2),
        ..RenderOptions::default()
    };
    let view = View::of_scene(&scene, &options, 64, 36);
    let mut buffers = mirage::preview::pack::pack(&scene, &scene.medium, &view).unwrap();
    use mirage::preview::gpu::{BAND_BYTES, Tracer};
    let frame = |buffers: &mirage::preview::pack::SceneBuffers, band_bytes: u64| {
        let tracer = Tracer::with_band_bytes(&gpu, buffers, band_bytes);
        let pixels = tracer.render_to_cpu(&gpu).unwrap();
        (pixels, tracer.passes(), tracer.bands())
    };
    let (whole, passes, one) = frame(&buffers, BAND_BYTES);
    let row = 64 * std::mem::size_of::<mirage::preview::layout::GpuRay>() as u64;
    let (banded, _, bands) = frame(&buffers, 10 * row);
    buffers.params.march[1] = 7;
    let (cut, many, _) = frame(&buffers, BAND_BYTES);
    let differ = |other: &[[f32; 3]]| whole.iter().zip(other).filter(|(a, b)| a != b).count();
    let (by_passes, by_bands) = (differ(&cut), differ(&banded));
    eprintln!(
        "{test}: {passes} and {many} passes: {by_passes} pixels differ; {one} and {bands} bands: {by_bands}"
    );
    assert!(many > 10 * passes && one == 1 && bands == 4);
    assert_eq!(by_passes, 0, "{by_passes} pixels differ");
    assert_eq!(by_bands, 0, "{by_bands} pixels differ");
}

#[test]
fn gpu_draws_the_same_stars_as_the_cpu_at_night() {
    let test = "gpu_draws_the_same_stars_as_the_cpu_at_night";
    let Some(gpu) = gpu(test) else { return };
    // The physical sky 25° after sunset, looking 17° up with a 20° field of
    // view; the stars are brightened so that the tone map shows them.
    let text = r#"{
      "name": "night",
      "camera": {"position": [0, 2, 0], "look_at": [0, 300, 1000], "vertical_fov": 20,
                 "width": 160, "height": 90},
      "medium": {"scale": 0.02, "background": {"n": 1.0, "a": 150.0}},
      "ground": {"albedo": [0.1, 0.1, 0.1]},
      "sun": {"elevation": -25, "azimuth": 40},
      "sky": {"type": "physical", "star_brightness": 1e5}
    }"#;
    let scene = Scene::parse(text, Path::new("night.json")).unwrap();
    let options = RenderOptions::default();
    let cpu = Renderer::new(&scene, &options).render();
    let view = View::of_scene(&scene, &options, 160, 90);
    let gpu_pixels = render_frame(&gpu, &scene, &scene.medium, &view).unwrap();
    let tone = ToneMap::Filmic { exposure: 1.0 };
    let stars = |px: &[[f32; 3]]| {
        px.iter()
            .filter(|p| p.iter().any(|&c| tone.apply(c) > 40))
            .count()
    };
    let (on_cpu, on_gpu) = (stars(&cpu.pixels), stars(&gpu_pixels));
    let (mean, share) = compare(&cpu.pixels, &gpu_pixels, tone);
    eprintln!(
        "{test}: star pixels CPU {on_cpu}, GPU {on_gpu}; mean |GPU − CPU| = {:.3}/255, pixels off by > 0.05: {:.3} %",
        mean * 255.0,
        share * 100.0
    );
    assert!(on_cpu > 50, "only {on_cpu} star pixels on the CPU");
    assert!(
        on_gpu.abs_diff(on_cpu) * 20 <= on_cpu,
        "{on_gpu} vs {on_cpu}"
    );
    assert!(
        mean < 1.0 / 255.0,
        "mean difference {:.3}/255",
        mean * 255.0
    );
    assert!(share < 0.01, "{:.3} % of pixels differ", share * 100.0);
}

#[test]
fn straight_rays_differ_from_curved_ones_on_the_road() {
    // The straight-rays toggle must change the picture where the mirage is.
    let Some(gpu) = gpu("straight_rays_differ_from_curved_ones_on_the_road") else {
        return;
    };
    let scene = scene("road.json");
    let mut options = RenderOptions {
        shading: Shading::Albedo,
        ..RenderOptions::default()
    };
    let curved = render_frame(
        &gpu,
        &scene,
        &scene.medium,
        &View::of_scene(&scene, &options, 160, 90),
    )
    .unwrap();
    options.straight = true;
    let straight = render_frame(
        &gpu,
        &scene,
        &scene.medium,
        &View::of_scene(&scene, &options, 160, 90),
    )
    .unwrap();
    let (_, share) = compare(&curved, &straight, ToneMap::Clamp);
    assert!(
        share > 0.02,
        "only {:.2} % of pixels changed",
        share * 100.0
    );
}

fn mirage_bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mirage"))
}

#[test]
fn headless_preview_of_a_problem_writes_a_png() {
    headless_preview_writes_a_png(
        "headless_preview_of_a_problem_writes_a_png",
        "problems/hot-road.json",
    );
}

#[test]
fn headless_preview_of_real_air_writes_a_png() {
    headless_preview_writes_a_png(
        "headless_preview_of_real_air_writes_a_png",
        "problems/hot-road-kelvin.json",
    );
}

fn headless_preview_writes_a_png(test: &str, problem: &str) {
    let Some(_gpu) = gpu(test) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("frame.png");
    let problem = Path::new(env!("CARGO_MANIFEST_DIR")).join(problem);
    let run = mirage_bin()
        .args([
            "preview",
            "--headless",
            "--width",
            "96",
            "--height",
            "54",
            "-o",
        ])
        .arg(&out)
        .arg(&problem)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let img = image::open(&out).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (96, 54));
    // Sky at the top, ground at the bottom: the picture is not uniform.
    let top = img.get_pixel(48, 2);
    let bottom = img.get_pixel(48, 52);
    assert_ne!(top, bottom);
}

#[test]
fn bad_input_is_reported_with_exit_code_2() {
    // No GPU needed: the input is checked before one is opened.
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.json");
    std::fs::write(
        &bad,
        r#"{"camera": {"position": [0, 1, 0], "look_at": [0, 1, 10], "vertical_fov": 0, "width": 10, "height": 10}, "medium": {}}"#,
    )
    .unwrap();
    let out = dir.path().join("frame.png");
    let run = mirage_bin()
        .args(["preview", "--headless", "-o"])
        .arg(&out)
        .arg(&bad)
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(2));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(
        err.contains("bad.json") && err.contains("camera.vertical_fov"),
        "{err}"
    );
    assert!(!out.exists());

    let neither = dir.path().join("neither.json");
    std::fs::write(&neither, r#"{"name": "x"}"#).unwrap();
    let run = mirage_bin()
        .args(["preview", "--headless", "-o"])
        .arg(&out)
        .arg(&neither)
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&run.stderr).contains("neither.json"));
}

// ------------------------------------------------------------------ probes
//
// The tracing shader's own functions run on single points and rays through
// an extra entry point appended to its source, so that the tests can compare
// them with the CPU's one by one.

/// WGSL appended to the tracing shader: `probe_medium` writes `medium(p)`
/// (∇δ, δ) for each input point.
const PROBE_WGSL: &str = r#"
@group(0) @binding(12) var<storage, read> probe_in: array<vec4<f32>>;
@group(0) @binding(13) var<storage, read_write> probe_out: array<vec4<f32>>;

@compute @workgroup_size(64)
fn probe_medium(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= arrayLength(&probe_in)) { return; }
    probe_out[i] = medium(probe_in[i].xyz);
}
"#;

/// Runs the probe `entry` over `input` with the scene's buffers bound as the
/// tracer binds them; returns `rows` output rows.
fn probe(
    gpu: &Gpu,
    buffers: &mirage::preview::pack::SceneBuffers,
    entry: &str,
    input: &[[f32; 4]],
    rows: usize,
    threads: u32,
) -> Vec<[f32; 4]> {
    use wgpu::util::DeviceExt;
    let device = &gpu.device;
    let source = mirage::preview::shader::trace_shader() + PROBE_WGSL;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("probe"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let storage = |binding: u32, read_only: bool| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
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
    let read = [1u32, 2, 3, 4, 7, 8, 10, 12];
    entries.extend(read.iter().map(|&b| storage(b, true)));
    entries.push(storage(13, false));
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("probe bindings"),
        entries: &entries,
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("probe layout"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("probe"),
        layout: Some(&pipeline_layout),
        module: &module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    });
    let make = |label: &str, bytes: &[u8], usage: wgpu::BufferUsages| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytes,
            usage,
        })
    };
    let s = wgpu::BufferUsages::STORAGE;
    let params = make(
        "params",
        bytemuck::bytes_of(&buffers.params),
        wgpu::BufferUsages::UNIFORM,
    );
    let bound = [
        make("hot spots", bytemuck::cast_slice(&buffers.hotspots), s),
        make("objects", bytemuck::cast_slice(&buffers.objects), s),
        make("nodes", bytemuck::cast_slice(&buffers.nodes), s),
        make("profile", bytemuck::cast_slice(&buffers.profile), s),
        make("cells", bytemuck::cast_slice(&buffers.cells), s),
        make("near", bytemuck::cast_slice(&buffers.near), s),
        make("air table", bytemuck::cast_slice(&buffers.air_table), s),
        make("probe in", bytemuck::cast_slice(input), s),
    ];
    let out_size = (rows * 16) as u64;
    let output = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("probe out"),
        size: out_size,
        usage: s | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("probe staging"),
        size: out_size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut group = vec![wgpu::BindGroupEntry {
        binding: 0,
        resource: params.as_entire_binding(),
    }];
    group.extend(
        read.iter()
            .zip(&bound)
            .map(|(&binding, b)| wgpu::BindGroupEntry {
                binding,
                resource: b.as_entire_binding(),
            }),
    );
    group.push(wgpu::BindGroupEntry {
        binding: 13,
        resource: output.as_entire_binding(),
    });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("probe bind group"),
        layout: &layout,
        entries: &group,
    });
    let mut encoder =
        device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("probe"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(threads.div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&output, 0, &staging, 0, out_size);
    gpu.queue.submit([encoder.finish()]);
    let (tx, rx) = std::sync::mpsc::channel();
    staging.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    gpu.device
        .poll(wgpu::PollType::wait_indefinitely())
        .unwrap();
    rx.recv().unwrap().unwrap();
    let data = staging.get_mapped_range(..).unwrap();
    bytemuck::cast_slice(&data[..]).to_vec()
}

#[test]
fn gpu_evaluates_real_air_as_the_cpu_field() {
    // The shader's own `medium` (its profile and formula tables in f32)
    // against `AirField::delta_gradient`, from the ground through the surface
    // layer and the inversion's duct.
    use mirage::math::V3;
    use mirage::medium::IndexField;
    let test = "gpu_evaluates_real_air_as_the_cpu_field";
    let Some(gpu) = gpu(test) else { return };
    let scene = with_medium("sea.json", STRATIFIED_AIR);
    let options = RenderOptions::default();
    let view = View::of_scene(&scene, &options, 32, 18);
    let buffers = mirage::preview::pack::pack(&scene, &scene.medium, &view).unwrap();
    let heights: Vec<f64> = (0..=100)
        .map(|i| 0.004 * i as f64)
        .chain((0..=160).map(|i| 0.125 * i as f64))
        .collect();
    let input: Vec<[f32; 4]> = heights
        .iter()
        .map(|&h| [30.0, h as f32, 2000.0, 0.0])
        .collect();
    let out = probe(
        &gpu,
        &buffers,
        "probe_medium",
        &input,
        input.len(),
        input.len() as u32,
    );
    let field = scene.medium.field();
    let (mut worst_delta, mut worst_slope) = (0.0f64, 0.0f64);
    for (&h, o) in heights.iter().zip(&out) {
        let (d, g) = field.delta_gradient(V3::new(30.0, h, 2000.0));
        worst_delta = worst_delta.max((o[3] as f64 - d).abs());
        worst_slope = worst_slope.max((o[1] as f64 - g.y).abs() / g.y.abs());
        assert!(
            o[0] == 0.0 && o[2] == 0.0,
            "a horizontal gradient at {h} m: {o:?}"
        );
    }
    eprintln!(
        "{test}: worst |δ − δ_CPU| {worst_delta:.2e}, worst relative ∂δ/∂h error {worst_slope:.2e}"
    );
    // δ ≈ 2.8e-4 to f32's 7 digits; the duct is 3.9e-6 deep.
    assert!(worst_delta < 1e-10, "δ off by {worst_delta:e}");
    assert!(worst_slope < 1e-4, "∂δ/∂h off by {worst_slope:e} relative");
}

#[test]
fn gpu_matches_cpu_over_the_round_earth() {
    // The looming freighter: real air with a cold-sea duct over the sphere,
    // the hull lifted back over the horizon.
    parity(
        "gpu_matches_cpu_over_the_round_earth",
        "looming.json",
        320,
        120,
    );
}

/// A linear frame: RGB, row-major.
type Frame = Vec<[f32; 3]>;

/// The window's accumulation, driven as the window drives it: each still
/// frame's samples from [`Accumulation`], set in the uniform block, traced
/// onto the sums of the frames before, for each of `per_frame` in turn (one
/// tracer: a shader compiled once). Returns per `per_frame` the picture
/// (with the scene's glare, as the window adds it once complete) and the
/// frames it took, and the picture after the very first frame.
fn accumulated_frames(
    gpu: &Gpu,
    scene: &Scene,
    view: &View,
    target: u32,
    per_frame: &[u32],
) -> (Vec<(Frame, u32)>, Frame) {
    use mirage::preview::accumulate::Accumulation;
    use mirage::preview::gpu::Tracer;
    let mut buffers = mirage::preview::pack::pack(scene, &scene.medium, view).unwrap();
    let mut tracer = Tracer::new(gpu, &buffers);
    assert!(tracer.accumulates());
    let mut first_frame = None;
    let mut out = Vec::new();
    for &per in per_frame {
        let moving = View {
            samples_per_pixel: per,
            ..*view
        };
        let mut acc = Accumulation::new(target);
        let mut frames = 0;
        loop {
            buffers.set_view(&moving);
            let Some(samples) = acc.next(frames > 0, per) else {
                break;
            };
            buffers.set_samples(samples, tracer.accumulates());
            tracer.update(gpu, &buffers);
            tracer.render(gpu);
            frames += 1;
            if first_frame.is_none() {
                first_frame = Some(tracer.read_back(gpu).unwrap());
            }
        }
        let mut pixels = tracer.read_back(gpu).unwrap();
        mirage::preview::apply_glare(scene, view, &mut pixels);
        out.push((pixels, frames));
    }
    (out, first_frame.unwrap())
}

/// Largest |a − b| / max(|a|, |b|, 1e-3) over pixels and channels, and the
/// number of values that differ at all.
fn relative_difference(a: &[[f32; 3]], b: &[[f32; 3]]) -> (f64, usize) {
    assert_eq!(a.len(), b.len());
    let (mut worst, mut differ) = (0.0f64, 0usize);
    for (p, q) in a.iter().zip(b) {
        for k in 0..3 {
            let (x, y) = (p[k] as f64, q[k] as f64);
            if x != y {
                differ += 1;
            }
            worst = worst.max((x - y).abs() / x.abs().max(y.abs()).max(1e-3));
        }
    }
    (worst, differ)
}

#[test]
fn the_accumulated_window_frame_is_the_headless_frame_at_as_many_samples() {
    // A problem's view: the checkered ground that aliases at one sample. The
    // headless frame at N samples per pixel sums each pixel's samples
    // 0..N−1 in one frame; the window, its view still, adds them frame by
    // frame in the accumulation buffer (one sample a frame, and three: the
    // last frame takes the two left). Both do the same f32 additions in the
    // same order, so they agree to rounding: the tolerance is 1e-6 relative
    // (8 ulp of f32), for a driver that schedules the two dispatch shapes
    // differently; a sample's worth of difference is ~1e-1, a display step
    // 4e-3.
    let test = "the_accumulated_window_frame_is_the_headless_frame_at_as_many_samples";
    let Some(gpu) = gpu(test) else { return };
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = mirage::preview::load_input(&root.join("problems/hot-road.json"))
        .unwrap()
        .scene;
    let n = 8;
    let options = RenderOptions {
        samples_per_pixel: Some(n),
        ..RenderOptions::default()
    };
    let view = View::of_scene(&scene, &options, 120, 68);
    let headless = render_frame(&gpu, &scene, &scene.medium, &view).unwrap();
    let per_frame = [1, 3];
    let (windows, one) = accumulated_frames(&gpu, &scene, &view, n, &per_frame);
    for (&per, (window, frames)) in per_frame.iter().zip(&windows) {
        assert_eq!(*frames, n.div_ceil(per));
        let (worst, differ) = relative_difference(&headless, window);
        eprintln!(
            "{test}: {per} a frame, {frames} frames: {differ} values differ \
             (largest {worst:.1e} relative) from the headless frame at {n} spp"
        );
        assert!(worst <= 1e-6, "{worst:e} ({differ} values differ)");
    }
    // Not a vacuous comparison: the samples change the picture.
    let (_, from_one) = relative_difference(&headless, &one);
    eprintln!("{test}: {from_one} values differ between 1 and {n} spp");
    assert!(from_one > 100, "only {from_one} values differ at 1 spp");
}
