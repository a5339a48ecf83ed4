"""The Foxglove layout for MRComm recordings and live runs, built with the Foxglove
SDK's layout types: the 3D scene in the ``map`` frame (map, robots, tasks, links), the
robots' timeline events, each robot's behaviour state over time, and the mission
summary. Shipped as ``data/foxglove/mrcomm-layout.json`` (import it in Foxglove:
Layouts → Import from file); ``python -m mrcomm.experiment.foxglove_layout`` writes it
again, for ``robots`` robots."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import foxglove.layouts as fl

from mrcomm.experiment.recording import (
    TOPIC_EVENTS,
    TOPIC_MAP,
    TOPIC_RESULT,
    TOPIC_ROLES,
    TOPIC_SCENE,
)
from mrcomm.experiment.recording_scene import FRAME

#: Robots whose state the shipped layout plots (S1's three; more are one line each).
SHIPPED_ROBOTS = ("robot_1", "robot_2", "robot_3")
SHIPPED = Path(__file__).resolve().parents[3] / "data" / "foxglove" / "mrcomm-layout.json"


def layout(robots: tuple[str, ...] = SHIPPED_ROBOTS) -> fl.Layout:
    scene = fl.ThreeDeePanel(
        title="Mission",
        config=fl.ThreeDeeConfig(
            fixed_frame=FRAME,
            follow_tf=FRAME,
            topics={
                TOPIC_MAP: fl.BaseRendererGridTopicSettings(visible=True, draw_behind=True),
                TOPIC_SCENE: fl.BaseRendererSceneUpdateTopicSettings(visible=True),
            },
        ),
    )
    states = fl.StateTransitionsPanel(
        title="Behaviour states",
        config=fl.StateTransitionsConfig(
            paths=[
                fl.StateTransitionsSeries(value=f"{TOPIC_ROLES}.states.{robot}", label=robot)
                for robot in robots
            ]
        ),
    )
    events = fl.LogPanel(title="Events", config=fl.LogConfig(topic_to_render=TOPIC_EVENTS))
    summary = fl.RawMessagesPanel(
        title="Mission summary", config=fl.RawMessagesConfig(topic_path=TOPIC_RESULT)
    )
    side = fl.SplitContainer(
        direction="column",
        items=[fl.SplitItem(content=states), fl.SplitItem(content=events),
               fl.SplitItem(content=summary)],
    )  # fmt: skip
    return fl.Layout(
        content=fl.SplitContainer(
            direction="row",
            items=[fl.SplitItem(proportion=2, content=scene), fl.SplitItem(content=side)],
        )
    )


def layout_json(robots: tuple[str, ...] = SHIPPED_ROBOTS) -> str:
    """The layout as the file Foxglove imports (indented, stable)."""
    return json.dumps(json.loads(layout(robots).to_json()), indent=2, sort_keys=True) + "\n"


if __name__ == "__main__":
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else SHIPPED
    out.write_text(layout_json())
