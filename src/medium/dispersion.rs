//! Dispersion: the same air seen at another vacuum wavelength.
//!
//! Real air's refractivity depends on the wavelength (Ciddor's and Edlén's
//! dispersion terms: n − 1 is about 1.5 % larger at 450 nm than at 700 nm),
//! so a point pair with its own `wavelength` (`docs/problem-format.md`) and a
//! dispersive scene's colour channels (`docs/scene-format.md`) each see the
//! medium with `air.wavelength` replaced. Only real air has a wavelength: the
//! logistic and analytic kinds are monochrome models, and
//! [`Medium::at_wavelength`] answers `None` for them (files that ask for a
//! wavelength there are refused when they are read).
//!
//! [`PairFields`] compiles one field per *distinct* wavelength of a list of
//! pairs, not one per pair: compiling real air tabulates its pressure, which
//! costs far more than evaluating it. The per-wavelength media are built from
//! the caller's medium by replacing one number, so a medium of dual numbers
//! (the fit's Jacobian) stays exact: every other parameter keeps its
//! derivative parts, and the pair's wavelength, a constant of the file, has
//! none (a free `air.wavelength` then has no effect on that pair's residual,
//! which is true).

use super::{Field, Medium};
use crate::math::Real;

impl<T: Copy> Medium<T> {
    /// This medium at the vacuum wavelength `nm` (nanometres), or `None` if
    /// its kind has no wavelength (only real air has one).
    pub fn at_wavelength(&self, nm: T) -> Option<Medium<T>> {
        match self {
            Medium::Air(m) => {
                let mut m = m.clone();
                m.air.wavelength = nm;
                Some(Medium::Air(m))
            }
            Medium::Logistic(_) | Medium::LinearSquare(_) => None,
        }
    }

    /// Whether the kind has a wavelength to disperse over.
    pub fn is_dispersive(&self) -> bool {
        matches!(self, Medium::Air(_))
    }
}

/// One compiled field per distinct wavelength of a list of pairs, and which
/// field each pair uses. Pairs without a wavelength (and every pair of a kind
/// without one) use the medium as given.
#[derive(Clone, Debug)]
pub struct PairFields<T = f64> {
    /// The medium as given first, then one per distinct wavelength in order
    /// of first appearance.
    fields: Vec<Field<T>>,
    /// Per pair, its index into `fields`.
    of_pair: Vec<usize>,
}

impl<T: Real> PairFields<T> {
    /// Compiles `medium` once for the pairs without a wavelength and once per
    /// distinct wavelength (nm) among `wavelengths` (one entry per pair).
    pub fn new(medium: &Medium<T>, wavelengths: impl IntoIterator<Item = Option<f64>>) -> Self {
        let mut fields = vec![medium.field()];
        let mut seen: Vec<(u64, usize)> = Vec::new();
        let of_pair = wavelengths
            .into_iter()
            .map(|w| {
                let Some(nm) = w else { return 0 };
                let Some(at) = medium.at_wavelength(T::cst(nm)) else {
                    return 0;
                };
                let key = nm.to_bits();
                if let Some(&(_, k)) = seen.iter().find(|(b, _)| *b == key) {
                    return k;
                }
                fields.push(at.field());
                seen.push((key, fields.len() - 1));
                fields.len() - 1
            })
            .collect();
        PairFields { fields, of_pair }
    }

    /// The field pair `i` is traced through.
    pub fn of(&self, i: usize) -> &Field<T> {
        &self.fields[self.of_pair.get(i).copied().unwrap_or(0)]
    }

    /// The compiled fields (the medium as given first).
    pub fn fields(&self) -> &[Field<T>] {
        &self.fields
    }

    /// Per pair, its index into [`PairFields::fields`].
    pub fn groups(&self) -> &[usize] {
        &self.of_pair
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::V3;
    use crate::medium::IndexField;

    fn air() -> Medium {
        serde_json::from_str(r#"{"air": {"temperature": {"base": 10.0}}}"#).unwrap()
    }

    #[test]
    fn one_field_per_distinct_wavelength() {
        let f = PairFields::new(&air(), [None, Some(450.0), Some(700.0), Some(450.0), None]);
        assert_eq!(f.fields().len(), 3);
        assert_eq!(f.groups(), &[0, 1, 2, 1, 0]);
        let p = V3::new(0.0, 1.0, 0.0);
        let (d450, _) = f.of(1).delta_gradient(p);
        let (d700, _) = f.of(2).delta_gradient(p);
        assert!(d450 > d700, "δ(450) = {d450} must exceed δ(700) = {d700}");
    }

    #[test]
    fn kinds_without_a_wavelength_use_the_medium_as_given() {
        let m: Medium = serde_json::from_str(r#"{"scale": 1.0}"#).unwrap();
        assert!(m.at_wavelength(450.0).is_none());
        let f = PairFields::new(&m, [Some(450.0)]);
        assert_eq!(f.fields().len(), 1);
        assert_eq!(f.groups(), &[0]);
    }
}
