//! Terrain (`docs/terrain.md`): elevation models read, placed by latitude
//! and longitude, and sampled as one height field.
//!
//! This room holds what the layers above (scenes, the renderer, photo
//! problems) need from the ground and nothing of theirs: [`Dem::open`]
//! reads the files a scene names, [`Dem::height`] gives the height above
//! mean sea level at a latitude and longitude.
//!
//! # Formats
//! - SRTM `.hgt` tiles ([`hgt`]): placed by their file names, as SRTM
//!   defines them, 1″ or 3″, voids −32768.
//! - GeoTIFF ([`geotiff`], read by the `tiff` crate): EPSG:4326, placed by
//!   ModelTiepoint + ModelPixelScale or ModelTransformation, never by the
//!   file's name; integer or float samples, GDAL_NODATA honoured; projected
//!   CRSs refused by EPSG code.
//!
//! A file is a tile by its `.hgt` extension, a GeoTIFF by its content (the
//! TIFF magic bytes), whatever its extension.
//!
//! # The mosaic
//! Files may overlap: at each point the first file (in the order given)
//! whose four samples around the point are valid gives the height,
//! bilinear between them ([`Grid::height`]); where none does the height is
//! `None` (the scene puts the sea there, or nothing). Exact at samples;
//! between them, the bilinear interpolant (for a DEM, whose samples are
//! themselves averages, nothing finer is meaningful).

mod error;
pub mod geotiff;
mod grid;
pub mod hgt;

pub use error::{DemError, GeoProblem};
pub use grid::Grid;

use std::path::{Path, PathBuf};

/// Elevation models, in the order their files were given.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Dem {
    /// One grid per file.
    pub grids: Vec<Grid>,
    /// The files, as given.
    pub files: Vec<PathBuf>,
}

impl Dem {
    /// Reads every file; the first that cannot be read is the error (with
    /// its index in `paths`).
    pub fn open(paths: &[PathBuf]) -> Result<Dem, (usize, DemError)> {
        let mut dem = Dem::default();
        for (i, p) in paths.iter().enumerate() {
            dem.grids.push(read(p).map_err(|e| (i, e))?);
            dem.files.push(p.clone());
        }
        Ok(dem)
    }

    /// The height (m above mean sea level) at (lat, lon) in degrees: the
    /// first grid's that has one there.
    pub fn height(&self, lat: f64, lon: f64) -> Option<f64> {
        self.grids.iter().find_map(|g| g.height(lat, lon))
    }

    /// The highest valid height of every grid (m), `None` when all are
    /// voids: the ceiling a ray above it can never meet.
    pub fn max_height(&self) -> Option<f64> {
        self.grids
            .iter()
            .filter_map(Grid::max_height)
            .reduce(f64::max)
    }
}

/// Reads one elevation model: `.hgt` by its extension, GeoTIFF by content.
pub fn read(path: &Path) -> Result<Grid, DemError> {
    let bytes = std::fs::read(path).map_err(|source| {
        if source.kind() == std::io::ErrorKind::NotFound {
            DemError::Missing {
                path: path.to_path_buf(),
            }
        } else {
            DemError::Unreadable {
                path: path.to_path_buf(),
                source,
            }
        }
    })?;
    from_bytes(&bytes, path)
}

/// [`read`] on bytes already in memory; `path` gives the `.hgt` extension
/// and tile name, and names the file in messages.
pub fn from_bytes(bytes: &[u8], path: &Path) -> Result<Grid, DemError> {
    let hgt = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("hgt"));
    if hgt {
        hgt::read(bytes, path)
    } else if geotiff::is_tiff(bytes) {
        geotiff::read(bytes, path)
    } else {
        Err(DemError::UnknownFormat {
            path: path.to_path_buf(),
        })
    }
}
