//! Long-averaging-time terms fitted to the Allan gap and the drift gap together (docs/diagnose.md,
//! "Drift in the loop"): where the measured drift leaves the model's band although the Allan
//! curve no longer names anything, a slow term the Allan points of the runs cannot resolve alone
//! may still be what the drift integrates.
//!
//! A candidate (rate random walk, bias-instability level, rate ramp, Gauss-Markov process with a
//! correlation time at or beyond the longest averaging time) changes the Allan variance by
//! (c - c0) f(tau) (`fit`) and the mean square of each drift quantity by (c - c0) u, u the
//! quantity's mean square per unit c of the term alone on the channel under the protocol: drift
//! errors are linear in the channel's error to first order (Woodman §3.2, §4.2: heading,
//! attitude and position integrate the rate and specific-force errors), so the independent
//! terms' mean squares add, as their Allan variances do. u is measured by simulating the term
//! alone (`UnitDrift`), at a coarser sample interval (the slow terms' drift does not depend on
//! it: their exact discrete processes are sampled every k dt, at least 100 samples per shortest
//! horizon) and many logs; it proposes a level, which the re-simulation at the logs' own rate
//! then confirms or rejects.
//!
//! The level minimises chi2 = sum over taus of z_allan^2 + w sum over the channel's (horizon,
//! quantity) pairs of z_drift^2 (`drift_gap::DriftFit::z`), and the candidate is named by the
//! Allan rule (`Settings::min_delta_bic`): its BIC = chi2 + k ln M (M taus and drift pairs) + the
//! cost of a searched shape must be below the unchanged model's chi2 by at least that much.
//!
//! Where the model cannot follow the channel's Allan curve (its chi2 over the M taus the candidate
//! can move, those where the term at its reference level makes at least a tenth of the band's Allan
//! variance, beyond the 0.999 quantile of chi2 with M degrees of freedom: an overdispersed fit, e.g.
//! a filter shape the model's filters do not have), the Allan part is divided by the dispersion
//! c = chi2 / M of the model as it stands there (`allan_dispersion`): the quasi-likelihood
//! correction for overdispersion (Burnham & Anderson, Model Selection and Multimodel Inference,
//! 2nd ed. 2002, §2.5, QAIC; Wedderburn 1974). Local, because a misfit at the shortest taus (a
//! filter) says nothing about how well the long taus a slow term moves are known.
//! Without it, a curve the model misses by 60 sigma decides every level by its small shifts, and a
//! drift 12 sigma off moves nothing. A fit inside its chi2 quantile is left as it is (c = 1), so a
//! clean run's likelihood, and the false-alarm rate measured on clean runs, do not change.
//!
//! The weight w (`DriftFitInput::drift_weight`) is there because the drift pairs are not
//! independent: gx informs roll, horizontal position and velocity at every horizon, and under a
//! static protocol the last two are the tilt error integrated, nearly the same draw; counted as
//! independent, one 2-sigma drift excursion weighed like six, and clean runs pooled four at a time
//! named a slow term on gx or gy in 11 of 100 diagnoses with the drift check (10 by this loop; 0
//! of 100 without it; docs/diagnose.md, "False alarms of the pooled rule"). The correlation of
//! the pairs comes from the model's own simulated logs (`drift_gap`), so the drift part of the
//! statistic is scaled to its null distribution under the model, not to our tests.

use crate::candidates::{
    drift_candidates, filtered_allan, level_term, shape_search_penalty, unit_family_signature,
    unit_signature,
};
use crate::drift_gap::DriftFit;
use crate::fit::{aic, bic, FitData, CHI2_1_95};
use crate::gap::{Band, Curve, Gap};
use crate::model_terms::{
    fitted_term, flicker_band, has_random_walk_bias_instability, set_term, squared_level,
};
use crate::protocol::{all_segment_errors, Protocol, Quantity};
use crate::simulate::{map_static_logs, LogJob, SimSetup};
use crate::trials::{at_squared_level, Named, Trial};
use noise::{Channel, Effect, GaussMarkov, ModelError, SensorModel, SlowGaussMarkov, Term};

/// Correlation times of the Gauss-Markov candidate per longest averaging time tau_max: at and
/// beyond it (a shorter one the Allan curve resolves itself).
const GAUSS_MARKOV_TIMES: [f64; 3] = [1.0, 3.0, 10.0];

/// First montecarlo run index of the unit simulations (apart from the bands' runs).
const UNIT_RUN_BASE: u64 = 1 << 40;

/// How the drift of a term alone is simulated: the runs' lengths, the protocol, the seed.
pub(crate) struct UnitDrift<'a> {
    pub(crate) dt_s: f64,
    pub(crate) samples: &'a [usize],
    pub(crate) protocol: &'a Protocol,
    pub(crate) seed: u64,
    /// Simulated logs per run length.
    pub(crate) logs: usize,
    /// The front end's stop flag (`SimSetup::stop`): once set, no further log is simulated and
    /// the mean squares are NaN (the caller sees the flag and drops them).
    pub(crate) stop: Option<&'a std::sync::atomic::AtomicBool>,
}

impl UnitDrift<'_> {
    /// The decimation k: the largest of a few that keeps every horizon and window a whole number
    /// of k dt and the shortest horizon at least 100 samples.
    fn decimation(&self) -> usize {
        let p = self.protocol;
        let spans: Vec<f64> = p
            .horizons_s
            .iter()
            .copied()
            .chain([p.lead_s()].into_iter().filter(|w| *w > 0.0))
            .map(|t| t / self.dt_s)
            .collect();
        let shortest = spans.iter().copied().fold(f64::INFINITY, f64::min);
        [100usize, 50, 40, 25, 20, 10, 5, 4, 2]
            .into_iter()
            .find(|&k| {
                shortest / k as f64 >= 100.0
                    && spans.iter().all(|s| {
                        let q = s / k as f64;
                        (q - q.round()).abs() < 1e-9 * q.max(1.0)
                    })
            })
            .unwrap_or(1)
    }

    /// Mean square of every quantity at every protocol horizon (`[h][Quantity::ALL index]`) of
    /// `model`'s channel `c` alone (the other channels ideal), over the simulated logs at every
    /// run length.
    pub(crate) fn mean_squares(&self, model: &SensorModel, c: Channel) -> Vec<[f64; 5]> {
        let k = self.decimation();
        let dt_u = self.dt_s * k as f64;
        let lengths: Vec<usize> = self.samples.iter().map(|n| n / k).collect();
        let setup = SimSetup {
            latitude_deg: self.protocol.latitude_deg,
            ..SimSetup::plain(
                dt_u,
                lengths.iter().copied().max().unwrap_or(0),
                noise::ImuChannels::from_fn(|i| i == c),
            )
            .stopped_by(self.stop)
        };
        let nh = self.protocol.horizons_s.len();
        let jobs: Vec<LogJob> = (0..self.logs as u64)
            .map(|s| LogJob {
                model,
                setup: setup.clone(),
                seed: self.seed,
                run: UNIT_RUN_BASE + s,
            })
            .collect();
        let sums = map_static_logs(&jobs, |_, log| {
            let mut acc: Vec<([f64; 5], usize)> = vec![([0.0; 5], 0usize); nh];
            for &n in &lengths {
                let chans = noise::ImuChannels::from_fn(|i| (i == c).then(|| &log[i][..n])).0;
                for (h, e) in all_segment_errors(&chans, dt_u, self.protocol)
                    .iter()
                    .enumerate()
                {
                    for (qi, q) in Quantity::ALL.iter().enumerate() {
                        acc[h].0[qi] += e.values(*q).iter().map(|x| x * x).sum::<f64>();
                    }
                    acc[h].1 += e.len();
                }
            }
            acc
        });
        let Some(sums) = sums else {
            return vec![[f64::NAN; 5]; nh];
        };
        // The pooled mean square from each log's sum of squares and count (no log's segments
        // are kept to hand to `stats::mean_square`); none: 0.
        (0..nh)
            .map(|h| {
                let count: usize = sums.iter().map(|a| a[h].1).sum();
                std::array::from_fn(|qi| {
                    sums.iter().map(|a| a[h].0[qi]).sum::<f64>() / count.max(1) as f64
                })
            })
            .collect()
    }
}

/// What one channel's drift candidates are fitted to.
pub(crate) struct DriftFitInput<'a> {
    pub(crate) model: &'a SensorModel,
    pub(crate) channel: Channel,
    pub(crate) measured: &'a Curve,
    pub(crate) band: &'a Band,
    pub(crate) gap: &'a Gap,
    pub(crate) dt_s: f64,
    /// The rate ramp's level (`trials`: the runs' least-squares slope).
    pub(crate) ramp_slope: f64,
    /// The channel's informed (horizon index, quantity, drift numbers), and the correlation of
    /// their z-scores under the model (`DriftGap::correlation_of_channel`, same order).
    pub(crate) drift: Vec<(usize, Quantity, DriftFit)>,
    pub(crate) correlation: Vec<Vec<f64>>,
    pub(crate) unit: UnitDrift<'a>,
}

/// A candidate of the drift loop: its trial (as an Allan candidate's, for the report) and its
/// BIC gain on the joint likelihood.
pub(crate) struct DriftTrial {
    pub(crate) trial: Trial,
    pub(crate) delta_bic: f64,
    /// The channel's rate random walk re-levelled with the candidate (`with_random_walk`).
    pub(crate) partner: Option<Partner>,
}

/// The rate random walk at the level fitted with a candidate: its term (None: removed), its
/// parameters before and at the ends of the 95 % interval, its change of the Allan variance.
pub(crate) struct Partner {
    pub(crate) term: Option<Term>,
    pub(crate) model: Named,
    pub(crate) lo: Named,
    pub(crate) hi: Named,
    pub(crate) delta_avar: Vec<f64>,
    pub(crate) signature: Vec<f64>,
}

/// One term's level moving in the joint chi2: its Allan signature, unit drift and level before.
struct Move<'a> {
    f: &'a [f64],
    u: &'a [[f64; 5]],
    c0: f64,
    /// The level whose Allan variance decides where the term can move the curve (the model's own,
    /// else the unit level).
    c_ref: f64,
}

/// The channel's fitted rate random walk: its term, Allan signature per unit squared level, unit
/// drift and squared level.
struct Walk<'a> {
    term: &'a Term,
    f: Vec<f64>,
    u: Vec<[f64; 5]>,
    c0: f64,
}

impl Walk<'_> {
    fn as_move(&self) -> Move<'_> {
        Move {
            f: &self.f,
            u: &self.u,
            c0: self.c0,
            c_ref: self.c0,
        }
    }
}

/// How the joint chi2 weighs its parts: the drift pairs by `w`, the Allan part divided by
/// `dispersion`.
#[derive(Clone, Copy)]
struct Scale {
    w: f64,
    dispersion: f64,
}

/// A fitted level (and the random walk's, when re-levelled with it).
struct Level {
    c: f64,
    bic: f64,
    aic: f64,
    interval: (f64, f64),
    partner: Option<Partner>,
}

impl DriftFitInput<'_> {
    /// The joint chi2 when each moved term's level goes from its c0 to c (its Allan signature `f`
    /// and unit drift `u[h][q]`): the Allan part divided by `scale.dispersion` (module doc), the
    /// drift pairs weighed by `scale.w` ([`DriftFitInput::drift_weight`]).
    fn chi2(&self, data: &FitData, moves: &[(&Move, f64)], scale: Scale) -> f64 {
        let mut delta_avar = vec![0.0; data.ln_meas.len()];
        for (m, c) in moves {
            for (d, f) in delta_avar.iter_mut().zip(m.f) {
                *d += (c - m.c0) * f;
            }
        }
        let allan = data.chi2(&delta_avar, 1.0) / scale.dispersion;
        let drift: f64 = self
            .drift
            .iter()
            .map(|(h, q, d)| {
                let qi = quantity_index(*q);
                let delta: f64 = moves.iter().map(|(m, c)| (c - m.c0) * m.u[*h][qi]).sum();
                d.z(delta).powi(2)
            })
            .sum();
        allan + scale.w * drift
    }

    /// The weight of the drift pairs' chi2 for a candidate with unit drift `u` (module doc): the
    /// pairs' z-scores are correlated (R, `correlation`), and a one-level candidate moves them
    /// along a = dz/dc, a_i = u_i / (2 MS_i scale_i) up to sign (`DriftFit::z` at c0). Their
    /// independence chi2 sum z_i^2 then overstates the evidence along a by a'Ra / a'a (its
    /// projection a'z has variance a'Ra, not a'a); the weight a'a / a'Ra (at most 1) makes the
    /// drift part of the likelihood-ratio statistic chi2_1 again: the magnitude adjustment of a
    /// composite likelihood for a scalar parameter, H / J with sensitivity H = a'a and
    /// variability J = a'Ra (Varin, Reid & Firth 2011, Statistica Sinica 21, 5-42, §2.3;
    /// Chandler & Bate 2007, Biometrika 94, 167-183).
    fn drift_weight(&self, u: &[[f64; 5]]) -> f64 {
        let a: Vec<f64> = self
            .drift
            .iter()
            .map(|(h, q, d)| u[*h][quantity_index(*q)] / (2.0 * d.mean_square * d.scale))
            .collect();
        let aa: f64 = a.iter().map(|x| x * x).sum();
        let ara: f64 = (0..a.len())
            .map(|i| {
                (0..a.len())
                    .map(|j| {
                        let r = self.correlation.get(i).and_then(|row| row.get(j));
                        a[i] * a[j] * r.copied().unwrap_or(1.0)
                    })
                    .sum::<f64>()
            })
            .sum();
        if ara > aa && aa > 0.0 {
            aa / ara
        } else {
            1.0
        }
    }

    /// Every drift candidate fitted (module doc), the best shape of each.
    pub(crate) fn trials(&self) -> Vec<DriftTrial> {
        let ln_meas: Vec<f64> = self.measured.adev.iter().map(|a| a.ln()).collect();
        let data = FitData {
            ln_meas: &ln_meas,
            ln_band: &self.band.ln_mean,
            avar_band: &self.band.avar_mean,
            s: &self.gap.s,
        };
        let tau_max = self.measured.tau_s.last().copied().unwrap_or(1.0);
        let mut out = Vec::new();
        for candidate in drift_candidates() {
            if candidate == Effect::BiasInstability
                && has_random_walk_bias_instability(self.model, self.channel)
            {
                continue;
            }
            let effect = match candidate {
                Effect::GaussMarkov => self.gauss_markov_slot(tau_max),
                e => e,
            };
            let current = fitted_term(self.model, self.channel, effect);
            let own_shape = current.and_then(|c| c.parameters().get(1).map(|p| p.1));
            let shapes: Vec<Option<f64>> = match (is_gauss_markov(effect), own_shape) {
                (true, Some(t)) => vec![Some(t)],
                (true, None) => GAUSS_MARKOV_TIMES
                    .iter()
                    .map(|k| Some(k * tau_max))
                    .collect(),
                _ => vec![None],
            };
            let penalty = shape_search_penalty(shapes.len());
            let best = shapes
                .into_iter()
                .filter_map(|shape| self.fit(&data, effect, shape, current, penalty))
                .min_by(|a, b| a.trial.bic.total_cmp(&b.trial.bic));
            out.extend(best);
        }
        out
    }

    /// Where the slow Gauss-Markov candidate goes: `gauss_markov` when the channel has none or has
    /// one at least as slow as the candidate's shortest correlation time (then it is refitted at
    /// its own), else `slow_gauss_markov` (the fast one, a stand-in the Allan rounds fitted at the
    /// shortest averaging times, stays).
    pub(crate) fn gauss_markov_slot(&self, tau_max: f64) -> Effect {
        gauss_markov_slot(self.model, self.channel, tau_max)
    }

    /// One candidate at one shape: its level alone, and (`with_random_walk`) with the channel's
    /// rate random walk re-levelled beside it; the better by BIC.
    fn fit(
        &self,
        data: &FitData,
        effect: Effect,
        shape: Option<f64>,
        current: Option<&Term>,
        penalty: f64,
    ) -> Option<DriftTrial> {
        let f = self.signature(effect, shape);
        let c0 = squared_level(current);
        // The unit level: the model's own, else the one at which the term alone would reach the
        // measured Allan variance at the longest tau (the drift is then of a realistic size).
        let last = f.len().checked_sub(1)?;
        let c_unit = if c0 > 0.0 {
            c0
        } else {
            self.measured.adev[last].powi(2) / f[last]
        };
        if !(c_unit > 0.0 && c_unit.is_finite()) {
            return None;
        }
        // The term at squared level c (a Gauss-Markov process at the shape tried).
        let term_at = |c: f64| -> Result<Term, ModelError> {
            match shape {
                Some(tau_s) if effect == Effect::SlowGaussMarkov => {
                    Ok(SlowGaussMarkov::new(c.sqrt(), tau_s)?.into())
                }
                Some(tau_s) => Ok(GaussMarkov::new(c.sqrt(), tau_s)?.into()),
                None => level_term(self.model, self.channel, effect, c.sqrt()),
            }
        };
        let u = self.unit_drift(&term_at(c_unit).ok()?, c_unit);
        let own = Move {
            f: &f,
            u: &u,
            c0,
            c_ref: c_unit,
        };
        // The channel's random walk, re-levelled beside the candidate (`with_random_walk`).
        let walk = (!matches!(effect, Effect::RateRamp | Effect::RateRandomWalk))
            .then(|| self.random_walk())
            .flatten();
        // One dispersion for every comparison of this candidate: over the taus the candidate or
        // the random walk can move, so its BIC gain compares chi2 values on one scale.
        let walk_move = walk.as_ref().map(Walk::as_move);
        let mut refs: Vec<&Move> = vec![&own];
        refs.extend(walk_move.as_ref());
        let scale = Scale {
            w: self.drift_weight(&u),
            dispersion: dispersion(data, &refs),
        };
        let chi = |c: f64| self.chi2(data, &[(&own, c)], scale);
        let (c, chi2) = if effect == Effect::RateRamp {
            // A ramp's level is the runs' slope (deterministic, `trials`).
            let c = self.ramp_slope * self.ramp_slope;
            (c, chi(c))
        } else {
            minimise(&chi, c0, c_unit)
        };
        let (k, m) = (effect.free_parameters(), f.len() + self.drift.len());
        let base = chi(c0);
        let mut best = Level {
            c,
            bic: bic(chi2, k, m) + penalty,
            aic: aic(chi2, k) + penalty,
            interval: interval(&chi, c, chi2 + CHI2_1_95),
            partner: None,
        };
        if let Some(walk) = &walk {
            let joint =
                self.with_random_walk(data, (&own, walk), (c_unit, scale), (k + 1, m), penalty);
            if joint.bic < best.bic {
                best = joint;
            }
        }
        let term = if effect == Effect::RateRamp {
            level_term(self.model, self.channel, effect, self.ramp_slope).ok()?
        } else {
            term_at(best.c).ok()?
        };
        let named = term.parameters();
        let (c_lo, c_hi) = best.interval;
        Some(DriftTrial {
            trial: Trial {
                effect,
                lo: at_squared_level(&named, c_lo),
                hi: at_squared_level(&named, c_hi),
                term,
                white_n: None,
                model: current.map(Term::parameters),
                bic: best.bic,
                aic: best.aic,
                delta_avar: f.iter().map(|v| (best.c - c0) * v).collect(),
                signature: f.to_vec(),
            },
            delta_bic: base - best.bic,
            partner: best.partner,
        })
    }

    /// The Allan variance per unit squared level of `effect` at each measured tau (a Gauss-Markov
    /// process at correlation time `shape`), behind the channel's output filter.
    fn signature(&self, effect: Effect, shape: Option<f64>) -> Vec<f64> {
        let flicker = flicker_band(self.model, self.channel);
        let fa = filtered_allan(self.model, self.channel, self.dt_s);
        self.measured
            .tau_s
            .iter()
            .map(|&t| match shape {
                Some(s) => unit_family_signature(effect, s, t, self.dt_s, fa.as_ref()),
                None => unit_signature(effect, t, self.dt_s, &flicker, fa.as_ref()),
            })
            .collect()
    }

    /// The channel's fitted rate random walk with its Allan signature and unit drift (None without
    /// one, or at level 0).
    fn random_walk(&self) -> Option<Walk<'_>> {
        let term = fitted_term(self.model, self.channel, Effect::RateRandomWalk)?;
        let c0 = squared_level(Some(term));
        if c0 <= 0.0 {
            return None;
        }
        Some(Walk {
            term,
            f: self.signature(Effect::RateRandomWalk, None),
            u: self.unit_drift(term, c0),
            c0,
        })
    }

    /// The candidate `own` fitted with the channel's rate random walk re-levelled beside it (the
    /// slow terms' levels are not identified by the Allan curve alone: a long Gauss-Markov process
    /// and a random walk look alike up to the longest averaging time, and the drift, which
    /// integrates them differently, helps tell them apart). The level pair minimising the joint
    /// chi2: the random walk's level profiled (`minimise` over its level, the candidate's
    /// minimised at each); the drift weight the smaller of the two terms'
    /// ([`DriftFitInput::drift_weight`]: the pairs' evidence counted at most once along either
    /// direction), the candidate's dispersion; one more free parameter.
    fn with_random_walk(
        &self,
        data: &FitData,
        (own, walk): (&Move, &Walk),
        (c_unit, scale): (f64, Scale),
        (k, m): (usize, usize),
        penalty: f64,
    ) -> Level {
        let scale = Scale {
            w: scale.w.min(self.drift_weight(&walk.u)),
            ..scale
        };
        let mv = walk.as_move();
        let joint = |c: f64, c_r: f64| self.chi2(data, &[(own, c), (&mv, c_r)], scale);
        let profile = |c_r: f64| minimise(&|c: f64| joint(c, c_r), own.c0, c_unit);
        let c_r = minimise(&|c_r: f64| profile(c_r).1, walk.c0, walk.c0).0;
        let (c, chi2) = profile(c_r);
        let named = walk.term.parameters();
        let (r_lo, r_hi) = interval(&|x: f64| joint(c, x), c_r, chi2 + CHI2_1_95);
        Level {
            c,
            bic: bic(chi2, k, m) + penalty,
            aic: aic(chi2, k) + penalty,
            interval: interval(&|x: f64| joint(x, c_r), c, chi2 + CHI2_1_95),
            partner: Some(Partner {
                term: (c_r > 0.0)
                    .then(|| walk.term.with_level(c_r.sqrt()).ok())
                    .flatten(),
                model: named.clone(),
                lo: at_squared_level(&named, r_lo),
                hi: at_squared_level(&named, r_hi),
                delta_avar: walk.f.iter().map(|v| (c_r - walk.c0) * v).collect(),
                signature: walk.f.clone(),
            }),
        }
    }

    /// u[h][q]: each quantity's mean square per unit c of `term` (at squared level c_unit) alone
    /// on the channel (a flicker term on the channel's own band: `level_term`).
    fn unit_drift(&self, term: &Term, c_unit: f64) -> Vec<[f64; 5]> {
        let mut alone = SensorModel {
            gyro: Default::default(),
            accel: Default::default(),
            ..self.model.clone()
        };
        set_term(&mut alone, self.channel, term.clone());
        self.unit
            .mean_squares(&alone, self.channel)
            .into_iter()
            .map(|ms| ms.map(|v| v / c_unit))
            .collect()
    }
}

/// [`DriftFitInput::gauss_markov_slot`] of channel `ch` of `model`, longest averaging time
/// `tau_max`.
pub(crate) fn gauss_markov_slot(model: &SensorModel, ch: Channel, tau_max: f64) -> Effect {
    let slowest_fast = GAUSS_MARKOV_TIMES[0] * tau_max;
    match fitted_term(model, ch, Effect::GaussMarkov) {
        None => Effect::GaussMarkov,
        Some(t) if t.parameters().get(1).is_some_and(|p| p.1 >= slowest_fast) => {
            Effect::GaussMarkov
        }
        Some(_) => Effect::SlowGaussMarkov,
    }
}

/// The dispersion of the Allan part for the terms `moves` (module doc): over the taus where they,
/// at their reference levels, make at least a tenth of the band's Allan variance (the taus the
/// change can move), the chi2 of the model as it stands.
fn dispersion(data: &FitData, moves: &[&Move]) -> f64 {
    let (mut chi2, mut m) = (0.0, 0);
    for i in 0..data.ln_meas.len() {
        let moved: f64 = moves.iter().map(|mv| mv.c_ref * mv.f[i].abs()).sum();
        if moved >= SUPPORT_SHARE * data.avar_band[i] {
            chi2 += ((data.ln_meas[i] - data.ln_band[i]) / data.s[i]).powi(2);
            m += 1;
        }
    }
    allan_dispersion(chi2, m)
}

/// Share of the band's Allan variance a moved term must make at a tau for the tau to count in the
/// dispersion (`DriftFitInput::dispersion`).
pub(crate) const SUPPORT_SHARE: f64 = 0.1;

/// Overdispersion test level of the Allan part (module doc).
const OVERDISPERSION_LEVEL: f64 = 1e-3;

/// The dispersion c of an Allan fit with chi2 `chi2` over `m` taus (module doc): chi2 / m where
/// chi2 exceeds the 1 - `OVERDISPERSION_LEVEL` quantile of chi2(m), else 1.
pub(crate) fn allan_dispersion(chi2: f64, m: usize) -> f64 {
    let k = m as f64;
    if m > 0 && chi2 > allan::chi2::chi2_ppf(1.0 - OVERDISPERSION_LEVEL, k) {
        chi2 / k
    } else {
        1.0
    }
}

/// Is `effect` one of the two first-order Gauss-Markov slots?
fn is_gauss_markov(effect: Effect) -> bool {
    matches!(effect, Effect::GaussMarkov | Effect::SlowGaussMarkov)
}

/// The index of `q` in `Quantity::ALL` (the unit drift's order).
fn quantity_index(q: Quantity) -> usize {
    Quantity::ALL.iter().position(|x| *x == q).unwrap_or(0)
}

/// The level c >= 0 minimising `chi`: 0, c0 and a log grid from 1e-6 to 1e4 times `scale`, then a
/// golden-section search in ln c between the best grid value's neighbours.
fn minimise(chi: &dyn Fn(f64) -> f64, c0: f64, scale: f64) -> (f64, f64) {
    const GRID: usize = 100;
    let (lo, hi) = ((scale * 1e-6).ln(), (scale * 1e4).ln());
    let grid: Vec<f64> = (0..=GRID)
        .map(|j| (lo + (hi - lo) * j as f64 / GRID as f64).exp())
        .collect();
    let mut best = (0.0, chi(0.0));
    if c0 > 0.0 {
        let v = chi(c0);
        if v < best.1 {
            best = (c0, v);
        }
    }
    let mut jb = None;
    for (j, &c) in grid.iter().enumerate() {
        let v = chi(c);
        if v < best.1 {
            best = (c, v);
            jb = Some(j);
        }
    }
    if let Some(j) = jb {
        let (mut a, mut b) = (grid[j.saturating_sub(1)].ln(), grid[(j + 1).min(GRID)].ln());
        let g = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..40 {
            let (x1, x2) = (b - g * (b - a), a + g * (b - a));
            if chi(x1.exp()) < chi(x2.exp()) {
                b = x2;
            } else {
                a = x1;
            }
        }
        let c = (0.5 * (a + b)).exp();
        let v = chi(c);
        if v < best.1 {
            best = (c, v);
        }
    }
    best
}

/// The profile interval {c : chi(c) <= level} around `c`, by bisection in ln c on each side
/// (bounded by 1e-6 and 1e6 times c).
fn interval(chi: &dyn Fn(f64) -> f64, c: f64, level: f64) -> (f64, f64) {
    if c <= 0.0 {
        return (0.0, 0.0);
    }
    let edge = |far: f64| {
        if chi(far) <= level {
            return far;
        }
        let (mut inside, mut outside) = (c.ln(), far.ln());
        for _ in 0..50 {
            let mid = 0.5 * (inside + outside);
            if chi(mid.exp()) <= level {
                inside = mid;
            } else {
                outside = mid;
            }
        }
        inside.exp()
    };
    let lo = if chi(0.0) <= level {
        0.0
    } else {
        edge(c * 1e-6)
    };
    (lo, edge(c * 1e6))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with_gauss_markov(tau_s: Option<f64>) -> SensorModel {
        let mut m = SensorModel::default();
        if let Some(t) = tau_s {
            set_term(
                &mut m,
                Channel::Gz,
                GaussMarkov::new(1e-4, t).unwrap().into(),
            );
        }
        m
    }

    /// A fit within its chi2 quantile keeps the Allan part as it is; an overdispersed one is divided
    /// by chi2 / M (the 0.999 quantile of chi2 with 16 degrees of freedom is 39.25).
    #[test]
    fn only_an_overdispersed_allan_fit_is_scaled() {
        assert_eq!(allan_dispersion(16.0, 16), 1.0);
        assert_eq!(allan_dispersion(39.0, 16), 1.0);
        assert_eq!(allan_dispersion(40.0, 16), 2.5);
        assert_eq!(allan_dispersion(78.0 * 78.0 * 16.0, 16), 78.0 * 78.0);
        assert_eq!(allan_dispersion(5.0, 0), 1.0);
    }

    /// The dispersion counts only the taus the moved terms can move: a misfit of 100 sigma at taus
    /// where the term makes nothing (a filter's region) leaves a slow term's Allan part as it is;
    /// counted, it divides it by (2 x 100^2 + 2) / 4.
    #[test]
    fn the_dispersion_is_over_the_taus_a_term_moves() {
        let ln_meas = [100.0, -100.0, 1.0, -1.0];
        let zeros = [0.0; 4];
        let data = FitData {
            ln_meas: &ln_meas,
            ln_band: &zeros,
            avar_band: &[1.0; 4],
            s: &[1.0; 4],
        };
        let u = [[0.0; 5]];
        let slow = Move {
            f: &[0.0, 0.01, 1.0, 2.0],
            u: &u,
            c0: 0.0,
            c_ref: 1.0,
        };
        assert_eq!(dispersion(&data, &[&slow]), 1.0);
        let everywhere = Move {
            f: &[1.0; 4],
            ..slow
        };
        assert_eq!(dispersion(&data, &[&everywhere]), 20002.0 / 4.0);
        assert_eq!(dispersion(&data, &[&slow, &everywhere]), 20002.0 / 4.0);
    }

    /// The slow candidate takes `gauss_markov` when it is free or already slow, and the second
    /// slot beside a fast stand-in (which stays).
    #[test]
    fn the_slow_candidate_goes_beside_a_fast_gauss_markov() {
        let tau_max = 1310.72;
        let slot = |t| gauss_markov_slot(&with_gauss_markov(t), Channel::Gz, tau_max);
        assert_eq!(slot(None), Effect::GaussMarkov);
        assert_eq!(slot(Some(0.0073)), Effect::SlowGaussMarkov);
        assert_eq!(slot(Some(0.5 * tau_max)), Effect::SlowGaussMarkov);
        assert_eq!(slot(Some(tau_max)), Effect::GaussMarkov);
        assert_eq!(slot(Some(10.0 * tau_max)), Effect::GaussMarkov);
    }
}
