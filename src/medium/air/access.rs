//! Real air's parameters by path: listing, reading, writing and mapping
//! (to dual numbers), in one fixed order.

use super::model::{Air, AirHotSpot, AirMedium, Exponential, Humidity, Lapse, Step, Temperature};
use super::refractivity::Formula;
use crate::error::FieldError;
use crate::medium::{AirParam, HotField, Param};

impl<T: Copy> AirMedium<T> {
    /// Every parameter with its value: the temperature's (base, lapse,
    /// exponential, inversion, table rows), pressure, humidity (the number,
    /// or the humidity table's rows as the temperature table's), wavelength,
    /// CO₂, the Gladstone–Dale constant, then each hot spot's x, z, radius,
    /// edge, delta, scale_height.
    pub fn params(&self) -> Vec<(Param, T)> {
        let mut out = Vec::new();
        let mut push = |a: AirParam, v: T| out.push((Param::Air(a), v));
        let t = &self.air.temperature;
        if let Some(b) = t.base {
            push(AirParam::Base, b);
        }
        if let Some(Lapse::Rate(r)) = t.lapse {
            push(AirParam::Lapse, r);
        }
        if let Some(e) = t.exponential {
            push(AirParam::ExponentialDelta, e.delta);
            push(AirParam::ExponentialScaleHeight, e.scale_height);
        }
        if let Some(i) = t.inversion {
            push(AirParam::InversionDelta, i.delta);
            push(AirParam::InversionHeight, i.height);
            push(AirParam::InversionThickness, i.thickness);
        }
        for (i, row) in t.table.iter().flatten().enumerate() {
            push(AirParam::TableHeight(i), row[0]);
            push(AirParam::TableTemperature(i), row[1]);
        }
        push(AirParam::Pressure, self.air.pressure);
        match &self.air.humidity {
            Humidity::Constant(h) => push(AirParam::Humidity, *h),
            Humidity::Table(rows) => {
                for (i, row) in rows.iter().enumerate() {
                    push(AirParam::HumidityTableHeight(i), row[0]);
                    push(AirParam::HumidityTableValue(i), row[1]);
                }
            }
        }
        push(AirParam::Wavelength, self.air.wavelength);
        push(AirParam::Co2, self.air.co2);
        if let Formula::GladstoneDale(k) = self.air.refractivity {
            push(AirParam::GladstoneDale, k);
        }
        for (j, h) in self.hotspots.iter().enumerate() {
            for f in HotField::AIR {
                out.push((Param::Hot(j, f), *h.field(f).expect("a real-air field")));
            }
        }
        out
    }

    /// The value of a parameter, or `None` if this medium has no such parameter.
    pub fn get(&self, p: Param) -> Option<T> {
        self.params()
            .into_iter()
            .find(|(q, _)| *q == p)
            .map(|(_, v)| v)
    }

    /// Sets a parameter; errors (path relative to the medium) if this medium has
    /// no such parameter.
    pub fn set(&mut self, p: Param, value: T) -> Result<(), FieldError> {
        match self.slot_mut(p) {
            Some(slot) => {
                *slot = value;
                Ok(())
            }
            None => Err(FieldError::new(p.to_string(), self.absent_reason(p))),
        }
    }

    fn slot_mut(&mut self, p: Param) -> Option<&mut T> {
        let air = &mut self.air;
        let t = &mut air.temperature;
        match p {
            Param::Air(a) => match a {
                AirParam::Base => t.base.as_mut(),
                AirParam::Lapse => match &mut t.lapse {
                    Some(Lapse::Rate(r)) => Some(r),
                    _ => None,
                },
                AirParam::ExponentialDelta => t.exponential.as_mut().map(|e| &mut e.delta),
                AirParam::ExponentialScaleHeight => {
                    t.exponential.as_mut().map(|e| &mut e.scale_height)
                }
                AirParam::InversionDelta => t.inversion.as_mut().map(|i| &mut i.delta),
                AirParam::InversionHeight => t.inversion.as_mut().map(|i| &mut i.height),
                AirParam::InversionThickness => t.inversion.as_mut().map(|i| &mut i.thickness),
                AirParam::TableHeight(i) => t
                    .table
                    .as_mut()
                    .and_then(|r| r.get_mut(i))
                    .map(|r| &mut r[0]),
                AirParam::TableTemperature(i) => t
                    .table
                    .as_mut()
                    .and_then(|r| r.get_mut(i))
                    .map(|r| &mut r[1]),
                AirParam::Pressure => Some(&mut air.pressure),
                AirParam::Humidity => match &mut air.humidity {
                    Humidity::Constant(h) => Some(h),
                    Humidity::Table(_) => None,
                },
                AirParam::HumidityTableHeight(i) => match &mut air.humidity {
                    Humidity::Table(rows) => rows.get_mut(i).map(|r| &mut r[0]),
                    Humidity::Constant(_) => None,
                },
                AirParam::HumidityTableValue(i) => match &mut air.humidity {
                    Humidity::Table(rows) => rows.get_mut(i).map(|r| &mut r[1]),
                    Humidity::Constant(_) => None,
                },
                AirParam::Wavelength => Some(&mut air.wavelength),
                AirParam::Co2 => Some(&mut air.co2),
                AirParam::GladstoneDale => match &mut air.refractivity {
                    Formula::GladstoneDale(k) => Some(k),
                    _ => None,
                },
            },
            Param::Hot(j, f) => self.hotspots.get_mut(j).and_then(|h| h.field_mut(f)),
            _ => None,
        }
    }

    /// Why `p` is not a parameter of this medium, in words.
    pub fn absent_reason(&self, p: Param) -> String {
        let t = &self.air.temperature;
        match p {
            Param::Air(a) => match a {
                AirParam::Base => "the temperature has no `base` (a table, or the default 15 °C, which is not a parameter until written)".to_string(),
                AirParam::Lapse => "the temperature has no numeric `lapse` (none, or \"standard\")".to_string(),
                AirParam::ExponentialDelta | AirParam::ExponentialScaleHeight => {
                    "the temperature has no `exponential` surface layer".to_string()
                }
                AirParam::InversionDelta
                | AirParam::InversionHeight
                | AirParam::InversionThickness => {
                    "the temperature has no `inversion` step".to_string()
                }
                AirParam::TableHeight(i) | AirParam::TableTemperature(i) => match &t.table {
                    None => "the temperature has no `table`".to_string(),
                    Some(rows) => format!(
                        "the table has {} rows (indices 0 to {}), not row {i}",
                        rows.len(),
                        rows.len().saturating_sub(1)
                    ),
                },
                AirParam::GladstoneDale => {
                    "the refractivity is not `{\"gladstone_dale\": K}`".to_string()
                }
                AirParam::Humidity => {
                    "the humidity is a table: its rows are `air.humidity.table[i][0]` (m) and `[i][1]` (0…1)".to_string()
                }
                AirParam::HumidityTableHeight(i) | AirParam::HumidityTableValue(i) => {
                    match &self.air.humidity {
                        Humidity::Constant(_) => {
                            "the humidity is one number (`air.humidity`), not a `table`".to_string()
                        }
                        Humidity::Table(rows) => format!(
                            "the humidity table has {} rows (indices 0 to {}), not row {i}",
                            rows.len(),
                            rows.len().saturating_sub(1)
                        ),
                    }
                }
                AirParam::Pressure | AirParam::Wavelength | AirParam::Co2 => {
                    "always present".to_string()
                }
            },
            Param::Hot(_, HotField::N | HotField::A) => {
                "a field of the logistic model's hot spots; a real-air hot spot has `delta` (K) and `scale_height` (m)".to_string()
            }
            Param::Hot(j, _) => match self.hotspots.len() {
                0 => "this medium has no hot spots".to_string(),
                n => format!(
                    "hot spot {j} does not exist: this medium has {n} (indices 0 to {})",
                    n - 1
                ),
            },
            _ => format!(
                "`{p}` is a parameter of the logistic model or the analytic kind, not of real air (its parameters are `air.…` and `hotspots[j].…`)"
            ),
        }
    }

    /// The same medium with every parameter mapped through `f` (to lift the
    /// parameters to dual numbers for exact derivatives).
    pub fn map<U>(&self, mut f: impl FnMut(Param, T) -> U) -> AirMedium<U> {
        let mut g = |a: AirParam, v: T| f(Param::Air(a), v);
        let t = &self.air.temperature;
        let temperature = Temperature {
            base: t.base.map(|b| g(AirParam::Base, b)),
            lapse: t.lapse.map(|l| match l {
                Lapse::Rate(r) => Lapse::Rate(g(AirParam::Lapse, r)),
                Lapse::Standard => Lapse::Standard,
            }),
            exponential: t.exponential.map(|e| Exponential {
                delta: g(AirParam::ExponentialDelta, e.delta),
                scale_height: g(AirParam::ExponentialScaleHeight, e.scale_height),
            }),
            inversion: t.inversion.map(|i| Step {
                delta: g(AirParam::InversionDelta, i.delta),
                height: g(AirParam::InversionHeight, i.height),
                thickness: g(AirParam::InversionThickness, i.thickness),
            }),
            table: t.table.as_ref().map(|rows| {
                rows.iter()
                    .enumerate()
                    .map(|(i, r)| {
                        [
                            g(AirParam::TableHeight(i), r[0]),
                            g(AirParam::TableTemperature(i), r[1]),
                        ]
                    })
                    .collect()
            }),
        };
        let a = &self.air;
        let air = Air {
            temperature,
            pressure: g(AirParam::Pressure, a.pressure),
            hydrostatic: a.hydrostatic,
            humidity: match &a.humidity {
                Humidity::Constant(h) => Humidity::Constant(g(AirParam::Humidity, *h)),
                Humidity::Table(rows) => Humidity::Table(
                    rows.iter()
                        .enumerate()
                        .map(|(i, r)| {
                            [
                                g(AirParam::HumidityTableHeight(i), r[0]),
                                g(AirParam::HumidityTableValue(i), r[1]),
                            ]
                        })
                        .collect(),
                ),
            },
            wavelength: g(AirParam::Wavelength, a.wavelength),
            co2: g(AirParam::Co2, a.co2),
            refractivity: match a.refractivity {
                Formula::Ciddor => Formula::Ciddor,
                Formula::Edlen => Formula::Edlen,
                Formula::GladstoneDale(k) => Formula::GladstoneDale(g(AirParam::GladstoneDale, k)),
            },
        };
        let hotspots = self
            .hotspots
            .iter()
            .enumerate()
            .map(|(j, h)| AirHotSpot {
                x: f(Param::Hot(j, HotField::X), h.x),
                z: f(Param::Hot(j, HotField::Z), h.z),
                radius: f(Param::Hot(j, HotField::Radius), h.radius),
                edge: f(Param::Hot(j, HotField::Edge), h.edge),
                delta: f(Param::Hot(j, HotField::Delta), h.delta),
                scale_height: f(Param::Hot(j, HotField::ScaleHeight), h.scale_height),
            })
            .collect();
        AirMedium { air, hotspots }
    }
}

impl<T> AirHotSpot<T> {
    fn field(&self, f: HotField) -> Option<&T> {
        match f {
            HotField::X => Some(&self.x),
            HotField::Z => Some(&self.z),
            HotField::Radius => Some(&self.radius),
            HotField::Edge => Some(&self.edge),
            HotField::Delta => Some(&self.delta),
            HotField::ScaleHeight => Some(&self.scale_height),
            HotField::N | HotField::A => None,
        }
    }
    fn field_mut(&mut self, f: HotField) -> Option<&mut T> {
        match f {
            HotField::X => Some(&mut self.x),
            HotField::Z => Some(&mut self.z),
            HotField::Radius => Some(&mut self.radius),
            HotField::Edge => Some(&mut self.edge),
            HotField::Delta => Some(&mut self.delta),
            HotField::ScaleHeight => Some(&mut self.scale_height),
            HotField::N | HotField::A => None,
        }
    }
}
