//! The assembly planner of section III: grows the printed state G by *consistent
//! subassemblies* (definition 3.1), each the lowest-cost one the best-first search finds, so
//! that the largest joint error ε over the whole sequence is minimised and the search never
//! reaches a dead end.
//!
//! One round (strict mode, the cantilever constraint on):
//! 1. a beam joining two stable joints costs nothing (its end joint exists): taken first;
//! 2. otherwise a *subassembly tree* grows from every stable joint free of cantilevers: its
//!    states are simple beam paths from the root (each new joint of a path is a cantilever tip,
//!    so a path never branches), each beam at most once per tree, expanded best-first by the
//!    bottleneck max(ε along the path); a beam is added when its predecessors are printed or
//!    in the path, and its direction is allowed;
//! 3. a path that reaches another stable joint, or two paths of different trees that reach a
//!    common new joint, form a path S between two stable joints: S is consistent when every
//!    predecessor of its beams is printed or in S and its two halves can be ordered; the first
//!    consistent S popped is the cheapest and is added;
//! 4. beams that are cantilevers in the finished design (a hanging path) are candidates once
//!    every other beam at their root is printed.
//!
//! Relaxed mode (no cantilever constraint) is the greedy of the bottleneck problem: at each
//! step the cheapest printable beam. Adding beams only stiffens the frame, so a beam printable
//! at cost ≤ τ stays so, and the greedy reaches the minimal max ε whenever a sequence exists.
//!
//! ε is the tip deflection of the beam being printed under the nominal load, its free end not
//! fused to anything at q (0 when q already exists: "the deflection of existing joints does not
//! appear in the cost function"). The heuristic holds every stable joint rigid (the cantilever
//! path alone); the exact cost takes the whole connected frame ([`frame::Flex`]).
//!
//! Each added subassembly records the ordering the paper asks for: its beams follow every
//! beam of the components it joins; the deadhead stage reorders within these.

use super::frame::{self, Flex, Section, M6, RIGID};
use super::precedence::Constraints;
use glam::DVec3;
use std::cmp::Ordering;
use std::collections::{BTreeMap, BinaryHeap, HashSet};

/// Default number of beams a plan fixes before they are sent ahead ([`plan_sending`]): enough
/// for minutes of printing, few enough to be fixed in a fraction of the plan's time.
pub const DEFAULT_SEND_AHEAD_BEAMS: usize = 200;

/// Default planning budget, s of work at [`WORK_PER_SECOND`] (deterministic: counted, not
/// timed, so a design plans alike on every machine).
pub const DEFAULT_BUDGET_S: f64 = 60.0;
/// Work units a second stands for: one unit is one multiply-add of the exact cost's compliance
/// updates or one tree expansion (measured: about 10⁹ a second natively).
pub const WORK_PER_SECOND: f64 = 1e9;
/// Closing beams between checks of the exact cost's running compliance against a sparse
/// factorisation (see [`frame::Flex::check`]).
pub const REFRESH_CONNECTS: usize = 2048;
/// Most free joints of a design checked so: the factorisation covers the design's whole
/// sparsity, whose fill grows fast (the 6 120-beam tower's 1 920 free joints: 0.3 s and
/// 170 MB a check; four times taller: 30 s and 700 MB).
pub const MAX_CHECKED_JOINTS: usize = 2500;

/// Most tree expansions in one round: a round that needs more is refused (the search is
/// exponential in the worst case, section II.B).
pub const MAX_ROUND_EXPANSIONS: u64 = 20_000_000;

/// The cantilever constraint.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// A joint may carry at most one cantilever (isomalt: heat melts the joint).
    Strict,
    /// No limit on cantilevers.
    Relaxed,
}

/// How ε is computed while planning.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Cost {
    /// The whole connected frame.
    Exact,
    /// The cantilevered path alone, stable joints rigid.
    Heuristic,
}

/// How a plan is made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Cantilever constraint.
    pub mode: Mode,
    /// Cost used to choose.
    pub cost: Cost,
    /// Connection constraint on (off: a beam may start anywhere).
    pub connection: bool,
    /// The beams' section and material.
    pub section: Section,
    /// Load at the tip of the beam being printed, N (straight down).
    pub load_n: f64,
    /// Planning budget, s of counted work ([`WORK_PER_SECOND`]). With the exact cost, past it the
    /// plan goes on with the heuristic cost (a complete sequence, exact up to that point).
    pub budget_s: f64,
}

/// One printed beam.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Step {
    /// Beam index.
    pub beam: usize,
    /// Joint the nozzle starts at.
    pub from: usize,
    /// Joint it ends at.
    pub to: usize,
    /// ε when printed in this plan's order, mm.
    pub cost_mm: f64,
    /// The subassembly it belongs to.
    pub block: usize,
}

/// A consistent subassembly: steps `start..end` of the plan.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Block {
    /// First step.
    pub start: usize,
    /// One past the last step.
    pub end: usize,
    /// Blocks every beam of which this one follows (the components it joins, at its time).
    pub after: Vec<usize>,
    /// Steps of this block that must precede each step (the path before it), as step indices:
    /// `chain[i]` is the step before step `start + i` in its path, or `usize::MAX`.
    pub chain: Vec<usize>,
    /// The search's bottleneck key for this block, mm.
    pub key_mm: f64,
}

/// A finished plan.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Plan {
    /// Steps in the plan's order.
    pub steps: Vec<Step>,
    /// The subassemblies.
    pub blocks: Vec<Block>,
    /// Tree states expanded.
    pub expansions: u64,
    /// Work counted (tree expansions and compliance updates), units of [`WORK_PER_SECOND`].
    pub work: f64,
    /// With the exact cost: the step from which the heuristic cost was used (the budget ran
    /// out); None when the whole plan used the cost asked for.
    pub exact_until: Option<usize>,
    /// Largest number of live joints held by the exact cost's compliance.
    pub peak_live: usize,
    /// Times the exact cost's running compliance was checked against a sparse factorisation
    /// of the printed frame (every [`REFRESH_CONNECTS`] closing beams), and the largest
    /// difference found (relative to the largest compliance entry).
    pub refreshes: usize,
    /// See `refreshes`.
    pub drift: f64,
    /// Planned in bands ([`super::bands`]): the first step of each band (empty: planned whole).
    /// Steps of a band wait for every step of the bands before it.
    pub bands: Vec<usize>,
    /// Steps sent ahead while planning went on ([`plan_sending`]; 0: none): they are printed
    /// first, in the order [`super::deadhead::order`] gives them alone.
    pub sent: usize,
}

impl Plan {
    /// The plan's first `n` steps as a plan of their own (`n` at a block's end).
    pub fn prefix(&self, n: usize) -> Plan {
        Plan {
            steps: self.steps[..n].to_vec(),
            blocks: self.blocks.iter().filter(|b| b.end <= n).cloned().collect(),
            bands: self.bands.iter().copied().filter(|&s| s < n).collect(),
            sent: 0,
            ..*self
        }
    }
}

/// Why a design cannot be printed (with what proves it).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Unconstructable {
    /// Collision precedences in a cycle: each beam must come before the next.
    Cycle {
        /// The cycle's beams.
        beams: Vec<usize>,
    },
    /// Strict mode: the finished design hangs two cantilevers on one joint.
    TwoCantilevers {
        /// The joint.
        joint: usize,
        /// Two beams cantilevered about it.
        beams: [usize; 2],
    },
    /// A beam of a hanging path can only be printed toward its root (steeper than the cone,
    /// pointing down): it would start at a free end that touches nothing.
    HangsDown {
        /// The beam.
        beam: usize,
        /// Its root-side joint.
        joint: usize,
    },
    /// Beams no order can reach: each needs a printed neighbour to start from (in an allowed
    /// direction) or a predecessor that is itself unreachable.
    Unreachable {
        /// The beams (first few).
        beams: Vec<usize>,
        /// How many.
        count: usize,
    },
    /// One round of the search needed more than [`MAX_ROUND_EXPANSIONS`] tree expansions.
    SearchTooLarge {
        /// Beams printed before it stopped.
        printed: usize,
        /// Beams left (first few).
        beams: Vec<usize>,
        /// How many.
        count: usize,
    },
    /// The search found no consistent subassembly in a state (strict mode; deciding this is
    /// NP-complete, section II.B): the beams left.
    NoSubassembly {
        /// Beams printed before it stopped.
        printed: usize,
        /// Beams left (first few).
        beams: Vec<usize>,
        /// How many.
        count: usize,
    },
}

/// The state-independent inputs of a plan.
pub struct Assembly<'a> {
    /// Joint positions, mm.
    pub joints: &'a [DVec3],
    /// Beams (joint pairs).
    pub beams: &'a [[usize; 2]],
    /// Grounded joints.
    pub grounded: &'a [bool],
    /// Directions and precedences.
    pub constraints: &'a Constraints,
}

/// Most beams listed in a reason.
const LISTED: usize = 12;

impl Assembly<'_> {
    /// The joint of beam `b` that is not `j`.
    pub fn other(&self, b: usize, j: usize) -> usize {
        let [p, q] = self.beams[b];
        if p == j {
            q
        } else {
            p
        }
    }
    /// May beam `b` be printed starting at joint `j`?
    pub fn allowed_from(&self, b: usize, j: usize) -> bool {
        if self.beams[b][0] == j {
            self.constraints.forward[b]
        } else {
            self.constraints.backward[b]
        }
    }
}

/// Incidence lists: beams at each joint, ascending.
fn incidence(d: &Assembly) -> Vec<Vec<usize>> {
    let mut inc = vec![Vec::new(); d.joints.len()];
    for (b, &[p, q]) in d.beams.iter().enumerate() {
        inc[p].push(b);
        inc[q].push(b);
    }
    inc
}

/// Stable joints of the graph of `present` beams: grounded, or two internally disjoint paths
/// to the ground (definition 2.3): the joint shares a biconnected block with the ground taken
/// as one super-joint joined to every grounded joint.
pub fn stable_joints(joints: &[DVec3], beams: &[[usize; 2]], grounded: &[bool], inc: &[Vec<usize>], present: &[bool]) -> Vec<bool> {
    let n = joints.len();
    let m = beams.len();
    let ground = n; // the super-joint
    let mut stable: Vec<bool> = grounded.to_vec();
    let grounded_list: Vec<usize> = (0..n).filter(|&j| grounded[j]).collect();
    let other = |b: usize, v: usize| if beams[b][0] == v { beams[b][1] } else { beams[b][0] };
    // The k-th edge of v: (neighbour, edge id); beams are 0..m, ground edges m + j.
    let edge = |v: usize, k: usize| -> Option<(usize, usize)> {
        if v == ground {
            return grounded_list.get(k).map(|&j| (j, m + j));
        }
        let mut seen = 0;
        for &b in &inc[v] {
            if present[b] {
                if seen == k {
                    return Some((other(b, v), b));
                }
                seen += 1;
            }
        }
        (grounded[v] && seen == k).then_some((ground, m + v))
    };
    // Iterative Tarjan (edge stack) from the ground.
    let mut disc = vec![u32::MAX; n + 1];
    let mut low = vec![0u32; n + 1];
    let mut time = 1u32;
    disc[ground] = 0;
    let mut estack: Vec<(usize, usize)> = Vec::new();
    let mut stack: Vec<(usize, usize, usize)> = vec![(ground, usize::MAX, 0)];
    while let Some(&mut (v, pe, ref mut k)) = stack.last_mut() {
        let next = edge(v, *k);
        *k += 1;
        match next {
            Some((w, e)) => {
                if e == pe {
                    continue;
                }
                if disc[w] == u32::MAX {
                    disc[w] = time;
                    low[w] = time;
                    time += 1;
                    estack.push((v, w));
                    stack.push((w, e, 0));
                } else if disc[w] < disc[v] {
                    low[v] = low[v].min(disc[w]);
                    estack.push((v, w));
                }
            }
            None => {
                stack.pop();
                if let Some(&(u, _, _)) = stack.last() {
                    low[u] = low[u].min(low[v]);
                    if low[v] >= disc[u] {
                        // The block of edge (u, v): popped off the edge stack.
                        let mut block: Vec<usize> = Vec::new();
                        let mut edges = 0;
                        while let Some((a, b)) = estack.pop() {
                            block.push(a);
                            block.push(b);
                            edges += 1;
                            if a == u && b == v {
                                break;
                            }
                        }
                        // With the ground and more than one edge: a cycle through the ground.
                        if edges > 1 && block.contains(&ground) {
                            for x in block {
                                if x != ground {
                                    stable[x] = true;
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    stable
}

/// The cantilevered beams of the finished design and, for strict mode, its hanging paths.
struct Hanging {
    /// Per beam: cantilevered in the finished design.
    cantilever: Vec<bool>,
    /// Per hanging beam: its root-side joint.
    root_side: Vec<usize>,
}

fn hanging(d: &Assembly, inc: &[Vec<usize>], stable: &[bool]) -> Hanging {
    let m = d.beams.len();
    let mut cantilever = vec![false; m];
    let mut root_side = vec![usize::MAX; m];
    // Walk out from stable joints along beams into unstable joints (BFS), recording the side
    // each beam is reached from.
    let mut queue: std::collections::VecDeque<usize> = (0..d.joints.len()).filter(|&j| stable[j]).collect();
    let mut reached: Vec<bool> = stable.to_vec();
    while let Some(j) = queue.pop_front() {
        for &b in &inc[j] {
            let o = d.other(b, j);
            if !stable[j] || !stable[o] {
                if root_side[b] == usize::MAX && (!stable[o] || stable[j]) {
                    cantilever[b] = true;
                    root_side[b] = j;
                }
                if !reached[o] {
                    reached[o] = true;
                    queue.push_back(o);
                }
            }
        }
    }
    Hanging { cantilever, root_side }
}

/// Tip deflection (mm) of compliance `c` under `load` N straight down.
fn eps(c: &M6, load: f64) -> f64 {
    frame::displacement(c, DVec3::new(0.0, 0.0, -load)).length()
}

/// Precomputed checks that prove a design unconstructable before any search.
fn proofs(d: &Assembly, inc: &[Vec<usize>], mode: Mode, connection: bool) -> Result<(Vec<bool>, Hanging), Unconstructable> {
    let m = d.beams.len();
    // 1. Precedence cycles (Tarjan SCC over the precedence graph, iterative).
    if let Some(cycle) = precedence_cycle(d.constraints, m) {
        return Err(Unconstructable::Cycle { beams: cycle });
    }
    let all = vec![true; m];
    let stable = stable_joints(d.joints, d.beams, d.grounded, inc, &all);
    let hang = hanging(d, inc, &stable);
    if mode == Mode::Strict {
        // 2. Two cantilevers about one joint in the finished design.
        let mut about: BTreeMap<usize, usize> = BTreeMap::new();
        for b in 0..m {
            if hang.cantilever[b] {
                let j = hang.root_side[b];
                if let Some(&first) = about.get(&j) {
                    return Err(Unconstructable::TwoCantilevers { joint: j, beams: [first, b] });
                }
                about.insert(j, b);
            }
        }
        // 3. A hanging beam that can only be printed toward its root.
        if connection {
            for b in 0..m {
                if hang.cantilever[b] && !d.allowed_from(b, hang.root_side[b]) {
                    return Err(Unconstructable::HangsDown { beam: b, joint: hang.root_side[b] });
                }
            }
        }
    }
    // 4. Reachability without the cantilever constraint (the AND/OR closure, linear time).
    let reach = relaxed_closure(d, inc, connection);
    let missing: Vec<usize> = (0..m).filter(|&b| !reach[b]).collect();
    if !missing.is_empty() {
        return Err(Unconstructable::Unreachable { count: missing.len(), beams: missing.into_iter().take(LISTED).collect() });
    }
    Ok((stable, hang))
}

/// Beams printable in some order ignoring cantilevers: repeatedly any beam whose predecessors
/// are all printed and which starts (in an allowed direction) at a grounded or printed joint.
fn relaxed_closure(d: &Assembly, inc: &[Vec<usize>], connection: bool) -> Vec<bool> {
    let m = d.beams.len();
    let mut printed = vec![false; m];
    let mut touched: Vec<bool> = d.grounded.to_vec();
    let mut waiting: Vec<u32> = (0..m).map(|b| d.constraints.preds(b).len() as u32).collect();
    let startable = |b: usize, touched: &[bool]| {
        let [p, q] = d.beams[b];
        !connection || (touched[p] && d.allowed_from(b, p)) || (touched[q] && d.allowed_from(b, q))
    };
    let mut queue: Vec<usize> = (0..m).filter(|&b| waiting[b] == 0 && startable(b, &touched)).collect();
    let mut queued = vec![false; m];
    for &b in &queue {
        queued[b] = true;
    }
    while let Some(b) = queue.pop() {
        printed[b] = true;
        let mut fresh: Vec<usize> = Vec::new();
        for j in d.beams[b] {
            if !touched[j] {
                touched[j] = true;
                fresh.extend(inc[j].iter().copied());
            }
        }
        for &s in d.constraints.succs(b) {
            waiting[s as usize] -= 1;
            fresh.push(s as usize);
        }
        for c in fresh {
            if !queued[c] && waiting[c] == 0 && startable(c, &touched) {
                queued[c] = true;
                queue.push(c);
            }
        }
    }
    printed
}

/// A cycle of the precedence graph, if any.
fn precedence_cycle(c: &Constraints, m: usize) -> Option<Vec<usize>> {
    // Colour DFS (iterative); a back edge closes a cycle read from the stack.
    let mut colour = vec![0u8; m];
    let mut parent = vec![usize::MAX; m];
    for s in 0..m {
        if colour[s] != 0 {
            continue;
        }
        let mut stack: Vec<(usize, usize)> = vec![(s, 0)];
        colour[s] = 1;
        while let Some(&mut (v, ref mut k)) = stack.last_mut() {
            let succ = c.succs(v);
            if *k < succ.len() {
                let w = succ[*k] as usize;
                *k += 1;
                if colour[w] == 0 {
                    colour[w] = 1;
                    parent[w] = v;
                    stack.push((w, 0));
                } else if colour[w] == 1 {
                    let mut cycle = vec![w];
                    let mut x = v;
                    while x != w && cycle.len() <= m {
                        cycle.push(x);
                        x = parent[x];
                    }
                    cycle.reverse();
                    // Start at the smallest beam for a stable message.
                    let at = cycle.iter().enumerate().min_by_key(|(_, &b)| b).map_or(0, |(i, _)| i);
                    cycle.rotate_left(at);
                    return Some(cycle);
                }
            } else {
                colour[v] = 2;
                stack.pop();
            }
        }
    }
    None
}

/// A tree state: a path from a root, ending at `tip` by `beam`.
struct State {
    root: usize,
    parent: usize, // state index, or NONE for the first beam
    beam: usize,
    tip: usize,
    /// Compliance at the tip (the path hanging from the root).
    c: M6,
    /// Bottleneck ε along the path, mm.
    max: f64,
    depth: usize,
}

const NONE: usize = usize::MAX;

/// A queued expansion: the state `parent` (or a root) grows by `beam` to `tip`.
#[derive(PartialEq)]
struct Cand {
    key: f64,
    seq: u64,
    root: usize,
    parent: usize,
    beam: usize,
    tip: usize,
    /// The transition's own ε (the path's tip after it).
    cost: f64,
    /// A final-state cantilever (a one-beam block).
    hang: bool,
}

impl Eq for Cand {}
impl Ord for Cand {
    fn cmp(&self, o: &Self) -> Ordering {
        // Min-heap by key, then by insertion order.
        o.key.total_cmp(&self.key).then(o.seq.cmp(&self.seq))
    }
}
impl PartialOrd for Cand {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// The planner's running state.
struct Planner<'a> {
    d: &'a Assembly<'a>,
    inc: Vec<Vec<usize>>,
    o: Options,
    printed: Vec<bool>,
    /// Joints in the frame (grounded or touched by a printed beam).
    in_frame: Vec<bool>,
    stable: Vec<bool>,
    /// Unprinted beams at each joint.
    open: Vec<u32>,
    /// Joints with a cantilever hanging about them (strict: blocked).
    blocked: Vec<bool>,
    hang: Hanging,
    /// Exact: compliance of the live frame. Heuristic: hanging chains' compliance per joint.
    flex: Flex,
    chain_c: Vec<Option<M6>>,
    /// Components (union-find over joints) and the last block of each.
    parent: Vec<usize>,
    last_block: Vec<usize>,
    plan: Plan,
    /// The cost in use (the exact cost may give way to the heuristic past the budget).
    cost: Cost,
    /// The design's sparsity for checking the running compliance (exact cost; made on first use).
    pattern: Option<frame::Pattern>,
    connects: usize,
    /// Strict mode's free beams to be: unprinted, not a cantilever of the design, both joints
    /// stable and unblocked (kept as joints change, so a round does not scan every joint).
    free: std::collections::BTreeSet<usize>,
}

impl<'a> Planner<'a> {
    fn could_be_free(&self, b: usize) -> bool {
        let [u, w] = self.d.beams[b];
        !self.printed[b] && !self.hang.cantilever[b] && self.stable[u] && self.stable[w] && !self.blocked[u] && !self.blocked[w]
    }

    /// Joint `x` is stable from now on.
    fn mark_stable(&mut self, x: usize) {
        self.stable[x] = true;
        for k in 0..self.inc[x].len() {
            let b = self.inc[x][k];
            if self.could_be_free(b) {
                self.free.insert(b);
            }
        }
    }

    /// Joint `x` carries a cantilever of the design for good.
    fn mark_blocked(&mut self, x: usize) {
        self.blocked[x] = true;
        for &b in &self.inc[x] {
            self.free.remove(&b);
        }
    }

    fn find(&mut self, mut x: usize) -> usize {
        while self.parent[x] != x {
            self.parent[x] = self.parent[self.parent[x]];
            x = self.parent[x];
        }
        x
    }

    fn preds_done(&self, b: usize) -> bool {
        self.d.constraints.preds(b).iter().all(|&p| self.printed[p as usize])
    }

    /// Compliance at joint `j` of the current frame (for a path hanging from it; a joint just
    /// added by a block has its chain's).
    fn root_c(&self, j: usize) -> M6 {
        match self.cost {
            Cost::Exact => self.flex.get(j),
            Cost::Heuristic => {
                if self.stable[j] {
                    RIGID
                } else {
                    self.chain_c[j].unwrap_or(RIGID)
                }
            }
        }
    }

    /// Commits the steps (beam, from, to) as one block.
    fn commit(&mut self, steps: &[(usize, usize, usize)], chain_prev: &[usize], key: f64) {
        let block = self.plan.blocks.len();
        let start = self.plan.steps.len();
        // The components it joins: those of every joint it touches that is already printed
        // (a path's roots and the stable joints it closes onto).
        let mut after: Vec<usize> = Vec::new();
        for &(_, from, to) in steps {
            for j in [from, to] {
                if self.in_frame[j] {
                    let r = self.find(j);
                    let lb = self.last_block[r];
                    if lb != NONE && !after.contains(&lb) {
                        after.push(lb);
                    }
                }
            }
        }
        after.sort_unstable();
        for (i, &(b, from, to)) in steps.iter().enumerate() {
            // ε at print time: 0 onto an existing joint, else the tip of the path from `from`.
            let c_from = self.root_c(from);
            let c_to = frame::extend(&c_from, self.d.joints[from], self.d.joints[to], &self.o.section);
            let cost = if self.in_frame[to] { 0.0 } else { eps(&c_to, self.o.load_n) };
            self.plan.steps.push(Step { beam: b, from, to, cost_mm: cost, block });
            self.printed[b] = true;
            self.free.remove(&b);
            // Frame updates.
            let (pf, pt) = (self.d.joints[from], self.d.joints[to]);
            if self.in_frame[to] {
                if self.cost == Cost::Exact {
                    let dofs = 6.0 * self.flex.live() as f64;
                    self.plan.work += 3.0 * dofs * dofs;
                    self.flex.connect(from, to, pf, pt, &self.o.section);
                    self.connects += 1;
                    if self.connects % REFRESH_CONNECTS == 0 {
                        self.refresh();
                    }
                }
            } else {
                if self.cost == Cost::Exact {
                    self.flex.attach(to, from, pf, pt, &self.o.section);
                }
                self.chain_c[to] = Some(c_to);
                self.in_frame[to] = true;
            }
            let (ra, rb) = (self.find(from), self.find(to));
            if ra != rb {
                self.parent[ra.max(rb)] = ra.min(rb);
            }
            for j in [from, to] {
                self.open[j] -= 1;
                if self.open[j] == 0 && self.cost == Cost::Exact {
                    self.flex.retire(j);
                }
            }
            let _ = i;
        }
        let r = self.find(steps[0].1);
        self.last_block[r] = block;
        self.plan.peak_live = self.plan.peak_live.max(self.flex.live());
        let end = self.plan.steps.len();
        let chain = chain_prev.iter().map(|&p| if p == NONE { NONE } else { start + p }).collect();
        self.plan.blocks.push(Block { start, end, after, chain, key_mm: key });
    }

    /// Checks the exact cost's running compliance against faer's sparse Cholesky of the
    /// printed frame (measures only: see [`frame::Flex::check`]).
    fn refresh(&mut self) {
        let free = self.d.grounded.iter().filter(|&&g| !g).count();
        if free > MAX_CHECKED_JOINTS {
            return;
        }
        if self.pattern.is_none() {
            self.pattern = frame::Pattern::new(self.d.joints, self.d.beams, self.d.grounded, self.o.section).ok();
        }
        if let Some(pattern) = &self.pattern {
            let dofs = pattern.dofs() as f64;
            // Counted as a factorisation plus a solve per live degree of freedom.
            self.plan.work += dofs * 200.0 + 12.0 * dofs * self.flex.live() as f64;
            if let Ok(d) = self.flex.check(pattern, &self.printed) {
                self.plan.refreshes += 1;
                self.plan.drift = self.plan.drift.max(d);
            }
        }
    }

    /// Past the budget, the exact cost gives way to the heuristic (once).
    fn over_budget(&mut self, budget: f64) {
        if self.cost == Cost::Exact && self.plan.work > budget {
            self.cost = Cost::Heuristic;
            self.plan.exact_until = Some(self.plan.steps.len());
            // The heuristic holds stable joints rigid and hanging joints by their chains.
        }
    }

    fn done(&self) -> bool {
        self.printed.iter().all(|&p| p)
    }
}

/// The proofs a design cannot be printed that need no search (precedence cycles, two
/// cantilevers on a joint, a strut hanging down, beams no order reaches).
pub fn prove(d: &Assembly, mode: Mode, connection: bool) -> Result<(), Unconstructable> {
    proofs(d, &incidence(d), mode, connection).map(|_| ())
}

/// Plans the design.
pub fn plan(d: &Assembly, o: &Options, progress: &mut dyn FnMut(usize, usize)) -> Result<Plan, Unconstructable> {
    plan_sending(d, o, 0, progress, &mut |_| {})
}

/// [`plan`], sending its beginning ahead: once `send_at` beams (> 0) are fixed and some are
/// left, `ahead` gets the plan so far. The search only adds to a plan, so those steps are the
/// final plan's first ones; the finished plan records how many were sent ([`Plan::sent`]).
pub fn plan_sending(
    d: &Assembly,
    o: &Options,
    send_at: usize,
    progress: &mut dyn FnMut(usize, usize),
    ahead: &mut dyn FnMut(&Plan),
) -> Result<Plan, Unconstructable> {
    let inc = incidence(d);
    let (_, hang) = proofs(d, &inc, o.mode, o.connection)?;
    let n = d.joints.len();
    let m = d.beams.len();
    let mut p = Planner {
        d,
        o: *o,
        printed: vec![false; m],
        in_frame: d.grounded.to_vec(),
        stable: d.grounded.to_vec(),
        open: inc.iter().map(|l| l.len() as u32).collect(),
        blocked: vec![false; n],
        hang,
        flex: Flex::new(n),
        chain_c: vec![None; n],
        parent: (0..n).collect(),
        last_block: vec![NONE; n],
        plan: Plan::default(),
        cost: o.cost,
        pattern: None,
        connects: 0,
        inc,
        free: Default::default(),
    };
    p.free = (0..m).filter(|&b| p.could_be_free(b)).collect();
    let mut tick = |p: &mut Plan, m: usize| {
        let done = p.steps.len();
        if send_at > 0 && p.sent == 0 && done >= send_at && done < m {
            p.sent = done;
            ahead(p);
        }
        progress(done, m)
    };
    match o.mode {
        Mode::Strict => strict(&mut p, &mut tick)?,
        Mode::Relaxed => relaxed(&mut p, &mut tick)?,
    }
    Ok(p.plan)
}

/// Strict mode: rounds of consistent subassemblies.
fn strict(p: &mut Planner, progress: &mut dyn FnMut(&mut Plan, usize)) -> Result<(), Unconstructable> {
    let m = p.d.beams.len();
    let budget = p.o.budget_s * WORK_PER_SECOND;
    while !p.done() {
        progress(&mut p.plan, m);
        p.over_budget(budget);
        // 1. A beam between two stable, unblocked joints costs nothing: taken first.
        if let Some((b, from, to)) = free_beam(p) {
            p.commit(&[(b, from, to)], &[NONE], 0.0);
            continue;
        }
        // 2.–4. The tree search.
        match search(p) {
            Search::Found(steps, chain, key) => {
                let hangs = steps.len() == 1 && p.hang.cantilever[steps[0].0];
                p.commit(&steps, &chain, key);
                if hangs {
                    // A cantilever of the finished design: its root is blocked for good.
                    p.mark_blocked(steps[0].1);
                } else {
                    for s in &steps {
                        p.mark_stable(s.2);
                    }
                }
            }
            Search::None => {
                let left: Vec<usize> = (0..m).filter(|&b| !p.printed[b]).collect();
                return Err(Unconstructable::NoSubassembly { printed: m - left.len(), count: left.len(), beams: left.into_iter().take(LISTED).collect() });
            }
            Search::Exhausted => {
                let left: Vec<usize> = (0..m).filter(|&b| !p.printed[b]).collect();
                return Err(Unconstructable::SearchTooLarge { printed: m - left.len(), count: left.len(), beams: left.into_iter().take(LISTED).collect() });
            }
        }
    }
    progress(&mut p.plan, m);
    Ok(())
}

/// A beam joining two stable unblocked joints, preds printed, in an allowed direction: the
/// lowest-numbered one (for determinism).
fn free_beam(p: &Planner) -> Option<(usize, usize, usize)> {
    let d = p.d;
    p.free.iter().find_map(|&b| {
        if !p.preds_done(b) {
            return None;
        }
        let [u, w] = d.beams[b];
        let (j, o) = (u.min(w), u.max(w));
        // Upward when allowed, else the allowed way (level: from the lower-numbered joint).
        let (lo, hi) = if d.joints[j].z <= d.joints[o].z { (j, o) } else { (o, j) };
        if d.allowed_from(b, lo) {
            Some((b, lo, hi))
        } else if d.allowed_from(b, hi) {
            Some((b, hi, lo))
        } else {
            None
        }
    })
}

/// The steps of a state's path from its root, in print order.
fn path_of(states: &[State], mut s: usize, d: &Assembly) -> Vec<(usize, usize, usize)> {
    let mut out = Vec::new();
    while s != NONE {
        let st = &states[s];
        let from = d.other(st.beam, st.tip);
        out.push((st.beam, from, st.tip));
        s = st.parent;
    }
    out.reverse();
    out
}

/// A path step as searched: (beam, from joint, to joint).
type PathStep = (usize, usize, usize);

/// Orders the steps of several paths (each in its own order) so every precedence between them
/// holds (Kahn's algorithm on the paths' heads, the first ready path first); None when they
/// block each other (a cycle through them). Returns the steps and each step's path predecessor.
fn merge_chains(chains: &[&[PathStep]], c: &Constraints) -> Option<(Vec<PathStep>, Vec<usize>)> {
    let members: HashSet<usize> = chains.iter().flat_map(|ch| ch.iter().map(|s| s.0)).collect();
    let total: usize = chains.iter().map(|ch| ch.len()).sum();
    let mut head = vec![0usize; chains.len()];
    let mut last = vec![NONE; chains.len()];
    let mut done: HashSet<usize> = HashSet::new();
    let mut out = Vec::with_capacity(total);
    let mut chain = Vec::with_capacity(total);
    while out.len() < total {
        let ready = (0..chains.len()).find(|&k| {
            head[k] < chains[k].len() && c.preds(chains[k][head[k]].0).iter().all(|&q| !members.contains(&(q as usize)) || done.contains(&(q as usize)))
        })?;
        let s = chains[ready][head[ready]];
        done.insert(s.0);
        chain.push(last[ready]);
        last[ready] = out.len();
        out.push(s);
        head[ready] += 1;
    }
    Some((out, chain))
}

/// A closure the search met whose predecessors are not all in it: kept to be joined with
/// others into a set of paths closed under precedence (the paper's general C).
struct Open {
    chains: Vec<Vec<(usize, usize, usize)>>,
    key: f64,
}

/// Most open closures kept in a round, and joined in pairs when nothing else is found.
const MAX_OPEN: usize = 256;

/// What a round's search found.
enum Search {
    /// A consistent subassembly: its steps in order, each step's path predecessor (index in the
    /// steps, or NONE), and its bottleneck key.
    Found(Vec<(usize, usize, usize)>, Vec<usize>, f64),
    /// None exists within the trees.
    None,
    /// The round needed more than [`MAX_ROUND_EXPANSIONS`].
    Exhausted,
}

/// One round's best-first search over the subassembly trees.
fn search(p: &mut Planner) -> Search {
    let d = p.d;
    let load = p.o.load_n;
    let s = p.o.section;
    let mut heap: BinaryHeap<Cand> = BinaryHeap::new();
    let mut states: Vec<State> = Vec::new();
    // States by tip joint (for meetings), and (root, beam) pairs used.
    let mut at_tip: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    let mut used: HashSet<(usize, usize)> = HashSet::new();
    // Beams in some state, with the roots of the trees holding them.
    let mut in_states: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    let mut seq = 0u64;
    // Seeds: every open stable joint's open beams; final cantilevers whose root is ready.
    for r in 0..d.joints.len() {
        if !p.in_frame[r] || !p.stable[r] || p.blocked[r] || p.open[r] == 0 {
            continue;
        }
        let c_r = p.root_c(r);
        for &b in &p.inc[r] {
            if p.printed[b] || !d.allowed_from(b, r) || !p.preds_done(b) {
                continue;
            }
            let x = d.other(b, r);
            if p.hang.cantilever[b] {
                // A hanging beam: from its root side, once every other beam there is printed.
                if p.hang.root_side[b] != r || p.open[r] != 1 {
                    continue;
                }
                let c = frame::extend(&c_r, d.joints[r], d.joints[x], &s);
                let cost = eps(&c, load);
                heap.push(Cand { key: cost, seq, root: r, parent: NONE, beam: b, tip: x, cost, hang: true });
                seq += 1;
                continue;
            }
            let cost = if p.in_frame[x] { 0.0 } else { eps(&frame::extend(&c_r, d.joints[r], d.joints[x], &s), load) };
            heap.push(Cand { key: cost, seq, root: r, parent: NONE, beam: b, tip: x, cost, hang: false });
            seq += 1;
        }
    }
    // Hanging paths continue from their last printed joint (the chain's tip, unstable).
    for j in 0..d.joints.len() {
        if !p.in_frame[j] || p.stable[j] || p.open[j] == 0 {
            continue;
        }
        for &b in &p.inc[j] {
            if !p.printed[b] && p.hang.cantilever[b] && p.hang.root_side[b] == j && d.allowed_from(b, j) && p.preds_done(b) {
                let x = d.other(b, j);
                let c = frame::extend(&p.root_c(j), d.joints[j], d.joints[x], &s);
                let cost = eps(&c, load);
                heap.push(Cand { key: cost, seq, root: j, parent: NONE, beam: b, tip: x, cost, hang: true });
                seq += 1;
            }
        }
    }
    let mut round = 0u64;
    let mut open: Vec<Open> = Vec::new();
    while let Some(cand) = heap.pop() {
        p.plan.expansions += 1;
        p.plan.work += 1.0;
        round += 1;
        if round > MAX_ROUND_EXPANSIONS {
            return Search::Exhausted;
        }
        if cand.hang {
            return Search::Found(vec![(cand.beam, d.other(cand.beam, cand.tip), cand.tip)], vec![NONE], cand.key);
        }
        if !used.insert((cand.root, cand.beam)) {
            continue;
        }
        let x = cand.tip;
        let mut path = if cand.parent == NONE { Vec::new() } else { path_of(&states, cand.parent, d) };
        let from = d.other(cand.beam, x);
        path.push((cand.beam, from, x));
        if p.in_frame[x] {
            // Onto an existing joint: a closure when it is stable, unblocked and not the root.
            if p.stable[x] && !p.blocked[x] && x != cand.root {
                if preds_within(p, &path, &[]) {
                    let chain = (0..path.len()).map(|i| if i == 0 { NONE } else { i - 1 }).collect();
                    return Search::Found(path, chain, cand.key);
                }
                if open.len() < MAX_OPEN {
                    open.push(Open { chains: vec![path], key: cand.key });
                }
            }
            continue;
        }
        // A meeting with another tree's state at x.
        if let Some(list) = at_tip.get(&x) {
            for &u in list {
                if states[u].root == cand.root {
                    continue;
                }
                let other = path_of(&states, u, d);
                if !disjoint(&path, &other, x) {
                    continue;
                }
                let key = cand.key.max(states[u].max);
                if !preds_within(p, &path, &other) {
                    if open.len() < MAX_OPEN {
                        open.push(Open { chains: vec![path.clone(), other], key });
                    }
                    continue;
                }
                if let Some((steps, chain)) = merge_chains(&[&path, &other], d.constraints) {
                    return Search::Found(steps, chain, key);
                }
            }
        }
        // A new state; its extensions.
        let parent_c = if cand.parent == NONE { p.root_c(cand.root) } else { states[cand.parent].c };
        let c = frame::extend(&parent_c, d.joints[from], d.joints[x], &s);
        let id = states.len();
        let depth = if cand.parent == NONE { 1 } else { states[cand.parent].depth + 1 };
        states.push(State { root: cand.root, parent: cand.parent, beam: cand.beam, tip: x, c, max: cand.key, depth });
        at_tip.entry(x).or_default().push(id);
        in_states.entry(cand.beam).or_default().push(cand.root);
        let on_path: HashSet<usize> = path.iter().flat_map(|s| [s.1, s.2]).collect();
        let in_path: HashSet<usize> = path.iter().map(|s| s.0).collect();
        for &b in &p.inc[x] {
            if p.printed[b] || p.hang.cantilever[b] || in_path.contains(&b) || used.contains(&(cand.root, b)) || !d.allowed_from(b, x) {
                continue;
            }
            let y = d.other(b, x);
            if on_path.contains(&y) && y != cand.root {
                continue; // not simple
            }
            if y == cand.root {
                continue; // a loop back to its own root: two cantilevers there
            }
            // Predecessors printed, on this path, or in a state of another tree (the paper's
            // criterion 2; a meeting checks that they come with it).
            let root = cand.root;
            let ok = |q: usize| p.printed[q] || in_path.contains(&q) || in_states.get(&q).is_some_and(|rs| rs.iter().any(|&r| r != root));
            if !d.constraints.preds(b).iter().all(|&q| ok(q as usize)) {
                continue;
            }
            let cost = if p.in_frame[y] { 0.0 } else { eps(&frame::extend(&c, d.joints[x], d.joints[y], &s), load) };
            heap.push(Cand { key: cand.key.max(cost), seq, root: cand.root, parent: id, beam: b, tip: y, cost, hang: false });
            seq += 1;
        }
    }
    join_open(p, &open)
}

/// Nothing closed on its own: two open closures whose predecessors lie in each other, on
/// disjoint joints, cheapest pair first.
fn join_open(p: &mut Planner, open: &[Open]) -> Search {
    let joints = |o: &Open| -> HashSet<usize> { o.chains.iter().flatten().flat_map(|s| [s.1, s.2]).collect() };
    let sets: Vec<HashSet<usize>> = open.iter().map(joints).collect();
    let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
    for i in 0..open.len() {
        for k in i + 1..open.len() {
            if sets[i].is_disjoint(&sets[k]) {
                pairs.push((open[i].key.max(open[k].key), i, k));
            }
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    for (key, i, k) in pairs {
        p.plan.work += 1.0;
        let all: Vec<(usize, usize, usize)> = open[i].chains.iter().chain(&open[k].chains).flatten().copied().collect();
        if !preds_within(p, &all, &[]) {
            continue;
        }
        let chains: Vec<&[(usize, usize, usize)]> = open[i].chains.iter().chain(&open[k].chains).map(|c| c.as_slice()).collect();
        if let Some((steps, chain)) = merge_chains(&chains, p.d.constraints) {
            return Search::Found(steps, chain, key);
        }
    }
    Search::None
}

/// Every predecessor of the beams of `a` ∪ `b` is printed or in `a` ∪ `b`.
fn preds_within(p: &Planner, a: &[(usize, usize, usize)], b: &[(usize, usize, usize)]) -> bool {
    let set: HashSet<usize> = a.iter().chain(b).map(|s| s.0).collect();
    a.iter().chain(b).all(|s| p.d.constraints.preds(s.0).iter().all(|&q| p.printed[q as usize] || set.contains(&(q as usize))))
}

/// Two paths share no beam and no joint but `x`.
fn disjoint(a: &[(usize, usize, usize)], b: &[(usize, usize, usize)], x: usize) -> bool {
    let ja: HashSet<usize> = a.iter().flat_map(|s| [s.1, s.2]).collect();
    b.iter().all(|s| (s.1 == x || !ja.contains(&s.1)) && (s.2 == x || !ja.contains(&s.2))) && {
        let ba: HashSet<usize> = a.iter().map(|s| s.0).collect();
        b.iter().all(|s| !ba.contains(&s.0))
    }
}

/// Relaxed mode: the greedy of the bottleneck problem.
fn relaxed(p: &mut Planner, progress: &mut dyn FnMut(&mut Plan, usize)) -> Result<(), Unconstructable> {
    let d = p.d;
    let m = d.beams.len();
    let load = p.o.load_n;
    let s = p.o.section;
    let budget = p.o.budget_s * WORK_PER_SECOND;
    while !p.done() {
        progress(&mut p.plan, m);
        p.over_budget(budget);
        let mut best: Option<(f64, usize, usize, usize)> = None;
        for b in 0..m {
            if p.printed[b] || !p.preds_done(b) {
                continue;
            }
            let [u, w] = d.beams[b];
            for (from, to) in [(u, w), (w, u)] {
                if (p.o.connection && !p.in_frame[from]) || !d.allowed_from(b, from) {
                    continue;
                }
                let cost = if p.in_frame[to] { 0.0 } else { eps(&frame::extend(&p.root_c(from), d.joints[from], d.joints[to], &s), load) };
                if best.is_none_or(|x| cost < x.0) {
                    best = Some((cost, b, from, to));
                }
            }
        }
        let Some((cost, b, from, to)) = best else {
            let left: Vec<usize> = (0..m).filter(|&b| !p.printed[b]).collect();
            return Err(Unconstructable::Unreachable { count: left.len(), beams: left.into_iter().take(LISTED).collect() });
        };
        p.plan.expansions += 1;
        let closing = p.in_frame[to];
        p.commit(&[(b, from, to)], &[NONE], cost);
        if closing {
            // A loop closed: stability may change anywhere in the component.
            let present = p.printed.clone();
            let st = stable_joints(d.joints, d.beams, d.grounded, &p.inc, &present);
            for j in 0..d.joints.len() {
                if st[j] && !p.stable[j] {
                    p.stable[j] = true;
                }
            }
        }
    }
    progress(&mut p.plan, m);
    Ok(())
}
