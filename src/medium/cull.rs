//! Hot-spot culling: which hot spots can matter at a point (x, z).
//!
//! # The threshold
//!
//! A hot spot's rim weight is w = 1 − σ(t) = σ(−t) with t = e·(ρ − R). Once
//! t > [`CULL_UNITS`] (= 40), w < e^(−t) < e^(−40) ≈ 4.2·10⁻¹⁸: the hot spot
//! is *culled* there, i.e. left out of the sum. Its *reach* is the disc
//! ρ ≤ R + 40/e around its centre; outside it the term is culled.
//!
//! # The structure
//!
//! A uniform grid of square cells over the bounding box of all reach discs.
//! Each cell lists, in ascending order, the hot spots whose reach disc meets
//! the cell grown by a rounding margin ([`HotSpotGrid::candidates`]); a point
//! outside the box has an empty list. So a hot spot absent from the list of
//! the point's cell is farther than its reach: every term left out has
//! t > 40. Listing a hot spot that turns out not to matter is harmless (its
//! term is then computed exactly, as without the grid).
//!
//! The cell side is half the mean reach radius (a list holds the discs that
//! meet its cell, so its mean length is the density of hot spots times the
//! area of a reach disc grown by about a cell: with 1,024 patches over
//! 20 km², half the reach took the lanes kernel from 44 % to 52 % of the
//! one-hot-spot speed, and the scalar path from 75 % to 87 %), raised so
//! that there are at most 16 cells per hot spot (sparse patches: smaller
//! cells there only make rays change cell more often, which measured 27 %
//! slower with 64 patches) and at most 2²² entries in all (`MAX_ENTRIES`;
//! large, overlapping hot spots). A grid is only built when it pays: with at
//! least two hot spots, finite parameters and lists whose mean length is at
//! most half the hot spots; else [`HotSpotGrid::new`] gives `None` and every
//! hot spot is evaluated everywhere.
//!
//! The accuracy this gives a medium, its gradient and its parameter
//! derivatives is stated in `docs/model.md` ("Culling").

/// Units of e·(ρ − R) beyond which a hot spot is left out (see the module
/// documentation): its weight is then below e^(−40) ≈ 4.2·10⁻¹⁸.
pub const CULL_UNITS: f64 = 40.0;

/// Most entries (hot spot, cell) a grid holds; a coarser grid is taken until
/// it fits.
const MAX_ENTRIES: usize = 1 << 22;

/// Most cells per hot spot.
const CELLS_PER_SPOT: f64 = 16.0;

/// A hot spot as the grid sees it: its centre and the radius of its reach
/// (R + 40/e).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reach {
    /// Centre x (metres).
    pub x: f64,
    /// Centre z (metres).
    pub z: f64,
    /// Radius of the reach disc, R + [`CULL_UNITS`]/e (metres).
    pub radius: f64,
}

impl Reach {
    /// The reach of a hot spot of radius `radius` and rim sharpness `edge`
    /// centred at (x, z).
    pub fn of(x: f64, z: f64, radius: f64, edge: f64) -> Self {
        Reach {
            x,
            z,
            radius: radius + CULL_UNITS / edge,
        }
    }
}

/// A uniform grid over (x, z) listing, per cell, the hot spots that can
/// matter in it (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct HotSpotGrid {
    x0: f64,
    z0: f64,
    cell: f64,
    inv_cell: f64,
    nx: usize,
    nz: usize,
    /// Where each cell's list starts in `items`; one more cell than the grid
    /// has (the empty list of points outside it), and one end.
    starts: Vec<u32>,
    items: Vec<u32>,
    longest: usize,
}

impl HotSpotGrid {
    /// The grid for these hot spots (in the medium's order), or `None` where
    /// culling would not pay or cannot be trusted: fewer than two hot spots,
    /// a non-finite centre or reach (an unvalidated medium: every term is
    /// then evaluated, so its non-finite values show), or lists as long as
    /// half the hot spots on average.
    pub fn new(spots: &[Reach]) -> Option<Self> {
        let n = spots.len();
        if !(2..=MAX_ENTRIES).contains(&n)
            || spots
                .iter()
                .any(|s| !(s.x.is_finite() && s.z.is_finite() && s.radius.is_finite()))
        {
            return None;
        }
        // The box of all reach discs (a disc of negative radius reaches
        // nothing; it is kept at its centre so the box stays well formed).
        let (mut x0, mut x1, mut z0, mut z1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for s in spots {
            let r = s.radius.max(0.0);
            x0 = x0.min(s.x - r);
            x1 = x1.max(s.x + r);
            z0 = z0.min(s.z - r);
            z1 = z1.max(s.z + r);
        }
        let (w, h) = ((x1 - x0).max(1e-9), (z1 - z0).max(1e-9));
        if !(w * h).is_finite() {
            return None;
        }
        let mean_reach = spots.iter().map(|s| s.radius.max(0.0)).sum::<f64>() / n as f64;
        let mut cell = (0.5 * mean_reach)
            .max((w * h / (CELLS_PER_SPOT * n as f64)).sqrt())
            .max(1e-6 * w.max(h));
        loop {
            let grid = Self::build(spots, x0, z0, w, h, cell)?;
            if let Some(grid) = grid {
                return (grid.items.len() as f64 / (grid.nx * grid.nz) as f64 <= 0.5 * n as f64)
                    .then_some(grid);
            }
            cell *= 2.0;
        }
    }

    /// The grid with cells of side `cell`; `Some(None)` when it would hold
    /// more than [`MAX_ENTRIES`] entries, `None` when it cannot be built.
    fn build(spots: &[Reach], x0: f64, z0: f64, w: f64, h: f64, cell: f64) -> Option<Option<Self>> {
        let nx = (w / cell).ceil().max(1.0);
        let nz = (h / cell).ceil().max(1.0);
        if nx * nz > MAX_ENTRIES as f64 {
            return Some(None);
        }
        let (nx, nz) = (nx as usize, nz as usize);
        // A point within rounding of a cell's side may be filed in the cell
        // next to it: grow every cell by a margin far above that rounding.
        let margin = 1e-9 * (cell + x0.abs().max(z0.abs()) + w.max(h));
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); nx * nz];
        let mut entries = 0usize;
        for (j, s) in spots.iter().enumerate() {
            if s.radius < 0.0 {
                continue;
            }
            let reach = s.radius + margin;
            let span = |c: f64, origin: f64, count: usize| {
                let lo = ((c - reach - origin) / cell).floor().max(0.0);
                let hi = ((c + reach - origin) / cell)
                    .floor()
                    .min(count as f64 - 1.0);
                (lo as usize, hi as usize)
            };
            let (i0, i1) = span(s.x, x0, nx);
            let (k0, k1) = span(s.z, z0, nz);
            for k in k0..=k1 {
                for i in i0..=i1 {
                    // Distance from the centre to the cell (a square of side
                    // `cell` grown by the margin).
                    let cx0 = x0 + i as f64 * cell;
                    let cz0 = z0 + k as f64 * cell;
                    let dx = (cx0 - s.x).max(s.x - (cx0 + cell)).max(0.0);
                    let dz = (cz0 - s.z).max(s.z - (cz0 + cell)).max(0.0);
                    if dx.hypot(dz) <= reach {
                        lists[k * nx + i].push(j as u32);
                        entries += 1;
                        if entries > MAX_ENTRIES {
                            return Some(None);
                        }
                    }
                }
            }
        }
        let mut starts = Vec::with_capacity(nx * nz + 2);
        let mut items = Vec::with_capacity(entries);
        for list in &lists {
            starts.push(items.len() as u32);
            items.extend_from_slice(list);
        }
        // The outside cell (index nx·nz) and the end.
        starts.push(items.len() as u32);
        starts.push(items.len() as u32);
        let longest = lists.iter().map(Vec::len).max().unwrap_or(0);
        Some(Some(HotSpotGrid {
            x0,
            z0,
            cell,
            inv_cell: 1.0 / cell,
            nx,
            nz,
            starts,
            items,
            longest,
        }))
    }

    /// The cell of the point (x, z); points outside the grid (and NaN) share
    /// the cell [`Self::outside`], whose list is empty.
    #[inline]
    pub fn cell_of(&self, x: f64, z: f64) -> usize {
        let fx = (x - self.x0) * self.inv_cell;
        let fz = (z - self.z0) * self.inv_cell;
        // `!(a < b)` also takes NaN outside.
        if fx >= 0.0 && fz >= 0.0 && fx < self.nx as f64 && fz < self.nz as f64 {
            // The last cell absorbs a point within rounding of the far side.
            let i = (fx as usize).min(self.nx - 1);
            let k = (fz as usize).min(self.nz - 1);
            k * self.nx + i
        } else {
            self.outside()
        }
    }

    /// The cell of every point outside the grid (its list is empty).
    #[inline]
    pub fn outside(&self) -> usize {
        self.nx * self.nz
    }

    /// The hot spots listed in `cell` (indices into the medium's hot spots,
    /// ascending).
    #[inline]
    pub fn list(&self, cell: usize) -> &[u32] {
        &self.items[self.starts[cell] as usize..self.starts[cell + 1] as usize]
    }

    /// The hot spots that can matter at (x, z): every hot spot whose term
    /// there is not below the threshold, ascending; possibly a few more.
    #[inline]
    pub fn candidates(&self, x: f64, z: f64) -> &[u32] {
        self.list(self.cell_of(x, z))
    }

    /// The longest list of any cell.
    pub fn longest(&self) -> usize {
        self.longest
    }

    /// The side of a cell (metres).
    pub fn cell_size(&self) -> f64 {
        self.cell
    }

    /// Number of cells (without the outside one).
    pub fn cells(&self) -> usize {
        self.nx * self.nz
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A uniform number in [0, 1) from a 64-bit LCG (the lanes' culling
    /// test scatters its desert with it too).
    pub(crate) fn lcg(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*seed >> 11) as f64 / (1u64 << 53) as f64
    }

    fn scatter(n: usize) -> Vec<Reach> {
        let mut seed = 7;
        (0..n)
            .map(|_| Reach {
                x: -2000.0 + 4000.0 * lcg(&mut seed),
                z: -1000.0 + 5000.0 * lcg(&mut seed),
                radius: 10.0 + 60.0 * lcg(&mut seed),
            })
            .collect()
    }

    /// Every hot spot within its reach of a point is listed there, on and
    /// around cell sides too.
    #[test]
    fn lists_every_hot_spot_in_reach() {
        let spots = scatter(500);
        let grid = HotSpotGrid::new(&spots).expect("a scattered field is culled");
        assert!(grid.longest() < 50, "longest list {}", grid.longest());
        let mut seed = 3;
        for trial in 0..20_000 {
            let (x, z) = if trial % 2 == 0 {
                (
                    -2200.0 + 4400.0 * lcg(&mut seed),
                    -1200.0 + 5400.0 * lcg(&mut seed),
                )
            } else {
                // On a cell side.
                let i = (lcg(&mut seed) * grid.nx as f64).floor();
                (grid.x0 + i * grid.cell, -1000.0 + 5000.0 * lcg(&mut seed))
            };
            let list = grid.candidates(x, z);
            assert!(list.windows(2).all(|w| w[0] < w[1]), "ascending");
            for (j, s) in spots.iter().enumerate() {
                if (x - s.x).hypot(z - s.z) <= s.radius {
                    assert!(list.contains(&(j as u32)), "spot {j} at ({x}, {z})");
                }
            }
        }
        assert!(grid.candidates(1e12, 0.0).is_empty());
        assert!(grid.candidates(f64::NAN, 0.0).is_empty());
    }

    #[test]
    fn declines_when_it_would_not_pay() {
        assert_eq!(HotSpotGrid::new(&scatter(1)), None);
        // Eight discs that all cover each other.
        let big: Vec<Reach> = (0..8)
            .map(|j| Reach {
                x: 10.0 * j as f64,
                z: 0.0,
                radius: 900.0,
            })
            .collect();
        assert_eq!(HotSpotGrid::new(&big), None);
        let mut bad = scatter(10);
        bad[3].radius = f64::INFINITY;
        assert_eq!(HotSpotGrid::new(&bad), None);
    }

    #[test]
    fn reach_is_forty_rim_units() {
        let r = Reach::of(1.0, 2.0, 30.0, 4.0);
        assert_eq!(r.radius, 40.0);
        // The weight at the reach: σ(−40).
        let w = 1.0 / (1.0 + CULL_UNITS.exp());
        assert!(w < 4.3e-18);
    }
}
