"""``imudrift.simulate``, ``simulate_shard`` and ``merge``: the Monte Carlo drift run of
``imudrift simulate`` (and its shards and ``imudrift merge``) from Python."""

import os

from ._document import Document
from ._imudrift import InvalidInput, LogUnreadable
from . import _args
from ._imudrift import merge_shards as _merge
from ._imudrift import simulate_run as _simulate
from ._imudrift import simulate_shard_bytes as _shard


class Quantities(list):
    """The navigation-error quantities' names, one per column of ``SimulateResult.values``
    (docs/cli.md: ``heading_rad`` for the heading error in every command). The older name
    ``yaw_rad`` still finds the heading: ``index("yaw_rad")`` and ``"yaw_rad" in q`` accept it."""

    ALIASES = {"yaw_rad": "heading_rad"}

    def index(self, name, *args):
        return super().index(self.ALIASES.get(name, name), *args)

    def __contains__(self, name):
        return super().__contains__(self.ALIASES.get(name, name))

    def with_aliases(self):
        """The names with each alias after the name it stands for (the rows of drift.csv)."""
        out = []
        for q in self:
            out.append(q)
            out.extend(a for a, n in self.ALIASES.items() if n == q)
        return out


class SimulateResult(Document):
    """The result of :func:`simulate` or :func:`merge`.

    - ``values``: per-run values, a numpy array runs x checkpoints x quantities (the runs that
      finished, in run-index order; ``run_ids`` gives their indices);
    - ``t``: checkpoint times (s); ``quantities``: the navigation-error quantities' names, one
      per column of ``values`` (``roll_rad``, ``pitch_rad``, ``heading_rad``, ``pos_north_m``,
      ..., the docs/cli.md names; angles in rad). The heading error's older name ``yaw_rad`` is
      accepted as an alias: ``quantities.index("yaw_rad")`` is the heading's column and
      ``"yaw_rad" in quantities`` is true;
    - ``seed``, ``runs``, ``runs_ok``, ``scenario``, ``sensor``;
    - ``checkpoints``: per checkpoint ``t_s`` and ``channels`` {quantity: statistics and law:
      ``mean std rms p5 p50 p95 law_mean law_std law_rms ratio ratio_lo ratio_hi ...``};
    - ``to_dict()``: the document ``imudrift simulate --json`` prints, equal key by key;
    - ``to_pandas()``: one row per checkpoint and quantity (the rows and columns of drift.csv:
      the heading under ``heading_rad`` and again under ``yaw_rad``, as in the JSON).
    """

    def __init__(self, raw):
        super().__init__(raw["document"])
        self.values = raw["values"]
        self.run_ids = raw["run_ids"]
        self.t = raw["t_s"]
        self.quantities = Quantities(raw["quantities"])

    def to_pandas(self):
        """One row per checkpoint and quantity: ``t_s, quantity, mean, std, rms, p5, p50, p95,
        law_mean, law_std, law_rms, ratio, ratio_lo, ratio_hi, law_note`` (None where there is no
        law); the heading's rows are under ``heading_rad`` and, repeated, under its older name
        ``yaw_rad`` (the JSON keeps both keys too). Needs pandas."""
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("SimulateResult.to_pandas needs pandas: pip install pandas") from None
        cols = ["mean", "std", "rms", "p5", "p50", "p95", "law_mean", "law_std", "law_rms",
                "ratio", "ratio_lo", "ratio_hi", "law_note"]
        rows = []
        for cp in self._doc["checkpoints"]:
            for q in self.quantities.with_aliases():
                c = cp["channels"][q]
                rows.append([cp["t_s"], q] + [c.get(k) for k in cols])
        return pd.DataFrame(rows, columns=["t_s", "quantity"] + cols)

    def __repr__(self):
        return (f"SimulateResult(scenario={self.scenario!r}, sensor={self.sensor!r}, "
                f"runs={self.runs}, runs_ok={self.runs_ok}, seed={self.seed}, "
                f"values shape {tuple(self.values.shape)})")


def _subject(x):
    """A scenario or sensor file path, or a :class:`Sensor` (its text and name)."""
    text = getattr(x, "_text", None)
    if text is not None:
        return (text, x._source)
    if isinstance(x, (str, os.PathLike)):
        return os.fspath(x)
    raise InvalidInput(
        f"scenario: expected a scenario or sensor file path or an imudrift.Sensor, got {type(x).__name__}")


def _settings(runs, seed, duration_s, rate_hz, only, without, ablation, threads):
    return {
        "runs": _args.optional_integer("runs", runs),
        "seed": _args.optional_integer("seed", seed),
        "duration_s": _args.optional_number("duration_s", duration_s),
        "rate_hz": _args.optional_number("rate_hz", rate_hz),
        "only": None if only is None else _args.texts("only", only),
        "without": [] if without is None else _args.texts("without", without),
        "ablation": None if ablation is None else bool(ablation),
        "threads": _args.optional_integer("threads", threads),
    }


def simulate(scenario, runs=None, seed=None, threads=None, duration_s=None, rate_hz=None,
             only=None, without=None, ablation=None):
    """``imudrift simulate SCENARIO``: the Monte Carlo drift run, the same numbers as the CLI.

    ``scenario``: a scenario TOML path (configs/scenarios/), a sensor file path (TOML, Kalibr or
    OpenVINS YAML) or an :class:`imudrift.Sensor`; a sensor is simulated lying still and level
    (the default static scenario: 60 s at 100 Hz, 500 runs, seed 1). ``runs``, ``seed``,
    ``duration_s``, ``rate_hz`` override the scenario's; ``only`` / ``without`` switch error
    terms (``"gyro.white_noise"``, lists accepted); ``ablation`` adds each term alone and the model
    without it (None: as the scenario says); ``threads``: worker threads (None: every core; the
    results do not depend on it). The GIL is released while the runs go on and Ctrl-C stops them.

    >>> r = imudrift.simulate("configs/scenarios/mtx-static-60s.toml", runs=200, seed=3)
    >>> r.values.shape                    # runs x checkpoints x quantities
    >>> r.to_pandas().query("quantity == 'pos_horizontal_m'")
    """
    s = _settings(runs, seed, duration_s, rate_hz, only, without, ablation, threads)
    return SimulateResult(_simulate(_subject(scenario), s))


def simulate_shard(scenario, index, count, runs=None, seed=None, threads=None, duration_s=None,
                   rate_hz=None, only=None, without=None, ablation=None):
    """``imudrift simulate SCENARIO --shard index/count``: the runs of slice ``index`` of
    ``count`` (0 <= index < count), as the bytes of a shard file (the JSON ``imudrift merge``
    reads; write them to ``shard-i-of-k.json`` for the CLI). Give every shard the same arguments;
    :func:`merge` of all ``count`` shards equals :func:`simulate` exactly.

    >>> shards = [imudrift.simulate_shard(path, i, 4, runs=400) for i in range(4)]
    >>> imudrift.merge(shards).to_dict() == imudrift.simulate(path, runs=400).to_dict()
    True
    """
    s = _settings(runs, seed, duration_s, rate_hz, only, without, ablation, threads)
    return _shard(_subject(scenario), _args.integer("index", index),
                  _args.integer("count", count), s)


def merge(shards):
    """``imudrift merge``: the shard files' bytes of :func:`simulate_shard` (or the CLI's shard
    files, read as bytes or given as paths), all ``count`` of them in any order, merged into the
    :class:`SimulateResult` a single :func:`simulate` gives."""
    if isinstance(shards, (str, bytes, os.PathLike)):
        shards = [shards]
    try:
        shards = list(shards)
    except TypeError:
        raise InvalidInput(
            f"shards: expected a list of shards' bytes or paths, got {type(shards).__name__}") from None
    data = []
    for i, s in enumerate(shards):
        if isinstance(s, (str, os.PathLike)):
            try:
                with open(s, "rb") as f:
                    s = f.read()
            except OSError as e:
                raise LogUnreadable(f"cannot read {os.fspath(s)} as a shard file: {e.strerror}") from None
        if not isinstance(s, (bytes, bytearray, memoryview)):
            raise InvalidInput(
                f"shards[{i}]: expected a shard's bytes or a shard file's path, got {type(s).__name__}")
        data.append(bytes(s))
    return SimulateResult(_merge(data))
