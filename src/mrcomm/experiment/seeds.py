"""Stable identities and seeds of a sweep's configurations and runs.

* ``config_id`` = ``<label>-<digest>``: readable, and the 8-hex-digit digest covers
  everything that determines the configuration (experiment, base seed, scenario, every
  option given in the schema), so an edited schema never reuses the results of another
  configuration under the same id.
* ``run_id`` = ``<config_id>-r<repetition:03d>``.
* The seed of a run comes from (base seed, config id, repetition) through numpy's
  ``SeedSequence``; hashes are blake2b, never Python's salted ``hash()``, so ids and
  seeds are the same in every process, on every machine and Python version.
"""

from __future__ import annotations

import hashlib
import json
from typing import Any

import numpy as np

#: Seeds fit a signed 64-bit database column.
_SEED_MASK = (1 << 63) - 1


def content_digest(content: dict[str, Any]) -> str:
    """8 hex digits identifying ``content`` (canonical JSON: sorted keys, no spaces)."""
    text = json.dumps(content, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.blake2b(text.encode(), digest_size=4).hexdigest()


def make_config_id(label: str, content: dict[str, Any]) -> str:
    return f"{label}-{content_digest(content)}"


def make_run_id(config_id: str, repetition: int) -> str:
    return f"{config_id}-r{repetition:03d}"


def _words(text: str) -> tuple[int, ...]:
    # SeedSequence spawn keys are 32-bit words: 4 words of a 16-byte digest.
    digest = hashlib.blake2b(text.encode(), digest_size=16).digest()
    return tuple(int.from_bytes(digest[i : i + 4], "little") for i in range(0, 16, 4))


def run_seed(base_seed: int, config_id: str, repetition: int) -> int:
    """The seed of repetition ``repetition`` of configuration ``config_id``."""
    sequence = np.random.SeedSequence(entropy=base_seed, spawn_key=(*_words(config_id), repetition))
    low, high = (int(w) for w in sequence.generate_state(2, dtype=np.uint32))
    return ((high << 32) | low) & _SEED_MASK
