//! The medium's right-hand-side terms, lane-wise: δ and ∇δ of a compiled
//! [`LogisticField`] at every lane's position, with the operations of
//! `LogisticField::delta_gradient` in its order and the polynomial
//! exponential inlined, so that each term loop compiles to SIMD code.
//!
//! # Culling
//!
//! Where the field has a [`HotSpotGrid`], each lane pays only for the hot
//! spots listed in its own cell, the list the scalar field takes at the same
//! point, in the same order ([`HotCache`]): the lanes then agree with the
//! scalar code as they do without culling. Each lane's list is copied into
//! lane-major slots when the lane enters another cell, and the k-th slots
//! of all lanes are evaluated together in one SIMD loop (the coefficients
//! loaded per lane instead of broadcast); a lane with a shorter list is
//! padded with a hot spot of zero amplitude, which adds exactly 0. A step
//! thus costs the longest list among the lanes, not the number of hot spots.
//!
//! Where the lanes sit in different cells (a fan of rays over a desert of
//! patches), the longest list is several times the mean one, and most of
//! those slots are padding. The cache then also *packs* the lists: the
//! (lane, hot spot) pairs, k-th entries of all lanes before the (k+1)-th,
//! fill chunks of N items; each chunk's terms are computed in one SIMD loop
//! (the positions gathered by lane) and added to their lanes one item at a
//! time, in chunk order. Each lane thus still adds its hot spots in its
//! list's order, the terms are the same numbers, and a step costs
//! ⌈Σ lists / N⌉ chunks instead of the longest list. The cache takes the
//! packed form whenever it has fewer chunks than the longest list has
//! entries (decided when a lane changes cell).

// Lane loops index several arrays in lockstep; `for i in 0..N` over fixed-size
// arrays is the form the compiler vectorizes.
#![allow(clippy::needless_range_loop)]

use super::num::LaneNum;
use crate::medium::LogisticField;
use crate::medium::cull::HotSpotGrid;

/// The compiled field as plain numbers (see `LogisticField::coefficients`).
#[derive(Clone, Debug)]
pub(crate) struct Coefficients {
    /// Background `[amp, 1/a]`.
    pub background: Option<[f64; 2]>,
    /// Inversion `[amp, 1/a, height]`.
    pub inversion: Option<[f64; 3]>,
    /// Hot spots `[amp, 1/a, x, z, radius, edge]`.
    pub hotspots: Vec<[f64; 6]>,
    /// The grid that culls them, if any.
    pub grid: Option<HotSpotGrid>,
}

/// A hot spot that adds exactly 0 at every finite point (zero amplitude,
/// finite everything else): the padding of a short list.
const NULL_SPOT: [f64; 6] = [0.0, 1.0, 0.0, 0.0, 0.0, 1.0];

/// Each lane's culled hot spots (see the module documentation): the cell it
/// was last evaluated in and that cell's hot spots, lane-major.
pub(crate) struct HotCache<const N: usize> {
    /// Each lane's cell (`usize::MAX`: none yet).
    cell: [usize; N],
    /// Each lane's number of listed hot spots.
    count: [usize; N],
    /// The largest count.
    longest: usize,
    /// `slots[k][f][i]`: coefficient f of lane i's k-th hot spot.
    slots: Vec<[[f64; N]; 6]>,
    /// The packed lists (see the module documentation): chunks of N
    /// (lane, hot spot) items, the last one possibly partly full; empty
    /// when the lanes use their slots instead.
    chunks: Vec<Chunk<N>>,
}

/// N packed items: each its lane and its hot spot's coefficients.
#[derive(Clone, Copy)]
struct Chunk<const N: usize> {
    /// `coef[f][j]`: coefficient f of item j's hot spot.
    coef: [[f64; N]; 6],
    /// Item j's lane (padding items: lane 0 and [`NULL_SPOT`], never added).
    lane: [usize; N],
    /// Items in use.
    len: usize,
}

impl<const N: usize> HotCache<N> {
    /// A cache for the lists of `grid` (none: an empty cache, never read).
    pub(crate) fn new(grid: Option<&HotSpotGrid>) -> Self {
        let lane_major = std::array::from_fn(|f| [NULL_SPOT[f]; N]);
        HotCache {
            cell: [usize::MAX; N],
            count: [0; N],
            longest: 0,
            slots: vec![lane_major; grid.map_or(0, HotSpotGrid::longest)],
            chunks: Vec::new(),
        }
    }

    /// Brings every lane's list to the cell of its position (x, z).
    #[inline(always)]
    fn update(&mut self, grid: &HotSpotGrid, spots: &[[f64; 6]], x: &[f64; N], z: &[f64; N]) {
        let mut changed = false;
        for i in 0..N {
            let cell = grid.cell_of(x[i], z[i]);
            if cell != self.cell[i] {
                self.refill(i, cell, grid, spots);
                changed = true;
            }
        }
        if changed {
            self.longest = self.count.iter().copied().max().unwrap_or(0);
            self.chunks.clear();
            let total: usize = self.count.iter().sum();
            if total.div_ceil(N) < self.longest {
                self.pack();
            }
        }
    }

    /// Fills `chunks` from the lanes' slots: the k-th entries of all lanes,
    /// lane by lane, before the (k+1)-th (rare: on a change of cell).
    #[inline(never)]
    fn pack(&mut self) {
        let empty = Chunk {
            coef: std::array::from_fn(|f| [NULL_SPOT[f]; N]),
            lane: [0; N],
            len: 0,
        };
        let mut chunk = empty;
        for (k, slot) in self.slots[..self.longest].iter().enumerate() {
            for i in 0..N {
                if k >= self.count[i] {
                    continue;
                }
                let j = chunk.len;
                for f in 0..6 {
                    chunk.coef[f][j] = slot[f][i];
                }
                chunk.lane[j] = i;
                chunk.len += 1;
                if chunk.len == N {
                    self.chunks.push(chunk);
                    chunk = empty;
                }
            }
        }
        if chunk.len > 0 {
            self.chunks.push(chunk);
        }
    }

    /// Copies the list of `cell` into lane `i`'s slots (rare: on entering a
    /// cell, so not inlined into the lane loops).
    #[inline(never)]
    fn refill(&mut self, i: usize, cell: usize, grid: &HotSpotGrid, spots: &[[f64; 6]]) {
        let list = grid.list(cell);
        for (slot, &j) in self.slots.iter_mut().zip(list) {
            let h = spots[j as usize];
            for f in 0..6 {
                slot[f][i] = h[f];
            }
        }
        for slot in &mut self.slots[list.len()..self.count[i].max(list.len())] {
            for f in 0..6 {
                slot[f][i] = NULL_SPOT[f];
            }
        }
        self.cell[i] = cell;
        self.count[i] = list.len();
    }
}

impl Coefficients {
    pub(crate) fn of(field: &LogisticField) -> Self {
        let raw = field.coefficients();
        Coefficients {
            background: raw.background,
            inversion: raw.inversion,
            hotspots: raw.hotspots,
            grid: raw.grid,
        }
    }

    /// Adds the stratified terms' δ and dδ/dy at heights `y` to `d` and `gy`,
    /// with the operations of `LogisticField::delta_gradient` in its order.
    #[inline(always)]
    pub(crate) fn layers<const N: usize, const FMA: bool>(
        &self,
        y: &[f64; N],
        d: &mut [f64; N],
        gy: &mut [f64; N],
    ) {
        // Each combination of terms gets its own loop (the const parameters),
        // so no lane loop tests for absent terms.
        match (self.background, self.inversion) {
            (Some(bg), Some(inv)) => layer_loop::<N, FMA, true, true>(bg, inv, y, d, gy),
            (Some(bg), None) => layer_loop::<N, FMA, true, false>(bg, [0.0; 3], y, d, gy),
            (None, Some(inv)) => layer_loop::<N, FMA, false, true>([0.0; 2], inv, y, d, gy),
            (None, None) => {}
        }
    }

    /// δ and ∇δ at the lanes' positions, the whole field with hot spots,
    /// accumulated into `d` and `g` (which the caller zeroes); `cache` holds
    /// each lane's culled hot spots where the field has a grid.
    #[inline(always)]
    pub(crate) fn delta_gradient<const N: usize, const FMA: bool>(
        &self,
        cache: &mut HotCache<N>,
        p: [&[f64; N]; 3],
        d: &mut [f64; N],
        g: [&mut [f64; N]; 3],
    ) {
        if let Some(grid) = &self.grid {
            cache.update(grid, &self.hotspots, p[0], p[2]);
            let (bg, inv) = (self.background, self.inversion);
            return match (bg, inv) {
                (Some(bg), Some(inv)) => culled::<N, FMA, true, true>(bg, inv, cache, p, d, g),
                (Some(bg), None) => culled::<N, FMA, true, false>(bg, [0.0; 3], cache, p, d, g),
                (None, Some(inv)) => culled::<N, FMA, false, true>([0.0; 2], inv, cache, p, d, g),
                (None, None) => culled::<N, FMA, false, false>([0.0; 2], [0.0; 3], cache, p, d, g),
            };
        }
        match (self.background, self.inversion) {
            (Some(bg), Some(inv)) => self.full::<N, FMA, true, true>(bg, inv, p, d, g),
            (Some(bg), None) => self.full::<N, FMA, true, false>(bg, [0.0; 3], p, d, g),
            (None, Some(inv)) => self.full::<N, FMA, false, true>([0.0; 2], inv, p, d, g),
            (None, None) => self.full::<N, FMA, false, false>([0.0; 2], [0.0; 3], p, d, g),
        }
    }

    /// [`Self::delta_gradient`] for one combination of layers. The layers
    /// share a lane loop with the first hot spot, and further hot spots go two
    /// to a loop: several independent exponentials per lane keep enough
    /// multiply–add chains in flight to hide their latency. Terms are still
    /// added in the scalar code's order.
    #[inline(always)]
    fn full<const N: usize, const FMA: bool, const BG: bool, const INV: bool>(
        &self,
        bg: [f64; 2],
        inv: [f64; 3],
        [x, y, z]: [&[f64; N]; 3],
        d: &mut [f64; N],
        [gx, gy, gz]: [&mut [f64; N]; 3],
    ) {
        let Some((first, rest)) = self.hotspots.split_first() else {
            if BG || INV {
                layer_loop::<N, FMA, BG, INV>(bg, inv, y, d, gy);
            }
            return;
        };
        for i in 0..N {
            let (di, gyi) = layer_point::<FMA, BG, INV>(bg, inv, y[i], d[i], gy[i]);
            let acc = hot_point::<FMA>(*first, x[i], y[i], z[i], [di, gx[i], gyi, gz[i]]);
            [d[i], gx[i], gy[i], gz[i]] = acc;
        }
        for pair in rest.chunks(2) {
            match *pair {
                [h0, h1] => {
                    for i in 0..N {
                        let acc = [d[i], gx[i], gy[i], gz[i]];
                        let acc = hot_point::<FMA>(h0, x[i], y[i], z[i], acc);
                        let acc = hot_point::<FMA>(h1, x[i], y[i], z[i], acc);
                        [d[i], gx[i], gy[i], gz[i]] = acc;
                    }
                }
                [h0] => {
                    for i in 0..N {
                        let acc = [d[i], gx[i], gy[i], gz[i]];
                        [d[i], gx[i], gy[i], gz[i]] = hot_point::<FMA>(h0, x[i], y[i], z[i], acc);
                    }
                }
                _ => unreachable!("chunks of at most two"),
            }
        }
    }
}

/// The culled field for one combination of layers: the layers, then each
/// lane's listed hot spots (see the module documentation), two slots to a
/// loop as in the unculled code, in the scalar code's order.
#[inline(always)]
fn culled<const N: usize, const FMA: bool, const BG: bool, const INV: bool>(
    bg: [f64; 2],
    inv: [f64; 3],
    cache: &HotCache<N>,
    [x, y, z]: [&[f64; N]; 3],
    d: &mut [f64; N],
    [gx, gy, gz]: [&mut [f64; N]; 3],
) {
    if BG || INV {
        layer_loop::<N, FMA, BG, INV>(bg, inv, y, d, gy);
    }
    if !cache.chunks.is_empty() {
        return packed::<N, FMA>(cache, [x, y, z], d, [gx, gy, gz]);
    }
    let lane = |slot: &[[f64; N]; 6], i: usize| std::array::from_fn(|f| slot[f][i]);
    for pair in cache.slots[..cache.longest].chunks(2) {
        match pair {
            [s0, s1] => {
                for i in 0..N {
                    let acc = [d[i], gx[i], gy[i], gz[i]];
                    let acc = hot_point::<FMA>(lane(s0, i), x[i], y[i], z[i], acc);
                    let acc = hot_point::<FMA>(lane(s1, i), x[i], y[i], z[i], acc);
                    [d[i], gx[i], gy[i], gz[i]] = acc;
                }
            }
            [s0] => {
                for i in 0..N {
                    let acc = [d[i], gx[i], gy[i], gz[i]];
                    [d[i], gx[i], gy[i], gz[i]] =
                        hot_point::<FMA>(lane(s0, i), x[i], y[i], z[i], acc);
                }
            }
            _ => unreachable!("chunks of at most two"),
        }
    }
}

/// The packed lists' terms (see the module documentation): per chunk, the
/// items' positions gathered from their lanes, their terms in one SIMD loop,
/// then each added to its lane in item order.
#[inline(always)]
fn packed<const N: usize, const FMA: bool>(
    cache: &HotCache<N>,
    [x, y, z]: [&[f64; N]; 3],
    d: &mut [f64; N],
    [gx, gy, gz]: [&mut [f64; N]; 3],
) {
    for chunk in &cache.chunks {
        // `% N` keeps the index in bounds without a check (N is a power of
        // two); every lane index is below N already.
        let at = |v: &[f64; N], j: usize| v[chunk.lane[j] % N];
        let mut t = [[0.0; N]; 4];
        for j in 0..N {
            let coef = std::array::from_fn(|f| chunk.coef[f][j]);
            let term = hot_term::<f64, FMA>(coef, at(x, j), at(y, j), at(z, j));
            for k in 0..4 {
                t[k][j] = term[k];
            }
        }
        for j in 0..chunk.len {
            let i = chunk.lane[j] % N;
            d[i] += t[0][j];
            gx[i] += t[1][j];
            gy[i] += t[2][j];
            gz[i] += t[3][j];
        }
    }
}

/// The layers' loop over lanes: adds the background (if `BG`) and the
/// inversion (if `INV`) to `d` and `gy`.
#[inline(always)]
fn layer_loop<const N: usize, const FMA: bool, const BG: bool, const INV: bool>(
    bg: [f64; 2],
    inv: [f64; 3],
    y: &[f64; N],
    d: &mut [f64; N],
    gy: &mut [f64; N],
) {
    for i in 0..N {
        (d[i], gy[i]) = layer_point::<FMA, BG, INV>(bg, inv, y[i], d[i], gy[i]);
    }
}

/// `d` and `gy` plus the layers' terms at height y, in the scalar order.
#[inline(always)]
fn layer_point<const FMA: bool, const BG: bool, const INV: bool>(
    bg: [f64; 2],
    inv: [f64; 3],
    y: f64,
    mut d: f64,
    mut gy: f64,
) -> (f64, f64) {
    if BG {
        let (db, gb) = background_term::<f64, FMA>(bg, y);
        d += db;
        gy += gb;
    }
    if INV {
        let (di, gi) = inversion_term::<f64, FMA>(inv, y);
        d += di;
        gy -= gi;
    }
    (d, gy)
}

/// (δ, ∂δ/∂x, ∂δ/∂y, ∂δ/∂z) plus one hot spot's terms at (x, y, z), with the
/// operations of `LogisticField::delta_gradient`.
#[inline(always)]
fn hot_point<const FMA: bool>(
    spot: [f64; 6],
    x: f64,
    y: f64,
    z: f64,
    [d, gx, gy, gz]: [f64; 4],
) -> [f64; 4] {
    let [td, tx, ty, tz] = hot_term::<f64, FMA>(spot, x, y, z);
    [d + td, gx + tx, gy + ty, gz + tz]
}

/// One hot spot's (δ, ∂δ/∂x, ∂δ/∂y, ∂δ/∂z) at (x, y, z), with the operations
/// of `LogisticField::delta_gradient`; in [`Tan`](super::num::Tan) numbers
/// (the tangent kernel) also their derivatives along its seeds. It is its
/// three parts in a row ([`rim_part`], [`layer_part`], [`hot_combine`]),
/// which the tangent kernel runs as three lane loops.
#[inline(always)]
pub(crate) fn hot_term<T: LaneNum, const FMA: bool>(
    [amp, inv_rate, hx, hz, radius, edge]: [T; 6],
    x: T,
    y: T,
    z: T,
) -> [T; 4] {
    let rim = rim_part::<T, FMA>([hx, hz, radius, edge], x, z);
    let layer = layer_part::<T, FMA>(inv_rate, y);
    hot_combine(amp, inv_rate, rim, layer)
}

/// A hot spot's rim at (x, z): `[w, dw/dρ, ρ̂_x, ρ̂_z]`.
#[inline(always)]
pub(crate) fn rim_part<T: LaneNum, const FMA: bool>(
    [hx, hz, radius, edge]: [T; 4],
    x: T,
    z: T,
) -> [T; 4] {
    let dx = x - hx;
    let dz = z - hz;
    // ρ without the scalar code's rescaling: an overflow to ∞ for
    // |dx| > 10¹⁵⁴ still gives w = 0 and a zero gradient, not NaN.
    let rho = T::fmadd::<FMA>(dx, dx, dz * dz).sqrt();
    let (w, dw) = (edge * (radius - rho)).sigmoid::<FMA>();
    let dw_drho = -(edge * dw);
    // At the cone tip (ρ = 0) the horizontal derivative is 0; so it is where
    // dx² + dz² underflows (within 10⁻¹⁶² m of the centre), where ρ = 0 too
    // and dx/ρ would blow up.
    let inv_rho = rho.recip_or_zero();
    [w, dw_drho, dx * inv_rho, dz * inv_rho]
}

/// A hot spot's layer at height y: `[σ(y/a), σ'(y/a)]`.
#[inline(always)]
pub(crate) fn layer_part<T: LaneNum, const FMA: bool>(inv_rate: T, y: T) -> [T; 2] {
    let (s, ds) = (y * inv_rate).sigmoid::<FMA>();
    [s, ds]
}

/// A hot spot's terms from its rim and layer parts.
#[inline(always)]
pub(crate) fn hot_combine<T: LaneNum>(
    amp: T,
    inv_rate: T,
    [w, dw_drho, ux, uz]: [T; 4],
    [s, ds]: [T; 2],
) -> [T; 4] {
    let amp_s = amp * s;
    [
        amp_s * w,
        amp_s * dw_drho * ux,
        amp * w * ds * inv_rate,
        amp_s * dw_drho * uz,
    ]
}

/// The background's (δ, dδ/dy) at height y.
#[inline(always)]
pub(crate) fn background_term<T: LaneNum, const FMA: bool>(
    [amp, inv_rate]: [T; 2],
    y: T,
) -> (T, T) {
    let (s, ds) = (y * inv_rate).sigmoid::<FMA>();
    (amp * s, amp * ds * inv_rate)
}

/// The inversion's δ and −dδ/dy at height y (subtracted, as in the scalar code).
#[inline(always)]
pub(crate) fn inversion_term<T: LaneNum, const FMA: bool>(
    [amp, inv_rate, height]: [T; 3],
    y: T,
) -> (T, T) {
    let (s, ds) = ((height - y) * inv_rate).sigmoid::<FMA>();
    (amp * s, amp * ds * inv_rate)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::medium::{Background, HotSpot, IndexField, Inversion, LogisticMedium};

    /// 400 patches over 2 km × 2 km on a background and an inversion.
    fn desert() -> LogisticField {
        let mut seed = 7_u64;
        let mut uniform = move || crate::medium::cull::tests::lcg(&mut seed);
        LogisticMedium {
            scale: 1.3,
            background: Some(Background { n: 1.0, a: 40.0 }),
            inversion: Some(Inversion {
                n: 0.3,
                a: 2.0,
                height: 25.0,
            }),
            hotspots: (0..400)
                .map(|_| HotSpot {
                    x: -1000.0 + 2000.0 * uniform(),
                    z: -1000.0 + 2000.0 * uniform(),
                    radius: 10.0 + 30.0 * uniform(),
                    n: -2.0,
                    a: -0.8,
                    edge: 1.0,
                })
                .collect(),
        }
        .field()
    }

    type Out = ([f64; 16], [[f64; 16]; 3]);

    fn evaluate(c: &Coefficients, cache: &mut HotCache<16>, p: &[[f64; 16]; 3]) -> Out {
        let (mut d, mut g) = ([0.0; 16], [[0.0; 16]; 3]);
        let [gx, gy, gz] = &mut g;
        c.delta_gradient::<16, false>(cache, [&p[0], &p[1], &p[2]], &mut d, [gx, gy, gz]);
        (d, g)
    }

    /// Lanes scattered over the desert take the packed lists, and those give
    /// bit for bit the lane-major slots' sums (each lane adds the same terms
    /// in the same order), which equal the scalar field's to rounding.
    #[test]
    fn packed_lists_give_the_slots_sums() {
        let field = desert();
        let c = Coefficients::of(&field);
        let grid = c.grid.as_ref().expect("a desert is culled");
        let mut packed_steps = 0;
        for step in 0..200 {
            // A fan of lanes walking outwards from the origin.
            let r = 5.0 * step as f64;
            let p: [[f64; 16]; 3] = [
                std::array::from_fn(|i| r * (0.1 * i as f64 - 0.75).sin()),
                std::array::from_fn(|i| 0.2 + 0.1 * i as f64),
                std::array::from_fn(|i| r * (0.1 * i as f64 - 0.75).cos()),
            ];
            let mut cache = HotCache::<16>::new(Some(grid));
            let a = evaluate(&c, &mut cache, &p);
            if cache.chunks.is_empty() {
                continue;
            }
            packed_steps += 1;
            let total: usize = cache.count.iter().sum();
            assert!(total.div_ceil(16) < cache.longest);
            assert_eq!(cache.chunks.len(), total.div_ceil(16));
            // The same lists from the lane-major slots.
            cache.chunks.clear();
            let b = evaluate(&c, &mut cache, &p);
            let bits = |o: &Out| {
                let mut v: Vec<u64> = o.0.iter().map(|x| x.to_bits()).collect();
                v.extend(o.1.iter().flatten().map(|x| x.to_bits()));
                v
            };
            assert_eq!(bits(&a), bits(&b), "step {step}");
            for i in 0..16 {
                let q = crate::math::V3::new(p[0][i], p[1][i], p[2][i]);
                let (d, g) = field.delta_gradient(q);
                // δ is ~10⁻⁴ at most: 10⁻¹⁸ is a hundred roundings of it.
                assert!((a.0[i] - d).abs() <= 1e-18, "lane {i}: {} vs {d}", a.0[i]);
                for (k, gk) in [g.x, g.y, g.z].into_iter().enumerate() {
                    assert!(
                        (a.1[k][i] - gk).abs() <= 1e-12 * gk.abs() + 1e-18,
                        "lane {i}"
                    );
                }
            }
        }
        assert!(packed_steps > 100, "only {packed_steps} of 200 packed");
    }
}
