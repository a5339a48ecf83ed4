"""The operator console's web page (NiceGUI: its JavaScript ships with the package, so
the page works offline), served locally while a :class:`ConsoleSession` runs.

The page shows the session's latest snapshot, refreshed four times a second: the map
with every robot where the operator knows it (faded when its pose is old; with "ground
truth" on, also where it is, and each link coloured by state), the tasks as the
operator heard them (green: its completion reached the operator; yellow, with ground
truth: done by the robot but not heard — a lost status), the mission clock and a speed
control, the commands sent and who acknowledged them, message counters and the events.
Clicking a task selects it; clicking free map selects a position. The buttons send the
operator's commands for the selected task, robot and position.
"""

from __future__ import annotations

import base64
import threading
from collections.abc import Callable
from typing import Any, TypeVar

from nicegui import app, ui

from mrcomm.console.guard import ConsoleGuard
from mrcomm.console.live_session import LiveConsole
from mrcomm.console.replay import Replay
from mrcomm.console.session import SPEEDS, ConsoleSession
from mrcomm.console.view import Pixels, map_png, svg

REFRESH = 0.25  # s between page updates
T = TypeVar("T")


def build(session: ConsoleSession | LiveConsole, *, quit_button: bool = False) -> None:
    """Register the console page for ``session`` (a simulated mission's, with ground
    truth and a pace to set; or a live operator's, with neither). ``quit_button``: once
    the mission has ended, a button stops the server (the page stays up until then)."""
    grid = session.grid
    pixels = Pixels(grid)
    source = "data:image/png;base64," + base64.b64encode(map_png(grid)).decode("ascii")
    robots = session.robot_ids

    @ui.page("/")
    def index() -> None:
        picked: dict[str, Any] = {"task": "", "robot": robots[0], "where": None, "events": 0}
        ui.page_title("MRComm console")
        with ui.row().classes("items-center w-full"):
            clock = ui.label("").props('id="clock"').classes("text-lg font-mono")
            if session.speed is not None:
                speeds = dict(SPEEDS)
                start = next((n for n, v in speeds.items() if v == session.speed), None)
                if start is None:  # the pace the run was started with
                    start = f"x{session.speed:g}"
                    speeds[start] = session.speed
                ui.toggle(list(speeds), value=start,
                          on_change=lambda e: setattr(session, "speed", speeds[e.value])
                          ).props('id="speed"')  # fmt: skip
            truth = ui.switch("ground truth", value=session.has_truth).props('id="truth"')
            truth.set_visibility(session.has_truth)
            status = ui.label("").props('id="status"')
            leave = ui.button("quit", on_click=app.shutdown).props('id="quit" dense')
            leave.set_visibility(False)
        with ui.row().classes("w-full no-wrap"):
            image = ui.interactive_image(source, content="", events=["click"],
                                         sanitize=False).classes("w-3/4")  # fmt: skip
            image.props('id="map"')
            with ui.column().classes("w-1/4"):
                selection = ui.label("").props('id="selection"')
                with ui.row():
                    for rid in robots:
                        ui.button(rid, on_click=lambda _e, r=rid: pick("robot", r)).props(
                            f'id="pick-{rid}" dense outline'
                        )
                with ui.row():
                    for kind in ("reassign", "redo", "confirm", "add", "pause", "resume",
                                 "end"):  # fmt: skip
                        ui.button(kind, on_click=lambda _e, k=kind: send(k)).props(
                            f'id="cmd-{kind}" dense'
                        )
                notes = ui.label("").props('id="notes"').classes("text-red-700 text-sm")
                commands = ui.table(
                    columns=[{"name": n, "label": n, "field": n} for n in
                             ("time", "command", "robot", "task", "acknowledged", "finished")],
                    rows=[], row_key="time",
                ).props('id="commands" dense').classes("w-full")  # fmt: skip
                counters = ui.table(
                    columns=[{"name": n, "label": n, "field": n}
                             for n in ("topic", "sent", "received", "dropped")],
                    rows=[], row_key="topic",
                ).props('id="counters" dense').classes("w-full")  # fmt: skip
        log = ui.log(max_lines=300).props('id="events"').classes("w-full h-48")

        def pick(what: str, value: Any) -> None:
            picked[what] = value
            where = picked["where"]
            place = f"({where[0]:.1f}, {where[1]:.1f})" if where else "-"
            selection.text = f"task {picked['task'] or '-'} · robot {picked['robot']} · at {place}"

        def send(kind: str) -> None:
            task = picked["task"] if kind in ("reassign", "redo", "confirm") else ""
            if kind == "add":
                task = f"op{len(session.view.commands) + 1}"
            robot = "" if kind in ("redo", "confirm") else picked["robot"]
            where = picked["where"] if kind == "add" else None
            session.submit(kind, robot, task, where)

        def on_svg(event: Any) -> None:
            element = str(event.args.get("element_id", ""))
            if element.startswith("task-"):
                pick("task", element.removeprefix("task-"))

        def on_click(event: Any) -> None:
            pick("where", pixels.to_map(event.image_x, event.image_y))

        image.on("svg:pointerdown", on_svg)
        image.on_mouse(on_click)
        pick("robot", robots[0])

        def refresh() -> None:
            view = session.view
            image.content = svg(view, pixels, truth=truth.value, selected_task=picked["task"])
            clock.text = f"t = {view.now:7.1f} s"
            if view.ended:
                verdict = "successful" if view.successful else "failed"
                status.text = f"mission ended: {verdict}" + (
                    f" · {view.result}" if view.result else "")  # fmt: skip
                leave.set_visibility(quit_button)
            else:
                heard = sum(t.heard for t in view.tasks)
                waiting = " · robots done: send them back for lost statuses, or end" if (
                    session.waiting) else ""  # fmt: skip
                status.text = f"{heard} of {len(view.tasks)} tasks heard{waiting}"
            notes.text = " · ".join(view.notes)
            commands.rows = [
                {"time": f"{c['time']:.1f}", "command": c["command"], "robot": c["robot"],
                 "task": c["task_id"] or "-",
                 "acknowledged": ", ".join(m for m in c["acknowledged"] if m != "operator"),
                 "finished": "-" if c["finished_at"] is None else f"{c['finished_at']:.1f}"}
                for c in view.commands
            ]  # fmt: skip
            counters.rows = [{"topic": t, **c} for t, c in sorted(view.counters.items())]
            new = min(view.events_total - picked["events"], len(view.events))
            for line in view.events[len(view.events) - new :] if new > 0 else ():
                log.push(line)
            picked["events"] = view.events_total

        ui.timer(REFRESH, refresh)


def serve(
    console: ConsoleSession | LiveConsole,
    guard: ConsoleGuard,
    work: Callable[[], T],
    *,
    linger: float = 2.0,
    stay_up: Callable[[T], None] | None = None,
) -> T | None:
    """Serve the console page on ``guard.port`` (localhost, behind the guard: its URL
    with the secret opens it) while ``work`` — what steps the mission: a session's run,
    a live operator process's loop — runs in its own thread. When it ends, the server
    stops ``linger`` s later; with ``stay_up``, it is called with the return value and
    the page stays up, showing the final state, until Ctrl-C or the page's quit button.
    Returns ``work``'s value (None if it raised)."""
    build(console, quit_button=stay_up is not None)
    done: list[T] = []

    def run() -> None:
        try:
            done.append(work())
        finally:
            if stay_up is None or not done:
                threading.Timer(linger, app.shutdown).start()
        if stay_up is not None:
            stay_up(done[0])

    app.on_startup(lambda: threading.Thread(target=run, daemon=True).start())
    _run_server(guard, "MRComm console")
    return done[0] if done else None


class _Guarded:
    """The NiceGUI app behind a :class:`ConsoleGuard` (Starlette's middleware form)."""

    def __init__(self, inner: Any, guard: ConsoleGuard) -> None:
        self._app = guard.middleware(inner)

    async def __call__(self, scope: Any, receive: Any, send: Any) -> None:
        await self._app(scope, receive, send)


def _run_server(guard: ConsoleGuard, title: str) -> None:
    app.add_middleware(_Guarded, guard=guard)
    ui.run(host="127.0.0.1", port=guard.port, reload=False, show=False, title=title,
           show_welcome_message=False)  # fmt: skip


def build_replay(replay: Replay) -> None:
    """Register the replay page: the recording's frames under a time slider, played
    at ×10 with the play switch."""
    pixels = Pixels(replay.grid)
    source = "data:image/png;base64," + base64.b64encode(map_png(replay.grid)).decode("ascii")

    @ui.page("/")
    def index() -> None:
        ui.page_title(f"MRComm replay: {replay.label}")
        with ui.row().classes("items-center w-full"):
            clock = ui.label("").props('id="clock"').classes("text-lg font-mono")
            ui.label(replay.label)
            playing = ui.switch("play ×10", value=False).props('id="play"')
        slider = ui.slider(min=0.0, max=replay.end, step=0.1, value=0.0).props(
            'id="time" label-always'
        )
        image = ui.interactive_image(source, content="", sanitize=False).classes("w-3/4")
        image.props('id="map"')
        log = ui.log(max_lines=300).props('id="events"').classes("w-full h-48")

        def show() -> None:
            view = replay.at(float(slider.value))
            image.content = svg(view, pixels, truth=True)
            clock.text = f"t = {view.now:7.1f} s of {replay.end:.1f} s"
            log.clear()
            for line in view.events[-100:]:
                log.push(line)

        def advance() -> None:
            if playing.value and slider.value < replay.end:
                slider.value = min(replay.end, float(slider.value) + 10 * REFRESH)

        slider.on_value_change(lambda _e: show())
        ui.timer(REFRESH, advance)
        show()


def serve_replay(replay: Replay, guard: ConsoleGuard) -> None:
    """Serve the replay page on ``guard.port`` (localhost, behind the guard) until
    interrupted."""
    build_replay(replay)
    _run_server(guard, "MRComm replay")
