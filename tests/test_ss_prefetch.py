"""The switch NLP built in the background while the push plan is solved: the same NLP, the same plan."""

from __future__ import annotations

import numpy as np
import pytest

from tooltransfer.errors import InputError
from tooltransfer.planner.solve import solve
from tooltransfer.planner.ss import nlp as nlp_module
from tooltransfer.planner.ss.bodies import UNIT, all_bodies
from tooltransfer.planner.ss.cases import fig11_task
from tooltransfer.planner.ss.nlp import build_nlp, clear_cache, get_nlp, prefetch_nlp, wait_for_prefetch
from tooltransfer.problems.named import task_file
from tooltransfer.problems.task import load_task
from tooltransfer.tools.objects import Disc


def test_prefetched_nlp_is_used_once_built_and_equals_a_direct_build() -> None:
    clear_cache()
    task = fig11_task("fig11b")
    bodies = all_bodies(task.shape, (Disc(np.array([0.05, 0.17]), 0.01),))
    assert prefetch_nlp(task.tool, 9, task.omni, bodies, reach=False)
    assert not prefetch_nlp(task.tool, 11, task.omni, bodies, reach=False)  # one prefetch at a time
    got, built = get_nlp(task.tool, 9, task.omni, bodies, reach=False)
    assert built  # its first user reports the build (attempt records keep their build time)
    assert get_nlp(task.tool, 9, task.omni, bodies, reach=False) == (got, False)
    assert not prefetch_nlp(task.tool, 9, task.omni, bodies, reach=False)  # cached: nothing to do
    direct = build_nlp(task.tool, 9, task.omni, bodies, reach=False)
    rng = np.random.default_rng(0)
    x = (np.array([0.0, 0.16]) + rng.uniform(-0.03, 0.03, (9, 2))) / UNIT
    p = np.concatenate([x.ravel(), rng.uniform(0, 2, 18), *[b.data for b in bodies], [25.0]])
    z = np.concatenate([x.ravel(), rng.normal(size=direct.n_vars - x.size)])
    np.testing.assert_array_equal(np.asarray(got.rows(z, p)), np.asarray(direct.rows(z, p)))
    assert got.families == direct.families and got.n_params == direct.n_params
    clear_cache()


def test_invalid_prefetch_raises_in_the_caller() -> None:
    task = fig11_task("fig11b")
    with pytest.raises(InputError, match="n_knots"):
        prefetch_nlp(task.tool, 3, task.omni, all_bodies(task.shape, ()))
    wait_for_prefetch()
    assert not nlp_module._PREFETCH


def test_solve_plans_the_same_with_and_without_prefetch() -> None:
    task = load_task(task_file("paper/transfer_tool2"))
    clear_cache()
    with_prefetch = solve(task)
    assert not nlp_module._PREFETCH  # solve leaves no build running
    clear_cache()
    without = solve(task, prefetch=False)
    assert with_prefetch.status == without.status == "solved"
    np.testing.assert_array_equal(with_prefetch.tool_pose, without.tool_pose)
    np.testing.assert_array_equal(with_prefetch.object_xy, without.object_xy)


def test_a_guess_that_cannot_be_built_is_left_to_the_switch() -> None:
    from tooltransfer.planner.switches import prefetch_opt_nlp

    task = fig11_task("fig11b")
    assert not prefetch_opt_nlp(task.tool, task.omni, 0.0175, (), n_knots=3)  # too few knots: no prefetch, no raise
    assert not nlp_module._PREFETCH
