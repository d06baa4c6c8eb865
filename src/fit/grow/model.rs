//! A model under growth: a logistic medium, its free parameters and their
//! bounds, and which of its terms growing added (only those may be dropped).
//!
//! Adding or dropping a term changes S = Σ|amplitudes|, which divides every
//! term (`docs/model.md`); `scale` is multiplied by S_new/S_old at the same time,
//! so the other terms' δ does not change, and `scale` is freed with the first
//! term added, so the fit can set every term's strength (with one amplitude,
//! the background's, left fixed there is no gauge freedom).

use crate::medium::{HotField, HotSpot, Inversion, LogisticMedium, Param};

/// The parameters a grown hot spot frees (its `edge` stays as seeded).
pub const HOT_FREE: [HotField; 5] = [
    HotField::X,
    HotField::Z,
    HotField::Radius,
    HotField::N,
    HotField::A,
];

/// A term growing may add or drop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Term {
    /// The inversion layer.
    Inversion,
    /// Hot spot j of the medium.
    HotSpot(usize),
}

impl Term {
    /// Its path name (`inversion`, `hotspots[2]`).
    pub fn name(self) -> String {
        match self {
            Term::Inversion => "inversion".into(),
            Term::HotSpot(j) => format!("hotspots[{j}]"),
        }
    }

    /// Whether `p` is one of its parameters.
    pub fn owns(self, p: Param) -> bool {
        match (self, p) {
            (Term::Inversion, Param::InversionN | Param::InversionA | Param::InversionHeight) => {
                true
            }
            (Term::HotSpot(j), Param::Hot(k, _)) => j == k,
            _ => false,
        }
    }
}

/// A medium with its free parameters: what one candidate fit fits.
#[derive(Clone, Debug, PartialEq)]
pub struct Model {
    /// The medium, at the current (start or fitted) values.
    pub medium: LogisticMedium,
    /// Free parameters, in order: the problem's, then `scale`, then each
    /// grown term's.
    pub free: Vec<Param>,
    /// `[low, high]` per free parameter.
    pub bounds: Vec<(f64, f64)>,
    /// Terms growing added, in the order added.
    pub grown: Vec<Term>,
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

    /// The medium's terms by name, in the medium's order.
    pub fn terms(&self) -> Vec<String> {
        let m = &self.medium;
        let mut t = Vec::new();
        if m.background.is_some() {
            t.push("background".to_string());
        }
        if m.inversion.is_some() {
            t.push(Term::Inversion.name());
        }
        t.extend((0..m.hotspots.len()).map(|j| Term::HotSpot(j).name()));
        t
    }

    /// Frees `p` with `bounds` unless it is free already.
    fn free_param(&mut self, p: Param, bounds: (f64, f64)) {
        if !self.free.contains(&p) {
            self.free.push(p);
            self.bounds.push(bounds);
        }
    }

    /// Rescales `scale` after S changed from `s_old`, so that the terms
    /// already there keep their δ.
    fn keep_strengths(&mut self, s_old: f64) {
        let s_new = self.medium.amplitude_sum();
        if s_old > 0.0 && s_new > 0.0 {
            self.medium.scale *= s_new / s_old;
        }
    }

    /// The model with `spot` added as a new hot spot, its [`HOT_FREE`]
    /// parameters freed within `bounds` (in that order).
    pub fn with_hot_spot(&self, spot: HotSpot, bounds: [(f64, f64); 5]) -> Model {
        let mut m = self.clone();
        let s_old = m.medium.amplitude_sum();
        m.medium.hotspots.push(spot);
        m.keep_strengths(s_old);
        m.free_param(Param::Scale, (0.0, f64::INFINITY));
        let j = m.medium.hotspots.len() - 1;
        for (f, b) in HOT_FREE.iter().zip(bounds) {
            m.free_param(Param::Hot(j, *f), b);
        }
        m.grown.push(Term::HotSpot(j));
        m
    }

    /// The model with `layer` added as its inversion, its three parameters
    /// (n, a, height) freed within `bounds`.
    pub fn with_inversion(&self, layer: Inversion, bounds: [(f64, f64); 3]) -> Model {
        let mut m = self.clone();
        let s_old = m.medium.amplitude_sum();
        m.medium.inversion = Some(layer);
        m.keep_strengths(s_old);
        m.free_param(Param::Scale, (0.0, f64::INFINITY));
        for (p, b) in [Param::InversionN, Param::InversionA, Param::InversionHeight]
            .into_iter()
            .zip(bounds)
        {
            m.free_param(p, b);
        }
        m.grown.push(Term::Inversion);
        m
    }

    /// The model without the grown term `term`: its parameters leave `free`,
    /// later hot spots are renumbered, `scale` keeps the other terms' δ.
    pub fn without(&self, term: Term) -> Model {
        let mut m = self.clone();
        let s_old = m.medium.amplitude_sum();
        match term {
            Term::Inversion => m.medium.inversion = None,
            Term::HotSpot(j) => {
                m.medium.hotspots.remove(j);
            }
        }
        m.keep_strengths(s_old);
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
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::medium::Background;

    fn base() -> Model {
        Model {
            medium: LogisticMedium {
                scale: 0.02,
                background: Some(Background { n: 1.0, a: 150.0 }),
                inversion: None,
                hotspots: vec![],
            },
            free: vec![],
            bounds: vec![],
            grown: vec![],
        }
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
        let bg = |m: &Model| m.medium.scale * 1.0 / m.medium.amplitude_sum();
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
        assert_eq!(one.medium.hotspots, vec![spot(50.0, -1.0)]);
        assert_eq!(one.grown, vec![Term::HotSpot(0)]);
        assert!(one.free.contains(&Param::Hot(0, HotField::X)));
        assert!(!one.free.iter().any(|p| matches!(p, Param::Hot(1, _))));
        assert_eq!(one.free.len(), one.bounds.len());
        // The remaining spot's and the background's δ are unchanged.
        let share = |m: &Model, n: f64| m.medium.scale * n / m.medium.amplitude_sum();
        assert!((share(&one, -1.0) - share(&two, -1.0)).abs() < 1e-15);
        assert!((share(&one, 1.0) - share(&two, 1.0)).abs() < 1e-15);
        assert_eq!(one.without(Term::HotSpot(0)).free, vec![Param::Scale]);
    }
}
