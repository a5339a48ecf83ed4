"""Unit tests of the AON endpoint: happy path, publication counts, aggregation, stale
copies, answers from released state, incarnation restarts, long partitions, the lease
(left out by name, then brought up to date) and input checks."""

from __future__ import annotations

import pytest

from mrcomm.messaging.aon import AonEndpoint
from mrcomm.messaging.aon_state import SeqRecord, TeamIndex
from mrcomm.messaging.messages import (
    TOPIC_AON,
    AonEntry,
    AonMsg,
    TaskState,
    TaskStatus,
    decode,
    encode,
)
from tests.messaging.aon_team import AonTeam
from tests.messaging.fakenet import Cut, FakeNet


def names(n: int) -> list[str]:
    return [f"r{i}" for i in range(n)]


def status(sender: str) -> TaskStatus:
    return TaskStatus(
        sender=sender,
        incarnation=0,
        seq=0,
        stamp=0.0,
        robot=sender,
        task_id="1",
        state=TaskState.SUCCESS,
    )


def test_happy_path_delivers_once_and_finishes_everywhere() -> None:
    net = FakeNet(names(3), seed=1)
    team = AonTeam(net)
    mid = team.send("r0", "task-7")
    assert mid == ("r0", 0, 0)
    net.run(5.0, stop=team.all_done)
    assert team.all_done()
    assert not team.violations
    for member in ("r1", "r2"):
        assert team.delivered[member][mid] == 1
        assert team.endpoints[member].stats.deliveries == 1
    assert team.delivered["r0"][mid] == 0  # the sender is not handed its own payload
    for member in team.team:
        (report,) = team.reports[member]
        assert report.msg_id == mid and report.left_out == () and not report.late
        assert team.endpoints[member].memory() == {"states": 0, "records": 1, "record_extras": 0}
        assert team.endpoints[member].pending_ids() == ()


@pytest.mark.parametrize("n", [1, 2, 3, 5, 10])
def test_loss_free_cost_is_2n_publications_below_n_n_plus_1(n: int) -> None:
    net = FakeNet(names(n), seed=2)
    team = AonTeam(net)
    team.send("r0")
    net.run(5.0, stop=team.all_done)
    assert team.all_done()
    total = sum(net.counts.published.values())
    # 1 send + (n-1) acknowledgements + n *received*; with two members the
    # acknowledgement already carries *received*, and one member needs nobody.
    assert total == {1: 0, 2: 3}.get(n, 2 * n)
    assert total < n * (n + 1)
    assert all(e.stats.resend_publications == 0 for e in team.endpoints.values())
    # Three network steps: send, acknowledge, received.
    assert net.now == pytest.approx(0.3 if n > 1 else 0.1)


def test_concurrent_messages_share_publications() -> None:
    n = 5
    net = FakeNet(names(n), seed=3)
    team = AonTeam(net)
    for member in team.team:
        team.send(member)
    net.run(5.0, stop=team.all_done)
    assert team.all_done() and not team.violations
    total = sum(net.counts.published.values())
    # n sends, then one aggregated acknowledgement and one aggregated received each.
    assert total == 3 * n
    assert total < n * 2 * n


def test_stale_copy_after_release_is_ignored_but_answered() -> None:
    net = FakeNet(names(3), seed=4)
    team = AonTeam(net)
    mid = team.send("r0")
    net.run(5.0, stop=team.all_done)
    assert team.all_done()
    r2 = team.endpoints["r2"]
    index = TeamIndex(team.team)
    stale = AonMsg(
        sender="r1",
        incarnation=0,
        seq=99,
        stamp=0.0,
        team_crc=index.crc,
        entries=(
            AonEntry(
                *mid,
                have=index.encode(index.bit["r0"] | index.bit["r1"]),
                recv=index.encode(0),
                ask=True,
                payload=team.sent[mid],
            ),
        ),
    )
    net.buses["r2"].handlers[TOPIC_AON][0](stale)
    assert team.delivered["r2"][mid] == 1  # not delivered again
    assert r2.stats.stale == 1
    assert r2.memory()["states"] == 0  # no state resurrected
    net.record = True
    net.tick()
    (answer,) = [m for _, s, _, m in net.log if s == "r2"]
    assert isinstance(answer, AonMsg)
    (entry,) = answer.entries
    assert (entry.sender, entry.incarnation, entry.seq) == mid
    assert index.decode(entry.have) == index.full and index.decode(entry.recv) == index.full
    assert entry.payload is None
    assert r2.stats.replies == 1


def test_finished_member_answers_a_peer_still_resending() -> None:
    # r2 misses the last round (the *received* publications) and must learn from the
    # others, who have already finished and released the message.
    net = FakeNet(names(3), seed=5, cuts=[Cut("r2", None, 0.25, 0.35, inbound_only=True)])
    team = AonTeam(net)
    mid = team.send("r0")
    net.run(0.3)
    assert team.endpoints["r0"].is_finished(mid) and team.endpoints["r1"].is_finished(mid)
    assert team.endpoints["r0"].memory()["states"] == 0
    assert team.endpoints["r1"].memory()["states"] == 0
    assert not team.endpoints["r2"].is_finished(mid)
    net.run(5.0, stop=team.all_done)
    assert team.all_done() and not team.violations
    assert team.endpoints["r2"].stats.resend_publications >= 1
    assert team.endpoints["r0"].stats.replies + team.endpoints["r1"].stats.replies >= 1


def test_incarnation_restart_is_a_new_identity() -> None:
    net = FakeNet(names(3), seed=6)
    team = AonTeam(net)
    old = team.send("r0", "a")
    net.run(5.0, stop=team.all_done)
    old_copy = AonMsg(
        sender="r0",
        incarnation=0,
        seq=0,
        stamp=0.0,
        team_crc=TeamIndex(team.team).crc,
        entries=(AonEntry(*old, have=b"\x01", recv=b"\x00", payload=team.sent[old]),),
    )
    team.start("r0", incarnation=1)  # r0 crashed and came back: sequence restarts at 0
    new = team.send("r0", "b")
    assert new == ("r0", 1, 0) and new != old
    endpoints = team.endpoints.values()
    net.run(
        10.0, stop=lambda: all(e.is_finished(new) and not e.memory()["states"] for e in endpoints)
    )
    assert all(e.is_finished(new) for e in endpoints) and not team.violations
    assert not team.endpoints["r0"].is_finished(old)  # the new incarnation never held it
    for member in ("r1", "r2"):
        assert team.delivered[member][old] == 1
        assert team.delivered[member][new] == 1
        # A stale copy from the former incarnation, arriving late, is not redelivered.
        net.buses[member].handlers[TOPIC_AON][0](old_copy)
        assert team.delivered[member][old] == 1
        assert team.endpoints[member].stats.stale >= 1
    assert team.endpoints["r1"].memory()["records"] == 2  # one per (sender, incarnation)


def test_member_out_of_range_for_minutes_gets_it_when_the_link_returns() -> None:
    net = FakeNet(names(3), seed=7, loss=0.25, cuts=[Cut("r2", None, 0.0, 300.0)])
    team = AonTeam(net)
    net.tick()
    mid = team.send("r0")
    net.run(299.0)
    assert team.delivered["r2"][mid] == 0
    assert all(not e.is_finished(mid) for e in team.endpoints.values())
    assert team.endpoints["r0"].stats.restarts >= 15  # fail-safe every 15 s
    assert team.endpoints["r0"].stats.resend_publications > 100  # still trying, 3 Hz
    net.run(320.0, stop=team.all_done)
    assert team.all_done() and not team.violations
    assert team.delivered["r2"][mid] == 1
    assert net.now < 320.0


def assert_paused_until(net: FakeNet, until: float) -> None:
    """Nothing is published from now until ``until``: re-sending is paused."""
    before = sum(net.counts.published.values())
    net.run(until)
    assert sum(net.counts.published.values()) == before


def test_lease_names_the_silent_member_then_brings_it_up_to_date() -> None:
    net = FakeNet(names(3), seed=8, cuts=[Cut("r2", None, 0.0, 60.0)])
    team = AonTeam(net, lease=5.0, beacons=True)
    net.tick()
    mid = team.send("r0")
    net.run(4.0)
    assert not team.endpoints["r0"].is_finished(mid)  # within the lease: still waiting
    net.run(8.0)
    for member in ("r0", "r1"):
        endpoint = team.endpoints[member]
        (report,) = team.reports[member]
        assert report.left_out == ("r2",) and not report.late
        assert endpoint.is_finished(mid)
        assert endpoint.left_out_ids() == (mid,) and endpoint.pending_ids() == ()
        assert endpoint.stats.left_out_reports == 1
    assert team.delivered["r2"][mid] == 0
    assert_paused_until(net, 55.0)  # while r2 is silent: no futile re-sends
    # r2 is back: brought up to date, and the others report completion, late.
    net.run(80.0, stop=team.all_done)
    assert team.all_done() and not team.violations
    assert net.now < 62.0
    assert team.delivered["r2"][mid] == 1
    for member in ("r0", "r1"):
        late = team.reports[member][-1]
        assert late.late and late.left_out == ()
        assert team.endpoints[member].memory()["states"] == 0
    assert [r.left_out for r in team.reports["r2"]] == [()]


def test_lease_does_not_fire_while_members_are_heard() -> None:
    net = FakeNet(names(3), seed=9, loss=0.6)
    team = AonTeam(net, lease=2.0, beacons=True)
    for member in team.team:
        team.send(member)
    net.run(60.0, stop=team.all_done)
    assert team.all_done() and not team.violations
    assert all(r.left_out == () for rs in team.reports.values() for r in rs)


def test_ignores_foreign_team_and_non_members() -> None:
    net = FakeNet(["r0", "r1", "x"], seed=10)
    delivered: list[object] = []
    endpoint = AonEndpoint(
        net.buses["r0"], "r0", 0, ["r0", "r1"], on_deliver=lambda p, m: delivered.append(m)
    )
    other = AonEndpoint(
        net.buses["x"], "x", 0, ["r0", "x"], on_deliver=lambda p, m: delivered.append(m)
    )
    net.steppers += [endpoint.step, other.step]
    other.send(status("x"), 0.0)
    net.run(1.0)
    assert delivered == [] and endpoint.stats.foreign >= 1


def test_team_order_does_not_matter_and_large_teams_work() -> None:
    members = names(70)  # more members than a 64-bit bitmap could hold
    net = FakeNet(members, seed=11)
    team = AonTeam(net, team=list(reversed(members)))
    team.send("r42")
    net.run(5.0, stop=team.all_done)
    assert team.all_done() and not team.violations
    assert sum(net.counts.published.values()) == 2 * 70


def test_message_arriving_before_the_first_step() -> None:
    net = FakeNet(names(2), seed=12)
    team = AonTeam(net)
    net.steppers.clear()  # r1 is not stepped until later
    team.endpoints["r0"].send(status("r0"), 0.0)
    net.tick()  # delivered to r1, which has never seen a clock
    assert team.endpoints["r1"].stats.deliveries == 1
    net.steppers.append(team.step)
    net.run(5.0, stop=lambda: all(not e.memory()["states"] for e in team.endpoints.values()))
    (report,) = team.reports["r1"]
    assert 0.0 < report.started <= report.finished < 5.0


def test_wire_round_trip() -> None:
    index = TeamIndex(names(100))
    entry = AonEntry("r1", 3, 4, index.encode(index.full), index.encode(5), True, None)
    msg = AonMsg(sender="r1", incarnation=3, seq=1, stamp=2.5, team_crc=index.crc, entries=(entry,))
    back = decode(encode(msg))
    assert back == msg
    assert isinstance(back, AonMsg)
    assert index.decode(back.entries[0].have) == index.full
    assert index.names(index.decode(back.entries[0].recv)) == ("r0", "r10")


def test_seq_record_compacts_to_a_watermark() -> None:
    record = SeqRecord()
    for seq in (2, 0, 3, 5):
        record.add(seq)
    assert record.watermark == 1 and record.above == {2, 3, 5}
    record.add(1)
    assert record.watermark == 4 and record.above == {5}
    assert 0 in record and 3 in record and 5 in record and 4 not in record


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"owner": "zz"}, "not in the team"),
        ({"team": ["r0", "r0"]}, "duplicate"),
        ({"team": []}, "empty"),
        ({"resend_period": 0.0}, "resend_period"),
        ({"failsafe_timeout": -1.0}, "failsafe_timeout"),
        ({"lease": 0.0}, "lease"),
    ],
)
def test_constructor_rejects_bad_arguments(kwargs: dict[str, object], match: str) -> None:
    net = FakeNet(names(2), seed=0)
    args: dict[str, object] = {"owner": "r0", "team": ["r0", "r1"], **kwargs}
    owner = args.pop("owner")
    team = args.pop("team")
    with pytest.raises(ValueError, match=match):
        AonEndpoint(net.buses["r0"], owner, 0, team, on_deliver=lambda p, m: None, **args)  # type: ignore[arg-type]


def test_a_left_out_member_heard_again_is_brought_up_to_date_while_another_is_away() -> None:
    # r2 and r3 are both silent when the lease runs out; r2 comes back at 30 s while r3
    # stays away until 200 s. r2 must get the message soon after 30 s: it lacks it and
    # is heard, so re-sending is not futile (it used to wait for r3 as well).
    net = FakeNet(names(4), seed=3, cuts=[Cut("r2", None, 0.0, 30.0), Cut("r3", None, 0.0, 200.0)])
    team = AonTeam(net, lease=5.0, beacons=True)
    net.tick()
    mid = team.send("r0")
    net.run(12.0)
    assert team.reports["r0"][0].left_out == ("r2", "r3")
    net.run(40.0)
    assert team.delivered["r2"][mid] == 1
    assert team.delivered["r3"][mid] == 0
    assert_paused_until(net, 150.0)  # everyone heard has it, r3 silent: no re-sends
    net.run(300.0, stop=team.all_done)
    assert team.all_done() and not team.violations
    assert team.delivered["r3"][mid] == 1
