//! Objects of a print for object labels ([`super::ObjectLabels`]): the parts a host can cancel
//! one by one. Found from the toolpath itself, so every job kind and every input gets them:
//! paths whose extrusion lies in one connected piece of the plate (seen from above, over all
//! layers) are one object. Parts of a multi-object 3MF placed apart, a plate of copies, foam
//! regions side by side are objects each; a stack or a lattice is one. The skirt and brim
//! belong to no object (as in PrusaSlicer): they are printed on the first layer whatever is
//! cancelled, and a skirt round a single part does not make a second object.
//!
//! The plate is a grid of cells ([`cell_mm`]: at least 1 mm, at most [`MAX_CELLS`] cells a
//! side); each extruding segment marks the cells it crosses, and marked cells that touch
//! (8-neighbours) make one piece, so parts closer than about a cell merge. Work: cells crossed
//! (the extruded length over the cell size, at most [`MAX_STEPS`]; past it the print is one
//! object) plus the grid.

use super::format::fixed;
use super::ObjectLabels;
use crate::geom::{Feature, Toolpath};
use glam::DVec3;

/// Most cells along a side of the grid.
pub const MAX_CELLS: usize = 512;
/// Most cells the segments may cross before the print is taken as one object.
pub const MAX_STEPS: usize = 40_000_000;
/// Most objects labelled; a print with more is one object (a firmware keeps a few dozen).
pub const MAX_OBJECTS: usize = 64;

/// One object.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    /// Name in the labels: letters, digits, `_` and `-` only.
    pub name: String,
    /// Centre of its outline's bounds, printer X Y, mm.
    pub center: [f64; 2],
    /// Its outline: the convex hull of its cells, printer X Y, mm, counter-clockwise.
    pub polygon: Vec<[f64; 2]>,
}

/// Objects of a print and the object of every path.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Objects {
    /// The objects, in the order the print starts them.
    pub list: Vec<Object>,
    /// Object of each path, counted over all passes in order (paths without extrusion: none).
    pub of_path: Vec<Option<usize>>,
}

/// Cell size for a plate spanning `span_mm` (the larger side): at least 1 mm.
pub fn cell_mm(span_mm: f64) -> f64 {
    (span_mm / (MAX_CELLS - 1) as f64).max(1.0)
}

/// The objects of `toolpath`, with `offset` added to give printer coordinates and names made
/// from `name`.
pub fn find(toolpath: &Toolpath, offset: DVec3, name: &str) -> Objects {
    let paths: Vec<&crate::geom::Path> = toolpath.passes.iter().flat_map(|p| &p.paths).collect();
    // Paths that belong to an object: printed ones other than the skirt and brim.
    let part = |p: &crate::geom::Path| p.points.len() >= 2 && p.feature != Feature::Skirt;
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in paths.iter().filter(|p| part(p)) {
        for q in &p.points {
            lo = [lo[0].min(q.x), lo[1].min(q.y)];
            hi = [hi[0].max(q.x), hi[1].max(q.y)];
        }
    }
    let whole = |paths: &[&crate::geom::Path]| {
        let of_path = paths.iter().map(|p| part(p).then_some(0)).collect();
        let poly = if lo[0].is_finite() { vec![[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]] } else { vec![] };
        let list = if lo[0].is_finite() { vec![object(stem(name), &poly, offset)] } else { vec![] };
        Objects { list, of_path }
    };
    if !(lo[0].is_finite() && hi[0].is_finite() && lo[1].is_finite() && hi[1].is_finite()) {
        return whole(&paths);
    }
    let cell = cell_mm((hi[0] - lo[0]).max(hi[1] - lo[1]));
    let nx = ((hi[0] - lo[0]) / cell) as usize + 1;
    let ny = ((hi[1] - lo[1]) / cell) as usize + 1;
    let at = |q: DVec3| -> (usize, usize) { ((((q.x - lo[0]) / cell) as usize).min(nx - 1), (((q.y - lo[1]) / cell) as usize).min(ny - 1)) };
    // Mark the cells every extruding segment crosses (sampled at half a cell).
    let mut grid = vec![false; nx * ny];
    let mut steps = 0usize;
    for p in paths.iter().filter(|p| part(p)) {
        for w in p.points.windows(2) {
            let n = ((w[0].distance(w[1]) / (cell * 0.5)).ceil() as usize).max(1);
            steps += n;
            if steps > MAX_STEPS {
                return whole(&paths);
            }
            for k in 0..=n {
                let (i, j) = at(w[0].lerp(w[1], k as f64 / n as f64));
                grid[j * nx + i] = true;
            }
        }
    }
    // Pieces (8-connected), numbered in the order the print reaches them.
    let mut piece = vec![usize::MAX; nx * ny];
    let mut cells_of: Vec<Vec<usize>> = Vec::new();
    let mut of_path = Vec::with_capacity(paths.len());
    let mut stack = Vec::new();
    for p in &paths {
        if !part(p) {
            of_path.push(None);
            continue;
        }
        let (i, j) = at(p.points[0]);
        let c = j * nx + i;
        if piece[c] == usize::MAX {
            let id = cells_of.len();
            let mut cells = Vec::new();
            piece[c] = id;
            stack.push(c);
            while let Some(c) = stack.pop() {
                cells.push(c);
                let (ci, cj) = ((c % nx) as i64, (c / nx) as i64);
                for (di, dj) in [(-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)] {
                    let (a, b) = (ci + di, cj + dj);
                    if a >= 0 && b >= 0 && (a as usize) < nx && (b as usize) < ny {
                        let d = b as usize * nx + a as usize;
                        if grid[d] && piece[d] == usize::MAX {
                            piece[d] = id;
                            stack.push(d);
                        }
                    }
                }
            }
            cells_of.push(cells);
        }
        of_path.push(Some(piece[c]));
    }
    if cells_of.len() > MAX_OBJECTS || cells_of.len() <= 1 {
        return whole(&paths);
    }
    let base = stem(name);
    let list = cells_of
        .iter()
        .enumerate()
        .map(|(k, cells)| {
            let mut corners = Vec::with_capacity(cells.len() * 4);
            for &c in cells {
                let (x, y) = (lo[0] + (c % nx) as f64 * cell, lo[1] + (c / nx) as f64 * cell);
                corners.extend([[x, y], [x + cell, y], [x + cell, y + cell], [x, y + cell]]);
            }
            object(format!("{base}_{}", k + 1), &hull(corners), offset)
        })
        .collect();
    Objects { list, of_path }
}

/// Lines declaring the objects at the top of the moves: `M486 T<count>` and each named
/// (`M486 S<i> A"name"`, then `M486 S-1`), or Klipper's `EXCLUDE_OBJECT_DEFINE` with centre and
/// outline (3 decimals).
pub fn define(list: &[Object], style: ObjectLabels) -> String {
    let mut s = String::new();
    let f = |v: f64| fixed(v, 3);
    match style {
        ObjectLabels::None => {}
        ObjectLabels::M486 => {
            s.push_str(&format!("M486 T{}\n", list.len()));
            for (i, o) in list.iter().enumerate() {
                s.push_str(&format!("M486 S{i} A\"{}\"\n", o.name));
            }
            s.push_str("M486 S-1\n");
        }
        ObjectLabels::ExcludeObject => {
            for o in list {
                let poly: Vec<String> = o.polygon.iter().map(|p| format!("[{},{}]", f(p[0]), f(p[1]))).collect();
                s.push_str(&format!("EXCLUDE_OBJECT_DEFINE NAME={} CENTER={},{} POLYGON=[{}]\n", o.name, f(o.center[0]), f(o.center[1]), poly.join(",")));
            }
        }
    }
    s
}

/// The line starting object `i`.
pub fn start(list: &[Object], i: usize, style: ObjectLabels) -> String {
    match style {
        ObjectLabels::None => String::new(),
        ObjectLabels::M486 => format!("M486 S{i}"),
        ObjectLabels::ExcludeObject => format!("EXCLUDE_OBJECT_START NAME={}", list[i].name),
    }
}

/// The line ending object `i`.
pub fn end(list: &[Object], i: usize, style: ObjectLabels) -> String {
    match style {
        ObjectLabels::None => String::new(),
        ObjectLabels::M486 => "M486 S-1".into(),
        ObjectLabels::ExcludeObject => format!("EXCLUDE_OBJECT_END NAME={}", list[i].name),
    }
}

fn object(name: String, poly: &[[f64; 2]], offset: DVec3) -> Object {
    let polygon: Vec<[f64; 2]> = poly.iter().map(|p| [p[0] + offset.x, p[1] + offset.y]).collect();
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in &polygon {
        lo = [lo[0].min(p[0]), lo[1].min(p[1])];
        hi = [hi[0].max(p[0]), hi[1].max(p[1])];
    }
    Object { name, center: [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0], polygon }
}

/// The name's letters, digits, `_` and `-` (others become `_`), at most 40 bytes; `part` when
/// none are left.
pub fn stem(name: &str) -> String {
    let s: String = name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' { c } else { '_' }).take(40).collect();
    let s = s.trim_matches('_').to_string();
    if s.is_empty() {
        "part".into()
    } else {
        s
    }
}

/// Convex hull, counter-clockwise (monotone chain).
fn hull(mut pts: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
    pts.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
    let mut h: Vec<[f64; 2]> = Vec::with_capacity(pts.len() + 1);
    for pass in 0..2 {
        let start = h.len();
        let it: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 { Box::new(pts.iter()) } else { Box::new(pts.iter().rev()) };
        for &p in it {
            while h.len() >= start + 2 && cross(h[h.len() - 2], h[h.len() - 1], p) <= 0.0 {
                h.pop();
            }
            h.push(p);
        }
        h.pop();
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{Pass, Path};

    fn square(x: f64, y: f64, s: f64, z: f64) -> Path {
        let p = [[x, y], [x + s, y], [x + s, y + s], [x, y + s], [x, y]].map(|q| DVec3::new(q[0], q[1], z));
        Path::new(p.to_vec(), Feature::Perimeter, 0.4)
    }

    #[test]
    fn parts_apart_are_objects_in_print_order() {
        let layer = |z| Pass::layer(z, 0.2, vec![square(20.0, 0.0, 10.0, z), square(0.0, 0.0, 10.0, z), square(20.5, 0.5, 9.0, z)]);
        let tp = Toolpath { passes: vec![layer(0.2), layer(0.4)] };
        let o = find(&tp, DVec3::new(100.0, 100.0, 0.0), "my part.stl");
        assert_eq!(o.list.len(), 2);
        assert_eq!(o.list[0].name, "my_part_stl_1");
        assert_eq!(o.of_path, vec![Some(0), Some(1), Some(0), Some(0), Some(1), Some(0)]);
        let c = o.list[0].center;
        assert!((c[0] - 125.0).abs() < 1.1 && (c[1] - 105.0).abs() < 1.1, "{c:?}");
        assert!(o.list[1].polygon.len() >= 4);
    }

    #[test]
    fn one_piece_is_one_object_named_after_the_design() {
        let tp = Toolpath { passes: vec![Pass::layer(0.2, 0.2, vec![square(0.0, 0.0, 10.0, 0.2), square(5.0, 5.0, 10.0, 0.2)])] };
        let o = find(&tp, DVec3::ZERO, "");
        assert_eq!(o.list.len(), 1);
        assert_eq!(o.list[0].name, "part");
        assert_eq!(o.of_path, vec![Some(0), Some(0)]);
    }

    #[test]
    fn the_skirt_and_brim_belong_to_no_object() {
        let mut skirt = square(-5.0, -5.0, 20.0, 0.2);
        skirt.feature = Feature::Skirt;
        // A skirt round one part, and a skirt round two parts apart.
        let one = Toolpath { passes: vec![Pass::layer(0.2, 0.2, vec![skirt.clone(), square(0.0, 0.0, 10.0, 0.2)])] };
        let o = find(&one, DVec3::ZERO, "cube");
        assert_eq!(o.list.len(), 1);
        assert_eq!(o.of_path, vec![None, Some(0)]);
        assert!(o.list[0].polygon.iter().all(|p| p[0] >= -0.01 && p[0] <= 10.01), "the outline is the part's: {:?}", o.list[0].polygon);
        let mut wide = square(-5.0, -5.0, 60.0, 0.2);
        wide.feature = Feature::Skirt;
        let two = Toolpath { passes: vec![Pass::layer(0.2, 0.2, vec![wide, square(0.0, 0.0, 10.0, 0.2), square(40.0, 0.0, 10.0, 0.2)])] };
        let o = find(&two, DVec3::ZERO, "pair");
        assert_eq!(o.list.len(), 2);
        assert_eq!(o.of_path, vec![None, Some(0), Some(1)]);
    }

    #[test]
    fn hull_of_a_square_grid() {
        let h = hull(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.5]]);
        assert_eq!(h, vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
    }
}
