// Shows the traced linear image in a rectangle of the window: tone mapping as
// `mirage render`'s PNG (ACES filmic for lit frames, a clamp for albedo ones),
// then sRGB encoding (the surface is a non-sRGB format, as egui wants).

struct Display {
    // Rectangle in framebuffer pixels: origin, size.
    rect: vec4<f32>,
    // Traced image size, mode (0 filmic, 1 clamp), exposure.
    image: vec4<f32>,
}

@group(0) @binding(0) var<uniform> D: Display;
@group(0) @binding(1) var linear: texture_2d<f32>;

@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let x = f32((i << 1u) & 2u) * 2.0 - 1.0;
    let y = f32(i & 2u) * 2.0 - 1.0;
    return vec4<f32>(x, y, 0.0, 1.0);
}

fn aces(x: f32) -> f32 {
    let v = max(x, 0.0);
    return clamp((v * (2.51 * v + 0.03)) / (v * (2.43 * v + 0.59) + 0.14), 0.0, 1.0);
}

fn srgb(x: f32) -> f32 {
    let v = clamp(x, 0.0, 1.0);
    if (v <= 0.0031308) { return 12.92 * v; }
    return 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}

@fragment
fn fs(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let uv = (pos.xy - D.rect.xy) / D.rect.zw;
    let size = vec2<i32>(D.image.xy);
    let texel = clamp(vec2<i32>(uv * D.image.xy), vec2<i32>(0), size - vec2<i32>(1));
    let c = textureLoad(linear, texel, 0).xyz;
    var m: vec3<f32>;
    if (D.image.z > 0.5) {
        m = clamp(c, vec3<f32>(0.0), vec3<f32>(1.0));
    } else {
        let e = c * D.image.w;
        m = vec3<f32>(aces(e.x), aces(e.y), aces(e.z));
    }
    return vec4<f32>(srgb(m.x), srgb(m.y), srgb(m.z), 1.0);
}
