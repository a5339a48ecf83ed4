"""Sensor noise of a simulated robot: noisy wheel odometry and a small, slowly varying
localisation error (what AMCL leaves after correcting the odometry drift).

Every draw comes from the numpy Generator handed in. Normals are drawn in blocks and
handed out one by one as Python floats, so the per-step cost is a list index, not a
numpy call; the sequence of values depends only on the generator's seed and the order
of use, so equal seeds give identical runs.
"""

from __future__ import annotations

import math

import numpy as np

_BLOCK = 4096


class NormalStream:
    """Standard normal draws from a Generator, served as floats from a buffer."""

    __slots__ = ("_buf", "_i", "_rng")

    def __init__(self, rng: np.random.Generator) -> None:
        self._rng = rng
        self._buf: list[float] = []
        self._i = 0

    def next(self) -> float:
        i = self._i
        if i >= len(self._buf):
            self._buf = self._rng.standard_normal(_BLOCK).tolist()
            i = 0
        self._i = i + 1
        return self._buf[i]


class Odometry:
    """Wheel odometry: integrates the true motion increments with multiplicative noise.

    ``distance`` is the odometer (sum of |noisy distance increments|); ``x, y, theta``
    is the dead-reckoned pose in the odometry frame (starts at the true start pose and
    drifts away from it).
    """

    __slots__ = ("_d_sigma", "_h_sigma", "_normals", "distance", "theta", "x", "y")

    def __init__(
        self,
        normals: NormalStream,
        start: tuple[float, float, float],
        d_sigma: float,
        h_sigma: float,
    ) -> None:
        self._normals = normals
        self._d_sigma = d_sigma
        self._h_sigma = h_sigma
        self.x, self.y, self.theta = start
        self.distance = 0.0

    def add(self, ds: float, dtheta: float) -> float:
        """Record a true increment (signed distance, heading change); returns the noisy
        distance increment the odometer measured."""
        n = self._normals
        ds_m = ds * (1.0 + self._d_sigma * n.next())
        dth_m = dtheta * (1.0 + self._h_sigma * n.next())
        mid = self.theta + 0.5 * dth_m
        self.x += ds_m * math.cos(mid)
        self.y += ds_m * math.sin(mid)
        self.theta += dth_m
        step = abs(ds_m)
        self.distance += step
        return step


class LocalisationError:
    """A first-order Gauss-Markov error (ex, ey, etheta) added to the true pose.

    Updated only while the robot moves (AMCL updates on motion), so a parked robot's
    estimate stays still; stationary variance is ``sigma**2`` per axis with correlation
    time ``tau``.
    """

    __slots__ = ("_a", "_b", "_dt", "_normals", "_sh", "_sp", "_tau", "eth", "ex", "ey")

    def __init__(self, normals: NormalStream, sigma_pos: float, sigma_heading: float, tau: float):
        self._normals = normals
        self._sp = sigma_pos
        self._sh = sigma_heading
        self._tau = tau
        self._dt = -1.0
        self._a = self._b = 0.0
        # Start from the stationary distribution so statistics do not depend on time.
        self.ex = sigma_pos * normals.next()
        self.ey = sigma_pos * normals.next()
        self.eth = sigma_heading * normals.next()

    def step(self, dt: float) -> None:
        if dt != self._dt:  # the step is nearly always the same: cache its decay
            self._dt = dt
            self._a = math.exp(-dt / self._tau)
            self._b = math.sqrt(1.0 - self._a * self._a)
        a = self._a
        b = self._b
        n = self._normals
        self.ex = a * self.ex + b * self._sp * n.next()
        self.ey = a * self.ey + b * self._sp * n.next()
        self.eth = a * self.eth + b * self._sh * n.next()
