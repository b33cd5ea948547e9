"""Plants that misbehave on purpose: wrappers injecting a real device's faults into any plant.

Each class wraps a :class:`tooltransfer.planner.execution.plant.Plant` and is one itself, so a
closed loop (or a driver's own test) can be run against a camera that freezes, drops frames or sees
outliers, an arm that tracks off its command or lags, a driver that raises, or a puck knocked by
something else. Faults are seeded (``seed``, ``numpy.random.default_rng``) and start after a count
of the plant's calls, so a run is repeatable. Every wrapper forwards ``true_object()`` and
``execution`` when the wrapped plant has them, counts the commands sent (``moves``) and the plant
time they took (``plant_time`` [s], the sum of each command's duration), records the plant time
its fault started at (``fault_time``, None before), and passes any other method on to the wrapped
plant (a driver's ``stop()``).

:data:`FAULTS` names one setting of each for the benchmark and the tests
(:func:`fault_plant`); the recoverable ones (:data:`RECOVERABLE`) are faults a closed loop should
still reach the target through.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError
from tooltransfer.planner.execution.health import obstacle_gap
from tooltransfer.planner.execution.plant import Plant
from tooltransfer.tools.objects import Disc, Obstacle

#: A bump's size [m] (:func:`bump_toward`).
BUMP = 0.014
#: The longest bump [m] toward an obstacle (:func:`bump_toward`).
BUMP_TOWARD_MAX = 0.05


class FaultPlant:
    """The wrapped ``plant`` unchanged; the subclasses override what misbehaves (module docstring)."""

    def __init__(self, plant: Plant, seed: int = 0) -> None:
        self.plant, self.rng = plant, np.random.default_rng(seed)
        self.moves, self.frames, self.plant_time = 0, 0, 0.0
        self.fault_time: float | None = None

    def _fault(self) -> None:
        if self.fault_time is None:
            self.fault_time = self.plant_time

    def observe_object(self) -> NDArray[np.float64]:
        self.frames += 1
        return self.frame(self.plant.observe_object())

    def frame(self, xy: NDArray[np.float64]) -> Any:
        """The camera frame the wrapper returns for the wrapped plant's ``xy``."""
        return xy

    def tool_pose(self) -> NDArray[np.float64]:
        return self.plant.tool_pose()

    def move_tool(self, t: NDArray[np.float64], tool_pose: NDArray[np.float64]) -> None:
        self.moves += 1
        self.command(np.asarray(t, dtype=float), np.asarray(tool_pose, dtype=float))
        self.plant_time += float(t[-1])

    def command(self, t: NDArray[np.float64], tool_pose: NDArray[np.float64]) -> None:
        """Send the command to the wrapped plant (as the arm executes it)."""
        self.plant.move_tool(t, tool_pose)

    @property
    def execution(self) -> object:
        return getattr(self.plant, "execution", None)

    def __getattr__(self, name: str) -> Any:
        """The wrapped plant's other methods (a driver's ``stop()``, ``displace_object``)."""
        if name.startswith("_") or name == "plant":
            raise AttributeError(name)
        return getattr(self.plant, name)


class FrozenCamera(FaultPlant):
    """After ``after_moves`` commands the camera returns its last frame again and again."""

    def __init__(self, plant: Plant, after_moves: int = 3, seed: int = 0) -> None:
        super().__init__(plant, seed)
        self.after = after_moves
        self.last: NDArray[np.float64] | None = None

    def frame(self, xy: NDArray[np.float64]) -> NDArray[np.float64]:
        if self.moves >= self.after and self.last is not None:
            self._fault()
            return self.last.copy()
        self.last = np.array(xy, dtype=float)
        return xy


class DroppedFrames(FaultPlant):
    """Frames the camera drops (NaN): the frames numbered in ``at`` (from 0), and each frame with
    probability ``rate``."""

    def __init__(self, plant: Plant, at: tuple[int, ...] = (), rate: float = 0.0, seed: int = 0) -> None:
        super().__init__(plant, seed)
        self.at, self.rate = set(at), rate

    def frame(self, xy: NDArray[np.float64]) -> NDArray[np.float64]:
        if self.frames - 1 in self.at or self.rng.random() < self.rate:
            self._fault()
            return np.full(2, np.nan)
        return xy


class OutlierFrames(FaultPlant):
    """Each frame with probability ``rate`` is off by ``size`` [m] in a random direction."""

    def __init__(self, plant: Plant, rate: float = 0.05, size: float = 0.05, seed: int = 0) -> None:
        super().__init__(plant, seed)
        self.rate, self.size = rate, size

    def frame(self, xy: NDArray[np.float64]) -> NDArray[np.float64]:
        if self.rng.random() < self.rate:
            self._fault()
            a = self.rng.uniform(0.0, 2.0 * np.pi)
            return xy + self.size * np.array([np.cos(a), np.sin(a)])
        return xy


class NoisyCamera(FaultPlant):
    """Every frame with extra normal noise of ``noise`` [m] per axis."""

    def __init__(self, plant: Plant, noise: float = 0.01, seed: int = 0) -> None:
        super().__init__(plant, seed)
        self.noise = noise

    def frame(self, xy: NDArray[np.float64]) -> NDArray[np.float64]:
        self._fault()
        return xy + self.rng.normal(0.0, self.noise, 2)


class TrackingOffset(FaultPlant):
    """The arm tracks every command ``offset`` (2,) [m] off (a bent tool, a calibration error; the
    offset grows in along the first command, as a tool slips in its grip); the encoders report where
    the tool is."""

    def __init__(self, plant: Plant, offset: ArrayLike = (0.003, 0.0), seed: int = 0) -> None:
        super().__init__(plant, seed)
        self.offset = np.asarray(offset, dtype=float)
        self.applied = np.zeros(2)

    def command(self, t: NDArray[np.float64], tool_pose: NDArray[np.float64]) -> None:
        self._fault()
        u = (t / t[-1])[:, None]
        shifted = tool_pose.copy()
        shifted[:, :2] += (1.0 - u) * self.applied + u * self.offset
        self.plant.move_tool(t, shifted)
        self.applied = self.offset


class TrackingLag(FaultPlant):
    """The arm follows every command ``lag`` [s] late and stops when the command's time is up, short
    of its end."""

    def __init__(self, plant: Plant, lag: float = 0.1, seed: int = 0) -> None:
        super().__init__(plant, seed)
        self.lag = lag

    def command(self, t: NDArray[np.float64], tool_pose: NDArray[np.float64]) -> None:
        self._fault()
        late = np.clip(t - self.lag, 0.0, None)
        self.plant.move_tool(t, np.column_stack([np.interp(late, t, tool_pose[:, j]) for j in range(3)]))


class DriverFault(FaultPlant):
    """The ``method`` (``"observe_object"``, ``"tool_pose"`` or ``"move_tool"``) misbehaves from its
    ``at``-th call (from 0) for ``times`` calls: raises ``error`` (an exception instance) or, with
    ``value`` given, returns it (a wrong shape, NaN)."""

    def __init__(self, plant: Plant, method: str = "move_tool", at: int = 0, times: int = 1,
                 error: Exception | None = None, value: object = None, seed: int = 0) -> None:
        super().__init__(plant, seed)
        if method not in ("observe_object", "tool_pose", "move_tool"):
            raise InputError("method", "observe_object, tool_pose or move_tool", method)
        self.method, self.at, self.times = method, at, times
        self.error, self.value, self.calls = error or RuntimeError("driver fault"), value, 0

    def _misbehaves(self, method: str) -> bool:
        if method != self.method:
            return False
        self.calls += 1
        if not self.at <= self.calls - 1 < self.at + self.times:
            return False
        self._fault()
        if self.value is None:
            raise self.error
        return True

    def observe_object(self) -> NDArray[np.float64]:
        if self._misbehaves("observe_object"):
            return self.value  # type: ignore[return-value]
        return super().observe_object()

    def tool_pose(self) -> NDArray[np.float64]:
        if self._misbehaves("tool_pose"):
            return self.value  # type: ignore[return-value]
        return super().tool_pose()

    def command(self, t: NDArray[np.float64], tool_pose: NDArray[np.float64]) -> None:
        if not self._misbehaves("move_tool"):
            self.plant.move_tool(t, tool_pose)


class Bump(FaultPlant):
    """After the ``at_move``-th command (from 0) the object is knocked by ``displacement`` (2,) [m],
    or by ``displacement(object_xy)`` for a function of where the object truly is then; the wrapped
    plant must offer ``displace_object(displacement)`` (the project's plants do)."""

    def __init__(self, plant: Plant, at_move: int = 4,
                 displacement: ArrayLike | Callable[[NDArray[np.float64]], NDArray[np.float64]] = (0.0, 0.014),
                 seed: int = 0) -> None:
        super().__init__(plant, seed)
        if not callable(getattr(plant, "displace_object", None)):
            raise InputError("plant", "a plant with displace_object(displacement)", type(plant).__name__)
        self.at, self.displacement = at_move, displacement

    def command(self, t: NDArray[np.float64], tool_pose: NDArray[np.float64]) -> None:
        self.plant.move_tool(t, tool_pose)
        if self.moves - 1 == self.at:
            self._fault()
            d = self.displacement
            d = d(self.plant.true_object()) if callable(d) else d  # type: ignore[attr-defined]
            self.plant.displace_object(np.asarray(d, dtype=float))  # type: ignore[attr-defined]


def bump_away(obstacles: Sequence[Obstacle], radius: float, target: ArrayLike,
              size: float = BUMP) -> Callable[[NDArray[np.float64]], NDArray[np.float64]]:
    """A :class:`Bump`'s displacement for an object of ``radius`` [m]: ``size`` [m] (at most half the
    way left) on along its way, toward the task's ``target`` (2,) [m] (not back into the tool that
    pushes it), turned by up to 60 degrees to land farthest from the obstacles."""
    goal = np.asarray(target, dtype=float)

    def displacement(xy: NDArray[np.float64]) -> NDArray[np.float64]:
        ahead = goal - xy
        a0 = float(np.arctan2(ahead[1], ahead[0]))
        n = min(size, 0.5 * float(np.hypot(*ahead)))
        best, best_gap = np.zeros(2), -np.inf
        for da in np.radians([0.0, 30.0, -30.0, 60.0, -60.0]):
            d = n * np.array([np.cos(a0 + da), np.sin(a0 + da)])
            gap = min(obstacle_gap(obstacles, xy + d, radius), 1.0)
            if gap > best_gap + 1e-9:
                best, best_gap = d, gap
        return best

    return displacement


def bump_toward(obstacles: Sequence[Obstacle], radius: float, margin: float,
                size: float = BUMP) -> Callable[[NDArray[np.float64]], NDArray[np.float64]]:
    """A :class:`Bump`'s displacement for an object of ``radius`` [m] toward the nearest obstacle, to
    half the ``margin`` [m] from it, at most :data:`BUMP_TOWARD_MAX` [m] (``size`` [m] along +y
    without obstacles)."""

    def displacement(xy: NDArray[np.float64]) -> NDArray[np.float64]:
        if not obstacles:
            return np.array([0.0, size])
        centres = [ob.centre if isinstance(ob, Disc) else np.array(ob.centroid.coords[0]) for ob in obstacles]
        gaps = [obstacle_gap((ob,), xy, radius) for ob in obstacles]
        j = int(np.argmin(gaps))
        u = (centres[j] - xy) / max(float(np.hypot(*(centres[j] - xy))), 1e-9)
        return min(BUMP_TOWARD_MAX, max(0.0, gaps[j] - 0.5 * margin)) * u

    return displacement


#: One setting of each fault, by name: the wrapper's class and its keyword arguments.
FAULTS: dict[str, tuple[type[FaultPlant], dict[str, Any]]] = {
    "frozen camera": (FrozenCamera, {"after_moves": 3}),
    "dropped frame": (DroppedFrames, {"at": (25,)}),
    "dropped frames 10%": (DroppedFrames, {"rate": 0.1}),
    "outliers 5%": (OutlierFrames, {"rate": 0.05, "size": 0.05}),
    "noise 10 mm": (NoisyCamera, {"noise": 0.01}),
    "tracking offset 3 mm": (TrackingOffset, {"offset": (0.003, 0.0)}),
    "tracking offset 8 mm": (TrackingOffset, {"offset": (0.0, 0.008)}),
    "tracking lag 0.1 s": (TrackingLag, {"lag": 0.1}),
    "camera raises once": (DriverFault, {"method": "observe_object", "at": 0, "times": 1}),
    "camera wrong shape": (DriverFault, {"method": "observe_object", "at": 0, "times": 10**9,
                                         "value": np.zeros(3)}),
    "encoder NaN": (DriverFault, {"method": "tool_pose", "at": 5, "times": 10**9,
                                  "value": np.full(3, np.nan)}),
    "driver raises": (DriverFault, {"method": "move_tool", "at": 3}),
    "bump away": (Bump, {"at_move": 4}),
    "bump toward obstacle": (Bump, {"at_move": 4}),
}
#: The faults a closed loop should still reach the target through.
RECOVERABLE = ("dropped frame", "outliers 5%", "noise 10 mm", "tracking offset 3 mm", "bump away")


def fault_plant(name: str, plant: Plant, seed: int = 0, obstacles: Sequence[Obstacle] = (), radius: float = 0.0,
                margin: float = 0.0, target: ArrayLike = (0.0, 0.0)) -> FaultPlant:
    """``plant`` wrapped in the fault ``name`` of :data:`FAULTS` (seed ``seed``); the bumps go on
    toward the task's ``target`` (2,) [m] away from ``obstacles`` (:func:`bump_away`), or toward the
    nearest obstacle (:func:`bump_toward`, the object's ``radius`` and the plan's ``margin`` [m])."""
    if name not in FAULTS:
        raise InputError("fault", f"one of {sorted(FAULTS)}", name)
    cls, kwargs = FAULTS[name]
    if cls is Bump:
        bump = bump_toward(obstacles, radius, margin) if "toward" in name else bump_away(obstacles, radius, target)
        kwargs = {**kwargs, "displacement": bump}
    return cls(plant, seed=seed, **kwargs)
