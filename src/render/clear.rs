//! Clear boxes: long steps through open air.
//!
//! A cell's unbounding sphere ([`super::accel::Grid`]) reaches only as far as
//! the nearest surface in *any* direction, so a ray running down a corridor
//! (a road between rows of poles, the air above a line of cars) takes steps of
//! the corridor's half-width however long the corridor is. A box is not so
//! limited: it can be metres wide and hundreds of metres long.
//!
//! # What a clear box is
//!
//! A cell is **clear** when its unbounding sphere covers it (`empty` greater
//! than the half-diagonal): no object's solid meets the closed cell, since
//! every SDF is a 1-Lipschitz lower bound of the distance. A union of clear
//! cells is free of solid, so for each clear cell we keep one axis-aligned box
//! of clear cells that contains it, found on first use (lazily, per cell; the
//! box depends on the cell only, so renders stay bitwise independent of the
//! number of threads and of the order rays come in):
//!
//! 1. grow the cell by one cell on each face in turn, a few rounds, so the box
//!    starts roughly cubic (a box one cell thick would be left sideways by a
//!    slightly slanted ray at once);
//! 2. then push each face as far as it goes (galloping, then bisection), the
//!    faces across the grid's longest axis first: scenes spread out along the
//!    view (roads, sea lanes) get boxes long along it.
//!
//! Emptiness of a candidate box is one lookup in a summed-volume table of the
//! cells that are not clear (eight reads). A box that reaches a face of the
//! grid extends beyond it to infinity, except downward (the grid may be cut
//! at the ground, below which objects can reach).
//!
//! # The step a box allows
//!
//! A ray at `p` with unit tangent `t` and curvature at most κ strays from its
//! tangent line by at most κs²/2 over an arc s, in any coordinate as well: it
//! cannot reach a face at distance d along an axis before the root of
//! κs²/2 + t_k·s = d (the function `exit`). The least such root over the
//! six faces is a free arc (capped at the grid's diagonal); the sphere tracer
//! takes the larger of it and the sphere's.

use glam::DVec3;
use std::sync::OnceLock;

/// Rounds of one-cell growth on every face before the faces are pushed out.
const CUBIC_ROUNDS: usize = 4;

/// The clear boxes of a grid (see the module documentation).
#[derive(Clone, Debug)]
pub struct ClearBoxes {
    dims: [usize; 3],
    /// Summed-volume table of the cells that are not clear, (dims + 1)³.
    blocked: Vec<u32>,
    /// Per cell, its box as cell ranges `lo[k] .. hi[k]`, once computed;
    /// `None` for a cell that is not clear.
    boxes: Vec<OnceLock<Option<[u16; 6]>>>,
    /// Face order of step 2: axes by decreasing grid extent.
    axes: [usize; 3],
    /// The grid's box and cell size.
    origin: DVec3,
    cell: DVec3,
    /// Longest free arc considered (the grid's diagonal): caps the curvature
    /// margin of boxes open to infinity.
    reach: f64,
}

impl ClearBoxes {
    /// The clear boxes of a grid of `dims` cells of size `cell` from `origin`,
    /// where `clear[idx]` (x fastest) says whether a cell is clear.
    pub fn new(dims: [usize; 3], origin: DVec3, cell: DVec3, clear: &[bool]) -> ClearBoxes {
        let [nx, ny, nz] = dims;
        let (sx, sy) = (nx + 1, (nx + 1) * (ny + 1));
        let mut blocked = vec![0u32; sy * (nz + 1)];
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let own = u32::from(!clear[i + nx * (j + ny * k)]);
                    let at = |i: usize, j: usize, k: usize| i + sx * j + sy * k;
                    blocked[at(i + 1, j + 1, k + 1)] = own
                        + blocked[at(i, j + 1, k + 1)]
                        + blocked[at(i + 1, j, k + 1)]
                        + blocked[at(i + 1, j + 1, k)]
                        - blocked[at(i, j, k + 1)]
                        - blocked[at(i, j + 1, k)]
                        - blocked[at(i + 1, j, k)]
                        + blocked[at(i, j, k)];
                }
            }
        }
        let size = [0, 1, 2].map(|k| dims[k] as f64 * cell[k]);
        let mut axes = [0usize, 1, 2];
        axes.sort_by(|&a, &b| size[b].total_cmp(&size[a]));
        ClearBoxes {
            dims,
            blocked,
            boxes: (0..nx * ny * nz).map(|_| OnceLock::new()).collect(),
            axes,
            origin,
            cell,
            reach: DVec3::new(size[0], size[1], size[2]).length(),
        }
    }

    /// Number of cells that are not clear in the cell box `lo .. hi`.
    #[inline]
    fn blocked_in(&self, lo: [usize; 3], hi: [usize; 3]) -> u32 {
        let [nx, ny, _] = self.dims;
        let (sx, sy) = (nx + 1, (nx + 1) * (ny + 1));
        let at = |i: usize, j: usize, k: usize| self.blocked[i + sx * j + sy * k];
        // Wrapping: the partial sums may dip below zero on the way.
        at(hi[0], hi[1], hi[2])
            .wrapping_sub(at(lo[0], hi[1], hi[2]))
            .wrapping_sub(at(hi[0], lo[1], hi[2]))
            .wrapping_sub(at(hi[0], hi[1], lo[2]))
            .wrapping_add(at(lo[0], lo[1], hi[2]))
            .wrapping_add(at(lo[0], hi[1], lo[2]))
            .wrapping_add(at(hi[0], lo[1], lo[2]))
            .wrapping_sub(at(lo[0], lo[1], lo[2]))
    }

    /// Whether the box `lo .. hi` with face (`axis`, `up`) moved out by `by`
    /// cells is still clear (and inside the grid).
    fn can_push(&self, lo: [usize; 3], hi: [usize; 3], axis: usize, up: bool, by: usize) -> bool {
        let (mut a, mut b) = (lo, hi);
        if up {
            if hi[axis] + by > self.dims[axis] {
                return false;
            }
            a[axis] = hi[axis];
            b[axis] = hi[axis] + by;
        } else {
            if lo[axis] < by {
                return false;
            }
            a[axis] = lo[axis] - by;
            b[axis] = lo[axis];
        }
        self.blocked_in(a, b) == 0
    }

    /// The box of the clear cell `(i, j, k)` (step 1, then step 2).
    fn grow(&self, c: [usize; 3]) -> [u16; 6] {
        let mut lo = c;
        let mut hi = c.map(|v| v + 1);
        for _ in 0..CUBIC_ROUNDS {
            for axis in 0..3 {
                for up in [true, false] {
                    if self.can_push(lo, hi, axis, up, 1) {
                        if up {
                            hi[axis] += 1;
                        } else {
                            lo[axis] -= 1;
                        }
                    }
                }
            }
        }
        for axis in self.axes {
            for up in [true, false] {
                // Gallop to a bound, then bisect: `ok` cells can be added,
                // `bad` cannot.
                let (mut ok, mut bad) = (0usize, 1usize);
                while self.can_push(lo, hi, axis, up, bad) {
                    ok = bad;
                    bad *= 2;
                }
                while bad - ok > 1 {
                    let mid = (ok + bad) / 2;
                    if self.can_push(lo, hi, axis, up, mid) {
                        ok = mid;
                    } else {
                        bad = mid;
                    }
                }
                if up {
                    hi[axis] += ok;
                } else {
                    lo[axis] -= ok;
                }
            }
        }
        [lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]].map(|v| v as u16)
    }

    /// The box of cell `(i, j, k)` in world coordinates (infinite on the faces
    /// open beyond the grid), or `None` if the cell is not clear.
    fn world_box(&self, c: [usize; 3], idx: usize) -> Option<(DVec3, DVec3)> {
        let b = self.boxes[idx]
            .get_or_init(|| (self.blocked_in(c, c.map(|v| v + 1)) == 0).then(|| self.grow(c)));
        let b = b.as_ref()?;
        let mut lo = DVec3::ZERO;
        let mut hi = DVec3::ZERO;
        for k in 0..3 {
            lo[k] = self.origin[k] + b[k] as f64 * self.cell[k];
            hi[k] = self.origin[k] + b[k + 3] as f64 * self.cell[k];
            // Open beyond the grid, but never downward (see above).
            if k != 1 && b[k] == 0 {
                lo[k] = f64::NEG_INFINITY;
            }
            if b[k + 3] as usize == self.dims[k] {
                hi[k] = f64::INFINITY;
            }
        }
        Some((lo, hi))
    }

    /// The free arc from `p` (in cell `c`, index `idx`) along the unit
    /// tangent `t` for a ray bending at most `kappa` (0 where the cell is not
    /// clear).
    #[inline]
    pub fn arc(&self, c: [usize; 3], idx: usize, p: DVec3, t: DVec3, kappa: f64) -> f64 {
        let Some((lo, hi)) = self.world_box(c, idx) else {
            return 0.0;
        };
        exit(p, t, kappa, lo, hi).min(self.reach)
    }
}

/// The arc length a curve from `p` with unit tangent `t`, bending at most
/// `kappa`, surely stays in the box `lo .. hi` (0 if `p` is not inside it):
/// the least [`face_root`] over the six faces.
#[inline]
pub(crate) fn exit(p: DVec3, t: DVec3, kappa: f64, lo: DVec3, hi: DVec3) -> f64 {
    let mut s = f64::INFINITY;
    for k in 0..3 {
        for (d, toward) in [(hi[k] - p[k], t[k]), (p[k] - lo[k], -t[k])] {
            if d < 0.0 {
                return 0.0;
            }
            if d.is_finite() {
                s = s.min(face_root(d, toward, kappa));
            }
        }
    }
    s
}

/// The least arc s ≥ 0 after which a curve bending at most `kappa` may have
/// moved `d` ≥ 0 along an axis it moves along at rate `toward` (the tangent's
/// component): along an arc s each coordinate is within κs²/2 of the
/// tangent's, so this is the root of κs²/2 + toward·s = d, in the form
/// without cancellation for either sign of `toward` (∞ where there is none:
/// a straight curve moving away or parallel; 0 on the face itself when it
/// can bend off it).
#[inline]
pub(crate) fn face_root(d: f64, toward: f64, kappa: f64) -> f64 {
    let r = (toward * toward + 2.0 * kappa * d).sqrt();
    if toward >= 0.0 {
        let den = toward + r;
        if den > 0.0 {
            2.0 * d / den
        } else if d == 0.0 {
            0.0
        } else {
            f64::INFINITY
        }
    } else if kappa > 0.0 {
        (r - toward) / kappa
    } else {
        f64::INFINITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 10³ grid of unit cells with a blocked cell at (5, 5, 5).
    fn one_block() -> ClearBoxes {
        let mut clear = vec![true; 1000];
        clear[5 + 10 * (5 + 10 * 5)] = false;
        ClearBoxes::new([10, 10, 10], DVec3::ZERO, DVec3::ONE, &clear)
    }

    #[test]
    fn boxes_hold_no_blocked_cell_and_contain_their_cell() {
        let b = one_block();
        for k in 0..10 {
            for j in 0..10 {
                for i in 0..10 {
                    let idx = i + 10 * (j + 10 * k);
                    let Some((lo, hi)) = b.world_box([i, j, k], idx) else {
                        assert_eq!([i, j, k], [5, 5, 5]);
                        continue;
                    };
                    let centre = DVec3::new(i as f64, j as f64, k as f64) + 0.5;
                    assert!(centre.cmpge(lo).all() && centre.cmple(hi).all());
                    // The blocked cell's centre is outside every box.
                    let blocked = DVec3::splat(5.5);
                    assert!(!(blocked.cmpge(lo).all() && blocked.cmple(hi).all()));
                }
            }
        }
    }

    #[test]
    fn open_faces_reach_infinity_but_not_downward() {
        let b = one_block();
        let (lo, hi) = b.world_box([0, 0, 0], 0).unwrap();
        assert_eq!(lo.y, 0.0);
        assert!(lo.x == f64::NEG_INFINITY || lo.z == f64::NEG_INFINITY);
        assert!(hi.x.is_infinite() || hi.y.is_infinite() || hi.z.is_infinite());
    }

    #[test]
    fn the_arc_stays_inside_with_curvature() {
        let b = one_block();
        // From the middle of the bottom layer straight up the box is clear to
        // the grid top and beyond: capped by the reach.
        let p = DVec3::new(5.5, 0.5, 2.5);
        let straight = b.arc([5, 0, 2], 5 + 10 * 20, p, DVec3::Y, 0.0);
        assert!(straight > 0.0);
        // Bending lowers the arc, never raises it.
        let bent = b.arc([5, 0, 2], 5 + 10 * 20, p, DVec3::Y, 1e-2);
        assert!(bent <= straight);
        // Along +z towards the blocked cell's row the arc ends before it.
        let p = DVec3::new(5.5, 5.5, 0.5);
        let arc = b.arc([5, 5, 0], 5 + 10 * 5, p, DVec3::Z, 0.0);
        assert!(arc <= 4.5 + 1e-12, "{arc}");
    }
}
