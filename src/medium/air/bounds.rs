//! Real air's [`Envelope`]: bounds of n and |∇δ| above the ground, from a
//! dense sample of the uniform profile with the hot spots' extreme excesses
//! added (n falls with T and rises with P, so the coldest air at each height
//! bounds n from above and the warmest from below), with a margin.

use super::field::AirField;
use super::model::{AirMedium, Lapse};
use crate::math::V3;
use crate::medium::IndexField;
use crate::medium::envelope::{Envelope, Patch, VerticalFeature};

/// How far up the bounds are sampled (m): the renderer's profile top.
const TOP: f64 = 50_000.0;
/// The vertical feature of a smooth profile (lapse, pressure): the scale of
/// the analytic kind's, so that the renderer's profile reaches [`TOP`].
const SMOOTH_SCALE: f64 = TOP / 40.0;

impl AirMedium<f64> {
    /// Bounds and features for stepping through the air ([`Envelope`]).
    pub fn envelope(&self) -> Envelope {
        let field = AirField::new(self);
        let t = &self.air.temperature;
        let mut layers = Vec::new();
        if let Some(e) = t.exponential {
            layers.push(VerticalFeature {
                scale: e.scale_height,
                centre: 0.0,
            });
        }
        if let Some(i) = t.inversion {
            layers.push(VerticalFeature {
                scale: i.thickness,
                centre: i.height,
            });
        }
        if let Some(rows) = &t.table {
            let gap = rows
                .windows(2)
                .map(|w| w[1][0] - w[0][0])
                .fold(f64::INFINITY, f64::min);
            layers.push(VerticalFeature {
                scale: gap.max(1e-3),
                centre: rows[0][0],
            });
        }
        if self.air.hydrostatic || matches!(t.lapse, Some(Lapse::Rate(_) | Lapse::Standard)) {
            layers.push(VerticalFeature {
                scale: SMOOTH_SCALE,
                centre: 0.0,
            });
        }
        let finest = layers
            .iter()
            .map(|l| l.scale)
            .chain(self.hotspots.iter().map(|h| h.scale_height))
            .fold(f64::INFINITY, f64::min);
        // Heights: fine near the ground and every feature, coarser far up.
        let mut heights: Vec<f64> = Vec::new();
        let dy = (finest / 8.0).clamp(1e-4, 1.0);
        let mut h = 0.0;
        while h < TOP.min(field.ceiling()) {
            heights.push(h);
            h += dy.max(h * 0.01);
        }
        for l in &layers {
            for k in -400..=400 {
                let y = l.centre + l.scale * k as f64 / 20.0;
                if y >= 0.0 {
                    heights.push(y);
                }
            }
        }
        let (mut n_max, mut n_min, mut g_max) = (1.0f64, f64::INFINITY, 0.0f64);
        let far = 1e12;
        let hot_sum: f64 = self.hotspots.iter().map(|s| s.delta.abs()).sum();
        for &y in &heights {
            let p = V3::new(far, y, far);
            let (d, g) = field.delta_gradient(p);
            // The hot spots shift T by at most Σ|δT_j|, so n by at most
            // |∂δ/∂T|·Σ|δT_j| (with a margin).
            let (tu, _) = field.uniform_kelvin(y);
            let d_dt = d / tu; // |∂δ/∂T| ≈ δ/T for every formula (δ ∝ P/T).
            let spread = d_dt * hot_sum * 1.5;
            n_max = n_max.max(1.0 + d + spread);
            n_min = n_min.min(1.0 + d - spread);
            g_max = g_max.max(g.norm());
        }
        for s in &self.hotspots {
            // ∂δ/∂T·δT·(|w'| + e^(−h/H)/H): w' ≤ edge/4.
            let d0 = field.delta(V3::new(far, 0.0, far));
            let (t0, _) = field.uniform_kelvin(0.0);
            g_max += 1.5 * d0 / (t0 - s.delta.abs()).max(50.0)
                * s.delta.abs()
                * (0.25 * s.edge + 1.0 / s.scale_height);
        }
        if !n_min.is_finite() {
            n_min = 1.0;
        }
        Envelope {
            n_max,
            n_min: n_min.clamp(0.5, 1.0 + 1e-12),
            gradient_max: 1.5 * g_max,
            layers,
            patches: self
                .hotspots
                .iter()
                .map(|h| Patch {
                    x: h.x,
                    z: h.z,
                    radius: h.radius,
                    edge: h.edge,
                    rate: -h.scale_height,
                })
                .collect(),
        }
    }
}
