"""Starting a live agent process: the loop on the world's shared clock
(:class:`~mrcomm.live.agent.AgentProcess`) or, with ``--agent-clock host``, on its own
host's clock (:class:`~mrcomm.live.host_clock.HostClockAgent`, which extends it)."""

from __future__ import annotations

from mrcomm.live.agent import AgentProcess
from mrcomm.live.host_clock import HostClockAgent
from mrcomm.live.journal import new_incarnation
from mrcomm.live.settings import LiveSettings


def run_agent(settings: LiveSettings, agent: str, incarnation: int | None = None) -> int:
    """Run one agent process to the end of the mission; returns the exit status."""
    inc = incarnation if incarnation is not None else new_incarnation(settings.record_dir, agent)
    if settings.agent_clock == "host":
        return HostClockAgent(settings, agent, inc).run()
    return AgentProcess(settings, agent, inc).run()
