"""Experiments at scale: schema files expanded into configurations and seeded runs
(:mod:`.schema`, :mod:`.seeds`), the sweep runner and its workers (:mod:`.runner`,
:mod:`.worker`), the DuckDB results database (:mod:`.tables`, :mod:`.rows`,
:mod:`.store`) and the notebook API (:mod:`.api`). See docs/RESULTS.md.

Nothing is imported here, so that ``import mrcomm.experiment.schema`` stays light.
"""
