"""Fitting a radio profile to RSSI readings (``mrcomm radio fit``).

A reading is one RSSI value (dBm) measured at a receiver of a transmitter's packets,
with both antennas' positions and the walls between them on the map. The model is the
``radio`` network model's (:mod:`mrcomm.net.radio.model`)::

    rssi = A − 10 n log10(max(d, 1 m)) − w · walls + ε,     A = tx_power − L0

**Mean** — ordinary least squares for (A, n, w). The wall loss must be ≥ 0: a negative
least-squares value is clipped to 0 and A, n refitted without the walls (noted). When
the readings do not vary in the number of walls crossed (none crosses a wall, or all
cross the same number), w cannot be told apart from A: it is kept at the base
profile's value (noted) and A, n fitted with it. L0 = tx_power − A, for the transmit
power the user states (default: the base profile's).

**Residuals** — ε is, in the model, the sum of

* the link's shadowing ``S = (F(a) + F(b)) / √2`` of a field F with standard deviation
  σ and correlation ``exp(−Δ/dc)``; two readings i, j (transmitter a, receiver b) have
  ``cov(S_i, S_j) = σ² · ½ [ρ(a_i a_j) + ρ(a_i b_j) + ρ(b_i a_j) + ρ(b_i b_j)]``
  (so a short link varies by up to 2σ²: its two ends share the field);
* the per-direction offset of the pair (σ_a, ``asymmetry_db``): ``+x`` one way, ``−x``
  the other, fixed for a run;
* a nugget τ² of independent noise per reading: quantisation to whole dBm (1/12 dB²),
  fast fading, measurement noise.

Readings of different groups (runs: each run draws its own field and offsets) are
independent. **Shadowing** — a weighted least-squares fit of the semivariogram, the
classic way of fitting Gudmundson's ``exp(−Δ/dc)`` to measurements, with each pair's
own geometry instead of one Δ per bin: for pairs of readings i, j of the same group,
``½ (r_i − r_j)²`` has expectation

    γ_ij = σ² [½(1 + ρ(d_i)) + ½(1 + ρ(d_j)) − k_ij(dc)] + σ_a² (1 − s_ij) + τ²

(k_ij the bracket above, ρ(d) the correlation of a link's own two ends d apart,
s_ij = ±1 for two readings of the same robot pair the same or the other way, 0
otherwise). Differences, not products, so each group's (each run's) own mean level
cancels. σ_a comes first, when the readings say when they were taken: half the
difference of a pair's two directions read at the same moment is its offset plus
independent noise, whatever the shadowing, walls or position errors (the two share
them) — :func:`reciprocal_asymmetry`; its part of γ is then taken out. For each dc on a
log grid (then refined), (σ², τ²[, σ_a² when it was not found so]) are the
non-negative least-squares solution — linear — and dc the one with the smallest
error; a pilot fit with equal weights, then weights 1/γ² (the variance of
½(r_i − r_j)² is 2γ² for Gaussian residuals, so short lags, where dc shows, count
more: Cressie's weighting). The pairs: every pair of a group when there are at most
``max_pairs``, else a seeded sample, half of it neighbours in the readings' order (they
come in time order: close in space) and half uniform; lags beyond half the largest are
left out (few, far apart places). Without link identities (a CSV of readings) σ_a is
not fitted (kept at the base profile's value; the nugget holds it). Residuals are
scaled by N/(N − p) first (p fitted mean parameters). :attr:`RadioFit.variogram` bins
the measured and fitted semivariogram by the mean distance between matched link ends.

What is identifiable: σ and dc only as well as the readings sample the field. A few
robots in a few runs see a few dozen decorrelation areas; a field that does not
decorrelate within the readings' extent leaves dc unidentified (kept at the base's,
σ refitted with it, noted), and over a small area σ and dc come out low together (the
semivariogram of one realisation levels off below its sill). The simulator's own field
(:mod:`mrcomm.net.radio.shadowing`, bilinear between grid points dc/8 apart) is
smoother than ``exp(−Δ/dc)`` at lags of a few grid points, so readings of robots that
stand still much of the time (many short lags) give a larger dc than the profile's.

**Intervals** — the readings are strongly correlated (a robot reads its peers twice a
second while the field changes over metres), so independent-error standard errors
would be far too small: the covariance of (A, n, w) is the sandwich
``(XᵀX)⁻¹ XᵀΣX (XᵀX)⁻¹`` with Σ the fitted residual covariance (exact per group up to
:data:`MEAT_EXACT` readings, beyond an unbiased estimate from a seeded subset); 95 %
intervals are ±1.96 standard errors. σ, dc and σ_a get no interval.

**Censoring** — a card reports nothing below its sensitivity, so readings near it are
a censored sample. When no reading lies below the sensitivity, readings within
``censor_margin_db`` of it are left out (noted, with their share: the rest is then a
truncated sample, biased towards a stronger signal where many readings lie near the
floor). When some do (a simulation records the modelled power whatever it is), the
readings are not censored and all are kept.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from mrcomm.errors import InputError
from mrcomm.fileio import atomic_write_text
from mrcomm.net.radio.fit_data import Estimate, FloatArray, Readings, rounded
from mrcomm.net.radio.fit_shadowing import fit_covariance, meat
from mrcomm.net.radio.profile import RadioProfile

#: Fewest readings a profile is fitted from (after censored ones are left out).
MIN_READINGS = 30
#: Readings within this many dB of the sensitivity are left out as censored (when no
#: reading lies below it).
CENSOR_MARGIN_DB = 1.0
#: Reading pairs used by the covariance fit (all pairs of a group if fewer).
MAX_PAIRS = 200_000


#: The profile's key of each fitted parameter, in the order of the summary.
PROFILE_KEYS = {
    "reference_loss": "reference_loss_db",
    "exponent": "exponent",
    "wall_loss": "wall_loss_db",
    "sigma": "shadowing_sigma_db",
    "decorrelation": "decorrelation_m",
    "asymmetry": "asymmetry_db",
}


@dataclass(frozen=True)
class RadioFit:
    """What :func:`fit_profile` found."""

    base: RadioProfile
    tx_power_dbm: float
    #: A = tx − L0: the mean power at the 1 m reference, dBm.
    intercept: Estimate
    reference_loss: Estimate
    exponent: Estimate
    wall_loss: Estimate
    sigma: Estimate
    decorrelation: Estimate
    asymmetry: Estimate
    #: Independent noise per reading (quantisation, fading), dB.
    nugget_db: float
    readings: int
    groups: int
    excluded_censored: int
    r_squared: float
    #: Standard deviation of the residuals, corrected for the fitted mean parameters.
    residual_std_db: float
    #: The semivariogram of the residuals, measured and fitted, binned by distance.
    variogram: list[dict[str, float]]
    notes: list[str] = field(default_factory=list)
    source: str = ""

    def estimates(self) -> dict[str, Estimate]:
        return {name: getattr(self, name) for name in PROFILE_KEYS}

    def profile(self, name: str, source: str) -> RadioProfile:
        """The base profile with the fitted values (and the stated transmit power)."""
        values = self.base.model_dump()
        values.update({key: rounded(getattr(self, k).value) for k, key in PROFILE_KEYS.items()})
        values.update(name=name, source=source, tx_power_dbm=self.tx_power_dbm)
        return RadioProfile.model_validate(values)

    def as_dict(self) -> dict[str, Any]:
        return {
            "source": self.source,
            "base": self.base.name,
            "tx_power_dbm": self.tx_power_dbm,
            "intercept_dbm": self.intercept.as_dict(),
            **{key: getattr(self, k).as_dict() for k, key in PROFILE_KEYS.items()},
            "nugget_db": rounded(self.nugget_db),
            "readings": self.readings,
            "groups": self.groups,
            "excluded_censored": self.excluded_censored,
            "r_squared": rounded(self.r_squared, 4),
            "residual_std_db": rounded(self.residual_std_db),
            "variogram": self.variogram,
            "notes": list(self.notes),
        }


def fit_profile(
    readings: Readings,
    base: RadioProfile,
    *,
    tx_power_dbm: float | None = None,
    seed: int = 0,
    max_pairs: int = MAX_PAIRS,
    censor_margin_db: float = CENSOR_MARGIN_DB,
    min_readings: int = MIN_READINGS,
) -> RadioFit:
    """Fit L0, n, wall loss, σ, dc (and σ_a when the readings name their links) to
    ``readings``; see the module docstring. Too few or degenerate readings are an
    :class:`InputError` naming the readings' source."""
    notes = list(readings.notes)
    tx = base.tx_power_dbm if tx_power_dbm is None else float(tx_power_dbm)
    readings, excluded = censor(readings, base.sensitivity_dbm, censor_margin_db, notes=notes)
    n = len(readings)
    where = readings.source or None
    if n < min_readings:
        raise InputError(
            f"only {n} usable readings, need at least {min_readings}", file=where, field="rssi"
        )
    if np.all(readings.rssi == np.round(readings.rssi)):
        notes.append(
            "readings are whole dBm (quantised: 1/12 dB² of noise per reading, in the nugget)"
        )
    y = readings.rssi
    log_d = np.log10(np.maximum(readings.distance, 1.0))
    if np.ptp(log_d) < 1e-3:
        raise InputError(
            "every reading is at the same distance (or within 1 m): the exponent cannot be fitted",
            file=where,
            field="readings",
        )
    walls = readings.walls.astype(np.float64)
    beta, design, offset, wall_status = _fit_mean(y, log_d, walls, base.wall_loss_db, notes)
    p = design.shape[1]
    if np.linalg.matrix_rank(design) < p:
        raise InputError(
            "distance and walls vary together in these readings: L0, n and the wall loss "
            "cannot be told apart",
            file=where,
            field="readings",
        )
    a_value, n_value = float(beta[0]), float(beta[1])
    if n_value <= 0:
        raise InputError(
            f"the fitted exponent is {n_value:.2f}: the readings do not fall with distance",
            file=where,
            field="rssi",
        )
    residual = y - offset - design @ beta
    dof = n - p
    residual_std = float(np.sqrt(residual @ residual / dof))
    total = float(np.sum((y - y.mean()) ** 2))
    r_squared = 1.0 - float(residual @ residual) / total if total > 0 else 0.0

    cov, shadowing, nugget, variogram = fit_covariance(
        readings, residual * math.sqrt(n / dof), base, seed=seed, max_pairs=max_pairs, notes=notes
    )
    bread = np.linalg.inv(design.T @ design)
    beta_cov = bread @ meat(design, readings, cov, seed) @ bread
    se = np.sqrt(np.clip(np.diag(beta_cov), 0.0, None))

    base_a = base.tx_power_dbm - base.reference_loss_db
    intercept = Estimate(a_value, base_a, float(se[0]))
    reference = Estimate(tx - a_value, base.reference_loss_db, float(se[0]))
    exponent = Estimate(n_value, base.exponent, float(se[1]))
    if wall_status == "fitted":
        wall = Estimate(float(beta[2]), base.wall_loss_db, float(se[2]))
    else:
        value = 0.0 if wall_status == "clipped" else base.wall_loss_db
        wall = Estimate(value, base.wall_loss_db, None, wall_status)
    return RadioFit(
        base=base,
        tx_power_dbm=tx,
        intercept=intercept,
        reference_loss=reference,
        exponent=exponent,
        wall_loss=wall,
        sigma=shadowing["sigma"],
        decorrelation=shadowing["decorrelation"],
        asymmetry=shadowing["asymmetry"],
        nugget_db=nugget,
        readings=n,
        groups=int(np.unique(readings.group).size),
        excluded_censored=excluded,
        r_squared=r_squared,
        residual_std_db=residual_std,
        variogram=variogram,
        notes=notes,
        source=readings.source,
    )


def censor(
    readings: Readings,
    sensitivity: float,
    margin: float = CENSOR_MARGIN_DB,
    *,
    notes: list[str],
) -> tuple[Readings, int]:
    """Leave out readings within ``margin`` dB of the sensitivity, unless the readings
    go below it (then they are not censored); say which in ``notes``. Returns the
    readings kept and how many were left out."""
    below = int(np.count_nonzero(readings.rssi < sensitivity - 0.5))
    if below:
        notes.append(
            f"{below} readings lie below the sensitivity ({sensitivity:g} dBm): the "
            "readings are not censored (a simulation records the modelled power), all kept"
        )
        return readings, 0
    near = readings.rssi <= sensitivity + margin
    count = int(np.count_nonzero(near))
    if count:
        share = 100.0 * count / max(len(readings), 1)
        notes.append(
            f"left out {count} readings ({share:.1f} %) within {margin:g} dB of the "
            f"sensitivity ({sensitivity:g} dBm): a card reports nothing below it, so they "
            "are a censored sample"
            + ("; so many that the fit is biased towards a stronger signal" if share > 5 else "")
        )
    return readings.subset(~near), count


def _fit_mean(
    y: FloatArray, log_d: FloatArray, walls: FloatArray, base_wall: float, notes: list[str]
) -> tuple[FloatArray, FloatArray, FloatArray, str]:
    """Least squares (A, n[, w]): (coefficients, design, fixed offset, wall status)."""
    ones = np.ones_like(y)
    slope = -10.0 * log_d
    if np.unique(walls).size < 2:
        crossed = (
            "no reading crosses a wall"
            if walls.max() == 0
            else (f"every reading crosses {int(walls[0])} wall(s)")
        )
        notes.append(
            f"{crossed}: the wall loss cannot be told apart from L0; kept the base "
            f"profile's {base_wall:g} dB"
        )
        design = np.column_stack([ones, slope])
        offset = -base_wall * walls
        beta = np.asarray(np.linalg.lstsq(design, y - offset, rcond=None)[0], np.float64)
        return beta, design, offset, "kept"
    design = np.column_stack([ones, slope, -walls])
    beta = np.asarray(np.linalg.lstsq(design, y, rcond=None)[0], np.float64)
    if beta[2] >= 0:
        return beta, design, np.zeros_like(y), "fitted"
    notes.append(
        f"the least-squares wall loss is negative ({beta[2]:.2f} dB): clipped to 0 and "
        "L0, n refitted without walls"
    )
    design = design[:, :2]
    beta = np.asarray(np.linalg.lstsq(design, y, rcond=None)[0], np.float64)
    return beta, design, np.zeros_like(y), "clipped"


# -- the residuals' covariance ---------------------------------------------------------


def profile_yaml(profile: RadioProfile, header: Sequence[str] = ()) -> str:
    """A profile as YAML that :func:`~mrcomm.net.radio.profile.load_profile` reads."""
    comments = "".join(f"# {line}\n" if line else "#\n" for line in header)
    body = yaml.safe_dump(profile.model_dump(), sort_keys=False, width=1 << 16)
    return comments + body


def write_profile(path: str | Path, profile: RadioProfile, header: Sequence[str] = ()) -> None:
    """Write a profile atomically (temporary file + rename)."""
    atomic_write_text(path, profile_yaml(profile, header))
