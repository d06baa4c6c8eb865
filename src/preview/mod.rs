//! The GPU previewer: the CPU renderer's scene, medium, curved rays, sky and
//! shading in a WGSL compute shader, shown live in a window with controls to
//! edit the air, or rendered headless to a PNG.
//!
//! Data flow: a scene or problem file ([`Input`]) → [`pack::pack`] (f32
//! buffers laid out as in [`layout`], the objects compiled by [`program`], the
//! medium in δ form) → [`gpu::Tracer`] (a frame traced into a linear HDR
//! image by a few dozen compute dispatches, each of which marches every
//! pixel's ray on by a bounded number of iterations; see [`pack`]'s "Passes")
//! → either read back and written
//! like `mirage render`'s PNG (headless), or tone-mapped on the GPU and drawn
//! under the egui panels ([`window`]).
//!
//! Not ported: the CPU renderer's path table for stratified air (the GPU
//! integrates every ray; the table is an approximation of exactly that) and its
//! distance grid (the GPU evaluates every object whose bounding sphere is
//! nearer than the best distance so far).

pub mod accumulate;
pub mod camera;
mod command;
pub mod display;
pub mod editing;
pub mod frame;
pub mod gpu;
pub mod input;
pub mod layout;
pub mod pack;
pub mod photo;
pub mod photo_window;
pub mod program;
pub mod real_air;
pub mod script;
pub mod shader;
pub mod window;

pub use command::{PreviewOptions, preview_command};
pub use frame::{apply_glare, open_gpu, render_frame};
pub use input::{BENCH_SIZE, Input, load_input, logistic, previewable, problem_scene};
