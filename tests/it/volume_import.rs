//! Volume import: DICOM series (geometry, HU, syntaxes, every refusal), zip, NRRD, raw, the
//! estimate, and a seeded mutation smoke test.

use rand_core::Rng;
use rand_pcg::Pcg64;
use weft::testgen::dicom::{bone_phantom, bone_phantom_hu, meta, read_back, write_series, zip_files, SeriesOptions, Syntax};
use weft::volume::{estimate, read_volume, Error, Imported, Options, Placement, RawLayout, Volume, VoxelType, MAX_FILES, MAX_VOXELS};

fn read(files: &[(String, Vec<u8>)]) -> Result<Imported, Error> {
    let refs: Vec<(&str, &[u8])> = files.iter().map(|(n, b)| (n.as_str(), b.as_slice())).collect();
    read_volume(&refs, &Options::default())
}

fn read_with(files: &[(String, Vec<u8>)], options: &Options) -> Result<Imported, Error> {
    let refs: Vec<(&str, &[u8])> = files.iter().map(|(n, b)| (n.as_str(), b.as_slice())).collect();
    read_volume(&refs, options)
}

fn one(name: &str, bytes: Vec<u8>) -> Vec<(String, Vec<u8>)> {
    vec![(name.to_string(), bytes)]
}

/// A rotation (Rodrigues) by `angle` about unit `axis`, as the placement's axes.
fn rotation(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
    let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    let [x, y, z] = axis.map(|v| v / n);
    let (s, c) = (angle.sin(), angle.cos());
    let t = 1.0 - c;
    // Columns of R are the images of the unit axes.
    let r = [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ];
    [[r[0][0], r[1][0], r[2][0]], [r[0][1], r[1][1], r[2][1]], [r[0][2], r[1][2], r[2][2]]]
}

fn phantom() -> Volume {
    bone_phantom([16, 12, 9], [0.7, 0.9, 1.25])
}

fn assert_close(a: f64, b: f64, tol: f64, what: &str) {
    assert!((a - b).abs() <= tol, "{what}: {a} vs {b}");
}

fn assert_same_volume(got: &Volume, want: &Volume, options: &SeriesOptions) {
    assert_eq!(got.dims, want.dims);
    for a in 0..3 {
        assert_close(got.spacing_mm[a], want.spacing_mm[a], 1e-9, "spacing");
        assert_close(got.placement.origin_mm[a], want.placement.origin_mm[a], 1e-9, "origin");
        for b in 0..3 {
            assert_close(got.placement.axes[a][b], want.placement.axes[a][b], 1e-12, "axes");
        }
    }
    for (n, (g, w)) in got.values.iter().zip(&want.values).enumerate() {
        assert_eq!(*g, read_back(*w, options), "voxel {n}");
    }
}

#[test]
fn geometry_round_trips_oblique_anisotropic_shuffled_and_misnamed() {
    let mut v = phantom();
    v.placement = Placement { origin_mm: [-9.80818, 148.609, 488.571], axes: rotation([1.0, 2.0, 0.5], 0.6) };
    let options = SeriesOptions::default();
    let mut files = write_series(&v, &options);
    // Shuffle, and name the files so that name order and instance order mislead.
    let mut rng = Pcg64::new(7, 11);
    for i in (1..files.len()).rev() {
        let j = (rng.next_u64() % (i as u64 + 1)) as usize;
        files.swap(i, j);
    }
    let n = files.len();
    for (i, f) in files.iter_mut().enumerate() {
        f.0 = format!("IM{:03}", n - i);
    }
    let got = read(&files).unwrap();
    // DS strings hold 16 characters: the oblique directions come back to ~1e-13.
    let want = &v;
    assert_eq!(got.volume.dims, want.dims);
    for a in 0..3 {
        assert_close(got.volume.spacing_mm[a], want.spacing_mm[a], 1e-9, "spacing");
        assert_close(got.volume.placement.origin_mm[a], want.placement.origin_mm[a], 1e-9, "origin");
        for b in 0..3 {
            assert_close(got.volume.placement.axes[a][b], want.placement.axes[a][b], 1e-9, "axes");
        }
    }
    for (g, w) in got.volume.values.iter().zip(&want.values) {
        assert_eq!(*g, read_back(*w, &options));
    }
    assert_eq!(got.report.files_read, 9);
    assert_close(got.report.slice_gap_mm, 1.25, 1e-9, "gap");
    assert_eq!(got.volume.info.format, "DICOM");
    assert_eq!(got.volume.info.modality, "CT");
    assert_eq!(got.volume.info.unit, "HU");
    assert_eq!(got.volume.info.series_uid, options.series_uid);
    assert_eq!(got.report.min, -1000.0);
    assert!(got.report.max >= 1200.0);

    // The axis-aligned case round-trips exactly.
    let v = phantom();
    let got = read(&write_series(&v, &options)).unwrap();
    assert_same_volume(&got.volume, &v, &options);
}

#[test]
fn hu_of_known_voxels_with_slope_intercept_signed_and_unsigned() {
    let v = phantom();
    let dims = v.dims;
    let sp = v.spacing_mm;
    // Centre column at mid-height is the medullary canal (0 HU), a corner is air, the slice
    // ends are trabecular/cortical per the formula.
    assert_eq!(bone_phantom_hu(dims, sp, 0, 0, 4), -1000.0);
    for (signed, slope, intercept) in [(false, 1.0, -1024.0), (true, 1.0, 0.0), (true, 0.5, -1000.0), (false, 2.0, -1024.0)] {
        let options = SeriesOptions { signed, slope, intercept, ..Default::default() };
        let got = read(&write_series(&v, &options)).unwrap().volume;
        for (i, j, k) in [(0, 0, 0), (7, 5, 4), (8, 6, 4), (7, 5, 0), (7, 5, 8), (3, 5, 2), (11, 6, 6)] {
            let want = bone_phantom_hu(dims, sp, i, j, k);
            let expect = read_back(want, &options);
            assert_eq!(got.at(i, j, k), expect, "signed {signed} slope {slope} voxel ({i},{j},{k})");
            if slope == 1.0 || slope == 0.5 {
                assert_eq!(got.at(i, j, k), want, "whole HU survive slope {slope}");
            }
        }
    }
    // Unsigned, intercept −1024: air is stored as 24; signed, intercept 0: as −1000.
    assert_eq!(weft::testgen::dicom::stored_sample(-1000.0, &SeriesOptions::default()), 24);
    assert_eq!(weft::testgen::dicom::stored_sample(-1000.0, &SeriesOptions { signed: true, intercept: 0.0, ..Default::default() }), -1000);
}

#[test]
fn bits_stored_masks_junk_high_bits_and_sign_extends() {
    let v = phantom();
    for (signed, intercept) in [(false, -1024.0), (true, 0.0)] {
        let options = SeriesOptions { bits_stored: 12, signed, intercept, ..Default::default() };
        let got = read(&write_series(&v, &options)).unwrap().volume;
        assert_same_volume(&got, &v, &options);
    }
}

#[test]
fn all_four_syntaxes_read_the_same_volume() {
    let mut v = phantom();
    v.placement = Placement { origin_mm: [1.5, -2.0, 30.0], axes: rotation([0.0, 0.0, 1.0], 0.3) };
    for (syntax, name) in [
        (Syntax::ImplicitLe, "Implicit VR Little Endian"),
        (Syntax::ExplicitLe, "Explicit VR Little Endian"),
        (Syntax::ExplicitBe, "Explicit VR Big Endian"),
        (Syntax::DeflatedLe, "Deflated Explicit VR Little Endian"),
    ] {
        let options = SeriesOptions { syntax, signed: true, intercept: 0.0, ..Default::default() };
        let got = read(&write_series(&v, &options)).unwrap();
        assert_eq!(got.volume.info.transfer_syntax, name);
        for (g, w) in got.volume.values.iter().zip(&v.values) {
            assert_eq!(g, w, "{name}");
        }
        assert_eq!(got.volume.dims, v.dims, "{name}");
        assert_close(got.volume.placement.axes[0][1], v.placement.axes[0][1], 1e-12, name);
    }
}

/// A hand-made file: meta with `syntax_uid`, an Explicit VR LE data set with an 4×4 image
/// whose pixel data are encapsulated (offset table + one fragment).
fn encapsulated(syntax_uid: &str) -> Vec<u8> {
    let mut out = meta("1.2.840.10008.5.1.4.1.1.2", "1.2.3.4", syntax_uid);
    let mut el = |g: u16, e: u16, vr: &[u8; 2], v: &[u8]| {
        out.extend_from_slice(&g.to_le_bytes());
        out.extend_from_slice(&e.to_le_bytes());
        out.extend_from_slice(vr);
        out.extend_from_slice(&(v.len() as u16).to_le_bytes());
        out.extend_from_slice(v);
    };
    el(0x0028, 0x0002, b"US", &1u16.to_le_bytes());
    el(0x0028, 0x0010, b"US", &4u16.to_le_bytes());
    el(0x0028, 0x0011, b"US", &4u16.to_le_bytes());
    el(0x0028, 0x0100, b"US", &16u16.to_le_bytes());
    el(0x0028, 0x0101, b"US", &16u16.to_le_bytes());
    // (7FE0,0010) OB, undefined length, empty offset table, one fragment, delimiter.
    out.extend_from_slice(&[0xE0, 0x7F, 0x10, 0x00, b'O', b'B', 0, 0, 0xFF, 0xFF, 0xFF, 0xFF]);
    out.extend_from_slice(&[0xFE, 0xFF, 0x00, 0xE0, 0, 0, 0, 0]);
    out.extend_from_slice(&[0xFE, 0xFF, 0x00, 0xE0, 8, 0, 0, 0, 0xFF, 0x4F, 0xFF, 0x51, 0, 0, 0, 0]);
    out.extend_from_slice(&[0xFE, 0xFF, 0xDD, 0xE0, 0, 0, 0, 0]);
    out
}

#[test]
fn compressed_syntaxes_are_refused_naming_them() {
    for (uid, name) in [
        ("1.2.840.10008.1.2.4.90", "JPEG 2000 Image Compression (Lossless Only)"),
        ("1.2.840.10008.1.2.4.70", "JPEG Lossless, Non-Hierarchical, First-Order Prediction (Process 14 [Selection Value 1])"),
        ("1.2.840.10008.1.2.5", "RLE Lossless"),
    ] {
        let e = read(&one("a.dcm", encapsulated(uid))).unwrap_err();
        assert_eq!(e, Error::Compressed { file: "a.dcm".into(), syntax_name: name.into() });
        assert!(e.to_string().contains(name));
    }
}

fn series(v: &Volume, options: &SeriesOptions) -> Vec<(String, Vec<u8>)> {
    write_series(v, options)
}

#[test]
fn every_series_refusal_has_its_variant() {
    let v = phantom();
    let o = SeriesOptions::default();
    let files = series(&v, &o);

    // Truncated: the last file cut inside its pixel data.
    let mut f = files.clone();
    let last = f.last_mut().unwrap();
    last.1.truncate(last.1.len() - 10);
    assert!(matches!(read(&f).unwrap_err(), Error::Truncated { file, .. } if file == "slice-0008.dcm"));

    // Missing pixel data: the pixel element (the last, 12-byte header) removed.
    let mut f = files.clone();
    let px = 12 + 16 * 12 * 2;
    let b = &mut f[3].1;
    b.truncate(b.len() - px);
    assert_eq!(read(&f).unwrap_err(), Error::NoPixelData { file: "slice-0003.dcm".into() });

    // Different sizes: a slice of another grid at the next position.
    let mut f = files.clone();
    let mut other = bone_phantom([16, 10, 10], [0.7, 0.9, 1.25]);
    other.placement = v.placement;
    f.push(("z.dcm".into(), series(&other, &o).pop().unwrap().1));
    assert!(matches!(read(&f).unwrap_err(), Error::SizeMismatch { file, .. } if file == "z.dcm"));

    // Different pixel spacing.
    let mut f = files.clone();
    let other = bone_phantom([16, 12, 10], [0.8, 0.9, 1.25]);
    f.push(("z.dcm".into(), series(&other, &o).pop().unwrap().1));
    assert!(matches!(read(&f).unwrap_err(), Error::SpacingMismatch { file, .. } if file == "z.dcm"));

    // Different orientation.
    let mut f = files.clone();
    let mut other = bone_phantom([16, 12, 10], [0.7, 0.9, 1.25]);
    other.placement.axes = rotation([0.0, 0.0, 1.0], 0.2);
    f.push(("z.dcm".into(), series(&other, &o).pop().unwrap().1));
    assert!(matches!(read(&f).unwrap_err(), Error::OrientationMismatch { file_b, .. } if file_b == "z.dcm"));

    // Duplicate position: a slice given twice under two names.
    let mut f = files.clone();
    f.push(("copy.dcm".into(), f[4].1.clone()));
    match read(&f).unwrap_err() {
        Error::DuplicatePosition { file_a, file_b, position } => {
            let mut names = [file_a, file_b];
            names.sort();
            assert_eq!(names, ["copy.dcm".to_string(), "slice-0004.dcm".to_string()]);
            assert_close(position[2], 4.0 * 1.25, 1e-9, "duplicate position");
        }
        e => panic!("{e:?}"),
    }

    // Mixed studies, mixed series.
    let mut f = files.clone();
    let other = series(&bone_phantom([16, 12, 10], [0.7, 0.9, 1.25]), &SeriesOptions { study_uid: "1.2.3.9".into(), ..Default::default() });
    f.push(("z.dcm".into(), other.last().unwrap().1.clone()));
    assert_eq!(read(&f).unwrap_err(), Error::MixedSeries { what: "studies", file_a: "slice-0000.dcm".into(), file_b: "z.dcm".into() });
    let mut f = files.clone();
    let other = series(&bone_phantom([16, 12, 10], [0.7, 0.9, 1.25]), &SeriesOptions { series_uid: "1.2.3.9".into(), ..Default::default() });
    f.push(("z.dcm".into(), other.last().unwrap().1.clone()));
    assert_eq!(read(&f).unwrap_err(), Error::MixedSeries { what: "series", file_a: "slice-0000.dcm".into(), file_b: "z.dcm".into() });

    // Uneven gaps: a missing slice.
    let mut f = files.clone();
    f.remove(5);
    match read(&f).unwrap_err() {
        Error::UnevenSlices { file_a, file_b, gap_mm, expected_mm } => {
            assert_eq!((file_a.as_str(), file_b.as_str()), ("slice-0004.dcm", "slice-0006.dcm"));
            assert_close(gap_mm, 2.5, 1e-9, "gap");
            assert_close(expected_mm, 1.25, 1e-9, "median gap");
        }
        e => panic!("{e:?}"),
    }

    // A single slice is not a volume; a lone non-DICOM file is not one either.
    assert!(matches!(read(&files[..1]).unwrap_err(), Error::NotAVolume { .. }));
    assert!(matches!(read(&one("notes.txt", b"hello".to_vec())).unwrap_err(), Error::NotAVolume { .. }));
    assert_eq!(read(&[]).unwrap_err(), Error::NoFiles);
    // Every refusal's message names what to do.
    assert!(Error::NoFiles.to_string().contains("drop"));
}

#[test]
fn non_dicom_files_and_dicomdir_are_skipped_and_listed_and_thickness_noted() {
    let v = phantom();
    let mut files = series(&v, &SeriesOptions { thickness_mm: Some(2.0), ..Default::default() });
    files.push(("README.txt".into(), b"scanned 2024".to_vec()));
    let mut dir = meta("1.2.840.10008.1.3.10", "1.2.3", "1.2.840.10008.1.2.1");
    dir.extend_from_slice(&[0x04, 0x00, 0x20, 0x12, b'S', b'Q', 0, 0, 0, 0, 0, 0]);
    files.push(("DICOMDIR".into(), dir));
    let got = read(&files).unwrap();
    assert_eq!(got.report.skipped, vec!["README.txt: not a DICOM file".to_string(), "DICOMDIR: DICOMDIR, a directory index, not an image".to_string()]);
    assert_eq!(got.report.files_read, 9);
    assert_eq!(got.report.notes.len(), 1);
    assert!(got.report.notes[0].contains("Slice Thickness 2 mm"), "{:?}", got.report.notes);
    assert_close(got.volume.spacing_mm[2], 1.25, 1e-12, "the gap, not the thickness");
}

#[test]
fn a_zip_of_the_series_reads_the_same_as_its_files() {
    let v = phantom();
    let o = SeriesOptions::default();
    let mut files: Vec<(String, Vec<u8>)> = series(&v, &o).into_iter().map(|(n, b)| (format!("CT/{n}"), b)).collect();
    let plain = read(&files).unwrap();
    files.push(("__MACOSX/CT/._slice-0000.dcm".into(), vec![0; 10]));
    files.push(("CT/.DS_Store".into(), vec![0; 10]));
    let zipped = zip_files(&files);
    let got = read(&one("series.zip", zipped.clone())).unwrap();
    assert_eq!(got.volume, plain.volume);
    assert_eq!(got.report.format, "DICOM in zip");
    assert_eq!(got.report.skipped, vec!["__MACOSX/CT/._slice-0000.dcm: macOS metadata".to_string(), "CT/.DS_Store: a hidden file".to_string()]);
    let e = estimate(&[("series.zip", &zipped)], &Options::default());
    assert_eq!(e.stage, "volume");
    assert_eq!(e.get("voxels"), (16 * 12 * 9) as f64);
    assert!(e.refused.is_none());
}

/// Sets a little-endian u32 at `at`.
fn put_u32(b: &mut [u8], at: usize, v: u32) {
    b[at..at + 4].copy_from_slice(&v.to_le_bytes());
}

/// Patches the declared uncompressed size of every entry (local and central headers).
fn patch_sizes(zip: &mut [u8], size: u32) {
    for i in 0..zip.len().saturating_sub(4) {
        if &zip[i..i + 4] == b"PK\x03\x04" {
            put_u32(zip, i + 22, size);
        } else if &zip[i..i + 4] == b"PK\x01\x02" {
            put_u32(zip, i + 24, size);
        }
    }
}

#[test]
fn zip_bombs_and_too_many_entries_are_refused() {
    let zeros = vec![(String::from("a.dcm"), vec![0u8; 100_000])];
    // Declares 3.9 GiB: refused before inflating.
    let mut z = zip_files(&zeros);
    patch_sizes(&mut z, 0xF000_0000);
    assert!(matches!(read(&one("bomb.zip", z)).unwrap_err(), Error::Zip { message, .. } if message.contains("unpack to")));
    // Declares 1 KiB but inflates to 100 kB: caught one byte past the declared size.
    let mut z = zip_files(&zeros);
    patch_sizes(&mut z, 1000);
    let e = read(&one("liar.zip", z)).unwrap_err();
    assert!(matches!(&e, Error::Zip { message, .. } if message.contains("more than the 1000 bytes") || message.contains("damaged")), "{e:?}");
    // More entries than a series may have.
    let many: Vec<(String, Vec<u8>)> = (0..=MAX_FILES).map(|i| (format!("{i}.dcm"), vec![1u8])).collect();
    assert!(matches!(read(&one("many.zip", zip_files(&many))).unwrap_err(), Error::Zip { message, .. } if message.contains("4097 files")));
    // A damaged archive.
    assert!(matches!(read(&one("cut.zip", b"PK\x03\x04 garbage".to_vec())).unwrap_err(), Error::Zip { .. }));
}

fn i16_le(values: &[i16]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

#[test]
fn nrrd_attached_detached_and_gzip_read_back_exactly() {
    let values: Vec<i16> = (0..4 * 3 * 2).map(|n| (n * 37 - 300) as i16).collect();
    let mut attached =
        b"NRRD0004\n# a comment\ntype: short\ndimension: 3\nsizes: 4 3 2\nendian: little\nencoding: raw\nspacings: 0.5 0.6 2\nkey:=value\n\n".to_vec();
    attached.extend_from_slice(&i16_le(&values));
    let got = read(&one("v.nrrd", attached)).unwrap();
    assert_eq!(got.volume.dims, [4, 3, 2]);
    assert_eq!(got.volume.spacing_mm, [0.5, 0.6, 2.0]);
    assert_eq!(got.volume.values, values.iter().map(|&v| v as f32).collect::<Vec<_>>());
    assert_eq!(got.volume.info.format, "NRRD");

    // gzip, big-endian float, space directions and origin in RAS (turned to LPS).
    let floats: Vec<f32> = (0..24).map(|n| n as f32 * 0.25 - 1.0).collect();
    let be: Vec<u8> = floats.iter().flat_map(|v| v.to_be_bytes()).collect();
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    std::io::Write::write_all(&mut gz, &be).unwrap();
    let mut nrrd = b"NRRD0005\ntype: float\ndimension: 3\nspace: right-anterior-superior\nsizes: 4 3 2\nspace directions: (0,0.5,0) (-0.6,0,0) (0,0,2)\nspace origin: (10,20,30)\nendian: big\nencoding: gzip\n\n".to_vec();
    nrrd.extend_from_slice(&gz.finish().unwrap());
    let got = read(&one("v.nrrd", nrrd)).unwrap();
    assert_eq!(got.volume.values, floats);
    assert_eq!(got.volume.spacing_mm, [0.5, 0.6, 2.0]);
    assert_eq!(got.volume.placement.origin_mm, [-10.0, -20.0, 30.0]);
    assert_eq!(got.volume.placement.axes, [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]);

    // Detached: the data file found by base name among the files, with a byte skip.
    let header = b"NRRD0004\ntype: int16\ndimension: 3\nsizes: 4 3 2\nendian: little\nencoding: raw\nbyte skip: 3\ndata file: ./data/v.raw\n".to_vec();
    let mut data = vec![9, 9, 9];
    data.extend_from_slice(&i16_le(&values));
    let got = read(&[("v.nhdr".into(), header.clone()), ("folder/v.raw".into(), data.clone()), ("other.txt".into(), vec![1])]).unwrap();
    assert_eq!(got.volume.values, values.iter().map(|&v| v as f32).collect::<Vec<_>>());
    assert_eq!(got.report.files_read, 2);
    assert_eq!(got.report.skipped, vec!["other.txt: not used by the NRRD header".to_string()]);
    assert!(got.report.notes[0].contains("no spacing"));

    // Errors: the data file missing, a bad type, no sizes, a data size mismatch.
    assert!(matches!(read(&one("v.nhdr", header)).unwrap_err(), Error::Nrrd { line: 0, message, .. } if message.contains("v.raw")));
    let bad = b"NRRD0004\ntype: quaternion\ndimension: 3\n\n".to_vec();
    assert!(matches!(read(&one("b.nrrd", bad)).unwrap_err(), Error::Nrrd { line: 2, .. }));
    let bad = b"NRRD0004\ntype: short\ndimension: 3\nendian: little\n\n\x00\x00".to_vec();
    assert!(matches!(read(&one("b.nrrd", bad)).unwrap_err(), Error::Nrrd { message, .. } if message.contains("sizes")));
    let mut bad = b"NRRD0004\ntype: short\ndimension: 3\nsizes: 4 3 2\nendian: little\n\n".to_vec();
    bad.extend_from_slice(&[0; 47]);
    assert!(matches!(read(&one("b.nrrd", bad)).unwrap_err(), Error::SizeMismatch { .. }));
    let bad = b"NRRD0004\ntype: short\ndimension: 2\n\n".to_vec();
    assert!(matches!(read(&one("b.nrrd", bad)).unwrap_err(), Error::Nrrd { line: 3, .. }));
}

#[test]
fn raw_reads_back_and_refuses_unset_or_wrong_layouts() {
    let values: Vec<u16> = (0..5 * 4 * 3).map(|n| n * 1000).collect();
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_be_bytes()).collect();
    let layout = RawLayout { dims: [5, 4, 3], spacing_mm: [0.3, 0.4, 0.5], voxel: VoxelType::U16, big_endian: true, slope: 0.5, intercept: -100.0 };
    let got = read_with(&one("ct.raw", bytes.clone()), &Options { raw: layout.clone() }).unwrap();
    assert_eq!(got.volume.values, values.iter().map(|&v| v as f32 * 0.5 - 100.0).collect::<Vec<_>>());
    assert_eq!(got.volume.spacing_mm, [0.3, 0.4, 0.5]);
    assert_eq!(got.report.format, "raw");
    let e = read(&one("ct.raw", bytes.clone())).unwrap_err();
    assert!(matches!(&e, Error::Raw { message, .. } if message.contains("raw.dims")), "{e}");
    let wrong = Options { raw: RawLayout { dims: [5, 4, 4], ..layout } };
    let e = read_with(&one("ct.raw", bytes), &wrong).unwrap_err();
    assert!(matches!(&e, Error::Raw { message, .. } if message.contains("holds 120 bytes") && message.contains("need 160")), "{e}");
    // Options are strict JSON with snake_case voxel names.
    let o: Options = serde_json::from_str(r#"{"raw":{"dims":[2,2,2],"voxel":"f32"}}"#).unwrap();
    assert_eq!(o.raw.voxel, VoxelType::F32);
    assert_eq!(o.raw.spacing_mm, [1.0; 3]);
    assert!(serde_json::from_str::<Options>(r#"{"raw":{"dim":[2,2,2]}}"#).is_err());
}

#[test]
fn estimates_state_voxels_and_refuse_over_the_limits_before_reading() {
    let v = phantom();
    let files = series(&v, &SeriesOptions::default());
    let refs: Vec<(&str, &[u8])> = files.iter().map(|(n, b)| (n.as_str(), b.as_slice())).collect();
    let e = estimate(&refs, &Options::default());
    assert_eq!(e.get("voxels"), (16 * 12 * 9) as f64);
    assert_eq!(e.get("files"), 9.0);
    assert!(e.bytes >= 4.0 * (16 * 12 * 9) as f64);
    assert!(e.refused.is_none());
    // An NRRD claiming 1024³ voxels of gzip data: refused from its header, before inflating.
    let big = b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 1024 1024 1024\nencoding: gzip\n\n\x1f\x8b".to_vec();
    let e = estimate(&[("big.nrrd", &big)], &Options::default());
    let r = e.refused.clone().unwrap();
    assert_eq!(r.what, "voxels");
    assert_eq!(r.limit, MAX_VOXELS as f64);
    assert!(matches!(read(&one("big.nrrd", big)).unwrap_err(), Error::TooBig(o) if o.what == "voxels"));
    // Raw over the limit (only the layout is checked: 600³ of u8 would need a 216 MB file).
    let o = Options { raw: RawLayout { dims: [600, 600, 600], voxel: VoxelType::U8, ..Default::default() } };
    let e = estimate(&[("x.raw", &[0u8; 4])], &o);
    assert!(e.refused.is_none(), "a raw size mismatch is read_volume's error, not a budget refusal");
}

#[test]
fn seeded_mutations_never_panic_and_every_error_formats() {
    let v = bone_phantom([6, 5, 3], [0.5, 0.5, 1.0]);
    let base: Vec<Vec<(String, Vec<u8>)>> = [Syntax::ExplicitLe, Syntax::ImplicitLe, Syntax::ExplicitBe, Syntax::DeflatedLe]
        .iter()
        .map(|&syntax| write_series(&v, &SeriesOptions { syntax, ..Default::default() }))
        .collect();
    let mut rng = Pcg64::new(2024, 11);
    let (mut ok, mut err) = (0, 0);
    for case in 0..3000 {
        let mut files = base[case % base.len()].clone();
        let f = (rng.next_u64() % files.len() as u64) as usize;
        match rng.next_u64() % 5 {
            0 => {
                let b = &mut files[f].1;
                for _ in 0..1 + rng.next_u64() % 8 {
                    let at = (rng.next_u64() % b.len() as u64) as usize;
                    b[at] = rng.next_u64() as u8;
                }
            }
            1 => {
                let b = &mut files[f].1;
                let at = (rng.next_u64() % b.len() as u64) as usize;
                b.truncate(at);
            }
            2 => {
                let dup = files[f].clone();
                files.push(dup);
            }
            3 => {
                // Mutate the header region (the first 400 bytes) more densely.
                let b = &mut files[f].1;
                for _ in 0..4 {
                    let at = (rng.next_u64() % 400.min(b.len() as u64)) as usize;
                    b[at] = [0x00, 0xFF, 0xFE, 0x7F, b'S', b'Q'][(rng.next_u64() % 6) as usize];
                }
            }
            _ => {
                let z = zip_files(&files);
                let mut z = z.clone();
                let at = (rng.next_u64() % z.len() as u64) as usize;
                z[at] ^= 1 << (rng.next_u64() % 8);
                files = vec![("s.zip".into(), z)];
            }
        }
        let refs: Vec<(&str, &[u8])> = files.iter().map(|(n, b)| (n.as_str(), b.as_slice())).collect();
        let _ = estimate(&refs, &Options::default());
        match read_volume(&refs, &Options::default()) {
            Ok(i) => {
                assert!(i.volume.values.len() == i.volume.len());
                ok += 1;
            }
            Err(e) => {
                assert!(!e.to_string().is_empty());
                err += 1;
            }
        }
    }
    // Both outcomes occur (a mutation in pixel data still reads).
    assert!(ok > 100 && err > 100, "ok {ok}, err {err}");
}

/// Explicit VR LE element writers for hand-made files.
struct Ds(Vec<u8>);

impl Ds {
    fn el(&mut self, g: u16, e: u16, vr: &[u8; 2], v: &[u8]) -> &mut Self {
        let mut v = v.to_vec();
        if v.len() % 2 == 1 {
            v.push(b' ');
        }
        self.0.extend_from_slice(&g.to_le_bytes());
        self.0.extend_from_slice(&e.to_le_bytes());
        self.0.extend_from_slice(vr);
        if vr == b"OW" {
            self.0.extend_from_slice(&[0, 0]);
            self.0.extend_from_slice(&(v.len() as u32).to_le_bytes());
        } else {
            self.0.extend_from_slice(&(v.len() as u16).to_le_bytes());
        }
        self.0.extend_from_slice(&v);
        self
    }
    fn us(&mut self, g: u16, e: u16, v: u16) -> &mut Self {
        self.el(g, e, b"US", &v.to_le_bytes())
    }
    /// Undefined-length sequence start.
    fn sq(&mut self, g: u16, e: u16) -> &mut Self {
        self.0.extend_from_slice(&g.to_le_bytes());
        self.0.extend_from_slice(&e.to_le_bytes());
        self.0.extend_from_slice(&[b'S', b'Q', 0, 0, 0xFF, 0xFF, 0xFF, 0xFF]);
        self
    }
    fn item(&mut self) -> &mut Self {
        self.0.extend_from_slice(&[0xFE, 0xFF, 0x00, 0xE0, 0xFF, 0xFF, 0xFF, 0xFF]);
        self
    }
    fn item_end(&mut self) -> &mut Self {
        self.0.extend_from_slice(&[0xFE, 0xFF, 0x0D, 0xE0, 0, 0, 0, 0]);
        self
    }
    fn sq_end(&mut self) -> &mut Self {
        self.0.extend_from_slice(&[0xFE, 0xFF, 0xDD, 0xE0, 0, 0, 0, 0]);
        self
    }
}

/// An enhanced (multi-frame) CT of 3 frames of 2 rows × 3 columns: shared orientation, pixel
/// measures and rescale; per-frame positions z = 4, 0, 2 (out of order) when `positions`.
fn multi_frame(positions: bool) -> Vec<u8> {
    let mut d = Ds(Vec::new());
    d.el(0x0008, 0x0060, b"CS", b"CT").el(0x0020, 0x000D, b"UI", b"1.2.3").el(0x0020, 0x000E, b"UI", b"1.2.3.4");
    d.us(0x0028, 0x0002, 1).el(0x0028, 0x0008, b"IS", b"3").us(0x0028, 0x0010, 2).us(0x0028, 0x0011, 3);
    d.us(0x0028, 0x0100, 16).us(0x0028, 0x0101, 16).us(0x0028, 0x0102, 15).us(0x0028, 0x0103, 1);
    d.sq(0x5200, 0x9229).item();
    d.sq(0x0020, 0x9116).item().el(0x0020, 0x0037, b"DS", b"1\\0\\0\\0\\1\\0").item_end().sq_end();
    d.sq(0x0028, 0x9110).item().el(0x0018, 0x0050, b"DS", b"2").el(0x0028, 0x0030, b"DS", b"0.5\\0.4").item_end().sq_end();
    d.sq(0x0028, 0x9145).item().el(0x0028, 0x1052, b"DS", b"-5").el(0x0028, 0x1053, b"DS", b"2").item_end().sq_end();
    d.item_end().sq_end();
    if positions {
        d.sq(0x5200, 0x9230);
        for z in [b"1\\2\\4", b"1\\2\\0", b"1\\2\\2"] {
            d.item().sq(0x0020, 0x9113).item().el(0x0020, 0x0032, b"DS", z).item_end().sq_end().item_end();
        }
        d.sq_end();
    }
    let px: Vec<u8> = (0..3).flat_map(|f| (0..6).map(move |n| (f * 100 + n - 50) as i16)).flat_map(|v| v.to_le_bytes()).collect();
    d.el(0x7FE0, 0x0010, b"OW", &px);
    let mut out = meta("1.2.840.10008.5.1.4.1.1.2.1", "1.2.3.4.5", "1.2.840.10008.1.2.1");
    out.extend_from_slice(&d.0);
    out
}

#[test]
fn a_multi_frame_file_is_read_from_its_functional_groups() {
    let got = read(&one("enhanced.dcm", multi_frame(true))).unwrap();
    let v = &got.volume;
    assert_eq!(v.dims, [3, 2, 3]);
    assert_eq!(v.spacing_mm, [0.4, 0.5, 2.0]);
    assert_eq!(v.placement.origin_mm, [1.0, 2.0, 0.0]);
    // k = 0 is frame 2 (z 0), k = 1 frame 3 (z 2), k = 2 frame 1 (z 4).
    for (k, f) in [(0, 1), (1, 2), (2, 0)] {
        for n in 0..6 {
            assert_eq!(v.values[k * 6 + n], ((f * 100 + n as i32 - 50) * 2 - 5) as f32, "k {k} n {n}");
        }
    }
    assert_eq!(v.info.unit, "HU");
    let e = read(&one("enhanced.dcm", multi_frame(false))).unwrap_err();
    assert!(matches!(&e, Error::Unsupported { what, .. } if what.contains("multi-frame")), "{e}");
}
