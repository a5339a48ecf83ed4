"""``mrcomm team``: make the certificates a live team authenticates with.

* ``mrcomm team init DIR --members robot_1,robot_2,... [--scenario S]`` — a new team
  CA and a certificate per member (the world is always one): what ``--team-dir DIR``
  of ``live`` / ``world`` / ``agent`` / ``pulse`` reads;
* ``mrcomm team add DIR --members robot_4`` — sign certificates for new members;
* ``mrcomm team show DIR`` — the members, and whose files are present.

Each member's certificate names 127.0.0.1, localhost and the addresses given with
``--address MEMBER=HOST`` (repeatable): what its peers connect to.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from mrcomm.errors import InputError

team_app = typer.Typer(
    help="Team certificates for live mode: init, add, show.",
    no_args_is_help=True,
    rich_markup_mode=None,
)

DirArg = Annotated[Path, typer.Argument(help="The team directory.")]
MembersOpt = Annotated[
    str | None,
    typer.Option(help="Comma-separated member names (process ids: robot ids, assigner)."),
]
AddressOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--address",
        help="MEMBER=HOST: an address (IP or DNS name) the member is reached at (repeatable).",
    ),
]
DaysOpt = Annotated[int, typer.Option(help="Validity of the certificates, days.")]


def _members(text: str | None) -> list[str]:
    return [m.strip() for m in text.split(",") if m.strip()] if text else []


def _addresses(items: list[str] | None) -> dict[str, list[str]]:
    out: dict[str, list[str]] = {}
    for item in items or []:
        member, sep, host = item.partition("=")
        if not sep or not member.strip() or not host.strip():
            raise InputError(f"expected MEMBER=HOST, got {item!r}", field="--address")
        out.setdefault(member.strip(), []).append(host.strip())
    return out


@team_app.command()
def init(
    directory: DirArg,
    members: MembersOpt = None,
    scenario: Annotated[
        Path | None,
        typer.Option(help="Take the members from a scenario: its robots and the assigner."),
    ] = None,
    address: AddressOpt = None,
    days: DaysOpt = 365,
) -> None:
    """Make a team CA and a certificate per member (and the world's) in DIR."""
    from mrcomm.live.identity import live_members
    from mrcomm.live.protocol import WORLD_ID
    from mrcomm.net.team_dir import init_team

    names = _members(members)
    if scenario is not None:
        from mrcomm.bundled import resolve
        from mrcomm.world.scenario import load_scenario

        source = load_scenario(resolve(scenario, "scenario"))
        names += [m for m in live_members(source) if m not in names]
    if not names:
        raise InputError("give --members or --scenario", field="--members")
    if WORLD_ID not in names:
        names.insert(0, WORLD_ID)  # every live team has a world: its clock
    team = init_team(directory, names, addresses=_addresses(address), days=days)
    typer.echo(f"team in {team.path}: CA ca.pem, members {', '.join(team.members)}")
    typer.echo(
        "give each host ca.pem, team.yaml and its own <member>.pem/.key; keep ca.key off the robots"
    )


@team_app.command()
def add(
    directory: DirArg,
    members: MembersOpt = None,
    address: AddressOpt = None,
    days: DaysOpt = 365,
) -> None:
    """Sign certificates for new members with the team's CA."""
    from mrcomm.net.team_dir import add_members

    team = add_members(directory, _members(members), addresses=_addresses(address), days=days)
    typer.echo(f"team in {team.path}: members {', '.join(team.members)}")


@team_app.command()
def show(directory: DirArg) -> None:
    """The team's members and which of their files are in DIR."""
    from mrcomm.net.team_dir import load_team

    team = load_team(directory, "DIR")
    for member in team.members:
        files = team.files(member)
        present = [p.name for p in (files.cert, files.key) if p.is_file()]
        typer.echo(f"{member}: {', '.join(present) if present else 'no files here'}")
