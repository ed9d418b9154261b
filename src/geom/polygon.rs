use glam::DVec2;

/// A region of one layer: an outer loop (counter-clockwise) and its holes (clockwise).
/// Loops are implicitly closed: the last point is not repeated.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Polygon {
    /// Outer boundary, counter-clockwise, mm.
    pub outer: Vec<DVec2>,
    /// Holes, clockwise, mm.
    pub holes: Vec<Vec<DVec2>>,
}

impl Polygon {
    /// Enclosed area in mm² (outer minus holes).
    pub fn area(&self) -> f64 {
        signed_area(&self.outer) + self.holes.iter().map(|h| signed_area(h)).sum::<f64>()
    }
}

/// Shoelace area of a closed loop, positive when counter-clockwise, mm².
pub fn signed_area(ring: &[DVec2]) -> f64 {
    let n = ring.len();
    if n < 3 {
        return 0.0;
    }
    let mut twice = 0.0;
    for i in 0..n {
        let a = ring[i];
        let b = ring[(i + 1) % n];
        twice += a.x * b.y - b.x * a.y;
    }
    twice * 0.5
}
