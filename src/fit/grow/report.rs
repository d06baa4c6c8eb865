//! What growing did, step by step, as `mirage fit --grow` reports it (the
//! `grow` section of the result, `docs/problem-format.md`).

use serde::Serialize;

fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// One candidate term tried at a step: the best of its seeds.
#[derive(Clone, Debug, Serialize)]
pub struct CandidateReport {
    /// The term it adds (`inversion`, `hotspots[1]`).
    pub term: String,
    /// Seeds fitted.
    pub seeds: usize,
    /// Index of the seed whose fit was best.
    pub best_seed: usize,
    /// F (m²) of the best seed's fit.
    pub objective: f64,
    /// The criterion of that fit.
    pub criterion: f64,
    /// Parameters the fit held (undetermined), beyond the seed's.
    #[serde(skip_serializing_if = "is_zero")]
    pub held: usize,
}

/// A parameter of the grown model held at a value instead of fitted.
#[derive(Clone, Debug, Serialize)]
pub struct HeldReport {
    /// Its path (`hotspots[0].radius`, `background.a`).
    pub name: String,
    /// The value it is held at.
    pub value: f64,
    /// Why: undetermined by the pairs, ran away in a fit, or the gauge.
    pub reason: String,
}

/// One step of the growth: the model it left and why.
#[derive(Clone, Debug, Serialize)]
pub struct GrowStep {
    /// 0 for the starting model.
    pub step: usize,
    /// What the step did: `start`, `add inversion`, `add hotspots[0]`,
    /// `drop hotspots[1]`, `drop inversion`, `no candidate lowers the criterion`.
    pub action: String,
    /// The medium's terms after the step (`background`, `inversion`, `hotspots[0]`).
    pub terms: Vec<String>,
    /// The free parameters after the step, by path name.
    pub free: Vec<String>,
    /// F (m²) of the model after the step.
    pub objective: f64,
    /// χ² when σ is known: 2F/σ², or Σ|rᵢ|²/(wᵢσᵢ)² with per-pair σᵢ.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub chi2: Option<f64>,
    /// The criterion of the model after the step (lower is better).
    pub criterion: f64,
    /// The candidates tried at this step (empty for `start` and drops).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub candidates: Vec<CandidateReport>,
}

/// The account of a grown model.
#[derive(Clone, Debug, Serialize)]
pub struct GrowReport {
    /// The criterion, in words: `BIC, σ = … m known: χ² + p·ln m, χ² = 2F/σ²`,
    /// `BIC, σᵢ per pair known: …` or `BIC, σ estimated: m·ln(2F/m) + p·ln m`.
    pub criterion: String,
    /// Endpoint noise σ (m) the criterion assumes, if given (with per-pair
    /// σᵢ: that of the pairs without their own).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub noise: Option<f64>,
    /// Pairs that carry their own σᵢ (`pairs[i].noise`); 0: none.
    #[serde(skip_serializing_if = "is_zero")]
    pub pairs_with_noise: usize,
    /// Residual components m (two per pair: the endpoint lies on the target
    /// plane, so the third component is zero).
    pub residual_components: usize,
    /// Most terms growing could add.
    pub max_terms: usize,
    /// Every step, the start first.
    pub steps: Vec<GrowStep>,
    /// Why growing stopped.
    pub stop_reason: String,
    /// Whether the final model fits to the noise floor (χ² ≤ (m − p) +
    /// 2·√(2(m − p))), when σ is known.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub at_noise_floor: Option<bool>,
    /// The grown model's held parameters: not fitted, kept at these values.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub held: Vec<HeldReport>,
    /// Candidate and refit fits made, over all steps.
    pub fits: usize,
    /// Wall time of the growth, before the final fit (seconds).
    pub wall_time_s: f64,
}
