//! The tracing shader's source: a prelude of WGSL constants generated from
//! the Rust ones, then `trace.wgsl`.
//!
//! Every number both sides must agree on (the SDF opcodes, the value stack's
//! depth, the codes in the uniform block's flags, the stand-in for infinity,
//! the star cells' grid, the workgroup size) is defined once, in Rust; the
//! shader only names them. The tests parse the composed shader with naga and
//! check the layouts it computes for the uniform and storage structs against
//! the Rust `#[repr(C)]` structs of [`super::layout`].

use super::layout::{
    BIG, GROUND_CHECKER, GROUND_NONE, GROUND_UNIFORM, MEDIUM_AIR, MEDIUM_LOGISTIC, PHASE_DONE,
    PHASE_START, PHASE_TRACING, SHADING_ALBEDO, SHADING_LIT,
};
use super::program::{Op, STACK_DEPTH};
use crate::render::sky::{STAR_CELLS, STAR_MARGIN_MAX};
use std::fmt::Write;

/// The hand-written part of the tracing shader (WGSL), which uses the
/// prelude's names; see [`trace_shader`] for the whole.
pub const TRACE_WGSL: &str = include_str!("trace.wgsl");

/// The display shader (WGSL): tone mapping and sRGB encoding of the traced
/// image into the window. It shares no constant with Rust.
pub const DISPLAY_SHADER: &str = include_str!("display.wgsl");

/// Compute workgroup side (the shader's `@workgroup_size(WORKGROUP,
/// WORKGROUP)`).
pub const WORKGROUP: u32 = 8;

/// A constant of the prelude: its WGSL name and value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Constant {
    /// A `u32`.
    U32(&'static str, u32),
    /// An `f32`.
    F32(&'static str, f32),
}

/// Every constant the prelude defines, in its order.
pub fn constants() -> Vec<Constant> {
    use Constant::{F32, U32};
    let mut out: Vec<Constant> = Op::ALL
        .into_iter()
        .map(|op| U32(op.wgsl_name(), op.code()))
        .collect();
    out.extend([
        U32("OP_FIRST_BINARY", Op::FIRST_BINARY.code()),
        U32("STACK_DEPTH", STACK_DEPTH as u32),
        U32("WORKGROUP", WORKGROUP),
        U32("SHADING_LIT", SHADING_LIT),
        U32("SHADING_ALBEDO", SHADING_ALBEDO),
        U32("GROUND_NONE", GROUND_NONE),
        U32("GROUND_UNIFORM", GROUND_UNIFORM),
        U32("GROUND_CHECKER", GROUND_CHECKER),
        U32("MEDIUM_LOGISTIC", MEDIUM_LOGISTIC),
        U32("MEDIUM_AIR", MEDIUM_AIR),
        U32("PHASE_START", PHASE_START),
        U32("PHASE_TRACING", PHASE_TRACING),
        U32("PHASE_DONE", PHASE_DONE),
        F32("BIG", BIG),
        F32("STAR_CELLS", STAR_CELLS as f32),
        F32("STAR_MARGIN_MAX", STAR_MARGIN_MAX as f32),
    ]);
    out
}

/// An f32 as a WGSL literal that reads back as the same f32: Rust's shortest
/// round-trip form, with a decimal point or an exponent so that WGSL reads a
/// float.
fn f32_literal(x: f32) -> String {
    let s = format!("{x:?}");
    if s.contains(['.', 'e', 'E']) || !x.is_finite() {
        s
    } else {
        format!("{s}.0")
    }
}

/// The prelude: one `const` line per [`constants`] entry.
pub fn prelude() -> String {
    let mut out = String::from("// Generated from the Rust constants (src/preview/shader.rs).\n");
    for c in constants() {
        // Writing to a String cannot fail.
        let _ = match c {
            Constant::U32(name, v) => writeln!(out, "const {name}: u32 = {v}u;"),
            Constant::F32(name, v) => writeln!(out, "const {name}: f32 = {};", f32_literal(v)),
        };
    }
    out.push('\n');
    out
}

/// The whole tracing shader: the [`prelude`], then [`TRACE_WGSL`].
pub fn trace_shader() -> String {
    prelude() + TRACE_WGSL
}

#[cfg(test)]
mod tests {
    use super::super::layout::{GpuCell, GpuHotSpot, GpuObject, GpuRay, Node, Params};
    use super::*;
    use naga::{AddressSpace, ArraySize, Module, TypeInner};
    use std::mem::{offset_of, size_of};

    /// Parses and validates a WGSL source as wgpu will (no GPU needed).
    fn validate(name: &str, source: &str) -> Module {
        let module = naga::front::wgsl::parse_str(source)
            .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(source)));
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::default(),
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(source)));
        module
    }

    #[test]
    fn the_shaders_are_valid_wgsl() {
        validate("trace shader", &trace_shader());
        validate("display.wgsl", DISPLAY_SHADER);
    }

    #[test]
    fn the_prelude_has_every_constant_once_and_exactly() {
        let src = prelude();
        let module = validate("prelude", &src);
        let cs = constants();
        for c in &cs {
            let (name, want) = match *c {
                Constant::U32(n, v) => (n, naga::Literal::U32(v)),
                Constant::F32(n, v) => (n, naga::Literal::F32(v)),
            };
            let hits: Vec<_> = module
                .constants
                .iter()
                .filter(|(_, k)| k.name.as_deref() == Some(name))
                .collect();
            assert_eq!(hits.len(), 1, "{name}");
            let got = &module.global_expressions[hits[0].1.init];
            assert_eq!(got, &naga::Expression::Literal(want), "{name}");
        }
        assert_eq!(module.constants.len(), cs.len());
        // The hand-written part defines none of them itself.
        for c in &cs {
            let (Constant::U32(name, _) | Constant::F32(name, _)) = *c;
            assert!(
                !TRACE_WGSL.contains(&format!("const {name}:")),
                "trace.wgsl defines {name}"
            );
        }
    }

    /// `(member name, offset)` of the named fields of a Rust struct.
    macro_rules! fields {
        ($t:ty { $($f:ident),* $(,)? }) => {
            [$((stringify!($f), offset_of!($t, $f))),*]
        };
    }

    /// Checks the WGSL struct `name`'s size and members (names, offsets, in
    /// order) against a Rust struct's.
    fn check_struct(module: &Module, name: &str, size: usize, members: &[(&str, usize)]) {
        let (_, ty) = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("no struct {name} in the shader"));
        let TypeInner::Struct {
            members: wgsl,
            span,
        } = &ty.inner
        else {
            panic!("{name} is not a struct");
        };
        assert_eq!(*span as usize, size, "{name}: size");
        let got: Vec<(&str, usize)> = wgsl
            .iter()
            .map(|m| (m.name.as_deref().unwrap_or("?"), m.offset as usize))
            .collect();
        assert_eq!(got, members, "{name}: members and offsets");
    }

    #[test]
    fn the_shader_structs_match_the_rust_layouts() {
        let module = validate("trace shader", &trace_shader());
        check_struct(
            &module,
            "Params",
            size_of::<Params>(),
            &fields!(Params {
                origin,
                forward,
                right,
                up,
                size,
                flags,
                background,
                inversion,
                air,
                profile,
                tolerance,
                ground0,
                ground1,
                box_min,
                box_max,
                sun_dir,
                sun_irradiance,
                ambient,
                disc_dir,
                disc_radiance,
                counts,
                grid_min,
                grid_max,
                grid_dims,
                grid_cell,
                stars,
                medium,
                air_range,
                air_grid,
                march,
                accumulate,
            }),
        );
        check_struct(
            &module,
            "Ray",
            size_of::<GpuRay>(),
            &fields!(GpuRay {
                x,
                v,
                a,
                at,
                sum,
                count
            }),
        );
        check_struct(
            &module,
            "Cell",
            size_of::<GpuCell>(),
            &fields!(GpuCell {
                empty,
                far,
                start,
                len
            }),
        );
        check_struct(
            &module,
            "HotSpot",
            size_of::<GpuHotSpot>(),
            &fields!(GpuHotSpot { a, b, c }),
        );
        check_struct(
            &module,
            "Object",
            size_of::<GpuObject>(),
            &fields!(GpuObject {
                range,
                albedo,
                center
            }),
        );
        // The shader spells the three rows of the affine map out.
        let rows = offset_of!(Node, rows);
        let mut node = fields!(Node { kind }).to_vec();
        node.extend([("row0", rows), ("row1", rows + 16), ("row2", rows + 32)]);
        node.extend(fields!(Node { p0, p1 }));
        check_struct(&module, "Node", size_of::<Node>(), &node);
    }

    #[test]
    fn the_bindings_hold_the_rust_elements() {
        let module = validate("trace shader", &trace_shader());
        // Binding → the size of one element of what SceneBuffers uploads
        // there (11: the tracer's own ray states; 13: its per-pixel sums
        // of samples, RGBA f32).
        let storage = [
            (1, size_of::<GpuHotSpot>()),
            (2, size_of::<GpuObject>()),
            (3, size_of::<Node>()),
            (4, size_of::<[f32; 4]>()),
            (7, size_of::<GpuCell>()),
            (8, size_of::<u32>()),
            (9, size_of::<[f32; 4]>()),
            (10, size_of::<[f32; 4]>()),
            (11, size_of::<GpuRay>()),
            (13, size_of::<[f32; 4]>()),
        ];
        let mut seen = 0;
        for (_, var) in module.global_variables.iter() {
            let Some(rb) = &var.binding else { continue };
            assert_eq!(rb.group, 0);
            let inner = &module.types[var.ty].inner;
            match var.space {
                AddressSpace::Uniform if rb.binding == 12 => {
                    // The band: [first row, rows, 0, 0] (gpu.rs writes u32s).
                    assert_eq!(
                        inner,
                        &TypeInner::Vector {
                            size: naga::VectorSize::Quad,
                            scalar: naga::Scalar::U32
                        }
                    );
                    seen += 1;
                }
                AddressSpace::Uniform => {
                    assert_eq!(rb.binding, 0);
                    let TypeInner::Struct { span, .. } = inner else {
                        panic!("the uniform block is not a struct");
                    };
                    assert_eq!(*span as usize, size_of::<Params>());
                    seen += 1;
                }
                AddressSpace::Storage { .. } => {
                    let &(_, want) = storage
                        .iter()
                        .find(|(b, _)| *b == rb.binding)
                        .unwrap_or_else(|| panic!("unexpected storage binding {}", rb.binding));
                    let TypeInner::Array {
                        size: ArraySize::Dynamic,
                        stride,
                        ..
                    } = inner
                    else {
                        panic!("binding {} is not a runtime array", rb.binding);
                    };
                    assert_eq!(*stride as usize, want, "binding {}: stride", rb.binding);
                    seen += 1;
                }
                _ => {}
            }
        }
        assert_eq!(seen, 2 + storage.len());
    }
}
