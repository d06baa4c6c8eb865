//! A lattice of heights in geographic coordinates, and bilinear sampling.
//!
//! Sample (r, c) (row r from the north, column c from the west) stands at
//! latitude `lat0 + r·dlat` and longitude `lon0 + c·dlon`, with `dlat < 0`
//! and `dlon > 0` (north-up, as SRTM tiles and GeoTIFFs from GDAL are
//! stored; a south-up file is flipped when read). A height is metres above
//! mean sea level, `NaN` where the file has a void.
//!
//! # Sampling ([`Grid::height`])
//!
//! Bilinear in (latitude, longitude) between the four samples around the
//! point: exact at samples, continuous, and exact for any height that is
//! linear in latitude and in longitude separately. A point whose four
//! samples are not all valid, or that lies outside the lattice by more than
//! `margin` samples (half a sample for a grid whose pixels are areas, zero
//! for point samples), has no height: the mosaic above then asks the next
//! file, or the sea.

/// The margin of a grid of point samples (in samples): its edge, give or
/// take the rounding of a latitude computed from its tags.
pub const EDGE: f64 = 1e-6;

/// Heights on a regular latitude–longitude lattice (see the module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    /// Latitude of row 0 (degrees).
    pub lat0: f64,
    /// Longitude of column 0 (degrees).
    pub lon0: f64,
    /// Latitude step from one row to the next (degrees, < 0: rows go south).
    pub dlat: f64,
    /// Longitude step from one column to the next (degrees, > 0).
    pub dlon: f64,
    /// Number of rows.
    pub rows: usize,
    /// Number of columns.
    pub cols: usize,
    /// Heights (m), row after row; `NaN` for a void.
    pub heights: Vec<f32>,
    /// How far outside the outer samples (in samples) the grid still answers,
    /// by clamping to its edge: ½ for area pixels, 0 for point samples.
    pub margin: f64,
}

impl Grid {
    /// The height at (lat, lon) in degrees, bilinear; `None` outside the
    /// grid or next to a void. `lon` is taken modulo 360° to the grid's
    /// longitudes.
    pub fn height(&self, lat: f64, lon: f64) -> Option<f64> {
        if self.rows == 0 || self.cols == 0 || !(lat.is_finite() && lon.is_finite()) {
            return None;
        }
        let lon = self.lon0 + (lon - self.lon0).rem_euclid(360.0);
        let r = (lat - self.lat0) / self.dlat;
        let mut c = (lon - self.lon0) / self.dlon;
        // A longitude just west of the grid reads as ~360° east of it.
        if c > self.cols as f64 - 1.0 + self.margin
            && (lon - 360.0 - self.lon0) / self.dlon >= -self.margin
        {
            c = (lon - 360.0 - self.lon0) / self.dlon;
        }
        let (rmax, cmax) = ((self.rows - 1) as f64, (self.cols - 1) as f64);
        if r < -self.margin || r > rmax + self.margin || c < -self.margin || c > cmax + self.margin
        {
            return None;
        }
        let (r, c) = (r.clamp(0.0, rmax), c.clamp(0.0, cmax));
        let (r0, c0) = (
            (r.floor() as usize).min(self.rows.saturating_sub(2)),
            (c.floor() as usize).min(self.cols.saturating_sub(2)),
        );
        let (r1, c1) = ((r0 + 1).min(self.rows - 1), (c0 + 1).min(self.cols - 1));
        let (fr, fc) = (r - r0 as f64, c - c0 as f64);
        let at = |i: usize, j: usize| f64::from(self.heights[i * self.cols + j]);
        let (h00, h01, h10, h11) = (at(r0, c0), at(r0, c1), at(r1, c0), at(r1, c1));
        let h = (1.0 - fr) * ((1.0 - fc) * h00 + fc * h01) + fr * ((1.0 - fc) * h10 + fc * h11);
        h.is_finite().then_some(h)
    }

    /// The highest valid height (m), or `None` when every sample is a void.
    pub fn max_height(&self) -> Option<f64> {
        self.heights
            .iter()
            .filter(|h| h.is_finite())
            .map(|&h| f64::from(h))
            .reduce(f64::max)
    }

    /// The latitudes and longitudes the grid covers (degrees):
    /// `[south, north]`, `[west, east]`, margins included.
    pub fn bounds(&self) -> ([f64; 2], [f64; 2]) {
        let lat_a = self.lat0 - self.margin * self.dlat;
        let lat_b = self.lat0 + (self.rows as f64 - 1.0 + self.margin) * self.dlat;
        let lon_a = self.lon0 - self.margin * self.dlon;
        let lon_b = self.lon0 + (self.cols as f64 - 1.0 + self.margin) * self.dlon;
        (
            [lat_a.min(lat_b), lat_a.max(lat_b)],
            [lon_a.min(lon_b), lon_a.max(lon_b)],
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 3 × 4 grid of h = 10·lat + lon over lat 43…41, lon 2…5.
    fn planar(margin: f64) -> Grid {
        let (rows, cols) = (3, 4);
        let mut heights = Vec::new();
        for r in 0..rows {
            for c in 0..cols {
                heights.push((10.0 * (43.0 - r as f64) + (2.0 + c as f64)) as f32);
            }
        }
        Grid {
            lat0: 43.0,
            lon0: 2.0,
            dlat: -1.0,
            dlon: 1.0,
            rows,
            cols,
            heights,
            margin,
        }
    }

    #[test]
    fn bilinear_is_exact_for_bilinear_heights() {
        let g = planar(0.0);
        for (lat, lon) in [(43.0, 2.0), (41.0, 5.0), (42.3, 3.7), (41.5, 2.25)] {
            let h = g.height(lat, lon).unwrap();
            assert!((h - (10.0 * lat + lon)).abs() < 1e-9, "{lat} {lon}: {h}");
        }
        // Longitudes modulo 360°.
        let h = g.height(42.0, 3.5 + 360.0).unwrap();
        assert!((h - 423.5).abs() < 1e-9);
        let h = g.height(42.0, 3.5 - 720.0).unwrap();
        assert!((h - 423.5).abs() < 1e-9);
    }

    #[test]
    fn outside_and_voids_have_no_height() {
        let mut g = planar(0.0);
        assert_eq!(g.height(43.01, 3.0), None);
        assert_eq!(g.height(42.0, 1.99), None);
        assert_eq!(g.height(42.0, 5.01), None);
        assert_eq!(g.height(f64::NAN, 3.0), None);
        // Half a sample of margin, clamped to the edge.
        let a = planar(0.5);
        assert_eq!(a.height(43.4, 2.0), a.height(43.0, 2.0));
        assert_eq!(a.height(43.6, 2.0), None);
        assert_eq!(a.height(42.0, 1.6), a.height(42.0, 2.0));
        assert_eq!(a.bounds(), ([40.5, 43.5], [1.5, 5.5]));
        g.heights[5] = f32::NAN; // (r 1, c 1): lat 42, lon 3
        assert_eq!(g.height(42.5, 2.5), None);
        assert_eq!(g.height(41.5, 3.5), None);
        assert!(g.height(42.5, 4.5).is_some());
        assert_eq!(g.max_height(), Some(435.0));
    }
}
