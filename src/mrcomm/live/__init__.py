"""Live mode (DESIGN ``live``; issue 7): every agent its own OS process over Eclipse
Zenoh, running the same agent classes as the simulation.

* ``world`` — the world process: simulates every robot's base (the role Stage plays)
  and publishes the shared clock;
* ``agent`` — one agent process: a task executor (and the task assigner it hosts),
  stepped on the shared clock, its base a :class:`~mrcomm.live.remote_base.RemoteBase`;
* ``launcher`` — ``mrcomm live``: world + every agent as separate processes on this
  host, then the collection of every robot's own records (``collect``).
"""
