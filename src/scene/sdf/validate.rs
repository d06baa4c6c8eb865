//! Validation of deserialized shapes and objects.
//!
//! Every parameter is checked and the first problem is reported as a
//! [`FieldError`] whose path is relative to the value validated
//! (`children[1].radius`); each level prefixes its own field with
//! [`FieldError::within`] as the error travels up, so the caller that knows
//! where the value sits in its document (`objects`) gives the full path
//! `objects[2].shape.children[1].radius`. Evaluating a shape that failed
//! validation gives meaningless numbers.

use glam::DVec3;

use super::{SceneObject, Sdf};
use crate::error::FieldError;

fn check_finite(field: &str, x: f64) -> Result<(), FieldError> {
    if x.is_finite() {
        Ok(())
    } else {
        Err(FieldError::new(field, format!("must be finite, got {x}")))
    }
}

fn check_positive(field: &str, x: f64) -> Result<(), FieldError> {
    check_finite(field, x)?;
    if x > 0.0 {
        Ok(())
    } else {
        Err(FieldError::new(field, format!("must be > 0, got {x}")))
    }
}

fn check_vec_finite(field: &str, v: DVec3) -> Result<(), FieldError> {
    for (i, x) in v.to_array().into_iter().enumerate() {
        check_finite(&format!("{field}[{i}]"), x)?;
    }
    Ok(())
}

fn check_vec_positive(field: &str, v: DVec3) -> Result<(), FieldError> {
    for (i, x) in v.to_array().into_iter().enumerate() {
        check_positive(&format!("{field}[{i}]"), x)?;
    }
    Ok(())
}

fn check_nonzero_direction(field: &str, v: DVec3) -> Result<(), FieldError> {
    check_vec_finite(field, v)?;
    if v.length_squared() > 0.0 && v.length().is_normal() {
        Ok(())
    } else {
        Err(FieldError::new(
            field,
            format!("must be a non-zero vector, got [{}, {}, {}]", v.x, v.y, v.z),
        ))
    }
}

fn validate_children(children: &[Sdf]) -> Result<(), FieldError> {
    if children.is_empty() {
        return Err(FieldError::new(
            "children",
            "must contain at least one shape",
        ));
    }
    for (i, c) in children.iter().enumerate() {
        c.validate()
            .map_err(|e| e.within(&format!("children[{i}]")))?;
    }
    Ok(())
}

impl Sdf {
    /// Checks every parameter of the tree.
    ///
    /// Rejects non-finite numbers, radii/half extents/half heights ≤ 0,
    /// a rounded-box radius above the smallest half extent, a torus tube
    /// wider than its ring, zero plane normals and rotation axes, empty
    /// `children`, `k ≤ 0` and scale `factor ≤ 0`. The first problem found is
    /// reported with its path relative to this shape, e.g.
    /// `children[1].radius: must be > 0, got -1`; prefix it with
    /// [`FieldError::within`] (`objects[2].shape`).
    pub fn validate(&self) -> Result<(), FieldError> {
        match self {
            Sdf::Sphere { center, radius } => {
                check_vec_finite("center", *center)?;
                check_positive("radius", *radius)
            }
            Sdf::Box {
                center,
                half_extents,
            } => {
                check_vec_finite("center", *center)?;
                check_vec_positive("half_extents", *half_extents)
            }
            Sdf::RoundedBox {
                center,
                half_extents,
                radius,
            } => {
                check_vec_finite("center", *center)?;
                check_vec_positive("half_extents", *half_extents)?;
                check_positive("radius", *radius)?;
                let smallest = half_extents.min_element();
                if *radius > smallest {
                    return Err(FieldError::new(
                        "radius",
                        format!("must be <= the smallest half extent ({smallest}), got {radius}"),
                    ));
                }
                Ok(())
            }
            Sdf::Plane(plane) => {
                check_nonzero_direction("normal", plane.normal)?;
                check_finite("offset", plane.offset)
            }
            Sdf::Torus {
                center,
                major_radius,
                minor_radius,
            } => {
                check_vec_finite("center", *center)?;
                check_positive("major_radius", *major_radius)?;
                check_positive("minor_radius", *minor_radius)?;
                if minor_radius > major_radius {
                    return Err(FieldError::new(
                        "minor_radius",
                        format!("must be <= major_radius ({major_radius}), got {minor_radius}"),
                    ));
                }
                Ok(())
            }
            Sdf::Cylinder {
                center,
                radius,
                half_height,
            } => {
                check_vec_finite("center", *center)?;
                check_positive("radius", *radius)?;
                check_positive("half_height", *half_height)
            }
            Sdf::Capsule { a, b, radius } => {
                check_vec_finite("a", *a)?;
                check_vec_finite("b", *b)?;
                check_positive("radius", *radius)
            }
            Sdf::Union { children } | Sdf::Intersection { children } => validate_children(children),
            Sdf::Difference { base, subtract } => {
                base.validate().map_err(|e| e.within("base"))?;
                subtract.validate().map_err(|e| e.within("subtract"))
            }
            Sdf::SmoothUnion { children, k } => {
                check_positive("k", *k)?;
                validate_children(children)
            }
            Sdf::Translate { offset, child } => {
                check_vec_finite("offset", *offset)?;
                child.validate().map_err(|e| e.within("child"))
            }
            Sdf::Rotate(r) => {
                check_nonzero_direction("axis", r.axis)?;
                check_finite("degrees", r.degrees)?;
                r.child.validate().map_err(|e| e.within("child"))
            }
            Sdf::Scale(s) => {
                check_positive("factor", s.factor)?;
                s.child.validate().map_err(|e| e.within("child"))
            }
        }
    }
}

impl SceneObject {
    /// Checks the albedo and the shape; paths are relative to the object
    /// (`shape.radius`, `albedo[1]`).
    pub fn validate(&self) -> Result<(), FieldError> {
        for (i, a) in self.albedo.iter().enumerate() {
            let field = format!("albedo[{i}]");
            check_finite(&field, *a)?;
            if !(0.0..=1.0).contains(a) {
                return Err(FieldError::new(
                    field,
                    format!("must be in [0, 1], got {a}"),
                ));
            }
        }
        self.shape.validate().map_err(|e| e.within("shape"))
    }
}

/// Validates every object; paths start at the index (`[2].shape.radius`), so
/// `validate_objects(o).map_err(|e| e.within("objects"))` gives
/// `objects[2].shape.children[1].radius: must be > 0, got -1`.
pub fn validate_objects(objects: &[SceneObject]) -> Result<(), FieldError> {
    for (i, o) in objects.iter().enumerate() {
        o.validate().map_err(|e| e.within(&format!("[{i}]")))?;
    }
    Ok(())
}
