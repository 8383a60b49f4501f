"""The paper's experiment reproduced: what ``sedsabso-jax reproduce`` runs and writes. Builds
on every other layer; nothing below imports it.

- :mod:`.experiment`: the experiment (Sec. 5) end to end, its settings and scenarios;
- :mod:`.report`: Tables 4-5 and Figures 5-6 with the paper's numbers beside ours, and the
  base-parameter table with the paper's Table 5.

The paper's published numbers themselves are in :mod:`sedsabso_jax.paper`.
"""
