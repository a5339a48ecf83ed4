"""Ad-hoc runs: ONE finished mission (``mrcomm run``, ``live`` or ``collect`` with
``--db``) stored in a results database, next to sweeps (docs/RESULTS.md, "Ad-hoc runs").

* The run belongs to an ad-hoc experiment (``--experiment``, default ``adhoc``),
  registered with base seed 0 and ``schema_path`` :data:`ADHOC_SOURCE`, so that a sweep
  never takes it for one of its own and an ad-hoc run never joins a sweep's experiment.
* Its configuration's id covers the experiment, the mode, the scenario and every option
  given except the seed. Options at their default are left out (as in sweeps: a new
  RunConfig field keeps the ids); paths are absolute. A live configuration therefore
  never shares an id with a simulated one, and its label ends in ``_LIVE``.
* The repetition is the next free number of that configuration; the seed is the
  run's own. A run already stored is not stored again: a simulated run with the same
  configuration, seed and input files (it would give the same result), or a live run
  from the same record (``collect`` twice). ``keep_duplicate`` stores it anyway.
* The experiment's ``schema_yaml`` lists every run stored in it with its mode, seed,
  options and the command that reproduces it.

:func:`check_target` runs before the mission (read-only, so bad input fails before any
work); :func:`store_result` after it, writing experiment, configuration and every
table of the run in one transaction.
"""

from __future__ import annotations

import hashlib
import json
import re
import shlex
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from mrcomm.errors import InputError
from mrcomm.experiment.rows import result_rows
from mrcomm.experiment.schema import Configuration, Experiment, RunSpec
from mrcomm.experiment.seeds import make_config_id, make_run_id
from mrcomm.experiment.store import ResultStore, inspect_database
from mrcomm.experiment.tables import RUN_MODES
from mrcomm.run.config import RunConfig, make_config, param_assignments
from mrcomm.run.provenance import fingerprint, input_hashes
from mrcomm.run.result import MissionResult

#: ``experiments.schema_path`` of an ad-hoc experiment (sweeps hold their schema file).
ADHOC_SOURCE = "mrcomm:adhoc"
DEFAULT_EXPERIMENT = "adhoc"
#: Options of a live run beyond RunConfig, with their defaults: a default is left out
#: of the configuration's id, so ``collect`` (which sees only the record) and ``live``
#: give the same id to the same default run.
LIVE_DEFAULTS: dict[str, Any] = {
    "speed": 1.0,
    "lease": None,
    "protocol": "tcp",
    "team_dir": None,
    "insecure": False,
    "agent_clock": "shared",
    "base": "native",
    "emulate": False,
}
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]*$")
_HEADER = (
    "# Ad-hoc runs stored by `mrcomm run|live|collect --db` (not a sweep schema): each\n"
    "# entry gives the mode, seed and options (with the command) that reproduce it.\n"
)


@dataclass(frozen=True)
class StoredRun:
    """Where :func:`store_result` put a run."""

    db_path: Path
    experiment: str
    config_id: str
    run_id: str
    repetition: int
    mode: str
    #: False: the same run was already stored (as ``run_id``); nothing was written.
    new: bool = True

    def describe(self) -> str:
        if not self.new:
            return (
                f"already stored as {self.run_id} (same configuration, seed and inputs"
                f"{' and record' if self.mode == 'live' else ''}) in {self.db_path}: "
                "not stored again (--keep-duplicate stores a copy)"
            )
        return (
            f"stored as {self.run_id} (experiment {self.experiment}, mode {self.mode}) "
            f"in {self.db_path}"
        )


def check_target(db_path: Path, experiment: str = DEFAULT_EXPERIMENT) -> None:
    """Refuse (InputError) a bad experiment name, a database that is not a results
    database of this version or is in use, or an experiment that is a sweep's.
    Read-only: the file is never modified."""
    if not _NAME.match(experiment):
        raise InputError(
            f"{experiment!r} is not a valid name (letters, digits, '_', '.', '-')",
            field="--experiment",
        )
    source = inspect_database(db_path).sources.get(experiment)
    if source is not None and source != ADHOC_SOURCE:
        raise InputError(
            f"experiment '{experiment}' in this database is a sweep of {source}; "
            "store ad-hoc runs under another --experiment",
            file=db_path,
            field="--experiment",
        )


def store_result(
    db_path: Path,
    result: MissionResult,
    *,
    experiment: str = DEFAULT_EXPERIMENT,
    live_options: dict[str, Any] | None = None,
    run_fingerprint: str | None = None,
    keep_duplicate: bool = False,
) -> StoredRun:
    """Store one finished run. The mode is the result's own (``config['mode']``, 'sim'
    when absent); ``live_options`` are the live command's options beyond RunConfig
    (:data:`LIVE_DEFAULTS`; a live result's recorded speed is taken from it).
    ``run_fingerprint`` identifies a live run (its record; see
    :func:`mrcomm.live.collect.record_fingerprint`); a simulated run's is computed."""
    check_target(db_path, experiment)
    mode = str(result.config.get("mode", "sim"))
    if mode not in RUN_MODES:
        raise ValueError(f"unknown mode {mode!r}")
    config = _absolute(_run_config(result))
    extra = _extra_options(mode, result, live_options or {})
    # The scenario has no default, so it is always among the options.
    options = {**config.model_dump(mode="json", exclude_defaults=True, exclude={"seed"}), **extra}
    scenario_name = str(result.config.get("scenario_name") or result.scenario.name)
    label = config.label() + ("_LIVE" if mode == "live" else "")
    content = {
        "experiment": experiment,
        "mode": mode,
        "scenario": scenario_name,
        "options": options,
        **config.id_content(),
    }
    config_id = make_config_id(label, content)
    configuration = Configuration(
        config_id,
        experiment,
        label,
        scenario_name,
        config.model_copy(update={"seed": 0}),
        extra_options=extra,
    )
    if mode == "live" and run_fingerprint is None:
        raise ValueError("a live run is stored with the fingerprint of its record")
    store = ResultStore.open(db_path)
    try:
        hashes = input_hashes(config)
        if result.operator:  # an operator's commands change the run: part of what it is
            commands = json.dumps(result.operator.get("commands", []), sort_keys=True)
            hashes = {**hashes, "operator": hashlib.sha256(commands.encode()).hexdigest()}
        run_fingerprint = run_fingerprint or fingerprint(config_id, config.seed, hashes)
        earlier = store.run_with_fingerprint(run_fingerprint)
        if earlier is not None and not keep_duplicate:
            run_id, repetition = earlier
            return StoredRun(
                Path(db_path), experiment, config_id, run_id, repetition, mode, new=False
            )
        # Numbered with the write lock held: no other writer can take the same number.
        repetition = store.next_repetition(config_id)
        spec = RunSpec(
            run_id=make_run_id(config_id, repetition),
            config_id=config_id,
            experiment=experiment,
            label=label,
            scenario_name=scenario_name,
            repetition=repetition,
            seed=config.seed,
            config=config,
            mode=mode,
        )
        entry = {
            "run_id": spec.run_id,
            "mode": mode,
            "seed": config.seed,
            "command": command_line(mode, options, config.seed),
            "options": options,
        }
        registered = Experiment(
            name=experiment,
            path=Path(ADHOC_SOURCE),
            yaml_text=_yaml_text(experiment, store.experiment_yaml(experiment), entry),
            description="ad-hoc runs",
            repetitions=1,
            base_seed=0,
            configurations=(configuration,),
        )
        rows = result_rows(spec, result, result.wall_time_s, run_fingerprint)
        store.write_run(rows, experiment=registered)
    finally:
        store.close()
    return StoredRun(Path(db_path), experiment, config_id, spec.run_id, repetition, mode)


def command_line(mode: str, options: dict[str, Any], seed: int) -> str:
    """The ``mrcomm run`` / ``mrcomm live`` command of a run with these options."""
    words = ["mrcomm", "run" if mode == "sim" else "live", str(options["scenario"])]
    for key, value in options.items():
        if key == "scenario":
            continue
        if key == "params":
            config = RunConfig.model_construct(params=value)
            for item in param_assignments(config):
                words += ["--set", shlex.quote(item)]
            continue
        flag = "--" + key.replace("_", "-")
        if value is True:
            words.append(flag)
        elif isinstance(value, float):
            words += [flag, f"{value:g}"]
        else:
            words += [flag, str(value)]
    words += ["--seed", str(seed)]
    return " ".join(words)


def _run_config(result: MissionResult) -> RunConfig:
    values = {k: v for k, v in result.config.items() if k in RunConfig.model_fields}
    return make_config(None, **values)


def _absolute(config: RunConfig) -> RunConfig:
    """Paths resolved: the same file gives the same id from any working directory."""
    params = {kind: dict(section) for kind, section in config.params.items()}
    threshold = params.get("threshold", {})
    for key in ("model", "trace"):  # the threshold parameters that name files
        if threshold.get(key) is not None:
            threshold[key] = str(Path(threshold[key]).expanduser().resolve())
    scenario = Path(config.scenario).expanduser().resolve()
    return config.model_copy(update={"scenario": scenario, "params": params})


def _extra_options(mode: str, result: MissionResult, given: dict[str, Any]) -> dict[str, Any]:
    """The live options that differ from their default (none for a simulated run)."""
    unknown = sorted(set(given) - set(LIVE_DEFAULTS))
    if unknown:
        raise ValueError(f"unknown live option {unknown[0]!r}")
    if mode != "live":
        if given:
            raise ValueError("live options given for a simulated run")
        return {}
    values = {"speed": result.config.get("speed", LIVE_DEFAULTS["speed"]), **given}
    out: dict[str, Any] = {}
    for key, default in LIVE_DEFAULTS.items():
        value = values.get(key, default)
        if value is None or value == default:
            continue
        out[key] = str(Path(value).expanduser().resolve()) if key == "team_dir" else value
    return out


def _yaml_text(name: str, previous: str | None, entry: dict[str, Any]) -> str:
    """The experiment's ``schema_yaml``: the runs stored so far plus ``entry``."""
    runs: list[Any] = []
    if previous:
        try:
            loaded = yaml.safe_load(previous)
        except yaml.YAMLError:
            loaded = None
        if isinstance(loaded, dict) and isinstance(loaded.get("runs"), list):
            runs = loaded["runs"]
    body = {"name": name, "runs": [*runs, entry]}
    # No line folding: each command stays one line to copy.
    return _HEADER + yaml.safe_dump(body, sort_keys=False, default_flow_style=False, width=1 << 16)
