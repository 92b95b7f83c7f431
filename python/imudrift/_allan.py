"""``imudrift.allan``: the analysis of ``imudrift allan`` for one channel, as Python objects."""

from dataclasses import dataclass
from typing import Dict, Optional

import numpy as np

from ._imudrift import InvalidInput
from ._imudrift import allan_analysis as _analysis
from ._samples import as_samples as _as_samples
from . import _args

ONE_SIGMA = 0.6826894921370859  # erf(1/sqrt 2), NIST SP 1065 §5.3

# IEEE 952 term, its Allan-variance slope and the unit of its coefficient (u: unit of the samples).
_TERMS = {
    "q": ("quantisation", "u*s"),
    "n": ("white noise (ARW / VRW)", "u*sqrt(s)"),
    "b": ("bias instability", "u"),
    "k": ("rate random walk", "u/sqrt(s)"),
    "r": ("rate ramp", "u/s"),
}


@dataclass(frozen=True)
class Term:
    """One IEEE 952 coefficient in the unit of the samples times seconds to the term's power
    (Q u*s, N u*sqrt(s), B u, K u/sqrt(s), R u/s) with its 1-sigma standard error and the
    interval value -/+ sigma."""

    name: str
    value: float
    sigma: float

    @property
    def interval(self):
        return (self.value - self.sigma, self.value + self.sigma)


@dataclass(frozen=True)
class Fit:
    """The IEEE 952 fit of a curve (crate ``allan``, module ``fit``): weighted non-negative least
    squares of sigma^2(tau) = 3Q^2/tau^2 + N^2/tau + (2 ln2/pi) B^2 + K^2 tau/3 + R^2 tau^2/2
    (IEEE 952-1997 Annex C). ``terms`` maps q, n, b, k, r to a :class:`Term` or ``None`` (term
    not present); ``readings`` are the spec-sheet readings of the curve as ``imudrift allan --json``
    gives them: the -1/2 (-1, +1/2) line fitted where its term dominates, the minimum only where
    the curve rises significantly after it, B = minimum / 0.664; a reading the curve does not
    resolve is ``None`` with ``<name>_bound`` beside it (docs/allan.md, "Readings")."""

    terms: Dict[str, Optional[Term]]
    reduced_chi2: float
    model_error: float
    readings: Dict[str, Optional[float]]

    def to_dict(self):
        return {
            "terms": {
                k: None if t is None else {"value": t.value, "sigma": t.sigma}
                for k, t in self.terms.items()
            },
            "reduced_chi2": self.reduced_chi2,
            "model_error": self.model_error,
            "readings": dict(self.readings),
        }


class AllanResult:
    """A deviation curve with its confidence intervals, as ``imudrift allan`` computes it.

    Arrays, one value per averaging time: ``tau`` (s), ``deviation`` (unit of the samples),
    ``lo`` and ``hi`` (the interval at ``confidence``; ``interval`` gives both), ``edf``
    (equivalent degrees of freedom), ``alpha`` (noise type: rate PSD ~ f^alpha, 2 white PM ...
    -2 random-walk FM), ``m`` (averaging factor), ``n_terms``, ``bins`` (non-overlapping
    intervals of length tau in the record).
    """

    _COLUMNS = ("tau", "deviation", "lo", "hi", "edf", "alpha", "m", "n_terms", "bins")

    def __init__(self, raw, estimator, rate, confidence):
        for c in self._COLUMNS:
            setattr(self, c, raw[c])
        self.estimator = estimator
        self.rate = rate
        self.confidence = confidence
        self._fit = raw["fit"]

    @property
    def interval(self):
        """``(lo, hi)``: the chi-squared confidence interval of each deviation (SP 1065 eq 45)."""
        return self.lo, self.hi

    def __len__(self):
        return len(self.tau)

    def __repr__(self):
        return f"AllanResult({self.estimator}, {len(self)} taus from {self.tau[0]:g} s to {self.tau[-1]:g} s)"

    def fit(self):
        """The IEEE 952 terms with their standard errors (:class:`Fit`). Only the Allan-variance
        estimators (adev, oadev, totdev) have one; others raise ``ValueError``."""
        if self._fit is None:
            raise ValueError(
                f"no IEEE 952 fit for {self.estimator}: the model's closed forms are those of the Allan variance (use adev, oadev or totdev)"
            )
        f = self._fit
        terms = {
            k: None if v is None else Term(_TERMS[k][0], float(v[0]), float(v[1]))
            for k, v in f["terms"].items()
        }
        return Fit(terms, f["reduced_chi2"], f["model_error"], dict(f["readings"]))

    def to_dict(self):
        """Plain Python lists and numbers (JSON-ready; NaN where no interval was computed)."""
        d = {c: getattr(self, c).tolist() for c in self._COLUMNS}
        d.update(estimator=self.estimator, rate=self.rate, confidence=self.confidence)
        d["fit"] = None if self._fit is None else self.fit().to_dict()
        return d

    def to_pandas(self):
        """A ``pandas.DataFrame`` with one row per tau (pandas is optional)."""
        try:
            import pandas as pd
        except ImportError:
            raise ImportError(
                "AllanResult.to_pandas() needs pandas: pip install pandas (or use .to_dict())"
            ) from None
        return pd.DataFrame({c: getattr(self, c) for c in self._COLUMNS})


    def plot(self, ax=None, label=None):
        """The curve with its interval band on log-log axes, and the IEEE 952 fit when there is
        one (matplotlib is optional). Returns the matplotlib ``Axes``."""
        try:
            import matplotlib.pyplot as plt
        except ImportError:
            raise ImportError(
                "AllanResult.plot() needs matplotlib: pip install matplotlib"
            ) from None
        if ax is None:
            _, ax = plt.subplots()
        line = ax.loglog(self.tau, self.deviation, "o-", ms=3, label=label or self.estimator)[0]
        ax.fill_between(self.tau, self.lo, self.hi, color=line.get_color(), alpha=0.2, lw=0)
        if self._fit is not None:
            # The fitted model's deviation (crate allan, Fit::model_dev), sampled by the library.
            ax.loglog(self._fit["model_tau"], self._fit["model_dev"], "k--", lw=1, label="IEEE 952 fit")
        ax.set_xlabel("tau (s)")
        ax.set_ylabel(f"{self.estimator} (unit of the samples)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
        return ax


def allan(
    data,
    rate,
    data_type="freq",
    estimator="oadev",
    taus="octave",
    confidence=ONE_SIGMA,
    edf="greenhall",
    stable32_stop=True,
):
    """Allan-family deviation of ``data`` sampled at ``rate`` Hz with confidence intervals, noise
    types and (adev, oadev, totdev) the IEEE 952 fit: what ``imudrift allan`` computes per channel.

    ``data``: one channel (a 1-D array) gives one :class:`AllanResult`; an N x k array (one
    channel per column, MATLAB ``allanvar``'s layout, e.g. a gyro triad or a DataFrame's values)
    gives a list of k results, each the result of the 1-D call on its column.

    ``data_type``: ``"freq"`` (rate samples: gyro rate, specific force) or ``"phase"``.
    ``estimator``: adev, oadev, mdev, hdev, ohdev, totdev (Stable32's total deviation, bias
    corrected once the noise type is known), mtotdev, htotdev (HTOT bias corrected as Stable32
    does), theo1 (tau = 0.75 m / rate, even m), theoh (oadev below a tenth of the record,
    bias-removed Theo1 beyond); docs/allan.md. ``taus``: ``"octave"``, ``"decade"``, ``"all"``,
    ``"N/decade"``, or averaging times in seconds. ``edf``: ``"greenhall"`` (noise identified per
    tau by the lag-1 ACF), ``"simple"`` (SP 1065 Table 5) or ``"none"``. ``stable32_stop``: stop
    at Stable32's largest averaging factor (N/4 for oadev).

    >>> import numpy as np, imudrift
    >>> gyro = np.random.default_rng(1).normal(0.0, 0.01, 360_000)  # rad/s at 100 Hz
    >>> r = imudrift.allan(gyro, 100.0)
    >>> r.fit().terms["n"].value  # about 0.01 / sqrt(100) = 1e-3 rad/sqrt(s)
    """
    rate = _args.number("rate", rate)
    confidence = _args.number("confidence", confidence)
    columns = _columns(data)
    if columns is not None:
        results = []
        for j, c in enumerate(columns):
            try:
                results.append(_one(_as_samples(c), rate, data_type, estimator, taus, confidence,
                                    edf, stable32_stop))
            except InvalidInput as e:
                raise InvalidInput(f"data[:, {j}] (column {j} of {len(columns)}): {e}") from None
        return results
    return _one(_as_samples(data), rate, data_type, estimator, taus, confidence, edf, stable32_stop)


def _columns(data):
    """The columns of a 2-D array (N x k), or None when ``data`` is not 2-D (the 1-D path then
    checks it)."""
    if data is None or isinstance(data, (str, bytes)):
        return None
    try:
        a = np.asarray(data)
    except (TypeError, ValueError):
        return None
    if a.ndim != 2:
        return None
    if a.shape[1] == 0:
        raise InvalidInput(f"data: an N x k array needs at least one column, got shape {a.shape}")
    return [a[:, j] for j in range(a.shape[1])]


def _one(samples, rate, data_type, estimator, taus, confidence, edf, stable32_stop):
    raw = _analysis(
        samples,
        rate,
        _args.text("data_type", data_type),
        _args.text("estimator", estimator),
        taus if isinstance(taus, str) else _args.numbers_list("taus", taus),
        confidence,
        _args.text("edf", edf),
        bool(stable32_stop),
    )
    return AllanResult(raw, estimator, rate, confidence)
