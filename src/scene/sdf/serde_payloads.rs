//! serde for the payloads with derived fields: (de)serialize the plain fields
//! through a spec struct that denies unknown fields, derive the rest.

use glam::DVec3;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::{Plane, Rotate, Scale, Sdf};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PlaneSpec {
    normal: DVec3,
    offset: f64,
}

#[derive(Serialize)]
struct PlaneRef {
    normal: DVec3,
    offset: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RotateSpec {
    axis: DVec3,
    degrees: f64,
    child: Sdf,
}

#[derive(Serialize)]
struct RotateRef<'a> {
    axis: DVec3,
    degrees: f64,
    child: &'a Sdf,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ScaleSpec {
    factor: f64,
    child: Sdf,
}

#[derive(Serialize)]
struct ScaleRef<'a> {
    factor: f64,
    child: &'a Sdf,
}

impl<'de> Deserialize<'de> for Plane {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let s = PlaneSpec::deserialize(deserializer)?;
        Ok(Plane::new(s.normal, s.offset))
    }
}

impl Serialize for Plane {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        PlaneRef {
            normal: self.normal,
            offset: self.offset,
        }
        .serialize(serializer)
    }
}

impl<'de> Deserialize<'de> for Rotate {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let s = RotateSpec::deserialize(deserializer)?;
        Ok(Rotate::new(s.axis, s.degrees, s.child))
    }
}

impl Serialize for Rotate {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        RotateRef {
            axis: self.axis,
            degrees: self.degrees,
            child: &self.child,
        }
        .serialize(serializer)
    }
}

impl<'de> Deserialize<'de> for Scale {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let s = ScaleSpec::deserialize(deserializer)?;
        Ok(Scale::new(s.factor, s.child))
    }
}

impl Serialize for Scale {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        ScaleRef {
            factor: self.factor,
            child: &self.child,
        }
        .serialize(serializer)
    }
}
