"""The conformance checks (see :mod:`mrcomm.testing`), each a function of a variant's
spec returning a :class:`CheckResult`."""

from __future__ import annotations

import inspect
import json
import math
import os
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from mrcomm.bundled import data_root
from mrcomm.specs import VariantSpec, parameter_names

S1 = data_root() / "scenarios" / "s1.yaml"
S1_TRACE = data_root() / "traces" / "s1_synthetic_esd.csv"
#: Modules agent-side code must never import: simulators and transports.
FORBIDDEN_IN_AGENTS = (
    "zenoh",
    "mrcomm.sim",
    "mrcomm.live",
    "mrcomm.net.inprocess",
    "mrcomm.net.zenoh_bus",
    "mrcomm.robot.base",
)


@dataclass(frozen=True)
class CheckResult:
    check: str
    passed: bool
    detail: str
    seconds: float = 0.0


def mission_config(spec: VariantSpec, *, spl: float = 0.0, seed: int = 1) -> Any:
    """The S1 mission that exercises ``spec``: behaviours on AH with SLT (so LF
    switches); thresholds and network models with LF (which reacts to them); a utility
    as LF's ``behaviour.utility``."""
    from mrcomm.run.config import make_config

    options: dict[str, Any] = {"network": "ah", "threshold": "slt", "behaviour": "lf"}
    params: dict[str, dict[str, Any]] = {}
    if spec.kind == "behaviour":
        options["behaviour"] = spec.name
    elif spec.kind == "threshold":
        options["threshold"] = spec.name
        if spec.network_types is not None and "ah" not in spec.network_types:
            options["network"] = sorted(spec.network_types)[0]
        if spec.pulse:  # its robots' pulses replay S1's synthetic trace
            params["threshold"] = {"trace": str(S1_TRACE)}
    elif spec.kind == "network":
        options["network"] = spec.name
    elif spec.kind == "utility":
        params["behaviour"] = {"utility": spec.name}
    return make_config(None, scenario=S1, spl=spl, seed=seed, params=params, **options)


# -- api --------------------------------------------------------------------------------


def check_api(spec: VariantSpec) -> str:
    """Raises AssertionError with what is wrong; returns a short summary."""
    model = spec.params_model()
    params = model()
    undocumented = [n for n, f in model.model_fields.items() if not f.description]
    assert not undocumented, f"parameters without a description: {undocumented}"
    entry = spec.load()
    if spec.kind == "behaviour":
        from mrcomm.agents.executor import TaskExecutor

        assert isinstance(entry, type) and issubclass(entry, TaskExecutor), (
            f"{entry!r} is not a TaskExecutor subclass"
        )
        assert issubclass(model, entry.Params), (
            f"the spec's params {model.__name__} are not the executor's {entry.Params.__name__}"
        )
        assert entry.uses_aon == spec.uses_aon, (
            f"the executor's uses_aon is {entry.uses_aon}, the spec says {spec.uses_aon}"
        )
    elif spec.kind == "threshold":
        from mrcomm.net.thresholds import Threshold
        from mrcomm.run.resources import ScenarioResources

        assert isinstance(entry, type) and issubclass(entry, Threshold)
        for method in ("build", "sensor"):
            assert getattr(entry, method).__func__ is not getattr(Threshold, method).__func__, (
                f"{entry.__name__} does not implement {method}"
            )
        resources = ScenarioResources.load(S1)
        if spec.pulse:
            params = spec.make_params({"trace": str(S1_TRACE)})
        entry.build(params, resources, ("robot_1", "robot_2"))
        entry.sensor(params, resources)
    elif spec.kind == "network":
        from mrcomm.net.network import NetworkModel

        assert isinstance(entry, type) and issubclass(entry, NetworkModel)
        if entry.needs_walls:
            return _check_power_model(entry, params)
        network = entry(params)
        rng = np.random.default_rng(0)
        distance = rng.uniform(0.0, 3.0 * min(network.reach_m, 30.0), (6, 6))
        distance = (distance + distance.T) / 2
        np.fill_diagonal(distance, 0.0)
        connected = network.connected(distance)
        assert connected.shape == (6, 6) and connected.dtype == np.bool_
        for (a, b), d in np.ndenumerate(distance):
            assert bool(connected[a, b]) == network.in_range(float(d)), (
                f"connected() and in_range() disagree at {d:.2f} m"
            )
    elif spec.kind == "utility":
        from mrcomm.agents.utility import UtilityInputs

        assert callable(entry)
        for goal in (None, 0.05, 1.0, 25.0):
            for n in (0, 1, 4):
                for just in (False, True):
                    u = entry(UtilityInputs(goal, n, just))
                    assert isinstance(u, float) and math.isfinite(u), f"utility gave {u!r}"
                    if n == 0:
                        assert u == 0.0, f"an idle robot must have utility 0, got {u}"
    return f"{spec.kind} {entry.__name__ if hasattr(entry, '__name__') else entry}"


def _check_power_model(entry: Any, params: Any) -> str:
    """A network model that decides range from received power: on S1's map, for random
    free positions, the link model gets a finite power for every link, the same in
    both directions up to the model's fixed offsets, and a boolean range matrix."""
    from mrcomm.net.links import LinkModel
    from mrcomm.net.thresholds import NoThreshold
    from mrcomm.run.resources import ScenarioResources

    resources = ScenarioResources.load(S1)
    network = entry.build(params, resources, 1)
    grid = resources.scenario.grid
    rng = np.random.default_rng(0)
    free = np.argwhere(~grid.inflated(0.3).occupied)
    cells = free[rng.choice(len(free), 5, replace=False)]
    xy = [grid.cell_to_world(int(iy), int(ix)) for iy, ix in cells]
    ids = tuple(f"n{i}" for i in range(5))
    state = LinkModel(ids, grid, network, NoThreshold()).update(xy, 0.0)
    assert state.power is not None, "the link model got no received power"
    assert state.connected.shape == (5, 5) and state.connected.dtype == np.bool_
    off = ~np.eye(5, dtype=np.bool_)
    assert np.isfinite(state.power[off]).all(), "a link without a finite power"
    reciprocal = state.power - network.offsets(5)
    assert np.allclose(reciprocal[off], reciprocal.T[off]), "mean power is not reciprocal"
    return f"network {entry.__name__}: power and range of 5 nodes on S1"


# -- determinism and deadlock ----------------------------------------------------------


def comparable(result: Any) -> str:
    """A run's result without wall time, timelines included, as canonical JSON."""
    summary = dict(result.summary())
    summary.pop("wall_time_s")
    summary["timelines"] = {
        rid: [(i.track, i.label, i.start, i.end) for i in tl.intervals]
        + [(e.time, e.label) for e in tl.events]
        for rid, tl in result.timelines.items()
    }
    return json.dumps(summary, sort_keys=True, default=str)


def check_determinism(spec: VariantSpec) -> str:
    from mrcomm.run.resources import ScenarioResources
    from mrcomm.sim.mission import run_mission

    resources = ScenarioResources.load(S1)
    first = comparable(run_mission(mission_config(spec, spl=25, seed=3), resources))
    again = comparable(run_mission(mission_config(spec, spl=25, seed=3), resources))
    assert first == again, "the same configuration and seed gave different results"
    other = comparable(run_mission(mission_config(spec, spl=25, seed=4), resources))
    assert other != first, "a different seed gave the same result: is the seed used?"
    return "seed 3 twice identical; seed 4 differs"


def check_no_deadlock(spec: VariantSpec) -> str:
    from mrcomm.run.resources import ScenarioResources
    from mrcomm.sim.mission import run_mission

    resources = ScenarioResources.load(S1)
    ends = []
    for seed in (1, 2):
        result = run_mission(mission_config(spec, spl=50, seed=seed), resources)
        assert not result.mission["timed_out"], (
            f"seed {seed}: the mission hit its time limit at SPL 50"
        )
        ends.append(f"{result.sim_time_s:.0f} s")
    return "S1 at SPL 50 ends in " + ", ".join(ends)


# -- the two buses -----------------------------------------------------------------------


def check_same_decisions(spec: VariantSpec, steps: int = 600) -> str:
    from mrcomm.testing.buses import compare_buses

    if "live" not in spec.modes:
        return "simulation only (no live mode): nothing to compare"
    compared = compare_buses(mission_config(spec, spl=50, seed=5), steps)
    return f"{compared} delivery decisions identical on both buses"


# -- one assembly -----------------------------------------------------------------------


def check_assembly(spec: VariantSpec) -> str:
    """Every parameter of the variant set to a value other than its default: the
    simulation and a live agent process build robot_1's executor alike."""
    from mrcomm.testing.assembly import compare_assembly, non_default_values

    if "live" not in spec.modes:
        return "simulation only (no live mode): nothing to compare"
    from mrcomm.run.config import make_config

    base = mission_config(spec)
    entry = spec.load()
    # Values live mode refuses (a network's simulation-only options) cannot be compared.
    refusal = getattr(entry, "live_refusal", None) if spec.kind == "network" else None
    values, missed = non_default_values(spec.params_model(), refusal)
    params = {kind: dict(section) for kind, section in base.params.items()}
    if spec.kind == "behaviour":
        params.setdefault("behaviour", {}).update(values)
    elif values:  # the variant's own section: it reaches this variant only
        params.setdefault(spec.kind, {})[spec.name] = values
    config = make_config(None, **{**base.model_dump(exclude={"params"}), "params": params})
    made = compare_assembly(config)
    varied = f"{len(parameter_names(spec.params_model())) - len(missed)} parameters varied"
    left = f" ({', '.join(missed)} left at their defaults)" if missed else ""
    return f"{made['class'].rsplit('.', 1)[-1]} the same in simulation and live, {varied}{left}"


# -- layering ----------------------------------------------------------------------------


def check_layering(spec: VariantSpec) -> str:
    if spec.kind not in ("behaviour", "utility"):
        return "not agent-side code: nothing to check"
    entry = spec.load()
    module = inspect.getmodule(entry)
    assert module is not None, f"cannot tell the module of {entry!r}"
    code = f"import sys, json; import {module.__name__}; print(json.dumps(sorted(sys.modules)))"
    # The child sees this process's path: a plugin found here is found there.
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, env=env
    )
    assert done.returncode == 0, f"importing {module.__name__} failed: {done.stderr[-300:]}"
    loaded = json.loads(done.stdout)
    bad = [m for m in loaded if any(m == f or m.startswith(f + ".") for f in FORBIDDEN_IN_AGENTS)]
    assert not bad, f"{module.__name__} imports {', '.join(bad)}"
    return f"{module.__name__} imports no simulator or transport"


#: Every check, by name, in the order they run.
CHECKS: dict[str, Callable[[VariantSpec], str]] = {
    "api": check_api,
    "determinism": check_determinism,
    "no_deadlock": check_no_deadlock,
    "same_decisions": check_same_decisions,
    "assembly": check_assembly,
    "layering": check_layering,
}


def check_variant(
    spec: VariantSpec,
    only: list[str] | None = None,
    starting: Callable[[str], None] | None = None,
) -> list[CheckResult]:
    """Run the checks (all, or ``only`` these) on ``spec``; a check that fails does not
    stop the others. ``starting(name)`` is called as each check starts (progress)."""
    from mrcomm.specs import REGISTRY

    with REGISTRY.registered(spec):
        return _run_checks(spec, only, starting)


def _run_checks(
    spec: VariantSpec, only: list[str] | None, starting: Callable[[str], None] | None
) -> list[CheckResult]:
    results = []
    for name, check in CHECKS.items():
        if only and name not in only:
            continue
        if starting is not None:
            starting(name)
        start = time.perf_counter()
        try:
            detail, passed = check(spec), True
        except AssertionError as err:
            detail, passed = str(err) or "assertion failed", False
        except Exception as err:  # a broken variant is a failed check, not a crash
            detail, passed = f"{type(err).__name__}: {err}", False
        results.append(
            CheckResult(name, passed, " ".join(detail.split()), time.perf_counter() - start)
        )
    return results
