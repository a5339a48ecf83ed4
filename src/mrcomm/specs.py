"""Variants as specs: the registry of behaviours, thresholds, network models and
utility functions, each with its validated parameters.

A *variant* is one registered :class:`VariantSpec`: a stable name and version (both go
into the configuration), the object that implements it (a class or function, or a
``"module:attribute"`` string loaded on first use, like Gymnasium's ``entry_point``),
a pydantic model of its parameters (defaults and units documented in its fields), and
what it needs and offers: the network models it works with, the topics it publishes,
the metrics it adds, whether it uses AON.

Built-in variants and users' plugins are found the same way: through the Python
entry-point group ``mrcomm.variants``, each entry naming a spec (or a list of specs)::

    [project.entry-points."mrcomm.variants"]
    wander = "my_package.wander:SPEC"

This module is a leaf: it imports nothing of MRComm but the error type, so any layer
may use it without import circles.
"""

from __future__ import annotations

import difflib
import importlib
import sys
from collections.abc import Iterable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from importlib.metadata import entry_points
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from mrcomm.errors import InputError, did_you_mean

Kind = Literal["behaviour", "threshold", "network", "utility"]
KINDS: tuple[Kind, ...] = ("behaviour", "threshold", "network", "utility")
ENTRY_POINT_GROUP = "mrcomm.variants"


def parameter(default: Any, description: str, unit: str | None = None, **limits: Any) -> Any:
    """A documented variant parameter: its default, what it means, its unit (shown by
    ``mrcomm variants``) and pydantic limits (``gt=0``...). Never NaN or infinite."""
    extra: Any = {"unit": unit} if unit else None
    if isinstance(default, int | float) and not isinstance(default, bool):
        limits.setdefault("allow_inf_nan", False)
    return Field(default, description=description, json_schema_extra=extra, **limits)


@dataclass(frozen=True)
class TeamMetric:
    """A team metric a behaviour adds: the sum over the robots of the per-robot metric
    of the same name (its spec's ``robot_metrics`` computes that). Stored with every
    run of the behaviour, tested and drawn by ``mrcomm analyze`` / ``mrcomm report``
    like MRComm's own metrics."""

    name: str
    #: What a figure or table calls it ("Rendezvous time").
    label: str
    #: Its unit ("s", "count", "m").
    unit: str
    #: The direction of the test of SPL 0 against SPL X: "less" = fewer at SPL 0.
    alternative: Literal["less", "greater", "two-sided"] = "less"


class NoParams(BaseModel):
    """A variant without parameters."""

    model_config = ConfigDict(frozen=True, extra="forbid")


@dataclass(frozen=True)
class VariantSpec:
    """One registered variant (see the module docstring)."""

    kind: Kind
    name: str
    #: The implementation, or ``"module:attribute"`` to import it on first use.
    entry: Any
    #: The model of its parameters, or ``"module:attribute"``.
    params: Any = NoParams
    version: int = 1
    summary: str = ""
    #: Network models it can be combined with (None: any).
    network_types: frozenset[str] | None = None
    #: Topics it publishes (behaviours) beyond the ones every executor uses.
    topics: tuple[str, ...] = ()
    #: Metrics it adds to a run's results.
    metrics: tuple[str, ...] = ()
    #: Behaviours: the function (or ``"module:function"``) computing the metrics it adds
    #: from one robot's timeline (None: none).
    robot_metrics: Any = None
    #: Behaviours: the team metrics it adds (each the sum of its robots' metric of
    #: that name), in the order results list them.
    team_metrics: tuple[TeamMetric, ...] = ()
    #: Thresholds: whether each robot measures its links with a pulse process (ESD):
    #: replayed from the threshold's ``trace`` parameter, or read off the radio model
    #: when it has none.
    pulse: bool = False
    #: Behaviours: whether task statuses travel with AON.
    uses_aon: bool = False
    #: Behaviours: whether an operator may move tasks between its robots or add tasks
    #: (reassign, add); sending a robot back (redo), pause and resume always apply.
    accepts_reassignment: bool = True
    #: Behaviours: whether it acts on the threshold's warnings (False: the threshold
    #: only shapes the recorded link statistics; runs with other thresholds are alike).
    uses_threshold: bool = True
    #: Run modes it supports ("sim": simulation; "live": separate processes over Zenoh).
    modes: frozenset[str] = frozenset({"sim", "live"})
    #: Where the variant came from: the distribution that registered it.
    origin: str = "mrcomm"
    #: Other names users give it ("adhoc" for ah): a mistyped name close to one of them
    #: is answered with this variant's name. Never accepted in its place (a run records
    #: one name per variant).
    aliases: tuple[str, ...] = ()

    @property
    def key(self) -> str:
        """``kind.name``, the name of its parameter section (``behaviour.lf``)."""
        return f"{self.kind}.{self.name}"

    @property
    def versioned(self) -> str:
        """``name-vN``: what configurations record."""
        return f"{self.name}-v{self.version}"

    def load(self) -> Any:
        """The implementation (imported on first use when given as a string)."""
        return _resolve(self.entry, self.key)

    def robot_metrics_function(self) -> Any:
        """The function computing its per-robot metrics (None: it adds none)."""
        return None if self.robot_metrics is None else _resolve(self.robot_metrics, self.key)

    def params_model(self) -> type[BaseModel]:
        model = _resolve(self.params, self.key)
        if not (isinstance(model, type) and issubclass(model, BaseModel)):
            raise TypeError(f"{self.key}: params must be a pydantic model, got {model!r}")
        return model

    def make_params(self, values: Mapping[str, Any], where: str | None = None) -> BaseModel:
        """Validate ``values`` (nested dicts for nested models) into the parameter model;
        a bad key or value is a one-line :class:`InputError` naming ``kind.key``."""
        return validate_params(
            self.params_model(), values, self.kind, f"{self.kind} {self.name!r}", where
        )


def validate_params(
    model: type[BaseModel],
    values: Mapping[str, Any],
    section: str,
    owner: str,
    where: str | None = None,
) -> BaseModel:
    """Validate ``values`` into ``model``; a bad key or value is a one-line
    :class:`InputError` naming ``section.key`` (``owner`` names whose parameters they
    are in the message about an unknown key)."""
    try:
        return model(**dict(values))
    except ValidationError as err:
        first = err.errors()[0]
        loc = ".".join(str(p) for p in first["loc"])
        field = f"{section}.{loc}" if loc else section
        if first["type"] == "extra_forbidden":
            known = parameter_names(model)
            message = (
                f"unknown parameter of {owner}{did_you_mean(loc, known)}; "
                f"it has {', '.join(known) if known else 'no parameters'}"
            )
        else:
            got = first.get("input")
            message = first["msg"].removeprefix("Value error, ")
            if not isinstance(got, Mapping) and repr(got) not in message:
                message += f", got {got!r}"
        raise InputError(message, file=where, field=field) from None


def suggest(name: str, specs: Iterable[VariantSpec]) -> str:
    """`` (did you mean 'x'?)`` for a mistyped variant name: by edit distance among the
    variants' names and their aliases (an alias answers with its variant's name)."""
    by_word: dict[str, str] = {}
    for spec in specs:
        by_word[spec.name] = spec.name
        for alias in spec.aliases:
            by_word.setdefault(_plain(alias), spec.name)
    exact = by_word.get(_plain(name))
    if exact is not None and exact != name:
        return f" (did you mean '{exact}'?)"
    close = difflib.get_close_matches(_plain(name), list(by_word), n=1, cutoff=0.6)
    return f" (did you mean '{by_word[close[0]]}'?)" if close else ""


def _plain(word: str) -> str:
    """A name as compared for suggestions: lower case, without - _ and spaces."""
    return "".join(c for c in word.lower() if c not in "-_ ")


def _resolve(target: Any, key: str) -> Any:
    if not isinstance(target, str):
        return target
    module, _, attribute = target.partition(":")
    try:
        obj: Any = importlib.import_module(module)
        for part in attribute.split(".") if attribute else ():
            obj = getattr(obj, part)
    except (ImportError, AttributeError) as err:
        raise InputError(f"cannot load {target!r}: {err}", field=key) from None
    return obj


def parameter_names(model: type[BaseModel], prefix: str = "") -> list[str]:
    """Every settable key of a parameter model, nested models as ``outer.inner``."""
    names: list[str] = []
    for name, info in model.model_fields.items():
        sub = info.annotation
        if isinstance(sub, type) and issubclass(sub, BaseModel):
            names += parameter_names(sub, f"{prefix}{name}.")
        else:
            names.append(f"{prefix}{name}")
    return names


class SpecRegistry:
    """Every variant, by kind and name. Entry points are read on first use."""

    def __init__(self, group: str = ENTRY_POINT_GROUP) -> None:
        self.group = group
        self._specs: dict[Kind, dict[str, VariantSpec]] = {k: {} for k in KINDS}
        self._discovered = False
        #: ``kind.name`` -> why the plugin registering it failed to load.
        self.broken: dict[str, str] = {}

    def register(self, spec: VariantSpec) -> VariantSpec:
        if spec.kind not in KINDS:
            raise ValueError(f"unknown variant kind {spec.kind!r}; kinds: {', '.join(KINDS)}")
        existing = self._specs[spec.kind].get(spec.name)
        if existing is not None and existing != spec:
            raise ValueError(
                f"{spec.kind} {spec.name!r} registered twice "
                f"(by {existing.origin} and by {spec.origin})"
            )
        self._specs[spec.kind][spec.name] = spec
        return spec

    @contextmanager
    def registered(self, spec: VariantSpec) -> Iterator[VariantSpec]:
        """``spec`` registered for the duration of a ``with`` block (unless it already
        is): checks and tests of variants that no entry point declares."""
        self.discover()
        known = self._specs[spec.kind].get(spec.name)
        if known is None:
            self.register(spec)
        try:
            yield spec
        finally:
            if known is None:
                del self._specs[spec.kind][spec.name]

    def get(self, kind: Kind, name: str) -> VariantSpec:
        self.discover()
        entries = self._specs[kind]
        try:
            return entries[name]
        except KeyError:
            broken = self.broken.get(f"{kind}.{name}")
            if broken is not None:
                raise InputError(broken, field=kind) from None
            raise InputError(
                f"unknown {kind} {name!r}{suggest(name, entries.values())}; "
                f"choose from {', '.join(sorted(entries))}",
                field=kind,
            ) from None

    def names(self, kind: Kind) -> list[str]:
        self.discover()
        return sorted(self._specs[kind])

    def all(self) -> list[VariantSpec]:
        self.discover()
        return [self._specs[k][n] for k in KINDS for n in sorted(self._specs[k])]

    def discover(self) -> None:
        """Register every spec the installed distributions declare (once)."""
        if self._discovered:
            return
        self._discovered = True
        found = entry_points(group=self.group)
        if not any(ep.dist is not None and ep.dist.name == "mrcomm" for ep in found):
            raise InputError(
                "MRComm's built-in variants are not registered: reinstall the package "
                "(`pip install -e .` or `make`)",
                field=self.group,
            )
        for ep in sorted(found, key=lambda e: (e.dist.name if e.dist else "", e.name)):
            origin = ep.dist.name if ep.dist is not None else "?"
            try:
                loaded = ep.load()
            except Exception as err:  # a broken plugin names itself, never a traceback
                self._refuse(ep.name, ep.value, origin, f"{type(err).__name__}: {err}")
                continue
            specs = list(loaded) if isinstance(loaded, Iterable) else [loaded]
            if not all(isinstance(spec, VariantSpec) for spec in specs):
                self._refuse(ep.name, ep.value, origin, "it is not a VariantSpec")
                continue
            for spec in specs:
                if spec.origin == "mrcomm" and origin != "mrcomm":
                    spec = _with_origin(spec, origin)
                self.register(spec)

    def _refuse(self, name: str, value: str, origin: str, why: str) -> None:
        """A plugin that cannot be loaded is skipped with one warning line (on standard
        error), so that it breaks no command that does not use it; naming it is then
        an error (:meth:`get`). MRComm's own variants failing is a broken install."""
        message = f"plugin {name} = {value} (from {origin}) failed to load: {why}"
        if origin == "mrcomm":
            raise InputError(message, field=self.group)
        self.broken[name] = message
        print(f"warning: {message}; skipped", file=sys.stderr)


def _with_origin(spec: VariantSpec, origin: str) -> VariantSpec:
    from dataclasses import replace

    return replace(spec, origin=origin)


#: The registry every part of MRComm uses.
REGISTRY = SpecRegistry()


def get_spec(kind: Kind, name: str) -> VariantSpec:
    return REGISTRY.get(kind, name)


def variant_names(kind: Kind) -> list[str]:
    return REGISTRY.names(kind)


def register(spec: VariantSpec) -> VariantSpec:
    """Register a spec directly (tests; a plugin normally uses its entry point)."""
    return REGISTRY.register(spec)
