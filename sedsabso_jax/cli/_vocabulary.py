"""The words the command's flags take and the defaults their help states, written out
here so that parsing the command line and showing its help import neither JAX nor the
library (``sedsabso-jax --help`` answers at once). Each is the library's own value, as
tests/test_cli_startup.py checks; the library checks them again when a command runs."""

from __future__ import annotations

#: ``identification.FRICTION_TERMS``: the words of ``--friction``'s ``a+b`` text, as
#: the terms' order declares them (``sedsabso_jax/_terms.py``, which imports nothing).
from .._terms import FRICTION_TERMS as FRICTION_TERMS

#: ``identification.AUTO``: ``--method``, ``--weights`` and ``--friction`` left to
#: validation.
AUTO = "auto"
#: ``Estimator.registered()``: the names ``identify --method`` takes.
ESTIMATORS = ("OLS", "WLS", "L1", "LM", "SEDSABSO", "BSO", "LDWPSO")
#: ``identification.FRICTION_CANDIDATES`` as ``--friction`` text.
FRICTION_CANDIDATES = ("viscous-coulomb+smooth", "viscous-coulomb+offset+smooth",
                       "viscous-coulomb+offset+armature+smooth",
                       "viscous-coulomb+offset+smooth+load",
                       "viscous-coulomb+offset+armature+smooth+load")
#: ``identification.DEFAULT``'s folds of the motion's phase, and its speed split: fit where
#: a joint moves below ``FIT_BELOW`` of its peak speed, predict above ``PREDICT_ABOVE``.
FOLDS = 5
FIT_BELOW = 0.7
PREDICT_ABOVE = 0.8
#: ``identification.PRIOR_STRENGTHS``: what ``--prior-strength cv`` chooses from.
PRIOR_STRENGTHS = (0.0, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0)
#: ``identification.GAIN_METHODS``' names, and the default method's.
GAIN_METHODS = ("ordinary", "total", "likelihood", "physical")
DEFAULT_GAIN_METHOD = "likelihood"
#: ``compare``'s defaults: ``DEFAULT_ALGORITHMS``, ``DEFAULT_BUDGET``, the BBOB
#: functions (all 24), dimensions and instances as the flags write them.
COMPARE_ALGORITHMS = ("SEDSABSO", "BSO", "LDWPSO", "PSO", "CMA_ES")
COMPARE_BUDGET = "500d"
BBOB_FUNCTIONS = "1-24"
BBOB_DIMENSIONS = (2, 3, 5, 10, 20, 40)
BBOB_INSTANCES = "1-5,101-110"
