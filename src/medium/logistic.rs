//! The logistic refractive model of `docs/model.md`.
//!
//! ```text
//! δ(p) = C · |k_s| · D(p) / S
//! D(p) =   n_bg  · σ( y / a_bg )                         background
//!        + n_inv · σ( (h_ciso − y) / a_inv )             inversion layer
//!        + Σ_j n_hot_j · w_j(x, z) · σ( y / a_hot_j )     areal hot spots
//! w_j  = 1 − σ( e_j · (ρ_j − R_j) ),  ρ_j = |(x − x_j, z − z_j)|
//! S    = |n_bg| + |n_inv| + Σ_j |n_hot_j|,   C = 0.003
//! ```
//!
//! | parameter | symbol | unit | meaning |
//! | --- | --- | --- | --- |
//! | `scale` | k_s | – | overall strength (default 1); \|C·k_s\| < 1 keeps n positive |
//! | `background.n`, `background.a` | n_bg, a_bg | –, m | background step: amplitude, rate |
//! | `inversion.n`, `inversion.a`, `inversion.height` | n_inv, a_inv, h | –, m, m | inversion layer |
//! | `hotspots[j].n`, `.a` | n_hot, a_hot | –, m | hot spot strength and vertical rate |
//! | `hotspots[j].x`, `.z`, `.radius` | x_j, z_j, R_j | m | centre on the ground, radius |
//! | `hotspots[j].edge` | e_j | 1/m | rim sharpness (default 10) |
//!
//! Every term is optional: a term that is absent is absent from D and S and has
//! no parameters. A rate may be negative (it flips the step), never zero.
//!
//! ```json
//! { "scale": 1.0,
//!   "background": { "n": 1.0, "a": 40.0 },
//!   "inversion":  { "n": 0.3, "a": 2.0, "height": 25.0 },
//!   "hotspots": [ { "x": 0, "z": 600, "radius": 120, "n": -2, "a": -0.4 } ] }
//! ```

use super::cull::{HotSpotGrid, Reach};
use super::envelope::{Envelope, Patch, VerticalFeature};
use super::rim::rim_weight;
use super::{HotField, IndexField, Param};
use crate::error::FieldError;
use crate::math::{Real, V3, sigmoid};
use serde::{Deserialize, Serialize};

/// The constant C of the model.
pub const C_SCALE: f64 = 0.003;

/// Smallest |rate| accepted: sharper steps than this cannot be resolved in f64
/// over any ray step, and 1/a must stay finite.
const MIN_RATE: f64 = 1e-12;

fn default_scale<T: From<f64>>() -> T {
    T::from(1.0)
}
fn default_edge<T: From<f64>>() -> T {
    T::from(10.0)
}

/// Background term: n_bg · σ(y / a_bg).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Background<T = f64> {
    /// Amplitude n_bg.
    pub n: T,
    /// Rate a_bg (metres).
    pub a: T,
}

/// Inversion layer: n_inv · σ((h − y) / a_inv).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Inversion<T = f64> {
    /// Amplitude n_inv.
    pub n: T,
    /// Rate a_inv (metres).
    pub a: T,
    /// Height of the layer h_ciso (metres).
    pub height: T,
}

/// An areal hot spot: n_hot · w(x, z) · σ(y / a_hot).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(
    deny_unknown_fields,
    bound(deserialize = "T: Deserialize<'de> + From<f64>")
)]
pub struct HotSpot<T = f64> {
    /// Centre x (metres).
    pub x: T,
    /// Centre z (metres).
    pub z: T,
    /// Radius R (metres).
    pub radius: T,
    /// Strength n_hot.
    pub n: T,
    /// Vertical rate a_hot (metres).
    pub a: T,
    /// Rim sharpness e (1/metre).
    #[serde(default = "default_edge")]
    pub edge: T,
}

/// The parameters of the logistic model: the medium as files and the fitter see it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(
    deny_unknown_fields,
    bound(deserialize = "T: Deserialize<'de> + From<f64>")
)]
pub struct LogisticMedium<T = f64> {
    /// Overall strength k_s.
    #[serde(default = "default_scale")]
    pub scale: T,
    /// Background term, if the scene has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub background: Option<Background<T>>,
    /// Inversion layer, if the scene has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inversion: Option<Inversion<T>>,
    /// Areal hot spots.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub hotspots: Vec<HotSpot<T>>,
}

impl<T: Copy> LogisticMedium<T> {
    /// Every parameter with its value, in a fixed order: scale, background,
    /// inversion, then each hot spot's x, z, radius, n, a, edge.
    pub fn params(&self) -> Vec<(Param, T)> {
        let mut out = vec![(Param::Scale, self.scale)];
        if let Some(b) = &self.background {
            out.push((Param::BackgroundN, b.n));
            out.push((Param::BackgroundA, b.a));
        }
        if let Some(i) = &self.inversion {
            out.push((Param::InversionN, i.n));
            out.push((Param::InversionA, i.a));
            out.push((Param::InversionHeight, i.height));
        }
        for (j, h) in self.hotspots.iter().enumerate() {
            for f in HotField::LOGISTIC {
                out.push((Param::Hot(j, f), *h.field(f).expect("a logistic field")));
            }
        }
        out
    }

    /// The value of a parameter, or `None` if this medium has no such parameter.
    pub fn get(&self, p: Param) -> Option<T> {
        self.slot(p).copied()
    }

    /// Sets a parameter; errors if this medium has no such parameter.
    pub fn set(&mut self, p: Param, value: T) -> Result<(), FieldError> {
        match self.slot_mut(p) {
            Some(slot) => {
                *slot = value;
                Ok(())
            }
            None => Err(FieldError::new(p.to_string(), self.absent_reason(p))),
        }
    }

    /// Why `p` is not a parameter of this medium, in words.
    pub fn absent_reason(&self, p: Param) -> String {
        match p {
            Param::BackgroundN | Param::BackgroundA => {
                "this medium has no background term".to_string()
            }
            Param::InversionN | Param::InversionA | Param::InversionHeight => {
                "this medium has no inversion layer".to_string()
            }
            Param::Scale => "always present".to_string(),
            Param::Hot(_, HotField::Delta | HotField::ScaleHeight) => {
                "a field of real air's hot spots (docs/air.md); a logistic hot spot has `n` and `a`"
                    .to_string()
            }
            Param::Hot(j, _) => match self.hotspots.len() {
                0 => "this medium has no hot spots".to_string(),
                n => format!(
                    "hot spot {j} does not exist: this medium has {n} (indices 0 to {})",
                    n - 1
                ),
            },
            Param::LinearN0 | Param::LinearG => {
                "a parameter of the analytic n²-linear kind, not of the logistic model".to_string()
            }
            Param::Air(_) => {
                "a parameter of real air (docs/air.md), not of the logistic model".to_string()
            }
        }
    }

    /// The same medium with every parameter mapped through `f` (used to lift the
    /// parameters to dual numbers for exact derivatives).
    pub fn map<U>(&self, mut f: impl FnMut(Param, T) -> U) -> LogisticMedium<U> {
        LogisticMedium {
            scale: f(Param::Scale, self.scale),
            background: self.background.map(|b| Background {
                n: f(Param::BackgroundN, b.n),
                a: f(Param::BackgroundA, b.a),
            }),
            inversion: self.inversion.map(|i| Inversion {
                n: f(Param::InversionN, i.n),
                a: f(Param::InversionA, i.a),
                height: f(Param::InversionHeight, i.height),
            }),
            hotspots: self
                .hotspots
                .iter()
                .enumerate()
                .map(|(j, h)| HotSpot {
                    x: f(Param::Hot(j, HotField::X), h.x),
                    z: f(Param::Hot(j, HotField::Z), h.z),
                    radius: f(Param::Hot(j, HotField::Radius), h.radius),
                    n: f(Param::Hot(j, HotField::N), h.n),
                    a: f(Param::Hot(j, HotField::A), h.a),
                    edge: f(Param::Hot(j, HotField::Edge), h.edge),
                })
                .collect(),
        }
    }

    fn slot(&self, p: Param) -> Option<&T> {
        match p {
            Param::Scale => Some(&self.scale),
            Param::BackgroundN => self.background.as_ref().map(|b| &b.n),
            Param::BackgroundA => self.background.as_ref().map(|b| &b.a),
            Param::InversionN => self.inversion.as_ref().map(|i| &i.n),
            Param::InversionA => self.inversion.as_ref().map(|i| &i.a),
            Param::InversionHeight => self.inversion.as_ref().map(|i| &i.height),
            Param::Hot(j, f) => self.hotspots.get(j).and_then(|h| h.field(f)),
            Param::LinearN0 | Param::LinearG | Param::Air(_) => None,
        }
    }

    fn slot_mut(&mut self, p: Param) -> Option<&mut T> {
        match p {
            Param::Scale => Some(&mut self.scale),
            Param::BackgroundN => self.background.as_mut().map(|b| &mut b.n),
            Param::BackgroundA => self.background.as_mut().map(|b| &mut b.a),
            Param::InversionN => self.inversion.as_mut().map(|i| &mut i.n),
            Param::InversionA => self.inversion.as_mut().map(|i| &mut i.a),
            Param::InversionHeight => self.inversion.as_mut().map(|i| &mut i.height),
            Param::Hot(j, f) => self.hotspots.get_mut(j).and_then(|h| h.field_mut(f)),
            Param::LinearN0 | Param::LinearG | Param::Air(_) => None,
        }
    }
}

impl<T> HotSpot<T> {
    fn field(&self, f: HotField) -> Option<&T> {
        match f {
            HotField::X => Some(&self.x),
            HotField::Z => Some(&self.z),
            HotField::Radius => Some(&self.radius),
            HotField::N => Some(&self.n),
            HotField::A => Some(&self.a),
            HotField::Edge => Some(&self.edge),
            HotField::Delta | HotField::ScaleHeight => None,
        }
    }
    fn field_mut(&mut self, f: HotField) -> Option<&mut T> {
        match f {
            HotField::X => Some(&mut self.x),
            HotField::Z => Some(&mut self.z),
            HotField::Radius => Some(&mut self.radius),
            HotField::N => Some(&mut self.n),
            HotField::A => Some(&mut self.a),
            HotField::Edge => Some(&mut self.edge),
            HotField::Delta | HotField::ScaleHeight => None,
        }
    }
}

impl LogisticMedium<f64> {
    /// A medium with no terms: δ ≡ 0.
    pub fn vacuum() -> Self {
        LogisticMedium {
            scale: 1.0,
            background: None,
            inversion: None,
            hotspots: Vec::new(),
        }
    }

    /// Whether the model has any term at all.
    pub fn has_terms(&self) -> bool {
        self.background.is_some() || self.inversion.is_some() || !self.hotspots.is_empty()
    }

    /// Checks every rule of `docs/model.md`; the first violation is returned with the
    /// path of the field it concerns.
    pub fn validate(&self) -> Result<(), FieldError> {
        let bad = |p: Param, message: String| Err(FieldError::new(p.to_string(), message));
        for (p, v) in self.params() {
            if !v.is_finite() {
                return bad(p, format!("must be a finite number, got {v}"));
            }
            let is_rate = matches!(
                p,
                Param::BackgroundA | Param::InversionA | Param::Hot(_, HotField::A)
            );
            if is_rate && v.abs() < MIN_RATE {
                return bad(
                    p,
                    format!(
                        "a rate must not be zero (|a| ≥ {MIN_RATE:e} m; a negative rate flips the step), got {v}"
                    ),
                );
            }
            if p == Param::Scale && (C_SCALE * v).abs() >= 1.0 {
                return bad(
                    p,
                    format!(
                        "|C·scale| must stay below 1 so that n = 1 + δ stays positive (|scale| < {:.4}), got {v}",
                        1.0 / C_SCALE
                    ),
                );
            }
            if let Param::Hot(_, HotField::Radius) = p
                && v < 0.0
            {
                return bad(p, format!("a radius must be ≥ 0, got {v}"));
            }
            if let Param::Hot(_, HotField::Edge) = p
                && v <= 0.0
            {
                return bad(
                    p,
                    format!("the rim sharpness must be > 0 (1/metre), got {v}"),
                );
            }
        }
        if self.has_terms() && self.amplitude_sum() == 0.0 {
            let first = self
                .params()
                .into_iter()
                .find(|(p, _)| p.is_amplitude())
                .map(|(p, _)| p)
                .unwrap_or(Param::Scale);
            return bad(
                first,
                "all amplitudes are zero while a term is present, so S = 0 and δ is undefined; remove the terms instead".to_string(),
            );
        }
        Ok(())
    }

    /// S = Σ |amplitudes|.
    pub fn amplitude_sum(&self) -> f64 {
        self.params()
            .into_iter()
            .filter(|(p, _)| p.is_amplitude())
            .map(|(_, v)| v.abs())
            .sum()
    }

    /// The compiled, evaluation-ready field.
    pub fn field(&self) -> LogisticField<f64> {
        LogisticField::new(self)
    }

    /// Bounds and features for stepping through the air ([`Envelope`]):
    /// |D/S| ≤ 1 since every σ and w lies in [0, 1], so n ∈ [1 − k, 1 + k] with
    /// k = C·|k_s|; |σ'| ≤ 1/4 bounds each term's gradient by its share of k
    /// times ¼·(1/|a| + e).
    pub fn envelope(&self) -> Envelope {
        if !self.has_terms() {
            return Envelope {
                n_max: 1.0,
                n_min: 1.0,
                gradient_max: 0.0,
                layers: Vec::new(),
                patches: Vec::new(),
            };
        }
        let k = C_SCALE * self.scale.abs();
        let s = self.amplitude_sum();
        let share = |n: f64| if s > 0.0 { n.abs() / s } else { 0.0 };
        let mut g = 0.0;
        let mut layers = Vec::new();
        if let Some(b) = &self.background {
            g += share(b.n) * 0.25 / b.a.abs();
            layers.push(VerticalFeature {
                scale: b.a.abs(),
                centre: 0.0,
            });
        }
        if let Some(i) = &self.inversion {
            g += share(i.n) * 0.25 / i.a.abs();
            layers.push(VerticalFeature {
                scale: i.a.abs(),
                centre: i.height,
            });
        }
        for h in &self.hotspots {
            g += share(h.n) * 0.25 * (1.0 / h.a.abs() + h.edge);
        }
        Envelope {
            n_max: 1.0 + k,
            n_min: 1.0 - k,
            gradient_max: k * g,
            layers,
            patches: self
                .hotspots
                .iter()
                .map(|h| Patch {
                    x: h.x,
                    z: h.z,
                    radius: h.radius,
                    edge: h.edge,
                    rate: h.a,
                })
                .collect(),
        }
    }
}

/// The logistic model compiled for evaluation: amplitudes pre-divided by S and
/// multiplied by C·|k_s|, reciprocal rates, all in the scalar type `T` so that
/// the same code yields exact parameter derivatives.
///
/// With many hot spots, a point pays only for those within reach: a
/// [`HotSpotGrid`] built from the parameters' real parts lists them, and the
/// terms left out are below the threshold of `docs/model.md` ("Culling").
/// [`LogisticField::unculled`] evaluates every term.
#[derive(Clone, Debug)]
pub struct LogisticField<T = f64> {
    background: Option<Layer<T>>,
    inversion: Option<(Layer<T>, T)>,
    hotspots: Vec<CompiledHotSpot<T>>,
    grid: Option<HotSpotGrid>,
}

#[derive(Clone, Copy, Debug)]
struct Layer<T> {
    amp: T,
    inv_rate: T,
}

#[derive(Clone, Copy, Debug)]
struct CompiledHotSpot<T> {
    layer: Layer<T>,
    x: T,
    z: T,
    radius: T,
    edge: T,
}

impl<T: Real> LogisticField<T> {
    /// Compiles a medium (validated or not: an invalid medium gives non-finite
    /// values that the caller must treat as a failed evaluation).
    pub fn new(m: &LogisticMedium<T>) -> Self {
        // Normalise by the largest amplitude first so that S cannot overflow even
        // for amplitudes near f64::MAX; only the ratios n/S matter.
        let amps: Vec<T> = m
            .params()
            .into_iter()
            .filter(|(p, _)| p.is_amplitude())
            .map(|(_, v)| v)
            .collect();
        // A subnormal largest amplitude (below 2.2e-308) has no finite 1/big:
        // lift every amplitude by 2^600 first (exact), then divide (fuzzing
        // found δ = NaN from 1/big = ∞).
        let big = amps.iter().map(|a| a.val().abs()).fold(0.0, f64::max);
        let pre = if big < f64::MIN_POSITIVE {
            2f64.powi(600)
        } else {
            1.0
        };
        let norm = if big > 0.0 && big.is_finite() {
            1.0 / (big * pre)
        } else {
            1.0
        };
        let unit = |a: T| (a * pre) * norm;
        let s: T = amps.iter().fold(T::cst(0.0), |acc, a| acc + unit(*a).abs());
        let k = m.scale.abs() * C_SCALE;
        let coef = |n: T| k * unit(n) / s;
        let layer = |n: T, a: T| Layer {
            amp: coef(n),
            inv_rate: a.recip(),
        };
        let reaches: Vec<Reach> = m
            .hotspots
            .iter()
            .map(|h| Reach::of(h.x.val(), h.z.val(), h.radius.val(), h.edge.val()))
            .collect();
        LogisticField {
            grid: HotSpotGrid::new(&reaches),
            background: m.background.map(|b| layer(b.n, b.a)),
            inversion: m.inversion.map(|i| (layer(i.n, i.a), i.height)),
            hotspots: m
                .hotspots
                .iter()
                .map(|h| CompiledHotSpot {
                    layer: layer(h.n, h.a),
                    x: h.x,
                    z: h.z,
                    radius: h.radius,
                    edge: h.edge,
                })
                .collect(),
        }
    }
}

impl<T> LogisticField<T> {
    /// The same field evaluating every hot spot everywhere (no culling): the
    /// reference that culled results are checked against.
    pub fn unculled(mut self) -> Self {
        self.grid = None;
        self
    }

    /// The grid that culls the hot spots, if this field has one (see
    /// [`HotSpotGrid::new`] for when it does).
    pub fn grid(&self) -> Option<&HotSpotGrid> {
        self.grid.as_ref()
    }
}

/// A [`LogisticField`]'s compiled coefficients as plain arrays, for the
/// SIMD tracer (`trace::batch`), which evaluates the same formula lane-wise
/// (in `f64`, or from a dual-number field for its tangent kernel).
#[derive(Clone, Debug)]
pub(crate) struct RawCoefficients<T = f64> {
    /// Background `[amp, 1/a]`.
    pub background: Option<[T; 2]>,
    /// Inversion `[amp, 1/a, height]`.
    pub inversion: Option<[T; 3]>,
    /// Per hot spot `[amp, 1/a, x, z, radius, edge]`.
    pub hotspots: Vec<[T; 6]>,
    /// The grid that culls them, if any.
    pub grid: Option<HotSpotGrid>,
}

impl<T: Copy> LogisticField<T> {
    /// The compiled coefficients as plain arrays (see [`RawCoefficients`]).
    pub(crate) fn coefficients(&self) -> RawCoefficients<T> {
        RawCoefficients {
            background: self.background.map(|l| [l.amp, l.inv_rate]),
            inversion: self.inversion.map(|(l, h)| [l.amp, l.inv_rate, h]),
            hotspots: self
                .hotspots
                .iter()
                .map(|h| [h.layer.amp, h.layer.inv_rate, h.x, h.z, h.radius, h.edge])
                .collect(),
            grid: self.grid.clone(),
        }
    }
}

impl<T: Real> IndexField<T> for LogisticField<T> {
    #[inline]
    fn delta_gradient(&self, p: V3<T>) -> (T, V3<T>) {
        let zero = T::cst(0.0);
        let mut delta = zero;
        let mut grad = V3::new(zero, zero, zero);
        if let Some(b) = &self.background {
            let (s, ds) = sigmoid(p.y * b.inv_rate);
            delta += b.amp * s;
            grad.y += b.amp * ds * b.inv_rate;
        }
        if let Some((l, h)) = &self.inversion {
            let (s, ds) = sigmoid((*h - p.y) * l.inv_rate);
            delta += l.amp * s;
            grad.y -= l.amp * ds * l.inv_rate;
        }
        let mut add = |hs: &CompiledHotSpot<T>| {
            let (w, dw_drho, ux, uz) = rim_weight(p.x - hs.x, p.z - hs.z, hs.radius, hs.edge);
            let (s, ds) = sigmoid(p.y * hs.layer.inv_rate);
            let amp_s = hs.layer.amp * s;
            delta += amp_s * w;
            grad.y += hs.layer.amp * w * ds * hs.layer.inv_rate;
            grad.x += amp_s * dw_drho * ux;
            grad.z += amp_s * dw_drho * uz;
        };
        match &self.grid {
            // The hot spots within reach, in the medium's order (the decision
            // on the real parts: the set is constant around the point, so
            // dual parts are those of the terms kept).
            Some(grid) => {
                for &j in grid.candidates(p.x.val(), p.z.val()) {
                    add(&self.hotspots[j as usize]);
                }
            }
            None => self.hotspots.iter().for_each(add),
        }
        (delta, grad)
    }

    fn is_stratified(&self) -> bool {
        self.hotspots.is_empty()
    }
}
