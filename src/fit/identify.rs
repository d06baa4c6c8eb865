//! What the point pairs determine: standard errors from JᵀJ at the solution, and
//! the parameter combinations in J's near-null space, named instead of given
//! meaningless numbers.
//!
//! J is first scaled by its column norms (so units do not matter), then
//! decomposed, Js = U Σ Vᵀ. A singular value below `RCOND`·σ_max marks a
//! direction Vᵢ along which no endpoint moves (to first order): the parameters
//! with weight in it are undetermined. Covariance on the rest is
//! σ²·D⁻¹ V_r Σ_r⁻² V_rᵀ D⁻¹ with σ² = 2F / (3m − rank) when there are more
//! residuals than determined directions (otherwise σ² = 1: errors per metre of
//! residual, flagged as unscaled).

use crate::medium::Param;
use nalgebra::{DMatrix, DVector};
use serde::Serialize;

/// Singular values below this fraction of the largest are treated as zero.
pub const RCOND: f64 = 1e-8;

/// Weight (squared, in scaled units) a parameter must have in the null space to
/// be called undetermined.
const NULL_WEIGHT: f64 = 1e-2;

/// One free parameter's verdict.
#[derive(Clone, Debug, Serialize)]
pub struct ParamVerdict {
    /// Standard error, or `None` when the parameter is undetermined.
    pub standard_error: Option<f64>,
    /// Whether the pairs determine it.
    pub determined: bool,
}

/// A direction in parameter space the pairs cannot see.
#[derive(Clone, Debug, Serialize)]
pub struct NullDirection {
    /// Parameters and their weights along the direction (unit norm in parameter
    /// units), largest first; parameters with negligible weight are left out.
    pub combination: Vec<(String, f64)>,
    /// σᵢ / σ_max.
    pub relative_singular_value: f64,
    /// What it means, in words.
    pub note: String,
}

/// The identifiability report.
#[derive(Clone, Debug, Serialize)]
pub struct Identifiability {
    /// Per free parameter, in order.
    pub params: Vec<ParamVerdict>,
    /// Directions the pairs cannot determine.
    pub undetermined: Vec<NullDirection>,
    /// Number of determined directions.
    pub rank: usize,
    /// Whether the standard errors are scaled by the residual variance.
    pub scaled_by_residual_variance: bool,
}

/// Analyses the Jacobian `jac` (3m × n) at the solution `x` with objective `f`.
pub fn analyse(jac: &DMatrix<f64>, x: &[f64], free: &[Param], f: f64) -> Identifiability {
    let names: Vec<String> = free.iter().map(|p| p.to_string()).collect();
    let amplitude: Vec<bool> = free.iter().map(|p| p.is_amplitude()).collect();
    analyse_named(jac, x, &names, &amplitude, f, None)
}

/// [`analyse`] with the parameters by name, and whether each is an
/// amplitude of the logistic model (the gauge): for x holding more than the
/// medium's parameters (a photo's camera, `crate::fit::objective`). With
/// `known` (the residuals' noise variance σ², as a photo problem's `noise`
/// gives it) the standard errors use it instead of the residual variance
/// 2F/(m − rank).
pub fn analyse_named(
    jac: &DMatrix<f64>,
    x: &[f64],
    names: &[String],
    amplitude: &[bool],
    f: f64,
    known: Option<f64>,
) -> Identifiability {
    let (m, n) = jac.shape();
    if n == 0 {
        return Identifiability {
            params: vec![],
            undetermined: vec![],
            rank: 0,
            scaled_by_residual_variance: false,
        };
    }
    let norms: Vec<f64> = (0..n).map(|k| jac.column(k).norm()).collect();
    let scaled = DMatrix::from_fn(m, n, |i, k| {
        if norms[k] > 0.0 && norms[k].is_finite() {
            jac[(i, k)] / norms[k]
        } else {
            0.0
        }
    });
    // A thin SVD needs m ≥ n for V to span everything; pad with zero rows.
    let padded = if m < n {
        scaled.clone().resize_vertically(n, 0.0)
    } else {
        scaled
    };
    let svd = padded.svd(false, true);
    let v_t = svd.v_t.expect("requested V");
    let sigma = &svd.singular_values;
    let smax = sigma.iter().cloned().fold(0.0, f64::max);
    let cutoff = RCOND * smax;

    let mut null_weight = vec![0.0; n];
    let mut undetermined = Vec::new();
    let mut rank = 0;
    for i in 0..sigma.len() {
        let row = v_t.row(i);
        if sigma[i] > cutoff && smax > 0.0 {
            rank += 1;
            continue;
        }
        for k in 0..n {
            null_weight[k] += row[k] * row[k];
        }
        // Back to parameter units: Δp_k = v_k / D_k.
        let mut dir: Vec<(usize, f64)> = (0..n)
            .map(|k| {
                (
                    k,
                    if norms[k] > 0.0 {
                        row[k] / norms[k]
                    } else {
                        row[k]
                    },
                )
            })
            .collect();
        let len = dir
            .iter()
            .map(|(_, d)| d * d)
            .sum::<f64>()
            .sqrt()
            .max(f64::MIN_POSITIVE);
        for d in &mut dir {
            d.1 /= len;
        }
        let keep: Vec<(usize, f64)> = {
            let mut k: Vec<(usize, f64)> = dir
                .iter()
                .cloned()
                .filter(|(k, _)| row[*k] * row[*k] > 1e-4)
                .collect();
            k.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
            // One sign convention, so reports are reproducible.
            if k.first().is_some_and(|(_, w)| *w < 0.0) {
                for e in &mut k {
                    e.1 = -e.1;
                }
            }
            k
        };
        let note = explain(&keep, x, names, amplitude);
        undetermined.push(NullDirection {
            combination: keep.iter().map(|(k, w)| (names[*k].clone(), *w)).collect(),
            relative_singular_value: if smax > 0.0 { sigma[i] / smax } else { 0.0 },
            note,
        });
    }

    if !undetermined
        .iter()
        .any(|u| u.combination.iter().any(|(n, _)| n == "camera.tilt"))
        && let Some(d) = tilt_degeneracy(jac, &norms, names)
    {
        undetermined.push(d);
    }

    let dof = m as i64 - rank as i64;
    let scaled_by_variance = dof > 0 && known.is_none();
    let variance = match known {
        Some(v) => v,
        None if scaled_by_variance => 2.0 * f / dof as f64,
        None => 1.0,
    };
    let params = (0..n)
        .map(|k| {
            let determined = null_weight[k] < NULL_WEIGHT && norms[k] > 0.0;
            let standard_error = determined.then(|| {
                let mut c = 0.0;
                for i in 0..sigma.len() {
                    if sigma[i] > cutoff && smax > 0.0 {
                        let v = v_t[(i, k)];
                        c += v * v / (sigma[i] * sigma[i]);
                    }
                }
                (variance * c).sqrt() / norms[k]
            });
            ParamVerdict {
                standard_error,
                determined,
            }
        })
        .collect();
    Identifiability {
        params,
        undetermined,
        rank,
        scaled_by_residual_variance: scaled_by_variance,
    }
}

/// How close the camera's tilt column may come to the span of the air's
/// columns (the sine of the angle between them, columns scaled to unit
/// length) before the pair is reported: at 0.05 the tilt's standard error
/// is 20 times what it would be with the air known.
pub const TILT_DEGENERACY: f64 = 0.05;

/// The tilt–refraction degeneracy of a photo fit, when the marks cannot
/// separate a tilt of the camera from a change of the air (every mark at
/// one distance, no horizon mark): the tilt column lies within
/// [`TILT_DEGENERACY`] of the span of the air's columns, though not
/// exactly in it (which the rank test above would catch).
fn tilt_degeneracy(jac: &DMatrix<f64>, norms: &[f64], names: &[String]) -> Option<NullDirection> {
    let t = names.iter().position(|n| n == "camera.tilt")?;
    let air: Vec<usize> = (0..names.len())
        .filter(|k| !names[*k].starts_with("camera.") && norms[*k] > 0.0 && norms[*k].is_finite())
        .collect();
    if air.is_empty() || !(norms[t] > 0.0 && norms[t].is_finite()) {
        return None;
    }
    let m = jac.nrows();
    let a = DMatrix::from_fn(m, air.len(), |i, c| jac[(i, air[c])] / norms[air[c]]);
    let tcol = DVector::from_fn(m, |i, _| jac[(i, t)] / norms[t]);
    let c = a.clone().svd(true, true).solve(&tcol, 1e-12).ok()?;
    let sine = (&tcol - &a * &c).norm();
    if sine.is_nan() || sine >= TILT_DEGENERACY {
        return None;
    }
    // Δtilt·t = Σ c_k·(air column k), in parameter units.
    let mut combination = vec![("camera.tilt".to_string(), 1.0 / norms[t])];
    for (j, &k) in air.iter().enumerate() {
        combination.push((names[k].clone(), -c[j] / norms[k]));
    }
    let len = combination.iter().map(|(_, w)| w * w).sum::<f64>().sqrt();
    for e in &mut combination {
        e.1 /= len;
    }
    let air_names: Vec<&str> = air.iter().map(|k| names[*k].as_str()).collect();
    Some(NullDirection {
        combination,
        relative_singular_value: sine,
        note: format!(
            "tilt–refraction degeneracy: the marks cannot tell a tilt of the camera from a change of the air ({}) — the tilt's column lies within {:.2e} (sine of the angle) of the air's; add a horizon mark or marks at other distances, or fix `camera.tilt`",
            air_names.join(", "),
            sine
        ),
    })
}

/// Words for a null direction; recognises the model's gauge freedom (all
/// amplitudes scaled together).
fn explain(combination: &[(usize, f64)], x: &[f64], all: &[String], amplitude: &[bool]) -> String {
    let names: Vec<String> = combination.iter().map(|(k, _)| all[*k].clone()).collect();
    if combination.len() == 1 {
        return format!(
            "no pair's endpoint depends on `{}`: fix it (remove it from `free`) or add pairs whose rays it bends",
            names[0]
        );
    }
    let camera = |n: &String| n.starts_with("camera.");
    if names.iter().any(|n| n == "camera.tilt") && names.iter().any(|n| !camera(n)) {
        return format!(
            "tilt–refraction degeneracy: a change of the camera's tilt and of the air ({}) move the marks alike (every mark at one distance bends by one angle); add a horizon mark, or marks at other distances, or fix `camera.tilt`",
            names.join(", ")
        );
    }
    let amplitudes: Vec<usize> = (0..all.len()).filter(|k| amplitude[*k]).collect();
    let is_gauge = !amplitudes.is_empty()
        && combination.iter().all(|(k, _)| amplitude[*k])
        && combination.len() == amplitudes.len()
        && {
            // Direction ∝ the amplitudes themselves.
            let norm_x = amplitudes.iter().map(|k| x[*k] * x[*k]).sum::<f64>().sqrt();
            combination
                .iter()
                .all(|(k, w)| (w - x[*k] / norm_x).abs() < 1e-3)
                || combination
                    .iter()
                    .all(|(k, w)| (w + x[*k] / norm_x).abs() < 1e-3)
        };
    if is_gauge {
        format!(
            "gauge freedom: scaling all amplitudes ({}) by the same factor leaves δ unchanged; fix one of them, or free `scale` instead",
            names.join(", ")
        )
    } else {
        format!(
            "the pairs cannot tell these apart: moving {} together in these proportions leaves every endpoint unchanged (to first order)",
            names.join(", ")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::medium::HotField;

    #[test]
    fn a_flat_combination_is_named_and_the_rest_get_errors() {
        // r depends on p0 + p1 only, and on p2.
        let jac = DMatrix::from_row_slice(
            4,
            3,
            &[1.0, 1.0, 0.0, 2.0, 2.0, 0.0, 0.0, 0.0, 3.0, 0.0, 0.0, 1.0],
        );
        let free = [
            Param::Hot(0, HotField::X),
            Param::Hot(0, HotField::Z),
            Param::InversionHeight,
        ];
        let r = analyse(&jac, &[1.0, 2.0, 3.0], &free, 0.5);
        assert_eq!(r.rank, 2);
        assert_eq!(r.undetermined.len(), 1);
        let names: Vec<&str> = r.undetermined[0]
            .combination
            .iter()
            .map(|(n, _)| n.as_str())
            .collect();
        assert_eq!(names.len(), 2);
        assert!(names.contains(&"hotspots[0].x") && names.contains(&"hotspots[0].z"));
        let w = &r.undetermined[0].combination;
        assert!((w[0].1 + w[1].1).abs() < 1e-12, "direction (1, −1)/√2");
        assert!(!r.params[0].determined && !r.params[1].determined);
        assert!(r.params[2].determined);
        // p2's error: σ² (JᵀJ)⁻¹ with σ² = 2F/(m − rank) = 1/2, JᵀJ = 10.
        let se = r.params[2].standard_error.unwrap();
        assert!((se - (0.5f64 / 10.0).sqrt()).abs() < 1e-12, "{se}");
    }

    #[test]
    fn gauge_freedom_is_recognised() {
        // Columns for three amplitudes with J·x = 0 along x = (1, −2, 0.5).
        let a = [1.0, -2.0, 0.5];
        let jac = DMatrix::from_row_slice(3, 3, &[2.0, 1.0, 0.0, 0.0, 0.25, 1.0, 1.0, 0.0, -2.0]);
        assert!((&jac * nalgebra::DVector::from_row_slice(&a)).norm() < 1e-15);
        let free = [
            Param::BackgroundN,
            Param::InversionN,
            Param::Hot(0, HotField::N),
        ];
        let r = analyse(&jac, &a, &free, 0.0);
        assert_eq!(r.undetermined.len(), 1);
        assert!(
            r.undetermined[0].note.contains("gauge"),
            "{}",
            r.undetermined[0].note
        );
        assert!(
            r.params
                .iter()
                .all(|p| !p.determined && p.standard_error.is_none())
        );
    }
}
