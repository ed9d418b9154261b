//! The exact planner for small designs (beyond the paper): the least largest ε over *every*
//! valid sequence, or the proof that no sequence exists, for designs of up to
//! [`DEFAULT_MAX_BEAMS`] beams (at most [`MAX_BEAMS`]: a state is a 64-bit set).
//!
//! Depth-first branch and bound with a shrinking bound. A state is the set S of printed beams:
//! everything that decides what may come next (the joints in the frame, the cantilevers about
//! them, the predecessors done) and what it costs (the frame's compliance) is a function of S
//! alone, so the beam's direction only sets the step's own ε and each beam gives one child
//! (its cheapest allowed direction). The search looks for a sequence whose every ε is below a
//! bound (first the planner's largest ε, when known); each one found lowers the bound to just
//! under its own largest ε and the search starts again. A state explored in full without
//! reaching the end under a bound fails under every lower bound too, so failed states are
//! remembered across restarts. When a search under the bound ends without a sequence, the best
//! one found is optimal (within [`TIE`]), or, with no bound at all, no sequence exists.
//!
//! The constraints are the planner's: connection (a beam starts at a grounded or printed
//! joint, in an allowed direction), the collision precedences, and in strict mode the
//! cantilever rule (a step never heats a joint with a beam cantilevered about it, and after a
//! step no joint carries two). ε is the exact cost (the whole connected frame,
//! [`frame::Flex`], kept incrementally along the search's path).

use super::frame::{self, Flex, Section, M6};
use super::plan::{Assembly, Mode, Step};
use glam::DVec3;
use std::collections::HashSet;

/// Default largest design searched, beams (the "about 30").
pub const DEFAULT_MAX_BEAMS: usize = 32;
/// Largest design the search can take at all: a state is a 64-bit set of beams.
pub const MAX_BEAMS: usize = 64;
/// Default number of states explored before the search gives up (measured: about 50 µs and
/// 20 bytes each on a 30-beam dome).
pub const DEFAULT_MAX_STATES: usize = 100_000;
/// Relative margin by which a sequence must beat the best one known: below it two largest ε
/// are the same up to rounding.
pub const TIE: f64 = 1e-9;

/// How the search runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Cantilever constraint.
    pub mode: Mode,
    /// The beams' section and material.
    pub section: Section,
    /// Load at the tip of the beam being printed, N (straight down).
    pub load_n: f64,
    /// States explored at most.
    pub max_states: usize,
    /// The largest ε of a sequence already known (the planner's, exact cost), mm: the search
    /// looks only for better ones.
    pub known_mm: Option<f64>,
}

impl Options {
    /// The defaults for a section and load.
    pub fn new(mode: Mode, section: Section, load_n: f64) -> Options {
        Options { mode, section, load_n, max_states: DEFAULT_MAX_STATES, known_mm: None }
    }
}

/// What the search found.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Optimum {
    /// A sequence better than the known one (or, with none known, the best found); None when
    /// the known one was not beaten.
    pub steps: Option<Vec<Step>>,
    /// The least largest ε found, mm (the known one's when not beaten); None when no sequence
    /// is known or found.
    pub best_mm: Option<f64>,
    /// The search finished: `best_mm` is the optimum (or, when None, no sequence exists).
    pub proven: bool,
    /// States explored.
    pub states: usize,
    /// Better sequences found one after another (restarts of the search).
    pub improvements: usize,
}

/// Why the search was not run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Error {
    /// More beams than a state can hold.
    #[error("{beams} beams are more than the exact search can take ({MAX_BEAMS}); plan such designs with the planner alone")]
    TooManyBeams {
        /// The design's beams.
        beams: usize,
    },
}

/// The least largest ε over every valid sequence of the design (see the module's text).
pub fn optimum(d: &Assembly, o: &Options, progress: &mut dyn FnMut(usize, usize)) -> Result<Optimum, Error> {
    let m = d.beams.len();
    if m > MAX_BEAMS {
        return Err(Error::TooManyBeams { beams: m });
    }
    let n = d.joints.len();
    let mut inc = vec![Vec::new(); n];
    for (b, &[p, q]) in d.beams.iter().enumerate() {
        inc[p].push(b);
        inc[q].push(b);
    }
    let preds: Vec<u64> = (0..m).map(|b| d.constraints.preds(b).iter().fold(0u64, |s, &p| s | 1 << p)).collect();
    let full = if m == 64 { u64::MAX } else { (1u64 << m) - 1 };
    let mut s = Search {
        d,
        o,
        inc,
        preds,
        full,
        failed: HashSet::new(),
        states: 0,
        limit: f64::INFINITY,
        path: Vec::with_capacity(m),
        found: None,
        exhausted: false,
        progress,
    };
    let mut out = Optimum { best_mm: o.known_mm, ..Optimum::default() };
    if let Some(k) = o.known_mm {
        s.limit = k * (1.0 - TIE);
    }
    loop {
        let root = Node { mask: 0, in_frame: d.grounded.to_vec(), open: s.inc.iter().map(|l| l.len() as u32).collect(), flex: Flex::new(n) };
        if m == 0 {
            out.proven = true;
            out.best_mm = Some(0.0);
            out.steps = Some(Vec::new());
            break;
        }
        if s.limit <= 0.0 {
            out.proven = true;
            break;
        }
        s.found = None;
        if s.dfs(root) {
            let (steps, max) = s.found.take().unwrap_or_default();
            out.improvements += 1;
            out.best_mm = Some(max);
            out.steps = Some(steps);
            s.limit = max * (1.0 - TIE);
            continue;
        }
        out.proven = !s.exhausted;
        break;
    }
    out.states = s.states;
    (s.progress)(s.states, s.states);
    Ok(out)
}

struct Search<'a, 'b> {
    d: &'a Assembly<'a>,
    o: &'a Options,
    inc: Vec<Vec<usize>>,
    preds: Vec<u64>,
    full: u64,
    /// States explored in full without a sequence under the bound in force then.
    failed: HashSet<u64>,
    states: usize,
    /// Every step's ε must be below this, mm.
    limit: f64,
    path: Vec<Step>,
    found: Option<(Vec<Step>, f64)>,
    exhausted: bool,
    progress: &'b mut dyn FnMut(usize, usize),
}

/// A state on the search's path.
struct Node {
    mask: u64,
    /// Joints grounded or touched by a printed beam.
    in_frame: Vec<bool>,
    /// Unprinted beams at each joint (a joint with none leaves the compliance).
    open: Vec<u32>,
    flex: Flex,
}

fn eps(c: &M6, load: f64) -> f64 {
    frame::displacement(c, DVec3::new(0.0, 0.0, -load)).length()
}

impl Search<'_, '_> {
    /// Printed beams (j, x) of `mask` cantilevered about `j`: x is not grounded and cannot
    /// reach the ground over printed beams without passing through j.
    fn cantilevers_about(&self, mask: u64, j: usize) -> usize {
        let d = self.d;
        let mine: Vec<usize> = self.inc[j].iter().copied().filter(|&b| mask >> b & 1 == 1).collect();
        if mine.is_empty() {
            return 0;
        }
        let mut seen = vec![false; d.joints.len()];
        let mut stack: Vec<usize> = (0..d.joints.len()).filter(|&x| d.grounded[x] && x != j).collect();
        for &x in &stack {
            seen[x] = true;
        }
        while let Some(x) = stack.pop() {
            for &b in &self.inc[x] {
                if mask >> b & 1 == 1 {
                    let y = d.other(b, x);
                    if y != j && !seen[y] {
                        seen[y] = true;
                        stack.push(y);
                    }
                }
            }
        }
        mine.into_iter()
            .filter(|&b| {
                let x = d.other(b, j);
                !d.grounded[x] && !seen[x]
            })
            .count()
    }

    /// The children of `node`: per beam that may come next, its cheapest allowed direction
    /// (from, to, ε), cheapest first.
    fn children(&self, node: &Node) -> Vec<(f64, usize, usize, usize)> {
        let d = self.d;
        let mut about: Vec<Option<usize>> = vec![None; d.joints.len()];
        let cant = |j: usize, about: &mut Vec<Option<usize>>| *about[j].get_or_insert_with(|| self.cantilevers_about(node.mask, j));
        let mut out = Vec::new();
        for (b, &[p, q]) in d.beams.iter().enumerate() {
            if node.mask >> b & 1 == 1 || self.preds[b] & !node.mask != 0 {
                continue;
            }
            let mut best: Option<(f64, usize, usize)> = None;
            for (from, to) in [(p, q), (q, p)] {
                if !node.in_frame[from] || !d.allowed_from(b, from) {
                    continue;
                }
                let closing = node.in_frame[to];
                if self.o.mode == Mode::Strict {
                    // No joint it heats may have a beam cantilevered about it ...
                    if cant(from, &mut about) > 0 || (closing && cant(to, &mut about) > 0) {
                        continue;
                    }
                    // ... and afterwards no joint carries two (a new tip hangs alone from a
                    // joint that had none; a closing beam may leave one hanging).
                    if closing {
                        let after = node.mask | 1 << b;
                        if self.cantilevers_about(after, from) > 1 || self.cantilevers_about(after, to) > 1 {
                            continue;
                        }
                    }
                }
                let e = if closing { 0.0 } else { eps(&frame::extend(&node.flex.get(from), d.joints[from], d.joints[to], &self.o.section), self.o.load_n) };
                if best.is_none_or(|(c, _, _)| e < c) {
                    best = Some((e, from, to));
                }
            }
            if let Some((e, from, to)) = best {
                if e < self.limit {
                    out.push((e, b, from, to));
                }
            }
        }
        out.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        out
    }

    /// Searches below `node` for the rest of a sequence under the bound.
    fn dfs(&mut self, node: Node) -> bool {
        if node.mask == self.full {
            let max = self.path.iter().map(|s| s.cost_mm).fold(0.0, f64::max);
            self.found = Some((self.path.clone(), max));
            return true;
        }
        if self.failed.contains(&node.mask) {
            return false;
        }
        if self.states >= self.o.max_states {
            self.exhausted = true;
            return false;
        }
        self.states += 1;
        if self.states % 4096 == 0 {
            (self.progress)(self.states, self.o.max_states);
        }
        let d = self.d;
        for (e, b, from, to) in self.children(&node) {
            let mut flex = node.flex.clone();
            let (a, c) = (d.joints[from], d.joints[to]);
            if node.in_frame[to] {
                flex.connect(from, to, a, c, &self.o.section);
            } else {
                flex.attach(to, from, a, c, &self.o.section);
            }
            let mut open = node.open.clone();
            for j in [from, to] {
                open[j] -= 1;
                if open[j] == 0 {
                    flex.retire(j);
                }
            }
            let mut in_frame = node.in_frame.clone();
            in_frame[from] = true;
            in_frame[to] = true;
            let i = self.path.len();
            self.path.push(Step { beam: b, from, to, cost_mm: e, block: i });
            let hit = self.dfs(Node { mask: node.mask | 1 << b, in_frame, open, flex });
            self.path.pop();
            if hit {
                return true;
            }
            if self.exhausted {
                return false;
            }
        }
        self.failed.insert(node.mask);
        false
    }
}
