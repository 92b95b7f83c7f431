//! Time-domain detectors beside the Allan gap (docs/real-effects.md, "What diagnose does with
//! them"): effects that are deterministic or not stationary, which an Allan curve hides or mistakes
//! for noise.
//!
//! - Outliers: samples far from the median of their neighbours, in robust standard deviations.
//! - Temperature: least-squares regression of the channel on the log's temperature column.
//! - Warm-up transient: least-squares fit of an exponential A e^{-t/tau} at the start of the log.
//!
//! A regression coefficient c = w . x (w the least-squares weights of the centred regressor) has, when
//! the channel's noise e is coloured, the variance Var(w . e), not the white-noise sigma^2 sum w^2: a slow
//! bias wander correlates with any slow regressor. [`coloured_variance`] computes Var(w . e) exactly
//! for white noise, flicker (the noise crate's Gauss-Markov band) and rate random walk, with the
//! levels fitted (IEEE 952, `allan::fit_ieee952`) to the Allan deviation of the regression's residual.

use crate::stats::median;
use allan::{DataKind, Estimator, TauGrid};
use noise::{Channel, Flicker, ImuChannels};

/// Largest half-width of the neighbourhood whose median is a sample's reference.
const HALF_WINDOW: usize = 3;

/// What the outlier detector found in one channel.
#[derive(Clone, Debug)]
pub struct Spikes {
    /// Indices of the outlying samples, ascending.
    pub indices: Vec<usize>,
    /// Their displacement from the neighbours' median (signal units, signed).
    pub excess: Vec<f64>,
    /// Robust standard deviation of the displacement of ordinary samples (1.4826 MAD).
    pub sigma: f64,
    /// Threshold used, in robust standard deviations.
    pub threshold: f64,
}

impl Spikes {
    /// Median absolute displacement of the outliers: the size an outlier term is given.
    pub fn size(&self) -> f64 {
        let mut a: Vec<f64> = self.excess.iter().map(|e| e.abs()).collect();
        median(&mut a)
    }
}

/// Upper-tail quantile of the standard normal: z with Q(z) = p (the allan crate's `normal_ppf`).
pub fn normal_upper_quantile(p: f64) -> f64 {
    -allan::chi2::normal_ppf(p)
}

/// The outlier threshold for `n` samples: the two-sided Gaussian level that ordinary samples exceed
/// with probability 0.01 over the whole log (Bonferroni: 2 n Q(z) = 0.01), and never below 10 robust
/// standard deviations: real sensors' ordinary noise has heavier tails than Gaussian (the MTi-G log
/// has a continuous tail: 25 650 samples beyond 6, 7 900 beyond 8, 1 940 beyond 10 robust sigma), and
/// 10 is the level at which that log is known to hold its outliers.
pub fn spike_threshold(n: usize) -> f64 {
    normal_upper_quantile(0.005 / n.max(1) as f64).max(10.0)
}

/// The median of the window of 2 HALF_WINDOW + 1 samples centred on sample k (Hampel's identifier,
/// Hampel et al. 1986; shorter at the ends).
fn neighbour_median(x: &[f64], k: usize, buf: &mut Vec<f64>) -> f64 {
    let lo = k.saturating_sub(HALF_WINDOW);
    let hi = (k + HALF_WINDOW + 1).min(x.len());
    if hi - lo == 2 * HALF_WINDOW + 1 {
        // Interior: the full window on the stack.
        let mut w = [0.0; 2 * HALF_WINDOW + 1];
        w.copy_from_slice(&x[lo..hi]);
        w.sort_unstable_by(f64::total_cmp);
        return w[HALF_WINDOW];
    }
    buf.clear();
    buf.extend_from_slice(&x[lo..hi]);
    median(buf)
}

/// Robust outlier detection (a Hampel identifier with a global scale): each sample's displacement
/// r_k from the median of the 7-sample window centred on it, scaled by the robust standard deviation
/// of all displacements (1.4826 times their median absolute value); samples beyond
/// [`spike_threshold`] that also stand out from their two neighbours' mean (see below) are outliers.
/// An isolated outlier barely moves its window's median.
pub fn detect_spikes(x: &[f64]) -> Spikes {
    let n = x.len();
    let mut buf = Vec::with_capacity(2 * HALF_WINDOW);
    let r: Vec<f64> = (0..n)
        .map(|k| x[k] - neighbour_median(x, k, &mut buf))
        .collect();
    let mut a: Vec<f64> = r.iter().map(|v| v.abs()).collect();
    let mut sigma = 1.4826 * median(&mut a);
    if sigma <= 0.0 || !sigma.is_finite() {
        // Coarsely quantised data: most displacements are 0; use the RMS of the central 98 %.
        let cut = a[(0.98 * (n as f64 - 1.0)) as usize];
        let (s, c) = a
            .iter()
            .filter(|&&v| v <= cut)
            .fold((0.0, 0usize), |(s, c), v| (s + v * v, c + 1));
        sigma = (s / c.max(1) as f64).sqrt();
    }
    let threshold = spike_threshold(n);
    // A spike also stands out from the channel's own short-term spread: at least 8 robust standard
    // deviations of the channel less its centred 101-sample moving average. On white noise the
    // window displacements' scale is about 0.9 of the channel's, so the threshold above (>= 10,
    // about 9 of the channel's) is the stricter; on a smooth (filtered or held) channel the running
    // median follows the signal closely, the displacements' scale collapses and their heavy tails
    // would pass for spikes of a few of the channel's own standard deviations.
    let floor = 8.0 * high_passed_sigma(x, 50);
    let isolated = |k: usize| r[k].abs() > floor;
    let mut indices = Vec::new();
    let mut excess = Vec::new();
    if sigma > 0.0 {
        for (k, &v) in r.iter().enumerate() {
            if v.abs() > threshold * sigma && isolated(k) {
                indices.push(k);
                excess.push(v);
            }
        }
    }
    Spikes {
        indices,
        excess,
        sigma,
        threshold,
    }
}

/// Robust standard deviation (1.4826 x the median absolute deviation) of `x` less its centred moving
/// average over 2 `half` + 1 samples (shorter at the ends).
fn high_passed_sigma(x: &[f64], half: usize) -> f64 {
    let n = x.len();
    let mut prefix = Vec::with_capacity(n + 1);
    prefix.push(0.0);
    for v in x {
        prefix.push(prefix.last().copied().unwrap_or(0.0) + v);
    }
    let mut hp: Vec<f64> = (0..n)
        .map(|k| {
            let (lo, hi) = (k.saturating_sub(half), (k + half + 1).min(n));
            x[k] - (prefix[hi] - prefix[lo]) / (hi - lo) as f64
        })
        .collect();
    // The median reorders hp; the absolute deviations from it do not depend on the order.
    let m = median(&mut hp);
    hp.iter_mut().for_each(|v| *v = (*v - m).abs());
    1.4826 * median(&mut hp)
}

/// The series with each outlier replaced by the median of its neighbours.
pub fn remove_spikes(x: &[f64], spikes: &Spikes) -> Vec<f64> {
    let mut out = x.to_vec();
    let mut buf = Vec::new();
    for &k in &spikes.indices {
        out[k] = neighbour_median(x, k, &mut buf);
    }
    out
}

/// Noise levels of a residual for [`coloured_variance`] (SI, IEEE 952 coefficients).
#[derive(Clone, Copy, Debug, Default)]
pub struct NoiseLevels {
    pub n: f64,
    pub b: f64,
    pub k: f64,
}

impl NoiseLevels {
    /// Each level the larger of this one's and `floor`'s.
    pub fn at_least(&self, floor: &NoiseLevels) -> NoiseLevels {
        NoiseLevels {
            n: self.n.max(floor.n),
            b: self.b.max(floor.b),
            k: self.k.max(floor.k),
        }
    }
}

/// White, flicker and random-walk levels of `x` from its octave Allan deviation (IEEE 952 fit).
/// Quantisation is counted as white noise at the sample interval; the ramp is left out (a trend is a
/// regressor's business, not noise).
pub fn noise_levels(x: &[f64], dt_s: f64) -> NoiseLevels {
    let points = allan::deviation(
        x,
        DataKind::Rate,
        dt_s,
        Estimator::Overlapping,
        &TauGrid::Octave,
    );
    let fit = allan::fit::fit_ieee952(&points);
    let v = |t: Option<allan::fit::Term>| t.map_or(0.0, |t| t.value.max(0.0));
    let q = v(fit.q);
    // 3 Q^2 / tau^2 at tau = dt equals a white density sqrt(3) Q / sqrt(dt) there.
    let n = v(fit.n).hypot(3f64.sqrt() * q / dt_s.sqrt());
    NoiseLevels {
        n,
        b: v(fit.b),
        k: v(fit.k),
    }
}

/// Var(w . e) for noise e of the given levels sampled every `dt_s`, with sum w = 0:
/// white: (N^2/dt) sum w^2; random walk (step variance K^2 dt, any start): K^2 dt sum_l W_l^2 with the
/// tail sums W_l = sum_{k >= l} w_k; flicker as the noise crate's Gauss-Markov band (sigma_i, T_i):
/// sigma_i^2 (2 sum_k w_k F_k - sum_k w_k^2), F_k = phi F_{k-1} + w_k, phi = e^{-dt/T_i}.
pub fn coloured_variance(w: &[f64], dt_s: f64, levels: &NoiseLevels) -> f64 {
    let sum_w2: f64 = w.iter().map(|v| v * v).sum();
    let mut var = levels.n * levels.n / dt_s * sum_w2;
    if levels.k > 0.0 {
        let mut tail = 0.0;
        let mut s = 0.0;
        for &v in w.iter().rev() {
            tail += v;
            s += tail * tail;
        }
        var += levels.k * levels.k * dt_s * s;
    }
    if levels.b > 0.0 {
        // B is finite and positive here (an IEEE 952 fit); a band refused adds nothing.
        let band = Flicker::with_b(levels.b).map_or_else(|_| Vec::new(), |f| f.components());
        for (tc, sigma) in band {
            let phi = (-dt_s / tc).exp();
            let mut f = 0.0;
            let mut s = 0.0;
            for &v in w {
                f = phi * f + v;
                s += v * f;
            }
            var += sigma * sigma * (2.0 * s - sum_w2);
        }
    }
    var
}

/// Least-squares fit of x on (1, g): the coefficient of g, its weights w (x . w = coefficient), and
/// the residual. None when g is constant.
pub fn regress(x: &[f64], g: &[f64]) -> Option<(f64, Vec<f64>, Vec<f64>)> {
    let gm = stats::mean(g);
    let sgg: f64 = g.iter().map(|v| (v - gm) * (v - gm)).sum();
    if sgg <= 0.0 || !sgg.is_finite() {
        return None;
    }
    let w: Vec<f64> = g.iter().map(|v| (v - gm) / sgg).collect();
    let c: f64 = w.iter().zip(x).map(|(a, b)| a * b).sum();
    let xm = stats::mean(x);
    let resid = x
        .iter()
        .zip(g)
        .map(|(xi, gi)| xi - xm - c * (gi - gm))
        .collect();
    Some((c, w, resid))
}

/// `v` minus its least-squares line in the sample index (the residual of a fit on (1, k)).
pub fn detrend(v: &[f64]) -> Vec<f64> {
    let n = v.len() as f64;
    let km = (n - 1.0) / 2.0;
    let vm = stats::mean(v);
    let (mut skv, mut skk) = (0.0, 0.0);
    for (k, &x) in v.iter().enumerate() {
        let d = k as f64 - km;
        skv += d * (x - vm);
        skk += d * d;
    }
    let b = if skk > 0.0 { skv / skk } else { 0.0 };
    v.iter()
        .enumerate()
        .map(|(k, &x)| x - vm - b * (k as f64 - km))
        .collect()
}

/// Least-squares fit of x on (1, k, g): the coefficient of g, its weights w (orthogonal to 1 and k;
/// x . w = coefficient) and the residual (Frisch-Waugh: g and x both detrended). None when g is a
/// straight line in time to 1e-9 of its variance (nothing left to fit but rounding).
pub fn regress_detrended(x: &[f64], g: &[f64]) -> Option<(f64, Vec<f64>, Vec<f64>)> {
    let gt = detrend(g);
    let sgg: f64 = gt.iter().map(|v| v * v).sum();
    let gm = stats::mean(g);
    let centred: f64 = g.iter().map(|v| (v - gm) * (v - gm)).sum();
    if sgg <= 1e-9 * centred || !sgg.is_finite() {
        return None;
    }
    let w: Vec<f64> = gt.iter().map(|v| v / sgg).collect();
    let c: f64 = w.iter().zip(x).map(|(a, b)| a * b).sum();
    let resid = detrend(x)
        .iter()
        .zip(&gt)
        .map(|(xi, gi)| xi - c * gi)
        .collect();
    Some((c, w, resid))
}

/// A regression with its coloured-noise standard error.
#[derive(Clone, Debug)]
pub struct Regression {
    pub coefficient: f64,
    pub sd: f64,
    /// coefficient / sd.
    pub z: f64,
    /// The channel with the fitted term removed (the mean kept).
    pub corrected: Vec<f64>,
}

/// Regress `x` on `g` and give the coefficient's standard error under the residual's coloured noise:
/// each level the larger of the one fitted to the residual and `floor` (the sensor model's own).
pub fn regression(x: &[f64], g: &[f64], dt_s: f64, floor: &NoiseLevels) -> Option<Regression> {
    let (c, w, resid) = regress(x, g)?;
    let levels = noise_levels(&resid, dt_s).at_least(floor);
    let sd = coloured_variance(&w, dt_s, &levels).max(0.0).sqrt();
    let gm = stats::mean(g);
    let corrected = x.iter().zip(g).map(|(xi, gi)| xi - c * (gi - gm)).collect();
    Some(Regression {
        coefficient: c,
        sd,
        z: z_score(c, sd),
        corrected,
    })
}

/// c / sd, with a noiseless channel's exact fit counted as decisive only when it finds something
/// (a constant channel's zero coefficient is z = 0, not 0/0).
fn z_score(c: f64, sd: f64) -> f64 {
    if sd > 0.0 {
        c / sd
    } else if c == 0.0 {
        0.0
    } else {
        f64::INFINITY.copysign(c)
    }
}

/// |z| a temperature coefficient must exceed: two-sided 1e-3 per channel under Gaussian errors
/// (3.29), raised to 5 because the standard error itself comes from noise levels fitted to one log
/// (at 4, one channel of 24 clean 22-minute logs with a recorded warm-up named a temperature effect).
pub const TEMPERATURE_Z: f64 = 5.0;

/// A fitted warm-up transient.
#[derive(Clone, Debug)]
pub struct Transient {
    /// Bias at t = 0 relative to the settled value, signal units.
    pub amplitude: f64,
    pub tau_s: f64,
    /// 95 % profile interval of the time constant.
    pub tau_lo_s: f64,
    pub tau_hi_s: f64,
    pub z: f64,
    pub corrected: Vec<f64>,
}

/// |z| a transient must exceed: its time constant is searched over about 40 values (a
/// look-elsewhere factor), so two-sided 1e-3 / 40 per channel (4.06), raised to 5 for the fitted
/// noise levels.
pub const TRANSIENT_Z: f64 = 5.0;

/// Fit A e^{-t/tau} + const by least squares over time constants from 20 samples to a third of the
/// log (40 per decade... log-spaced, then golden-section refined in ln tau), the amplitude's standard
/// error from the residual's coloured noise. Returns the best fit whatever its z.
pub fn fit_transient(x: &[f64], dt_s: f64, floor: &NoiseLevels) -> Option<Transient> {
    let n = x.len();
    let t_log = n as f64 * dt_s;
    let (lo, hi) = (20.0 * dt_s, t_log / 3.0);
    if hi <= lo {
        return None;
    }
    let profile = TransientProfile::new(x, dt_s);
    let tau = profile.best_tau(lo, hi)?;
    let g: Vec<f64> = (0..n).map(|k| (-(k as f64) * dt_s / tau).exp()).collect();
    let (c, w, resid) = regress_detrended(x, &g)?;
    let rss_min: f64 = resid.iter().map(|v| v * v).sum();
    let levels = noise_levels(&resid, dt_s).at_least(floor);
    let var_c = coloured_variance(&w, dt_s, &levels).max(0.0);
    let sd = var_c.sqrt();
    // Profile interval of tau: RSS(tau) <= RSS_min + 3.84 s^2 f, s^2 = RSS_min/(n - 3) the white
    // residual variance and f = Var_coloured(A) / Var_white(A) at the optimum, the design effect of
    // the coloured noise on this regressor (Kish 1965; the effective-sample-size correction of
    // regression on autocorrelated errors).
    let s2 = rss_min / (n as f64 - 4.0);
    let var_white = s2 * w.iter().map(|v| v * v).sum::<f64>();
    let f = if var_white > 0.0 {
        (var_c / var_white).max(1.0)
    } else {
        1.0
    };
    let level = rss_min + 3.841_458_820_694_124 * s2 * f;
    let (tau_lo, tau_hi) = profile.tau_interval(tau, level, (lo, hi));
    // Remove the exponential itself (mean kept), not its detrended shape: the straight line it was
    // fitted beside belongs to the data, and subtracting c (g - its line) would add c x that line,
    // a spurious ramp of slope ~ c tau / T^2 that a long tau makes large enough to be named.
    let gm = stats::mean(&g);
    Some(Transient {
        amplitude: c,
        tau_s: tau,
        tau_lo_s: tau_lo.min(tau),
        tau_hi_s: tau_hi.max(tau),
        z: z_score(c, sd),
        corrected: x
            .iter()
            .zip(&g)
            .map(|(xi, gi)| xi - c * (gi - gm))
            .collect(),
    })
}

/// The residual sum of squares of a transient fit as a function of its time constant. The
/// transient must stand out from a straight line (a rate ramp or a slow drift is not a
/// transient): everything is fitted beside (1, k). Profile: the residual sum of squares at tau,
/// RSS = S~xx - S~xg^2 / S~gg with x~ the detrended log and S~gg = S_gg - S_g^2/n - S_kg^2/S_kk,
/// g_k = phi^k accumulated in one pass. Each pass over the log serves up to [`LANES`] time
/// constants (the grid, the golden section's two points, the bisection's next three levels, the
/// interval's next steps): the searches are the same, each value is.
struct TransientProfile {
    dt_s: f64,
    /// The detrended log and its sum of squares.
    xt: Vec<f64>,
    sxx: f64,
    /// Is every sample of `xt` finite (then a decayed exponential adds nothing: [`decay_sums`]).
    finite: bool,
    /// n, the mean sample index and the index's centred sum of squares.
    nf: f64,
    km: f64,
    skk: f64,
}

/// Time constants per pass of [`decay_sums`].
const LANES: usize = 8;

/// Samples between [`decay_sums`]' checks for exponentials decayed to exactly 0.
const ZERO_CHECK: usize = 1024;

allan::wide_variant! {
    /// The transient profile's sums (S_g, S_gg, S_kg, S_xg) over the detrended log `xt`, g_k =
    /// phi^k, for [`LANES`] factors `phi` at once: in each lane the operations of one time constant
    /// alone, in sample order (the same bits). Once every g is 0 (a time constant short beside the
    /// log) the rest adds +-0 to sums that are never -0 (they start at +0, and a rounded sum is -0
    /// only of two -0), which changes no bit if the log is `finite` (0 x inf would not be 0): it
    /// stops there.
    fn decay_sums(xt: &[f64], km: f64, phi: [f64; LANES], finite: bool) -> [[f64; LANES]; 4] {
        let mut g = [1.0f64; LANES];
        let (mut sg, mut sgg, mut skg, mut sxg) = ([0.0; LANES], [0.0; LANES], [0.0; LANES], [0.0; LANES]);
        for (block, xs) in xt.chunks(ZERO_CHECK).enumerate() {
            if finite && g.iter().all(|&v| v == 0.0) {
                break;
            }
            for (j, &v) in xs.iter().enumerate() {
                let d = (block * ZERO_CHECK + j) as f64 - km;
                for l in 0..LANES {
                    sg[l] += g[l];
                    sgg[l] += g[l] * g[l];
                    skg[l] += d * g[l];
                    sxg[l] += g[l] * v;
                    g[l] *= phi[l];
                }
            }
        }
        [sg, sgg, skg, sxg]
    }
}

impl TransientProfile {
    fn new(x: &[f64], dt_s: f64) -> TransientProfile {
        let xt = detrend(x);
        let sxx: f64 = xt.iter().map(|v| v * v).sum();
        let nf = x.len() as f64;
        TransientProfile {
            dt_s,
            finite: xt.iter().all(|v| v.is_finite()),
            xt,
            sxx,
            nf,
            km: (nf - 1.0) / 2.0,
            skk: nf * (nf * nf - 1.0) / 12.0,
        }
    }

    /// (RSS, amplitude) at each time constant of `taus`, in passes of [`LANES`] (None where the
    /// exponential is a straight line).
    fn rss_many(&self, taus: &[f64]) -> Vec<Option<(f64, f64)>> {
        let (nf, skk) = (self.nf, self.skk);
        let mut out = Vec::with_capacity(taus.len());
        for group in taus.chunks(LANES) {
            // Spare lanes repeat the first time constant (decayed no later than it).
            let phi: [f64; LANES] =
                std::array::from_fn(|l| (-self.dt_s / group.get(l).unwrap_or(&group[0])).exp());
            let [sg, sgg, skg, sxg] = decay_sums(&self.xt, self.km, phi, self.finite);
            out.extend((0..group.len()).map(|l| {
                let sgg_c = sgg[l] - sg[l] * sg[l] / nf - skg[l] * skg[l] / skk;
                (sgg_c > 1e-12 * sgg[l])
                    .then(|| (self.sxx - sxg[l] * sxg[l] / sgg_c, sxg[l] / sgg_c))
            }));
        }
        out
    }

    /// The time constant of least RSS in [lo, hi]: 41 log-spaced values, then golden section in
    /// ln tau between the best one's neighbours.
    fn best_tau(&self, lo: f64, hi: f64) -> Option<f64> {
        let steps = 40;
        let grid: Vec<f64> = (0..=steps)
            .map(|j| lo * (hi / lo).powf(j as f64 / steps as f64))
            .collect();
        let mut best: Option<(f64, f64)> = None;
        for (&tau, r) in grid.iter().zip(self.rss_many(&grid)) {
            if let Some((rss, _)) = r {
                if best.is_none_or(|(b, _)| rss < b) {
                    best = Some((rss, tau));
                }
            }
        }
        let (_, tau0) = best?;
        let step = (hi / lo).ln() / steps as f64;
        let (mut a, mut b) = (
            (tau0.ln() - step).max(lo.ln()),
            (tau0.ln() + step).min(hi.ln()),
        );
        let gr = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..30 {
            let x1 = b - gr * (b - a);
            let x2 = a + gr * (b - a);
            let r = self.rss_many(&[x1.exp(), x2.exp()]);
            let f1 = r[0].map_or(f64::INFINITY, |v| v.0);
            let f2 = r[1].map_or(f64::INFINITY, |v| v.0);
            if f1 < f2 {
                b = x2;
            } else {
                a = x1;
            }
        }
        Some((0.5 * (a + b)).exp())
    }

    /// The time constants around `tau` where the RSS reaches `level` (steps of 1.25, then
    /// bisection in ln tau), within [lo, hi].
    fn tau_interval(&self, tau: f64, level: f64, (lo, hi): (f64, f64)) -> (f64, f64) {
        let down = |t: f64| (t / 1.25).max(lo);
        let up = |t: f64| (t * 1.25).min(hi);
        (
            self.reach(tau, level, lo, |t| t > lo, down),
            self.reach(tau, level, hi, |t| t < hi, up),
        )
    }

    /// From `tau` by `step` while `short_of_bound` and the RSS stays within `level`: the crossing
    /// of `level` (by [`Self::crossing`]) after the last step inside, or `bound`. The next steps
    /// (up to [`LANES`], none past the bound) are evaluated in one pass and walked in order.
    fn reach(
        &self,
        tau: f64,
        level: f64,
        bound: f64,
        short_of_bound: impl Fn(f64) -> bool,
        step: impl Fn(f64) -> f64,
    ) -> f64 {
        let (mut reached, mut t) = (bound, tau);
        while short_of_bound(t) {
            let mut steps = vec![step(t)];
            while steps.len() < LANES && short_of_bound(steps[steps.len() - 1]) {
                steps.push(step(steps[steps.len() - 1]));
            }
            for (&next, r) in steps.iter().zip(self.rss_many(&steps)) {
                if r.is_none_or(|v| v.0 > level) {
                    return self.crossing(t, next, level);
                }
                t = next;
                reached = t;
            }
        }
        reached
    }

    /// 25 bisections in ln tau between `inside` (RSS within `level`) and `outside`, the last
    /// inside point. Each pass evaluates the midpoints of the next three halvings on every path
    /// they can take (seven lanes, node n's halves at 2n + 1 (moved inside) and 2n + 2), then
    /// follows the one taken.
    fn crossing(&self, inside: f64, outside: f64, level: f64) -> f64 {
        let (mut i, mut o) = (inside.ln(), outside.ln());
        let mut left = 25;
        while left > 0 {
            let depth = left.min(3);
            let nodes = (1 << depth) - 1;
            let mut ends = vec![(i, o); nodes];
            let mut mids = vec![0.0; nodes];
            for n in 0..nodes {
                let (a, b) = ends[n];
                mids[n] = 0.5 * (a + b);
                if 2 * n + 2 < nodes {
                    ends[2 * n + 1] = (mids[n], b);
                    ends[2 * n + 2] = (a, mids[n]);
                }
            }
            let taus: Vec<f64> = mids.iter().map(|m| m.exp()).collect();
            let rss = self.rss_many(&taus);
            let mut n = 0;
            for _ in 0..depth {
                if rss[n].is_some_and(|v| v.0 <= level) {
                    i = mids[n];
                    n = 2 * n + 1;
                } else {
                    o = mids[n];
                    n = 2 * n + 2;
                }
            }
            left -= depth;
        }
        i.exp()
    }
}

/// May a sinusoid at `f0_hz` be named in `x` ([`crate::spectrum::line_allowed_runs`] of one log).
pub fn line_allowed(x: &[f64], dt_s: f64, f0_hz: f64) -> bool {
    crate::spectrum::line_allowed_runs(&[x], dt_s, f0_hz)
}

/// Is there a spectral line at `f0_hz` in `x` ([`crate::spectrum::is_spectral_line_runs`] of one
/// log).
pub fn is_spectral_line(x: &[f64], dt_s: f64, f0_hz: f64) -> bool {
    crate::spectrum::is_spectral_line_runs(&[x], dt_s, f0_hz)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::normals;

    /// The transient profile's passes in lanes (with the stop at decayed exponentials, the
    /// interval's speculative steps and bisections) give the bits of one time constant at a time.
    #[test]
    fn transient_profile_lanes_equal_one_at_a_time() {
        let dt = 0.01;
        let x: Vec<f64> = normals(30_000, 11)
            .iter()
            .enumerate()
            .map(|(k, e)| 0.02 * e + 0.05 * (-(k as f64) * dt / 8.0).exp())
            .collect();
        let p = TransientProfile::new(&x, dt);
        // RSS at one tau the plain way: the sums over the whole log, one sample after the other.
        let one = |tau: f64| -> Option<(f64, f64)> {
            let phi = (-dt / tau).exp();
            let (mut g, mut sg, mut sgg, mut skg, mut sxg) = (1.0, 0.0, 0.0, 0.0, 0.0);
            for (k, &v) in p.xt.iter().enumerate() {
                sg += g;
                sgg += g * g;
                skg += (k as f64 - p.km) * g;
                sxg += g * v;
                g *= phi;
            }
            let sgg_c = sgg - sg * sg / p.nf - skg * skg / p.skk;
            (sgg_c > 1e-12 * sgg).then(|| (p.sxx - sxg * sxg / sgg_c, sxg / sgg_c))
        };
        let bits = |r: Option<(f64, f64)>| r.map(|(a, b)| (a.to_bits(), b.to_bits()));
        let taus: Vec<f64> = (0..19).map(|j| 0.05 * 1.9f64.powi(j)).collect();
        for (&tau, r) in taus.iter().zip(p.rss_many(&taus)) {
            assert_eq!(bits(r), bits(one(tau)), "tau {tau}");
        }
        // The interval the plain way: steps of 1.25 one at a time, then 25 single bisections.
        let plain_crossing = |inside: f64, outside: f64, level: f64| {
            let (mut i, mut o) = (inside.ln(), outside.ln());
            for _ in 0..25 {
                let mid = 0.5 * (i + o);
                if one(mid.exp()).is_some_and(|v| v.0 <= level) {
                    i = mid;
                } else {
                    o = mid;
                }
            }
            i.exp()
        };
        let (lo, hi) = (20.0 * dt, x.len() as f64 * dt / 3.0);
        let tau = p.best_tau(lo, hi).expect("a fit");
        let rss = one(tau).expect("a fit").0;
        for level in [rss * 1.000_01, rss * 1.001, rss * 1.1, rss * 10.0] {
            let mut t = tau;
            let mut plain_lo = lo;
            while t > lo {
                let next = (t / 1.25).max(lo);
                if one(next).is_none_or(|v| v.0 > level) {
                    plain_lo = plain_crossing(t, next, level);
                    break;
                }
                t = next;
                plain_lo = t;
            }
            let (fast_lo, _) = p.tau_interval(tau, level, (lo, hi));
            assert_eq!(fast_lo.to_bits(), plain_lo.to_bits(), "level {level}");
        }
    }

    #[test]
    fn normal_quantiles() {
        // Table values: Q(1.959964) = 0.025, Q(3.290527) = 5e-4, Q(5.997807) = 1e-9.
        for (p, z) in [(0.025, 1.959_964), (5e-4, 3.290_527), (1e-9, 5.997_807)] {
            assert!((normal_upper_quantile(p) - z).abs() < 1e-5, "{p}");
        }
    }

    #[test]
    fn coloured_variance_matches_brute_force() {
        // Random-walk and Gauss-Markov quadratic forms against O(n^2) sums, n = 300.
        let n = 300;
        let dt = 0.1;
        let g: Vec<f64> = (0..n)
            .map(|k| ((k as f64) * 0.03).sin() + 0.001 * k as f64)
            .collect();
        let (_, w, _) = regress(&vec![0.0; n], &g).unwrap();
        let lv = NoiseLevels {
            n: 0.0,
            b: 0.0,
            k: 0.7,
        };
        let fast = coloured_variance(&w, dt, &lv);
        // Random walk from an arbitrary start: Cov(x_i, x_j) = s^2 min(i, j) (+ start, cancelled).
        let s2 = 0.49 * dt;
        let mut brute = 0.0;
        for i in 0..n {
            for j in 0..n {
                brute += w[i] * w[j] * s2 * (i.min(j) + 1) as f64;
            }
        }
        assert!((fast - brute).abs() < 1e-9 * brute, "{fast} {brute}");
        let lv = NoiseLevels {
            n: 0.3,
            b: 0.2,
            k: 0.0,
        };
        let fast = coloured_variance(&w, dt, &lv);
        let mut brute = 0.09 / dt * w.iter().map(|v| v * v).sum::<f64>();
        for (tc, s) in Flicker::with_b(0.2).unwrap().components() {
            let phi = (-dt / tc).exp();
            for i in 0..n {
                for j in 0..n {
                    brute += w[i] * w[j] * s * s * phi.powi((i as i32 - j as i32).abs());
                }
            }
        }
        assert!((fast - brute).abs() < 1e-9 * brute, "{fast} {brute}");
    }

    #[test]
    fn spectral_lines_are_told_from_broad_peaks() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(9);
        let dt = 0.01;
        let n = 200_000;
        let noise: Vec<f64> = (0..n).map(|_| rng.gen::<f64>() - 0.5).collect();
        // A tone at 0.56 Hz, 0.05 of the noise amplitude: a line.
        let tone: Vec<f64> = (0..n)
            .map(|k| noise[k] + 0.05 * (std::f64::consts::TAU * 0.56 * k as f64 * dt).sin())
            .collect();
        assert!(is_spectral_line(&tone, dt, 0.56));
        assert!(!is_spectral_line(&noise, dt, 0.56));
        // A broad resonance near 20.6 Hz (an AR(2) process, bandwidth about 0.4 Hz): not a line.
        let r: f64 = (-std::f64::consts::PI * 0.4 * dt).exp();
        let th = std::f64::consts::TAU * 20.6 * dt;
        let (mut y1, mut y2) = (0.0, 0.0);
        let broad: Vec<f64> = noise
            .iter()
            .map(|&e| {
                let y = 2.0 * r * th.cos() * y1 - r * r * y2 + e;
                y2 = y1;
                y1 = y;
                y
            })
            .collect();
        assert!(!is_spectral_line(&broad, dt, 20.6));
    }

    #[test]
    fn a_constant_or_quantised_channel_names_nothing() {
        // A channel stuck at one value, and one that toggles between two LSB values: no outliers,
        // no temperature effect, no transient (and no 0/0).
        let n = 20_000;
        let constant = vec![0.25; n];
        let toggling: Vec<f64> = (0..n)
            .map(|k| if k % 3 == 0 { 0.05 } else { 0.0 })
            .collect();
        let temp: Vec<f64> = (0..n).map(|k| 20.0 + 1e-3 * k as f64).collect();
        let floors = ImuChannels::<NoiseLevels>::default();
        let mut channels: ImuChannels<Option<&[f64]>> = ImuChannels::default();
        channels[Channel::Gx] = Some(&constant);
        channels[Channel::Gy] = Some(&toggling);
        let pre = preprocess(channels, Some(&temp), 0.01, &floors);
        for c in [Channel::Gx, Channel::Gy] {
            assert!(
                pre.findings[c].is_empty(),
                "channel {c}: {:?}",
                pre.findings[c]
            );
        }
    }

    #[test]
    fn spikes_found_and_removed() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(5);
        let mut x: Vec<f64> = (0..100_000)
            .map(|_| {
                let u: f64 = rng.gen::<f64>() - 0.5;
                let v: f64 = rng.gen::<f64>() - 0.5;
                u + v // triangular, bounded: no false outliers possible at 10 sigma
            })
            .collect();
        let at = [10usize, 5000, 5001 + 10, 77_777];
        for (j, &k) in at.iter().enumerate() {
            x[k] += if j % 2 == 0 { 12.0 } else { -12.0 };
        }
        let s = detect_spikes(&x);
        assert_eq!(s.indices, at.to_vec());
        assert!((s.size() - 12.0).abs() < 1.0, "{}", s.size());
        let clean = remove_spikes(&x, &s);
        assert!(clean.iter().all(|v| v.abs() < 1.0));
    }

    /// A smooth channel (white noise through two first-order low-passes, a = 0.9: about 10 samples
    /// of memory) has no spikes: the window median follows it, and the displacements' heavy tails
    /// pass 10 of their own robust sigma many times, but never 8 of the channel's. Spikes of 12 of
    /// the channel's standard deviations are found exactly.
    #[test]
    fn a_smooth_channel_has_no_spikes_but_its_spikes_are_found() {
        let e = normals(131_072, 11);
        let (mut a, mut b) = (0.0, 0.0);
        let mut x: Vec<f64> = e
            .iter()
            .map(|v| {
                a = 0.9 * a + 0.1 * v;
                b = 0.9 * b + 0.1 * a;
                b
            })
            .collect();
        let sd = stats::rms(&x);
        let hampel_alone = {
            let mut buf = Vec::new();
            let r: Vec<f64> = (0..x.len())
                .map(|k| x[k] - neighbour_median(&x, k, &mut buf))
                .collect();
            let mut ar: Vec<f64> = r.iter().map(|v| v.abs()).collect();
            let sigma = 1.4826 * median(&mut ar);
            r.iter()
                .filter(|v| v.abs() > spike_threshold(x.len()) * sigma)
                .count()
        };
        assert!(hampel_alone > 3, "the case needs the floor: {hampel_alone}");
        assert!(detect_spikes(&x).indices.is_empty());
        let at = [1000usize, 40_000, 90_001];
        for &k in &at {
            x[k] += 12.0 * sd;
        }
        assert_eq!(detect_spikes(&x).indices, at.to_vec());
    }

    /// The transient's correction removes the exponential only: a log that is a pure transient in
    /// white noise has no slope left (within 5 standard errors of the least-squares slope), where
    /// removing the detrended exponential would leave amplitude x the exponential's own slope.
    #[test]
    fn the_transient_correction_leaves_no_ramp() {
        let (n, dt, tau, amp) = (100_000usize, 0.01, 300.0, 0.5);
        let e = normals(n, 12);
        let x: Vec<f64> = (0..n)
            .map(|k| amp * (-(k as f64) * dt / tau).exp() + 0.1 * e[k])
            .collect();
        let tr = fit_transient(&x, dt, &NoiseLevels::default()).expect("a fit");
        let km = (n as f64 - 1.0) / 2.0;
        let skk: f64 = (0..n).map(|k| (k as f64 - km).powi(2)).sum();
        let slope: f64 = (0..n)
            .map(|k| (k as f64 - km) * tr.corrected[k])
            .sum::<f64>()
            / skk;
        let se = 0.1 / skk.sqrt();
        assert!(slope.abs() < 5.0 * se, "slope {slope:e} vs se {se:e}");
        assert!((tr.amplitude / amp - 1.0).abs() < 0.05, "{}", tr.amplitude);
    }
}

/// One time-domain finding on one channel: the term for the corrected model, its parameters with
/// 95 % bounds, and the evidence (z^2 - ln n, the BIC gain of one regressor with known variance; for
/// outliers the count's z under the Gaussian false-alarm level).
#[derive(Clone, Debug)]
pub struct Finding {
    pub term: noise::Term,
    /// Effects the data cannot tell this one from.
    pub cannot_tell_from: Vec<noise::Effect>,
    pub parameters: Vec<(&'static str, f64, f64, f64)>,
    pub delta_bic: f64,
}

/// What the detectors did to a log: the corrected channels and the findings per channel.
pub struct Preprocessed {
    pub channels: ImuChannels<Option<Vec<f64>>>,
    pub findings: ImuChannels<Vec<Finding>>,
    /// The broad spectral peak of each corrected channel (a resonance's frequency and bandwidth).
    pub peaks: ImuChannels<Option<crate::spectrum::SpectralPeak>>,
    /// The spectral lines of each corrected channel (`spectrum::spectral_lines_runs`), Hz.
    pub lines: ImuChannels<Vec<f64>>,
}

/// At least this many outliers are needed to name them (the threshold admits 0.01 false ones per log).
pub const MIN_OUTLIERS: usize = 3;
/// At most this fraction of the samples may be outliers: beyond it the "outliers" are the ordinary
/// samples of a channel whose short-term noise is not white (a heavily low-pass filtered log is smooth,
/// so its window residuals are tiny and their tail is the signal's curvature), and none are named.
pub const MAX_OUTLIER_FRACTION: f64 = 0.01;

/// Run the detectors on every channel, in order: outliers (removed), temperature regression
/// (subtracted when |z| > [`TEMPERATURE_Z`]), warm-up transient (subtracted when |z| > [`TRANSIENT_Z`]).
/// A temperature column that follows a warm-up looks like a transient: the temperature, a measured
/// cause, is tried first.
pub fn preprocess(
    channels: ImuChannels<Option<&[f64]>>,
    temperature_c: Option<&[f64]>,
    dt_s: f64,
    floors: &ImuChannels<NoiseLevels>,
) -> Preprocessed {
    use rayon::prelude::*;
    // Channels in parallel (each result depends on its channel only).
    let per: Vec<Option<Detected>> = Channel::ALL
        .into_par_iter()
        .map(|c| channels[c].map(|raw| detect_channel(raw, temperature_c, dt_s, &floors[c])))
        .collect();
    let mut out = Preprocessed {
        channels: Default::default(),
        findings: Default::default(),
        peaks: Default::default(),
        lines: Default::default(),
    };
    for (c, d) in Channel::ALL.into_iter().zip(per) {
        if let Some(d) = d {
            out.channels[c] = Some(d.corrected);
            out.findings[c] = d.findings;
            out.peaks[c] = d.peak;
            out.lines[c] = d.lines;
        }
    }
    out
}

/// What the detectors made of one channel.
struct Detected {
    corrected: Vec<f64>,
    findings: Vec<Finding>,
    peak: Option<crate::spectrum::SpectralPeak>,
    lines: Vec<f64>,
}

/// The detectors of [`preprocess`] on one channel, each on what the one before left.
fn detect_channel(
    raw: &[f64],
    temperature_c: Option<&[f64]>,
    dt_s: f64,
    floor: &NoiseLevels,
) -> Detected {
    let mut findings: Vec<Finding> = Vec::new();
    let mut x = raw.to_vec();
    if let Some((corrected, f)) = outlier_finding(&x, dt_s) {
        x = corrected;
        findings.push(f);
    }
    // An effect smaller than 1e-9 of the channel's magnitude is floating-point rounding of
    // the log's values (text logs carry at most 17 significant digits, sensors 4 to 6).
    let scale = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if let Some(t) = temperature_c {
        if let Some((corrected, f)) = temperature_finding(&x, t, dt_s, floor, scale) {
            x = corrected;
            findings.push(f);
        }
    }
    if let Some((corrected, f)) = transient_finding(&x, dt_s, floor, scale) {
        x = corrected;
        findings.push(f);
    }
    let (peak, lines) = crate::spectrum::peak_and_lines_runs(&[&x], dt_s);
    Detected {
        corrected: x,
        findings,
        peak,
        lines,
    }
}

/// Whether the change `c` times the regressor `g` (over its range) stands above the rounding of a
/// channel of magnitude `scale`.
fn visible(c: f64, g: &[f64], scale: f64) -> bool {
    let (lo, hi) = g
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    (c * (hi - lo)).abs() > 1e-9 * scale
}

/// Outliers, when there are between [`MIN_OUTLIERS`] and [`MAX_OUTLIER_FRACTION`] of the samples:
/// the channel with them replaced, and the finding.
fn outlier_finding(x: &[f64], dt_s: f64) -> Option<(Vec<f64>, Finding)> {
    let n = x.len();
    let hours = |n: usize| n as f64 * dt_s / 3600.0;
    let spikes = detect_spikes(x);
    let count = spikes.indices.len();
    if !(count >= MIN_OUTLIERS && (count as f64) <= MAX_OUTLIER_FRACTION * n as f64) {
        return None;
    }
    let x = remove_spikes(x, &spikes);
    let rate = count as f64 / hours(n);
    // Poisson 95 % bounds on the rate (normal approximation with continuity, count >= 3).
    let (lo, hi) = (
        (count as f64 - 1.96 * (count as f64).sqrt()).max(0.0) / hours(n),
        (count as f64 + 1.96 * (count as f64).sqrt() + 1.0) / hours(n),
    );
    let size = spikes.size();
    let n_without = noise_levels(&x, dt_s).n;
    let finding = Finding {
        cannot_tell_from: vec![],
        // A rate or size that is not a finite number is no finding.
        term: noise::Outliers::new(rate, size).ok()?.into(),
        parameters: vec![
            ("count", count as f64, count as f64, count as f64),
            ("rate_per_hour", rate, lo, hi),
            ("size", size, size, size),
            (
                "threshold_sigma",
                spikes.threshold,
                spikes.threshold,
                spikes.threshold,
            ),
            ("n_without", n_without, n_without, n_without),
        ],
        delta_bic: f64::INFINITY,
    };
    Some((x, finding))
}

/// A temperature effect, when the regression on the temperature `t` is significant and visible:
/// the channel with it subtracted, and the finding.
fn temperature_finding(
    x: &[f64],
    t: &[f64],
    dt_s: f64,
    floor: &NoiseLevels,
    scale: f64,
) -> Option<(Vec<f64>, Finding)> {
    let reg = regression(x, t, dt_s, floor)?;
    if !(reg.z.abs() > TEMPERATURE_Z && visible(reg.coefficient, t, scale)) {
        return None;
    }
    let c1 = reg.coefficient;
    // Beside a straight line, is the temperature still needed? If not, its effect
    // cannot be told from a rate ramp (a temperature that rises steadily).
    let beside_line = regress_detrended(x, t).map(|(cd, w, resid)| {
        let lv = noise_levels(&resid, dt_s).at_least(floor);
        cd / coloured_variance(&w, dt_s, &lv)
            .max(f64::MIN_POSITIVE)
            .sqrt()
    });
    let cannot_tell = beside_line.is_none_or(|z| z.abs() <= TEMPERATURE_Z);
    let finding = Finding {
        cannot_tell_from: if cannot_tell {
            vec![noise::Effect::RateRamp]
        } else {
            vec![]
        },
        // A coefficient that is not finite is no finding.
        term: noise::TemperatureBias::new(c1).ok()?.into(),
        parameters: vec![("coefficient", c1, c1 - 1.96 * reg.sd, c1 + 1.96 * reg.sd)],
        delta_bic: reg.z * reg.z - (x.len() as f64).ln(),
    };
    Some((reg.corrected, finding))
}

/// A warm-up transient, when its fit is significant and visible: the channel with it subtracted,
/// and the finding.
fn transient_finding(
    x: &[f64],
    dt_s: f64,
    floor: &NoiseLevels,
    scale: f64,
) -> Option<(Vec<f64>, Finding)> {
    let tr = fit_transient(x, dt_s, floor)?;
    if !(tr.z.abs() > TRANSIENT_Z && visible(tr.amplitude, &[0.0, 1.0], scale)) {
        return None;
    }
    let sd = (tr.amplitude / tr.z).abs();
    let finding = Finding {
        cannot_tell_from: vec![],
        // Values the constructor refuses are no finding.
        term: noise::WarmupTransient::new(tr.amplitude, tr.tau_s, false)
            .ok()?
            .into(),
        parameters: vec![
            (
                "amplitude",
                tr.amplitude,
                tr.amplitude - 1.96 * sd,
                tr.amplitude + 1.96 * sd,
            ),
            ("tau_s", tr.tau_s, tr.tau_lo_s, tr.tau_hi_s),
        ],
        delta_bic: tr.z * tr.z - (x.len() as f64).ln(),
    };
    Some((tr.corrected, finding))
}

/// [`preprocess`] of a log, each regression's noise floor from the sensor model's levels
/// ([`model_levels`]).
pub fn preprocess_log(log: &crate::input::LogInput, model: &noise::SensorModel) -> Preprocessed {
    preprocess(
        log.channels,
        log.temperature_c,
        log.dt_s,
        &model_levels(model),
    )
}

/// The noise levels of the sensor model's channels (white, flicker B, rate random walk K; a Woodman
/// bias random walk counts as K), the floor of the regressions' coloured-noise levels.
pub fn model_levels(model: &noise::SensorModel) -> ImuChannels<NoiseLevels> {
    ImuChannels::from_fn(|c| {
        let a = model.axis(c.sensor(), c.axis());
        let (b, k_bi) = match a.get::<noise::BiasInstability>() {
            Some(noise::BiasInstability::Flicker(f)) => (f.b(), 0.0),
            Some(noise::BiasInstability::RandomWalk(w)) => {
                (0.0, w.stability() / w.period_s().sqrt())
            }
            None => (0.0, 0.0),
        };
        NoiseLevels {
            n: a.white_noise_density().unwrap_or(0.0),
            b,
            k: a.get::<noise::RateRandomWalk>()
                .map_or(0.0, noise::RateRandomWalk::density)
                .hypot(k_bi),
        }
    })
}
