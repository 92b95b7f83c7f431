//! The sensor's own digital output filter.
//!
//! An [`OutputFilter`] runs at an internal rate (`decimation` times the output rate) on everything
//! the channel's error terms produce except quantisation and outliers, which act on the output
//! register; the output keeps every `decimation`-th filtered sample. Every kind has unit DC gain, so
//! the long-tau Allan deviation and the drift growth laws (which depend on the noise spectrum at
//! low frequency) are unchanged; the filter lowers the short-tau Allan deviation, correlates
//! neighbouring samples and delays the signal by its group delay. Its exact Allan variance is in
//! `crate::filter::FilteredAllan`.
//!
//! Impulse responses (internal interval `dt_i`, normalised to unit DC gain):
//! - `moving_average` with `taps` L: h_i = 1/L, i < L.
//! - `bartlett` with `taps` L: the triangle h_i proportional to min(i + 1, L - i), i < L (the
//!   convolution of two moving averages of ceil(L/2) and floor(L/2) + 1 taps; Oppenheim & Schafer,
//!   "Discrete-Time Signal Processing", 3rd ed., §7.5.1, Bartlett window without its zero end points).
//! - `lowpass1` with `cutoff_hz` f_c: y_n = a y_{n-1} + (1 - a) x_n, a = exp(-2 pi f_c dt_i) (impulse
//!   invariance of the RC low-pass, Oppenheim & Schafer §7.2.1).
//! - `lowpass2` with `cutoff_hz` f_c: second-order Butterworth by the bilinear transform with
//!   pre-warping, K = tan(pi f_c dt_i) (Oppenheim & Schafer §7.2.2; the RBJ audio-EQ cookbook biquad
//!   with Q = 1/sqrt(2)).
//!
//! The infinite responses are truncated where the remaining tail is below 1e-17 of the response's
//! peak (their sum then differs from 1 by less than 1e-15).

use super::term::{note_value_units, ErrorTerm, GenContext, NoGenerator, TermKind, WriteContext};
use crate::config::error::ConfigError;
use crate::config::read::{Integer, ReadContext, Text};
use crate::filter::FilteredAllan;
use crate::law_source::{LawSource, LawSourceContext};
use crate::model_error::{check, ModelError};
use crate::units::{Quantity, Signal};
use crate::ImuRng;

/// Which filter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FilterKind {
    MovingAverage { taps: u32 },
    Bartlett { taps: u32 },
    LowPass1 { cutoff_hz: f64 },
    LowPass2 { cutoff_hz: f64 },
}

impl FilterKind {
    /// The config / JSON name.
    pub fn name(&self) -> &'static str {
        match self {
            FilterKind::MovingAverage { .. } => "moving_average",
            FilterKind::Bartlett { .. } => "bartlett",
            FilterKind::LowPass1 { .. } => "lowpass1",
            FilterKind::LowPass2 { .. } => "lowpass2",
        }
    }
    /// The kinds' names, for messages.
    pub const NAMES: [&'static str; 4] = ["moving_average", "bartlett", "lowpass1", "lowpass2"];
}

/// Longest impulse response accepted, internal samples (the exact Allan variance costs its square).
pub const MAX_RESPONSE: usize = 8192;

/// The channel's digital output filter: `kind` at the internal rate `decimation` x the output rate,
/// every `decimation`-th filtered sample kept (1: no decimation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OutputFilter {
    kind: FilterKind,
    decimation: u32,
}

impl OutputFilter {
    /// Check the values: taps 1..=MAX_RESPONSE, decimation >= 1, cutoff finite and > 0.
    /// (The cutoff's upper limit, the internal Nyquist frequency, depends on the rate: see
    /// [`OutputFilter::check_rate`].)
    pub fn new(kind: FilterKind, decimation: u32) -> Result<OutputFilter, ModelError> {
        match kind {
            FilterKind::MovingAverage { taps } | FilterKind::Bartlett { taps } => {
                if taps == 0 || taps as usize > MAX_RESPONSE {
                    return Err(ModelError {
                        what: "output filter taps",
                        expected: "1 to 8192 taps",
                        found: f64::from(taps),
                    });
                }
            }
            FilterKind::LowPass1 { cutoff_hz } | FilterKind::LowPass2 { cutoff_hz } => {
                check("output filter cutoff", cutoff_hz, true)?;
            }
        }
        if decimation == 0 {
            return Err(ModelError {
                what: "output filter decimation",
                expected: "a whole number >= 1",
                found: 0.0,
            });
        }
        Ok(OutputFilter { kind, decimation })
    }

    /// Which filter, with its taps or cutoff.
    pub fn kind(&self) -> FilterKind {
        self.kind
    }

    /// Internal samples per output sample (1: no decimation).
    pub fn decimation(&self) -> u32 {
        self.decimation
    }

    /// Internal sample interval for output interval `dt_s`.
    pub fn internal_dt(&self, dt_s: f64) -> f64 {
        dt_s / f64::from(self.decimation)
    }

    /// Can this filter run at output interval `dt_s`? A low-pass cutoff must lie below the internal
    /// Nyquist frequency and its response must fit in [`MAX_RESPONSE`] internal samples.
    pub fn check_rate(&self, dt_s: f64) -> Result<(), ModelError> {
        let dt_i = self.internal_dt(dt_s);
        if let FilterKind::LowPass1 { cutoff_hz } | FilterKind::LowPass2 { cutoff_hz } = self.kind {
            if cutoff_hz >= 0.5 / dt_i {
                return Err(ModelError {
                    what: "output filter cutoff",
                    expected: "a frequency below the internal Nyquist frequency (output rate x decimation / 2)",
                    found: cutoff_hz,
                });
            }
        }
        if self.response_len(dt_i).is_none() {
            return Err(ModelError {
                what: "output filter cutoff",
                expected:
                    "a cutoff high enough that the response settles within 8192 internal samples",
                found: match self.kind {
                    FilterKind::LowPass1 { cutoff_hz } | FilterKind::LowPass2 { cutoff_hz } => {
                        cutoff_hz
                    }
                    _ => f64::NAN,
                },
            });
        }
        Ok(())
    }

    fn response_len(&self, dt_i: f64) -> Option<usize> {
        let h = self.raw_response(dt_i, MAX_RESPONSE + 1);
        (h.len() <= MAX_RESPONSE).then_some(h.len())
    }

    /// Impulse response at the internal interval `dt_i`, unit DC gain (see the module docs).
    /// At most `limit` samples.
    fn raw_response(&self, dt_i: f64, limit: usize) -> Vec<f64> {
        match self.kind {
            FilterKind::MovingAverage { taps } => vec![1.0 / f64::from(taps); taps as usize],
            FilterKind::Bartlett { taps } => {
                let l = taps as usize;
                let w: Vec<f64> = (0..l).map(|i| (i + 1).min(l - i) as f64).collect();
                let s: f64 = w.iter().sum();
                w.into_iter().map(|v| v / s).collect()
            }
            FilterKind::LowPass1 { cutoff_hz } => {
                let (b, a) = lowpass1_coefficients(cutoff_hz, dt_i);
                iir_response(&b, &a, limit)
            }
            FilterKind::LowPass2 { cutoff_hz } => {
                let (b, a) = lowpass2_coefficients(cutoff_hz, dt_i);
                iir_response(&b, &a, limit)
            }
        }
    }

    /// The impulse response at output interval `dt_s` (internal samples, unit DC gain).
    pub fn impulse_response(&self, dt_s: f64) -> Vec<f64> {
        let mut h = self.raw_response(self.internal_dt(dt_s), MAX_RESPONSE);
        let s: f64 = h.iter().sum();
        if s != 0.0 && (s - 1.0).abs() > 0.0 {
            h.iter_mut().for_each(|v| *v /= s);
        }
        h
    }

    /// The recursion (b, a) for the IIR kinds at output interval `dt_s`
    /// (y_n = sum b_j x_{n-j} - sum_{j>=1} a_j y_{n-j}, a_0 = 1); None for the FIR kinds.
    pub fn recursion(&self, dt_s: f64) -> Option<(Vec<f64>, Vec<f64>)> {
        let dt_i = self.internal_dt(dt_s);
        match self.kind {
            FilterKind::LowPass1 { cutoff_hz } => Some(lowpass1_coefficients(cutoff_hz, dt_i)),
            FilterKind::LowPass2 { cutoff_hz } => Some(lowpass2_coefficients(cutoff_hz, dt_i)),
            _ => None,
        }
    }

    /// One-sided equivalent noise bandwidth of the output, Hz: white noise of one-sided density S0
    /// leaves the filter with variance S0 B. B = (f_i / 2) sum h_i^2 (f_i the internal rate, unit DC
    /// gain); no filter: the Nyquist frequency. Decimation keeps the variance, so B is that of the
    /// internal filter.
    pub fn noise_bandwidth_hz(&self, dt_s: f64) -> f64 {
        let dt_i = self.internal_dt(dt_s);
        let h = self.impulse_response(dt_s);
        0.5 / dt_i * h.iter().map(|v| v * v).sum::<f64>()
    }

    /// Group delay at DC, s (sum i h_i dt_i): how far the filtered signal lags.
    pub fn delay_s(&self, dt_s: f64) -> f64 {
        let dt_i = self.internal_dt(dt_s);
        self.impulse_response(dt_s)
            .iter()
            .enumerate()
            .map(|(i, v)| i as f64 * v)
            .sum::<f64>()
            * dt_i
    }
}

fn lowpass1_coefficients(cutoff_hz: f64, dt_i: f64) -> (Vec<f64>, Vec<f64>) {
    let a = (-std::f64::consts::TAU * cutoff_hz * dt_i).exp();
    (vec![1.0 - a], vec![1.0, -a])
}

fn lowpass2_coefficients(cutoff_hz: f64, dt_i: f64) -> (Vec<f64>, Vec<f64>) {
    let k = (std::f64::consts::PI * cutoff_hz * dt_i).tan();
    let r2 = std::f64::consts::SQRT_2;
    let norm = 1.0 / (1.0 + r2 * k + k * k);
    let b0 = k * k * norm;
    (
        vec![b0, 2.0 * b0, b0],
        vec![
            1.0,
            2.0 * (k * k - 1.0) * norm,
            (1.0 - r2 * k + k * k) * norm,
        ],
    )
}

/// Impulse response of the recursion, until the remaining tail is below 1e-17 of the peak (checked
/// over the last two samples, which bound a stable first- or second-order tail), at most `limit`.
fn iir_response(b: &[f64], a: &[f64], limit: usize) -> Vec<f64> {
    let mut h: Vec<f64> = Vec::new();
    let mut peak: f64 = 0.0;
    for n in 0..limit {
        let mut y = if n < b.len() { b[n] } else { 0.0 };
        for j in 1..a.len() {
            if n >= j {
                y -= a[j] * h[n - j];
            }
        }
        peak = peak.max(y.abs());
        h.push(y);
        if n >= b.len() + 2 && h[n].abs() + h[n - 1].abs() < 1e-17 * peak {
            break;
        }
    }
    h
}

/// `output_filter = { kind, taps | cutoff, decimation? }` as written.
#[derive(serde::Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawOutputFilter {
    kind: Text,
    taps: Option<Integer>,
    cutoff: Option<Text>,
    decimation: Option<Integer>,
}

/// The filter adds no error of its own; it changes the other terms' Allan variances
/// (`crate::filter::FilteredAllan`, used by `AxisModel`).
impl ErrorTerm for OutputFilter {
    /// None: unit DC gain adds no error of its own, and the other terms' laws hold for times much
    /// longer than its impulse response.
    fn law_sources(&self, _cx: &LawSourceContext) -> Vec<LawSource> {
        Vec::new()
    }

    /// The taps (`taps`) or the cutoff (`cutoff_hz`), and the decimation (`decimation`); a filter
    /// has no level.
    fn shape(&self) -> Vec<(&'static str, f64)> {
        let first = match self.kind {
            FilterKind::MovingAverage { taps } | FilterKind::Bartlett { taps } => {
                ("taps", f64::from(taps))
            }
            FilterKind::LowPass1 { cutoff_hz } | FilterKind::LowPass2 { cutoff_hz } => {
                ("cutoff_hz", cutoff_hz)
            }
        };
        vec![first, ("decimation", f64::from(self.decimation))]
    }

    fn config_value(&self, cx: &WriteContext) -> String {
        let parameter = match self.kind {
            FilterKind::MovingAverage { taps } | FilterKind::Bartlett { taps } => {
                format!("taps = {taps}")
            }
            FilterKind::LowPass1 { cutoff_hz } | FilterKind::LowPass2 { cutoff_hz } => {
                format!("cutoff = {}", cx.quoted(cutoff_hz, Quantity::Frequency))
            }
        };
        format!(
            "{{ kind = \"{}\", {parameter}, decimation = {} }}",
            self.kind.name(),
            self.decimation
        )
    }
}

impl TermKind for OutputFilter {
    const STOCHASTIC: bool = false;
    const LONG_TERM: bool = false;
    const FREE_PARAMETERS: usize = 2;
    const SHOWS_IN_STATIC_LOG: bool = true;
    type Raw = RawOutputFilter;
    const EXAMPLE: Option<&'static str> = Some("output_filter = { kind = \"lowpass2\", cutoff = \"25 Hz\", decimation = 4 } or { kind = \"bartlett\", taps = 8 }");

    /// Kind `"moving_average"` or `"bartlett"` with `taps` (an integer, 1 to 8192), `"lowpass1"` or
    /// `"lowpass2"` with `cutoff` (a frequency); `decimation` (integer >= 1, default 1) internal
    /// samples per output sample. The kind's own parameter and no other.
    fn from_raw(raw: &RawOutputFilter, cx: &ReadContext) -> Result<OutputFilter, ConfigError> {
        let sub = |name: &str| cx.sub(name);
        let ctx = cx.ctx;
        // An integer's place in the file, for `invalid_at`.
        let at = |i: &Integer| Text::new(i.span(), i.get_ref().to_string());
        let kind = raw.kind.get_ref().as_str();
        let fir = match kind {
        "moving_average" | "bartlett" => true,
        "lowpass1" | "lowpass2" => false,
        other => {
            return Err(ctx.invalid_at(
                &sub("kind"),
                Some(&raw.kind),
                "one of \"moving_average\", \"bartlett\" (with taps), \"lowpass1\", \"lowpass2\" (with cutoff)",
                format!("\"{other}\""),
            ))
        }
    };
        let (needs, extra) = if fir {
            ("taps", raw.cutoff.clone().map(|c| ("cutoff", c)))
        } else {
            ("cutoff", raw.taps.as_ref().map(|t| ("taps", at(t))))
        };
        if let Some((name, text)) = extra {
            return Err(ctx.invalid_at(
                &sub(name),
                Some(&text),
                format!("only `{needs}` and `decimation` for kind \"{kind}\""),
                "an extra key",
            ));
        }
        let kind = if fir {
            let t = raw.taps.as_ref().ok_or_else(|| {
                ctx.invalid(
                    &sub("taps"),
                    format!("the number of taps for kind \"{kind}\", an integer such as taps = 8"),
                    "nothing",
                )
            })?;
            let taps = u32::try_from(*t.get_ref())
                .ok()
                .filter(|&n| n >= 1 && n as usize <= MAX_RESPONSE)
                .ok_or_else(|| {
                    ctx.invalid_at(
                        &sub("taps"),
                        Some(&at(t)),
                        format!("an integer from 1 to {MAX_RESPONSE}"),
                        t.get_ref().to_string(),
                    )
                })?;
            if kind == "moving_average" {
                FilterKind::MovingAverage { taps }
            } else {
                FilterKind::Bartlett { taps }
            }
        } else {
            let c = raw.cutoff.as_ref().ok_or_else(|| {
                ctx.invalid(
                    &sub("cutoff"),
                    format!("the cutoff frequency for kind \"{kind}\", e.g. cutoff = \"25 Hz\""),
                    "nothing",
                )
            })?;
            let cutoff_hz = ctx.positive(&sub("cutoff"), c, Quantity::Frequency)?;
            if kind == "lowpass1" {
                FilterKind::LowPass1 { cutoff_hz }
            } else {
                FilterKind::LowPass2 { cutoff_hz }
            }
        };
        let decimation = match &raw.decimation {
            None => 1,
            Some(d) => u32::try_from(*d.get_ref())
                .ok()
                .filter(|&n| n >= 1)
                .ok_or_else(|| {
                    ctx.invalid_at(
                    &sub("decimation"),
                    Some(&at(d)),
                    "a whole number >= 1 (internal samples per output sample; 1: no decimation)",
                    d.get_ref().to_string(),
                )
                })?,
        };
        OutputFilter::new(kind, decimation).map_err(|e| cx.refused(&cx.key, e))
    }

    fn note_units(value: &toml::Value, sig: Signal, note: &mut dyn FnMut(Quantity, &toml::Value)) {
        note_value_units(value, Quantity::Signal(sig), sig, note);
    }

    type Generator = NoGenerator;

    /// The channel runs the filter itself ([`FilterState`]): it sets the interval of every other
    /// term's raw samples.
    fn generator(&self, _cx: &GenContext, _rng: &dyn Fn() -> ImuRng) -> NoGenerator {
        NoGenerator
    }
}

/// An IIR recursion: coefficients (b, a) and the input and output histories (newest first).
#[derive(Clone, Debug)]
struct IirState {
    b: Vec<f64>,
    a: Vec<f64>,
    xs: Vec<f64>,
    ys: Vec<f64>,
}

/// Which raw samples of a block are read out: the one at `next` (index in the block) into output
/// slot `slot`, then every `every`-th into the following slots.
#[derive(Clone, Copy)]
struct Readout {
    next: u64,
    slot: usize,
    every: u64,
}

impl Readout {
    /// Output `y`, raw sample `j` of the block, if it is the next one read out.
    #[inline(always)]
    fn take(&mut self, j: usize, y: f64, out: &mut [f64]) {
        if j as u64 == self.next {
            out[self.slot] = y;
            self.slot += 1;
            self.next += self.every;
        }
    }
}

impl IirState {
    /// The recursion over `raw`, y_r = sum_i b_i x_{r-i} - sum_{i>=1} a_i y_{r-i} (the histories
    /// newest first), writing the samples `read` names into `out`; `NB`, `NA` the lengths of b and
    /// a (the first- and second-order kinds), so the histories stay in registers.
    #[inline]
    fn run<const NB: usize, const NA: usize>(
        &mut self,
        raw: &[f64],
        read: Readout,
        out: &mut [f64],
    ) {
        let b: [f64; NB] = std::array::from_fn(|i| self.b[i]);
        let a: [f64; NA] = std::array::from_fn(|i| self.a[i]);
        let mut xs: [f64; NB] = std::array::from_fn(|i| self.xs[i]);
        let mut ys: [f64; NA] = std::array::from_fn(|i| self.ys[i]);
        let mut read = read;
        for (j, &x) in raw.iter().enumerate() {
            xs.rotate_right(1);
            xs[0] = x;
            let mut y: f64 = b.iter().zip(xs.iter()).map(|(b, x)| b * x).sum();
            for i in 1..NA {
                y -= a[i] * ys[i - 1];
            }
            ys.rotate_right(1);
            ys[0] = y;
            read.take(j, y, out);
        }
        self.xs.copy_from_slice(&xs);
        self.ys.copy_from_slice(&ys);
    }

    /// [`Self::run`] of the second-order kind (b and a of 3), its histories in named variables:
    /// the same operations in the same order, but the generic loop's dot product is compiled to a
    /// packed multiply that reloads the rotated history from memory each sample, and that store
    /// and reload lie on the recursion's critical path (about 1.5 times slower).
    fn run_second_order(&mut self, raw: &[f64], read: Readout, out: &mut [f64]) {
        let (b0, b1, b2) = (self.b[0], self.b[1], self.b[2]);
        let (a1, a2) = (self.a[1], self.a[2]);
        // Newest first: x1 the last input, y1 the last output.
        let [mut x1, mut x2, mut x3] = [self.xs[0], self.xs[1], self.xs[2]];
        let [mut y1, mut y2, mut y3] = [self.ys[0], self.ys[1], self.ys[2]];
        let mut read = read;
        for (j, &x) in raw.iter().enumerate() {
            // `run`'s sum starts at -0.0, which adds nothing: -0.0 + v is v, bit for bit.
            let mut y = b0 * x + b1 * x1 + b2 * x2;
            y -= a1 * y1;
            y -= a2 * y2;
            (x3, x2, x1) = (x2, x1, x);
            (y3, y2, y1) = (y2, y1, y);
            read.take(j, y, out);
        }
        self.xs.copy_from_slice(&[x1, x2, x3]);
        self.ys.copy_from_slice(&[y1, y2, y3]);
    }
}

/// The output filter's running state: the raw history it needs and where the raw stream stands.
#[derive(Clone, Debug)]
pub(crate) struct FilterState {
    /// Impulse response (FIR kinds; for the IIR kinds only its length sets the pre-roll).
    h: Vec<f64>,
    /// The IIR kinds' recursion and histories.
    iir: Option<IirState>,
    pub(crate) decimation: usize,
    /// Raw samples before the one output 0 is read at: the response's length - 1, so the filter's
    /// history is full (FIR) or settled to 1e-17 (IIR) at t = 0.
    pub(crate) preroll: usize,
    /// Raw samples produced so far.
    pub(crate) raw_done: u64,
    /// The last `h.len() - 1` raw samples (FIR), oldest first.
    history: Vec<f64>,
    /// Scratch for one block's raw samples.
    pub(crate) raw: Vec<f64>,
    /// Scratch for the FIR kinds: the history and the block's first samples.
    head: Vec<f64>,
}

impl FilterState {
    pub(crate) fn new(f: &OutputFilter, dt_s: f64) -> FilterState {
        let h = f.impulse_response(dt_s);
        let iir = f.recursion(dt_s).map(|(b, a)| {
            let (nb, na) = (b.len(), a.len());
            IirState {
                b,
                a,
                xs: vec![0.0; nb],
                ys: vec![0.0; na],
            }
        });
        FilterState {
            preroll: h.len() - 1,
            h,
            iir,
            decimation: f.decimation as usize,
            raw_done: 0,
            history: Vec::new(),
            head: Vec::new(),
            raw: Vec::new(),
        }
    }

    /// A FIR kind (no recursion).
    pub(crate) fn is_fir(&self) -> bool {
        self.iir.is_none()
    }

    /// The impulse response (internal samples, unit DC gain).
    pub(crate) fn response(&self) -> &[f64] {
        &self.h
    }

    /// The raw index (in a block starting at raw sample `start`) and output slot of the block's
    /// first sample read out, then every d-th; output k0 the block's first output.
    fn readout(&self, start: u64, k0: u64) -> Readout {
        let (d, pre) = (self.decimation as u64, self.preroll as u64);
        let first = if start <= pre {
            pre
        } else {
            pre + (start - pre).div_ceil(d) * d
        };
        Readout {
            next: first - start,
            slot: ((first - pre) / d - k0) as usize,
            every: d,
        }
    }

    pub(crate) fn filter(&mut self, start: u64, raw: &[f64], k0: u64, out: &mut [f64]) {
        let read = self.readout(start, k0);
        if let Some(state) = &mut self.iir {
            match (state.b.len(), state.a.len()) {
                (1, 2) => state.run::<1, 2>(raw, read, out),
                (2, 2) => state.run::<2, 2>(raw, read, out),
                (2, 3) => state.run::<2, 3>(raw, read, out),
                (3, 3) => state.run_second_order(raw, read, out),
                // `OutputFilter::recursion` makes only these two orders.
                (nb, na) => {
                    unreachable!("an IIR output filter of order 1 or 2, not b {nb}, a {na}")
                }
            }
        } else {
            self.fir(start, raw, k0, out);
        }
        self.raw_done = start + raw.len() as u64;
    }
}

impl FilterState {
    /// The FIR kinds' block: y_r = sum_i h_i x_{r-i}, only at the raw indices that are read out.
    /// A window that reaches back before the block reads the history joined with the block's
    /// first samples (`head`); the others read the block itself, so the block is not copied
    /// (the sums are the same products added in the same order either way).
    fn fir(&mut self, start: u64, raw: &[f64], k0: u64, out: &mut [f64]) {
        let (d, pre) = (self.decimation as u64, self.preroll as u64);
        let l = self.h.len();
        let hist = self.history.len();
        let mut head = std::mem::take(&mut self.head);
        head.clear();
        head.extend_from_slice(&self.history);
        head.extend_from_slice(&raw[..(l - 1).min(raw.len())]);
        let first = start.max(pre);
        let mut r = pre + (first - pre).div_ceil(d) * d;
        let end = start + raw.len() as u64;
        let window_sum = |w: &[f64]| {
            let mut y = 0.0;
            for (hi, x) in self.h.iter().zip(w.iter().rev()) {
                y += hi * x;
            }
            y
        };
        while r < end {
            // Position of raw sample r in the history followed by the block; its window is the
            // l samples ending there (the pre-roll makes p >= l - 1).
            let p = (r - start) as usize + hist;
            out[((r - pre) / d - k0) as usize] = if p < head.len() {
                window_sum(&head[p + 1 - l..=p])
            } else {
                // Here p >= hist + l - 1: the window lies in the block.
                window_sum(&raw[p - hist + 1 - l..=p - hist])
            };
            r += d;
        }
        // The last l - 1 raw samples: from the block alone, or (a block shorter than that) from
        // the history and the whole block, which `head` then holds.
        let keep = l - 1;
        self.history.clear();
        if raw.len() >= keep {
            self.history.extend_from_slice(&raw[raw.len() - keep..]);
        } else {
            self.history
                .extend_from_slice(&head[head.len() - keep.min(head.len())..]);
        }
        self.head = head;
    }
}

/// A valid term of the effect, for the registry's tests (`terms::samples`).
/// Filters [`FilteredAllan::new`] (the filter's exact Allan forms, `crate::filter`) remembers per thread: `imudrift diagnose` builds the same few
/// thousand candidate filters tens of thousands of times (a golden-section search revisits its
/// points, every channel's round rebuilds its model's filter; 59 003 builds of 13 146 distinct
/// filters for one ADIS16405 log, 2026-11-26).
const REMEMBERED: usize = 256;

thread_local! {
    /// The last [`REMEMBERED`] filters built on this thread, oldest first, with their output interval.
    static BUILT: std::cell::RefCell<std::collections::VecDeque<(OutputFilter, u64, FilteredAllan)>> =
        std::cell::RefCell::default();
}

impl FilteredAllan {
    /// The Allan forms behind `filter` at output interval `dt_s`: remembered per thread (a
    /// deterministic function of its arguments, so a remembered one is the one built anew).
    pub fn new(filter: &OutputFilter, dt_s: f64) -> FilteredAllan {
        let key = dt_s.to_bits();
        let hit = BUILT.with(|b| {
            b.borrow()
                .iter()
                .rev()
                .find(|(f, d, _)| *d == key && f == filter)
                .map(|(_, _, fa)| fa.clone())
        });
        if let Some(fa) = hit {
            return fa;
        }
        let fa = Self::build(filter, dt_s);
        BUILT.with(|b| {
            let mut b = b.borrow_mut();
            if b.len() == REMEMBERED {
                b.pop_front();
            }
            b.push_back((*filter, key, fa.clone()));
        });
        fa
    }

    fn build(filter: &OutputFilter, dt_s: f64) -> FilteredAllan {
        let h = filter.impulse_response(dt_s);
        let l = h.len();
        // The filter's autocorrelation A_h(d) = sum_i h_i h_{i+d}: directly for short responses,
        // through the FFT for long ones (a low-pass far below the rate responds for thousands of
        // samples, and every candidate filter of diagnose builds one).
        let a_h = if l <= 256 {
            (0..l)
                .map(|d| (0..l - d).map(|i| h[i] * h[i + d]).sum())
                .collect()
        } else {
            crate::fft::autocorrelation(&h)
        };
        FilteredAllan::from_parts(
            a_h,
            filter.decimation() as usize,
            dt_s,
            filter.internal_dt(dt_s),
        )
    }
}

#[cfg(test)]
pub(crate) fn sample() -> OutputFilter {
    OutputFilter::new(FilterKind::Bartlett { taps: 8 }, 2).unwrap()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The FIR path read out block by block (blocks of 1 to 600 outputs, so raw blocks both
    /// shorter and longer than the response) gives, bit for bit, the direct sum
    /// y_r = sum_i h_i x_{r-i} over the whole raw stream, for every FIR kind.
    #[test]
    fn fir_blocks_equal_the_direct_sum() {
        for kind in [
            FilterKind::Bartlett { taps: 8 },
            FilterKind::MovingAverage { taps: 5 },
            FilterKind::MovingAverage { taps: 1 },
        ] {
            for decimation in [1, 2, 4] {
                let f = OutputFilter::new(kind, decimation).unwrap();
                let mut state = FilterState::new(&f, 0.01);
                assert!(state.iir.is_none());
                let (d, pre) = (state.decimation as u64, state.preroll as u64);
                let h = state.h.clone();
                let outputs = 3000u64;
                let total = (pre + (outputs - 1) * d + 1) as usize;
                // A deterministic, irregular raw stream.
                let x: Vec<f64> = (0..total)
                    .map(|j| ((j * 7919 % 1013) as f64).sin())
                    .collect();
                let mut got = vec![0.0; outputs as usize];
                let (mut k0, mut size) = (0u64, 1u64);
                while k0 < outputs {
                    let n = size.min(outputs - k0);
                    let end = pre + (k0 + n - 1) * d + 1;
                    let start = state.raw_done;
                    let raw = x[start as usize..end as usize].to_vec();
                    state.filter(start, &raw, k0, &mut got[k0 as usize..(k0 + n) as usize]);
                    k0 += n;
                    size = size * 7 % 601 + 1;
                }
                for (k, g) in got.iter().enumerate() {
                    let r = pre as usize + k * d as usize;
                    let mut y = 0.0;
                    for (i, hi) in h.iter().enumerate() {
                        y += hi * x[r - i];
                    }
                    assert_eq!(
                        g.to_bits(),
                        y.to_bits(),
                        "{kind:?} / {decimation}: output {k}"
                    );
                }
            }
        }
    }

    /// The second-order recursion with named histories gives the bits of the generic one, over
    /// blocks of any length (the state carried between them), with signed zeros in the input and
    /// read out at every decimation and offset.
    #[test]
    fn second_order_run_equals_the_generic_one() {
        let f = OutputFilter::new(FilterKind::LowPass2 { cutoff_hz: 31.7 }, 2).unwrap();
        let (b, a) = f.recursion(0.01).unwrap();
        let fresh = || IirState {
            b: b.clone(),
            a: a.clone(),
            xs: vec![0.0; 3],
            ys: vec![0.0; 3],
        };
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let raw: Vec<f64> = (0..5000)
            .map(|k| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                match k % 97 {
                    0..=9 => -0.0,
                    10 => 0.0,
                    _ => (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5,
                }
            })
            .collect();
        for (block, every) in [(1, 1), (7, 2), (64, 3), (1000, 8), (5000, 1)] {
            let (mut generic, mut named) = (fresh(), fresh());
            let (mut out_g, mut out_n) = (vec![0.0; raw.len()], vec![0.0; raw.len()]);
            let mut slot = 0;
            for (i, chunk) in raw.chunks(block).enumerate() {
                let start = i * block;
                let first = start.div_ceil(every) * every;
                let read = Readout {
                    next: (first - start) as u64,
                    slot,
                    every: every as u64,
                };
                generic.run::<3, 3>(chunk, read, &mut out_g);
                named.run_second_order(chunk, read, &mut out_n);
                slot += (start + chunk.len()).div_ceil(every) - first.div_ceil(every);
            }
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&out_g), bits(&out_n), "block {block} every {every}");
            assert_eq!(bits(&generic.xs), bits(&named.xs));
            assert_eq!(bits(&generic.ys), bits(&named.ys));
        }
    }
}

impl FilterState {
    /// [`FilterState::filter`] of several runs' filters (lanes) over blocks of one length, lane l
    /// reading `raws[l]` into `outs[l]`: each lane's outputs those of its own call. Each four
    /// filters of one shape run in one AVX2 loop ([`lanes4`]), the rest one after the other.
    pub(crate) fn filter_lanes(
        filters: &mut [FilterState],
        start: u64,
        raws: &[Vec<f64>],
        k0: u64,
        outs: &mut [&mut [f64]],
    ) {
        for ((f, raw), out) in filters
            .chunks_mut(4)
            .zip(raws.chunks(4))
            .zip(outs.chunks_mut(4))
        {
            #[cfg(target_arch = "x86_64")]
            if let (Ok(f4), Ok(r4), Ok(o4)) = (
                <&mut [FilterState; 4]>::try_from(&mut *f),
                <&[Vec<f64>; 4]>::try_from(raw),
                <&mut [&mut [f64]; 4]>::try_from(&mut *out),
            ) {
                if lanes4::available(f4, r4) {
                    // SAFETY: `available` checked that the CPU has AVX2.
                    unsafe { lanes4::filter(f4, start, r4, k0, o4) };
                    continue;
                }
            }
            for ((f, raw), out) in f.iter_mut().zip(raw).zip(out.iter_mut()) {
                f.filter(start, raw, k0, out);
            }
        }
    }
}

/// Four runs' output filters in one AVX2 loop, run l in lane l of each 256-bit register: the
/// operations of [`FilterState::filter`] per run in its order (no fused multiply-adds), so each
/// lane's outputs are the bits of its run alone (tested in `tests/lanes.rs`). The IIR kinds are
/// one chain of dependent operations a raw sample (9 cycles for the second order), which four runs
/// share; the FIR kinds' products are shared.
#[cfg(target_arch = "x86_64")]
mod lanes4 {
    use super::{FilterState, Readout};
    use std::arch::x86_64::*;

    thread_local! {
        /// The four lanes' (history and) raw samples interleaved, sample-major; reused.
        static INTERLEAVED: std::cell::RefCell<Vec<f64>> = std::cell::RefCell::default();
    }

    /// Whether the four filters run in lockstep here: AVX2, one kind and shape, one position.
    pub(super) fn available(f: &[FilterState; 4], raws: &[Vec<f64>; 4]) -> bool {
        let shape = |s: &FilterState| {
            (
                s.decimation,
                s.preroll,
                s.raw_done,
                s.history.len(),
                s.h.len(),
                s.iir.as_ref().map(|i| (i.b.len(), i.a.len())),
            )
        };
        std::arch::is_x86_feature_detected!("avx2")
            && f.iter().all(|s| shape(s) == shape(&f[0]))
            && raws.iter().all(|r| r.len() == raws[0].len())
            && matches!(
                f[0].iir.as_ref().map(|i| (i.b.len(), i.a.len())),
                None | Some((1, 2) | (2, 2) | (2, 3) | (3, 3))
            )
    }

    #[inline(always)]
    fn set(v: [f64; 4]) -> __m256d {
        // SAFETY: AVX is implied by the callers' AVX2.
        unsafe { _mm256_set_pd(v[3], v[2], v[1], v[0]) }
    }

    #[inline(always)]
    fn get(v: __m256d) -> [f64; 4] {
        let mut out = [0.0; 4];
        // SAFETY: four f64 into `out`.
        unsafe { _mm256_storeu_pd(out.as_mut_ptr(), v) };
        out
    }

    /// dst[4 k + l] = (lane l's `head` followed by its `raw`)[k]: the heads (a filter's short
    /// history) one by one, the blocks by [`crate::transpose4`].
    #[target_feature(enable = "avx2")]
    fn interleave(head: [&[f64]; 4], raw: &[Vec<f64>; 4], dst: &mut Vec<f64>) {
        let (h, m) = (head[0].len(), raw[0].len());
        if dst.len() < 4 * (h + m) {
            dst.resize(4 * (h + m), 0.0);
        }
        for (l, head) in head.iter().enumerate() {
            for (k, &v) in head.iter().enumerate() {
                dst[4 * k + l] = v;
            }
        }
        crate::transpose4::interleave(
            std::array::from_fn(|l| &raw[l][..]),
            &mut dst[4 * h..4 * (h + m)],
        );
    }

    /// [`FilterState::filter`] of four lanes ([`available`] true).
    #[target_feature(enable = "avx2")]
    pub(super) fn filter(
        f: &mut [FilterState; 4],
        start: u64,
        raws: &[Vec<f64>; 4],
        k0: u64,
        outs: &mut [&mut [f64]; 4],
    ) {
        crate::transpose4::count_block(true);
        INTERLEAVED.with(|buf| {
            let buf = &mut *buf.borrow_mut();
            let m = raws[0].len();
            if f[0].iir.is_some() {
                interleave([&[][..]; 4], raws, buf);
                let read = f[0].readout(start, k0);
                match f[0].iir.as_ref().map(|i| (i.b.len(), i.a.len())) {
                    Some((1, 2)) => iir::<1, 2>(f, &buf[..4 * m], read, outs),
                    Some((2, 2)) => iir::<2, 2>(f, &buf[..4 * m], read, outs),
                    Some((2, 3)) => iir::<2, 3>(f, &buf[..4 * m], read, outs),
                    _ => iir::<3, 3>(f, &buf[..4 * m], read, outs),
                }
            } else {
                let hist = f[0].history.len();
                interleave(std::array::from_fn(|l| &f[l].history[..]), raws, buf);
                fir(f, &buf[..4 * (hist + m)], start, k0, outs);
                // Each lane's last l - 1 samples of its history followed by its block.
                let keep = f[0].h.len() - 1;
                for (s, raw) in f.iter_mut().zip(raws) {
                    let total = s.history.len() + raw.len();
                    let from = total - keep.min(total);
                    let mut next = Vec::with_capacity(keep);
                    next.extend(s.history.iter().chain(raw.iter()).skip(from).copied());
                    s.history = next;
                }
            }
            for (s, raw) in f.iter_mut().zip(raws) {
                s.raw_done = start + raw.len() as u64;
            }
        });
    }

    /// `IirState::run` (and `run_second_order`, the same operations) of four lanes over the
    /// interleaved raw samples `x`.
    #[target_feature(enable = "avx2")]
    fn iir<const NB: usize, const NA: usize>(
        f: &mut [FilterState; 4],
        x: &[f64],
        mut read: Readout,
        outs: &mut [&mut [f64]; 4],
    ) {
        let state = |l: usize| f[l].iir.as_ref().expect("an IIR kind (checked)");
        let b: [__m256d; NB] = std::array::from_fn(|i| set(std::array::from_fn(|l| state(l).b[i])));
        let a: [__m256d; NA] = std::array::from_fn(|i| set(std::array::from_fn(|l| state(l).a[i])));
        let mut xs: [__m256d; NB] =
            std::array::from_fn(|i| set(std::array::from_fn(|l| state(l).xs[i])));
        let mut ys: [__m256d; NA] =
            std::array::from_fn(|i| set(std::array::from_fn(|l| state(l).ys[i])));
        for j in 0..x.len() / 4 {
            xs.rotate_right(1);
            // SAFETY: x holds four values for each of its x.len() / 4 samples.
            xs[0] = unsafe { _mm256_loadu_pd(x.as_ptr().add(4 * j)) };
            // The dot product from b0 x0 (the scalar sum starts at -0.0, which adds nothing).
            let mut y = _mm256_mul_pd(b[0], xs[0]);
            for i in 1..NB {
                y = _mm256_add_pd(y, _mm256_mul_pd(b[i], xs[i]));
            }
            for i in 1..NA {
                y = _mm256_sub_pd(y, _mm256_mul_pd(a[i], ys[i - 1]));
            }
            ys.rotate_right(1);
            ys[0] = y;
            if j as u64 == read.next {
                let v = get(y);
                for (out, v) in outs.iter_mut().zip(v) {
                    out[read.slot] = v;
                }
                read.slot += 1;
                read.next += read.every;
            }
        }
        let (xs, ys) = (xs.map(get), ys.map(get));
        for (l, s) in f.iter_mut().enumerate() {
            let st = s.iir.as_mut().expect("an IIR kind (checked)");
            for (h, v) in st.xs.iter_mut().zip(&xs) {
                *h = v[l];
            }
            for (h, v) in st.ys.iter_mut().zip(&ys) {
                *h = v[l];
            }
        }
    }

    /// `FilterState::fir` of four lanes over the interleaved history and block `x`: y_r = sum_i
    /// h_i x_{r-i} from 0.0, in i order, at the raw indices read out.
    #[target_feature(enable = "avx2")]
    fn fir(f: &[FilterState; 4], x: &[f64], start: u64, k0: u64, outs: &mut [&mut [f64]; 4]) {
        let (d, pre) = (f[0].decimation as u64, f[0].preroll as u64);
        let l = f[0].h.len();
        let hist = f[0].history.len();
        let h: Vec<__m256d> = (0..l)
            .map(|i| set(std::array::from_fn(|k| f[k].h[i])))
            .collect();
        let end = start + (x.len() / 4 - hist) as u64;
        let first = start.max(pre);
        let mut r = pre + (first - pre).div_ceil(d) * d;
        while r < end {
            // The window of raw sample r ends at p in the history followed by the block (the
            // pre-roll makes p >= l - 1).
            let p = (r - start) as usize + hist;
            let mut y = _mm256_setzero_pd();
            for (i, hi) in h.iter().enumerate() {
                // SAFETY: p - i >= p + 1 - l >= 0 and p < x.len() / 4.
                let xv = unsafe { _mm256_loadu_pd(x.as_ptr().add(4 * (p - i))) };
                y = _mm256_add_pd(y, _mm256_mul_pd(*hi, xv));
            }
            let slot = ((r - pre) / d - k0) as usize;
            for (out, v) in outs.iter_mut().zip(get(y)) {
                out[slot] = v;
            }
            r += d;
        }
    }
}
