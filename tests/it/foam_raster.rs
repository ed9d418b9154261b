//! The continuous raster of a VTP foam layer (`foam::raster`): one path, inside the polygon,
//! through every scan interval. The intervals are recomputed here independently (half-open rule,
//! angle 0) and each one's midpoint must lie on the path; every point and every segment of the
//! path must stay inside or on the polygon (even-odd test plus on-boundary distance); lengths,
//! cells, the start, refusals and determinism are checked on small shapes whose answers are known.

use weft::foam::raster::{estimate_intervals, raster, Error, Options, Raster, DEFAULT_ANGLE_DEG, DEFAULT_SPACING_MM, MAX_SCAN_INTERSECTIONS};
use weft::geom::{DVec2, Polygon};

const ON: f64 = 1e-6;

fn v(x: f64, y: f64) -> DVec2 {
    DVec2::new(x, y)
}

fn poly(outer: &[(f64, f64)], holes: &[&[(f64, f64)]]) -> Polygon {
    Polygon { outer: outer.iter().map(|&(x, y)| v(x, y)).collect(), holes: holes.iter().map(|h| h.iter().map(|&(x, y)| v(x, y)).collect()).collect() }
}

fn opts(spacing_mm: f64, angle_deg: f64) -> Options {
    Options { spacing_mm, angle_deg }
}

fn square(side: f64) -> Polygon {
    poly(&[(0.0, 0.0), (side, 0.0), (side, side), (0.0, side)], &[])
}

fn rings(p: &Polygon) -> Vec<&Vec<DVec2>> {
    std::iter::once(&p.outer).chain(p.holes.iter()).collect()
}

fn segment_distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let len2 = ab.dot(ab);
    let t = if len2 == 0.0 { 0.0 } else { ((p - a).dot(ab) / len2).clamp(0.0, 1.0) };
    (a + ab * t - p).length()
}

fn on_boundary(p: &Polygon, q: DVec2) -> bool {
    rings(p).iter().any(|r| (0..r.len()).any(|i| segment_distance(q, r[i], r[(i + 1) % r.len()]) <= ON))
}

/// Even-odd over all rings, or within `ON` of the boundary.
fn inside(p: &Polygon, q: DVec2) -> bool {
    if on_boundary(p, q) {
        return true;
    }
    let mut odd = false;
    for r in rings(p) {
        for i in 0..r.len() {
            let (a, b) = (r[i], r[(i + 1) % r.len()]);
            if (a.y > q.y) != (b.y > q.y) && q.x < a.x + (q.y - a.y) / (b.y - a.y) * (b.x - a.x) {
                odd = !odd;
            }
        }
    }
    odd
}

/// Every point inside, every segment inside (sampled), no NaN, no consecutive duplicates, and the
/// three lengths add up to the path's length.
fn assert_path_inside(p: &Polygon, r: &Raster, what: &str) {
    assert!(r.points.len() >= 2, "{what}: path of {} points", r.points.len());
    for (i, &q) in r.points.iter().enumerate() {
        assert!(q.x.is_finite() && q.y.is_finite(), "{what}: point {i} {q}");
        assert!(inside(p, q), "{what}: point {i} {q} outside");
    }
    let mut length = 0.0;
    for (i, w) in r.points.windows(2).enumerate() {
        assert!(w[0] != w[1], "{what}: duplicate point {i} {}", w[0]);
        length += (w[1] - w[0]).length();
        for s in 1..32 {
            let q = w[0] + (w[1] - w[0]) * (s as f64 / 32.0);
            assert!(inside(p, q), "{what}: segment {i} {} → {} leaves the polygon at {q}", w[0], w[1]);
        }
    }
    let parts = r.raster_mm + r.boundary_mm + r.retraced_mm;
    assert!((length - parts).abs() < 1e-9 * length.max(1.0), "{what}: length {length} vs parts {parts}");
}

/// The scan intervals at angle 0, computed independently: y_k = y_min + s(k + ½) < y_max (one
/// middle line when thinner than s), edges cut when (a.y <= y) != (b.y <= y), sorted x pairwise.
fn scan_intervals(p: &Polygon, spacing: f64) -> Vec<(DVec2, DVec2)> {
    let ys = rings(p).into_iter().flatten().map(|q| q.y).collect::<Vec<_>>();
    let (lo, hi) = ys.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &y| (l.min(y), h.max(y)));
    let lines: Vec<f64> =
        if hi - lo < spacing { vec![lo + (hi - lo) * 0.5] } else { (0..).map(|k| lo + spacing * (0.5 + k as f64)).take_while(|&y| y < hi).collect() };
    let mut out = Vec::new();
    for y in lines {
        let mut xs = Vec::new();
        for r in rings(p) {
            for i in 0..r.len() {
                let (a, b) = (r[i], r[(i + 1) % r.len()]);
                if (a.y <= y) != (b.y <= y) {
                    xs.push(a.x + (y - a.y) / (b.y - a.y) * (b.x - a.x));
                }
            }
        }
        xs.sort_by(f64::total_cmp);
        assert!(xs.len() % 2 == 0);
        for pair in xs.chunks(2) {
            out.push((v(pair[0], y), v(pair[1], y)));
        }
    }
    out
}

/// Every independent interval's midpoint lies on a segment of the path, and the raster length is
/// the intervals' total (each printed once).
fn assert_covers(p: &Polygon, r: &Raster, spacing: f64, what: &str) {
    let intervals = scan_intervals(p, spacing);
    assert!(!intervals.is_empty(), "{what}: no intervals");
    for (a, b) in &intervals {
        let mid = (*a + *b) * 0.5;
        let near = r.points.windows(2).map(|w| segment_distance(mid, w[0], w[1])).fold(f64::INFINITY, f64::min);
        assert!(near < 1e-9, "{what}: interval {a} – {b} not printed (midpoint {near} mm from the path)");
    }
    let total: f64 = intervals.iter().map(|(a, b)| b.x - a.x).sum();
    assert!((r.raster_mm - total).abs() < 1e-9, "{what}: raster {} mm vs intervals {total} mm", r.raster_mm);
}

fn l_shape() -> Polygon {
    poly(&[(0.0, 0.0), (20.0, 0.0), (20.0, 10.0), (10.0, 10.0), (10.0, 20.0), (0.0, 20.0)], &[])
}

fn u_shape() -> Polygon {
    poly(&[(0.0, 0.0), (30.0, 0.0), (30.0, 30.0), (20.0, 30.0), (20.0, 10.0), (10.0, 10.0), (10.0, 30.0), (0.0, 30.0)], &[])
}

fn ring_shape() -> Polygon {
    poly(&[(0.0, 0.0), (30.0, 0.0), (30.0, 30.0), (0.0, 30.0)], &[&[(10.0, 10.0), (10.0, 20.0), (20.0, 20.0), (20.0, 10.0)]])
}

/// A C whose back is 1 mm thick: each scan line through the back is a 1 mm interval.
fn c_thin_back() -> Polygon {
    poly(&[(0.0, 0.0), (30.0, 0.0), (30.0, 10.0), (1.0, 10.0), (1.0, 20.0), (30.0, 20.0), (30.0, 30.0), (0.0, 30.0)], &[])
}

/// Two blocks joined by a neck 0.8 mm high between the lines y = 3 and y = 5: no scan line
/// crosses the neck, the blocks are joined only along its boundary.
fn dumbbell() -> Polygon {
    poly(
        &[
            (0.0, 0.0),
            (10.0, 0.0),
            (10.0, 3.6),
            (20.0, 3.6),
            (20.0, 0.0),
            (30.0, 0.0),
            (30.0, 10.0),
            (20.0, 10.0),
            (20.0, 4.4),
            (10.0, 4.4),
            (10.0, 10.0),
            (0.0, 10.0),
        ],
        &[],
    )
}

/// A neck whose top edge lies exactly on the scan line y = 5, and a sawtooth whose notches
/// (y = 5) lie on a line and whose tooth tip (y = 7) touches one from below.
fn on_line_shapes() -> Vec<(&'static str, Polygon)> {
    vec![
        (
            "neck on a line",
            poly(
                &[
                    (0.0, 0.0),
                    (10.0, 0.0),
                    (10.0, 4.2),
                    (20.0, 4.2),
                    (20.0, 0.0),
                    (30.0, 0.0),
                    (30.0, 10.0),
                    (20.0, 10.0),
                    (20.0, 5.0),
                    (10.0, 5.0),
                    (10.0, 10.0),
                    (0.0, 10.0),
                ],
                &[],
            ),
        ),
        ("sawtooth", poly(&[(0.0, 0.0), (20.0, 0.0), (20.0, 10.0), (15.0, 5.0), (10.0, 7.0), (5.0, 5.0), (0.0, 10.0)], &[])),
        (
            "hole with vertices on lines",
            poly(&[(0.0, 0.0), (30.0, 0.0), (30.0, 30.0), (0.0, 30.0)], &[&[(15.0, 9.0), (9.0, 15.0), (15.0, 21.0), (21.0, 15.0)]]),
        ),
        (
            "two holes",
            poly(
                &[(0.0, 0.0), (40.0, 0.0), (40.0, 20.0), (0.0, 20.0)],
                &[&[(5.0, 5.0), (5.0, 15.0), (15.0, 15.0), (15.0, 5.0)], &[(17.0, 4.0), (17.0, 16.0), (30.0, 16.0), (30.0, 4.0)]],
            ),
        ),
    ]
}

#[test]
fn defaults_are_the_documented_ones() {
    assert_eq!(Options::default(), Options { spacing_mm: DEFAULT_SPACING_MM, angle_deg: DEFAULT_ANGLE_DEG });
    assert_eq!((DEFAULT_SPACING_MM, DEFAULT_ANGLE_DEG), (2.0, 0.0));
}

#[test]
fn square_is_one_cell_of_ten_lines_joined_along_its_sides() {
    let p = square(20.0);
    let r = raster(&p, None, &opts(2.0, 0.0)).unwrap();
    assert_eq!(r.cells, 1);
    assert!((r.raster_mm - 200.0).abs() < 1e-9, "raster {}", r.raster_mm);
    assert!((r.boundary_mm - 18.0).abs() < 1e-9, "boundary {}", r.boundary_mm);
    assert_eq!(r.retraced_mm, 0.0);
    // Bottom-left of the lowest line, then 10 lines × 2 ends.
    assert_eq!(r.points[0], v(0.0, 1.0));
    assert_eq!(r.points.len(), 20);
    assert_eq!(*r.points.last().unwrap(), v(0.0, 19.0));
    assert_eq!(estimate_intervals(&p, &opts(2.0, 0.0)), 10);
    assert_path_inside(&p, &r, "square");
    assert_covers(&p, &r, 2.0, "square");
}

#[test]
fn rotated_squares_stay_one_path_inside() {
    let p = square(20.0);
    for angle in [45.0, 90.0, -30.0, 137.0, 360.0 + 90.0] {
        let r = raster(&p, None, &opts(2.0, angle)).unwrap();
        assert_path_inside(&p, &r, &format!("square at {angle}°"));
        assert_eq!(r.cells, 1, "square at {angle}°");
        assert!(r.raster_mm > 150.0, "square at {angle}°: raster {}", r.raster_mm);
    }
    // A quarter turn is exact: the same lines as at 0°, along Y.
    let r = raster(&p, None, &opts(2.0, 90.0)).unwrap();
    assert!((r.raster_mm - 200.0).abs() < 1e-9 && (r.boundary_mm - 18.0).abs() < 1e-9, "{r:?}");
    assert!(r.points.windows(2).all(|w| w[0].x == w[1].x || w[0].y == w[1].y), "90° path not axis-aligned");
}

#[test]
fn l_shape_is_covered_inside() {
    let p = l_shape();
    let r = raster(&p, None, &opts(2.0, 0.0)).unwrap();
    assert_path_inside(&p, &r, "L");
    assert_covers(&p, &r, 2.0, "L");
    // The strip between y = 9 and 11 joins the wide line to the narrow one: a single cell.
    assert_eq!(r.cells, 1);
    assert_eq!(r.retraced_mm, 0.0);
}

#[test]
fn u_shape_has_three_cells_and_is_covered_inside() {
    let p = u_shape();
    let r = raster(&p, None, &opts(2.0, 0.0)).unwrap();
    assert_path_inside(&p, &r, "U");
    assert_covers(&p, &r, 2.0, "U");
    assert!(r.cells >= 3, "U: {} cells", r.cells);
    assert_eq!(r.cells, 3);
    assert!((r.raster_mm - 350.0).abs() < 1e-9, "U raster {}", r.raster_mm);
    println!("U path: {:?}", r.points);
    println!("U: cells {} raster {} boundary {} retraced {}", r.cells, r.raster_mm, r.boundary_mm, r.retraced_mm);
}

#[test]
fn square_with_a_hole_is_covered_inside() {
    let p = ring_shape();
    let r = raster(&p, None, &opts(2.0, 0.0)).unwrap();
    assert_path_inside(&p, &r, "ring");
    assert_covers(&p, &r, 2.0, "ring");
    assert_eq!(r.cells, 4);
    for angle in [30.0, 45.0, 90.0] {
        let r = raster(&p, None, &opts(2.0, angle)).unwrap();
        assert_path_inside(&p, &r, &format!("ring at {angle}°"));
    }
}

#[test]
fn c_with_a_thin_back_and_a_thin_neck_are_covered_inside() {
    for (name, p) in [("C", c_thin_back()), ("dumbbell", dumbbell())] {
        let r = raster(&p, None, &opts(2.0, 0.0)).unwrap();
        assert_path_inside(&p, &r, name);
        assert_covers(&p, &r, 2.0, name);
    }
    // The neck is crossed by no line: the two blocks are reached along its boundary.
    let r = raster(&dumbbell(), None, &opts(2.0, 0.0)).unwrap();
    assert!(r.cells >= 2 && r.boundary_mm >= 10.0, "{r:?}");
}

#[test]
fn vertices_and_edges_on_scan_lines_are_handled() {
    for (name, p) in on_line_shapes() {
        for spacing in [2.0, 1.0] {
            let r = raster(&p, None, &opts(spacing, 0.0)).unwrap();
            assert_path_inside(&p, &r, name);
            assert_covers(&p, &r, spacing, name);
        }
        for angle in [45.0, 90.0, 180.0] {
            let r = raster(&p, None, &opts(2.0, angle)).unwrap();
            assert_path_inside(&p, &r, &format!("{name} at {angle}°"));
        }
    }
}

#[test]
fn spacing_wider_than_the_polygon_gives_one_middle_line() {
    let p = poly(&[(0.0, 0.0), (12.0, 0.0), (12.0, 1.5), (0.0, 1.5)], &[]);
    let r = raster(&p, None, &opts(2.0, 0.0)).unwrap();
    assert_eq!(r.points, vec![v(0.0, 0.75), v(12.0, 0.75)]);
    assert_eq!((r.cells, r.raster_mm, r.boundary_mm), (1, 12.0, 0.0));
}

#[test]
fn start_is_the_nearest_node() {
    let p = square(20.0);
    // Nodes: the corners and the lines' ends on x = 0 and x = 20 at odd y.
    for (start, expect) in [(v(25.0, 7.3), v(20.0, 7.0)), (v(3.0, 12.2), v(0.0, 13.0)), (v(-1.0, -2.0), v(0.0, 0.0))] {
        let r = raster(&p, Some(start), &opts(2.0, 0.0)).unwrap();
        assert_eq!(r.points[0], expect, "start {start}");
        assert_path_inside(&p, &r, "square from a start");
        assert_covers(&p, &r, 2.0, "square from a start");
    }
    // From (20, 7) the nearest corner of the cell is (20, 1), 6 mm down the side.
    let r = raster(&p, Some(v(25.0, 7.3)), &opts(2.0, 0.0)).unwrap();
    assert_eq!(r.points[1..4], [v(20.0, 5.0), v(20.0, 3.0), v(20.0, 1.0)]);
    assert!((r.boundary_mm - 24.0).abs() < 1e-9, "boundary {}", r.boundary_mm);
    // Ending where a layer ended starts the next one there.
    let first = raster(&ring_shape(), None, &opts(2.0, 0.0)).unwrap();
    let end = *first.points.last().unwrap();
    let next = raster(&ring_shape(), Some(end), &opts(2.0, 0.0)).unwrap();
    assert_eq!(next.points[0], end);
}

#[test]
fn bad_options_are_refused_with_the_range() {
    let p = square(20.0);
    for s in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let e = raster(&p, None, &opts(s, 0.0)).unwrap_err();
        assert!(matches!(e, Error::BadSpacing { .. }), "{s}: {e:?}");
        assert!(e.to_string().contains("finite number of millimetres above 0"), "{e}");
    }
    let e = raster(&p, None, &opts(2.0, f64::NAN)).unwrap_err();
    assert!(matches!(e, Error::BadAngle { .. }) && e.to_string().contains("finite number of degrees"), "{e}");
    let e = raster(&p, Some(v(f64::NAN, 0.0)), &opts(2.0, 0.0)).unwrap_err();
    assert!(matches!(e, Error::BadStart { .. }), "{e}");
}

#[test]
fn degenerate_and_too_narrow_polygons_are_refused() {
    let o = opts(2.0, 0.0);
    let two = poly(&[(0.0, 0.0), (10.0, 0.0)], &[]);
    assert!(matches!(raster(&two, None, &o), Err(Error::Degenerate { .. })));
    let flat = poly(&[(0.0, 0.0), (10.0, 10.0), (5.0, 5.0)], &[]);
    let e = raster(&flat, None, &o).unwrap_err();
    assert!(matches!(e, Error::Degenerate { .. }) && e.to_string().contains("no area"), "{e}");
    let nan = poly(&[(0.0, 0.0), (10.0, f64::NAN), (5.0, 5.0)], &[]);
    assert!(matches!(raster(&nan, None, &o), Err(Error::Degenerate { .. })));
    let bad_hole = poly(&[(0.0, 0.0), (10.0, 0.0), (5.0, 5.0)], &[&[(1.0, 1.0)]]);
    assert!(matches!(raster(&bad_hole, None, &o), Err(Error::Degenerate { .. })));
    // An hourglass 2 mm high pinched at y = 1: the only line at 2 mm spacing runs through the
    // pinch; a finer spacing passes.
    let hourglass = poly(&[(0.0, 0.0), (10.0, 0.0), (5.0, 1.0), (10.0, 2.0), (0.0, 2.0), (5.0, 1.0)], &[]);
    let e = raster(&hourglass, None, &o).unwrap_err();
    assert!(matches!(e, Error::TooNarrow { .. }), "{e:?}");
    assert!(e.to_string().contains("2.0000 mm wide at most") && e.to_string().contains("lower the line spacing"), "{e}");
    assert!(raster(&hourglass, None, &opts(1.5, 0.0)).is_ok());
}

#[test]
fn over_the_work_limit_is_refused_by_the_estimate() {
    let p = square(1000.0);
    // 10 000 lines × 2 crossings = 10 000 intervals.
    assert_eq!(estimate_intervals(&p, &opts(0.1, 0.0)), 10_000);
    let est = estimate_intervals(&p, &opts(1e-4, 0.0));
    assert!(est > MAX_SCAN_INTERSECTIONS, "{est}");
    let e = raster(&p, None, &opts(1e-4, 0.0)).unwrap_err();
    match &e {
        Error::TooMuchWork { intervals, limit, suggested_mm, .. } => {
            assert_eq!((*intervals, *limit), (est, MAX_SCAN_INTERSECTIONS));
            assert!(*suggested_mm > 1e-4 && estimate_intervals(&p, &opts(*suggested_mm, 0.0)) <= MAX_SCAN_INTERSECTIONS);
        }
        other => panic!("{other:?}"),
    }
    assert!(e.to_string().contains("raise the line spacing") && e.to_string().contains(&est.to_string()), "{e}");
    // Absurd spacings are refused at once, without counting line by line.
    let (w, r) = crate::work::measure(|| raster(&p, None, &opts(1e-300, 0.0)).map(drop));
    assert!(matches!(r, Err(Error::TooMuchWork { .. })));
    assert!(w.bytes < 1 << 20 && w.allocs < 1000, "refused at once: {w:?}");
    // Bad options estimate nothing.
    assert_eq!(estimate_intervals(&p, &opts(-1.0, 0.0)), 0);
}

#[test]
fn a_hole_outside_the_outline_is_refused_as_unreachable() {
    let p = poly(&[(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)], &[&[(20.0, 2.0), (20.0, 8.0), (26.0, 8.0), (26.0, 2.0)]]);
    let e = raster(&p, None, &opts(2.0, 0.0)).unwrap_err();
    assert!(matches!(e, Error::Unreachable { .. }), "{e:?}");
    assert!(e.to_string().contains("one connected piece"), "{e}");
}

#[test]
fn same_input_same_bits() {
    let shapes = [square(20.0), l_shape(), u_shape(), ring_shape(), c_thin_back(), dumbbell()];
    for p in &shapes {
        for angle in [0.0, 33.0, 90.0] {
            let a = raster(p, Some(v(3.3, 4.4)), &opts(1.7, angle)).unwrap();
            let b = raster(p, Some(v(3.3, 4.4)), &opts(1.7, angle)).unwrap();
            let bits = |r: &Raster| {
                let lengths = [r.raster_mm.to_bits(), r.boundary_mm.to_bits(), r.retraced_mm.to_bits()];
                r.points.iter().flat_map(|q| [q.x.to_bits(), q.y.to_bits()]).chain(lengths).collect::<Vec<_>>()
            };
            assert_eq!(bits(&a), bits(&b));
            assert_eq!(a.cells, b.cells);
        }
    }
}

#[test]
fn many_holes_and_fine_spacing_stay_inside_and_covered() {
    // A plate with a 4 × 3 grid of diamond holes: many cells, links that cross earlier lines.
    let mut holes: Vec<Vec<(f64, f64)>> = Vec::new();
    for i in 0..4 {
        for j in 0..3 {
            let (cx, cy) = (10.0 + 12.0 * i as f64, 10.0 + 12.0 * j as f64);
            holes.push(vec![(cx, cy - 4.0), (cx - 4.0, cy), (cx, cy + 4.0), (cx + 4.0, cy)]);
        }
    }
    let hole_refs: Vec<&[(f64, f64)]> = holes.iter().map(|h| &h[..]).collect();
    let p = poly(&[(0.0, 0.0), (50.0, 0.0), (50.0, 38.0), (0.0, 38.0)], &hole_refs);
    for spacing in [2.0, 0.7, 0.5] {
        let r = raster(&p, None, &opts(spacing, 0.0)).unwrap();
        assert_path_inside(&p, &r, "plate");
        assert_covers(&p, &r, spacing, "plate");
        assert!(r.cells > 12, "plate: {} cells", r.cells);
    }
    for angle in [15.0, 60.0] {
        let r = raster(&p, Some(v(49.0, 37.0)), &opts(1.0, angle)).unwrap();
        assert_path_inside(&p, &r, "plate turned");
    }
}

/// The crate's deterministic generator (rand_pcg), seeded per test.
struct Rng(rand_pcg::Pcg64);

impl Rng {
    fn seeded(seed: u64) -> Rng {
        Rng(rand_core::SeedableRng::seed_from_u64(seed))
    }
    fn unit(&mut self) -> f64 {
        (rand_core::Rng::next_u64(&mut self.0) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A star-shaped ring around `c`: deep notches, radii between `r0` and `r1`, some vertices at
/// integer heights (on the scan lines of spacing 2 and 1 from y = 0).
fn star(rng: &mut Rng, c: DVec2, r0: f64, r1: f64, n: usize, snap: bool) -> Vec<DVec2> {
    (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * (i as f64 + 0.3 * rng.unit()) / n as f64;
            let r = r0 + (r1 - r0) * rng.unit();
            let mut q = c + DVec2::new(a.cos(), a.sin()) * r;
            if snap && rng.unit() < 0.4 {
                q.y = q.y.round();
            }
            q
        })
        .collect()
}

#[test]
fn random_notched_outlines_with_holes_are_covered_inside() {
    let mut rng = Rng::seeded(0x9E37_79B9_7F4A_7C15);
    for case in 0..60 {
        let c = DVec2::new(20.0, 20.0);
        let inner_radius = 8.0 + 3.0 * rng.unit();
        let outer = star(&mut rng, c, inner_radius, 19.0, 8 + case % 17, case % 2 == 0);
        let mut holes = Vec::new();
        if case % 3 != 0 {
            // A small hole near the centre, well inside the outline (its chords stay beyond 6 mm), clockwise.
            let centre = c + DVec2::new(rng.unit() - 0.5, rng.unit() - 0.5);
            let mut h = star(&mut rng, centre, 1.0, 4.5, 5 + case % 5, case % 4 == 1);
            h.reverse();
            holes.push(h);
        }
        let p = Polygon { outer, holes };
        for spacing in [2.0, 1.0, 0.45] {
            let r = raster(&p, None, &opts(spacing, 0.0)).unwrap_or_else(|e| panic!("case {case} at {spacing}: {e}"));
            let what = format!("case {case} at {spacing} mm");
            assert_path_inside(&p, &r, &what);
            assert_covers(&p, &r, spacing, &what);
        }
        let angle = 360.0 * rng.unit();
        let start = DVec2::new(40.0 * rng.unit(), 40.0 * rng.unit());
        let r = raster(&p, Some(start), &opts(1.3, angle)).unwrap_or_else(|e| panic!("case {case} at {angle}°: {e}"));
        assert_path_inside(&p, &r, &format!("case {case} at {angle}°"));
    }
}
