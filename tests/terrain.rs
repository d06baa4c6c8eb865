//! Elevation models (`docs/terrain.md`): GeoTIFFs written here with the
//! `tiff` crate's encoder and SRTM tiles written byte by byte, read back,
//! placed by their tags or names, and sampled; and every bad file refused
//! naming the file and the problem.

use mirage::terrain::{Dem, DemError, GeoProblem, read};
use std::io::Cursor;
use std::path::{Path, PathBuf};
use tiff::encoder::{TiffEncoder, colortype};
use tiff::tags::Tag;

/// A Gaussian hill on a sloping plain: h(lat, lon) in metres.
fn hill(lat: f64, lon: f64) -> f64 {
    let (dy, dx) = ((lat - 42.52) / 0.05, (lon - 2.46) / 0.07);
    2000.0 * (-(dx * dx + dy * dy)).exp() + 100.0 * (lat - 42.0) + 3.0
}

/// How a test file places its grid.
#[derive(Clone, Copy)]
enum Place {
    /// PixelIsArea, tiepoint at raster (0, 0).
    Area,
    /// PixelIsPoint, tiepoint at raster (3, 5).
    Point,
    /// ModelTransformation, PixelIsArea.
    Matrix,
    /// ModelTransformation with Sy < 0: stored south-up.
    SouthUp,
}

/// The samples of `hill` on a lattice of `rows` × `cols` pixels of
/// `step` degrees whose north-west corner is (43, 2) (pixel centres for
/// area pixels), rows north to south, placed as `place` says.
fn lattice(rows: u32, cols: u32, step: f64, place: Place) -> (Vec<f64>, Vec<(f64, f64)>) {
    let mut v = Vec::new();
    let mut at = Vec::new();
    for r in 0..rows {
        for c in 0..cols {
            let (lat, lon) = (
                43.0 - (r as f64 + 0.5) * step,
                2.0 + (c as f64 + 0.5) * step,
            );
            v.push(hill(lat, lon));
            at.push((lat, lon));
        }
    }
    if matches!(place, Place::SouthUp) {
        let rows_rev: Vec<f64> = v.chunks(cols as usize).rev().flatten().copied().collect();
        v = rows_rev;
    }
    (v, at)
}

/// GeoKeys: model type, raster type, then `extra` (id, value) pairs.
fn geokeys(raster: u16, extra: &[(u16, u16)]) -> Vec<u16> {
    let mut keys = vec![(1024u16, 2u16), (1025, raster)];
    keys.extend_from_slice(extra);
    let mut out = vec![1, 1, 0, keys.len() as u16];
    for (id, v) in keys {
        out.extend_from_slice(&[id, 0, 1, v]);
    }
    out
}

/// Writes the tags of `place` (grid of `step`° from corner (43, 2)).
fn place_tags<W: std::io::Write + std::io::Seek, K: tiff::encoder::TiffKind>(
    e: &mut tiff::encoder::DirectoryEncoder<'_, W, K>,
    place: Place,
    step: f64,
    rows: u32,
) {
    match place {
        Place::Area => {
            e.write_tag(Tag::ModelPixelScaleTag, &[step, step, 0.0][..])
                .unwrap();
            e.write_tag(Tag::ModelTiepointTag, &[0.0, 0.0, 0.0, 2.0, 43.0, 0.0][..])
                .unwrap();
            e.write_tag(Tag::GeoKeyDirectoryTag, &geokeys(1, &[(2048, 4326)])[..])
                .unwrap();
        }
        Place::Point => {
            // Raster point (3, 5) is pixel (3, 5)'s centre.
            let (x, y) = (2.0 + 3.5 * step, 43.0 - 5.5 * step);
            e.write_tag(Tag::ModelPixelScaleTag, &[step, step, 0.0][..])
                .unwrap();
            e.write_tag(Tag::ModelTiepointTag, &[3.0, 5.0, 0.0, x, y, 0.0][..])
                .unwrap();
            e.write_tag(Tag::GeoKeyDirectoryTag, &geokeys(2, &[(2048, 4326)])[..])
                .unwrap();
        }
        Place::Matrix => {
            let m = [
                step, 0.0, 0.0, 2.0, 0.0, -step, 0.0, 43.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0,
            ];
            e.write_tag(Tag::ModelTransformationTag, &m[..]).unwrap();
            e.write_tag(Tag::GeoKeyDirectoryTag, &geokeys(1, &[])[..])
                .unwrap();
        }
        Place::SouthUp => {
            let south = 43.0 - rows as f64 * step;
            let m = [
                step, 0.0, 0.0, 2.0, 0.0, step, 0.0, south, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0,
            ];
            e.write_tag(Tag::ModelTransformationTag, &m[..]).unwrap();
            e.write_tag(Tag::GeoKeyDirectoryTag, &geokeys(1, &[(2048, 4326)])[..])
                .unwrap();
        }
    }
}

/// Which sample type a test file stores.
#[derive(Clone, Copy)]
enum Samples {
    I16,
    I32,
    F32,
}

/// A GeoTIFF of `hill`, `rows` × `cols` pixels of `step` degrees.
fn geotiff(
    rows: u32,
    cols: u32,
    step: f64,
    place: Place,
    samples: Samples,
    nodata: Option<&str>,
) -> Vec<u8> {
    let (v, _) = lattice(rows, cols, step, place);
    let mut buf = Cursor::new(Vec::new());
    let mut t = TiffEncoder::new(&mut buf).unwrap();
    macro_rules! write_as {
        ($ct:ty, $conv:expr) => {{
            let mut img = t.new_image::<$ct>(cols, rows).unwrap();
            let e = img.encoder();
            place_tags(e, place, step, rows);
            if let Some(n) = nodata {
                e.write_tag(Tag::GdalNodata, n).unwrap();
            }
            let data: Vec<_> = v.iter().map($conv).collect();
            img.write_data(&data).unwrap();
        }};
    }
    match samples {
        Samples::I16 => write_as!(colortype::GrayI16, |&h: &f64| h.round() as i16),
        Samples::I32 => write_as!(colortype::GrayI32, |&h: &f64| h.round() as i32),
        Samples::F32 => write_as!(colortype::Gray32Float, |&h: &f64| h as f32),
    }
    buf.into_inner()
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// A small seeded generator of points inside the lattice (degrees).
fn points(seed: u64, n: usize, step: f64, rows: u32, cols: u32) -> Vec<(f64, f64)> {
    let mut s = seed;
    let mut u = move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| {
            let lat = 43.0 - (0.5 + u() * (rows as f64 - 1.0)) * step;
            let lon = 2.0 + (0.5 + u() * (cols as f64 - 1.0)) * step;
            (lat, lon)
        })
        .collect()
}

#[test]
fn every_placement_of_the_same_dem_gives_the_same_heights() {
    let dir = tempfile::tempdir().unwrap();
    let (rows, cols, step) = (60, 90, 0.01);
    let reference = read(&write(
        dir.path(),
        "a.tif",
        &geotiff(rows, cols, step, Place::Area, Samples::F32, None),
    ))
    .unwrap();
    // The same samples under other tags, sample types and file names.
    for (k, (place, name)) in [
        (Place::Point, "N99E999.tif"),
        (Place::Matrix, "tile-with-a-misleading-name_N10W010.tiff"),
        (Place::SouthUp, "south-up.dat"),
    ]
    .into_iter()
    .enumerate()
    {
        let g = read(&write(
            dir.path(),
            name,
            &geotiff(rows, cols, step, place, Samples::F32, None),
        ))
        .unwrap();
        for (lat, lon) in points(k as u64, 500, step, rows, cols) {
            let (a, b) = (
                reference.height(lat, lon).unwrap(),
                g.height(lat, lon).unwrap(),
            );
            assert!((a - b).abs() < 1e-9, "{name} at ({lat}, {lon}): {a} vs {b}");
        }
    }
    // At a pixel's centre the height is the sample; between, bilinear, so
    // within the hill's curvature × step² of the truth.
    let (_, at) = lattice(rows, cols, step, Place::Area);
    for &(lat, lon) in at.iter().step_by(97) {
        let h = reference.height(lat, lon).unwrap();
        assert!((h - hill(lat, lon)).abs() < 1e-3, "({lat}, {lon}): {h}");
    }
    for (lat, lon) in points(9, 300, step, rows, cols) {
        let h = reference.height(lat, lon).unwrap();
        assert!(
            (h - hill(lat, lon)).abs() < 25.0,
            "({lat}, {lon}): {h} vs {}",
            hill(lat, lon)
        );
    }
}

#[test]
fn integer_samples_and_nodata() {
    let dir = tempfile::tempdir().unwrap();
    let (rows, cols, step) = (40, 50, 0.02);
    for samples in [Samples::I16, Samples::I32] {
        let g = read(&write(
            dir.path(),
            "i.tif",
            &geotiff(rows, cols, step, Place::Area, samples, None),
        ))
        .unwrap();
        let (_, at) = lattice(rows, cols, step, Place::Area);
        for &(lat, lon) in at.iter().step_by(31) {
            let h = g.height(lat, lon).unwrap();
            assert!((h - hill(lat, lon)).abs() <= 0.5 + 1e-9, "{h}");
        }
    }
    // The corner pixel's height (3 + 100·(42.99 − 42) ≈ 102) as nodata:
    // every pixel rounding to 102 becomes a void.
    let nd = geotiff(rows, cols, step, Place::Area, Samples::I16, Some("102"));
    let g = read(&write(dir.path(), "nd.tif", &nd)).unwrap();
    let (v, at) = lattice(rows, cols, step, Place::Area);
    let mut voids = 0;
    for (h, &(lat, lon)) in v.iter().zip(&at) {
        if h.round() == 102.0 {
            voids += 1;
            assert_eq!(g.height(lat, lon), None, "({lat}, {lon})");
        }
    }
    assert!(voids > 0);
    // A mosaic: where the first file has a void, the second answers.
    let full = write(
        dir.path(),
        "full.tif",
        &geotiff(rows, cols, step, Place::Point, Samples::F32, None),
    );
    let dem = Dem::open(&[dir.path().join("nd.tif"), full]).unwrap();
    for &(lat, lon) in &at {
        let h = dem.height(lat, lon).unwrap();
        assert!((h - hill(lat, lon)).abs() < 0.5 + 1e-6, "{h}");
    }
    assert_eq!(dem.height(10.0, 10.0), None);
}

#[test]
fn a_wrong_pixel_scale_is_placed_where_its_tags_say() {
    // The same samples written with twice the true pixel size: the summit
    // goes where the tags put it (twice as far from the corner), not where
    // a reader that guessed from the name or assumed 3600 samples per
    // degree would.
    let dir = tempfile::tempdir().unwrap();
    let (rows, cols, step) = (60, 90, 0.01);
    let (v, _) = lattice(rows, cols, step, Place::Area);
    let mut buf = Cursor::new(Vec::new());
    let mut t = TiffEncoder::new(&mut buf).unwrap();
    let mut img = t.new_image::<colortype::Gray32Float>(cols, rows).unwrap();
    place_tags(img.encoder(), Place::Area, 2.0 * step, rows);
    let data: Vec<f32> = v.iter().map(|&h| h as f32).collect();
    img.write_data(&data).unwrap();
    let g = read(&write(dir.path(), "N42E002.tif", &buf.into_inner())).unwrap();
    // Pixel (47, 45) is at (42.525, 2.455) in truth, near the summit;
    // under the doubled scale its centre is twice as far from the corner.
    let (truth, placed) = ((42.525, 2.455), (43.0 - 47.5 * 0.02, 2.0 + 45.5 * 0.02));
    let h = g.height(placed.0, placed.1).unwrap();
    assert!((h - hill(truth.0, truth.1)).abs() < 1e-3, "{h}");
    assert!(hill(truth.0, truth.1) > 2000.0);
    assert!(g.height(truth.0, truth.1).unwrap() < 1000.0);
    let (lat, lon) = g.bounds();
    assert!(
        (lat[0] - (43.0 - 2.0 * step * rows as f64)).abs() < 1e-9,
        "{lat:?}"
    );
    assert!(
        (lon[1] - (2.0 + 2.0 * step * cols as f64)).abs() < 1e-9,
        "{lon:?}"
    );
}

#[test]
fn srtm_tiles_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let n = 1201usize;
    let mut bytes = Vec::with_capacity(2 * n * n);
    for r in 0..n {
        for c in 0..n {
            let (lat, lon) = (43.0 - r as f64 / 1200.0, 2.0 + c as f64 / 1200.0);
            bytes.extend_from_slice(&(hill(lat, lon).round() as i16).to_be_bytes());
        }
    }
    let p = write(dir.path(), "N42E002.hgt", &bytes);
    let dem = Dem::open(&[p]).unwrap();
    let h = dem.height(42.52, 2.46).unwrap();
    assert!((h - hill(42.52, 2.46)).abs() < 1.0, "{h}");
    assert_eq!(dem.height(41.99, 2.5), None);
    assert!((dem.max_height().unwrap() - 2055.0).abs() < 2.0);
}

/// The directory of a TIFF being written in memory.
type Dir<'a> =
    tiff::encoder::DirectoryEncoder<'a, &'a mut Cursor<Vec<u8>>, tiff::encoder::TiffKindStandard>;

/// The message of reading `bytes` as `name`.
fn refused(name: &str, bytes: &[u8]) -> String {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), name, bytes);
    let e = read(&p).unwrap_err();
    let s = e.to_string();
    assert!(
        s.contains(&p.display().to_string()),
        "the file is not named: {s}"
    );
    s
}

#[test]
fn bad_files_are_refused_by_name() {
    let good = geotiff(20, 30, 0.01, Place::Area, Samples::I16, None);
    // Missing.
    let e = read(Path::new("/nonexistent/N42E002.hgt")).unwrap_err();
    assert!(
        matches!(e, DemError::Missing { .. }) && e.to_string().contains("/nonexistent/N42E002.hgt")
    );
    // Truncated TIFF and HGT, a wrong size, an unknown format.
    assert!(refused("cut.tif", &good[..good.len() / 2]).contains("not a readable TIFF"));
    assert!(refused("N42E002.hgt", &vec![0; 1000]).contains("1000 bytes"));
    assert!(refused("dem.png", b"\x89PNG\r\n\x1a\n....").contains("neither an SRTM"));
    assert!(refused("tile.hgt", &vec![0; 2 * 1201 * 1201]).contains("south-west corner"));

    // Projected, another datum, no georeference, colour, rotated.
    let with = |keys: Vec<u16>, extra: &dyn Fn(&mut Dir<'_>)| {
        let mut buf = Cursor::new(Vec::new());
        {
            let mut t = TiffEncoder::new(&mut buf).unwrap();
            let mut img = t.new_image::<colortype::GrayI16>(4, 3).unwrap();
            let e = img.encoder();
            if !keys.is_empty() {
                e.write_tag(Tag::GeoKeyDirectoryTag, &keys[..]).unwrap();
            }
            extra(e);
            img.write_data(&[0i16; 12]).unwrap();
        }
        buf.into_inner()
    };
    let placed = |e: &mut Dir<'_>| {
        e.write_tag(Tag::ModelPixelScaleTag, &[30.0, 30.0, 0.0][..])
            .unwrap();
        e.write_tag(
            Tag::ModelTiepointTag,
            &[0.0, 0.0, 0.0, 500000.0, 4700000.0, 0.0][..],
        )
        .unwrap();
    };
    let utm = with(vec![1, 1, 0, 2, 1024, 0, 1, 1, 3072, 0, 1, 32631], &placed);
    let s = refused("utm.tif", &utm);
    assert!(s.contains("EPSG:32631") && s.contains("projected"), "{s}");
    let ed50 = with(geokeys(1, &[(2048, 4230)]), &placed);
    assert!(refused("ed50.tif", &ed50).contains("EPSG:4230"));
    let bare = with(geokeys(1, &[]), &|_| {});
    assert!(refused("bare.tif", &bare).contains("no georeference"));
    let half = with(geokeys(1, &[]), &|e| {
        e.write_tag(Tag::ModelPixelScaleTag, &[0.1, 0.1, 0.0][..])
            .unwrap();
    });
    assert!(refused("half.tif", &half).contains("one of them is missing"));
    let rotated = with(geokeys(1, &[]), &|e| {
        let m = [
            0.1, 0.01, 0.0, 2.0, 0.0, -0.1, 0.0, 43.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ];
        e.write_tag(Tag::ModelTransformationTag, &m[..]).unwrap();
    });
    assert!(matches!(
        read(&write(
            tempfile::tempdir().unwrap().path(),
            "r.tif",
            &rotated
        )),
        Err(DemError::Georeference {
            problem: GeoProblem::Rotated,
            ..
        })
    ));
    let zero = with(geokeys(1, &[]), &|e| {
        e.write_tag(Tag::ModelPixelScaleTag, &[0.0, 0.1, 0.0][..])
            .unwrap();
        e.write_tag(Tag::ModelTiepointTag, &[0.0, 0.0, 0.0, 2.0, 43.0, 0.0][..])
            .unwrap();
    });
    assert!(refused("zero.tif", &zero).contains("pixel size"));
    let polar = with(geokeys(1, &[]), &|e| {
        e.write_tag(Tag::ModelPixelScaleTag, &[1.0, 1.0, 0.0][..])
            .unwrap();
        e.write_tag(Tag::ModelTiepointTag, &[0.0, 0.0, 0.0, 2.0, 91.0, 0.0][..])
            .unwrap();
    });
    assert!(refused("polar.tif", &polar).contains("beyond the poles"));
    let mut buf = Cursor::new(Vec::new());
    {
        let mut t = TiffEncoder::new(&mut buf).unwrap();
        let mut img = t.new_image::<colortype::RGB8>(2, 2).unwrap();
        place_tags(img.encoder(), Place::Area, 0.1, 2);
        img.write_data(&[0u8; 12]).unwrap();
    }
    assert!(refused("rgb.tif", &buf.into_inner()).contains("3 samples per pixel"));
}

#[test]
fn garbage_is_refused_never_a_panic() {
    // Seeded mutations of a valid GeoTIFF and of an SRTM tile's header:
    // each read either succeeds or fails with a message naming the file.
    let good = geotiff(8, 9, 0.01, Place::Area, Samples::I16, Some("-32768"));
    let mut s = 7u64;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        s >> 33
    };
    let dir = tempfile::tempdir().unwrap();
    for k in 0..400 {
        let mut b = good.clone();
        for _ in 0..1 + next() % 6 {
            let i = (next() as usize) % b.len();
            b[i] = next() as u8;
        }
        if k % 5 == 0 {
            b.truncate((next() as usize) % b.len());
        }
        let p = write(dir.path(), "m.tif", &b);
        match read(&p) {
            Ok(g) => {
                for (lat, lon) in points(k, 20, 0.01, 8, 9) {
                    if let Some(h) = g.height(lat, lon) {
                        assert!(h.is_finite());
                    }
                }
            }
            Err(e) => assert!(e.to_string().contains(&p.display().to_string()), "{e}"),
        }
    }
}
