//! Problems with a known answer: trace a known medium and move each pair's
//! target to where its ray lands. Fitting from a perturbed start must then find
//! the known medium again (the recovery tests), and it is how the bundled
//! example problems were made consistent.

pub mod grow_cases;

use crate::medium::IndexField;
use crate::pair::PointPair;
use crate::trace::TraceOptions;

/// Replaces each pair's target by the endpoint of its ray through `field`.
///
/// The target plane depends on the target's horizontal position, so the endpoint
/// is recomputed until it is a fixed point (the ray crosses the plane through
/// itself); three rounds reach rounding level for rays that bend sideways by
/// less than a few metres. Pairs whose ray never reaches the plane keep their
/// target and are returned in the second list by index.
pub fn retarget<F: IndexField + ?Sized>(
    pairs: &[PointPair],
    field: &F,
    options: &TraceOptions,
) -> (Vec<PointPair>, Vec<usize>) {
    let mut out = pairs.to_vec();
    let mut failed = Vec::new();
    for (i, p) in out.iter_mut().enumerate() {
        for _ in 0..6 {
            let (t, _) = p.evaluate::<f64, _>(field, options, None);
            if t.unreachable {
                failed.push(i);
                break;
            }
            let moved = (t.endpoint - p.target()).norm();
            p.target = t.endpoint.to_array();
            if moved < 1e-12 * (1.0 + t.arc_length) {
                break;
            }
        }
    }
    (out, failed)
}
