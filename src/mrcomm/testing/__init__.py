"""The conformance kit: the checks every variant must pass, built-in or plugin.

Run it on a variant from Python (``check_variant(spec)``), from pytest, or from the
command line (``mrcomm check behaviour.mine``), as PettingZoo ships its API and seed
tests for users' environments. The checks (:mod:`mrcomm.testing.checks`):

* ``api`` — the spec loads, its parameters build with their defaults and document
  themselves, the implementation is what its kind needs;
* ``determinism`` — the S1 mission with the variant, same seed twice, is identical, and
  another seed differs;
* ``no_deadlock`` — the mission ends before its time limit at SPL 50 (two seeds);
* ``same_decisions`` — the mission's traffic, handed to the Zenoh bus (a real Zenoh
  session on loopback), gets the delivery decisions the in-process bus made;
* ``layering`` — agent-side code (behaviours, utilities) imports no simulator and no
  transport.
"""

from __future__ import annotations

from mrcomm.testing.checks import CHECKS, CheckResult, check_variant, mission_config

__all__ = ["CHECKS", "CheckResult", "check_variant", "mission_config"]
