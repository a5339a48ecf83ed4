"""Experiment schema files: validated YAML that expands into configurations.

An experiment is a scenario (or several), a full factorial over run options and a
number of repetitions::

    name: ah                          # experiment name (default: the file name)
    scenario: ../scenarios/s1.yaml    # or a list; relative to this file; or a generator
                                      # spec with team sizes (generated.py)
    repetitions: 30
    base_seed: 7                      # run seeds derive from it (see seeds.py)
    factors:                          # option -> list of levels (a scalar = one level)
      network: [ah]
      spl: [0, 25, 50, 75]
      threshold: [slt, ssd]
      behaviour: [nb, lf]
    options: {max_time: 1800}         # fixed options of every configuration
    params:                           # fixed variant parameters (mrcomm variants)
      behaviour.aon_lease: 30
    exclude:                          # optional: drop combinations matching all keys
      - {network: wlan, threshold: ssd}

Factors and options are any :class:`~mrcomm.run.config.RunConfig` field except
``scenario`` and ``seed``, or a variant parameter ``KIND.KEY`` (``behaviour.utility:
[original, greedy]``); ``params`` holds fixed parameters (dotted or nested keys).
Everything is checked here, before any database is opened:
unknown keys (with "did you mean"), empty factors, the number of runs (at most
:data:`MAX_RUNS`, counted before anything is built), and every value, by building the
RunConfig of every configuration.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pydantic
from pydantic import BaseModel, ConfigDict, Field

from mrcomm.errors import InputError, did_you_mean
from mrcomm.experiment.generated import generated_scenarios
from mrcomm.experiment.seeds import make_config_id, make_run_id, run_seed
from mrcomm.run.config import LEGACY_OPTIONS, PARAM_SECTIONS, RunConfig, make_config
from mrcomm.run.resources import checked_scenario
from mrcomm.world.scenario import load_scenario
from mrcomm.world.yamlfile import read_yaml, validation_error

#: Factors that RunConfig.label() already spells out.
LABEL_FACTORS = ("network", "spl", "threshold", "behaviour")
#: RunConfig fields that hold file paths (resolved relative to the schema file).
PATH_FIELDS = ("signal_model", "rssi_trace", "threshold.model", "threshold.trace")
_NOT_OPTIONS = {
    "scenario": "give scenarios in the top-level 'scenario' key",
    "seed": "run seeds derive from 'base_seed' (see docs/RESULTS.md)",
    "params": "give variant parameters in the top-level 'params' key or as KIND.KEY",
}


class ExperimentModel(BaseModel):
    """The YAML file as written."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    name: str | None = Field(None, pattern=r"^[A-Za-z0-9][A-Za-z0-9_.-]*$")
    description: str = ""
    #: A scenario file, a list of them, or a generator spec (team size as a factor:
    #: ``experiment/generated.py``).
    scenario: str | list[str] | dict[str, Any]
    repetitions: int = Field(ge=1)
    base_seed: int = Field(0, ge=0, lt=1 << 63)
    factors: dict[str, Any] = Field(default_factory=dict)
    options: dict[str, Any] = Field(default_factory=dict)
    params: dict[str, Any] = Field(default_factory=dict)
    exclude: list[dict[str, Any]] = Field(default_factory=list)


@dataclass(frozen=True)
class RunSpec:
    """One run to store: a configuration, a repetition and its seed (a sweep derives
    the seed from them; an ad-hoc run brings its own, see ``adhoc.py``)."""

    run_id: str
    config_id: str
    experiment: str
    label: str
    scenario_name: str
    repetition: int
    seed: int
    config: RunConfig
    #: 'sim' (simulation: sweeps, ``mrcomm run``) or 'live' (``mrcomm live``/``collect``).
    mode: str = "sim"


@dataclass(frozen=True)
class Configuration:
    """One point of the factorial."""

    config_id: str
    experiment: str
    label: str
    scenario_name: str
    #: The run options, with seed 0 (each run gets its own).
    config: RunConfig
    #: Options beyond the RunConfig (a live run's speed, lease, ...), stored with it in
    #: ``configs.options``. Not hashed: a frozen dataclass hashes its fields.
    extra_options: dict[str, Any] = dataclasses.field(default_factory=dict, hash=False)

    def run(self, repetition: int, base_seed: int) -> RunSpec:
        seed = run_seed(base_seed, self.config_id, repetition)
        return RunSpec(
            run_id=make_run_id(self.config_id, repetition),
            config_id=self.config_id,
            experiment=self.experiment,
            label=self.label,
            scenario_name=self.scenario_name,
            repetition=repetition,
            seed=seed,
            config=self.config.model_copy(update={"seed": seed}),
        )


#: Most runs one experiment (configurations x repetitions) may expand to. Every run is
#: planned in memory and recorded in the database before the first starts; a study of
#: more is a few experiments (each its own name, in one database).
MAX_RUNS = 100_000


def check_run_count(
    configurations: int, repetitions: int, path: Path, given_reps: int | None = None
) -> None:
    """Refuse an experiment of more than :data:`MAX_RUNS` runs (one line, nothing built).
    ``given_reps``: the repetitions came from ``--reps`` (named as the culprit)."""
    total = configurations * repetitions
    if total > MAX_RUNS:
        option = "--reps" if given_reps is not None else "repetitions"
        raise InputError(
            f"the experiment expands to {total:,} runs ({configurations:,} configurations x "
            f"{repetitions:,} repetitions); at most {MAX_RUNS:,} per sweep (split it, or "
            f"lower {option})",
            file=None if given_reps is not None else path,
            field=option,
        )


@dataclass(frozen=True)
class Experiment:
    """A validated, expanded experiment schema."""

    name: str
    path: Path
    yaml_text: str
    description: str
    repetitions: int
    base_seed: int
    configurations: tuple[Configuration, ...]

    def runs(self, repetitions: int | None = None) -> list[RunSpec]:
        """Every run, configuration-major, repetitions numbered from 1 (refused in one
        line, before any is built, beyond :data:`MAX_RUNS`)."""
        reps = self.repetitions if repetitions is None else repetitions
        check_run_count(len(self.configurations), reps, self.path, given_reps=repetitions)
        return [c.run(r, self.base_seed) for c in self.configurations for r in range(1, reps + 1)]


def load_experiment(
    path: str | Path, params: dict[str, Any] | None = None, *, repetitions: int | None = None
) -> Experiment:
    """Read, validate and expand an experiment schema file (InputError on bad input).
    ``params`` (``sweep --set``) adds fixed variant parameters to the file's ``params``;
    one the file already sets, as a parameter or a factor, is an error. ``repetitions``
    (``sweep --reps``) replaces the file's in the run count, which is checked against
    :data:`MAX_RUNS` before any scenario is read or configuration built."""
    path = Path(path)
    raw = read_yaml(path)
    if not isinstance(raw, dict):
        raise InputError("must be a mapping with scenario, factors, repetitions", file=path)
    for key in raw:
        # Before pydantic, whose first error would be the key then found missing.
        if key not in ExperimentModel.model_fields:
            hint = did_you_mean(str(key), ExperimentModel.model_fields)
            raise InputError(f"unknown key '{key}'{hint}", file=path)
    try:
        model = ExperimentModel(**raw)
    except pydantic.ValidationError as err:
        raise validation_error(err, file=path, root=ExperimentModel) from None
    if params:
        given = _flat_params(model.params, path)
        extra = _flat_params(params, path)
        for key in sorted(extra):
            if key in given or key in model.factors or key in model.options:
                raise InputError(f"{key} is already set by {path}", field="--set")
        model = model.model_copy(update={"params": {**given, **extra}})
    return _expand(model, path, path.read_text(encoding="utf-8"), repetitions)


def _allowed_options() -> list[str]:
    fields = [name for name in RunConfig.model_fields if name not in _NOT_OPTIONS]
    return [*fields, *LEGACY_OPTIONS, *(f"{kind}.KEY" for kind in PARAM_SECTIONS)]


def _is_parameter(key: str) -> bool:
    kind, dot, rest = key.partition(".")
    return bool(dot and rest) and kind in PARAM_SECTIONS


def _flat_params(params: dict[str, Any], path: Path) -> dict[str, Any]:
    """The ``params`` section as dotted keys (it may be written nested or dotted)."""
    flat: dict[str, Any] = {}

    def walk(prefix: str, node: dict[str, Any]) -> None:
        for key, value in node.items():
            name = f"{prefix}{key}"
            if isinstance(value, dict):
                walk(f"{name}.", value)
            else:
                flat[name] = value

    walk("", params)
    for key in flat:
        if not _is_parameter(key):
            kind = key.partition(".")[0]
            raise InputError(
                f"unknown parameter section '{kind}'{did_you_mean(kind, PARAM_SECTIONS)}; "
                f"sections: {', '.join(PARAM_SECTIONS)}",
                file=path,
                field=f"params.{key}",
            )
    return flat


def _nest(values: dict[str, Any]) -> dict[str, Any]:
    """Run options with dotted parameter keys -> make_config's keyword arguments."""
    out: dict[str, Any] = {}
    params: dict[str, Any] = {}
    for key, value in values.items():
        if not _is_parameter(key):
            out[key] = value
            continue
        node = params
        *outer, last = key.split(".")
        for part in outer:
            node = node.setdefault(part, {})
        node[last] = value
    if params:
        out["params"] = params
    return out


def _check_keys(keys: Sequence[str], section: str, path: Path) -> None:
    allowed = _allowed_options()
    for key in keys:
        if key in _NOT_OPTIONS:
            raise InputError(
                f"'{key}' cannot be set here: {_NOT_OPTIONS[key]}", file=path, field=section
            )
        if key not in allowed and not _is_parameter(key):
            kind = "factor" if section == "factors" else "option"
            raise InputError(
                f"unknown {kind} '{key}'{did_you_mean(key, allowed)}; "
                f"choose from {', '.join(allowed)}",
                file=path,
                field=section,
            )


def _levels(model: ExperimentModel, path: Path) -> dict[str, list[Any]]:
    _check_keys(list(model.factors), "factors", path)
    _check_keys(list(model.options), "options", path)
    params = _flat_params(model.params, path)
    both = sorted(set(model.factors) & set(model.options))
    if both:
        raise InputError(f"'{both[0]}' is both a factor and an option", file=path, field="options")
    for key in sorted(set(params) & (set(model.factors) | set(model.options))):
        raise InputError(f"'{key}' is set twice", file=path, field=f"params.{key}")
    levels: dict[str, list[Any]] = {}
    for name, value in model.factors.items():
        values = list(value) if isinstance(value, list) else [value]
        if not values:
            raise InputError(
                "empty factorial: the factor has no values", file=path, field=f"factors.{name}"
            )
        for v in values:
            if isinstance(v, dict | list):
                raise InputError(
                    f"factor values must be scalars, got {v!r}", file=path, field=f"factors.{name}"
                )
        if len({repr(v) for v in values}) != len(values):
            raise InputError("a value is given twice", file=path, field=f"factors.{name}")
        levels[name] = values
    return levels


def _check_exclude(model: ExperimentModel, levels: dict[str, list[Any]], path: Path) -> None:
    for i, rule in enumerate(model.exclude):
        field = f"exclude[{i}]"
        if not rule:
            raise InputError("an exclude entry needs at least one factor", file=path, field=field)
        for key, value in rule.items():
            if key not in levels:
                raise InputError(
                    f"'{key}' is not a factor{did_you_mean(key, levels)}", file=path, field=field
                )
            if value not in levels[key]:
                raise InputError(
                    f"{value!r} is not a level of factor '{key}' ({levels[key]})",
                    file=path,
                    field=field,
                )


def _resolve_path(value: Any, base: Path, field: str, path: Path) -> Path:
    resolved = (base / str(value)).resolve()
    if not resolved.is_file():
        raise InputError(f"file not found: {resolved}", file=path, field=field)
    return resolved


def _scenarios(model: ExperimentModel, path: Path) -> list[tuple[str, Path, str]]:
    """(as written, resolved path, scenario name) of each scenario, loaded and checked."""
    if isinstance(model.scenario, dict):
        made = generated_scenarios(model.scenario, path)  # each one checked there
        return [(str(p.relative_to(path.parent)), p, load_scenario(p).name) for p in made]
    written = model.scenario if isinstance(model.scenario, list) else [model.scenario]
    if not written:
        raise InputError("empty factorial: no scenario given", file=path, field="scenario")
    found: list[tuple[str, Path, str]] = []
    for i, text in enumerate(written):
        field = f"scenario[{i}]" if isinstance(model.scenario, list) else "scenario"
        resolved = _resolve_path(text, path.parent, field, path)
        try:
            name = checked_scenario(resolved).name
        except InputError as err:
            # The scenario's own message, with the file and field it names.
            where = "" if err.file in (None, str(resolved)) else f" (from {err.file})"
            inner = f"{err.field}: {err.message}" if err.field else err.message
            raise InputError(
                f"scenario {resolved}{where}: {inner}", file=path, field=field
            ) from None
        found.append((text, resolved, name))
    names = [n for _, _, n in found]
    if len(set(names)) != len(names):
        raise InputError("two scenarios have the same name", file=path, field="scenario")
    return found


def _label_part(name: str, value: Any) -> str:
    if name in PATH_FIELDS:
        text = Path(str(value)).stem
    elif isinstance(value, float):
        text = f"{value:g}"
    else:
        text = str(value)
    name = name.rsplit(".", 1)[-1]  # a parameter by its own name: UTILITYgreedy
    return re.sub(r"[^A-Za-z0-9.+-]", "", f"{name.upper().replace('_', '')}{text}")


def _build(
    values: dict[str, Any], levels: dict[str, list[Any]], path: Path, params: set[str]
) -> RunConfig:
    try:
        return make_config(None, **_nest(values))
    except InputError as err:
        field = (err.field or "").removeprefix("params.")
        if field in levels:
            got = repr(values[field])
            message = err.message if got in err.message else f"{err.message}, got {got}"
            raise InputError(message, file=path, field=f"factors.{field}") from None
        if field in params:
            raise InputError(err.message, file=path, field=f"params.{field}") from None
        if field and field in values and field != "scenario":
            raise InputError(err.message, file=path, field=f"options.{field}") from None
        if _is_parameter(field) or field in PARAM_SECTIONS:
            raise InputError(err.message, file=path, field=field) from None
        combo = ", ".join(f"{k}: {values[k]}" for k in levels)
        raise InputError(
            f"combination {{{combo}}}: {err.message} (drop it with an 'exclude' entry)",
            file=path,
            field="factors",
        ) from None


def _excluded(chosen: dict[str, Any], rules: list[dict[str, Any]]) -> bool:
    """Whether an ``exclude`` entry matches every one of its keys in ``chosen``."""
    return any(all(chosen[k] == v for k, v in rule.items()) for rule in rules)


def _check_size(
    model: ExperimentModel, levels: dict[str, list[Any]], path: Path, repetitions: int | None
) -> None:
    """Count the runs arithmetically and refuse more than :data:`MAX_RUNS` before anything
    is built: a few factors with many levels, or ``--reps 1000000``, would otherwise
    expand into more than any machine can hold (and a generator spec would first make
    every scenario)."""
    scenarios = model.scenario
    if isinstance(scenarios, dict):  # one per team size; the spec is validated later
        sizes = scenarios.get("robots")
        n_scenarios = len(sizes) if isinstance(sizes, list) else 1
    else:
        n_scenarios = len(scenarios) if isinstance(scenarios, list) else 1
    names = list(levels)
    # Exclusions only lower the count, so the product bounds it without listing any.
    combos = max(n_scenarios, 1) * math.prod(len(levels[n]) for n in names)
    if combos > MAX_RUNS:
        raise InputError(
            f"the factors multiply to {combos:,} configurations; at most {MAX_RUNS:,} runs "
            "per sweep (split it, or drop levels)",
            file=path,
            field="factors",
        )
    if model.exclude:  # at most MAX_RUNS combinations: cheap to count exactly
        kept = sum(
            not _excluded(dict(zip(names, combo, strict=True)), model.exclude)
            for combo in itertools.product(*(levels[n] for n in names))
        )
        combos = max(n_scenarios, 1) * kept
    if repetitions is not None and repetitions < 1:
        raise InputError(f"must be at least 1, got {repetitions}", field="--reps")
    reps = model.repetitions if repetitions is None else repetitions
    check_run_count(combos, reps, path, given_reps=repetitions)


def _expand(
    model: ExperimentModel, path: Path, yaml_text: str, repetitions: int | None = None
) -> Experiment:
    name = model.name or path.stem
    levels = _levels(model, path)
    _check_exclude(model, levels, path)
    _check_size(model, levels, path, repetitions)
    scenarios = _scenarios(model, path)
    base = path.parent
    params = _flat_params(model.params, path)
    written = {**model.options, **params}
    options = {
        k: (_resolve_path(v, base, f"options.{k}", path) if k in PATH_FIELDS else v)
        for k, v in written.items()
    }
    for key in PATH_FIELDS:
        for v in levels.get(key, []):
            _resolve_path(v, base, f"factors.{key}", path)
    names = list(levels)
    configurations: list[Configuration] = []
    labels: dict[str, str] = {}
    for _written, scenario_path, scenario_name in scenarios:
        for combo in itertools.product(*(levels[n] for n in names)):
            chosen = dict(zip(names, combo, strict=True))
            if _excluded(chosen, model.exclude):
                continue
            given = {
                **options,
                **{
                    k: (_resolve_path(v, base, f"factors.{k}", path) if k in PATH_FIELDS else v)
                    for k, v in chosen.items()
                },
            }
            config = _build(
                {"scenario": scenario_path, **given, "seed": 0}, levels, path, set(params)
            )
            label = _make_label(config, chosen, levels, scenario_name, len(scenarios) > 1)
            if label in labels:
                raise InputError(
                    f"two configurations share the label {label}", file=path, field="factors"
                )
            # The id covers what was *given* (not defaults), as normalised by RunConfig,
            # with paths as written: stable when RunConfig gains a field, and the same
            # on every machine.
            dumped = _given_content(config, given)
            for k in PATH_FIELDS:
                if k in given:
                    dumped[k] = str(chosen.get(k, written.get(k)))
            content = {
                "experiment": name,
                "base_seed": model.base_seed,
                "scenario": scenario_name,
                "options": dumped,
                **config.id_content(),
            }
            config_id = make_config_id(label, content)
            labels[label] = config_id
            configurations.append(Configuration(config_id, name, label, scenario_name, config))
    if not configurations:
        raise InputError(
            "empty factorial: every combination is excluded", file=path, field="exclude"
        )
    return Experiment(
        name=name,
        path=path,
        yaml_text=yaml_text,
        description=model.description,
        repetitions=model.repetitions,
        base_seed=model.base_seed,
        configurations=tuple(configurations),
    )


def _given_content(config: RunConfig, given: dict[str, Any]) -> dict[str, Any]:
    """What the configuration id covers of the given options, normalised: RunConfig's
    own fields as it dumps them, legacy options and parameters as JSON values."""
    fields = {k for k in given if k in RunConfig.model_fields}
    dumped: dict[str, Any] = config.model_dump(mode="json", include=fields)
    for key in given.keys() - fields:
        value = given[key]
        if key in LEGACY_OPTIONS and isinstance(value, int | float) and not isinstance(value, bool):
            value = float(value)  # as the RunConfig field of earlier versions dumped it
        dumped[key] = (
            value if isinstance(value, str | int | float | bool) or value is None else str(value)
        )
    return dumped


def _make_label(
    config: RunConfig,
    chosen: dict[str, Any],
    levels: dict[str, list[Any]],
    scenario_name: str,
    many_scenarios: bool,
) -> str:
    parts = [re.sub(r"[^A-Za-z0-9.+-]", "", scenario_name)] if many_scenarios else []
    parts.append(config.label())
    parts += [
        _label_part(k, v)
        for k, v in chosen.items()
        if k not in LABEL_FACTORS and len(levels[k]) > 1
    ]
    return "_".join(parts)
