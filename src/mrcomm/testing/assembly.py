"""The assembly check: a run's agents are the same in every mode.

A variant's parameters are set to values other than their defaults
(:func:`non_default_values`), and the agents of one S1 run are built by the simulation
and by a live agent process (a Zenoh session on loopback, no world needed); what each
robot's executor was made with — its class, its parameters, the team's tie-break ranks,
its incarnation, its link sensor, what the scenario told it — must be equal
(:func:`executor_summary`). A plugin author learns here of a failure that only live
mode would show.
"""

from __future__ import annotations

import tempfile
import typing
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ValidationError

from mrcomm.agents.executor import TaskExecutor
from mrcomm.errors import InputError
from mrcomm.run.config import RunConfig
from mrcomm.specs import REGISTRY, parameter_names


def _value(model: BaseModel, name: str) -> Any:
    value: Any = model
    for part in name.split("."):
        value = getattr(value, part)
    return value


def _nested(flat: dict[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for name, value in flat.items():
        *outer, last = name.split(".")
        place = out
        for part in outer:
            place = place.setdefault(part, {})
        place[last] = value
    return out


def _field_annotation(model: type[BaseModel], name: str) -> Any:
    annotation: Any = model
    for part in name.split("."):
        annotation = annotation.model_fields[part].annotation
    return annotation


def _candidates(model: type[BaseModel], name: str, default: Any) -> list[Any]:
    """Values to try for parameter ``name`` instead of its ``default``."""
    choices = [
        a
        for arg in (
            _field_annotation(model, name),
            *typing.get_args(_field_annotation(model, name)),
        )
        for a in typing.get_args(arg)
        if typing.get_origin(arg) is typing.Literal
    ]
    if choices:
        return [c for c in choices if c != default]
    if isinstance(default, bool):
        return [not default]
    if isinstance(default, int):
        return [default + 1, default - 1, default * 2, 1, 0]
    if isinstance(default, float):
        return [default * 1.5, default * 0.75, default + 1.0, default - 0.5, 0.5, 1.0]
    if isinstance(default, str) and name.rsplit(".", 1)[-1] == "utility":  # LF's
        return [n for n in REGISTRY.names("utility") if n != default]
    if default is None:
        return [30.0, 1.0, 2, True]
    return []


def non_default_values(
    model: type[BaseModel], refuses: Callable[[BaseModel], str | None] | None = None
) -> tuple[dict[str, Any], list[str]]:
    """Parameters of ``model`` each set to a value other than its default that
    validates together with the others (nested as a parameter section is) and that
    ``refuses`` (e.g. live mode's refusals) does not refuse, and the names no value
    could be found for."""
    defaults = model.model_validate({})
    chosen: dict[str, Any] = {}
    missed: list[str] = []
    for name in parameter_names(model):
        default = _value(defaults, name)
        for candidate in _candidates(model, name, default):
            try:
                validated = model.model_validate(_nested({**chosen, name: candidate}))
            except (ValidationError, InputError):  # a value its own validator refuses
                continue
            if refuses is not None and refuses(validated) is not None:
                continue  # e.g. the shared channel, which live mode cannot run
            if _value(validated, name) != default:
                chosen[name] = candidate
                break
        else:
            missed.append(name)
    return _nested(chosen), missed


def executor_summary(executor: TaskExecutor, robots: tuple[str, ...]) -> dict[str, Any]:
    """What an executor was made with, as plain data."""
    statuses = executor.statuses
    return {
        "class": f"{type(executor).__module__}.{type(executor).__qualname__}",
        "params": executor.params.model_dump(mode="json"),
        "ranks": [executor.rank(r) for r in robots],
        "incarnation": executor.incarnation,
        "link_sensor": type(executor.link_sensor).__name__,
        "link_sensor_settings": _plain(vars(executor.link_sensor)),
        "queues_at_passages": executor.queue is not None,
        "statuses": type(statuses).__name__ if statuses is not None else None,
        "assigner_home": statuses.assigner_home if statuses is not None else None,
        "assigner_host": statuses.assigner_host if statuses is not None else None,
    }


def _plain(values: dict[str, Any]) -> dict[str, Any]:
    """The scalar settings among an object's attributes."""
    return {k: v for k, v in values.items() if isinstance(v, int | float | str | bool | None)}


def network_summary(network: Any) -> dict[str, Any]:
    """What a network model was made with, as plain data."""
    return {**network.describe(), **_plain(vars(network))}


def simulated_executors(config: RunConfig) -> dict[str, dict[str, Any]]:
    """Each robot's executor summary as the simulation builds it (and, as
    ``network``, its network model's)."""
    from mrcomm.sim.mission import Mission

    mission = Mission(config)
    made = {r: executor_summary(e, mission.robot_ids) for r, e in mission.executors.items()}
    relay = mission.network.relay
    network = {**network_summary(mission.links.network), "relay_hops": relay.hops if relay else 0}
    return {**made, "network": network}


@contextmanager
def live_agent(config: RunConfig, robot: str, record_dir: Path) -> Iterator[Any]:
    """A live agent process of ``robot`` (built, not run: its Zenoh session listens
    on loopback only), closed at the end."""
    from mrcomm.live.agent import AgentProcess
    from mrcomm.live.settings import LiveSettings
    from mrcomm.net.zenoh_config import make_options

    options = make_options(team="assembly-check", listen=["tcp/127.0.0.1:0"], multicast=False)
    process = AgentProcess(LiveSettings(config, options, record_dir), robot, incarnation=1)
    try:
        yield process
    finally:
        process._finish()


def live_executor(config: RunConfig, robot: str) -> dict[str, Any]:
    """``robot``'s executor summary as a live agent process builds it."""
    with (
        tempfile.TemporaryDirectory(prefix="mrcomm-assembly-") as record,
        live_agent(config, robot, Path(record)) as process,
    ):
        executor = process.executor
        assert executor is not None, f"the live process of {robot} has no executor"
        summary = executor_summary(executor, process.robot_ids)
        rules = process.bus.rules
        network = {**network_summary(rules.network), "relay_hops": rules.relay_hops}
        return {**summary, "network": network}


def compare_assembly(config: RunConfig, robot: str = "robot_1") -> dict[str, Any]:
    """``robot``'s executor summary, the same in simulation and live (AssertionError
    naming the first difference otherwise)."""
    everyone = simulated_executors(config)
    simulated = {**everyone[robot], "network": everyone["network"]}
    live = live_executor(config, robot)
    for key, value in simulated.items():
        assert live[key] == value, f"{key}: simulation {value!r}, live agent {live[key]!r}"
    return simulated
