//! Step 4: every candidate effect fitted to one channel's gap.

use crate::candidates::{
    candidates, filter_grid, filtered_allan, level_term, named, power_law_at, power_law_like,
    resonance_grid, resonance_refinement, resonance_signature, shape_grid, shape_search_penalty,
    unit_family_signature, unit_signature, white_signature,
};
use crate::fit::predicted_ln_adev;
use crate::fit::{
    aic, bic, birge_scale, correlation_factor, fit_family, fit_linear, linear_interval, FamilyFit,
    FitData, LinearFit, CHI2_1_95, CHI2_2_95,
};
use crate::gap::{Band, Curve, Gap};
use crate::model_terms::{
    fitted_term, flicker_band, has_random_walk_bias_instability, output_filter, squared_level,
};
use crate::spectrum::SpectralPeak;
use noise::{
    Channel, Effect, FilterKind, GaussMarkov, OutputFilter, PowerLaw, SensorModel, Sinusoid, Term,
};
use std::collections::BTreeMap;

/// What one channel's candidates are fitted to: its model, measurement, band and gap, and what the
/// log's spectrum says.
pub(crate) struct ChannelFit<'a> {
    pub(crate) model: &'a SensorModel,
    pub(crate) channel: Channel,
    pub(crate) measured: &'a Curve,
    pub(crate) band: &'a Band,
    pub(crate) gap: &'a Gap,
    pub(crate) dt_s: f64,
    /// Least-squares slope of the log against time (a rate ramp's level).
    pub(crate) ramp_slope: f64,
    /// The log's broad spectral peak: where a resonance is searched and no sinusoid is offered.
    pub(crate) peak: Option<SpectralPeak>,
    /// The log's spectral lines (`spectrum::spectral_lines_runs`), Hz, the resolution below 6
    /// times which its spectrum cannot show one (None: too short for a spectrum), and the
    /// resolution the lines' frequencies are measured to
    /// (`spectrum::line_frequency_resolution_hz`).
    pub(crate) lines: &'a [f64],
    pub(crate) line_resolution_hz: Option<f64>,
    pub(crate) line_frequency_resolution_hz: Option<f64>,
}

/// Parameters by their docs/cli.md JSON names.
pub(crate) type Named = Vec<(&'static str, f64)>;

/// A fitted candidate before selection.
pub(crate) struct Trial {
    pub(crate) effect: Effect,
    /// The fitted term.
    pub(crate) term: Term,
    /// For an output filter, the white-noise density refitted through it (the filter reshapes the
    /// white noise, so the two are fitted and named together).
    pub(crate) white_n: Option<f64>,
    /// The parameters at the ends of their 95 % intervals.
    pub(crate) lo: Named,
    pub(crate) hi: Named,
    /// The model's own parameters of the effect, if it has the term.
    pub(crate) model: Option<Named>,
    pub(crate) bic: f64,
    pub(crate) aic: f64,
    /// (c - c0) f(tau): the change of the band's Allan variance.
    pub(crate) delta_avar: Vec<f64>,
    /// f(tau), the Allan variance per unit squared level (empty where the change is not of that
    /// form, the output filter's).
    pub(crate) signature: Vec<f64>,
}

/// One candidate's fit, before its interval.
struct Fitted {
    fit: LinearFit,
    term: Term,
    /// The 95 % interval of a searched shape.
    shape: ShapeInterval,
    /// The candidate's Allan variance per unit squared level at each tau, f(tau).
    signature: Vec<f64>,
    /// Look-elsewhere cost of the shapes tried (chi2 scale).
    penalty: f64,
}

/// The interval of a shape chosen by search.
enum ShapeInterval {
    /// No shape searched (a level, or a shape kept from the model).
    None,
    /// A Gauss-Markov correlation time or a sinusoid frequency.
    Scalar(f64, f64),
    /// A resonance's frequency and bandwidth.
    Resonance {
        frequency_hz: (f64, f64),
        bandwidth_hz: (f64, f64),
    },
}

/// `named` (a term's parameters, its level first) with the level set to sqrt(c), of the sign the
/// level has.
pub(crate) fn at_squared_level(named: &Named, c: f64) -> Named {
    let mut out = named.clone();
    if let Some(level) = out.first_mut() {
        let sign = if level.1 < 0.0 { -1.0 } else { 1.0 };
        level.1 = c.max(0.0).sqrt().copysign(sign);
    }
    out
}

/// Fit every candidate to one channel; the trials are in `candidates()` order, the output filter last.
pub(crate) fn trials(input: &ChannelFit) -> Vec<Trial> {
    let ln_meas: Vec<f64> = input.measured.adev.iter().map(|a| a.ln()).collect();
    let data = FitData {
        ln_meas: &ln_meas,
        ln_band: &input.band.ln_mean,
        avar_band: &input.band.avar_mean,
        s: &input.gap.s,
    };
    let ch = input.channel;
    let mut out = Vec::new();
    for effect in candidates() {
        // A Woodman random-walk bias instability occupies the axis's one bias-instability slot; a flicker
        // candidate would replace it, so it is not offered (its level shows as a rate random walk).
        if effect == Effect::BiasInstability && has_random_walk_bias_instability(input.model, ch) {
            continue;
        }
        // White noise after the filter is told from white noise before it only by the filter.
        if effect == Effect::OutputWhiteNoise && output_filter(input.model, ch).is_none() {
            continue;
        }
        let current = fitted_term(input.model, ch, effect);
        if let Some(Term::PowerLaw(own)) = current {
            out.extend(refit_power_law(input, &data, own));
            continue;
        }
        let fitted = match effect {
            Effect::GaussMarkov | Effect::Sinusoidal | Effect::PowerLaw => {
                fit_shaped(input, &data, effect, current)
            }
            Effect::Resonance => fit_resonance(input, &data, current),
            _ => fit_level(input, &data, effect, current),
        };
        if let Some(fitted) = fitted {
            out.push(trial(&data, effect, current, fitted));
        }
    }
    out.extend(filter_trial(input, &data));
    out
}

/// A Gauss-Markov process, a sinusoid or a new power law (the model's own is
/// [`refit_power_law`]'s). A term the model has keeps its shape (a wrong level); an
/// absent one is searched over shapes. A new sinusoid takes its frequency from a line of the log's
/// spectrum where the spectrum resolves one (`sinusoid_shapes`).
fn fit_shaped(
    input: &ChannelFit,
    data: &FitData,
    effect: Effect,
    current: Option<&Term>,
) -> Option<Fitted> {
    let (tau, dt_s) = (&input.measured.tau_s, input.dt_s);
    let m = tau.len();
    let (shapes, penalty, from_lines) = match current.and_then(|c| c.parameters().get(1).copied()) {
        // A sinusoid named at a line keeps the line's frequency and its interval.
        Some((_, s)) => (
            vec![s],
            0.0,
            effect == Effect::Sinusoidal && input.lines.contains(&s),
        ),
        None if effect == Effect::Sinusoidal => sinusoid_shapes(input)?,
        None => {
            let g = shape_grid(effect, tau[0], tau[m - 1], dt_s);
            let penalty = shape_search_penalty(g.len());
            (g, penalty, false)
        }
    };
    let fa = filtered_allan(input.model, input.channel, dt_s);
    let sigs: Vec<Vec<f64>> = shapes
        .iter()
        .map(|&s| {
            tau.iter()
                .map(|&t| unit_family_signature(effect, s, t, dt_s, fa.as_ref()))
                .collect()
        })
        .collect();
    let c0 = squared_level(current);
    let ff = fit_family(data, &shapes, &sigs, &|_| c0)?;
    let j = shapes.iter().position(|&s| s == ff.shape).unwrap_or(0);
    // The model's own term keeps its shape (and a sinusoid its phase); a new one takes the
    // shape found.
    let level = ff.fit.c.sqrt();
    let term = match (current, effect) {
        (Some(own), _) => own.with_level(level).ok()?,
        (None, Effect::GaussMarkov) => GaussMarkov::new(level, ff.shape).ok()?.into(),
        // Level at tau = 1 s on the default band, as `candidates::power_law_signature`.
        (None, Effect::PowerLaw) => PowerLaw::with_alpha(ff.shape, level, 1.0).ok()?.into(),
        (None, _) => Sinusoid::new(level, ff.shape, None).ok()?.into(),
    };
    // Shape interval at the 95 % threshold widened by this fit's Birge ratio; a line's frequency
    // is the spectrum's, known to half the resolution it was measured to.
    let scale = birge_scale(ff.fit.chi2, effect.free_parameters(), m);
    let (shape_lo, shape_hi) = match (from_lines, input.line_frequency_resolution_hz) {
        (true, Some(df)) => (ff.shape - 0.5 * df, ff.shape + 0.5 * df),
        _ => {
            let mu = |c: f64, k: usize| -> Vec<f64> {
                (0..m)
                    .map(|i| {
                        predicted_ln_adev(data.ln_band[i], data.avar_band[i], (c - c0) * sigs[k][i])
                    })
                    .collect()
            };
            let threshold = shape_threshold(input.band, data.s, &mu, ff.fit.c, j, shapes.len());
            ff.shape_interval(threshold * scale * scale)
        }
    };
    Some(Fitted {
        fit: ff.fit,
        term,
        shape: ShapeInterval::Scalar(shape_lo, shape_hi),
        signature: sigs[j].clone(),
        penalty,
    })
}

/// The profile threshold of a searched shape's 95 % interval (before the Birge ratio): the
/// chi-square's 3.84 assumes independent errors at the taus, while neighbouring overlapping Allan
/// deviations err together and the shape is then known less well than the profile says. So the
/// threshold is t_{K-1}(0.975)^2 kappa: kappa the sandwich factor of `fit::correlation_factor`
/// with the errors' correlation from the band's K simulated logs (Student's t because kappa is
/// estimated from them), the derivatives taken at the best fit (level `c`, grid shape `j` of `n`)
/// of `mu(c, j)`, the predicted ln adev, by differences (central in the level at 1e-4 of it;
/// between the neighbouring grid shapes, one-sided at the grid's ends), each over the tau's
/// standard error `s`. 3.84 where the band has fewer than 3 logs or the grid one shape; where
/// kappa cannot be estimated (a shape the level explains) it is 1 and the threshold t^2.
/// Measured on hidden power laws: docs/diagnose.md, "The power-law candidate".
fn shape_threshold(
    band: &Band,
    s: &[f64],
    mu: &dyn Fn(f64, usize) -> Vec<f64>,
    c: f64,
    j: usize,
    n: usize,
) -> f64 {
    let k = band.standardised.len();
    if k < 3 || n < 2 || c.is_nan() || c <= 0.0 {
        return CHI2_1_95;
    }
    let (lo, hi) = (j.saturating_sub(1), (j + 1).min(n - 1));
    let (a, b) = (mu(c, lo), mu(c, hi));
    let j_shape: Vec<f64> = (0..s.len())
        .map(|i| (b[i] - a[i]) / (hi - lo) as f64 / s[i])
        .collect();
    let h = 1e-4 * c;
    let (up, down) = (mu(c + h, j), mu(c - h, j));
    let j_level: Vec<f64> = (0..s.len())
        .map(|i| (up[i] - down[i]) / (2.0 * h) / s[i])
        .collect();
    let kappa = correlation_factor(&band.standardised, &j_level, &j_shape);
    let t = allan::chi2::t_ppf(0.975, (k - 1) as f64);
    t * t * kappa
}

/// One slope's fit of [`refit_power_law`]: its signature f, the band's move c0 (f - f_old), the
/// moved band (ln adev centre, mean Allan variance) and the level fitted there.
struct SlopeFit {
    f: Vec<f64>,
    shift: Vec<f64>,
    ln: Vec<f64>,
    avar: Vec<f64>,
    fit: LinearFit,
}

/// A power law the model has: its slope searched again over the grid (its reference time and band
/// kept), because the slope is what the term says about the sensor and it moves as other terms
/// join the channel (a Gauss-Markov time or a sinusoid's frequency is kept). A new slope changes the
/// band by c f_new - c0 f_old, not by (c - c0) f: each slope's level is fitted to the band moved by
/// c0 (f_new - f_old), as the joint re-level moves it for the other terms (`relevel::moved`), and
/// that move is part of the change the trial predicts. Its signature stays the term's own, at its
/// slope (what the re-level, which keeps shapes, moves).
fn refit_power_law(input: &ChannelFit, data: &FitData, own: &PowerLaw) -> Option<Trial> {
    let (tau, dt_s) = (&input.measured.tau_s, input.dt_s);
    let m = tau.len();
    let fa = filtered_allan(input.model, input.channel, dt_s);
    let signature = |alpha: f64| -> Vec<f64> {
        tau.iter()
            .map(|&t| power_law_like(Some(own), alpha, t, dt_s, fa.as_ref()))
            .collect()
    };
    let c0 = own.level() * own.level();
    let f_old = signature(own.alpha());
    let shapes = shape_grid(Effect::PowerLaw, tau[0], tau[m - 1], dt_s);
    let penalty = shape_search_penalty(shapes.len());
    // Per slope: its signature, the band moved to it at the old level, and the fit there.
    let per_shape: Vec<SlopeFit> = shapes
        .iter()
        .map(|&alpha| {
            let f = signature(alpha);
            let shift: Vec<f64> = f.iter().zip(&f_old).map(|(n, o)| c0 * (n - o)).collect();
            let ln: Vec<f64> = (0..m)
                .map(|i| predicted_ln_adev(data.ln_band[i], data.avar_band[i], shift[i]))
                .collect();
            let avar: Vec<f64> = (0..m).map(|i| data.avar_band[i] + shift[i]).collect();
            let moved = FitData {
                ln_band: &ln,
                avar_band: &avar,
                ..data.clone()
            };
            let fit = fit_linear(&moved, &f, c0);
            SlopeFit {
                f,
                shift,
                ln,
                avar,
                fit,
            }
        })
        .collect();
    let jb = (0..shapes.len())
        .min_by(|&a, &b| per_shape[a].fit.chi2.total_cmp(&per_shape[b].fit.chi2))?;
    let SlopeFit {
        f,
        shift,
        ln,
        avar,
        fit,
    } = &per_shape[jb];
    let ff = FamilyFit {
        shape: shapes[jb],
        fit: *fit,
        shapes: shapes.clone(),
        chi2_by_shape: per_shape.iter().map(|p| p.fit.chi2).collect(),
    };
    let k = Effect::PowerLaw.free_parameters();
    let scale = birge_scale(fit.chi2, k, m);
    let moved = FitData {
        ln_band: ln,
        avar_band: avar,
        ..data.clone()
    };
    let (c_lo, c_hi) = linear_interval(&moved, f, c0, fit, CHI2_1_95 * scale * scale);
    let term: Term = power_law_at(Some(own), ff.shape, fit.c.sqrt()).ok()?.into();
    let mu = |c: f64, k: usize| -> Vec<f64> {
        let p = &per_shape[k];
        (0..m)
            .map(|i| predicted_ln_adev(p.ln[i], p.avar[i], (c - c0) * p.f[i]))
            .collect()
    };
    let threshold = shape_threshold(input.band, data.s, &mu, fit.c, jb, shapes.len());
    let (s_lo, s_hi) = ff.shape_interval(threshold * scale * scale);
    let shape = ShapeInterval::Scalar(s_lo, s_hi);
    let (lo, hi) = bounds(&term.parameters(), (c_lo, c_hi), &shape);
    Some(Trial {
        effect: Effect::PowerLaw,
        term,
        white_n: None,
        lo,
        hi,
        model: Some(Term::PowerLaw(own.clone()).parameters()),
        bic: bic(fit.chi2, k, m) + penalty,
        aic: aic(fit.chi2, k) + penalty,
        delta_avar: f
            .iter()
            .zip(shift)
            .map(|(v, s)| (fit.c - c0) * v + s)
            .collect(),
        signature: f_old,
    })
}

/// The frequencies a new sinusoid is tried at, the look-elsewhere cost of the choice, and whether
/// they are the spectrum's lines. A tone is a line of the spectrum: where the log's spectrum shows
/// lines (`spectrum::spectral_lines_runs`, from 6 of its resolutions up to the Nyquist frequency),
/// the sinusoid is offered at their frequencies only, each measured on the spectrum to the runs'
/// resolution; only the amplitude is fitted, at a cost of 2 ln of the number of lines chosen from.
/// A sinusoid searched on the Allan grid has no line to stand on (a stand-in), so it is offered
/// only on a channel whose spectrum shows no line: there the grid below the spectrum's resolution
/// is searched (`shape_grid`, with its own cost); nothing below the resolution either: no
/// sinusoid. Neither inside a broad spectral peak: the spectrum shows the power there spread over
/// many resolutions, not a line (the resonance candidate describes it).
fn sinusoid_shapes(input: &ChannelFit) -> Option<(Vec<f64>, f64, bool)> {
    let (tau, dt_s) = (&input.measured.tau_s, input.dt_s);
    let outside_peak = |f: &f64| input.peak.is_none_or(|p| !p.covers(*f));
    let lines: Vec<f64> = input.lines.iter().copied().filter(outside_peak).collect();
    if !lines.is_empty() {
        let cost = shape_search_penalty(lines.len());
        return Some((lines, cost, true));
    }
    let mut grid = shape_grid(Effect::Sinusoidal, tau[0], tau[tau.len() - 1], dt_s);
    grid.retain(outside_peak);
    if let Some(df) = input.line_resolution_hz {
        grid.retain(|&f| f < 6.0 * df);
    }
    let cost = shape_search_penalty(grid.len());
    (!grid.is_empty()).then_some((grid, cost, false))
}

/// A resonance. One the model has is refitted around its shape (the other terms it was fitted
/// beside may have changed since: a filter, the white level). An absent one needs a broad peak in
/// the log's spectrum (`spectrum::broad_peak`), which gives its frequency and bandwidth roughly (a
/// real peak is seldom the symmetric shape of the model); the shape is then fitted to the Allan
/// curve on a grid around them (frequency within a peak width, bandwidth 0.15-3 times the peak's),
/// with the look-elsewhere cost of the shapes tried, through the channel's output filter.
fn fit_resonance(input: &ChannelFit, data: &FitData, current: Option<&Term>) -> Option<Fitted> {
    let own = match current {
        Some(Term::Resonance(r)) => Some((r.frequency_hz(), r.bandwidth_hz())),
        _ => None,
    };
    let shapes: Vec<(f64, f64)> = match (own, input.peak) {
        (Some(shape), _) => resonance_refinement(shape, 1.0, input.dt_s),
        (None, Some(p)) => resonance_grid(p, input.dt_s),
        (None, None) => return None,
    };
    let search = ResonanceSearch {
        data,
        tau: &input.measured.tau_s,
        dt_s: input.dt_s,
        filter: output_filter(input.model, input.channel),
        c0: squared_level(current),
        peak: input.peak,
    };
    let (shapes, fits) = search.run(shapes, own);
    let jb = ResonanceSearch::best_of(&fits)?;
    let fit = fits[jb].0;
    // Shape interval: the grid's shapes within the 95 % threshold (Birge-widened) of the best.
    let scale = birge_scale(
        fit.chi2,
        Effect::Resonance.free_parameters(),
        search.tau.len(),
    );
    let near: Vec<(f64, f64)> = (0..fits.len())
        .filter(|&j| fits[j].0.chi2 <= fit.chi2 + CHI2_2_95 * scale * scale)
        .map(|j| shapes[j])
        .collect();
    let span = |g: fn(&(f64, f64)) -> f64| {
        near.iter()
            .map(g)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            })
    };
    let (frequency_hz, bandwidth_hz) = shapes[jb];
    Some(Fitted {
        fit,
        term: noise::Resonance::new(fit.c.sqrt(), frequency_hz, bandwidth_hz)
            .ok()?
            .into(),
        shape: ShapeInterval::Resonance {
            frequency_hz: span(|s| s.0),
            bandwidth_hz: span(|s| s.1),
        },
        signature: fits[jb].1.clone(),
        penalty: shape_search_penalty(shapes.len()),
    })
}

/// Each shape's fit and signature.
type ShapeFits = Vec<(LinearFit, Vec<f64>)>;

/// The search over resonance shapes (frequency, bandwidth) of [`fit_resonance`].
struct ResonanceSearch<'a> {
    data: &'a FitData<'a>,
    tau: &'a [f64],
    dt_s: f64,
    filter: Option<OutputFilter>,
    c0: f64,
    peak: Option<SpectralPeak>,
}

impl ResonanceSearch<'_> {
    fn fit_shape(&self, shape: (f64, f64)) -> (LinearFit, Vec<f64>) {
        let f = resonance_signature(self.filter.as_ref(), shape, self.tau, self.dt_s);
        (fit_linear(self.data, &f, self.c0), f)
    }

    /// The bandwidth stays within what the spectrum allows: at least 0.15 times the broad peak's
    /// width (the grid's lowest; a mode much narrower than its peak is a line the spectrum does not
    /// show) and at most 3 times it.
    fn allowed(&self, b: f64) -> bool {
        self.peak
            .is_none_or(|p| (0.149 * p.bandwidth_hz..=3.001 * p.bandwidth_hz).contains(&b))
    }

    fn best_of(fits: &[(LinearFit, Vec<f64>)]) -> Option<usize> {
        (0..fits.len()).min_by(|&a, &b| fits[a].0.chi2.total_cmp(&fits[b].0.chi2))
    }

    /// Every shape tried with its fit. The model's own shape is always refitted. Refinements around
    /// the best, each twice as fine (frequency in steps of 1/4, 1/8, 1/16 of the bandwidth,
    /// bandwidth in steps of 30 %, 15 %, 7.5 %): the grid's steps are coarse beside a narrow mode,
    /// the short taus are sensitive to the frequency, and a frequency a fraction of a bandwidth off
    /// is otherwise made up by a wider bandwidth.
    fn run(
        &self,
        shapes: Vec<(f64, f64)>,
        own: Option<(f64, f64)>,
    ) -> (Vec<(f64, f64)>, ShapeFits) {
        let mut shapes: Vec<(f64, f64)> = shapes
            .into_iter()
            .filter(|s| self.allowed(s.1) || Some(*s) == own)
            .collect();
        let mut fits: Vec<(LinearFit, Vec<f64>)> =
            shapes.iter().map(|&shape| self.fit_shape(shape)).collect();
        for step in [2.0, 1.0, 0.5] {
            let Some(jb) = Self::best_of(&fits) else {
                break;
            };
            for shape in resonance_refinement(shapes[jb], step, self.dt_s) {
                if !shapes.contains(&shape) && self.allowed(shape.1) {
                    fits.push(self.fit_shape(shape));
                    shapes.push(shape);
                }
            }
        }
        (shapes, fits)
    }
}

/// A one-level term (quantisation, white noise, flicker, rate random walk, rate ramp).
fn fit_level(
    input: &ChannelFit,
    data: &FitData,
    effect: Effect,
    current: Option<&Term>,
) -> Option<Fitted> {
    let (tau, dt_s) = (&input.measured.tau_s, input.dt_s);
    let ch = input.channel;
    let (flicker, fa) = (
        flicker_band(input.model, ch),
        filtered_allan(input.model, ch, dt_s),
    );
    let f: Vec<f64> = tau
        .iter()
        .map(|&t| unit_signature(effect, t, dt_s, &flicker, fa.as_ref()))
        .collect();
    let c0 = squared_level(current);
    let fit = fit_linear(data, &f, c0);
    let (fit, level) = if effect == Effect::RateRamp {
        // A ramp is deterministic: its level is the least-squares slope of the log (the ML
        // estimate of a ramp in white noise), not a free Allan parameter. A long-tau rise that is
        // really a random walk then fits as a ramp only if the log does drift that way, which the
        // last two or three Allan points (a handful of EDF) cannot tell.
        let c = input.ramp_slope * input.ramp_slope;
        let ramp = LinearFit {
            c,
            chi2: data.chi2(&f, c - c0),
        };
        (ramp, input.ramp_slope)
    } else {
        (fit, fit.c.sqrt())
    };
    Some(Fitted {
        fit,
        term: level_term(input.model, ch, effect, level).ok()?,
        shape: ShapeInterval::None,
        signature: f,
        penalty: 0.0,
    })
}

/// A fitted candidate with its 95 % interval (widened by the Birge ratio of its fit) and
/// information criteria.
fn trial(data: &FitData, effect: Effect, current: Option<&Term>, fitted: Fitted) -> Trial {
    let Fitted {
        fit,
        term,
        shape,
        signature: f,
        penalty,
    } = fitted;
    let (k, m) = (effect.free_parameters(), data.ln_meas.len());
    let c0 = squared_level(current);
    let scale = birge_scale(fit.chi2, k, m);
    // (For the ramp: the profile interval of the Allan fit alone, around its own optimum.)
    let allan_fit = if effect == Effect::RateRamp {
        fit_linear(data, &f, c0)
    } else {
        fit
    };
    let (c_lo, c_hi) = linear_interval(data, &f, c0, &allan_fit, CHI2_1_95 * scale * scale);
    let (lo, hi) = bounds(&term.parameters(), (c_lo, c_hi), &shape);
    Trial {
        effect,
        term,
        white_n: None,
        lo,
        hi,
        model: current.map(Term::parameters),
        bic: bic(fit.chi2, k, m) + penalty,
        aic: aic(fit.chi2, k) + penalty,
        delta_avar: f.iter().map(|v| (fit.c - c0) * v).collect(),
        signature: f,
    }
}

/// The parameters at the ends of the level interval (c_lo, c_hi), with the shape's own interval.
fn bounds(params: &Named, (c_lo, c_hi): (f64, f64), shape: &ShapeInterval) -> (Named, Named) {
    let mut lo = at_squared_level(params, c_lo);
    let mut hi = at_squared_level(params, c_hi);
    if let (Some(l), Some(h)) = (lo.first_mut(), hi.first_mut()) {
        if l.1 > h.1 {
            std::mem::swap(&mut l.1, &mut h.1);
        }
    }
    let mut set = |name: &str, (a, b): (f64, f64)| {
        for (side, v) in [(&mut lo, a), (&mut hi, b)] {
            if let Some(p) = side.iter_mut().find(|p| p.0 == name) {
                p.1 = v;
            }
        }
    };
    match shape {
        ShapeInterval::Resonance {
            frequency_hz,
            bandwidth_hz,
        } => {
            set("frequency_hz", *frequency_hz);
            set("bandwidth_hz", *bandwidth_hz);
        }
        // The one shape of a Gauss-Markov process or a sinusoid, after the level.
        ShapeInterval::Scalar(s_lo, s_hi) => {
            if let Some(name) = params.get(1).map(|p| p.0) {
                set(name, (*s_lo, *s_hi));
            }
        }
        ShapeInterval::None => {}
    }
    (lo, hi)
}

/// The output-filter candidate: every filter of [`filter_grid`] with the white-noise level refitted
/// through it (the filter reshapes the white noise, the term it visibly changes; the other terms'
/// filtering is left to the re-simulation, which applies the filter to all of them). The change of
/// the band is c fw_F(tau) - c0 fw(tau), fw the model's current white signature, fw_F the one through F.
fn filter_trial(input: &ChannelFit, data: &FitData) -> Option<Trial> {
    let search = FilterSearch::new(input, data);
    let grid = filter_grid(input.dt_s);
    let penalty = shape_search_penalty(grid.len());
    let mut tried: Vec<(f64, OutputFilterFit)> = grid
        .into_iter()
        .filter_map(|f| search.try_filter(f))
        .collect();
    search.refine(&mut tried);
    let (chi2, b) = search.simplest(tried)?;
    let (k, m) = (Effect::OutputFilter.free_parameters(), search.tau.len());
    let scale = birge_scale(chi2, k, m);
    let (c_lo, c_hi) = b.interval(search.data, search.c0);
    let lo = (c_lo / (scale * scale).max(1.0)).min(b.fit.c);
    let hi = c_hi * (scale * scale).max(1.0);
    let p = |c: f64| named(&b.filter.into(), Some(c.max(0.0).sqrt()));
    Some(Trial {
        effect: Effect::OutputFilter,
        term: b.filter.into(),
        white_n: Some(b.fit.c.max(0.0).sqrt()),
        lo: p(lo),
        hi: p(hi),
        model: search
            .current
            .map(|filter| named(&filter.into(), Some(search.c0.sqrt()))),
        bic: bic(chi2, k, m) + penalty,
        aic: aic(chi2, k) + penalty,
        delta_avar: b.delta,
        signature: Vec::new(),
    })
}

/// One filter's refit white level, with what its interval needs.
struct OutputFilterFit {
    filter: OutputFilter,
    fit: LinearFit,
    delta: Vec<f64>,
    /// The white signature through the filter and the band shifted to it (the fit's data).
    fw: Vec<f64>,
    ln_band: Vec<f64>,
    avar_band: Vec<f64>,
}

impl OutputFilterFit {
    /// The fit's 95 % profile interval on the squared white level (of `data`, the unshifted fit data).
    fn interval(&self, data: &FitData, c0: f64) -> (f64, f64) {
        let shifted = FitData {
            ln_band: &self.ln_band,
            avar_band: &self.avar_band,
            ..data.clone()
        };
        linear_interval(&shifted, &self.fw, c0, &self.fit, CHI2_1_95)
    }
}

/// The search over output filters of [`filter_trial`].
struct FilterSearch<'a> {
    data: &'a FitData<'a>,
    tau: &'a [f64],
    dt_s: f64,
    /// The channel's filter and white-noise level (squared) now, and its white signature.
    current: Option<OutputFilter>,
    c0: f64,
    fw_cur: Vec<f64>,
    /// The band over the current model's closed form at each tau (1 where that is 0).
    g: Vec<f64>,
}

impl<'a> FilterSearch<'a> {
    fn new(input: &'a ChannelFit, data: &'a FitData<'a>) -> FilterSearch<'a> {
        let (tau, dt_s) = (input.measured.tau_s.as_slice(), input.dt_s);
        let ch = input.channel;
        let current = output_filter(input.model, ch);
        let c0 = squared_level(fitted_term(input.model, ch, Effect::WhiteNoise));
        let fw_cur = white_signature(current.as_ref(), tau, dt_s);
        // The band scaled by closed-form ratios, not shifted by closed-form differences: a filter can
        // take the short-tau variance down 30-fold, and subtracting the unfiltered white noise from a
        // simulated band would leave its seed-to-seed error 30 times larger relative to what remains.
        // g = band / closed form of the current model, so band + c0 (fw_F - fw) g =
        // g (closed form - c0 fw + c0 fw_F): the band's relative error carried, not amplified.
        let cf_old = input
            .model
            .axis(input.channel.sensor(), input.channel.axis())
            .allan_variance_sampled_many(tau, dt_s);
        let g: Vec<f64> = (0..tau.len())
            .map(|i| {
                if cf_old[i] > 0.0 {
                    data.avar_band[i] / cf_old[i]
                } else {
                    1.0
                }
            })
            .collect();
        FilterSearch {
            data,
            tau,
            dt_s,
            current,
            c0,
            fw_cur,
            g,
        }
    }

    /// The white level refitted through `filter` (None for the current filter, or one the rate
    /// does not allow): its chi2 and fit.
    fn try_filter(&self, filter: OutputFilter) -> Option<(f64, OutputFilterFit)> {
        if Some(filter) == self.current || filter.check_rate(self.dt_s).is_err() {
            return None;
        }
        let (m, data, g, c0) = (self.tau.len(), self.data, &self.g, self.c0);
        let fw: Vec<f64> = white_signature(Some(&filter), self.tau, self.dt_s)
            .iter()
            .zip(g)
            .map(|(f, g)| f * g)
            .collect();
        let shift: Vec<f64> = (0..m)
            .map(|i| c0 * (fw[i] - self.fw_cur[i] * g[i]))
            .collect();
        let ln_band: Vec<f64> = (0..m)
            .map(|i| predicted_ln_adev(data.ln_band[i], data.avar_band[i], shift[i]))
            .collect();
        let avar_band: Vec<f64> = (0..m)
            .map(|i| (data.avar_band[i] + shift[i]).max(0.0))
            .collect();
        let shifted = FitData {
            ln_meas: data.ln_meas,
            ln_band: &ln_band,
            avar_band: &avar_band,
            s: data.s,
        };
        let fit = fit_linear(&shifted, &fw, c0);
        let delta = (0..m)
            .map(|i| fit.c * fw[i] - c0 * self.fw_cur[i] * g[i])
            .collect();
        Some((
            fit.chi2,
            OutputFilterFit {
                filter,
                fit,
                delta,
                fw,
                ln_band,
                avar_band,
            },
        ))
    }

    /// Refine around the best of each kind and decimation: every tap count within 30 %, or the
    /// cutoff by golden section in ln f between its grid neighbours (a factor 1.63 either side).
    fn refine(&self, tried: &mut Vec<(f64, OutputFilterFit)>) {
        let mut seeds: Vec<OutputFilter> = Vec::new();
        for t in tried.iter() {
            let same = |f: &OutputFilter| {
                f.decimation() == t.1.filter.decimation()
                    && std::mem::discriminant(&f.kind())
                        == std::mem::discriminant(&t.1.filter.kind())
            };
            let best_of_family = tried
                .iter()
                .filter(|u| same(&u.1.filter))
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .map(|u| u.1.filter);
            if best_of_family == Some(t.1.filter) && !seeds.contains(&t.1.filter) {
                seeds.push(t.1.filter);
            }
        }
        for f in seeds {
            match f.kind() {
                FilterKind::MovingAverage { taps } | FilterKind::Bartlett { taps } => {
                    self.refine_taps(f, taps, tried)
                }
                FilterKind::LowPass1 { cutoff_hz } | FilterKind::LowPass2 { cutoff_hz } => {
                    tried.extend(self.refine_cutoff(f, cutoff_hz))
                }
            }
        }
    }

    /// Every tap count within 30 % of `taps` not tried yet.
    fn refine_taps(&self, f: OutputFilter, taps: u32, tried: &mut Vec<(f64, OutputFilterFit)>) {
        let lo = ((f64::from(taps) / 1.3).floor() as u32).max(2);
        let hi = (f64::from(taps) * 1.3).ceil() as u32;
        for l in lo..=hi {
            let kind = match f.kind() {
                FilterKind::MovingAverage { .. } => FilterKind::MovingAverage { taps: l },
                _ => FilterKind::Bartlett { taps: l },
            };
            if let Ok(g) = OutputFilter::new(kind, f.decimation()) {
                if !tried.iter().any(|u| u.1.filter == g) {
                    tried.extend(self.try_filter(g));
                }
            }
        }
    }

    /// The cutoff by golden section in ln f within one grid step either side of `cutoff_hz`.
    fn refine_cutoff(&self, f: OutputFilter, cutoff_hz: f64) -> Option<(f64, OutputFilterFit)> {
        let with = |fc: f64| {
            let kind = match f.kind() {
                FilterKind::LowPass1 { .. } => FilterKind::LowPass1 { cutoff_hz: fc },
                _ => FilterKind::LowPass2 { cutoff_hz: fc },
            };
            OutputFilter::new(kind, f.decimation()).ok()
        };
        let chi = |ln_fc: f64| {
            with(ln_fc.exp())
                .and_then(|f| self.try_filter(f))
                .map_or(f64::INFINITY, |u| u.0)
        };
        let step = (0.4f64 / 0.005).ln() / 9.0;
        let (mut a, mut b) = (cutoff_hz.ln() - step, cutoff_hz.ln() + step);
        let g = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..25 {
            let (x1, x2) = (b - g * (b - a), a + g * (b - a));
            if chi(x1) < chi(x2) {
                b = x2;
            } else {
                a = x1;
            }
        }
        with((0.5 * (a + b)).exp()).and_then(|f| self.try_filter(f))
    }

    /// Of the filters the data cannot tell apart (chi2 within 6 of the best, "not strong" evidence,
    /// Kass & Raftery 1995; widened by the best fit's Birge ratio squared, as the intervals are, when
    /// the rest of the model leaves the fit overdispersed), the one with the smallest decimation: the
    /// simplest, and the cheapest to simulate.
    fn simplest(&self, tried: Vec<(f64, OutputFilterFit)>) -> Option<(f64, OutputFilterFit)> {
        let m = self.tau.len();
        let best_chi2 = tried.iter().map(|t| t.0).fold(f64::INFINITY, f64::min);
        let alike = 6.0 * birge_scale(best_chi2, Effect::OutputFilter.free_parameters(), m).powi(2);
        tried
            .into_iter()
            .filter(|t| t.0 <= best_chi2 + alike)
            .min_by(|a, b| {
                a.1.filter
                    .decimation()
                    .cmp(&b.1.filter.decimation())
                    .then(a.0.total_cmp(&b.0))
            })
    }
}

impl Trial {
    /// The fitted parameters by their docs/cli.md names (an output filter's with its white noise).
    pub(crate) fn named(&self) -> Named {
        named(&self.term, self.white_n)
    }
}

/// Named parameters as the report's map.
pub(crate) fn named_map(p: &Named) -> BTreeMap<String, f64> {
    p.iter().map(|(k, v)| (k.to_string(), *v)).collect()
}
