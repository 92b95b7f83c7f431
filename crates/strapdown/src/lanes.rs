//! `L` strapdown integrators advanced in lockstep, one per lane (structure of arrays): the
//! mechanisation of [`crate::Scheme`] written once, over lanes. [`crate::Strapdown`] is the
//! one-lane case; the Monte Carlo runner advances several runs at a time, and with the loops over
//! lanes compiled for a wide vector unit one instruction does the same operation for every run.
//!
//! Every lane performs exactly the operations of a one-lane integrator in the same order (no
//! fused multiply-add, no reassociation), so a run's numbers do not depend on the lane it ran in
//! nor on how many runs shared the step (tested in `tests/lanes.rs`).

// Index loops over components and lanes state the arithmetic as written in the sources (and let
// the compiler see the lane loops whole): clearer here than iterator chains.
#![allow(clippy::needless_range_loop)]

use crate::frames::{
    rodrigues_coefficients, rodrigues_entries, rodrigues_series, Attitude, BodyVector, NavVector,
};
use crate::mechanisation::{NavState, Scheme, RENORMALISE_EVERY};
use crate::round_earth::{Origin, RoundEarth, Vertical};
use nalgebra::{Matrix3, Vector3};

/// `[[f64; L]; N]`: component `k` of every lane at `[k][lane]`.
pub type Lanes<const N: usize, const L: usize> = [[f64; L]; N];

/// Samples per chunk of [`StrapdownLanes::integrate`] (eight keep a chunk of eight lanes in the
/// first-level cache).
pub const CHUNK: usize = 8;

/// `L` strapdown integrators (see the module docs).
#[derive(Clone, Debug)]
pub struct StrapdownLanes<const L: usize> {
    scheme: Scheme,
    /// Body-to-navigation direction cosine matrices, row-major: entry (i, j) at `[3 i + j]`.
    c: Lanes<9, L>,
    /// Velocity and position, NED.
    v: Lanes<3, L>,
    p: Lanes<3, L>,
    /// Previous gyro increment `w_{k-1} dt` (rad), for the coning correction.
    previous: Lanes<3, L>,
    /// Gravity in the navigation frame, `(0, 0, +g)` (flat Earth).
    gravity_nav: [f64; 3],
    /// The round Earth (`None`: Woodman's flat one). With it, `p` holds latitude (rad), longitude
    /// (rad) and height (m) (crate::round_earth).
    earth: Option<Origin>,
    /// The round Earth's slowly varying quantities per lane, refreshed every [`EARTH_EVERY`] steps.
    slow: EarthSlow<L>,
    steps_since_renormalise: u32,
}

/// Steps between refreshes of the round Earth's position-dependent quantities (radii, gravity,
/// Earth rate in NED): over 8 steps at 100 Hz a navigator at 100 m/s moves 1.3e-8 rad of latitude,
/// which changes gravity by 5e-10 m/s^2 and the radii by 1e-9 relative, far below any sensor.
pub const EARTH_EVERY: u32 = 8;

/// Per lane: sin L, cos L, tan L, 1 / (R_N + h), 1 / ((R_E + h) cos L), 1 / (R_E + h), normal
/// gravity (crate::round_earth).
#[derive(Clone, Debug)]
struct EarthSlow<const L: usize> {
    sin: [f64; L],
    cos: [f64; L],
    tan: [f64; L],
    inv_re_h_cos: [f64; L],
    inv_rn_h: [f64; L],
    inv_re_h: [f64; L],
    g: [f64; L],
    steps: u32,
}

impl<const L: usize> StrapdownLanes<L> {
    /// Integrators starting at `initial` (one state per lane), gravity `gravity_mps2` down.
    pub fn new(scheme: Scheme, initial: &[NavState; L], gravity_mps2: f64) -> Self {
        let mut s = StrapdownLanes {
            scheme,
            c: [[0.0; L]; 9],
            v: [[0.0; L]; 3],
            p: [[0.0; L]; 3],
            previous: [[0.0; L]; 3],
            gravity_nav: [0.0, 0.0, gravity_mps2],
            earth: None,
            slow: EarthSlow {
                sin: [0.0; L],
                cos: [0.0; L],
                tan: [0.0; L],
                inv_re_h_cos: [0.0; L],
                inv_rn_h: [0.0; L],
                inv_re_h: [0.0; L],
                g: [0.0; L],
                steps: 0,
            },
            steps_since_renormalise: 0,
        };
        for (l, state) in initial.iter().enumerate() {
            let c = state.attitude.matrix();
            for i in 0..3 {
                for j in 0..3 {
                    s.c[3 * i + j][l] = c[(i, j)];
                }
                s.v[i][l] = state.velocity.0[i];
                s.p[i][l] = state.position.0[i];
            }
        }
        s
    }

    /// Integrators on the round, rotating Earth `earth` (crate::round_earth), starting at
    /// `initial` (positions in NED metres from `earth.place`).
    pub fn on_earth(scheme: Scheme, initial: &[NavState; L], earth: RoundEarth) -> Self {
        let mut s = Self::new(scheme, initial, earth.place.gravity_mps2());
        let origin = Origin::new(earth);
        for l in 0..L {
            let geo = origin.geodetic_of([s.p[0][l], s.p[1][l], s.p[2][l]]);
            for k in 0..3 {
                s.p[k][l] = geo[k];
            }
        }
        s.earth = Some(origin);
        s
    }

    /// The round Earth the lanes navigate on (`None`: the flat one).
    pub fn earth(&self) -> Option<RoundEarth> {
        self.earth.map(|o| o.earth)
    }

    /// The gyro sample (rad/s) of the interval before the first step, the same for every lane
    /// (the coning correction of [`Scheme::Accurate`]'s first step).
    pub fn set_previous_gyro(&mut self, gyro: &Vector3<f64>, dt_s: f64) {
        for k in 0..3 {
            self.previous[k] = [gyro[k] * dt_s; L];
        }
    }

    /// The scheme in use.
    pub fn scheme(&self) -> Scheme {
        self.scheme
    }

    /// Lane `lane`'s navigation solution.
    /// On the round Earth the position is NED metres from the start place (crate::round_earth).
    pub fn state(&self, lane: usize) -> NavState {
        let mut p = [self.p[0][lane], self.p[1][lane], self.p[2][lane]];
        if let Some(o) = &self.earth {
            p = o.ned_of(p[0], p[1], p[2]);
        }
        NavState {
            attitude: Attitude(Matrix3::from_fn(|i, j| self.c[3 * i + j][lane])),
            velocity: NavVector(Vector3::from_fn(|i, _| self.v[i][lane])),
            position: NavVector(Vector3::from(p)),
        }
    }

    /// Advance every lane by one sample: `gyro[k][lane]` (rad/s) and `accel[k][lane]` (specific
    /// force, m/s^2), body axis k, interval averages over `[t_k, t_k + dt_s]` (the input
    /// convention of [`crate::Strapdown::step`]).
    #[inline(always)]
    pub fn step(&mut self, gyro: &Lanes<3, L>, accel: &Lanes<3, L>, dt_s: f64) {
        if let Some(origin) = self.earth {
            self.step_round(&origin, gyro, accel, dt_s);
        } else {
            self.step_flat(gyro, accel, dt_s);
        }
        self.steps_since_renormalise += 1;
        if self.steps_since_renormalise >= RENORMALISE_EVERY {
            self.steps_since_renormalise = 0;
            self.c = renormalise(&self.c);
        }
    }

    /// The body's rotation over the step (Woodman eq 41, or the coning-corrected exact one).
    #[inline(always)]
    fn body_rotation(&mut self, gyro: &Lanes<3, L>, dt_s: f64) -> Lanes<9, L> {
        let mut dtheta = [[0.0; L]; 3];
        for k in 0..3 {
            for l in 0..L {
                dtheta[k][l] = gyro[k][l] * dt_s;
            }
        }
        match self.scheme {
            // Woodman eq 41: C(t+dt) = C(t) exp(B), B = [w dt x].
            Scheme::Woodman => so3_exp_lanes(&dtheta),
            Scheme::Accurate => {
                // One-plus-previous-sample coning correction phi = dtheta + (1/12) dtheta_prev x
                // dtheta (G. Yan's PSINS `cnscl.m`, "single sample + previous sample"; Savage 1998,
                // JGCD 21(1) 19-28); its order is measured by tests/order on classical coning.
                let mut phi = [[0.0; L]; 3];
                let q = &self.previous;
                let d = &dtheta;
                for l in 0..L {
                    let cross = [
                        q[1][l] * d[2][l] - q[2][l] * d[1][l],
                        q[2][l] * d[0][l] - q[0][l] * d[2][l],
                        q[0][l] * d[1][l] - q[1][l] * d[0][l],
                    ];
                    for k in 0..3 {
                        phi[k][l] = d[k][l] + cross[k] * (1.0 / 12.0);
                    }
                }
                self.previous = dtheta;
                // Exact rotation for the (corrected) constant-rate increment, Woodman eq 41.
                so3_exp_lanes(&phi)
            }
        }
    }

    /// One step on Woodman's flat, non-rotating Earth.
    #[inline(always)]
    fn step_flat(&mut self, gyro: &Lanes<3, L>, accel: &Lanes<3, L>, dt_s: f64) {
        let c_old = self.c;
        let rotation = self.body_rotation(gyro, dt_s);
        self.c = mat_mul(&c_old, &rotation);
        match self.scheme {
            Scheme::Woodman => {
                // Eq 42 with the newly rotated sample, eq 45 (gravity +g down), eq 46 with v(t+dt).
                let a_nav = mat_vec(&self.c, accel);
                for k in 0..3 {
                    for l in 0..L {
                        let v_new = self.v[k][l] + dt_s * (a_nav[k][l] + self.gravity_nav[k]);
                        self.p[k][l] += dt_s * v_new;
                        self.v[k][l] = v_new;
                    }
                }
            }
            Scheme::Accurate => {
                // Trapezoidal rule for eq 43, (C_k + C_{k+1}) f / 2 (one matrix-vector product),
                // and for eq 44.
                let a = sum_times(&c_old, &self.c, accel);
                for k in 0..3 {
                    for l in 0..L {
                        let v_old = self.v[k][l];
                        let v_new = v_old + dt_s * (0.5 * a[k][l] + self.gravity_nav[k]);
                        self.p[k][l] += (0.5 * dt_s) * (v_old + v_new);
                        self.v[k][l] = v_new;
                    }
                }
            }
        }
    }

    /// One step on the round, rotating Earth (crate::round_earth: Groves eqs 5.45, 5.53, 5.56).
    /// The position-dependent quantities are refreshed every [`EARTH_EVERY`] steps, the transport
    /// rate and Coriolis term from the step's velocity; Woodman's scheme then steps velocity
    /// and position as on the flat Earth (rectangles, the new attitude), the accurate one with
    /// the trapezoid and the Coriolis term at the step's mean velocity (one prediction).
    #[inline(always)]
    fn step_round(&mut self, o: &Origin, gyro: &Lanes<3, L>, accel: &Lanes<3, L>, dt_s: f64) {
        let c_old = self.c;
        let rotation = self.body_rotation(gyro, dt_s);
        let c_body = mat_mul(&c_old, &rotation);
        if self.slow.steps == 0 {
            for l in 0..L {
                let (s, c) = o.sin_cos(self.p[0][l]);
                let (rnh, reh, gamma) = o.radii_gravity(s, self.p[2][l]);
                self.slow.sin[l] = s;
                self.slow.cos[l] = c;
                self.slow.inv_rn_h[l] = 1.0 / rnh;
                self.slow.inv_re_h[l] = 1.0 / reh;
                self.slow.tan[l] = s / c;
                self.slow.inv_re_h_cos[l] = 1.0 / (reh * c);
                self.slow.g[l] = gamma;
            }
        }
        self.slow.steps = (self.slow.steps + 1) % EARTH_EVERY;
        let w = o.earth.rate_rad_s();
        let sl = &self.slow;
        let mut zeta = [[0.0; L]; 3];
        let mut cor = [[0.0; L]; 3];
        for l in 0..L {
            let (s, c) = (sl.sin[l], sl.cos[l]);
            let (vn, ve) = (self.v[0][l], self.v[1][l]);
            let ie = [w * c, 0.0, -w * s];
            let e_over_r = ve * sl.inv_re_h[l];
            let en = [e_over_r, -vn * sl.inv_rn_h[l], -e_over_r * sl.tan[l]];
            for k in 0..3 {
                zeta[k][l] = -(ie[k] + en[k]) * dt_s;
                cor[k][l] = 2.0 * ie[k] + en[k];
            }
        }
        let g = sl.g;
        // The navigation frame's turn over the step, exp(-[omega_in dt x]), applied after the body's.
        self.c = mat_mul(&so3_exp_lanes(&zeta), &c_body);
        let coriolis = |v: &Lanes<3, L>| -> Lanes<3, L> {
            let mut out = [[0.0; L]; 3];
            for l in 0..L {
                out[0][l] = cor[1][l] * v[2][l] - cor[2][l] * v[1][l];
                out[1][l] = cor[2][l] * v[0][l] - cor[0][l] * v[2][l];
                out[2][l] = cor[0][l] * v[1][l] - cor[1][l] * v[0][l];
            }
            out
        };
        let v_old = self.v;
        let held = o.earth.vertical == Vertical::Held;
        let (v_new, v_pos) = match self.scheme {
            Scheme::Woodman => {
                let a = mat_vec(&self.c, accel);
                let cv = coriolis(&v_old);
                let mut v_new = [[0.0; L]; 3];
                for k in 0..3 {
                    for l in 0..L {
                        let gk = if k == 2 { g[l] } else { 0.0 };
                        v_new[k][l] = v_old[k][l] + dt_s * (a[k][l] + gk - cv[k][l]);
                    }
                }
                if held {
                    v_new[2] = [0.0; L];
                }
                (v_new, v_new)
            }
            Scheme::Accurate => {
                let a = sum_times(&c_old, &self.c, accel);
                let mut force = [[0.0; L]; 3];
                for k in 0..3 {
                    for l in 0..L {
                        force[k][l] = 0.5 * a[k][l] + if k == 2 { g[l] } else { 0.0 };
                    }
                }
                let c0 = coriolis(&v_old);
                let mut v_mid = [[0.0; L]; 3];
                for k in 0..3 {
                    for l in 0..L {
                        let pred = v_old[k][l] + dt_s * (force[k][l] - c0[k][l]);
                        v_mid[k][l] = 0.5 * (v_old[k][l] + pred);
                    }
                }
                let cm = coriolis(&v_mid);
                let mut v_new = [[0.0; L]; 3];
                let mut v_pos = [[0.0; L]; 3];
                for k in 0..3 {
                    for l in 0..L {
                        v_new[k][l] = v_old[k][l] + dt_s * (force[k][l] - cm[k][l]);
                    }
                }
                if held {
                    v_new[2] = [0.0; L];
                }
                for k in 0..3 {
                    for l in 0..L {
                        v_pos[k][l] = 0.5 * (v_old[k][l] + v_new[k][l]);
                    }
                }
                (v_new, v_pos)
            }
        };
        for l in 0..L {
            let sl = &self.slow;
            self.p[0][l] += dt_s * v_pos[0][l] * sl.inv_rn_h[l];
            self.p[1][l] += dt_s * v_pos[1][l] * sl.inv_re_h_cos[l];
            self.p[2][l] -= dt_s * v_pos[2][l];
        }
        self.v = v_new;
    }

    /// Advance every lane by `n` samples whose inputs `fill(start, chunk)` writes, [`CHUNK`]
    /// samples at a time: `chunk[j][c][lane]` is sample `start + j`'s channel `c` (gyro x y z,
    /// then accelerometer x y z; `chunk.len()` samples, the last chunk shorter). The same steps as
    /// [`Self::step`], compiled as is and, with more than one lane, with AVX-512F or AVX2 enabled
    /// (the widest the CPU has, chosen at run time): the lanes' operations are the same at every
    /// width (no fused multiply-add), so the same bits. The sample-major chunk stays in the
    /// first-level cache while the caller gathers it.
    #[inline]
    pub fn integrate<F>(&mut self, n: usize, dt_s: f64, fill: F)
    where
        F: FnMut(usize, &mut [Lanes<6, L>]),
    {
        #[inline(always)]
        fn run<const L: usize, F: FnMut(usize, &mut [Lanes<6, L>])>(
            nav: &mut StrapdownLanes<L>,
            n: usize,
            dt_s: f64,
            mut fill: F,
        ) {
            let mut samples = [[[0.0f64; L]; 6]; CHUNK];
            for start in (0..n).step_by(CHUNK) {
                let chunk = &mut samples[..CHUNK.min(n - start)];
                fill(start, chunk);
                for s in chunk.iter() {
                    nav.step(&[s[0], s[1], s[2]], &[s[3], s[4], s[5]], dt_s);
                }
            }
        }
        #[cfg(target_arch = "x86_64")]
        {
            #[target_feature(enable = "avx512f")]
            fn avx512<const L: usize, F: FnMut(usize, &mut [Lanes<6, L>])>(
                nav: &mut StrapdownLanes<L>,
                n: usize,
                dt_s: f64,
                fill: F,
            ) {
                run(nav, n, dt_s, fill)
            }
            #[target_feature(enable = "avx2")]
            fn avx2<const L: usize, F: FnMut(usize, &mut [Lanes<6, L>])>(
                nav: &mut StrapdownLanes<L>,
                n: usize,
                dt_s: f64,
                fill: F,
            ) {
                run(nav, n, dt_s, fill)
            }
            if L > 1 && std::arch::is_x86_feature_detected!("avx512f") {
                // SAFETY: the CPU supports AVX-512F (checked just above).
                return unsafe { avx512(self, n, dt_s, fill) };
            }
            if L > 1 && std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU supports AVX2 (checked just above).
                return unsafe { avx2(self, n, dt_s, fill) };
            }
        }
        run(self, n, dt_s, fill)
    }
}

/// Row-major 3x3 product per lane: (A B)_ij = (A_i0 B_0j + A_i1 B_1j) + A_i2 B_2j.
#[inline(always)]
fn mat_mul<const L: usize>(a: &Lanes<9, L>, b: &Lanes<9, L>) -> Lanes<9, L> {
    let mut out = [[0.0; L]; 9];
    for i in 0..3 {
        for j in 0..3 {
            for l in 0..L {
                out[3 * i + j][l] = a[3 * i][l] * b[j][l]
                    + a[3 * i + 1][l] * b[3 + j][l]
                    + a[3 * i + 2][l] * b[6 + j][l];
            }
        }
    }
    out
}

/// (A + B) x per lane: the trapezoid's specific force, twice its mean over the step.
#[inline(always)]
fn sum_times<const L: usize>(a: &Lanes<9, L>, b: &Lanes<9, L>, x: &Lanes<3, L>) -> Lanes<3, L> {
    let mut sum = [[0.0; L]; 9];
    for e in 0..9 {
        for l in 0..L {
            sum[e][l] = a[e][l] + b[e][l];
        }
    }
    mat_vec(&sum, x)
}

/// Row-major 3x3 times vector per lane: (A x)_i = (A_i0 x_0 + A_i1 x_1) + A_i2 x_2.
#[inline(always)]
fn mat_vec<const L: usize>(a: &Lanes<9, L>, x: &Lanes<3, L>) -> Lanes<3, L> {
    let mut out = [[0.0; L]; 3];
    for i in 0..3 {
        for l in 0..L {
            out[i][l] =
                a[3 * i][l] * x[0][l] + a[3 * i + 1][l] * x[1][l] + a[3 * i + 2][l] * x[2][l];
        }
    }
    out
}

/// `exp([phi x])` per lane (Woodman eq 41; the Rodrigues form of `crate::frames::so3_exp`):
/// `I + a B + b B^2`, `B^2 = phi phi^T - s^2 I`. The coefficients come from their series when
/// every lane's angle is below 0.1 rad (the usual case, vectorised), else lane by lane.
#[inline(always)]
fn so3_exp_lanes<const L: usize>(phi: &Lanes<3, L>) -> Lanes<9, L> {
    let [x, y, z] = phi;
    let mut s2 = [0.0; L];
    for l in 0..L {
        s2[l] = x[l] * x[l] + y[l] * y[l] + z[l] * z[l];
    }
    let (mut a, mut b) = ([0.0; L], [0.0; L]);
    if s2.iter().all(|&s| s < 1e-2) {
        for l in 0..L {
            (a[l], b[l]) = rodrigues_series(s2[l]);
        }
    } else {
        for l in 0..L {
            (a[l], b[l]) = rodrigues_coefficients(s2[l]);
        }
    }
    let mut e = [[0.0; L]; 9];
    for l in 0..L {
        let m = rodrigues_entries(a[l], b[l], s2[l], x[l], y[l], z[l]);
        for k in 0..9 {
            e[k][l] = m[k];
        }
    }
    e
}

/// First-order symmetric orthonormalisation `C <- C - C (C^T C - I) / 2` per lane: the first term of
/// the nearest orthonormal matrix `C (C^T C)^(-1/2) = C (I + D)^(-1/2)`, `D = C^T C - I`
/// (I. Bar-Itzhack, "Strapdown matrix orthogonalization: the dual iterative algorithm", IEEE TAES
/// 1976; the same series is spelled out in M. Jah's public `orthodcm.m`). With `|D| ~ 1e-14` the
/// neglected `3/8 D^2` is below rounding. Exact identity stays exact identity.
#[inline(always)]
fn renormalise<const L: usize>(c: &Lanes<9, L>) -> Lanes<9, L> {
    let mut e = [[0.0; L]; 9];
    for i in 0..3 {
        for j in 0..3 {
            for l in 0..L {
                let g = c[i][l] * c[j][l] + c[3 + i][l] * c[3 + j][l] + c[6 + i][l] * c[6 + j][l];
                e[3 * i + j][l] = g - if i == j { 1.0 } else { 0.0 };
            }
        }
    }
    let ce = mat_mul(c, &e);
    let mut out = [[0.0; L]; 9];
    for k in 0..9 {
        for l in 0..L {
            out[k][l] = c[k][l] - 0.5 * ce[k][l];
        }
    }
    out
}

/// A strapdown integrator. Allocation-free, fixed-size state; one [`Strapdown::step`] per IMU sample.
/// The one-lane case of [`StrapdownLanes`] (the mechanisation is written once, there).
#[derive(Clone, Debug)]
pub struct Strapdown(StrapdownLanes<1>);

impl Strapdown {
    /// A new integrator starting at `initial`, with gravity magnitude `gravity_mps2` pointing down.
    /// The coning correction of the first step assumes a zero previous increment unless
    /// [`Strapdown::set_previous_gyro`] provides it.
    pub fn new(scheme: Scheme, initial: NavState, gravity_mps2: f64) -> Strapdown {
        Strapdown(StrapdownLanes::new(scheme, &[initial], gravity_mps2))
    }

    /// A new integrator on the round, rotating Earth `earth`, starting at `initial` (position in NED
    /// metres from `earth.place`; crate::round_earth).
    pub fn on_earth(scheme: Scheme, initial: NavState, earth: RoundEarth) -> Strapdown {
        Strapdown(StrapdownLanes::on_earth(scheme, &[initial], earth))
    }

    /// Provide the gyro sample of the interval before the first step (for the coning correction of the
    /// first step of [`Scheme::Accurate`]); ignored by [`Scheme::Woodman`].
    pub fn set_previous_gyro(&mut self, gyro: &BodyVector, dt_s: f64) {
        self.0.set_previous_gyro(&gyro.0, dt_s);
    }

    /// The scheme in use.
    pub fn scheme(&self) -> Scheme {
        self.0.scheme()
    }

    /// The current navigation solution.
    pub fn state(&self) -> NavState {
        self.0.state(0)
    }

    /// Advance by one sample: `gyro` (rad/s) and `accel` (specific force, m/s^2), body frame, interval
    /// averages over `[t_k, t_k + dt_s]`. Woodman: `C <- C exp(B)` (eq 41), `a_nav = C_{k+1} f`
    /// (eq 42), `v += dt (a_nav + gamma)` (eq 45), `p += dt v_{k+1}` (eq 46); Accurate: the coning
    /// correction, the exact rotation, trapezoidal velocity and position ([`Scheme`]); the DCM
    /// re-orthonormalised every 256 steps (`renormalise`).
    #[inline]
    pub fn step(&mut self, gyro: &BodyVector, accel: &BodyVector, dt_s: f64) {
        let g = [[gyro.0.x], [gyro.0.y], [gyro.0.z]];
        let a = [[accel.0.x], [accel.0.y], [accel.0.z]];
        self.0.step(&g, &a, dt_s);
    }
}
