//! Why an elevation model cannot be used, naming the file.

use std::path::PathBuf;

/// An elevation model that cannot be read or placed. Every variant names
/// the file; the scene reading it adds the field (`terrain.files[i]`).
#[derive(Debug, thiserror::Error)]
pub enum DemError {
    /// There is no file at the path.
    #[error("the elevation model {} does not exist", path.display())]
    Missing {
        /// The path as given.
        path: PathBuf,
    },
    /// The file exists but cannot be read.
    #[error("cannot read the elevation model {}: {source}", path.display())]
    Unreadable {
        /// The path as given.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// Neither `.hgt` nor a TIFF.
    #[error(
        "{} is neither an SRTM .hgt tile (by its extension) nor a GeoTIFF (by its content)",
        path.display()
    )]
    UnknownFormat {
        /// The path as given.
        path: PathBuf,
    },
    /// An `.hgt` whose name does not say its corner.
    #[error(
        "{}: an SRTM tile's name gives its south-west corner, as N42E002.hgt or S33W071.hgt (latitude 0–89, longitude 0–179)",
        path.display()
    )]
    HgtName {
        /// The path as given.
        path: PathBuf,
    },
    /// An `.hgt` of neither 1″ nor 3″ size.
    #[error(
        "{}: {len} bytes is not an SRTM tile's size (3601 × 3601 × 2 = 25934402 for 1″, 1201 × 1201 × 2 = 2884802 for 3″); the file is truncated or not a tile",
        path.display()
    )]
    HgtSize {
        /// The path as given.
        path: PathBuf,
        /// The file's length.
        len: usize,
    },
    /// The TIFF cannot be decoded.
    #[error("{}: not a readable TIFF: {source}", path.display())]
    Tiff {
        /// The path as given.
        path: PathBuf,
        /// What the decoder said.
        source: tiff::TiffError,
    },
    /// A TIFF that is not georeferenced as the contract asks.
    #[error("{}: {problem}", path.display())]
    Georeference {
        /// The path as given.
        path: PathBuf,
        /// What is wrong with it.
        problem: GeoProblem,
    },
}

/// What is wrong with a GeoTIFF's georeferencing or samples.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GeoProblem {
    /// Neither ModelTiepoint with ModelPixelScale nor ModelTransformation.
    #[error(
        "no georeference: a GeoTIFF is placed by its ModelTiepoint and ModelPixelScale tags or its ModelTransformation tag, never by its name"
    )]
    NoGeoreference,
    /// A projected CRS (UTM, Lambert, …).
    #[error(
        "its CRS is projected (EPSG:{code}); mirage reads elevation models in geographic coordinates (EPSG:4326): reproject it, e.g. `gdalwarp -t_srs EPSG:4326 IN.tif OUT.tif`"
    )]
    Projected {
        /// ProjectedCSTypeGeoKey (32767: user-defined).
        code: u16,
    },
    /// A geographic CRS on another datum.
    #[error(
        "its geographic CRS is EPSG:{code}; mirage reads EPSG:4326 (WGS 84) and the datums that agree with it within metres (EPSG:4269 NAD83, 4258 ETRS89, 4979): reproject it with gdalwarp -t_srs EPSG:4326"
    )]
    Datum {
        /// GeographicTypeGeoKey.
        code: u16,
    },
    /// A model type other than geographic or projected.
    #[error("its model type (GTModelTypeGeoKey) is {code}, not geographic (2)")]
    ModelType {
        /// GTModelTypeGeoKey.
        code: u16,
    },
    /// A rotated or sheared grid.
    #[error("its ModelTransformation rotates or shears the grid; mirage reads north-up grids")]
    Rotated,
    /// Scales, tiepoints or transformations that do not place a grid.
    #[error("{0}")]
    Tags(&'static str),
    /// More than one sample per pixel.
    #[error("it has {0} samples per pixel; an elevation model has one")]
    Channels(u16),
    /// Its samples do not fit the lattice it declares.
    #[error("its {0} samples do not fill its {1} × {2} pixels")]
    Short(usize, u32, u32),
    /// The grid lies outside latitudes −90…90.
    #[error("its grid runs from latitude {0:.6}° to {1:.6}°, beyond the poles")]
    Latitude(f64, f64),
}
