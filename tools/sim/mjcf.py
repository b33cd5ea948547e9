"""The simulated platform's MuJoCo model, written as MJCF from the DH table, the tool and the scene.

Kinematics. Each DH row ``Rz(theta) Tz(d) Tx(a) Rx(alpha)`` becomes a body whose hinge turns
about its local z (the joint), with the next body at ``(a, 0, d)`` turned by ``Rx(alpha)``; the
tool centre point is the origin of the tool-row body, exactly as :mod:`tools.omni.dh`.

The tool. The Omni's last three joints are fixed, so the tool turns in the table plane with q1
only (DESIGN section 7): a planar tool stays flat on the table while the shoulder and the elbow
move. The tool body hangs from the tool centre point on two hinges about the arm-plane normal
held by joint equalities at ``-q2`` and ``-q3`` (a parallelogram, as the real holder keeps the tool
level), so its orientation is ``Rz(base_yaw + q1 - pi/2)`` whatever the arm's pitch. Its outline's
convex pieces are extruded into prisms from 1 to 11 mm above the table (the puck is 10 mm high);
it never touches the table.

Contact settings measured to matter with MuJoCo 4.0 on exactly this push (the issue's figures):
``multiccd`` disabled (on, edge contacts got a wrong normal: 22 mm final error and 5 mm
penetration), elliptic friction cones (pyramidal let the puck slide off the tool: 103 mm error),
contact damping ratio 1 with a 5 ms time constant (0.3 gave 30 mm error), a 1 ms step,
``implicitfast`` integration, the Newton solver, and ``priority`` on the table and tool geoms so
their friction is the one used against the puck.

The arm: gravity compensation on every moving body, and a position plus a velocity actuator per
joint (PD tracking of a joint reference, as the real device after dynamics compensation).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from numpy.typing import NDArray

from tools.model import Tool
from tools.objects import OBJECT_RADIUS, Disc, Obstacle
from tools.omni.dh import D1, D_TOOL, L1, L2, THETA_TOOL
from tools.omni.platform import OmniPlatform

TOOL_BOTTOM, TOOL_TOP = 0.001, 0.011
"""Height [m] of the tool's prisms above the table."""
PUCK_HALF_HEIGHT = 0.005


@dataclass(frozen=True)
class SimParams:
    """Physical parameters of the simulated platform (SI units).

    Attributes:
        timestep: physics step [s]; puck_mass [kg]; puck_friction: sliding friction of the puck on
        the table; tool_friction: between tool and puck; kp [N m/rad], kv [N m s/rad]: joint PD
        gains; contact_timeconst [s].
    """

    timestep: float = 0.001
    puck_mass: float = 0.02
    puck_friction: float = 0.3
    tool_friction: float = 0.8
    kp: float = 40.0
    kv: float = 0.8
    contact_timeconst: float = 0.005


def _quat_x(angle: float) -> str:
    return f"{np.cos(angle / 2):.17g} {np.sin(angle / 2):.17g} 0 0"


def _mat_to_quat(m: NDArray[np.float64]) -> NDArray[np.float64]:
    """Unit quaternion (w, x, y, z) of a rotation matrix (3, 3)."""
    w = np.sqrt(max(0.0, 1.0 + m[0, 0] + m[1, 1] + m[2, 2])) / 2
    x = np.copysign(np.sqrt(max(0.0, 1.0 + m[0, 0] - m[1, 1] - m[2, 2])) / 2, m[2, 1] - m[1, 2])
    y = np.copysign(np.sqrt(max(0.0, 1.0 - m[0, 0] + m[1, 1] - m[2, 2])) / 2, m[0, 2] - m[2, 0])
    z = np.copysign(np.sqrt(max(0.0, 1.0 - m[0, 0] - m[1, 1] + m[2, 2])) / 2, m[1, 0] - m[0, 1])
    q = np.array([w, x, y, z])
    return q / np.linalg.norm(q)


def _rz(a: float) -> NDArray[np.float64]:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rx(a: float) -> NDArray[np.float64]:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _prism(name: str, ring: NDArray[np.float64]) -> str:
    pts = [(x, y, z) for z in (TOOL_BOTTOM, TOOL_TOP) for x, y in ring]
    return f'<mesh name="{name}" vertex="{" ".join(f"{v:.9g}" for p in pts for v in p)}"/>'


def build_mjcf(
    tool: Tool, platform: OmniPlatform, obstacles: Sequence[Obstacle] = (), params: SimParams | None = None
) -> str:
    """The MJCF text of the platform carrying ``tool`` with the puck and ``obstacles``."""
    p = params or SimParams()
    # the planar tool frame in the tool-row body once the two level-keeping hinges have acted:
    # base-frame orientation Rz(q1) Rx(-pi/2) Rz(theta_t) G must equal Rz(q1 - pi/2)
    g = (_rx(-np.pi / 2) @ _rz(THETA_TOOL)).T @ _rz(-np.pi / 2)
    gq = " ".join(f"{v:.17g}" for v in _mat_to_quat(g))
    pieces = [np.asarray(pc.exterior.coords)[:-1] for pc in tool.convex_pieces]
    assets = [_prism(f"tool_piece{i}", r) for i, r in enumerate(pieces)]
    tool_geoms = "\n".join(
        f'<geom name="tool_piece{i}" type="mesh" mesh="tool_piece{i}" priority="1" '
        f'friction="{p.tool_friction} 0.005 0.0001" rgba="0.3 0.5 0.8 1" mass="0.002"/>'
        for i in range(len(pieces))
    )
    obstacle_geoms = []
    for i, o in enumerate(obstacles):
        if isinstance(o, Disc):
            obstacle_geoms.append(
                f'<geom name="obstacle{i}" type="cylinder" size="{o.radius} {PUCK_HALF_HEIGHT * 2}" '
                f'pos="{o.centre[0]} {o.centre[1]} {PUCK_HALF_HEIGHT * 2}" rgba="0.8 0.3 0.3 1" priority="1"/>'
            )
        else:
            ring = np.asarray(shapely.geometry.polygon.orient(o, 1.0).exterior.coords)[:-1]
            pts = [(x, y, z) for z in (0.0, 4 * PUCK_HALF_HEIGHT) for x, y in ring]
            assets.append(f'<mesh name="obstacle{i}" vertex="{" ".join(f"{v:.9g}" for q in pts for v in q)}"/>')
            obstacle_geoms.append(f'<geom name="obstacle{i}" type="mesh" mesh="obstacle{i}" rgba="0.8 0.3 0.3 1" '
                                  'priority="1"/>')
    bx, by = platform.base_xy
    base_quat = f"{np.cos(platform.base_yaw / 2)} 0 0 {np.sin(platform.base_yaw / 2)}"
    link = 'contype="0" conaffinity="0" rgba="0.6 0.6 0.6 0.5"'
    inertia = 'mass="0.08" diaginertia="2e-4 2e-4 2e-4"'
    return f"""
<mujoco model="omni_{tool.name}">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{p.timestep}" integrator="implicitfast" solver="Newton" cone="elliptic" gravity="0 0 -9.81">
    <flag multiccd="disable"/>
  </option>
  <default>
    <geom solref="{p.contact_timeconst} 1" solimp="0.95 0.99 0.001"/>
    <joint armature="0.001" damping="0.01"/>
  </default>
  <asset>
    {chr(10).join(assets)}
  </asset>
  <worldbody>
    <geom name="table" type="plane" size="1 1 0.01" priority="1" friction="{p.puck_friction} 0.005 0.0001"
          rgba="0.9 0.9 0.85 1"/>
    {chr(10).join(obstacle_geoms)}
    <body name="puck" pos="0 0 {PUCK_HALF_HEIGHT + 1e-4}">
      <freejoint name="puck"/>
      <geom name="puck" type="cylinder" size="{OBJECT_RADIUS} {PUCK_HALF_HEIGHT}" mass="{p.puck_mass}"
            friction="{p.puck_friction} 0.005 0.0001" rgba="0.2 0.2 0.2 1"/>
    </body>
    <body name="base" pos="{bx} {by} {-platform.table_height}" quat="{base_quat}">
      <body name="link1" gravcomp="1">
        <joint name="q1" axis="0 0 1" range="{platform.limits.lower[0]} {platform.limits.upper[0]}"/>
        <inertial pos="0 0 0.05" {inertia}/>
        <geom type="capsule" fromto="0 0 0 0 0 {D1}" size="0.012" {link}/>
        <body name="link2" pos="0 0 {D1}" quat="{_quat_x(-np.pi / 2)}" gravcomp="1">
          <joint name="q2" axis="0 0 1"/>
          <inertial pos="{L1 / 2} 0 0" {inertia}/>
          <geom type="capsule" fromto="0 0 0 {L1} 0 0" size="0.008" {link}/>
          <body name="link3" pos="{L1} 0 0" gravcomp="1">
            <joint name="q3" axis="0 0 1"/>
            <inertial pos="{L2 / 2} 0 0" {inertia}/>
            <geom type="capsule" fromto="0 0 0 {L2} 0 0" size="0.006" {link}/>
            <body name="wrist" pos="{L2} 0 0" gravcomp="1">
              <inertial pos="0 0 0" mass="0.01" diaginertia="1e-6 1e-6 1e-6"/>
              <body name="tcp" quat="{np.cos(THETA_TOOL / 2)} 0 0 {np.sin(THETA_TOOL / 2)}" gravcomp="1">
                <inertial pos="0 0 0" mass="0.005" diaginertia="1e-6 1e-6 1e-6"/>
                <body name="tcp_row" pos="{platform.a_t} 0 {D_TOOL}" gravcomp="1">
                  <inertial pos="0 0 0" mass="0.005" diaginertia="1e-6 1e-6 1e-6"/>
                  <body name="level2" gravcomp="1">
                    <joint name="level2" axis="0 0 1"/>
                    <inertial pos="0 0 0" mass="0.005" diaginertia="1e-6 1e-6 1e-6"/>
                    <body name="tool" gravcomp="1">
                      <joint name="level3" axis="0 0 1"/>
                      <inertial pos="0 0 0" mass="0.01" diaginertia="1e-6 1e-6 1e-6"/>
                      <body name="tool_plane" quat="{gq}" gravcomp="1">
                        {tool_geoms}
                      </body>
                    </body>
                  </body>
                </body>
              </body>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
  <equality>
    <joint joint1="level2" joint2="q2" polycoef="0 -1 0 0 0" solref="0.002 1"/>
    <joint joint1="level3" joint2="q3" polycoef="0 -1 0 0 0" solref="0.002 1"/>
  </equality>
  <actuator>
    <position name="p1" joint="q1" kp="{p.kp}"/>
    <position name="p2" joint="q2" kp="{p.kp}"/>
    <position name="p3" joint="q3" kp="{p.kp}"/>
    <velocity name="v1" joint="q1" kv="{p.kv}"/>
    <velocity name="v2" joint="q2" kv="{p.kv}"/>
    <velocity name="v3" joint="q3" kv="{p.kv}"/>
  </actuator>
</mujoco>
"""
