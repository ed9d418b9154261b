//! A linear elastic 3D frame by the direct stiffness method (the paper's stability model,
//! section II.B): beams are Euler–Bernoulli frame elements of circular section rigidly joined
//! at their joints, grounded joints are clamped, and a point load acts at one joint.
//!
//! Two tools, one model:
//! - [`Pattern`] assembles the sparse stiffness of any subset of a design's beams on the
//!   design's whole sparsity pattern (joints not in the subset decoupled on an identity), so
//!   the symbolic Cholesky factorisation (ordering, elimination tree, supernodes) is done once
//!   per design and every state pays only the numeric factorisation (faer, sparse `Llt`).
//! - A beam path hanging from one joint is statically determinate: its 6×6 compliance at the
//!   tip follows from the compliance at its root by a rigid transfer plus each element's own
//!   flexibility ([`extend`]), with no solve. The paper's heuristic is this with the root
//!   rigid; the exact cost is the same with the root's compliance in the whole frame
//!   ([`Factored::compliance`]), which is exactly the whole-frame solve (the path is attached
//!   at its root only).
//!
//! Units: mm, N, MPa (N/mm²); displacements in mm, rotations in radians.

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, Side};
use glam::DVec3;

/// Young's modulus of isomalt, MPa (the paper's 2.6 GPa).
pub const DEFAULT_E_MPA: f64 = 2600.0;
/// Shear modulus, MPa (the paper's 1.1 GPa: Poisson's ratio 0.2).
pub const DEFAULT_G_MPA: f64 = 1100.0;
/// The nominal load at the free end of the beam being printed, N (the paper's 10⁻⁴ N).
pub const DEFAULT_LOAD_N: f64 = 1e-4;

/// A 6×6 matrix over (u, θ) at a joint (mm, rad) and (F, M) (N, N·mm), row-major.
pub type M6 = [[f64; 6]; 6];

/// The zero compliance: a rigid (clamped) joint.
pub const RIGID: M6 = [[0.0; 6]; 6];

/// A solid circular section of one material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Section {
    /// Beam diameter, mm.
    pub diameter_mm: f64,
    /// Young's modulus, MPa.
    pub e_mpa: f64,
    /// Shear modulus, MPa.
    pub g_mpa: f64,
}

impl Section {
    /// Area, mm².
    pub fn area(&self) -> f64 {
        std::f64::consts::PI * self.diameter_mm * self.diameter_mm / 4.0
    }
    /// Second moment of area about any diameter, mm⁴.
    pub fn inertia(&self) -> f64 {
        std::f64::consts::PI * self.diameter_mm.powi(4) / 64.0
    }
    /// Polar moment (torsion constant of a solid circle), mm⁴.
    pub fn polar(&self) -> f64 {
        2.0 * self.inertia()
    }
}

fn outer(x: DVec3) -> [[f64; 3]; 3] {
    let v = x.to_array();
    let mut m = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = v[i] * v[j];
        }
    }
    m
}

/// `[x]×`: the matrix of `v ↦ x × v`.
fn skew(x: DVec3) -> [[f64; 3]; 3] {
    [[0.0, -x.z, x.y], [x.z, 0.0, -x.x], [-x.y, x.x, 0.0]]
}

/// The flexibility of the element a→b at b with a clamped, in global axes: (u, θ) at b per
/// (F, M) at b. Axial L/EA, bending L³/3EI, L²/2EI, L/EI, torsion L/GJ (a circular section
/// bends alike about every diameter, so no local y, z axes are needed).
pub fn element_flexibility(a: DVec3, b: DVec3, s: &Section) -> M6 {
    let d = b - a;
    let l = d.length();
    let x = d / l;
    let (ei, ea, gj) = (s.e_mpa * s.inertia(), s.e_mpa * s.area(), s.g_mpa * s.polar());
    let (axial, bend, couple, rot, twist) = (l / ea, l * l * l / (3.0 * ei), l * l / (2.0 * ei), l / ei, l / gj);
    let xx = outer(x);
    let sk = skew(x);
    let mut c = RIGID;
    for i in 0..3 {
        for j in 0..3 {
            let id = if i == j { 1.0 } else { 0.0 };
            c[i][j] = axial * xx[i][j] + bend * (id - xx[i][j]);
            c[3 + i][3 + j] = twist * xx[i][j] + rot * (id - xx[i][j]);
            // u from M: c·(M × x) = −c·[x]× M; θ from F: c·(x × F) = c·[x]× F.
            c[i][3 + j] = -couple * sk[i][j];
            c[3 + i][j] = couple * sk[i][j];
        }
    }
    c
}

/// The compliance `c` at a point p seen at q = p + d through a rigid link:
/// Γ(d)ᵀ c Γ(d), Γ(d) = [[I, 0], [[d]×, I]] (a wrench at q is (F, M + d × F) at p; the motion
/// at q is u + θ × d).
pub fn transfer(c: &M6, d: DVec3) -> M6 {
    let mut g = [[0.0; 6]; 6];
    let sk = skew(d);
    for i in 0..6 {
        g[i][i] = 1.0;
    }
    for i in 0..3 {
        for j in 0..3 {
            g[3 + i][j] = sk[i][j];
        }
    }
    // t = c·Γ, then Γᵀ·t.
    let mut t = [[0.0; 6]; 6];
    for i in 0..6 {
        for j in 0..6 {
            let mut s = 0.0;
            for k in 0..6 {
                s += c[i][k] * g[k][j];
            }
            t[i][j] = s;
        }
    }
    let mut out = [[0.0; 6]; 6];
    for i in 0..6 {
        for j in 0..6 {
            let mut s = 0.0;
            for k in 0..6 {
                s += g[k][i] * t[k][j];
            }
            out[i][j] = s;
        }
    }
    out
}

/// The compliance at b of a path that reached a with compliance `c_a` and goes on by the
/// element a→b.
pub fn extend(c_a: &M6, a: DVec3, b: DVec3, s: &Section) -> M6 {
    let mut c = transfer(c_a, b - a);
    let e = element_flexibility(a, b, s);
    for i in 0..6 {
        for j in 0..6 {
            c[i][j] += e[i][j];
        }
    }
    c
}

/// The displacement (mm) of a point of compliance `c` under a force `f` (N) with no moment.
pub fn displacement(c: &M6, f: DVec3) -> DVec3 {
    let row = |i: usize| c[i][0] * f.x + c[i][1] * f.y + c[i][2] * f.z;
    DVec3::new(row(0), row(1), row(2))
}

/// The local stiffness of a frame element (12×12, DOF order u v w θx θy θz at each end) turned
/// to global axes.
pub fn element_stiffness(a: DVec3, b: DVec3, s: &Section) -> [[f64; 12]; 12] {
    let d = b - a;
    let l = d.length();
    let x = d / l;
    // Any local y ⟂ x (the section is round).
    let helper = if x.z.abs() < 0.9 { DVec3::Z } else { DVec3::X };
    let y = helper.cross(x).normalize();
    let z = x.cross(y);
    let r = [x.to_array(), y.to_array(), z.to_array()];
    let (ei, ea, gj) = (s.e_mpa * s.inertia(), s.e_mpa * s.area(), s.g_mpa * s.polar());
    let mut k = [[0.0; 12]; 12];
    let (a1, t1) = (ea / l, gj / l);
    let (b12, b6, b4, b2) = (12.0 * ei / (l * l * l), 6.0 * ei / (l * l), 4.0 * ei / l, 2.0 * ei / l);
    let mut set = |i: usize, j: usize, v: f64| {
        k[i][j] = v;
        k[j][i] = v;
    };
    set(0, 0, a1);
    set(6, 6, a1);
    set(0, 6, -a1);
    set(3, 3, t1);
    set(9, 9, t1);
    set(3, 9, -t1);
    // v (y) with θz.
    set(1, 1, b12);
    set(7, 7, b12);
    set(1, 7, -b12);
    set(1, 5, b6);
    set(1, 11, b6);
    set(5, 7, -b6);
    set(7, 11, -b6);
    set(5, 5, b4);
    set(11, 11, b4);
    set(5, 11, b2);
    // w (z) with θy.
    set(2, 2, b12);
    set(8, 8, b12);
    set(2, 8, -b12);
    set(2, 4, -b6);
    set(2, 10, -b6);
    set(4, 8, b6);
    set(8, 10, b6);
    set(4, 4, b4);
    set(10, 10, b4);
    set(4, 10, b2);
    // K_g = Tᵀ K T, T = diag(R, R, R, R).
    let mut t = [[0.0; 12]; 12];
    for blk in 0..4 {
        for i in 0..3 {
            for j in 0..3 {
                t[3 * blk + i][3 * blk + j] = r[i][j];
            }
        }
    }
    let mut kt = [[0.0; 12]; 12];
    for i in 0..12 {
        for j in 0..12 {
            let mut s = 0.0;
            for m in 0..12 {
                s += k[i][m] * t[m][j];
            }
            kt[i][j] = s;
        }
    }
    let mut out = [[0.0; 12]; 12];
    for i in 0..12 {
        for j in 0..12 {
            let mut s = 0.0;
            for m in 0..12 {
                s += t[m][i] * kt[m][j];
            }
            out[i][j] = s;
        }
    }
    out
}

/// Why a frame could not be solved.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// The stiffness matrix is not positive definite: a part of the frame can move freely
    /// (not connected to a grounded joint), or a beam is degenerate.
    #[error("the frame's stiffness is singular (a part is not held by a grounded joint, or a beam has no length)")]
    Singular,
    /// faer could not allocate.
    #[error("out of memory factorising the frame ({0})")]
    Memory(String),
}

/// The sparsity of a design's whole frame with its symbolic factorisation: the stiffness of
/// any subset of its beams is assembled on it and factorised numerically only.
pub struct Pattern {
    joints: Vec<DVec3>,
    beams: Vec<[usize; 2]>,
    /// First DOF of each joint, or `usize::MAX` for a grounded (clamped) joint.
    dof: Vec<usize>,
    n: usize,
    /// The lower triangle's pattern: (row, col) of every stored entry, sorted, and the
    /// index of each beam's 78 lower entries and each joint's 21 diagonal-block entries in it.
    entries: Vec<(usize, usize)>,
    beam_slots: Vec<Vec<(usize, usize, usize)>>,
    joint_diag: Vec<Vec<usize>>,
    symbolic: SymbolicLlt<usize>,
    section: Section,
}

/// One numeric factorisation: the frame of a set of beams.
pub struct Factored<'a> {
    pattern: &'a Pattern,
    llt: Llt<usize, f64>,
}

impl Pattern {
    /// The pattern of the frame of `beams` over `joints`, `grounded` joints clamped.
    pub fn new(joints: &[DVec3], beams: &[[usize; 2]], grounded: &[bool], section: Section) -> Result<Pattern, Error> {
        let mut dof = vec![usize::MAX; joints.len()];
        let mut n = 0;
        for (j, g) in grounded.iter().enumerate() {
            if !g {
                dof[j] = n;
                n += 6;
            }
        }
        // Lower-triangle entries: each free joint's diagonal block, each beam's coupling block.
        let mut set = std::collections::BTreeSet::new();
        for j in 0..joints.len() {
            if dof[j] != usize::MAX {
                for r in 0..6 {
                    for c in 0..=r {
                        set.insert((dof[j] + r, dof[j] + c));
                    }
                }
            }
        }
        for &[a, b] in beams {
            if dof[a] != usize::MAX && dof[b] != usize::MAX {
                for r in 0..6 {
                    for c in 0..6 {
                        let (i, k) = (dof[a] + r, dof[b] + c);
                        set.insert((i.max(k), i.min(k)));
                    }
                }
            }
        }
        let entries: Vec<(usize, usize)> = set.into_iter().collect();
        let index = |r: usize, c: usize| entries.binary_search(&(r.max(c), r.min(c))).ok();
        let mut beam_slots = Vec::with_capacity(beams.len());
        for &[a, b] in beams {
            let mut slots = Vec::new();
            for (ea, ja) in [(0usize, a), (6, b)] {
                for (eb, jb) in [(0usize, a), (6, b)] {
                    if dof[ja] == usize::MAX || dof[jb] == usize::MAX {
                        continue;
                    }
                    for r in 0..6 {
                        for c in 0..6 {
                            let (i, k) = (dof[ja] + r, dof[jb] + c);
                            if i >= k {
                                if let Some(slot) = index(i, k) {
                                    slots.push((slot, ea + r, eb + c));
                                }
                            }
                        }
                    }
                }
            }
            beam_slots.push(slots);
        }
        let mut joint_diag = vec![Vec::new(); joints.len()];
        for j in 0..joints.len() {
            if dof[j] != usize::MAX {
                for r in 0..6 {
                    if let Some(slot) = index(dof[j] + r, dof[j] + r) {
                        joint_diag[j].push(slot);
                    }
                }
            }
        }
        let triplets: Vec<Triplet<usize, usize, f64>> = entries.iter().map(|&(r, c)| Triplet::new(r, c, 1.0)).collect();
        let m = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets).map_err(|e| Error::Memory(format!("{e:?}")))?;
        let symbolic = SymbolicLlt::try_new(m.symbolic(), Side::Lower).map_err(|e| Error::Memory(format!("{e:?}")))?;
        Ok(Pattern { joints: joints.to_vec(), beams: beams.to_vec(), dof, n, entries, beam_slots, joint_diag, symbolic, section })
    }

    /// Factorises the frame of the beams where `present[b]`; joints no present beam touches
    /// are decoupled (their solution is 0).
    pub fn factor(&self, present: &[bool]) -> Result<Factored<'_>, Error> {
        let mut values = vec![0.0; self.entries.len()];
        let mut touched = vec![false; self.joints.len()];
        for (b, &[a, c]) in self.beams.iter().enumerate() {
            if !present.get(b).copied().unwrap_or(false) {
                continue;
            }
            touched[a] = true;
            touched[c] = true;
            let k = element_stiffness(self.joints[a], self.joints[c], &self.section);
            for &(slot, r, col) in &self.beam_slots[b] {
                values[slot] += k[r][col];
            }
        }
        for (j, t) in touched.iter().enumerate() {
            if !t {
                for &slot in &self.joint_diag[j] {
                    values[slot] = 1.0;
                }
            }
        }
        let triplets: Vec<Triplet<usize, usize, f64>> = self.entries.iter().zip(&values).map(|(&(r, c), &v)| Triplet::new(r, c, v)).collect();
        let m = SparseColMat::<usize, f64>::try_new_from_triplets(self.n, self.n, &triplets).map_err(|e| Error::Memory(format!("{e:?}")))?;
        let llt = Llt::try_new_with_symbolic(self.symbolic.clone(), m.as_ref(), Side::Lower).map_err(|_| Error::Singular)?;
        Ok(Factored { pattern: self, llt })
    }

    /// Degrees of freedom.
    pub fn dofs(&self) -> usize {
        self.n
    }
}

impl Factored<'_> {
    /// The 6×6 compliance of joint `j` (its motion per unit wrench there); a grounded joint's
    /// is [`RIGID`].
    pub fn compliance(&self, j: usize) -> M6 {
        let p = self.pattern;
        let d = p.dof[j];
        if d == usize::MAX {
            return RIGID;
        }
        let mut rhs = Mat::<f64>::zeros(p.n, 6);
        for k in 0..6 {
            rhs[(d + k, k)] = 1.0;
        }
        let x = self.llt.solve(rhs.as_ref());
        let mut c = RIGID;
        for r in 0..6 {
            for k in 0..6 {
                c[r][k] = x[(d + r, k)];
            }
        }
        c
    }

    /// The displacement of joint `at` under force `f` (N) at joint `at`.
    pub fn deflection(&self, at: usize, f: DVec3) -> DVec3 {
        displacement(&self.compliance(at), f)
    }

    /// The compliance between the joints `joints` (all free): entry (a, b) is the 6×6 motion
    /// of joint `joints[a]` per unit wrench at `joints[b]`, row-major over 6·n.
    pub fn block(&self, joints: &[usize]) -> Vec<f64> {
        let p = self.pattern;
        let k = 6 * joints.len();
        let mut rhs = Mat::<f64>::zeros(p.n, k);
        for (c, &j) in joints.iter().enumerate() {
            for t in 0..6 {
                rhs[(p.dof[j] + t, 6 * c + t)] = 1.0;
            }
        }
        let x = self.llt.solve(rhs.as_ref());
        let mut out = vec![0.0; k * k];
        for (r, &j) in joints.iter().enumerate() {
            for t in 0..6 {
                for c in 0..k {
                    out[(6 * r + t) * k + c] = x[(p.dof[j] + t, c)];
                }
            }
        }
        out
    }
}

/// The compliance of a growing frame, kept dense over its *live* joints (joints that may still
/// take new beams) and updated as beams are added, so every state's exact joint compliance is
/// a lookup (the whole-frame solve done incrementally):
/// - a new joint hanging from a live or grounded one by a beam ([`Flex::attach`]): its row is
///   the rigid transfer of its parent's, plus the beam's own flexibility on the diagonal;
/// - a beam between two joints already in the frame ([`Flex::connect`]): a rank-12 Woodbury
///   update F − F_{·,ab} (I + K_e F_{ab,ab})⁻¹ K_e F_{ab,·} with the element stiffness K_e;
/// - a joint that will take no more beams leaves the set ([`Flex::retire`]): the compliance of
///   the others is unchanged (a sub-block of the same inverse);
/// - a joint held rigid from now on ([`Flex::clamp`]): F − F_{·,j} F_jj⁻¹ F_{j,·}.
///
/// Cost: N² per connected beam for N live degrees of freedom, N per attached joint.
#[derive(Clone, Debug, Default)]
pub struct Flex {
    /// Slot of each joint (index into the matrix's 6-blocks), or `NONE`.
    slot: Vec<u32>,
    /// Joint of each slot (`NONE` when free).
    owner: Vec<u32>,
    /// Free slots (reused before the matrix grows).
    free: Vec<u32>,
    /// Dense (6·cap)² compliance, row-major.
    m: Vec<f64>,
    cap: usize,
}

const NONE: u32 = u32::MAX;
/// Live degrees of freedom above which [`Flex::connect`] updates whole rows (twice the
/// products, streamed) rather than a triangle mirrored (half the products, a cache miss per
/// mirrored entry once the matrix outgrows the cache: 768² doubles are 4.5 MB).
const FULL_ROWS_ABOVE: usize = 768;

impl Flex {
    /// An empty frame over `joints` joints (grounded joints are never live: rigid).
    pub fn new(joints: usize) -> Flex {
        Flex { slot: vec![NONE; joints], owner: Vec::new(), free: Vec::new(), m: Vec::new(), cap: 0 }
    }

    /// Live joints.
    pub fn live(&self) -> usize {
        self.owner.iter().filter(|&&o| o != NONE).count()
    }

    /// Bytes held by the matrix.
    pub fn bytes(&self) -> usize {
        self.m.len() * 8
    }

    /// Whether joint `j` is live.
    pub fn is_live(&self, j: usize) -> bool {
        self.slot[j] != NONE
    }

    fn n(&self) -> usize {
        6 * self.cap
    }

    /// The compliance of joint `j` ([`RIGID`] when it is not live: grounded or clamped).
    pub fn get(&self, j: usize) -> M6 {
        let s = self.slot[j];
        if s == NONE {
            return RIGID;
        }
        let (n, o) = (self.n(), 6 * s as usize);
        let mut c = RIGID;
        for r in 0..6 {
            for k in 0..6 {
                c[r][k] = self.m[(o + r) * n + o + k];
            }
        }
        c
    }

    fn grow(&mut self) {
        let old = self.cap;
        let cap = (old * 2).max(16);
        let (n0, n1) = (6 * old, 6 * cap);
        let mut m = vec![0.0; n1 * n1];
        for r in 0..n0 {
            m[r * n1..r * n1 + n0].copy_from_slice(&self.m[r * n0..r * n0 + n0]);
        }
        self.m = m;
        self.owner.resize(cap, NONE);
        for s in (old..cap).rev() {
            self.free.push(s as u32);
        }
        self.cap = cap;
    }

    fn take_slot(&mut self, j: usize) -> usize {
        if self.free.is_empty() {
            self.grow();
        }
        let s = self.free.pop().unwrap_or(0) as usize;
        self.owner[s] = j as u32;
        self.slot[j] = s as u32;
        s
    }

    /// Joint `q` joins the frame hanging from `p` (live, or rigid: grounded or clamped) by the
    /// element p→q.
    pub fn attach(&mut self, q: usize, p: usize, a: DVec3, b: DVec3, s: &Section) {
        let sq = self.take_slot(q);
        let n = self.n();
        let oq = 6 * sq;
        let e = element_flexibility(a, b, s);
        // Clear q's rows and columns (a reused slot).
        for r in 0..6 {
            self.m[(oq + r) * n..(oq + r) * n + n].fill(0.0);
        }
        for row in 0..n {
            for k in 0..6 {
                self.m[row * n + oq + k] = 0.0;
            }
        }
        if self.slot[p] != NONE {
            let op = 6 * self.slot[p] as usize;
            // Row q = Γᵀ · row p: u_q = u_p − [d]× θ_p, θ_q = θ_p.
            let sk = skew(b - a);
            for col in 0..n {
                let mut pr = [0.0; 6];
                for r in 0..6 {
                    pr[r] = self.m[(op + r) * n + col];
                }
                for r in 0..3 {
                    let mut u = pr[r];
                    for k in 0..3 {
                        u -= sk[r][k] * pr[3 + k];
                    }
                    self.m[(oq + r) * n + col] = u;
                    self.m[(oq + 3 + r) * n + col] = pr[3 + r];
                }
            }
            for row in 0..n {
                for k in 0..6 {
                    self.m[row * n + oq + k] = self.m[(oq + k) * n + row];
                }
            }
            // The diagonal block: Γᵀ F_pp Γ (the column just written from row p is F_qp).
            let fp = {
                let mut c = RIGID;
                for r in 0..6 {
                    for k in 0..6 {
                        c[r][k] = self.m[(op + r) * n + op + k];
                    }
                }
                c
            };
            let t = transfer(&fp, b - a);
            for r in 0..6 {
                for k in 0..6 {
                    self.m[(oq + r) * n + oq + k] = t[r][k];
                }
            }
        }
        for r in 0..6 {
            for k in 0..6 {
                self.m[(oq + r) * n + oq + k] += e[r][k];
            }
        }
    }

    /// The beam a–b joins two joints already in the frame (each live, or rigid). The element
    /// stiffness is Dᵀ C_e⁻¹ D with D = [−Γ(d)ᵀ, I] (the motion of b relative to a carried
    /// rigidly) and C_e its flexibility, so Woodbury reads F − V S⁻¹ Vᵀ with V = F Dᵀ and
    /// S = C_e + D F Dᵀ ≥ C_e: a symmetric rank-6 downdate through a well-conditioned 6×6
    /// Cholesky (the relative flexibility of the two ends plus the beam's own).
    pub fn connect(&mut self, ja: usize, jb: usize, a: DVec3, b: DVec3, s: &Section) {
        let (sa, sb) = (self.slot[ja], self.slot[jb]);
        if sa == NONE && sb == NONE {
            return;
        }
        let n = self.n();
        let sk = skew(b - a);
        // V = F Dᵀ: column block of b minus the rigid transfer of a's (u_b − u_a − θ_a × d,
        // θ_b − θ_a), row by row: V[i] = F[i][b] − (F[i][a] Γ(d)).
        let mut v = vec![0.0; n * 6];
        let live_rows: Vec<usize> = (0..self.cap).filter(|&x| self.owner[x] != NONE).collect();
        for &slot in &live_rows {
            for r in 0..6 {
                let i = 6 * slot + r;
                let row = &self.m[i * n..i * n + n];
                let mut out = [0.0; 6];
                if sb != NONE {
                    let ob = 6 * sb as usize;
                    out.copy_from_slice(&row[ob..ob + 6]);
                }
                if sa != NONE {
                    let oa = 6 * sa as usize;
                    let fa = &row[oa..oa + 6];
                    // (Γᵀ m)_u = m_u − [d]× m_θ, (Γᵀ m)_θ = m_θ, with m = F[i][a] as a motion.
                    for t in 0..3 {
                        let mut u = fa[t];
                        for k in 0..3 {
                            u -= sk[t][k] * fa[3 + k];
                        }
                        out[t] -= u;
                        out[3 + t] -= fa[3 + t];
                    }
                }
                v[i * 6..i * 6 + 6].copy_from_slice(&out);
            }
        }
        // S = C_e + D F Dᵀ = C_e + (rows of V at b) − Γᵀ (rows of V at a).
        let mut sm = element_flexibility(a, b, s);
        let rows_at = |slot: u32, v: &Vec<f64>| -> [[f64; 6]; 6] {
            let mut x = [[0.0; 6]; 6];
            if slot != NONE {
                let o = 6 * slot as usize;
                for r in 0..6 {
                    x[r].copy_from_slice(&v[(o + r) * 6..(o + r) * 6 + 6]);
                }
            }
            x
        };
        let (vb, va) = (rows_at(sb, &v), rows_at(sa, &v));
        for c in 0..6 {
            for t in 0..3 {
                let mut u = va[t][c];
                for k in 0..3 {
                    u -= sk[t][k] * va[3 + k][c];
                }
                sm[t][c] += vb[t][c] - u;
                sm[3 + t][c] += vb[3 + t][c] - va[3 + t][c];
            }
        }
        // Symmetrise, Cholesky S = L Lᵀ, W = V L⁻ᵀ, F −= W Wᵀ (upper triangle, mirrored).
        for r in 0..6 {
            for c in 0..r {
                let x = 0.5 * (sm[r][c] + sm[c][r]);
                sm[r][c] = x;
                sm[c][r] = x;
            }
        }
        let Some(l) = cholesky6(&sm) else { return };
        for &slot in &live_rows {
            for r in 0..6 {
                let i = 6 * slot + r;
                let row = &mut v[i * 6..i * 6 + 6];
                // Solve L w = row (forward substitution): w = L⁻¹ row, i.e. W[i] = V[i] L⁻ᵀ.
                for t in 0..6 {
                    let mut x = row[t];
                    for k in 0..t {
                        x -= l[t][k] * row[k];
                    }
                    row[t] = x / l[t][t];
                }
            }
        }
        let idx: Vec<usize> = live_rows.iter().flat_map(|&s| (0..6).map(move |r| 6 * s + r)).collect();
        if idx.len() <= FULL_ROWS_ABOVE {
            for (x, &i) in idx.iter().enumerate() {
                let wi: [f64; 6] = std::array::from_fn(|t| v[i * 6 + t]);
                for &j in &idx[x..] {
                    let wj = &v[j * 6..j * 6 + 6];
                    let d = wi[0] * wj[0] + wi[1] * wj[1] + wi[2] * wj[2] + wi[3] * wj[3] + wi[4] * wj[4] + wi[5] * wj[5];
                    self.m[i * n + j] -= d;
                    if j != i {
                        self.m[j * n + i] = self.m[i * n + j];
                    }
                }
            }
        } else {
            // A big matrix: whole rows, in memory order (the mirrored writes above miss the
            // cache once per entry). The same bits: the matrix is exactly symmetric and each
            // product sums its six terms in the same order, whichever factor comes first.
            for &i in &idx {
                let wi: [f64; 6] = std::array::from_fn(|t| v[i * 6 + t]);
                let row = &mut self.m[i * n..i * n + n];
                for &j in &idx {
                    let wj = &v[j * 6..j * 6 + 6];
                    row[j] -= wi[0] * wj[0] + wi[1] * wj[1] + wi[2] * wj[2] + wi[3] * wj[3] + wi[4] * wj[4] + wi[5] * wj[5];
                }
            }
        }
    }

    /// Checks the compliance of the live joints against a fresh sparse factorisation of the
    /// frame of the `present` beams (faer's Cholesky on `pattern`): the largest difference of
    /// an entry relative to the largest diagonal entry, the rounding the running updates have
    /// gathered. It only measures: faer's sums run in a SIMD order that differs between
    /// machines, so its numbers must not steer a plan that has to give the same bytes
    /// everywhere; the running updates are plain scalar arithmetic, the same on every target.
    pub fn check(&self, pattern: &Pattern, present: &[bool]) -> Result<f64, Error> {
        let live: Vec<(usize, usize)> = (0..self.cap).filter(|&s| self.owner[s] != NONE).map(|s| (s, self.owner[s] as usize)).collect();
        if live.is_empty() {
            return Ok(0.0);
        }
        let f = pattern.factor(present)?;
        let joints: Vec<usize> = live.iter().map(|&(_, j)| j).collect();
        let fresh = f.block(&joints);
        let (k, n) = (6 * live.len(), self.n());
        let scale = (0..k).map(|i| fresh[i * k + i].abs()).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
        let mut drift: f64 = 0.0;
        for (a, &(sa, _)) in live.iter().enumerate() {
            for (b, &(sb, _)) in live.iter().enumerate() {
                for r in 0..6 {
                    for c in 0..6 {
                        let v = fresh[(6 * a + r) * k + 6 * b + c];
                        drift = drift.max((self.m[(6 * sa + r) * n + 6 * sb + c] - v).abs() / scale);
                    }
                }
            }
        }
        Ok(drift)
    }

    /// Joint `j` will take no more beams: it leaves the live set.
    pub fn retire(&mut self, j: usize) {
        let s = self.slot[j];
        if s != NONE {
            self.owner[s as usize] = NONE;
            self.free.push(s);
            self.slot[j] = NONE;
        }
    }

    /// Joint `j` is held rigid from now on (the heuristic's stable joints), and leaves the set.
    pub fn clamp(&mut self, j: usize) {
        let s = self.slot[j];
        if s == NONE {
            return;
        }
        let n = self.n();
        let o = 6 * s as usize;
        let mut fjj = vec![0.0; 36];
        for r in 0..6 {
            for c in 0..6 {
                fjj[r * 6 + c] = self.m[(o + r) * n + o + c];
            }
        }
        // X = F_jj⁻¹ F_{j,·} (6 × n); F −= F_{·,j} X.
        let mut rows = vec![0.0; 6 * n];
        for r in 0..6 {
            rows[r * n..r * n + n].copy_from_slice(&self.m[(o + r) * n..(o + r) * n + n]);
        }
        let x = {
            let mut out = vec![0.0; 6 * n];
            let a = &mut fjj;
            let lu = lu_factor(a, 6);
            for col in 0..n {
                let mut b = [0.0; 6];
                for r in 0..6 {
                    b[r] = rows[r * n + col];
                }
                lu_solve(a, &lu, &mut b, 6);
                for r in 0..6 {
                    out[r * n + col] = b[r];
                }
            }
            out
        };
        for i in 0..n {
            if self.owner[i / 6] == NONE {
                continue;
            }
            let fi: [f64; 6] = std::array::from_fn(|t| self.m[i * n + o + t]);
            let row = &mut self.m[i * n..i * n + n];
            for jcol in 0..n {
                let mut s = 0.0;
                for t in 0..6 {
                    s += fi[t] * x[t * n + jcol];
                }
                row[jcol] -= s;
            }
        }
        self.retire(j);
    }
}

/// Cholesky factor (lower) of a symmetric positive definite 6×6 matrix.
fn cholesky6(a: &M6) -> Option<M6> {
    let mut l = RIGID;
    for i in 0..6 {
        for j in 0..=i {
            let mut s = a[i][j];
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            if i == j {
                if !(s > 0.0) {
                    return None;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    Some(l)
}

/// LU with partial pivoting of the k×k matrix `a` in place; returns the row permutation.
fn lu_factor(a: &mut [f64], k: usize) -> Vec<usize> {
    let mut perm: Vec<usize> = (0..k).collect();
    for c in 0..k {
        let mut p = c;
        for r in c + 1..k {
            if a[r * k + c].abs() > a[p * k + c].abs() {
                p = r;
            }
        }
        if p != c {
            for t in 0..k {
                a.swap(c * k + t, p * k + t);
            }
            perm.swap(c, p);
        }
        let d = a[c * k + c];
        if d == 0.0 {
            continue;
        }
        for r in c + 1..k {
            let f = a[r * k + c] / d;
            a[r * k + c] = f;
            for t in c + 1..k {
                a[r * k + t] -= f * a[c * k + t];
            }
        }
    }
    perm
}

/// Solves with an [`lu_factor`]ed matrix; `b` is overwritten with the solution.
fn lu_solve(a: &[f64], perm: &[usize], b: &mut [f64], k: usize) {
    let pb: Vec<f64> = perm.iter().map(|&p| b[p]).collect();
    b.copy_from_slice(&pb);
    for r in 0..k {
        for t in 0..r {
            b[r] -= a[r * k + t] * b[t];
        }
    }
    for r in (0..k).rev() {
        for t in r + 1..k {
            b[r] -= a[r * k + t] * b[t];
        }
        let d = a[r * k + r];
        b[r] = if d != 0.0 { b[r] / d } else { 0.0 };
    }
}
