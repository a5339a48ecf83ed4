"""Configuration of one mission run (a point of the experiment design), as a frozen,
validated model shared by ``mrcomm run``, sweeps and live mode.

The variants — network model, threshold, behaviour — are chosen by name from the spec
registry (:mod:`mrcomm.specs`); each one's parameters sit in ``params`` under its kind
(``params = {"behaviour": {"utility": "greedy"}}``), validated against the variant's
parameter model. Only values that differ from the defaults are kept, so a configuration
that sets nothing is the same configuration it always was.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from mrcomm.errors import InputError, did_you_mean
from mrcomm.robot.variation import VariationParams
from mrcomm.specs import Kind, VariantSpec, get_spec, validate_params, variant_names

#: The kinds a run chooses one variant of, in the order of its label.
RUN_KINDS: tuple[Kind, ...] = ("network", "behaviour", "threshold")
#: Sections of ``params``: one per variant kind, and ``robot`` (the robots' run-to-run
#: variation, :class:`~mrcomm.robot.variation.VariationParams`; not a variant).
PARAM_SECTIONS: tuple[str, ...] = (*RUN_KINDS, "robot")

#: Options of earlier versions that are now a variant's parameter: option ->
#: (kind, variant, parameter). Still accepted (old journals, schemas, scripts).
LEGACY_OPTIONS: dict[str, tuple[Kind, str, str]] = {
    "ah_range": ("network", "ah", "range_m"),
    "slt_warning": ("threshold", "slt", "warning_m"),
    "ssd_warning": ("threshold", "ssd", "warning_dbm"),
    "esd_warning": ("threshold", "esd", "warning_dbm"),
    "signal_model": ("threshold", "ssd", "model"),
    "rssi_trace": ("threshold", "esd", "trace"),
}
#: What earlier versions wrote into every run's options for a legacy option whose
#: parameter's default has changed since (ESD's warning level follows the network now):
#: on a run of another variant that value is still "unset".
LEGACY_DEFAULTS: dict[str, Any] = {"esd_warning": -41.0}


class RunConfig(BaseModel):
    """Everything that determines a run; same config + seed => same result."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    scenario: Path
    network: str = "wlan"
    spl: float = Field(0.0, ge=0.0, le=100.0, description="simulated packet loss, %")
    threshold: str = "none"
    behaviour: str = "nb"
    #: Stored as a 64-bit integer (results databases, recordings): larger is refused.
    seed: int = Field(1, ge=0, lt=2**63)
    max_time: float = Field(
        1800.0, gt=0.0, le=1e6, description="mission time limit, simulated s (at most 1e6)"
    )
    # At least 1 ms: a smaller step only makes a run take forever (1e-9 s never ends).
    dt: float = Field(0.1, ge=0.001, le=0.5, description="simulation step, s (0.001-0.5)")
    #: Parameters of the chosen variants by kind, as given (non-default values only).
    params: dict[str, dict[str, Any]] = Field(default_factory=dict)

    @model_validator(mode="after")
    def _combinations(self) -> RunConfig:
        unknown = set(self.params) - set(PARAM_SECTIONS)
        if unknown:
            kind = sorted(unknown)[0]
            raise InputError(
                f"unknown parameter section {kind!r}{did_you_mean(kind, PARAM_SECTIONS)}; "
                f"sections: {', '.join(PARAM_SECTIONS)}",
                field=f"params.{kind}",
            )
        # Spec look-ups raise InputError with a "did you mean" hint; so do parameters.
        normalised: dict[str, dict[str, Any]] = {
            kind: self._check_params(kind) for kind in RUN_KINDS
        }
        # Only non-defaults are kept: a run of the default profile has no robot section,
        # so its configuration (and its id) is what it was before the section existed.
        normalised["robot"] = self.robot_variation().model_dump(mode="json", exclude_defaults=True)
        object.__setattr__(self, "params", {k: v for k, v in normalised.items() if v})
        checked: tuple[Kind, ...] = ("threshold", "behaviour")
        for kind in checked:
            spec = self.spec(kind)
            if spec.network_types is not None and self.network not in spec.network_types:
                raise ValueError(
                    f"{kind} {spec.name!r} needs network "
                    f"{' or '.join(repr(n) for n in sorted(spec.network_types))}"
                )
        if (
            self.spec("threshold").pulse
            and getattr(self.variant_params("threshold"), "trace", None) is None
            and not self.spec("network").load().needs_walls
        ):
            raise ValueError(
                f"threshold {self.threshold!r} needs --rssi-trace CSV (or --network radio, "
                "whose signal the pulses then measure)"
            )
        return self

    def _check_params(self, kind: Kind) -> dict[str, Any]:  # only given, non-default values
        spec = self.spec(kind)
        given = dict(self.params.get(kind, {}))
        # A section named after a variant of this kind holds parameters of that variant
        # only (``threshold.esd.warning_dbm``): a study sweeping thresholds can set ESD's
        # warning level without giving SLT a key it does not have.
        for name in variant_names(kind):
            scoped = given.get(name)
            if isinstance(scoped, dict):
                del given[name]
                get_spec(kind, name).make_params(scoped)  # a typo is an error in any run
                if name == spec.name:
                    given.update(scoped)
        model = spec.make_params(given)
        dumped: dict[str, Any] = model.model_dump(mode="json", exclude_defaults=True)
        return dumped

    def spec(self, kind: Kind) -> VariantSpec:
        """The spec of the chosen variant of ``kind``."""
        return get_spec(kind, str(getattr(self, kind)))

    def variant_params(self, kind: Kind) -> Any:
        """The chosen variant's validated parameters (its parameter model)."""
        return self.spec(kind).make_params(self.params.get(kind, {}))

    def robot_variation(self) -> VariationParams:
        """The robots' run-to-run variation (``robot.*``; default profile ``none``)."""
        model = validate_params(VariationParams, self.params.get("robot", {}), "robot", "robot")
        assert isinstance(model, VariationParams)
        return model

    def variants(self) -> dict[str, str]:
        """kind -> ``name-vN`` of every chosen variant (recorded with each run)."""
        return {kind: self.spec(kind).versioned for kind in RUN_KINDS}

    def id_content(self) -> dict[str, str]:
        """What a configuration id adds for its variants: the versions of those past
        their first (a new version of a variant is a new configuration; ids of
        configurations on first versions stay what they always were)."""
        bumped = {k: v for k, v in self.variants().items() if not v.endswith("-v1")}
        return {"variants": json.dumps(bumped, sort_keys=True)} if bumped else {}

    def check_mode(self, mode: str) -> None:
        """Refuse (one line) a variant that cannot run in ``mode`` ("sim" | "live")."""
        for kind in ("network", "threshold", "behaviour"):
            spec = self.spec(kind)
            if mode not in spec.modes:
                where = " and ".join(sorted(spec.modes))
                raise InputError(
                    f"{kind} '{spec.name}' runs in {where} mode only, not in {mode} mode",
                    field=f"--{kind}",
                )

        network = self.variant_params("network")
        if mode != "sim" and getattr(network, "relay", False) and network.relay_store:
            # The Zenoh bus relays, but does not store and forward: refused, not ignored.
            raise InputError(
                "store and forward is simulated only (live mode relays without it)",
                field="network.relay_store",
            )

    def ignored_settings(self) -> list[str]:
        """Settings accepted that change nothing the team does, or that the network model
        finds doubtful (a threshold on another scale than its signal), one line each (the
        commands warn about them)."""
        behaviour = self.spec("behaviour")
        network: list[str] = self.spec("network").load().advice(self)
        if self.threshold != "none" and not behaviour.uses_threshold:
            return [
                f"{behaviour.name.upper()} ignores the threshold ({self.threshold}): its runs "
                "are those of --threshold none; the threshold is recorded for link "
                "statistics only",
                *network,
            ]
        return network

    def label(self) -> str:
        """Short configuration label, e.g. ``AH_NB_SPL25_SSD``."""
        spl = f"{self.spl:g}"
        parts = [self.network.upper(), self.behaviour.upper(), f"SPL{spl}"]
        if self.threshold != "none":
            parts.append(self.threshold.upper())
        return "_".join(parts)


def make_config(source: str | Path | None = None, **values: Any) -> RunConfig:
    """Build a RunConfig, turning validation errors into a one-line InputError.
    Options of earlier versions (:data:`LEGACY_OPTIONS`) become parameters."""
    values = fold_legacy_options(values, source)
    try:
        return RunConfig(**values)
    except ValidationError as err:
        first = err.errors()[0]
        loc = ".".join(str(p) for p in first["loc"]) or None
        message = first["msg"]
        if first["type"] == "extra_forbidden" and loc:
            known = [*RunConfig.model_fields, *LEGACY_OPTIONS]
            message = f"unknown option{did_you_mean(loc, known)}"
        raise InputError(message.removeprefix("Value error, "), file=source, field=loc) from None
    except InputError as err:
        if err.file is None and source is not None:
            raise InputError(err.message, file=source, field=err.field) from None
        raise


def fold_legacy_options(values: Mapping[str, Any], source: str | Path | None) -> dict[str, Any]:
    """Move legacy options into ``params``: the one that applies to the chosen variant
    becomes its parameter; one that applies to another variant must be unset (None or
    that variant's default), else it would be ignored in silence."""
    out = dict(values)
    legacy = {k: out.pop(k) for k in list(out) if k in LEGACY_OPTIONS}
    if not legacy:
        return out
    params = {kind: dict(section) for kind, section in dict(out.get("params") or {}).items()}
    defaults = {"network": "wlan", "threshold": "none", "behaviour": "nb"}
    for option, value in legacy.items():
        kind, variant, parameter = LEGACY_OPTIONS[option]
        chosen = str(out.get(kind, defaults[kind]))
        if chosen == variant:
            params.setdefault(kind, {}).setdefault(parameter, value)
            continue
        default = get_spec(kind, variant).params_model().model_fields[parameter].default
        if value is not None and value != default and value != LEGACY_DEFAULTS.get(option):
            raise InputError(
                f"applies to {kind} {variant!r} only (this run's {kind} is {chosen!r})",
                file=source,
                field=option,
            )
    out["params"] = params
    return out


def param_assignments(config: RunConfig) -> list[str]:
    """The run's parameters as ``kind.key=value`` assignments (what ``--set`` takes),
    nested models flattened to dotted keys."""
    out: list[str] = []

    def walk(prefix: str, values: Mapping[str, Any]) -> None:
        for key, value in values.items():
            if isinstance(value, Mapping):
                walk(f"{prefix}{key}.", value)
            else:
                out.append(f"{prefix}{key}={json.dumps(value)}")

    for kind, section in config.params.items():
        walk(f"{kind}.", section)
    return out
