"""Comparing optimisers the way optimisation research does: equal budgets in fitness
evaluations, many seeded runs, a standard suite, statistics. What ``sedsabso-jax compare``
runs and writes. Builds on every layer below it (the identification problems come from
``reproduce``'s experiment and the real KUKA data).

- :mod:`.problems`: BBOB f1-f24 (evosax's JAX implementation) and the identification
  problems, with their known optima;
- :mod:`.statistics`: median / IQR, Mann-Whitney U with Holm's correction, Vargha-Delaney
  A12, run lengths and their ECDF;
- :mod:`.run`: the runs, one resumable JSON file per problem;
- :mod:`.report`: report.md, summary.json and the ECDF figures.
"""
