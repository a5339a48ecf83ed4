"""Kinematics: speed/acceleration limits and exact unicycle integration."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from mrcomm.robot.kinematics import integrate, limit_velocity, wrap

speeds = st.floats(-5.0, 5.0, allow_nan=False)


@given(speeds, speeds, st.floats(-0.5, 0.5), st.floats(-1.5, 1.5), st.floats(0.01, 0.5))
def test_limits_hold(v_cmd: float, w_cmd: float, v: float, w: float, dt: float) -> None:
    nv, nw = limit_velocity(v_cmd, w_cmd, v, w, dt, 0.5, 1.5, 1.0, 3.0)
    assert abs(nv) <= 0.5 + 1e-12
    assert abs(nw) <= 1.5 + 1e-12
    assert abs(nv - v) <= 1.0 * dt + 1e-12
    assert abs(nw - w) <= 3.0 * dt + 1e-12


def test_reachable_command_is_reached_exactly() -> None:
    assert limit_velocity(0.3, -0.2, 0.25, -0.1, 0.1, 0.5, 1.5, 1.0, 3.0) == (0.3, -0.2)


def test_turning_in_place_does_not_translate() -> None:
    x, y, th = integrate(1.0, 2.0, 0.3, 0.0, 1.5, 0.1)
    assert (x, y) == (1.0, 2.0)
    assert th == pytest.approx(0.45)


def test_straight_line() -> None:
    x, y, th = integrate(0.0, 0.0, math.pi / 2, 0.5, 0.0, 0.2)
    assert x == pytest.approx(0.0, abs=1e-12)
    assert y == pytest.approx(0.1)
    assert th == pytest.approx(math.pi / 2)


@given(st.floats(0.05, 0.5), st.floats(0.1, 1.5), st.floats(-3.0, 3.0))
def test_arc_stays_on_its_circle(v: float, w: float, th: float) -> None:
    # Integrating in many small steps and in one step land at the same place, on the
    # circle of radius v/w.
    x1, y1, th1 = integrate(0.0, 0.0, th, v, w, 1.0)
    x, y, t = 0.0, 0.0, th
    for _ in range(10):
        x, y, t = integrate(x, y, t, v, w, 0.1)
    assert (x, y, t) == pytest.approx((x1, y1, th1), abs=1e-9)
    r = v / w
    cx, cy = -r * math.sin(th), r * math.cos(th)
    assert math.hypot(x1 - cx, y1 - cy) == pytest.approx(r)


@given(st.floats(-50.0, 50.0))
def test_wrap(angle: float) -> None:
    a = wrap(angle)
    assert -math.pi <= a < math.pi
    assert math.sin(a) == pytest.approx(math.sin(angle), abs=1e-9)
    assert math.cos(a) == pytest.approx(math.cos(angle), abs=1e-9)
