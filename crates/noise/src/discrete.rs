//! The exact discrete processes several terms share (docs/model.md §3): the normal draws, the
//! bank of first-order Gauss-Markov processes (flicker's band, the Gauss-Markov term) and the
//! random walk (rate random walk, Woodman's bias random walk). Each takes its RNG as an argument.

use crate::wide::NormalStream;
use rand::Rng;

/// One standard normal (rand_distr's `StandardNormal`, bit for bit; inlined, see `ziggurat`).
#[inline]
pub(crate) fn normal<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    crate::ziggurat::standard_normal(rng)
}

/// `n` fresh normals of `stream` in `scratch` (grown as needed).
pub(crate) fn draws<'a>(
    stream: &mut NormalStream,
    scratch: &'a mut Vec<f64>,
    n: usize,
) -> &'a [f64] {
    if scratch.len() < n {
        scratch.resize(n, 0.0);
    }
    stream.fill(&mut scratch[..n]);
    &scratch[..n]
}

/// A bank of independent first-order Gauss-Markov processes, summed (one process, or flicker's band).
/// Exact discretisation (docs/model.md §3, rotors_simulator / Maybeck 4-114):
/// x_{k+1} = phi x_k + sigma sqrt(1 - phi^2) w_k, phi = e^{-dt/T}; started from the stationary distribution.
///
/// Multi-rate option ([`GaussMarkovBank::multirate`]): a component whose correlation time T is at
/// least `1 / HOLD_FRACTION` = 1000 samples is advanced exactly only every `m = floor(HOLD_FRACTION T / dt)`
/// samples, x_{j+m} = phi^m x_j + sigma sqrt(1 - phi^(2m)) w (the same exact discretisation at interval
/// m dt, so its values on the coarse grid are an exact sample of the process) and held in between.
/// Over a hold interval M = m dt <= T / 1000 such a component moves like a random walk of density
/// K^2 = 2 sigma^2 / T (docs/model.md §2); a random walk updated every m samples with m times the step
/// variance has, averaged over the grid's phase (which the overlapping estimator does), exactly the
/// same Allan variance K^2 dt (2n^2 + 1)/(6n) at every tau = n dt as one updated every sample, so
/// the hold changes that component's Allan variance only at relative order M/T <= 1e-3
/// (computed exactly in `tests/held_gauss_markov.rs`: at most 5.0e-4 relative, about M/(2T), at
/// every tau); its k-fold integrals change at most at relative order M/T (the held value lags the
/// process by less than M; not computed exactly, the montecarlo crate's law tests cover flicker
/// alone). It saves the draws of the slow components:
/// the default flicker band 0.1 s .. 1e5 s at 100 Hz needs 3.1 instead of 7 normals per sample.
/// The draws remain a pure function of the sample index, so results do not depend on scheduling.
#[derive(Clone, Debug)]
pub struct GaussMarkovBank {
    /// Components advanced every sample.
    phi: Vec<f64>,
    drive: Vec<f64>,
    state: Vec<f64>,
    /// Components advanced every `every` samples and held in between.
    held: Vec<HeldComponent>,
    /// Sum of the held components' states (changes only when one of them is updated).
    held_sum: f64,
    /// Samples between the last and the next update of any held component, and samples left until it.
    event_span: u32,
    until_event: u32,
    /// Subtracted from every value: 0 by default (bit-identical output), the value at t = 0 after
    /// [`GaussMarkovBank::reference_to_start`].
    offset: f64,
    /// (correlation time s, stationary std, initial state) of each component, in component order:
    /// what [`GaussMarkovBank::reference_to_window_mean`] conditions on.
    start: Vec<(f64, f64, f64)>,
}

#[derive(Clone, Copy, Debug)]
struct HeldComponent {
    /// phi^m and sigma sqrt(1 - phi^(2m)) for the hold of m = `every` samples.
    phi: f64,
    drive: f64,
    state: f64,
    every: u32,
    /// Samples left before the next update.
    left: u32,
}

/// Largest hold interval of a [`GaussMarkovBank::multirate`] component, as a fraction of its
/// correlation time.
pub const HOLD_FRACTION: f64 = 1e-3;

impl GaussMarkovBank {
    /// `components`: (correlation time s, stationary std); the initial state is drawn from `rng`.
    /// Every component is advanced every sample.
    pub fn new<R: Rng + ?Sized>(components: &[(f64, f64)], dt_s: f64, rng: &mut R) -> Self {
        Self::with_holds(components, dt_s, rng, |_| 1)
    }

    /// As [`GaussMarkovBank::new`], but a component of correlation time T >= 1000 dt is updated
    /// exactly every m = floor(T / (1000 dt)) samples and held in between (see the type's docs).
    pub fn multirate<R: Rng + ?Sized>(components: &[(f64, f64)], dt_s: f64, rng: &mut R) -> Self {
        Self::with_holds(components, dt_s, rng, |tc| {
            (HOLD_FRACTION * tc / dt_s)
                .floor()
                .clamp(1.0, f64::from(u32::MAX)) as u32
        })
    }

    /// The hold of each component from its correlation time; initial states drawn in component order.
    fn with_holds<R: Rng + ?Sized>(
        components: &[(f64, f64)],
        dt_s: f64,
        rng: &mut R,
        hold: impl Fn(f64) -> u32,
    ) -> Self {
        let mut bank = GaussMarkovBank {
            phi: Vec::new(),
            drive: Vec::new(),
            state: Vec::new(),
            held: Vec::new(),
            held_sum: 0.0,
            event_span: u32::MAX,
            until_event: u32::MAX,
            offset: 0.0,
            start: Vec::with_capacity(components.len()),
        };
        for &(tc, s) in components {
            let x0 = s * normal(rng);
            bank.start.push((tc, s, x0));
            let every = hold(tc);
            let step = f64::from(every) * dt_s;
            let phi = (-step / tc).exp();
            // sigma sqrt(1 - phi^2) = sigma sqrt(-expm1(-2 step/T)), accurate for T >> step.
            let drive = s * (-(-2.0 * step / tc).exp_m1()).sqrt();
            if every == 1 {
                bank.phi.push(phi);
                bank.drive.push(drive);
                bank.state.push(x0);
            } else {
                bank.held.push(HeldComponent {
                    phi,
                    drive,
                    state: x0,
                    every,
                    left: every,
                });
            }
        }
        bank.sync_held(0);
        bank
    }

    /// Count down `span` samples on every held component (the next event: one of them reaches 0),
    /// update the ones that are due (in component order, each with one value of `draw`), and
    /// recompute the held sum and the next event.
    #[inline]
    fn sync_held(&mut self, span: u32) {
        self.sync_held_with(span, || {
            unreachable!("no held component is due at construction")
        });
    }

    #[inline]
    fn sync_held_with(&mut self, span: u32, mut draw: impl FnMut() -> f64) {
        let mut sum = 0.0;
        let mut next = u32::MAX;
        for h in &mut self.held {
            h.left -= span;
            if h.left == 0 {
                h.left = h.every;
                h.state = h.phi * h.state + h.drive * draw();
            }
            sum += h.state;
            next = next.min(h.left);
        }
        self.held_sum = sum;
        self.event_span = next;
        self.until_event = next;
    }

    /// One sample: the current value (every-sample components in order, then the held sum), then
    /// advance, with the sample's draws from `draw` in order: the every-sample components, then the
    /// held ones that are due, each in component order.
    #[inline(always)]
    fn step(&mut self, mut draw: impl FnMut() -> f64) -> f64 {
        let mut sum = 0.0;
        for ((x, &phi), &d) in self.state.iter_mut().zip(&self.phi).zip(&self.drive) {
            sum += *x;
            *x = phi * *x + d * draw();
        }
        sum += self.held_sum;
        // x - 0.0 == x bit for bit: the default (offset 0) output is unchanged.
        sum -= self.offset;
        if !self.held.is_empty() {
            self.until_event -= 1;
            if self.until_event == 0 {
                self.sync_held_with(self.event_span, draw);
            }
        }
        sum
    }

    /// Reference the process to its value at t = 0: from now on every value is b(t) - b(0), as seen
    /// by a user who estimates the bias perfectly at turn-on and subtracts it (Woodman TR-696
    /// §3.2.1). Call before the first sample (it takes the current value as b(0)); the draws do
    /// not change.
    pub fn reference_to_start(&mut self) {
        // The value `step` returns next, summed in the same order, so the first value is exactly 0.
        let mut sum = 0.0;
        for &x in &self.state {
            sum += x;
        }
        sum += self.held_sum;
        self.offset = sum;
    }

    /// Reference the process to its mean over a calibration window of length `window_s` before
    /// t = 0: from now on every value is b(t) - m, m = (1/W) int_{-W}^0 b(s) ds, as seen by a user
    /// who averages the static output for W seconds before the run and subtracts that estimate.
    /// Each component's window mean is drawn exactly given its value at t = 0 (the window is not
    /// simulated): m_i | b_i(0) ~ N(rho b_i(0), sigma_i^2 c), with (rho, c) from
    /// [`crate::closed_form::gauss_markov_window_mean_moments`] (the conditional Gaussian, \[derived\]
    /// there). One standard normal per component from `rng`, in component order: pass a stream
    /// other than the process's own, so the process's draws (and so b(t)) are unchanged.
    /// Call before the first sample.
    pub fn reference_to_window_mean<R: Rng + ?Sized>(&mut self, window_s: f64, rng: &mut R) {
        let mut m = 0.0;
        for &(tc, s, x0) in &self.start {
            let (rho, _, cond) = crate::closed_form::gauss_markov_window_mean_moments(tc, window_s);
            m += rho * x0 + s * cond.max(0.0).sqrt() * normal(rng);
        }
        self.offset = m;
    }

    /// The current value (sum of the components), then advance one step. Draw order within a step:
    /// the every-sample components, then the held ones that are due, each in component order.
    #[inline]
    pub fn next<R: Rng + ?Sized>(&mut self, rng: &mut R) -> f64 {
        self.step(|| normal(rng))
    }

    /// Add the next `out.len()` values to `out`: the values of as many `next` calls, from the same
    /// draws in the same order (the block's draws are made first, then consumed in that order).
    pub(crate) fn add_block(
        &mut self,
        rng: &mut NormalStream,
        out: &mut [f64],
        scratch: &mut Vec<f64>,
    ) {
        let n = out.len();
        // Held updates within the block: component h is next due in left - (span - until) samples.
        let elapsed = self.event_span - self.until_event;
        let held_draws: usize = self
            .held
            .iter()
            .map(|h| {
                let (left, every) = ((h.left - elapsed) as usize, h.every as usize);
                if n >= left {
                    1 + (n - left) / every
                } else {
                    0
                }
            })
            .sum();
        let w = draws(rng, scratch, n * self.state.len() + held_draws);
        // The usual banks (flicker's band has 2-4 components advanced every sample) with their
        // states in registers; the same operations in the same order as `step`.
        let used = match self.state.len() {
            1 => self.add_block_fixed::<1>(w, out),
            2 => self.add_block_fixed::<2>(w, out),
            3 => self.add_block_fixed::<3>(w, out),
            4 => self.add_block_fixed::<4>(w, out),
            _ => {
                let mut j = 0;
                for v in out.iter_mut() {
                    *v += self.step(|| {
                        j += 1;
                        w[j - 1]
                    });
                }
                j
            }
        };
        debug_assert_eq!(used, w.len());
    }

    /// [`Self::step`] over a block for a bank of `N` every-sample components, the draws taken
    /// from `w` in order; returns how many it used.
    #[inline(always)]
    fn add_block_fixed<const N: usize>(&mut self, w: &[f64], out: &mut [f64]) -> usize {
        let mut x: [f64; N] = std::array::from_fn(|c| self.state[c]);
        let phi: [f64; N] = std::array::from_fn(|c| self.phi[c]);
        let drive: [f64; N] = std::array::from_fn(|c| self.drive[c]);
        let mut j = 0;
        for v in out.iter_mut() {
            let mut sum = 0.0;
            for c in 0..N {
                sum += x[c];
                x[c] = phi[c] * x[c] + drive[c] * w[j + c];
            }
            j += N;
            sum += self.held_sum;
            sum -= self.offset;
            *v += sum;
            if !self.held.is_empty() {
                self.until_event -= 1;
                if self.until_event == 0 {
                    self.sync_held_with(self.event_span, || {
                        j += 1;
                        w[j - 1]
                    });
                }
            }
        }
        self.state.copy_from_slice(&x);
        j
    }
}

/// Random walk b_{k+1} = b_k + K sqrt(dt) w_k from b_0 = 0 (docs/model.md §3, Kalibr: sigma_bd = sigma_b sqrt(dt)).
#[derive(Clone, Copy, Debug)]
pub struct RandomWalk {
    step: f64,
    state: f64,
}

impl RandomWalk {
    pub fn new(k: f64, dt_s: f64) -> RandomWalk {
        RandomWalk {
            step: k * dt_s.sqrt(),
            state: 0.0,
        }
    }
    /// The current value, then advance one step.
    #[inline]
    pub fn next<R: Rng + ?Sized>(&mut self, rng: &mut R) -> f64 {
        let b = self.state;
        self.state += self.step * normal(rng);
        b
    }
    /// Add the next `out.len()` values to `out` (the values of as many `next` calls).
    pub(crate) fn add_block(
        &mut self,
        rng: &mut NormalStream,
        out: &mut [f64],
        scratch: &mut Vec<f64>,
    ) {
        let n = out.len();
        for (v, w) in out.iter_mut().zip(draws(rng, scratch, n)) {
            *v += self.state;
            self.state += self.step * w;
        }
    }
}
