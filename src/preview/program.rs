//! The SDF program: each object's tree compiled to a flat list of opcodes the
//! shader runs on a small value stack.
//!
//! Each object's tree becomes a post-order list of [`Node`]s evaluated with a
//! small value stack. Transforms are folded into the primitives at packing
//! time: every primitive carries the affine map world → its local frame and the
//! product of the scale factors above it (`d = factor · child(p / factor)`).
//! n-ary unions, intersections and smooth unions become left folds of binary
//! operations, so the stack never holds more than the tree's depth + 1 values.
//!
//! The opcodes ([`Op`]) and the stack depth ([`STACK_DEPTH`]) are defined
//! here only: the shader gets them from the generated prelude
//! ([`super::shader`]).

use super::layout::{GpuObject, Node, rgb4, v4};
use crate::error::FieldError;
use crate::scene::sdf::{SceneObject, Sdf};
use glam::{DMat3, DVec3};

/// Deepest value stack an SDF program may need (the shader's array size).
pub const STACK_DEPTH: usize = 16;

/// SDF program opcodes (the shader's `OP_*` constants). Primitives push a
/// distance; the binary operations, from [`Op::FIRST_BINARY`] on, pop two and
/// push one.
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Op {
    /// Sphere: `p0 = (centre, radius)`.
    Sphere = 1,
    /// Box: `p0 = centre`, `p1 = half extents`.
    Box = 2,
    /// Rounded box: `p0 = (centre, radius)`, `p1 = half extents`.
    RoundedBox = 3,
    /// Plane: `p0 = (unit normal, offset)`.
    Plane = 4,
    /// Torus: `p0 = centre`, `p1 = (major, minor)`.
    Torus = 5,
    /// Cylinder: `p0 = centre`, `p1 = (radius, half height)`.
    Cylinder = 6,
    /// Capsule: `p0 = (a, radius)`, `p1 = b`.
    Capsule = 7,
    /// Pops b, a; pushes min(a, b).
    Min = 10,
    /// Pops b, a; pushes max(a, b).
    Max = 11,
    /// Pops b, a; pushes max(a, −b).
    Diff = 12,
    /// Pops b, a; pushes the smooth minimum with width `p0.x`.
    Smin = 13,
}

impl Op {
    /// Every opcode.
    pub const ALL: [Op; 11] = [
        Op::Sphere,
        Op::Box,
        Op::RoundedBox,
        Op::Plane,
        Op::Torus,
        Op::Cylinder,
        Op::Capsule,
        Op::Min,
        Op::Max,
        Op::Diff,
        Op::Smin,
    ];

    /// The first binary operation: every code below it is a primitive.
    pub const FIRST_BINARY: Op = Op::Min;

    /// The code in [`Node::kind`].
    pub const fn code(self) -> u32 {
        self as u32
    }

    /// The opcode of `code`, if it is one.
    pub fn from_code(code: u32) -> Option<Op> {
        Op::ALL.into_iter().find(|op| op.code() == code)
    }

    /// Whether this opcode pushes a distance (rather than combining two).
    pub const fn is_primitive(self) -> bool {
        self.code() < Op::FIRST_BINARY.code()
    }

    /// The shader's name for it (`OP_SPHERE`).
    pub const fn wgsl_name(self) -> &'static str {
        match self {
            Op::Sphere => "OP_SPHERE",
            Op::Box => "OP_BOX",
            Op::RoundedBox => "OP_ROUNDED_BOX",
            Op::Plane => "OP_PLANE",
            Op::Torus => "OP_TORUS",
            Op::Cylinder => "OP_CYLINDER",
            Op::Capsule => "OP_CAPSULE",
            Op::Min => "OP_MIN",
            Op::Max => "OP_MAX",
            Op::Diff => "OP_DIFF",
            Op::Smin => "OP_SMIN",
        }
    }
}

/// The world → local affine map of a primitive and its distance multiplier.
#[derive(Clone, Copy, Debug)]
struct Frame {
    a: DMat3,
    b: DVec3,
    mult: f64,
}

impl Frame {
    const IDENTITY: Frame = Frame {
        a: DMat3::IDENTITY,
        b: DVec3::ZERO,
        mult: 1.0,
    };

    fn node(&self, kind: Op, p0: [f32; 4], p1: [f32; 4]) -> Node {
        let r = self.a.transpose();
        let mut p1 = p1;
        p1[3] = self.mult as f32;
        Node {
            kind: [kind.code(), 0, 0, 0],
            rows: [
                v4(r.x_axis, self.b.x),
                v4(r.y_axis, self.b.y),
                v4(r.z_axis, self.b.z),
            ],
            p0,
            p1,
        }
    }
}

fn binary(kind: Op, k: f64) -> Node {
    Node {
        kind: [kind.code(), 0, 0, 0],
        p0: [k as f32, 0.0, 0.0, 0.0],
        ..Node::default()
    }
}

/// Appends the program of `sdf` in `frame`; returns the stack depth it needs.
fn compile(sdf: &Sdf, frame: Frame, out: &mut Vec<Node>) -> usize {
    let fold = |children: &[Sdf], kind: Op, k: f64, out: &mut Vec<Node>| -> usize {
        let mut depth = 0;
        for (i, c) in children.iter().enumerate() {
            let d = compile(c, frame, out);
            if i == 0 {
                depth = d;
            } else {
                depth = depth.max(1 + d);
                out.push(binary(kind, k * frame.mult));
            }
        }
        depth
    };
    match sdf {
        Sdf::Sphere { center, radius } => {
            out.push(frame.node(Op::Sphere, v4(*center, *radius), [0.0; 4]));
            1
        }
        Sdf::Box {
            center,
            half_extents,
        } => {
            out.push(frame.node(Op::Box, v4(*center, 0.0), v4(*half_extents, 0.0)));
            1
        }
        Sdf::RoundedBox {
            center,
            half_extents,
            radius,
        } => {
            out.push(frame.node(Op::RoundedBox, v4(*center, *radius), v4(*half_extents, 0.0)));
            1
        }
        Sdf::Plane(p) => {
            out.push(frame.node(Op::Plane, v4(p.unit_normal(), p.offset()), [0.0; 4]));
            1
        }
        Sdf::Torus {
            center,
            major_radius,
            minor_radius,
        } => {
            out.push(frame.node(
                Op::Torus,
                v4(*center, 0.0),
                [*major_radius as f32, *minor_radius as f32, 0.0, 0.0],
            ));
            1
        }
        Sdf::Cylinder {
            center,
            radius,
            half_height,
        } => {
            out.push(frame.node(
                Op::Cylinder,
                v4(*center, 0.0),
                [*radius as f32, *half_height as f32, 0.0, 0.0],
            ));
            1
        }
        Sdf::Capsule { a, b, radius } => {
            out.push(frame.node(Op::Capsule, v4(*a, *radius), v4(*b, 0.0)));
            1
        }
        Sdf::Union { children } => fold(children, Op::Min, 0.0, out),
        Sdf::Intersection { children } => fold(children, Op::Max, 0.0, out),
        Sdf::SmoothUnion { children, k } => fold(children, Op::Smin, *k, out),
        Sdf::Difference { base, subtract } => {
            let a = compile(base, frame, out);
            let b = compile(subtract, frame, out);
            out.push(binary(Op::Diff, 0.0));
            a.max(1 + b)
        }
        Sdf::Translate { offset, child } => compile(
            child,
            Frame {
                b: frame.b - *offset,
                ..frame
            },
            out,
        ),
        Sdf::Rotate(r) => {
            let m = r.world_to_local();
            compile(
                r.child(),
                Frame {
                    a: m * frame.a,
                    b: m * frame.b,
                    mult: frame.mult,
                },
                out,
            )
        }
        Sdf::Scale(s) => {
            let f = s.factor();
            compile(
                s.child(),
                Frame {
                    a: frame.a * (1.0 / f),
                    b: frame.b / f,
                    mult: frame.mult * f,
                },
                out,
            )
        }
    }
}

/// The SDF programs of `objects` and their records; errors when a tree needs
/// a deeper stack than the shader has.
pub fn compile_objects(objects: &[SceneObject]) -> Result<(Vec<GpuObject>, Vec<Node>), FieldError> {
    let mut nodes = Vec::new();
    let mut records = Vec::new();
    for (i, o) in objects.iter().enumerate() {
        let start = nodes.len();
        let depth = compile(&o.shape, Frame::IDENTITY, &mut nodes);
        if depth > STACK_DEPTH {
            return Err(FieldError::new(
                format!("objects[{i}].shape"),
                format!("nested {depth} levels deep, more than the previewer's {STACK_DEPTH}"),
            ));
        }
        let (c, r) = o.shape.bounding_sphere();
        let r = if r.is_finite() && c.is_finite() {
            r
        } else {
            -1.0
        };
        records.push(GpuObject {
            range: [start as u32, (nodes.len() - start) as u32, 0, 0],
            albedo: rgb4(o.albedo, r),
            center: v4(if c.is_finite() { c } else { DVec3::ZERO }, 0.0),
        });
    }
    Ok((records, nodes))
}

/// Evaluates an SDF program on the CPU, in f32 as the shader does (for tests
/// of the packing, and the editor's picking).
pub fn eval_program(nodes: &[Node], p: [f32; 3]) -> f32 {
    let mut stack = [0.0f32; STACK_DEPTH];
    let mut top = 0usize;
    for n in nodes {
        let local = |row: [f32; 4]| row[0] * p[0] + row[1] * p[1] + row[2] * p[2] + row[3];
        let q = [local(n.rows[0]), local(n.rows[1]), local(n.rows[2])];
        let sub = |c: [f32; 4]| [q[0] - c[0], q[1] - c[1], q[2] - c[2]];
        let len3 = |v: [f32; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        let box_d = |d: [f32; 3], h: [f32; 4], shrink: f32| {
            let e = [
                d[0].abs() - h[0] + shrink,
                d[1].abs() - h[1] + shrink,
                d[2].abs() - h[2] + shrink,
            ];
            len3([e[0].max(0.0), e[1].max(0.0), e[2].max(0.0)]) + e[0].max(e[1]).max(e[2]).min(0.0)
                - shrink
        };
        let kind = Op::from_code(n.kind[0]);
        let value = match kind {
            Some(Op::Sphere) => Some(len3(sub(n.p0)) - n.p0[3]),
            Some(Op::Box) => Some(box_d(sub(n.p0), n.p1, 0.0)),
            Some(Op::RoundedBox) => Some(box_d(sub(n.p0), n.p1, n.p0[3])),
            Some(Op::Plane) => Some(n.p0[0] * q[0] + n.p0[1] * q[1] + n.p0[2] * q[2] - n.p0[3]),
            Some(Op::Torus) => {
                let d = sub(n.p0);
                let rho = (d[0] * d[0] + d[2] * d[2]).sqrt();
                Some((rho - n.p1[0]).hypot(d[1]) - n.p1[1])
            }
            Some(Op::Cylinder) => {
                let d = sub(n.p0);
                let a = (d[0] * d[0] + d[2] * d[2]).sqrt() - n.p1[0];
                let b = d[1].abs() - n.p1[1];
                Some(a.max(b).min(0.0) + a.max(0.0).hypot(b.max(0.0)))
            }
            Some(Op::Capsule) => {
                let pa = sub(n.p0);
                let ba = [n.p1[0] - n.p0[0], n.p1[1] - n.p0[1], n.p1[2] - n.p0[2]];
                let bb = ba[0] * ba[0] + ba[1] * ba[1] + ba[2] * ba[2];
                let h = if bb > 0.0 {
                    ((pa[0] * ba[0] + pa[1] * ba[1] + pa[2] * ba[2]) / bb).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                Some(len3([pa[0] - ba[0] * h, pa[1] - ba[1] * h, pa[2] - ba[2] * h]) - n.p0[3])
            }
            _ => None,
        };
        match value {
            Some(d) => {
                stack[top] = d * n.p1[3];
                top += 1;
            }
            None => {
                let b = stack[top - 1];
                let a = stack[top - 2];
                top -= 1;
                stack[top - 1] = match kind {
                    Some(Op::Min) => a.min(b),
                    Some(Op::Max) => a.max(b),
                    Some(Op::Diff) => a.max(-b),
                    _ => {
                        let k = n.p0[0];
                        let h = (k - (a - b).abs()).max(0.0) / k;
                        a.min(b) - h * h * k * 0.25
                    }
                };
            }
        }
    }
    if top == 0 { f32::INFINITY } else { stack[0] }
}

#[cfg(test)]
mod tests {
    use super::*;
    fn shapes() -> Vec<Sdf> {
        let cyl = Sdf::cylinder(DVec3::new(0.0, 0.0, 0.0), 0.34, 0.12);
        vec![
            Sdf::sphere(DVec3::new(1.0, 2.0, 3.0), 0.5),
            Sdf::translate(
                DVec3::new(-1.7, 0.0, 262.0),
                Sdf::rotate(
                    DVec3::Y,
                    180.0,
                    Sdf::union(vec![
                        Sdf::rounded_box(
                            DVec3::new(0.0, 0.78, 0.0),
                            DVec3::new(0.9, 0.45, 2.2),
                            0.18,
                        ),
                        Sdf::translate(
                            DVec3::new(-0.86, 0.34, -1.35),
                            Sdf::rotate(DVec3::Z, 90.0, cyl.clone()),
                        ),
                        Sdf::cuboid(DVec3::new(0.0, 1.5, 0.0), DVec3::new(0.7, 0.3, 1.1)),
                    ]),
                ),
            ),
            Sdf::difference(
                Sdf::scale(2.0, Sdf::torus(DVec3::new(0.0, 1.0, 5.0), 1.0, 0.3)),
                Sdf::capsule(DVec3::new(0.0, 1.0, 9.0), DVec3::new(0.0, 3.0, 11.0), 0.5),
            ),
            Sdf::smooth_union(
                vec![
                    Sdf::sphere(DVec3::new(0.0, 1.0, 0.0), 1.0),
                    Sdf::scale(0.5, Sdf::sphere(DVec3::new(2.0, 2.0, 0.0), 1.0)),
                    Sdf::cylinder(DVec3::new(-1.0, 1.0, 0.0), 0.3, 2.0),
                ],
                0.4,
            ),
            Sdf::intersection(vec![
                Sdf::plane(DVec3::new(0.3, 1.0, 0.0), 2.0),
                Sdf::sphere(DVec3::ZERO, 3.0),
            ]),
        ]
    }

    #[test]
    fn programs_match_the_cpu_distances() {
        for (i, s) in shapes().into_iter().enumerate() {
            let obj = SceneObject {
                name: None,
                albedo: [0.5; 3],
                shape: s.clone(),
            };
            let (records, nodes) = compile_objects(std::slice::from_ref(&obj)).unwrap();
            let r = records[0].range;
            let prog = &nodes[r[0] as usize..(r[0] + r[1]) as usize];
            let (c, _) = s.bounding_sphere();
            let c = if c.is_finite() { c } else { DVec3::ZERO };
            let mut worst = 0.0f64;
            for k in 0..500 {
                // A deterministic cloud of points around the shape.
                let f = k as f64;
                let p = c + DVec3::new(
                    (f * 0.754_877).fract() - 0.5,
                    (f * 0.569_840).fract() - 0.5,
                    (f * 0.381_966).fract() - 0.5,
                ) * 12.0;
                let want = s.distance(p);
                let got = eval_program(prog, [p.x as f32, p.y as f32, p.z as f32]) as f64;
                worst = worst.max((got - want).abs() / want.abs().max(1.0));
            }
            assert!(worst < 2e-5, "shape {i}: worst relative error {worst:e}");
        }
    }

    #[test]
    fn too_deep_trees_are_refused() {
        let mut s = Sdf::sphere(DVec3::ZERO, 1.0);
        for k in 0..20 {
            s = Sdf::difference(Sdf::sphere(DVec3::new(k as f64, 0.0, 0.0), 1.0), s);
        }
        let obj = SceneObject {
            name: None,
            albedo: [0.5; 3],
            shape: s,
        };
        let err = compile_objects(&[obj]).unwrap_err();
        assert_eq!(err.path, "objects[0].shape");
        assert!(err.message.contains("21 levels deep"), "{err}");
    }

    #[test]
    fn opcodes_are_distinct_and_primitives_come_first() {
        for (i, a) in Op::ALL.iter().enumerate() {
            assert_eq!(Op::from_code(a.code()), Some(*a));
            for b in &Op::ALL[i + 1..] {
                assert_ne!(a.code(), b.code(), "{a:?} and {b:?}");
                assert_ne!(a.wgsl_name(), b.wgsl_name());
            }
        }
        let primitives: Vec<Op> = Op::ALL.into_iter().filter(|o| o.is_primitive()).collect();
        assert_eq!(primitives.len(), 7);
        assert_eq!(Op::from_code(0), None);
    }
}
