//! GeoTIFF elevation models in geographic coordinates, read with the `tiff`
//! crate (image-rs): the first image of the file, one sample per pixel
//! (int8/16/32, uint8/16/32, float32/64), placed by its tags alone.
//!
//! # Placement
//!
//! The GeoKey directory (tag 34735) must say a geographic model
//! (GTModelTypeGeoKey 2) on WGS 84 (GeographicTypeGeoKey 4326, or 4269,
//! 4258, 4979, whose datums agree with it within a few metres; absent means
//! 4326); a projected CRS is refused naming its EPSG code. A file without a
//! GeoKey directory is read as EPSG:4326 (as GDAL writes some plain tiles).
//! Raster space → longitude, latitude comes from ModelPixelScale (Sx, Sy)
//! with ModelTiepoint (I, J, ·, X, Y, ·): λ = X + (i − I)·Sx,
//! φ = Y − (j − J)·Sy; or from ModelTransformation (a 4 × 4 matrix, which
//! must not rotate or shear). Raster coordinates (i, j) are pixel corners
//! when GTRasterTypeGeoKey is PixelIsArea (1, the default): the sample of
//! pixel (c, r) stands at the pixel's centre, (c + ½, r + ½); with
//! PixelIsPoint (2) it stands at (c, r). A grid stored south-up (Sy < 0 in
//! the transformation) is flipped to north-up.
//!
//! # Voids
//!
//! The GDAL_NODATA tag (42113, ASCII) gives the void value; NaN samples are
//! voids too.

use super::error::{DemError, GeoProblem};
use super::grid::{EDGE, Grid};
use std::io::Cursor;
use std::path::Path;
use tiff::decoder::{Decoder, DecodingResult};
use tiff::tags::Tag;

/// GeoKey ids (GeoTIFF 1.1, Annex B).
const GT_MODEL_TYPE: u16 = 1024;
const GT_RASTER_TYPE: u16 = 1025;
const GEOGRAPHIC_TYPE: u16 = 2048;
const PROJECTED_CS_TYPE: u16 = 3072;

/// Geographic CRSs read as WGS 84 (their datums agree within metres).
const WGS84_LIKE: [u16; 4] = [4326, 4269, 4258, 4979];

/// Whether `bytes` start as a TIFF or BigTIFF, either byte order.
pub fn is_tiff(bytes: &[u8]) -> bool {
    matches!(
        bytes.get(..4),
        Some(b"II*\0" | b"MM\0*" | b"II+\0" | b"MM\0+")
    )
}

/// Reads a GeoTIFF from its bytes (`path` is for the messages).
pub fn read(bytes: &[u8], path: &Path) -> Result<Grid, DemError> {
    let tiff_err = |source| DemError::Tiff {
        path: path.to_path_buf(),
        source,
    };
    let geo = |problem| DemError::Georeference {
        path: path.to_path_buf(),
        problem,
    };
    let mut d = Decoder::new(Cursor::new(bytes)).map_err(tiff_err)?;
    let keys = d
        .find_tag_unsigned_vec::<u16>(Tag::GeoKeyDirectoryTag)
        .map_err(tiff_err)?
        .unwrap_or_default();
    let key = |id: u16| -> Option<u16> {
        // Header (4 shorts), then per key: id, location, count, value. A
        // location of 0 holds the value in place.
        keys.get(4..)?
            .chunks_exact(4)
            .find(|k| k[0] == id && k[1] == 0)
            .map(|k| k[3])
    };
    if let Some(code) = key(PROJECTED_CS_TYPE) {
        return Err(geo(GeoProblem::Projected { code }));
    }
    match key(GT_MODEL_TYPE) {
        None | Some(2) => {}
        Some(1) => return Err(geo(GeoProblem::Projected { code: 32767 })),
        Some(code) => return Err(geo(GeoProblem::ModelType { code })),
    }
    if let Some(code) = key(GEOGRAPHIC_TYPE)
        && !WGS84_LIKE.contains(&code)
    {
        return Err(geo(GeoProblem::Datum { code }));
    }
    let point = key(GT_RASTER_TYPE) == Some(2);

    let f64s = |d: &mut Decoder<Cursor<&[u8]>>, tag| -> Result<Option<Vec<f64>>, DemError> {
        match d.find_tag(tag).map_err(tiff_err)? {
            None => Ok(None),
            Some(v) => v.into_f64_vec().map(Some).map_err(tiff_err),
        }
    };
    let scale = f64s(&mut d, Tag::ModelPixelScaleTag)?;
    let tie = f64s(&mut d, Tag::ModelTiepointTag)?;
    let matrix = f64s(&mut d, Tag::ModelTransformationTag)?;
    // (X at raster (0, 0), Sx per column, Y at raster (0, 0), Sy per row,
    // with Y decreasing down the rows when Sy > 0.)
    let (x0, sx, y0, sy) = match (scale, tie, matrix) {
        (Some(s), Some(t), _) => {
            if s.len() < 2 || t.len() < 6 {
                return Err(geo(GeoProblem::Tags(
                    "ModelPixelScale needs 3 numbers and ModelTiepoint 6",
                )));
            }
            (t[3] - t[0] * s[0], s[0], t[4] + t[1] * s[1], s[1])
        }
        (_, _, Some(m)) => {
            if m.len() < 16 {
                return Err(geo(GeoProblem::Tags(
                    "ModelTransformation needs 16 numbers",
                )));
            }
            if m[1] != 0.0 || m[4] != 0.0 {
                return Err(geo(GeoProblem::Rotated));
            }
            (m[3], m[0], m[7], -m[5])
        }
        (Some(_), None, None) | (None, Some(_), None) => {
            return Err(geo(GeoProblem::Tags(
                "ModelPixelScale and ModelTiepoint come together; one of them is missing",
            )));
        }
        (None, None, None) => return Err(geo(GeoProblem::NoGeoreference)),
    };
    if !(x0.is_finite() && y0.is_finite() && sx.is_finite() && sy.is_finite())
        || sx <= 0.0
        || sy == 0.0
        || sx > 360.0
        || sy.abs() > 180.0
    {
        return Err(geo(GeoProblem::Tags(
            "its pixel size must be finite, > 0 across and ≠ 0 down (degrees), and its tiepoint finite",
        )));
    }

    let nodata = d
        .find_tag(Tag::GdalNodata)
        .map_err(tiff_err)?
        .and_then(|v| v.into_string().ok())
        .and_then(|s| s.trim_matches(char::from(0)).trim().parse::<f64>().ok());
    let (cols, rows) = d.dimensions().map_err(tiff_err)?;
    let samples = d
        .find_tag_unsigned::<u16>(Tag::SamplesPerPixel)
        .map_err(tiff_err)?
        .unwrap_or(1);
    if samples != 1 {
        return Err(geo(GeoProblem::Channels(samples)));
    }
    let data = d.read_image().map_err(tiff_err)?;
    let values: Vec<f64> = match data {
        DecodingResult::U8(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U16(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U64(v) => v.into_iter().map(|x| x as f64).collect(),
        DecodingResult::I8(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I16(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I64(v) => v.into_iter().map(|x| x as f64).collect(),
        DecodingResult::F16(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::F32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::F64(v) => v,
    };
    let (rows_u, cols_u) = (rows as usize, cols as usize);
    if values.len() < rows_u * cols_u {
        return Err(geo(GeoProblem::Short(values.len(), cols, rows)));
    }
    let mut heights: Vec<f32> = values[..rows_u * cols_u]
        .iter()
        .map(|&v| {
            if v.is_nan() || nodata == Some(v) || (nodata.is_some_and(|n| (n as f32 as f64) == v)) {
                f32::NAN
            } else {
                v as f32
            }
        })
        .collect();
    // The first sample's place: the pixel centre for area pixels.
    let half = if point { 0.0 } else { 0.5 };
    let lon0 = x0 + half * sx;
    let mut lat0 = y0 - half * sy;
    let mut dlat = -sy;
    if dlat > 0.0 {
        // South-up: flip the rows.
        let flipped: Vec<f32> = heights
            .chunks_exact(cols_u)
            .rev()
            .flatten()
            .copied()
            .collect();
        heights = flipped;
        lat0 += (rows as f64 - 1.0) * dlat;
        dlat = -dlat;
    }
    let south = lat0 + (rows as f64 - 1.0) * dlat;
    // Point samples: the lattice's edge, give or take rounding.
    let margin = if point { EDGE } else { 0.5 };
    if lat0 - margin * dlat > 90.0 + 1e-9 || south + margin * dlat < -90.0 - 1e-9 {
        return Err(geo(GeoProblem::Latitude(south, lat0)));
    }
    Ok(Grid {
        lat0,
        lon0,
        dlat,
        dlon: sx,
        rows: rows_u,
        cols: cols_u,
        heights,
        margin,
    })
}
