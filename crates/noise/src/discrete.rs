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

    /// Remove the components, (phi, drive, state) each at one sample's step, for a generator that
    /// runs them elsewhere (`crate::block`, exactly: a held component becomes a component advanced
    /// every sample, phi^(1/m) with its stationary std); the offset stays, the bank's value is
    /// then -offset.
    pub(crate) fn take_components(&mut self) -> Vec<(f64, f64, f64)> {
        let phi = std::mem::take(&mut self.phi);
        let drive = std::mem::take(&mut self.drive);
        let state = std::mem::take(&mut self.state);
        let mut out: Vec<(f64, f64, f64)> = phi
            .into_iter()
            .zip(drive)
            .zip(state)
            .map(|((p, d), x)| (p, d, x))
            .collect();
        for h in std::mem::take(&mut self.held) {
            // drive = sigma sqrt(1 - phi^2) for the hold's step (`with_holds`).
            let sigma = h.drive / (-(2.0 * h.phi.ln()).exp_m1()).sqrt();
            let ln1 = h.phi.ln() / f64::from(h.every);
            out.push((ln1.exp(), sigma * (-(2.0 * ln1).exp_m1()).sqrt(), h.state));
        }
        self.held_sum = 0.0;
        self.event_span = u32::MAX;
        self.until_event = u32::MAX;
        out
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
        if self.state.is_empty() {
            let w = self.block_draws(rng, scratch, out.len());
            let used = self.add_block_held(w, out);
            debug_assert_eq!(used, w.len());
        } else if !self.add_block_with(rng, out, scratch, &mut NoFollower) {
            self.add_block_stepwise(rng, out, scratch);
        }
    }

    /// [`Self::add_block`] of a bank of held components only (all slow, or the every-sample ones
    /// run elsewhere, `crate::block`): between updates its value is a constant. The values of
    /// `step` (0 + held sum - offset); returns the draws used.
    fn add_block_held(&mut self, w: &[f64], out: &mut [f64]) -> usize {
        let (mut i, mut j) = (0, 0);
        while i < out.len() {
            let run = self.run_len(out.len() - i);
            let v = 0.0 + self.held_sum - self.offset;
            for o in &mut out[i..i + run] {
                *o += v;
            }
            i += run;
            self.count_down(run, w, &mut j);
        }
        j
    }

    /// Samples from now, at most `left`, before the next held update.
    #[inline(always)]
    fn run_len(&self, left: usize) -> usize {
        if self.held.is_empty() {
            left
        } else {
            left.min(self.until_event as usize)
        }
    }

    /// `run` samples of the held components' countdown (at most to the next event); at the
    /// event, the due updates with draws from `w` at `j` on.
    #[inline(always)]
    fn count_down(&mut self, run: usize, w: &[f64], j: &mut usize) {
        if !self.held.is_empty() {
            // `run` <= until_event, which fits in u32.
            self.until_event -= run as u32;
            if self.until_event == 0 {
                self.sync_held_with(self.event_span, || {
                    *j += 1;
                    w[*j - 1]
                });
            }
        }
    }

    /// [`Self::add_block`] and then `follower`'s processes (a random walk, a resonance: the terms
    /// that follow the flicker band in the generation order) on the same block, in one pass
    /// where the bank has 1 to 4 every-sample components: each value gets the bank's value and
    /// then each follower's, the same additions in the same order as one pass per term, from
    /// the same draws (tested below and in `terms/resonance.rs`). Why: each pass is a chain of
    /// dependent floating-point operations per sample (the bank's recursions, the walk's sum, the
    /// resonance's recursion), and chains side by side take about the time of the longest (the
    /// walk alone was 3.5 % of `imudrift drift`, the resonance 6.6 %, 2026-11-26).
    pub(crate) fn add_block_then(
        &mut self,
        rng: &mut NormalStream,
        out: &mut [f64],
        scratch: &mut Vec<f64>,
        follower: &mut impl Follower,
    ) {
        if !self.add_block_with(rng, out, scratch, follower) {
            self.add_block_stepwise(rng, out, scratch);
            for (i, v) in out.iter_mut().enumerate() {
                follower.add(i, v);
            }
        }
    }

    /// The draws of the next `out.len()` samples: the every-sample components' and the held
    /// updates falling in the block.
    fn block_draws<'a>(
        &self,
        rng: &mut NormalStream,
        scratch: &'a mut Vec<f64>,
        n: usize,
    ) -> &'a [f64] {
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
        draws(rng, scratch, n * self.state.len() + held_draws)
    }

    /// The usual banks (flicker's band has 2-4 components advanced every sample) with their
    /// states in registers, `follower` adding its value after the bank's to each sample; false
    /// (nothing done, nothing drawn) for another number of components.
    #[inline(always)]
    fn add_block_with(
        &mut self,
        rng: &mut NormalStream,
        out: &mut [f64],
        scratch: &mut Vec<f64>,
        follower: &mut impl Follower,
    ) -> bool {
        if !(1..=4).contains(&self.state.len()) {
            return false;
        }
        let w = self.block_draws(rng, scratch, out.len());
        let used = match self.state.len() {
            1 => self.add_block_fixed::<1>(w, out, follower),
            2 => self.add_block_fixed::<2>(w, out, follower),
            3 => self.add_block_fixed::<3>(w, out, follower),
            _ => self.add_block_fixed::<4>(w, out, follower),
        };
        debug_assert_eq!(used, w.len());
        true
    }

    /// [`Self::add_block`] by [`Self::step`], one sample at a time (any number of components).
    fn add_block_stepwise(
        &mut self,
        rng: &mut NormalStream,
        out: &mut [f64],
        scratch: &mut Vec<f64>,
    ) {
        let w = self.block_draws(rng, scratch, out.len());
        let mut j = 0;
        for v in out.iter_mut() {
            *v += self.step(|| {
                j += 1;
                w[j - 1]
            });
        }
        debug_assert_eq!(j, w.len());
    }

    /// [`Self::step`] over a block for a bank of `N` every-sample components, the draws taken
    /// from `w` in order; returns how many it used.
    ///
    /// The block goes in runs between the held components' updates: within a run the held sum
    /// and the offset are constants and the components' states stay in registers, so each sample
    /// is the components' recursions alone (a chain of one multiply-add per component) with no
    /// branch and no memory update of the countdown (that decrement through memory was part of
    /// every sample's dependency chain: the bank was 13 % of `imudrift drift`, 2026-11-26). The
    /// same operations in the same order as `step`: the same bits (tested below).
    #[inline(always)]
    fn add_block_fixed<const N: usize>(
        &mut self,
        w: &[f64],
        out: &mut [f64],
        follower: &mut impl Follower,
    ) -> usize {
        let mut x: [f64; N] = std::array::from_fn(|c| self.state[c]);
        let phi: [f64; N] = std::array::from_fn(|c| self.phi[c]);
        let drive: [f64; N] = std::array::from_fn(|c| self.drive[c]);
        let mut j = 0;
        let mut i = 0;
        while i < out.len() {
            let run = self.run_len(out.len() - i);
            let (held_sum, offset) = (self.held_sum, self.offset);
            let draws = &w[j..j + run * N];
            for (r, (v, d)) in out[i..i + run]
                .iter_mut()
                .zip(draws.chunks_exact(N))
                .enumerate()
            {
                let mut sum = 0.0;
                for c in 0..N {
                    sum += x[c];
                    x[c] = phi[c] * x[c] + drive[c] * d[c];
                }
                sum += held_sum;
                sum -= offset;
                *v += sum;
                follower.add(i + r, v);
            }
            j += run * N;
            i += run;
            self.count_down(run, w, &mut j);
        }
        self.state.copy_from_slice(&x);
        j
    }
}

/// One run's share of [`fused4::run`]: its bank and the bank's draws for the block (made by
/// [`GaussMarkovBank::block_draws`]), the random walk and the resonance that follow it (each with
/// its draws, or None), and its block.
pub(crate) struct FusedLane<'a> {
    pub bank: &'a mut GaussMarkovBank,
    pub bank_draws: &'a [f64],
    pub walk: Option<(&'a mut RandomWalk, &'a [f64])>,
    pub res: Option<(ResonatorLane<'a>, &'a [f64])>,
    pub out: &'a mut [f64],
}

/// A resonance's recursion as [`fused4`] runs it (`terms/resonance.rs` makes it): the transition
/// matrix Phi, the Cholesky factor (l11, l21, l22) of the drive's covariance, the state (x, x').
pub(crate) struct ResonatorLane<'a> {
    pub phi: [[f64; 2]; 2],
    pub chol: (f64, f64, f64),
    pub state: &'a mut [f64; 2],
}

impl GaussMarkovBank {
    /// Whether `other` can run in lockstep with this bank: the same number of every-sample
    /// components, and the held ones on the same schedule (holds and countdowns).
    fn same_schedule(&self, other: &GaussMarkovBank) -> bool {
        self.state.len() == other.state.len()
            && self.event_span == other.event_span
            && self.until_event == other.until_event
            && self.held.len() == other.held.len()
            && self
                .held
                .iter()
                .zip(&other.held)
                .all(|(a, b)| a.every == b.every && a.left == b.left)
    }

    /// The draws of the next `n` samples into `scratch` ([`Self::block_draws`]); their count.
    pub(crate) fn draw_block(
        &self,
        rng: &mut NormalStream,
        scratch: &mut Vec<f64>,
        n: usize,
    ) -> usize {
        self.block_draws(rng, scratch, n).len()
    }
}

/// Four runs' banks, each followed by its random walk and resonance (or not), advanced in one
/// AVX2 loop, run l in lane l of each 256-bit register. Per run and sample the operations of
/// [`GaussMarkovBank::add_block_then`] with its followers, in their order, without fused
/// multiply-adds: each lane gets the bits of its run alone (tested in `tests/lanes.rs`). Why: one
/// run's loop costs about 40 instructions a raw sample (the bank's components, the walk, the
/// resonance, five draw streams, the output) and its resonance a 12-cycle chain; in lanes the
/// arithmetic is shared by four runs and the chains run side by side. The draws and blocks are
/// transposed into sample-major order around the loop.
pub(crate) mod fused4 {
    use super::{FusedLane, GaussMarkovBank};

    /// Runs advanced together.
    pub(crate) const LANES: usize = 4;

    /// Whether four banks can run in [`run`]: the CPU has AVX2, 1-4 every-sample components,
    /// one schedule.
    pub(crate) fn available(banks: [&GaussMarkovBank; LANES]) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            std::arch::is_x86_feature_detected!("avx2")
                && (1..=4).contains(&banks[0].state.len())
                && banks.iter().all(|b| b.same_schedule(banks[0]))
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = banks;
            false
        }
    }

    /// The four lanes (all with or all without a walk, and a resonance; blocks of one length;
    /// [`available`] true).
    pub(crate) fn run(lanes: &mut [FusedLane; LANES]) {
        #[cfg(target_arch = "x86_64")]
        {
            let n = lanes[0].bank.state.len();
            let (w, r) = (lanes[0].walk.is_some(), lanes[0].res.is_some());
            assert!(
                lanes.iter().all(|l| l.walk.is_some() == w
                    && l.res.is_some() == r
                    && l.out.len() == lanes[0].out.len()
                    && l.bank.state.len() == n),
                "lanes of one shape"
            );
            macro_rules! go {
                ($n:literal) => {
                    // SAFETY: `available` checked that the CPU has AVX2.
                    unsafe {
                        match (w, r) {
                            (true, true) => x86::run::<$n, true, true>(lanes),
                            (true, false) => x86::run::<$n, true, false>(lanes),
                            (false, true) => x86::run::<$n, false, true>(lanes),
                            (false, false) => x86::run::<$n, false, false>(lanes),
                        }
                    }
                };
            }
            match n {
                1 => go!(1),
                2 => go!(2),
                3 => go!(3),
                _ => go!(4),
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = lanes;
            unreachable!("fused4::available is false here")
        }
    }

    #[cfg(target_arch = "x86_64")]
    mod x86 {
        use super::{FusedLane, LANES};
        use std::arch::x86_64::*;

        thread_local! {
            /// The transposed draws and block (sample-major, four lanes a sample), reused.
            static SCRATCH: std::cell::RefCell<[Vec<f64>; 4]> = std::cell::RefCell::default();
        }

        /// dst[4 k + l] = src[l][k], k < len ([`crate::transpose4`]).
        #[target_feature(enable = "avx2")]
        fn interleave(src: [&[f64]; LANES], len: usize, dst: &mut Vec<f64>) {
            // Every value below LANES * len is written; a longer buffer's tail is left as it is.
            if dst.len() < LANES * len {
                dst.resize(LANES * len, 0.0);
            }
            crate::transpose4::interleave(
                std::array::from_fn(|l| &src[l][..len]),
                &mut dst[..LANES * len],
            );
        }

        /// Each lane's block from the interleaved `src` ([`crate::transpose4`]).
        #[target_feature(enable = "avx2")]
        fn deinterleave(src: &[f64], dst: &mut [FusedLane; LANES]) {
            let len = dst[0].out.len();
            crate::transpose4::deinterleave(
                &src[..LANES * len],
                dst.each_mut().map(|l| &mut *l.out),
            );
        }

        /// Lane l of a register from four values.
        #[inline(always)]
        fn set(v: [f64; LANES]) -> __m256d {
            // SAFETY: AVX is implied by the callers' AVX2.
            unsafe { _mm256_set_pd(v[3], v[2], v[1], v[0]) }
        }

        #[inline(always)]
        fn get(v: __m256d) -> [f64; LANES] {
            let mut out = [0.0; LANES];
            // SAFETY: four f64 into `out`.
            unsafe { _mm256_storeu_pd(out.as_mut_ptr(), v) };
            out
        }

        /// The four lanes' states and coefficients, one register per quantity (lane l in
        /// element l): the bank's `N` every-sample components, the walk, the resonance.
        struct Regs<const N: usize> {
            x: [__m256d; N],
            phi: [__m256d; N],
            drive: [__m256d; N],
            walk: __m256d,
            step: __m256d,
            /// The resonance's state (x, x'), Phi row by row and the Cholesky factor of Q.
            rx: __m256d,
            rv: __m256d,
            p: [__m256d; 4],
            l: [__m256d; 3],
        }

        impl<const N: usize> Regs<N> {
            /// The lanes' values (a lane without a walk or resonance reads 0: never used).
            #[inline(always)]
            fn load(lanes: &[FusedLane; LANES]) -> Regs<N> {
                let by = |f: &dyn Fn(usize) -> f64| set(std::array::from_fn(f));
                let walk = |f: &dyn Fn(&super::super::RandomWalk) -> f64| {
                    by(&|l| lanes[l].walk.as_ref().map_or(0.0, |w| f(w.0)))
                };
                let res = |f: &dyn Fn(&crate::discrete::ResonatorLane) -> f64| {
                    by(&|l| lanes[l].res.as_ref().map_or(0.0, |r| f(&r.0)))
                };
                Regs {
                    x: std::array::from_fn(|c| by(&|l| lanes[l].bank.state[c])),
                    phi: std::array::from_fn(|c| by(&|l| lanes[l].bank.phi[c])),
                    drive: std::array::from_fn(|c| by(&|l| lanes[l].bank.drive[c])),
                    walk: walk(&|w| w.state),
                    step: walk(&|w| w.step),
                    rx: res(&|r| r.state[0]),
                    rv: res(&|r| r.state[1]),
                    p: [0, 1, 2, 3].map(|k| res(&|r| r.phi[k / 2][k % 2])),
                    l: [res(&|r| r.chol.0), res(&|r| r.chol.1), res(&|r| r.chol.2)],
                }
            }

            /// One sample of the four lanes: the bank's value (its draws at `d`, the held sum
            /// and the offset), then the walk's (its draw at `w`) if `W`, then the resonance's
            /// (its two draws at `r`) if `R`, added to the block's value at `o`; the scalar
            /// code's operations in its order. Safety: AVX2, and four readable values at `d`
            /// (N of them), `w`, `r` (eight) and `o`, writable at `o`.
            #[inline(always)]
            unsafe fn step<const W: bool, const R: bool>(
                &mut self,
                (d, w, r, o): (*const f64, *const f64, *const f64, *mut f64),
                held_sum: __m256d,
                offset: __m256d,
            ) {
                // SAFETY: the caller's.
                unsafe {
                    let mut sum = _mm256_setzero_pd();
                    for c in 0..N {
                        sum = _mm256_add_pd(sum, self.x[c]);
                        self.x[c] = _mm256_add_pd(
                            _mm256_mul_pd(self.phi[c], self.x[c]),
                            _mm256_mul_pd(self.drive[c], _mm256_loadu_pd(d.add(4 * c))),
                        );
                    }
                    sum = _mm256_sub_pd(_mm256_add_pd(sum, held_sum), offset);
                    let mut v = _mm256_add_pd(_mm256_loadu_pd(o), sum);
                    if W {
                        v = _mm256_add_pd(v, self.walk);
                        let dw = _mm256_mul_pd(self.step, _mm256_loadu_pd(w));
                        self.walk = _mm256_add_pd(self.walk, dw);
                    }
                    if R {
                        let ([p00, p01, p10, p11], [l11, l21, l22]) = (self.p, self.l);
                        let (rx, rv) = (self.rx, self.rv);
                        v = _mm256_add_pd(v, rx);
                        let (d0, d1) = (_mm256_loadu_pd(r), _mm256_loadu_pd(r.add(4)));
                        let ax = _mm256_add_pd(_mm256_mul_pd(p00, rx), _mm256_mul_pd(p01, rv));
                        let av = _mm256_add_pd(_mm256_mul_pd(p10, rx), _mm256_mul_pd(p11, rv));
                        self.rx = _mm256_add_pd(ax, _mm256_mul_pd(l11, d0));
                        self.rv = _mm256_add_pd(
                            _mm256_add_pd(av, _mm256_mul_pd(l21, d0)),
                            _mm256_mul_pd(l22, d1),
                        );
                    }
                    _mm256_storeu_pd(o, v);
                }
            }

            /// Each lane's states back into its bank, walk and resonance.
            fn store(&self, lanes: &mut [FusedLane; LANES]) {
                let xs: [[f64; LANES]; N] = self.x.map(get);
                let (ws, rx, rv) = (get(self.walk), get(self.rx), get(self.rv));
                for (l, lane) in lanes.iter_mut().enumerate() {
                    for (state, xs) in lane.bank.state.iter_mut().zip(&xs) {
                        *state = xs[l];
                    }
                    if let Some((w, _)) = &mut lane.walk {
                        w.state = ws[l];
                    }
                    if let Some((r, _)) = &mut lane.res {
                        *r.state = [rx[l], rv[l]];
                    }
                }
            }
        }

        /// The loop ([`super::run`]): `N` every-sample components, a walk if `W`, a resonance if `R`.
        #[target_feature(enable = "avx2")]
        pub(super) fn run<const N: usize, const W: bool, const R: bool>(
            lanes: &mut [FusedLane; LANES],
        ) {
            crate::transpose4::count_block(false);
            SCRATCH.with(|s| {
                let [bank_t, walk_t, res_t, out_t] = &mut *s.borrow_mut();
                let n = lanes[0].out.len();
                let nb = lanes[0].bank_draws.len();
                interleave(std::array::from_fn(|l| lanes[l].bank_draws), nb, bank_t);
                if W {
                    let w = |l: usize| lanes[l].walk.as_ref().map_or(&[][..], |w| w.1);
                    interleave(std::array::from_fn(w), n, walk_t);
                }
                if R {
                    let r = |l: usize| lanes[l].res.as_ref().map_or(&[][..], |r| r.1);
                    interleave(std::array::from_fn(r), 2 * n, res_t);
                }
                interleave(std::array::from_fn(|l| &*lanes[l].out), n, out_t);
                let mut regs = Regs::<N>::load(lanes);
                let mut held = Held::load(lanes);
                let (bt, wt, rt, ot) = (
                    bank_t.as_ptr(),
                    walk_t.as_ptr(),
                    res_t.as_ptr(),
                    out_t.as_mut_ptr(),
                );
                let (mut i, mut j) = (0, 0);
                while i < n {
                    let run = if held.any {
                        (n - i).min(held.until_event as usize)
                    } else {
                        n - i
                    };
                    for k in i..i + run {
                        // SAFETY: AVX2 (this function's); draw j + (k - i) N + c < nb, walk
                        // k < n, resonance 2k + 1 < 2n, block k < n: the interleaved buffers
                        // hold four values for each (the walk's and resonance's only read
                        // when W, R).
                        unsafe {
                            let at = (
                                bt.add(4 * (j + (k - i) * N)),
                                wt.wrapping_add(4 * k),
                                rt.wrapping_add(8 * k),
                                ot.add(4 * k),
                            );
                            regs.step::<W, R>(at, held.sum, held.offset);
                        }
                    }
                    j += run * N;
                    i += run;
                    if held.any {
                        // SAFETY: AVX2 (this function's); the due components' draws are the
                        // bank's next ones, below nb (the bank drew them for this block).
                        j = unsafe { held.advance(run, bt, j) };
                    }
                }
                held.store(lanes);
                deinterleave(out_t, lanes);
                regs.store(lanes);
            });
        }

        /// The four lanes' held components (one schedule: `fused4::available`), their states
        /// in registers (component c of lane l in element l of `state[c]`), the schedule kept
        /// once: [`super::super::GaussMarkovBank::sync_held_with`] for four lanes at a time,
        /// the same operations per lane in its order (so the same bits), without a call and a
        /// loop over the lanes at every update (a component held for m samples updates every m;
        /// m is 2-8 for the fitted ADIS16405 model's faster held components).
        struct Held {
            any: bool,
            phi: Vec<__m256d>,
            drive: Vec<__m256d>,
            state: Vec<__m256d>,
            every: Vec<u32>,
            left: Vec<u32>,
            /// The held states' sum and the bank's offset, per lane.
            sum: __m256d,
            offset: __m256d,
            event_span: u32,
            until_event: u32,
        }

        impl Held {
            #[inline(always)]
            fn load(lanes: &[FusedLane; LANES]) -> Held {
                let bank0 = &*lanes[0].bank;
                let by = |f: &dyn Fn(&super::super::HeldComponent) -> f64| -> Vec<__m256d> {
                    (0..bank0.held.len())
                        .map(|c| set(std::array::from_fn(|l| f(&lanes[l].bank.held[c]))))
                        .collect()
                };
                Held {
                    any: !bank0.held.is_empty(),
                    phi: by(&|h| h.phi),
                    drive: by(&|h| h.drive),
                    state: by(&|h| h.state),
                    every: bank0.held.iter().map(|h| h.every).collect(),
                    left: bank0.held.iter().map(|h| h.left).collect(),
                    sum: set(std::array::from_fn(|l| lanes[l].bank.held_sum)),
                    offset: set(std::array::from_fn(|l| lanes[l].bank.offset)),
                    event_span: bank0.event_span,
                    until_event: bank0.until_event,
                }
            }

            /// After `run` samples: count down, and at an event update the due components from
            /// the lanes' draws at `j` on (interleaved at `bt`), in component order, and
            /// recompute the sum and the next event; the next draw's index. Safety: AVX2, and
            /// four values at `bt` for each draw used.
            #[inline(always)]
            unsafe fn advance(&mut self, run: usize, bt: *const f64, mut j: usize) -> usize {
                // `run` <= until_event, which fits in u32.
                self.until_event -= run as u32;
                if self.until_event != 0 {
                    return j;
                }
                let span = self.event_span;
                let mut next = u32::MAX;
                // SAFETY: the caller's.
                unsafe {
                    let mut sum = _mm256_setzero_pd();
                    for c in 0..self.state.len() {
                        self.left[c] -= span;
                        if self.left[c] == 0 {
                            self.left[c] = self.every[c];
                            self.state[c] = _mm256_add_pd(
                                _mm256_mul_pd(self.phi[c], self.state[c]),
                                _mm256_mul_pd(self.drive[c], _mm256_loadu_pd(bt.add(4 * j))),
                            );
                            j += 1;
                        }
                        sum = _mm256_add_pd(sum, self.state[c]);
                        next = next.min(self.left[c]);
                    }
                    self.sum = sum;
                }
                self.event_span = next;
                self.until_event = self.event_span;
                j
            }

            /// The states, countdowns, sum and next event back into each lane's bank.
            fn store(&self, lanes: &mut [FusedLane; LANES]) {
                let states: Vec<[f64; LANES]> = self.state.iter().map(|&v| get(v)).collect();
                let sums = get(self.sum);
                for (l, lane) in lanes.iter_mut().enumerate() {
                    let bank = &mut *lane.bank;
                    for (c, h) in bank.held.iter_mut().enumerate() {
                        h.state = states[c][l];
                        h.left = self.left[c];
                    }
                    if self.any {
                        bank.held_sum = sums[l];
                        bank.event_span = self.event_span;
                        bank.until_event = self.until_event;
                    }
                }
            }
        }
    }
}

/// A process whose values the bank's block loop adds after its own to each sample
/// ([`GaussMarkovBank::add_block_then`]), its draws for the block made beforehand.
pub(crate) trait Follower {
    /// Add this process's value at sample `i` of the block to `v`, then advance it.
    fn add(&mut self, i: usize, v: &mut f64);
}

/// Nothing follows the bank.
struct NoFollower;

impl Follower for NoFollower {
    #[inline(always)]
    fn add(&mut self, _i: usize, _v: &mut f64) {}
}

/// Two followers, in order.
impl<A: Follower, B: Follower> Follower for (A, B) {
    #[inline(always)]
    fn add(&mut self, i: usize, v: &mut f64) {
        self.0.add(i, v);
        self.1.add(i, v);
    }
}

/// A random walk's [`RandomWalk::add_block`] over a block, as a [`Follower`]; its state is
/// written back by [`WalkFollower::finish`].
pub(crate) struct WalkFollower<'a> {
    walk: &'a mut RandomWalk,
    state: f64,
    step: f64,
    draws: &'a [f64],
}

impl<'a> WalkFollower<'a> {
    /// The walk over a block whose draws (one per sample) are `draws`.
    pub(crate) fn new(walk: &'a mut RandomWalk, draws: &'a [f64]) -> WalkFollower<'a> {
        let (state, step) = (walk.state, walk.step);
        WalkFollower {
            walk,
            state,
            step,
            draws,
        }
    }

    /// Keep the walk's state at the end of the block.
    pub(crate) fn finish(self) {
        self.walk.state = self.state;
    }
}

impl Follower for WalkFollower<'_> {
    #[inline(always)]
    fn add(&mut self, i: usize, v: &mut f64) {
        *v += self.state;
        self.state += self.step * self.draws[i];
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
    /// (K sqrt(dt), the current state).
    pub(crate) fn parts(&self) -> (f64, f64) {
        (self.step, self.state)
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

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    /// The bank and a random walk in one pass give the bits of the two passes one after the
    /// other, for 1 to 5 every-sample components (5: the stepwise fallback) and held ones.
    #[test]
    fn bank_then_walk_equals_the_two_passes() {
        for every in 1..=5usize {
            let comps: Vec<(f64, f64)> = (0..every)
                .map(|c| (0.05 * (c + 1) as f64, 1e-3 * (c + 1) as f64))
                .chain([(20.0, 2e-4), (2500.0, 3e-4)])
                .collect();
            let mut seed_rng = crate::ImuRng::seed_from_u64(4);
            let mut fused = GaussMarkovBank::multirate(&comps, 0.0025, &mut seed_rng);
            let mut apart = fused.clone();
            let (mut walk_a, mut walk_b) =
                (RandomWalk::new(3e-5, 0.0025), RandomWalk::new(3e-5, 0.0025));
            let mut r = [1u64, 2, 3, 4].map(|s| NormalStream::new(crate::ImuRng::seed_from_u64(s)));
            let [ra, wa, rb, wb] = &mut r;
            *rb = ra.clone();
            *wb = wa.clone();
            let n = 30_000;
            let (mut a, mut b) = (vec![0.5; n], vec![0.5; n]);
            let (mut s1, mut s2, mut s3) = (Vec::new(), Vec::new(), Vec::new());
            let mut k = 0;
            for len in [2048usize, 1, 5, 512, 4095].iter().cycle() {
                if k >= n {
                    break;
                }
                let end = (k + len).min(n);
                let mut f = WalkFollower::new(&mut walk_a, draws(wa, &mut s2, end - k));
                fused.add_block_then(ra, &mut a[k..end], &mut s1, &mut f);
                f.finish();
                apart.add_block(rb, &mut b[k..end], &mut s3);
                walk_b.add_block(wb, &mut b[k..end], &mut s3);
                k = end;
            }
            assert!(
                a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()),
                "{every} every-sample components"
            );
        }
    }

    /// The bank's block path (runs between the held updates, states in registers) gives the bits
    /// of `step` sample by sample on the same stream, for 1 to 5 every-sample components with and
    /// without held ones, offsets included, in blocks of mixed lengths.
    #[test]
    fn block_path_equals_step_by_step() {
        for every in 1..=5usize {
            for held in [0usize, 1, 4] {
                // Every-sample components (T < 1000 dt), then slow ones held for 2 .. 500 samples.
                let comps: Vec<(f64, f64)> = (0..every)
                    .map(|c| (0.05 * (c + 1) as f64, 1e-3 * (c + 1) as f64))
                    .chain((0..held).map(|h| (20.0 * 5f64.powi(h as i32), 2e-4)))
                    .collect();
                let mut seed_rng = crate::ImuRng::seed_from_u64(9);
                let mut fast = GaussMarkovBank::multirate(&comps, 0.01, &mut seed_rng);
                fast.offset = 1.5e-4;
                let mut slow = fast.clone();
                let n = 20_000;
                let mut a = vec![0.25; n];
                let mut b = a.clone();
                let mut s1 = NormalStream::new(crate::ImuRng::seed_from_u64(3));
                let mut s2 = s1.clone();
                let mut scratch = Vec::new();
                let mut k = 0;
                for len in [1usize, 3, 512, 7, 2048, 999].iter().cycle() {
                    if k >= n {
                        break;
                    }
                    let end = (k + len).min(n);
                    fast.add_block(&mut s1, &mut a[k..end], &mut scratch);
                    k = end;
                }
                for v in &mut b {
                    *v += slow.step(|| s2.normal());
                }
                assert!(
                    a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()),
                    "{every} every-sample, {held} held"
                );
            }
        }
    }
}
