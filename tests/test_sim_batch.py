"""Many executions at once (:func:`tooltransfer.tools.sim.execute_many`, a rollout on a thread pool): each equals
the sequential execution on :class:`SimPlatform` bit for bit, whatever the number of threads and
the jobs' lengths."""

from __future__ import annotations

import numpy as np
import pytest

from tooltransfer.errors import InputError
from tooltransfer.tools import contact_on_platform, load_tool
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.sim import Job, Rates, SimPlatform, execute_many


def _jobs(plat: OmniPlatform) -> list[Job]:
    tool = load_tool("finger")
    jobs = []
    for dx, dur in ((-0.01, 1.5), (0.0, 1.0), (0.01, 1.2)):
        obj = np.array([dx, 0.15])
        pose = contact_on_platform(tool, "upper", obj, np.pi / 2, plat).contact.pose
        t = np.linspace(0.0, dur, 151)
        xy = np.array([pose.x, pose.y - 0.005]) + (t / dur)[:, None] * np.array([0.0, 0.02])
        jobs.append(Job.from_tool_path(plat, obj, t, xy))
    return jobs


def test_a_batch_equals_the_sequential_executions() -> None:
    tool = load_tool("finger")
    plat = OmniPlatform(a_t=tool.a_t)
    jobs = _jobs(plat)
    rates = Rates(object_hz=30.0, tool_hz=100.0)
    batch = execute_many(tool, jobs, platform=plat, rates=rates, threads=2)
    single = execute_many(tool, jobs, platform=plat, rates=rates, threads=1)
    sim = SimPlatform(tool, plat)
    for job, a, b in zip(jobs, batch, single, strict=True):
        sim.reset(job.object_xy, q0=job.q[0])
        s = sim.execute(job.t, job.q, rates=rates)
        for name in ("t_object", "object_xy", "t_tool", "tool_pose", "joints", "contact", "penetration"):
            assert np.array_equal(getattr(a, name), getattr(s, name)), name
            assert np.array_equal(getattr(b, name), getattr(s, name)), name
        assert a.contacts == s.contacts
        assert a.t_tool[-1] == pytest.approx(job.t[-1] - 0.01)
    assert batch[1].object_xy[-1, 1] > 0.153 and batch[1].contacts  # the puck was pushed


def test_a_bad_job_is_refused_naming_it() -> None:
    tool = load_tool("finger")
    plat = OmniPlatform(a_t=tool.a_t)
    jobs = _jobs(plat)
    bad = Job(jobs[1].object_xy, jobs[1].t, jobs[1].q[:, :2])
    with pytest.raises(InputError) as err:
        execute_many(tool, [jobs[0], bad], platform=plat)
    assert err.value.field == "jobs[1].q"
    assert execute_many(tool, [], platform=plat) == []
