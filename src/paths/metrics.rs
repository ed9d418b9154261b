//! The paper's solution metrics: equation 1 (score), equation 2 (LTS %), equation 3 (OE %)
//! and the long / medium / short path classes.
//!
//! A path with `s` segments has `s + 1` nodes (a closed loop counts its start node twice,
//! as the printed point sequence does).
//!
//! The paper is inconsistent about "long": equation 2's text calls a path long when it has
//! n ≥ 5 nodes, while Figure 2's classes are long > 15, medium 5–15, short < 5 nodes. weft
//! uses **n ≥ 5 nodes** ([`LTS_LONG_MIN_NODES`]) for LTS and OE, as the equations define, and
//! the paper's classes — long **more than** 15 nodes, medium 5–15, short fewer than 5
//! ([`CLASS_LONG_ABOVE_NODES`], [`CLASS_MEDIUM_MIN_NODES`]) — for the histogram counts.

/// A path ("long") counts in equations 2 and 3 from this many nodes.
pub const LTS_LONG_MIN_NODES: usize = 5;
/// Class "long" above this many nodes (medium: [`CLASS_MEDIUM_MIN_NODES`] up to this).
pub const CLASS_LONG_ABOVE_NODES: usize = 15;
/// Class "medium" from this many nodes; fewer is "short".
pub const CLASS_MEDIUM_MIN_NODES: usize = 5;

/// One printed path for the metrics: its length (mm) and number of segments (edges).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Run {
    /// Length, mm.
    pub length: f64,
    /// Segments (graph edges).
    pub segments: usize,
}

/// Equation 1: Σ_i (length_i · NumEdges_i) / (TotalLength · TotalPaths). 0 for no paths.
pub fn score(runs: &[Run]) -> f64 {
    let total: f64 = runs.iter().map(|r| r.length).sum();
    let num: f64 = runs.iter().map(|r| r.length * r.segments as f64).sum();
    if runs.is_empty() || total <= 0.0 {
        0.0
    } else {
        num / (total * runs.len() as f64)
    }
}

/// Equation 2: share of the total length in long paths (≥ 5 nodes), percent.
pub fn lts_percent(runs: &[Run]) -> f64 {
    let total: f64 = runs.iter().map(|r| r.length).sum();
    let long: f64 = runs.iter().filter(|r| r.segments + 1 >= LTS_LONG_MIN_NODES).map(|r| r.length).sum();
    if total <= 0.0 {
        0.0
    } else {
        100.0 * long / total
    }
}

/// Equation 3: Σ_long (length_i · NumEdges_i) / (TotalLength · TotalEdges), percent.
pub fn oe_percent(runs: &[Run]) -> f64 {
    let total: f64 = runs.iter().map(|r| r.length).sum();
    let edges: usize = runs.iter().map(|r| r.segments).sum();
    let num: f64 = runs.iter().filter(|r| r.segments + 1 >= LTS_LONG_MIN_NODES).map(|r| r.length * r.segments as f64).sum();
    if total <= 0.0 || edges == 0 {
        0.0
    } else {
        100.0 * num / (total * edges as f64)
    }
}

/// (long, medium, short) path counts: > 15, 5–15, < 5 nodes.
pub fn classes(runs: &[Run]) -> (usize, usize, usize) {
    let mut c = (0, 0, 0);
    for r in runs {
        let nodes = r.segments + 1;
        if nodes > CLASS_LONG_ABOVE_NODES {
            c.0 += 1;
        } else if nodes >= CLASS_MEDIUM_MIN_NODES {
            c.1 += 1;
        } else {
            c.2 += 1;
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hand_computed() {
        // Paths of 3 mm / 3 edges, 1 mm / 1 edge: (9 + 1) / (4 · 2) = 1.25.
        let runs = [Run { length: 3.0, segments: 3 }, Run { length: 1.0, segments: 1 }];
        assert!((score(&runs) - 1.25).abs() < 1e-15);
        // Nothing has 5 nodes: LTS = OE = 0.
        assert_eq!(lts_percent(&runs), 0.0);
        let runs = [Run { length: 6.0, segments: 4 }, Run { length: 2.0, segments: 2 }];
        assert!((lts_percent(&runs) - 75.0).abs() < 1e-12);
        // 6·4 / (8·6) = 0.5.
        assert!((oe_percent(&runs) - 50.0).abs() < 1e-12);
        assert_eq!(classes(&runs), (0, 1, 1));
        // Paths of 5, 15 and 16 nodes: medium, medium, long; 4 nodes: short.
        let nodes = |n: usize| Run { length: 1.0, segments: n - 1 };
        assert_eq!(classes(&[nodes(5), nodes(15), nodes(16)]), (1, 2, 0));
        assert_eq!(classes(&[nodes(4), nodes(2)]), (0, 0, 2));
    }
}
