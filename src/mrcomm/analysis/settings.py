"""Which variant parameters set a run apart, as columns the statistics group by.

A study may sweep variant parameters as factors (``network.relay: [false, true]``,
``behaviour.utility: [original, greedy]``); the ``runs`` table keeps them in
``configs.options`` only. Pooling runs that differ in them would mix configurations, so
before any statistics:

* a behaviour's own parameters become part of its name, ``lf[utility=greedy]`` — a
  behaviour with other parameters is another arm of the between-behaviour comparison;
* every other parameter (network, threshold, robot) goes into a ``setting`` column,
  ``network.relay=true`` ("" when a run has none): runs are compared only within the
  same setting.
"""

from __future__ import annotations

import json
from typing import Any

import pandas as pd

#: The column of the non-behaviour parameters (part of every configuration group).
SETTING = "setting"


def _flat(params: dict[str, Any], prefix: str = "") -> list[str]:
    out: list[str] = []
    for key in sorted(params):
        value = params[key]
        if isinstance(value, dict):
            out += _flat(value, f"{prefix}{key}.")
        else:
            out.append(f"{prefix}{key}={json.dumps(value)}")
    return out


def _split(options: Any) -> tuple[str, str]:
    """(behaviour parameters, setting) of one configuration's options."""
    values = json.loads(options) if isinstance(options, str) else (options or {})
    params = values.get("params") or {}
    own = ",".join(_flat(params.get("behaviour") or {}))
    rest = {k: v for k, v in params.items() if k != "behaviour"}
    return own, ", ".join(_flat(rest))


def with_settings(runs: pd.DataFrame, configs: pd.DataFrame) -> pd.DataFrame:
    """``runs`` with the behaviour's parameters in its name and a ``setting`` column
    (see the module docstring); unchanged columns otherwise."""
    out = runs.copy()
    if configs.empty or "config_id" not in out:
        out[SETTING] = ""
        return out
    pairs = zip(configs["config_id"], configs["options"], strict=True)
    split = {cid: _split(opts) for cid, opts in pairs}
    own = out["config_id"].map(lambda c: split.get(c, ("", ""))[0])
    out[SETTING] = out["config_id"].map(lambda c: split.get(c, ("", ""))[1]).fillna("")
    named = own.fillna("") != ""
    out.loc[named, "behaviour"] = out.loc[named, "behaviour"] + "[" + own[named] + "]"
    return out
