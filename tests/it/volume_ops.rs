//! Volume operations: trilinear sampling, slice images, ROI histograms, isolines.

use weft::geom::DVec3;
use weft::volume::{histogram, histogram_in, isolines, slice_image, Axis, Roi, SliceImage, Volume};

/// SplitMix64: a fixed random stream, same on every run.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn volume(dims: [usize; 3], spacing_mm: [f64; 3], f: impl Fn(usize, usize, usize) -> f32) -> Volume {
    let mut values = Vec::with_capacity(dims[0] * dims[1] * dims[2]);
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                values.push(f(i, j, k));
            }
        }
    }
    Volume { dims, spacing_mm, values, ..Default::default() }
}

const SPACINGS: [[f64; 3]; 4] = [[1.0, 1.0, 1.0], [0.976562, 0.976562, 3.27], [0.3, 2.0, 1.1], [1.7, 0.45, 0.6]];

#[test]
fn trilinear_is_exact_on_linear_and_multilinear_fields() {
    let mut rng = Rng(7);
    for spacing in SPACINGS {
        let dims = [6, 5, 7];
        // Integer values in index space are exact in f32; in mm the field is linear.
        let lin = volume(dims, spacing, |i, j, k| (3 + 2 * i as i32 - 5 * j as i32 + 7 * k as i32) as f32);
        let lin_at = |p: DVec3| 3.0 + 2.0 * p.x / spacing[0] - 5.0 * p.y / spacing[1] + 7.0 * p.z / spacing[2];
        // Trilinear reproduces products of per-axis linear terms too (checks each weight).
        let tri = volume(dims, spacing, |i, j, k| ((i + 1) * (j + 2) * (k + 3)) as f32);
        let tri_at = |p: DVec3| (p.x / spacing[0] + 1.0) * (p.y / spacing[1] + 2.0) * (p.z / spacing[2] + 3.0);
        let e = lin.extent_mm();
        for _ in 0..2000 {
            let p = DVec3::new(rng.unit() * e.x, rng.unit() * e.y, rng.unit() * e.z);
            let (a, b) = (lin.sample(p).unwrap(), lin_at(p));
            assert!((a - b).abs() < 1e-9 * (1.0 + b.abs()), "linear at {p}: {a} vs {b}");
            let (a, b) = (tri.sample(p).unwrap(), tri_at(p));
            assert!((a - b).abs() < 1e-9 * (1.0 + b.abs()), "trilinear at {p}: {a} vs {b}");
        }
        // The far corner and faces are inside.
        assert!((lin.sample(e).unwrap() - lin_at(e)).abs() < 1e-9);
        assert_eq!(lin.sample(DVec3::ZERO), Some(3.0));
    }
}

#[test]
fn sample_at_voxel_centres_is_the_voxel_value_exactly() {
    let mut rng = Rng(11);
    for spacing in SPACINGS {
        let dims = [5, 4, 6];
        let vals: Vec<f32> = (0..dims.iter().product::<usize>()).map(|_| (rng.unit() * 4000.0 - 1000.0) as f32).collect();
        let v = Volume { dims, spacing_mm: spacing, values: vals, ..Default::default() };
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    let p = DVec3::new(i as f64 * spacing[0], j as f64 * spacing[1], k as f64 * spacing[2]);
                    assert_eq!(v.sample(p), Some(f64::from(v.at(i, j, k))), "voxel ({i},{j},{k}) spacing {spacing:?}");
                }
            }
        }
    }
}

#[test]
fn sample_outside_or_not_finite_is_none() {
    let v = volume([4, 3, 5], [0.5, 2.0, 1.5], |i, j, k| (i + j + k) as f32);
    let e = v.extent_mm();
    assert_eq!(e, DVec3::new(1.5, 4.0, 6.0));
    let eps = 1e-9;
    for p in [
        DVec3::new(-eps, 1.0, 1.0),
        DVec3::new(1.0, -eps, 1.0),
        DVec3::new(1.0, 1.0, -eps),
        DVec3::new(e.x + eps, 1.0, 1.0),
        DVec3::new(1.0, e.y + eps, 1.0),
        DVec3::new(1.0, 1.0, e.z + eps),
        DVec3::new(f64::NAN, 1.0, 1.0),
        DVec3::new(1.0, f64::INFINITY, 1.0),
        DVec3::new(1.0, 1.0, f64::NEG_INFINITY),
    ] {
        assert_eq!(v.sample(p), None, "{p}");
    }
    assert_eq!(Volume::default().sample(DVec3::ZERO), None);
    // Values shorter than the dims say: refused, not a panic.
    let mut bad = v.clone();
    bad.values.truncate(10);
    assert_eq!(bad.sample(DVec3::ZERO), None);
}

#[test]
fn single_voxel_axis_is_constant_and_only_its_plane_is_inside() {
    let v = volume([4, 3, 1], [1.0, 1.0, 2.5], |i, j, _| (i * 10 + j) as f32);
    assert_eq!(v.sample(DVec3::new(1.5, 0.5, 0.0)), Some(15.5));
    assert_eq!(v.sample(DVec3::new(1.5, 0.5, 0.1)), None);
    let line = volume([1, 1, 3], [1.0, 1.0, 1.0], |_, _, k| k as f32 * 4.0);
    assert_eq!(line.sample(DVec3::new(0.0, 0.0, 1.25)), Some(5.0));
    let one = volume([1, 1, 1], [1.0, 1.0, 1.0], |_, _, _| 42.0);
    assert_eq!(one.sample(DVec3::ZERO), Some(42.0));
}

#[test]
fn sample_with_maps_corners_before_interpolating() {
    let v = volume([2, 2, 2], [1.0, 1.0, 1.0], |i, _, _| i as f32);
    let p = DVec3::new(0.5, 0.3, 0.8);
    assert_eq!(v.sample(p), Some(0.5));
    // ρ = f(HU) interpolated: (0² + 1²)/2, not 0.5².
    assert_eq!(v.sample_with(p, |x| f64::from(x * x)), Some(0.5));
    assert_eq!(v.sample_with(p, |x| 2.0 * f64::from(x) + 1.0), Some(2.0));
    assert_eq!(v.sample_with(DVec3::new(2.0, 0.0, 0.0), f64::from), None);
}

#[test]
fn slice_image_picks_the_right_voxels_on_each_axis() {
    let dims = [4, 5, 6];
    let spacing = [0.5, 0.75, 2.0];
    let v = volume(dims, spacing, |i, j, k| (i + 100 * j + 10000 * k) as f32);
    let code = |i: usize, j: usize, k: usize| (i + 100 * j + 10000 * k) as f32;
    for index in 0..7 {
        let s = slice_image(&v, Axis::Axial, index);
        let k = index.min(5);
        assert_eq!((s.index, s.count, s.width, s.height), (k, 6, 4, 5));
        assert_eq!((s.pixel_mm, s.position_mm), ([0.5, 0.75], k as f64 * 2.0));
        assert_eq!(s.values.len(), 20);
        for y in 0..5 {
            for x in 0..4 {
                assert_eq!(s.values[x + 4 * y], code(x, y, k));
            }
        }
        let s = slice_image(&v, Axis::Coronal, index);
        let j = index.min(4);
        assert_eq!((s.index, s.count, s.width, s.height), (j, 5, 4, 6));
        assert_eq!((s.pixel_mm, s.position_mm), ([0.5, 2.0], j as f64 * 0.75));
        for y in 0..6 {
            for x in 0..4 {
                assert_eq!(s.at(x, y), code(x, j, y));
            }
        }
        let s = slice_image(&v, Axis::Sagittal, index);
        let i = index.min(3);
        assert_eq!((s.index, s.count, s.width, s.height), (i, 4, 5, 6));
        assert_eq!((s.pixel_mm, s.position_mm), ([0.75, 2.0], i as f64 * 0.5));
        for y in 0..6 {
            for x in 0..5 {
                assert_eq!(s.at(x, y), code(i, x, y));
            }
        }
    }
    let e = slice_image(&Volume::default(), Axis::Coronal, 3);
    assert_eq!((e.width, e.height, e.values.len()), (0, 0, 0));
    assert_eq!(serde_json::to_string(&Axis::Sagittal).unwrap(), "\"sagittal\"");
    assert_eq!(serde_json::from_str::<Axis>("\"axial\"").unwrap(), Axis::Axial);
}

#[test]
fn histogram_counts_the_voxels_in_the_roi_and_their_mean() {
    let dims = [9, 8, 7];
    let spacing = [0.5, 1.0, 1.5];
    let f = |i: usize, j: usize, k: usize| ((i * 7 + j * 3 + k * 5) % 23) as f32 - 4.0;
    let v = volume(dims, spacing, f);
    let roi = Roi { min_mm: [0.7, 1.0, 1.4], max_mm: [3.0, 5.5, 9.0] };
    // Independent count: every voxel centre inside the box.
    let mut expect = Vec::new();
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let c = [i as f64 * spacing[0], j as f64 * spacing[1], k as f64 * spacing[2]];
                if (0..3).all(|a| c[a] >= roi.min_mm[a] && c[a] <= roi.max_mm[a]) {
                    expect.push(f64::from(f(i, j, k)));
                }
            }
        }
    }
    // i ∈ {2..6} (1.0..3.0), j ∈ {1..5}, k ∈ {1..6} (1.5..9.0).
    assert_eq!(expect.len(), 5 * 5 * 6);
    let h = histogram(&v, &roi, 10);
    assert_eq!(h.voxels, expect.len() as u64);
    assert_eq!(h.counts.iter().sum::<u64>(), h.voxels);
    assert_eq!(h.mean, expect.iter().sum::<f64>() / expect.len() as f64);
    let (lo, hi) = expect.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
    assert_eq!((h.min, h.max, h.bin_width), (lo, hi, (hi - lo) / 10.0));
    for (b, &n) in h.counts.iter().enumerate() {
        let in_bin = expect.iter().filter(|&&x| ((((x - lo) / h.bin_width).floor() as usize).min(9)) == b).count();
        assert_eq!(n, in_bin as u64, "bin {b}");
    }
    // Fixed range: outside values go to the end bins; the counts still add up.
    let h = histogram_in(&v, &roi, [10.0, 0.0], 5);
    assert_eq!((h.min, h.max, h.bin_width), (0.0, 10.0, 2.0));
    assert_eq!(h.counts.iter().sum::<u64>(), expect.len() as u64);
    assert_eq!(h.counts[0], expect.iter().filter(|&&x| x < 2.0).count() as u64);
    assert_eq!(h.counts[4], expect.iter().filter(|&&x| x >= 8.0).count() as u64);
    // An empty region, and a non-finite voxel skipped.
    let none = histogram(&v, &Roi { min_mm: [100.0; 3], max_mm: [200.0; 3] }, 4);
    assert_eq!((none.voxels, none.counts, none.mean), (0, vec![0; 4], 0.0));
    let mut nan = v.clone();
    nan.values[0] = f32::NAN;
    let whole = histogram(&nan, &Roi::whole(&nan), 0);
    assert_eq!((whole.voxels, whole.counts.len()), ((9 * 8 * 7 - 1) as u64, 1));
}

fn image(w: usize, h: usize, pixel_mm: [f64; 2], f: impl Fn(f64, f64) -> f64) -> SliceImage {
    let mut values = Vec::new();
    for r in 0..h {
        for c in 0..w {
            values.push(f(c as f64 * pixel_mm[0], r as f64 * pixel_mm[1]) as f32);
        }
    }
    SliceImage { axis: Axis::Axial, index: 0, count: 1, width: w, height: h, pixel_mm, position_mm: 0.0, values }
}

/// Checks the segments form one chained, closed polyline; returns (length, signed area).
fn closed_loop(segs: &[[f32; 5]]) -> (f64, f64) {
    assert!(segs.len() > 8);
    let (mut len, mut area) = (0.0, 0.0);
    for (n, s) in segs.iter().enumerate() {
        let next = segs[(n + 1) % segs.len()];
        assert_eq!([s[2], s[3]], [next[0], next[1]], "segment {n} does not chain");
        let (x0, y0, x1, y1) = (s[0] as f64, s[1] as f64, s[2] as f64, s[3] as f64);
        len += ((x1 - x0).powi(2) + (y1 - y0).powi(2)).sqrt();
        area += 0.5 * (x0 * y1 - x1 * y0);
    }
    (len, area)
}

#[test]
fn isolines_of_a_radial_field_are_closed_circles_with_higher_values_on_the_left() {
    let r = 30.0;
    for pixel in [[0.5, 0.5], [0.4, 0.7]] {
        let (cx, cy) = (50.0, 52.0);
        let dist = move |x: f64, y: f64| ((x - cx).powi(2) + (y - cy).powi(2)).sqrt();
        let img = image((100.0 / pixel[0]) as usize + 1, (104.0 / pixel[1]) as usize + 1, pixel, dist);
        let segs = isolines(&img, &[r]);
        let (len, area) = closed_loop(&segs);
        assert!((len / (2.0 * std::f64::consts::PI * r) - 1.0).abs() < 0.01, "length {len}");
        // Values grow outwards: outside on the left, so the loop turns clockwise (x right, y up).
        assert!(area < 0.0 && (area.abs() / (std::f64::consts::PI * r * r) - 1.0).abs() < 0.01, "area {area}");
        for s in &segs {
            assert_eq!(s[4], 0.0);
            for (x, y) in [(s[0], s[1]), (s[2], s[3])] {
                // Linear interpolation of a convex field along an edge: off by ≤ h²/(8r).
                assert!((dist(x as f64, y as f64) - r).abs() < 3e-3, "point ({x}, {y})");
            }
            let (mx, my) = ((s[0] + s[2]) as f64 / 2.0, (s[1] + s[3]) as f64 / 2.0);
            let (dx, dy) = ((s[2] - s[0]) as f64, (s[3] - s[1]) as f64);
            assert!((mx - cx) * -dy + (my - cy) * dx > 0.0, "left of {s:?} is not outwards");
        }
        // A peak instead of a pit: the same circle, counter-clockwise.
        let peak = image(img.width, img.height, pixel, |x, y| 100.0 - dist(x, y));
        let (len2, area2) = closed_loop(&isolines(&peak, &[100.0 - r]));
        assert!(area2 > 0.0 && (len2 - len).abs() < 1e-3 * len);
    }
}

#[test]
fn isolines_points_are_at_the_level_by_interpolation_and_levels_are_indexed() {
    let img = image(41, 37, [1.0, 1.0], |x, y| 0.3 * x * x - 0.2 * x * y + y);
    let levels = [5.0, f64::NAN, 40.0, 120.0];
    let segs = isolines(&img, &levels);
    let mut seen = [0usize; 4];
    for s in &segs {
        let li = s[4] as usize;
        assert_eq!(s[4], li as f32);
        seen[li] += 1;
        for (x, y) in [(s[0] as f64, s[1] as f64), (s[2] as f64, s[3] as f64)] {
            // On a pixel edge: one coordinate is whole; linear along it gives the level.
            let (c, r) = (x.floor() as usize, y.floor() as usize);
            let v = |c: usize, r: usize| f64::from(img.at(c.min(40), r.min(36)));
            let value = if x.fract() == 0.0 {
                let t = y - r as f64;
                (1.0 - t) * v(c, r) + t * v(c, r + 1)
            } else {
                assert_eq!(y.fract(), 0.0);
                let t = x - c as f64;
                (1.0 - t) * v(c, r) + t * v(c + 1, r)
            };
            assert!((value - levels[li]).abs() < 1e-3 * (1.0 + levels[li].abs()), "{value} vs level {}", levels[li]);
        }
    }
    assert!(seen[0] > 10 && seen[2] > 10 && seen[3] > 10, "{seen:?}");
    assert_eq!(seen[1], 0, "a NaN level has no isoline");
    // Level order in the output.
    assert!(segs.windows(2).all(|w| w[0][4] <= w[1][4]));
}

#[test]
fn isolines_of_a_ramp_are_one_open_line_running_with_the_higher_side_left() {
    let img = image(11, 8, [0.5, 2.0], |x, _| x);
    let segs = isolines(&img, &[2.25]);
    assert_eq!(segs.len(), 7);
    for (n, s) in segs.iter().enumerate() {
        assert_eq!((s[0], s[2]), (2.25, 2.25));
        // Higher x on the left: the line runs towards −y.
        assert_eq!((s[1], s[3]), ((7 - n) as f32 * 2.0, (6 - n) as f32 * 2.0));
    }
}

#[test]
fn isolines_resolve_saddles_by_the_centre_average() {
    // Corners (0,0)=1, (1,0)=0, (1,1)=1, (0,1)=0; centre 0.5 ≥ 0.5: the high corners join,
    // each low corner is cut off.
    let img = image(2, 2, [1.0, 1.0], |x, y| if x == y { 1.0 } else { 0.0 });
    let segs = isolines(&img, &[0.5]);
    assert_eq!(segs.len(), 2);
    let mut cut: Vec<[f32; 4]> = segs.iter().map(|s| [s[0], s[1], s[2], s[3]]).collect();
    cut.sort_by(|a, b| a.partial_cmp(b).unwrap());
    // Low corner (1,0) on the right of bottom-mid → right-mid, low corner (0,1) on the right
    // of top-mid → left-mid.
    assert_eq!(cut, vec![[0.5, 0.0, 1.0, 0.5], [0.5, 1.0, 0.0, 0.5]]);
    // Lower centre (0.55 / 2 < 0.5): the high corners are cut off instead, on the left.
    let img = image(2, 2, [1.0, 1.0], |x, y| if x == y { 0.55 } else { 0.0 });
    let mut cut: Vec<[f32; 4]> = isolines(&img, &[0.5]).iter().map(|s| [s[0], s[1], s[2], s[3]]).collect();
    cut.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let u = 1.0 - 0.5 / 0.55;
    let expect = [[u, 0.0, 0.0, u], [1.0 - u, 1.0, 1.0, 1.0 - u]];
    assert_eq!(cut.len(), 2);
    for (got, want) in cut.iter().zip(expect) {
        for (g, w) in got.iter().zip(want) {
            assert!((*g as f64 - w).abs() < 1e-6, "{cut:?} vs {expect:?}");
        }
    }
}

#[test]
fn isolines_of_a_constant_or_degenerate_image_are_empty() {
    let img = image(20, 15, [1.0, 1.0], |_, _| 7.0);
    assert!(isolines(&img, &[6.0, 7.0, 8.0]).is_empty());
    let line = image(20, 1, [1.0, 1.0], |x, _| x);
    assert!(isolines(&line, &[3.5]).is_empty());
    let mut nan = image(3, 3, [1.0, 1.0], |x, _| x);
    nan.values[4] = f32::NAN;
    assert!(isolines(&nan, &[0.5]).is_empty(), "every cell touches the NaN centre");
    assert!(isolines(&image(3, 3, [1.0, 1.0], |x, _| x), &[]).is_empty());
}
