"""COCO's data format, checked against COCO itself: the ``.dat`` / ``.tdat`` lines the
package writes against the lines cocoex's own ``bbob`` observer writes for the same
evaluations; cocopp reading the package's folders (no warning, no error); and the aRT and
run lengths of the report against cocopp's ``DataSet.detERT`` / ``detEvals`` on the same
files: on synthetic runs placed on and just above the targets (where cocopp's alignment
tolerances decide) and on a small campaign."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from sedsabso_jax.compare import _alignment as A
from sedsabso_jax.compare import _cocodata as C
from sedsabso_jax.compare import _statistics as S

cocoex = pytest.importorskip("cocoex")
#: cocopp's own target list for its runtime ECDFs (``pprldmany_target_values``)
PPRLDMANY_TARGETS = 10 ** np.arange(2, -8.2, -0.2)


@pytest.fixture(scope="module")
def cocopp():
    with warnings.catch_warnings():  # about its online archive, offline here
        warnings.filterwarnings("ignore", message="failed to connect to")
        cocopp = pytest.importorskip("cocopp")
    cocopp.genericsettings.verbose = False
    return cocopp


def _load(cocopp, folder, capsys):
    """cocopp's data sets of one folder by (function, dimension), and its warnings."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        dsl = cocopp.load(str(folder))
    capsys.readouterr()  # its "Data consistent" line
    return {(ds.funcId, ds.dim): ds for ds in dsl}, [str(w.message) for w in caught]


def _observer_lines(path):
    """``(evaluations, f - f_opt)`` of each run of a .dat or .tdat file."""
    runs = []
    for line in open(path):
        if line.startswith("%"):
            runs.append([])
        else:
            n, _, df = line.split()[:3]
            runs[-1].append((int(n), float(df)))
    return runs


def test_lines_are_the_observers(tmp_path, monkeypatch):
    """A (1+1)-ES with one evaluation per iteration through cocoex's observer, and the
    same best values through :func:`run_lines`: every line after the first is the
    observer's (the first, evaluation 1, is logged as 3e21 by the package)."""
    monkeypatch.chdir(tmp_path)
    rng = np.random.default_rng(0)
    for function, dim, evaluations in ((1, 2, 3000), (2, 10, 3000), (21, 5, 1000)):
        options = f"function_indices: {function} dimensions: {dim}"
        suite = cocoex.Suite("bbob", "instances: 101", options)
        observed = suite.get_problem(0)
        shadow = cocoex.Suite("bbob", "instances: 101", options).get_problem(0)  # unobserved
        observed.observe_with(cocoex.Observer("bbob", f"result_folder: f{function}"))
        x = rng.uniform(-4, 4, dim)
        while shadow(x) >= shadow(np.full(dim, 5.0)):  # evaluation 2 improves on 1
            x = rng.uniform(-4, 4, dim)
        values = [observed(np.full(dim, 5.0)), observed(x)]
        sigma = 1.0
        for _ in range(evaluations - 2):
            y = x + sigma * rng.standard_normal(dim)
            values.append(observed(y))
            if values[-1] <= min(values[:-1]):
                x, sigma = y, sigma * 1.5
            else:
                sigma *= 1.5 ** -0.25
        observed.free()
        f_opt = float(open(f"exdata/f{function}/data_f{function}/bbobexp_f{function}_DIM{dim}"
                           ".dat").readline().split("Fopt (")[1].split(")")[0])
        best = np.minimum.accumulate(values)
        dat, tdat = C.run_lines(np.arange(2, evaluations + 1), best[1:], f_opt, dim)
        stem = f"exdata/f{function}/data_f{function}/bbobexp_f{function}_DIM{dim}"
        for ours, which in ((dat, "dat"), (tdat, "tdat")):
            theirs, = _observer_lines(f"{stem}.{which}")
            mine = [(n, C.printed_precision(f, f_opt)) for n, f in ours]
            assert mine[0] == (1, C.printed_precision(C.LOGGED_INFINITY, f_opt))
            assert mine[1:] == theirs[1:], (function, dim, which)
            assert len(theirs) > 10
        assert best[-1] - f_opt < 1e-8 or function != 1  # the sphere's lines reach 1e-8


def _synthetic(rng, dim):
    """Runs of an imaginary algorithm: best values falling by random factors, some on a
    target, just above one (inside and outside cocopp's tolerances) or at 0."""
    iterations, population = int(rng.integers(20, 150)), int(rng.integers(2, 30))
    counts = population * np.arange(1, iterations + 1)
    df = 10 ** (np.log10(rng.uniform(1, 1e3))
                - np.cumsum(rng.exponential(rng.uniform(0.01, 0.6), iterations)))
    target = S.COCO_TARGETS[rng.integers(0, 51, iterations)]
    kind = rng.random(iterations)
    df = np.where(kind < 0.1, target, df)
    df = np.where((kind >= 0.1) & (kind < 0.2),
                  target * (1 + rng.choice([4e-10, 9e-10, 1.1e-9, 2e-9], iterations)), df)
    df = np.where((kind >= 0.2) & (kind < 0.22), 0.0, df)
    f_opt = float(np.round(rng.uniform(-1000, 1000), 2))
    return counts, np.minimum.accumulate(f_opt + df), f_opt


def _entry(rng, function, dim, instances):
    runs = [_synthetic(rng, dim) for _ in instances]
    lines = [C.run_lines(c, b, f, dim) for c, b, f in runs]
    entry = C.Entry(function, dim, "synthetic", tuple(instances), tuple(f for *_, f in runs),
                    tuple(tuple(d) for d, _ in lines), tuple(tuple(t) for _, t in lines))
    printed = [np.array([(n, C.printed_precision(f, fo)) for n, f in d])
               for d, fo in zip(entry.dat, entry.f_opt)]
    lengths = A.run_lengths(printed, S.COCO_TARGETS)
    return entry, lengths, np.array([c[-1] for c, *_ in runs])


def test_art_and_run_lengths_are_cocopps_on_synthetic_runs(tmp_path, cocopp, capsys):
    rng = np.random.default_rng(1)
    entries = [_entry(rng, f, d, (1, 2, 3, 4, 5, *range(101, 111)))
               for f in (1, 7, 24) for d in (2, 5)]
    C.write_folder(tmp_path / "SYN", "SYN", [e for e, *_ in entries])
    sets, caught = _load(cocopp, tmp_path / "SYN", capsys)
    assert caught == []
    compared = 0
    for entry, lengths, spent in entries:
        ds = sets[entry.function, entry.dim]
        ours = S.average_runtime(lengths, spent)
        theirs = np.array(ds.detERT(list(S.COCO_TARGETS)), dtype=float)
        assert np.array_equal(np.isinf(ours), np.isinf(theirs))
        finite = np.isfinite(ours)
        np.testing.assert_allclose(ours[finite], theirs[finite], rtol=1e-9, atol=0)
        compared += finite.sum()
        evals = np.array(ds.detEvals(list(PPRLDMANY_TARGETS))).T
        np.testing.assert_array_equal(np.where(np.isnan(evals), np.inf, evals), lengths)
    assert compared > 200


def test_cocopp_reads_a_campaign_and_agrees(small_campaign, cocopp, capsys):
    """The small campaign's folders: cocopp reads them without a warning, and the
    report's aRT equals cocopp's on every (function, dimension, target) either reaches;
    the runtime ECDF's run lengths equal cocopp's at its own ECDF targets."""
    out, docs, summary = small_campaign
    compared, worst = 0, 0.0
    for algorithm in ("LDWPSO", "CMA_ES"):
        sets, caught = _load(cocopp, out / "coco" / algorithm, capsys)
        assert caught == [] and len(sets) == 2
        for row in (r for r in summary["anytime"]["aRT"] if r["algorithm"] == algorithm):
            ds = sets[row["function"], row["dim"]]
            assert ds.algId == algorithm and sorted(ds.instancenumbers) == [
                1, 2, 3, 4, 5, *range(101, 111)]
            ours = np.array([np.inf if v is None else v for v in row["aRT"]])
            theirs = np.array(ds.detERT(list(S.COCO_TARGETS)), dtype=float)
            assert np.array_equal(np.isinf(ours), np.isinf(theirs))
            finite = np.isfinite(ours)
            worst = max(worst, float(np.max(np.abs(ours[finite] / theirs[finite] - 1))))
            compared += int(finite.sum())
            doc = next(d for d in docs if d["problem"]["name"] == row["problem"]
                       and algorithm in d["algorithms"])
            lengths = np.array(doc["algorithms"][algorithm]["run_lengths"], dtype=float)
            evals = np.array(ds.detEvals(list(PPRLDMANY_TARGETS))).T
            np.testing.assert_array_equal(np.where(np.isnan(evals), np.inf, evals),
                                          np.nan_to_num(lengths, nan=np.inf))
    assert compared >= 20 and worst <= 1e-9, (compared, worst)
