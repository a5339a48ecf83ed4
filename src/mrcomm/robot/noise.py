"""Sensor noise of a simulated robot: noisy wheel odometry and a small, slowly varying
localisation error (what AMCL leaves after correcting the odometry drift) — and, for
the ``realistic`` variation profile (robot/variation.py), that error with AMCL's heading
drift and occasional re-localisation jumps (:class:`AmclError`).

Every draw comes from the numpy Generator handed in. Normals are drawn in blocks and
handed out one by one as Python floats, so the per-step cost is a list index, not a
numpy call; the sequence of values depends only on the generator's seed and the order
of use, so equal seeds give identical runs.
"""

from __future__ import annotations

import math

import numpy as np

#: Normals drawn at a time: numpy draws the same values in blocks of any size, so this
#: only trades calls for memory (4,096 Python floats, 131 kB, per stream was 131 MB for
#: campus1000's streams).
_BLOCK = 256


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


class AmclError(LocalisationError):
    """:class:`LocalisationError` plus what AMCL adds on a real robot: a slow heading
    drift (a second Gauss-Markov process with a long time constant) and re-localisation
    jumps (a Poisson process in driving time; a jump offsets the error at once, and the
    Gauss-Markov decay then fades it, as the estimate re-converges).

    The base error draws from the robot's shared noise stream exactly as
    :class:`LocalisationError` does; drift and jumps draw from their own generator, so
    the odometry noise sees the same sequence whatever the drift and jump settings.
    """

    __slots__ = (
        "_da",
        "_db",
        "_ddt",
        "_drift_sigma",
        "_drift_tau",
        "_extra",
        "_gm_th",
        "_jump_h",
        "_jump_rate",
        "_jump_xy",
        "_next_jump",
        "_rng",
        "drift",
        "driven",
        "jumps",
    )

    def __init__(
        self,
        normals: NormalStream,
        sigma_pos: float,
        sigma_heading: float,
        tau: float,
        rng: np.random.Generator,
        *,
        drift_sigma: float,
        drift_tau: float,
        jump_rate: float,
        jump_sigma: float,
        jump_heading_sigma: float,
    ) -> None:
        super().__init__(normals, sigma_pos, sigma_heading, tau)
        self._rng = rng
        self._extra = NormalStream(rng)
        self._drift_sigma = drift_sigma
        self._drift_tau = drift_tau
        self._ddt = -1.0
        self._da = self._db = 0.0
        self._jump_rate = jump_rate
        self._jump_xy = jump_sigma
        self._jump_h = jump_heading_sigma
        self._gm_th = self.eth  # the fast heading component; eth = it + drift
        self.drift = drift_sigma * self._extra.next()
        self.eth = self._gm_th + self.drift
        self.driven = 0.0  #: s of driving so far (the clock of the jump process)
        self.jumps = 0  #: re-localisation jumps so far
        self._next_jump = self._wait()

    def _wait(self) -> float:
        """Driving time of the next jump (exponential gaps: a Poisson process)."""
        if self._jump_rate <= 0.0:
            return math.inf
        return self.driven + float(self._rng.exponential(1.0 / self._jump_rate))

    def step(self, dt: float) -> None:
        # The fast part is the base class's process on (ex, ey, _gm_th).
        self.eth = self._gm_th
        super().step(dt)
        self._gm_th = self.eth
        if dt != self._ddt:
            self._ddt = dt
            self._da = math.exp(-dt / self._drift_tau)
            self._db = math.sqrt(1.0 - self._da * self._da)
        self.drift = self._da * self.drift + self._db * self._drift_sigma * self._extra.next()
        self.driven += dt
        while self.driven >= self._next_jump:
            x = self._extra
            self.ex += self._jump_xy * x.next()
            self.ey += self._jump_xy * x.next()
            self._gm_th += self._jump_h * x.next()
            self.jumps += 1
            self._next_jump = self._wait()
        self.eth = self._gm_th + self.drift
