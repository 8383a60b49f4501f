"""What every identification estimator shares: the rows it fits (:class:`FitProblem`), what
it returns (:class:`EstimatorFit`), the one row weighting (:func:`weigh`), and the
:class:`Estimator` interface with its registry of names.

An estimator is an immutable ``equinox.Module`` carrying only its own options, converted
and checked when it is built, with one :meth:`~Estimator.fit` method (the modules of
:mod:`~sedsabso_jax.identification._estimators` have them all). A final class that sets
``registered_as = {"NAME": {}}`` is known by that name to the command line's ``--method`` and to
:meth:`Estimator.named`: writing the class is all it takes to add one.
"""
# no `from __future__ import annotations`: equinox reads the AbstractVar annotations
import abc
import dataclasses
from collections.abc import Callable, Sequence
from typing import Any, ClassVar, TypeAlias

import equinox as eqx
import numpy as np
from jaxtyping import ArrayLike, Float

from ..._deprecation import caller_stacklevel
from ...optim._linear import Factorization, factorize
from .._model._torque_model import TorqueModel

#: How rows are weighted: each joint's rows divided by its standard deviation sigma.
WEIGHTINGS = ("equal", "residual", "limits", "given")
_NAMED: dict[str, tuple[type["Estimator"], dict[str, Any]]] = {}
#: A row weighting (:func:`weigh`): None, ``"residual"``, ``"limits"`` or one positive
#: number per joint.
Sigma: TypeAlias = str | Sequence[float] | Float[ArrayLike, " n"] | None
#: Per-joint torque limits (N m), or None where they are unknown.
Limits: TypeAlias = Sequence[float] | Float[ArrayLike, " n"] | None
#: ``progress(label, done, total)``: called after each fit of a long call (its return value
#: is ignored); ``done`` and ``total``: the work done and in all, in estimated seconds
#: (sedsabso_jax/identification/_work.py), ``done`` growing to ``total``.
ProgressCallback: TypeAlias = Callable[[str, float, float], object]


def per_joint(name: str, value: Sigma, n: int, allow_none: bool = True
              ) -> Float[np.ndarray, " n"] | None:
    """``value`` as ``n`` positive finite numbers (one per joint), or None if allowed."""
    if value is None and allow_none:
        return None
    v = np.asarray(value, dtype=float)
    if v.shape != (n,) or not np.all(np.isfinite(v)) or np.any(v <= 0):
        raise ValueError(f"{name} must be {n} positive finite numbers (one per joint), got "
                         f"{value!r}")
    return v


def check_sigma(sigma: object) -> None:
    """That ``sigma`` (numbers converted to a tuple of floats,
    :func:`~.._options.as_floats`) is None (the estimator's default
    weighting), ``"equal"``, ``"residual"``, ``"limits"`` or positive finite numbers (one
    per joint; their count is checked against the model)."""
    if sigma is None or (isinstance(sigma, str) and sigma in ("equal", "residual", "limits")):
        return
    if not (isinstance(sigma, tuple) and sigma and all(np.isfinite(sigma))
            and min(sigma) > 0):
        raise ValueError(f"sigma must be None, 'equal', 'residual', 'limits' or positive "
                         f"finite numbers (one per joint), got {sigma!r}")


def weighting(sigma: Sigma, default: str = "equal") -> str:
    """The kind of weighting ``sigma`` stands for (one of :data:`WEIGHTINGS`); None is
    ``default``."""
    if sigma is None:
        return default
    return sigma if isinstance(sigma, str) else "given"


def _as_array(value: object) -> object:
    """An array of numbers as a float array; None (and anything else) as given."""
    try:
        return None if value is None else np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return value


class FitProblem(eqx.Module):
    """The rows an estimator fits, checked: the torque ``model``, its regressor
    ``Y (T, n, d)`` and the torques ``tau (T, n)`` (all samples, or a validation's
    training samples), the per-joint torque ``limits`` (or None), and ``warn``: report a
    rank-deficient or ill-conditioned regressor (a ``UserWarning``).

    Rows compressed to their normal equations (:mod:`._normal_equations`) stand for more
    samples than they are: ``samples`` is how many (None: ``Y.shape[0]``), and ``floor
    (n,)`` each joint's squared residual norm that the rows leave out (None: 0)."""

    model: TorqueModel
    Y: np.ndarray = eqx.field(converter=_as_array)
    tau: np.ndarray = eqx.field(converter=_as_array)
    limits: np.ndarray | None = eqx.field(default=None, converter=_as_array)
    warn: bool = True
    floor: np.ndarray | None = eqx.field(default=None, converter=_as_array)
    samples: int | None = None

    def __check_init__(self):
        if not isinstance(self.model, TorqueModel):
            raise TypeError(f"model must be a TorqueModel, got {type(self.model).__name__}")
        n, d = self.model.robot.n_joints, self.model.dim
        Y, tau = self.Y, self.tau
        if not isinstance(Y, np.ndarray) or Y.ndim != 3 or Y.shape[1:] != (n, d):
            raise ValueError(f"Y must have shape (samples, {n}, {d}) (the torque model's "
                             f"regressor), got {np.shape(Y)}")
        if not isinstance(tau, np.ndarray) or tau.shape != (Y.shape[0], n):
            raise ValueError(f"tau must have shape ({Y.shape[0]}, {n}) (one row per sample of "
                             f"Y), got {np.shape(tau)}")
        if Y.shape[0] == 0:
            raise ValueError("no samples")
        if not (np.all(np.isfinite(tau)) and np.isfinite(np.sum(Y))):
            raise ValueError("Y or tau contains NaN or Inf")
        per_joint("limits", self.limits, n)

    @classmethod
    def of(cls, model: TorqueModel, Y: ArrayLike, tau: ArrayLike, limits: Limits = None,
           warn: bool = True) -> "FitProblem":
        """The problem of these rows (all of them, not compressed)."""
        return cls(model, Y, tau, limits, warn)  # type: ignore[arg-type]

    @property
    def n_samples(self) -> int:
        """How many samples the rows stand for."""
        return self.Y.shape[0] if self.samples is None else self.samples

    @property
    def left_out(self) -> np.ndarray:
        """Each joint's squared residual norm the rows leave out (0 unless compressed)."""
        return np.zeros(self.model.robot.n_joints) if self.floor is None else self.floor


@dataclasses.dataclass(frozen=True, eq=False)
class EstimatorFit:
    """What :meth:`Estimator.fit` returns: the model's values ``x`` (and the full
    parameters ``full`` of a physical fit), the ``sigma`` used, the factorisation of the
    unweighted rows ``factor0`` (None when neither the diagnostics nor the fit needed it),
    the weighted rows ``W x ~ b``, the solver's :class:`~sedsabso_jax.Result` (box
    searches, LM) and ``extra`` settings for the report."""

    x: np.ndarray
    full: np.ndarray | None
    sigma: np.ndarray
    factor0: Factorization | None
    W: np.ndarray
    b: np.ndarray
    result: Any
    extra: dict


@dataclasses.dataclass(frozen=True, eq=False)
class WeightedRows:
    """What :func:`weigh` returns: ``sigma``, the rows ``W x ~ b`` divided by it, the
    unweighted factorisation ``factor0`` and the weighted one ``factor`` (when asked)."""

    sigma: np.ndarray
    W: np.ndarray
    b: np.ndarray
    factor0: Factorization | None
    factor: Factorization | None

    @property
    def weighted_factor(self) -> Factorization:
        """The weighted rows' factorisation (``weigh(..., factor=True)``)."""
        if self.factor is None:
            raise ValueError("weigh(..., factor=True) factorises the weighted rows")
        return self.factor


def weigh(problem: FitProblem, sigma: Sigma, *, default: str = "equal",
          factor: bool = False, passes: int = 1) -> WeightedRows:
    """The row weighting every estimator uses: each joint's rows divided by its sigma.

    ``sigma`` (see :func:`check_sigma`): None (``default``: equal, or ``"residual"`` for
    WLS), ``"residual"`` (Gautier's two-step estimate: the RMS of each joint's OLS
    residual, corrected for the parameters acting on that joint), ``"limits"`` (the
    problem's torque limits: the L2 objective is then the squared NRMS over the limits),
    or ``n`` numbers. ``factor``: also factorise the weighted rows (least squares).
    ``passes``: Gautier's estimate made again from the residual of the fit it weighs, so
    many times in all (the first pass's residual of a joint with small torques carries
    the large joints' noise through the parameters they share)."""
    Y, tau, n = problem.Y, problem.tau, problem.model.robot.n_joints
    T = problem.n_samples
    d = Y.shape[-1]
    kind = weighting(sigma, default)
    if kind == "limits" and problem.limits is None:
        raise ValueError("sigma='limits' needs limits=(one torque limit per joint)")
    given = per_joint("sigma", sigma, n, allow_none=False) if kind == "given" else None
    W0, tau0 = Y.reshape(-1, d), tau.reshape(-1)
    # the unweighted factor: the diagnostics, the OLS fit and Gautier's first pass
    factor0 = factorize(W0, tau0) if problem.warn or kind in ("equal", "residual") else None
    if factor0 is not None and problem.warn:
        factor0.warn("identify: the stacked regressor", problem.model.names,
                     stacklevel=caller_stacklevel())
    if kind == "equal":
        return WeightedRows(np.ones(n), W0, tau0, factor0, factor0)
    s: np.ndarray | None
    if kind == "limits":
        s = problem.limits
    elif kind == "given":
        s = given
    else:  # Gautier: sigma_j^2 = ||r_j||^2 / (T - d_j), d_j = parameters acting on joint j
        assert factor0 is not None  # computed above for "residual"
        d_j = np.count_nonzero(np.any(Y != 0, axis=0), axis=-1)
        x = factor0.solve()
        for k in range(passes):
            r = Y @ x - tau
            s = np.sqrt((np.sum(r ** 2, axis=0) + problem.left_out) / np.maximum(T - d_j, 1))
            s = np.where(s > 0, s, max(s.max(), 1e-12))
            if k + 1 < passes:  # the fit these weights give, for the next pass
                row = np.tile(1.0 / s, Y.shape[0])
                x = factorize(W0 * row[:, None], tau0 * row).solve()
    assert s is not None
    row = np.tile(1.0 / s, Y.shape[0])
    W, b = W0 * row[:, None], tau0 * row
    return WeightedRows(np.asarray(s), W, b, factor0, factorize(W, b) if factor else None)


class Estimator(eqx.Module):
    """An identification estimator: an immutable ``equinox.Module`` whose fields are its
    options (converted and checked when it is built: a bad one is a ``ValueError`` naming
    it), with :meth:`fit` to fit a :class:`FitProblem`; abstract or final, as equinox's
    modules are.

    What the orchestration needs to know it asks the estimator: :attr:`name`,
    :attr:`sigma` and :attr:`weights` (the row weighting, :func:`weigh`),
    :attr:`physical`, :attr:`costly`, :attr:`normal_equations`, :attr:`needs_limits`,
    :meth:`physically_consistent`, :meth:`check`, :meth:`settings`. A final class with
    ``registered_as = {"NAME": {fixed options}}`` is known by that name to the command
    line's ``--method`` and to :meth:`named`: writing the class is all it takes."""

    #: Whether the fit is physically consistent (full link parameters).
    physical: eqx.AbstractClassVar[bool]
    #: Whether every fit is costly (a box search): the command then searches no weighting.
    costly: eqx.AbstractClassVar[bool]
    #: Whether :meth:`fit` reads the rows only through each joint's normal equations
    #: (least squares with one weight per joint): validations then fit compressed rows
    #: (:mod:`._compressed`).
    normal_equations: eqx.AbstractClassVar[bool]
    #: The norm of the weighted residual the fit minimises: 2 (least squares) or 1.
    norm: eqx.AbstractClassVar[int]
    #: Name -> the options it fixes, for :meth:`named` and ``--method``.
    registered_as: ClassVar[dict[str, dict[str, Any]]] = {}

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        for name, fixed in cls.__dict__.get("registered_as", {}).items():
            _NAMED[name] = (cls, fixed)

    @property
    @abc.abstractmethod
    def sigma(self) -> str | tuple[float, ...] | None:
        """The row weighting (see :func:`check_sigma`)."""

    @property
    @abc.abstractmethod
    def name(self) -> str:
        """What reports call the method: ``"OLS"``, ``"WLS"``, ``"L1"``, ``"LM"``, a
        solver's label."""

    @property
    @abc.abstractmethod
    def default_weighting(self) -> str:
        """What ``sigma=None`` means for this estimator (one of :data:`WEIGHTINGS`)."""

    @abc.abstractmethod
    def fit(self, problem: FitProblem) -> EstimatorFit:
        """Fit the rows of ``problem``."""

    @abc.abstractmethod
    def check(self, model: TorqueModel, limits: Limits) -> None:
        """What can be checked before any data: the options against ``model`` and the
        torque ``limits`` (None if unknown)."""

    @abc.abstractmethod
    def settings(self) -> dict:
        """The settings the JSON report writes for this estimator (``method``,
        ``physical``, ``weights`` and the estimator's own)."""

    @abc.abstractmethod
    def physically_consistent(self) -> "Estimator":
        """This fit over parameters a real body can have: a least-squares fit's
        :class:`~._least_squares.PhysicallyConsistent` form (itself if it is one); a
        ValueError naming the estimator for the others."""

    @property
    def weights(self) -> str:
        """The kind of row weighting (one of :data:`WEIGHTINGS`)."""
        return weighting(self.sigma, self.default_weighting)

    def loss(self, residual: np.ndarray) -> float:
        """What the fit minimises of its weighted ``residual``: the sum of squares (norm
        2) or of absolute values (norm 1)."""
        r = np.asarray(residual, dtype=float)
        return float(r @ r) if self.norm == 2 else float(np.abs(r).sum())

    @property
    def needs_limits(self) -> bool:
        """Whether the fit needs the torque limits (it weights rows by them)."""
        return self.weights == "limits"

    @staticmethod
    def registered() -> tuple[str, ...]:
        """Every registered name, in the order the classes were defined."""
        return tuple(_NAMED)

    @staticmethod
    def named(name: str, **options: Any) -> "Estimator":
        """The estimator registered as ``name`` (e.g. ``"WLS"``, ``"SEDSABSO"``), built
        with ``options`` (``sigma``, ``runs``, ...; those it does not have are ignored:
        the command passes every swarm option to every estimator)."""
        if name not in _NAMED:
            raise ValueError(f"unknown estimator {name!r}; expected one of {tuple(_NAMED)}")
        cls, fixed = _NAMED[name]
        fields = {f.name for f in dataclasses.fields(cls)}
        return cls(**{k: v for k, v in options.items() if k in fields and k not in fixed},
                   **fixed)


def checked_estimator(estimator: object) -> Estimator:
    """``estimator``, checked to be one."""
    if not isinstance(estimator, Estimator):
        raise TypeError(f"estimator must be an Estimator (OLS(), WLS(...), L1(), "
                        f"BoxSearch(...), ...), got {estimator!r}")
    return estimator


def check_weighting(estimator: Estimator, model: TorqueModel, limits: Limits) -> None:
    """The checks of ``estimator``'s weighting before any data: ``"limits"`` needs them,
    given numbers one per joint."""
    if estimator.needs_limits and limits is None:
        raise ValueError("sigma='limits' needs limits=(one torque limit per joint)")
    if estimator.weights == "given":
        per_joint("sigma", estimator.sigma, model.robot.n_joints, allow_none=False)


def weighting_settings(estimator: Estimator) -> dict:
    """The settings every estimator reports: ``method``, ``physical``, ``weights``."""
    return {"method": estimator.name, "physical": estimator.physical,
            "weights": estimator.weights}


def no_physical_form(estimator: Estimator) -> ValueError:
    """The error of an estimator that has no physically consistent form."""
    return ValueError(f"a physically consistent fit is a least-squares fit: use method 'OLS' "
                      f"or 'WLS', not {estimator.name!r}")


def describe(estimator: Estimator, model: TorqueModel, limits: Limits) -> dict:
    """The settings of fitting ``model`` with ``estimator`` that do not depend on the data,
    in the order the reports write them."""
    own = dict(estimator.settings())
    out = {"method": own.pop("method"), "friction": model.friction,
           "physical": own.pop("physical"), "weights": own.pop("weights"), "limits": limits}
    return {**out, **model.settings(), **own}
