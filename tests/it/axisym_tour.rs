//! Axisymmetric tour (issue 10): NN + 2-opt path through (u, θ) points, sampled geodesics.

use weft::axisym::geodesic::{self, geodesic};
use weft::axisym::platform::{normal, position, Platform, Profile};
use weft::axisym::tour::{self, plan, Error, Options, Start, Tour};

/// SplitMix64: a fixed, platform-independent stream for the test points.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn rect(n: usize, u: [f64; 2], t: [f64; 2], seed: u64) -> Vec<[f64; 2]> {
    let mut r = Rng(seed);
    (0..n).map(|_| [u[0] + (u[1] - u[0]) * r.next(), t[0] + (t[1] - t[0]) * r.next()]).collect()
}

/// An L (non-convex) on the barrel with a notch: the rectangle minus its upper-right quarter
/// and minus a slot, points rejection-sampled.
fn l_shape(n: usize, seed: u64) -> Vec<[f64; 2]> {
    let mut r = Rng(seed);
    let mut out = Vec::new();
    while out.len() < n {
        let q = [0.8 + 0.4 * r.next(), r.next()];
        let quarter = q[0] > 1.0 && q[1] > 0.5;
        let slot = q[0] < 0.95 && (0.2..0.3).contains(&q[1]);
        if !quarter && !slot {
            out.push(q);
        }
    }
    out
}

fn geo_dist(p: &Platform) -> impl Fn([f64; 2], [f64; 2]) -> f64 + '_ {
    let o = geodesic::Options::default();
    move |a, b| geodesic(p, a, b, &o).map(|g| g.length_mm).unwrap_or(f64::NAN)
}

fn chord_dist(p: &Platform) -> impl Fn([f64; 2], [f64; 2]) -> f64 + '_ {
    move |a, b| {
        let (x, y) = (position(p, a[0], a[1]), position(p, b[0], b[1]));
        ((x[0] - y[0]).powi(2) + (x[1] - y[1]).powi(2) + (x[2] - y[2]).powi(2)).sqrt()
    }
}

fn cross(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    // Independent of the module: parametric intersection, strictly inside both pieces.
    let r = [b[0] - a[0], b[1] - a[1]];
    let s = [d[0] - c[0], d[1] - c[1]];
    let den = r[0] * s[1] - r[1] * s[0];
    if den == 0.0 {
        return false;
    }
    let q = [c[0] - a[0], c[1] - a[1]];
    let t = (q[0] * s[1] - q[1] * s[0]) / den;
    let u = (q[0] * r[1] - q[1] * r[0]) / den;
    t > 1e-12 && t < 1.0 - 1e-12 && u > 1e-12 && u < 1.0 - 1e-12
}

/// O(n²) over all sampled pieces.
fn brute_crossings(s: &[Vec<[f64; 2]>]) -> usize {
    let pieces: Vec<(usize, [f64; 2], [f64; 2])> = s.iter().enumerate().flat_map(|(k, seg)| seg.windows(2).map(move |w| (k, w[0], w[1]))).collect();
    let mut n = 0;
    for i in 0..pieces.len() {
        for j in i + 1..pieces.len() {
            let (a, b) = (pieces[i], pieces[j]);
            if a.0 != b.0 && cross(a.1, a.2, b.1, b.2) {
                n += 1;
            }
        }
    }
    n
}

fn run(p: &Platform, pts: &[[f64; 2]], o: &Options, d: &dyn Fn([f64; 2], [f64; 2]) -> f64, label: &str) -> Tour {
    let mut last = -1.0f32;
    let tour = plan(p, pts, o, d, None, &mut |f| {
        assert!(f >= last && (0.0..=1.0).contains(&f), "progress goes up within 0..=1");
        last = f;
    })
    .unwrap();
    println!(
        "{label}: {} points; NN {:.1} mm → 2-opt {:.1} mm ({} passes, {} moves), crossings removed {} left {}, {} poses",
        pts.len(),
        tour.nn_length_mm,
        tour.length_mm,
        tour.two_opt_passes,
        tour.two_opt_moves,
        tour.crossings_removed,
        tour.crossings_left,
        tour.poses.len()
    );
    tour
}

fn check(p: &Platform, pts: &[[f64; 2]], o: &Options, tour: &Tour, want_start: usize) {
    let n = pts.len();
    let mut seen = vec![false; n];
    assert_eq!(tour.order.len(), n);
    for &i in &tour.order {
        assert!(!seen[i], "point {i} visited twice");
        seen[i] = true;
    }
    assert_eq!(tour.order[0], want_start, "start point");
    assert_eq!(tour.crossings_left, 0);
    assert_eq!(brute_crossings(&tour.samples), 0, "sampled geodesics cross in the map");
    assert!(tour.length_mm <= tour.nn_length_mm + 1e-9, "2-opt {} > NN {}", tour.length_mm, tour.nn_length_mm);
    assert_eq!(tour.samples.len(), n - 1);
    let mut total = 0;
    for (k, seg) in tour.samples.iter().enumerate() {
        assert!(seg.len() >= 2);
        assert_eq!(seg[0], pts[tour.order[k]], "segment starts at its point");
        let end = pts[tour.order[k + 1]];
        let last = seg[seg.len() - 1];
        assert_eq!(last[0], end[0]);
        assert!(((last[1] - end[1]) / (2.0 * std::f64::consts::PI)).fract().abs() < 1e-12);
        for w in seg.windows(2) {
            let (a, b) = (position(p, w[0][0], w[0][1]), position(p, w[1][0], w[1][1]));
            let l = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            assert!(l <= o.step_mm * (1.0 + 1e-9), "samples {l} mm apart > step {}", o.step_mm);
        }
        total += seg.len() - 1;
    }
    assert_eq!(tour.poses.len(), total + 1, "joints not repeated");
    for q in &tour.poses {
        let m = q.normal;
        assert!(((m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt() - 1.0).abs() < 1e-12, "unit normal");
        // Outward: z falls monotonically with u on these ranges, so the normal points away from the axis.
        let r = (q.position[0] * m[0] + q.position[1] * m[1]) / q.position[0].hypot(q.position[1]);
        assert!(r > 0.1, "normal {m:?} at {:?} not outward", q.position);
    }
}

fn corner(p: &Platform, pts: &[[f64; 2]]) -> usize {
    let u = pts.iter().map(|q| q[0]).fold(f64::MIN, f64::max);
    let t = pts.iter().map(|q| q[1]).fold(f64::MAX, f64::min);
    let j = p.jet(u);
    let (su, st) = ((j.x[1] * j.x[1] + j.z[1] * j.z[1]).sqrt(), j.x[0]);
    let d = |q: &[f64; 2]| ((q[0] - u) * su).powi(2) + ((q[1] - t) * st).powi(2);
    (0..pts.len()).min_by(|&a, &b| d(&pts[a]).total_cmp(&d(&pts[b])).then(a.cmp(&b))).unwrap()
}

#[test]
fn hourglass_200_points() {
    let p = Platform::hourglass();
    let pts = rect(200, [1.0, 3.0], [0.0, 1.0], 1);
    let o = Options::default();
    let tour = run(&p, &pts, &o, &geo_dist(&p), "hourglass rect");
    check(&p, &pts, &o, &tour, corner(&p, &pts));
    assert!(tour.length_mm < 0.95 * tour.nn_length_mm, "2-opt should shorten a random NN path");
}

#[test]
fn barrel_500_points_and_nearest_start() {
    let p = Platform::barrel();
    let pts = rect(500, [0.8, 1.2], [0.0, 1.0], 2);
    let o = Options { start: Start::Nearest { u: pts[137][0], theta: pts[137][1] }, ..Options::default() };
    let tour = run(&p, &pts, &o, &chord_dist(&p), "barrel rect (chord dist)");
    check(&p, &pts, &o, &tour, 137);
}

#[test]
fn barrel_non_convex() {
    let p = Platform::barrel();
    let pts = l_shape(538, 3);
    let o = Options::default();
    let tour = run(&p, &pts, &o, &chord_dist(&p), "barrel L-shape (chord dist)");
    check(&p, &pts, &o, &tour, corner(&p, &pts));
}

#[test]
fn crossings_of_the_nn_path_are_removed() {
    // Without 2-opt the NN path crosses itself; the map check must find and undo every crossing.
    let p = Platform::barrel();
    let pts = rect(300, [0.8, 1.2], [0.0, 1.0], 6);
    let o = Options { two_opt_passes: 0, ..Options::default() };
    let tour = run(&p, &pts, &o, &chord_dist(&p), "barrel NN only");
    assert!(tour.crossings_removed > 0, "a random NN path has crossings");
    assert_eq!(tour.crossings_left, 0);
    assert_eq!(brute_crossings(&tour.samples), 0);
    // And the module's grid check agrees with the brute force on a crossing pair.
    let s = vec![vec![[0.0, 0.0], [1.0, 1.0]], vec![[1.0, 1.0], [2.0, 0.0]], vec![[2.0, 0.0], [0.0, 1.0]]];
    assert_eq!(tour::crossings(&s), vec![(0, 2)]);
    assert_eq!(brute_crossings(&s), 1);
}

#[test]
fn deterministic() {
    let p = Platform::hourglass();
    let pts = rect(150, [1.0, 3.0], [0.0, 1.0], 7);
    let d = chord_dist(&p);
    let a = plan(&p, &pts, &Options::default(), &d, None, &mut |_| {}).unwrap();
    let b = plan(&p, &pts, &Options::default(), &d, None, &mut |_| {}).unwrap();
    assert_eq!(a, b);
}

#[test]
fn barrel_equator_normal_is_plus_x() {
    let p = Platform::barrel();
    let t = plan(&p, &[[1.0, 0.0]], &Options::default(), &chord_dist(&p), None, &mut |_| {}).unwrap();
    assert_eq!(t.order, [0]);
    assert!(t.samples.is_empty());
    let n = t.poses[0].normal;
    assert!((n[0] - 1.0).abs() < 1e-12 && n[1].abs() < 1e-12 && n[2].abs() < 1e-9, "{n:?}");
    assert_eq!(normal(&p, 1.0, 0.0)[0].signum(), 1.0);
}

#[test]
fn bad_input_is_refused_with_typed_errors() {
    let p = Platform::barrel();
    let d = chord_dist(&p);
    let go = |pts: &[[f64; 2]], o: &Options| plan(&p, pts, o, &d, None, &mut |_| {});
    let o = Options::default();
    assert_eq!(go(&[], &o), Err(Error::NoPoints));
    assert_eq!(go(&[[1.0, 0.0], [f64::NAN, 0.0]], &o), Err(Error::NotFinite { index: 1 }));
    assert_eq!(go(&[[1.0, f64::INFINITY]], &o), Err(Error::NotFinite { index: 0 }));
    assert!(matches!(go(&[[1.0, 0.0], [7.0, 0.0]], &o), Err(Error::Point { index: 1, .. })));
    assert!(matches!(go(&[[0.0, 0.0], [1.0, 0.0]], &o), Err(Error::Point { index: 0, .. })), "the pole");
    for step in [0.0, -1.0, f64::NAN, 1e-9, 1e300] {
        assert!(matches!(go(&[[1.0, 0.0], [1.1, 0.1]], &Options { step_mm: step, ..o.clone() }), Err(Error::BadOption { name: "step_mm", .. })));
    }
    assert!(matches!(go(&[[1.0, 0.0]], &Options { start: Start::Nearest { u: f64::NAN, theta: 0.0 }, ..o.clone() }), Err(Error::BadOption { .. })));
    assert!(matches!(go(&[[1.0, 0.0]], &Options { neighbours: 0, ..o.clone() }), Err(Error::BadOption { .. })));
    let nan = |_: [f64; 2], _: [f64; 2]| f64::NAN;
    assert!(matches!(plan(&p, &rect(20, [0.9, 1.1], [0.0, 1.0], 8), &o, &nan, None, &mut |_| {}), Err(Error::BadDistance { .. })));
    let many = vec![[1.0, 0.0]; tour::MAX_POINTS + 1];
    let e = go(&many, &o).unwrap_err();
    assert!(matches!(e, Error::OverBudget(_)) && e.to_string().contains("points in one tour"), "{e}");
    // Fine step over a long path: refused before the samples are allocated.
    let far = |_: [f64; 2], _: [f64; 2]| 1e4;
    let e = plan(&p, &rect(200, [0.3, 1.7], [0.0, 6.0], 9), &Options { step_mm: 0.01, ..o.clone() }, &far, None, &mut |_| {}).unwrap_err();
    assert!(e.to_string().contains("path samples"), "{e}");
    // Duplicate points are a valid (degenerate) input.
    let t = go(&[[1.0, 0.0], [1.0, 0.0], [1.05, 0.1]], &o).unwrap();
    assert_eq!(t.order.len(), 3);
    // Options parse with defaults and refuse unknown fields.
    let o: Options = serde_json::from_str(r#"{"start":{"kind":"nearest","u":1.0,"theta":0.5}}"#).unwrap();
    assert_eq!(o.step_mm, tour::DEFAULT_STEP_MM);
    assert!(serde_json::from_str::<Options>(r#"{"stepmm":1}"#).is_err());
}

#[test]
fn the_path_goes_around_a_hole() {
    use weft::axisym::domain::Domain;
    use weft::axisym::uniform;
    let p = Platform::barrel();
    // A slit 9 mm long and 0.75 mm wide (about a spacing): a plain path hops over it often.
    let d = Domain::Polygon {
        points: vec![[0.8, 0.0], [1.2, 0.0], [1.2, 1.0], [0.8, 1.0]],
        holes: vec![vec![[0.85, 0.485], [1.15, 0.485], [1.15, 0.515], [0.85, 0.515]]],
    };
    let pts = uniform::distribute(&p, &d, &uniform::Options { iterations: 20, ..uniform::Options::default() }, 0.4, 1, &mut |_| {}).unwrap().points;
    let dist = geo_dist(&p);
    let crosses = |a: [f64; 2], b: [f64; 2]| d.segment_crosses_hole(a, b);
    let plain = plan(&p, &pts, &Options::default(), &dist, None, &mut |_| {}).unwrap();
    let around = plan(&p, &pts, &Options::default(), &dist, Some(&crosses), &mut |_| {}).unwrap();
    let over = |t: &Tour| t.samples.iter().filter(|s| s.windows(2).any(|w| crosses(w[0], w[1]))).count();
    println!(
        "{} points around a hole: {} segments over it without avoidance ({:.1} mm), {} with ({:.1} mm, {} crossings left)",
        pts.len(),
        over(&plain),
        plain.length_mm,
        around.hole_crossings,
        around.length_mm,
        around.crossings_left
    );
    let chords = around.order.windows(2).filter(|w| crosses(pts[w[0]], pts[w[1]])).count();
    println!("chords over the hole: {chords}");
    assert_eq!(plain.hole_crossings, 0, "not counted without avoid");
    assert!(over(&plain) > 0, "the plain path should cross the hole somewhere");
    assert_eq!(around.hole_crossings, over(&around));
    assert!(around.hole_crossings < over(&plain) && around.hole_crossings <= 1, "{}", around.hole_crossings);
    assert_eq!(around.order.len(), pts.len());
    // The lengths leave the penalty out: a few percent longer at most.
    assert!(around.length_mm < 1.1 * plain.length_mm, "{} vs {}", around.length_mm, plain.length_mm);
}
