"""The report tour: where a robot goes to bring the task assigner a missed status."""

from __future__ import annotations

from mrcomm.agents.report_tour import AIM_TIMEOUT, REACH, ReportTour

PLACES = {"assigner": (0.0, 0.0), "robot_2": (10.0, 0.0), "robot_3": (20.0, 0.0)}
ORDER = ["assigner", "robot_2", "robot_3"]


def test_the_assigner_first_then_the_mates_most_recently_heard() -> None:
    tour = ReportTour()
    assert tour.target((30.0, 0.0), PLACES, ORDER, 0.0, failed=False) == (0.0, 0.0)
    # Still on the way: the same place.
    assert tour.target((15.0, 0.0), PLACES, ORDER, 10.0, failed=False) == (0.0, 0.0)
    # Reached without the assigner heard: on to the next place.
    near = (REACH - 0.1, 0.0)
    assert tour.target(near, PLACES, ORDER, 20.0, failed=False) == (10.0, 0.0)
    # The drive there failed (unreachable): the next.
    assert tour.target(near, PLACES, ORDER, 21.0, failed=True) == (20.0, 0.0)
    # Too long on the way (a robot standing on the spot): start the tour again.
    late = 21.0 + AIM_TIMEOUT + 1.0
    assert tour.target(near, PLACES, ORDER, late, failed=False) == (0.0, 0.0)


def test_a_moving_place_is_followed_and_nowhere_to_go_is_none() -> None:
    tour = ReportTour()
    assert tour.target((5.0, 5.0), {"robot_2": (1.0, 1.0)}, ["robot_2"], 0.0, failed=False) == (
        1.0,
        1.0,
    )
    # The host's last known position moved on: the tour aims at where it is now.
    moved = {"robot_2": (8.0, 8.0)}
    assert tour.target((5.0, 5.0), moved, ["robot_2"], 1.0, failed=False) == (8.0, 8.0)
    assert ReportTour().target((0.0, 0.0), {}, [], 0.0, failed=False) is None
