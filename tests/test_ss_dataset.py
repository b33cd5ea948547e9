"""SS skill from the default dataset (tool 1's demonstrations, segmented): Fig. 9's switch."""

from __future__ import annotations

import numpy as np
import pytest

from tooltransfer.planner.learning.switch_dataset import dataset_switches, default_dataset
from tooltransfer.planner.planning.ss import SwitchTask, learn_switch_skill, optimize, recombine
from tooltransfer.tools.library import load_tool


@pytest.fixture(scope="module")
def demos():
    return dataset_switches(default_dataset(), ("upper", "left"))


def test_upper_to_left_switches_are_found_and_reproduced(demos) -> None:
    assert len(demos) >= 8
    skill = learn_switch_skill(demos, virtual="arch", tool="finger")
    tool = load_tool("finger")
    rms = []
    for d in demos:
        task = SwitchTask(tool, "upper", "left", d.centre, duration=d.duration)
        path = recombine(skill, task, n_samples=d.t.size)
        assert path.ok
        rms.append(float(np.sqrt(np.mean(np.sum((path.xy - d.xy) ** 2, axis=1)))))
        assert path.object_penetration < 1e-6
    print(f"dmp vs demonstrated switch: RMS median {1e3 * np.median(rms):.2f} mm, max {1e3 * max(rms):.2f} mm")
    assert max(rms) < 4e-3
    opt = optimize(skill, SwitchTask(tool, "upper", "left", demos[0].centre))
    assert opt.ok and opt.max_penetration <= 5e-6
