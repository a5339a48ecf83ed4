"""Differential-drive kinematics: velocity and acceleration limits, and exact integration
of a unicycle over one time step.

Pure scalar functions on floats (the math module only): they run once per robot per
simulation step, where small numpy operations would cost more than the arithmetic.
"""

from __future__ import annotations

import math


def limit_velocity(
    v_cmd: float,
    w_cmd: float,
    v: float,
    w: float,
    dt: float,
    max_v: float,
    max_w: float,
    max_accel: float,
    max_ang_accel: float,
) -> tuple[float, float]:
    """The (v, w) actually reached after ``dt`` when commanding ``(v_cmd, w_cmd)`` from
    ``(v, w)``: clipped to the speed limits, then to what the accelerations allow."""
    v_cmd = max_v if v_cmd > max_v else (-max_v if v_cmd < -max_v else v_cmd)
    w_cmd = max_w if w_cmd > max_w else (-max_w if w_cmd < -max_w else w_cmd)
    dv = max_accel * dt
    dw = max_ang_accel * dt
    if v_cmd > v + dv:
        v_cmd = v + dv
    elif v_cmd < v - dv:
        v_cmd = v - dv
    if w_cmd > w + dw:
        w_cmd = w + dw
    elif w_cmd < w - dw:
        w_cmd = w - dw
    return v_cmd, w_cmd


def integrate(
    x: float, y: float, theta: float, v: float, w: float, dt: float
) -> tuple[float, float, float]:
    """Pose after driving at constant (v, w) for ``dt`` (exact arc, not Euler: a robot
    turning in place must not drift). ``theta`` is left unwrapped."""
    if -1e-9 < w < 1e-9:
        return x + v * dt * math.cos(theta), y + v * dt * math.sin(theta), theta
    theta1 = theta + w * dt
    r = v / w
    return (
        x + r * (math.sin(theta1) - math.sin(theta)),
        y - r * (math.cos(theta1) - math.cos(theta)),
        theta1,
    )


def wrap(angle: float) -> float:
    """Wrap an angle to [-pi, pi) cheaply (no trigonometry)."""
    return (angle + math.pi) % math.tau - math.pi
