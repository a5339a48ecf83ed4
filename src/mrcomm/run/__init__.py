"""The run kernel shared by every mode: a run's configuration, the per-scenario
resources runs share, the wiring of a run from its configuration, and its result."""
