//! SRTM `.hgt` tiles: the tile's corner from its file name, heights from
//! its bytes.
//!
//! A tile is N × N big-endian signed 16-bit heights in metres, row after row
//! from the north, N = 3601 (1″) or 1201 (3″); −32768 is a void. Its name,
//! `N42E002.hgt` (case-insensitive, any folder, `S`/`W` for negative),
//! gives the latitude and longitude of its south-west corner; samples are
//! points: the first row lies at latitude φ + 1°, the last at φ, and the
//! first and last columns at λ and λ + 1° (neighbouring tiles share their
//! edges). This is the format as NASA defines it (SRTM Topography, v2.1,
//! "Data formats"); nothing else is read from the file.

use super::error::DemError;
use super::grid::Grid;
use std::path::Path;

/// The tile's south-west corner from its file name: `N42E002` → (42, 2).
pub fn corner(path: &Path) -> Result<(i32, i32), DemError> {
    let bad = || DemError::HgtName {
        path: path.to_path_buf(),
    };
    let stem = path.file_stem().and_then(|s| s.to_str()).ok_or_else(bad)?;
    let b = stem.as_bytes();
    if b.len() < 7 || !b.is_ascii() {
        return Err(bad());
    }
    let sign_lat = match b[0].to_ascii_uppercase() {
        b'N' => 1,
        b'S' => -1,
        _ => return Err(bad()),
    };
    let sign_lon = match b[3].to_ascii_uppercase() {
        b'E' => 1,
        b'W' => -1,
        _ => return Err(bad()),
    };
    let digits = |s: &str| -> Option<i32> {
        s.bytes()
            .all(|c| c.is_ascii_digit())
            .then(|| s.parse().ok())
            .flatten()
    };
    let lat = digits(&stem[1..3]).ok_or_else(bad)?;
    let lon = digits(&stem[4..7]).ok_or_else(bad)?;
    // Anything after the seven characters must not be more digits (a
    // name like `N42E0021` is not a tile's).
    if stem[7..].starts_with(|c: char| c.is_ascii_digit()) || lat > 89 || lon > 179 {
        return Err(bad());
    }
    Ok((sign_lat * lat, sign_lon * lon))
}

/// Reads a tile from its bytes (`path` names it and gives its corner).
pub fn read(bytes: &[u8], path: &Path) -> Result<Grid, DemError> {
    let (lat, lon) = corner(path)?;
    let n = match bytes.len() {
        l if l == 2 * 3601 * 3601 => 3601,
        l if l == 2 * 1201 * 1201 => 1201,
        len => {
            return Err(DemError::HgtSize {
                path: path.to_path_buf(),
                len,
            });
        }
    };
    let heights = bytes
        .chunks_exact(2)
        .map(|b| match i16::from_be_bytes([b[0], b[1]]) {
            -32768 => f32::NAN,
            h => f32::from(h),
        })
        .collect();
    let step = 1.0 / (n - 1) as f64;
    Ok(Grid {
        lat0: f64::from(lat) + 1.0,
        lon0: f64::from(lon),
        dlat: -step,
        dlon: step,
        rows: n,
        cols: n,
        heights,
        margin: super::grid::EDGE,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corners_from_names() {
        for (name, want) in [
            ("N42E002.hgt", (42, 2)),
            ("dem/s33w071.HGT", (-33, -71)),
            ("N00W000.hgt", (0, 0)),
            ("S89E179.hgt", (-89, 179)),
            ("N27E086.SRTMGL1.hgt", (27, 86)),
        ] {
            assert_eq!(corner(Path::new(name)).unwrap(), want, "{name}");
        }
        for name in [
            "X42E002.hgt",
            "N42Q002.hgt",
            "N4E002.hgt",
            "N42E0021.hgt",
            "N90E000.hgt",
            "N42E180.hgt",
            "tile.hgt",
            "N4xE002.hgt",
        ] {
            let e = corner(Path::new(name)).unwrap_err();
            assert!(e.to_string().contains(name), "{e}");
        }
    }

    #[test]
    fn a_3_arcsecond_tile_is_placed_by_its_name() {
        let n = 1201;
        let mut bytes = vec![0u8; 2 * n * n];
        // Row 0 (the north edge) column 0 = 1000 m, the south-east corner
        // = −5 m, one void in the middle.
        bytes[0..2].copy_from_slice(&1000i16.to_be_bytes());
        let last = 2 * (n * n - 1);
        bytes[last..last + 2].copy_from_slice(&(-5i16).to_be_bytes());
        let mid = 2 * (600 * n + 600);
        bytes[mid..mid + 2].copy_from_slice(&(-32768i16).to_be_bytes());
        let g = read(&bytes, Path::new("S12W077.hgt")).unwrap();
        assert_eq!((g.rows, g.cols), (1201, 1201));
        assert_eq!(g.height(-11.0, -77.0), Some(1000.0));
        assert_eq!(g.height(-12.0, -76.0), Some(-5.0));
        assert_eq!(g.height(-11.5, -76.5), None);
        let h = g.height(-11.0 - 0.5 / 1200.0, -77.0).unwrap();
        assert!((h - 500.0).abs() < 1e-6, "{h}");
        assert_eq!(g.height(-11.0 + 0.5 / 1200.0, -77.0), None);
        assert_eq!(g.height(-12.001, -76.5), None);
    }

    #[test]
    fn wrong_sizes_are_named() {
        for len in [0, 1, 2 * 1201 * 1201 - 2, 2 * 3601 * 3601 + 2] {
            let e = read(&vec![0; len], Path::new("N42E002.hgt")).unwrap_err();
            let s = e.to_string();
            assert!(
                s.contains("N42E002.hgt") && s.contains(&len.to_string()),
                "{s}"
            );
        }
    }
}
