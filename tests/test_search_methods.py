"""The search methods of a model's nonlinear parameters (``CoordinateSearch``,
``PopulationSearch``, ``LeastSquaresSearch``) on problems whose minimum is known: a
separable bowl with a ridge coupling two coordinates, and a loss with a local minimum on
one coordinate; a search never ends above where it began, stays in its box and counts
its trials; bad options get one line."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import sedsabso_jax as sj
from sedsabso_jax.identification import CoordinateSearch, LeastSquaresSearch, PopulationSearch

CENTRE = np.array([-1.0, 0.5, 2.0])


class Bowl(eqx.Module):
    """A weighted bowl around ``centre`` with two coordinates coupled, as residuals."""

    centre: jax.Array

    def residual(self, u):
        d = u - self.centre
        return jnp.stack([d[0], 3.0 * d[1], 0.5 * d[2], 0.3 * (d[0] + d[1])])

    def loss(self, u):
        return jnp.mean(self.residual(u) ** 2)


class TwoMinima(eqx.Module):
    """A local minimum near u0 = -1.4 and the global one at u0 = 1.5 (loss 0)."""

    offset: jax.Array

    def residual(self, u):
        x = u[0] - self.offset
        return jnp.stack([(x ** 2 - 2.25) / 2, 0.25 * (x - 1.5) * (x < 0), u[1]])

    def loss(self, u):
        return jnp.mean(self.residual(u) ** 2)


class Asymmetric(eqx.Module):
    """A convex kink at ``centre``, ten times steeper on its left: the best point of a
    grid can lie more than half a step from the minimum."""

    centre: jax.Array

    def loss(self, u):
        d = u - self.centre
        return jnp.sum(jnp.where(d > 0, d, -10.0 * d))

    def residual(self, u):
        return jnp.sqrt(self.loss(u))[None]


class Cliff(eqx.Module):
    """:class:`Bowl`'s loss where ``u[2] <= centre[2]``, undefined (NaN) beyond: a loss
    that cannot be evaluated everywhere (a model singular there)."""

    centre: jax.Array

    def residual(self, u):
        r = Bowl(self.centre).residual(u)
        return jnp.where(u[2] > self.centre[2], jnp.nan, r)

    def loss(self, u):
        return jnp.mean(self.residual(u) ** 2)


LOWER, UPPER = np.full(3, -4.0), np.full(3, 4.0)
METHODS = [CoordinateSearch(), PopulationSearch(sj.LDWPSO(), evaluations=2000),
           PopulationSearch(sj.Evosax("CMA_ES"), evaluations=2000), LeastSquaresSearch()]


@pytest.mark.parametrize("method", METHODS, ids=lambda m: getattr(m, "solver", m).__class__
                         .__name__)
def test_each_method_finds_the_bowls_minimum(method):
    """Every method reaches the centre (to 5e-3 in each coordinate; a swarm's 2000 trials
    measured within 2.3e-3) from a corner, inside the box, with no more trials than it
    says and a loss that matches its point."""
    problem = Bowl(jnp.asarray(CENTRE))
    found = method.search(problem, np.array([3.5, -3.5, -3.5]), LOWER, UPPER)
    np.testing.assert_allclose(found.u, CENTRE, atol=5e-3)
    assert np.all((found.u >= LOWER) & (found.u <= UPPER))
    assert found.loss == pytest.approx(float(problem.loss(jnp.asarray(found.u))), rel=1e-9,
                                       abs=1e-15)
    assert 0 < found.evaluations <= (2200 if isinstance(method, PopulationSearch) else 500)


def test_the_global_searches_pass_a_local_minimum():
    """From the local minimum's side, the coordinate search's first sweep spans the bounds
    and lands in the global one; the local method (Levenberg-Marquardt) stays where it
    began: the start competes, and no search ends above it."""
    problem = TwoMinima(jnp.asarray(0.0))
    start, lower, upper = np.array([-1.4, 0.3]), np.array([-3.0, -1.0]), np.array([3.0, 1.0])
    f_start = float(problem.loss(jnp.asarray(start)))
    coordinate = CoordinateSearch().search(problem, start, lower, upper)
    assert coordinate.u[0] == pytest.approx(1.5, abs=1e-2) and coordinate.loss < 1e-5
    local = LeastSquaresSearch().search(problem, start, lower, upper)
    assert local.u[0] < 0 and local.loss > 0.1
    for method in METHODS:
        assert method.search(problem, start, lower, upper).loss <= f_start


def test_the_coordinate_grid_keeps_the_minimum_inside():
    """A kink at 0.1 (first grid: -4, -3, ..., 4, whose best point is 1, 0.9 away): each
    later grid spans a step either side of the best, so the minimum stays inside and is
    found to the last grid's step."""
    problem = Asymmetric(jnp.full(3, 0.1))
    found = CoordinateSearch(points=9, sweeps=4).search(problem, np.zeros(3), LOWER, UPPER)
    np.testing.assert_allclose(found.u, 0.1, atol=0.02)


def test_a_search_from_the_minimum_stays_there():
    """Nothing a search tries from the minimum (here off every grid) is better: the
    coordinate search returns the start itself (a sweep keeps no move that raises the
    loss), the others a point as good."""
    centre = np.array([-0.7, 0.3, 1.7])
    problem = Bowl(jnp.asarray(centre))
    for method in METHODS:
        found = method.search(problem, centre, LOWER, UPPER)
        assert found.loss <= 1e-12, method
    kink = Asymmetric(jnp.asarray(centre))  # a minimum no parabola finds exactly
    np.testing.assert_array_equal(CoordinateSearch().search(kink, centre, LOWER, UPPER).u,
                                  centre)


def test_a_loss_undefined_near_the_minimum_stops_the_polish():
    """Trials the loss cannot evaluate (NaN) around the best point: Newton's polish
    stays where it is, and the search returns that point and its loss."""
    problem = Cliff(jnp.asarray(CENTRE))
    start = np.array([0.0, 0.0, 0.0])
    found = CoordinateSearch().search(problem, start, LOWER, UPPER)
    assert np.isfinite(found.loss) and found.u[2] <= CENTRE[2]
    assert found.loss == pytest.approx(float(problem.loss(jnp.asarray(found.u))))
    assert found.loss < float(problem.loss(jnp.asarray(start)))


@pytest.mark.parametrize("make, match", [
    (lambda: CoordinateSearch(points=3), "^points must be an integer >= 5, got 3$"),
    (lambda: CoordinateSearch(sweeps=0), "^sweeps must be an integer >= 1, got 0$"),
    (lambda: PopulationSearch("LDWPSO"), r"^solver must be an optimiser \(LDWPSO\(\)"),
    (lambda: PopulationSearch(sj.LDWPSO(), evaluations=0), "^evaluations must be"),
    (lambda: LeastSquaresSearch(max_steps=0), "^max_steps must be"),
    (lambda: sj.TorqueModel.of(sj.robots.rs010n(), search="coordinate"),
     r"^search must be a search method \(CoordinateSearch\(\)"),
])
def test_bad_options_are_one_line(make, match):
    with pytest.raises((ValueError, TypeError), match=match) as err:
        make()
    assert "\n" not in str(err.value)
