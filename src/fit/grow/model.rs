//! A model under growth: a medium of either growable kind (the logistic
//! model or real air), its free parameters and their bounds, and which of its
//! terms growing added (only those may be dropped).
//!
//! **The logistic model.** Adding or dropping a term changes
//! S = Σ|amplitudes|, which divides every term (`docs/model.md`); `scale` is
//! multiplied by S_new/S_old at the same time, so the other terms' δ does not
//! change.
//!
//! **The gauge.** δ does not change when every amplitude is multiplied by the
//! same number, so with `scale` free one amplitude must be held, or the fit
//! has a flat direction that makes every amplitude look undetermined.
//! `scale` is freed with the first grown term (the grown terms' amplitudes
//! free, the problem's as the problem says), so the background's amplitude
//! stays fixed unless the problem frees it; a model with every amplitude
//! free has the first held ([`GAUGE_REASON`]). With every grown term dropped
//! again, `scale` is free only if the problem freed it. Every model growing
//! fits is therefore gauge-free, and its identifiability means what the data
//! can tell. A fit that turned every term off (`scale` → 0) gives a new
//! term no strength and no derivative: its seeds start from the start's
//! strength per unit of amplitude.
//!
//! **Held parameters.** A parameter the pairs cannot determine, or one that
//! runs away, is held ([`Model::hold`]): set back to its value at the start
//! of the fit, taken out of `free`, and listed in `held` with the reason.
//!
//! **Real air.** Temperatures are absolute (`docs/air.md`): a term adds its
//! kelvins and nothing else changes, so nothing is rescaled and no extra
//! parameter is freed.

use crate::medium::air::{AirHotSpot, Exponential, Step};
use crate::medium::{AirParam, HotField, HotSpot, Inversion, Medium, Param};

/// The parameters a grown logistic hot spot frees (its `edge` stays as seeded).
pub const HOT_FREE: [HotField; 5] = [
    HotField::X,
    HotField::Z,
    HotField::Radius,
    HotField::N,
    HotField::A,
];

/// The parameters a grown real-air hot spot frees (its `edge` stays as seeded).
pub const AIR_HOT_FREE: [HotField; 5] = [
    HotField::X,
    HotField::Z,
    HotField::Radius,
    HotField::Delta,
    HotField::ScaleHeight,
];

/// The parameters of the logistic inversion, in the order they are freed.
const INVERSION_FREE: [Param; 3] = [Param::InversionN, Param::InversionA, Param::InversionHeight];

/// The parameters of real air's step aloft, in the order they are freed.
const AIR_INVERSION_FREE: [Param; 3] = [
    Param::Air(AirParam::InversionDelta),
    Param::Air(AirParam::InversionHeight),
    Param::Air(AirParam::InversionThickness),
];

/// The parameters of real air's surface layer, in the order they are freed.
const SURFACE_FREE: [Param; 2] = [
    Param::Air(AirParam::ExponentialDelta),
    Param::Air(AirParam::ExponentialScaleHeight),
];

/// A term growing may add or drop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Term {
    /// Real air's surface layer, `air.temperature.exponential`.
    SurfaceLayer,
    /// The inversion: the logistic `inversion`, or real air's step aloft
    /// `air.temperature.inversion`.
    Inversion,
    /// Hot spot j of the medium.
    HotSpot(usize),
}

impl Term {
    /// Its path name in `medium` (`inversion`, `air.temperature.inversion`,
    /// `air.temperature.exponential`, `hotspots[2]`).
    pub fn name(self, medium: &Medium) -> String {
        let air = matches!(medium, Medium::Air(_));
        match self {
            Term::SurfaceLayer => "air.temperature.exponential".into(),
            Term::Inversion if air => "air.temperature.inversion".into(),
            Term::Inversion => "inversion".into(),
            Term::HotSpot(j) => format!("hotspots[{j}]"),
        }
    }

    /// Whether `p` is one of its parameters (of either kind).
    pub fn owns(self, p: Param) -> bool {
        match (self, p) {
            (Term::SurfaceLayer, p) => SURFACE_FREE.contains(&p),
            (Term::Inversion, p) => INVERSION_FREE.contains(&p) || AIR_INVERSION_FREE.contains(&p),
            (Term::HotSpot(j), Param::Hot(k, _)) => j == k,
            (Term::HotSpot(_), _) => false,
        }
    }
}

/// A medium with its free parameters: what one candidate fit fits.
#[derive(Clone, Debug, PartialEq)]
pub struct Model {
    /// The medium, at the current (start or fitted) values: the logistic
    /// model or real air.
    pub medium: Medium,
    /// Free parameters, in order: the problem's, then (logistic) `scale`,
    /// then each grown term's.
    pub free: Vec<Param>,
    /// `[low, high]` per free parameter.
    pub bounds: Vec<(f64, f64)>,
    /// Terms growing added, in the order added.
    pub grown: Vec<Term>,
    /// Parameters held at a value instead of fitted, and why.
    pub held: Vec<Held>,
    /// The problem's own free parameters and their bounds (what `free`
    /// returns to when every grown term is dropped, less the held ones).
    pub base_free: Vec<(Param, (f64, f64))>,
    /// The start's `scale` per unit of amplitude, k/S (logistic; 0 for real
    /// air): a seed whose strength fell far below it starts from it.
    pub base_strength: f64,
}

/// The least |rate| (m) of a logistic rate the problem frees without
/// bounds, during growth: the rate keeps its sign.
pub const MIN_RATE: f64 = 1e-3;

/// Why the gauge amplitude is held.
pub const GAUGE_REASON: &str = "the gauge: δ does not change when every amplitude is multiplied by the same number, so the first is held and the others and `scale` set the strengths";

/// A parameter held at a value: one the pairs do not determine, one that
/// ran away in a fit, or the amplitude that fixes the logistic gauge.
#[derive(Clone, Debug, PartialEq)]
pub struct Held {
    /// The parameter.
    pub param: Param,
    /// The value it is held at: where the fit put it (undetermined), its start
    /// (ran away), or the start's (the gauge).
    pub value: f64,
    /// Why, in words.
    pub reason: String,
}

impl Model {
    /// The free parameters' current values.
    pub fn x(&self) -> Vec<f64> {
        self.free
            .iter()
            .map(|p| self.medium.get(*p).unwrap_or(f64::NAN))
            .collect()
    }

    /// The same model with the free parameters set to `x`.
    pub fn at(&self, x: &[f64]) -> Model {
        let mut m = self.clone();
        for (p, v) in self.free.iter().zip(x) {
            // Every free parameter names a term of the medium.
            let _ = m.medium.set(*p, *v);
        }
        m
    }

    /// The medium's hot spots.
    pub fn hot_spots(&self) -> usize {
        match &self.medium {
            Medium::Logistic(m) => m.hotspots.len(),
            Medium::Air(m) => m.hotspots.len(),
            Medium::LinearSquare(_) => 0,
        }
    }

    /// Whether the medium has the (logistic or real-air) inversion.
    pub fn has_inversion(&self) -> bool {
        match &self.medium {
            Medium::Logistic(m) => m.inversion.is_some(),
            Medium::Air(m) => m.air.temperature.inversion.is_some(),
            Medium::LinearSquare(_) => true,
        }
    }

    /// The medium's terms by name, in the medium's order: `background` or
    /// `air` (the uniform air: base, lapse or table), then the layers, then
    /// the hot spots.
    pub fn terms(&self) -> Vec<String> {
        let mut t = Vec::new();
        match &self.medium {
            Medium::Logistic(m) => {
                if m.background.is_some() {
                    t.push("background".to_string());
                }
                if m.inversion.is_some() {
                    t.push(Term::Inversion.name(&self.medium));
                }
            }
            Medium::Air(m) => {
                t.push("air".to_string());
                if m.air.temperature.exponential.is_some() {
                    t.push(Term::SurfaceLayer.name(&self.medium));
                }
                if m.air.temperature.inversion.is_some() {
                    t.push(Term::Inversion.name(&self.medium));
                }
            }
            Medium::LinearSquare(_) => t.push("linear_square".to_string()),
        }
        t.extend((0..self.hot_spots()).map(|j| Term::HotSpot(j).name(&self.medium)));
        t
    }

    /// The model of a problem's start: its medium, free parameters and
    /// bounds, nothing grown; a logistic start that frees every amplitude
    /// has the first held ([`GAUGE_REASON`]).
    pub fn start(medium: Medium, free: Vec<Param>, bounds: Vec<(f64, f64)>) -> Model {
        let base_strength = match &medium {
            Medium::Logistic(l) if l.amplitude_sum() > 0.0 => l.scale / l.amplitude_sum(),
            _ => 0.0,
        };
        // A logistic rate never crosses zero, where the model is undefined:
        // an unbounded one keeps its sign (and |a| ≥ 1 mm), as grown ones do.
        let bounds: Vec<(f64, f64)> = free
            .iter()
            .zip(bounds)
            .map(|(p, b)| {
                let rate = matches!(
                    p,
                    Param::BackgroundA | Param::InversionA | Param::Hot(_, HotField::A)
                );
                match medium.get(*p) {
                    Some(v) if rate && b.0 == f64::NEG_INFINITY && b.1 == f64::INFINITY => {
                        if v > 0.0 {
                            (MIN_RATE, f64::INFINITY)
                        } else {
                            (f64::NEG_INFINITY, -MIN_RATE)
                        }
                    }
                    _ => b,
                }
            })
            .collect();
        let mut m = Model {
            medium,
            base_free: free.iter().copied().zip(bounds.iter().copied()).collect(),
            free,
            bounds,
            grown: vec![],
            held: vec![],
            base_strength,
        };
        m.regauge();
        m
    }

    /// Whether `p` is held.
    pub fn is_held(&self, p: Param) -> bool {
        self.held.iter().any(|h| h.param == p)
    }

    /// The model with `params` held: each set to `values` (same order), taken
    /// out of `free` and listed in `held` with its reason.
    pub fn hold(&self, params: &[(Param, f64, String)]) -> Model {
        let mut m = self.clone();
        for (p, v, why) in params {
            let _ = m.medium.set(*p, *v);
            m.unfree(*p);
            m.held.push(Held {
                param: *p,
                value: *v,
                reason: why.clone(),
            });
        }
        m
    }

    /// Takes `p` out of `free` (and its bounds), if it is there.
    fn unfree(&mut self, p: Param) {
        if let Some(k) = self.free.iter().position(|q| *q == p) {
            self.free.remove(k);
            self.bounds.remove(k);
        }
    }

    /// The problem's bounds of `p`, if the problem frees it.
    fn base_bounds(&self, p: Param) -> Option<(f64, f64)> {
        self.base_free
            .iter()
            .find(|(q, _)| *q == p)
            .map(|(_, b)| *b)
    }

    /// Sets the logistic parametrisation after a change of terms (see the
    /// module doc): `scale` free with a grown term or where the problem
    /// frees it, and the first amplitude held when every one is free. Real
    /// air has no gauge: nothing changes.
    fn regauge(&mut self) {
        let Medium::Logistic(l) = &self.medium else {
            return;
        };
        let mut amplitudes: Vec<(Param, f64)> = Vec::new();
        if let Some(b) = l.background {
            amplitudes.push((Param::BackgroundN, b.n));
        }
        if let Some(i) = l.inversion {
            amplitudes.push((Param::InversionN, i.n));
        }
        amplitudes.extend(
            l.hotspots
                .iter()
                .enumerate()
                .map(|(j, h)| (Param::Hot(j, HotField::N), h.n)),
        );
        self.held.retain(|h| h.reason != GAUGE_REASON);
        let grown = !self.grown.is_empty();
        match (self.base_bounds(Param::Scale), grown) {
            (Some(b), _) => self.free_param(Param::Scale, b),
            (None, true) => self.free_param(Param::Scale, (0.0, f64::INFINITY)),
            (None, false) => self.unfree(Param::Scale),
        }
        if amplitudes.is_empty() || !amplitudes.iter().all(|(p, _)| self.free.contains(p)) {
            return;
        }
        // Every amplitude free: the first (the background's) is held.
        let (p, v) = amplitudes[0];
        self.unfree(p);
        self.held.push(Held {
            param: p,
            value: v,
            reason: GAUGE_REASON.into(),
        });
    }

    /// Frees `p` with `bounds` unless it is free already or held.
    fn free_param(&mut self, p: Param, bounds: (f64, f64)) {
        if !self.free.contains(&p) && !self.is_held(p) {
            self.free.push(p);
            self.bounds.push(bounds);
        }
    }

    /// The model with `change` made to its medium, then `term`'s
    /// parameters `params` freed within their bounds. A logistic medium keeps
    /// the other terms' δ (its `scale` rescaled, and freed).
    fn with_term(
        &self,
        term: Term,
        change: impl FnOnce(&mut Medium),
        params: impl IntoIterator<Item = (Param, (f64, f64))>,
    ) -> Model {
        let mut m = self.clone();
        let s_old = amplitude_sum(&m.medium);
        change(&mut m.medium);
        keep_strengths(&mut m.medium, s_old);
        if let Medium::Logistic(l) = &mut m.medium {
            // A model whose fit turned every term off (`scale` → 0) would
            // give the new term no strength and no derivative: the seed
            // starts from the start's strength per unit of amplitude.
            let s = l.amplitude_sum();
            if l.scale < 0.1 * self.base_strength * s {
                l.scale = self.base_strength * s;
            }
        }
        if matches!(m.medium, Medium::Logistic(_)) {
            let b = self
                .base_bounds(Param::Scale)
                .unwrap_or((0.0, f64::INFINITY));
            m.free_param(Param::Scale, b);
        }
        for (p, b) in params {
            m.free_param(p, b);
        }
        m.grown.push(term);
        m.regauge();
        m
    }

    /// The logistic model with `spot` added as a new hot spot, its
    /// [`HOT_FREE`] parameters freed within `bounds` (in that order).
    pub fn with_hot_spot(&self, spot: HotSpot, bounds: [(f64, f64); 5]) -> Model {
        let j = self.hot_spots();
        self.with_term(
            Term::HotSpot(j),
            |m| {
                if let Medium::Logistic(m) = m {
                    m.hotspots.push(spot);
                }
            },
            HOT_FREE.map(|f| Param::Hot(j, f)).into_iter().zip(bounds),
        )
    }

    /// The real-air model with `spot` added as a new hot spot, its
    /// [`AIR_HOT_FREE`] parameters freed within `bounds` (in that order).
    pub fn with_air_hot_spot(&self, spot: AirHotSpot, bounds: [(f64, f64); 5]) -> Model {
        let j = self.hot_spots();
        self.with_term(
            Term::HotSpot(j),
            |m| {
                if let Medium::Air(m) = m {
                    m.hotspots.push(spot);
                }
            },
            AIR_HOT_FREE
                .map(|f| Param::Hot(j, f))
                .into_iter()
                .zip(bounds),
        )
    }

    /// The logistic model with `layer` added as its inversion, its three
    /// parameters (n, a, height) freed within `bounds`.
    pub fn with_inversion(&self, layer: Inversion, bounds: [(f64, f64); 3]) -> Model {
        self.with_term(
            Term::Inversion,
            |m| {
                if let Medium::Logistic(m) = m {
                    m.inversion = Some(layer);
                }
            },
            INVERSION_FREE.into_iter().zip(bounds),
        )
    }

    /// The real-air model with `step` added as its step aloft
    /// (`air.temperature.inversion`), its delta, height and thickness freed
    /// within `bounds`.
    pub fn with_air_inversion(&self, step: Step, bounds: [(f64, f64); 3]) -> Model {
        self.with_term(
            Term::Inversion,
            |m| {
                if let Medium::Air(m) = m {
                    m.air.temperature.inversion = Some(step);
                }
            },
            AIR_INVERSION_FREE.into_iter().zip(bounds),
        )
    }

    /// The real-air model with `layer` added as its surface layer
    /// (`air.temperature.exponential`), its delta and scale height freed
    /// within `bounds`.
    pub fn with_surface_layer(&self, layer: Exponential, bounds: [(f64, f64); 2]) -> Model {
        self.with_term(
            Term::SurfaceLayer,
            |m| {
                if let Medium::Air(m) = m {
                    m.air.temperature.exponential = Some(layer);
                }
            },
            SURFACE_FREE.into_iter().zip(bounds),
        )
    }

    /// The model without the grown term `term`: its parameters leave `free`,
    /// later hot spots are renumbered, and (logistic) `scale` keeps the other
    /// terms' δ.
    pub fn without(&self, term: Term) -> Model {
        let mut m = self.clone();
        let s_old = amplitude_sum(&m.medium);
        match (&mut m.medium, term) {
            (Medium::Logistic(l), Term::Inversion) => l.inversion = None,
            (Medium::Logistic(l), Term::HotSpot(j)) => {
                l.hotspots.remove(j);
            }
            (Medium::Air(a), Term::Inversion) => a.air.temperature.inversion = None,
            (Medium::Air(a), Term::SurfaceLayer) => a.air.temperature.exponential = None,
            (Medium::Air(a), Term::HotSpot(j)) => {
                a.hotspots.remove(j);
            }
            // Never grown: nothing to remove.
            (Medium::Logistic(_), Term::SurfaceLayer) | (Medium::LinearSquare(_), _) => {}
        }
        keep_strengths(&mut m.medium, s_old);
        let renumber = |p: Param| match (term, p) {
            (Term::HotSpot(j), Param::Hot(k, f)) if k > j => Param::Hot(k - 1, f),
            _ => p,
        };
        let kept: Vec<(Param, (f64, f64))> = self
            .free
            .iter()
            .zip(&self.bounds)
            .filter(|(p, _)| !term.owns(**p))
            .map(|(p, b)| (renumber(*p), *b))
            .collect();
        m.free = kept.iter().map(|(p, _)| *p).collect();
        m.bounds = kept.iter().map(|(_, b)| *b).collect();
        m.grown = self
            .grown
            .iter()
            .filter(|t| **t != term)
            .map(|t| match (term, *t) {
                (Term::HotSpot(j), Term::HotSpot(k)) if k > j => Term::HotSpot(k - 1),
                (_, t) => t,
            })
            .collect();
        m.held = self
            .held
            .iter()
            .filter(|h| !term.owns(h.param))
            .map(|h| Held {
                param: renumber(h.param),
                ..h.clone()
            })
            .collect();
        m.regauge();
        m
    }
}

/// S = Σ|amplitudes| of a logistic medium; 0 for real air (which has none).
pub(super) fn amplitude_sum(medium: &Medium) -> f64 {
    match medium {
        Medium::Logistic(m) => m.amplitude_sum(),
        _ => 0.0,
    }
}

/// Rescales a logistic medium's `scale` after S changed from `s_old`, so that
/// the terms already there keep their δ; real air needs nothing.
fn keep_strengths(medium: &mut Medium, s_old: f64) {
    if let Medium::Logistic(m) = medium {
        let s_new = m.amplitude_sum();
        if s_old > 0.0 && s_new > 0.0 {
            m.scale *= s_new / s_old;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::medium::{Background, LogisticMedium};

    fn base() -> Model {
        Model {
            medium: Medium::Logistic(LogisticMedium {
                scale: 0.02,
                background: Some(Background { n: 1.0, a: 150.0 }),
                inversion: None,
                hotspots: vec![],
            }),
            free: vec![],
            bounds: vec![],
            grown: vec![],
            held: vec![],
            base_free: vec![],
            base_strength: 0.02,
        }
    }

    fn logistic(m: &Model) -> &LogisticMedium {
        m.medium.as_logistic().unwrap()
    }

    fn spot(x: f64, n: f64) -> HotSpot {
        HotSpot {
            x,
            z: 100.0,
            radius: 20.0,
            n,
            a: -0.5,
            edge: 0.5,
        }
    }

    #[test]
    fn adding_a_term_keeps_the_others_delta_and_frees_scale() {
        let b = [(f64::NEG_INFINITY, f64::INFINITY); 5];
        let m = base().with_hot_spot(spot(0.0, -2.0), b);
        // δ_bg ∝ k_s·n_bg/S: 0.02·1/1 before, 0.06·1/3 after.
        let bg = |m: &Model| logistic(m).scale * 1.0 / logistic(m).amplitude_sum();
        assert!((bg(&m) - 0.02).abs() < 1e-15);
        assert_eq!(m.free[0], Param::Scale);
        assert_eq!(m.free.len(), 6);
        assert_eq!(m.grown, vec![Term::HotSpot(0)]);
    }

    #[test]
    fn dropping_a_hot_spot_renumbers_the_later_ones() {
        let b = [(f64::NEG_INFINITY, f64::INFINITY); 5];
        let two = base()
            .with_hot_spot(spot(0.0, -2.0), b)
            .with_hot_spot(spot(50.0, -1.0), b);
        let one = two.without(Term::HotSpot(0));
        assert_eq!(logistic(&one).hotspots, vec![spot(50.0, -1.0)]);
        assert_eq!(one.grown, vec![Term::HotSpot(0)]);
        assert!(one.free.contains(&Param::Hot(0, HotField::X)));
        assert!(!one.free.iter().any(|p| matches!(p, Param::Hot(1, _))));
        assert_eq!(one.free.len(), one.bounds.len());
        // The remaining spot's and the background's δ are unchanged.
        let share = |m: &Model, n: f64| logistic(m).scale * n / logistic(m).amplitude_sum();
        assert!((share(&one, -1.0) - share(&two, -1.0)).abs() < 1e-15);
        assert!((share(&one, 1.0) - share(&two, 1.0)).abs() < 1e-15);
        // Every grown term dropped: `scale` is fixed again, as in the start.
        assert!(one.without(Term::HotSpot(0)).free.is_empty());
    }

    #[test]
    fn real_air_terms_add_their_kelvins_and_nothing_else() {
        let air: Medium =
            serde_json::from_str(r#"{"air": {"temperature": {"base": 20.0}}}"#).unwrap();
        let start = Model {
            medium: air,
            free: vec![],
            bounds: vec![],
            grown: vec![],
            held: vec![],
            base_free: vec![],
            base_strength: 0.02,
        };
        let b = (0.0, 1.0);
        let m = start
            .with_surface_layer(
                Exponential {
                    delta: 5.0,
                    scale_height: 0.3,
                },
                [b; 2],
            )
            .with_air_inversion(
                Step {
                    delta: 1.0,
                    height: 3.0,
                    thickness: 0.5,
                },
                [b; 3],
            );
        // No `scale`: the air's own parameters only.
        assert_eq!(m.free.len(), 5);
        assert!(m.free.iter().all(|p| matches!(p, Param::Air(_))));
        assert_eq!(
            m.terms(),
            vec![
                "air",
                "air.temperature.exponential",
                "air.temperature.inversion"
            ]
        );
        assert!(Term::SurfaceLayer.owns(Param::Air(AirParam::ExponentialScaleHeight)));
        assert!(Term::Inversion.owns(Param::Air(AirParam::InversionThickness)));
        assert!(!Term::SurfaceLayer.owns(Param::Air(AirParam::InversionDelta)));
        let back = m.without(Term::SurfaceLayer).without(Term::Inversion);
        assert_eq!(back, start);
    }
}
