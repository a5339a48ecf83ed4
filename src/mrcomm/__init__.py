"""MRComm: a testbed for multi-robot teams whose communication degrades.

Layers (each a subpackage, dependencies point downwards only):
cli -> experiment/analysis -> sim/live -> agents -> messaging/net/robot/metrics -> world.
See docs/ARCHITECTURE.md.
"""

__version__ = "0.1.0"
