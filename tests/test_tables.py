"""Tables that explain themselves: every table the package writes or prints (``reproduce``'s
Tables 4 and 5, the base-parameter table, ``identify``'s report, ``compare``'s report.md)
has a note right under it that defines each column, in backticks as
:func:`~sedsabso_jax._output.columns_note` writes it, unless the header carries its unit in
brackets. Each is rendered here from small synthetic inputs; and ``markdown_table`` (now
tabulate's) keeps its cells and stays a GitHub table."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import sedsabso_jax as sj
from sedsabso_jax._output import columns_note, markdown_table, to_its_std
from sedsabso_jax.compare._report import render
from sedsabso_jax.identification._default._report import IdentificationReport
from sedsabso_jax.identification._validation._cross_validation import CrossValidation
from sedsabso_jax.identification._validation._selection import PriorSelection, Selection
from sedsabso_jax.reproduce._report import base_parameter_table, table4, table5

#: Units a header may carry in brackets instead of a definition in the note.
UNITS = {"s", "%", "N m"}
SAME = "Columns as in the fit table above."


def _tables(text: str) -> list[tuple[list[str], str]]:
    """``(headers, note)`` of every markdown table in ``text``: the note is the paragraph
    right after the table (after one blank line)."""
    lines, out, i = text.splitlines(), [], 0
    delimiter = re.compile(r"\|(\s*:?-+:?\s*\|)+")
    while i + 1 < len(lines):
        if not (lines[i].startswith("|") and delimiter.fullmatch(lines[i + 1].strip())):
            i += 1
            continue
        head = [c.strip().strip("*") for c in lines[i].strip().strip("|").split("|")]
        i += 2
        while i < len(lines) and lines[i].startswith("|"):
            assert lines[i].count("|") == len(head) + 1, lines[i]  # a cell held a "|"
            i += 1
        note = []
        if i + 1 < len(lines) and not lines[i].strip():
            i += 1
            while i < len(lines) and lines[i].strip():
                note.append(lines[i])
                i += 1
        out.append((head, " ".join(" ".join(note).split())))
    return out


def undefined(text: str) -> list[str]:
    """The headers of ``text``'s tables that neither carry a unit nor are defined in their
    note (or, for a note saying so, in the first table of the same columns)."""
    tables, missing = _tables(text), []
    assert tables, "no table"
    for k, (head, note) in enumerate(tables):
        if note == SAME:
            assert any(h == head for h, n in tables[:k] if n != SAME), head
            continue
        for h in head:
            unit = re.fullmatch(r".*\[(.+)\]", h)
            if not (unit and unit.group(1) in UNITS) and f"`{h}`" not in note:
                missing.append(h)
    return missing


def test_markdown_table_keeps_cells_and_aligns_numbers():
    text = markdown_table(["#", "name", "value", "note"],
                          [["1", "ZZ1R", "0.0000", "a b"], ["12", "FV1", "-1.5e+06", ""]])
    assert text.splitlines() == [
        "| #   | name   |    value | note   |",
        "|:----|:-------|---------:|:-------|",
        "| 1   | ZZ1R   |   0.0000 | a b    |",
        "| 12  | FV1    | -1.5e+06 |        |"]
    assert markdown_table(["a"], [["x"]], align=["right"]).splitlines()[1] == "|----:|"


@pytest.mark.parametrize("value, std, printed", [
    (0.128649, 0.0202, "0.129"), (3.46302, 0.00182, "3.4630"), (1234.5, 120.0, "1230"),
    (7.51405e-06, 0.0172, "0.000"), (-0.0003, 0.0172, "0.000"), (-0.00080188, 0.0289, "-0.001"),
    (3e-07, 1e-09, "3.000e-07"), (-2.5e-12, 1e-09, "0"), (1.23456789e-08, 2.3e-12, "1.23457e-08"),
    (4.9999999999990115, 4.05e-14, "4.999999999999011"), (0.00123, 1e-9, "0.0012300000"),
    (1e300, 1e-300, "1.0000000000000001e+300"),
    (0.123456789, math.inf, "0.123457"), (0.123456789, 0.0, "0.123457")])
def test_a_value_is_printed_to_its_stds_second_significant_digit(value, std, printed):
    """What a report prints of a value: the digits its std leaves (no ``-0``); 6
    significant digits where the std is ``inf`` (not determined) or 0."""
    assert to_its_std(value, std) == printed


@given(st.floats(-1e3, 1e3), st.floats(1e-11, 1e2))
def test_a_printed_value_is_within_half_a_digit_and_the_same_on_another_processor(value, std):
    """The printed value lies within half a unit of the std's second significant digit of
    the value, and a change far below it (another processor's last bits) prints the same
    but where the value lies within 1e-6 of that unit of a rounding boundary."""
    step = 10.0 ** (math.floor(math.log10(std)) - 1)
    printed = to_its_std(value, std)
    assert abs(float(printed) - value) <= 0.5 * step * (1 + 1e-9) + 1e-12 * abs(value)
    if abs(abs(value / step) % 1 - 0.5) > 1e-6:
        assert to_its_std(value + 1e-8 * step, std) == printed


def test_the_checker_finds_a_missing_definition():
    note = columns_note(("a", "first"), (["b c", "d"], "others"))
    text = markdown_table(["a", "b c", "d", "t [s]"], [["1", "2", "3", "4"]]) + "\n\n" + note
    assert undefined(text) == []
    assert undefined(text.replace("`d`", "d")) == ["d"]
    assert undefined(text.replace("t [s]", "t [ms]")) == ["t [ms]"]


@pytest.mark.parametrize("paper_columns", [True, False])
def test_base_parameter_table(paper_columns):
    text = base_parameter_table(sj.robots.rs010n(), paper_columns=paper_columns)
    assert undefined(text) == []
    assert "kg m^2" in text and "N m s/rad" in text


def _results() -> dict:
    methods = ("SEDSABSO", "BSO", "LDWPSO", "OLS", "LM", "L1-LP")
    names, exprs = ["ZZ1R", "FV1"], ["ZZ1 + YY2", "FV1"]
    return {
        "settings": {"samples": 20, "noise": 0.0, "scenario": "paper",
                     "search_box": {"rule": "true +- 10 %"}, "runs": 2, "iterations": 3,
                     "seed": 0, "dtype": "float64", "device": "cpu: cpu",
                     "excitation": {"cond": 12.5}},
        "base_parameters": {"names": names, "expressions": exprs, "true": [1.0, 0.5]},
        "algorithms": {m: {"fitness_mean": 1.0 + k, "fitness_std": 0.1 * k,
                           "time_mean_s": 0.01, "batched_time_s": None if k > 2 else 0.02,
                           "compile_s": 1.0, "max_abs_error": 1e-3,
                           "gap_to_l1_optimum": 1.27e6 if k < 5 else 0.0,
                           "params_mean": [1.0 + 1e-3 * k, 0.5]}
                       for k, m in enumerate(methods)},
    }


def test_reproduce_tables():
    results = _results()
    for text in (table4(results), table5(results)):
        assert undefined(text) == []
    assert "1e-9 sum |tau|" in table4(results)


def test_reproduce_tables_print_the_same_on_another_processor():
    """Noise-free data: the baselines' fitness and errors are rounding (another
    processor's: 1.43e-10 or 9.87e-11 N m, errors 2.8e-14 or 7.1e-14, a value -1e-15 or
    +1e-15); both print the same (``0``, ``0.0000``), what lies above 1e-9 of the scale
    as it is."""
    def results(fitness: float, error: float, sign: float) -> dict:
        r = _results()
        r["torque_l1_norm"] = 2e5  # the rounding floor 2e-4 N m
        for k, m in enumerate(("OLS", "LM", "L1-LP")):
            r["algorithms"][m].update(fitness_mean=fitness * (k + 1), fitness_std=0.0,
                                      max_abs_error=error,
                                      params_mean=[1.0 + error, sign * 1e-15])
        r["base_parameters"]["true"] = [1.0, 0.0]
        f_l1 = r["algorithms"]["L1-LP"]["fitness_mean"]
        for m in ("OLS", "LM"):  # as the experiment computes it
            r["algorithms"][m]["gap_to_l1_optimum"] = (
                r["algorithms"][m]["fitness_mean"] - f_l1) / max(f_l1, 1e-9 * 2e5)
        return r

    here, other = results(1.43e-10, 2.8e-14, -1.0), results(9.87e-11, 7.1e-14, 1.0)
    assert table4(here) == table4(other) and table5(here) == table5(other)
    ols = next(r for r in table4(here).splitlines() if r.startswith("| OLS"))
    assert [c.strip() for c in ols.split("|")[2:4]] == ["0", "0"]
    assert ols.split("|")[8].strip() == "0"  # the gap
    assert "-0.0000" not in table5(here) and undefined(table4(here)) == []
    above = results(1e-3, 1e-6, 1.0)  # above the floors: as they are
    ols = next(r for r in table4(above).splitlines() if r.startswith("| OLS"))
    assert [c.strip() for c in ols.split("|")[2:3]] == ["0.001"] and "1e-06" in ols


def test_a_dropped_definition_fails():
    """The check on a real table: Table 4 without one column's definition fails."""
    text = table4(_results())
    assert undefined(text.replace("`max abs error`", "max abs error")) == ["max abs error"]


def _compare_docs() -> list[dict]:
    rng = np.random.default_rng(0)
    docs = []
    for name, suite, dim in (("bbob-f01-sphere-d02", "bbob", 2),
                             ("rs010n-prior", "identification", 21)):
        targets = 51 if suite == "bbob" else 2
        algs = {n: {"label": label, "precision": rng.lognormal(k, 1, 6).tolist(),
                    "run_lengths": [[10.0] * 3 + [None] * (targets - 3)] * 6,
                    "evaluations": 100}
                for k, (n, label) in enumerate((("SEDSABSO", "SEDSABSO"), ("BSO", "BSO"),
                                                ("PSO", "evosax PSO")))}
        docs.append({"problem": {"name": name, "suite": suite, "dim": dim}, "algorithms": algs})
    return docs


def test_compare_report():
    settings = {"runs": 6, "budget": "100d", "seed": 0, "dtype": "float32", "version": "0",
                "instances": [1, 2]}
    text, _ = render(_compare_docs(), settings)
    assert len(_tables(text)) == 5 and undefined(text) == []
    assert "## SEDSABSO against BSO and evosax PSO (" in text
    # without BSO and PSO: the heading names the peer compared (LDWPSO)
    docs = _compare_docs()
    for d in docs:
        d["algorithms"] = {"SEDSABSO": d["algorithms"]["SEDSABSO"],
                           "LDWPSO": {**d["algorithms"]["BSO"], "label": "LDWPSO"}}
    text, _ = render(docs, settings)
    assert "## SEDSABSO against LDWPSO (" in text and not re.search(r"\bBSO\b", text)


def _cross_validation(rng, tau, limits, n_parameters) -> CrossValidation:
    metrics = sj.validation_metrics(tau, tau + rng.normal(0, 0.1, tau.shape), limits)
    return CrossValidation(metrics, rng.uniform(1, 2, 4), 2.5, np.arange(len(tau)) % 4,
                           n_parameters, {})


@pytest.mark.parametrize("limits", [None, (100.0, 200.0, 50.0)], ids=["no limits", "limits"])
def test_identify_report(limits):
    """The report of a noise-free OLS fit, with made-up cross-validation, model and prior
    selections and held-out data: every table of its text."""
    rng = np.random.default_rng(1)
    robot = sj.robots.rs010n()
    traj = sj.FourierTrajectory(rng.uniform(-0.3, 0.3, (3, 3)), rng.uniform(-0.3, 0.3, (3, 3)),
                                np.zeros(3), wf=0.6)
    data = sj.simulate_measurements_along(robot, traj, np.arange(120) / 40.0)
    with pytest.warns(UserWarning, match="excite the robot's base parameters poorly"):
        ident = sj.identify(robot, data, sj.OLS(), sj.TorqueModel.of(robot))  # 3 s
    cvs = [_cross_validation(rng, np.asarray(data.tau), limits, k) for k in (21, 24)]
    settings = [{"method": "OLS", "sigma": None, "friction": "viscous-coulomb"},
                {"method": "WLS", "sigma": "residual", "friction": "viscous-coulomb+offset"}]
    selection = Selection(tuple(zip(settings, cvs)), settings[0], settings[1])
    prior = PriorSelection(((0.0, cvs[0]), (1e-3, cvs[1])), 1e-3, 0.0)
    report = IdentificationReport.evaluate(ident, data, data, limits, cross_validation=cvs[0],
                                           selection=selection, prior_selection=prior)
    text = report.text()
    # the 7th: extrapolation, the 8th: rests
    assert len(_tables(text)) == 8 and undefined(text) == []
    # each value to its std's second significant digit: within half of it (the std from
    # noise-free data 1e-10 or less, so that 6 significant digits would lie farther), the
    # std to 2 significant digits
    rows = [r.split("|")[2:5] for r in text.splitlines() if re.match(r"\| \d+ +\|", r)]
    assert [n.strip() for n, _, _ in rows] == list(ident.names)
    std = np.asarray(ident.std)
    assert 0 < std.max() < 1e-10
    step = 10.0 ** (np.floor(np.log10(std)) - 1)
    printed = np.array([float(v) for _, v, _ in rows])
    assert np.all(np.abs(printed - ident.values) <= 0.5 * step * (1 + 1e-9))
    assert [float(s) for _, _, s in rows] == [float(f"{sd:.2g}") for sd in std]
    assert "100 RMS error / (2 torque limit)" in " ".join(text.split())
