//! `imudrift._imudrift`: the compiled half of the Python package `imudrift` (python/imudrift/).
//! Thin: every number comes from the library crates the CLI uses (`allan`); this crate turns
//! numpy arrays and Python arguments into their types, releases the GIL while the library
//! works, and turns bad input into `imudrift.InvalidInput` (a `ValueError`).
//!
//! Units: deviations carry the unit of the samples, averaging times are seconds, `rate` is Hz.

use allan::fit::{Fit, TERM_NAMES};
use allan::{AllanPoint, DataKind, EdfMethod, Estimator, Options, Series, TauGrid};
use numpy::{IntoPyArray, PyArrayMethods, PyReadonlyArray1};
use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

create_exception!(
    imudrift,
    InvalidInput,
    PyValueError,
    "Input an imudrift function cannot use (empty or non-finite data, a bad rate, an unknown name)."
);

create_exception!(
    imudrift,
    LogUnreadable,
    pyo3::exceptions::PyOSError,
    "A log file or directory that cannot be read or mapped (an OSError)."
);

mod analyse;
mod sensor;
mod sim;

fn invalid(msg: String) -> PyErr {
    InvalidInput::new_err(msg)
}

/// A tau list as allantools takes it: a keyword or averaging times in seconds.
#[derive(FromPyObject)]
enum TausArg {
    Name(String),
    Seconds(Vec<f64>),
}

fn data_kind(data_type: &str) -> PyResult<DataKind> {
    match data_type {
        "phase" => Ok(DataKind::Phase),
        "freq" => Ok(DataKind::Rate),
        _ => Err(invalid(format!(
            "unknown data_type {data_type:?}: expected \"phase\" or \"freq\""
        ))),
    }
}

fn check_rate(rate: f64) -> PyResult<()> {
    request::allan::check_rate(rate)
        .map(|_| ())
        .map_err(allan_error)
}

/// The samples, copied out of the numpy array while the GIL is held (the library then works on
/// its own buffer with the GIL released, so no Python thread can change the data under it).
fn samples(data: &PyReadonlyArray1<'_, f64>) -> PyResult<Vec<f64>> {
    let data = data
        .as_slice()
        .map_err(|_| invalid("data: expected a contiguous 1-D float64 array".into()))?;
    if data.is_empty() {
        return Err(invalid("data is empty: expected samples".into()));
    }
    // One spare slot: the phase of n rate samples has n + 1 points and is built in this buffer
    // (`Series::from_rate`), which would otherwise be reallocated and copied for the last one.
    let mut owned = Vec::with_capacity(data.len() + 1);
    owned.extend_from_slice(data);
    Ok(owned)
}

/// The averaging factors of a tau list given in seconds (`request::allan::factors_of_seconds`).
fn factors_of_seconds(taus: &[f64], rate: f64, n_phase: usize) -> PyResult<TauGrid> {
    request::allan::factors_of_seconds(taus, rate, n_phase).map_err(allan_error)
}

/// Number of phase points the data gives (rate samples are integrated from x_0 = 0).
fn phase_len(n: usize, kind: DataKind) -> usize {
    match kind {
        DataKind::Rate => n + 1,
        DataKind::Phase => n,
    }
}

fn estimator(name: &str) -> PyResult<Estimator> {
    Estimator::from_name(name).ok_or_else(|| {
        invalid(format!(
            "unknown estimator {name:?}: expected one of {}",
            Estimator::ALL.map(Estimator::name).join(", ")
        ))
    })
}

/// `work` on the phase of `data` (rate samples integrated as `imudrift allan` does), computed
/// with the GIL released on the numpy array in place (no copy: as numpy's own functions do, the
/// array is read while other Python threads run, so it must not be changed meanwhile). Samples
/// an analysis cannot use are refused first, by the rules of a log's samples
/// (`request::allan::check_samples`: at least 2, finite, of magnitude below 1e100, not all one
/// value).
fn with_phase<T: Send>(
    py: Python<'_>,
    data: &[f64],
    kind: DataKind,
    rate: f64,
    work: impl FnOnce(&[f64]) -> T + Send,
) -> PyResult<T> {
    if data.is_empty() {
        return Err(invalid("data is empty: expected samples".into()));
    }
    let tau0_s = 1.0 / rate;
    // Rate data: its phase goes into a numpy array (numpy backs large arrays with huge pages:
    // fewer page faults than a fresh Vec), dropped after the call.
    let phase_array = match kind {
        DataKind::Rate => Some(numpy::PyArray1::<f64>::zeros(py, data.len() + 1, false)),
        DataKind::Phase => None,
    };
    let mut phase_rw = phase_array.as_ref().map(|a| a.readwrite());
    let phase_out = match phase_rw.as_mut() {
        Some(rw) => Some(
            rw.as_slice_mut()
                .map_err(|_| invalid("cannot lay out the phase array".into()))?,
        ),
        None => None,
    };
    sim::detached(py, move || {
        request::allan::check_samples(data).map_err(allan_error)?;
        Ok(match phase_out {
            None => work(data),
            Some(out) => {
                allan::rate_to_phase_into(data, tau0_s, out);
                work(out)
            }
        })
    })?
}

/// The deviation curve from `allan` on the phase of `data` ([`with_phase`]).
fn curve(
    py: Python<'_>,
    data: &[f64],
    kind: DataKind,
    rate: f64,
    est: Estimator,
    grid: TauGrid,
    opts: Options,
) -> PyResult<Vec<AllanPoint>> {
    let tau0_s = 1.0 / rate;
    // The estimators' sums need only the phase (allantools' functions identify no noise
    // type): the integrated rate is used as phase data.
    with_phase(py, data, kind, rate, move |x| {
        Series::new(x, DataKind::Phase, tau0_s).deviation(est, &grid, &opts)
    })
}

type Columns<'py> = (
    Bound<'py, numpy::PyArray1<f64>>,
    Bound<'py, numpy::PyArray1<f64>>,
    Bound<'py, numpy::PyArray1<f64>>,
    Bound<'py, numpy::PyArray1<f64>>,
);

/// allantools' `adev, oadev, mdev, tdev, hdev, ohdev, totdev, mtotdev, ttotdev, htotdev,
/// theo1, mtie, tierms`: `(taus, devs, errs, ns)`. Its conventions: tau grid from the phase
/// length, no Stable32 stop ratio, no total-variance bias correction, `errs = dev / sqrt(n)`
/// (Theo1: dev / sqrt(N - m); TIE rms: 0), points with fewer than 2 terms dropped, Theo1's tau
/// m / rate (not 0.75 m / rate).
#[pyfunction]
#[pyo3(signature = (data, rate, data_type, function, taus=None))]
fn allantools_dev<'py>(
    py: Python<'py>,
    data: PyReadonlyArray1<'py, f64>,
    rate: f64,
    data_type: &str,
    function: &str,
    taus: Option<TausArg>,
) -> PyResult<Columns<'py>> {
    check_rate(rate)?;
    let kind = data_kind(data_type)?;
    // tdev and ttotdev are the modified deviations scaled: TVAR = tau^2/3 MVAR, SP 1065
    // eq (15); TTOT = tau^2/3 MTOT (SP 1065 eq (28) writes tau^3, a misprint allantools notes).
    let time_dev = matches!(function, "tdev" | "ttotdev");
    let time_error = matches!(function, "mtie" | "tierms");
    let est = match function {
        "tdev" => Estimator::Modified,
        "ttotdev" => Estimator::ModifiedTotal,
        // Not estimators of the curve: their own sums below (the grid's estimator is a name).
        "mtie" | "tierms" => Estimator::Overlapping,
        _ => estimator(function)?,
    };
    let data = data
        .as_slice()
        .map_err(|_| invalid("data: expected a contiguous 1-D float64 array".into()))?;
    let n_phase = phase_len(data.len(), kind);
    let grid = grid_of(taus, rate, n_phase)?;
    let n = data.len();
    if time_error {
        let tie = function == "tierms";
        let ms = grid.ms(n_phase);
        let rows: Vec<(usize, f64, usize)> = with_phase(py, data, kind, rate, move |x| {
            ms.iter()
                .filter_map(|&m| {
                    let r = if tie {
                        allan::total::tie_rms(x, m)
                    } else {
                        allan::total::mtie(x, m)
                    };
                    r.filter(|&(_, k)| k > 1).map(|(v, k)| (m, v, k))
                })
                .collect()
        })?;
        if rows.is_empty() {
            request::allan::check_points(function, n, &[]).map_err(allan_error)?;
        }
        let taus: Vec<f64> = rows.iter().map(|r| r.0 as f64 / rate).collect();
        let devs: Vec<f64> = rows.iter().map(|r| r.1).collect();
        let ns: Vec<f64> = rows.iter().map(|r| r.2 as f64).collect();
        // allantools: MTIE's error bar dev / sqrt(n); TIE rms has none (0).
        let errs: Vec<f64> = devs
            .iter()
            .zip(&ns)
            .map(|(d, k)| if tie { 0.0 } else { d / k.sqrt() })
            .collect();
        return Ok((
            taus.into_pyarray(py),
            devs.into_pyarray(py),
            errs.into_pyarray(py),
            ns.into_pyarray(py),
        ));
    }
    let opts = Options {
        edf: EdfMethod::None,
        stable32_stop: false,
        totvar_bias_correction: false,
        ..Options::default()
    };
    let points = curve(py, data, kind, rate, est, grid, opts)?;
    request::allan::check_points(function, n, &points).map_err(allan_error)?;
    // allantools reports tau = m / rate (Theo1 too).
    let taus: Vec<f64> = points.iter().map(|p| p.m as f64 / rate).collect();
    let devs: Vec<f64> = points
        .iter()
        .zip(&taus)
        .map(|(p, tau)| {
            if time_dev {
                tau * p.dev / 3f64.sqrt()
            } else {
                p.dev
            }
        })
        .collect();
    let ns: Vec<f64> = points.iter().map(|p| p.n_terms as f64).collect();
    // allantools' error bar: dev / sqrt(n), not a confidence interval; Theo1's divides by the
    // number of outer terms N - m.
    let errs: Vec<f64> = devs
        .iter()
        .zip(&points)
        .map(|(d, p)| {
            let k = if est == Estimator::Theo1 {
                (n_phase - p.m) as f64
            } else {
                p.n_terms as f64
            };
            d / k.sqrt()
        })
        .collect();
    Ok((
        taus.into_pyarray(py),
        devs.into_pyarray(py),
        errs.into_pyarray(py),
        ns.into_pyarray(py),
    ))
}

/// The factors of an allantools tau argument: `None` or an empty list is "octave", a keyword,
/// or averaging times in seconds (`request::allan::factors_of_seconds`).
fn grid_of(taus: Option<TausArg>, rate: f64, n_phase: usize) -> PyResult<TauGrid> {
    Ok(match taus {
        None => TauGrid::Octave,
        Some(TausArg::Seconds(s)) if s.is_empty() => TauGrid::Octave,
        Some(TausArg::Seconds(s)) => factors_of_seconds(&s, rate, n_phase)?,
        Some(TausArg::Name(name)) => match name.as_str() {
            "octave" => TauGrid::Octave,
            "decade" => TauGrid::Decade,
            "all" => TauGrid::All,
            _ => {
                return Err(invalid(format!(
                    "taus {name:?}: expected \"all\", \"octave\", \"decade\" or averaging times in seconds"
                )))
            }
        },
    })
}

/// allantools' `gradev`: the gap-tolerant overlapping Allan deviation, NaN samples being gaps,
/// `(taus, devs, [lo, hi], ns)` with `ns` the terms whose three phase points are present and
/// [lo, hi] the chi-squared interval at level `ci` from SP 1065 Table 5's EDF for `noisetype`
/// (`wp`, `wf`, `fp`, `ff`, `rf`; N - 1 degrees of freedom otherwise), N the phase points present.
#[pyfunction]
#[pyo3(signature = (data, rate, data_type, taus, ci, noisetype))]
#[allow(clippy::type_complexity)]
fn allantools_gradev<'py>(
    py: Python<'py>,
    data: PyReadonlyArray1<'py, f64>,
    rate: f64,
    data_type: &str,
    taus: Option<TausArg>,
    ci: f64,
    noisetype: &str,
) -> PyResult<(
    Bound<'py, numpy::PyArray1<f64>>,
    Bound<'py, numpy::PyArray1<f64>>,
    (
        Bound<'py, numpy::PyArray1<f64>>,
        Bound<'py, numpy::PyArray1<f64>>,
    ),
    Bound<'py, numpy::PyArray1<f64>>,
)> {
    check_rate(rate)?;
    let kind = data_kind(data_type)?;
    request::allan::check_confidence(ci).map_err(allan_error)?;
    // allantools maps "fp" to alpha = -2 (random-walk FM); flicker PM is alpha = +1 (SP 1065
    // Table 5), which is what its docstring says "fp" means.
    let alpha = match noisetype {
        "wp" => 2,
        "fp" => 1,
        "wf" => 0,
        "ff" => -1,
        "rf" => -2,
        _ => i32::MAX,
    };
    let data = samples(&data)?;
    let n = data.len();
    let tau0_s = 1.0 / rate;
    let rows = sim::detached(py, move || -> PyResult<Vec<[f64; 5]>> {
        request::allan::check_samples_with_gaps(&data).map_err(allan_error)?;
        let phase = match kind {
            DataKind::Phase => data,
            DataKind::Rate => allan::total::rate_to_phase_with_gaps(&data, tau0_s),
        };
        let n_phase = phase.len();
        let present = phase.iter().filter(|v| !v.is_nan()).count();
        let grid = grid_of(taus, rate, n_phase)?;
        Ok(grid
            .ms(n_phase)
            .into_iter()
            .filter_map(|m| {
                let (sum, count) = allan::total::gap_sum(&phase, m);
                // allantools: sqrt(sum / 2n) / m * rate, points of fewer than 2 terms dropped.
                (count > 1).then(|| {
                    let dev = (sum / (2.0 * count as f64)).sqrt() / m as f64 * rate;
                    let edf = allan::edf::simple(present, m, alpha);
                    let (lo, hi) = allan::chi2::confidence_interval(dev, edf, ci);
                    [m as f64 / rate, dev, lo, hi, count as f64]
                })
            })
            .collect())
    })??;
    if rows.is_empty() {
        request::allan::check_points("gradev", n, &[]).map_err(allan_error)?;
    }
    let col = |k: usize| -> Vec<f64> { rows.iter().map(|r| r[k]).collect() };
    Ok((
        col(0).into_pyarray(py),
        col(1).into_pyarray(py),
        (col(2).into_pyarray(py), col(3).into_pyarray(py)),
        col(4).into_pyarray(py),
    ))
}

fn edf_method(name: &str) -> PyResult<EdfMethod> {
    match name {
        "greenhall" => Ok(EdfMethod::Greenhall),
        "simple" => Ok(EdfMethod::Simple),
        "none" => Ok(EdfMethod::None),
        _ => Err(invalid(format!(
            "edf {name:?}: expected \"greenhall\", \"simple\" or \"none\""
        ))),
    }
}

/// Points of a fitted model curve drawn between the first and the last tau.
const MODEL_CURVE_POINTS: usize = 100;

/// The fit, its model curve (`model_tau`, `model_dev`) and the spec-sheet readings as
/// `imudrift allan --json` gives them (docs/cli.md): a reading the curve does not resolve is
/// `None`, with `<name>_bound` beside it; a resolved one has `<name>_lo` / `<name>_hi`
/// (`allan::sheet`).
fn fit_dict<'py>(
    py: Python<'py>,
    fit: &Fit,
    points: &[AllanPoint],
    sheet: Option<&allan::sheet::SheetReadings>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    if let (Some(first), Some(last)) = (points.first(), points.last()) {
        let (a, b) = (first.tau_s.ln(), last.tau_s.ln());
        let steps = (MODEL_CURVE_POINTS - 1) as f64;
        let tau: Vec<f64> = (0..MODEL_CURVE_POINTS)
            .map(|i| (a + (b - a) * i as f64 / steps).exp())
            .collect();
        let dev: Vec<f64> = tau.iter().map(|&t| fit.model_dev(t)).collect();
        d.set_item("model_tau", tau.into_pyarray(py))?;
        d.set_item("model_dev", dev.into_pyarray(py))?;
    }
    let terms = PyDict::new(py);
    for (name, t) in TERM_NAMES.iter().zip(fit.terms()) {
        terms.set_item(name, t.map(|t| (t.value, t.sigma)))?;
    }
    d.set_item("terms", terms)?;
    d.set_item("reduced_chi2", fit.reduced_chi2)?;
    d.set_item("model_error", fit.model_error)?;
    let readings = PyDict::new(py);
    if let Some(sh) = sheet {
        let ieee = 1.0 / allan::fit::BI_PLATEAU_FACTOR;
        for (name, rd, scale) in [
            ("arw_at_1s", &sh.arw, 1.0),
            ("bi_min", &sh.bi_min, 1.0),
            ("bi_ieee", &sh.bi_min, ieee),
            ("rrw_at_3s", &sh.rrw, 1.0),
            ("q_at_sqrt3s", &sh.q, 1.0),
        ] {
            let resolved = rd.value.is_some();
            readings.set_item(name, rd.value.map(|v| v * scale))?;
            readings.set_item(format!("{name}_lo"), resolved.then_some(rd.lo * scale))?;
            readings.set_item(format!("{name}_hi"), resolved.then_some(rd.hi * scale))?;
            readings.set_item(
                format!("{name}_bound"),
                (!resolved).then_some(rd.bound * scale),
            )?;
        }
        readings.set_item("arw_tau_s", sh.arw.value.map(|_| sh.arw.tau_s[0]))?;
        readings.set_item("bi_min_tau_s", sh.bi_min.value.map(|_| sh.bi_min.tau_s[0]))?;
        readings.set_item("rrw_tau_s", sh.rrw.value.map(|_| sh.rrw.tau_s[0]))?;
    }
    d.set_item("readings", readings)?;
    Ok(d)
}

/// A request error of `imudrift.allan`, whose rate argument is `rate` (allantools' name).
fn allan_error(e: request::RequestError) -> PyErr {
    invalid(e.render(&|s| match s {
        request::Setting::Rate => "rate",
        other => sim::argument(other),
    }))
}

/// The analysis `imudrift allan` does for one channel ([`allan::analyse`]): deviations, noise
/// type and EDF per tau, chi-squared intervals, and the IEEE 952 fit (Allan-variance estimators).
#[pyfunction]
#[pyo3(signature = (data, rate, data_type, estimator, taus, confidence, edf, stable32_stop))]
#[allow(clippy::too_many_arguments)]
fn allan_analysis<'py>(
    py: Python<'py>,
    data: PyReadonlyArray1<'py, f64>,
    rate: f64,
    data_type: &str,
    estimator: &str,
    taus: TausArg,
    confidence: f64,
    edf: &str,
    stable32_stop: bool,
) -> PyResult<Bound<'py, PyDict>> {
    request::allan::check_rate(rate).map_err(allan_error)?;
    let kind = data_kind(data_type)?;
    let est = self::estimator(estimator)?;
    request::allan::check_confidence(confidence).map_err(allan_error)?;
    let opts = Options {
        edf: edf_method(edf)?,
        confidence,
        stable32_stop,
        ..Options::default()
    };
    let data = samples(&data)?;
    // The rules of a log's samples (`request::allan`; the CLI's reader applies the same).
    request::allan::check_samples(&data).map_err(allan_error)?;
    let n_phase = phase_len(data.len(), kind);
    let grid = match &taus {
        TausArg::Name(text) => TauGrid::parse(text).ok_or_else(|| {
            invalid(format!(
                "taus {text:?}: expected octave, decade, all, N/decade, or averaging times in seconds"
            ))
        })?,
        TausArg::Seconds(s) => factors_of_seconds(s, rate, n_phase)?,
    };
    let n = data.len();
    // Ctrl-C stops the analysis within a second (`sim::run_until`: the library reads the flag
    // between its stages and before each simulated null log).
    let allan::Analysis {
        points, fit, sheet, ..
    } = sim::run_until(py, None, |stop| {
        let tau0_s = 1.0 / rate;
        let quiet = |_: &str| {};
        match kind {
            DataKind::Rate => {
                allan::analyse_rate_until(data, tau0_s, est, &grid, &opts, &quiet, stop)
            }
            DataKind::Phase => allan::analyse_until(
                &Series::new(&data, kind, tau0_s),
                est,
                &grid,
                &opts,
                &quiet,
                stop,
            ),
        }
    })?;
    // The rule of a channel's curve (`request::allan::check_curve`; the CLI applies the same).
    request::allan::check_curve("data", None, n, &points).map_err(allan_error)?;
    let d = PyDict::new(py);
    let col = |f: &dyn Fn(&AllanPoint) -> f64| -> Vec<f64> { points.iter().map(f).collect() };
    d.set_item("tau", col(&|p| p.tau_s).into_pyarray(py))?;
    d.set_item("deviation", col(&|p| p.dev).into_pyarray(py))?;
    d.set_item("lo", col(&|p| p.lo).into_pyarray(py))?;
    d.set_item("hi", col(&|p| p.hi).into_pyarray(py))?;
    d.set_item("edf", col(&|p| p.edf).into_pyarray(py))?;
    let ints = |f: &dyn Fn(&AllanPoint) -> i64| -> Vec<i64> { points.iter().map(f).collect() };
    d.set_item("alpha", ints(&|p| p.alpha.into()).into_pyarray(py))?;
    d.set_item("m", ints(&|p| p.m as i64).into_pyarray(py))?;
    d.set_item("n_terms", ints(&|p| p.n_terms as i64).into_pyarray(py))?;
    d.set_item("bins", ints(&|p| p.bins as i64).into_pyarray(py))?;
    match &fit {
        Some(f) => d.set_item("fit", fit_dict(py, f, &points, sheet.as_ref())?)?,
        None => d.set_item("fit", py.None())?,
    }
    Ok(d)
}

/// The reader's settings by the names of `imudrift.read_log`'s arguments (the CLI names its flags).
fn read_log_argument(setting: logio::Setting) -> &'static str {
    use logio::Setting;
    match setting {
        Setting::Rate => "rate",
        Setting::Columns => "columns",
        Setting::GyroUnit => "gyro_unit",
        Setting::AccelUnit => "accel_unit",
        Setting::TimeUnit => "time_unit",
        Setting::Topic => "topic",
    }
}

fn unit<U: Copy>(
    arg: &str,
    text: Option<&str>,
    all: &[U],
    name: fn(U) -> &'static str,
) -> PyResult<Option<U>> {
    let Some(text) = text else { return Ok(None) };
    all.iter()
        .copied()
        .find(|&u| name(u) == text)
        .map(Some)
        .ok_or_else(|| {
            let names: Vec<&str> = all.iter().map(|&u| name(u)).collect();
            invalid(format!(
                "{arg} {text:?}: expected one of {}",
                names.join(", ")
            ))
        })
}

/// How the reader reads log files: `read_log`'s arguments.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct ReaderArgs {
    rate: Option<f64>,
    gyro_unit: Option<String>,
    accel_unit: Option<String>,
    time_unit: Option<String>,
    columns: Option<Vec<(String, String)>>,
    topic: Option<String>,
}

/// The reader's settings from `read_log`'s arguments (checked, named by them in errors).
fn read_options(reader: &ReaderArgs) -> PyResult<logio::ReadOptions> {
    if let Some(rate_hz) = reader.rate.filter(|&r| !logio::valid_rate_hz(r)) {
        return Err(invalid(
            logio::Problem::BadRate { rate_hz }.render(&read_log_argument),
        ));
    }
    Ok(logio::ReadOptions {
        rate_hz: reader.rate,
        units: logio::UnitOptions {
            gyro: unit(
                "gyro_unit",
                reader.gyro_unit.as_deref(),
                &logio::GyroUnit::ALL,
                logio::GyroUnit::name,
            )?,
            accel: unit(
                "accel_unit",
                reader.accel_unit.as_deref(),
                &logio::AccelUnit::ALL,
                logio::AccelUnit::name,
            )?,
            time: unit(
                "time_unit",
                reader.time_unit.as_deref(),
                &logio::TimeUnit::ALL,
                logio::TimeUnit::name,
            )?,
        },
        columns: reader.columns.clone().unwrap_or_default(),
        topic: reader.topic.clone(),
    })
}

/// A log file read by the CLI's reader; an unreadable file is a [`LogUnreadable`] (an
/// `OSError`), anything else an [`InvalidInput`], with the reader's message (settings named by
/// `read_log`'s arguments).
fn read_log_file(path: &std::path::Path, opts: &logio::ReadOptions) -> PyResult<logio::Log> {
    logio::read_log(path, opts).map_err(|e| {
        let msg = e.render(&read_log_argument);
        match *e.problem {
            logio::Problem::Unreadable
            | logio::Problem::UnreadableDirectory
            | logio::Problem::Unmappable => LogUnreadable::new_err(match &e.cause {
                Some(c) => format!("{msg}: {c}"),
                None => msg,
            }),
            _ => invalid(msg),
        }
    })
}

/// A log file read by the CLI's reader ([`logio::read_log`]): CSV or gzip CSV, ROS 1 bag, ROS 2
/// MCAP. Returns `source`, `rate_hz`, `t` (s, or None) and `channels`: (name, SI array) pairs in
/// the log's order.
#[pyfunction]
fn read_log_columns<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
    reader: ReaderArgs,
) -> PyResult<Bound<'py, PyDict>> {
    let opts = read_options(&reader)?;
    let mut log = sim::detached(py, || read_log_file(&path, &opts))??;
    let d = PyDict::new(py);
    d.set_item("source", &log.source)?;
    d.set_item("rate_hz", log.rate_hz)?;
    d.set_item(
        "t",
        log.take(logio::Quantity::Time).map(|t| t.into_pyarray(py)),
    )?;
    let mut cols = Vec::new();
    for q in log.order.clone() {
        if let Some(v) = log.take(q) {
            cols.push((q.channel(), v.into_pyarray(py)));
        }
    }
    d.set_item("channels", cols)?;
    Ok(d)
}

/// A static, level IMU log generated from a sensor model ([`noise::ImuErrors::fill_static`]), the
/// values `imudrift generate` writes for the same model, seed and run: `t` (k / rate, s), the six
/// channels gx..az (rad/s, m/s^2) and `temp` (degC), and the model's name.
#[pyfunction]
#[pyo3(signature = (sensor_text, source, duration_s, rate_hz, seed, run, only=None, without=Vec::new()))]
#[allow(clippy::too_many_arguments)]
fn generate_columns<'py>(
    py: Python<'py>,
    sensor_text: &str,
    source: &str,
    duration_s: f64,
    rate_hz: f64,
    seed: u64,
    run: u64,
    only: Option<Vec<String>>,
    without: Vec<String>,
) -> PyResult<Bound<'py, PyDict>> {
    let plan = request::generate::GenerateRequest {
        sensor: request::SensorSource::Text {
            text: sensor_text.to_string(),
            source: source.to_string(),
        },
        duration_s,
        rate_hz,
        seed,
        run,
        only: only.as_deref().map(|t| sim::terms("only", t)).transpose()?,
        without: sim::terms("without", &without)?,
        output: None,
    }
    .validate()
    .map_err(sim::request_error)?;
    let samples = plan.samples as f64;
    // Eight float64 columns, held twice at most (here and in the DataFrame): a limit of the
    // arrays Python returns (the CLI writes its log in blocks).
    let need = samples * 8.0 * 8.0 * 2.0;
    if let Some(free) = logio::available_memory_bytes() {
        if need > free as f64 {
            return Err(invalid(format!(
                "{samples} samples need about {:.1} GiB and {:.1} GiB are available: generate a shorter log or at a lower rate",
                need / 1073741824.0,
                free as f64 / 1073741824.0
            )));
        }
    }
    let model = plan.model;
    let dt_s = 1.0 / rate_hz;
    let n = samples as usize;
    let (cols, temp) = sim::detached(py, || {
        let mut errors = noise::ImuErrors::new(&model, dt_s, seed, run);
        let ideal = noise::StaticLevel::STANDARD;
        let mut cols: [Vec<f64>; 6] = std::array::from_fn(|_| vec![0.0; n]);
        errors.fill_static(
            0,
            &ideal.triad(noise::Sensor::Gyro),
            &ideal.triad(noise::Sensor::Accel),
            cols.each_mut().map(|c| c.as_mut_slice()),
        );
        let temp: Vec<f64> = (0..n as u64).map(|k| errors.temperature_c(k)).collect();
        (cols, temp)
    })?;
    request::generate::GeneratePlan::check_values(
        0,
        noise::Channel::ALL
            .iter()
            .zip(&cols)
            .map(|(&c, v)| (c, v.as_slice())),
    )
    .map_err(sim::request_error)?;
    let d = PyDict::new(py);
    d.set_item("sensor", &model.name)?;
    // t = k / rate from the integer index (docs/architecture.md: never t += dt).
    let t: Vec<f64> = (0..n as u64).map(|k| k as f64 / rate_hz).collect();
    d.set_item("t", t.into_pyarray(py))?;
    for (c, values) in noise::Channel::ALL.iter().zip(cols) {
        d.set_item(c.name(), values.into_pyarray(py))?;
    }
    d.set_item("temp", temp.into_pyarray(py))?;
    Ok(d)
}

/// The module `imudrift._imudrift`.
#[pymodule]
fn _imudrift(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // The channel names in log-column order, and the temperature's (noise::Channel, logio).
    m.add(
        "CHANNELS",
        noise::Channel::ALL.map(noise::Channel::name).to_vec(),
    )?;
    m.add("TEMPERATURE", logio::Quantity::Temperature.channel())?;
    // The defaults of diagnose and drift, the request layer's (`request::diagnose`): the Python
    // signatures show them and pass what the user gave.
    let d = diagnose::Settings::default();
    let lat = diagnose::protocol::DEFAULT_LATITUDE_DEG;
    let diagnose_defaults = PyDict::new(m.py());
    diagnose_defaults.set_item("seed", d.seed)?;
    diagnose_defaults.set_item("seeds", d.seeds)?;
    diagnose_defaults.set_item("rounds", d.max_rounds)?;
    diagnose_defaults.set_item("horizons", d.horizons_s.clone())?;
    diagnose_defaults.set_item("min_delta_bic", d.min_delta_bic)?;
    diagnose_defaults.set_item("tau_min", d.tau_min_s)?;
    diagnose_defaults.set_item("latitude", lat)?;
    m.add("DIAGNOSE_DEFAULTS", diagnose_defaults)?;
    let drift_defaults = PyDict::new(m.py());
    drift_defaults.set_item("horizons", request::diagnose::DRIFT_HORIZONS_S.to_vec())?;
    drift_defaults.set_item("replicates", request::diagnose::DRIFT_REPLICATES)?;
    drift_defaults.set_item("seed", d.seed)?;
    drift_defaults.set_item("latitude", lat)?;
    m.add("DRIFT_DEFAULTS", drift_defaults)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("InvalidInput", m.py().get_type::<InvalidInput>())?;
    m.add_function(wrap_pyfunction!(allantools_dev, m)?)?;
    m.add_function(wrap_pyfunction!(allantools_gradev, m)?)?;
    m.add_function(wrap_pyfunction!(allan_analysis, m)?)?;
    m.add("LogUnreadable", m.py().get_type::<LogUnreadable>())?;
    m.add_function(wrap_pyfunction!(read_log_columns, m)?)?;
    m.add_function(wrap_pyfunction!(generate_columns, m)?)?;
    m.add_function(wrap_pyfunction!(sim::simulate_run, m)?)?;
    m.add_function(wrap_pyfunction!(sim::simulate_shard_bytes, m)?)?;
    m.add_function(wrap_pyfunction!(sim::merge_shards, m)?)?;
    m.add_function(wrap_pyfunction!(sensor::sensor_parse, m)?)?;
    m.add_function(wrap_pyfunction!(sensor::sensor_source, m)?)?;
    m.add_function(wrap_pyfunction!(sensor::sensor_toml_of_json, m)?)?;
    m.add_function(wrap_pyfunction!(sensor::sensor_noise_file, m)?)?;
    m.add_function(wrap_pyfunction!(sensor::sensor_plan, m)?)?;
    m.add_function(wrap_pyfunction!(analyse::spec_run, m)?)?;
    m.add_function(wrap_pyfunction!(analyse::diagnose_run, m)?)?;
    m.add_function(wrap_pyfunction!(analyse::drift_run, m)?)?;
    m.add_function(wrap_pyfunction!(analyse::seconds_of, m)?)?;
    Ok(())
}
