"""The run options, declared once and shared by every command that starts a run
(``run``, ``live``, ``world``, ``agent``; ``sweep`` takes ``--set``), as zenoh-python's
examples share one set of connection options: each option's type, default and help
here, and one function that turns them into a validated
:class:`~mrcomm.run.config.RunConfig`.

``--set KIND.KEY=VALUE`` sets a parameter of the chosen variant of that kind
(``behaviour.utility=greedy``, ``threshold.warning_dbm=-41``, ``network.range_m=10``,
``behaviour.collision.danger_radius=1.2``); the value is read as YAML (numbers, true /
false, null, strings). ``mrcomm variants`` lists every parameter. ``robot.KEY`` sets the
robots' run-to-run variation (``robot.variation=realistic``; docs/ROBOT.md).
"""

from __future__ import annotations

import functools
import inspect
import typing
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any

import typer
import yaml

from mrcomm.errors import InputError, did_you_mean

ScenarioArg = Annotated[
    Path,
    typer.Argument(
        help="Scenario YAML, or a bundled scenario's name: s1, s2, s3, s4, campus1000 "
        "(`mrcomm scenario list`)."
    ),
]
NetworkOpt = Annotated[
    str, typer.Option(help="Network model (see `mrcomm variants`): wlan, ah, ...")
]
SplOpt = Annotated[float, typer.Option(help="Simulated packet loss, percent (0-100).")]
BehaviourOpt = Annotated[
    str, typer.Option(help="Team behaviour (see `mrcomm variants`): nb, lf, ...")
]
ThresholdOpt = Annotated[
    str, typer.Option(help="Signal threshold (see `mrcomm variants`): none, slt, ssd, esd, ...")
]
SeedOpt = Annotated[int, typer.Option(help="Random seed of the run.")]
MaxTimeOpt = Annotated[float, typer.Option(help="Mission time limit, simulated s.")]
DtOpt = Annotated[float, typer.Option(help="Simulation step (live: clock tick), simulated s.")]
RssiTraceOpt = Annotated[
    Path | None,
    typer.Option(
        help="ESD: recorded RSSI trace CSV (time,from,to,rssi) replayed by the robots' "
        "pulses, or a bundled trace's name (s1_synthetic_esd); same as "
        "--set threshold.trace=PATH."
    ),
]
SignalModelOpt = Annotated[
    Path | None,
    typer.Option(
        help="SSD: signal model JSON (default: bundled); same as --set threshold.model=PATH."
    ),
]
SetOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--set",
        metavar="KIND.KEY=VALUE",
        help="Set a variant parameter, e.g. behaviour.utility=greedy (repeatable; "
        "`mrcomm variants` lists them), or the robots' run-to-run variation, e.g. "
        "robot.variation=realistic (docs/ROBOT.md).",
    ),
]

SET_KINDS = ("network", "behaviour", "threshold", "robot")


def _run_options(
    scenario: ScenarioArg,
    network: NetworkOpt = "wlan",
    spl: SplOpt = 0.0,
    behaviour: BehaviourOpt = "nb",
    threshold: ThresholdOpt = "none",
    seed: SeedOpt = 1,
    max_time: MaxTimeOpt = 1800.0,
    dt: DtOpt = 0.1,
    rssi_trace: RssiTraceOpt = None,
    signal_model: SignalModelOpt = None,
    sets: SetOpt = None,
) -> None:
    """The run options every run-starting command takes (their one declaration)."""


def with_run_options(command: Callable[..., None]) -> Callable[..., None]:
    """Give a command the run options. ``command``'s first parameter is ``run``: it
    receives the validated RunConfig built from them; its other parameters follow
    the run options on the command line."""
    first = next(iter(inspect.signature(command).parameters))
    if first != "run":
        raise TypeError(f"{command.__name__}: the first parameter must be 'run'")
    return expand_parameter(command, "run", _run_options, run_config)


def expand_parameter(
    command: Callable[..., None],
    name: str,
    declaration: Callable[..., object],
    make: Callable[..., Any],
    names: dict[str, Any] | None = None,
) -> Callable[..., None]:
    """``command`` with its parameter ``name`` replaced, on the command line, by the
    parameters of ``declaration`` (options declared once for several commands); the
    command receives ``make(**their values)`` as ``name``. The parameters after it
    become keyword-only (a command's own required option may follow the defaults).
    ``names``: types the command's annotations name only when type checking."""
    own = inspect.signature(command)
    shared = list(inspect.signature(declaration).parameters.values())
    keys = [p.name for p in shared]
    # Typer reads the annotations: resolve them here, in each function's own module
    # (commands name RunConfig only when type checking).
    from mrcomm.run.config import RunConfig

    local = {"RunConfig": RunConfig, **(names or {})}
    hints = {
        **typing.get_type_hints(declaration, include_extras=True),
        **typing.get_type_hints(command, localns=local, include_extras=True),
    }
    parameters: list[inspect.Parameter] = []
    after = False
    for p in own.parameters.values():
        if p.name == name:
            kind = inspect.Parameter.KEYWORD_ONLY if parameters else p.kind
            parameters += [s.replace(annotation=hints[s.name], kind=kind) for s in shared]
            after = True
        elif after:
            parameters.append(
                p.replace(annotation=hints[p.name], kind=inspect.Parameter.KEYWORD_ONLY)
            )
        else:
            parameters.append(p.replace(annotation=hints[p.name]))
    if not after:
        raise TypeError(f"{command.__name__} has no parameter {name!r}")

    @functools.wraps(command)
    def wrapper(*args: Any, **kwargs: Any) -> None:
        options = {key: kwargs.pop(key) for key in keys}
        command(*args, **{name: make(**options)}, **kwargs)

    del wrapper.__wrapped__  # typer must see the new signature, not the command's
    wrapper.__signature__ = own.replace(parameters=parameters)  # type: ignore[attr-defined]
    wrapper.__annotations__ = {p.name: p.annotation for p in parameters} | {"return": None}
    return wrapper


def parse_assignments(items: list[str] | None, field: str = "--set") -> dict[str, dict[str, Any]]:
    """``["behaviour.utility=greedy", ...]`` -> ``{"behaviour": {"utility": "greedy"}}``
    (dotted keys nest); a malformed item is a one-line error."""
    params: dict[str, dict[str, Any]] = {}
    for item in items or []:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise InputError(f"expected KIND.KEY=VALUE, got {item!r}", field=field)
        kind, _, rest = key.partition(".")
        if kind not in SET_KINDS:
            raise InputError(
                f"unknown parameter section {kind!r}{did_you_mean(kind, SET_KINDS)} in "
                f"{item!r}; sections: {', '.join(SET_KINDS)}",
                field=field,
            )
        if not rest:
            raise InputError(f"expected KIND.KEY=VALUE, got {item!r}", field=field)
        try:
            value = yaml.safe_load(text) if text.strip() else ""
        except yaml.YAMLError:
            value = text
        node: dict[str, Any] = params.setdefault(kind, {})
        *outer, last = rest.split(".")
        for part in outer:
            inner = node.setdefault(part, {})
            if not isinstance(inner, dict):
                raise InputError(f"{kind}.{part} is set twice, as a value and as a section")
            node = inner
        node[last] = value
    return params


def run_config(
    *,
    scenario: Path,
    network: str,
    spl: float,
    behaviour: str,
    threshold: str,
    seed: int,
    max_time: float,
    dt: float,
    sets: list[str] | None = None,
    rssi_trace: Path | None = None,
    signal_model: Path | None = None,
) -> Any:
    """The validated RunConfig of a command line (``--set`` wins over the shortcuts)."""
    from mrcomm.bundled import resolve
    from mrcomm.run.config import make_config

    params = parse_assignments(sets)
    scenario = resolve(scenario, "scenario")
    if rssi_trace is not None:
        rssi_trace = resolve(rssi_trace, "trace")
    shortcuts = {"rssi_trace": rssi_trace, "signal_model": signal_model}
    given = {k: v for k, v in shortcuts.items() if v is not None}
    try:
        config = make_config(
            None,
            scenario=scenario,
            network=network,
            spl=spl,
            behaviour=behaviour,
            threshold=threshold,
            seed=seed,
            max_time=max_time,
            dt=dt,
            params=params,
            **given,
        )
    except InputError as err:
        raise InputError(err.message, field=_option_name(err.field)) from None
    return config


def warn_ignored_settings(config: Any) -> None:
    """Say in one line per setting that it changes nothing (called once every check
    has passed, just before the work: bad input still gets a single line)."""
    for warning in config.ignored_settings():
        typer.echo(f"mrcomm: warning: {warning}", err=True)


def _option_name(field: str | None) -> str | None:
    """A RunConfig field as the command line spells it (``max_time`` -> ``--max-time``;
    ``params.behaviour.x`` and ``behaviour.x`` -> ``--set behaviour.x``)."""
    if field is None:
        return None
    field = field.removeprefix("params.")
    if "." in field:
        return f"--set {field}"
    return "--" + field.replace("_", "-")
