//! The criterion growing minimises: the Bayesian information criterion of
//! least squares, with the endpoint noise known (one σ, or a σᵢ per pair) or
//! estimated, and the noise floor where growing stops (see the parent
//! module's doc for why BIC and how χ² is formed).

use crate::error::{Error, Result};
use crate::problem::Problem;

/// What the criterion knows of the endpoint noise.
#[derive(Clone, Debug, PartialEq)]
pub enum Noise {
    /// σ unknown: estimated from the residuals.
    Unknown,
    /// One σ (m) for every pair: χ² = 2F/σ².
    Uniform(f64),
    /// A σᵢ per pair: χ² = Σᵢ kᵢ·|rᵢ|² with kᵢ = 1/(wᵢσᵢ)² held here, one per
    /// pair (0 for a pair of weight 0, whose residual is 0).
    PerPair(Vec<f64>),
}

/// The information criterion of least squares with endpoint noise σ.
#[derive(Clone, Debug, PartialEq)]
pub struct Criterion {
    /// The noise.
    pub noise: Noise,
    /// Residual components m.
    pub m: usize,
}

impl Criterion {
    /// The criterion of `problem`'s pairs with the global σ `noise`
    /// (`--noise`, `solver.noise`): per-pair σᵢ when some pair carries one
    /// (then every pair must have one, its own or the global one).
    pub fn of(problem: &Problem, noise: Option<f64>) -> Result<Criterion> {
        let m = 2 * problem.pairs.len();
        // σ in the residual's unit (arcseconds → radians for angle residuals).
        let unit = |v: f64| problem.residual.noise_in_residual_units(v);
        let noise = noise.map(unit);
        let own = |i: usize| problem.pair_noise.get(i).copied().flatten().map(unit);
        let with_own = (0..problem.pairs.len())
            .filter(|&i| own(i).is_some())
            .count();
        if with_own == 0 {
            let noise = noise.map_or(Noise::Unknown, Noise::Uniform);
            return Ok(Criterion { noise, m });
        }
        let mut k = Vec::with_capacity(problem.pairs.len());
        for (i, pair) in problem.pairs.iter().enumerate() {
            let Some(sigma) = own(i).or(noise) else {
                return Err(Error::input(
                    &problem.source,
                    "solver.noise",
                    format!(
                        "{with_own} of {} pairs carry their own `noise` but pairs[{i}] does not: give every pair a `noise`, or a σ for the rest in `solver.noise` (or --noise)",
                        problem.pairs.len()
                    ),
                ));
            };
            let ws = pair.weight * sigma;
            k.push(if pair.weight > 0.0 {
                1.0 / (ws * ws)
            } else {
                0.0
            });
        }
        Ok(Criterion {
            noise: Noise::PerPair(k),
            m,
        })
    }

    /// The criterion in words.
    pub fn describe(&self) -> String {
        match &self.noise {
            Noise::Uniform(s) => format!("BIC, σ = {s} m known: χ² + p·ln m, χ² = 2F/σ²"),
            Noise::PerPair(_) => "BIC, σᵢ per pair known: χ² + p·ln m, χ² = Σ|rᵢ|²/(wᵢσᵢ)²".into(),
            Noise::Unknown => "BIC, σ estimated: m·ln(2F/m) + p·ln m".into(),
        }
    }

    /// Whether χ² needs each pair's |rᵢ|², not only F.
    pub fn needs_pairs(&self) -> bool {
        matches!(self.noise, Noise::PerPair(_))
    }

    /// χ² of a fit with objective `f` and per-pair |rᵢ|² `pair_sq` (read only
    /// with per-pair σᵢ), if σ is known.
    pub fn chi2(&self, f: f64, pair_sq: &[f64]) -> Option<f64> {
        match &self.noise {
            Noise::Unknown => None,
            Noise::Uniform(s) => Some(2.0 * f / (s * s)),
            Noise::PerPair(_) if !f.is_finite() => Some(f64::INFINITY),
            Noise::PerPair(k) => {
                let c: f64 = k.iter().zip(pair_sq).map(|(k, r2)| k * r2).sum();
                Some(if c.is_finite() { c } else { f64::INFINITY })
            }
        }
    }

    /// The criterion of a fit with objective `f`, χ² `chi2` (from
    /// [`Criterion::chi2`]) and `p` free parameters.
    pub fn value(&self, f: f64, chi2: Option<f64>, p: usize) -> f64 {
        let m = self.m as f64;
        let penalty = p as f64 * m.ln();
        match chi2 {
            Some(c) => c + penalty,
            None => m * (2.0 * f / m).max(f64::MIN_POSITIVE).ln() + penalty,
        }
    }

    /// Whether χ² is within the noise floor (`None` when σ is unknown).
    pub fn at_floor(&self, chi2: Option<f64>, p: usize) -> Option<bool> {
        let dof = self.m.saturating_sub(p).max(1) as f64;
        chi2.map(|c| c <= dof + 2.0 * (2.0 * dof).sqrt())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_criterion_charges_ln_m_per_parameter_and_knows_its_floor() {
        let c = Criterion {
            noise: Noise::Uniform(0.01),
            m: 50,
        };
        // χ² = 2F/σ² = 50 at F = 2.5e-3.
        let chi2 = c.chi2(2.5e-3, &[]);
        assert!((chi2.unwrap() - 50.0).abs() < 1e-9);
        let d = c.value(2.5e-3, chi2, 6) - c.value(2.5e-3, chi2, 0);
        assert!((d - 6.0 * 50f64.ln()).abs() < 1e-9);
        // Floor for p = 0: 50 + 2·√100 = 70.
        assert_eq!(c.at_floor(c.chi2(0.5 * 70.0e-4, &[]), 0), Some(true));
        assert_eq!(c.at_floor(c.chi2(0.5 * 70.1e-4, &[]), 0), Some(false));
        let unknown = Criterion {
            noise: Noise::Unknown,
            m: 50,
        };
        assert_eq!(unknown.at_floor(unknown.chi2(1.0, &[]), 0), None);
    }

    /// A problem of three pairs with weights 1, 2, 0 and the given `noise`
    /// fields.
    fn three_pairs(noise: [&str; 3]) -> Problem {
        let pair = |w: f64, n: &str| {
            format!(
                r#"{{"origin": [0, 1.6, 0], "through": [0, 1.0, 900], "target": [0, 2.0, 900], "weight": {w}{n}}}"#
            )
        };
        let text = format!(
            r#"{{"medium": {{"scale": 1.0, "background": {{"n": 1.0, "a": 40.0}}}}, "pairs": [{}, {}, {}]}}"#,
            pair(1.0, noise[0]),
            pair(2.0, noise[1]),
            pair(0.0, noise[2]),
        );
        Problem::parse(&text, std::path::Path::new("p.json")).unwrap()
    }

    #[test]
    fn per_pair_noise_weighs_each_pairs_residual_by_its_own_sigma() {
        let p = three_pairs([r#", "noise": 0.01"#, r#", "noise": 0.02"#, ""]);
        assert_eq!(p.pair_noise, vec![Some(0.01), Some(0.02), None]);
        // The third pair has no σ of its own and none is given: refused,
        // naming `solver.noise`.
        let e = Criterion::of(&p, None).unwrap_err().to_string();
        assert!(e.contains("solver.noise") && e.contains("pairs[2]"), "{e}");
        // With a global σ for it: kᵢ = 1/(wᵢσᵢ)², 0 at weight 0.
        let c = Criterion::of(&p, Some(0.5)).unwrap();
        assert_eq!(
            c.noise,
            Noise::PerPair(vec![1e4, 1.0 / (0.04f64 * 0.04), 0.0])
        );
        assert!(c.needs_pairs());
        // |r₁|² = (1·3 cm)², |r₂|² = (2·2 cm)²: each pair at 3σ and 1σ,
        // χ² = 9 + 1 (the pair of weight 0 counts nothing).
        let sq = [0.03f64.powi(2), 0.04f64.powi(2), 0.0];
        let f = 0.5 * sq.iter().sum::<f64>();
        let chi2 = c.chi2(f, &sq).unwrap();
        assert!((chi2 - 10.0).abs() < 1e-9, "{chi2}");
        // One global σ would have read 2F/σ² = Σ|rᵢ|²/σ² instead.
        let uniform = Criterion::of(&three_pairs(["", "", ""]), Some(0.01)).unwrap();
        assert_eq!(uniform.noise, Noise::Uniform(0.01));
        assert!((uniform.chi2(f, &[]).unwrap() - 25.0).abs() < 1e-9);
        assert!(uniform.describe().contains("2F/σ²"));
        assert!(c.describe().contains("σᵢ"));
        // A failed fit has χ² = ∞.
        assert_eq!(c.chi2(f64::INFINITY, &[]), Some(f64::INFINITY));
    }
}
