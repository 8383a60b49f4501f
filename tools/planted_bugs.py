"""Mutation testing by planted bugs: each bug is applied to a scratch copy of the package,
the relevant tests run on that copy, and the bug must make them fail ("killed").

    python tools/planted_bugs.py                 # every bug (about 10-20 minutes, 2 cores)
    python tools/planted_bugs.py --only 3 5      # some of them
    python tools/planted_bugs.py --list

Each bug is one textual replacement in one module: a wrong sign, a dropped term, an
off-by-one schedule, a loosened tolerance, the kind of slip the swarm, fitness, driver and
least-squares code could plausibly contain. A bug that survives is either killed by a new
test or listed below, with the reason it is equivalent. The tool prints a markdown table
and exits with status 1 if any bug not marked equivalent survives.

Not part of the test suite (too slow for CI); run it after changing the modules it covers.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FAST = ["tests/test_swarm_steps.py", "tests/test_linear.py"]
SWARMS = [*FAST, "tests/test_swarms.py"]
BASELINES = [*FAST, "tests/test_baselines.py", "tests/test_identification.py"]
KERNELS = [*FAST, "tests/test_backends.py", "tests/test_swarms.py"]
COMPARE = ["tests/test_compare.py"]
COCO_FORMAT = ["tests/test_compare_coco.py"]
CAMPAIGNS = ["tests/test_compare_campaigns.py"]
COMPOSE = ["tests/test_composition.py"]
PATHS = ["tests/test_solver_paths.py"]
FRICTION = ["tests/test_friction_terms.py"]
STATE = ["tests/test_friction_state.py"]
VALIDATIONS = ["tests/test_validations.py"]
IDENTIFICATION = ["tests/test_identification.py"]
SEARCH = ["tests/test_search_methods.py"]
PAYLOAD = ["tests/test_payload.py"]
RESTS = ["tests/test_rests.py"]
HELD_OUT = ["tests/test_held_out.py"]
SAME = ["tests/test_same_answer.py"]
DEGENERATE = ["tests/test_degenerate_inputs.py"]
STARTUP = ["tests/test_cli_startup.py"]
USABILITY = ["tests/test_cli_usability.py"]
REPRODUCE = ["tests/test_reproduce.py"]
CHAIN = ["tests/test_signal_chain.py"]

#: (module, text, replacement, what the bug is, tests to run, reason if equivalent)
BUGS = [
    ("optim/_swarm.py",
     "        state = when(jnp.asarray(plan.starts)[t],\n"
     "                     lambda s: reorder(s, jnp.asarray(plan.slots)[t]), state)\n", "",
     "step (a loop the user owns) never reorders at a phase's start", PATHS, None),
    ("optim/_driver.py", "    keys = jax.random.split(key, runs)\n    mode, _ = _batching(",
     "    keys = jax.random.split(key, runs)[::-1]\n    mode, _ = _batching(",
     "minimise inside a caller's jit gives its runs other keys", COMPOSE, None),
    ("optim/_bso.py", "antenna_difference(values[n:2 * n],\n"
     "                                                values[2 * n:])",
     "antenna_difference(values[2 * n:],\n"
     "                                                values[n:2 * n])",
     "tell reads the beetles' antennae the wrong way round", PATHS, None),
    ("compare/_cocodata.py", 'return f"{evaluations} 0 {f - f_opt:+10.9e}',
     'return f"{evaluations + 1} 0 {f - f_opt:+10.9e}',
     "a COCO .dat/.tdat line states one evaluation too many", COCO_FORMAT, None),
    ("compare/_cocodata.py", "        lin = linear < self.linear\n", "        lin = False\n",
     "the observer's linear targets (multiples of 1e5, 0 below 1e-12) left out", COCO_FORMAT,
     None),
    ("optim/_sedsabso.py", "return jnp.exp(-(f_new - f_old) / temperature) > u",
     "return jnp.exp((f_new - f_old) / temperature) > u",
     "Metropolis rule with its sign flipped", SWARMS, None),
    ("optim/_sedsabso.py", "            temperature=s.temperature * self.decay)\n",
     "            temperature=s.temperature)\n", "the temperature never cools", SWARMS, None),
    ("optim/_sedsabso.py",
     "e = self.exponent_start + (self.exponent_end - self.exponent_start) * t",
     "e = self.exponent_end + (self.exponent_start - self.exponent_end) * t",
     "Eq. 15-16 in the increasing form", SWARMS, None),
    ("optim/_population.py",
     "order = jnp.argsort(jnp.where(state.active, state.pbest_f, jnp.inf))\n    rank",
     "order = jnp.argsort(jnp.where(state.active, -state.pbest_f, jnp.inf))\n    rank",
     "the best beetles leave first when N(t) falls", SWARMS, None),
    ("optim/_sedsabso.py", "gx = jnp.where(chosen >= 0, cand[jnp.maximum(chosen, 0)], s.guide_x)",
     "gx = s.guide_x", "an accepted annealing candidate never becomes the guide", SWARMS, None),
    ("optim/_sedsabso.py",
     "return jnp.clip(gx * (1.0 + self.perturbation_scale * r), lower, upper)",
     "return jnp.clip(gx * (1.0 + self.perturbation_scale * (r - 0.5)), lower, upper)",
     "Eq. 14 as P_g (1 + (r - 0.5))", SWARMS, None),
    ("optim/_sedsabso.py", "ok = metropolis_accept(u[j], fc[j], guide_f, s.temperature)",
     "ok = metropolis_accept(u[j], fc[j], swarm_best(s)[1], s.temperature)",
     "Metropolis against the swarm's best, not the current guide", SWARMS, None),
    ("optim/_sedsabso.py", "swarm_better = gf < s.guide_f", "swarm_better = gf > s.guide_f",
     "the guide takes the swarm's best only when it is worse", SWARMS, None),
    ("optim/_sedsabso.py", "better = fc[i] < s.best_f", "better = fc[i] < jnp.inf",
     "the best ever is overwritten by the best candidate", SWARMS, None),
    ("optim/_bso.py", "        if not self.literal_sign:\n            direction = -direction\n",
     "", "the antenna step toward the worse antenna (the literal sign always)", SWARMS, None),
    ("optim/_bso.py", "d = self.delta / self.c", "d = self.delta * self.c",
     "antenna distance delta c instead of delta / c (Eq. 13)", SWARMS, None),
    ("optim/_bso.py",
     "        v = jnp.clip(v, -vmax, vmax)\n        return jnp.clip(s.x + self.lam",
     "        return jnp.clip(s.x + self.lam", "no velocity clamp in BSO", SWARMS, None),
    ("optim/_bso.py",
     "return jnp.clip(s.x + self.lam * v + (1.0 - self.lam) * xi, lower, upper)",
     "return s.x + self.lam * v + (1.0 - self.lam) * xi", "no box clip in BSO", SWARMS, None),
    ("optim/_bso.py", "absorb_positions(s, raw, 3,", "absorb_positions(s, raw, 2,",
     "BSO counts two evaluations per beetle, not three", SWARMS, None),
    ("optim/_ldwpso.py", "s.t / max(s.iterations - 1, 1)", "s.t / s.iterations",
     "LDWPSO's inertia never reaches w_end", SWARMS, None),
    ("optim/_ldwpso.py", "+ self.c2 * r2 * (s.guide_x - s.x)", "+ self.c2 * r1 * (s.guide_x - s.x)",
     "LDWPSO reuses r1 for the social term", SWARMS, None),
    ("optim/_population.py", "better = state.active & (f < state.pbest_f)",
     "better = f < state.pbest_f",
     "inactive slots keep updating their personal bests", SWARMS, None),
    ("optim/_population.py", "masked = jnp.where(state.active, pbest_f, jnp.inf)",
     "masked = pbest_f",
     "inactive slots can become the swarm's best", SWARMS, None),
    ("optim/_population.py",
     "    order = jnp.argsort(jnp.where(state.active, state.pbest_f, jnp.inf))\n    state = eqx",
     "    order = jnp.arange(state.pbest_f.shape[0])\n    state = eqx",
     "a shrinking phase keeps the first slots, not the best", SWARMS, None),
    ("optim/_fitness.py", "return jnp.where(jnp.isfinite(f), f, jnp.inf)", "return f",
     "NaN fitness is not mapped to +Inf", SWARMS, None),
    ("optim/_fitness.py", "return jnp.abs(R + a * G) - jnp.abs(R - a * G)",
     "return jnp.abs(R - a * G) - jnp.abs(R + a * G)",
     "Eq. 17's one-pass antenna difference with its sign flipped", SWARMS, None),
    ("optim/_swarm.py", "        if plan.drops.any():\n            state = when(",
     "        if False:\n            state = when(",
     "the population is never re-ranked when N(t) falls", SWARMS, None),
    ("optim/_random.py", "    key, sub = jax.random.split(key)\n    return key, sub",
     "    key, sub = jax.random.split(key)\n    return key, key",
     "every iteration draws from the same chain key", SWARMS, None),
    ("optim/_fitness.py", "return jnp.sum(jnp.abs(self.embed(X) - self.tau), -1)",
     "return jnp.sum(jnp.abs(self.embed(X) - self.tau[0]), -1)",
     "a population's Eq. 17 against the first torque only", KERNELS, None),
    ("optim/_random.py", "for r in ((13, 15, 26, 6), (17, 29, 16, 24))[i % 2]:",
     "for r in ((13, 15, 26, 6), (17, 29, 16, 25))[i % 2]:",
     "the written-out threefry hash with a wrong rotation", KERNELS, None),
    ("optim/_population.py", "(state.nonfinite_total, jnp.zeros(slots, jnp.int32))",
     "(state.n_nonfinite, jnp.zeros(slots, jnp.int32))",
     "non-finite evaluations counted per slot are lost when a phase shrinks", KERNELS,
     None),
    ("optim/_linear.py", "RANK_RTOL = 1e-10", "RANK_RTOL = 1e-4",
     "a loose rank tolerance", BASELINES, None),
    ("optim/_linear.py", "        scale = _scale(self.norms[self.perm])\n",
     "        scale = np.ones(d)\n", "minimum-norm solution on raw, not unit-norm, columns",
     BASELINES, None),
    ("optim/_linear.py", "    Rs = R / _scale(norms[perm])", "    Rs = R",
     "rank and conditioning judged on raw columns", BASELINES, None),
    ("optim/_box.py", "half = np.maximum(fraction * np.abs(centre), floor)",
     "half = fraction * np.abs(centre) + floor", "the box rule adds the floor", BASELINES,
     None),
    ("optim/_sedsabso.py",
     "candidates=self.candidates(swarm_best(s)[0], s.trial_r, lower,",
     "candidates=self.candidates(s.guide_x, s.trial_r, lower,",
     "the annealing candidates perturb the guide, not the swarm's best after the move",
     SWARMS, None),
    ("optim/_sedsabso.py", "trial_r=r, trial_u=u, candidates=jnp.zeros_like(r))",
     "trial_r=jnp.zeros_like(r), trial_u=u, candidates=jnp.zeros_like(r))",
     "the annealing round loses the iteration's draws of Eq. 14", SWARMS, None),
    ("optim/_driver.py", "        while len(self._calls) > self.size:",
     "        while False:", "the compile cache never drops a run", PATHS, None),
    ("optim/_fitness.py", "        check_arity(self.fn)\n", "",
     "a fitness of one argument is not refused before tracing", PATHS, None),
    ("optim/_driver.py", "lo = eqx.error_if(lo, jnp.any(~(lo < hi)),",
     "lo = eqx.error_if(lo, jnp.any(lo != lo),",
     "a traced box inside out runs silently", PATHS, None),
    ("optim/_driver.py", "out = multihost_utils.process_allgather(out, tiled=True)",
     "out = out", "across hosts each process keeps only its own devices' runs",
     ["tests/test_multihost.py"], None),
    ("optim/_driver.py", "lambda index: data[index])",
     "lambda index: data[index] + np.uint32(jax.process_index()))",
     "each host seeds its runs differently",
     ["tests/test_multihost.py"], None),
    ("identification/_validation/_splits.py", "test = tuple(speed[:, i] > self.predict_above",
     "test = tuple(speed[:, i] > self.fit_below", "speed splits predict from the wrong "
     "threshold", VALIDATIONS, None),
    ("identification/_estimators/_normal_equations.py",
     "floor[j] = max(float(self.s[j] - c @ c), 0.0)",
     "floor[j] = 0.0", "normal equations forget the residual the rows leave out (Gautier's "
     "weights)", VALIDATIONS, None),
    ("identification/_fit/_samples.py",
     "everything - NormalEquations.of(rows[out], whole.tau[out])",
     "everything - NormalEquations.of(rows[~out], whole.tau[~out])",
     "a subset's normal equations subtract the wrong rows", VALIDATIONS, None),
    ("identification/_estimators/_normal_equations.py", "            rows[:, norms == 0] = 0.0",
     "            pass", "rounding left in the columns a joint does not see (Gautier's "
     "column count)", VALIDATIONS, None),
    ("identification/_model/_offset.py", "share = jnp.full(batch + (R,), 1.0 / R)",
     "share = jnp.full(batch + (R,), 1.0)", "new motions get the sum of the recordings' "
     "offsets, not their mean", VALIDATIONS, None),
    ("identification/_estimators/_programme.py",
     "np.zeros(self.dim), 1.0,", "np.zeros(self.dim), 2.0,",
     "the conic solver set up on another instance than cvxpy's first solve (another "
     "equilibration: not cvxpy's numbers)", ["tests/test_physical_programme.py"], None),
    ("identification/_estimators/_physical.py",
     "    shape = programme(n, model.dim, n_extra, nonneg,",
     "    shape = programme(n, model.dim, n_extra, (),",
     "quadratic friction may turn negative in a physical fit", VALIDATIONS, None),
    ("identification/_default/_policy.py", "not physical[i], i))",
     "physical[i], i))", "the rule prefers the unconstrained fit at equal "
     "parameters", VALIDATIONS, None),
    ("identification/_default/_choice.py", "    return Pooled((interpolation, SpeedSplits()))",
     "    return SpeedSplits()", "the default chooses by the speed splits alone",
     ["tests/test_identify_cli.py"], None),
    ("identification/_recordings.py", "if max(rates) > (1 + RATE_TOLERANCE) * min(rates):",
     "if max(rates) > 2 * (1 + RATE_TOLERANCE) * min(rates):",
     "recordings at twice the rate of another accepted", VALIDATIONS, None),
    ("identification/_model/_term.py", "        u = jnp.sign(u)\n", "        u = -jnp.sign(u)\n",
     "the coupled motor's Coulomb column with its sign flipped", IDENTIFICATION, None),
    ("identification/_model/_friction.py", 'return tuple(f"{self.prefix}{j + 1}" for j',
     'return tuple(f"{self.prefix}{j}" for j', "a joint friction term's names numbered "
     "from 0", IDENTIFICATION, None),
    ("identification/_model/_order.py", "key=lambda t: rank.get(type(t), len(TERMS))))",
     "key=lambda t: -rank.get(type(t), len(TERMS))))", "the terms' columns in reverse order",
     IDENTIFICATION, None),
    ("identification/_estimators/_box_search.py",
     "(x - lower <= margin) | (upper - x <= margin)",
     "(x - lower <= margin) & (upper - x <= margin)", "a parameter on a face of the box "
     "counted only when it is on both", IDENTIFICATION, None),
    ("identification/_estimators/_box_search.py", '"at_bounds": {"count": len(faces),',
     '"at_bounds": {"count": len(faces) - 1,', "the count of parameters on the box's faces "
     "off by one", IDENTIFICATION, None),
    ("identification/_default/_choice.py", "if self.validation is None and self.candidates > 1:",
     "if self.validation is None and self.candidates > 2:", "no validation with two "
     "candidates accepted (the first fitted, unchosen)", ["tests/test_identify_cli.py"], None),
    ("compare/_cocodata.py", "BASE_EVALUATIONS = (1, 2, 5)", "BASE_EVALUATIONS = (1, 2, 4)",
     ".tdat lines at dim x {1, 2, 4} x 10^k evaluations", COCO_FORMAT, None),
    ("compare/_alignment.py", "worst = worst - 1e-12 if worst >= 2e-12 else worst / 2",
     "worst = worst", "run lengths without cocopp's 1e-12 lowering of a row's worst value",
     COCO_FORMAT, None),
    ("compare/_statistics.py", "return np.where(successes > 0, total / successes, np.inf)",
     "return np.where(successes > 0, total / len(rl), np.inf)",
     "aRT divided by all runs, not by the successful ones", COCO_FORMAT, None),
    ("compare/_bbob.py", "DEFAULT_INSTANCES = (1, 2, 3, 4, 5, *range(101, 111))",
     "DEFAULT_INSTANCES = (1, 2, 3, 4, 5, *range(101, 110))",
     "14 default BBOB instances, not a COCO year's 15", COCO_FORMAT, None),
    ("compare/_dask.py", "            yield futures[future], doc\n",
     "            yield futures[future], doc\n            yield futures[future], doc\n",
     "a task finished on a worker counted twice", CAMPAIGNS, None),
    ("compare/_dask.py", "self.client.submit(R.run_task, task, settings, key=key, pure=False)",
     "self.client.submit(R.run_task, task, __import__('dataclasses').replace(settings, seed="
     "settings.seed + 1), key=key, pure=False)", "the workers' runs seeded differently",
     CAMPAIGNS, None),
    ("compare/_campaign.py", "    todo = [t for t in tasks if docs[t] is None]",
     "    todo = list(tasks)", "a restarted campaign runs its finished tasks again",
     CAMPAIGNS, None),
    ("identification/_model/_friction.py", "jnp.exp(-(s.qd / self.per_joint(n)) ** 2) * s.coulomb",
     "jnp.exp(-(s.qd / self.per_joint(n))) * s.coulomb", "Stribeck's curve without the square",
     FRICTION, None),
    ("identification/_model/_load.py", "        load = jnp.abs(s.rigid_torque(point))\n",
     "        load = s.rigid_torque(point)\n",
     "friction growing with the signed, not the absolute, load", FRICTION, None),
    ("identification/_model/_torque_model.py",
     'friction = {c for p in ("FV", "FC") for c in self.base.joint_columns(p)',
     'friction = {c for p in ("FV",) for c in self.base.joint_columns(p)',
     "the load torque with the Coulomb friction columns in it", FRICTION, None),
    ("identification/_fit/_fit.py",
     "        change = _change(model, new, samples)\n        model = new\n",
     "        change = _change(model, new, samples)\n",
     "the load's fixed point never moves its load point", FRICTION, None),
    ("identification/_fit/_fit.py", "    return model.with_nonlinear(np.exp(searched.u)), {",
     "    return model, {", "the searched velocity scales never applied", FRICTION, None),
    ("identification/_fit/_uncertainty.py",
     "    return np.where(free | (norms == 0), np.inf, np.sqrt(var))",
     "    return np.sqrt(var)", "undetermined scales reported with a finite std", FRICTION, None),
    ("identification/_validation/_cross_validation.py",
     "these.split(test).predict(fitted.model, fitted.fit.x)",
     "these.split(test).predict(model, fitted.fit.x)", "a split predicted by the model "
     "as given, not as its fit left it (scales, load point)", FRICTION, None),
    ("identification/_model/_dahl.py", "z = s + (z - s) * jnp.exp(-jnp.abs(d) / q_c)",
     "z = s + (z - s) * jnp.exp(-(jnp.abs(d) + 1e-4) / q_c)",
     "the presliding state decays at rest", STATE, None),
    ("identification/_model/_dahl.py", "        start[1:] |= index[1:] != index[:-1]\n",
     "", "the presliding state carried over from one recording to the next", STATE, None),
    ("identification/_fit/_samples.py",
     "        root, mask = self.root, self.mask\n",
     "        root, mask = self, None\n",
     "a split's presliding state integrated on the split alone", STATE, None),
    ("identification/_fit/_samples.py",
     "mask[np.flatnonzero(self.mask)[inner]] = True",
     "mask[np.flatnonzero(inner)] = True", "a split of a split indexes the whole samples "
     "wrongly", STATE,
     None),
    ("identification/_model/_dahl.py", "        s = jnp.sign(d)\n",
     "        s = jnp.sign(d) * 0.9\n", "the presliding state saturates below 1", STATE, None),
    ("identification/_model/_regrouping.py",
     "    return np.flatnonzero(independent[model.base.rank:] | np.array(bodies, dtype=bool))",
     "    return np.flatnonzero(independent[model.base.rank:])",
     "a payload's columns the base spans dropped (undetermined parameters lost)", PAYLOAD,
     None),
    # the structure of issue 35: the compiled search, the search methods, the stages
    ("identification/_fit/_projection.py",
     "        return V * self.weights[joints] * self.mask[:, None]",
     "        return V * self.mask[:, None]", "the moved columns' rows not weighted", STATE,
     None),
    ("identification/_fit/_projection.py",
     "        return V * self.weights[joints] * self.mask[:, None]",
     "        return V * self.weights[joints]", "the search fits a split's left-out samples "
     "too (the moved columns unmasked)", STATE, None),
    ("identification/_fit/_projection.py",
     "    rows = tuple((j, tuple(int(c) for c in np.flatnonzero(on_row[j])))",
     "    rows = tuple((j, tuple(int(c) for c in np.flatnonzero(on_row[0])))",
     "every moved column crossed with the first joint's columns", STATE, None),
    ("identification/_search/_methods.py", "            elif lowest[single] < best - tol:",
     "            elif True:", "a sweep's best single move kept though it raises the loss",
     SEARCH, None),
    ("identification/_search/_methods.py", "            centre, half = u, half * 2 / (G - 1)",
     "            centre, half = u, half * 1 / (G - 1)",
     "the coordinate search's grid narrows past the minimum", SEARCH, None),
    ("identification/_fit/_fit.py",
     '    return samples.kept(("searched", weights.tobytes()),',
     '    return samples.kept(("searched",),',
     "a search kept for estimators that weigh the rows otherwise", STATE, None),
    ("identification/_fit/_fit.py", "    if model.waiting:\n",
     "    if False:\n", "load friction's first stage skipped (the prior's load kept)",
     FRICTION, None),
    ("identification/_payload/_term.py",
     "            on = np.isin(np.asarray(s.recording), np.asarray(self.carried, dtype=int))",
     "            on = ~np.isin(np.asarray(s.recording), np.asarray(self.carried, dtype=int))",
     "the payload on the unloaded recordings", PAYLOAD, None),
    ("identification/_estimators/_programme.py",
     "            np.ones(10 * nb), np.tile(-link[np.nonzero(link)], nb),",
     "            np.zeros(10 * nb), np.tile(-link[np.nonzero(link)], nb),",
     "a body term's parameters not tied to its pseudo-inertia (links constrained)",
     PAYLOAD, None),
    ("identification/_estimators/_conic.py",
     "np.linalg.eigvalsh(pseudo_inertia(p)).min() >= PSD_MARGIN for p in own",
     "True for p in own", "an inconsistent payload taken as consistent (links free, robot given, "
     "gains)",
     PAYLOAD, None),
    ("identification/_model/_load.py",
     "        rigid = model.rigid_values(np.asarray(values, dtype=float))",
     "        rigid = np.asarray(values, dtype=float)[:len(model.rigid_columns)]",
     "the load point read from the wrong columns", FRICTION, None),
    ("identification/_estimators/_estimator.py",
     "            if k + 1 < passes:", "            if k + 1 < 1:",
     "Gautier's weights made once whatever the passes", ["tests/test_identification.py"],
     None),
    ("identification/_validation/_kept_terms.py",
     "        fine = [i for i, cv in enumerate(tried) if not_worse(cv, chosen)]",
     "        fine = list(range(len(tried)))",
     "kept terms kept however much worse they validate", RESTS, None),
    ("identification/_validation/_kept_terms.py",
     "        return min(fine, key=lambda i: tried[i].score) if fine else None",
     "        return fine[0] if fine else None",
     "the first kept alternative, not the lowest-scoring", RESTS, None),
    ("identification/_validation/_selection.py",
     "    if kept is not None:\n        index = _with_kept(",
     "    if False:\n        index = _with_kept(",
     "the default's kept terms never tried", RESTS, None),
    ("identification/_validation/_rests.py",
     "        rms_new = np.sqrt(np.sum(shares_new * errors, axis=0))",
     "        rms_new = np.sqrt(np.sum(shares * errors, axis=0))",
     "the error weighed to the fitted recording's speeds, not the new motion's",
     RESTS, None),
    ("identification/_validation/_rests.py",
     "            if inside.sum() >= MIN_SAMPLES:", "            if inside.sum() >= 1:",
     "a band's error from a handful of samples", RESTS, None),
    ("identification/_validation/_rests.py",
     "    peak = peak_speed(qd)", "    peak = peak_speed(qd_new)",
     "rests counted against the new motion's peak speed", RESTS, None),
    ("identification/_metrics.py",
     "np.mean(values, axis=0) if key in _PER_JOINT else float(np.mean(values))",
     "np.average(values, axis=0, weights=[m.n_samples for m in metrics])",
     "held-out recordings averaged by their samples, not alike", HELD_OUT, None),
    ("identification/_default/_held_out.py",
     "        beyond = extrapolation(data, held, joint_names=joints)",
     "        held = named[0][1]\n        beyond = extrapolation(data, held, joint_names=joints)",
     "every held-out recording judged as the first", HELD_OUT, None),
    ("identification/_default/_held_out.py",
     "        at_rest = rests(data, held,", "        at_rest = rests(data, named[0][1],",
     "every held-out recording's error weighed to the first one's speeds", HELD_OUT, None),
    ("identification/_default/_select_and_identify.py",
     "    ident = identified(robot, recordings, estimator, model, limits,  # data checked "
     "above\n                       samples=samples)[0]",
     "    ident = identified(robot, [*recordings, *held.values()], estimator, model, "
     "limits)[0]", "the held-out recordings fitted too", HELD_OUT, None),
    ("identification/_default/_held_out.py",
     "labels = [f\"held_out[{k}]\" for k in range(len(held_out))]",
     "labels = [f\"held_out[{k + 1}]\" for k in range(len(held_out))]",
     "a bad held-out entry named by the wrong index", HELD_OUT, None),
    ("identification/_default/_held_out.py", "_warn(name if len(named) > 1 else None,",
     "_warn(None,", "several held-out recordings' warnings without their names", HELD_OUT,
     None),
    ("identification/_default/_held_out.py",
     "    return float(np.mean(predicted)) if len(predicted) == len(judged) else None",
     "    return float(predicted[0]) if len(predicted) == len(judged) else None",
     "the mean prediction the first recording's", HELD_OUT, None),
    ("cli/_identify.py", "        if any(os.path.realpath(path) == os.path.realpath(p)",
     "        if any(path == p", "a held-out file given twice under another spelling",
     HELD_OUT, None),
    ("identification/_search/_methods.py",
     "            at = np.argmax(f <= lowest[:, None] + tol, axis=1)  # the first within tol",
     "            at = np.argmin(f, axis=1)",
     "a grid's ties broken by the loss's last bits", SAME, None),
    ("identification/_search/_methods.py", "            better = lowest < best - tol",
     "            better = lowest < best", "a move kept for a gain within the rounding",
     SAME, None),
    ("identification/_search/_methods.py",
     "    newton: int = eqx.field(default=10, converter=as_int)",
     "    newton: int = eqx.field(default=0, converter=as_int)",
     "the search stops at the grid (no Newton's method)", SAME, None),
    ("identification/_search/_problem.py", "    near = 1e-9 * (upper - lower)",
     "    near = 0.0 * (upper - lower)", "a grid point an ulp inside a bound is not on it",
     SAME, None),
    ("identification/_search/_newton.py", "        if -0.5 * float(g @ d) <= FTOL * scale:",
     "        if -0.5 * float(g @ d) <= 0.0:", "Newton's method steps on the rounding",
     SAME, None),
    ("identification/_search/_newton.py", "        keep = np.abs(lam) > floor",
     "        keep = np.abs(lam) > 0", "Newton's method steps along directions the rounding "
     "makes", SAME, None),
    ("identification/_fit/_fit.py",
     "        model = dataclasses.replace(model, search=HELD)\n", "",
     "a fitted model searched again when fitted again", SAME, None),
    ("identification/_fit/_uncertainty.py",
     "    determined = log_std <= np.log(upper / lower)",
     "    determined = np.isfinite(log_std)",
     "a displacement the data cannot place reported with a standard deviation", SAME, None),
    ('identification/_data_checks.py',
     '    if samples * n < need:\n        names',
     '    if False:\n        names',
     'samples check removed', DEGENERATE, None),
    ('identification/_data_checks.py',
     '    if still.size == robot.n_joints:\n        raise',
     '    if False:\n        raise',
     'no-motion error removed', DEGENERATE, None),
    ('identification/_data_checks.py',
     '    if still.size and warn:',
     '    if False:',
     'still-joint warning removed', DEGENERATE, None),
    ('identification/_data_checks.py',
     '    if still_joints(robot, recordings).size:\n        return',
     '    if True:\n        return',
     'excitation check removed', DEGENERATE, None),
    ('identification/_data_checks.py',
     '(excess > POSITION_RANGES * span)',
     '(excess > 1e9 * span)',
     'positions check removed', DEGENERATE, None),
    ('identification/_data_checks.py',
     '(peak > LIMIT_FACTOR * qd_max)',
     '(peak > 1e9 * qd_max)',
     'speeds check removed', DEGENERATE, None),
    ('identification/_data_checks.py',
     'np.flatnonzero(ratio > LIMIT_FACTOR)',
     'np.flatnonzero(ratio > 1e9)',
     'torque error removed', DEGENERATE, None),
    ('identification/_data_checks.py',
     'np.flatnonzero(ratio > 1) if warn else ()',
     '()',
     'torque warning removed', DEGENERATE, None),
    ('identification/_data_checks.py',
     '            if same:\n',
     '            if False:\n',
     'identical recordings allowed', DEGENERATE, None),
    ('identification/_data_checks.py',
     '    bad = np.flatnonzero(~(np.isfinite(values) & (values > 0)))',
     '    bad = np.flatnonzero(values != values) * 0 + np.zeros(0, int)',
     'drive gains unchecked', DEGENERATE, None),
    ('identification/_data_checks.py',
     '        if rows < need:\n            raise',
     '        if False:\n            raise',
     'split check removed', DEGENERATE, None),
    ('identification/_model/_presliding.py',
     '            if not lo < largest <= hi:  # NaN too',
     '            if False:',
     'presliding range unchecked', DEGENERATE, None),
    ('measurements/_formats.py',
     'return next((d for d in CSV_DELIMITERS if d in header), ",")',
     'return ","',
     'semicolons not detected', DEGENERATE, None),
    ('measurements/_formats.py',
     '        stated = _UNIT.match(name)\n',
     '        stated = None\n',
     'units not read', DEGENERATE, None),
    ('cli/_checks.py',
     '    if len(rates) < 2 or max(rates)',
     '    if True or max(rates)',
     'rates unchecked by the command', DEGENERATE, None),
    ('cli/_common.py',
     '            fd, probe = tempfile.mkstemp(dir=existing, prefix=".sedsabso-jax-check.")\n            os.close(fd)\n            os.unlink(probe)',
     "            if not os.access(existing, os.W_OK):\n                raise OSError(13, 'Permission denied')",
     'outputs checked by permissions only', DEGENERATE, None),
    ('_output.py',
     '    if err.errno is None:\n        return err',
     '    if True:\n        return err',
     "temporary file's name in the error", DEGENERATE, None),
    ('cli/_checks.py',
     '    from ..identification._estimators._estimator import Estimator\n\n',
     '    from ..identification._estimators._estimator import Estimator\n    return\n',
     'contradictions allowed', DEGENERATE, None),
    ('cli/_checks.py',
     '    given = [(flag, path) for flag, path in outputs.items() if path is not None]',
     '    given = []',
     'outputs may overwrite inputs', DEGENERATE, None),
    ('identification/_data_checks.py',
     '    return bool(getattr(estimator, "prior_strength", 0.0) or',
     '    return False and bool(getattr(estimator, "prior_strength", 0.0) or',
     'a prior does not soften the excitation error', DEGENERATE, None),
    ('identification/_gains/_result.py',
     '        if self.motor_side or len(self.joint_names) != n:',
     '        if True:',
     'gains labelled 1..n', DEGENERATE, None),
    ("cli/_main.py", "    parser = build_parser()\n    args = config.parse_args(",
     "    import jax  # noqa: F401\n    parser = build_parser()\n    args = config.parse_args(",
     "the command imports JAX before it parses", STARTUP, None),
    ("cli/_main.py",
     "        check_files(args)  # before JAX is imported: a missing file is said at once\n",
     "", "files checked only once the command runs, after JAX", STARTUP, None),
    ("cli/_identify.py", "    from ._vocabulary import ESTIMATORS, FRICTION_CANDIDATES, "
     "FRICTION_TERMS, PRIOR_STRENGTHS\n",
     "    from ._vocabulary import ESTIMATORS, FRICTION_CANDIDATES, PRIOR_STRENGTHS\n"
     "    from ..identification._model._order import FRICTION_TERMS\n",
     "identify's help reads a word from the library (which imports JAX)", STARTUP, None),
    ("__init__.py", "from ._version import __version__ as __version__\n",
     "from ._version import __version__ as __version__\nfrom . import optim as optim\n",
     "the package root imports a namespace eagerly", STARTUP, None),
    ("cli/_vocabulary.py", '"SEDSABSO", "BSO", "LDWPSO")', '"SEDSABSO", "BSO")',
     "a word the library takes missing from the command's", STARTUP, None),
    ("_lazy.py", "found[name] = ((where + alias.name, None) if line.module is None\n"
     "                               else (where, alias.name))",
     "found[name] = (where, alias.name)",
     "a lazy namespace reads `from . import a` as a name of the package", STARTUP, None),
    ("dynamics/_urdf.py", "    if _PARSER not in sys.modules:",
     "    import pytorch_kinematics  # noqa: F401\n    if _PARSER not in sys.modules:",
     "reading a URDF imports torch", STARTUP, None),
    ("identification/_work.py", "    if k:\n        seconds += (SEARCH",
     "    if False:\n        seconds += (SEARCH",
     "a fit that searches weighs as a least-squares fit in the progress", USABILITY, None),
    ("identification/_default/_select_and_identify.py",
     '    fits.step("fit on all the data", final, evaluation)',
     '    fits.step("fit on all the data", 0.0, evaluation)',
     "the fit on all the data not counted in the progress", USABILITY, None),
    ("cli/_common.py", "        start, done0 = self.first\n",
     "        start, done0 = self.start, 0.0\n",
     "the progress's pace counts what came before the first step", USABILITY, None),
    ("cli/_main.py", "then=write_seconds(settings), every=0)",
     "then=write_seconds(settings), every=1.0)",
     "reproduce writes no line but its last off a terminal", REPRODUCE, None),
    # issue 43: what a model computes once is keyed by its structure and values
    ("identification/_model/_torque_model.py",
     "    return (treedef, tuple(_leaf_key(x) for x in leaves))",
     "    return (treedef, ())", "a model's structure by its tree alone, not its values: a "
     "term's field that settings() omit reuses another model's columns",
     ["tests/test_term_keys.py"], None),
    # issue 44: the identified model written for MuJoCo
    ("dynamics/_mjcf_writer.py", "(w, np.cross(w, v)) if revolute",
     "(w, np.zeros(3)) if revolute", "an MJCF joint turns about the link origin, not its "
     "axis (standard DH)", ["tests/test_mjcf_writer.py"], None),
    ("dynamics/_mjcf_writer.py", "FRICTION_SOLIMP = (0.999, 0.999, 0.001)",
     "FRICTION_SOLIMP = (0.9, 0.95, 0.001)", "MuJoCo's default impedance for the dry "
     "friction: much of the Coulomb friction lost", ["tests/test_mjcf_writer.py"], None),
    ("identification/_model/_offset.py", "InSimulator(offset=np.asarray(values, float)",
     "InSimulator(offset=-np.asarray(values, float)", "the torque offset's sign in the "
     "actuators' bias", ["tests/test_mjcf_writer.py"], None),
    ("dynamics/_forward.py", "cho_factor(M + jnp.diag(armature), lower=True)",
     "cho_factor(M, lower=True)", "the armature left out of forward dynamics",
     ["tests/test_forward_dynamics.py"], None),
    ("dynamics/_forward.py", "jnp.swapaxes(tau, 0, 1))",
     "jnp.roll(jnp.swapaxes(tau, 0, 1), 1, 0))", "a rollout holds each torque one step "
     "late", ["tests/test_forward_dynamics.py"], None),
    ("dynamics/_forward.py", "jnp.asarray(tau[idx[:, :-1]])",
     "jnp.asarray(tau[idx[:, 1:]])", "a window's torques taken one sample late",
     ["tests/test_forward_dynamics.py"], None),
    ("dynamics/_mjcf_update.py", "            if body is below:\n                continue\n",
     "            if True:\n                continue\n", "the bodies merged into an "
     "identified link keep their own inertia in the user's MJCF",
     ["tests/test_mjcf_update.py"], None),
    ("identification/_estimators/_programme.py",
     "return [J[1, 1] + J[2, 2], J[0, 0] + J[2, 2],",
     "return [J[1, 1] + J[2, 2], J[0, 0] + J[1, 1],",
     "Iyy from the wrong diagonal of a pseudo-inertia (the physical fit's and the "
     "refinement's map)", ["tests/test_output_error.py"], None),
    ("identification/_fit/_output_error.py", "r = (sim - measured)[:, 1:]",
     "r = (sim - jnp.roll(measured, 1, 1))[:, 1:]", "the refinement compares each "
     "simulated position with the measured one a sample earlier",
     ["tests/test_output_error.py"], None),
    ("identification/_fit/_projection.py", "            derivative[:, j, c] = d_coulomb[:, j]\n",
     "            pass\n", "the Coulomb columns a searched Coulomb shape moves taken as "
     "unmoved by the search", STATE, None),
    ("identification/_fit/_projection.py", "    return ~moved & model.kept\n",
     "    return ~moved\n", "the columns the base regressor spans kept among the search's "
     "fixed columns (a singular Gram matrix inverted)", STATE, None),
    ("identification/_fit/_delay.py", "            vertex += 0.5 * (down - up) / curvature\n",
     "            pass\n", "the delay rounded to whole samples (no parabola's vertex)",
     ["tests/test_delay.py"], None),
    ("identification/_fit/_delay.py", "        b = (samples.tau[rows + k] * w).reshape(-1)\n",
     "        b = (samples.tau[rows - k] * w).reshape(-1)\n", "the delay's sign turned",
     ["tests/test_delay.py"], None),
    ("identification/_default/_signals.py",
     "    chosen = incumbent if DEFAULT.not_worse(scores[incumbent], best) else "
     "scores.index(best)\n",
     "    chosen = incumbent\n", "the signal chain as loaded, whatever the validation says",
     CHAIN, None),
    ("identification/_default/_signals.py",
     "        return [r.with_chain(chain, trim_s=trim, given=False)",
     "        return [r.with_chain(chain, trim_s=None, given=False)",
     "each signal chain validated on the samples it keeps (not on the same ones)", CHAIN,
     None),
    ("identification/_default/_select_and_identify.py",
     "            held = {k: r.with_chain(signals.chain, given=False)\n",
     "            held = {k: r.with_chain(chains[0], given=False)\n",
     "the held-out recordings made by the loaded chain, not the chosen one", CHAIN, None),
    ("measurements/_chain.py", "        return Recorded(self.times, self.q @ motion - offset, "
     "self.tau @ torque,", "        return Recorded(self.times, self.q @ motion - offset, "
     "self.tau,", "the recorded torques left on the motor side", CHAIN, None),
    ("measurements/_container.py", "        keep = np.isin(made.times, self.times)\n",
     "        keep = np.ones(made.n_samples, bool)\n",
     "a part of a recording made again as the whole", CHAIN, None),
    ("identification/_search/_newton.py", "        if not np.isfinite(f).all():",
     "        if False:", "Newton's polish on a stencil with losses it cannot evaluate",
     SEARCH, None),
    ("measurements/_chain.py", "                times - self.delay_s) for x in (q, qd, qdd))",
     "                times + self.delay_s) for x in (q, qd, qdd))",
     "the chain's delay moving the motion the wrong way", CHAIN, None),
    ("identification/_default/_signals.py",
     "                seconds = delay_of(samples, model, rate, m, limits, train).seconds\n",
     "                seconds = delay_of(samples, model, rate, m, limits).seconds\n",
     "each split's delay searched on all the samples (its test torques read)", CHAIN, None),
    ("identification/_fit/_delay.py", "        inside &= usable[j]\n", "",
     "the delay search reading samples outside its training mask", CHAIN, None),
    ("identification/_fit/_delay.py",
     "    usable = np.ones(n_samples, bool) if train is None else np.asarray(train, bool)",
     "    usable = inside if train is None else np.asarray(train, bool)",
     "the delay search's mask eroding itself (samples dropped at the ends)",
     ["tests/test_delay.py"], None),
    ("identification/_default/_signals.py", "            if a[keep].any() and b[keep].any()]",
     "            if True]", "chains compared on splits left with nothing to predict",
     CHAIN, None),
    ("identification/_default/_signals.py",
     "            kept, index = not DEFAULT.not_worse(cv, tried[-1][2]), len(tried) - 1\n",
     "            kept, index = True, len(tried) - 1\n",
     "the delay kept whatever the validation says", CHAIN, None),
    ("identification/_default/_select_and_identify.py",
     "                       samples=samples)[0]", "                       samples=None)[0]",
     "the fit on all the data searching again what the chain's fit searched", CHAIN, None),
    ("identification/_fit/_samples.py",
     "        if last is None or last[0] != model.structure:",
     "        if last is None:", "a split predicting with the rows of the model it read last",
     VALIDATIONS, None),
    ("identification/_estimators/_programme.py",
     "return _programme(threading.get_ident(), n_joints",
     "return _programme(0, n_joints", "one conic solver shared by the threads that fit "
     "a validation's splits at once", VALIDATIONS, None),
    ("identification/_default/_signals.py",
     "    if searches and searches[0][1].at_bound and derived is not None:",
     "    if False:", "no delay searched on derived signals where the loaded ones' lay at "
     "the bound", CHAIN, None),
    ("identification/_search/_problem.py", "COMPILED = threading.RLock()",
     "import contextlib\nCOMPILED = contextlib.nullcontext()",
     "populations evaluated on threads at once (jaxlib's batched Cholesky then waits on "
     "itself)", ["tests/test_validations.py"], None),
    ("identification/_estimators/_conic.py",
     "            constraints.append(own[list(np.flatnonzero(body.index < 0))]\n"
     "                               == body.known[body.index < 0])",
     "            pass", "the gains' physical payload free of its given mass",
     ["tests/test_drive_gains.py"], None),
    ("identification/_estimators/_conic.py",
     "        out[placed] = z[self.index[placed]] / self.weight[placed]",
     "        out[placed] = z[self.index[placed]]",
     "a placed body's parameters read in the unknowns' scale", [*PAYLOAD,
                                                               "tests/test_drive_gains.py"],
     None),
    ("identification/_payload/_least_squares.py",
     "        xs, report = statement(M.shape[0], M.shape[1], nonneg, bodies).solve(",
     "        xs, report = statement(M.shape[0], M.shape[1], nonneg, bodies).set_up().solve(",
     "a payload's or the gains' one conic fit equilibrated on a trivial instance, not its "
     "own data", [*PAYLOAD, "tests/test_drive_gains.py"], None),
    ("identification/_estimators/_conic.py",
     "return _shared(threading.get_ident(), dim", "return _shared(0, dim",
     "the terms-only fit's statement shared by the threads that fit a validation's splits",
     ["tests/test_physical_programme.py"], None),
    ("dynamics/_regressor.py",
     "        padded = padded_samples(samples, chunk or 1)",
     "        padded = samples",
     "the regressor compiled for each length of recording",
     ["tests/test_batching.py"], None),
    ("dynamics/_regressor.py", "    return Y[:math.prod(batch), :, np.asarray(columns)]",
     "    return Y[-math.prod(batch):, :, np.asarray(columns)]",
     "the padded regressor's rows taken from its end", ["tests/test_batching.py"], None),
    ("dynamics/_regressor.py", "    step = 1 << max(0, samples.bit_length() - 4)",
     "    step = 1 << max(0, samples.bit_length() - 2)",
     "two padded lengths per doubling (up to half again the samples)",
     ["tests/test_batching.py"], None),
    ("identification/_fit/_projection.py",
     "    read = tuple((i, field) for i in terms for field in model.terms[i].read_fields",
     "    read = tuple((i, field) for i in () for field in model.terms[i].read_fields",
     "what a term reads of a fit baked into its search's compiled code (one compilation "
     "per split)", ["tests/test_friction_state.py"], None),
    ("identification/_fit/_projection.py",
     "            terms[i] = eqx.tree_at(lambda t: getattr(t, field), terms[i], value,",
     "            terms[i] = eqx.tree_at(lambda t: getattr(t, field), terms[i], None,",
     "a search's trials without what the terms read of a fit", ["tests/test_friction_state.py"],
     None),
    ("dynamics/_regressor.py",
     "    return -(-(-(-samples // step) * step) // multiple) * multiple",
     "    return -(-samples // step) * step",
     "padded lengths not a multiple of the chunk (a second body compiled for the remainder)",
     ["tests/test_batching.py"], None),
    ("identification/_search/_problem.py", "SMALLEST = 2", "SMALLEST = 1",
     "a single trial compiled apart from a pair", ["tests/test_friction_state.py"], None),
    ("cli/_common.py", "* max(total - done, 0.0) + self.then", "* (self.total - done)",
     "the writing after the fits paced as the fits (a warm cache made it a quarter)",
     ["tests/test_cli_usability.py"], None),
    ("identification/_work.py",
     "    searched = model.search is None or model.search.searches  # not held where they are",
     "    searched = True", "a fit with its searched values held estimated as a search",
     ["tests/test_cli_usability.py"], None),
]


def run(index: int, bug, python: str, keep: bool) -> tuple[str, float]:
    module, text, replacement, what, tests, equivalent = bug
    scratch = Path(tempfile.mkdtemp(prefix=f"planted-{index}-"))
    try:
        shutil.copytree(ROOT / "sedsabso_jax", scratch / "sedsabso_jax")
        shutil.copytree(ROOT / "tests", scratch / "tests")
        for shared in ("benchmarks", "data"):  # some tests read a benchmark's plant
            shutil.copytree(ROOT / shared, scratch / shared)
        shutil.copy(ROOT / "pyproject.toml", scratch / "pyproject.toml")
        target = scratch / "sedsabso_jax" / module
        source = target.read_text()
        if source.count(text) != 1:
            return f"NOT APPLIED (the text occurs {source.count(text)} times)", 0.0
        target.write_text(source.replace(text, replacement))
        env = dict(os.environ, PYTHONPATH=str(scratch))  # before the installed package
        t0 = time.perf_counter()
        proc = subprocess.run([python, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider",
                               *tests], cwd=scratch, env=env, capture_output=True, text=True)
        seconds = time.perf_counter() - t0
        if "sedsabso_jax" not in proc.stdout + proc.stderr and proc.returncode not in (0, 1):
            return f"ERROR (pytest exit {proc.returncode})", seconds
        if proc.returncode == 0:
            return "survived" + (f" (equivalent: {equivalent})" if equivalent else ""), seconds
        failed = [line.split(" ")[1] for line in proc.stdout.splitlines()
                  if line.startswith("FAILED")]
        return f"killed by {failed[0] if failed else 'an error'}", seconds
    finally:
        if not keep:
            shutil.rmtree(scratch, ignore_errors=True)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", type=int, nargs="*", help="bug numbers (1-based)")
    ap.add_argument("--list", action="store_true", help="list the bugs and exit")
    ap.add_argument("--keep", action="store_true", help="keep the scratch copies")
    args = ap.parse_args(argv)
    chosen = args.only or range(1, len(BUGS) + 1)
    if args.list:
        for i in chosen:
            print(f"{i:2d}. sedsabso_jax/{BUGS[i - 1][0]}: {BUGS[i - 1][3]}")
        return 0
    print("| # | planted bug | module | result | seconds |")
    print("|---|---|---|---|---|")
    survivors = 0
    for i in chosen:
        bug = BUGS[i - 1]
        result, seconds = run(i, bug, sys.executable, args.keep)
        survivors += not result.startswith("killed") and "equivalent" not in result
        print(f"| {i} | {bug[3]} | `{bug[0]}` | {result} | {seconds:.0f} |", flush=True)
    return 1 if survivors else 0


if __name__ == "__main__":
    sys.exit(main())
