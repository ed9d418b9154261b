//! The layers a foam can be printed from as one thread: one outline per layer, no empty layer
//! inside the stack, no two regions overlapping in a layer; and each outline inset for the
//! raster's turns, refused where it vanishes or splits. The kind `foam` slices the regions with
//! the foundation's slicer and hands the cuts here.

use crate::geom::{DVec2, Polygon};

/// One sliced layer as the checks read it.
#[derive(Clone, Copy, Debug)]
pub struct Cut<'a> {
    /// Top of the layer, mm.
    pub z: f64,
    /// Height the layer was cut at, mm (the same in every region's stack).
    pub slice_z: f64,
    /// The layer's outlines.
    pub regions: &'a [Polygon],
}

/// One layer's outline.
#[derive(Clone, Debug)]
pub struct Layer {
    /// Top of the layer, mm.
    pub z: f64,
    /// The union's one outline.
    pub polygon: Polygon,
}

/// Why the union cannot be printed as one thread.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum LayerError {
    /// A layer with several outlines.
    #[error("the layer at z = {z:.2} mm is {count} separate outlines ({regions}); one continuous thread needs one outline per layer: join the parts, or print them as separate foams")]
    Several {
        /// Top of the layer.
        z: f64,
        /// Outlines.
        count: usize,
        /// The regions in the layer.
        regions: String,
    },
    /// An empty layer between two printed ones.
    #[error("nothing to print at z = {z:.2} mm between regions below and above: the regions do not make one connected foam (close the gap)")]
    Gap {
        /// Top of the layer.
        z: f64,
    },
    /// Two regions overlap in a layer.
    #[error("regions {a} and {b} overlap by {area:.2} mm² in the layer at z = {z:.2} mm; regions must only touch (move or trim one of them)")]
    Overlap {
        /// One region.
        a: String,
        /// The other.
        b: String,
        /// The overlap's area.
        area: f64,
        /// Top of the layer.
        z: f64,
    },
    /// Nothing at all.
    #[error("the regions slice to nothing: check that the meshes are closed solids")]
    Empty,
}

fn polygon_area(shapes: &[Polygon]) -> f64 {
    shapes.iter().map(|p| p.area()).sum()
}

fn contours(p: &[Polygon]) -> Vec<Vec<[f64; 2]>> {
    p.iter().flat_map(|p| std::iter::once(&p.outer).chain(&p.holes)).map(|r| r.iter().map(|q| [q.x, q.y]).collect()).collect()
}

/// Area of the intersection of two sets of polygons, mm².
fn overlap_area(a: &[Polygon], b: &[Polygon]) -> f64 {
    use i_overlay::core::fill_rule::FillRule;
    use i_overlay::core::overlay_rule::OverlayRule;
    use i_overlay::float::single::SingleFloatOverlay;
    let shapes = contours(a).overlay(&contours(b), OverlayRule::Intersect, FillRule::NonZero);
    shapes.iter().flatten().map(|r| crate::geom::signed_area(&r.iter().map(|p| DVec2::new(p[0], p[1])).collect::<Vec<_>>())).sum()
}

/// The per-layer rules: one outline per layer, no empty layer inside the stack, no overlap of
/// two regions in a layer (beyond 0.1 % of the layer's area and 0.01 mm²).
pub fn check_layers(union: &[Cut], per_region: &[Vec<Cut>], names: &[&str]) -> Result<Vec<Layer>, LayerError> {
    let first = union.iter().position(|l| !l.regions.is_empty()).ok_or(LayerError::Empty)?;
    let last = union.iter().rposition(|l| !l.regions.is_empty()).unwrap_or(first);
    let mut out = Vec::new();
    for (k, l) in union.iter().enumerate().take(last + 1).skip(first) {
        // Every slicing starts its stack at the plate with the same heights: layer k of a
        // region is layer k of the union (a lower region just has fewer).
        let here: Vec<(usize, &[Polygon])> = per_region
            .iter()
            .enumerate()
            .filter_map(|(r, layers)| layers.get(k).filter(|x| (x.slice_z - l.slice_z).abs() < 1e-9).map(|x| (r, x.regions)))
            .filter(|(_, p)| !p.is_empty())
            .collect();
        let listed = || here.iter().map(|(r, _)| names[*r]).collect::<Vec<_>>().join(", ");
        if l.regions.is_empty() {
            return Err(LayerError::Gap { z: l.z });
        }
        let total = polygon_area(l.regions);
        let sum: f64 = here.iter().map(|(_, p)| polygon_area(p)).sum();
        if sum > total + total * 1e-3 + 0.01 {
            for (x, (ra, pa)) in here.iter().enumerate() {
                for (rb, pb) in &here[x + 1..] {
                    let area = overlap_area(pa, pb);
                    if area > 0.01 {
                        return Err(LayerError::Overlap { a: names[*ra].into(), b: names[*rb].into(), area, z: l.z });
                    }
                }
            }
        }
        if l.regions.len() > 1 {
            return Err(LayerError::Several { z: l.z, count: l.regions.len(), regions: listed() });
        }
        out.push(Layer { z: l.z, polygon: l.regions[0].clone() });
    }
    Ok(out)
}

/// An outline that cannot be inset for the raster's turns.
#[derive(Debug, thiserror::Error)]
#[error("layer at z = {z:.2} mm: the outline inset by {d:.2} mm {what}; lower the turn inset or the line spacing")]
pub struct InsetError {
    /// Top of the layer, mm.
    pub z: f64,
    /// The inset, mm.
    pub d: f64,
    /// What became of the outline.
    pub what: &'static str,
}

/// `polygon` shrunk by `d` mm (the raster's turns run there); refused when it vanishes or splits.
pub fn inset(polygon: &Polygon, d: f64, z: f64) -> Result<Polygon, InsetError> {
    use i_overlay::mesh::float::outline::offset::OutlineOffset;
    use i_overlay::mesh::float::style::OutlineStyle;
    if d <= 0.0 {
        return Ok(polygon.clone());
    }
    let shape = contours(std::slice::from_ref(polygon));
    let out = shape.outline(&OutlineStyle::new(-d));
    let mut polys: Vec<Polygon> = out
        .iter()
        .filter(|s| !s.is_empty())
        .map(|s| {
            let ring = |r: &Vec<[f64; 2]>| r.iter().map(|p| DVec2::new(p[0], p[1])).collect::<Vec<_>>();
            Polygon { outer: ring(&s[0]), holes: s[1..].iter().map(ring).collect() }
        })
        .filter(|p| p.area() > 1e-9)
        .collect();
    match polys.len() {
        0 => Err(InsetError { z, d, what: "vanishes (the part is too thin)" }),
        1 => Ok(polys.remove(0)),
        _ => Err(InsetError { z, d, what: "splits into several parts (a neck narrower than twice the inset)" }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(x: f64, side: f64) -> Polygon {
        let p = |a: f64, b: f64| DVec2::new(a, b);
        Polygon { outer: vec![p(x, 0.0), p(x + side, 0.0), p(x + side, side), p(x, side)], holes: Vec::new() }
    }

    fn cut(z: f64, regions: &[Polygon]) -> Cut<'_> {
        Cut { z, slice_z: z - 0.5, regions }
    }

    #[test]
    fn one_outline_a_layer_no_gap_no_overlap() {
        let (a, b) = (vec![square(0.0, 10.0)], vec![square(10.0, 10.0)]);
        let both = vec![square(0.0, 20.0)];
        let layers = check_layers(&[cut(1.0, &both)], &[vec![cut(1.0, &a)], vec![cut(1.0, &b)]], &["a", "b"]).unwrap();
        assert_eq!(layers.len(), 1);
        assert!((layers[0].polygon.area() - 400.0).abs() < 1e-9);

        let apart = vec![square(0.0, 10.0), square(30.0, 10.0)];
        let e = check_layers(&[cut(1.0, &apart)], &[vec![cut(1.0, &apart[..1])], vec![cut(1.0, &apart[1..])]], &["a", "b"]).unwrap_err();
        assert!(matches!(e, LayerError::Several { count: 2, .. }), "{e}");

        let e = check_layers(&[cut(1.0, &a), cut(2.0, &[]), cut(3.0, &a)], &[vec![cut(1.0, &a), cut(2.0, &[]), cut(3.0, &a)]], &["a"]).unwrap_err();
        assert_eq!(e, LayerError::Gap { z: 2.0 });

        let over = vec![square(5.0, 10.0)];
        let p = |a: f64, b: f64| DVec2::new(a, b);
        let union = vec![Polygon { outer: vec![p(0.0, 0.0), p(15.0, 0.0), p(15.0, 10.0), p(0.0, 10.0)], holes: Vec::new() }];
        let e = check_layers(&[cut(1.0, &union)], &[vec![cut(1.0, &a)], vec![cut(1.0, &over)]], &["a", "b"]).unwrap_err();
        assert!(matches!(e, LayerError::Overlap { area, .. } if (area - 50.0).abs() < 1e-6), "{e}");
    }

    #[test]
    fn an_inset_that_vanishes_or_splits_is_refused() {
        assert!((inset(&square(0.0, 10.0), 1.0, 0.2).unwrap().area() - 64.0).abs() < 1e-6);
        let e = inset(&square(0.0, 1.0), 1.0, 0.2).unwrap_err();
        assert!(e.to_string().contains("vanishes"), "{e}");
        // Two 10 mm squares joined by a neck 1 mm wide.
        let ring = [
            (0.0, 0.0),
            (10.0, 0.0),
            (10.0, 4.5),
            (20.0, 4.5),
            (20.0, 0.0),
            (30.0, 0.0),
            (30.0, 10.0),
            (20.0, 10.0),
            (20.0, 5.5),
            (10.0, 5.5),
            (10.0, 10.0),
            (0.0, 10.0),
        ];
        let dumbbell = Polygon { outer: ring.iter().map(|&(x, y)| DVec2::new(x, y)).collect(), holes: Vec::new() };
        let e = inset(&dumbbell, 1.0, 0.4).unwrap_err();
        assert!(e.to_string().contains("splits") && e.to_string().contains("z = 0.40 mm"), "{e}");
    }
}
