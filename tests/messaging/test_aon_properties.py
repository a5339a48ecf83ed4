"""Property-based tests of AON over the fake lossy network.

Generated cases mix team sizes, loss up to 90 %, duplication, random delays (so copies
overtake each other), members isolated or single links cut for long spells, and several
messages from several senders in flight at once. Every case checks, as it runs, that no
payload is delivered twice and that nothing is reported finished while a member lacks
it; and at the end that, once the network has healed, every message finishes at every
member within a bounded simulated time with its state released. Each network is seeded
from a drawn integer, printed in every assertion message, so a failure reruns exactly.
"""

from __future__ import annotations

from dataclasses import dataclass

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.stateful import (
    RuleBasedStateMachine,
    initialize,
    invariant,
    precondition,
    rule,
)

from tests.messaging.aon_team import AonTeam
from tests.messaging.fakenet import Cut, FakeNet

MAX_LOSS = 0.9


def liveness_bound(loss: float) -> float:
    """Simulated seconds after healing within which everything must have finished.

    A request/reply round trip gets through with probability (1 - loss)^2 and is tried
    at 3 Hz, so a few dozen round trips' worth of time is ample (measured worst cases
    are 5-10x below this bound)."""
    return 30.0 + 30.0 / (1.0 - loss) ** 2


@dataclass(frozen=True)
class Scenario:
    n: int
    seed: int
    loss: float
    dup: float
    max_delay: int
    sends: tuple[tuple[float, int], ...]
    cuts: tuple[tuple[int, int | None, float, float, bool], ...]

    def members(self) -> list[str]:
        return [f"r{i}" for i in range(self.n)]

    def net(self) -> FakeNet:
        names = self.members()
        cuts = [
            Cut(names[a], None if b is None else names[b], start, start + length, inbound)
            for a, b, start, length, inbound in self.cuts
        ]
        return FakeNet(
            names, self.seed, loss=self.loss, dup=self.dup, max_delay=self.max_delay, cuts=cuts
        )


@st.composite
def scenarios(draw: st.DrawFn) -> Scenario:
    n = draw(st.integers(2, 6))
    member = st.integers(0, n - 1)
    loss = draw(st.sampled_from([0.0, 0.25, 0.5, 0.75, MAX_LOSS]) | st.floats(0.0, MAX_LOSS))
    sends = draw(
        st.lists(st.tuples(st.floats(0.0, 20.0), member), min_size=1, max_size=8).map(
            lambda s: tuple(sorted(s))
        )
    )
    cuts = draw(
        st.lists(
            st.tuples(
                member,
                st.none() | member,
                st.floats(0.0, 30.0),
                st.floats(0.0, 180.0),
                st.booleans(),
            ).filter(lambda c: c[0] != c[1]),
            max_size=3,
        )
    )
    return Scenario(
        n=n,
        seed=draw(st.integers(0, 2**32 - 1)),
        loss=loss,
        dup=draw(st.floats(0.0, 0.3)),
        max_delay=draw(st.integers(1, 6)),
        sends=sends,
        cuts=tuple(cuts),
    )


def check_done(team: AonTeam, deadline: float, what: str) -> None:
    """Liveness and bounded memory at the end of a case."""
    assert not team.violations, f"{what}: {team.violations[:3]}"
    assert team.all_done(), f"{what}: not finished by t={deadline:.0f}: " + ", ".join(
        f"{m}: {e.pending_ids()}" for m, e in team.endpoints.items()
    )
    for member, endpoint in team.endpoints.items():
        for mid, sender in ((mid, mid[0]) for mid in team.sent):
            expected = 0 if sender == member else 1
            assert team.delivered[member][mid] == expected, f"{what}: {member} {mid}"
        memory = endpoint.memory()
        assert memory["states"] == 0 and memory["record_extras"] == 0, f"{what}: {memory}"


@settings(max_examples=500, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scenarios())
def test_everything_finishes_everywhere_and_nothing_is_finished_early(case: Scenario) -> None:
    what = f"seed={case.seed} {case}"
    net = case.net()
    team = AonTeam(net, label=what)
    for at, sender in case.sends:
        net.run(at)
        team.send(f"r{sender}")
        assert not team.violations, team.violations[:3]
    healed = max(net.heal_time(), net.now)
    deadline = healed + liveness_bound(case.loss)
    net.run(deadline, stop=team.all_done)
    check_done(team, deadline, what)


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    n=st.integers(3, 5),
    seed=st.integers(0, 2**32 - 1),
    loss=st.floats(0.0, 0.75),
    sends=st.lists(st.tuples(st.floats(0.0, 10.0), st.integers(0, 3)), min_size=1, max_size=6),
    down_for=st.floats(30.0, 120.0),
)
def test_lease_leaves_out_a_crashed_member_by_name_then_catches_it_up(
    n: int, seed: int, loss: float, sends: list[tuple[float, int]], down_for: float
) -> None:
    """The last member is silent from the start (lease 5 s) until ``down_for`` s after the
    survivors had time to finish: they report every message finished naming only it,
    then bring it up to date when it returns."""
    lease = 5.0
    names = [f"r{i}" for i in range(n)]
    dead = names[-1]
    what = f"seed={seed} n={n} loss={loss} sends={sends} down_for={down_for}"
    # The last send is at 10 s at most; under heavy loss the survivors' own exchanges
    # take a while (a round trip gets through with probability (1 - loss)^2).
    finish_by = 10.0 + liveness_bound(loss)
    back_at = finish_by + down_for
    net = FakeNet(names, seed, loss=loss, dup=0.1, max_delay=3, cuts=[Cut(dead, None, 0, back_at)])
    team = AonTeam(net, lease=lease, beacons=True, label=what)
    survivors = [m for m in names if m != dead]
    for at, sender in sorted(sends):
        net.run(at)
        team.send(survivors[sender % len(survivors)])

    def survivors_done() -> bool:
        return all(
            team.endpoints[m].pending_ids() == ()
            and {r.msg_id for r in team.reports[m]} == set(team.sent)
            for m in survivors
        )

    net.run(finish_by, stop=survivors_done)
    assert not team.violations, f"{what}: {team.violations[:3]}"
    for member in survivors:
        endpoint = team.endpoints[member]
        assert endpoint.pending_ids() == (), f"{what}: {member} still waits"
        for report in team.reports[member]:
            assert set(report.left_out) <= {dead}, f"{what}: {report}"
        assert {r.msg_id for r in team.reports[member]} == set(team.sent), what
    deadline = back_at + liveness_bound(loss)
    net.run(deadline, stop=team.all_done)
    check_done(team, deadline, what)


class AonMachine(RuleBasedStateMachine):
    """Interleaves sends, time, isolation and loss changes in any order."""

    @initialize(n=st.integers(2, 5), seed=st.integers(0, 2**32 - 1))
    def start(self, n: int, seed: int) -> None:
        self.seed = seed
        self.net = FakeNet([f"r{i}" for i in range(n)], seed, loss=0.3, dup=0.1, max_delay=4)
        self.team = AonTeam(self.net, label=f"seed={seed}")

    @rule(member=st.integers(0, 4))
    def send(self, member: int) -> None:
        self.team.send(f"r{member % len(self.team.team)}")

    @rule(seconds=st.floats(0.1, 20.0))
    def advance(self, seconds: float) -> None:
        self.net.run(self.net.now + seconds)

    @rule(member=st.integers(0, 4), seconds=st.floats(1.0, 120.0), inbound=st.booleans())
    def isolate(self, member: int, seconds: float, inbound: bool) -> None:
        name = f"r{member % len(self.team.team)}"
        self.net.cuts.append(Cut(name, None, self.net.now, self.net.now + seconds, inbound))

    @rule(loss=st.floats(0.0, MAX_LOSS))
    def set_loss(self, loss: float) -> None:
        self.net.loss = loss

    @precondition(lambda self: hasattr(self, "team"))
    @invariant()
    def safe(self) -> None:
        assert not self.team.violations, f"seed={self.seed}: {self.team.violations[:3]}"

    def teardown(self) -> None:
        if not hasattr(self, "team"):
            return
        deadline = max(self.net.heal_time(), self.net.now) + liveness_bound(self.net.loss)
        self.net.run(deadline, stop=self.team.all_done)
        check_done(self.team, deadline, f"seed={self.seed}")


AonMachine.TestCase.settings = settings(
    max_examples=100,
    stateful_step_count=25,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)
TestAonMachine = AonMachine.TestCase
