"""The search methods on a term whose nonlinear parameter has many valleys: the torque
ripple of docs/how-to/torque-model-term.md (its class and simulated data run from the
page itself), its three periods searched by each method from 0.1 rad.

    python -m benchmarks.term_search [--json benchmarks/results/term_search.json]

Prints each method's periods found (true 0.3, 0.2, 0.25 rad), its evaluations and the
seconds of its fit (compilation included: each method is a new compiled loss).
"""

from __future__ import annotations

import argparse
import re
import time
from pathlib import Path

import numpy as np

PAGE = Path(__file__).resolve().parents[1] / "docs" / "how-to" / "torque-model-term.md"
TRUE = (0.3, 0.2, 0.25)


def page_namespace() -> dict:
    """The page's first two code blocks (the term and the simulated data), run."""
    blocks = re.findall(r"```python\n(.*?)```", PAGE.read_text(), flags=re.S)
    namespace: dict = {}
    for block in blocks[:2]:
        code = block.split("\nmodel = ")[0] if "sj.identify(" in block else block
        code = "\n".join(line for line in code.splitlines()
                         if not line.startswith(("search = ", "print(")))
        exec(compile(code, str(PAGE), "exec"), namespace)  # noqa: S102 (our own page)
    return namespace


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, help="write the results here")
    args = parser.parse_args(argv)
    ns = page_namespace()
    sj, robot, data, Ripple = ns["sj"], ns["robot"], ns["data"], ns["Ripple"]
    search_of = sj.identification
    CoordinateSearch, PopulationSearch = search_of.CoordinateSearch, search_of.PopulationSearch
    LeastSquaresSearch = search_of.LeastSquaresSearch
    methods = [CoordinateSearch(), CoordinateSearch(points=15), CoordinateSearch(points=25),
               PopulationSearch(sj.SEDSABSO(), 1200), PopulationSearch(sj.LDWPSO(), 1200),
               PopulationSearch(sj.Evosax("CMA_ES"), 1200), LeastSquaresSearch()]
    rows = []
    for search in methods:
        t0 = time.perf_counter()
        fit = sj.identify(robot, data, sj.OLS(),
                          sj.TorqueModel.of(robot, Ripple(fitted=True), search=search))
        seconds = time.perf_counter() - t0
        found = fit.settings["searched"]
        periods = [found["parameters"][f"period{j + 1}"]["value"] for j in range(3)]
        rows.append({"search": repr(search), "periods": periods,
                     "right": bool(np.allclose(periods, TRUE, atol=5e-3)),
                     "evaluations": found["evaluations"], "seconds": seconds})
        print(f"{search!r:55s} {np.round(periods, 3)} "
              f"{'found' if rows[-1]['right'] else 'missed'} "
              f"{found['evaluations']:5d} evaluations {seconds:5.1f} s", flush=True)
    result = {"true_periods": TRUE, "methods": rows}
    if args.json:
        from benchmarks.output import to_json

        args.json.write_text(to_json(result))
    return result


if __name__ == "__main__":
    main()
