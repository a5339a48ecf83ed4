"""Agents: the task assigner, the task executor and its behaviours (NB, and the
communication-aware ones), collision avoidance. Agents act only through the Bus and Base
ports and are stepped with ``step(now)``; they know nothing of simulators or transports."""
