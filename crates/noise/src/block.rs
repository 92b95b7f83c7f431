//! The linear Gaussian raw terms behind a decimating FIR output filter, generated exactly at the
//! output rate.
//!
//! Behind an output filter the raw processes run at the filter's internal interval, d times the
//! output rate (docs/model.md §3); an output sample reads the filter's L taps. A raw term whose
//! values are a linear read-out x_k = c'·s_k of a Gauss-Markov state (s_{k+1} = Phi s_k + e_k,
//! e_k ~ N(0, Q): white noise with Phi = 0, a random walk with Phi = 1, a Gauss-Markov component,
//! a resonance's two states) needs no raw sample of its own: over the d raw steps between two
//! read-outs, the new state s_{e+d}, the output's share sum_i h_i x_{e+d-i} and the raw values the
//! next window still needs (the last L - 1 - d) are jointly Gaussian given s_e, a linear function
//! of s_e plus a Gaussian of known covariance (Kailath, Sayed & Hassibi, *Linear Estimation*,
//! §9.2: sums of a state-space model's samples are its linear functionals). They are drawn as
//! that joint law, exactly: the state from its marginal N(Phi^d s_e, S) and the rest from its
//! conditional law given the state (the Gaussian conditional, K = X S^-1, R = V - K X'), the
//! conditional remainders of all the channel's terms summed into one draw. Per output sample a
//! term costs its state's dimension in normal draws (and the channel 1 + L - 1 - d) instead of d
//! per sample and state (behind the moving average of 5 taps at 4 times the output rate that
//! `diagnose` fits on the ADIS16405's gx, gy and ax, d = 4).
//!
//! The joint law is the raw model's own: the block path and the raw path are the same process
//! (tested below against the covariance of the raw samples filtered, computed exactly); only the
//! draws differ, each component drawing from a block stream of its own.

// Small matrices (2 x 2 states, a few rows) read as the formulas when indexed.
#![allow(clippy::needless_range_loop)]

use crate::discrete::draws;
use crate::NormalStream;

/// One linear Gaussian recursion at the raw interval: state of dimension 1 or 2 (unused entries
/// 0), read out as its first entry.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Linear {
    pub phi: [[f64; 2]; 2],
    /// Lower Cholesky factor of the innovation covariance Q.
    pub q_chol: [[f64; 2]; 2],
    pub dim: usize,
    /// The state at the raw sample the next output's window starts from (the last read-out).
    pub state: [f64; 2],
}

impl Linear {
    /// A scalar recursion x_{k+1} = phi x_k + sd w_k from `x0`.
    pub fn scalar(phi: f64, sd: f64, x0: f64) -> Linear {
        Linear {
            phi: [[phi, 0.0], [0.0, 0.0]],
            q_chol: [[sd, 0.0], [0.0, 0.0]],
            dim: 1,
            state: [x0, 0.0],
        }
    }

    /// The innovation covariance Q = L L'.
    pub fn q(&self) -> [[f64; 2]; 2] {
        let l = &self.q_chol;
        let mut q = [[0.0; 2]; 2];
        for i in 0..2 {
            for j in 0..2 {
                q[i][j] = l[i][0] * l[j][0] + l[i][1] * l[j][1];
            }
        }
        q
    }
}

/// Where an output's window lies relative to the d (or, for output 0, L - 1) raw samples drawn
/// for it: the weight of each new sample and of the state's own sample, and which new samples
/// the next window still needs.
#[derive(Clone, Debug)]
struct Geometry {
    /// New raw samples (1 ..= m after the state's sample e).
    m: usize,
    /// Weight of new sample j (index j - 1) in the output.
    w_new: Vec<f64>,
    /// Weight of sample e itself.
    w_e: f64,
    /// The new samples kept for the next window, by position j (nearest the read-out last).
    keep: Vec<usize>,
}

impl Geometry {
    /// Output 0 (m = L - 1 new samples after raw sample 0) or a later one (m = d).
    fn new(h: &[f64], m: usize, carried: usize) -> Geometry {
        let tap = |i: usize| h.get(i).copied().unwrap_or(0.0);
        Geometry {
            m,
            w_new: (1..=m).map(|j| tap(m - j)).collect(),
            w_e: tap(m),
            keep: (1..=carried).rev().map(|i| m - i).collect(),
        }
    }
}

/// A component's block coefficients for one geometry: s_new = A s_e + Ls z; the rows of v (the
/// output's share, then the kept samples) = M s_e + K s_new + (remainder, drawn per channel).
#[derive(Clone, Debug)]
struct Coefficients {
    a: [[f64; 2]; 2],
    ls: [[f64; 2]; 2],
    m: Vec<[f64; 2]>,
    k: Vec<[f64; 2]>,
}

type Mat = Vec<Vec<f64>>;

fn mat_mul2(a: &[[f64; 2]; 2], b: &[[f64; 2]; 2]) -> [[f64; 2]; 2] {
    let mut c = [[0.0; 2]; 2];
    for i in 0..2 {
        for j in 0..2 {
            c[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j];
        }
    }
    c
}

/// Lower Cholesky factor of the symmetric positive semi-definite `a` (a pivot at or below 0,
/// rounding's, gives a zero column).
fn cholesky(a: &Mat) -> Mat {
    let n = a.len();
    let mut l = vec![vec![0.0; n]; n];
    for j in 0..n {
        let d = a[j][j] - (0..j).map(|k| l[j][k] * l[j][k]).sum::<f64>();
        if d <= 0.0 {
            continue;
        }
        let djj = d.sqrt();
        l[j][j] = djj;
        for i in j + 1..n {
            let s = a[i][j] - (0..j).map(|k| l[i][k] * l[j][k]).sum::<f64>();
            l[i][j] = s / djj;
        }
    }
    l
}

/// The component's block law for geometry `g`: its coefficients, and the conditional covariance
/// of v given the new state (its share of the channel's remainder).
fn coefficients(c: &Linear, g: &Geometry) -> (Coefficients, Mat) {
    let (dim, m) = (c.dim, g.m);
    let rows = 1 + g.keep.len();
    // Powers Phi^0 .. Phi^m.
    let mut pow = vec![[[1.0, 0.0], [0.0, 1.0]]; m + 1];
    for k in 1..=m {
        pow[k] = mat_mul2(&c.phi, &pow[k - 1]);
    }
    let weight = |k: usize| if k == 0 { g.w_e } else { g.w_new[k - 1] };
    // Read-out row of Phi^p: c' Phi^p = first row.
    let read = |p: usize| pow[p][0];
    // Mean coefficients on s_e.
    let mut mean_v = vec![[0.0; 2]; rows];
    for k in 0..=m {
        for d in 0..2 {
            mean_v[0][d] += weight(k) * read(k)[d];
        }
    }
    for (i, &p) in g.keep.iter().enumerate() {
        mean_v[1 + i] = read(p);
    }
    // The innovation e_j (entering s_j, j = 1..m) reaches s_k (k >= j) through Phi^(k-j); its
    // coefficient rows: the new state (dim rows), then v's rows. Covariance sum_j C_j Q C_j'.
    let q = c.q();
    let n = dim + rows;
    let mut cov = vec![vec![0.0; n]; n];
    let mut cj = vec![[0.0; 2]; n];
    for j in 1..=m {
        for (r, row) in cj.iter_mut().enumerate().take(dim) {
            *row = pow[m - j][r];
        }
        let mut y = [0.0; 2];
        for k in j..=m {
            for d in 0..2 {
                y[d] += weight(k) * read(k - j)[d];
            }
        }
        cj[dim] = y;
        for (i, &p) in g.keep.iter().enumerate() {
            cj[dim + 1 + i] = if p >= j { read(p - j) } else { [0.0; 2] };
        }
        for a in 0..n {
            for b in 0..n {
                let mut s = 0.0;
                for u in 0..dim {
                    for v in 0..dim {
                        s += cj[a][u] * q[u][v] * cj[b][v];
                    }
                }
                cov[a][b] += s;
            }
        }
    }
    // Condition v on the new state: K = X S^-1 (S singular, a term of level 0: K = 0).
    let s: Vec<Vec<f64>> = (0..dim).map(|i| cov[i][..dim].to_vec()).collect();
    let inv = match dim {
        1 if s[0][0] > 0.0 => Some([[1.0 / s[0][0], 0.0], [0.0, 0.0]]),
        2 => {
            let det = s[0][0] * s[1][1] - s[0][1] * s[1][0];
            (det > 0.0 && det.is_finite()).then(|| {
                [
                    [s[1][1] / det, -s[0][1] / det],
                    [-s[1][0] / det, s[0][0] / det],
                ]
            })
        }
        _ => None,
    };
    let mut k = vec![[0.0; 2]; rows];
    if let Some(inv) = inv {
        for (r, kr) in k.iter_mut().enumerate() {
            for d in 0..dim {
                kr[d] = (0..dim).map(|u| cov[dim + r][u] * inv[u][d]).sum();
            }
        }
    }
    let a = pow[m];
    let mut mcoef = vec![[0.0; 2]; rows];
    for r in 0..rows {
        for d in 0..dim {
            mcoef[r][d] = mean_v[r][d] - (0..dim).map(|u| k[r][u] * a[u][d]).sum::<f64>();
        }
    }
    let mut resid = vec![vec![0.0; rows]; rows];
    for r in 0..rows {
        for t in 0..rows {
            let kx: f64 = (0..dim).map(|u| k[r][u] * cov[dim + t][u]).sum();
            resid[r][t] = cov[dim + r][dim + t] - kx;
        }
    }
    let ls_full = cholesky(&s);
    let mut ls = [[0.0; 2]; 2];
    for i in 0..dim {
        for j in 0..dim {
            ls[i][j] = ls_full[i][j];
        }
    }
    let mut a2 = [[0.0; 2]; 2];
    for i in 0..dim {
        for j in 0..dim {
            a2[i][j] = a[i][j];
        }
    }
    (
        Coefficients {
            a: a2,
            ls,
            m: mcoef,
            k,
        },
        resid,
    )
}

/// One output's step of a component: its new state from `s` and the draws `z`; its share added
/// to `v` (the output's, then the kept samples').
#[inline]
fn step(g: &Coefficients, dim: usize, s: &[f64; 2], z: &[f64], v: &mut [f64]) -> [f64; 2] {
    let mut sn = [0.0; 2];
    for (a, sn) in sn.iter_mut().enumerate().take(dim) {
        let mut x = 0.0;
        for b in 0..dim {
            x += g.a[a][b] * s[b] + g.ls[a][b] * z[b];
        }
        *sn = x;
    }
    for (r, v) in v.iter_mut().enumerate() {
        let (m, k) = (&g.m[r], &g.k[r]);
        let mut x = 0.0;
        for b in 0..dim {
            x += m[b] * s[b] + k[b] * sn[b];
        }
        *v += x;
    }
    sn
}

/// A component: its recursion, its coefficients for output 0 and the later ones, its stream
/// and a block's draws from it (its dimension per output sample).
#[derive(Clone, Debug)]
struct Comp {
    lin: Linear,
    coef: [Coefficients; 2],
    rng: NormalStream,
    z: Vec<f64>,
}

/// Scalar components side by side, [`WIDTH`] at a time (padded with zeros), for outputs after
/// the first: their recursions are independent chains, run in one loop so that they overlap (one
/// at a time, each output waited for the last: the block path was a quarter of `imudrift drift`).
/// One output at a time over every group, its rows summed in a register array and written once;
/// the coefficients lane by row in fixed-size arrays, so that the rows go side by side (the same
/// sums in the same order as a row at a time: the same bits).
#[derive(Clone, Debug)]
struct Lanes {
    /// The indices in `comps` of each lane (None: padding).
    idx: [Option<usize>; WIDTH],
    a: [f64; WIDTH],
    l: [f64; WIDTH],
    /// Per lane, per row (the output's share, then the kept samples; rows past the last are 0).
    m: [[f64; MAX_ROWS]; WIDTH],
    k: [[f64; MAX_ROWS]; WIDTH],
}

/// A group's draws for outputs `first..first + zeros.len()` (a padding lane's: `zeros`).
fn lane_draws<'a>(
    comps: &'a [Comp],
    g: &Lanes,
    zeros: &'a [f64],
    first: usize,
) -> [&'a [f64]; WIDTH] {
    let end = first + zeros.len();
    std::array::from_fn(|j| g.idx[j].map_or(zeros, |c| &comps[c].z[first..end]))
}

/// A group's lanes' last states back into their components.
fn write_states(comps: &mut [Comp], g: &Lanes, xs: &[f64; WIDTH]) {
    for (j, c) in g.idx.iter().enumerate() {
        if let Some(c) = c {
            comps[*c].lin.state[0] = xs[j];
        }
    }
}

/// One group of side-by-side lanes over the outputs of `v` when each output has one row (no
/// kept samples), from the states `xs`, returning the last: called group after group, each over
/// every output with its states in registers (the same sums in the same order as
/// [`lanes_over_outputs`]; faster here, where there are no rows to share the loop with).
fn lanes_one_row(
    g: &Lanes,
    mut xs: [f64; WIDTH],
    zg: &[&[f64]; WIDTH],
    v: &mut [f64],
) -> [f64; WIDTH] {
    let (a, l) = (g.a, g.l);
    let m: [f64; WIDTH] = std::array::from_fn(|j| g.m[j][0]);
    let k: [f64; WIDTH] = std::array::from_fn(|j| g.k[j][0]);
    for (i, v) in v.iter_mut().enumerate() {
        let zi: [f64; WIDTH] = std::array::from_fn(|j| zg[j][i]);
        let xn: [f64; WIDTH] = std::array::from_fn(|j| a[j] * xs[j] + l[j] * zi[j]);
        let t: [f64; WIDTH] = std::array::from_fn(|j| m[j] * xs[j] + k[j] * xn[j]);
        *v += (t[0] + t[1]) + (t[2] + t[3]);
        xs = xn;
    }
    xs
}

/// The side-by-side lanes over the outputs of `v` (`rows` values each, `rows <= R`), from their
/// states `x` and draws `z`. Per output and row the lanes' terms m x + k x' sum as
/// (t0 + t1) + (t2 + t3), group after group; R rows at a time across the row index (the rows past
/// `rows` have zero coefficients and are dropped).
fn lanes_over_outputs<const R: usize>(
    side: &[Lanes],
    x: &mut [[f64; WIDTH]],
    z: &[[&[f64]; WIDTH]],
    v: &mut [f64],
    rows: usize,
) {
    for (i, v) in v.chunks_exact_mut(rows).enumerate() {
        // v is 0 here (the lanes add first): the sums start from it.
        let mut acc = [0.0; R];
        for ((g, xg), zg) in side.iter().zip(x.iter_mut()).zip(z) {
            let zi: [f64; WIDTH] = std::array::from_fn(|j| zg[j][i]);
            let xn: [f64; WIDTH] = std::array::from_fn(|j| g.a[j] * xg[j] + g.l[j] * zi[j]);
            let t = |j: usize, r: usize| g.m[j][r] * xg[j] + g.k[j][r] * xn[j];
            for (r, acc) in acc.iter_mut().enumerate() {
                *acc += (t(0, r) + t(1, r)) + (t(2, r) + t(3, r));
            }
            *xg = xn;
        }
        for (v, a) in v.iter_mut().zip(acc) {
            *v = a;
        }
    }
}

const WIDTH: usize = 4;

/// Longest FIR response the block path takes ([`BlockTerms::suits`]).
const MAX_TAPS: usize = 64;
/// Most raw samples a window may reach back before the previous read-out. Each kept sample adds
/// a row to every component's share and a draw to the remainder, and with many the raw path is
/// faster: MTx behind a Bartlett 16 / 8 (7 kept) takes 43-44 ms per 100 000 samples of 6
/// channels here against 22.6-24.5 ms on the raw path (criterion `generate_mtx_filtered/bartlett16_x8`,
/// both paths in one session); with none kept the block path is faster (the fitted ADIS16405's
/// moving average 5 / 4, `generate_mtx_filtered/moving_average5_x4`: 11-12 ms; `drift` of its
/// six runs 72 -> 52 s of CPU). A choice by cost would
/// change which draws a model's filtered channels get, and with them `diagnose`'s fits
/// (docs/drift.md): not made yet.
const MAX_CARRIED: usize = 7;
/// Rows of an output's block: its share and the kept samples.
const MAX_ROWS: usize = 1 + MAX_CARRIED;

/// The channel's block-generated terms (see the module docs).
#[derive(Clone, Debug)]
pub(crate) struct BlockTerms {
    comps: Vec<Comp>,
    side: Vec<Lanes>,
    /// Weights of the carried raw values (oldest first) in a later output.
    w_carried: Vec<f64>,
    /// The carried raw values, summed over the terms (nearest the last read-out last).
    carried: Vec<f64>,
    /// Cholesky factors of the summed conditional remainder, output 0's and the later ones'.
    rest: [[[f64; MAX_ROWS]; MAX_ROWS]; 2],
    rng: NormalStream,
    scratch: Vec<f64>,
    /// Draws of a padding lane (zeros).
    zeros: Vec<f64>,
    /// Per output of a block: the output's share, then the kept samples.
    v: Vec<f64>,
    started: bool,
}

impl BlockTerms {
    /// Whether the FIR response `h` (L taps) read every `d` raw samples suits the block path:
    /// decimation, 2 to [`MAX_TAPS`] taps, and a window reaching back less than one output
    /// interval and at most [`MAX_CARRIED`] raw samples before the previous read-out (the block's law is computed once per run, in
    /// O(L^2) per component; a sensor's decimating FIR filters are far shorter).
    pub fn suits(h: &[f64], d: usize) -> bool {
        let l = h.len();
        d >= 2 && (2..=MAX_TAPS).contains(&l) && l - 1 < 2 * d && l - 1 <= d + MAX_CARRIED
    }

    /// The components behind FIR response `h` read every `d` raw samples
    /// ([`BlockTerms::suits`]), each with its own stream; the remainder's draws from `rng`.
    pub fn new(
        h: &[f64],
        d: usize,
        comps: Vec<(Linear, NormalStream)>,
        rng: NormalStream,
    ) -> BlockTerms {
        let l = h.len();
        let carried = (l - 1).saturating_sub(d);
        debug_assert!(
            Self::suits(h, d),
            "BlockTerms::new of a filter that does not suit"
        );
        let geometries = [
            Geometry::new(h, l - 1, carried),
            Geometry::new(h, d, carried),
        ];
        let rows = 1 + carried;
        let mut rest = [vec![vec![0.0; rows]; rows], vec![vec![0.0; rows]; rows]];
        let comps: Vec<Comp> = comps
            .into_iter()
            .map(|(lin, rng)| {
                let coef = [0, 1].map(|g| {
                    let (coef, r) = coefficients(&lin, &geometries[g]);
                    for (a, b) in rest[g].iter_mut().zip(&r) {
                        for (x, y) in a.iter_mut().zip(b) {
                            *x += y;
                        }
                    }
                    coef
                });
                Comp {
                    lin,
                    coef,
                    rng,
                    z: Vec::new(),
                }
            })
            .collect();
        let scalar: Vec<usize> = (0..comps.len())
            .filter(|&i| comps[i].lin.dim == 1)
            .collect();
        let side = scalar
            .chunks(WIDTH)
            .map(|chunk| {
                let idx: [Option<usize>; WIDTH] = std::array::from_fn(|j| chunk.get(j).copied());
                let get = |j: usize, f: &dyn Fn(&Coefficients) -> f64| {
                    idx[j].map_or(0.0, |c| f(&comps[c].coef[1]))
                };
                let mut lanes = Lanes {
                    idx,
                    a: std::array::from_fn(|j| get(j, &|g| g.a[0][0])),
                    l: std::array::from_fn(|j| get(j, &|g| g.ls[0][0])),
                    m: [[0.0; MAX_ROWS]; WIDTH],
                    k: [[0.0; MAX_ROWS]; WIDTH],
                };
                for j in 0..WIDTH {
                    for r in 0..rows {
                        lanes.m[j][r] = get(j, &|g| g.m[r][0]);
                        lanes.k[j][r] = get(j, &|g| g.k[r][0]);
                    }
                }
                lanes
            })
            .collect();
        BlockTerms {
            comps,
            side,
            w_carried: (1..=carried).rev().map(|i| h[d + i]).collect(),
            carried: vec![0.0; carried],
            rest: rest.map(|r| {
                let c = cholesky(&r);
                std::array::from_fn(|i| {
                    std::array::from_fn(|j| {
                        c.get(i).map_or(0.0, |c| c.get(j).copied().unwrap_or(0.0))
                    })
                })
            }),
            rng,
            scratch: Vec::new(),
            zeros: Vec::new(),
            v: Vec::new(),
            started: false,
        }
    }

    /// Add the terms' share of the next `out.len()` output samples.
    pub fn add(&mut self, out: &mut [f64]) {
        let n = out.len();
        if n == 0 {
            return;
        }
        let rows = 1 + self.carried.len();
        self.v.clear();
        self.v.resize(n * rows, 0.0);
        let first = usize::from(!self.started);
        self.started = true;
        for c in &mut self.comps {
            draws(&mut c.rng, &mut c.z, n * c.lin.dim);
        }
        if first == 1 {
            for c in &mut self.comps {
                let dim = c.lin.dim;
                c.lin.state = step(
                    &c.coef[0],
                    dim,
                    &c.lin.state,
                    &c.z[..dim],
                    &mut self.v[..rows],
                );
            }
        }
        // The side-by-side scalar components, then the others one at a time.
        if !self.side.is_empty() && n > first {
            if self.zeros.len() < n {
                self.zeros.resize(n, 0.0);
            }
            let zeros = &self.zeros[first..n];
            let v = &mut self.v[first * rows..];
            let x_of = |comps: &[Comp], g: &Lanes| -> [f64; WIDTH] {
                std::array::from_fn(|j| g.idx[j].map_or(0.0, |c| comps[c].lin.state[0]))
            };
            if rows == 1 {
                // Group after group, each over every output: nothing allocated per call.
                for g in &self.side {
                    let xs = lanes_one_row(
                        g,
                        x_of(&self.comps, g),
                        &lane_draws(&self.comps, g, zeros, first),
                        v,
                    );
                    write_states(&mut self.comps, g, &xs);
                }
            } else {
                let mut x: Vec<[f64; WIDTH]> =
                    self.side.iter().map(|g| x_of(&self.comps, g)).collect();
                let z: Vec<[&[f64]; WIDTH]> = self
                    .side
                    .iter()
                    .map(|g| lane_draws(&self.comps, g, zeros, first))
                    .collect();
                if rows <= 4 {
                    lanes_over_outputs::<4>(&self.side, &mut x, &z, v, rows);
                } else {
                    lanes_over_outputs::<MAX_ROWS>(&self.side, &mut x, &z, v, rows);
                }
                for (g, xs) in self.side.iter().zip(&x) {
                    write_states(&mut self.comps, g, xs);
                }
            }
        }
        for ci in 0..self.comps.len() {
            if self.side.iter().any(|g| g.idx.contains(&Some(ci))) {
                continue;
            }
            let c = &mut self.comps[ci];
            let (dim, g) = (c.lin.dim, &c.coef[1]);
            let mut s = c.lin.state;
            let v = self.v[first * rows..].chunks_exact_mut(rows);
            if dim == 2 {
                // A resonance: the same sums as `step`, its coefficients in registers.
                let (a, l) = (g.a, g.ls);
                for (v, z) in v.zip(c.z[2 * first..].chunks_exact(2)) {
                    let sn = [
                        a[0][0] * s[0] + l[0][0] * z[0] + (a[0][1] * s[1] + l[0][1] * z[1]),
                        a[1][0] * s[0] + l[1][0] * z[0] + (a[1][1] * s[1] + l[1][1] * z[1]),
                    ];
                    for ((v, m), k) in v.iter_mut().zip(&g.m).zip(&g.k) {
                        *v += m[0] * s[0] + k[0] * sn[0] + (m[1] * s[1] + k[1] * sn[1]);
                    }
                    s = sn;
                }
            } else {
                for (i, v) in (first..n).zip(v) {
                    s = step(g, dim, &s, &c.z[i * dim..(i + 1) * dim], v);
                }
            }
            c.lin.state = s;
        }
        let z = draws(&mut self.rng, &mut self.scratch, n * rows);
        for (i, (v, o)) in self.v.chunks_exact(rows).zip(out.iter_mut()).enumerate() {
            let l = &self.rest[usize::from(i >= first)];
            let zi = &z[i * rows..(i + 1) * rows];
            let mut y = 0.0;
            for (b, zb) in zi.iter().enumerate() {
                y += l[0][b] * zb;
            }
            y += v[0];
            if i >= first {
                for (w, c) in self.w_carried.iter().zip(&self.carried) {
                    y += w * c;
                }
            }
            *o += y;
            for (r, c) in self.carried.iter_mut().enumerate() {
                let mut x = v[1 + r];
                for (b, zb) in zi.iter().enumerate().take(r + 2) {
                    x += l[1 + r][b] * zb;
                }
                *c = x;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::discrete::normal;
    use crate::ImuRng;
    use rand::SeedableRng;

    /// White noise, a random walk, a Gauss-Markov component and a resonance, each with an
    /// initial state of known covariance (drawn here: the model's draws at construction).
    fn components(rng: &mut ImuRng) -> (Vec<Linear>, Vec<[[f64; 2]; 2]>) {
        let res_phi = [[0.95, 0.02], [-3.0, 0.9]];
        let res_chol = [[0.01, 0.0], [0.2, 0.5]];
        let p0: Vec<[[f64; 2]; 2]> = vec![
            [[1.0, 0.0], [0.0, 0.0]],
            [[0.0, 0.0], [0.0, 0.0]],
            [[0.25 / (1.0 - 0.81), 0.0], [0.0, 0.0]],
            [[0.04, 0.0], [0.0, 1.0]],
        ];
        let comps = vec![
            Linear::scalar(0.0, 1.0, normal(rng)),
            Linear::scalar(1.0, 0.3, 0.0),
            Linear::scalar(0.9, 0.5, p0[2][0][0].sqrt() * normal(rng)),
            Linear {
                phi: res_phi,
                q_chol: res_chol,
                dim: 2,
                state: [0.2 * normal(rng), normal(rng)],
            },
        ];
        (comps, p0)
    }

    /// Cov(y_a, y_b) of outputs 0..k of the raw model filtered by `h` and read every `d` raw
    /// samples (output n at raw sample L - 1 + n d), from the raw samples' exact covariance.
    fn exact_cov(comps: &[Linear], p0: &[[[f64; 2]; 2]], h: &[f64], d: usize, k: usize) -> Mat {
        let pre = h.len() - 1;
        let nraw = pre + (k - 1) * d + 1;
        let mut cx = vec![vec![0.0; nraw]; nraw];
        for (c, p) in comps.iter().zip(p0) {
            let q = c.q();
            let tr = |a: &[[f64; 2]; 2]| [[a[0][0], a[1][0]], [a[0][1], a[1][1]]];
            // State covariances P_k.
            let mut ps = vec![*p];
            for i in 1..nraw {
                let pp = mat_mul2(&mat_mul2(&c.phi, &ps[i - 1]), &tr(&c.phi));
                let mut n = [[0.0; 2]; 2];
                for a in 0..2 {
                    for b in 0..2 {
                        n[a][b] = pp[a][b] + q[a][b];
                    }
                }
                ps.push(n);
            }
            for a in 0..nraw {
                let mut f = [[1.0, 0.0], [0.0, 1.0]];
                for b in a..nraw {
                    // Cov(s_b, s_a) = Phi^(b-a) P_a; read-outs: [0][0].
                    let v = mat_mul2(&f, &ps[a])[0][0];
                    cx[a][b] += v;
                    if b != a {
                        cx[b][a] += v;
                    }
                    f = mat_mul2(&c.phi, &f);
                }
            }
        }
        let rows: Vec<Vec<(usize, f64)>> = (0..k)
            .map(|n| (0..h.len()).map(|i| (pre + n * d - i, h[i])).collect())
            .collect();
        (0..k)
            .map(|a| {
                (0..k)
                    .map(|b| {
                        let mut s = 0.0;
                        for &(i, hi) in &rows[a] {
                            for &(j, hj) in &rows[b] {
                                s += hi * hj * cx[i][j];
                            }
                        }
                        s
                    })
                    .collect()
            })
            .collect()
    }

    fn terms(comps: Vec<Linear>, seed: u64) -> Vec<(Linear, NormalStream)> {
        comps
            .into_iter()
            .enumerate()
            .map(|(i, c)| {
                (
                    c,
                    NormalStream::new(ImuRng::seed_from_u64(seed * 16 + i as u64)),
                )
            })
            .collect()
    }

    /// Components and their initial states' covariances.
    type Drawn = (Vec<Linear>, Vec<[[f64; 2]; 2]>);

    /// The outputs 0..K of `BlockTerms::new(h, d, ...)` with the components `draw` gives (their
    /// initial states' covariances beside them), over N runs, against the raw model's exact
    /// covariance: every entry within 4.42 standard errors (two-sided 1e-5 each), the standard
    /// error of a sample covariance of jointly normal values sqrt((s_aa s_bb + s_ab^2) / N).
    fn check_covariance(h: &[f64], d: usize, draw: &dyn Fn(&mut ImuRng) -> Drawn, label: &str) {
        const K: usize = 4;
        const N: usize = 20_000;
        assert!(BlockTerms::suits(h, d));
        let mut rng = ImuRng::seed_from_u64(7);
        let (_, p0) = draw(&mut rng);
        let mut sum = vec![vec![0.0; K]; K];
        for rep in 0..N {
            let (comps, _) = draw(&mut rng);
            let rest = NormalStream::new(ImuRng::seed_from_u64(1_000_000 + rep as u64));
            let mut b = BlockTerms::new(h, d, terms(comps, rep as u64), rest);
            let mut y = [0.0; K];
            b.add(&mut y[..1]);
            b.add(&mut y[1..]);
            for a in 0..K {
                for c in 0..K {
                    sum[a][c] += y[a] * y[c];
                }
            }
        }
        let (comps, _) = draw(&mut rng);
        let exact = exact_cov(&comps, &p0, h, d, K);
        for a in 0..K {
            for c in a..K {
                let est = sum[a][c] / N as f64;
                let se = ((exact[a][a] * exact[c][c] + exact[a][c].powi(2)) / N as f64).sqrt();
                let z = (est - exact[a][c]) / se;
                assert!(
                    z.abs() < 4.42,
                    "h {h:?} d {d} components {label}: cov(y{a}, y{c}) {est} against {} (z = {z:.2})",
                    exact[a][c]
                );
            }
        }
    }

    fn bartlett(l: usize) -> Vec<f64> {
        let w: Vec<f64> = (0..l).map(|i| (i + 1).min(l - i) as f64).collect();
        let s: f64 = w.iter().sum();
        w.into_iter().map(|v| v / s).collect()
    }

    /// The filters of the covariance tests: 1, 0, 4 and 0 raw samples kept before the previous
    /// read-out (rows 2, 1, 5, 1: each of the lanes' paths).
    fn test_filters() -> [(Vec<f64>, usize); 4] {
        [
            (vec![0.1; 10], 8),
            (vec![0.2; 5], 4),
            (bartlett(13), 8),
            (vec![0.5; 2], 4),
        ]
    }

    /// The block path's outputs 0..4 have the raw model's covariance (`check_covariance`; 10
    /// entries, 5 sets of components and 4 filters: a false alarm in about 2e-3 of runs).
    #[test]
    fn outputs_have_the_raw_models_covariance() {
        // All four together, then each alone (a slow component's variance would hide a wrong
        // weight on white noise's samples).
        let sets: [&[usize]; 5] = [&[0, 1, 2, 3], &[0], &[1], &[2], &[3]];
        for (h, d) in test_filters() {
            for set in sets {
                let draw = |rng: &mut ImuRng| {
                    let (c, p) = components(rng);
                    let c: Vec<Linear> = set.iter().map(|&i| c[i]).collect();
                    let p: Vec<[[f64; 2]; 2]> = set.iter().map(|&i| p[i]).collect();
                    (c, p)
                };
                check_covariance(&h, d, &draw, &format!("{set:?}"));
            }
        }
    }

    /// Nine scalar components (three groups of side-by-side lanes, the last with one) and a
    /// resonance: each group keeps its own states and draws (a group reading another's, or its
    /// states not carried to the next call, changes the covariance). 4 filters x 10 entries at
    /// 1e-5 each.
    #[test]
    fn many_lanes_have_the_raw_models_covariance() {
        for (h, d) in test_filters() {
            let draw = |rng: &mut ImuRng| {
                let mut c = Vec::new();
                let mut p = Vec::new();
                for _ in 0..3 {
                    let (ci, pi) = components(rng);
                    c.extend_from_slice(&ci[..3]);
                    p.extend_from_slice(&pi[..3]);
                }
                let (ci, pi) = components(rng);
                c.push(ci[3]);
                p.push(pi[3]);
                (c, p)
            };
            check_covariance(&h, d, &draw, "3 x [0, 1, 2] and 3");
        }
    }

    /// The values do not depend on how the outputs are split into calls.
    #[test]
    fn blocks_of_any_length_give_the_same_values() {
        let run = |splits: &[usize]| {
            let mut rng = ImuRng::seed_from_u64(3);
            let (comps, _) = components(&mut rng);
            let rest = NormalStream::new(ImuRng::seed_from_u64(99));
            let mut b = BlockTerms::new(&[0.1; 10], 8, terms(comps, 5), rest);
            let mut y = vec![0.0; 600];
            let mut at = 0;
            for &s in splits {
                b.add(&mut y[at..at + s]);
                at += s;
            }
            y
        };
        let whole = run(&[600]);
        assert_eq!(whole, run(&[1, 2, 597]));
        assert_eq!(whole, run(&[300, 1, 299]));
    }
}
