"""What the report says about who made the runs and how: one provenance row per
configuration, version, commit, machine and input files, and each configuration's
variant parameters and versions, read from its stored options."""

from __future__ import annotations

import json
from typing import Any

import pandas as pd

PROVENANCE_COLUMNS = ("mrcomm_version", "git_commit", "machine", "input_hashes")


def provenance_rows(runs: pd.DataFrame) -> list[list[str]]:
    """Who made the runs: one row per distinct (configuration label, MRComm version,
    commit, machine, input hashes) with its number of runs."""
    if not set(PROVENANCE_COLUMNS) <= set(runs.columns):
        return []
    keys = ["label", *PROVENANCE_COLUMNS]
    frame = runs.reindex(columns=keys).fillna("").astype(str)
    rows = []
    for key, group in frame.groupby(keys, sort=True):
        label, version, commit, machine, hashes = (str(k) for k in key)
        try:
            files = json.loads(hashes) if hashes else {}
        except ValueError:
            files = {}
        listed = ", ".join(f"{role} {digest}" for role, digest in sorted(files.items()))
        rows.append(
            [label, str(len(group)), version, commit or "(not a checkout)", machine, listed]
        )
    return rows


def config_rows(configs: pd.DataFrame) -> list[list[str]]:
    """Each configuration's columns, then its variant parameters (``--set`` form) and
    the versions of its variants, read from its stored options."""
    rows: list[list[str]] = []
    for record in configs.to_dict("records"):
        try:
            options = json.loads(str(record.get("options") or "{}"))
        except ValueError:
            options = {}
        params = options.get("params") or {}
        assignments = [
            f"{kind}.{key}={value}"
            for kind, section in sorted(params.items())
            for key, value in sorted(_flatten(section).items())
        ]
        variants = options.get("variants") or {}
        cells = [str(v) for k, v in record.items() if k != "options"]
        cells.append(", ".join(assignments) or "defaults")
        cells.append(", ".join(f"{k} {v}" for k, v in sorted(variants.items())))
        rows.append(cells)
    return rows


def _flatten(section: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in section.items():
        if isinstance(value, dict):
            out.update(_flatten(value, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = value
    return out
